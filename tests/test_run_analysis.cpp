// A run with its analyses (study/run_analysis.cpp), read as typed results: periodic and period-2
// responses are recognised, the Flores example's results are complete and consistent, statistics
// over a crank-angle range match the closed form, the Lyapunov estimate carries its inputs, and
// an extra observer sees exactly the main run.
#include <algorithm>
#include <cmath>

#include "study/run_analysis.hpp"
#include "test_support.hpp"

using namespace lash;
using namespace lash::test;

namespace {
struct Analysed {
  Model model;
  RunAnalysis run;
};

Analysed analyse(const std::string& yaml, const std::vector<std::string>& overrides = {},
                 AnalysisOptions o = {}, Observer* extra = nullptr) {
  Analysed a;
  a.model = load_model_text(yaml, "t.yaml", overrides).model;
  a.run = analyze_run(a.model, o, extra);
  return a;
}

const ChannelStatistics& stat(const RunAnalysis& r, const std::string& channel) {
  for (const auto& s : r.statistics)
    if (s.channel == channel) return s;
  throw std::runtime_error("no statistics for " + channel);
}

const std::vector<double>& values(const DecimatedSeries& s, const std::string& channel) {
  const int i = s.index(channel);
  if (i < 0) throw std::runtime_error("no channel " + channel);
  return s.values[i];
}

const ChannelComparison& comparison(const RunAnalysis& r, const std::string& channel) {
  for (const auto& c : r.ideal_twin.value().comparison)
    if (c.channel == channel) return c;
  throw std::runtime_error("no comparison for " + channel);
}

const std::string kSubharmonic(double w, double k) {
  return R"Y(
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
}
}  // namespace

TEST(RunAnalysis, IdealSliderCrankIsPeriodicWithOnePoincarePoint) {
  const Analysed a = analyse(read_file(example_path("flores_slider_crank_ideal.yaml")),
                             {"solver.end_time=0.12", "solver.output_interval=1e-4"});
  const RunAnalysis& r = a.run;
  ASSERT_TRUE(r.result.status.ok);
  EXPECT_EQ(r.period_driver, "crank");
  ASSERT_TRUE(r.poincare.has_value());
  const PoincareSections& p = *r.poincare;
  EXPECT_EQ(p.kind, "stroboscopic");
  EXPECT_TRUE(p.planes.empty());
  EXPECT_NEAR(p.period, 0.012, 1e-12);
  EXPECT_EQ(p.points.size(), 10u);  // sections at 0.012, 0.024, …, 0.12 (t = 0 is transient)
  ASSERT_EQ(p.times.size(), 10u);
  for (size_t k = 0; k < p.times.size(); ++k) EXPECT_NEAR(p.times[k], 0.012 * (k + 1), 1e-9);
  EXPECT_EQ(p.distinct, 1);
  // Ten sections are too few for a verdict (16 needed): the evidence says how long to run.
  EXPECT_EQ(r.verdict.kind, "undetermined");
  EXPECT_EQ(r.verdict.distinct_points, 1);
  EXPECT_EQ(r.verdict.sections, 10);
  EXPECT_NEAR(r.verdict.period, 0.012, 1e-12);
  EXPECT_EQ(r.verdict.evidence.back(),
            "not enough periods: 10 sections after the transient, 16 needed; run to end_time >= 0.192 s");
  EXPECT_EQ(r.verdict.rule, verdict_rule());
  // Run that long: 16 sections, one point, periodic.
  const Analysed longer = analyse(read_file(example_path("flores_slider_crank_ideal.yaml")),
                                  {"solver.end_time=0.192", "solver.output_interval=1e-4"});
  EXPECT_EQ(longer.run.verdict.sections, 16);
  EXPECT_EQ(longer.run.verdict.kind, "periodic");
  EXPECT_EQ(longer.run.verdict.evidence.back(), "period-1 orbit: every point recurs");
  // No clearance joint: no twin, no joint analysis.
  EXPECT_FALSE(r.ideal_twin.has_value());
  EXPECT_TRUE(r.clearance.empty());
  // The driver fixes every coordinate: there is no free direction, so no exponent.
  ASSERT_TRUE(r.lyapunov.has_value());
  EXPECT_FALSE(r.lyapunov->estimated);
  EXPECT_TRUE(std::isnan(r.lyapunov->exponent));
  EXPECT_TRUE(std::isnan(r.verdict.lyapunov_exponent));
  EXPECT_NE(r.lyapunov->message.find("no free degree of freedom"), std::string::npos) << r.lyapunov->message;
}

