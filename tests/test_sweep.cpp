// Parameter studies: study files, their runs, one run's record, the study database, the
// bifurcation diagram's period detection, and `lash sweep` as a user runs it (kill -9 and
// --resume, a failing run, the report).
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <thread>

#include "analysis/bifurcation.hpp"
#include "io/diagnostics.hpp"
#include "io/number_format.hpp"
#include "study/study_db.hpp"
#include "study/sweep.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace lash;

namespace {

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("lash_sweep_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string example() { return lash::test::example_path("flores_slider_crank.yaml"); }

/// A study file in `dir` over the Flores example; `body` is everything after `model:`.
fs::path write_study(const fs::path& dir, const std::string& body, const std::string& name = "s.yaml") {
  const fs::path p = dir / name;
  std::ofstream(p) << "study: test\nmodel: " << example() << "\n" << body;
  return p;
}

StudySpec study_text(const std::string& text) {
  return load_study_text(text, "s.yaml", [](const std::string& p) { return lash::test::read_file(p); });
}

StudySpec from_text(const std::string& body) {
  return study_text("study: test\nmodel: " + example() + "\n" + body);
}

/// The problems of a study file's whole text, one a line ("no error" if none).
std::string text_problems(const std::string& text) {
  try {
    study_text(text);
  } catch (const ModelError& e) {
    std::string all;
    for (const auto& d : e.diagnostics()) all += d.str() + "\n";
    return all;
  }
  return "no error";
}

/// The problems of a study over the Flores example; `body` is everything after `model:`.
std::string problems(const std::string& body) {
  return text_problems("study: test\nmodel: " + example() + "\n" + body);
}

struct Result {
  int code;
  std::string out;
};
Result sh(const std::string& command) {
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  std::string out;
  char buf[4096];
  while (size_t n = fread(buf, 1, sizeof buf, p)) out.append(buf, n);
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}
Result lash_cmd(const std::string& args) { return sh(std::string(LASH_BINARY) + " " + args); }

/// Rows of a query on a study database, each as "a|b|c".
std::vector<std::string> query(const fs::path& db, const std::string& sql) {
  sqlite3* h = nullptr;
  EXPECT_EQ(sqlite3_open_v2(db.c_str(), &h, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_busy_timeout(h, 5000);
  std::vector<std::string> rows;
  sqlite3_exec(
      h, sql.c_str(),
      [](void* out, int n, char** v, char**) {
        std::string row;
        for (int i = 0; i < n; ++i) row += (i ? "|" : "") + std::string(v[i] ? v[i] : "NULL");
        static_cast<std::vector<std::string>*>(out)->push_back(row);
        return 0;
      },
      &rows, nullptr);
  sqlite3_close(h);
  return rows;
}

/// Starts `lash sweep STUDY -q -j 1 -o OUT` (output to /dev/null), returns its process id.
pid_t spawn_sweep(const fs::path& study, const fs::path& out) {
  const pid_t pid = fork();
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    dup2(null, 1), dup2(null, 2);
    execl(LASH_BINARY, LASH_BINARY, "sweep", study.c_str(), "-q", "-j", "1", "-o", out.c_str(),
          static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

/// Waits (up to 20 s) until the study database at `db` holds `n` runs.
void wait_for_runs(const fs::path& db, int n) {
  for (int i = 0; i < 1000; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (!fs::exists(db)) continue;
    const auto rows = query(db, "select count(*) from runs");
    if (!rows.empty() && std::stoi(rows[0]) >= n) return;
  }
}

}  // namespace

TEST(StudyFile, CrossZipRangesAndCases) {
  const StudySpec cross = from_text(
      "parameters:\n"
      "  drivers.crank.speed_rpm: {from: 1000, to: 3000, count: 3}\n"
      "  joints.rod_slider.clearance: {values: [1.0e-4, 2.0e-4]}\n");
  const auto runs = study_runs(cross);
  ASSERT_EQ(runs.size(), 6u);
  // The first parameter varies slowest.
  EXPECT_EQ(runs[0].values, (std::vector<std::string>{"1000", "1.0e-4"}));
  EXPECT_EQ(runs[1].values, (std::vector<std::string>{"1000", "2.0e-4"}));
  EXPECT_EQ(runs[5].values, (std::vector<std::string>{"3000", "2.0e-4"}));
  EXPECT_EQ(runs[3].overrides.back(), "joints.rod_slider.clearance=2.0e-4");
  EXPECT_DOUBLE_EQ(runs[2].numbers[0], 2000.0);

  const StudySpec zip = from_text(
      "combine: zip\n"
      "parameters:\n"
      "  drivers.crank.speed_rpm: {values: [1000, 2000]}\n"
      "  joints.rod_slider.clearance: {values: [1.0e-4, 2.0e-4]}\n");
  ASSERT_EQ(study_runs(zip).size(), 2u);
  EXPECT_EQ(study_runs(zip)[1].values, (std::vector<std::string>{"2000", "2.0e-4"}));

  // A logarithmic range ends exactly on its bounds and is geometric in between.
  const StudySpec log = from_text(
      "parameters:\n  joints.rod_slider.clearance: {from: 1.0e-5, to: 1.0e-3, count: 3, scale: log}\n");
  const auto lr = study_runs(log);
  EXPECT_DOUBLE_EQ(lr[0].numbers[0], 1e-5);
  EXPECT_EQ(lr[1].numbers[0], 1e-4);  // in decades: exactly (exp and log gave 9.99999999999999e-05)
  EXPECT_DOUBLE_EQ(lr[2].numbers[0], 1e-3);

  // Ranges at the ends of the doubles: every level finite (1e308 to 1e308 gave inf).
  for (const char* range : {"{from: 1e308, to: 1e308, count: 1}", "{from: 1e308, to: -1e308, count: 3}",
                            "{from: 1.7976931348623157e308, to: 0, count: 4}"}) {
    const auto big = study_runs(from_text("parameters:\n  bodies.crank.mass: " + std::string(range) + "\n"));
    ASSERT_GE(big.size(), std::string(range).find("count: 1}") != std::string::npos ? 1u : 3u) << range;
    for (const auto& run : big) EXPECT_TRUE(std::isfinite(run.numbers[0])) << range << ": " << run.values[0];
    EXPECT_EQ(big[0].numbers[0], std::strtod(std::string(range).substr(7).c_str(), nullptr)) << range;
  }

  // Cases: named sets of overrides, one of them another model file.
  const StudySpec cases = from_text(
      "parameters:\n"
      "  location:\n"
      "    cases:\n"
      "      rod_slider: {}\n"
      "      crank_rod: {model: " + lash::test::example_path("flores_slider_crank_crank_rod_clearance.yaml") +
      ", joints.crank_rod.clearance: 2.0e-4}\n");
  const auto cr = study_runs(cases);
  ASSERT_EQ(cr.size(), 2u);
  EXPECT_EQ(cr[1].values[0], "crank_rod");
  EXPECT_NE(cr[1].model.find("crank_rod_clearance"), std::string::npos);
  EXPECT_EQ(cr[1].overrides.back(), "joints.crank_rod.clearance=2.0e-4");
  EXPECT_EQ(cr[0].model, cases.model);
}

TEST(StudyFile, ALevelListedTwiceIsRefusedWhereItIs) {
  // The same run made twice, and a report with two points for one value: refused at the second
  // occurrence; numbers compare as numbers.
  const auto problem = [](const std::string& params, const std::string& extra = "") {
    try {
      from_text(extra + "parameters:\n" + params);
    } catch (const ModelError& e) {
      return e.diagnostics().front().str();
    }
    return std::string("accepted");
  };
  EXPECT_EQ(problem("  drivers.crank.speed_rpm: {values: [4000, 5000, 5.0e3]}\n"),
            "s.yaml:4:50: parameter 'drivers.crank.speed_rpm': level 5.0e3 is listed twice (levels 2 "
            "and 3); its runs would be made twice");
  EXPECT_NE(problem("  drivers.crank.speed_rpm: {from: 4000, to: 4000, count: 3}\n")
                .find("s.yaml:4:28: parameter 'drivers.crank.speed_rpm': level 4000 comes twice from the range"),
            std::string::npos);
  EXPECT_NE(problem("  solver.integrator: {values: [bdf, dopri5, bdf]}\n").find("level bdf is listed twice"),
            std::string::npos);
  // Lists and maps compare entry by entry, numbers as numbers.
  EXPECT_NE(problem("  gravity: {values: [[0, -9.81], [0.0, -9.81]]}\n")
                .find("parameter 'gravity': level [0.0, -9.81] is listed twice (levels 1 and 2)"),
            std::string::npos);
  EXPECT_EQ(problem("  gravity: {values: [[0, -9.81], [0, -9.8]]}\n"), "accepted");
  EXPECT_NE(problem("  joints.rod_slider.friction: {values: [{law: none}, {law: none}]}\n")
                .find("is listed twice"),
            std::string::npos);
  // zip: a parameter may repeat a level; a whole row may not.
  EXPECT_EQ(problem("  drivers.crank.speed_rpm: {values: [4000, 5000, 4000]}\n"
                    "  joints.rod_slider.clearance: {values: [1.0e-4, 2.0e-4, 3.0e-4]}\n", "combine: zip\n"),
            "accepted");
  EXPECT_NE(problem("  drivers.crank.speed_rpm: {values: [4000, 5000, 4000]}\n"
                    "  joints.rod_slider.clearance: {values: [1.0e-4, 2.0e-4, 1.0e-4]}\n", "combine: zip\n")
                .find("combine: zip: levels 1 and 3 are the same in every parameter"),
            std::string::npos);
  // A continuation chain may come back to a level: from another state, another run.
  EXPECT_EQ(problem("  drivers.crank.speed_rpm: {values: [8000, 2000, 8000]}\n", "continuation: up\n"),
            "accepted");
}

TEST(StudyFile, AStudysModelOfTheWrongKindAndARefusedMaxAreSaidOnce) {
  // `model: [m.yaml]` was "'model' is missing" at 1:1; a max of .inf added "sampling: no
  // parameter has min/max to draw", the parameter having been dropped with its error.
  EXPECT_EQ(text_problems("study: s\nmodel: [m.yaml]\nparameters: {a: {values: [1]}}\n"),
            "s.yaml:2:8: model: expected the base model file's name (relative to this file), got a list\n");
  EXPECT_EQ(text_problems("study: s\nmodel: " + example() +
                          "\nparameters: {drivers.crank.speed_rpm: {min: 3000, max: .inf}}\n"
                          "sampling: {method: random, count: 3}\n"),
            "s.yaml:3:56: parameter 'drivers.crank.speed_rpm': max: expected a finite number, got '.inf'\n");
}

TEST(StudyFile, LatinHypercubeFillsEveryStratumOnceAndIsReproducible) {
  const std::string body =
      "sampling: {method: latin_hypercube, count: 20, seed: 7}\n"
      "parameters:\n"
      "  drivers.crank.speed_rpm: {min: 1000, max: 5000}\n"
      "  joints.rod_slider.clearance: {min: 1.0e-4, max: 5.0e-4}\n";
  const auto a = study_runs(from_text(body));
  const auto b = study_runs(from_text(body));
  ASSERT_EQ(a.size(), 20u);
  for (int p = 0; p < 2; ++p) {
    const double lo = p == 0 ? 1000 : 1e-4, hi = p == 0 ? 5000 : 5e-4;
    std::set<int> strata;
    for (const auto& r : a) {
      EXPECT_GE(r.numbers[p], lo);
      EXPECT_LT(r.numbers[p], hi);
      strata.insert(static_cast<int>((r.numbers[p] - lo) / (hi - lo) * 20));
    }
    EXPECT_EQ(strata.size(), 20u) << "parameter " << p << ": one sample per stratum";
  }
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].overrides, b[i].overrides);
  // Another seed, other samples.
  const auto c = study_runs(from_text(
      "sampling: {method: latin_hypercube, count: 20, seed: 8}\nparameters:\n"
      "  drivers.crank.speed_rpm: {min: 1000, max: 5000}\n"));
  EXPECT_NE(c[0].numbers[0], a[0].numbers[0]);
}

TEST(StudyFile, ProblemsAreLocatedInTheStudyFile) {
  EXPECT_NE(problems("parameters:\n  drivers.crank.speed_rpm: {form: 1, to: 2, count: 3}\n")
                .find("s.yaml:4:29: parameter 'drivers.crank.speed_rpm': unknown key 'form'"),
            std::string::npos)
      << problems("parameters:\n  drivers.crank.speed_rpm: {form: 1, to: 2, count: 3}\n");
  // A path the model does not have: the model loader's message, said to come from the study.
  EXPECT_NE(problems("parameters:\n  drivers.crank.speed_rpm: {values: [1], scal: log}\n")
                .find("unknown key 'scal', did you mean 'scale'?"),
            std::string::npos);
  const std::string typo = problems("parameters:\n  drivers.crank.sped_rpm: {values: [1000]}\n");
  EXPECT_NE(typo.find("driver 'crank': unknown key 'sped_rpm', did you mean 'speed_rpm'? (a value the study s.yaml sets)"),
            std::string::npos) << typo;
  const std::string parent = problems("parameters:\n  drivers.crank2.speed_rpm: {values: [1000]}\n");
  EXPECT_NE(parent.find("s.yaml:4:3: 'drivers.crank2.speed_rpm': no 'drivers.crank2' in the model, did you mean 'crank'? (in run 0)"),
            std::string::npos) << parent;
  EXPECT_NE(typo.find("(in run 0)"), std::string::npos) << typo;
  EXPECT_NE(problems("parameters:\n  drivers.crank.speed_rpm: {values: [1000, 2000], scale: log}\n")
                .find("s.yaml:4:58: parameter 'drivers.crank.speed_rpm': scale applies to"),
            std::string::npos);
  // A model file where a study goes: one problem (it was one per model section).
  const std::string model_file = text_problems(lash::test::read_file(example()));
  EXPECT_NE(model_file.find(":1:1: this is a model file (it has bodies or joints), not a study"),
            std::string::npos) << model_file;
  EXPECT_EQ(model_file.find("unknown key"), std::string::npos) << model_file;
  // An unknown key beside a parameter of the same joint: the message lists every key of the joint
  // (clearance among them), and both study paths seemed named, so it had no location.
  const std::string beside = problems(
      "set:\n  joints.rod_slider.foo: 1\nparameters:\n  joints.rod_slider.clearance: {values: [1.0e-4]}\n");
  EXPECT_NE(beside.find("s.yaml:4:3: joint 'rod_slider': unknown key 'foo'"), std::string::npos) << beside;
  const std::string channel =
      problems("parameters:\n  drivers.crank.speed_rpm: {values: [1000]}\nkeep: {channels: [slider.axx]}\n");
  EXPECT_NE(channel.find("no channel 'slider.axx' in the model, did you mean 'slider.ax'?"), std::string::npos)
      << channel;
  // Each unknown name at its own entry, in whichever list it is.
  const std::string two = problems(
      "parameters:\n  drivers.crank.speed_rpm: {values: [1000]}\nkeep:\n"
      "  channels: [slider.ax, slider.axx]\n  series: {channels: [slider.x, slider.xx], points: 10}\n");
  EXPECT_NE(two.find("s.yaml:6:25: keep: no channel 'slider.axx'"), std::string::npos) << two;
  EXPECT_NE(two.find("s.yaml:7:33: keep: no channel 'slider.xx'"), std::string::npos) << two;
  EXPECT_NE(problems("parameters:\n  drivers.crank.speed_rpm: {from: 1, to: 2, count: 0}\n")
                .find("count: expected a whole number from 1"),
            std::string::npos);
  EXPECT_NE(problems("combine: zip\nparameters:\n  drivers.crank.speed_rpm: {values: [1, 2]}\n"
                     "  joints.rod_slider.clearance: {values: [1.0e-4]}\n")
                .find("zip needs the same number of levels"),
            std::string::npos);
  // An empty level: it became the text '~', refused only when its run started.
  const std::string empty = problems("parameters:\n  drivers.crank.speed_rpm: {values: [1000, ~]}\n");
  EXPECT_NE(empty.find("s.yaml:4:44: parameter 'drivers.crank.speed_rpm': a level is empty (~ or nothing), expected a value"),
            std::string::npos) << empty;
  // At the drawn parameter (it was the file's start, 1:1).
  const std::string drawn = problems("parameters:\n  drivers.crank.speed_rpm: {min: 1, max: 2}\n");
  EXPECT_NE(drawn.find("s.yaml:4:3: parameters with min/max are drawn: add sampling"),
            std::string::npos) << drawn;
  // zip with a sampled parameter: said once, with no count of the drawn parameter's "0 levels".
  const std::string zip = problems("combine: zip\nsampling: {method: random, count: 4}\nparameters:\n"
                                   "  drivers.crank.speed_rpm: {min: 1000, max: 2000}\n"
                                   "  joints.rod_slider.clearance: {values: [1.0e-4, 2.0e-4]}\n");
  EXPECT_NE(zip.find("s.yaml:3:10: combine: zip is for listed levels"), std::string::npos) << zip;
  EXPECT_EQ(zip.find("has 0"), std::string::npos) << zip;
  // Duplicate keys: refused with both places, as in model files.
  const std::string dup = problems("transient: {periods: 1}\ntransient: {periods: 2}\nparameters:\n"
                                   "  drivers.crank.speed_rpm: {values: [1000]}\n");
  EXPECT_NE(dup.find("duplicate key 'transient'"), std::string::npos) << dup;
  // A transient in periods needs a constant-speed driver; one longer than the run is refused.
  std::string model = lash::test::read_file(example());
  model.replace(model.find("speed_rpm: 5000"), 15, "speed: 'step5(time, 0, 0, 0.005, 500)'");
  const fs::path ramp_model = fs::temp_directory_path() / ("lash_sweep_ramp_" + std::to_string(getpid()) + ".yaml");
  std::ofstream(ramp_model) << model;
  std::string ramp;
  try {
    load_study_text("study: ramp\nmodel: " + ramp_model.string() +
                        "\nparameters:\n  joints.rod_slider.clearance: {values: [2.0e-4]}\n"
                        "transient: {periods: 2}\ncontinuation: up\nkeep: {sections: [slider.x]}\n",
                    "s.yaml", [](const std::string& p) { return lash::test::read_file(p); });
  } catch (const ModelError& e) {
    ramp = e.what();
  }
  fs::remove(ramp_model);
  EXPECT_NE(ramp.find("s.yaml:5:12: transient: periods needs a constant-speed rotary driver"), std::string::npos) << ramp;
  EXPECT_NE(ramp.find("s.yaml:6:15: continuation: needs a constant-speed rotary driver"), std::string::npos) << ramp;
  // Sections are taken once per driver period: without one, none would be recorded (silently).
  EXPECT_NE(ramp.find("s.yaml:7:18: keep: sections are taken once per period of a constant-speed"), std::string::npos) << ramp;
  // Metric-like parameter names would share runs.csv's columns with the metrics.
  EXPECT_NE(problems("parameters:\n  rod_slider.Fn.peak: {cases: {a: {}}}\n").find("named like a metric"),
            std::string::npos);
  // Column names ignore case: 'Direction' is the metric column 'direction' (it passed).
  for (const char* name : {"Direction", "rod_slider.Fn.PEAK", "SECTIONS"})
    EXPECT_NE(problems(std::string("parameters:\n  ") + name + ": {cases: {a: {}, b: {}}}\n").find("named like a metric"),
              std::string::npos) << name;
  // Parameters are database columns: no duplicates, none named like a run's own columns.
  EXPECT_NE(problems("parameters:\n  status: {cases: {a: {}, b: {}}}\n").find("s.yaml:4:3: parameter 'status': a name every run's row has"),
            std::string::npos) << problems("parameters:\n  status: {cases: {a: {}, b: {}}}\n");
  EXPECT_NE(problems("parameters:\n  drivers.crank.speed_rpm: {values: [1]}\n  Drivers.crank.speed_rpm: {values: [2]}\n")
                .find("given twice"),
            std::string::npos);
  // Nor like sections.csv's columns (a case parameter 'value' gave a header with two).
  for (const char* name : {"k", "t", "channel", "value"})
    EXPECT_NE(problems(std::string("parameters:\n  ") + name + ": {cases: {a: {}, b: {}}}\n")
                  .find("a name every run's row has"),
              std::string::npos)
        << name;
  // An empty map of parameters says so; count 1 with two different ends drops one: refused.
  EXPECT_NE(problems("parameters: {}\n").find("parameters: empty"), std::string::npos);
  EXPECT_NE(problems("parameters:\n  drivers.crank.speed_rpm: {from: 4000, to: 5000, count: 1}\n")
                .find("s.yaml:4:58: parameter 'drivers.crank.speed_rpm': count 1 gives from only, but to (5000) differs"),
            std::string::npos)
      << problems("parameters:\n  drivers.crank.speed_rpm: {from: 4000, to: 5000, count: 1}\n");
  EXPECT_EQ(problems("parameters:\n  drivers.crank.speed_rpm: {from: 4000, to: 4000, count: 1}\n"), "no error");
}

TEST(StudyRun, ABadParameterCombinationIsRecordedNotThrown) {
  const StudySpec spec = from_text(
      "set: {solver.end_time: 0.03}\n"
      "parameters:\n  joints.rod_slider.clearance: {values: [2.0e-4, -1.0e-4]}\n"
      "transient: {periods: 1}\n"
      "keep: {sections: [rod_slider.ex]}\n");
  const auto runs = study_runs(spec);
  const RunRecord good = run_study_point(spec, runs[0]);
  EXPECT_EQ(good.status, "completed") << good.message;
  EXPECT_NEAR(good.t_reached, 0.03, 1e-12);
  // 0.03 s at 5000 rpm: 2.5 periods, one discarded: sections at 0.012 and 0.024 s.
  ASSERT_EQ(good.section_times.size(), 2u);
  EXPECT_NEAR(good.section_times[0], 0.012, 1e-12);
  bool has_impacts = false;
  for (const auto& [name, v] : good.metrics) has_impacts |= name == "rod_slider.impacts" && v > 0;
  EXPECT_TRUE(has_impacts);
  const RunRecord bad = run_study_point(spec, runs[1]);
  EXPECT_EQ(bad.status, "error");
  EXPECT_NE(bad.message.find("clearance"), std::string::npos) << bad.message;
  // The record survives the trip to another process unchanged.
  const RunRecord back = record_from_json(nlohmann::json::parse(to_json(good).dump()));
  EXPECT_EQ(to_json(back), to_json(good));
  EXPECT_EQ(back.section_values, good.section_values);
}

TEST(StudyRun, ARunWhoseDriverStandsStillHasNoTransientInPeriods) {
  // Speed 0 in one level: the study is not refused for it (it was, when that level came first),
  // and that run is an error naming why, instead of completing with statistics from t = 0 (it
  // did, when it came later).
  for (const char* levels : {"[0, 4000]", "[4000, 0]"}) {
    SCOPED_TRACE(levels);
    const StudySpec spec = from_text(std::string("set: {solver.end_time: 0.03}\n"
                                                 "parameters:\n  drivers.crank.speed_rpm: {values: ") +
                                     levels + "}\ntransient: {periods: 1}\n");
    for (const auto& run : study_runs(spec)) {
      const RunRecord r = run_study_point(spec, run);
      if (run.values[0] == "0") {
        EXPECT_EQ(r.status, "error");
        EXPECT_NE(r.message.find("driver 'crank' does not turn in this run (speed 0)"), std::string::npos)
            << r.message;
      } else {
        EXPECT_EQ(r.status, "completed") << r.message;
      }
    }
  }
}

TEST(StudyRun, ALyapunovExponentNotComputedIsSaid) {
  // 0.02 s at 5000 rpm leaves 0.008 s after the first section past the transient, less than a
  // period: the exponent was left out of the metrics with no word on why.
  const StudySpec spec = from_text(
      "set: {solver.end_time: 0.02}\n"
      "parameters:\n  drivers.crank.speed_rpm: {values: [5000]}\n"
      "transient: {periods: 1}\n"
      "lyapunov: true\n");
  const RunRecord r = run_study_point(spec, study_runs(spec)[0]);
  EXPECT_EQ(r.status, "completed") << r.message;
  for (const auto& [name, v] : r.metrics) EXPECT_NE(name, "lyapunov_exponent");
  EXPECT_NE(r.message.find("no Lyapunov exponent: the run leaves 0.008 s after its first section "
                           "past the transient, at least one period (0.012 s) needed"),
            std::string::npos)
      << r.message;
}

TEST(StudyRun, AContinuationDoesNotGoOnFromAFailedRun) {
  // The run after a failed one started from where the integrator gave up, and was recorded
  // as completed.
  const StudySpec spec = from_text(
      "set: {solver.end_time: 0.02, solver.max_steps: 300}\n"
      "parameters:\n  drivers.crank.speed_rpm: {values: [4000, 4500]}\n"
      "transient: {time: 0.004}\ncontinuation: up\n");
  const auto runs = study_runs(spec);
  ASSERT_EQ(runs.size(), 2u);
  const RunRecord first = run_study_point(spec, runs[0]);
  ASSERT_EQ(first.status, "failed") << first.message;
  // Where it stopped, as `lash run` says it (runs.csv has no t_reached column).
  EXPECT_EQ(first.message.rfind("stopped at t = " + lash::shortest_number(first.t_reached) + " s: ", 0), 0u)
      << first.message;
  EXPECT_GT(first.t_reached, 0.0);
  EXPECT_EQ(first.final_state.y.size(), 0);
  const RunRecord second = run_study_point(spec, runs[1], nullptr, &first);
  EXPECT_EQ(second.status, "error");
  EXPECT_NE(second.message.find("run 0, which this run continues, has no final state (failed)"),
            std::string::npos) << second.message;
}

TEST(StudyFile, AStudyNameThatIsNoTextIsRefused) {
  // study: [a, b], {x: 1}, ~ and "" were taken as the name "study" without a word.
  for (const char* name : {"[a, b]", "{x: 1}", "~", "\"\""}) {
    const std::string all = text_problems(std::string("study: ") + name + "\nmodel: " + example() +
                                          "\nparameters:\n  drivers.crank.speed_rpm: {values: [5000]}\n");
    EXPECT_NE(all.find("s.yaml:1:8: study: expected a name (text)"), std::string::npos)
        << name << ": " << all;
  }
}

TEST(StudyFile, AChannelKeptTwiceIsRefusedAtItsLine) {
  // Its metrics collided in the database (UNIQUE constraint failed, every resume alike); its
  // sections and series were stored twice.
  for (const char* keep : {"keep: {channels: [slider.ax, slider.ax]}\n",
                           "keep: {sections: [rod_slider.ex, rod_slider.ex]}\n",
                           "keep: {series: {channels: [slider.ax, slider.ax]}}\n"}) {
    const std::string all =
        problems(std::string("parameters:\n  drivers.crank.speed_rpm: {values: [5000]}\n") + keep);
    EXPECT_NE(all.find("s.yaml:5:"), std::string::npos) << keep << all;
    EXPECT_NE(all.find("is listed twice; list each channel once"), std::string::npos) << keep << all;
  }
}

TEST(StudyDatabase, AnotherProgramsDatabaseIsNotAdopted) {
  // A study.db with tables of its own (no `study`) had the study's tables added to it.
  const fs::path dir = temp_dir("foreign_db");
  const std::string db = (dir / "study.db").string();
  ASSERT_EQ(sh("/usr/bin/python3 -c \"import sqlite3; c = sqlite3.connect('" + db +
               "'); c.execute('create table foo(x)'); c.commit()\"").code, 0);
  const StudySpec spec = from_text("parameters:\n  drivers.crank.speed_rpm: {values: [1000]}\n");
  try {
    StudyDb study(db, spec, 1);
    ADD_FAILURE() << "adopted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("not a lash study database (its tables: foo)"),
              std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

TEST(StudyRun, PeakMetricsDoNotDependOnTheOutputInterval) {
  // The same runs written every 1e-3 s and every 1e-5 s: the kept channels' peaks after the
  // transient are found between outputs, so they agree although the coarse samples miss them.
  auto peaks = [](const std::string& interval) {
    const StudySpec spec = from_text(
        "set: {solver.end_time: 0.036, solver.output_interval: " + interval + "}\n"
        "parameters:\n  drivers.crank.speed_rpm: {values: [5000]}\ntransient: {periods: 1}\n"
        "keep: {channels: [slider.ax, rod_slider.Fn]}\n");
    const RunRecord r = run_study_point(spec, study_runs(spec)[0]);
    std::map<std::string, double> m(r.metrics.begin(), r.metrics.end());
    return m;
  };
  auto coarse = peaks("1.0e-3"), fine = peaks("1.0e-5");
  for (const char* name : {"slider.ax.peak", "rod_slider.Fn.peak", "slider.ax.min"}) {
    ASSERT_TRUE(coarse.count(name) && fine.count(name)) << name;
    EXPECT_NEAR(coarse[name], fine[name], 1e-3 * std::abs(fine[name])) << name;
  }
}

TEST(StudyRun, AContinuedRunKeepsAsManySeriesPointsAsTheFirst) {
  // The series is decimated over the run's own outputs: a continued run's end_time counts from
  // t = 0 (0.06 s for the second run here), and counting its outputs from there kept 24 points
  // of 50 in the second run, fewer down the chain.
  const StudySpec spec = from_text(
      "set: {solver.end_time: 0.03, solver.output_interval: 1.0e-4}\n"
      "parameters:\n  drivers.crank.speed_rpm: {values: [5000]}\n"
      "continuation: both\ntransient: {periods: 0}\n"
      "keep: {series: {channels: [slider.ax], points: 50}}\n");
  const auto runs = study_runs(spec);
  const RunRecord first = run_study_point(spec, runs[0]);
  ASSERT_EQ(first.status, "completed") << first.message;
  const RunRecord second = run_study_point(spec, runs[1], nullptr, &first);
  ASSERT_EQ(second.status, "completed") << second.message;
  EXPECT_EQ(first.series_time.size(), 43u);  // 301 outputs, every 7th
  EXPECT_EQ(second.series_time.size(), first.series_time.size());
}

TEST(StudyRun, ATransientOfMoreThanAMillionPeriodsIsSaidInTheStudysTerms) {
  // 1000.5 s at 60 000 rpm is 1.0005e6 crank periods: the analyses' limit, which the run's
  // message gave as an option the study has not ("--discard 1000500"); at 1e300 rpm the
  // period count overflowed an int.
  for (const char* speed : {"60000", "1.0e+300"}) {
    const StudySpec spec = from_text(std::string("set: {solver.end_time: 1001, solver.output_interval: 0.01}\n") +
                                     "transient: {time: 1000.5}\nparameters:\n  drivers.crank.speed_rpm: {values: [" +
                                     speed + "]}\n");
    const RunRecord r = run_study_point(spec, study_runs(spec)[0]);
    EXPECT_EQ(r.status, "error") << speed;
    EXPECT_NE(r.message.find("the transient (1000.5 s) is "), std::string::npos) << r.message;
    EXPECT_NE(r.message.find(" periods of the driver at this speed; at most 1000000"), std::string::npos)
        << r.message;
  }
}

TEST(StudyRun, ContinuationStartsEachRunWhereThePreviousEnded) {
  // Up then down over one level: run 1 continues run 0 at the same speed, so its journal motion
  // is that of one uninterrupted run of twice the length, up to the integrator's restart.
  const StudySpec spec = from_text(
      "set: {solver.end_time: 0.03, solver.output_interval: 1.0e-4}\n"
      "parameters:\n  drivers.crank.speed_rpm: {values: [5000]}\n"
      "continuation: both\ntransient: {periods: 0}\n"
      "keep: {series: {channels: [rod_slider.ex, rod_slider.ey], points: 100000}}\n");
  const auto runs = study_runs(spec);
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[0].values, (std::vector<std::string>{"5000", "up"}));
  EXPECT_EQ(runs[1].values, (std::vector<std::string>{"5000", "down"}));
  EXPECT_EQ(runs[1].previous, 0);
  const RunRecord first = run_study_point(spec, runs[0]);
  ASSERT_EQ(first.status, "completed") << first.message;
  ASSERT_EQ(first.final_state.y.size() > 0, true);
  const RunRecord second = run_study_point(spec, runs[1], nullptr, &first);
  ASSERT_EQ(second.status, "completed") << second.message;
  EXPECT_NEAR(second.t_reached, 0.06, 1e-12);
  ASSERT_GT(second.series_time.size(), 20u);
  EXPECT_NEAR(second.series_time.front(), 0.03, 1e-12);  // the hand-over state itself
  // The same model run for 0.06 s at once.
  const StudySpec whole = from_text(
      "set: {solver.end_time: 0.06, solver.output_interval: 1.0e-4}\n"
      "parameters:\n  drivers.crank.speed_rpm: {values: [5000]}\ntransient: {periods: 0}\n"
      "keep: {series: {channels: [rod_slider.ex, rod_slider.ey], points: 100000}}\n");
  const RunRecord ref = run_study_point(whole, study_runs(whole)[0]);
  ASSERT_EQ(ref.status, "completed");
  for (size_t k = 0; k < 10; ++k) {  // the first millisecond after the hand-over
    const size_t j = 300 + k;        // 0.03 s + k·1e-4 s in the uninterrupted run
    ASSERT_NEAR(ref.series_time[j], second.series_time[k], 1e-12);
    EXPECT_NEAR(second.series_values[0][k], ref.series_values[0][j], 1e-8) << "ex at " << ref.series_time[j];
    EXPECT_NEAR(second.series_values[1][k], ref.series_values[1][j], 1e-8) << "ey at " << ref.series_time[j];
  }
  // Over the clearance the hand-over would put the journal deep into a smaller bearing: refused.
  const StudySpec shrink = from_text(
      "set: {solver.end_time: 0.03}\nparameters:\n  joints.rod_slider.clearance: {values: [5.0e-4, 1.0e-5]}\n"
      "continuation: up\ntransient: {periods: 1}\n");
  const auto sr = study_runs(shrink);
  const RunRecord big = run_study_point(shrink, sr[0]);
  const RunRecord small = run_study_point(shrink, sr[1], nullptr, &big);
  EXPECT_EQ(small.status, "error");
  EXPECT_NE(small.message.find("into this run's bearing"), std::string::npos) << small.message;
  // Another speed: the run starts at t0 = t1·ω1/ω, where the crank has the angle it ended at.
  const StudySpec faster = from_text(
      "set: {solver.end_time: 0.03}\nparameters:\n  drivers.crank.speed_rpm: {values: [4000, 5000]}\n"
      "continuation: up\ntransient: {periods: 1}\n");
  const auto fr = study_runs(faster);
  const RunRecord a = run_study_point(faster, fr[0]);
  const RunRecord b = run_study_point(faster, fr[1], nullptr, &a);
  ASSERT_EQ(b.status, "completed") << b.message;
  EXPECT_NEAR(b.t_reached, 0.03 * 4000.0 / 5000.0 + 0.03, 1e-12);
  // A soft contact over speed: the first run ends with its journal 2.3 mm into the bearing
  // (K = 1e7 N/m^1.5), more than a tenth of the clearance, as the run itself reached it. It was
  // refused as if the speed had changed the joint; the gap is the same under both models.
  const StudySpec soft = from_text(
      "set: {solver.end_time: 0.03, joints.rod_slider.stiffness: 1.0e7}\n"
      "parameters:\n  drivers.crank.speed_rpm: {values: [4000, 5000]}\n"
      "continuation: up\ntransient: {periods: 1}\n");
  const auto so = study_runs(soft);
  const RunRecord s0 = run_study_point(soft, so[0]);
  ASSERT_EQ(s0.status, "completed") << s0.message;
  ASSERT_EQ(s0.final_state.gaps.size(), 1u);
  EXPECT_GT(s0.final_state.gaps[0], 0.1 * 0.5e-3);  // measured 2.3e-3 m
  const RunRecord s1 = run_study_point(soft, so[1], nullptr, &s0);
  EXPECT_EQ(s1.status, "completed") << s1.message;
  // The gap travels with the state kept in the study's database (a resumed study).
  EXPECT_EQ(state_from_json(state_json(s0.final_state)).gaps, s0.final_state.gaps);
}

TEST(StudyDatabase, KeepsRunsAndRefusesAnotherStudy) {
  const fs::path dir = temp_dir("db");
  const StudySpec spec = from_text("parameters:\n  drivers.crank.speed_rpm: {values: [1000, fast]}\n");
  const auto runs = study_runs(spec);
  RunRecord r;
  r.index = 1;
  r.status = "error";
  r.message = "a, \"quoted\" message";
  r.metrics = {{"x.peak", 2.5}};
  r.section_channels = {"a"};
  r.section_times = {0.1, 0.2};
  r.section_values = {{1.0}, {2.0}};
  {
    StudyDb db((dir / "study.db").string(), spec, 2);
    db.add(runs[1], r, "thread 0");
    EXPECT_EQ(db.finished(), (std::set<int>{1}));
    db.export_csv(dir.string());
  }
  const StudyTable t = read_study((dir / "study.db").string());
  ASSERT_EQ(t.rows.size(), 1u);
  EXPECT_EQ(t.rows[0].values[0], "fast");
  EXPECT_TRUE(std::isnan(t.rows[0].numbers[0]));
  EXPECT_EQ(t.rows[0].metrics[0].second, 2.5);
  ASSERT_EQ(t.points.size(), 1u);
  EXPECT_EQ(t.points[0][1].second, 2.0);
  const std::string csv = lash::test::read_file((dir / "runs.csv").string());
  EXPECT_NE(csv.find("run,drivers.crank.speed_rpm,status,verdict,wall_seconds,x.peak,message"), std::string::npos) << csv;
  EXPECT_NE(csv.find("1,fast,error,,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\"a, \"\"quoted\"\" message\""), std::string::npos) << csv;
  // Another study file into the same database: refused, nothing mixed.
  const StudySpec other = from_text("parameters:\n  drivers.crank.speed_rpm: {values: [2000]}\n");
  EXPECT_THROW(StudyDb((dir / "study.db").string(), other, 1), std::invalid_argument);
  fs::remove_all(dir);
}

TEST(StudyDatabase, ResumesHoweverTheStudyFilesPathIsSpelled) {
  // The same study file named from another folder or by its absolute path: the model file it
  // names is the same file, so --resume goes on. An edited model is still refused.
  const fs::path dir = temp_dir("db_paths");
  const std::string model = lash::test::read_file(example());
  const std::string text = "study: t\nmodel: m.yaml\nparameters:\n  drivers.crank.speed_rpm: {values: [1000]}\n";
  auto spelled = [&](const std::string& file, const std::string& m) {
    return load_study_text(text, file, [&](const std::string&) { return m; });
  };
  { StudyDb db((dir / "study.db").string(), spelled("study.yaml", model), 1); }
  EXPECT_NO_THROW(StudyDb((dir / "study.db").string(), spelled("/home/u/work/study.yaml", model), 1));
  EXPECT_NO_THROW(StudyDb((dir / "study.db").string(), spelled("work/study.yaml", model), 1));
  // The message names the edited file, as the study file names it.
  try {
    StudyDb((dir / "study.db").string(), spelled("work/study.yaml", model + "# edited\n"), 1);
    ADD_FAILURE() << "an edited model was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("changed since this study began (m.yaml)"),
              std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

TEST(Bifurcation, TheLogisticMapDoublesItsPeriodAtTheKnownParameters) {
  // x ← r x (1 − x): period 1 up to r = 3, period 2 up to 1 + √6 = 3.4495, period 4 up to
  // 3.5441 (May, Nature 261, 1976), chaos beyond the accumulation point 3.5699.
  std::vector<BifurcationColumn> columns;
  for (double r = 2.8; r < 3.58; r += 0.005) {
    BifurcationColumn c{r, {}};
    double x = 0.3;
    for (int i = 0; i < 20000; ++i) x = r * x * (1 - x);  // transient
    for (int i = 0; i < 64; ++i) c.points.push_back(x = r * x * (1 - x));
    columns.push_back(c);
  }
  const auto changes = period_changes(columns, 1e-4);
  std::vector<PeriodChange> doublings;
  for (const auto& c : changes)
    if (c.doubling()) doublings.push_back(c);
  ASSERT_GE(doublings.size(), 3u);
  // Near a doubling the orbit converges slowly; the tolerance absorbs the columns next to it.
  EXPECT_EQ(doublings[0].from_period, 1);
  EXPECT_NEAR(doublings[0].to_parameter, 3.0, 0.011);
  EXPECT_EQ(doublings[1].from_period, 2);
  EXPECT_NEAR(doublings[1].to_parameter, 1 + std::sqrt(6.0), 0.011);
  EXPECT_EQ(doublings[2].from_period, 4);
  EXPECT_NEAR(doublings[2].to_parameter, 3.5441, 0.011);
  // Past the accumulation point: no period this diagram can name.
  EXPECT_EQ(column_period(columns.back().points, 1e-4), 0);
}

TEST(SweepCli, CheckOfAStudyFileChecksItAsSweepDoes) {
  // `lash check` of a study file listed its keys as unknown model keys.
  const fs::path dir = temp_dir("check");
  const fs::path good = write_study(
      dir, "set: {solver.end_time: 0.024}\ntransient: {periods: 1}\n"
           "parameters:\n  drivers.crank.speed_rpm: {values: [3000, 5000]}\n");
  Result r = lash_cmd("check " + good.string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find(good.string() + ": ok: study 'test', 2 runs of 1 model"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("warning"), std::string::npos) << r.out;
  // Without its optional `study:` key: checked as a study too (as a model before, with six
  // unknown-key errors, while lash sweep ran it).
  {
    std::string text = lash::test::read_file(good.string());
    text.erase(0, text.find('\n') + 1);
    std::ofstream(dir / "unnamed.yaml") << text;
  }
  r = lash_cmd("check " + (dir / "unnamed.yaml").string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find(": ok: study 'study', 2 runs of 1 model"), std::string::npos) << r.out;
  // Each run is checked as the sweep starts it. With the default transient (5 periods: 0.1 s at
  // 3000 rpm) every run would be an error: refused, the runs named (it said "ok").
  const fs::path all_bad = write_study(
      dir, "set: {solver.end_time: 0.024}\nparameters:\n  drivers.crank.speed_rpm: {values: [3000, 5000]}\n",
      "all_bad.yaml");
  r = lash_cmd("check " + all_bad.string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("error: run 0: the transient (0.1 s) is not shorter than the run (0.024 s)"),
            std::string::npos) << r.out;
  EXPECT_NE(r.out.find("every one of 2 runs would be an error"), std::string::npos) << r.out;
  // A value bad in some runs only: a warning at the study's key naming those runs, exit 0.
  const fs::path some_bad = write_study(
      dir, "set: {solver.end_time: 0.024}\ntransient: {periods: 1}\nparameters:\n"
           "  drivers.crank.speed_rpm: {values: [3000, 5000]}\n"
           "  joints.rod_slider.clearance: {values: [0.5e-3, -1.0e-4]}\n", "some_bad.yaml");
  r = lash_cmd("check " + some_bad.string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("warning: runs 1, 3: " + some_bad.string() + ":7:3: joint 'rod_slider': clearance must be >= 0"),
            std::string::npos) << r.out;
  EXPECT_NE(r.out.find("4 runs of 1 model; 2 of them would be recorded as errors"), std::string::npos) << r.out;
  // A continuation chain: a run that would be an error (a transient of 0.03 s in 0.01 s) makes
  // the run continuing it one too.
  const fs::path chain = write_study(
      dir, "set: {solver.end_time: 0.01}\ntransient: {periods: 1}\ncontinuation: up\n"
           "parameters:\n  drivers.crank.speed_rpm: {values: [8000, 2000, 8000]}\n", "chain.yaml");
  r = lash_cmd("check " + chain.string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("warning: run 1: the transient (0.03 s) is not shorter than the run (0.01 s)"),
            std::string::npos) << r.out;
  EXPECT_NE(r.out.find("warning: run 2: it continues run 1, which would be an error"), std::string::npos) << r.out;
  // 2 400 runs: 2 000 checked, among them runs of every level. Checked one run in two or more,
  // it saw the first level(s) of the 4-level parameter only (with 1000 rpm first, "every one
  // ... would be an error"; listed last, "ok").
  const fs::path many = write_study(
      dir, "set: {solver.end_time: 0.02}\ntransient: {periods: 1}\nparameters:\n"
           "  joints.rod_slider.restitution: {from: 0.5, to: 0.9, count: 600}\n"
           "  drivers.crank.speed_rpm: {values: [4000, 5000, 6000, 1000]}\n", "many.yaml");
  r = lash_cmd("check " + many.string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("2000 of its 2400 runs"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("the transient (0.06 s) is not shorter than the run (0.02 s)"), std::string::npos) << r.out;
  // A value bad in the first 100 runs (the outer parameter's first level) is those runs' error;
  // the study was refused ("in run 0 ... nothing was run").
  const fs::path outer = write_study(
      dir, "set: {solver.end_time: 0.024}\ntransient: {periods: 1}\nparameters:\n"
           "  joints.rod_slider.restitution: {values: [0, 0.5, 1]}\n"
           "  drivers.crank.speed_rpm: {from: 3000, to: 5000, count: 100}\n", "outer.yaml");
  r = lash_cmd("check " + outer.string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("300 runs of 1 model; 100 of them would be recorded as errors"), std::string::npos) << r.out;
  const fs::path bad = write_study(
      dir, "set: {solver.rtol: 5}\nparameters:\n  drivers.crank.sped_rpm: {values: [3000]}\n", "bad.yaml");
  r = lash_cmd("check " + bad.string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("bad.yaml:3:"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("unknown key 'study'"), std::string::npos) << r.out;
  r = lash_cmd("check " + good.string() + " --set solver.rtol=1e-9");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("is a study"), std::string::npos) << r.out;
  fs::remove_all(dir);
}

TEST(SweepCli, AKilledStudyResumesWithEveryRunExactlyOnce) {
  const fs::path dir = temp_dir("resume");
  const fs::path study = write_study(
      dir, "set: {solver.end_time: 0.08, solver.output_interval: 1.0e-4}\n"
           "parameters:\n  drivers.crank.speed_rpm: {from: 3000, to: 5000, count: 16}\n"
           "transient: {periods: 2}\nkeep: {sections: [rod_slider.ex], channels: [rod_slider.Fn]}\n");
  const fs::path out = dir / "out";
  // The whole study once without interruption, for reference.
  Result r = lash_cmd("sweep " + study.string() + " -q -j 2 -o " + (dir / "ref").string());
  ASSERT_EQ(r.code, 0) << r.out;
  // kill -9 once some runs are recorded.
  const pid_t pid = spawn_sweep(study, out);
  wait_for_runs(out / "study.db", 3);
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the study ended before the kill";
  const auto partial = query(out / "study.db", "select count(*) from runs");
  ASSERT_EQ(partial.size(), 1u);
  const int kept = std::stoi(partial[0]);
  EXPECT_GE(kept, 3);
  ASSERT_LT(kept, 16) << "the study ended before the kill; make its runs longer";
  // Without --resume the folder is refused; with it only the missing runs run.
  r = lash_cmd("sweep " + study.string() + " -q -o " + out.string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("add --resume"), std::string::npos) << r.out;
  r = lash_cmd("sweep " + study.string() + " -j 2 --resume -o " + out.string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find(std::to_string(kept) + " of 16 runs already in"), std::string::npos) << r.out;
  EXPECT_EQ(query(out / "study.db", "select count(*), count(distinct run), min(run), max(run) from runs")[0],
            "16|16|0|15");
  // The resumed study holds what the uninterrupted one holds (timing aside).
  const std::string cols = "select run, \"drivers.crank.speed_rpm\", status, verdict, t_reached, steps from runs order by run";
  EXPECT_EQ(query(out / "study.db", cols), query(dir / "ref" / "study.db", cols));
  const std::string m = "select run, name, value from metrics order by run, name";
  EXPECT_EQ(query(out / "study.db", m), query(dir / "ref" / "study.db", m));
  EXPECT_EQ(query(out / "study.db", "select * from sections order by run, k"),
            query(dir / "ref" / "study.db", "select * from sections order by run, k"));
  // runs.csv: a header and 16 rows.
  std::ifstream csv(out / "runs.csv");
  int lines = 0;
  for (std::string l; std::getline(csv, l);) ++lines;
  EXPECT_EQ(lines, 17);
  // An edited study file into the same folder: refused.
  std::ofstream(study, std::ios::app) << "# edited\n";
  r = lash_cmd("sweep " + study.string() + " -q --resume -o " + out.string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("holds the results of another study file"), std::string::npos) << r.out;
  fs::remove_all(dir);
}

TEST(SweepCli, ARunDeletedFromTheDatabaseByHandIsRunAgainOnResume) {
  // A runs row deleted with its metrics and sections kept: --resume ran it again and stopped on
  // "UNIQUE constraint failed ...; then map::at" (exit 3).
  const fs::path dir = temp_dir("hand_deleted");
  const fs::path study = write_study(
      dir, "set: {solver.end_time: 0.03, solver.output_interval: 1.0e-4}\n"
           "parameters:\n  drivers.crank.speed_rpm: {values: [4000, 5000]}\n"
           "transient: {periods: 1}\nkeep: {sections: [rod_slider.ex], channels: [rod_slider.Fn]}\n");
  const fs::path out = dir / "out";
  Result r = lash_cmd("sweep " + study.string() + " -q -o " + out.string());
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string m = "select run, name, value from metrics order by run, name";
  const std::string sec = "select * from sections order by run, k";
  const auto metrics = query(out / "study.db", m), sections = query(out / "study.db", sec);
  ASSERT_FALSE(sections.empty());
  sqlite3* h = nullptr;
  ASSERT_EQ(sqlite3_open((out / "study.db").c_str(), &h), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(h, "delete from runs where run = 1", nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(h);
  r = lash_cmd("sweep " + study.string() + " -q --resume -o " + out.string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(query(out / "study.db", "select count(*) from runs")[0], "2");
  EXPECT_EQ(query(out / "study.db", m), metrics);
  EXPECT_EQ(query(out / "study.db", sec), sections);
  fs::remove_all(dir);
}

TEST(SweepCli, AKilledContinuationResumesFromTheRecordedState) {
  const fs::path dir = temp_dir("continuation");
  const fs::path study = write_study(
      dir, "set: {solver.end_time: 0.06, solver.output_interval: 1.0e-4}\n"
           "parameters:\n  drivers.crank.speed_rpm: {from: 3000, to: 5000, count: 8}\n"
           "continuation: up\ntransient: {periods: 1}\nkeep: {sections: [rod_slider.ex]}\n");
  ASSERT_EQ(lash_cmd("sweep " + study.string() + " -q -o " + (dir / "ref").string()).code, 0);
  const fs::path out = dir / "out";
  const pid_t pid = spawn_sweep(study, out);
  wait_for_runs(out / "study.db", 2);
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the study ended before the kill";
  const Result r = lash_cmd("sweep " + study.string() + " -q --resume -o " + out.string());
  ASSERT_EQ(r.code, 0) << r.out;
  // The chain went on from the state the database kept: the same runs as without the kill.
  const std::string q = "select run, \"drivers.crank.speed_rpm\", direction, status, t_reached, steps from runs order by run";
  EXPECT_EQ(query(out / "study.db", q), query(dir / "ref" / "study.db", q));
  EXPECT_EQ(query(out / "study.db", "select * from sections order by run, k"),
            query(dir / "ref" / "study.db", "select * from sections order by run, k"));
  fs::remove_all(dir);
}

TEST(SweepCli, ASignalStopsTheStudyKeepingItsFinishedRuns) {
  const fs::path dir = temp_dir("signal");
  const fs::path study = write_study(
      dir, "set: {solver.end_time: 0.08, solver.output_interval: 1.0e-4}\n"
           "parameters:\n  drivers.crank.speed_rpm: {from: 3000, to: 5000, count: 16}\n"
           "transient: {periods: 2}\n");
  const fs::path out = dir / "out";
  const pid_t pid = spawn_sweep(study, out);
  wait_for_runs(out / "study.db", 2);
  kill(pid, SIGTERM);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  const int kept = std::stoi(query(out / "study.db", "select count(*) from runs")[0]);
  EXPECT_GE(kept, 2);
  EXPECT_LT(kept, 16);
  // Every recorded run is whole (none cut by the signal), and runs.csv lists exactly them.
  EXPECT_EQ(query(out / "study.db", "select count(*) from runs where status = 'completed' and t_reached = 0.08")[0],
            std::to_string(kept));
  std::ifstream csv(out / "runs.csv");
  int lines = 0;
  for (std::string l; std::getline(csv, l);) ++lines;
  EXPECT_EQ(lines, kept + 1);
  fs::remove_all(dir);
}

TEST(SweepCli, AFailingRunIsRecordedAndTheRestComplete) {
  const fs::path dir = temp_dir("failing");
  // A negative clearance in the second run is a model error of that run only; the third one's
  // integrator gives up (max_steps) and is recorded as failed.
  const fs::path study = write_study(
      dir, "set: {solver.end_time: 0.03}\n"
           "combine: zip\n"
           "parameters:\n"
           "  joints.rod_slider.clearance: {values: [2.0e-4, -1.0e-4, 2.0e-4, 3.0e-4]}\n"
           "  solver.max_steps: {values: [1000000, 1000000, 50, 1000000]}\n"
           "transient: {periods: 1}\n");
  Result r = lash_cmd("sweep " + study.string() + " -o " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("4 runs in"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(2 failed)"), std::string::npos) << r.out;
  // Resumed, nothing runs and the closing line still counts the failures the database holds.
  r = lash_cmd("sweep " + study.string() + " --resume -o " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("4 runs in"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(2 failed)"), std::string::npos) << r.out;
  const auto rows = query(dir / "out" / "study.db", "select run, status from runs order by run");
  EXPECT_EQ(rows, (std::vector<std::string>{"0|completed", "1|error", "2|failed", "3|completed"}));
  const auto msg = query(dir / "out" / "study.db", "select message from runs where run = 1");
  EXPECT_NE(msg[0].find("clearance"), std::string::npos) << msg[0];
  // Run 2 stopped inside its transient (the first period): no metrics from after it, contact
  // metrics included (they were counted over the transient instead); the completed runs have them.
  const auto contact = query(dir / "out" / "study.db",
                             "select run, count(*) from metrics where name like 'rod_slider.%' "
                             "group by run order by run");
  EXPECT_EQ(contact, (std::vector<std::string>{"0|9", "3|9"}));
  // The study's report names the failed runs with their errors. It leaves no SQLite side files
  // (a read-only connection to the WAL database created study.db-wal and -shm and could not
  // remove them), and a folder given with a trailing slash is printed without a doubled one.
  r = lash_cmd("report " + (dir / "out").string() + "/");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.find("//"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "out" / "study.db-wal"));
  EXPECT_FALSE(fs::exists(dir / "out" / "study.db-shm"));
  const std::string html = lash::test::read_file((dir / "out" / "study_report.html").string());
  EXPECT_NE(html.find("<h2>Failed runs</h2><table>"), std::string::npos);
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_NE(html.find("rod_slider.Fn.peak"), std::string::npos);
  fs::remove_all(dir);
}

TEST(SweepCli, AStudyOfOneLevelIsPlottedOnItsOwnScale) {
  // One clearance of 0.2 mm was drawn on an axis from -0.5 to 0.5 m, its dot on the 0 tick.
  const fs::path dir = temp_dir("one_level");
  const fs::path study = write_study(
      dir, "set: {solver.end_time: 0.03, solver.output_interval: 1.0e-4}\n"
           "parameters:\n  joints.rod_slider.clearance: {values: [2.0e-4]}\n"
           "transient: {periods: 1}\nkeep: {channels: [rod_slider.Fn]}\n");
  ASSERT_EQ(lash_cmd("sweep " + study.string() + " -q -o " + (dir / "out").string()).code, 0);
  ASSERT_EQ(lash_cmd("report " + (dir / "out").string()).code, 0);
  const std::string html = lash::test::read_file((dir / "out" / "study_report.html").string());
  EXPECT_NE(html.find("text-anchor=\"middle\">0.0002</text>"), std::string::npos);
  EXPECT_EQ(html.find("text-anchor=\"middle\">0.5</text>"), std::string::npos);
  fs::remove_all(dir);
}

TEST(SweepCli, AStudyWhoseEveryRunFailedExitsWithOne) {
  // Nothing to analyse: `lash sweep … && lash report …` must stop. The runs stay recorded, so a
  // resume runs nothing and says the same; a study with one completed run exits 0 (above).
  const fs::path dir = temp_dir("all_failed");
  const fs::path study = write_study(
      dir, "set: {solver.end_time: 0.03}\n"
           "parameters:\n"
           "  joints.rod_slider.clearance: {values: [2.0e-4, 3.0e-4]}\n"
           "  solver.max_steps: {values: [50]}\n"
           "transient: {periods: 1}\n");
  for (const char* resume : {"", " --resume"}) {
    SCOPED_TRACE(resume);
    const Result r = lash_cmd("sweep " + study.string() + resume + " -o " + (dir / "out").string());
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find("2 runs in"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("error: every one of the 2 runs failed; run 0: "), std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("maximum number of steps (50) reached"), std::string::npos) << r.out;
  }
  EXPECT_EQ(query(dir / "out" / "study.db", "select count(*) from runs"),
            std::vector<std::string>{"2"});
  fs::remove_all(dir);
}

TEST(SweepCli, PathsThatAreNotUtf8AreStudiedAndResumed) {
  // A Latin-1 file name (0xE9, é) in the study's path and its model's: JSON's writer refused
  // them (the study aborted with an uncaught exception; the model's name gave an unlocated
  // exit 2). Under MPI the study travels as MessagePack (tests/sweep/mpi_same_results.sh).
  const fs::path dir = temp_dir("latin1");
  const std::string model = "m_\xe9.yaml", name = "st_\xe9.yaml";
  fs::copy_file(example(), dir / model);
  std::ofstream(dir / name) << "study: latin1\nmodel: " << model
                            << "\nset: {solver.end_time: 0.03}\ntransient: {periods: 1}\n"
                               "parameters:\n  joints.rod_slider.clearance: {values: [1.0e-4, 3.0e-4]}\n";
  const std::string cmd = "sweep '" + (dir / name).string() + "' -q -j 1 -o " + (dir / "out").string();
  Result r = lash_cmd(cmd);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(query(dir / "out" / "study.db", "select run, status from runs order by run"),
            (std::vector<std::string>{"0|completed", "1|completed"}));
  r = lash_cmd(cmd + " --resume");
  EXPECT_EQ(r.code, 0) << r.out;
  // An edited model is still told from the one the study began with.
  std::ofstream(dir / model, std::ios::app) << "# edited\n";
  r = lash_cmd(cmd + " --resume");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("the model file(s) changed since this study began (m_\\xE9.yaml)"), std::string::npos)
      << r.out;
  fs::remove_all(dir);
}

TEST(SweepCli, ARunsFolderAndAStudysFolderAreNotOne) {
  // `lash run` into a study's folder was accepted, and `lash report` then reported the study
  // alone: the run's results were never reported. Each now refuses the other's folder, and
  // leaves it as it was.
  const fs::path dir = temp_dir("mixed");
  const fs::path study = write_study(dir, "set: {solver.end_time: 0.002}\n"
                                          "parameters:\n"
                                          "  joints.rod_slider.clearance: {values: [2.0e-4]}\n"
                                          "transient: {time: 0.001}\n");
  Result r = lash_cmd("sweep " + study.string() + " -q -j 0 -o " + (dir / "study").string());  // 0: every core
  ASSERT_EQ(r.code, 0) << r.out;
  r = lash_cmd("run " + lash::test::example_path("flores_slider_crank.yaml") + " -q -o " +
               (dir / "study").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("study.db: this folder holds a study of `lash sweep`"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "study" / "summary.json"));
  EXPECT_FALSE(fs::exists(dir / "study" / "model_resolved.yaml"));
  // `lash analyze` of a study's folder points to `lash report` (it stopped at "not a folder
  // written by `lash run` ").
  r = lash_cmd("analyze " + (dir / "study").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("it holds a study of `lash sweep`: `lash report "), std::string::npos) << r.out;
  r = lash_cmd("run " + lash::test::example_path("flores_slider_crank.yaml") +
               " -q --set solver.end_time=0.001 -o " + (dir / "run").string());
  ASSERT_EQ(r.code, 0) << r.out;
  r = lash_cmd("sweep " + study.string() + " -q -o " + (dir / "run").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("summary.json: this folder holds the results of a run of `lash run`"),
            std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "run" / "study.db"));
  fs::remove_all(dir);
}

TEST(SweepCli, AStudyOfCasesOnlyReportsItsMetricsAsATable) {
  // No numeric parameter to plot against: the report showed the status table only, and none of
  // the metrics runs.csv has. Now a table of them, one row per completed run.
  const fs::path dir = temp_dir("cases_report");
  const fs::path study = write_study(
      dir, "set: {solver.end_time: 0.03}\n"
           "parameters:\n  gap: {cases: {small: {joints.rod_slider.clearance: 1.0e-4}, "
           "large: {joints.rod_slider.clearance: 3.0e-4}}}\n"
           "transient: {periods: 1}\n");
  ASSERT_EQ(lash_cmd("sweep " + study.string() + " -q -o " + (dir / "out").string()).code, 0);
  ASSERT_EQ(lash_cmd("report " + (dir / "out").string()).code, 0);
  const std::string html = lash::test::read_file((dir / "out" / "study_report.html").string());
  EXPECT_NE(html.find("<h2>Metrics</h2><table><tr><th>run</th><th>gap</th>"), std::string::npos);
  EXPECT_NE(html.find("<th>rod_slider.Fn.peak</th>"), std::string::npos);
  EXPECT_NE(html.find("<td>small</td>"), std::string::npos);
  EXPECT_NE(html.find("<td>large</td>"), std::string::npos);
  EXPECT_NE(html.find("data in study.db, runs.csv, sections.csv ("), std::string::npos);
  // A sweep killed before its end leaves study.db without the CSV files: the report named them.
  fs::remove(dir / "out" / "runs.csv");
  fs::remove(dir / "out" / "sections.csv");
  ASSERT_EQ(lash_cmd("report " + (dir / "out").string()).code, 0);
  const std::string killed = lash::test::read_file((dir / "out" / "study_report.html").string());
  EXPECT_NE(killed.find("data in study.db ("), std::string::npos);
  fs::remove_all(dir);
}

TEST(SweepCli, AStudyThatCannotRunIsRefusedWithItsLocation) {
  const fs::path dir = temp_dir("refused");
  const fs::path study = write_study(dir, "parameters:\n  drivers.crank.speed_rpm: {values: [1000]}\ncombine: crossed\n");
  const Result r = lash_cmd("sweep " + study.string() + " -o " + (dir / "out").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find(study.string() + ":5:10: combine: expected cross"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "out" / "study.db"));
  fs::remove_all(dir);
}

TEST(SweepCli, UnderAnMpiLauncherWithoutLashMpiBesideItIsRefused) {
  // MPI lives in lash-mpi beside lash; a lash copied alone, started as one of two MPI processes,
  // says so instead of running the whole study in every process.
  const fs::path dir = temp_dir("no_lash_mpi");
  fs::copy_file(LASH_BINARY, dir / "lash");
  const fs::path study = write_study(dir, "parameters:\n  drivers.crank.speed_rpm: {values: [1000]}\n");
  const Result r = sh("OMPI_COMM_WORLD_SIZE=2 OMPI_COMM_WORLD_RANK=0 " + (dir / "lash").string() +
                      " sweep " + study.string() + " -o " + (dir / "out").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("no lash-mpi beside this lash"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "out" / "study.db"));
  fs::remove_all(dir);
}

namespace {
/// The study header of the regression tests below: Flores, 0.024 s (2 periods at 5000 rpm).
const std::string kShort =
    "set: {solver.end_time: 0.024, solver.output_interval: 1.0e-4}\ntransient: {periods: 1}\n";
}  // namespace

TEST(StudyFile, TwoParametersSettingOnePathAreRefusedWithBothPlaces) {
  // A parameter and a case of another parameter setting the same path: the row would name one
  // level and the model run with the other's value, whichever comes later. Refused, both ways.
  const std::string a = problems(
      kShort + "parameters:\n  drivers.crank.speed_rpm: {values: [3000, 5000]}\n"
               "  variant: {cases: {slow: {drivers.crank.speed_rpm: 3000}, plain: {joints.rod_slider.restitution: 0.9}}}\n");
  EXPECT_NE(a.find("s.yaml:7:28: 'drivers.crank.speed_rpm' is set by case 'slow' of parameter 'variant' and by "
                   "parameter 'drivers.crank.speed_rpm' (line 6, column 3)"),
            std::string::npos) << a;
  const std::string b = problems(
      kShort + "parameters:\n  variant: {cases: {slow: {drivers.crank.speed_rpm: 3000}, plain: {}}}\n"
               "  drivers.crank.speed_rpm: {values: [3000, 5000]}\n");
  EXPECT_NE(b.find("s.yaml:7:3: 'drivers.crank.speed_rpm' is set by parameter 'drivers.crank.speed_rpm' and by "
                   "case 'slow' of parameter 'variant' (line 6, column 28)"),
            std::string::npos) << b;
  // Two case parameters, and a path inside another's value.
  const std::string c = problems(
      kShort + "parameters:\n  v1: {cases: {a: {joints.rod_slider.clearance: 1.0e-4}, b: {}}}\n"
               "  v2: {cases: {c: {joints.rod_slider: {clearance: 2.0e-4}}, d: {}}}\n");
  EXPECT_NE(c.find("'joints.rod_slider' is set by case 'c' of parameter 'v2' and 'joints.rod_slider.clearance' "
                   "by case 'a' of parameter 'v1' (line 6, column 20)"),
            std::string::npos) << c;
  // `set` is every run's base: a case may override it, and its row names the case.
  const StudySpec spec = from_text(
      kShort + "parameters:\n  variant: {cases: {slow: {solver.end_time: 0.03}, plain: {}}}\n");
  EXPECT_EQ(study_runs(spec)[0].overrides.back(), "solver.end_time=0.03");
}

TEST(StudyFile, ACaseWithAPathTheModelLacksIsRefusedBeforeAnyRun) {
  const std::string a = problems(
      kShort + "parameters:\n  variant: {cases: {a: {joints.nope.clearance: 0}, b: {drivers.crank.speed_rpm: 3000}}}\n");
  EXPECT_NE(a.find("s.yaml:6:25: 'joints.nope.clearance': no 'joints.nope' in the model"),
            std::string::npos) << a;
  EXPECT_EQ(a.find("--set"), std::string::npos) << a;
  // The same in the second case, after a first that loads.
  const std::string b = problems(
      kShort + "parameters:\n  variant: {cases: {b: {drivers.crank.speed_rpm: 3000}, a: {joints.nope.clearance: 0}}}\n");
  EXPECT_NE(b.find("s.yaml:6:61: 'joints.nope.clearance': no 'joints.nope' in the model"), std::string::npos) << b;
  // A case whose value makes no model in any of its runs.
  const std::string c = problems(
      kShort + "parameters:\n  variant: {cases: {b: {drivers.crank.speed_rpm: 3000}, a: {drivers.crank.speed_rpm: fast}}}\n");
  EXPECT_NE(c.find("s.yaml:6:57: parameter 'variant': case 'a' makes no valid model"), std::string::npos) << c;
  EXPECT_NE(c.find("(a value the study s.yaml sets"), std::string::npos) << c;
  EXPECT_EQ(c.find("--set"), std::string::npos) << c;
}

TEST(StudyRun, AValueErrorOfARunNamesTheStudyNotSet) {
  // A level bad in one run only is that run's error; its message points into the study.
  const StudySpec spec = from_text(kShort + "parameters:\n  drivers.crank.speed_rpm: {values: [5000, fast]}\n");
  const RunRecord bad = run_study_point(spec, study_runs(spec)[1]);
  EXPECT_EQ(bad.status, "error");
  EXPECT_EQ(bad.message.find("--set"), std::string::npos) << bad.message;
  EXPECT_NE(bad.message.find("(a value the study s.yaml sets)"), std::string::npos) << bad.message;
  // At the key that set it (the message named the model file, with no line).
  EXPECT_EQ(bad.message.rfind("s.yaml:6:3: driver 'crank': ", 0), 0u) << bad.message;
  // A top-level key's level (gravity) too (it pointed at the model file).
  const StudySpec g = from_text(kShort + "parameters:\n  gravity: {values: [[0, -9.81], [0, abc]]}\n");
  const RunRecord bad_g = run_study_point(g, study_runs(g)[1]);
  EXPECT_EQ(bad_g.status, "error");
  EXPECT_EQ(bad_g.message.rfind("s.yaml:6:3: model: 'gravity' must be a pair of finite numbers", 0), 0u)
      << bad_g.message;
  // A bad value in `set:` fails every run: refused before any, at its key.
  const std::string set = problems(
      "set: {solver.end_time: 0.024, solver.rtol: 5}\nparameters:\n  drivers.crank.speed_rpm: {values: [5000]}\n");
  EXPECT_NE(set.find("s.yaml:3:31: solver: rtol must be in [1e-14, 0.1]"), std::string::npos) << set;
  EXPECT_NE(set.find("(a value the study s.yaml sets) (in run 0)"), std::string::npos) << set;
}

TEST(StudyRun, TransientTimeIsHonouredWithAConstantSpeedDriver) {
  // 0.01 s of 0.024 s at 5000 rpm (period 0.012 s): the default 5 periods would not fit.
  const StudySpec spec = from_text(
      "set: {solver.end_time: 0.024, solver.output_interval: 1.0e-4}\ntransient: {time: 0.01}\n"
      "parameters:\n  drivers.crank.speed_rpm: {values: [5000]}\nkeep: {sections: [rod_slider.ex]}\n");
  const RunRecord r = run_study_point(spec, study_runs(spec)[0]);
  EXPECT_EQ(r.status, "completed") << r.message;
  // Sections at 0.012 and 0.024 s, both after 0.01 s.
  ASSERT_EQ(r.section_times.size(), 2u);
  EXPECT_NEAR(r.section_times[0], 0.012, 1e-12);
  EXPECT_NE(problems("transient: {periods: 1, time: 0.01}\nparameters:\n  drivers.crank.speed_rpm: {values: [5000]}\n")
                .find("transient: give periods (crank periods) or time (seconds), not both"),
            std::string::npos);
}

TEST(StudyRun, ARunWhoseModelLacksAKeptChannelKeepsTheRest) {
  // Clearance 0 makes rod_slider ideal: no Fn, no ex. Both orders load; that run completes with
  // its other results and says which channels it lacks; the other run keeps them.
  for (const std::string levels : {"[0, 1.0e-4]", "[1.0e-4, 0]"}) {
    const StudySpec spec = from_text(kShort + "parameters:\n  joints.rod_slider.clearance: {values: " + levels +
                                     "}\nkeep: {channels: [rod_slider.Fn, slider.ax], sections: [rod_slider.ex]}\n");
    for (const auto& run : study_runs(spec)) {
      const RunRecord r = run_study_point(spec, run);
      EXPECT_EQ(r.status, "completed") << levels << " " << r.message;
      std::map<std::string, double> m(r.metrics.begin(), r.metrics.end());
      EXPECT_TRUE(m.count("slider.ax.peak")) << levels;
      if (run.numbers[0] == 0) {
        EXPECT_EQ(r.message, "not in this run's model, not kept: rod_slider.Fn, rod_slider.ex");
        EXPECT_FALSE(m.count("rod_slider.Fn.peak"));
        EXPECT_TRUE(r.section_channels.empty());
        EXPECT_TRUE(r.section_values.empty() || r.section_values[0].empty());
      } else {
        EXPECT_TRUE(m.count("rod_slider.Fn.peak")) << levels;
        EXPECT_EQ(r.section_channels, std::vector<std::string>{"rod_slider.ex"});
      }
    }
  }
  // A channel in no run's model is still refused.
  EXPECT_NE(problems(kShort + "parameters:\n  joints.rod_slider.clearance: {values: [0, 1.0e-4]}\n"
                                    "keep: {channels: [rod_slider.Fnn]}\n")
                .find("keep: no channel 'rod_slider.Fnn' in the model"),
            std::string::npos);
}

TEST(StudyFile, ContinuationLevelsThatStopOrReverseTheDriverAreRefused) {
  const std::string a = problems(
      kShort + "parameters:\n  drivers.crank.speed_rpm: {values: [3000, 0, -3000]}\ncontinuation: up\n");
  EXPECT_NE(a.find("s.yaml:6:3: continuation: level '0' of 'drivers.crank.speed_rpm' gives no turning constant-speed rotary driver"),
            std::string::npos) << a;
  EXPECT_NE(a.find("level '-3000' of 'drivers.crank.speed_rpm' turns the driver the other way"), std::string::npos) << a;
}

TEST(StudyRun, ARunKeepsTheWarningsLashRunWouldPrint) {
  // A puck on a 1e6 N·s/m damper is stiff for DOPRI5 (tests/test_simulate.cpp): the study's run
  // says so in its message, completed as it is; the undamped run says nothing.
  const fs::path dir = temp_dir("warned");
  fs::create_directories(dir);
  std::ofstream(dir / "puck.yaml") << lash::test::kStiffPuck;
  const StudySpec spec = study_text("study: puck\nmodel: " + (dir / "puck.yaml").string() +
                                    "\nparameters:\n  loads.tie.damping: {values: [1e6, 0]}\n"
                                    "transient: {time: 0}\nkeep: {channels: [puck.x]}\n");
  const auto runs = study_runs(spec);
  ASSERT_EQ(runs.size(), 2u);
  const RunRecord stiff = run_study_point(spec, runs[0]);
  EXPECT_EQ(stiff.status, "completed") << stiff.message;
  EXPECT_EQ(stiff.message.find("warning: the model is stiff for dopri5: "), 0u) << stiff.message;
  const RunRecord plain = run_study_point(spec, runs[1]);
  EXPECT_EQ(plain.status, "completed") << plain.message;
  EXPECT_EQ(plain.message, "");
  fs::remove_all(dir);
}
