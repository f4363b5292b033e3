// Exact extrema (core/extrema.hpp): peaks tracked between outputs on the dense output agree with
// closed forms the outputs miss, and do not depend on the output interval.
#include <algorithm>
#include <cmath>
#include <map>

#include "core/extrema.hpp"
#include "test_support.hpp"

using namespace lash;
using namespace lash::test;

namespace {

/// The summary peaks as ResultsWriter finds them, beside the extrema of the output samples only.
class PeakObserver : public Observer {
 public:
  explicit PeakObserver(const Model& m) : model_(m), tracked(m), sampled(m) {
    values_.resize(channel_info(m, Workspace(m)).size());
    for (const auto& c : channel_info(m, Workspace(m))) names_.push_back(c.name);
  }
  void output(double t, const Eigen::VectorXd& y, const Workspace& ws) override {
    channel_values(model_, ws, y, values_.data());
    tracked.sample(t, values_.data());
    sampled.sample(t, values_.data());
  }
  void event(const ContactEvent&, const Workspace&) override { tracked.restart(); }
  bool wants_steps() const override { return true; }
  void step(double t0, double t1, const Eigen::VectorXd& y, const Workspace& ws,
            StepProbe& probe) override {
    tracked.step(t0, t1, y, ws, probe);
  }
  int index(const std::string& name) const {
    for (size_t i = 0; i < names_.size(); ++i)
      if (names_[i] == name) return static_cast<int>(i);
    throw std::runtime_error("no channel " + name);
  }
  const Model& model_;
  ChannelExtrema tracked, sampled;

 private:
  std::vector<double> values_;
  std::vector<std::string> names_;
};

struct PeakRun {
  Model model;
  RunResult result;
  std::unique_ptr<PeakObserver> obs;
  const ChannelExtremum& tracked(const std::string& c) const {
    return obs->tracked.extrema()[obs->index(c)];
  }
  const ChannelExtremum& sampled(const std::string& c) const {
    return obs->sampled.extrema()[obs->index(c)];
  }
};

PeakRun run_peaks_text(const std::string& text, const std::string& name,
                       const std::vector<std::string>& overrides) {
  PeakRun r;
  r.model = load_model_text(text, name, overrides).model;
  Workspace ws(r.model);
  r.obs = std::make_unique<PeakObserver>(r.model);
  r.result = simulate(r.model, ws, *r.obs);
  return r;
}

PeakRun run_peaks(const std::string& example, const std::vector<std::string>& overrides) {
  return run_peaks_text(read_file(example_path(example)), example, overrides);
}

// Ideal slider-crank (Flores example: crank r = 0.05 m, rod l = 0.12 m, 5000 rpm, θ = ωt):
// x = r cos θ + λ with λ = √(l² − r² sin² θ), so
// ẍ = ω² x''(θ),  x''(θ) = −r cos θ − r² cos 2θ / λ − r⁴ sin² θ cos² θ / λ³.
// At top dead centre (θ = 0) ẍ = −rω²(1 + r/l) = −19 419 m/s². With r/l = 0.42 > 1/4 bottom dead
// centre (ẍ = rω²(1 − r/l) = +7 996 m/s²) is a local minimum between two maxima of ẍ, at
// θ* and 2π − θ*, found here by golden-section search on the formula.
constexpr double kCrank = 0.05, kRod = 0.12;
const double kOmega = 5000.0 * 2.0 * M_PI / 60.0;

double slider_acceleration(double theta) {
  const double r = kCrank, s = std::sin(theta), c = std::cos(theta);
  const double lam = std::sqrt(kRod * kRod - r * r * s * s);
  return kOmega * kOmega *
         (-r * c - r * r * std::cos(2 * theta) / lam - r * r * r * r * s * s * c * c / (lam * lam * lam));
}

/// θ* in (π/2, π) where ẍ is largest (golden section to 1e-12 rad).
double theta_of_max_acceleration() {
  double a = M_PI / 2, b = M_PI;
  const double g = 0.6180339887498949;
  while (b - a > 1e-12) {
    const double c = b - g * (b - a), d = a + g * (b - a);
    if (slider_acceleration(c) > slider_acceleration(d)) b = d; else a = c;
  }
  return 0.5 * (a + b);
}

/// A 2 kg slider on a frictionless guide, 800 N/m spring, pulled 10 mm: x = 0.1 + 0.01 cos 20t,
/// vx = −0.2 sin 20t, ax = −4 cos 20t. The output interval is the whole run: only t = 0 and
/// end_time are output.
const char* const kSpringYaml = R"Y(
bodies:
  block: {mass: 2.0, inertia: 0.01, position: [0.11, 0]}
ground:
  markers: {A: [0, 0]}
joints:
  guide: {type: translational, guide: ground.A, slider: block, axis: [1, 0]}
loads:
  spring: {type: spring_damper, from: ground.A, to: block, stiffness: 800, free_length: 0.1}
solver: {rtol: 1e-9, atol: 1e-12, end_time: 0.3, output_interval: 0.3, initial_state: given}
)Y";

}  // namespace

