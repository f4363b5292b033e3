// bench_flores: Lash on the Flores slider-crank (examples/flores_slider_crank.yaml) against a
// hand-specialized minimal-coordinate implementation of the same mechanism (the floor,
// bench/floor_slider_crank.hpp). What is measured and how to read it: bench/README.md.
//
//   bench_flores [--repeats N] [--model PATH]
//
// Every timed or memory-measured case runs in a freshly exec'd child of this executable
// (`--child MODE ...`), so each one's peak resident set is its own. The accuracy comparison
// runs in the parent. Exit status: 0 when Lash and the floor, both converged (kRefRtol), agree
// on the slider position within kMaxSliderDifference over the whole run, 1 when they do not,
// 2 on a usage or run error.
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "bench/floor_slider_crank.hpp"
#include "io/model_loader.hpp"
#include "io/results_writer.hpp"

extern char** environ;

namespace {

/// Largest tolerated |slider.x(Lash) − slider.x(floor)| at the output times, m.
constexpr double kMaxSliderDifference = 1e-5;
/// Tolerances of the reference solution used to measure each run's own error.
constexpr double kRefRtol = 1e-10, kRefAtol = 1e-13;

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Peak resident set of this process image from /proc/self/status (VmHWM), kB.
long vm_hwm_kb() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::atol(line.c_str() + 6);
  return -1;
}

long ru_maxrss_kb() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss;
}

/// Slider position and velocity at the output times.
struct Series {
  std::vector<double> t, x, vx;
  void reserve(size_t n) {
    t.reserve(n);
    x.reserve(n);
    vx.reserve(n);
  }
  void push(double tt, double xx, double vv) {
    t.push_back(tt);
    x.push_back(xx);
    vx.push_back(vv);
  }
};

size_t output_count(const lash::Model& m) {
  return static_cast<size_t>(std::ceil(m.solver.end_time / m.solver.output_interval - 1e-9)) + 1;
}

int body_index(const lash::Model& m, const std::string& name) {
  for (size_t b = 0; b < m.bodies.size(); ++b)
    if (m.bodies[b].name == name) return static_cast<int>(b);
  throw std::runtime_error("the model has no body '" + name + "'");
}

/// Keeps only the slider's x and vx (what the accuracy comparison needs).
class SliderObserver : public lash::Observer {
 public:
  SliderObserver(const lash::Model& m, Series& s) : s_(s), b_(body_index(m, "slider")) {}
  void output(double t, const Eigen::VectorXd& y, const lash::Workspace& ws) override {
    s_.push(t, y[ws.blocks[b_].offset], y[ws.nq + ws.blocks[b_].offset]);
  }

 private:
  Series& s_;
  int b_;
};

class FloorSeries : public lash::bench::FloorObserver {
 public:
  explicit FloorSeries(Series& s) : s_(s) {}
  void output(double t, const double* y) override { s_.push(t, y[1], y[3]); }

 private:
  Series& s_;
};

/// What one run reports.
struct RunFigures {
  bool ok = true;
  std::string message;
  lash::IntegratorStats stats;
  long rhs_total = 0;  ///< all right-hand-side evaluations, including those at outputs
};

RunFigures run_lash(const lash::Model& model, Series& s) {
  lash::Workspace ws(model);
  SliderObserver obs(model, s);
  const lash::RunResult r = lash::simulate(model, ws, obs);
  return {r.status.ok, r.status.message, r.stats, ws.rhs_evaluations};
}

RunFigures run_lash_csv(const lash::LoadedModel& loaded, const std::string& folder) {
  lash::Workspace ws(loaded.model);
  lash::ResultsWriter writer(loaded.model, folder, loaded.resolved_yaml);
  const lash::RunResult r = lash::simulate(loaded.model, ws, writer);
  writer.finish(r);
  return {r.status.ok, r.status.message, r.stats, ws.rhs_evaluations};
}

RunFigures run_floor(const lash::bench::FloorParams& p, Series& s) {
  FloorSeries obs(s);
  const lash::bench::FloorResult r = lash::bench::simulate_floor(p, obs);
  return {r.ok, r.message, r.stats, r.stats.rhs_evaluations};
}