TEST(RunAnalysis, ALightlyDampedOscillatorSettlingToRestIsConverging) {
  // m = 2 kg, k = 200 N/m, c = 0.4 N·s/m: ω = 10 rad/s, ζω = 0.1 1/s. Seen every 0.5 s, λT =
  // −0.05, inside the quasi-periodic band, and the verdict was "quasi-periodic" while the
  // points closed in on rest; the shrinking returns (exp(−0.05 · 22) = 0.33 in exact
  // arithmetic) now make it converging.
  const std::string yaml = R"Y(
ground: {markers: {O: [0, 0]}}
bodies: {m: {mass: 2.0, position: [0.2, 0]}}
joints: {g: {type: translational, guide: ground.O, slider: m, axis: [1, 0]}}
loads: {s: {type: spring_damper, from: ground, to: m, stiffness: 200, damping: 0.4, free_length: 0.1}}
solver: {end_time: 20.0, output_interval: 0.01, rtol: 1e-10, atol: 1e-13, initial_state: given}
)Y";
  AnalysisOptions o;
  o.period = 0.5;
  const Analysed a = analyse(yaml, {}, o);
  const RunAnalysis& r = a.run;
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  EXPECT_NEAR(r.verdict.lyapunov_exponent, -0.1, 2e-3);
  EXPECT_EQ(r.verdict.kind, "periodic");
  bool converging = false;
  for (const auto& e : r.verdict.evidence)
    converging |= e.find("converging: lambda*T < 0 and the points' returns shrank to 0.") != std::string::npos;
  EXPECT_TRUE(converging) << r.verdict.evidence.back();
}

TEST(RunAnalysis, SubharmonicResponseGivesTwoPoincarePoints) {
  // A flywheel turning at ω sets the period T = 2π/ω; a mass on a spring tuned to ω/2 moves
  // x = x0 cos(ωt/2): sampled every T it alternates between +x0 and −x0: a period-2 orbit.
  const double w = 100.0, m = 1.0, k = m * (w / 2) * (w / 2);
  const std::string yaml = kSubharmonic(w, k);
  AnalysisOptions o;
  o.lyapunov = false;
  const Analysed a = analyse(yaml, {}, o);
  const RunAnalysis& r = a.run;
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  ASSERT_TRUE(r.poincare.has_value());
  EXPECT_GE(r.poincare->points.size(), 18u);
  EXPECT_EQ(r.poincare->distinct, 2);
  // No clearance joint: every body's x, y and lever, each named (the names said x, y only, of
  // the first body, beside points of 4 coordinates per body).
  EXPECT_EQ(r.poincare->coordinates.size(), r.poincare->points.front().size());
  EXPECT_EQ(r.poincare->coordinates[2].substr(r.poincare->coordinates[2].find('.')), ".lever_x");
  EXPECT_EQ(r.verdict.kind, "periodic");
  EXPECT_FALSE(r.lyapunov.has_value());  // not asked for

  // Event-based: the block's velocity falling through zero happens at its largest x, once per
  // oscillation (2T): the same state every time, one distinct point.
  o.section_planes = {"block.vx=0,down"};
  const Analysed e = analyse(yaml, {}, o);
  ASSERT_TRUE(e.run.poincare.has_value());
  const PoincareSections& pe = *e.run.poincare;
  EXPECT_EQ(pe.kind, "event");
  EXPECT_EQ(pe.planes, o.section_planes);
  const double t_osc = 4 * M_PI / w;  // 0.1257 s; sections after the 1-period transient
  EXPECT_NEAR(static_cast<double>(pe.points.size()), std::floor((1.3 - 2 * M_PI / w) / t_osc), 1.0);
  EXPECT_EQ(pe.distinct, 1);
  for (const auto& p : pe.points) EXPECT_NEAR(p[0], 0.0, 1e-9);  // wheel x
  // Each section is one period of the block's oscillation after the previous one.
  for (size_t i = 1; i < pe.times.size(); ++i) EXPECT_NEAR(pe.times[i] - pe.times[i - 1], t_osc, 1e-6);
  // Bad planes are reported.
  o.section_planes = {"block.speed=0"};
  EXPECT_THROW(analyse(yaml, {}, o), std::invalid_argument);
}

TEST(RunAnalysis, ContactModesCoverTheStatisticsWindow) {
  // A sweep's metrics start after its transient (AnalysisOptions::stats_t0): so do the contact
  // modes. They counted the start-up impacts too, which a sweep leaves out.
  const std::string yaml = read_file(example_path("flores_slider_crank.yaml"));
  const std::vector<std::string> run{"solver.end_time=0.048"};
  AnalysisOptions o;
  o.lyapunov = false;
  o.ideal_twin = false;
  const Model m = load_model_text(yaml, "t.yaml", run).model;
  Recorder events(m);
  const Analysed whole = analyse(yaml, run, o, &events);
  o.stats_t0 = 0.024;
  const Analysed late = analyse(yaml, run, o);
  int all = 0, after = 0;
  double vmax_after = 0;
  for (const auto& e : events.events)
    if (e.onset) {
      ++all;
      if (e.t >= 0.024) ++after, vmax_after = std::max(vmax_after, std::abs(e.velocity));
    }
  ASSERT_GT(all, after);
  ASSERT_GT(after, 3);
  EXPECT_EQ(whole.run.clearance[0].modes.impacts, all);
  const ModeSummary& m2 = late.run.clearance[0].modes;
  EXPECT_EQ(m2.impacts, after);
  double vmax = 0;
  for (double v : m2.impact_velocities) vmax = std::max(vmax, std::abs(v));
  EXPECT_DOUBLE_EQ(vmax, vmax_after);
  EXPECT_NEAR(m2.impact_share + m2.continuous_share + m2.free_flight_share, 1.0, 1e-12);
  double in_contact = 0;
  for (const auto& e : m2.episodes) {
    EXPECT_GE(e.start, 0.024);
    in_contact += e.end - e.start;
  }
  EXPECT_NEAR(m2.impact_share + m2.continuous_share, in_contact / 0.024, 1e-12);
}

