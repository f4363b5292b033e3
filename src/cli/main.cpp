// lash: the command-line front end. `lash run MODEL -o OUT` simulates; `lash check MODEL`
// validates. Exit codes: 0 success, 1 numerical failure or I/O error, 2 bad model or options.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <filesystem>
#include <iostream>

#include "cli/tune_absorber.hpp"
#include "io/model_loader.hpp"
#include "io/report.hpp"
#include "io/results_writer.hpp"
#include "io/state_file.hpp"
#include "study/run_analysis.hpp"

namespace {

/// Forwards to the results writer and shows progress on a terminal.
class ProgressObserver : public lash::Observer {
 public:
  /// `w` may be null (progress only).
  ProgressObserver(lash::ResultsWriter* w, bool show) : w_(w), show_(show) {}
  void output(double t, const Eigen::VectorXd& y, const lash::Workspace& ws) override {
    if (w_) w_->output(t, y, ws);
    rhs_ = ws.rhs_evaluations;
  }
  void event(const lash::ContactEvent& e, const lash::Workspace& ws) override {
    if (w_) w_->event(e, ws);
  }
  void progress(double t, double t_end) override {
    if (!show_) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < std::chrono::milliseconds(200) && t < t_end) return;
    last_ = now;
    const double wall = std::chrono::duration<double>(now - start_).count();
    fmt::print(stderr, "\r  t = {:.6g} s  {:5.1f}%  {:.3g} simulated s per wall s  {} rhs   ", t,
               100.0 * t / t_end, wall > 0 ? t / wall : 0.0, rhs_);
    if (t >= t_end) fmt::print(stderr, "\n");
  }

 private:
  lash::ResultsWriter* w_;
  bool show_;
  long rhs_ = 0;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_{};
};

/// The signal that asked the run to stop (0: none). A handler may only store it.
std::atomic<int> g_interrupt{0};
extern "C" void on_signal(int sig) { g_interrupt.store(sig); }

/// SIGINT, SIGTERM and SIGHUP end the run at its next output, which then writes its summary and
/// final state like any stopped run; a second signal ends the program at once.
void install_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sa.sa_flags = SA_RESETHAND;
  sigemptyset(&sa.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaction(sig, &sa, nullptr);
}