TEST(Extrema, IdealSliderCrankPeaksMatchTheClosedFormBetweenOutputs) {
  const double a_tdc = -kCrank * kOmega * kOmega * (1.0 + kCrank / kRod);
  ASSERT_NEAR(a_tdc, -19419.0, 1.0);
  ASSERT_NEAR(slider_acceleration(0.0), a_tdc, 1e-9 * -a_tdc);
  ASSERT_NEAR(slider_acceleration(M_PI), kCrank * kOmega * kOmega * (1.0 - kCrank / kRod), 1e-6);
  const double theta_max = theta_of_max_acceleration();
  const double a_max = slider_acceleration(theta_max);
  for (const char* integrator : {"dopri5", "bdf"}) {
    SCOPED_TRACE(integrator);
    // Outputs every 0.7 ms, which fall on neither maximum (t = θ*/ω, (2π − θ*)/ω) nor on the
    // second top dead centre (t = T = 12.0 ms); the first, t = 0, is an output.
    const PeakRun r = run_peaks("flores_slider_crank_ideal.yaml",
                                {"solver.integrator=" + std::string(integrator),
                                 "solver.end_time=0.0126", "solver.output_interval=7e-4",
                                 "solver.rtol=1e-9", "solver.atol=1e-12"});
    ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
    const ChannelExtremum& tr = r.tracked("slider.ax");
    const ChannelExtremum& sa = r.sampled("slider.ax");
    // Tracked: the closed form to 1e-5 relative, at one of the two maxima to 1 µs (0.03° of crank).
    EXPECT_NEAR(tr.max, a_max, 1e-5 * a_max);
    const double t1 = theta_max / kOmega, t2 = (2 * M_PI - theta_max) / kOmega;
    EXPECT_LT(std::min(std::abs(tr.t_max - t1), std::abs(tr.t_max - t2)), 1e-6)
        << "t_max " << tr.t_max << " s, maxima at " << t1 << " and " << t2 << " s";
    EXPECT_NEAR(tr.min, a_tdc, 1e-5 * -a_tdc);
    // The output samples alone miss the maximum by more than 0.1 %, 100 times the tolerance.
    EXPECT_LT(sa.max, a_max * (1 - 1e-3));
    EXPECT_LT(sa.max, tr.max);
  }
}