TEST(RunAnalysis, APlaneSectionIsTakenOnlyWhereTheRunCrossesThePlane) {
  // The constant-speed crank passes crank.phi = 20 rad once, at t = 20/ω = 38.2 ms, while the
  // journal opens and closes its contact dozens of times. Every contact event after the crossing
  // used to be taken for a section too (the plane's function, positive since the crossing, was
  // the largest of the event functions), with both integrators.
  const double omega = 5000 * 2 * M_PI / 60;
  for (const char* integrator : {"dopri5", "bdf"}) {
    SCOPED_TRACE(integrator);
    AnalysisOptions o;
    o.lyapunov = false;
    o.section_planes = {"crank.phi=20"};
    const Analysed a = analyse(read_file(example_path("flores_slider_crank.yaml")),
                               {"solver.end_time=0.072", std::string("solver.integrator=") + integrator},
                               o);
    ASSERT_TRUE(a.run.result.status.ok) << a.run.result.status.message;
    ASSERT_TRUE(a.run.poincare);
    ASSERT_EQ(a.run.poincare->times.size(), 1u);
    EXPECT_NEAR(a.run.poincare->times[0], 20.0 / omega, 1e-9);
    EXPECT_GT(a.run.result.stats.events, 10);
  }
}

TEST(RunAnalysis, TheIdealTwinIsComparedOverTheStatisticsWindow) {
  // With --window, the peak ratio divided the window's peak by the ideal twin's whole-run peak
  // (slider.ax read 0.29 of the ideal in a window where it is 1.49 times it), and the deviations
  // were the whole run's. Both now come from the twin's rows in the window: the ideal peak is
  // the largest |value| of the ideal model's own rows there, run separately.
  AnalysisOptions o;
  o.lyapunov = false;
  o.stats_t0 = 0.0503, o.stats_t1 = 0.0507;
  const std::vector<std::string> set = {"solver.end_time=0.06", "solver.output_interval=2e-5"};
  const Analysed a = analyse(read_file(example_path("flores_slider_crank.yaml")), set, o);
  const SimRun ideal = run_example("flores_slider_crank_ideal.yaml", set);
  for (const char* channel : {"slider.ax", "crank_rod.F", "slider.x"}) {
    SCOPED_TRACE(channel);
    double peak = 0.0;
    for (size_t k = 0; k < ideal.rec->time.size(); ++k)
      if (ideal.rec->time[k] >= o.stats_t0 && ideal.rec->time[k] <= o.stats_t1)
        peak = std::max(peak, std::abs((*ideal.rec)[channel][k]));
    const ChannelComparison& cmp = comparison(a.run, channel);
    EXPECT_DOUBLE_EQ(cmp.ideal_peak, peak);
    EXPECT_DOUBLE_EQ(cmp.peak_ratio, stat(a.run, channel).peak / peak);
  }
  // The slider's position at the window: the same as the ideal one's within 1 %.
  EXPECT_NEAR(comparison(a.run, "slider.x").peak_ratio, 1.0, 0.01);
}

TEST(RunAnalysis, ASectionPlaneObservesTheRunWithoutChangingIt) {
  // The plane's crossings were located by the integrator as events and the integration restarted
  // at each: on the chaotic Flores example that made another trajectory (494 contact events
  // against 571 in 0.24 s). Located on the dense output instead, the run is the same step for
  // step, and each section lies on the plane.
  AnalysisOptions o;
  o.lyapunov = false;
  o.ideal_twin = false;
  const std::vector<std::string> set = {"solver.end_time=0.12", "solver.output_interval=2e-5"};
  const Analysed without = analyse(read_file(example_path("flores_slider_crank.yaml")), set, o);
  o.section_planes = {"slider.vx=0,down"};
  const Analysed with = analyse(read_file(example_path("flores_slider_crank.yaml")), set, o);
  ASSERT_TRUE(with.run.result.status.ok) << with.run.result.status.message;
  EXPECT_EQ(with.run.result.stats.steps, without.run.result.stats.steps);
  EXPECT_EQ(with.run.result.stats.events, without.run.result.stats.events);
  EXPECT_EQ(with.run.result.stats.rhs_evaluations, without.run.result.stats.rhs_evaluations);
  ASSERT_TRUE(with.run.poincare);
  EXPECT_GE(with.run.poincare->times.size(), 8u);  // one per period (12 ms), after the transient
  for (size_t i = 1; i < with.run.poincare->times.size(); ++i)
    EXPECT_NEAR(with.run.poincare->times[i] - with.run.poincare->times[i - 1], 0.012, 2e-4);
}

