// bench_whole: whole-process wall time of `lash run` on the Flores example against the
// hand-written floor program (floor_flores), both writing their CSV. What it measures and the
// results: bench/README.md, "Whole process".
//
//   bench_whole [--repeats N] [--model PATH] [--lash PATH] [--also NAME=PATH ...]
//
// Every case is a fresh process (posix_spawn, then waitpid), its stdout and stderr to /dev/null;
// the cases take turns within each repeat, so a slow spell of a shared machine falls on all of
// them alike. Reported: median and minimum wall time per case and their ratios to the floor's.
// --also adds the `lash` cases once more for another binary (e.g. a dynamically linked build),
// under NAME. Exit status 0, or 2 on a usage error or a case that failed.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bench/floor_slider_crank.hpp"
#include "io/model_loader.hpp"

extern char** environ;

namespace {

struct Case {
  Case(std::string n, std::vector<std::string> a, int status = 0)
      : name(std::move(n)), argv(std::move(a)), expected_status(status) {}
  std::string name;
  std::vector<std::string> argv;
  int expected_status = 0;
  std::vector<double> ms;
};

/// Wall time of one process, ms; throws if it does not exit with `expected`.
double time_process(const Case& c) {
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  std::vector<std::string> args = c.argv;
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const auto t0 = std::chrono::steady_clock::now();
  pid_t pid;
  const int rc = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw std::runtime_error(c.name + ": cannot start " + args[0] + ": " + std::strerror(rc));
  int status = 0;
  waitpid(pid, &status, 0);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!WIFEXITED(status) || WEXITSTATUS(status) != c.expected_status)
    throw std::runtime_error(c.name + ": exit status " + std::to_string(WEXITSTATUS(status)) +
                             ", expected " + std::to_string(c.expected_status));
  return ms;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string number(double v) {
  char s[40];
  std::snprintf(s, sizeof s, "%.17g", v);
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  int repeats = 21;
  std::string model_path = LASH_SOURCE_DIR "/examples/flores_slider_crank.yaml";
  std::string lash = LASH_BINARY;
  std::vector<std::pair<std::string, std::string>> also;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--repeats" && i + 1 < argc) repeats = std::max(1, std::atoi(argv[++i]));
    else if (a == "--model" && i + 1 < argc) model_path = argv[++i];
    else if (a == "--lash" && i + 1 < argc) lash = argv[++i];
    else if (a == "--also" && i + 1 < argc && std::strchr(argv[i + 1], '=')) {
      const std::string v = argv[++i];
      also.push_back({v.substr(0, v.find('=')), v.substr(v.find('=') + 1)});
    } else {
      std::fprintf(stderr,
                   "usage: bench_whole [--repeats N] [--model PATH] [--lash PATH] "
                   "[--also NAME=PATH ...]\n");
      return 2;
    }
  }
  try {
    const lash::Model model = lash::load_model_file(model_path, {}).model;
    const lash::bench::FloorParams p = lash::bench::floor_params_from_model(model);
    const std::string floor = FLOOR_BINARY;
    const std::string tmp =
        (std::filesystem::temp_directory_path() / ("bench_whole_" + std::to_string(getpid())))
            .string();
    std::filesystem::create_directories(tmp);

    std::vector<std::string> floor_argv = {floor, tmp + "/floor.csv"};
    for (double v : {p.crank_length, p.crank_speed, p.crank_angle0, p.rod_length, p.rod_mass,
                     p.rod_inertia, p.slider_mass, p.gx, p.gy, p.clearance, p.journal_radius,
                     p.stiffness, p.restitution, p.min_impact_velocity, p.rtol, p.atol,
                     p.end_time, p.output_interval})
      floor_argv.push_back(number(v));
    // The floor's 12 columns, by their Lash names (floor_flores.cpp).
    const std::string floor_channels =
        "rod.phi,rod.omega,rod.alpha,slider.x,slider.vx,slider.ax,rod_slider.ex,rod_slider.ey,"
        "rod_slider.e,rod_slider.delta,rod_slider.delta_dot,rod_slider.Fn";

    std::vector<Case> cases;
    cases.push_back({"floor_flores, 12 columns", floor_argv});
    cases.push_back({"floor_flores start-up only (usage error)", {floor}, 2});
    std::vector<std::pair<std::string, std::string>> binaries = {{"lash", lash}};
    binaries.insert(binaries.end(), also.begin(), also.end());
    for (const auto& [name, exe] : binaries) {
      const std::string out = tmp + "/" + name;
      auto run = [&](std::vector<std::string> extra) {
        std::vector<std::string> v = {exe, "run", model_path, "-q", "-o", out};
        v.insert(v.end(), extra.begin(), extra.end());
        return v;
      };
      cases.push_back({name + " run, all channels (CSV)", run({})});
      cases.push_back({name + " run, the floor's 12 channels (CSV)", run({"--channels", floor_channels})});
      cases.push_back({name + " run, all channels (HDF5)", run({"--format", "hdf5"})});
      cases.push_back({name + " --version (start-up only)", {exe, "--version"}});
    }
    // Warm the page cache (not timed); a case this binary cannot run (an option it lacks, a
    // build without HDF5) is left out and said so. The floor must run.
    std::vector<Case> runnable;
    for (Case& c : cases) {
      try {
        time_process(c);
        runnable.push_back(c);
      } catch (const std::exception& e) {
        if (runnable.empty()) throw;
        std::printf("left out: %s\n", e.what());
      }
    }
    cases = runnable;
    for (int r = 0; r < repeats; ++r)
      for (Case& c : cases) c.ms.push_back(time_process(c));
    std::filesystem::remove_all(tmp);

    const double floor_med = median(cases[0].ms);
    const double floor_min = *std::min_element(cases[0].ms.begin(), cases[0].ms.end());
    std::printf("Whole process, %s, %d repeats per case (cases interleaved)\n\n",
                model_path.c_str(), repeats);
    std::printf("| case | median ms | min ms | median / floor | min / floor |\n");
    std::printf("|---|---:|---:|---:|---:|\n");
    for (const Case& c : cases) {
      const double med = median(c.ms), mn = *std::min_element(c.ms.begin(), c.ms.end());
      std::printf("| %s | %.2f | %.2f | %.2fx | %.2fx |\n", c.name.c_str(), med, mn,
                  med / floor_med, mn / floor_min);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_whole: %s\n", e.what());
    return 2;
  }
  return 0;
}
