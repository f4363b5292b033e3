// The report of a run with its analyses (io/report.cpp): report_data.json follows
// docs/report-data.md (the Flores example complete and consistent, the ideal slider-crank's
// sections and verdict, rounding and nulls), and report.html embeds it safely.
#include <cmath>

#include <unistd.h>

#include <filesystem>

#include "io/report.hpp"
#include "test_support.hpp"

using namespace lash;
using namespace lash::test;
using nlohmann::json;

namespace {
struct Report {
  Model model;
  RunAnalysis run;
  json data;
};

Report report(const std::string& yaml, const std::vector<std::string>& overrides = {},
              AnalysisOptions o = {}) {
  Report r;
  r.model = load_model_text(yaml, "t.yaml", overrides).model;
  r.run = analyze_run(r.model, o);
  r.data = report_data(r.model, r.run);
  return r;
}

/// Six significant digits, as the document rounds its series.
double six_digits(double v) {
  if (v == 0.0) return 0.0;
  const double scale = std::pow(10.0, 5 - static_cast<int>(std::floor(std::log10(std::abs(v)))));
  return std::round(v * scale) / scale;
}
}  // namespace

TEST(Report, IdealSliderCrankSectionsAndVerdict) {
  const Report r = report(read_file(example_path("flores_slider_crank_ideal.yaml")),
                          {"solver.end_time=0.12", "solver.output_interval=1e-4"});
  ASSERT_TRUE(r.data["status"]["ok"].get<bool>());
  const auto& p = r.data["analysis"]["poincare"];
  EXPECT_EQ(p["kind"], "stroboscopic");
  EXPECT_TRUE(p["plane"].is_null());
  EXPECT_NEAR(p["period"].get<double>(), 0.012, 1e-12);
  EXPECT_EQ(p["points"].size(), 10u);  // sections at 0.012, 0.024, …, 0.12 (t = 0 is transient)
  EXPECT_EQ(p["times"].size(), 10u);
  // The times in full (rounded to six digits, k·T at 4321 rpm was off by up to 1.8e-7 s).
  const Report odd = report(read_file(example_path("flores_slider_crank_ideal.yaml")),
                            {"solver.end_time=0.1", "solver.output_interval=1e-4",
                             "drivers.crank.speed_rpm=4321"});
  ASSERT_TRUE(odd.run.poincare);
  const auto& ot = odd.data["analysis"]["poincare"]["times"];
  ASSERT_EQ(ot.size(), odd.run.poincare->times.size());
  for (size_t k = 0; k < ot.size(); ++k) {
    EXPECT_EQ(ot[k].get<double>(), odd.run.poincare->times[k]);
    EXPECT_NEAR(ot[k].get<double>(), (k + 1) * 60.0 / 4321, 1e-12);
  }
  EXPECT_EQ(p["distinct"].get<int>(), 1);
  EXPECT_EQ(p["variables"], json({"crank.x", "crank.y"}));  // no clearance joint: body poses
  for (const auto& x : p["points"]) EXPECT_EQ(x.size(), 2u);
  // Ten sections are fewer than the rule needs (16): undetermined, with the rule stated.
  EXPECT_EQ(r.data["analysis"]["verdict"]["class"], "undetermined");
  EXPECT_EQ(r.data["analysis"]["verdict"]["evidence"], json(r.run.verdict.evidence));
  EXPECT_EQ(r.data["analysis"]["verdict"]["rule"], r.run.verdict.rule);
  // No clearance joint: no twin.
  EXPECT_TRUE(r.data["series"]["ideal"].is_null());
  EXPECT_TRUE(r.data["analysis"]["comparison"].is_null());
  EXPECT_TRUE(r.data["analysis"]["clearance"].empty());
  // The driver fixes every coordinate: there is no free direction, so no exponent.
  const auto& ly = r.data["analysis"]["lyapunov"];
  EXPECT_TRUE(ly["exponent"].is_null());
  EXPECT_EQ(ly["renormalisations"], 0);
  EXPECT_TRUE(ly["history"].empty());
  EXPECT_NE(ly["message"].get<std::string>().find("no free degree of freedom"), std::string::npos) << ly["message"];
}

