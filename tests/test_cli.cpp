// The lash command as a user runs it: exit codes, messages, output files.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "io/files.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace {

struct Result {
  int code;
  std::string out;
};

/// Runs a shell command with stdout and stderr captured together.
Result run_lash_raw(const std::string& command) {
  const std::string cmd = command + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  char buf[4096];
  while (size_t n = fread(buf, 1, sizeof buf, p)) out.append(buf, n);
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

/// Runs `lash ARGS`.
Result run_lash(const std::string& args) { return run_lash_raw(std::string(LASH_BINARY) + " " + args); }

std::string example() { return lash::test::example_path("flores_slider_crank.yaml"); }

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("lash_cli_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(d);
  return d;
}

size_t line_count(const fs::path& p) {
  std::ifstream in(p);
  size_t n = 0;
  for (std::string l; std::getline(in, l);) ++n;
  return n;
}

/// Every row of a CSV has the header's number of fields (no row cut by a failure).
/// Every row of `csv` is whole. With `last_may_be_cut` (after kill -9) the last row may end
/// short: a write(2) of a buffer of rows can stop between pages when a fatal signal arrives, and
/// nothing in the process runs after SIGKILL to finish it; every row before it is whole.
void expect_whole_rows(const fs::path& csv, bool last_may_be_cut = false) {
  std::ifstream in(csv);
  std::string header, line;
  ASSERT_TRUE(std::getline(in, header)) << csv;
  const auto fields = std::count(header.begin(), header.end(), ',');
  std::vector<std::string> rows;
  while (std::getline(in, line)) rows.push_back(line);
  for (size_t n = 0; n < rows.size(); ++n) {
    if (last_may_be_cut && n + 1 == rows.size()) break;
    ASSERT_EQ(std::count(rows[n].begin(), rows[n].end(), ','), fields)
        << csv << " row " << n + 1 << ": " << rows[n];
  }
  if (last_may_be_cut) return;
  in.clear();
  in.seekg(-1, std::ios::end);
  char last = 0;
  in.get(last);
  EXPECT_EQ(last, '\n') << csv << " ends mid-row";
}

nlohmann::json read_summary(const fs::path& dir) {
  return nlohmann::json::parse(std::ifstream(dir / "summary.json"));
}


}  // namespace

TEST(Cli, HelpExplainsTheOptions) {
  Result r = run_lash("--help");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("run"), std::string::npos);
  EXPECT_NE(r.out.find("check"), std::string::npos);
  r = run_lash("run --help");
  EXPECT_EQ(r.code, 0);
  for (const char* opt : {"--output", "--set", "--quiet"})
    EXPECT_NE(r.out.find(opt), std::string::npos) << opt;
}

TEST(Cli, CheckAcceptsTheExamples) {
  const Result r = run_lash("check " + example());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("ok: 3 bodies, 4 joints (1 with clearance)"), std::string::npos) << r.out;
  // Every example in the folder.
  int n = 0;
  for (const auto& entry : fs::directory_iterator(lash::test::example_path("")))
    if (entry.path().extension() == ".yaml") {
      const Result each = run_lash("check " + entry.path().string());
      EXPECT_EQ(each.code, 0) << entry.path() << "\n" << each.out;
      ++n;
    }
  EXPECT_GE(n, 5);
  const Result tmd = run_lash("check " + lash::test::example_path("tmd_slider_crank.yaml"));
  EXPECT_NE(tmd.out.find("ok: 4 bodies, 4 joints (1 with clearance), 1 driver, 1 load"),
            std::string::npos) << tmd.out;
}

TEST(Cli, ModesAtTheStaticEquilibriumSaysWhereItLies) {
  const fs::path dir = temp_dir("modes_eq");
  fs::create_directories(dir);
  const std::string hanging =
      "gravity: [0, -9.81]\nground: {markers: {A: [0, 0]}}\n"
      "bodies: {block: {mass: 2.0, inertia: 0.01, position: [0, -0.3]}}\n"
      "joints: {guide: {type: translational, guide: ground.A, slider: block, axis: [0, 1]}}\n"
      "loads: {spring: {type: spring_damper, from: ground.A, to: block, stiffness: 800, "
      "free_length: 0.3}}\nsolver: {end_time: 1}\n";
  std::ofstream(dir / "hanging.yaml") << hanging;
  const Result r = run_lash("modes " + (dir / "hanging.yaml").string() + " --equilibrium");
  EXPECT_EQ(r.code, 0) << r.out;
  for (const char* text : {"the static equilibrium nearest the initial configuration",
                           "largest move 0.0245 m (block.y)",
                           "linearised at its static equilibrium", "3.18"})
    EXPECT_NE(r.out.find(text), std::string::npos) << text << "\n" << r.out;
  // Without the spring there is none: exit 2, the file named.
  std::ofstream(dir / "falling.yaml") << hanging.substr(0, hanging.find("loads:")) << "solver: {end_time: 1}\n";
  const Result none = run_lash("modes " + (dir / "falling.yaml").string() + " --equilibrium");
  EXPECT_EQ(none.code, 2) << none.out;
  EXPECT_NE(none.out.find("falling.yaml: no static equilibrium found"), std::string::npos) << none.out;
  fs::remove_all(dir);
}

TEST(Cli, ModesPrintsAFlexibleLinksFrequenciesBesideTheClosedForms) {
  const Result r =
      run_lash("modes " + lash::test::example_path("flores_slider_crank_flexible_rod.yaml") +
               " --count 3");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("body 'rod': flexible link, 0.12 m, 4 elements"), std::string::npos)
      << r.out;
  // The first clamped–free bending mode: 1.8751² √(EI/(ρA L⁴)) = 1154.88 Hz (EI = 1545.6 N·m²,
  // ρA = 1.75 kg/m, L = 0.12 m); 4 cubic elements are within 1e-4 of it.
  const size_t at = r.out.find("       1  bending");
  ASSERT_NE(at, std::string::npos) << r.out;
  std::istringstream row(r.out.substr(at));
  int index = 0;
  std::string kind;
  double mesh = 0, closed = 0;
  row >> index >> kind >> mesh >> closed;
  EXPECT_NEAR(closed, 1154.88, 0.01);
  EXPECT_NEAR(mesh / closed, 1.0, 1e-4);
  // A model without flexible links says so; the mechanism's own modes follow (the Flores
  // slider-crank's crank driver holds its one degree of freedom).
  const Result none = run_lash("modes " + example());
  EXPECT_EQ(none.code, 0);
  EXPECT_NE(none.out.find("no flexible links"), std::string::npos);
  EXPECT_NE(none.out.find("the mechanism, linearised at its initial configuration"),
            std::string::npos) << none.out;
  EXPECT_NE(none.out.find("0 degrees of freedom"), std::string::npos) << none.out;
  // The tuned-mass absorber example: its two absorbers' modes, damped.
  const Result tmd = run_lash("modes " + lash::test::example_path("tmd_slider_crank.yaml"));
  EXPECT_EQ(tmd.code, 0) << tmd.out;
  EXPECT_NE(tmd.out.find("2 degrees of freedom"), std::string::npos) << tmd.out;
  EXPECT_NE(tmd.out.find("damping ratio"), std::string::npos) << tmd.out;
}

