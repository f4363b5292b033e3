// The variational Lyapunov spectrum of models (study/variational_lyapunov.hpp): exact exponents
// of a damped oscillator built from model elements (a constrained body, so the projection onto
// the constraint manifold's tangent space is what keeps Baumgarte's artificial exponents out),
// and agreement with the two-trajectory estimate on the clearance-joint slider-crank.
#include <gtest/gtest.h>

#include <cmath>

#include "core/dynamics.hpp"
#include "io/model_loader.hpp"
#include "study/run_analysis.hpp"
#include "study/variational_lyapunov.hpp"

namespace lash {
namespace {

TEST(VariationalLyapunov, ConstrainedDampedOscillatorHasExactExponents) {
  // A 2 kg block on a frictionless guide (2 constraint rows: 1 DOF of 3 coordinates), 800 N/m
  // spring with 8 N·s/m damper: ω = 20 rad/s, ζ = c/(2mω) = 0.1, both exponents −ζω = −2 1/s.
  // The full linearised flow also has Baumgarte's −α = −100 1/s directions (twice per row):
  // the spectrum must have 2 exponents, both −2.
  const std::string yaml = R"Y(
gravity: [0, 0]
bodies:
  block: {mass: 2.0, inertia: 0.01, position: [0.11, 0]}
ground:
  markers: {A: [0, 0]}
joints:
  guide: {type: translational, guide: ground.A, slider: block, axis: [1, 0]}
loads:
  spring: {type: spring_damper, from: ground.A, to: block, stiffness: 800, damping: 8, free_length: 0.1}
solver: {rtol: 1e-9, atol: 1e-12, end_time: 6.0, output_interval: 0.01, initial_state: given}
)Y";
  const Model model = load_model_text(yaml, "oscillator.yaml", {}).model;
  Workspace ws(model);
  const Eigen::VectorXd y0 = initial_state(model, ws);
  const double omega = 20.0, zeta = 0.1, period = 2 * M_PI / omega;
  const double interval = period / 20;
  const int intervals = static_cast<int>(5.0 / interval);
  const LyapunovEstimate e =
      variational_lyapunov(model, y0, 0.0, interval, intervals, 1.0 / omega, nullptr);
  ASSERT_TRUE(e.ok) << e.message;
  EXPECT_EQ(e.method, "variational");
  ASSERT_EQ(e.spectrum.size(), 2u);
  // With the weight τ = 1/ω the tangent ellipse is nearly a circle: the finite-time scatter is
  // ln(1 + O(ζ)) / T ≈ 0.02 1/s over 5 s.
  EXPECT_NEAR(e.spectrum[0], -zeta * omega, 0.05);
  EXPECT_NEAR(e.spectrum[1], -zeta * omega, 0.05);
  // The sum is the trace of the reduced flow, −2ζω, at any time (Liouville).
  EXPECT_NEAR(e.spectrum[0] + e.spectrum[1], -2 * zeta * omega, 2e-3);
  EXPECT_EQ(e.spectrum_history.size(), e.history.size());
  EXPECT_EQ(e.renormalisations, intervals);
}

TEST(VariationalLyapunov, AMotionComeToRestKeepsItsExponents) {
  // The same oscillator with ζ = 0.05 (−ζω = −1 1/s) over 40 s at the default tolerances, and
  // overdamped (c = 100 N·s/m, ζ = 1.25: −ζω ± ω√(ζ² − 1) = −10 and −40 1/s) over 6 s. Once
  // the motion has decayed DOPRI5's steps span many periods, and one tangent RK4 step per step
  // gave −4.93, −4.93 and −0.18, −8.77; the steps are now cut (kTangentSubstep).
  const std::string yaml = R"Y(
bodies:
  block: {mass: 2.0, position: [0.31, 0]}
ground:
  markers: {A: [0, 0]}
joints:
  guide: {type: translational, guide: ground.A, slider: block, axis: [1, 0]}
loads:
  spring: {type: spring_damper, from: ground.A, to: block, stiffness: 800, damping: 4, free_length: 0.3}
solver: {end_time: 40, output_interval: 0.001}
)Y";
  const double period = 2 * M_PI / 20.0;
  struct Case {
    std::vector<std::string> set;
    double end, first, second, tolerance;
  };
  for (const Case& c : {Case{{}, 40.0, -1.0, -1.0, 0.02},
                        Case{{"loads.spring.damping=100"}, 6.0, -10.0, -40.0, 0.2}}) {
    std::vector<std::string> set = c.set;
    set.push_back("solver.end_time=" + std::to_string(c.end));
    const Model model = load_model_text(yaml, "oscillator.yaml", set).model;
    Workspace ws(model);
    const Eigen::VectorXd y0 = initial_state(model, ws);
    const double interval = period / 20;
    const int intervals = static_cast<int>((c.end - period) / interval);
    const LyapunovEstimate e =
        variational_lyapunov(model, y0, 0.0, interval, intervals, 1.0 / 20.0, nullptr);
    ASSERT_TRUE(e.ok) << e.message;
    ASSERT_EQ(e.spectrum.size(), 2u);
    EXPECT_NEAR(e.spectrum[0], c.first, c.tolerance) << c.end;
    EXPECT_NEAR(e.spectrum[1], c.second, c.tolerance * std::abs(c.second / c.first)) << c.end;
  }
}