TEST(Extrema, PeaksDoNotDependOnTheOutputInterval) {
  // Flores clearance joint, one crank revolution, outputs every 1 ms and every 10 µs: the
  // tracked peaks of the slider acceleration and the contact force agree within 0.1 %, while
  // the output samples alone differ by far more.
  auto run = [](const char* dt) {
    return run_peaks("flores_slider_crank.yaml",
                     {"solver.end_time=0.012", std::string("solver.output_interval=") + dt});
  };
  const PeakRun coarse = run("1e-3"), fine = run("1e-5");
  ASSERT_TRUE(coarse.result.status.ok) << coarse.result.status.message;
  ASSERT_TRUE(fine.result.status.ok) << fine.result.status.message;
  for (const char* c : {"slider.ax", "rod_slider.Fn"}) {
    SCOPED_TRACE(c);
    const ChannelExtremum &a = coarse.tracked(c), &b = fine.tracked(c);
    const double peak_a = std::max(std::abs(a.min), std::abs(a.max));
    const double peak_b = std::max(std::abs(b.min), std::abs(b.max));
    EXPECT_NEAR(peak_a, peak_b, 1e-3 * peak_b);
    EXPECT_NEAR(a.max, b.max, 1e-3 * peak_b);
    EXPECT_NEAR(a.t_max, b.t_max, 1e-6);
    // Without the tracking the coarse outputs miss the peak by more than 10 %.
    const ChannelExtremum& s = coarse.sampled(c);
    EXPECT_LT(std::max(std::abs(s.min), std::abs(s.max)), 0.9 * peak_b);
  }
}

TEST(Extrema, RefinementLocatesTurningPointsInsideSteps) {
  // A 2 kg slider on a frictionless guide, 800 N/m spring, pulled 10 mm: x = 0.1 + 0.01 cos 20t,
  // vx = −0.2 sin 20t (min −0.2 at 20t = π/2, max +0.2 at 3π/2), ax = −4 cos 20t (max +4 at
  // 20t = π). The output interval is the whole run: only t = 0 and end_time are output.
  PeakRun r;
  r.model = load_model_text(kSpringYaml, "spring.yaml", {}).model;
  Workspace ws(r.model);
  r.obs = std::make_unique<PeakObserver>(r.model);
  r.result = simulate(r.model, ws, *r.obs);
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const ChannelExtremum& v = r.tracked("block.vx");
  EXPECT_NEAR(v.min, -0.2, 1e-7);
  EXPECT_NEAR(v.t_min, M_PI / 40, 1e-5);
  EXPECT_NEAR(v.max, 0.2, 1e-7);
  EXPECT_NEAR(v.t_max, 3 * M_PI / 40, 1e-5);
  const ChannelExtremum& a = r.tracked("block.ax");
  EXPECT_NEAR(a.max, 4.0, 1e-6);
  EXPECT_NEAR(a.t_max, M_PI / 20, 1e-5);
  EXPECT_GT(r.obs->tracked.refinements(), 0);
  // The two outputs alone see none of it.
  EXPECT_LT(r.sampled("block.vx").max, 0.2 * 0.9);
}

TEST(Extrema, AWindowCountsItsEndsAndRefinesInsideItOnly) {
  // The spring-mass of the test above, extrema over t ∈ [0.05, 0.12] only (20t ∈ [1, 2.4]):
  // vx = −0.2 sin 20t has its minimum −0.2 inside (t = π/40) and its largest value at the
  // window's end, −0.2 sin 2.4; ax = −4 cos 20t rises through the window: −4 cos 1 at its start,
  // −4 cos 2.4 at its end. No output falls in the window (outputs at 0 and 0.3 s only).
  PeakRun r;
  r.model = load_model_text(kSpringYaml, "spring.yaml", {}).model;
  Workspace ws(r.model);
  r.obs = std::make_unique<PeakObserver>(r.model);
  r.obs->tracked.set_window(0.05, 0.12);
  r.result = simulate(r.model, ws, *r.obs);
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const ChannelExtremum& v = r.tracked("block.vx");
  EXPECT_NEAR(v.min, -0.2, 1e-7);
  EXPECT_NEAR(v.t_min, M_PI / 40, 1e-5);
  EXPECT_NEAR(v.max, -0.2 * std::sin(2.4), 1e-7);
  EXPECT_NEAR(v.t_max, 0.12, 1e-12);
  const ChannelExtremum& a = r.tracked("block.ax");
  EXPECT_NEAR(a.min, -4.0 * std::cos(1.0), 1e-6);
  EXPECT_NEAR(a.t_min, 0.05, 1e-12);
  EXPECT_NEAR(a.max, -4.0 * std::cos(2.4), 1e-6);
  EXPECT_NEAR(a.t_max, 0.12, 1e-12);
  // Over the whole run the same channel reaches +4 (t = π/20): outside the window, not counted.
  EXPECT_LT(a.max, 3.0);
}