int report_model_error(const lash::ModelError& e) {
  for (const auto& d : e.diagnostics()) std::cerr << d.str() << "\n";
  std::cerr << e.diagnostics().size() << " problem" << (e.diagnostics().size() == 1 ? "" : "s")
            << " found; nothing was run.\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Lash: dynamics of planar mechanisms with clearance joints"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "lash 0.1.0");

  std::string model_path, out_dir;
  std::vector<std::string> overrides;
  bool quiet = false;

  auto* run = app.add_subcommand("run", "Simulate a model and write its results to a folder");
  run->add_option("model", model_path, "Model file (YAML), see docs/model-format.md")
      ->required()
      ->check(CLI::ExistingFile);
  run->add_option("-o,--output", out_dir,
                  "Output folder for timeseries.csv, events.csv, summary.json "
                  "(default: out/<model file name without extension>)");
  run->add_option("--set", overrides,
                  "Override a model value before validation, KEY.PATH=VALUE, repeatable; "
                  "e.g. --set joints.rod_slider.clearance=0.25e-3 "
                  "--set drivers.crank.speed_rpm=3000 --set solver.integrator=bdf")
      ->take_all();
  run->add_flag("-q,--quiet", quiet, "No progress line and no closing summary");
  std::string from_state;
  run->add_option("--from", from_state,
                  "Continue from a saved state (a run's final_state.json), time and all, to the "
                  "model's end_time")
      ->check(CLI::ExistingFile);
  bool with_report = false;
  run->add_flag("--report", with_report,
                "Also analyse the run and write report.html, report_data.json and figures/");

  std::string run_dir;
  auto* report = app.add_subcommand(
      "report", "Analyse an earlier run folder (re-running its model_resolved.yaml) and write "
                "report.html, report_data.json and figures/ into it");
  report->add_option("folder", run_dir, "A folder written by `lash run`")
      ->required()
      ->check(CLI::ExistingDirectory);

  auto* analyze = app.add_subcommand(
      "analyze", "Nonlinear-dynamics analyses of an earlier run folder; prints them and writes "
                 "analysis.json");
  analyze->add_option("folder", run_dir, "A folder written by `lash run`")
      ->required()
      ->check(CLI::ExistingDirectory);
  std::string poincare_driver;
  std::vector<std::string> fft_channels;
  bool lyapunov = false;
  int discard_periods = 1;
  analyze->add_option("--poincare", poincare_driver,
                      "Stroboscopic Poincaré section once per period of this constant-speed "
                      "driver (default: the first one)");
  analyze->add_option("--fft", fft_channels, "Amplitude spectrum of these channels, e.g. slider.ax")
      ->take_all();
  analyze->add_flag("--lyapunov", lyapunov, "Largest Lyapunov exponent (two trajectories)");
  std::vector<std::string> planes;
  analyze->add_option("--plane", planes,
                      "Event-based Poincaré section instead of the stroboscopic one: "
                      "<body>.<x|y|phi|vx|vy|omega>=VALUE[,down], e.g. slider.vx=0,down");
  analyze->add_option("--discard", discard_periods, "Transient periods to discard (default 1)");
  std::vector<double> window, angle_range;
  for (auto* sub : {report, analyze}) {
    sub->add_option("--window", window, "Statistics over this time window, T0,T1 (s)")
        ->delimiter(',')
        ->expected(2);
    sub->add_option("--angle-range", angle_range,
                    "Statistics where the crank angle is in A0,A1 (degrees; wraps through 360)")
        ->delimiter(',')
        ->expected(2);
  }
  double lyapunov_d0 = 0.0;
  analyze->add_option("--lyapunov-d0", lyapunov_d0,
                      "Separation of the two trajectories, m (default 2e-4 x clearance, <= 1e-7)");

  auto* check = app.add_subcommand("check", "Validate a model: list every problem with file:line:column");
  check->add_option("model", model_path, "Model file (YAML)")->required()->check(CLI::ExistingFile);
  check->add_option("--set", overrides, "Override a model value, KEY.PATH=VALUE, repeatable")
      ->take_all();

  const lash::cli::TuneAbsorberCommand tune_absorber(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (tune_absorber.parsed()) return tune_absorber.run(std::cout, std::cerr);

  if (*report || *analyze) {
    model_path = run_dir + "/model_resolved.yaml";
    if (!std::filesystem::exists(model_path)) {
      std::cerr << run_dir << ": no model_resolved.yaml: not a folder written by `lash run`\n";
      return 2;
    }
  }
  lash::LoadedModel loaded;
  try {
    loaded = lash::load_model_file(model_path, overrides);
  } catch (const lash::ModelError& e) {
    return report_model_error(e);
  }
  const lash::Model& model = loaded.model;

  if (*check) {
    try {
      lash::Workspace ws(model);
      lash::initial_state(model, ws);
    } catch (const std::exception& e) {
      std::cerr << model_path << ": " << e.what() << "\n";
      return 2;
    }
    std::cout << model_path << ": ok: " << model.bodies.size() << " bodies, "
              << model.joints.size() << " joints (" << model.clearance_joint_count()
              << " with clearance), " << model.drivers.size() << " drivers, "
              << model.loads.size() << " loads, " << model.sensors.size() << " sensors\n";
    return 0;
  }

  if (*report || *analyze) {
    lash::AnalysisOptions ro;
    ro.discard_periods = discard_periods;
    if (window.size() == 2) ro.stats_t0 = window[0], ro.stats_t1 = window[1];
    if (angle_range.size() == 2) ro.stats_angle0 = angle_range[0], ro.stats_angle1 = angle_range[1];
    if (*analyze) {
      ro.lyapunov = lyapunov;
      ro.poincare_driver = poincare_driver;
      ro.fft_channels = fft_channels;
      ro.lyapunov_d0 = lyapunov_d0;
      ro.section_planes = planes;
    }
    try {
      ProgressObserver progress(nullptr, isatty(STDERR_FILENO));
      const lash::RunAnalysis ra = lash::analyze_run(model, ro, &progress);
      const nlohmann::json data = lash::report_data(model, ra);
      if (*report) {
        for (const auto& line : lash::write_report(data, run_dir)) std::cout << line << "\n";
        return ra.result.status.ok ? 0 : 1;
      }
      const auto& an = data["analysis"];
      std::ofstream(run_dir + "/analysis.json") << an.dump(2) << "\n";
      if (an["poincare"].is_object())
        fmt::print("poincare ({}): {} sections, {} distinct point(s)\n",
                   an["poincare"]["kind"].get<std::string>(), an["poincare"]["points"].size(),
                   an["poincare"]["distinct"].get<int>());
      for (const auto& [name, sp] : an["spectra"].items()) {
        // The three strongest local maxima.
        const auto& f = sp["frequency"];
        const auto& a = sp["amplitude"];
        std::vector<std::pair<double, double>> peaks;
        for (size_t k = 1; k + 1 < a.size(); ++k)
          if (a[k] >= a[k - 1] && a[k] >= a[k + 1]) peaks.push_back({a[k], f[k]});
        std::sort(peaks.rbegin(), peaks.rend());
        fmt::print("spectrum {}:", name);
        for (size_t k = 0; k < std::min<size_t>(3, peaks.size()); ++k)
          fmt::print(" {:.6g} Hz ({:.4g})", peaks[k].second, peaks[k].first);
        fmt::print("\n");
      }
      if (an["lyapunov"].is_object() && !an["lyapunov"]["exponent"].is_null())
        fmt::print("largest Lyapunov exponent: {:.4g} 1/s over {} renormalisations\n",
                   an["lyapunov"]["exponent"].get<double>(),
                   an["lyapunov"]["renormalisations"].get<int>());
      fmt::print("verdict: {}", an["verdict"]["class"].get<std::string>());
      for (const auto& e : an["verdict"]["evidence"]) fmt::print("; {}", e.get<std::string>());
      fmt::print("\nwrote {}/analysis.json\n", run_dir);
      return ra.result.status.ok ? 0 : 1;
    } catch (const std::invalid_argument& e) {
      std::cerr << "error: " << e.what() << "\n";
      return 2;
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << "\n";
      return 1;
    }
  }

  if (out_dir.empty())
    out_dir = "out/" + std::filesystem::path(model_path).stem().string();
  if (with_report && !from_state.empty()) {
    std::cerr << "error: --report analyses a whole run from t = 0; run without --from to get a "
                 "report, or report on the earlier run's folder\n";
    return 2;
  }
  lash::RunOptions run_options;
  install_signal_handlers();
  run_options.interrupt = &g_interrupt;
  lash::State start;
  if (!from_state.empty()) {
    try {
      lash::Workspace probe(model);
      start = lash::read_state(from_state, model, probe);
      if (const std::string why = lash::resume_problem(model, probe, start); !why.empty())
        throw std::runtime_error(from_state + ": " + why);
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << "\n";
      return 2;
    }
    run_options.from = &start;
  }
  try {
    lash::Workspace ws(model);
    lash::ResultsWriter writer(model, out_dir);
    lash::RunResult result;
    lash::RunAnalysis ra;
    try {
      if (with_report) {
        ProgressObserver progress(&writer, !quiet && isatty(STDERR_FILENO));
        ra = lash::analyze_run(model, lash::AnalysisOptions{}, &progress);
        result = ra.result;
      } else {
        ProgressObserver observer(&writer, !quiet && isatty(STDERR_FILENO));
        result = lash::simulate(model, ws, observer, {}, {}, run_options);
      }
    } catch (const std::runtime_error& e) {  // no consistent initial state
      std::cerr << model_path << ": " << e.what() << "\n";
      return 2;
    }
    for (const auto& w : result.warnings) std::cerr << model_path << ": warning: " << w << "\n";
    writer.finish(result, loaded.resolved_yaml, overrides, from_state);

    // The report covers what was computed, up to a failure too.
    std::vector<std::string> report_notes;
    if (with_report) report_notes = lash::write_report(lash::report_data(model, ra), out_dir);
    if (!result.status.ok) {
      for (const auto& line : report_notes) std::cerr << "report: " << line << "\n";
      if (const int sig = g_interrupt.load(); sig != 0) {
        std::cerr << "\ninterrupted at t = " << result.status.t << " s; results up to that time, "
                  << "summary.json and final_state.json are in " << out_dir << "/\n";
        return 128 + sig;
      }
      std::cerr << "\nerror: simulation stopped at t = " << result.status.t << " s"
                << (result.status.element.empty() ? "" : ", joint '" + result.status.element + "'")
                << ": " << result.status.message << "\nresults up to that time are in " << out_dir
                << "/\n";
      return 1;
    }
    if (!quiet)
      fmt::print("{}: {} outputs to {}/ in {:.3f} s ({} steps, {} rejected, {} rhs evaluations, "
                 "{} contact events; max constraint violation {:.2e})\n",
                 model.name, result.outputs, out_dir, result.wall_seconds, result.stats.steps,
                 result.stats.rejected_steps, result.stats.rhs_evaluations, result.stats.events,
                 result.max_constraint_violation);
    for (const auto& line : report_notes)
      if (!quiet) std::cout << "report: " << line << "\n";
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
