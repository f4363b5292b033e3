// lash: the command-line front end. `lash run MODEL -o OUT` simulates; `lash check MODEL`
// validates. Exit codes: 0 success, 1 numerical failure, 2 bad model or options, 3 I/O error
// (results could not be written), 130 interrupted by a signal.
#include <cmath>
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <signal.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>

#include "cli/sweep.hpp"
#include "cli/modes.hpp"
#include "cli/tune_absorber.hpp"
#include "io/files.hpp"
#include "io/model_loader.hpp"
#include "io/report.hpp"
#include "io/results_writer.hpp"
#include "io/run_folder.hpp"
#include "io/state_file.hpp"
#include "study/run_analysis.hpp"

namespace {

/// How a run's progress is shown on standard error.
enum class ProgressMode { none, terminal, log };

/// Forwards to the results writer and shows progress: on a terminal one line rewritten every
/// 0.2 s; otherwise (a log, a batch job) a line every `log_seconds` of wall time (default 30 s,
/// the environment's LASH_PROGRESS_SECONDS), so a run shorter than that writes none.
class ProgressObserver : public lash::Observer {
 public:
  /// `w` may be null (progress only).
  ProgressObserver(lash::ResultsWriter* w, ProgressMode mode, double log_seconds)
      : w_(w), mode_(mode),
        log_interval_(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
            std::chrono::duration<double>(log_seconds))) {}
  void output(double t, const Eigen::VectorXd& y, const lash::Workspace& ws) override {
    if (w_) w_->output(t, y, ws);
    rhs_ = ws.rhs_evaluations;
  }
  void event(const lash::ContactEvent& e, const lash::Workspace& ws) override {
    if (w_) w_->event(e, ws);
  }
  std::string stop_reason() const override { return w_ ? w_->stop_reason() : std::string(); }
  bool wants_steps() const override { return w_ && w_->wants_steps(); }
  void step(double t0, double t1, const Eigen::VectorXd& y, const lash::Workspace& ws,
            lash::StepProbe& probe) override {
    if (w_) w_->step(t0, t1, y, ws, probe);
  }
  void progress(double t, double t_end) override {
    if (mode_ == ProgressMode::none) return;
    const auto now = std::chrono::steady_clock::now();
    if (mode_ == ProgressMode::log) {
      if (now - last_log_ < log_interval_) return;
      last_log_ = now;
    } else if (now - last_ < std::chrono::milliseconds(200) && t < t_end) {
      return;
    }
    last_ = now;
    const double wall = std::chrono::duration<double>(now - start_).count();
    fmt::print(stderr, "{}  t = {:.6g} s  {:5.1f}%  {:.3g} simulated s per wall s  {} evaluation{} of the model{}",
               mode_ == ProgressMode::terminal ? "\r" : "", t, 100.0 * t / t_end,
               wall > 0 ? t / wall : 0.0, rhs_, rhs_ == 1 ? "" : "s",
               mode_ == ProgressMode::terminal ? "   " : "\n");
    if (mode_ == ProgressMode::terminal && t >= t_end) fmt::print(stderr, "\n");
  }

 private:
  lash::ResultsWriter* w_;
  ProgressMode mode_;
  std::chrono::steady_clock::duration log_interval_;
  std::chrono::steady_clock::time_point last_log_ = std::chrono::steady_clock::now();
  long rhs_ = 0;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_{};
};

/// The signal that asked the run to stop (0: none). A handler may only store it.
std::atomic<int> g_interrupt{0};
/// When the first signal came (CLOCK_MONOTONIC, ns).
std::atomic<long long> g_interrupt_ns{0};
/// The same signal again within this time of the first is the same request delivered twice:
/// GNU `timeout` sends its signal to the program and then to the program's process group.
constexpr long long kRepeatedSignalNs = 1'000'000'000;

extern "C" void on_signal(int sig) {
  // Only async-signal-safe calls here: clock_gettime, sigaction, raise.
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  const long long ns = now.tv_sec * 1'000'000'000LL + now.tv_nsec;
  const int first = g_interrupt.load();
  if (first == 0) {
    g_interrupt_ns.store(ns);
    g_interrupt.store(sig);
    return;
  }
  if (sig == first && ns - g_interrupt_ns.load() < kRepeatedSignalNs) return;
  // A second request: end at once, as the signal's default action.
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  sigaction(sig, &dfl, nullptr);
  raise(sig);
}

