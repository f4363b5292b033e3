// Cost of the variational Lyapunov spectrum (study/variational_lyapunov.hpp) against the plain
// run on the Flores example: both integrate the same 20 crank revolutions from the same state
// (the state after one revolution, as the analysis starts), the plain run with no observer, the
// variational estimate with its tangent vectors riding on every accepted step. Also the
// two-trajectory estimate at two separations, for comparison. Prints the minimum over repeats.
//   bench_lyapunov [revolutions=20] [repeats=3]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "core/simulate.hpp"
#include "io/model_loader.hpp"
#include "study/run_analysis.hpp"
#include "study/variational_lyapunov.hpp"

namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

int main(int argc, char** argv) {
  const int revolutions = argc > 1 ? std::atoi(argv[1]) : 20;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 3;
  lash::Model model =
      lash::load_model_file(LASH_SOURCE_DIR "/examples/flores_slider_crank.yaml").model;
  const double period = 2 * M_PI / std::abs(model.drivers[0].speed);
  // The start: the state after one revolution (the transient the analyses discard).
  lash::Workspace ws(model);
  lash::Simulator sim(model, ws);
  sim.start(0.0, lash::initial_state(model, ws));
  if (!sim.advance_to(period, nullptr)) return std::puts(sim.status().message.c_str()), 1;
  const Eigen::VectorXd y0 = sim.state();
  const double interval = period / 20, t_end = period * (1 + revolutions);
  const int intervals = 20 * revolutions;

  double plain = 1e300, variational = 1e300;
  long plain_rhs = 0;
  lash::LyapunovEstimate v;
  for (int r = 0; r < repeats; ++r) {
    lash::Workspace w(model);
    lash::Simulator s(model, w);
    auto t0 = std::chrono::steady_clock::now();
    s.start(period, y0);
    if (!s.advance_to(t_end, nullptr)) return std::puts(s.status().message.c_str()), 1;
    plain = std::min(plain, seconds_since(t0));
    plain_rhs = w.rhs_evaluations;
    t0 = std::chrono::steady_clock::now();
    v = lash::variational_lyapunov(model, y0, period, interval, intervals, period / (2 * M_PI),
                                   nullptr);
    variational = std::min(variational, seconds_since(t0));
  }
  if (!v.ok) return std::printf("variational estimate failed: %s\n", v.message.c_str()), 1;
  std::printf("Flores example, %d revolutions from t = %.4g s (%d renormalisations)\n",
              revolutions, period, v.renormalisations);
  std::printf("plain run                 %8.3f s   (%ld right-hand sides)\n", plain, plain_rhs);
  std::printf("variational spectrum      %8.3f s   = %.2f x the plain run\n", variational,
              variational / plain);
  std::printf("  spectrum (1/s):");
  for (double l : v.spectrum) std::printf(" %.5g", l);
  std::printf("\n  contact events mapped by saltation matrices: %d (unmapped %d)\n",
              v.events_mapped, v.events_unmapped);
  // The forward differences' perturbation length should not matter (kTangentStep = 1e-9).
  for (double step : {1e-8, 1e-10}) {
    const lash::LyapunovEstimate w = lash::variational_lyapunov(
        model, y0, period, interval, intervals, period / (2 * M_PI), nullptr, step);
    std::printf("  with forward-difference step %g:", step);
    for (double l : w.spectrum) std::printf(" %.5g", l);
    std::printf("\n");
  }
  for (double d0 : {1e-8, 1e-7, 1e-6}) {
    lash::AnalysisOptions o;
    const auto t0 = std::chrono::steady_clock::now();
    // The two-trajectory estimate over the same span (analyze_run's method, as a cross-check).
    lash::Model m = model;
    m.solver.end_time = t_end;
    o.ideal_twin = false;
    o.lyapunov_method = "two-trajectory";
    o.lyapunov_d0 = d0;
    o.display_points = 10;
    o.frames = 2;
    const lash::RunAnalysis a = lash::analyze_run(m, o);
    std::printf("two-trajectory, d0 = %-6g %8.3f s (whole analysis)   largest %.5g 1/s\n", d0,
                seconds_since(t0), a.lyapunov ? a.lyapunov->exponent : std::nan(""));
  }
  return 0;
}