TEST(Cli, CheckListsProblemsWithFileLineColumnAndExitsTwo) {
  const fs::path dir = temp_dir("check");
  fs::create_directories(dir);
  std::string text = lash::test::read_file(example());
  text.replace(text.find("clearance: 0.5e-3"), 17, "clearance: -0.001");
  text.replace(text.find("mass: 0.30"), 10, "mas: 0.30");
  const fs::path bad = dir / "bad.yaml";
  std::ofstream(bad) << text;
  const Result r = run_lash("check " + bad.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find(bad.string() + ":22:5: body 'crank': unknown key 'mas', did you mean 'mass'?"),
            std::string::npos) << r.out;
  EXPECT_NE(r.out.find("joint 'rod_slider': clearance must be >= 0, got -0.001"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("problems found; nothing was run"), std::string::npos);
  // run refuses the same model the same way and writes nothing.
  const Result run = run_lash("run " + bad.string() + " -o " + (dir / "out").string());
  EXPECT_EQ(run.code, 2);
  EXPECT_FALSE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}

TEST(Cli, RunWritesTheResultFiles) {
  const fs::path dir = temp_dir("run");
  const Result r = run_lash("run " + example() + " -o " + dir.string() + "/");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("2401 outputs"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("outputs to " + dir.string() + "/ in"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("\r"), std::string::npos) << "no progress line when not on a terminal";
  ASSERT_TRUE(fs::exists(dir / "timeseries.csv"));
  EXPECT_EQ(line_count(dir / "timeseries.csv"), 2402u);  // header + 0..0.024 s every 1e-5 s
  std::ifstream ts(dir / "timeseries.csv");
  std::string header;
  std::getline(ts, header);
  for (const char* col : {"time,", "slider.x,", "slider.ax,", "rod_slider.Fn,", "rod_slider.ex,",
                          "rod_slider.mode,", "crank.torque,", "crank_pivot.Fx,",
                          "energy.kinetic,", "energy.dissipated,"})
    EXPECT_NE(header.find(col), std::string::npos) << col;
  EXPECT_GT(line_count(dir / "events.csv"), 10u);
  const auto j = nlohmann::json::parse(std::ifstream(dir / "summary.json"));
  EXPECT_TRUE(j["status"]["ok"].get<bool>());
  EXPECT_GT(j["integrator"]["steps"].get<long>(), 100);
  EXPECT_GT(j["integrator"]["rhs_evaluations"].get<long>(), j["integrator"]["steps"].get<long>());
  EXPECT_GT(j["clearance_joints"]["rod_slider"]["impacts"].get<long>(), 5);
  const double share = j["clearance_joints"]["rod_slider"]["contact_share"].get<double>();
  EXPECT_GT(share, 0.0);
  EXPECT_LT(share, 1.0);
  // Impacts spike the slider acceleration beyond the ideal mechanism's −19 419 m/s².
  EXPECT_LT(j["channels"]["slider.ax"]["min"].get<double>(), -19419);
  EXPECT_LT(j["max_constraint_violation"].get<double>(), 1e-6);
  EXPECT_EQ(j["model"]["name"], "flores_slider_crank");
  fs::remove_all(dir);
}

TEST(Cli, SetOverridesReachTheRun) {
  const fs::path dir = temp_dir("set");
  const Result r = run_lash("run " + example() + " -q -o " + dir.string() +
                        " --set joints.rod_slider.clearance=0.25e-3 --set drivers.crank.speed_rpm=3000"
                        " --set solver.end_time=0.005");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(std::ifstream(dir / "summary.json"));
  EXPECT_DOUBLE_EQ(j["clearance_joints"]["rod_slider"]["clearance"].get<double>(), 0.25e-3);
  EXPECT_NEAR(j["channels"]["crank.omega"]["max"].get<double>(), 3000 * 2 * M_PI / 60, 1e-6);
  EXPECT_EQ(j["model"]["overrides"].size(), 3u);
  EXPECT_NE(lash::test::read_file((dir / "model_resolved.yaml").string()).find("0.25e-3"),
            std::string::npos);
  fs::remove_all(dir);
}

TEST(Cli, NumericalFailureKeepsResultsAndExitsOne) {
  const fs::path dir = temp_dir("fail");
  const Result r =
      run_lash("run " + example() + " -o " + dir.string() + " --set clearance_defaults.stiffness=10");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("simulation stopped at t = "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("joint 'rod_slider'"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("through its bearing"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("joint 'rod_slider'"), r.out.rfind("joint 'rod_slider'")) << "named once: " << r.out;
  EXPECT_GT(line_count(dir / "timeseries.csv"), 2u);
  const auto j = nlohmann::json::parse(std::ifstream(dir / "summary.json"));
  EXPECT_FALSE(j["status"]["ok"].get<bool>());
  EXPECT_EQ(j["status"]["element"], "rod_slider");
  // The folder is analysed like any stopped run (the stop was counted as a contact event, and
  // analyze refused events.csv as cut), and its final state is refused as a start, saying why.
  const Result an = run_lash("analyze " + dir.string() + " --no-lyapunov");
  EXPECT_EQ(an.code, 1) << an.out;  // the run's own outcome
  EXPECT_NE(an.out.find("analysis.json"), std::string::npos) << an.out;
  EXPECT_EQ(an.out.find("cut or edited"), std::string::npos) << an.out;
  const Result from = run_lash("run " + example() + " -q -o " + (dir / "again").string() +
                               " --set clearance_defaults.stiffness=10 --from " +
                               (dir / "final_state.json").string());
  EXPECT_EQ(from.code, 2) << from.out;
  EXPECT_NE(from.out.find("stopped with its journal through its bearing"), std::string::npos) << from.out;
  fs::remove_all(dir);
}

TEST(Cli, ProgressLineOnATerminal) {
  // `script` gives the run a pseudo-terminal: the progress line (simulated time, percent, rate)
  // must appear there, and only there (RunWritesTheResultFiles checks its absence in a pipe).
  if (std::system("command -v script > /dev/null 2>&1") != 0) GTEST_SKIP() << "no script(1)";
  const fs::path dir = temp_dir("tty");
  const std::string inner = std::string(LASH_BINARY) + " run " + example() + " -o " + dir.string();
  const Result r = run_lash_raw("script -qec '" + inner + "' /dev/null");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("\r  t = "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("100.0%"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("simulated s per wall s"), std::string::npos) << r.out;
  fs::remove_all(dir);
}

TEST(Cli, ProgressLinesInALogEveryIntervalOfWallTime) {
  // Without a terminal (a log, a batch job) a line every 30 s of wall time: none for a short run
  // (RunWritesTheResultFiles), one per output at LASH_PROGRESS_SECONDS=0, each on its own line.
  const fs::path dir = temp_dir("log_progress");
  const std::string run = " " + std::string(LASH_BINARY) + " run " + example() + " -o " +
                          dir.string() + " --set solver.end_time=5e-5";
  const Result r = run_lash_raw("LASH_PROGRESS_SECONDS=0" + run);
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.find('\r'), std::string::npos) << r.out;
  EXPECT_EQ(r.out.rfind("  t = 0 s    0.0%", 0), 0u) << r.out;
  for (const char* line : {"  t = 2e-05 s   40.0%", "  t = 5e-05 s  100.0%"})
    EXPECT_NE(r.out.find(std::string("\n") + line), std::string::npos) << line << "\n" << r.out;
  const Result quiet = run_lash_raw("LASH_PROGRESS_SECONDS=0" + run + " -q");
  EXPECT_EQ(quiet.out.find("  t = "), std::string::npos) << quiet.out;
  const Result bad = run_lash_raw("LASH_PROGRESS_SECONDS=-1" + run);
  EXPECT_EQ(bad.code, 0) << bad.out;
  EXPECT_NE(bad.out.find("warning: LASH_PROGRESS_SECONDS='-1' is not a number of seconds"),
            std::string::npos) << bad.out;
  EXPECT_EQ(bad.out.find("  t = "), std::string::npos) << bad.out;
  fs::remove_all(dir);
}

TEST(Cli, AReportMadeDuringARunWithChannelsLeftOutEqualsTheFoldersOwn) {
  // `--channels 'slider.*' --report` analysed every channel (orbits, the Fn spectrum) while
  // `lash report` of the folder left those out: the two reports of one run differed.
  const fs::path dir = temp_dir("channels_report");
  const Result r = run_lash("run " + example() + " -q -o " + dir.string() +
                            " --channels 'slider.*' --report --set solver.end_time=0.03");
  ASSERT_EQ(r.code, 0) << r.out;
  auto load = [&] { return nlohmann::json::parse(std::ifstream(dir / "report_data.json")); };
  const nlohmann::json in_run = load();
  const Result again = run_lash("report " + dir.string());
  ASSERT_EQ(again.code, 0) << again.out;
  const nlohmann::json folder = load();
  EXPECT_EQ(in_run["provenance"]["skipped"], folder["provenance"]["skipped"]);
  bool orbits_said = false;
  for (const auto& line : in_run["provenance"]["skipped"])
    orbits_said |= line.get<std::string>().find("journal orbits") == 0;
  EXPECT_TRUE(orbits_said) << in_run["provenance"].dump();
  std::vector<std::string> a, b;
  for (const auto& [k, v] : in_run["series"]["channels"].items()) a.push_back(k);
  for (const auto& [k, v] : folder["series"]["channels"].items()) b.push_back(k);
  EXPECT_EQ(a, b);
  EXPECT_FALSE(in_run["series"]["channels"].contains("rod_slider.Fn"));
  for (const auto& [k, v] : in_run["analysis"]["statistics"].items())
    for (const char* f : {"min", "max", "t_min", "t_max"})
      EXPECT_EQ(v[f], folder["analysis"]["statistics"][k][f]) << k << "." << f;
  EXPECT_EQ(in_run["model"]["file"], folder["model"]["file"]);
  fs::remove_all(dir);
}

TEST(Cli, AStudyFileWhereAModelBelongsIsNamedAsAStudy) {
  const fs::path dir = temp_dir("study_as_model");
  fs::create_directories(dir);
  std::ofstream(dir / "s.yaml") << "study: s\nmodel: " << example()
                                << "\nparameters:\n  joints.rod_slider.clearance: {values: [1e-4]}\n";
  for (const char* cmd : {"run", "modes"}) {
    const Result r = run_lash(std::string(cmd) + " " + (dir / "s.yaml").string() +
                              (std::string(cmd) == "run" ? " -o " + (dir / "out").string() : ""));
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find("s.yaml is a study file (it has 'study:', or 'model:' and no bodies), "
                         "not a model: run it with `lash sweep "), std::string::npos)
        << cmd << ": " << r.out;
    EXPECT_EQ(r.out.find("unknown"), std::string::npos) << r.out;
  }
  fs::remove_all(dir);
}

TEST(Cli, AContinuedRunIsNotAnalysedAsAWholeRun) {
  // A folder written with --from holds t >= its start only; analyze and report made the run
  // again from t = 0 and mixed that time into its sections and contact modes.
  const fs::path first = temp_dir("whole_first"), cont = temp_dir("whole_cont");
  ASSERT_EQ(run_lash("run " + example() + " -q -o " + first.string() +
                     " --set solver.end_time=0.006").code, 0);
  ASSERT_EQ(run_lash("run " + example() + " -q -o " + cont.string() +
                     " --set solver.end_time=0.012 --from " + (first / "final_state.json").string())
                .code,
            0);
  for (const char* command : {"analyze ", "report "}) {
    const Result r = run_lash(command + cont.string());
    EXPECT_EQ(r.code, 2) << command << r.out;
    EXPECT_NE(r.out.find("a run continued from"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("holds t >= 0.006 s only"), std::string::npos) << r.out;
  }
  EXPECT_FALSE(fs::exists(cont / "analysis.json"));
  EXPECT_EQ(run_lash("analyze " + first.string() + " --no-lyapunov").code, 0);
}

TEST(Cli, AStatisticsWindowWithoutAnOutputRowKeepsItsExactExtrema) {
  // Rows every 0.1 ms; a window of 10 µs between two of them. Its min, max and peak are the
  // exact ones (the run made again, tracked between outputs); RMS and crest factor need rows,
  // and analyze says so instead of leaving them out without a word.
  const fs::path dir = temp_dir("empty_window");
  ASSERT_EQ(run_lash("run " + example() + " -q -o " + dir.string() +
                     " --set solver.end_time=0.012 --set solver.output_interval=1e-4").code, 0);
  const Result r = run_lash("analyze " + dir.string() + " --no-lyapunov --window 0.01001,0.01002");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("skipped: statistics: RMS and crest factor: no output row lies in the "
                       "window (--window 0.01001,0.01002 s); min, max and peak are the exact ones"),
            std::string::npos)
      << r.out;
  const auto an = nlohmann::json::parse(std::ifstream(dir / "analysis.json"))["statistics"];
  // The same window sampled every µs (its own rows, and its exact extrema): the same extremes.
  const fs::path fine = temp_dir("fine_window");
  ASSERT_EQ(run_lash("run " + example() + " -q -o " + fine.string() +
                     " --set solver.end_time=0.012 --set solver.output_interval=1e-6").code, 0);
  ASSERT_EQ(run_lash("analyze " + fine.string() + " --no-lyapunov --window 0.01001,0.01002").code, 0);
  const auto ref = nlohmann::json::parse(std::ifstream(fine / "analysis.json"))["statistics"];
  for (const char* ch : {"slider.x", "slider.vx", "crank.phi", "rod.omega"}) {
    SCOPED_TRACE(ch);
    ASSERT_TRUE(an.contains(ch));
    EXPECT_EQ(an[ch]["extrema"], "exact");
    EXPECT_TRUE(an[ch]["rms"].is_null());
    EXPECT_TRUE(an[ch]["crest"].is_null());
    const double scale = std::abs(ref[ch]["peak"].get<double>());
    EXPECT_NEAR(an[ch]["min"].get<double>(), ref[ch]["min"].get<double>(), 1e-6 * scale);
    EXPECT_NEAR(an[ch]["max"].get<double>(), ref[ch]["max"].get<double>(), 1e-6 * scale);
    EXPECT_LT(an[ch]["min"].get<double>(), an[ch]["max"].get<double>());  // it moved in 10 µs
    EXPECT_GE(an[ch]["t_min"].get<double>(), 0.01001);
    EXPECT_LE(an[ch]["t_max"].get<double>(), 0.01002);
  }
  // A window that holds rows has its statistics and no such line.
  const Result ok = run_lash("analyze " + dir.string() + " --no-lyapunov --window 0.005,0.01");
  EXPECT_EQ(ok.out.find("no output row"), std::string::npos) << ok.out;
  fs::remove_all(dir);
  fs::remove_all(fine);
}

TEST(Cli, AnalyzeOfAStoppedRunSaysWhatItLeavesOut) {
  // A run stopped by max_steps before one period: analyze printed no Lyapunov line and no
  // spectrum line at all, nothing saying why.
  const fs::path dir = temp_dir("analyze_failed");
  ASSERT_EQ(run_lash("run " + example() + " -q -o " + dir.string() + " --set solver.max_steps=2000").code, 1);
  const Result r = run_lash("analyze " + dir.string() + " --fft slider.ax,crank.omega");
  EXPECT_EQ(r.code, 1) << r.out;
  for (const char* text :
       {"Lyapunov exponents not computed: the run stopped at t = 0.00582",
        "skipped: spectrum of slider.ax: 0 outputs after the transient (t >= 0.012 s), 16 needed",
        "skipped: spectrum of crank.omega: 0 outputs"})
    EXPECT_NE(r.out.find(text), std::string::npos) << text << "\n" << r.out;
  // A constant channel is said to be one.
  const Result c = run_lash("analyze " + dir.string() + " --discard 0 --no-lyapunov --fft crank.omega");
  EXPECT_NE(c.out.find("skipped: spectrum of crank.omega: constant to 1e-9 of its magnitude"),
            std::string::npos) << c.out;
  fs::remove_all(dir);
}

TEST(Cli, ReportAndAnalyzeAnEarlierRun) {
  const fs::path dir = temp_dir("analyze");
  ASSERT_EQ(run_lash("run " + example() + " -q -o " + dir.string()).code, 0);
  Result r = run_lash("analyze " + dir.string() + " --poincare crank --fft slider.ax");
  EXPECT_EQ(r.code, 0) << r.out;
  for (const char* text : {"poincare (stroboscopic): 2 sections", "spectrum slider.ax:",
                           "largest Lyapunov exponent:", "verdict: "})
    EXPECT_NE(r.out.find(text), std::string::npos) << text << "\n" << r.out;
  const auto an = nlohmann::json::parse(std::ifstream(dir / "analysis.json"));
  EXPECT_TRUE(an.contains("verdict"));
  EXPECT_TRUE(an["spectra"].contains("slider.ax"));
  // Bad requests name what is wrong and exit 2.
  r = run_lash("analyze " + dir.string() + " --fft slider.az");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--fft slider.az: no such channel"), std::string::npos) << r.out;
  r = run_lash("analyze " + dir.string() + " --plane slider.speed=0");
  EXPECT_EQ(r.code, 2);
  r = run_lash("analyze " + fs::temp_directory_path().string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("not a folder written by `lash run`"), std::string::npos) << r.out;
  // lash report writes the page and the data beside the run's results. It takes analyze's
  // options and applies them to the data the page and figures read; the same options give
  // analyze the same verdict.
  const std::string options = " --discard 0 --no-lyapunov --fft slider.ax";
  r = run_lash("report " + dir.string() + "//" + options);  // a folder's trailing slashes
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.find("//"), std::string::npos) << "paths printed as out//report.html\n" << r.out;
  EXPECT_TRUE(fs::exists(dir / "report.html"));
  EXPECT_TRUE(fs::exists(dir / "report_data.json"));
  const std::string html = lash::test::read_file((dir / "report.html").string());
  EXPECT_EQ(html.find("__LASH_REPORT_DATA__"), std::string::npos);
  EXPECT_NE(html.find("\"flores_slider_crank\""), std::string::npos);
  const auto data = nlohmann::json::parse(std::ifstream(dir / "report_data.json"))["analysis"];
  EXPECT_EQ(data["poincare"]["discarded_periods"], 0);
  EXPECT_EQ(data["poincare"]["points"].size(), 3u);  // sections at 0, T and 2T
  EXPECT_TRUE(data["lyapunov"].is_null()) << data["lyapunov"];
  EXPECT_EQ(data["spectra"].size(), 1u);
  EXPECT_TRUE(data["spectra"].contains("slider.ax"));
  r = run_lash("analyze " + dir.string() + options);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(dir / "analysis.json"))["verdict"], data["verdict"]);
  fs::remove_all(dir);
}

