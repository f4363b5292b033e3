// A run folder read back (io/run_folder.hpp): the analyses from what a run wrote agree with the
// same analyses made while it ran (the reference), and what the files lack is said.
#include <gtest/gtest.h>

#include <tuple>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "io/model_loader.hpp"
#include "io/results_writer.hpp"
#include "io/run_folder.hpp"
#include "study/run_analysis.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace {

fs::path temp_dir(const std::string& name) {
  const fs::path d =
      fs::temp_directory_path() / ("lash_run_folder_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(d);
  return d;
}

/// Runs the example into `dir` with the analyses made during the run, as `lash run --report`
/// does (the results writer observes the analysed run), and returns those analyses.
lash::RunAnalysis run_into(const fs::path& dir, const std::vector<std::string>& overrides,
                           const lash::AnalysisOptions& o, std::vector<std::string> channels = {}) {
  const lash::LoadedModel m =
      lash::load_model_file(lash::test::example_path("flores_slider_crank.yaml"), overrides);
  lash::OutputSettings out = m.output;
  if (!channels.empty()) out.channels = channels;
  lash::ResultsWriter w(m.model, dir.string(), m.resolved_yaml, overrides, "", out);
  lash::RunAnalysis ra = lash::analyze_run(m.model, o, &w);
  w.finish(ra.result);
  return ra;
}

/// The analyses of the folder, as `lash report DIR` makes them.
lash::RunAnalysis from_folder(const fs::path& dir, const lash::AnalysisOptions& o) {
  const lash::LoadedModel m = lash::load_model_file((dir / "model_resolved.yaml").string());
  lash::RecordedRun run = lash::read_run_folder(dir.string(), m.model);
  return lash::analyze_recorded_run(m.model, o, run);
}

/// |a − b| within the 9 significant digits of the CSV (relative 1e-8 of the channel's scale).
void expect_csv_close(double a, double b, double scale, const std::string& what) {
  EXPECT_NEAR(a, b, 1e-8 * std::max(std::abs(scale), 1e-300) + 1e-300) << what;
}

bool mentions(const std::vector<std::string>& lines, const std::string& text) {
  return std::any_of(lines.begin(), lines.end(),
                     [&](const std::string& l) { return l.find(text) != std::string::npos; });
}

}  // namespace