TEST(Report, FloresExampleDataIsCompleteAndConsistent) {
  const Report r = report(read_file(example_path("flores_slider_crank.yaml")));
  ASSERT_TRUE(r.run.result.status.ok);
  const auto& d = r.data;
  for (const char* key : {"version", "model", "status", "integrator", "max_constraint_violation",
                          "channel_info", "series", "frames", "analysis"})
    EXPECT_TRUE(d.contains(key)) << key;
  for (const char* key : {"statistics", "comparison", "clearance", "poincare", "spectra", "phase",
                          "lyapunov", "verdict"})
    EXPECT_TRUE(d["analysis"].contains(key)) << key;
  const size_t n = d["series"]["time"].size();
  EXPECT_GT(n, 1000u);
  EXPECT_LE(n, 4002u);
  EXPECT_EQ(d["series"]["channels"]["slider.ax"].size(), n);
  EXPECT_EQ(d["series"]["ideal"]["slider.ax"].size(), n);
  EXPECT_EQ(d["series"]["crank_angle"].size(), n);
  // Every channel with its unit and description; the twin's only where the run has them too.
  EXPECT_EQ(d["series"]["channels"].size(), r.run.series.channels.size());
  EXPECT_EQ(d["channel_info"].size(), r.run.series.channels.size());
  EXPECT_EQ(d["channel_info"]["slider.ax"]["unit"], "m/s²");
  for (const auto& [name, v] : d["series"]["ideal"].items())
    EXPECT_TRUE(d["series"]["channels"].contains(name)) << name;
  // Series are the typed ones rounded to six significant digits.
  const auto& ax = r.run.series.values[r.run.series.index("slider.ax")];
  for (size_t k = 0; k < n; ++k) {
    ASSERT_EQ(d["series"]["channels"]["slider.ax"][k].get<double>(), six_digits(ax[k])) << k;
    ASSERT_EQ(d["series"]["time"][k].get<double>(), six_digits(r.run.series.time[k])) << k;
  }
  // The statistics' extrema are exact (tracked between outputs): at least the series' peak.
  double peak = 0;
  for (double v : d["series"]["channels"]["slider.ax"]) peak = std::max(peak, std::abs(v));
  EXPECT_LE(peak, d["analysis"]["statistics"]["slider.ax"]["peak"].get<double>() * (1 + 1e-5));  // 6 digits
  EXPECT_EQ(d["analysis"]["statistics"]["slider.ax"]["extrema"], "exact");
  const double t_max = d["analysis"]["statistics"]["slider.ax"]["t_max"].get<double>();
  EXPECT_TRUE(t_max >= 0.0 && t_max <= 0.024) << t_max;
  EXPECT_TRUE(d["analysis"]["statistics"]["slider.ax"]["angle_range"].is_null());
  EXPECT_EQ(d["analysis"]["statistics"]["slider.ax"]["window"], json({0.0, 0.024}));
  // Clearance makes the slider acceleration peak larger than the ideal mechanism's 19.4 km/s².
  const auto& cmp = d["analysis"]["comparison"]["slider.ax"];
  EXPECT_NEAR(cmp["ideal_peak"].get<double>(), 19419, 30);
  EXPECT_GT(cmp["peak_ratio"].get<double>(), 1.0);
  // The ideal twin dissipates nothing (no clearance joint), the run does: no ratio, null (it
  // was 0, as if the clearance removed the channel).
  const auto& dissipated = d["analysis"]["comparison"]["energy.dissipated"];
  EXPECT_EQ(dissipated["ideal_peak"].get<double>(), 0.0);
  EXPECT_GT(dissipated["max_deviation"].get<double>(), 0.0);
  EXPECT_TRUE(dissipated["peak_ratio"].is_null()) << dissipated.dump();
  // Modes: shares add up, impacts match the onsets, the histogram counts every impact.
  const auto& cj = d["analysis"]["clearance"]["rod_slider"];
  const auto& m = cj["modes"];
  EXPECT_NEAR(m["free_flight_share"].get<double>() + m["impact_share"].get<double>() +
                  m["continuous_share"].get<double>(), 1.0, 1e-12);
  EXPECT_EQ(m["impacts"].get<int>(), static_cast<int>(cj["impact_velocities"].size()));
  EXPECT_EQ(m["episodes"].size(), r.run.clearance[0].modes.episodes.size());
  for (const auto& e : m["episodes"]) {
    ASSERT_EQ(e.size(), 3u);
    EXPECT_TRUE(e[2] == "impact" || e[2] == "continuous") << e;
  }
  int counted = 0;
  for (int c : cj["histogram"]["counts"]) counted += c;
  EXPECT_EQ(counted, m["impacts"].get<int>());
  // The orbit stays within the clearance circle plus the penetration.
  for (size_t i = 0; i < cj["orbit"]["ex"].size(); ++i)
    ASSERT_LT(std::hypot(cj["orbit"]["ex"][i].get<double>(), cj["orbit"]["ey"][i].get<double>()),
              0.5e-3 + 1e-4);
  EXPECT_TRUE(d["analysis"]["spectra"].contains("slider.ax"));
  EXPECT_EQ(d["analysis"]["spectra"]["slider.ax"]["window"], "hann");
  EXPECT_FALSE(d["analysis"]["verdict"]["class"].get<std::string>().empty());
  EXPECT_FALSE(d["analysis"]["verdict"]["evidence"].empty());
  EXPECT_EQ(d["frames"]["bodies"]["crank"].size(), d["frames"]["time"].size());
  EXPECT_EQ(d["frames"]["clearance"]["rod_slider"].size(), d["frames"]["time"].size());
  // Default phase portraits: the joint's ex–ey and δ–δ̇, all of them channels.
  EXPECT_EQ(d["analysis"]["phase"], json::parse(R"([{"x": "rod_slider.ex", "y": "rod_slider.ey"},
                                                    {"x": "rod_slider.delta", "y": "rod_slider.delta_dot"}])"));
}

