// STEP, STEP5, IMPACT and BISTOP against their closed forms (MSC Adams function reference).
#include <gtest/gtest.h>

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

TEST(Step5, MatchesQuinticAndSeed004Drive) {
  // Δ = 0.3: Δ³(10 − 15Δ + 6Δ²)
  const double d = 0.3, expected = d * d * d * (10 - 15 * d + 6 * d * d);
  EXPECT_NEAR(step5(0.3, 0.0, 0.0, 1.0, 1.0), expected, 1e-15);
  EXPECT_DOUBLE_EQ(step5(0.5, 0.0, 0.0, 1.0, 1.0), 0.5);
  // Seed 004 drive STEP5(time, 0, 0, 0.085, 230 mm): full stroke at 0.085 s, half at 0.0425 s.
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