TEST(RunFolder, AnalysesFromTheFilesMatchThoseMadeDuringTheRun) {
  // 17 crank periods of the Flores example (end_time 0.204 s; T = 12 ms at 5000 rpm): enough
  // sections for a verdict and an exponent. The reference is the in-run analysis.
  const fs::path dir = temp_dir("same");
  lash::AnalysisOptions o;
  const lash::RunAnalysis in_run = run_into(dir, {"solver.end_time=0.204"}, o);
  const lash::RunAnalysis files = from_folder(dir, o);

  // Status and statistics: the CSV keeps 9 significant digits.
  EXPECT_EQ(files.result.status.ok, in_run.result.status.ok);
  EXPECT_EQ(files.result.outputs, in_run.result.outputs);
  EXPECT_EQ(files.result.stats.events, in_run.result.stats.events);
  ASSERT_EQ(files.statistics.size(), in_run.statistics.size());
  for (size_t i = 0; i < in_run.statistics.size(); ++i) {
    const auto& a = in_run.statistics[i];
    const auto& b = files.statistics[i];
    ASSERT_EQ(a.channel, b.channel);
    EXPECT_EQ(a.samples, b.samples) << a.channel;
    expect_csv_close(b.min, a.min, a.peak, a.channel + " min");
    expect_csv_close(b.max, a.max, a.peak, a.channel + " max");
    expect_csv_close(b.rms, a.rms, a.peak, a.channel + " rms");
  }
  // The decimated series and the frames.
  ASSERT_EQ(files.series.time.size(), in_run.series.time.size());
  ASSERT_EQ(files.frames.time.size(), in_run.frames.time.size());
  ASSERT_EQ(files.crank_angle_deg.size(), in_run.crank_angle_deg.size());
  for (size_t k = 0; k < in_run.crank_angle_deg.size(); ++k)
    EXPECT_NEAR(files.crank_angle_deg[k], in_run.crank_angle_deg[k], 1e-9);
  // Contact modes and impact velocities (events.csv keeps 12 digits of time, 9 of velocity).
  ASSERT_EQ(files.clearance.size(), in_run.clearance.size());
  for (size_t c = 0; c < in_run.clearance.size(); ++c) {
    const auto& a = in_run.clearance[c].modes;
    const auto& b = files.clearance[c].modes;
    EXPECT_EQ(a.impacts, b.impacts);
    EXPECT_NEAR(a.free_flight_share, b.free_flight_share, 1e-9);
    EXPECT_NEAR(a.continuous_share, b.continuous_share, 1e-9);
    ASSERT_EQ(a.impact_velocities.size(), b.impact_velocities.size());
    for (size_t k = 0; k < a.impact_velocities.size(); ++k)
      expect_csv_close(b.impact_velocities[k], a.impact_velocities[k], a.impact_velocities[k], "δ̇⁻");
    EXPECT_EQ(files.clearance[c].histogram.counts, in_run.clearance[c].histogram.counts);
    EXPECT_EQ(files.clearance[c].orbit.size(), in_run.clearance[c].orbit.size());
  }
  // Stroboscopic sections interpolated between outputs against those the integrator took at
  // k·T: the same times and, within 1% of the clearance (the distinct-point tolerance), the same
  // points. The largest difference is printed (docs/analysis.md quotes it).
  ASSERT_TRUE(in_run.poincare && files.poincare);
  ASSERT_EQ(files.poincare->times.size(), in_run.poincare->times.size());
  ASSERT_GE(in_run.poincare->times.size(), 16u);
  double worst = 0.0;
  const double c = in_run.clearance[0].clearance;
  for (size_t k = 0; k < in_run.poincare->times.size(); ++k) {
    EXPECT_NEAR(files.poincare->times[k], in_run.poincare->times[k], 1e-12);
    for (size_t i = 0; i < in_run.poincare->points[k].size(); ++i)
      worst = std::max(worst, std::abs(files.poincare->points[k][i] - in_run.poincare->points[k][i]));
  }
  std::printf("sections: largest difference, interpolated vs located: %.3g m = %.3g of the clearance\n",
              worst, worst / c);
  EXPECT_LT(worst, 0.01 * c);
  EXPECT_EQ(files.poincare->distinct, in_run.poincare->distinct);
  // The spectra (same samples to 9 digits).
  ASSERT_EQ(files.spectra.size(), in_run.spectra.size());
  for (size_t i = 0; i < in_run.spectra.size(); ++i) {
    double top = 0.0;
    for (double a : in_run.spectra[i].amplitude) top = std::max(top, a);
    ASSERT_EQ(files.spectra[i].amplitude.size(), in_run.spectra[i].amplitude.size());
    for (size_t k = 0; k < in_run.spectra[i].amplitude.size(); ++k)
      EXPECT_NEAR(files.spectra[i].amplitude[k], in_run.spectra[i].amplitude[k], 1e-6 * top);
  }
  // The Lyapunov trajectories start from the state the run made again to its first section
  // after the transient: the same state, the same exponent.
  ASSERT_TRUE(in_run.lyapunov && files.lyapunov);
  ASSERT_TRUE(in_run.lyapunov->ok);
  EXPECT_EQ(files.lyapunov->t0, in_run.lyapunov->t0);
  EXPECT_NEAR(files.lyapunov->exponent, in_run.lyapunov->exponent,
              1e-9 * std::abs(in_run.lyapunov->exponent));
  EXPECT_EQ(files.verdict.kind, in_run.verdict.kind);
  EXPECT_EQ(files.verdict.evidence, in_run.verdict.evidence);
  // What was read and what was simulated now is said.
  EXPECT_TRUE(mentions(files.provenance.read, "timeseries.csv"));
  EXPECT_TRUE(mentions(files.provenance.read, "events.csv"));
  EXPECT_TRUE(mentions(files.provenance.read, "summary.json"));
  EXPECT_TRUE(mentions(files.provenance.read, "final_state.json"));
  EXPECT_TRUE(mentions(files.provenance.read, "stroboscopic sections: from the outputs"));
  EXPECT_TRUE(mentions(files.provenance.resimulated, "ideal twin"));
  EXPECT_TRUE(mentions(files.provenance.resimulated, "Lyapunov start state"));
  // The exponent's method is named as computed (the default, variational; once said "two
  // trajectories" whatever the method).
  ASSERT_EQ(files.lyapunov->method, "variational");
  EXPECT_TRUE(mentions(files.provenance.resimulated, "Lyapunov exponent: variational spectrum"));
  EXPECT_FALSE(mentions(files.provenance.resimulated, "two trajectories"));
  EXPECT_TRUE(files.provenance.skipped.empty());
  fs::remove_all(dir);
}