TEST(Cli, TuneAbsorberPrintsTheDesignTheFormulasAndASnippet) {
  // f_p = 25 Hz, μ = 0.25, M = 2 kg: m_a = 0.5 kg, f_a = 20 Hz, k_a = 800π² = 7895.68 N/m,
  // c_a = 50π sqrt(0.048) = 34.4144 N·s/m, ζ_opt = sqrt(0.048) = 0.219089, peak 3.
  Result r = run_lash("tune-absorber --frequency 25 --mass-ratio 0.25 --primary-mass 2.0");
  EXPECT_EQ(r.code, 0) << r.out;
  for (const char* text :
       {"absorber_mass        0.5 kg", "stiffness            7895.68 N/m",
        "damping              34.4144 N·s/m", "tuned_frequency      20 Hz",
        "damping_ratio        0.219089", "peak_amplification   3 ",
        "f_opt = ω_a / ω_p = 1 / (1 + μ) = 0.8", "sqrt(3μ / (8 (1 + μ)³))", "sqrt(1 + 2/μ) = 3",
        "Den Hartog, Mechanical Vibrations", "type: bushing", "from: link.P", "to: absorber",
        "frame: link", "stiffness: [7895.68, 7895.68]", "damping: [34.4144, 34.4144]",
        "mass: 0.5", "same values for a two-axis absorber"})
    EXPECT_NE(r.out.find(text), std::string::npos) << text << "\n" << r.out;

  // --absorber-mass instead of --primary-mass; --attach names the link in the snippet; --json.
  r = run_lash("tune-absorber --frequency 25 --mass-ratio 0.25 --absorber-mass 0.5 "
               "--attach rod.B --json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_DOUBLE_EQ(j["primary_mass"].get<double>(), 2.0);
  EXPECT_NEAR(j["stiffness"].get<double>(), 800 * M_PI * M_PI, 1e-9);
  EXPECT_NEAR(j["damping"].get<double>(), 50 * M_PI * std::sqrt(0.048), 1e-12);
  EXPECT_NEAR(j["tuned_frequency"].get<double>(), 20.0, 1e-12);
  EXPECT_NEAR(j["peak_amplification"].get<double>(), 3.0, 1e-14);
  EXPECT_GE(j["formulas"].size(), 5u);
  EXPECT_NE(j["citation"].get<std::string>().find("Den Hartog"), std::string::npos);
  const std::string yaml = j["yaml"].get<std::string>();
  EXPECT_NE(yaml.find("from: rod.B"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("frame: rod"), std::string::npos) << yaml;
}

TEST(Cli, TuneAbsorberRejectsBadInputWithExitTwo) {
  struct Case {
    const char* args;
    const char* message;
  };
  const Case cases[] = {
      {"--frequency 25 --mass-ratio=-0.05 --primary-mass 2",
       "--mass-ratio: expected a finite number > 0, got -0.05"},
      {"--frequency 0 --mass-ratio 0.05 --primary-mass 2",
       "--frequency: expected a finite number > 0, got 0"},
      {"--frequency 25 --mass-ratio 0.05 --absorber-mass=-1",
       "--absorber-mass: expected a finite number > 0, got -1"},
      {"--frequency 25 --mass-ratio 0.05 --primary-mass 2 --absorber-mass 0.1",
       "expected exactly one of --primary-mass or --absorber-mass, got both"},
      {"--frequency 25 --mass-ratio 0.05",
       "expected exactly one of --primary-mass or --absorber-mass, got neither"},
      {"--frequency 25 --mass-ratio 0.05 --primary-mass 2 --attach ground.O",
       "--attach: expected a point on the vibrating link, got 'ground.O'"},
      // Two dots named no point ('frame: a' in the snippet); the snippet's own body, a bushing
      // from the absorber to itself.
      {"--frequency 25 --mass-ratio 0.05 --primary-mass 2 --attach a.b.c",
       "--attach: expected BODY or BODY.MARKER (body: letters, digits, _), got 'a.b.c'"},
      {"--frequency 25 --mass-ratio 0.05 --primary-mass 2 --attach absorber.P",
       "is on the body the snippet adds ('absorber')"},
      {"--mass-ratio 0.05 --primary-mass 2", "--frequency is required"},
      // A name no model's body can have; an input below the normal doubles.
      {"--frequency 25 --mass-ratio 0.05 --primary-mass 2 --attach time",
       "--attach: 'time' is not a body a model can have (the name 'time' is reserved)"},
      {"--frequency 25 --mass-ratio 0.05 --primary-mass 1e-320",
       "--primary-mass: 1e-320 is below the smallest normal double"},
      {"--frequency 25 --mass-ratio abc --primary-mass 2", "--mass-ratio"},
  };
  for (const Case& c : cases) {
    const Result r = run_lash(std::string("tune-absorber ") + c.args);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.out;
    EXPECT_NE(r.out.find(c.message), std::string::npos) << c.args << "\n" << r.out;
  }
}

TEST(Cli, TuneAbsorberWarnsOfAnAbsorberHeavierThanTheMode) {
  const Result heavy = run_lash("tune-absorber --frequency 25 --mass-ratio 3 --primary-mass 2");
  EXPECT_EQ(heavy.code, 0) << heavy.out;
  EXPECT_NE(heavy.out.find("warning: --mass-ratio 3: the absorber outweighs the mode's modal mass"),
            std::string::npos) << heavy.out;
  const Result usual = run_lash("tune-absorber --frequency 25 --mass-ratio 0.25 --primary-mass 2");
  EXPECT_EQ(usual.code, 0) << usual.out;
  EXPECT_EQ(usual.out.find("warning"), std::string::npos) << usual.out;
}

// Every option finite and > 0, but the design overflows or vanishes: exit 2 naming the options a
// quantity is computed from, never `inf` in the snippet or `null` in the JSON with exit 0.
TEST(Cli, TuneAbsorberRejectsInputsWhoseDesignOverflows) {
  struct Case {
    const char* args;
    const char* message;
  };
  const Case cases[] = {
      {"--frequency 1e200 --mass-ratio 0.05 --primary-mass 2 --json",
       "--frequency 1e+200, --mass-ratio 0.05, --primary-mass 2: the design's stiffness k_a = m_a "
       "ω_a² (N/m) comes out as inf"},
      {"--frequency 1e200 --mass-ratio 0.05 --primary-mass 2",
       "--frequency 1e+200, --mass-ratio 0.05, --primary-mass 2: the design's stiffness"},
      {"--frequency 25 --mass-ratio 1e-300 --absorber-mass 1e10",
       "--absorber-mass 10000000000, --mass-ratio 1e-300: the design's primary_mass M = m_a / μ "
       "(kg) comes out as inf"},
      // Subnormal results (a design of 1e-322 kg and 1e-317 N/m was printed, exit 0).
      {"--frequency 25 --mass-ratio 0.01 --primary-mass 1e-307",
       "--mass-ratio 0.01, --primary-mass 1e-307: the design's absorber_mass m_a = μ M (kg) comes "
       "out as 1e-309"},
      {"--frequency 25 --mass-ratio 1e-300 --primary-mass 1e-300",
       "--mass-ratio 1e-300, --primary-mass 1e-300: the design's absorber_mass m_a = μ M (kg) "
       "comes out as 0"},
  };
  for (const Case& c : cases) {
    const Result r = run_lash(std::string("tune-absorber ") + c.args);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.out;
    EXPECT_NE(r.out.find(c.message), std::string::npos) << c.args << "\n" << r.out;
    EXPECT_EQ(r.out.find("stiffness: ["), std::string::npos) << c.args << "\n" << r.out;
  }
}

// The snippet is meant to be pasted: merged into a small model (a link pinned to the ground, the
// absorber sitting on its marker P or its centre of mass), it must pass `lash check` as printed,
// apart from the absorber's position, and run with the absorber as a point mass.
TEST(Cli, TuneAbsorberSnippetLoadsWhenPasted) {
  const fs::path dir = temp_dir("snippet");
  fs::create_directories(dir);
  for (const char* attach : {"link.P", "link"}) {
    SCOPED_TRACE(attach);
    const Result r = run_lash(std::string("tune-absorber --frequency 25 --mass-ratio 0.05 ") +
                              "--primary-mass 2 --json --attach " + attach);
    ASSERT_EQ(r.code, 0) << r.out;
    const std::string yaml = nlohmann::json::parse(r.out)["yaml"].get<std::string>();
    const size_t b = yaml.find("bodies:\n"), l = yaml.find("loads:\n");
    ASSERT_NE(b, std::string::npos) << yaml;
    ASSERT_NE(l, std::string::npos) << yaml;
    EXPECT_EQ(yaml.find("\n    inertia"), std::string::npos) << "the absorber is a point mass\n" << yaml;
    const std::string bodies = yaml.substr(b + 8, l - b - 8), loads = yaml.substr(l + 7);
    // The link's P is at the world origin, where the snippet puts the absorber.
    const std::string model = yaml.substr(0, b) +
                              "gravity: [0, -9.81]\n"
                              "ground: {markers: {O: [-0.1, 0]}}\n"
                              "bodies:\n"
                              "  link: {mass: 2.0, inertia: 0.01, markers: {O: [-0.1, 0], P: [0, 0]}}\n" +
                              bodies +
                              "joints:\n"
                              "  pivot: {type: revolute, journal: link.O, bearing: ground.O}\n"
                              "loads:\n" +
                              loads + "solver: {end_time: 0.05, output_interval: 1.0e-3}\n";
    const fs::path file = dir / "pasted.yaml";
    std::ofstream(file) << model;
    const Result check = run_lash("check " + file.string());
    EXPECT_EQ(check.code, 0) << check.out << "\n" << model;
    EXPECT_NE(check.out.find("ok: 2 bodies, 1 joint (0 with clearance), 0 drivers, 1 load"),
              std::string::npos)
        << check.out;
    const Result run = run_lash("run " + file.string() + " -q -o " + (dir / "out").string());
    ASSERT_EQ(run.code, 0) << run.out;
    const auto summary = nlohmann::json::parse(lash::test::read_file((dir / "out" / "summary.json").string()));
    const auto& channels = summary["channels"];
    for (const char* c : {"absorber.x", "absorber.vy", "absorber_mount.Fx", "absorber_mount.dy",
                          "absorber_mount.power"})
      EXPECT_TRUE(channels.contains(c)) << c;
    EXPECT_FALSE(channels.contains("absorber.phi")) << "a point mass has no angle";
    // The link swings under gravity and the absorber follows it on its spring.
    EXPECT_GT(channels["absorber.y"]["peak"].get<double>(), 1e-3);
  }
  fs::remove_all(dir);
}

TEST(Cli, ExpressionFailingMidRunExitsOneWithASummary) {
  // Loads valid at t = 0 that muparser cannot evaluate later (a step whose bounds cross: at
  // t = 1 ms, or once the block has moved 0.1 mm, a bound that depends on the state), with both
  // integrators: exit 1 with the results so far and a summary saying "failed", not an abort
  // (134) on an uncaught mu::ParserError.
  const fs::path dir = temp_dir("expr");
  fs::create_directories(dir);
  for (const std::string text : {"step(time, 0, 0, 1e-3 - time, 1)", "1 + step(time, 0, 0, 1e-4 - block.x, 1)"}) {
    std::ofstream(dir / "expr.yaml") << "gravity: [0, 0]\n"
                                        "bodies:\n  block: {mass: 2.0, inertia: 1e-3}\n"
                                        "loads:\n  push: {type: force, point: block, fx: \""
                                     << text
                                     << "\", fy: \"0\"}\n"
                                        "solver: {end_time: 0.05, output_interval: 1e-4, "
                                        "initial_state: given}\n";
    for (const char* integrator : {"dopri5", "bdf"}) {
      const fs::path out = dir / "out";
      const Result r = run_lash("run " + (dir / "expr.yaml").string() + " -q -o " + out.string() +
                                " --set solver.integrator=" + integrator);
      SCOPED_TRACE(text + " with " + integrator);
      EXPECT_EQ(r.code, 1) << r.out;
      EXPECT_NE(r.out.find("simulation stopped at t = "), std::string::npos) << r.out;
      EXPECT_NE(r.out.find("load 'push': expression '" + text + "'"), std::string::npos) << r.out;
      EXPECT_EQ(r.out.find("joint 'push'"), std::string::npos) << r.out;
      ASSERT_TRUE(fs::exists(out / "summary.json")) << r.out;
      const auto j = read_summary(out);
      EXPECT_EQ(j["status"]["outcome"], "failed");
      EXPECT_EQ(j["status"]["element"], "push");  // it was empty
      EXPECT_FALSE(j["status"]["ok"].get<bool>());
      EXPECT_GE(j["status"]["time"].get<double>(), 1e-3);
      EXPECT_LT(j["status"]["time"].get<double>(), 0.05);
      EXPECT_NE(j["status"]["message"].get<std::string>().find(text), std::string::npos);
      EXPECT_GT(line_count(out / "timeseries.csv"), 2u);
      expect_whole_rows(out / "timeseries.csv");
    }
  }
  fs::remove_all(dir);
}

TEST(Cli, ADriverExpressionFailingMidRunIsReportedUpToTheFailure) {
  // The report's period of an expression driver is its mean speed over the run's last half,
  // where this one cannot be evaluated (past 0.01 s): `run --report` exited 2 with the earlier
  // run's results deleted and none of its own, and `report` of the folder exited 1 with no
  // report. Now: no period, the run reported up to its failure, exit 1.
  const fs::path dir = temp_dir("driver_expr");
  fs::create_directories(dir);
  std::string text = lash::test::read_file(example());
  const std::string speed = "speed_rpm: 5000";
  ASSERT_NE(text.find(speed), std::string::npos);
  text.replace(text.find(speed), speed.size(), "motion: \"10*time + 0*sqrt(0.01 - time)\"");
  std::ofstream(dir / "m.yaml") << text;
  const fs::path out = dir / "out";
  Result r = run_lash("run " + (dir / "m.yaml").string() + " -q --report -o " + out.string());
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("driver 'crank': expression '10*time + 0*sqrt(0.01 - time)' failed at time 0.01"),
            std::string::npos) << r.out;
  ASSERT_TRUE(fs::exists(out / "summary.json")) << r.out;
  EXPECT_EQ(read_summary(out)["status"]["outcome"], "failed");
  EXPECT_TRUE(fs::exists(out / "report.html"));
  fs::remove(out / "report.html");
  r = run_lash("report " + out.string());
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(fs::exists(out / "report.html")) << r.out;
  fs::remove_all(dir);
}

TEST(Cli, AFailureWithoutClearanceJointsStillGivesTheState) {
  // A force that grows without bound at t = 2 ms: the integrator gives up there. Without a
  // clearance joint to describe, the message names the body with the largest acceleration
  // (it ended in "state: " and nothing).
  const fs::path dir = temp_dir("blowup");
  fs::create_directories(dir);
  std::ofstream(dir / "m.yaml") << "gravity: [0, 0]\nbodies:\n  block: {mass: 2.0, inertia: 1e-3}\n"
                                   "loads:\n  push: {type: force, point: block, fx: \"1/(2e-3 - time)^3\", fy: \"0\"}\n"
                                   "solver: {end_time: 0.01, output_interval: 1e-3, initial_state: given}\n";
  const Result r = run_lash("run " + (dir / "m.yaml").string() + " -q -o " + (dir / "out").string());
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("step size underflow"), std::string::npos) << r.out;
  // The load comes first: it, not a contact, is the likely cause (it was not named).
  const size_t at = r.out.find("; state at t = ");
  ASSERT_NE(at, std::string::npos) << r.out;
  EXPECT_NE(r.out.find(" s: load 'push' (the largest): force (", at), std::string::npos) << r.out;
  // The state where the integrator stopped, not at the last output (t = 1 ms, force 1e9 N:
  // the message described the cause as it stood up to an output interval earlier).
  const double t_state = std::stod(r.out.substr(at + 15));
  EXPECT_GT(t_state, 1.99e-3) << r.out;
  EXPECT_LE(t_state, 2e-3) << r.out;
  const double fx = std::stod(r.out.substr(r.out.find("force (", at) + 7));
  EXPECT_GT(fx, 1e15) << r.out;
  EXPECT_NE(r.out.find(" N·m; body 'block' (the largest acceleration): position ("), std::string::npos) << r.out;
  const auto status = read_summary(dir / "out")["status"];
  const std::string message = status["message"];
  EXPECT_NE(message.find("m/s^2"), std::string::npos) << message;
  // The element at fault: the load on the body whose velocity carried the step's largest error
  // (summary.json's status.element was empty on every integrator failure).
  EXPECT_EQ(status["element"], "push");
  EXPECT_NE(message.find("the last step's largest error was in block.vx"), std::string::npos)
      << message;
  fs::remove_all(dir);
}

TEST(Cli, TwoPinsOnOneAxisShareTheReactionInTheSummaryPeaksToo) {
  // A pendulum pinned twice on one axis: one pin's equations are redundant, and the reactions
  // reported are the smallest (equal shares). The integrator's own evaluations skip that report
  // (only the channels read reactions); where the summary's extrema reuse DOPRI5's step end, the
  // report must be completed, or its peaks are those of the one pin kept (twice the share).
  const fs::path dir = temp_dir("two_pins");
  fs::create_directories(dir);
  std::ofstream(dir / "m.yaml")
      << "gravity: [0, -9.81]\nground: {markers: {O: [0, 0]}}\nbodies:\n"
         "  arm: {mass: 1, inertia: 0.0833333, position: [0.5, 0], markers: {O: [-0.5, 0]}}\n"
         "joints:\n  pin: {type: revolute, journal: arm.O, bearing: ground.O}\n"
         "  pin2: {type: revolute, journal: arm.O, bearing: ground.O}\n"
         "solver: {end_time: 1, output_interval: 0.05}\n";
  const Result r = run_lash("run " + (dir / "m.yaml").string() + " -q -o " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto c = read_summary(dir / "out")["channels"];
  for (const char* f : {"Fx", "Fy", "F"})
    for (const char* k : {"min", "max"}) {
      const double a = c[std::string("pin.") + f][k], b = c[std::string("pin2.") + f][k];
      EXPECT_NEAR(a, b, 1e-9 * (std::abs(a) + std::abs(b) + 1.0)) << f << " " << k;
    }
  // Each pin's share of the largest pull: a unit bar released level from rest about its end
  // passes the bottom at ω² = 3g/L (m g L/2 = ½ (m L²/3) ω²), where the pin holds
  // m g + m ω² L/2 = 2.5 m g = 24.525 N and no tangential force: 12.2625 N each.
  EXPECT_NEAR(c["pin.F"]["max"].get<double>(), 1.25 * 9.81, 1e-5 * 12.2625);
  fs::remove_all(dir);
}

TEST(Cli, AStateNotFiniteAtTheStartNamesItsLoadAndWritesNoNaN) {
  // A load of 1e308·e^{100t} N makes the acceleration infinite at t = 0. The status named no
  // element, the time series held a row of nan and inf that `lash report` then refused ("a run
  // stops before it would write one"), and summary.json gave the acceleration's extrema as 0.
  const fs::path dir = temp_dir("nan_start");
  fs::create_directories(dir);
  std::ofstream(dir / "m.yaml")
      << "gravity: [0, -9.81]\nground: {markers: {O: [0, 0]}}\nbodies:\n"
         "  arm: {mass: 1, inertia: 0.0833333, position: [0.5, 0], markers: {O: [-0.5, 0], A: [0.5, 0]}}\n"
         "joints:\n  pin: {type: revolute, journal: arm.O, bearing: ground.O}\n"
         "loads:\n  push: {type: force, point: arm.A, fy: \"1e308*exp(time*100)\"}\n"
         "solver: {end_time: 0.1, output_interval: 0.01}\n";
  const fs::path out = dir / "out";
  const Result r = run_lash("run " + (dir / "m.yaml").string() + " -q -o " + out.string());
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("not finite (NaN/Inf); load 'push' (the largest)"), std::string::npos) << r.out;
  const auto j = read_summary(out);
  EXPECT_EQ(j["status"]["element"], "push");
  EXPECT_EQ(line_count(out / "timeseries.csv"), 1u);  // the header only
  EXPECT_TRUE(j["channels"]["arm.ay"]["max"].is_null()) << j["channels"]["arm.ay"];
  EXPECT_TRUE(j["channels"]["arm.ay"]["peak"].is_null());
  const Result rep = run_lash("report " + out.string());
  EXPECT_EQ(rep.out.find("not a finite number"), std::string::npos) << rep.out;
  fs::remove_all(dir);
}