TEST(RunAnalysis, FloresExampleResultsAreCompleteAndConsistent) {
  const Analysed a = analyse(read_file(example_path("flores_slider_crank.yaml")));
  const RunAnalysis& r = a.run;
  ASSERT_TRUE(r.result.status.ok);
  // Channel names, units and descriptions are the model's, in column order.
  const std::vector<ChannelInfo> info = channel_info(a.model, Workspace(a.model));
  ASSERT_EQ(r.series.channels.size(), info.size());
  for (size_t i = 0; i < info.size(); ++i) {
    EXPECT_EQ(r.series.channels[i].name, info[i].name);
    EXPECT_EQ(r.series.channels[i].unit, info[i].unit);
    EXPECT_EQ(r.series.channels[i].description, info[i].description);
  }
  EXPECT_EQ(r.series.channels[r.series.index("slider.ax")].unit, "m/s²");
  EXPECT_EQ(r.series.index("slider.az"), -1);
  const size_t n = r.series.time.size();
  EXPECT_GT(n, 1000u);
  EXPECT_LE(n, 4002u);
  ASSERT_EQ(r.series.values.size(), info.size());
  EXPECT_EQ(values(r.series, "slider.ax").size(), n);
  ASSERT_TRUE(r.ideal_twin.has_value());
  EXPECT_TRUE(r.ideal_twin->result.status.ok);
  EXPECT_EQ(values(r.ideal_twin->series, "slider.ax").size(), n);
  EXPECT_EQ(r.ideal_twin->series.time, r.series.time);  // the same time base
  EXPECT_EQ(r.ideal_twin->series.index("rod_slider.Fn"), -1);  // the twin has no clearance joint
  EXPECT_EQ(r.crank_angle_deg.size(), n);
  for (double deg : r.crank_angle_deg) {
    EXPECT_GE(deg, 0.0);
    EXPECT_LT(deg, 360.0);
  }
  // The statistics' extrema are tracked between outputs: at least the decimated series' peak.
  double peak = 0;
  for (double v : values(r.series, "slider.ax")) peak = std::max(peak, std::abs(v));
  EXPECT_TRUE(stat(r, "slider.ax").exact);
  EXPECT_LE(peak, stat(r, "slider.ax").peak);
  // Clearance makes the slider acceleration peak larger than the ideal mechanism's 19.4 km/s².
  const ChannelComparison& cmp = comparison(r, "slider.ax");
  EXPECT_NEAR(cmp.ideal_peak, 19419, 30);
  EXPECT_GT(cmp.peak_ratio, 1.0);
  EXPECT_DOUBLE_EQ(cmp.peak_ratio, stat(r, "slider.ax").peak / cmp.ideal_peak);
  // A channel that is 0 in the ideal twin (it dissipates nothing) has no ratio.
  EXPECT_EQ(comparison(r, "energy.dissipated").ideal_peak, 0.0);
  EXPECT_GT(stat(r, "energy.dissipated").peak, 0.0);
  EXPECT_TRUE(std::isnan(comparison(r, "energy.dissipated").peak_ratio));
  EXPECT_GE(cmp.max_deviation, cmp.rms_deviation);
  // Modes: shares add up, impacts match the onsets, the histogram counts every impact.
  ASSERT_EQ(r.clearance.size(), 1u);
  const ClearanceJointAnalysis& cj = r.clearance[0];
  EXPECT_EQ(cj.joint, "rod_slider");
  EXPECT_DOUBLE_EQ(cj.clearance, 0.5e-3);
  const ModeSummary& m = cj.modes;
  EXPECT_NEAR(m.free_flight_share + m.impact_share + m.continuous_share, 1.0, 1e-12);
  EXPECT_EQ(m.impacts, static_cast<int>(m.impact_velocities.size()));
  int counted = 0;
  for (int c : cj.histogram.counts) counted += c;
  EXPECT_EQ(counted, m.impacts);
  EXPECT_EQ(cj.histogram.edges.size(), cj.histogram.counts.size() + 1);
  // Episodes follow each other inside the run; the continuous ones are the long ones.
  EXPECT_NEAR(cj.continuous_contact_time, 0.1 * r.period, 1e-15);
  double last_end = 0.0;
  for (const auto& e : m.episodes) {
    EXPECT_GE(e.start, last_end);
    EXPECT_GE(e.end, e.start);
    EXPECT_LE(e.end, 0.024 + 1e-12);
    EXPECT_EQ(e.continuous, e.end - e.start >= cj.continuous_contact_time);
    last_end = e.end;
  }
  // The orbit stays within the clearance circle plus the penetration.
  ASSERT_FALSE(cj.orbit.empty());
  for (const Vec2& e : cj.orbit) ASSERT_LT(e.norm(), 0.5e-3 + 1e-4);
  // The default spectra: the slider's acceleration first (the verdict's broadband share is the
  // first one's), then the contact force.
  ASSERT_EQ(r.spectra.size(), 2u);
  EXPECT_EQ(r.spectra[0].channel, "slider.ax");
  EXPECT_EQ(r.spectra[1].channel, "rod_slider.Fn");
  EXPECT_FALSE(r.verdict.kind.empty());
  EXPECT_FALSE(r.verdict.evidence.empty());
  // Frames: every body and clearance joint, one pose per frame time.
  ASSERT_EQ(r.frames.bodies.size(), a.model.bodies.size());
  EXPECT_EQ(r.frames.bodies[0], "crank");
  EXPECT_EQ(r.frames.pose[0].size(), r.frames.time.size());
  ASSERT_EQ(r.frames.clearance_joints, std::vector<std::string>{"rod_slider"});
  EXPECT_EQ(r.frames.eccentricity[0].size(), r.frames.time.size());
}