TEST(RunFolder, ChannelsNotWrittenAreSaidAndTheirSectionsMadeAgain) {
  // A run that kept only the slider's channels: no eccentricities, so no orbits and no spectrum
  // of the contact force from the files; the sections come from the main run made again, and
  // are then exactly the in-run ones.
  const fs::path dir = temp_dir("subset");
  lash::AnalysisOptions o;
  o.lyapunov = false;
  const lash::RunAnalysis in_run = run_into(dir, {"solver.end_time=0.05"}, o, {"slider.*"});
  const lash::RunAnalysis files = from_folder(dir, o);
  EXPECT_TRUE(mentions(files.provenance.skipped, "animation frames: the pose (x, y, phi) of crank"))
      << ::testing::PrintToString(files.provenance.skipped);
  EXPECT_TRUE(files.frames.time.empty());
  EXPECT_TRUE(mentions(files.provenance.skipped, "journal orbits: rod_slider.ex/ey not written"))
      << ::testing::PrintToString(files.provenance.skipped);
  EXPECT_TRUE(mentions(files.provenance.skipped, "spectrum of rod_slider.Fn"));
  EXPECT_TRUE(mentions(files.provenance.resimulated, "stroboscopic sections (their channels were not written)"));
  ASSERT_TRUE(in_run.poincare && files.poincare);
  ASSERT_EQ(files.poincare->points.size(), in_run.poincare->points.size());
  for (size_t k = 0; k < in_run.poincare->points.size(); ++k)
    EXPECT_EQ(files.poincare->points[k], in_run.poincare->points[k]);
  EXPECT_TRUE(files.clearance[0].orbit.empty());
  // Statistics of the channels written, equal to the in-run ones to 9 digits.
  for (const auto& b : files.statistics) {
    const auto a = std::find_if(in_run.statistics.begin(), in_run.statistics.end(),
                                [&](const lash::ChannelStatistics& s) { return s.channel == b.channel; });
    ASSERT_NE(a, in_run.statistics.end());
    expect_csv_close(b.max, a->max, a->peak, b.channel);
  }
  EXPECT_EQ(files.statistics.size(), files.series.channels.size());
  fs::remove_all(dir);
}

