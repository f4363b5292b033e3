// STEP, STEP5, IMPACT and BISTOP against their closed forms (MSC Adams function reference).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/adams_functions.hpp"

using namespace lash;

TEST(Step, EndsMidpointAndCubic) {
  EXPECT_EQ(step(-1.0, 0.0, 2.0, 1.0, 5.0), 2.0);
  EXPECT_EQ(step(0.0, 0.0, 2.0, 1.0, 5.0), 2.0);
  EXPECT_EQ(step(1.0, 0.0, 2.0, 1.0, 5.0), 5.0);
  EXPECT_EQ(step(3.0, 0.0, 2.0, 1.0, 5.0), 5.0);
  EXPECT_DOUBLE_EQ(step(0.5, 0.0, 2.0, 1.0, 5.0), 3.5);
  // Δ = 0.25: h0 + (h1 − h0)Δ²(3 − 2Δ) = 2 + 3·0.0625·2.5
  EXPECT_DOUBLE_EQ(step(0.25, 0.0, 2.0, 1.0, 5.0), 2.0 + 3.0 * 0.0625 * 2.5);
  // Shifted interval: x0 = 1, x1 = 3, x = 2.5 → Δ = 0.75.
  EXPECT_DOUBLE_EQ(step(2.5, 1.0, 0.0, 3.0, 1.0), 0.5625 * 1.5);
}

TEST(Step, SlopeVanishesAtBothEnds) {
  const double h = 1e-6;
  EXPECT_NEAR((step(h, 0, 0, 1, 1) - step(0, 0, 0, 1, 1)) / h, 0.0, 1e-5);
  EXPECT_NEAR((step(1, 0, 0, 1, 1) - step(1 - h, 0, 0, 1, 1)) / h, 0.0, 1e-5);
}

TEST(Step5, MatchesQuinticAndTheBreakerDrive) {
  // Δ = 0.3: Δ³(10 − 15Δ + 6Δ²)
  const double d = 0.3, expected = d * d * d * (10 - 15 * d + 6 * d * d);
  EXPECT_NEAR(step5(0.3, 0.0, 0.0, 1.0, 1.0), expected, 1e-15);
  EXPECT_DOUBLE_EQ(step5(0.5, 0.0, 0.0, 1.0, 1.0), 0.5);
  // The UHV circuit-breaker linkage drive STEP5(time, 0, 0, 0.085, 230 mm) (flexible transmission
  // mechanism with multiclearance joints for UHV circuit breakers): full stroke at 0.085 s, half at 0.0425 s.
  EXPECT_DOUBLE_EQ(step5(0.085, 0, 0, 0.085, 0.230), 0.230);
  EXPECT_NEAR(step5(0.0425, 0, 0, 0.085, 0.230), 0.115, 1e-15);
  // Second derivative ~0 at the ends (STEP5 is C²): central difference at x0.
  const double h = 1e-4;
  const double f2 = (step5(h, 0, 0, 1, 1) - 2 * step5(0, 0, 0, 1, 1) + step5(-h, 0, 0, 1, 1)) / (h * h);
  EXPECT_NEAR(f2, 0.0, 1e-2);
}

TEST(Impact, FormulaInAdamsArgumentOrder) {
  const double k = 1e5, e = 1.5, cmax = 50, d = 0.1, x1 = 1.0;
  EXPECT_EQ(impact(1.2, -3.0, x1, k, e, cmax, d), 0.0);  // x ≥ x1: no contact
  // Inside the damping ramp: x = 0.95 → STEP(0.95, 0.9, 50, 1, 0) = 25.
  const double x = 0.95, xd = -2.0;
  const double expected = k * std::pow(0.05, 1.5) - 25.0 * xd;
  EXPECT_NEAR(impact(x, xd, x1, k, e, cmax, d), expected, 1e-9);
  // Deep: full damping cmax.
  EXPECT_NEAR(impact(0.5, -1.0, x1, k, e, cmax, d), k * std::pow(0.5, 1.5) + cmax, 1e-9);
  // Separating fast: the damping term would pull, the force is clipped at 0.
  EXPECT_EQ(impact(0.99, 1e6, x1, k, e, cmax, d), 0.0);
}

TEST(Bistop, FreeBetweenStopsAndSignedOutside) {
  const double k = 1e4, e = 2.0, cmax = 10, d = 0.01;
  EXPECT_EQ(bistop(0.5, 1.0, 0.0, 1.0, k, e, cmax, d), 0.0);
  EXPECT_NEAR(bistop(-0.1, 0.0, 0.0, 1.0, k, e, cmax, d), k * 0.01, 1e-9);    // pushes +
  EXPECT_NEAR(bistop(1.1, 0.0, 0.0, 1.0, k, e, cmax, d), -k * 0.01, 1e-9);    // pushes −
  EXPECT_NEAR(bistop(1.1, 2.0, 0.0, 1.0, k, e, cmax, d), -k * 0.01 - cmax * 2.0, 1e-9);
  EXPECT_EQ(bistop(1.001, -1e6, 0.0, 1.0, k, e, cmax, d), 0.0);               // clipped
}