TEST(RunAnalysis, StatisticsOverACrankAngleRange) {
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
  AnalysisOptions o;
  o.lyapunov = false;
  o.stats_angle0 = 350;
  o.stats_angle1 = 10;
  const std::string yaml = read_file(example_path("flores_slider_crank_ideal.yaml"));
  const Analysed top = analyse(yaml, {"solver.output_interval=1e-6"}, o);
  EXPECT_NEAR(stat(top.run, "slider.ax").min, extreme(-10, 10, false), 1.0);
  EXPECT_NEAR(extreme(-10, 10, false), -19419, 1.0);
  EXPECT_EQ(stat(top.run, "slider.ax").angle0_deg, 350);
  EXPECT_EQ(stat(top.run, "slider.ax").angle1_deg, 10);
  o.stats_angle0 = 170;
  o.stats_angle1 = 190;
  const Analysed bottom = analyse(yaml, {"solver.output_interval=1e-6"}, o);
  const ChannelStatistics& st = stat(bottom.run, "slider.ax");
  EXPECT_NEAR(st.max, extreme(170, 190, true), 1.0);
  EXPECT_NEAR(st.min, extreme(170, 190, false), 1.0);
  // 20° of each 360° revolution of the 0.024 s run, sampled every µs: 2 × 20/360 × 0.012 s.
  EXPECT_NEAR(static_cast<double>(st.samples), 2 * 20.0 / 360 * 0.012 / 1e-6, 3);
  EXPECT_EQ(st.t0, 0.0);
  EXPECT_EQ(st.t1, 0.024);
  // An angle range needs a driver to measure the angle by.
  o.poincare_driver = "no_such_driver";
  EXPECT_THROW(analyse(yaml, {}, o), std::invalid_argument);
}

TEST(RunAnalysis, VariationalSpectrumIsTheDefaultAndMakesTheVerdict) {
  // Three revolutions of the Flores example (DOF 2: 4 exponents), two of them estimated.
  const std::string yaml = read_file(example_path("flores_slider_crank.yaml"));
  AnalysisOptions o;
  o.ideal_twin = false;
  const Analysed a = analyse(yaml, {"solver.end_time=0.036"}, o);
  const RunAnalysis& r = a.run;
  ASSERT_TRUE(r.lyapunov.has_value());
  const LyapunovEstimate& l = *r.lyapunov;
  ASSERT_TRUE(l.ok) << l.message;
  EXPECT_EQ(l.method, "variational");
  ASSERT_EQ(l.spectrum.size(), 4u);
  EXPECT_TRUE(std::is_sorted(l.spectrum.rbegin(), l.spectrum.rend()));
  EXPECT_EQ(l.exponent, l.spectrum[0]);
  EXPECT_EQ(r.verdict.lyapunov_exponent, l.exponent);
  EXPECT_EQ(l.renormalisations, l.intervals);
  ASSERT_EQ(l.spectrum_history.size(), l.history.size());
  EXPECT_EQ(l.spectrum_history.back(), l.spectrum);
  // Renormalised at the first step end on or after each T/20 (steps are ~1e-5 s here).
  EXPECT_GE(l.history.front().first, l.t0 + l.interval - 1e-12);
  EXPECT_LT(l.history.front().first, l.t0 + l.interval + 1e-4);
  // Contact events in these two revolutions, every one located and mapped.
  EXPECT_GT(l.events_mapped, 0);
  EXPECT_EQ(l.events_unmapped, 0);
}