TEST(Extrema, NothingPastTheEndTimeCounts) {
  // The integrator's last step passes end_time and the last output is interpolated back to it;
  // the state at that step's end is not part of the run. Over exactly one crank turn the crank
  // angle (driven, rising) peaks at 2π at end_time, and the dissipated energy (never falling)
  // peaks at the last output's value. Before the fix both were taken 2 µs past the end.
  for (const char* integrator : {"dopri5", "bdf"}) {
    SCOPED_TRACE(integrator);
    const PeakRun r = run_peaks("flores_slider_crank.yaml",
                                {"solver.end_time=0.012", "solver.output_interval=1e-4",
                                 std::string("solver.integrator=") + integrator});
    ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
    for (const auto& e : r.obs->tracked.extrema()) {
      EXPECT_LE(e.t_max, 0.012);
      EXPECT_LE(e.t_min, 0.012);
    }
    const ChannelExtremum& phi = r.tracked("crank.phi");
    EXPECT_NEAR(phi.max, 2 * M_PI, 1e-9);
    EXPECT_EQ(phi.t_max, 0.012);
    const ChannelExtremum& dissipated = r.tracked("energy.dissipated");
    EXPECT_EQ(dissipated.max, r.sampled("energy.dissipated").max);
    EXPECT_EQ(dissipated.t_max, 0.012);
  }
}

TEST(Extrema, TurningPointsBelowTheIntegratorsResolutionAreNotSearched) {
  // The Flores example over one revolution, tracked twice in one run: as the results writer
  // does (a turning point is searched only where it rises above the step's ends by more than
  // rtol times the channel's magnitude, and the channel is not zero to rtol of its unit's
  // largest) and searching every turning point that may beat the extremum so far. They agree
  // within the integrator's resolution, rtol times each channel's magnitude, at a fraction of
  // the searches: the rest were spent on channels that are zero in exact arithmetic (the driven
  // crank's angular acceleration, the constraint violation) or on the energy balance's drift.
  class Both : public Observer {
   public:
    explicit Both(const Model& m) : model(m), tracked(m), every(m) {
      every.set_resolution(0.0);
      values.resize(channel_info(m, Workspace(m)).size());
    }
    void output(double t, const Eigen::VectorXd& y, const Workspace& ws) override {
      channel_values(model, ws, y, values.data());
      tracked.sample(t, values.data());
      every.sample(t, values.data());
    }
    void event(const ContactEvent&, const Workspace&) override {
      tracked.restart();
      every.restart();
    }
    bool wants_steps() const override { return true; }
    void step(double t0, double t1, const Eigen::VectorXd& y, const Workspace& ws,
              StepProbe& probe) override {
      tracked.step(t0, t1, y, ws, probe);
      ASSERT_TRUE(probe.at_end());
      every.step(t0, t1, probe.state(), probe.workspace(), probe);
    }
    const Model& model;
    ChannelExtrema tracked, every;
    std::vector<double> values;
  };
  const Model m = load_model_text(read_file(example_path("flores_slider_crank.yaml")),
                                  "flores_slider_crank.yaml", {"solver.end_time=0.012"})
                      .model;
  Workspace ws(m);
  Both both(m);
  const RunResult r = simulate(m, ws, both);
  ASSERT_TRUE(r.status.ok) << r.status.message;
  const double rtol = m.solver.rtol;
  const auto info = channel_info(m, Workspace(m));
  std::map<std::string, double> unit_scale;
  for (size_t i = 0; i < info.size(); ++i) {
    const ChannelExtremum& e = both.every.extrema()[i];
    unit_scale[info[i].unit] =
        std::max({unit_scale[info[i].unit], std::abs(e.min), std::abs(e.max)});
  }
  int zero_channels = 0;
  for (size_t i = 0; i < info.size(); ++i) {
    SCOPED_TRACE(info[i].name);
    const ChannelExtremum &a = both.tracked.extrema()[i], &b = both.every.extrema()[i];
    const double own = std::max(std::abs(b.min), std::abs(b.max));
    if (own <= 2 * rtol * unit_scale[info[i].unit]) {  // zero to the resolution of its unit
      ++zero_channels;
      EXPECT_LE(std::max(std::abs(a.min), std::abs(a.max)), own);
      continue;
    }
    // Never beyond what the full search found (the same samples and fewer searches), and short
    // of it by at most the resolution (twice: the Hermite estimate's own error).
    EXPECT_LE(a.max, b.max);
    EXPECT_GE(a.min, b.min);
    EXPECT_LE(b.max - a.max, 2 * rtol * own);
    EXPECT_LE(a.min - b.min, 2 * rtol * own);
  }
  EXPECT_GE(zero_channels, 5);  // crank.alpha, slider.y, slider.vy, constraint.violation, ...
  EXPECT_LT(2 * both.tracked.refinements(), both.every.refinements())  // 197 against 806
      << both.tracked.refinements() << " searches against " << both.every.refinements();
  // A physical peak is still searched inside its step: the slider's acceleration maximum is not
  // a sample's.
  EXPECT_GT(both.tracked.refinements(), 0);
}