TEST(Cli, ARunStalledByPlainCoulombFrictionSaysSo) {
  // A journal thrown head-on at its bearing (radial motion: the slip is round-off) with plain
  // Coulomb friction stalls at the first contact, where the frictionless run and the smooth laws
  // pass; the failure names the slip and the laws that smooth the switch.
  const fs::path dir = temp_dir("coulomb_stall");
  fs::create_directories(dir);
  std::ofstream(dir / "m.yaml")
      << "ground: {markers: {O: [0, 0]}}\nbodies:\n  pin: {mass: 1.0, inertia: 1.0e-4, "
         "position: [0, 0], velocity: [1, 0.7], markers: {J: [0, 0]}}\njoints:\n  cj: {type: "
         "revolute, journal: pin.J, bearing: ground.O, clearance: 0.5e-3, journal_radius: 9.5e-3, "
         "material: {youngs_modulus: 207e9, poisson_ratio: 0.3}, normal_law: "
         "lankarani_nikravesh, restitution: 0.9, friction: {law: coulomb, mu: 0.1}}\n"
         "solver: {end_time: 0.005, output_interval: 1e-6, rtol: 1e-10, atol: 1e-14, "
         "initial_state: given, max_steps: 200000}\n";
  const Result r = run_lash("run " + (dir / "m.yaml").string() + " -q -o " + (dir / "out").string());
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("(plain Coulomb friction is discontinuous at zero slip"), std::string::npos)
      << r.out;
  EXPECT_EQ(read_summary(dir / "out")["status"]["element"], "cj");
  const Result smooth = run_lash("run " + (dir / "m.yaml").string() + " -q -o " +
                                 (dir / "smooth").string() +
                                 " --set 'joints.cj.friction={law: ambrosio, mu: 0.1, v0: 1e-4, v1: 1e-3}'");
  EXPECT_EQ(smooth.code, 0) << smooth.out;
  // The other case the docs name: a spinning journal pressed on its bearing's wall by 100 N
  // stops spinning at 1.05 ms and sticks; the slip then chatters about 5e-5 m/s, and the hint
  // was left out (it asked for |vt| < 1e-6).
  std::ofstream(dir / "stick.yaml")
      << "ground: {markers: {B: [0, 0]}}\nbodies:\n  c: {mass: 1.0, position: [0.000501318, 0]}\n"
         "  j: {mass: 1.0, inertia: 1.0e-3, position: [0.000501318, 0], angular_velocity: 0.1}\n"
         "joints:\n  hub: {type: revolute, journal: j, bearing: c}\n"
         "  slide: {type: translational, guide: ground.B, slider: c, axis: [1, 0]}\n"
         "  cj: {type: revolute, journal: j, bearing: ground.B, clearance: 0.5e-3, journal_radius: "
         "9.5e-3, normal_law: hertz, stiffness: 6.6101983978968e10, friction: {law: coulomb, mu: 0.1}}\n"
         "loads:\n  push: {type: force, point: c, fx: 100}\n"
         "solver: {end_time: 0.01, output_interval: 1e-3, rtol: 1e-9, atol: 1e-13, initial_state: "
         "given, max_steps: 200000}\n";
  const Result stick = run_lash("run " + (dir / "stick.yaml").string() + " -q -o " + (dir / "stick").string());
  EXPECT_EQ(stick.code, 1) << stick.out;
  EXPECT_NE(stick.out.find("(plain Coulomb friction is discontinuous at zero slip"), std::string::npos)
      << stick.out;
  EXPECT_EQ(read_summary(dir / "stick")["status"]["element"], "cj");
  fs::remove_all(dir);
}

TEST(Cli, BdfFailsWhereTheRightHandSideBlowsUpInsteadOfCreeping) {
  // A load that diverges at 1 ms, and a contact stiffness of 1e300: DOPRI5 stops at once with
  // a step-size underflow; BDF crept on for its whole max_steps per output (9 million steps in
  // two minutes before a time-out). It now stops at its smallest step, 16 ε·|t|.
  // Each names the element at fault: the diverging load, the contact.
  const std::vector<std::pair<std::string, std::string>> cases = {
      {" --set solver.end_time=0.004 --set 'loads={f: {type: force, point: slider, fx: \"1/(0.001 - t)\"}}'", "f"},
      {" --set solver.end_time=0.002 --set joints.rod_slider.stiffness=1e300", "rod_slider"}};
  for (const auto& [extra, element] : cases) {
    SCOPED_TRACE(extra);
    const fs::path dir = temp_dir("bdf_blowup");
    const Result r = run_lash("run " + example() + " -q -o " + dir.string() +
                              " --set solver.integrator=bdf" + extra);
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find("integrator bdf failed"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("|h| = hmin"), std::string::npos) << r.out;
    const auto j = read_summary(dir);
    EXPECT_EQ(j["status"]["outcome"], "failed");
    EXPECT_LT(j["integrator"]["steps"].get<long>(), 100000);
    EXPECT_EQ(j["status"]["element"], element);
    fs::remove_all(dir);
  }
}

TEST(Cli, ARedundantLinkageContinuesFromAStateBesideItsInLinePosition) {
  // A double parallelogram driven at 2000 rpm from -30 degrees, stopped under BDF where its
  // cranks come in line (t = 2.5 ms; the state 2e-7 rad from it): continuing was refused with "driver
  // 'motor': its equation is redundant" (the joints' rows, one nearly dependent there, were
  // all kept in order, and the joints' null space was not found at LU's round-off threshold,
  // so no configuration nearby was probed). Now it continues under both integrators.
  const fs::path dir = temp_dir("redundant_from");
  fs::create_directories(dir);
  std::ofstream(dir / "m.yaml") << lash::test::parallelogram_yaml(3, 1.0)
                                << "drivers: {motor: {joint: pivot_0, speed_rpm: 2000}}\n";
  const std::string model = (dir / "m.yaml").string();
  Result r = run_lash("run " + model + " -q -o " + (dir / "a").string() +
                      " --set solver.end_time=0.0025 --set solver.output_interval=0.0025"
                      " --set solver.integrator=bdf");
  ASSERT_EQ(r.code, 0) << r.out;
  for (const char* integrator : {"bdf", "dopri5"}) {
    SCOPED_TRACE(integrator);
    const fs::path out = dir / integrator;
    r = run_lash("run " + model + " -q -o " + out.string() + " --from " +
                 (dir / "a" / "final_state.json").string() +
                 " --set solver.end_time=0.1 --set solver.integrator=" + integrator);
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_NE(r.out.find("joint 'coupler_2': 1 of its 2 equations is redundant"), std::string::npos)
        << r.out;
    const auto j = read_summary(out);
    EXPECT_EQ(j["status"]["outcome"], "completed");
    EXPECT_LT(std::abs(j["channels"]["coupler.phi"]["max"].get<double>()), 1e-6);  // a parallelogram
    EXPECT_LT(std::abs(j["channels"]["coupler.phi"]["min"].get<double>()), 1e-6);
  }
  fs::remove_all(dir);
}

TEST(Cli, AFiveCrankParallelogramDoesNotSwitchItsRowsAtEveryEvaluation) {
  // Five cranks (three joint equations redundant), posed 1e-3 rad from in line, driven at 2000
  // rpm under BDF at rtol 1e-7 (`lash run`: its exact extrema step CVODE one step at a time):
  // approaching an in-line position the rows to drop were chosen again at every evaluation,
  // among the cranks' x equations, all about as weak (the mechanism's own singular position),
  // so the right-hand side changed at every evaluation, and at t = 0.99 s, 12° before an
  // in-line position, BDF failed (error test failures at h = 3e-14 s). Now a choice made
  // again is not tried anew for kReselectWait evaluations.
  const fs::path dir = temp_dir("five_cranks");
  fs::create_directories(dir);
  std::ofstream(dir / "m.yaml") << lash::test::parallelogram_yaml(5, 1.0, 1e-3)
                                << "drivers: {motor: {joint: pivot_0, speed_rpm: 2000}}\n";
  const Result r = run_lash("run " + (dir / "m.yaml").string() + " -q -o " + (dir / "out").string() +
                            " --set solver.end_time=1 --set solver.output_interval=1e-3"
                            " --set solver.integrator=bdf --set solver.rtol=1e-7 --set solver.atol=1e-10");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = read_summary(dir / "out");
  EXPECT_EQ(j["status"]["outcome"], "completed");
  EXPECT_EQ(j["warnings"].size(), 3u);  // the three redundant equations; no stabilization warning
  // The parallelogram branch throughout: measured 6e-10 rad.
  EXPECT_LT(std::abs(j["channels"]["coupler.phi"]["max"].get<double>()), 1e-6);
  EXPECT_LT(std::abs(j["channels"]["coupler.phi"]["min"].get<double>()), 1e-6);
  fs::remove_all(dir);
}