TEST(Report, AFlexibleLinkCarriesItsDeflectionIntoTheAnimation) {
  AnalysisOptions o;
  o.ideal_twin = false;
  o.lyapunov = false;
  const Report r = report(read_file(example_path("flores_slider_crank_flexible_rod.yaml")),
                          {"solver.end_time=0.006"}, o);
  ASSERT_TRUE(r.run.result.status.ok);
  const auto& d = r.data;
  json rod;
  for (const auto& b : d["model"]["bodies"])
    if (b["name"] == "rod") rod = b;
  ASSERT_TRUE(rod.contains("flexible"));
  EXPECT_DOUBLE_EQ(rod["flexible"]["length"].get<double>(), 0.12);
  EXPECT_EQ(rod["flexible"]["elements"].get<int>(), 4);
  const auto& w = d["frames"]["deflection"]["rod"];
  ASSERT_EQ(w.size(), d["frames"]["time"].size());
  // The frames' deflection is the channel's at the frame times (six digits), and it moves.
  double largest = 0.0;
  for (const auto& v : w) largest = std::max(largest, std::abs(v.get<double>()));
  EXPECT_GT(largest, 1e-7);
  EXPECT_LT(largest, 1e-3);
  EXPECT_FALSE(d["frames"]["deflection"].contains("crank"));  // rigid bodies have none
}

TEST(Report, JointsAreNamedByTheirKindAndGroundPointsByTheirMarker) {
  // A distance joint was written as "fixed", and the ground's points as "ground.P" where the
  // document names them by marker ("P"); a bare "ground" is its origin.
  const Model model = load_model_text(R"Y(gravity: [0, -9.81]
ground: {markers: {P: [0, 1]}}
bodies:
  bob: {mass: 1, position: [0.5, 1]}
  arm: {mass: 1, inertia: 0.1, position: [0.25, 0], angle: 0, markers: {O: [-0.25, 0]}}
joints:
  rod: {type: distance, from: ground.P, to: bob}
  pin: {type: revolute, journal: arm.O, bearing: ground}
solver: {end_time: 0.01, output_interval: 0.001}
)Y", "t.yaml", {}).model;
  const json d = report_data(model, RunAnalysis{});
  ASSERT_EQ(d["model"]["joints"].size(), 2u);
  EXPECT_EQ(d["model"]["joints"][0]["type"], "distance");
  EXPECT_EQ(d["model"]["joints"][1]["type"], "revolute");
  EXPECT_EQ(d["model"]["ground_markers"], json({{"P", {0.0, 1.0}}, {"origin", {0.0, 0.0}}}));
}