/// SIGINT, SIGTERM and SIGHUP end the run within one integrator step; it then writes its summary
/// and final state like any stopped run; a second signal ends the program at once (the same
/// signal within kRepeatedSignalNs of the first is taken for the first delivered twice). A signal
/// the parent ignores stays ignored (`nohup lash run ...` survives a closed terminal).
void install_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sa.sa_flags = 0;
  sigemptyset(&sa.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    if (sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    sigaction(sig, &sa, nullptr);
  }
}

/// How a run ended, in a sentence ("the run <...> at t = ...").
const char* ended(lash::RunOutcome o) {
  switch (o) {
    case lash::RunOutcome::completed: return "completed";
    case lash::RunOutcome::failed: return "stopped on a numerical failure";
    case lash::RunOutcome::interrupted: return "was interrupted";
    case lash::RunOutcome::write_error: return "stopped on a write error";
  }
  return "stopped";
}

// Exit codes (README, docs/model-format.md).
constexpr int kExitOk = 0;
constexpr int kExitNumerical = 1;   ///< the run stopped: step-size underflow, NaN, an expression
constexpr int kExitBadInput = 2;    ///< bad model, options or state file; nothing was run
constexpr int kExitIo = 3;          ///< results could not be written (full disk, size limit, ...)
constexpr int kExitInterrupted = 130;