TEST(Extrema, TrackingAFewChannelsFindsTheirExtremaAsTrackingAll) {
  // A sweep tracks the channels whose metrics it keeps (rod_slider.Fn by default): their
  // extrema are the ones tracking every channel finds (up to what other channels' searches
  // sampled on the way, within the resolution), at fewer searches; the others stay unseen.
  class Both : public Observer {
   public:
    Both(const Model& m, std::vector<int> few) : model(m), all(m), some(m, std::move(few)) {
      values.resize(channel_info(m).size());
    }
    void output(double t, const Eigen::VectorXd& y, const Workspace& ws) override {
      channel_values(model, ws, y, values.data());
      all.sample(t, values.data());
      some.sample(t, values.data());
    }
    void event(const ContactEvent&, const Workspace&) override {
      all.restart();
      some.restart();
    }
    bool wants_steps() const override { return true; }
    void step(double t0, double t1, const Eigen::VectorXd& y, const Workspace& ws,
              StepProbe& probe) override {
      all.step(t0, t1, y, ws, probe);
      ASSERT_TRUE(probe.at_end());
      some.step(t0, t1, probe.state(), probe.workspace(), probe);
    }
    const Model& model;
    ChannelExtrema all, some;
    std::vector<double> values;
  };
  const Model m = load_model_text(read_file(example_path("flores_slider_crank.yaml")),
                                  "flores_slider_crank.yaml", {"solver.end_time=0.012"})
                      .model;
  const auto info = channel_info(m);
  auto index = [&](const std::string& name) {
    for (size_t i = 0; i < info.size(); ++i)
      if (info[i].name == name) return static_cast<int>(i);
    throw std::runtime_error("no channel " + name);
  };
  const std::vector<int> few = {index("rod_slider.Fn"), index("slider.ax")};
  Workspace ws(m);
  Both both(m, few);
  ASSERT_TRUE(simulate(m, ws, both).status.ok);
  for (size_t i = 0; i < info.size(); ++i) {
    SCOPED_TRACE(info[i].name);
    const ChannelExtremum &a = both.some.extrema()[i], &b = both.all.extrema()[i];
    if (std::find(few.begin(), few.end(), static_cast<int>(i)) == few.end()) {
      EXPECT_FALSE(a.seen);
      continue;
    }
    ASSERT_TRUE(a.seen);
    const double own = std::max(std::abs(b.min), std::abs(b.max));
    EXPECT_LE(a.max, b.max);
    EXPECT_GE(a.min, b.min);
    EXPECT_LE(b.max - a.max, 2 * m.solver.rtol * own);
    EXPECT_LE(a.min - b.min, 2 * m.solver.rtol * own);
  }
  EXPECT_GT(both.some.refinements(), 0);
  EXPECT_LT(2 * both.some.refinements(), both.all.refinements())
      << both.some.refinements() << " searches against " << both.all.refinements();
  EXPECT_THROW(ChannelExtrema(m, {static_cast<int>(info.size())}), std::invalid_argument);
}

