// lash: the command-line front end. `lash run MODEL -o OUT` simulates; `lash check MODEL`
// validates. Exit codes: 0 success, 1 numerical failure or I/O error, 2 bad model or options.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <iostream>

#include "io/model_loader.hpp"
#include "io/results_writer.hpp"

namespace {

/// Forwards to the results writer and shows progress on a terminal.
class ProgressObserver : public lash::Observer {
 public:
  ProgressObserver(lash::ResultsWriter& w, bool show) : w_(w), show_(show) {}
  void output(double t, const Eigen::VectorXd& y, const lash::Workspace& ws) override {
    w_.output(t, y, ws);
    rhs_ = ws.rhs_evaluations;
  }
  void event(const lash::ContactEvent& e, const lash::Workspace& ws) override { w_.event(e, ws); }
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
  lash::ResultsWriter& w_;
  bool show_;
  long rhs_ = 0;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_{};
};

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

  auto* check = app.add_subcommand("check", "Validate a model: list every problem with file:line:column");
  check->add_option("model", model_path, "Model file (YAML)")->required()->check(CLI::ExistingFile);
  check->add_option("--set", overrides, "Override a model value, KEY.PATH=VALUE, repeatable")
      ->take_all();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
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
              << model.loads.size() << " loads\n";
    return 0;
  }

  if (out_dir.empty())
    out_dir = "out/" + std::filesystem::path(model_path).stem().string();
  try {
    lash::Workspace ws(model);
    lash::ResultsWriter writer(model, out_dir);
    ProgressObserver observer(writer, !quiet && isatty(STDERR_FILENO));
    lash::RunResult result;
    try {
      result = lash::simulate(model, ws, observer);
    } catch (const std::runtime_error& e) {  // no consistent initial state
      std::cerr << model_path << ": " << e.what() << "\n";
      return 2;
    }
    writer.finish(result, loaded.resolved_yaml, overrides);
    if (!result.status.ok) {
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
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
