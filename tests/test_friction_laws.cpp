// Friction laws against shared/reference/formulas.md.
#include <gtest/gtest.h>

#include "core/adams_functions.hpp"
#include "core/friction_laws.hpp"

using namespace lash;

TEST(Coulomb, OpposesSliding) {
  FrictionParams p;
  p.mu = 0.1;
  EXPECT_DOUBLE_EQ(coulomb_friction(2.0, 100.0, p), -10.0);
  EXPECT_DOUBLE_EQ(coulomb_friction(-0.001, 100.0, p), 10.0);
  EXPECT_EQ(coulomb_friction(0.0, 100.0, p), 0.0);
}

TEST(Ambrosio, DynamicCorrectionCoefficient) {
  FrictionParams p;
  p.mu = 0.2;
  p.v0 = 1e-4;
  p.v1 = 1e-2;
  EXPECT_EQ(ambrosio_friction(5e-5, 50.0, p), 0.0);                     // |v| ≤ v0: c_d = 0
  const double v = 5e-3, cd = (v - p.v0) / (p.v1 - p.v0);
  EXPECT_NEAR(ambrosio_friction(v, 50.0, p), -0.2 * cd * 50.0, 1e-12);  // linear ramp
  EXPECT_NEAR(ambrosio_friction(-v, 50.0, p), 0.2 * cd * 50.0, 1e-12);
  EXPECT_DOUBLE_EQ(ambrosio_friction(1.0, 50.0, p), -10.0);              // c_d = 1
}

TEST(AdamsStepped, Seed004Table3Values) {
  FrictionParams p;
  p.mu_static = 0.2;
  p.mu_dynamic = 0.16;
  p.v_static = 1e-4;
  p.v_dynamic = 1e-2;
  const double fn = 1000.0;
  EXPECT_DOUBLE_EQ(adams_stepped_friction(0.5, fn, p), -160.0);          // μ_d
  EXPECT_DOUBLE_EQ(adams_stepped_friction(-0.5, fn, p), 160.0);
  EXPECT_NEAR(adams_stepped_friction(1e-4, fn, p), -200.0, 1e-9);        // μ_s at v_s
  EXPECT_NEAR(adams_stepped_friction(5.05e-3, fn, p),
              -step(5.05e-3, 1e-4, 0.2, 1e-2, 0.16) * fn, 1e-9);         // μ_s → μ_d
  EXPECT_EQ(adams_stepped_friction(0.0, fn, p), 0.0);                    // through zero
  EXPECT_NEAR(adams_stepped_friction(5e-5, fn, p), -step(5e-5, -1e-4, -0.2, 1e-4, 0.2) * fn, 1e-9);
  // Continuous at ±v_s.
  EXPECT_NEAR(adams_stepped_friction(1e-4 * (1 + 1e-9), fn, p),
              adams_stepped_friction(1e-4 * (1 - 1e-9), fn, p), 1e-4);
}

TEST(FrictionLaws, NeverAddEnergy) {
  FrictionParams p;
  p.mu = 0.3;
  p.v0 = 1e-3;
  p.v1 = 1e-2;
  p.mu_static = 0.3;
  p.mu_dynamic = 0.2;
  p.v_static = 1e-3;
  p.v_dynamic = 1e-2;
  for (const auto& info : kFrictionLaws)
    for (double v : {-3.0, -5e-3, -5e-4, 0.0, 5e-4, 5e-3, 3.0})
      EXPECT_LE(friction_force(info.law, v, 20.0, p) * v, 0.0) << info.name << " v=" << v;
}
