// A run with its analyses (io/report.cpp): periodic and period-2 responses are recognised, and
// the report data of the Flores example is complete and consistent.
#include <cmath>

#include <unistd.h>

#include <filesystem>

#include "io/report.hpp"
#include "test_support.hpp"

using namespace lash;
using namespace lash::test;

namespace {
ReportRun analyse(const std::string& yaml, const std::vector<std::string>& overrides = {},
                  ReportOptions o = {}) {
  const LoadedModel lm = load_model_text(yaml, "t.yaml", overrides);
  return run_with_analysis(lm, o, nullptr);
}
}  // namespace

TEST(Report, IdealSliderCrankIsPeriodicWithOnePoincarePoint) {
  const ReportRun r = analyse(read_file(example_path("flores_slider_crank_ideal.yaml")),
                              {"solver.end_time=0.12", "solver.output_interval=1e-4"});
  ASSERT_TRUE(r.result.status.ok);
  const auto& p = r.data["analysis"]["poincare"];
  EXPECT_EQ(p["kind"], "stroboscopic");
  EXPECT_NEAR(p["period"].get<double>(), 0.012, 1e-12);
  EXPECT_EQ(p["points"].size(), 10u);  // sections at 0.012, 0.024, …, 0.12 (t = 0 is transient)
  EXPECT_EQ(p["distinct"].get<int>(), 1);
  EXPECT_EQ(r.data["analysis"]["verdict"]["class"], "periodic");
  // The driver fixes every coordinate: there is no free direction, so no exponent.
  const auto& ly = r.data["analysis"]["lyapunov"];
  EXPECT_TRUE(ly["exponent"].is_null());
  EXPECT_NE(ly["message"].get<std::string>().find("no free degree of freedom"), std::string::npos) << ly["message"];
}

TEST(Report, SubharmonicResponseGivesTwoPoincarePoints) {
  // A flywheel turning at ω sets the period T = 2π/ω; a mass on a spring tuned to ω/2 moves
  // x = x0 cos(ωt/2): sampled every T it alternates between +x0 and −x0: a period-2 orbit.
  const double w = 100.0, m = 1.0, k = m * (w / 2) * (w / 2);
  const std::string yaml = R"Y(
bodies:
  wheel: {mass: 1, inertia: 0.01}
  block: {mass: 1.0, inertia: 0.01, position: [0.01, 1]}
ground: {markers: {O: [0, 0], R: [0, 1]}}
joints:
  axle: {type: revolute, journal: wheel, bearing: ground.O}
  rail: {type: translational, guide: ground.R, slider: block, axis: [1, 0]}
drivers:
  motor: {joint: axle, speed: )Y" + std::to_string(w) + R"Y(}
loads:
  spring: {type: spring_damper, from: ground.R, to: block, stiffness: )Y" + std::to_string(k) +
                           R"Y(, free_length: 0}
solver: {rtol: 1e-10, atol: 1e-13, end_time: 1.3, output_interval: 1e-3, initial_state: given}
)Y";
  ReportOptions o;
  o.lyapunov = false;
  const ReportRun r = analyse(yaml, {}, o);
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const auto& p = r.data["analysis"]["poincare"];
  EXPECT_GE(p["points"].size(), 18u);
  EXPECT_EQ(p["distinct"].get<int>(), 2);
  EXPECT_EQ(r.data["analysis"]["verdict"]["class"], "periodic");

  // Event-based: the block's velocity falling through zero happens at its largest x, once per
  // oscillation (2T): the same state every time, one distinct point.
  o.section_planes = {"block.vx=0,down"};
  const ReportRun e = analyse(yaml, {}, o);
  const auto& pe = e.data["analysis"]["poincare"];
  EXPECT_EQ(pe["kind"], "event");
  const double t_osc = 4 * M_PI / w;  // 0.1257 s; sections after the 1-period transient
  EXPECT_NEAR(static_cast<double>(pe["points"].size()), std::floor((1.3 - 2 * M_PI / w) / t_osc), 1.0);
  EXPECT_EQ(pe["distinct"].get<int>(), 1);
  for (const auto& p : pe["points"]) EXPECT_NEAR(p[0].get<double>(), 0.0, 1e-9);  // wheel x
  // Bad planes are reported.
  o.section_planes = {"block.speed=0"};
  EXPECT_THROW(analyse(yaml, {}, o), std::invalid_argument);
}

