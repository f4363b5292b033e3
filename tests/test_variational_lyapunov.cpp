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

}  // namespace
}  // namespace lash