TEST(RunFolder, ACutRowIsNamedWithItsLine) {
  const fs::path dir = temp_dir("cut");
  lash::AnalysisOptions o;
  o.lyapunov = false;
  o.ideal_twin = false;
  run_into(dir, {"solver.end_time=0.003"}, o);
  // A row with a field that is not a number, found as the row is read.
  std::string csv = lash::test::read_file((dir / "timeseries.csv").string());
  const size_t row3 = [&] {
    size_t p = 0;
    for (int i = 0; i < 3; ++i) p = csv.find('\n', p) + 1;
    return p;
  }();
  csv.replace(csv.find(',', row3) + 1, 1, "x");
  std::ofstream(dir / "timeseries.csv") << csv;
  try {
    from_folder(dir, o);
    FAIL() << "no error";
  } catch (const lash::RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("timeseries.csv:4:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("is not a number"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

TEST(RunFolder, NonFiniteTimesAndFilesThatAreNotRegularAreRefused) {
  const fs::path dir = temp_dir("tampered");
  lash::AnalysisOptions o;
  o.lyapunov = false;
  o.ideal_twin = false;
  run_into(dir, {"solver.end_time=0.003"}, o);
  const std::string csv = lash::test::read_file((dir / "timeseries.csv").string());
  const std::string events = lash::test::read_file((dir / "events.csv").string());
  ASSERT_NE(events.find("onset"), std::string::npos);
  auto expect_refused = [&](const std::string& text) {
    try {
      from_folder(dir, o);
      ADD_FAILURE() << "no error, expected " << text;
    } catch (const lash::RunFolderError& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  // nan and inf in the time column of either file (parsed as numbers, so the ordering checks
  // alone let them through).
  for (const std::string bad : {"nan", "inf"}) {
    std::string c = csv;
    const size_t row3 = c.find('\n', c.find('\n', c.find('\n') + 1) + 1) + 1;
    c.replace(row3, c.find(',', row3) - row3, bad);
    std::ofstream(dir / "timeseries.csv") << c;
    expect_refused("timeseries.csv:4:1: time " + bad + " is not a finite number");
    std::ofstream(dir / "timeseries.csv") << csv;
    std::string e = events;
    const size_t row2 = e.find('\n') + 1;
    e.replace(row2, e.find(',', row2) - row2, bad);
    std::ofstream(dir / "events.csv") << e;
    expect_refused("events.csv:2:1: time '" + bad + "' is not a finite number");
    std::ofstream(dir / "events.csv") << events;
    // And in a value: statistics of a column holding one would be null, not refused.
    c = csv;
    const size_t field2 = c.find(',', row3) + 1;
    c.replace(field2, c.find(',', field2) - field2, bad);
    std::ofstream(dir / "timeseries.csv") << c;
    expect_refused("timeseries.csv:4:" + std::to_string(field2 - row3 + 1) + ": '" + bad +
                   "' is not a finite number");
    std::ofstream(dir / "timeseries.csv") << csv;
  }
  // Fields of summary.json of the wrong kind are named, with what was expected (not "[json.
  // exception.type_error.304] cannot use at() with string").
  const std::string summary_text = lash::test::read_file((dir / "summary.json").string());
  for (const auto& [path, value, expected] :
       {std::tuple<const char*, nlohmann::json, const char*>{"/status", "ok", "status is \"ok\", expected an object"},
        {"/status/outcome", 5, "status.outcome is 5, expected text"},
        {"/output/channels", 5, "output.channels is 5, expected a list of texts"},
        {"/integrator/steps", "many", "integrator.steps is \"many\", expected a number"},
        {"/channels/slider.x/t_max", nullptr, "channels.slider.x.t_max is null, expected a number"},
        {"/max_constraint_violation", "x", "max_constraint_violation is \"x\", expected a number"},
        {"/integrator/projections", "x", "integrator.projections is \"x\", expected a number"},
        {"/warnings", nlohmann::json::array({1}), "warnings is [1], expected a list of texts"}}) {
    nlohmann::json j = nlohmann::json::parse(summary_text);
    j[nlohmann::json::json_pointer(path)] = value;
    std::ofstream(dir / "summary.json") << j.dump();
    expect_refused(expected);
  }
  std::ofstream(dir / "summary.json") << summary_text;
  // A link to /dev/zero would be read for ever: refused at once (ctest's time-out would end a
  // hang).
  for (const char* name : {"events.csv", "timeseries.csv"}) {
    fs::remove(dir / name);
    fs::create_symlink("/dev/zero", dir / name);
    expect_refused(std::string(name) + ": not a regular file");
    fs::remove(dir / name);
    std::ofstream(dir / name) << (std::string(name) == "events.csv" ? events : csv);
  }
  // A count in summary.json that is not a whole number >= 0 (1e30 rows was said as
  // -9223372036854775808).
  const std::string summary = lash::test::read_file((dir / "summary.json").string());
  for (const auto& [key, value] : std::vector<std::pair<std::string, std::string>>{
           {"output.rows", "1e30"}, {"output.rows", "-1"}, {"integrator.steps", "2.5"}}) {
    auto j = nlohmann::json::parse(summary);
    const std::string section = key.substr(0, key.find('.')), name = key.substr(key.find('.') + 1);
    j[section][name] = nlohmann::json::parse(value);
    std::ofstream(dir / "summary.json") << j.dump();
    expect_refused("summary.json: damaged (" + key + " is " + nlohmann::json::parse(value).dump() +
                   ", expected a whole number >= 0)");
  }
  std::ofstream(dir / "summary.json") << summary;
  EXPECT_NO_THROW(from_folder(dir, o));
  fs::remove_all(dir);
}

TEST(RunFolder, EventsCsvHoldsTheMissedCrossingsThatSummaryCounts) {
  // At a loose tolerance the integrator misses crossings; they are corrected at a step's end
  // and written to events.csv like the others (integrator.missed_events). The folder must read.
  const fs::path dir = temp_dir("missed");
  lash::AnalysisOptions o;
  o.lyapunov = false;
  o.ideal_twin = false;
  const lash::RunAnalysis made = run_into(
      dir, {"solver.rtol=2e-2", "solver.atol=1e-6", "drivers.crank.speed_rpm=3000"}, o);
  ASSERT_TRUE(made.result.status.ok) << made.result.status.message;
  ASSERT_GT(made.result.missed_events, 0) << "the case no longer misses a crossing";
  const lash::LoadedModel m = lash::load_model_file((dir / "model_resolved.yaml").string());
  const lash::RecordedRun run = lash::read_run_folder(dir.string(), m.model);
  EXPECT_EQ(static_cast<long>(run.events.size()),
            made.result.stats.events + made.result.missed_events);
  fs::remove_all(dir);
}

TEST(RunFolder, SectionsBetweenOutputsAgreeWithThoseTheIntegratorLocated) {
  // Output intervals that do not divide the period (T = 12 ms): every section is interpolated
  // through four outputs, and kept only when the estimated error is below a tenth of the point
  // tolerance (1% of the clearance); otherwise the sections are made again by the integrator and
  // are the in-run ones exactly. 17 periods; the measured difference is printed. At 9e-6 s the
  // estimate is 2.1e-7 m, below the bound (5e-7 m): interpolated; at 7e-5 s the contact rings
  // between outputs: made again (docs/analysis.md says both).
  for (const double dt : {9e-6, 7e-5}) {
    const fs::path dir = temp_dir("strobe");
    lash::AnalysisOptions o;
    o.lyapunov = false;
    o.ideal_twin = false;
    char interval[32];
    std::snprintf(interval, sizeof interval, "%g", dt);
    const lash::RunAnalysis in_run =
        run_into(dir, {"solver.end_time=0.204", std::string("solver.output_interval=") + interval}, o);
    const lash::RunAnalysis files = from_folder(dir, o);
    ASSERT_TRUE(in_run.poincare && files.poincare);
    ASSERT_EQ(files.poincare->times.size(), in_run.poincare->times.size());
    const double c = in_run.clearance[0].clearance;
    double worst = 0.0;
    for (size_t k = 0; k < in_run.poincare->times.size(); ++k) {
      EXPECT_NEAR(files.poincare->times[k], in_run.poincare->times[k], 1e-12);
      for (size_t i = 0; i < in_run.poincare->points[k].size(); ++i)
        worst = std::max(worst, std::abs(files.poincare->points[k][i] - in_run.poincare->points[k][i]));
    }
    const bool interpolated = mentions(files.provenance.read, "stroboscopic sections: interpolated");
    const bool again = mentions(files.provenance.resimulated, "stroboscopic sections (interpolated");
    EXPECT_NE(interpolated, again) << dt;
    EXPECT_EQ(interpolated, dt < 1e-5) << dt;
    std::printf("output interval %g s: %s; sections differ from the located ones by at most %.3g m "
                "= %.3g of the clearance\n", dt, interpolated ? "interpolated" : "made again",
                worst, worst / c);
    EXPECT_LT(worst, 1e-3 * c) << dt;
    if (again) {
      EXPECT_EQ(worst, 0.0) << dt;
    }
    EXPECT_EQ(files.poincare->distinct, in_run.poincare->distinct) << dt;
    EXPECT_EQ(files.verdict.kind, in_run.verdict.kind) << dt;
    fs::remove_all(dir);
  }
}

TEST(RunFolder, SectionsOfARunWithTooFewOutputsToEstimateAreMadeAgain) {
  // Three outputs (0, 0.03, 0.06 s) for five sections: no second interpolant to estimate the
  // error with. They were kept, "estimated error 0 m", hundreds of µm from the located ones.
  const fs::path dir = temp_dir("strobe_few");
  lash::AnalysisOptions o;
  o.lyapunov = false;
  o.ideal_twin = false;
  const lash::RunAnalysis in_run =
      run_into(dir, {"solver.end_time=0.06", "solver.output_interval=0.03"}, o);
  const lash::RunAnalysis files = from_folder(dir, o);
  ASSERT_TRUE(in_run.poincare && files.poincare);
  ASSERT_EQ(files.poincare->points.size(), in_run.poincare->points.size());
  ASSERT_GT(in_run.poincare->points.size(), 2u);
  EXPECT_EQ(files.poincare->points, in_run.poincare->points);
  EXPECT_TRUE(mentions(files.provenance.resimulated,
                       "the run has fewer than 4 outputs, so no interpolation error can be estimated"));
  fs::remove_all(dir);
}

TEST(RunFolder, StatisticsExtremaAreExactOverTheRunAndOverAWindow) {
  // Two revolutions of the Flores example with outputs every 1 ms and every 10 µs. The
  // statistics' min, max and peak are tracked between outputs, so they agree at both output
  // intervals (within 0.1 %), over the whole run and over the second revolution alone; read
  // back from the folder they are summary.json's (whole run) or made again (a window), and agree
  // with those of the run itself.
  lash::AnalysisOptions o;
  o.lyapunov = false;
  o.ideal_twin = false;
  lash::AnalysisOptions w = o;
  w.stats_t0 = 0.012;
  w.stats_t1 = 0.024;
  const fs::path coarse_dir = temp_dir("exact_coarse"), fine_dir = temp_dir("exact_fine");
  const std::vector<std::string> run = {"solver.end_time=0.024"};
  auto with = [](std::vector<std::string> v, const char* dt) {
    v.push_back(std::string("solver.output_interval=") + dt);
    return v;
  };
  const lash::RunAnalysis coarse = run_into(coarse_dir, with(run, "1e-3"), o);
  const lash::RunAnalysis fine = run_into(fine_dir, with(run, "1e-5"), o);
  const lash::RunAnalysis coarse_w = run_into(temp_dir("exact_coarse_w"), with(run, "1e-3"), w);
  const lash::RunAnalysis fine_w = run_into(temp_dir("exact_fine_w"), with(run, "1e-5"), w);
  auto stat = [](const lash::RunAnalysis& a, const std::string& c) {
    for (const auto& s : a.statistics)
      if (s.channel == c) return s;
    throw std::runtime_error("no statistics of " + c);
  };
  for (const char* c : {"slider.ax", "rod_slider.Fn", "crank_rod.Fy"}) {
    SCOPED_TRACE(c);
    const auto a = stat(coarse, c), b = stat(fine, c), aw = stat(coarse_w, c), bw = stat(fine_w, c);
    EXPECT_TRUE(a.exact && b.exact && aw.exact && bw.exact);
    EXPECT_NEAR(a.peak, b.peak, 1e-3 * b.peak);
    EXPECT_NEAR(a.max, b.max, 1e-3 * b.peak);
    EXPECT_NEAR(a.min, b.min, 1e-3 * b.peak);
    EXPECT_NEAR(aw.peak, bw.peak, 1e-3 * bw.peak);
    EXPECT_NEAR(aw.max, bw.max, 1e-3 * bw.peak);
    // The window's extrema lie in it and within the whole run's.
    EXPECT_GE(aw.t_max, 0.012);
    EXPECT_LE(aw.t_max, 0.024);
    EXPECT_GE(aw.t_min, 0.012);
    EXPECT_LE(aw.max, a.max);
    EXPECT_GE(aw.min, a.min);
    // From the folder: the whole run's from summary.json, the window's made again: the same.
    const auto f = stat(from_folder(coarse_dir, o), c);
    EXPECT_TRUE(f.exact);
    EXPECT_NEAR(f.max, a.max, 1e-12 * a.peak);
    EXPECT_NEAR(f.t_max, a.t_max, 1e-12);
    EXPECT_NEAR(f.min, a.min, 1e-12 * a.peak);
    const lash::RunAnalysis fw_all = from_folder(coarse_dir, w);
    const auto fw = stat(fw_all, c);
    EXPECT_TRUE(fw.exact);
    EXPECT_NEAR(fw.max, aw.max, 1e-9 * aw.peak);
    EXPECT_NEAR(fw.min, aw.min, 1e-9 * aw.peak);
    EXPECT_TRUE(mentions(fw_all.provenance.resimulated, "exact extrema"));
  }
  EXPECT_TRUE(mentions(from_folder(coarse_dir, o).provenance.read, "exact extrema"));
  // Over a crank-angle range the extrema are the samples', and that is said.
  lash::AnalysisOptions by_angle = o;
  by_angle.stats_angle0 = 0.0;
  by_angle.stats_angle1 = 180.0;
  const lash::RunAnalysis ang = from_folder(coarse_dir, by_angle);
  EXPECT_FALSE(stat(ang, "slider.ax").exact);
  EXPECT_TRUE(mentions(ang.provenance.skipped, "crank-angle range"));
  for (const char* d : {"exact_coarse", "exact_fine", "exact_coarse_w", "exact_fine_w"})
    fs::remove_all(temp_dir(d));
}