TEST(VariationalLyapunov, ChaoticPendulumAgreesWithTwoTrajectoriesAndSumRule) {
  // The damped, driven pendulum θ'' + θ'/Q + sin θ = g cos(ω_D t) with Q = 2, g = 1.5,
  // ω_D = 2/3 (chaotic; Baker & Gollub, Chaotic Dynamics: An Introduction) from model elements:
  // a body of 0.5 kg and 0.5 kg·m² hanging 1 m below a revolute joint (moment of inertia about
  // the pivot 1 kg·m²), gravity 2 m/s² (m g L = 1 N·m), a torsional damper 0.5 N·m·s/rad and a
  // torque load. Smooth (no events), so two trajectories with d0 = 1e-7 are a sound estimate
  // of the largest exponent, and the sum of the two exponents is the trace −1/Q exactly.
  const std::string yaml = R"Y(
gravity: [0, -2]
ground:
  markers: {O: [0, 0]}
bodies:
  bob: {mass: 0.5, inertia: 0.5, position: [0, -1], markers: {P: [0, 1]}}
joints:
  pivot: {type: revolute, journal: bob.P, bearing: ground.O}
loads:
  damper: {type: torsional_spring_damper, bodies: [ground, bob], stiffness: 0, damping: 0.5}
  drive: {type: torque, body: bob, torque: "1.5*cos(2/3*time)"}
solver: {rtol: 1e-9, atol: 1e-12, end_time: 300, output_interval: 0.25, initial_state: given}
)Y";
  const Model model = load_model_text(yaml, "pendulum.yaml", {}).model;
  AnalysisOptions o;
  o.ideal_twin = false;
  o.period = 3 * M_PI;  // 2π/ω_D
  o.discard_periods = 3;
  o.lyapunov_method = "variational";
  const RunAnalysis v = analyze_run(model, o);
  o.lyapunov_method = "two-trajectory";
  o.lyapunov_d0 = 1e-7;
  const RunAnalysis two = analyze_run(model, o);
  ASSERT_TRUE(v.lyapunov && v.lyapunov->ok) << (v.lyapunov ? v.lyapunov->message : "none");
  ASSERT_TRUE(two.lyapunov && two.lyapunov->ok);
  ASSERT_EQ(v.lyapunov->spectrum.size(), 2u);  // 1 DOF: Baumgarte's 4 directions left out
  const double l1 = v.lyapunov->exponent, l2 = v.lyapunov->spectrum[1];
  EXPECT_GT(l1, 0.05);
  EXPECT_NEAR(two.lyapunov->exponent, l1, 0.15 * l1)
      << "variational " << l1 << ", two-trajectory " << two.lyapunov->exponent;
  EXPECT_NEAR(l1 + l2, -0.5, 2e-3);
  RecordProperty("variational", std::to_string(l1) + " " + std::to_string(l2));
  RecordProperty("two_trajectory", std::to_string(two.lyapunov->exponent));
  EXPECT_EQ(v.verdict.kind, "chaotic");
  // The forward differences' perturbation length does not matter (1e-9 by default): the
  // reference trajectory is the same (the tangent vectors do not steer the steps); 5 periods.
  const LyapunovEstimate& e = *v.lyapunov;
  Workspace ws(model);
  Simulator sim(model, ws);
  sim.start(0.0, initial_state(model, ws));
  ASSERT_TRUE(sim.advance_to(e.t0, nullptr));
  const LyapunovEstimate base = variational_lyapunov(model, sim.state(), e.t0, e.interval,
                                                     100, 1.5, nullptr);
  ASSERT_TRUE(base.ok) << base.message;
  for (double step : {1e-7, 1e-11}) {
    const LyapunovEstimate w = variational_lyapunov(model, sim.state(), e.t0, e.interval,
                                                    100, 1.5, nullptr, step);
    ASSERT_TRUE(w.ok) << w.message;
    EXPECT_NEAR(w.spectrum[0], base.spectrum[0], 1e-3 * std::abs(base.spectrum[0])) << step;
    EXPECT_NEAR(w.spectrum[1], base.spectrum[1], 1e-3 * std::abs(base.spectrum[1])) << step;
  }
}

}  // namespace
TEST(VariationalLyapunov, CoulombFrictionFallsBackToTwoTrajectoriesAndSaysWhy) {
  // Coulomb friction jumps where the sliding velocity changes sign, which no event locates: the
  // analysis uses two trajectories there and says why; a continuous law keeps the variational
  // spectrum.
  for (const std::string law : {"coulomb", "ambrosio"}) {
    SCOPED_TRACE(law);
    std::vector<std::string> set{"solver.end_time=0.036", "clearance_defaults.friction.law=" + law,
                                 "clearance_defaults.friction.mu=0.05"};
    if (law == "ambrosio") {
      set.push_back("clearance_defaults.friction.v0=1.0e-4");
      set.push_back("clearance_defaults.friction.v1=1.0e-3");
    }
    const Model model =
        load_model_file(std::string(LASH_SOURCE_DIR) + "/examples/flores_slider_crank.yaml", set).model;
    AnalysisOptions o;
    o.ideal_twin = false;
    const RunAnalysis a = analyze_run(model, o);
    ASSERT_TRUE(a.lyapunov.has_value());
    if (law == "coulomb") {
      EXPECT_EQ(a.lyapunov->method, "two-trajectory");
      EXPECT_NE(a.lyapunov->note.find("joint 'rod_slider' has Coulomb friction"), std::string::npos)
          << a.lyapunov->note;
    } else {
      EXPECT_EQ(a.lyapunov->method, "variational");
      EXPECT_TRUE(a.lyapunov->note.empty()) << a.lyapunov->note;
    }
    EXPECT_TRUE(a.lyapunov->ok) << a.lyapunov->message;
  }
}

}  // namespace lash