TEST(Extrema, ReactionsPeakWhereTheHandCalculationSaysThroughInLinePositions) {
  // Parallelograms of unit cranks (1 kg, 1/12 kg m² about the centre, so 1/3 about the pivot)
  // under a translating 2 kg coupler, released at rest at θ0 = 45°: they swing through their
  // in-line position (a singular position) to the bottom θ = −90°, and on. Energy:
  // (n/6 + 1)ω² = (n/2 + 2) g (sin θ0 − sin θ); at the bottom α = 0, and the pivots carry the
  // weight and the centripetal forces, (n + 2) g + (n/2 + 2) ω², in equal shares (n = 3: one
  // equation is redundant and the smallest multipliers are reported). Within 1e-3 rad of the
  // in-line position the solve amplifies Baumgarte's terms along the nearly self-equilibrated
  // multipliers there: the exact peaks were 220 N (n = 2) and 10 355 N (n = 3) at that instant.
  const double g = 9.81, th0 = M_PI / 4;
  for (const int n : {2, 3}) {
    SCOPED_TRACE(n);
    const double w2 = (n / 2.0 + 2.0) * g * (std::sin(th0) + 1.0) / (n / 6.0 + 1.0);
    const double share = ((n + 2) * g + (n / 2.0 + 2.0) * w2) / n;  // 76.15 N, 61.94 N
    const PeakRun r = run_peaks_text(parallelogram_yaml(n, 1.0, th0), "parallelogram.yaml",
                                     {"solver.end_time=2"});
    ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
    EXPECT_GT(r.result.stats.projections, 0);  // it passed near its in-line position
    for (int i = 0; i < n; ++i) {
      const ChannelExtremum& e = r.tracked("pivot_" + std::to_string(i) + ".F");
      EXPECT_NEAR(e.max, share, 1e-3 * share) << "pivot_" << i << " at t = " << e.t_max;
    }
  }
}

TEST(Extrema, AStepObserverSeesTheWorkspaceOfTheStepsEnd) {
  // The step hook hands observers the workspace at the step's end without evaluating it again
  // where the integrator's last evaluation was there (DOPRI5's last stage), and evaluates it
  // where not (a step cut at an event; CVODE). Either way every channel must be what a fresh
  // evaluation at (t1, y) gives: on the Flores example, whose impacts cut steps, with both
  // integrators.
  class Check : public Observer {
   public:
    explicit Check(const Model& m)
        : model(m), a(channel_info(m, Workspace(m)).size()), b(a.size()) {}
    bool wants_steps() const override { return true; }
    void output(double, const Eigen::VectorXd&, const Workspace&) override {}
    void step(double, double, const Eigen::VectorXd& y, const Workspace& ws,
              StepProbe& probe) override {
      ++steps;
      channel_values(model, ws, y, a.data());
      ASSERT_TRUE(probe.at_end());
      ASSERT_EQ(probe.state(), y);
      channel_values(model, probe.workspace(), probe.state(), b.data());
      for (size_t i = 0; i < a.size(); ++i)
        if (a[i] != b[i] && !(std::isnan(a[i]) && std::isnan(b[i]))) ++differing;
    }
    const Model& model;
    std::vector<double> a, b;
    long steps = 0, differing = 0;
  };
  for (const char* integrator : {"dopri5", "bdf"}) {
    SCOPED_TRACE(integrator);
    const Model m = load_model_text(read_file(example_path("flores_slider_crank.yaml")),
                                    "flores_slider_crank.yaml",
                                    {"solver.end_time=0.012",
                                     "solver.integrator=" + std::string(integrator)})
                        .model;
    Workspace ws(m);
    Check check(m);
    const RunResult r = simulate(m, ws, check);
    ASSERT_TRUE(r.status.ok) << r.status.message;
    EXPECT_GT(r.stats.events, 10);
    EXPECT_GT(check.steps, 100);
    EXPECT_EQ(check.differing, 0);
  }
}