TEST(Cli, RunContinuesFromASavedStateTimeAndAll) {
  const fs::path dir = temp_dir("from");
  const fs::path a = dir / "a", b = dir / "b", bad = dir / "bad";
  Result r = run_lash("run " + example() + " -q -o " + a.string() + " --set solver.end_time=0.012");
  ASSERT_EQ(r.code, 0) << r.out;
  ASSERT_TRUE(fs::exists(a / "final_state.json"));
  const auto state = nlohmann::json::parse(std::ifstream(a / "final_state.json"));
  EXPECT_EQ(state["t"].get<double>(), 0.012);
  EXPECT_EQ(state["names"].size(), state["y"].size());
  r = run_lash("run " + example() + " -q -o " + b.string() + " --from " +
               (a / "final_state.json").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto summary = nlohmann::json::parse(std::ifstream(b / "summary.json"));
  EXPECT_EQ(summary["start"]["time"].get<double>(), 0.012);
  EXPECT_EQ(summary["status"]["time"].get<double>(), 0.024);
  EXPECT_NE(summary["start"]["from"].get<std::string>().find("final_state.json"), std::string::npos);
  std::ifstream ts(b / "timeseries.csv");
  std::string header, first;
  std::getline(ts, header);
  std::getline(ts, first);
  EXPECT_EQ(first.substr(0, first.find(',')), "0.012");
  EXPECT_EQ(summary["channels"]["rod_slider.Fn"]["unit"].get<std::string>(), "N");
  // A state of another model, and one already at end_time: exit 2, nothing run.
  r = run_lash("run " + lash::test::example_path("flores_slider_crank_ideal.yaml") + " -q -o " +
               bad.string() + " --from " + (a / "final_state.json").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("does not match the model"), std::string::npos) << r.out;
  r = run_lash("run " + example() + " -q -o " + bad.string() + " --set solver.end_time=0.012 --from " +
               (a / "final_state.json").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("not before the model's end_time"), std::string::npos) << r.out;
  // The same layout with another driver speed: the state breaks the driver's constraint.
  r = run_lash("run " + example() + " -q -o " + bad.string() +
               " --set drivers.crank.speed_rpm=3000 --from " + (a / "final_state.json").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("does not satisfy this model's joints and drivers"), std::string::npos) << r.out;
  // A redundant second driver on the crank: refused as without --from.
  r = run_lash("run " + example() + " -q -o " + bad.string() +
               " --set 'drivers.b={body: crank, coordinate: phi, speed_rpm: 5000}' --from " +
               (a / "final_state.json").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("redundant"), std::string::npos) << r.out;
  fs::remove_all(dir);
}


TEST(Cli, TheFiguresProgramReadsTheWholeResultsAndStopsWithTheRun) {
  // lash finds its figures program at ../share/lash/lash_figures.py beside its binary: a copy of
  // lash with a stand-in there that reports what it found in the run folder, then waits.
  const fs::path dir = temp_dir("figures_order");
  fs::create_directories(dir / "bin");
  fs::create_directories(dir / "share" / "lash");
  fs::copy_file(LASH_BINARY, dir / "bin" / "lash");
  std::ofstream(dir / "share" / "lash" / "lash_figures.py")
      << "import os, sys, time\n"
         "d = sys.argv[1]\n"
         "rows = sum(1 for _ in open(os.path.join(d, 'timeseries.csv'))) - 1\n"
         "print('rows', rows, 'final_state', os.path.exists(os.path.join(d, 'final_state.json')))\n"
         "sys.stdout.flush()\n"
         "if os.environ.get('LASH_TEST_FIGURES_WAIT'):\n"
         "    open(os.path.join(d, 'figures', 'started'), 'w').close()\n"
         "    time.sleep(300)\n";
  const std::string lash = (dir / "bin" / "lash").string();
  const fs::path out = dir / "out";
  // The time series is whole (every row summary.json counts) and final_state.json written
  // before the figures program starts: it draws the whole run.
  const Result r = run_lash_raw(lash + " run " + example() + " -q --report -o " + out.string() +
                                " --set solver.end_time=0.002");
  ASSERT_EQ(r.code, 0) << r.out;
  const long long rows = read_summary(out)["output"]["rows"].get<long long>();
  EXPECT_GT(rows, 100);
  EXPECT_EQ(lash::test::read_file((out / "figures.log").string()),
            "rows " + std::to_string(rows) + " final_state True\n");
  // A signal while the figures are drawn: the program is stopped with lash, at once (it would
  // wait 300 s), and none is left writing into the folder.
  const Result s = run_lash_raw(
      "LASH_TEST_FIGURES_WAIT=1 " + lash + " run " + example() + " -q --report -o " + out.string() +
      " --set solver.end_time=0.002 & pid=$!; i=0; while [ ! -e " + (out / "figures" / "started").string() +
      " ] && [ $i -lt 3000 ]; do sleep 0.1; i=$((i+1)); done; t0=$(date +%s%N); kill -TERM $pid; "
      "wait $pid; echo \"rc=$? ms=$(( ($(date +%s%N) - t0) / 1000000 ))\"");
  EXPECT_NE(s.out.find("rc=130 "), std::string::npos) << s.out;
  const size_t ms = s.out.find("ms=");
  ASSERT_NE(ms, std::string::npos) << s.out;
  EXPECT_LT(std::stol(s.out.substr(ms + 3)), 1000 * (lash::kKillGraceSeconds + 3)) << s.out;
  // ("[s]hare": the pattern does not match the shell that runs pgrep.)
  const Result left = run_lash_raw("pgrep -f '" + dir.string() + "/[s]hare' || echo none");
  EXPECT_NE(left.out.find("none"), std::string::npos) << left.out;
  // The run had completed: its results are whole, the report is not there.
  EXPECT_EQ(read_summary(out)["status"]["outcome"], "completed");
  EXPECT_EQ(read_summary(out)["interrupted_after_run"]["signal"], SIGTERM);
  EXPECT_FALSE(fs::exists(out / "report.html"));  // no half report beside the results
  // The same after a run that failed (a load's expression at 1 ms): exit 130 and the outcome
  // failed, said (it exited 1 with no word of the signal or of the report it left out).
  const Result f = run_lash_raw(
      "LASH_TEST_FIGURES_WAIT=1 " + lash + " run " + example() + " -q --report -o " + out.string() +
      " --set solver.end_time=0.002 --set 'loads={push: {type: force, point: slider.O, fx: "
      "\"sqrt(0.001 - time)\"}}' 2>&1 & pid=$!; i=0; while [ ! -e " +
      (out / "figures" / "started").string() +
      " ] && [ $i -lt 3000 ]; do sleep 0.1; i=$((i+1)); done; kill -TERM $pid; wait $pid; "
      "echo \"rc=$?\"");
  EXPECT_NE(f.out.find("rc=130"), std::string::npos) << f.out;
  EXPECT_NE(f.out.find("error: simulation stopped at t = 0.001"), std::string::npos) << f.out;
  EXPECT_NE(f.out.find("interrupted by signal 15 after the run, during its analyses or report"),
            std::string::npos) << f.out;
  const nlohmann::json failed = read_summary(out);
  EXPECT_EQ(failed["status"]["outcome"], "failed");
  EXPECT_EQ(failed["interrupted_after_run"]["signal"], SIGTERM);
  EXPECT_FALSE(failed.contains("verdict"));
  EXPECT_FALSE(fs::exists(out / "report.html"));
  fs::remove_all(dir);
}

TEST(Cli, ASignalStopsTheRunAndKeepsSummaryAndState) {
  // (timeout --foreground: one signal to lash only; without it timeout signals the whole process
  // group too, and a second signal ends lash at once, by design.)
  // SIGTERM, then SIGINT, one second into a long run: the run stops at its next output, writes
  // summary.json (outcome "interrupted") and final_state.json, and exits 130; every CSV row is
  // whole. The folder held a completed run before: its summary must not survive.
  const fs::path dir = temp_dir("signal");
  ASSERT_EQ(run_lash("run " + example() + " -q -o " + dir.string() + " --set solver.end_time=0.002").code, 0);
  ASSERT_EQ(read_summary(dir)["status"]["outcome"], "completed");
  for (const char* sig : {"TERM", "INT"}) {
    const Result r = run_lash_raw("timeout --foreground --preserve-status -s " + std::string(sig) + " 1 " +
                                  std::string(LASH_BINARY) + " run " + example() + " -q -o " +
                                  dir.string() + " --set solver.end_time=5");
    EXPECT_EQ(r.code, 130) << sig << "\n" << r.out;
    EXPECT_NE(r.out.find("interrupted at t = "), std::string::npos) << r.out;
    const auto summary = read_summary(dir);
    EXPECT_EQ(summary["status"]["outcome"], "interrupted");
    EXPECT_FALSE(summary["status"]["ok"].get<bool>());
    EXPECT_NE(summary["status"]["message"].get<std::string>().find("interrupted by signal"),
              std::string::npos);
    ASSERT_TRUE(fs::exists(dir / "final_state.json"));
    const auto state = nlohmann::json::parse(std::ifstream(dir / "final_state.json"));
    EXPECT_GT(state["t"].get<double>(), 0.0);
    EXPECT_LT(state["t"].get<double>(), 5.0);
    // No extremum after the state the run stopped in (stopped at an output, the last step
    // had passed it: its extrema were counted to the step's end).
    for (const auto& [name, c] : summary["channels"].items())
      if (!c["t_max"].is_null()) {
        EXPECT_LE(c["t_max"].get<double>(), summary["status"]["time"].get<double>()) << name;
        EXPECT_LE(c["t_min"].get<double>(), summary["status"]["time"].get<double>()) << name;
      }
    expect_whole_rows(dir / "timeseries.csv");
    expect_whole_rows(dir / "events.csv");
    EXPECT_EQ(summary["integrator"]["outputs"].get<long>() + 1,
              static_cast<long>(line_count(dir / "timeseries.csv")));
  }
  for (int attempt = 0; attempt < 3; ++attempt) {
    // timeout without --foreground signals lash and then its process group: the same SIGTERM
    // twice within microseconds, which ended lash at once (exit 143, no summary) unless the two
    // merged into one pending signal (1 time in 3 here). Taken as one request now.
    const Result r = run_lash_raw("(" + std::string(LASH_BINARY) + " run " + example() +
                                  " -q -o " + dir.string() + " --set solver.end_time=5 & p=$!; "
                                  "sleep 0.5; kill -TERM $p; kill -TERM $p; wait $p; echo rc=$?)");
    EXPECT_NE(r.out.find("rc=130"), std::string::npos) << r.out;
    EXPECT_EQ(read_summary(dir)["status"]["outcome"], "interrupted");
  }
  // kill -9 cannot be caught: no summary at all rather than the earlier run's, and whole rows
  // (the last one may be cut: expect_whole_rows says why; `lash report` refuses such a folder).
  const Result r = run_lash_raw("timeout -s KILL 1 " + std::string(LASH_BINARY) + " run " +
                                example() + " -q -o " + dir.string() + " --set solver.end_time=5");
  EXPECT_NE(r.code, 0);
  EXPECT_FALSE(fs::exists(dir / "summary.json")) << "a stale summary beside new rows";
  EXPECT_FALSE(fs::exists(dir / "final_state.json"));
  expect_whole_rows(dir / "timeseries.csv", true);
  // The events follow the series to disk (each time a block of rows goes out), not only at the
  // end: the contacts before the kill are there (the first is at t = 0.28 ms).
  expect_whole_rows(dir / "events.csv", true);
  EXPECT_GE(line_count(dir / "events.csv"), 2u) << "the events were lost with the kill";
  fs::remove_all(dir);
}

TEST(Cli, AWriteErrorStopsTheRunWithExitThreeAndWholeRows) {
  // A 200-block file-size limit: the CSV cannot hold the run. Exit 3, the rows before the
  // failure whole, summary.json (written last, small) says write_error and counts the rows.
  const fs::path dir = temp_dir("ulimit");
  const Result r = run_lash_raw("ulimit -f 200; " + std::string(LASH_BINARY) + " run " + example() +
                                " -q -o " + dir.string() + " --set solver.end_time=0.1");
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("timeseries.csv: write failed after"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("File too large"), std::string::npos) << r.out;
  const auto summary = read_summary(dir);
  EXPECT_EQ(summary["status"]["outcome"], "write_error");
  EXPECT_FALSE(summary["status"]["ok"].get<bool>());
  EXPECT_LT(summary["status"]["time"].get<double>(), 0.1);
  expect_whole_rows(dir / "timeseries.csv");
  expect_whole_rows(dir / "events.csv");
  EXPECT_GE(line_count(dir / "events.csv"), 2u) << "the events before the failure were lost";
  EXPECT_EQ(summary["integrator"]["outputs"].get<long>() + 1,
            static_cast<long>(line_count(dir / "timeseries.csv")));
  // The last row on disk is the time the message and summary.json give (they said the time the
  // run had reached, later than the last row that fitted).
  {
    std::ifstream in(dir / "timeseries.csv");
    std::string line, last;
    while (std::getline(in, line)) last = line;
    const double t_last = std::stod(last.substr(0, last.find(',')));
    EXPECT_EQ(summary["output"]["last_time"].get<double>(), t_last);
    std::ostringstream said;
    said << "(up to t = " << t_last << " s) are whole";
    EXPECT_NE(r.out.find(said.str()), std::string::npos) << r.out;
  }
  // The extrema are over the run up to where it stopped (the output it could not write): the
  // step that had passed that output counted up to its end, 5e-6 s later.
  const double t_stop = summary["status"]["time"].get<double>();
  int channels = 0;
  for (const auto& [name, c] : summary["channels"].items()) {
    if (c["t_max"].is_null()) continue;
    ++channels;
    EXPECT_LE(c["t_max"].get<double>(), t_stop) << name;
    EXPECT_LE(c["t_min"].get<double>(), t_stop) << name;
  }
  EXPECT_GT(channels, 40);
  // `lash analyze` refuses the folder and says why, without suggesting --from (a run stopped
  // by a write error leaves no final state).
  const Result an = run_lash("analyze " + dir.string() + " --no-lyapunov");
  EXPECT_EQ(an.code, 2) << an.out;
  EXPECT_NE(an.out.find("could not be written"), std::string::npos) << an.out;
  EXPECT_EQ(an.out.find("--from"), std::string::npos) << an.out;
  // An output folder that cannot be made (under /proc): exit 3, named; one that names a
  // character device is a mistaken option, exit 2.
  const Result proc = run_lash("run " + example() + " -q -o /proc/lash_cannot_be_made");
  EXPECT_EQ(proc.code, 3) << proc.out;
  EXPECT_NE(proc.out.find("/proc/lash_cannot_be_made: cannot create the output folder"),
            std::string::npos) << proc.out;
  const Result dev = run_lash("run " + example() + " -q -o /dev/full");
  EXPECT_EQ(dev.code, 2) << dev.out;
  EXPECT_NE(dev.out.find("/dev/full: exists and is not a folder"), std::string::npos) << dev.out;
  // A limit below summary.json's size (18 blocks): no summary can be written, and the rows are
  // kept (a file-size limit is per file: removing rows would make no room for it). They were
  // all removed, for nothing.
  fs::remove_all(dir);
  const Result small = run_lash_raw("ulimit -f 18; " + std::string(LASH_BINARY) + " run " + example() +
                                    " -q -o " + dir.string() + " --set solver.end_time=0.1");
  EXPECT_EQ(small.code, 3) << small.out;
  EXPECT_NE(small.out.find("summary.json: cannot write: File too large"), std::string::npos) << small.out;
  EXPECT_FALSE(fs::exists(dir / "summary.json"));
  expect_whole_rows(dir / "timeseries.csv");
  EXPECT_GT(line_count(dir / "timeseries.csv"), 10u);
  fs::remove_all(dir);
}

TEST(Cli, AModelFileAmongTheRunsOwnFilesIsNotReplaced) {
  // A model saved as OUT/events.csv, or an earlier run's OUT/model_resolved.yaml run again into
  // OUT: the run would write over its own model file. Refused, the file unchanged; a model of
  // another name in the folder is fine.
  const fs::path dir = temp_dir("model_in_out");
  fs::create_directories(dir);
  const std::string text = lash::test::read_file(example());
  for (const char* name : {"events.csv", "model_resolved.yaml"}) {
    std::ofstream(dir / name) << text;
    const Result r = run_lash("run " + (dir / name).string() + " -q -o " + dir.string() +
                              " --set solver.end_time=0.001");
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find("is one of the files this run writes"), std::string::npos) << r.out;
    EXPECT_EQ(lash::test::read_file((dir / name).string()), text) << name;
    fs::remove(dir / name);
  }
  std::ofstream(dir / "model.yaml") << text;
  const Result ok = run_lash("run " + (dir / "model.yaml").string() + " -q -o " + dir.string() +
                             " --set solver.end_time=0.001");
  EXPECT_EQ(ok.code, 0) << ok.out;
  EXPECT_EQ(lash::test::read_file((dir / "model.yaml").string()), text);
  fs::remove_all(dir);
}

TEST(Cli, AFolderWhoseCsvFilesGotWindowsLineEndsIsStillAnalysed) {
  // Saved again by an editor with CR LF: "events.csv:3: velocity '-3.91123009' is not a finite
  // number", the CR invisible in the message. Read as the same rows now.
  const fs::path dir = temp_dir("crlf");
  Result r = run_lash("run " + example() + " -q -o " + dir.string() + " --set solver.end_time=0.006");
  ASSERT_EQ(r.code, 0) << r.out;
  for (const char* name : {"timeseries.csv", "events.csv"}) {
    std::string text = lash::test::read_file((dir / name).string()), crlf;
    for (const char c : text) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
    std::ofstream(dir / name, std::ios::binary) << crlf;
  }
  r = run_lash("analyze " + dir.string() + " --no-lyapunov");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("wrote " + (dir / "analysis.json").string()), std::string::npos) << r.out;
  fs::remove_all(dir);
}

TEST(Cli, ANamedPipeInTheOutputFolderIsNamedAsOne) {
  // It said "events.csv: not a file that lash did not write is in the way".
  const fs::path dir = temp_dir("fifo");
  fs::create_directories(dir);
  ASSERT_EQ(::mkfifo((dir / "events.csv").c_str(), 0644), 0);
  const Result r = run_lash("run " + example() + " -q -o " + dir.string() + " --set solver.end_time=0.001");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("events.csv: a named pipe that lash did not write is in the way"), std::string::npos)
      << r.out;
  fs::remove_all(dir);
}

TEST(Cli, AGivenPoseWithAJournalThroughItsBearingIsRefusedAtTheJoint) {
  // initial_state: given with the slider 11 mm off: the journal lies 10.5 mm into its bearing's
  // wall, deeper than its radius (9.5 mm). `check` said ok and `run` failed at t = 0 blaming a
  // soft contact (exit 1); now both refuse it at the joint (exit 2), as a continued state is.
  const fs::path dir = temp_dir("given_through");
  fs::create_directories(dir);
  std::string text = lash::test::read_file(example());
  const std::string pose = "position: [0.17, 0]";
  ASSERT_NE(text.find(pose), std::string::npos);
  text.replace(text.find(pose), pose.size(), "position: [0.181, 0]");
  std::ofstream(dir / "m.yaml") << text;
  for (const std::string& args : {std::string(), " -q -o " + (dir / "out").string()}) {
    const Result r = run_lash((args.empty() ? "check " : "run ") + (dir / "m.yaml").string() + args +
                              " --set solver.initial_state=given");
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find("joint 'rod_slider': at the start the journal lies 0.0105 m into its "
                         "bearing's wall, as deep as its own radius 0.0095 m or deeper"),
              std::string::npos) << r.out;
  }
  fs::remove_all(dir);
}

TEST(Cli, AModelRefusedAtAssemblyIsReportedAtTheElement) {
  // A second driver of the crank, written in the file: refused when the model is assembled,
  // which had no line ("m.yaml: driver 'b': ..."); now at the driver, by check and run alike.
  const fs::path dir = temp_dir("assembly_line");
  fs::create_directories(dir);
  std::string text = lash::test::read_file(example());
  // After the crank's driver (its last line holds speed_rpm).
  const size_t rpm = text.find("speed_rpm", text.find("drivers:\n"));
  ASSERT_NE(rpm, std::string::npos);
  text.insert(text.find('\n', rpm) + 1, "  b: {body: crank, coordinate: phi, speed_rpm: 5000}\n");
  std::ofstream(dir / "m.yaml") << text;
  int line = 1;
  for (size_t i = 0; i < text.find("  b: {body"); ++i) line += text[i] == '\n';
  const std::string said = (dir / "m.yaml").string() + ":" + std::to_string(line) +
                           ":6: driver 'b': its equation is redundant with driver 'crank'";
  for (const std::string& args : {std::string(), " -q -o " + (dir / "out").string()}) {
    const Result r = run_lash((args.empty() ? "check " : "run ") + (dir / "m.yaml").string() + args);
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find(said), std::string::npos) << r.out;
  }
  // The same driver 0.1 rad apart from the crank's: assembly cannot close it, and said only
  // "initial assembly failed: ... (largest residual 0.0707); check the markers", at no line.
  const size_t b = text.find("  b: {body");
  text.replace(b, text.find('\n', b) - b, "  b: {body: crank, coordinate: phi, motion: \"0.1 + 523.6*time\"}");
  std::ofstream(dir / "m.yaml") << text;
  const Result r = run_lash("check " + (dir / "m.yaml").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find((dir / "m.yaml").string() + ":" + std::to_string(line) +
                       ":6: driver 'b': initial assembly failed: its equation is redundant with "
                       "driver 'crank' and disagrees with them by 0.0707"),
            std::string::npos)
      << r.out;
  fs::remove_all(dir);
}