TEST(RunAnalysis, LyapunovEstimateCarriesItsInputs) {
  // Three revolutions of the Flores example: one discarded, two of estimate, 20 renormalisations
  // each, from the first section after the transient (the two-trajectory method: its d0).
  const std::string yaml = read_file(example_path("flores_slider_crank.yaml"));
  AnalysisOptions o;
  o.ideal_twin = false;
  o.lyapunov_method = "two-trajectory";
  const Analysed a = analyse(yaml, {"solver.end_time=0.036"}, o);
  const RunAnalysis& r = a.run;
  ASSERT_TRUE(r.result.status.ok);
  ASSERT_TRUE(r.lyapunov.has_value());
  const LyapunovEstimate& l = *r.lyapunov;
  EXPECT_TRUE(l.estimated);
  ASSERT_TRUE(l.ok) << l.message;
  EXPECT_NEAR(l.t0, 0.012, 1e-12);
  EXPECT_NEAR(l.interval, 0.012 / 20, 1e-15);
  EXPECT_GE(l.intervals, 39);
  EXPECT_LE(l.intervals, 40);
  EXPECT_EQ(l.renormalisations, l.intervals);
  EXPECT_DOUBLE_EQ(l.d0, 1e-7);  // min(1e-7, 2e-4 × 0.5 mm)
  ASSERT_EQ(l.history.size(), static_cast<size_t>(l.renormalisations));
  EXPECT_NEAR(l.history.front().first, l.t0 + l.interval, 1e-12);
  EXPECT_NEAR(l.history.back().first, l.t0 + l.intervals * l.interval, 1e-12);
  EXPECT_NEAR(l.history.back().second, l.exponent, 1e-9 * std::abs(l.exponent));
  EXPECT_EQ(r.verdict.lyapunov_exponent, l.exponent);
  // Clearance-joint impacts make the two trajectories diverge (docs/analysis.md): λT > 0.1.
  EXPECT_GT(l.exponent * r.period, 0.1);
  // Two sections after the transient: the exponent alone does not make a verdict.
  EXPECT_EQ(r.verdict.kind, "undetermined");
  EXPECT_NE(r.verdict.evidence.back().find("not enough periods"), std::string::npos);
  // The separation can be set.
  o.lyapunov_d0 = 1e-8;
  const Analysed b = analyse(yaml, {"solver.end_time=0.036"}, o);
  ASSERT_TRUE(b.run.lyapunov.has_value());
  EXPECT_EQ(b.run.lyapunov->d0, 1e-8);
  // Too short a run after the transient (less than one period): no estimate, and why.
  const Analysed c = analyse(yaml, {"solver.end_time=0.018"}, o);
  ASSERT_TRUE(c.run.lyapunov.has_value());
  EXPECT_FALSE(c.run.lyapunov->estimated);
  EXPECT_NE(c.run.lyapunov->message.find("at least one period (0.012 s) needed"), std::string::npos)
      << c.run.lyapunov->message;
  EXPECT_TRUE(std::isnan(c.run.verdict.lyapunov_exponent));
}

TEST(RunAnalysis, ExtraObserverSeesTheMainRun) {
  const std::string yaml = read_file(example_path("flores_slider_crank.yaml"));
  const Model model = load_model_text(yaml, "t.yaml", {"solver.end_time=0.012"}).model;
  Recorder rec(model);
  AnalysisOptions o;
  o.lyapunov = false;
  const RunAnalysis r = analyze_run(model, o, &rec);
  ASSERT_TRUE(r.result.status.ok);
  // Every output and every contact event of the main run (not of the ideal twin).
  EXPECT_EQ(static_cast<long>(rec.time.size()), r.result.outputs);
  EXPECT_EQ(static_cast<long>(rec.events.size()), r.result.stats.events);
  // The contact modes are built from the same events: one impact per onset, with its velocity.
  std::vector<double> onset_velocities;
  for (const auto& e : rec.events)
    if (e.onset) onset_velocities.push_back(e.velocity);
  EXPECT_EQ(r.clearance[0].modes.impact_velocities, onset_velocities);
  // Min/max decimation keeps the impact spikes: the decimated peak is the largest output sample;
  // the statistics' peak, tracked between outputs, is at least that.
  double peak = 0, decimated = 0;
  for (double v : rec["slider.ax"]) peak = std::max(peak, std::abs(v));
  for (double v : values(r.series, "slider.ax")) decimated = std::max(decimated, std::abs(v));
  EXPECT_EQ(decimated, peak);
  EXPECT_GE(stat(r, "slider.ax").peak, peak);
  // An option naming what does not exist fails before anything runs.
  Recorder none(model);
  o.fft_channels = {"slider.az"};
  EXPECT_THROW(analyze_run(model, o, &none), std::invalid_argument);
  o.fft_channels.clear();
  o.phase = {{"rod_slider.ex", "rod_slider.nope"}};
  EXPECT_THROW(analyze_run(model, o, &none), std::invalid_argument);
  o.phase.clear();
  o.poincare_driver = "rod_slider";
  EXPECT_THROW(analyze_run(model, o, &none), std::invalid_argument);
  EXPECT_TRUE(none.time.empty());
}

