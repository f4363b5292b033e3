// Normal contact laws against their published formulas (contact_laws.hpp), to round-off.
#include <gtest/gtest.h>

#include <cmath>

#include "core/contact_laws.hpp"

using namespace lash;

namespace {
ContactParams params(double ce) {
  ContactParams p;
  p.stiffness = 6.61e10;
  p.exponent = 1.5;
  p.restitution = ce;
  p.damping_max = 1e4;
  p.damping_depth = 1e-5;
  return p;
}
}  // namespace

TEST(HertzStiffness, ReferenceCheckValue) {
  // formulas.md: R_J = 9.5 mm, R_B = 10 mm, steel ⇒ K ≈ 6.610e10 N/m^1.5.
  const double k = hertz_cylinder_stiffness(10e-3, 9.5e-3, 207e9, 0.3, 207e9, 0.3);
  EXPECT_NEAR(k / 6.610e10, 1.0, 5e-4);
  // Closed form recomputed term by term.
  const double sigma = (1 - 0.09) / 207e9;
  EXPECT_DOUBLE_EQ(k, 4.0 / (3.0 * 2 * sigma) * std::sqrt(10e-3 * 9.5e-3 / 0.5e-3));
}

TEST(NormalLaws, ZeroOutsideContact) {
  const auto p = params(0.9);
  for (const auto& info : kNormalLaws) {
    EXPECT_EQ(normal_force(info.law, 0.0, 1.0, 1.0, p).total, 0.0) << info.name;
    EXPECT_EQ(normal_force(info.law, -1e-6, 1.0, 1.0, p).total, 0.0) << info.name;
  }
}

TEST(NormalLaws, FormulasToRoundOff) {
  const auto p = params(0.8);
  const double d = 2e-6, dd = 0.3, v0 = 1.2;
  const double kd = p.stiffness * std::pow(d, 1.5);
  EXPECT_DOUBLE_EQ(hertz(d, p), kd);
  EXPECT_NEAR(hunt_crossley(d, dd, v0, p), kd * (1 + 3 * (1 - 0.8) / 2 * dd / v0), 1e-12 * kd);
  EXPECT_NEAR(lankarani_nikravesh(d, dd, v0, p), kd * (1 + 3 * (1 - 0.64) / 4 * dd / v0),
              1e-12 * kd);
  EXPECT_NEAR(flores(d, dd, v0, p), kd * (1 + 8 * (1 - 0.8) / (5 * 0.8) * dd / v0), 1e-12 * kd);
  // IMPACT: δ inside the ramp, damping STEP(2e-6, 0, 0, 1e-5, 1e4) = 1e4·0.04·2.6.
  EXPECT_NEAR(impact_law(d, dd, p), kd + 1e4 * 0.04 * 2.6 * dd, 1e-12 * kd);
}

TEST(NormalLaws, LankaraniNikraveshErkayaFormWithHysteresisDamping) {
  // Erkaya, Doğan & Ulus, Mech. Mach. Theory 88 (2015) eqs. 5 and 8:
  // F = K δ^1.5 + D δ̇, D = 3K(1 − cₑ²)δ^1.5/(4 δ̇⁻).
  const auto p = params(0.9);
  const double d = 5e-6, dd = -0.7, v0 = 2.0;
  const double damping = 3 * p.stiffness * (1 - 0.81) * std::pow(d, 1.5) / (4 * v0);
  EXPECT_NEAR(lankarani_nikravesh(d, dd, v0, p), p.stiffness * std::pow(d, 1.5) + damping * dd,
              1e-9);
}

TEST(NormalLaws, ElasticWhenRestitutionIsOne) {
  const auto p = params(1.0);
  for (auto law : {NormalLaw::hunt_crossley, NormalLaw::lankarani_nikravesh, NormalLaw::flores})
    EXPECT_DOUBLE_EQ(normal_force(law, 3e-6, 5.0, 1.0, p).total, hertz(3e-6, p));
}

TEST(NormalLaws, NeverPulls) {
  const auto p = params(0.5);
  // Fast separation: the damping term exceeds the elastic one; the force is clipped at 0.
  for (const auto& info : kNormalLaws)
    EXPECT_GE(normal_force(info.law, 1e-7, -1e3, 0.01, p).total, 0.0) << info.name;
  EXPECT_EQ(lankarani_nikravesh(1e-7, -1e3, 0.01, p), 0.0);
}

TEST(NormalLaws, RegistryNamesRoundTrip) {
  for (const auto& info : kNormalLaws) {
    ASSERT_TRUE(normal_law_from_name(info.name));
    EXPECT_EQ(*normal_law_from_name(info.name), info.law);
    EXPECT_EQ(normal_law_name(info.law), info.name);
  }
  EXPECT_FALSE(normal_law_from_name("hooke"));
}

TEST(ContactPotential, DerivativeIsTheElasticForce) {
  // Every law stores K δ^(n+1)/(n+1); its derivative is the elastic part K δⁿ, and that is the
  // whole force of a law without damping.
  const auto p = params(0.9);
  const double d = 4e-6, h = 1e-11;
  for (const auto& info : kNormalLaws) {
    const double dv = (normal_force(info.law, d + h, 0.3, 1.0, p).potential -
                       normal_force(info.law, d - h, 0.3, 1.0, p).potential) /
                      (2 * h);
    const NormalForce f = normal_force(info.law, d, 0.3, 1.0, p);
    EXPECT_NEAR(dv / f.elastic, 1.0, 1e-6) << info.name;
    EXPECT_DOUBLE_EQ(f.elastic, hertz(d, p)) << info.name;
  }
  EXPECT_NEAR(normal_force(NormalLaw::hertz, d, 0.3, 1.0, p).potential,
              p.stiffness * std::pow(d, 2.5) / 2.5, 1e-12 * p.stiffness * std::pow(d, 2.5));
}