TEST(Cli, CheckTakesAModelWithAStrayModelKeyForAModel) {
  // `model: foo` above a model's bodies: `lash check` read it as a study and listed nine
  // "study: unknown key 'bodies'" problems; `lash run` said the one that it is.
  const fs::path dir = temp_dir("stray_model_key");
  fs::create_directories(dir);
  std::ofstream(dir / "m.yaml") << "model: foo\n" << lash::test::read_file(example());
  const Result r = run_lash("check " + (dir / "m.yaml").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("m.yaml:1:1: model: unknown key 'model'"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("1 problem found"), std::string::npos) << r.out;
  fs::remove_all(dir);
}

TEST(Cli, AClosedPipeOnStdoutIsNotTheEndOfARun) {
  // `lash run ... | head -0`: the closing line cannot be written; the run's files are whole and
  // it exits 0, not 141 (SIGPIPE), so a script with `set -o pipefail` sees a good run.
  const fs::path dir = temp_dir("pipe");
  const Result r = run_lash_raw("bash -c 'set -o pipefail; " + std::string(LASH_BINARY) + " run " +
                                example() + " -o " + dir.string() +
                                " --set solver.end_time=0.002 | head -c 0; echo rc=$?'");
  EXPECT_NE(r.out.find("rc=0"), std::string::npos) << r.out;
  EXPECT_EQ(read_summary(dir)["status"]["outcome"], "completed");
  fs::remove_all(dir);
}

TEST(Cli, AFullDiskIsAWriteError) {
  // A real full file system: a 256 KiB tmpfs in a private mount namespace (needs the right to
  // mount; skipped otherwise). The results are copied out before the namespace ends.
  const fs::path dir = temp_dir("fulldisk");
  fs::create_directories(dir / "mnt");
  fs::create_directories(dir / "kept");
  const std::string script =
      "mount -t tmpfs -o size=256k tmpfs '" + (dir / "mnt").string() + "' || exit 99; '" +
      std::string(LASH_BINARY) + "' run '" + example() + "' -q -o '" + (dir / "mnt" / "out").string() +
      "' --set solver.end_time=0.1; rc=\\$?; cp '" + (dir / "mnt" / "out").string() + "'/* '" +
      (dir / "kept").string() + "'/; exit \\$rc";
  const Result r = run_lash_raw("unshare -m sh -c \"" + script + "\" 2>&1");
  if (r.code == 99 || r.out.find("unshare failed") != std::string::npos ||
      r.out.find("Operation not permitted") != std::string::npos)
    GTEST_SKIP() << "cannot mount a tmpfs here: " << r.out;
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("No space left on device"), std::string::npos) << r.out;
  const auto summary = read_summary(dir / "kept");
  EXPECT_EQ(summary["status"]["outcome"], "write_error");
  expect_whole_rows(dir / "kept" / "timeseries.csv");
  EXPECT_EQ(summary["integrator"]["outputs"].get<long>() + 1,
            static_cast<long>(line_count(dir / "kept" / "timeseries.csv")));
  fs::remove_all(dir);
}

TEST(Cli, OutputFolderNamesRunNoCommands) {
  // Quotes, spaces and $(...) in the folder's name: the figures step starts Python without a
  // shell, so nothing runs and the figures are drawn.
  const fs::path dir = temp_dir("names");
  fs::create_directories(dir);
  const std::string name = "it's a $(touch PWNED2) x';touch PWNED;'";
  const fs::path out = dir / name;
  const Result r = run_lash_raw("cd '" + dir.string() + "' && " + std::string(LASH_BINARY) +
                                " run " + example() + " -q --report --set solver.end_time=0.003 -o \"" +
                                "it's a \\$(touch PWNED2) x';touch PWNED;'\"");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(fs::exists(out / "summary.json")) << r.out;
  EXPECT_TRUE(fs::exists(out / "report.html"));
  EXPECT_FALSE(fs::exists(dir / "PWNED"));
  EXPECT_FALSE(fs::exists(dir / "PWNED2"));
  // A folder named like an option: the figures tool gets an absolute path, not "-h".
  const Result dash = run_lash_raw("cd '" + dir.string() + "' && " + std::string(LASH_BINARY) + " run " +
                                   example() + " -q --report --set solver.end_time=0.003 --output=-h");
  ASSERT_EQ(dash.code, 0) << dash.out;
  if (std::system("/usr/bin/python3 -c 'import matplotlib' 2>/dev/null") == 0) {
    EXPECT_TRUE(fs::exists(dir / "-h" / "figures" / "acceleration_peak.png"))
        << lash::test::read_file((dir / "-h" / "figures.log").string());
  }
  if (fs::exists("/usr/bin/python3") && std::system("/usr/bin/python3 -c 'import matplotlib' 2>/dev/null") == 0) {
    EXPECT_NE(r.out.find("figures failed"), 0u);
    EXPECT_TRUE(fs::exists(out / "figures")) << lash::test::read_file((out / "figures.log").string());
  }
  fs::remove_all(dir);
}

TEST(Cli, AnEmptyOutputFolderIsRefused) {
  // `-o ""` (an unset shell variable) wrote into out/<model name> without a word.
  const fs::path dir = temp_dir("empty_o");
  fs::create_directories(dir);
  for (const std::string& cmd : {"run " + example(), std::string("sweep study.yaml")}) {
    const Result r = run_lash_raw("cd '" + dir.string() + "' && " + std::string(LASH_BINARY) + " " +
                                  cmd + " -q -o ''");
    EXPECT_EQ(r.code, 2) << cmd << "\n" << r.out;
    EXPECT_NE(r.out.find("--output: is empty: name a folder, or leave out -o"), std::string::npos)
        << r.out;
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}

TEST(Cli, AnOutputFolderNamedByAFileIsAMistakenOption) {
  // `-o results.csv` (a file) was a failed write, exit 3 with "Not a directory".
  const fs::path dir = temp_dir("o_file");
  fs::create_directories(dir);
  const fs::path file = dir / "results.csv";
  std::ofstream(file) << "kept\n";
  const std::string study = std::string(LASH_SOURCE_DIR) + "/studies/flores_clearance.yaml";
  for (const std::string& cmd : {"run " + example(), "sweep " + study}) {
    const Result r = run_lash(cmd + " -q -o " + file.string());
    EXPECT_EQ(r.code, 2) << cmd << "\n" << r.out;
    EXPECT_NE(r.out.find(file.string() + ": exists and is not a folder"), std::string::npos) << r.out;
    EXPECT_EQ(lash::test::read_file(file.string()), "kept\n");
    // A path through the file (results.csv/sub) is the same mistake: it exited 3 as a failed
    // write.
    const Result through = run_lash(cmd + " -q -o " + (file / "sub").string());
    EXPECT_EQ(through.code, 2) << cmd << "\n" << through.out;
    EXPECT_NE(through.out.find("a part of this path is a file, not a folder"), std::string::npos)
        << through.out;
    EXPECT_EQ(lash::test::read_file(file.string()), "kept\n");
  }
  fs::remove_all(dir);
}

TEST(Cli, ChannelsThatNameNoPatternAreRefused) {
  // `--channels ','` wrote every channel, as if the option were not given.
  for (const std::string list : {",", " , ", ""}) {
    const Result r = run_lash("run " + example() + " -q -o /nonexistent/x --channels '" + list + "'");
    EXPECT_EQ(r.code, 2) << list << "\n" << r.out;
    EXPECT_NE(r.out.find("--channels: names no channel pattern"), std::string::npos) << r.out;
  }
}

TEST(Cli, AFolderHoldsOneRunAtATime) {
  const fs::path dir = temp_dir("twice");
  // The first run holds the folder for seconds; the second is refused with exit 2 and names it.
  FILE* first = popen((std::string(LASH_BINARY) + " run " + example() + " -q -o " + dir.string() +
                       " --set solver.end_time=0.5 2>&1").c_str(), "r");
  ASSERT_NE(first, nullptr);
  for (int i = 0; i < 200 && !fs::exists(dir / "timeseries.csv"); ++i) usleep(10000);
  const Result second = run_lash("run " + example() + " -q -o " + dir.string() + " --set solver.end_time=0.001");
  const Result analyze = run_lash("analyze " + dir.string());
  const int status = pclose(first);
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(second.code, 2) << second.out;
  EXPECT_NE(second.out.find("is in use by another lash (process "), std::string::npos) << second.out;
  EXPECT_EQ(analyze.code, 2) << analyze.out;
  EXPECT_NE(analyze.out.find("is in use by another lash (process "), std::string::npos) << analyze.out;
  // The first run's results are whole and its own.
  const auto summary = read_summary(dir);
  EXPECT_EQ(summary["status"]["outcome"], "completed");
  EXPECT_EQ(summary["solver"]["end_time"].get<double>(), 0.5);
  EXPECT_EQ(summary["integrator"]["outputs"].get<long>() + 1,
            static_cast<long>(line_count(dir / "timeseries.csv")));
  // Continuing a run into its own folder would replace the state being read: refused.
  const Result same = run_lash("run " + example() + " -q -o " + dir.string() + " --set solver.end_time=0.6 --from " +
                               (dir / "final_state.json").string());
  EXPECT_EQ(same.code, 2) << same.out;
  EXPECT_NE(same.out.find("whose files this run replaces"), std::string::npos) << same.out;
  // The same through a symbolic link to the state file elsewhere.
  fs::create_directories(dir.string() + "_links");
  fs::create_symlink(dir / "final_state.json", dir.string() + "_links/s.json");
  const Result linked = run_lash("run " + example() + " -q -o " + dir.string() +
                                 " --set solver.end_time=0.6 --from " + dir.string() + "_links/s.json");
  EXPECT_EQ(linked.code, 2) << linked.out;
  EXPECT_EQ(read_summary(dir)["solver"]["end_time"].get<double>(), 0.5);
  fs::remove_all(dir.string() + "_links");
  fs::remove_all(dir);
}

TEST(Cli, PeaksOffTheHarmonicsAreCountedOnlyWhereTheSpectrumCanTell) {
  // Over 4 periods or fewer, two bins reach half-way between the crank's harmonics: no peak
  // can be off them, and the evidence said "0 strong spectral peaks off the driving harmonics"
  // of a contact force with its top peaks at 1.5-2.2 kHz against 83 Hz harmonics.
  const fs::path dir = temp_dir("off_harmonic");
  ASSERT_EQ(run_lash("run " + example() + " -q -o " + dir.string() +
                     " --set solver.end_time=0.072 --set solver.output_interval=1e-4").code, 0);
  Result r = run_lash("analyze " + dir.string() + " --no-lyapunov --discard 3");  // 3 periods
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.find("off the driving harmonics"), std::string::npos) << r.out;
  r = run_lash("analyze " + dir.string() + " --no-lyapunov --discard 0");  // 6 periods
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("off the driving harmonics"), std::string::npos) << r.out;
  fs::remove_all(dir);
}

TEST(Cli, AnalysisOptionsAreRangeChecked) {
  const fs::path dir = temp_dir("options");
  ASSERT_EQ(run_lash("run " + example() + " -q -o " + dir.string() + " --set solver.end_time=0.003").code, 0);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"analyze --window 5,1", "--window 5,1: T0 must be less than T1"},
      {"report --window nan,1", "--window nan,1: both times must be finite numbers"},
      {"analyze --discard -1", "--discard -1: expected a whole number of periods"},
      {"analyze --lyapunov-d0 nan", "--lyapunov-d0 nan: expected a separation in [1e-12, 1e-3] m"},
      // Below the positions' round-off (gave an exponent of nonsense).
      {"analyze --lyapunov-d0 1e-300", "--lyapunov-d0 1e-300: expected a separation in"},
      {"analyze --lyapunov-method qr", "--lyapunov-method qr: expected variational or two-trajectory"},
      {"analyze --plane slider.x=nan", "value 'nan' is not a finite number"},
      // Two planes were pooled into one map: a period-1 orbit read as period-2.
      {"report --plane slider.x=0.1 --plane slider.x=0.12", "--plane: one section plane per analysis (2 given)"},
      {"report --angle-range 0,inf", "--angle-range 0,inf: both angles must be numbers in [0, 360]"},
      // The crank angle is in [0, 360): -30,30 selected 0..30 only; ±1e300 broke the figures.
      {"report --angle-range -30,30", "--angle-range -30,30: both angles must be numbers in [0, 360]"},
      {"report --angle-range -1e300,1e300", "--angle-range -1e+300,1e+300: both angles"},
      // No interval: accepted, then "no output row lies in the window".
      {"analyze --angle-range 10,10", "--angle-range 10,10: the two angles must differ"},
      {"analyze --angle-range 360,0", "--angle-range 360,0: the two angles must differ"},
      // Sections and renormalisations without bound (1e-9 ran out of memory).
      {"analyze --period 1e-9", "--period 1e-09: shorter than the run's output interval (1e-05 s)"}};
  for (const auto& [args, message] : cases) {
    const auto space = args.find(' ');
    const Result r = run_lash(args.substr(0, space) + " " + dir.string() + args.substr(space));
    EXPECT_EQ(r.code, 2) << args << "\n" << r.out;
    EXPECT_NE(r.out.find(message), std::string::npos) << args << "\n" << r.out;
  }
  EXPECT_FALSE(fs::exists(dir / "analysis.json"));
  EXPECT_FALSE(fs::exists(dir / "report.html"));
  fs::remove_all(dir);
}

TEST(Cli, TheIdealTwinsRedundantJointIsSaid) {
  // A double parallelogram whose third coupler pin has clearance: the run has no redundant
  // equation, its ideal twin (every clearance joint ideal) has one. analyze said nothing of it.
  const fs::path dir = temp_dir("twin_redundant");
  fs::create_directories(dir);
  std::ofstream(dir / "dp.yaml") << R"Y(gravity: [0, -9.81]
ground: {markers: {G0: [0, 0], G1: [1, 0], G2: [2, 0]}}
bodies:
  crank_0: {mass: 1, inertia: 0.08, position: [0.25, 0.4330127018922193], angle: 1.0471975511965976, markers: {O: [-0.5, 0], A: [0.5, 0]}}
  crank_1: {mass: 1, inertia: 0.08, position: [1.25, 0.4330127018922193], angle: 1.0471975511965976, markers: {O: [-0.5, 0], A: [0.5, 0]}}
  crank_2: {mass: 1, inertia: 0.08, position: [2.25, 0.4330127018922193], angle: 1.0471975511965976, markers: {O: [-0.5, 0], A: [0.5, 0]}}
  coupler: {mass: 2, inertia: 0.5, position: [1.5, 0.8660254037844386], markers: {P0: [-1, 0], P1: [0, 0], P2: [1, 0]}}
clearance_defaults:
  journal_radius: 9.5e-3
  material: {youngs_modulus: 207e9, poisson_ratio: 0.3}
  normal_law: lankarani_nikravesh
  restitution: 0.9
  friction: {law: none}
joints:
  pivot_0: {type: revolute, journal: crank_0.O, bearing: ground.G0}
  coupler_0: {type: revolute, journal: crank_0.A, bearing: coupler.P0}
  pivot_1: {type: revolute, journal: crank_1.O, bearing: ground.G1}
  coupler_1: {type: revolute, journal: crank_1.A, bearing: coupler.P1}
  pivot_2: {type: revolute, journal: crank_2.O, bearing: ground.G2}
  coupler_2: {type: revolute, journal: crank_2.A, bearing: coupler.P2, clearance: 0.5e-3}
drivers:
  motor: {joint: pivot_0, speed_rpm: 60}
solver: {end_time: 0.05, output_interval: 0.001, rtol: 1.0e-8, atol: 1.0e-11}
)Y";
  const Result run = run_lash("run " + (dir / "dp.yaml").string() + " -q -o " + (dir / "out").string());
  ASSERT_EQ(run.code, 0) << run.out;
  EXPECT_EQ(run.out.find("redundant"), std::string::npos) << run.out;
  const Result r = run_lash("analyze " + (dir / "out").string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("ideal twin: not saved by a run, simulated now; warning: joint 'coupler_2': "
                       "1 of its 2 equations is redundant with"),
            std::string::npos)
      << r.out;

  // lash check says what assembly finds, as lash run does (it said only "ok").
  const Result clearance = run_lash("check " + (dir / "dp.yaml").string());
  EXPECT_EQ(clearance.code, 0) << clearance.out;
  EXPECT_EQ(clearance.out.find("warning"), std::string::npos) << clearance.out;
  {
    std::ifstream in(dir / "dp.yaml");
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string gap = ", clearance: 0.5e-3";
    ASSERT_NE(text.find(gap), std::string::npos);
    text.erase(text.find(gap), gap.size());
    std::ofstream(dir / "ideal.yaml") << text;
  }
  const Result ideal = run_lash("check " + (dir / "ideal.yaml").string());
  EXPECT_EQ(ideal.code, 0) << ideal.out;
  EXPECT_NE(ideal.out.find("ideal.yaml:20:14: warning: joint 'coupler_2': 1 of its 2 equations is "
                           "redundant with"),
            std::string::npos)
      << ideal.out;
  EXPECT_NE(ideal.out.find("ideal.yaml: ok: 4 bodies, 6 joints (0 with clearance)"), std::string::npos)
      << ideal.out;
  fs::remove_all(dir);
}