TEST(Report, RoundingAndWhatIsMissing) {
  // A hand-made result: the document rounds series to six digits, keeps statistics exact, and
  // writes null for what was not computed.
  const Model model =
      load_model_text(read_file(example_path("flores_slider_crank_ideal.yaml")), "t.yaml", {}).model;
  RunAnalysis a;
  a.result.status.ok = false;
  a.result.status.t = 0.5;
  a.result.status.element = "crank_pivot";
  a.result.status.message = "stopped";
  a.series.time = {0.0, 1.0 / 3.0};
  a.series.channels = {{"slider.ax", "m/s²", "acceleration"}};
  a.series.values = {{1.23456789, -987654.321}};
  ChannelStatistics st;
  st.channel = "slider.ax";
  st.min = -987654.321;
  st.max = 1.23456789;
  st.t0 = 0.0;
  st.t1 = 0.5;
  st.angle0_deg = 350;
  st.angle1_deg = 10;
  a.statistics = {st};
  LyapunovEstimate l;
  l.estimated = true;
  l.ok = false;
  l.renormalisations = 3;
  l.interval = 1e-3;
  l.d0 = 1e-7;
  l.history = {{0.0123456789, 42.4242424}};
  l.message = "a trajectory failed";
  a.lyapunov = l;
  a.verdict.kind = "undetermined";
  const json d = report_data(model, a);
  EXPECT_EQ(d["version"], 1);
  EXPECT_EQ(d["model"]["name"], model.name);
  EXPECT_EQ(d["status"], json({{"ok", false}, {"time", 0.5}, {"element", "crank_pivot"},
                               {"message", "stopped"}}));
  EXPECT_EQ(d["series"]["time"], json({0.0, 0.333333}));
  EXPECT_EQ(d["series"]["channels"]["slider.ax"], json({1.23457, -987654.0}));
  EXPECT_EQ(d["channel_info"]["slider.ax"], json({{"unit", "m/s²"}, {"description", "acceleration"}}));
  EXPECT_TRUE(d["series"]["crank_angle"].is_null());
  EXPECT_TRUE(d["series"]["ideal"].is_null());
  EXPECT_EQ(d["analysis"]["statistics"]["slider.ax"]["min"], -987654.321);
  EXPECT_EQ(d["analysis"]["statistics"]["slider.ax"]["angle_range"], json({350.0, 10.0}));
  EXPECT_EQ(d["analysis"]["statistics"]["slider.ax"]["window"], json({0.0, 0.5}));
  EXPECT_TRUE(d["analysis"]["comparison"].is_null());
  EXPECT_TRUE(d["analysis"]["poincare"].is_null());
  EXPECT_TRUE(d["analysis"]["spectra"].empty());
  EXPECT_TRUE(d["analysis"]["phase"].empty());
  // A failed estimate keeps its inputs and history but gives no exponent.
  const auto& ly = d["analysis"]["lyapunov"];
  EXPECT_TRUE(ly["exponent"].is_null());
  EXPECT_EQ(ly["renormalisations"], 3);
  EXPECT_EQ(ly["interval"], 1e-3);
  EXPECT_EQ(ly["d0"], 1e-7);
  EXPECT_EQ(ly["history"], json({{0.0123457, 42.4242}}));
  EXPECT_EQ(ly["message"], "a trajectory failed");
  a.lyapunov.reset();
  EXPECT_TRUE(report_data(model, a)["analysis"]["lyapunov"].is_null());
}

TEST(Report, PageEmbedsTheDataSafely) {
  // A model name that tries to close the data script and open another one must come back intact
  // from the page, and must not end the script early.
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("lash_report_embed_" + std::to_string(getpid()));
  nlohmann::json d = {{"version", 1},
                      {"model", {{"name", "</script><!--<script>alert(1)</script>"}}}};
  write_report(d, dir.string());
  const std::string html = read_file((dir / "report.html").string());
  const std::string open = "<script id=\"lash-data\" type=\"application/json\">";
  const auto a = html.find(open);
  ASSERT_NE(a, std::string::npos);
  const auto b = html.find("</script>", a);
  ASSERT_NE(b, std::string::npos);
  const std::string embedded = html.substr(a + open.size(), b - a - open.size());
  EXPECT_EQ(embedded.find('<'), std::string::npos) << "no '<' may reach the HTML parser";
  EXPECT_EQ(nlohmann::json::parse(embedded), d);
  fs::remove_all(dir);
}