// Closed forms of the ramps on [0, 2] from 0 to 1, expanded in powers of x (Δ = x/2):
// step  = 0.75x² − 0.25x³;  step5 = 1.25x³ − 0.9375x⁴ + 0.1875x⁵.
namespace {
double cubic_closed(int n, double x) {
  switch (n) {
    case 1: return 1.5 * x - 0.75 * x * x;
    case 2: return 1.5 - 1.5 * x;
    case 3: return -1.5;
    default: return 0.0;
  }
}
double quintic_closed(int n, double x) {
  switch (n) {
    case 1: return 3.75 * x * x - 3.75 * x * x * x + 0.9375 * x * x * x * x;
    case 2: return 7.5 * x - 11.25 * x * x + 3.75 * x * x * x;
    case 3: return 7.5 - 22.5 * x + 11.25 * x * x;
    case 4: return -22.5 + 22.5 * x;
    case 5: return 22.5;
    default: return 0.0;
  }
}
// Relative comparison with a floor for values that cross zero.
void expect_close(double got, double want, const char* what, int n, double x) {
  EXPECT_NEAR(got, want, 1e-12 * std::max(1.0, std::abs(want))) << what << " n=" << n << " x=" << x;
}
}  // namespace

TEST(StepDerivative, MatchesTheExpandedCubicInsideTheRamp) {
  for (double x : {0.1, 0.5, 0.999, 1.0, 1.3, 1.9999}) {
    expect_close(step_derivative(0, x, 0, 0, 2, 1), 0.75 * x * x - 0.25 * x * x * x, "step", 0, x);
    for (int n = 1; n <= 5; ++n)
      expect_close(step_derivative(n, x, 0, 0, 2, 1), cubic_closed(n, x), "step", n, x);
    // Shifted and scaled: step(x, 1, 2, 3, −1) = 2 − 3 step(x − 1, 0, 0, 2, 1).
    for (int n = 1; n <= 3; ++n)
      expect_close(step_derivative(n, x + 1, 1, 2, 3, -1), -3.0 * cubic_closed(n, x), "shifted", n, x);
  }
}

TEST(StepDerivative, EdgesOfTheRamp) {
  // The slope is continuous and 0 at both ends; the second derivative jumps from 0 to ±6(h1 −
  // h0)/L² and at the ends themselves takes the value outside the ramp, as step() does.
  for (double x : {-1.0, 0.0, 2.0, 3.0}) {
    for (int n = 1; n <= 3; ++n) EXPECT_EQ(step_derivative(n, x, 0, 0, 2, 1), 0.0) << n << " " << x;
  }
  const double in = 1e-12;
  EXPECT_NEAR(step_derivative(1, in, 0, 0, 2, 1), 0.0, 1e-11);
  EXPECT_NEAR(step_derivative(2, in, 0, 0, 2, 1), 6.0 / 4.0, 1e-11);
  EXPECT_NEAR(step_derivative(2, 2 - in, 0, 0, 2, 1), -6.0 / 4.0, 1e-11);
  EXPECT_EQ(step_derivative(0, 0.0, 0, 7, 2, 1), 7.0);  // n = 0 is step itself
}

TEST(Step5Derivative, MatchesTheExpandedQuinticInsideTheRamp) {
  for (double x : {0.1, 0.5, 0.999, 1.0, 1.3, 1.9999}) {
    expect_close(step5_derivative(0, x, 0, 0, 2, 1),
                 1.25 * x * x * x - 0.9375 * x * x * x * x + 0.1875 * x * x * x * x * x, "step5", 0, x);
    for (int n = 1; n <= 7; ++n)
      expect_close(step5_derivative(n, x, 0, 0, 2, 1), quintic_closed(n, x), "step5", n, x);
    for (int n = 1; n <= 5; ++n)
      expect_close(step5_derivative(n, x + 1, 1, 2, 3, -1), -3.0 * quintic_closed(n, x), "shifted", n, x);
  }
}

TEST(Step5Derivative, FirstAndSecondDerivativesVanishAtTheEdges) {
  // STEP5 is C²: slope and curvature 0 at both ends, from inside as well; the third jumps
  // (to 7.5 = 60/L³ at x0⁺) and at the ends takes the value outside.
  const double in = 1e-9;
  for (double x : {0.0, 2.0}) {
    EXPECT_EQ(step5_derivative(1, x, 0, 0, 2, 1), 0.0);
    EXPECT_EQ(step5_derivative(2, x, 0, 0, 2, 1), 0.0);
    EXPECT_EQ(step5_derivative(3, x, 0, 0, 2, 1), 0.0);
  }
  EXPECT_NEAR(step5_derivative(1, in, 0, 0, 2, 1), 0.0, 1e-16);
  EXPECT_NEAR(step5_derivative(2, 2 - in, 0, 0, 2, 1), 0.0, 1e-8);
  EXPECT_NEAR(step5_derivative(3, in, 0, 0, 2, 1), 7.5, 1e-7);
}

TEST(StepDerivative, EachOrderIsTheSlopeOfThePreviousOne) {
  // The same quantity two ways: central differences of order n against order n + 1 (√ε-level).
  const double h = 1e-6;
  for (double x : {0.3, 1.1, 1.7}) {
    for (int n = 0; n <= 4; ++n) {
      const double fd = (step5_derivative(n, x + h, 0, 0, 2, 1) - step5_derivative(n, x - h, 0, 0, 2, 1)) / (2 * h);
      EXPECT_NEAR(fd, step5_derivative(n + 1, x, 0, 0, 2, 1), 1e-6) << n << " " << x;
      const double fc = (step_derivative(n, x + h, 0, 0, 2, 1) - step_derivative(n, x - h, 0, 0, 2, 1)) / (2 * h);
      EXPECT_NEAR(fc, step_derivative(n + 1, x, 0, 0, 2, 1), 1e-6) << n << " " << x;
    }
  }
}