TEST(Cli, ADamagedRunFolderIsNamedNotReported) {
  const fs::path dir = temp_dir("damaged");
  ASSERT_EQ(run_lash("run " + example() + " -q -o " + dir.string() + " --set solver.end_time=0.003").code, 0);
  // An edited model: the report would describe a run that never happened.
  const std::string model = lash::test::read_file((dir / "model_resolved.yaml").string());
  std::ofstream(dir / "model_resolved.yaml") << model << "# edited\n";
  Result r = run_lash("report " + dir.string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("model_resolved.yaml: differs from the model this run used"), std::string::npos) << r.out;
  std::ofstream(dir / "model_resolved.yaml") << model;
  // A cut summary.json.
  const std::string summary = lash::test::read_file((dir / "summary.json").string());
  std::ofstream(dir / "summary.json") << summary.substr(0, summary.size() / 2);
  r = run_lash("analyze " + dir.string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("summary.json: damaged (not valid JSON"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "report.html"));
  EXPECT_FALSE(fs::exists(dir / "analysis.json"));
  std::ofstream(dir / "summary.json") << summary;

  // Each damage class: the file is named, exit 2, and nothing is written (no report, no
  // report_data.json, no analysis.json). The folder is restored between cases.
  const std::string csv = lash::test::read_file((dir / "timeseries.csv").string());
  const std::string events = lash::test::read_file((dir / "events.csv").string());
  const size_t last_row = csv.rfind('\n', csv.size() - 2) + 1;
  const size_t third_row = [&] {
    size_t p = 0;
    for (int i = 0; i < 3; ++i) p = csv.find('\n', p) + 1;
    return p;
  }();
  auto with_field = [&](const std::string& field) {  // the third row's second field replaced
    std::string t = csv;
    const size_t a = t.find(',', third_row) + 1;
    return t.replace(a, t.find(',', a) - a, field);
  };
  auto interrupted = [&] {
    auto j = nlohmann::json::parse(summary);
    j["status"]["outcome"] = "interrupted";
    return j.dump(2);
  };
  struct Case {
    std::string what, file, text, message;
  };
  const std::vector<Case> cases = {
      {"last row cut in half", "timeseries.csv", csv.substr(0, last_row + (csv.size() - last_row) / 2),
       "timeseries.csv:" + std::to_string(line_count(dir / "timeseries.csv")) + ": the last row is cut (no line end)"},
      {"last row missing", "timeseries.csv", csv.substr(0, last_row), "timeseries.csv: 300 rows, summary.json says 301: cut or edited"},
      {"a field missing", "timeseries.csv", with_field("1,2").replace(with_field("1,2").find("1,2"), 4, ""),
       "timeseries.csv:4: "},
      {"an extra field", "timeseries.csv", with_field("1,2"), "timeseries.csv:4: more than"},
      {"not a number", "timeseries.csv", with_field("abc"), "timeseries.csv:4:"},
      {"events cut", "events.csv", events.substr(0, events.size() - 3), "events.csv:"},
      {"summary of an interrupted run", "summary.json", interrupted(),
       "summary.json: the run did not complete (status.outcome interrupted"},
  };
  for (const Case& c : cases) {
    std::ofstream(dir / c.file) << c.text;
    for (const char* command : {"report", "analyze"}) {
      r = run_lash(std::string(command) + " " + dir.string());
      EXPECT_EQ(r.code, 2) << c.what << "\n" << r.out;
      EXPECT_NE(r.out.find(c.message), std::string::npos) << c.what << "\n" << r.out;
      EXPECT_EQ(r.out.find("wrote"), std::string::npos) << c.what << "\n" << r.out;
      for (const char* f : {"report.html", "report_data.json", "analysis.json", "figures"})
        EXPECT_FALSE(fs::exists(dir / f)) << c.what << ": " << f;
    }
    std::ofstream(dir / "timeseries.csv") << csv;
    std::ofstream(dir / "events.csv") << events;
    std::ofstream(dir / "summary.json") << summary;
  }
  // A file missing.
  for (const char* f : {"events.csv", "timeseries.csv", "final_state.json", "summary.json"}) {
    const std::string keep = lash::test::read_file((dir / f).string());
    fs::remove(dir / f);
    r = run_lash("report " + dir.string());
    EXPECT_EQ(r.code, 2) << f << "\n" << r.out;
    EXPECT_NE(r.out.find((dir / f).string() + ": missing"), std::string::npos) << f << "\n" << r.out;
    EXPECT_FALSE(fs::exists(dir / "report.html"));
    std::ofstream(dir / f) << keep;
  }
  // The folder restored: the report reads it and says what it simulated again.
  r = run_lash("report " + dir.string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("read: time series: timeseries.csv (301 rows"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("simulated now: ideal twin"), std::string::npos) << r.out;
  const auto data = nlohmann::json::parse(std::ifstream(dir / "report_data.json"));
  EXPECT_FALSE(data["provenance"]["read"].empty());
  EXPECT_FALSE(data["provenance"]["resimulated"].empty());
  fs::remove_all(dir);
}

TEST(Cli, SpecialFilesAreNotReadAsModels) {
  for (const std::string path : {"/dev/zero", "/dev/null"}) {
    const Result r = run_lash("check " + path);
    EXPECT_EQ(r.code, 2) << path << "\n" << r.out;
    EXPECT_NE(r.out.find(path + ": cannot read the model file: not a regular file"), std::string::npos) << r.out;
  }
}

TEST(Cli, TheSameRunGetsTheSameVerdictEverywhere) {
  // 17 crank periods of the Flores example: analyze, report and the summary of run --report
  // print the same class, evidence and rule.
  const fs::path dir = temp_dir("verdict");
  const Result run = run_lash("run " + example() + " -q --report -o " + dir.string() +
                              " --set solver.end_time=0.204");
  ASSERT_EQ(run.code, 0) << run.out;
  const auto in_summary = read_summary(dir)["verdict"];
  const auto in_report = nlohmann::json::parse(std::ifstream(dir / "report_data.json"))["analysis"]["verdict"];
  const Result analyze = run_lash("analyze " + dir.string());
  ASSERT_EQ(analyze.code, 0) << analyze.out;
  const auto in_analysis = nlohmann::json::parse(std::ifstream(dir / "analysis.json"))["verdict"];
  EXPECT_EQ(in_summary, in_report);
  EXPECT_EQ(in_summary, in_analysis);
  EXPECT_EQ(in_summary["class"], "chaotic");
  EXPECT_NE(in_summary["evidence"][1].get<std::string>().find("in 17 sections"), std::string::npos);
  EXPECT_NE(analyze.out.find("verdict: " + in_summary["class"].get<std::string>()), std::string::npos);
  EXPECT_NE(analyze.out.find("rule: after the transient, with at least 16 Poincaré sections"),
            std::string::npos) << analyze.out;
  fs::remove_all(dir);
}

TEST(Cli, ARunRemovesOnlyWhatLashWrote) {
  // A user's figures/ folder in the output folder (no .lash-figures mark) is not deleted: the run
  // is refused (exit 2) and the folder and its file survive. A failed assembly leaves an earlier
  // run's results untouched.
  const fs::path dir = temp_dir("keep");
  fs::create_directories(dir / "figures");
  std::ofstream(dir / "figures" / "fig1.pdf") << "mine";
  Result r = run_lash("run " + example() + " -q -o " + dir.string() + " --set solver.end_time=0.002");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("figures: a folder that lash did not write is in the way"), std::string::npos) << r.out;
  EXPECT_EQ(lash::test::read_file((dir / "figures" / "fig1.pdf").string()), "mine");
  fs::remove_all(dir / "figures");
  // Refused before anything is removed: an earlier run's files stay with the user's folder.
  ASSERT_EQ(run_lash("run " + example() + " -q -o " + dir.string() + " --set solver.end_time=0.002").code, 0);
  fs::create_directories(dir / "figures");
  EXPECT_EQ(run_lash("run " + example() + " -q -o " + dir.string() + " --set solver.end_time=0.002").code, 2);
  EXPECT_TRUE(fs::exists(dir / "summary.json"));
  EXPECT_TRUE(fs::exists(dir / "timeseries.csv"));
  // lash report on that folder is refused before it writes anything (it wrote report.html and
  // report_data.json, and then exited 2).
  r = run_lash("report " + dir.string() + " --no-lyapunov");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("a folder that lash did not write is in the way"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "report.html"));
  EXPECT_FALSE(fs::exists(dir / "report_data.json"));
  fs::remove_all(dir / "figures");
  // A run with its report: the figures are lash's and the next run replaces them.
  r = run_lash("run " + example() + " -q --report -o " + dir.string() + " --set solver.end_time=0.002");
  ASSERT_EQ(r.code, 0) << r.out;
  ASSERT_TRUE(fs::exists(dir / "figures" / ".lash-figures"));
  r = run_lash("run " + example() + " -q -o " + dir.string() + " --set solver.end_time=0.003");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_FALSE(fs::exists(dir / "figures"));
  EXPECT_FALSE(fs::exists(dir / "report.html")) << "a report of the earlier run beside new results";
  // A model that cannot be assembled: exit 2, and the earlier results are all still there.
  const std::string before = lash::test::read_file((dir / "summary.json").string());
  r = run_lash("run " + example() + " -q -o " + dir.string() +
               " --set ground.markers.G=[0,1] --set joints.slider_guide.guide=ground.G");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("is unchanged"), std::string::npos) << r.out;
  EXPECT_EQ(lash::test::read_file((dir / "summary.json").string()), before);
  expect_whole_rows(dir / "timeseries.csv");
  EXPECT_EQ(read_summary(dir)["integrator"]["outputs"].get<long>() + 1,
            static_cast<long>(line_count(dir / "timeseries.csv")));
  fs::remove_all(dir);
}

TEST(Cli, SignalsAfterTheRunAndIgnoredSignals) {
  const fs::path dir = temp_dir("late_signal");
  // SIGTERM during run --report: whether it lands in the run or in the analyses after it, the
  // command exits 130 and no report stands beside the results. In the run, summary.json says
  // interrupted; after it (the usual case here: the run takes well under 2 s), the results are
  // whole, so the outcome is completed and the folder can be analysed and continued (it said
  // interrupted at t = end_time, and `report`, `analyze` and `--from` all refused the folder).
  Result r = run_lash_raw("timeout --foreground --preserve-status -s TERM 2 " + std::string(LASH_BINARY) + " run " +
                          example() + " -q --report -o " + dir.string() + " --set solver.end_time=0.3");
  EXPECT_EQ(r.code, 130) << r.out;
  for (const char* f : {"report.html", "report_data.json", "figures", "figures.log"})
    EXPECT_FALSE(fs::exists(dir / f)) << f;
  expect_whole_rows(dir / "timeseries.csv");
  const nlohmann::json late = read_summary(dir);
  if (late["status"]["outcome"] == "completed") {
    EXPECT_EQ(late["status"]["time"].get<double>(), 0.3);
    EXPECT_EQ(late["interrupted_after_run"]["signal"], SIGTERM) << late.dump();
    EXPECT_FALSE(late.contains("verdict")) << "a verdict from analyses cut short";
    EXPECT_NE(r.out.find("are as the run left them; `lash report"), std::string::npos) << r.out;
    const Result analysed = run_lash("analyze " + dir.string());
    EXPECT_EQ(analysed.code, 0) << analysed.out;
    const fs::path more = temp_dir("late_signal_more");
    const Result continued = run_lash("run " + example() + " -q -o " + more.string() + " --from " +
                                      (dir / "final_state.json").string() +
                                      " --set solver.end_time=0.301");
    EXPECT_EQ(continued.code, 0) << continued.out;
    fs::remove_all(more);
  } else {
    EXPECT_EQ(late["status"]["outcome"], "interrupted") << late.dump();
    EXPECT_FALSE(late.contains("interrupted_after_run"));
  }
  // A SIGHUP the parent ignores (nohup) stays ignored: the run completes.
  r = run_lash_raw("sh -c \"trap '' HUP; exec " + std::string(LASH_BINARY) + " run " + example() +
                   " -q -o " + dir.string() + " --set solver.end_time=1\" & p=$!; sleep 0.3; "
                   "kill -HUP $p || exit 97; wait $p");  // 97: it ended before the signal
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(read_summary(dir)["status"]["outcome"], "completed");
  fs::remove_all(dir);
}

namespace {

/// The rows of a CSV, split into fields (header first).
std::vector<std::vector<std::string>> read_csv(const fs::path& p) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream in(p);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> f;
    size_t start = 0;
    for (size_t c; (c = line.find(',', start)) != std::string::npos; start = c + 1)
      f.push_back(line.substr(start, c - start));
    f.push_back(line.substr(start));
    rows.push_back(f);
  }
  return rows;
}

}  // namespace

TEST(Cli, ChannelsSelectTheColumnsTimeAlwaysKept) {
  const fs::path all = temp_dir("channels_all"), some = temp_dir("channels_some");
  ASSERT_EQ(run_lash("run " + example() + " -q -o " + all.string()).code, 0);
  const Result r = run_lash("run " + example() + " -q -o " + some.string() +
                            " --channels 'slider.*, rod_slider.F?,time'");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto a = read_csv(all / "timeseries.csv"), s = read_csv(some / "timeseries.csv");
  const std::vector<std::string> expected = {"time",      "slider.x",  "slider.y",     "slider.phi",
                                             "slider.vx", "slider.vy", "slider.omega", "slider.ax",
                                             "slider.ay", "slider.alpha", "rod_slider.Fn",
                                             "rod_slider.Ft", "rod_slider.Fx", "rod_slider.Fy"};
  ASSERT_EQ(s.at(0), expected);
  ASSERT_EQ(s.size(), a.size());
  // Every selected column holds the same text as in the full run.
  for (size_t c = 0; c < expected.size(); ++c) {
    const auto it = std::find(a[0].begin(), a[0].end(), expected[c]);
    ASSERT_NE(it, a[0].end()) << expected[c];
    const size_t ac = it - a[0].begin();
    for (size_t row = 1; row < a.size(); ++row)
      ASSERT_EQ(s[row].at(c), a[row].at(ac)) << expected[c] << " row " << row;
  }
  const auto j = read_summary(some);
  EXPECT_EQ(j["output"]["format"], "csv");
  EXPECT_EQ(j["output"]["rows"], 2401);
  EXPECT_EQ(j["output"]["channels"].size(), expected.size() - 1);
  // summary.json keeps the peaks of every channel, written or not.
  EXPECT_EQ(j["channels"]["crank.torque"], read_summary(all)["channels"]["crank.torque"]);
  fs::remove_all(all);
  fs::remove_all(some);
}