TEST(Report, FloresExampleDataIsCompleteAndConsistent) {
  ReportOptions o;
  const ReportRun r = analyse(read_file(example_path("flores_slider_crank.yaml")), {}, o);
  ASSERT_TRUE(r.result.status.ok);
  const auto& d = r.data;
  for (const char* key : {"model", "status", "integrator", "series", "frames", "analysis"})
    EXPECT_TRUE(d.contains(key)) << key;
  const size_t n = d["series"]["time"].size();
  EXPECT_GT(n, 1000u);
  EXPECT_LE(n, 4002u);
  EXPECT_EQ(d["series"]["channels"]["slider.ax"].size(), n);
  EXPECT_EQ(d["series"]["ideal"]["slider.ax"].size(), n);
  EXPECT_EQ(d["series"]["crank_angle"].size(), n);
  // Min/max decimation keeps the impact spikes: the decimated peak is the true peak.
  double peak = 0;
  for (double v : d["series"]["channels"]["slider.ax"]) peak = std::max(peak, std::abs(v));
  EXPECT_NEAR(peak, d["analysis"]["statistics"]["slider.ax"]["peak"].get<double>(), 1e-5 * peak);  // 6 digits
  // Clearance makes the slider acceleration peak larger than the ideal mechanism's 19.4 km/s².
  const auto& cmp = d["analysis"]["comparison"]["slider.ax"];
  EXPECT_NEAR(cmp["ideal_peak"].get<double>(), 19419, 30);
  EXPECT_GT(cmp["peak_ratio"].get<double>(), 1.0);
  // Modes: shares add up, impacts match the onsets, the histogram counts every impact.
  const auto& cj = d["analysis"]["clearance"]["rod_slider"];
  const auto& m = cj["modes"];
  EXPECT_NEAR(m["free_flight_share"].get<double>() + m["impact_share"].get<double>() +
                  m["continuous_share"].get<double>(), 1.0, 1e-12);
  EXPECT_EQ(m["impacts"].get<int>(), static_cast<int>(cj["impact_velocities"].size()));
  int counted = 0;
  for (int c : cj["histogram"]["counts"]) counted += c;
  EXPECT_EQ(counted, m["impacts"].get<int>());
  // The orbit stays within the clearance circle plus the penetration.
  for (size_t i = 0; i < cj["orbit"]["ex"].size(); ++i)
    ASSERT_LT(std::hypot(cj["orbit"]["ex"][i].get<double>(), cj["orbit"]["ey"][i].get<double>()),
              0.5e-3 + 1e-4);
  EXPECT_TRUE(d["analysis"]["spectra"].contains("slider.ax"));
  EXPECT_FALSE(d["analysis"]["verdict"]["class"].get<std::string>().empty());
  EXPECT_FALSE(d["analysis"]["verdict"]["evidence"].empty());
  EXPECT_EQ(d["frames"]["bodies"]["crank"].size(), d["frames"]["time"].size());
}

TEST(Report, StatisticsOverACrankAngleRange) {
  // The ideal slider's acceleration over a crank-angle window against the closed form
  // a(θ) = −rω²(cos θ + (r/l) cos 2θ / √(1 − (r/l)² sin² θ) + ...) evaluated on a fine grid: at
  // top dead centre (350°…10°) the extreme is the −19 419 m/s² of mechanisms.md; near bottom dead
  // centre (170°…190°) r/l = 0.42 > 1/4 splits the maximum off 180° (8 089 m/s² > 7 996 m/s²).
  const double r = 0.05, l = 0.12, w = 5000 * 2 * M_PI / 60;
  auto ax = [&](double th) {
    const double s = std::sin(th), c = std::cos(th);
    const double root = std::sqrt(l * l - r * r * s * s), u = r * r * s * c;
    return -r * c * w * w - r * r * std::cos(2 * th) * w * w / root - u * u * w * w / (root * root * root);
  };
  auto extreme = [&](double a0, double a1, bool want_max) {
    double e = want_max ? -1e300 : 1e300;
    for (double a = a0; a <= a1; a += 0.001) {
      const double v = ax(a * M_PI / 180);
      e = want_max ? std::max(e, v) : std::min(e, v);
    }
    return e;
  };
  ReportOptions o;
  o.lyapunov = false;
  o.stats_angle0 = 350;
  o.stats_angle1 = 10;
  const std::string yaml = read_file(example_path("flores_slider_crank_ideal.yaml"));
  const ReportRun top = analyse(yaml, {"solver.output_interval=1e-6"}, o);
  EXPECT_NEAR(top.data["analysis"]["statistics"]["slider.ax"]["min"].get<double>(),
              extreme(-10, 10, false), 1.0);
  EXPECT_NEAR(extreme(-10, 10, false), -19419, 1.0);
  o.stats_angle0 = 170;
  o.stats_angle1 = 190;
  const ReportRun bottom = analyse(yaml, {"solver.output_interval=1e-6"}, o);
  const auto& st = bottom.data["analysis"]["statistics"]["slider.ax"];
  EXPECT_NEAR(st["max"].get<double>(), extreme(170, 190, true), 1.0);
  EXPECT_NEAR(st["min"].get<double>(), extreme(170, 190, false), 1.0);
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