int exit_code(lash::RunOutcome o) {
  switch (o) {
    case lash::RunOutcome::completed: return kExitOk;
    case lash::RunOutcome::failed: return kExitNumerical;
    case lash::RunOutcome::interrupted: return kExitInterrupted;
    case lash::RunOutcome::write_error: return kExitIo;
  }
  return kExitNumerical;
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
                  "(default: out/<model file name without extension>)")
      ->check([](const std::string& f) {
        return f.empty() ? std::string("is empty: name a folder, or leave out -o for "
                                       "out/<model file name without extension>")
                         : std::string();
      })
      ->transform([](std::string f) { return lash::folder_name(std::move(f)); });
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
  std::string channels_opt, format_opt;
  run->add_option("--channels", channels_opt,
                  "Write only these channels to the time series: comma-separated glob patterns, "
                  "e.g. 'slider.*,rod_slider.*' (time is always written; default: the model's "
                  "solver.output_channels, else all)")
      ->check([](const std::string& list) {
        return lash::split_channel_patterns(list).empty()
                   ? std::string("names no channel pattern: give comma-separated patterns such "
                                 "as 'slider.*,rod_slider.*', or leave out --channels")
                   : std::string();
      });
  run->add_option("--format", format_opt,
                  "Time series format: csv (timeseries.csv, 9 significant digits; the default) "
                  "or hdf5 (timeseries.h5, every double in full; default: the model's "
                  "solver.output_format)")
      ->check(CLI::IsMember({"csv", "hdf5"}));
  bool with_report = false;
  run->add_flag("--report", with_report,
                "Also analyse the run and write report.html, report_data.json and figures/");

  std::string run_dir;
  auto* report = app.add_subcommand(
      "report", "Analyse an earlier run folder from the files the run wrote (simulating only "
                "the ideal twin and the Lyapunov trajectories) and write report.html, "
                "report_data.json and figures/ into it");
  report->add_option("folder", run_dir, "A folder written by `lash run` (or by `lash sweep`: its study_report.html)")
      ->required()
      ->check(CLI::ExistingDirectory)
      ->transform([](std::string f) { return lash::folder_name(std::move(f)); });

  auto* analyze = app.add_subcommand(
      "analyze", "Nonlinear-dynamics analyses of an earlier run folder; prints them and writes "
                 "analysis.json");
  analyze->add_option("folder", run_dir, "A folder written by `lash run`")
      ->required()
      ->check(CLI::ExistingDirectory)
      ->transform([](std::string f) { return lash::folder_name(std::move(f)); });
  std::string poincare_driver;
  std::vector<std::string> fft_channels;
  bool no_lyapunov = false;
  int discard_periods = 1;
  std::string lyapunov_method = "variational";
  std::vector<std::string> planes;
  double lyapunov_d0 = 0.0;
  // The analysis options: the same on both commands, applied to every part of the analyses
  // (report.html and figures read the same data as analysis.json).
  for (auto* sub : {report, analyze}) {
    sub->add_option("--poincare", poincare_driver,
                    "Stroboscopic Poincaré section once per period of this constant-speed "
                    "driver (default: the first one)");
    sub->add_option("--fft", fft_channels,
                    "Amplitude spectrum of these channels, e.g. slider.ax rod_slider.Fn (or "
                    "comma-separated, as --channels)")
        ->take_all()
        ->delimiter(',');
    sub->add_flag("--no-lyapunov", no_lyapunov,
                  "Skip the Lyapunov exponents (computed by default, since the verdict needs "
                  "them)");
    sub->add_option("--lyapunov-method", lyapunov_method,
                    "variational (the spectrum from the variational equations with saltation "
                    "matrices at contact events; default) or two-trajectory (the largest "
                    "exponent from a pair of runs, a cross-check)");
    sub->add_option("--plane", planes,
                    "Event-based Poincaré section instead of the stroboscopic one: "
                    "<body>.<x|y|phi|vx|vy|omega>=VALUE[,down], e.g. slider.vx=0,down (one plane)");
    sub->add_option("--discard", discard_periods, "Transient periods to discard (default 1)");
    sub->add_option("--lyapunov-d0", lyapunov_d0,
                    "Separation of the two trajectories (--lyapunov-method two-trajectory), m "
                    "(default 2e-4 x clearance, <= 1e-7)");
  }
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
  double period = 0.0;
  for (auto* sub : {report, analyze})
    sub->add_option("--period", period,
                    "Period of the motion, s: sections, crank angle and exponent for a model whose "
                    "driver is an expression (default: a constant-speed driver's, else the "
                    "driver's mean speed over the run's last half)")
        ->check(CLI::Validator(
            [](std::string& v) {
              char* end = nullptr;
              const double x = std::strtod(v.c_str(), &end);
              return end != v.c_str() && *end == '\0' && x > 0.0 && std::isfinite(x)
                         ? std::string()
                         : "expected a period > 0 s, got '" + v + "'";
            },
            "SECONDS"));

  auto* check = app.add_subcommand(
      "check", "Validate a model or a study file (docs/studies.md): list every problem with file:line:column");
  check->add_option("model", model_path, "Model or study file (YAML)")->required()->check(CLI::ExistingFile);
  check->add_option("--set", overrides, "Override a model value, KEY.PATH=VALUE, repeatable")
      ->take_all();

  auto* modes = app.add_subcommand(
      "modes", "Natural frequencies of each flexible link of a model, from its mesh, beside the "
               "Euler–Bernoulli closed forms (clamped–free and free–free), and of the whole "
               "mechanism linearised at its initial configuration (or, with --equilibrium, at "
               "the static equilibrium nearest it)");
  int mode_count = 6;
  modes->add_option("model", model_path, "Model file (YAML)")->required()->check(CLI::ExistingFile);
  modes->add_option("--count", mode_count, "Modes per table (default 6)")
      ->check(CLI::Range(1, 100));
  modes->add_option("--set", overrides, "Override a model value, KEY.PATH=VALUE, repeatable")
      ->take_all();
  bool at_equilibrium = false;
  modes->add_flag("--equilibrium", at_equilibrium,
                  "Linearise at the static equilibrium nearest the initial configuration (under "
                  "gravity and the loads, drivers held) instead of at the initial configuration");

  const lash::cli::TuneAbsorberCommand tune_absorber(app);
  const lash::cli::SweepCommand sweep(app, argv);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  // Past a file-size limit (ulimit -f) a write then fails with EFBIG and is reported (exit 3)
  // instead of the process being killed with a half-written row.
  ::signal(SIGXFSZ, SIG_IGN);
  // A closed pipe on stdout (`lash run ... | head`) is a failed write, not the end of the run.
  ::signal(SIGPIPE, SIG_IGN);
  if (tune_absorber.parsed()) return tune_absorber.run(std::cout, std::cerr);
  if (sweep.parsed()) return sweep.run(g_interrupt, install_signal_handlers);

  // A study folder (lash sweep): its report is study_report.html from study.db.
  if (*report && std::filesystem::exists(run_dir + "/study.db")) {
    try {
      const lash::FolderLock lock(run_dir);
      const std::string written = lash::cli::write_study_report(run_dir);
      std::cout << "wrote " << written << "\n";
      return kExitOk;
    } catch (const lash::IoError& e) {
      std::cerr << "error: " << e.what() << "\n";
      return kExitIo;
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << "\n";
      return kExitBadInput;
    }
  }

  std::unique_ptr<lash::FolderLock> folder_lock;  // report/analyze: no run writes meanwhile
  if (*report || *analyze) {
    model_path = run_dir + "/model_resolved.yaml";
    if (!std::filesystem::exists(model_path)) {  // before the lock file is made
      std::cerr << "error: " << model_path << ": missing: not a folder written by `lash run`";
      if (*report)
        std::cerr << " (nor a study folder of `lash sweep`, which holds study.db)";
      else if (std::filesystem::exists(run_dir + "/study.db"))
        std::cerr << "; it holds a study of `lash sweep`: `lash report " << run_dir
                  << "` writes the study's report, and its runs' analyses are in runs.csv";
      std::cerr << "\n";
      return kExitBadInput;
    }
    try {
      folder_lock = std::make_unique<lash::FolderLock>(run_dir);
    } catch (const lash::IoError& e) {
      std::cerr << "error: " << e.what() << "\n";
      return kExitIo;
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << "\n";
      return kExitBadInput;
    }
  }
  // `lash check` of a study file (a map with `study:`): checked as `lash sweep` checks it, not
  // as a model (which listed its keys as unknown model keys).
  if (*check && lash::cli::is_study_file(model_path)) {
    if (!overrides.empty()) {
      std::cerr << "error: --set applies to a model; " << model_path
                << " is a study (its values are set in its set: and parameters:)\n";
      return kExitBadInput;
    }
    return lash::cli::check_study(model_path);
  }
  lash::LoadedModel loaded;
  try {
    loaded = lash::load_model_file(model_path, overrides);
  } catch (const lash::ModelError& e) {
    // A study file given where a model belongs: said so, not its keys listed as unknown (looked
    // at only when the file is no model, so a run parses its model once).
    if (!*report && !*analyze && lash::cli::is_study_file(model_path)) {
      std::cerr << "error: " << model_path << " is a study file (it has 'study:', or 'model:' "
                << "and no bodies), not a model: "
                << "run it with `lash sweep " << model_path << " -o DIR`, or name its model file\n";
      return kExitBadInput;
    }
    return report_model_error(e);
  }
  const lash::Model& model = loaded.model;

  if (*modes) {
    try {
      lash::cli::print_modes(model, mode_count, at_equilibrium, std::cout);
    } catch (const std::exception& e) {
      std::cerr << loaded.located(e.what()) << "\n";
      return 2;
    }
    return 0;
  }

  if (*check) {
    // What assembly finds is said as `lash run` says it: redundant joint equations dropped, an
    // assembly that moved far from the positions given (a model that loads can still warn).
    std::vector<std::string> warnings;
    try {
      lash::Workspace ws(model);
      lash::initial_state(model, ws);
      warnings = ws.warnings;
    } catch (const std::exception& e) {
      std::cerr << loaded.located(e.what()) << "\n";
      return 2;
    }
    for (const auto& w : warnings) std::cerr << loaded.located(w, "warning: ") << "\n";
    auto count = [](size_t n, const char* one, const char* many) {
      return std::to_string(n) + " " + (n == 1 ? one : many);
    };
    std::cout << model_path << ": ok: " << count(model.bodies.size(), "body", "bodies") << ", "
              << count(model.joints.size(), "joint", "joints") << " ("
              << model.clearance_joint_count() << " with clearance), "
              << count(model.drivers.size(), "driver", "drivers") << ", "
              << count(model.loads.size(), "load", "loads") << ", "
              << count(model.sensors.size(), "sensor", "sensors") << "\n";
    return 0;
  }

  if (*report || *analyze) {
    lash::AnalysisOptions ro;
    ro.discard_periods = discard_periods;
    ro.period = period;
    if (window.size() == 2) ro.stats_t0 = window[0], ro.stats_t1 = window[1];
    if (angle_range.size() == 2) ro.stats_angle0 = angle_range[0], ro.stats_angle1 = angle_range[1];
    ro.lyapunov = !no_lyapunov;
    ro.poincare_driver = poincare_driver;
    ro.fft_channels = fft_channels;
    ro.lyapunov_d0 = lyapunov_d0;
    ro.lyapunov_method = lyapunov_method;
    ro.section_planes = planes;
    install_signal_handlers();
    ro.interrupt = &g_interrupt;
    try {
      lash::check_options(ro);
    } catch (const std::invalid_argument& e) {
      std::cerr << "error: " << e.what() << "\n";
      return kExitBadInput;
    }
    // What the run wrote, checked before anything is simulated: a damaged folder is refused
    // naming the file (exit 2), one that cannot be read is an I/O error (exit 3).
    lash::RecordedRun recorded;
    try {
      recorded = lash::read_run_folder(run_dir, model);
    } catch (const lash::IoError& e) {
      std::cerr << "error: " << e.what() << "\n";
      return kExitIo;
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << "\n";
      return kExitBadInput;
    }
    try {
      lash::RunAnalysis ra = lash::analyze_recorded_run(model, ro, recorded);
      for (const auto& line : ra.provenance.read) std::cout << "read: " << line << "\n";
      for (const auto& line : ra.provenance.resimulated) std::cout << "simulated now: " << line << "\n";
      for (const auto& line : ra.provenance.skipped) std::cout << "skipped: " << line << "\n";
      if (const int sig = g_interrupt.load(); sig != 0) {  // during the run or the analyses
        std::cerr << "\ninterrupted by signal " << sig << "; nothing was written\n";
        return kExitInterrupted;
      }
      nlohmann::json data = lash::report_data(model, ra);
      // The model file the run was given, as the report made during the run names it (the
      // model was loaded from the folder's copy).
      if (!recorded.model_file.empty()) data["model"]["file"] = recorded.model_file;
      const int code = exit_code(ra.result.status.outcome);
      if (code != kExitOk)
        std::cerr << "the run stopped at t = " << ra.result.status.t
                  << " s: " << ra.result.status.message << "\n";
      if (*report) {
        for (const auto& line : lash::write_report(data, run_dir, &g_interrupt)) std::cout << line << "\n";
        if (const int sig = g_interrupt.load(); sig != 0) {  // during the figures
          std::cerr << "\ninterrupted by signal " << sig
                    << " while the figures were drawn; report.html and report_data.json are "
                       "complete, figures/ may not be\n";
          return kExitInterrupted;
        }
        return code;
      }
      const auto& an = data["analysis"];
      lash::write_file_atomic(
          run_dir + "/analysis.json",
          an.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
      if (an["period"]["value"].is_number())
        fmt::print("period: {:.6g} s ({})\n", an["period"]["value"].get<double>(),
                   an["period"]["source"].get<std::string>());
      else
        fmt::print("period: none (no revolute driver with a well-defined mean speed; --period "
                   "sets one)\n");
      if (an["poincare"].is_object())
        fmt::print("poincare ({}): {} sections, {} distinct point(s)\n",
                   an["poincare"]["kind"].get<std::string>(), an["poincare"]["points"].size(),
                   an["poincare"]["distinct"].get<int>());
      if (an["poincare"].is_object())
        for (const auto& j : an["poincare"]["joints"])
          fmt::print("  joint {}: {} distinct point(s) within {:.3g} m\n",
                     j["joint"].get<std::string>(), j["distinct"].get<int>(),
                     j["tolerance"].get<double>());
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
      if (an["lyapunov"].is_object() && an["lyapunov"]["exponent"].is_null() &&
          !an["lyapunov"]["message"].get<std::string>().empty())
        fmt::print("Lyapunov exponents not computed: {}\n",
                   an["lyapunov"]["message"].get<std::string>());
      if (an["lyapunov"].is_object() && !an["lyapunov"]["exponent"].is_null()) {
        const auto& l = an["lyapunov"];
        fmt::print("largest Lyapunov exponent: {:.4g} 1/s over {} renormalisations ({})\n",
                   l["exponent"].get<double>(), l["renormalisations"].get<int>(),
                   l["method"].get<std::string>());
        if (l.contains("note")) fmt::print("  ({})\n", l["note"].get<std::string>());
        if (l.contains("spectrum") && l["spectrum"].is_array()) {
          fmt::print("Lyapunov spectrum (1/s):");
          for (const auto& v : l["spectrum"]) fmt::print(" {:.4g}", v.get<double>());
          fmt::print("; {} contact events mapped by saltation matrices\n",
                     l["events_mapped"].get<int>());
        }
      }
      fmt::print("verdict: {}", an["verdict"]["class"].get<std::string>());
      for (const auto& e : an["verdict"]["evidence"]) fmt::print("; {}", e.get<std::string>());
      fmt::print("\nrule: {}\n", an["verdict"]["rule"].get<std::string>());
      fmt::print("wrote {}/analysis.json\n", run_dir);
      return code;
    } catch (const lash::IoError& e) {
      std::cerr << "error: " << e.what() << "\n";
      return kExitIo;
    } catch (const std::invalid_argument& e) {
      std::cerr << "error: " << e.what() << "\n";
      return kExitBadInput;
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << "\n";
      return kExitNumerical;
    }
  }

  if (out_dir.empty())
    out_dir = "out/" + std::filesystem::path(model_path).stem().string();
  if (with_report && !from_state.empty()) {
    std::cerr << "error: --report analyses a whole run from t = 0; run without --from to get a "
                 "report, or report on the earlier run's folder\n";
    return 2;
  }
  {
    // The model file itself among the files the run writes (`lash run out/model_resolved.yaml
    // -o out`, a model saved as out/events.csv): it would be replaced by the run's.
    namespace fs = std::filesystem;
    std::error_code e1, e2;
    const fs::path model_file = fs::weakly_canonical(fs::absolute(model_path), e1);
    const fs::path to_dir = fs::weakly_canonical(fs::absolute(out_dir), e2);
    if (!e1 && !e2 && model_file.parent_path() == to_dir) {
      const auto& files = lash::ResultsWriter::run_files();
      if (std::find(files.begin(), files.end(), model_file.filename().string()) != files.end()) {
        std::cerr << "error: the model file " << model_path << " is one of the files this run "
                  << "writes into " << out_dir << "/; copy it elsewhere or write into another "
                  << "folder (-o)\nnothing was run\n";
        return kExitBadInput;
      }
    }
  }
  if (!from_state.empty()) {
    // The state file would be replaced by the new run's before it is read to the end, and the
    // run it came from lost: continue into another folder.
    namespace fs = std::filesystem;
    std::error_code e1, e2;
    const fs::path from_dir = fs::weakly_canonical(fs::absolute(from_state), e1).parent_path();
    const fs::path to_dir = fs::weakly_canonical(fs::absolute(out_dir), e2);
    if (!e1 && !e2 && from_dir == to_dir) {
      std::cerr << "error: --from " << from_state << " is in the output folder " << out_dir
                << ", whose files this run replaces; continue into another folder (-o)\n";
      return kExitBadInput;
    }
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
      return kExitBadInput;
    }
    run_options.from = &start;
  }
  if (from_state.empty()) {
    // A model that cannot be assembled is refused before the output folder is touched, so an
    // earlier run's results there survive it.
    try {
      lash::Workspace probe(model);
      lash::initial_state(model, probe);
    } catch (const std::exception& e) {
      std::cerr << loaded.located(e.what()) << "\nnothing was run; " << out_dir
                << "/ is unchanged\n";
      return kExitBadInput;
    }
  }
  // The time series' channels and format: the options replace the model's solver settings. A
  // pattern of --channels that matches nothing is refused before the folder is touched (the
  // model's own output_channels were checked by the loader, at their lines).
  lash::OutputSettings output = loaded.output;
  if (!channels_opt.empty()) output.channels = lash::split_channel_patterns(channels_opt);
  if (!format_opt.empty())
    output.format = format_opt == "hdf5" ? lash::OutputFormat::hdf5 : lash::OutputFormat::csv;
  try {
    lash::select_channels(lash::channel_info(model), output.channels);
  } catch (const std::invalid_argument& e) {
    std::cerr << "error: --channels: " << e.what() << "\nnothing was run; " << out_dir
              << "/ is unchanged\n";
    return kExitBadInput;
  }
  if (output.format == lash::OutputFormat::hdf5 && !lash::hdf5_available()) {
    std::cerr << "error: HDF5 output: this lash was built without HDF5 (libhdf5-dev); use --format "
                 "csv\nnothing was run; " << out_dir << "/ is unchanged\n";
    return kExitBadInput;
  }
  std::unique_ptr<lash::FolderLock> lock;
  std::unique_ptr<lash::ResultsWriter> writer;
  try {
    lock = std::make_unique<lash::FolderLock>(out_dir);
    writer = std::make_unique<lash::ResultsWriter>(model, out_dir, loaded.resolved_yaml, overrides,
                                                   from_state, output);
  } catch (const lash::IoError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitIo;
  } catch (const std::exception& e) {  // the folder is another run's
    std::cerr << "error: " << e.what() << "\n";
    return kExitBadInput;
  }
  lash::RunResult result;
  lash::RunAnalysis ra;
  try {
    lash::Workspace ws(model);
    // A line every 30 s in a log, or every LASH_PROGRESS_SECONDS (>= 0; 0: every output).
    double log_seconds = 30.0;
    if (const char* env = std::getenv("LASH_PROGRESS_SECONDS"); env && *env && !quiet) {
      char* end = nullptr;
      const double v = std::strtod(env, &end);
      if (*end == '\0' && std::isfinite(v) && v >= 0.0 && v <= 1e9)
        log_seconds = v;
      else
        std::cerr << "warning: LASH_PROGRESS_SECONDS='" << env
                  << "' is not a number of seconds from 0 to 1e9; progress lines every 30 s\n";
    }
    ProgressObserver progress(writer.get(),
                              quiet                   ? ProgressMode::none
                              : isatty(STDERR_FILENO) ? ProgressMode::terminal
                                                      : ProgressMode::log,
                              log_seconds);
    if (with_report) {
      lash::AnalysisOptions ao;
      ao.interrupt = &g_interrupt;
      // The report covers what the run writes, as `lash report` of its folder later would.
      if (!output.channels.empty()) {
        const std::vector<lash::ChannelInfo> all = lash::channel_info(model);
        ao.channels.emplace();
        for (const std::size_t i : lash::select_channels(all, output.channels))
          ao.channels->push_back(all[i].name);
      }
      ra = lash::analyze_run(model, ao, &progress);
      result = ra.result;
    } else {
      result = lash::simulate(model, ws, progress, {}, {}, run_options);
    }
  } catch (const std::exception& e) {  // no consistent initial state
    std::cerr << loaded.located(e.what()) << "\n";
    return kExitBadInput;
  }
  for (const auto& w : result.warnings) std::cerr << loaded.located(w, "warning: ") << "\n";
  if (!result.warnings.empty()) writer->add_to_summary("warnings", result.warnings);

  // The results on disk whole first (the figures read timeseries.csv), then the report, then
  // summary.json: a folder with a summary holds everything it promises. The report covers what
  // was computed, up to a failure too (not after a signal or a write error).
  writer->close_files(result);
  std::vector<std::string> report_notes;
  bool report_failed = false;
  const auto outcome = result.status.outcome;
  if (with_report && g_interrupt.load() == 0 && writer->stop_reason().empty() &&
      (outcome == lash::RunOutcome::completed || outcome == lash::RunOutcome::failed)) {
    try {
      report_notes = lash::write_report(lash::report_data(model, ra), out_dir, &g_interrupt);
      if (g_interrupt.load() != 0) {  // during the figures: no half report beside the results
        lash::remove_report(out_dir);
        report_notes.clear();
      }
    } catch (const std::exception& e) {
      report_notes.push_back(std::string("not written: ") + e.what());
      report_failed = true;
    }
  }
  // The run ended by itself (it reached end_time, or failed) with its files written, and the
  // signal came after it, during the analyses, the report or the closing: the outcome stays the
  // run's (a completed run's folder can be reported, analysed and continued with --from), the
  // report and the verdict (which may rest on analyses cut short) are left out, and lash exits
  // as interrupted.
  const int signal_after_run =
      (outcome == lash::RunOutcome::completed || outcome == lash::RunOutcome::failed) &&
              writer->stop_reason().empty()
          ? g_interrupt.load()
          : 0;
  if (signal_after_run != 0) {
    if (with_report) lash::remove_report(out_dir);  // it may have finished just before the signal
    writer->add_to_summary(
        "interrupted_after_run",
        {{"signal", signal_after_run},
         {"message", with_report ? "a signal during the analyses or the report, after the run: "
                                   "its results are as it left them; the report and the verdict "
                                   "were not written"
                                 : "a signal as the run closed its files: its results are as it "
                                   "left them"}});
  } else if (with_report)
    writer->add_to_summary("verdict", {{"class", ra.verdict.kind},
                                       {"evidence", ra.verdict.evidence},
                                       {"rule", ra.verdict.rule}});
  lash::RunStatus status;
  try {
    try {
      status = writer->finish(result);
    } catch (const lash::IoError&) {
      // No room for the summary: the report, optional, gives way to it.
      if (!with_report || report_notes.empty() || report_failed) throw;
      lash::remove_report(out_dir);
      report_notes = {"removed: no room for summary.json beside it"};
      report_failed = true;
      status = writer->finish(result);
    }
  } catch (const std::exception& e) {  // summary.json itself
    std::cerr << "\nerror: " << e.what() << "\nthe run " << ended(result.status.outcome)
              << " at t = " << result.status.t << " s, but its summary could not be written\n";
    return kExitIo;
  }
  int code = exit_code(status.outcome);
  if (report_failed && code == kExitOk) code = kExitIo;
  const bool said_after_run = signal_after_run != 0 && (status.outcome == lash::RunOutcome::completed ||
                                                         status.outcome == lash::RunOutcome::failed);
  if (said_after_run) code = kExitInterrupted;
  auto print_notes = [&](std::ostream& os) {
    for (const auto& line : report_notes) os << "report: " << line << "\n";
  };
  switch (status.outcome) {
    case lash::RunOutcome::completed:
      if (!quiet)
        fmt::print("{}: {} outputs to {}/ in {:.3f} s ({} steps, {} rejected, {} rhs evaluations, "
                   "{} contact events; max constraint violation {:.2e})\n",
                   model.name, result.outputs, out_dir, result.wall_seconds, result.stats.steps,
                   result.stats.rejected_steps, result.stats.rhs_evaluations, result.stats.events,
                   result.max_constraint_violation);
      if (!quiet || code != kExitOk) print_notes(code == kExitOk ? std::cout : std::cerr);
      break;
    case lash::RunOutcome::interrupted:
      std::cerr << "\ninterrupted at t = " << status.t << " s; results up to that time, "
                << "summary.json and final_state.json are in " << out_dir << "/\n";
      break;
    case lash::RunOutcome::write_error:
      std::cerr << "\nerror: " << status.message << "\n";
      if (std::isnan(writer->last_row_time()))
        std::cerr << "no row of the time series reached the disk";
      else
        std::cerr << "the rows written before it (up to t = " << writer->last_row_time()
                  << " s) are whole";
      std::cerr << "; summary.json in " << out_dir << "/ says what happened\n";
      break;
    case lash::RunOutcome::failed:
      print_notes(std::cerr);
      // A message with an element opens with it ("joint 'rod_slider': ...", "load 'push': ...").
      std::cerr << "\nerror: simulation stopped at t = " << status.t << " s: " << status.message
                << "\nresults up to that time are in " << out_dir << "/\n";
      break;
  }
  if (said_after_run)
    std::cerr << "\ninterrupted by signal " << signal_after_run << " after the run, "
              << (with_report ? "during its analyses or report" : "as it closed its files")
              << ": its results in " << out_dir << "/ are as the run left them"
              << (with_report ? "; `lash report " + out_dir + "` makes the report" : "") << "\n";
  return code;
}