TEST(Cli, AnalysisOfARunWithTimeAloneSaysSo) {
  // `--channels time` wrote 5001 rows of time alone, and `lash analyze` said "no output row lies
  // in the window".
  const fs::path out = temp_dir("channels_time");
  ASSERT_EQ(run_lash("run " + example() + " -q --set solver.end_time=0.002 --channels time -o " +
                     out.string()).code, 0);
  const Result r = run_lash("analyze " + out.string());
  EXPECT_NE(r.out.find("statistics: the time series holds no channel besides time"), std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find("no output row lies in the window"), std::string::npos) << r.out;
  fs::remove_all(out);
}

TEST(Cli, ChannelPatternMatchingNothingIsAnErrorNamingTheClosest) {
  const fs::path dir = temp_dir("channels_bad");
  Result r = run_lash("run " + example() + " -q -o " + dir.string() +
                      " --channels 'slider.x,slidr.vx,TIME,Slider.AX'");
  EXPECT_EQ(r.code, 2) << r.out;
  // Every pattern that matches nothing is named (only the first was), each with the closest
  // names ranked with case ignored (TIME was told of other channels, not of time).
  EXPECT_NE(r.out.find("--channels: channel pattern 'slidr.vx' matches no channel (names are "
                       "case-sensitive); the closest are: slider.vx"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("; channel pattern 'TIME' matches no channel (names are case-sensitive); "
                       "the closest are: time"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("; channel pattern 'Slider.AX' matches no channel (names are "
                       "case-sensitive); the closest are: slider.ax"),
            std::string::npos)
      << r.out;
  EXPECT_FALSE(fs::exists(dir)) << "refused before the folder is touched";
  // The same from the model file's solver settings (here through --set), named as such.
  r = run_lash("run " + example() + " -q -o " + dir.string() + " --set solver.output_channels=rod.*,nope*");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("solver: output_channels: channel pattern 'nope*' matches no channel"),
            std::string::npos)
      << r.out;
  // lash check finds it too, at the entry's line and column (it said ok, and run refused).
  fs::create_directories(dir.parent_path());
  const fs::path oc = dir.parent_path() / "oc.yaml";
  std::ofstream(oc) << "bodies: {b: {mass: 1, inertia: 1}}\nsolver:\n  end_time: 0.01\n"
                       "  output_channels: [b.x, b.vxx]\n";
  r = run_lash("check " + oc.string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find(oc.string() + ":4:26: solver: output_channels: channel pattern 'b.vxx' matches "
                       "no channel"),
            std::string::npos)
      << r.out;
  fs::remove(oc);
  r = run_lash("run " + example() + " -q -o " + dir.string() + " --set solver.output_format=xml");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("unknown output_format 'xml', expected one of: csv, hdf5"), std::string::npos)
      << r.out;
  EXPECT_FALSE(fs::exists(dir));
}

TEST(Cli, ModelFileSelectsTheChannels) {
  const fs::path dir = temp_dir("channels_model");
  const Result r = run_lash("run " + example() + " -q -o " + dir.string() +
                            " --set solver.output_channels=rod_slider.delta,energy.balance");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto s = read_csv(dir / "timeseries.csv");
  EXPECT_EQ(s.at(0), (std::vector<std::string>{"time", "rod_slider.delta", "energy.balance"}));
  EXPECT_EQ(s.size(), 2402u);
  EXPECT_EQ(read_summary(dir)["output"]["patterns"],
            (nlohmann::json{"rod_slider.delta", "energy.balance"}));
  fs::remove_all(dir);
}

#ifdef LASH_HDF5
#include <hdf5.h>

namespace {

/// A dataset of timeseries.h5: its values and its string attributes.
struct H5Column {
  std::vector<double> values;
  std::string unit, description;
};

/// A variable-length UTF-8 string attribute ("<missing>", "<not a variable-length string>":
/// h5py returns a fixed-length one as bytes).
std::string h5_string_attribute(hid_t ds, const char* name) {
  const hid_t attr = H5Aopen(ds, name, H5P_DEFAULT);
  if (attr < 0) return "<missing>";
  const hid_t type = H5Aget_type(attr);
  std::string s = "<not a variable-length string>";
  if (H5Tis_variable_str(type) > 0 && H5Tget_cset(type) == H5T_CSET_UTF8) {
    char* text = nullptr;
    if (H5Aread(attr, type, &text) >= 0 && text) s = text;
    H5free_memory(text);
  }
  H5Tclose(type);
  H5Aclose(attr);
  return s;
}

/// Reads every dataset named in `names` from `path`.
std::map<std::string, H5Column> read_h5(const fs::path& path, const std::vector<std::string>& names) {
  std::map<std::string, H5Column> out;
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) return out;
  for (const auto& n : names) {
    const hid_t ds = H5Dopen2(f, n.c_str(), H5P_DEFAULT);
    if (ds < 0) continue;
    const hid_t space = H5Dget_space(ds);
    hsize_t dims[1] = {0};
    H5Sget_simple_extent_dims(space, dims, nullptr);
    H5Column c;
    c.values.resize(dims[0]);
    H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, c.values.data());
    c.unit = h5_string_attribute(ds, "unit");
    c.description = h5_string_attribute(ds, "description");
    H5Sclose(space);
    H5Dclose(ds);
    out[n] = c;
  }
  H5Fclose(f);
  return out;
}

std::string g9(double v) {
  char s[40];
  std::snprintf(s, sizeof s, "%.9g", v);
  return s;
}

}  // namespace

TEST(Cli, Hdf5HoldsTheCsvValuesInFullWithUnits) {
  // 0.06 s = 6001 rows: more than one chunk of 4096, so rows are appended as the run goes.
  const fs::path csv = temp_dir("h5_csv"), h5 = temp_dir("h5_h5");
  const std::string run = "run " + example() + " -q --set solver.end_time=0.06 -o ";
  ASSERT_EQ(run_lash(run + csv.string()).code, 0);
  const Result r = run_lash(run + h5.string() + " --format hdf5");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_FALSE(fs::exists(h5 / "timeseries.csv"));
  EXPECT_TRUE(fs::exists(h5 / "events.csv"));
  const auto rows = read_csv(csv / "timeseries.csv");
  const auto& names = rows.at(0);
  const auto cols = read_h5(h5 / "timeseries.h5", names);
  ASSERT_EQ(cols.size(), names.size()) << "one dataset per column";
  const auto j = read_summary(h5);
  EXPECT_EQ(j["output"]["format"], "hdf5");
  EXPECT_EQ(j["output"]["rows"], 6001);
  EXPECT_EQ(j["integrator"]["outputs"], 6001);
  EXPECT_EQ(cols.at("time").unit, "s");
  size_t full_precision = 0;
  for (size_t c = 0; c < names.size(); ++c) {
    const H5Column& col = cols.at(names[c]);
    ASSERT_EQ(col.values.size(), rows.size() - 1) << names[c];
    if (c > 0) {
      EXPECT_EQ(col.unit, j["channels"][names[c]]["unit"].get<std::string>()) << names[c];
      EXPECT_EQ(col.description, j["channels"][names[c]]["description"].get<std::string>());
      EXPECT_FALSE(col.description.empty()) << names[c];
    }
    for (size_t k = 0; k < col.values.size(); ++k) {
      // The CSV's printed digits are the HDF5 value's, rounded to 9 significant digits.
      ASSERT_EQ(g9(col.values[k]), rows[k + 1][c]) << names[c] << " row " << k + 1;
      full_precision += std::strtod(rows[k + 1][c].c_str(), nullptr) != col.values[k];
    }
  }
  EXPECT_GT(full_precision, 1000u) << "the HDF5 values carry more than the CSV's 9 digits";
  fs::remove_all(csv);
  fs::remove_all(h5);
}

TEST(Cli, Hdf5SelectedChannelsAndAnInterruptedRun) {
  // SIGTERM during a long run: it stops at an output, and summary.json counts the rows the file
  // holds, every dataset as long as `time`.
  const fs::path dir = temp_dir("h5_term");
  const std::string cmd = std::string(LASH_BINARY) + " run " + example() + " -q -o " + dir.string() +
                          " --format hdf5 --channels 'slider.*' --set solver.end_time=2 & pid=$!; "
                          "sleep 1.5; kill -TERM $pid; wait $pid";
  const Result r = run_lash_raw(cmd);
  ASSERT_EQ(r.code, 130) << r.out;
  const auto j = read_summary(dir);
  EXPECT_EQ(j["status"]["outcome"], "interrupted");
  const long rows = j["output"]["rows"].get<long>();
  EXPECT_GT(rows, 0);
  std::vector<std::string> names = {"time"};
  for (const auto& n : j["output"]["channels"]) names.push_back(n.get<std::string>());
  EXPECT_EQ(names.size(), 10u);  // time and slider's 9 channels
  const auto cols = read_h5(dir / "timeseries.h5", names);
  ASSERT_EQ(cols.size(), names.size());
  for (const auto& [n, c] : cols) EXPECT_EQ(static_cast<long>(c.values.size()), rows) << n;
  EXPECT_NEAR(cols.at("time").values.back(), j["status"]["time"].get<double>(), 1e-12);
  fs::remove_all(dir);
}

/// Writes `value` at row `row` of the dataset `name` in `path` (a damaged file for the tests).
void write_h5_value(const fs::path& path, const std::string& name, hsize_t row, double value) {
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  const hid_t ds = H5Dopen2(f, name.c_str(), H5P_DEFAULT);
  const hid_t space = H5Dget_space(ds);
  const hsize_t start[1] = {row}, count[1] = {1};
  H5Sselect_hyperslab(space, H5S_SELECT_SET, start, nullptr, count, nullptr);
  const hid_t mem = H5Screate_simple(1, count, nullptr);
  EXPECT_GE(H5Dwrite(ds, H5T_NATIVE_DOUBLE, mem, space, H5P_DEFAULT, &value), 0);
  H5Sclose(mem);
  H5Sclose(space);
  H5Dclose(ds);
  H5Fclose(f);
}

TEST(Cli, AnHdf5TimeColumnIsCheckedAsTheCsvOne) {
  // A time that is not finite, or that does not follow the row before, is a damaged folder
  // (exit 2, naming the row), as in timeseries.csv; it was read as data.
  const fs::path dir = temp_dir("h5_time");
  ASSERT_EQ(run_lash("run " + example() + " -q -o " + dir.string() +
                     " --format hdf5 --set solver.end_time=0.003").code, 0);
  write_h5_value(dir / "timeseries.h5", "time", 5, std::nan(""));
  Result r = run_lash("analyze " + dir.string() + " --no-lyapunov");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("timeseries.h5: time of row 6 (nan) is not a finite number"), std::string::npos) << r.out;
  write_h5_value(dir / "timeseries.h5", "time", 5, 5e-5);
  write_h5_value(dir / "timeseries.h5", "time", 100, 0.5e-3);
  r = run_lash("report " + dir.string() + " --no-lyapunov");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("timeseries.h5: time of row 101 (0.00050000000000000001) does not follow"),
            std::string::npos) << r.out;
  fs::remove_all(dir);
}

TEST(Cli, AnHdf5FileThatCannotGrowKeepsItsChunksAndCloses) {
  // File-size limits (sh counts 512-byte blocks) that the first chunk (about 1.9 MB of 57
  // channels) and the third pass: exit 3 with summary.json, and a file that opens with the
  // chunks written before. A write HDF5 could not finish left a file it could not open, and
  // its exit handler crashed (139).
  // 6000 blocks and 5001 rows: the second, partial chunk is refused too (HDF5 allocates it
  // whole; sized by its 905 rows, it was started, and the file could not be opened).
  struct Case {
    int blocks;
    const char* end_time;
    long chunks;
  };
  for (const Case& c : {Case{1000, "0.12", 0}, Case{10000, "0.12", 2}, Case{6000, "0.05", 1}}) {
    const auto [blocks, end_time, chunks] = c;
    SCOPED_TRACE(blocks);
    const fs::path dir = temp_dir("h5_limit");
    const Result r = run_lash_raw("ulimit -f " + std::to_string(blocks) + "; " +
                                  std::string(LASH_BINARY) + " run " + example() + " -q -o " +
                                  dir.string() + " --format hdf5 --set solver.end_time=" + end_time);
    EXPECT_EQ(r.code, 3) << r.out;
    EXPECT_NE(r.out.find("File too large"), std::string::npos) << r.out;
    const auto j = read_summary(dir);
    EXPECT_EQ(j["status"]["outcome"], "write_error");
    EXPECT_EQ(j["output"]["rows"].get<long>(), chunks * 4096);
    if (chunks == 0)
      EXPECT_TRUE(j["output"]["last_time"].is_null()) << j["output"];
    else
      EXPECT_NEAR(j["output"]["last_time"].get<double>(), (chunks * 4096 - 1) * 1e-5, 1e-12);
    std::vector<std::string> names = {"time", "slider.x", "rod_slider.Fn"};
    const auto cols = read_h5(dir / "timeseries.h5", names);
    ASSERT_EQ(cols.size(), names.size());
    for (const auto& [n, c] : cols) EXPECT_EQ(static_cast<long>(c.values.size()), chunks * 4096) << n;
    if (chunks > 0) {
      EXPECT_NEAR(cols.at("time").values.back(), (chunks * 4096 - 1) * 1e-5, 1e-12);
    }
    fs::remove_all(dir);
  }
}
#endif

TEST(Cli, AnHdf5RunIsReadLikeACsvRun) {
  // The same run written as CSV and as HDF5: analyze reads each folder's own time series and
  // gets the same statistics (the CSV keeps 9 digits); a dataset of another length than
  // summary.json's rows, and an edited model, are refused naming the file.
  const fs::path h5 = temp_dir("h5_report"), csv = temp_dir("csv_report");
  const std::string run = "run " + example() + " -q --set solver.end_time=0.003 -o ";
  Result r = run_lash(run + h5.string() + " --format hdf5");
  if (r.code == 2 && r.out.find("without HDF5") != std::string::npos) GTEST_SKIP() << "no HDF5";
  ASSERT_EQ(r.code, 0) << r.out;
  ASSERT_EQ(run_lash(run + csv.string()).code, 0);
  r = run_lash("analyze " + h5.string() + " --no-lyapunov");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("read: time series: timeseries.h5"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("simulated now: the main run"), std::string::npos) << r.out;
  ASSERT_EQ(run_lash("analyze " + csv.string() + " --no-lyapunov").code, 0);
  using nlohmann::json;
  const json a = json::parse(lash::test::read_file((h5 / "analysis.json").string()));
  const json b = json::parse(lash::test::read_file((csv / "analysis.json").string()));
  const json& sa = a["statistics"];
  ASSERT_EQ(sa.size(), b["statistics"].size());
  for (const auto& [name, v] : sa.items()) {
    const json& w = b["statistics"][name];
    const double scale = std::max(1e-300, std::abs(w["peak"].get<double>()));
    for (const char* k : {"min", "max", "rms"})
      EXPECT_NEAR(v[k].get<double>(), w[k].get<double>(), 1e-8 * scale) << name << " " << k;
  }
  // summary.json claiming one row more than the datasets hold.
  json sum = json::parse(lash::test::read_file((h5 / "summary.json").string()));
  sum["output"]["rows"] = sum["output"]["rows"].get<long long>() + 1;
  std::ofstream(h5 / "summary.json") << sum.dump(2);
  fs::remove(h5 / "analysis.json");
  r = run_lash("analyze " + h5.string() + " --no-lyapunov");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("timeseries.h5: dataset 'time' has"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(h5 / "analysis.json"));
  fs::remove_all(h5);
  fs::remove_all(csv);
}