// --- child: one measured case, reported as key=value on stdout ------------------------------

int child_main(const std::string& mode, int repeats, const std::string& model_path,
               const std::vector<std::string>& overrides, const std::string& folder) {
  std::vector<double> wall, load_wall;
  RunFigures fig;
  lash::LoadedModel loaded;
  for (int i = 0; i < repeats; ++i) {
    const auto t_load = Clock::now();
    loaded = lash::load_model_file(model_path, overrides);
    load_wall.push_back(seconds_since(t_load));
  }
  const lash::Model& model = loaded.model;
  const lash::bench::FloorParams params = lash::bench::floor_params_from_model(model);
  Series s;
  for (int i = 0; i < repeats; ++i) {
    s = Series{};
    s.reserve(output_count(model));
    const auto t0 = Clock::now();
    if (mode == "lash-mem")
      fig = run_lash(model, s);
    else if (mode == "lash-csv")
      fig = run_lash_csv(loaded, folder);
    else if (mode == "floor")
      fig = run_floor(params, s);
    else
      throw std::runtime_error("unknown child mode " + mode);
    wall.push_back(seconds_since(t0));
    if (!fig.ok) break;
  }
  std::printf(
      "ok=%d median_s=%.9g min_s=%.9g load_s=%.9g steps=%ld rejected=%ld rhs=%ld rhs_total=%ld "
      "events=%ld maxrss_kb=%ld hwm_kb=%ld end_time=%.9g\n",
      fig.ok ? 1 : 0, median(wall), *std::min_element(wall.begin(), wall.end()),
      median(load_wall), fig.stats.steps, fig.stats.rejected_steps, fig.stats.rhs_evaluations,
      fig.rhs_total, fig.stats.events, ru_maxrss_kb(), vm_hwm_kb(), model.solver.end_time);
  if (!fig.ok) std::fprintf(stderr, "%s run failed: %s\n", mode.c_str(), fig.message.c_str());
  return fig.ok ? 0 : 1;
}

// --- parent ---------------------------------------------------------------------------------

using Figures = std::map<std::string, double>;

std::string self_path() {
  return std::filesystem::read_symlink("/proc/self/exe").string();
}