TEST(RunAnalysis, PeriodDriverAndIdealModel) {
  const Model model =
      load_model_text(read_file(example_path("flores_slider_crank.yaml")), "t.yaml", {}).model;
  const Driver* d = period_driver(model, "");
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(d->name, "crank");
  EXPECT_EQ(period_driver(model, "crank"), d);
  EXPECT_EQ(period_driver(model, "nope"), nullptr);
  const Model ideal = ideal_model(model);
  EXPECT_EQ(model.clearance_joint_count(), 1);
  EXPECT_EQ(ideal.clearance_joint_count(), 0);
  EXPECT_EQ(ideal.joints.size(), model.joints.size());
  // Without a rotary driver there is no period: no stroboscopic section.
  const Model free_model = load_model_text(R"Y(
bodies:
  block: {mass: 1.0, inertia: 0.01, position: [0.01, 0]}
ground: {markers: {O: [0, 0]}}
joints:
  rail: {type: translational, guide: ground.O, slider: block, axis: [1, 0]}
loads:
  spring: {type: spring_damper, from: ground.O, to: block, stiffness: 100, free_length: 0}
gravity: [0, 0]
solver: {end_time: 0.5, output_interval: 1e-3, initial_state: given}
)Y", "t.yaml", {}).model;
  EXPECT_EQ(period_driver(free_model, ""), nullptr);
  const RunAnalysis r = analyze_run(free_model, AnalysisOptions{});
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  EXPECT_EQ(r.period, 0.0);
  EXPECT_TRUE(r.period_driver.empty());
  EXPECT_TRUE(r.crank_angle_deg.empty());
  EXPECT_FALSE(r.poincare.has_value());
  ASSERT_TRUE(r.lyapunov.has_value());  // not estimated, said why
  EXPECT_FALSE(r.lyapunov->estimated);
  EXPECT_NE(r.lyapunov->message.find("no period"), std::string::npos) << r.lyapunov->message;
  EXPECT_EQ(r.verdict.sections, 0);
}

TEST(RunAnalysis, SectionsForEveryClearanceJoint) {
  // Flores slider-crank with clearance at crank–rod and rod–slider: each joint gets its own
  // section points (its eccentricity at every section) and distinct count; the first two
  // coordinates of the combined points stay the first joint's.
  AnalysisOptions o;
  o.lyapunov = false;
  o.ideal_twin = false;
  const Analysed a = analyse(read_file(example_path("flores_slider_crank.yaml")),
                             {"joints.crank_rod.clearance=0.5e-3", "solver.end_time=0.06",
                              "solver.output_interval=1e-4"},
                             o);
  ASSERT_TRUE(a.run.result.status.ok) << a.run.result.status.message;
  ASSERT_TRUE(a.run.poincare.has_value());
  const PoincareSections& p = *a.run.poincare;
  ASSERT_EQ(p.joints.size(), 2u);
  EXPECT_EQ(p.joints[0].joint, "crank_rod");
  EXPECT_EQ(p.joints[1].joint, "rod_slider");
  EXPECT_EQ(p.joints[1].variables, (std::vector<std::string>{"rod_slider.ex", "rod_slider.ey"}));
  ASSERT_GE(p.times.size(), 4u);  // sections from T on, after one discarded period
  for (size_t c = 0; c < 2; ++c) {
    const JointSections& js = p.joints[c];
    ASSERT_EQ(js.points.size(), p.times.size());
    EXPECT_GE(js.distinct, 1);
    EXPECT_LE(js.distinct, static_cast<int>(js.points.size()));
    EXPECT_DOUBLE_EQ(js.tolerance, 0.01 * 0.5e-3);
    for (size_t k = 0; k < js.points.size(); ++k) {
      EXPECT_EQ(js.points[k].x(), p.points[k][2 * c]);
      EXPECT_EQ(js.points[k].y(), p.points[k][2 * c + 1]);
      // An eccentricity: the clearance plus a penetration (tens of µm at 5000 rpm) at most.
      EXPECT_LT(js.points[k].norm(), 0.5e-3 * 1.2);
    }
  }
}