/// Runs `bench_flores --child ARGS...` and parses its key=value line.
Figures spawn_child(const std::vector<std::string>& args) {
  int fd[2];
  if (pipe(fd) != 0) throw std::runtime_error("pipe failed");
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_adddup2(&fa, fd[1], STDOUT_FILENO);
  posix_spawn_file_actions_addclose(&fa, fd[0]);
  posix_spawn_file_actions_addclose(&fa, fd[1]);
  const std::string exe = self_path();
  std::vector<std::string> all{exe, "--child"};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid;
  const int rc = posix_spawn(&pid, exe.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  close(fd[1]);
  if (rc != 0) {
    close(fd[0]);
    throw std::runtime_error(std::string("posix_spawn failed: ") + std::strerror(rc));
  }
  std::string out;
  char buf[4096];
  for (ssize_t n; (n = read(fd[0], buf, sizeof buf)) > 0;) out.append(buf, n);
  close(fd[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  Figures f;
  std::istringstream in(out);
  for (std::string kv; in >> kv;) {
    const auto eq = kv.find('=');
    if (eq != std::string::npos) f[kv.substr(0, eq)] = std::atof(kv.c_str() + eq + 1);
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || f.count("ok") == 0)
    throw std::runtime_error("child '" + args[0] + "' failed (output: " + out + ")");
  return f;
}

/// Max |a − b| over the common output times with t ≤ t_max.
struct Diff {
  double x = 0.0, vx = 0.0;
};
Diff max_diff(const Series& a, const Series& b, double t_max) {
  Diff d;
  const size_t n = std::min(a.t.size(), b.t.size());
  for (size_t i = 0; i < n && a.t[i] <= t_max + 1e-12; ++i) {
    d.x = std::max(d.x, std::abs(a.x[i] - b.x[i]));
    d.vx = std::max(d.vx, std::abs(a.vx[i] - b.vx[i]));
  }
  return d;
}

void print_row(const char* name, const Figures& f) {
  std::printf("  %-34s %10.3f %10.3f %8.0f %9.0f %10.0f %10.0f %7.0f %10.1f %10.1f\n", name,
              1e3 * f.at("median_s"), 1e3 * f.at("min_s"), f.at("steps"), f.at("rejected"),
              f.at("rhs"), f.at("rhs_total"), f.at("events"), f.at("hwm_kb") / 1024.0,
              f.at("maxrss_kb") / 1024.0);
}

/// Tolerance override pair for load_model_file.
std::vector<std::string> tolerance_overrides(double rtol, double atol) {
  char r[64], a[64];
  std::snprintf(r, sizeof r, "solver.rtol=%.17g", rtol);
  std::snprintf(a, sizeof a, "solver.atol=%.17g", atol);
  return {r, a};
}

/// Shortest wall time of `repeats` calls of f (in this process), s: the least disturbed by
/// other work on the machine.
template <class F>
double timed_min(int repeats, F&& f) {
  double best = 1e300;
  for (int i = 0; i < repeats; ++i) {
    const auto t0 = Clock::now();
    f();
    best = std::min(best, seconds_since(t0));
  }
  return best;
}

/// One row of the work–precision table: a formulation at one tolerance.
struct WorkPoint {
  double rtol = 0.0, atol = 0.0, seconds = 0.0;
  RunFigures fig;
  Diff err, err_rev;  ///< against the reference: whole run, first revolution
};

/// Errors within this factor count as equal accuracy (the saturated errors of two diverged
/// trajectories differ by noise, not by accuracy).
constexpr double kEqualAccuracyBand = 1.1;

int parent_main(int repeats, const std::string& model_path) {
  const lash::LoadedModel loaded = lash::load_model_file(model_path);
  const lash::Model& model = loaded.model;
  const lash::bench::FloorParams params = lash::bench::floor_params_from_model(model);
  const double t_end = model.solver.end_time, rtol0 = model.solver.rtol;
  const double atol_per_rtol = model.solver.atol / rtol0;
  const double t_rev = 2.0 * M_PI / std::abs(params.crank_speed);
  auto floor_at = [&](double rtol) {
    lash::bench::FloorParams q = params;
    q.rtol = rtol;
    q.atol = rtol * atol_per_rtol;
    return q;
  };

  // --- accuracy and work–precision, in this process ----------------------------------------
  // Reference: the floor at tight tolerances. Physics check: Lash at the same tolerances.
  Series s_ref, s_lash_tight;
  lash::bench::FloorParams ref_params = params;
  ref_params.rtol = kRefRtol;
  ref_params.atol = kRefAtol;
  const RunFigures r_ref = run_floor(ref_params, s_ref);
  const lash::LoadedModel tight =
      lash::load_model_file(model_path, tolerance_overrides(kRefRtol, kRefAtol));
  const RunFigures r_lash_tight = run_lash(tight.model, s_lash_tight);
  if (!r_ref.ok || !r_lash_tight.ok) {
    std::fprintf(stderr, "a reference run failed: %s %s\n", r_ref.message.c_str(),
                 r_lash_tight.message.c_str());
    return 2;
  }

  // Both formulations over a range of tolerances (atol/rtol at the model's ratio).
  const int wp_repeats = std::max(5, repeats / 2);  // the sweep runs 20 cases
  const std::vector<double> rtols{1e-6, 5e-7, 2e-7, 1e-7, 5e-8, 2e-8, 1e-8, 5e-9, 2e-9, 1e-9};
  std::vector<WorkPoint> wp_lash, wp_floor;
  Series s_lash, s_floor;  // at the model's own tolerances
  for (double r : rtols) {
    const lash::LoadedModel lm =
        lash::load_model_file(model_path, tolerance_overrides(r, r * atol_per_rtol));
    const lash::bench::FloorParams fp = floor_at(r);
    WorkPoint wl, wf;
    wl.rtol = wf.rtol = r;
    wl.atol = wf.atol = r * atol_per_rtol;
    Series sl, sf;
    sl.reserve(output_count(model));
    sf.reserve(output_count(model));
    wl.fig = run_lash(lm.model, sl);
    wf.fig = run_floor(fp, sf);
    if (!wl.fig.ok || !wf.fig.ok) {
      std::fprintf(stderr, "run at rtol %g failed: %s %s\n", r, wl.fig.message.c_str(),
                   wf.fig.message.c_str());
      return 2;
    }
    wl.err = max_diff(sl, s_ref, t_end);
    wl.err_rev = max_diff(sl, s_ref, t_rev);
    wf.err = max_diff(sf, s_ref, t_end);
    wf.err_rev = max_diff(sf, s_ref, t_rev);
    Series scratch;
    wl.seconds = timed_min(wp_repeats, [&] {
      scratch = Series{};
      scratch.reserve(output_count(model));
      run_lash(lm.model, scratch);
    });
    wf.seconds = timed_min(wp_repeats, [&] {
      scratch = Series{};
      scratch.reserve(output_count(model));
      run_floor(fp, scratch);
    });
    if (r == rtol0) s_lash = sl, s_floor = sf;
    wp_lash.push_back(wl);
    wp_floor.push_back(wf);
  }
  if (s_lash.t.empty()) {
    std::fprintf(stderr, "the model's rtol %g is not in the sweep\n", rtol0);
    return 2;
  }
  // For each Lash point: the floor point at least as accurate (within the band) with the
  // fewest rhs evaluations (a deterministic choice; the ratio then uses the measured times).
  auto cheapest_floor = [&](const WorkPoint& l) {
    int best = -1;
    for (size_t i = 0; i < wp_floor.size(); ++i) {
      const WorkPoint& f = wp_floor[i];
      if (f.err.x <= kEqualAccuracyBand * l.err.x && f.err.vx <= kEqualAccuracyBand * l.err.vx &&
          (best < 0 || f.fig.stats.rhs_evaluations < wp_floor[best].fig.stats.rhs_evaluations))
        best = static_cast<int>(i);
    }
    return best;
  };
  int i0 = 0;
  while (wp_lash[i0].rtol != rtol0) ++i0;
  const int eq0 = cheapest_floor(wp_lash[i0]);

  // --- timings and memory at the model's tolerances, each case in a fresh process -----------
  std::string tmpl = (std::filesystem::temp_directory_path() / "lash_bench_XXXXXX").string();
  if (!mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
  const std::string tmp = tmpl;
  struct RemoveOnExit {
    std::string path;
    ~RemoveOnExit() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  } remove_tmp{tmp};
  const std::string rep = std::to_string(repeats);
  const Figures lash_mem = spawn_child({"lash-mem", rep, model_path, tmp + "/mem"});
  const Figures lash_csv = spawn_child({"lash-csv", rep, model_path, tmp + "/csv"});
  const Figures floor = spawn_child({"floor", rep, model_path, tmp + "/floor"});
  Figures floor_eq = floor;
  if (eq0 >= 0 && wp_floor[eq0].rtol != rtol0) {
    std::vector<std::string> args{"floor", rep, model_path, tmp + "/floor"};
    for (const auto& o : tolerance_overrides(wp_floor[eq0].rtol, wp_floor[eq0].atol))
      args.push_back(o);
    floor_eq = spawn_child(args);
  }
  const Figures flat_1 =
      spawn_child({"lash-csv", "1", model_path, tmp + "/flat1", "solver.end_time=0.024"});
  const Figures flat_10 =
      spawn_child({"lash-csv", "1", model_path, tmp + "/flat10", "solver.end_time=0.24"});
  const auto csv_bytes_1 = std::filesystem::file_size(tmp + "/flat1/timeseries.csv");
  const auto csv_bytes_10 = std::filesystem::file_size(tmp + "/flat10/timeseries.csv");

  // --- report ---------------------------------------------------------------------------------
  std::printf("Flores slider-crank (%s): end_time %.4g s (%.3g crank revolutions), "
              "rtol %.0e, atol %.0e, DOPRI5, outputs every %.0e s\n",
              model_path.c_str(), t_end, t_end / t_rev, rtol0, model.solver.atol,
              model.solver.output_interval);
  std::printf("\n1. At the model's tolerances: median (and min) of %d repeats, each case in its "
              "own process.\n   rhs: evaluations by the integrator; rhs total adds Lash's "
              "evaluations at the outputs.\n\n",
              repeats);
  std::printf("  %-34s %10s %10s %8s %9s %10s %10s %7s %10s %10s\n", "case", "median ms",
              "min ms", "steps", "rejected", "rhs", "rhs total", "events", "VmHWM MiB",
              "maxrss MiB");
  print_row("Lash, slider-only observer", lash_mem);
  print_row("Lash, ResultsWriter CSV", lash_csv);
  print_row("floor, minimal coordinates", floor);
  if (eq0 >= 0 && wp_floor[eq0].rtol != rtol0) {
    char name[64];
    std::snprintf(name, sizeof name, "floor at rtol %.0e (equal acc.)", wp_floor[eq0].rtol);
    print_row(name, floor_eq);
  }
  std::printf("\n  Lash / floor wall time (target <= 2x at equal accuracy): %.2fx with the "
              "slider-only observer, %.2fx writing CSV results\n  (ratios of the minima: "
              "%.2fx, %.2fx)\n",
              lash_mem.at("median_s") / floor_eq.at("median_s"),
              lash_csv.at("median_s") / floor_eq.at("median_s"),
              lash_mem.at("min_s") / floor_eq.at("min_s"),
              lash_csv.at("min_s") / floor_eq.at("min_s"));
  std::printf("  time per rhs evaluation (median wall / rhs total): Lash %.3f us, floor %.3f us "
              "(%.1fx)\n",
              1e6 * lash_mem.at("median_s") / lash_mem.at("rhs_total"),
              1e6 * floor.at("median_s") / floor.at("rhs_total"),
              (lash_mem.at("median_s") / lash_mem.at("rhs_total")) /
                  (floor.at("median_s") / floor.at("rhs_total")));
  std::printf("  model loading (YAML, not in the times above): median %.3f ms\n",
              1e3 * lash_mem.at("load_s"));

  std::printf("\n2. Memory flatness: Lash writing CSV results, one run per process.\n\n");
  print_row("end_time 0.024 s", flat_1);
  print_row("end_time 0.24 s", flat_10);
  std::printf("\n  peak RSS (VmHWM) change for 10x the duration: %+.2f MiB; timeseries.csv "
              "%.1f MiB -> %.1f MiB\n",
              (flat_10.at("hwm_kb") - flat_1.at("hwm_kb")) / 1024.0, csv_bytes_1 / 1048576.0,
              csv_bytes_10 / 1048576.0);

  std::printf("\n3. Work-precision (in this process, min of %d repeats). Error: max |x - "
              "x_ref| (m) and |vx - vx_ref| (m/s)\n   at the %zu output times against the "
              "floor at rtol %.0e, atol %.0e. Equal accuracy: the floor run whose\n   "
              "errors are within %.1fx of Lash's, with the fewest rhs evaluations.\n\n",
              wp_repeats, s_ref.t.size(), kRefRtol, kRefAtol, kEqualAccuracyBand);
  std::printf("  %7s | %8s %7s %6s %10s %9s | %8s %7s %6s %10s %9s | %13s %8s\n", "rtol",
              "Lash ms", "rhs", "events", "x error", "vx error", "floor ms", "rhs", "events",
              "x error", "vx error", "floor at eq.", "ratio");
  for (size_t i = 0; i < rtols.size(); ++i) {
    const WorkPoint &l = wp_lash[i], &f = wp_floor[i];
    const int e = cheapest_floor(l);
    char eq_s[32] = "none", ratio_s[32] = "-";
    if (e >= 0) {
      std::snprintf(eq_s, sizeof eq_s, "rtol %.0e", wp_floor[e].rtol);
      std::snprintf(ratio_s, sizeof ratio_s, "%.2fx", l.seconds / wp_floor[e].seconds);
    }
    std::printf("  %7.0e | %8.3f %7ld %6ld %10.3e %9.3e | %8.3f %7ld %6ld %10.3e %9.3e | %13s "
                "%8s\n",
                l.rtol, 1e3 * l.seconds, l.fig.stats.rhs_evaluations, l.fig.stats.events, l.err.x,
                l.err.vx, 1e3 * f.seconds, f.fig.stats.rhs_evaluations, f.fig.stats.events,
                f.err.x, f.err.vx, eq_s, ratio_s);
  }

  const Diff d_all = max_diff(s_lash, s_floor, t_end), d_rev = max_diff(s_lash, s_floor, t_rev);
  const Diff d_tight = max_diff(s_lash_tight, s_ref, t_end);
  const Diff d_tight_rev = max_diff(s_lash_tight, s_ref, t_rev);
  double t_split = -1.0;
  for (size_t i = 0; i < s_lash.t.size() && i < s_floor.t.size(); ++i)
    if (std::abs(s_lash.x[i] - s_floor.x[i]) > kMaxSliderDifference) {
      t_split = s_lash.t[i];
      break;
    }
  std::printf("\n4. Lash against the floor (max abs difference; x in m, vx in m/s; 1st rev: "
              "t <= %.4f s)\n\n",
              t_rev);
  std::printf("  %-40s %11s %11s %11s %11s %7s\n", "", "x, all", "vx, all", "x, 1st rev",
              "vx, 1st rev", "events");
  std::printf("  %-40s %11.3e %11.3e %11.3e %11.3e %3ld/%ld\n", "both at the model's tolerances",
              d_all.x, d_all.vx, d_rev.x, d_rev.vx, wp_lash[i0].fig.stats.events,
              wp_floor[i0].fig.stats.events);
  char both_tight[64];
  std::snprintf(both_tight, sizeof both_tight, "both at rtol %.0e, atol %.0e", kRefRtol, kRefAtol);
  std::printf("  %-40s %11.3e %11.3e %11.3e %11.3e %3ld/%ld\n", both_tight, d_tight.x, d_tight.vx,
              d_tight_rev.x, d_tight_rev.vx, r_lash_tight.stats.events, r_ref.stats.events);
  std::printf("  %-40s %11.3e %11.3e %11.3e %11.3e %7ld\n", "Lash at the model's tol. - reference",
              wp_lash[i0].err.x, wp_lash[i0].err.vx, wp_lash[i0].err_rev.x,
              wp_lash[i0].err_rev.vx, wp_lash[i0].fig.stats.events);
  std::printf("  %-40s %11.3e %11.3e %11.3e %11.3e %7ld\n", "floor at the model's tol. - reference",
              wp_floor[i0].err.x, wp_floor[i0].err.vx, wp_floor[i0].err_rev.x,
              wp_floor[i0].err_rev.vx, wp_floor[i0].fig.stats.events);
  if (t_split >= 0)
    std::printf("  at the model's tolerances |dx| first exceeds %.0e m at t = %.5f s\n",
                kMaxSliderDifference, t_split);

  // Gate: identical physics. Both formulations converged (reference tolerances) must give the
  // same slider motion over the whole run. At the model's own tolerances the two trajectories
  // carry different integration errors, which the impacts amplify (bench/README.md).
  const bool same_physics = d_tight.x <= kMaxSliderDifference;
  std::printf("\nCheck: |slider.x(Lash) - slider.x(floor)| <= %.0e m over the whole run with "
              "both converged (rtol %.0e): %.3e m, %s\n",
              kMaxSliderDifference, kRefRtol, d_tight.x, same_physics ? "ok" : "FAILED");
  return same_physics ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::vector<std::string> args(argv + 1, argv + argc);
    if (!args.empty() && args[0] == "--child") {
      // --child MODE REPEATS MODEL FOLDER [OVERRIDE...]
      if (args.size() < 5) return 2;
      const std::vector<std::string> overrides(args.begin() + 5, args.end());
      return child_main(args[1], std::stoi(args[2]), args[3], overrides, args[4]);
    }
    int repeats = 31;
    std::string model_path = LASH_SOURCE_DIR "/examples/flores_slider_crank.yaml";
    for (size_t i = 0; i < args.size(); ++i) {
      if (args[i] == "--repeats" && i + 1 < args.size()) {
        repeats = std::max(1, std::stoi(args[++i]));
      } else if (args[i] == "--model" && i + 1 < args.size()) {
        model_path = args[++i];
      } else {
        std::fprintf(stderr, "usage: bench_flores [--repeats N] [--model PATH]\n");
        return 2;
      }
    }
    return parent_main(repeats, model_path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_flores: %s\n", e.what());
    return 2;
  }
}