TEST(RunAnalysis, ExpressionDriverGetsAPeriodFromItsMeanSpeedOrFromTheUser) {
  // The subharmonic model with a start-up ramp: speed 20·min(t/0.2, 1) rad/s. Over the run's
  // last half the speed is 20 rad/s, so the period is 2π/20 s; --period overrides it.
  std::string yaml = kSubharmonic(20.0, 100.0);
  const std::string from = "speed: 20.000000", to = "speed: \"20*min(time/0.2, 1)\"";
  ASSERT_NE(yaml.find(from), std::string::npos);
  yaml.replace(yaml.find(from), from.size(), to);
  AnalysisOptions o;
  o.lyapunov = false;
  o.ideal_twin = false;
  const Analysed a = analyse(yaml, {}, o);
  ASSERT_TRUE(a.run.result.status.ok) << a.run.result.status.message;
  EXPECT_EQ(a.run.period_driver, "motor");
  EXPECT_NEAR(a.run.period, 2 * M_PI / 20.0, 1e-9);
  EXPECT_NE(a.run.period_source.find("mean speed of driver 'motor'"), std::string::npos)
      << a.run.period_source;
  ASSERT_TRUE(a.run.poincare.has_value());
  EXPECT_EQ(a.run.poincare->times.size(), 4u);  // T, 2T, 3T, 4T ≤ 1.3 s (before T discarded)
  // The crank angle follows the ramp: ∫ 100 τ dτ = 50 t² rad before t = 0.2 s, then 20 rad/s.
  ASSERT_FALSE(a.run.crank_angle_deg.empty());
  for (size_t k = 0; k < a.run.series.time.size(); ++k) {
    const double t = a.run.series.time[k];
    const double rad = t < 0.2 ? 50 * t * t : 2.0 + 20 * (t - 0.2);
    double deg = std::fmod(rad * 180 / M_PI, 360.0);
    const double diff = std::abs(deg - a.run.crank_angle_deg[k]);
    EXPECT_LT(std::min(diff, 360 - diff), 1e-3) << "t = " << t;
  }
  o.period = 0.25;
  const Analysed b = analyse(yaml, {}, o);
  EXPECT_DOUBLE_EQ(b.run.period, 0.25);
  EXPECT_EQ(b.run.period_source, "--period 0.25 s");
  ASSERT_TRUE(b.run.poincare.has_value());
  EXPECT_EQ(b.run.poincare->times.size(), 5u);  // 0.25 … 1.25 s after one discarded period
}

TEST(RunAnalysis, RedundantLinkageCountsItsDegreesOfFreedomAndHasItsExponents) {
  // A free double parallelogram of three cranks has nq − m = 12 − 12 = 0 but one degree of
  // freedom (one equation is redundant). It was said to have "no free degree of freedom"; the
  // same linkage driven has nq − m = −1 and the variational method failed on an empty basis.
  // Now the count is nq less the rows the solver keeps: the redundant linkage has the
  // exponents of its non-redundant twin (two cranks, the first doubled: the same motion).
  AnalysisOptions o;
  o.period = 1.0;
  o.discard_periods = 1;
  const Analysed three = analyse(parallelogram_yaml(3, 1.0), {"solver.end_time=3"}, o);
  const Analysed two = analyse(parallelogram_yaml(2, 2.0), {"solver.end_time=3"}, o);
  // Turned 60° and posed with its cranks along the world's x axis: every row was kept there
  // (the rows dropped at the assembled and a nearby configuration differed), so it counted no
  // free degree of freedom.
  const Analysed on_axis =
      analyse(parallelogram_yaml(3, 1.0, -M_PI / 3, M_PI / 3), {"solver.end_time=3"}, o);
  for (const Analysed* a : {&three, &two, &on_axis}) {
    ASSERT_TRUE(a->run.result.status.ok) << a->run.result.status.message;
    ASSERT_TRUE(a->run.lyapunov.has_value());
    ASSERT_TRUE(a->run.lyapunov->estimated) << a->run.lyapunov->message;
    ASSERT_EQ(a->run.lyapunov->spectrum.size(), 2u);  // one position and one velocity direction
  }
  // The linkages agree to 5 % (measured 1.5 % over these two periods: finite-time estimates
  // of a weak exponent, each carrying its tangent equations' differencing noise), and a
  // conservative system's two exponents are nearly opposite.
  const double l3 = three.run.lyapunov->exponent, l2 = two.run.lyapunov->exponent;
  EXPECT_GT(l3, 0.0);
  EXPECT_NEAR(l3, l2, 0.05 * std::abs(l2));
  EXPECT_NEAR(three.run.lyapunov->spectrum[1], two.run.lyapunov->spectrum[1], 0.05 * std::abs(l2));
  EXPECT_LT(three.run.lyapunov->spectrum[1], 0.0);
  EXPECT_NEAR(three.run.lyapunov->spectrum[1], -l3, 0.05 * l3);

  // Driven by its first pivot: no free direction left, said so.
  const Analysed driven = analyse(parallelogram_yaml(3, 1.0) +
                                      "drivers:\n  motor: {joint: pivot_0, speed: 6.283185307179586}\n",
                                  {"solver.end_time=3"}, o);
  ASSERT_TRUE(driven.run.result.status.ok) << driven.run.result.status.message;
  ASSERT_TRUE(driven.run.lyapunov.has_value());
  EXPECT_FALSE(driven.run.lyapunov->estimated);
  EXPECT_NE(driven.run.lyapunov->message.find("no free degree of freedom"), std::string::npos)
      << driven.run.lyapunov->message;
}
