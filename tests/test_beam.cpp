// The planar ANCF beam (core/beam.hpp) against beam theory: exact rigid motions, derivatives
// computed twice, the cantilever PL³/3EI, Euler–Bernoulli frequencies with their convergence,
// the elastica (published values and an independent shooting solution), energy conservation
// of a free beam, and the rigid pendulum as the stiff limit.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <functional>

#include "core/beam.hpp"

using namespace lash;
using namespace lash::beam;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Aluminium bar 1 m × 20 mm × 10 mm (h = 10 mm in the plane): slenderness L/r ≈ 346, so its
// first axial frequency lies far above the first three bending ones.
Mesh bar(int elements) {
  Mesh m;
  m.section = rectangle(0.02, 0.01, 70e9, 2700.0);
  m.length = 1.0;
  m.elements = elements;
  return m;
}

double bending_scale(const Mesh& m) {
  const Section& s = m.section;
  return std::sqrt(s.youngs_modulus * s.inertia /
                   (s.density * s.area * std::pow(m.length, 4)));
}

// The bending frequencies (transverse share > 0.9, above rigid-body round-off), ascending.
std::vector<double> bending(const Mesh& m, Support support) {
  std::vector<double> out;
  for (const Mode& mode : modes(m, support))
    if (mode.transverse > 0.9 && mode.omega > 1e-3 * bending_scale(m)) out.push_back(mode.omega);
  return out;
}

// Tip load P (−y) at the free end of a clamped beam: the load vector.
Eigen::VectorXd tip_load(const Mesh& m, double p) {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(m.coordinates());
  f[kNodeCoordinates * m.elements + 1] = -p;
  return f;
}

// Elastica of a cantilever under a tip load P (−y), by shooting on θ'(0): θ'' = (P/EI) cos θ,
// θ(0) = 0, θ'(L) = 0 (moment-free tip), x' = cos θ, y' = sin θ; RK4 with 20 000 steps.
// Returns (x_L, y_L, θ_L) for L = 1 and load parameter α = PL²/EI.
Eigen::Vector3d elastica(double alpha) {
  auto shoot = [alpha](double k0, Eigen::Vector3d& tip) {
    const int n = 20000;
    const double h = 1.0 / n;
    Eigen::Vector4d s(0, k0, 0, 0);  // θ, θ', x, y
    auto f = [alpha](const Eigen::Vector4d& z) {
      return Eigen::Vector4d(z[1], alpha * std::cos(z[0]), std::cos(z[0]), std::sin(z[0]));
    };
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector4d k1 = f(s), k2 = f(s + 0.5 * h * k1), k3 = f(s + 0.5 * h * k2),
                            k4 = f(s + h * k3);
      s += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    tip = Eigen::Vector3d(s[2], s[3], s[0]);
    return s[1];  // θ'(L), zero at the solution
  };
  // θ'(0) = −α x_L lies in [−α, 0]; bisection on the moment at the tip.
  double lo = -alpha, hi = 0.0;
  Eigen::Vector3d tip;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (shoot(mid, tip) > 0 ? hi : lo) = mid;
  }
  shoot(0.5 * (lo + hi), tip);
  return tip;
}

}  // namespace

TEST(Beam, RigidMotionsAreExactAndStoreNoEnergy) {
  const Mesh m = bar(3);
  const Vec2 origin(0.3, -0.2);
  const double angle = 2.1;
  const Eigen::VectorXd q = straight_coordinates(m, origin, angle);
  const Vec2 t(std::cos(angle), std::sin(angle));
  for (double x : {0.0, 0.17, 0.5, 0.71, 1.0}) {
    EXPECT_LT((position(m, q, x) - (origin + x * t)).norm(), 1e-15);
    EXPECT_LT((slope(m, q, x) - t).norm(), 1e-15);
  }
  EXPECT_LT(strain_energy(m, q), 1e-20);
  EXPECT_LT(elastic_force(m, q).norm(), 1e-6);  // against element forces of order EA = 1.4e7 N
}

TEST(Beam, MassMatrixGivesRigidKineticEnergy) {
  // ½ q̇ᵀ M q̇ of a translation is ½ mv², of a rotation about end A ½ (mL²/3) ω²: the Hermite
  // cubics represent both fields exactly, so these hold to round-off at any mesh.
  for (int n : {1, 4}) {
    const Mesh m = bar(n);
    const Eigen::MatrixXd mm = mass_matrix(m);
    const double mass = m.section.density * m.section.area * m.length;
    Eigen::VectorXd v = Eigen::VectorXd::Zero(m.coordinates()), w = v;
    const double omega = 3.0;
    for (int i = 0; i < m.nodes(); ++i) {
      v[4 * i] = 2.0;                                  // vx = 2 m/s everywhere
      w[4 * i + 1] = omega * i * m.element_length();   // ṙ = ω k × r, r = (x, 0)
      w[4 * i + 3] = omega;                            // ṙ' = ω k × (1, 0)
    }
    EXPECT_NEAR(0.5 * v.dot(mm * v) / (0.5 * mass * 4.0), 1.0, 1e-13);
    EXPECT_NEAR(0.5 * w.dot(mm * w) / (0.5 * mass * m.length * m.length / 3 * omega * omega), 1.0,
                1e-13);
  }
}

TEST(Beam, ForceAndStiffnessAreDerivativesOfTheEnergy) {
  const Section s = bar(1).section;
  const double l = 0.25;
  // A bent, stretched and rotated element.
  Vec8 e;
  e << 0.1, 0.2, std::cos(0.4), std::sin(0.4), 0.1 + 0.24, 0.2 + 0.12, 1.01 * std::cos(0.6),
      1.01 * std::sin(0.6);
  const Vec8 f = element_elastic_force(s, l, e);
  const Mat8 k = element_stiffness(s, l, e);
  for (int j = 0; j < 8; ++j) {
    const double h = 1e-6;
    Vec8 ep = e, em = e;
    ep[j] += h, em[j] -= h;
    const double du = (element_strain_energy(s, l, ep) - element_strain_energy(s, l, em)) / (2 * h);
    EXPECT_NEAR(-f[j], du, 1e-6 * f.norm()) << "force " << j;
    const Vec8 dk = -(element_elastic_force(s, l, ep) - element_elastic_force(s, l, em)) / (2 * h);
    EXPECT_LT((k.col(j) - dk).norm(), 1e-6 * k.norm()) << "stiffness column " << j;
  }
  EXPECT_LT((k - k.transpose()).norm(), 1e-12 * k.norm());
}

TEST(Beam, CantileverTipLoadSmallDeflection) {
  // δ = PL³/3EI for δ/L = 1e-4 (geometric non-linearity O((δ/L)²)); the Hermite cubics hold the
  // linear solution exactly, so one element already gives it. The root moment is PL (σ = PLc/I)
  // and the mid-span point lies PL³/16EI off the chord.
  for (int n : {1, 2, 4}) {
    const Mesh m = bar(n);
    const double ei = m.section.youngs_modulus * m.section.inertia;
    const double delta = 1e-4 * m.length, p = 3 * ei * delta / std::pow(m.length, 3);
    const Eigen::VectorXd q = clamped_static(m, tip_load(m, p), 1);
    EXPECT_NEAR(-q[4 * n + 1] / delta, 1.0, 1e-5) << n << " elements";
    double x_max = -1;
    const Resultants r = largest_stress(m, q, &x_max);
    EXPECT_NEAR(x_max, 0.0, 1e-12);
    EXPECT_NEAR(std::abs(r.bending_moment) / (p * m.length), 1.0, 1e-5);
    // The stress adds |N|/A: the clamped end's slope may stretch, and the Hermite field's axial
    // strain there is a spurious 8.6e-4 (1 element), 1.8e-4 (2), 2.8e-5 (4) of the bending stress.
    EXPECT_NEAR(r.stress / (p * m.length * m.section.fibre / m.section.inertia), 1.0, 1e-3);
    EXPECT_NEAR(chord_deflection(m, q, 0.5 * m.length) / (p * std::pow(m.length, 3) / (16 * ei)),
                1.0, 1e-4);
  }
}

TEST(Beam, AxialTipLoad) {
  // N = P along the whole bar and elongation PL/EA (to O(ε)).
  const Mesh m = bar(2);
  const double ea = m.section.youngs_modulus * m.section.area, p = 1e-5 * ea;
  Eigen::VectorXd f = Eigen::VectorXd::Zero(m.coordinates());
  f[4 * m.elements] = p;
  const Eigen::VectorXd q = clamped_static(m, f, 1);
  EXPECT_NEAR((q[4 * m.elements] - m.length) / (p * m.length / ea), 1.0, 1e-4);
  EXPECT_NEAR(resultants(m, q, 0.3).axial_force / p, 1.0, 1e-4);
  EXPECT_NEAR(resultants(m, q, 0.3).stress / (p / m.section.area), 1.0, 1e-4);
  // At 5 % strain N is still the load it holds (EA ε, the Green–Lagrange force, read P/λ).
  const double big = 0.05 * ea;
  f[4 * m.elements] = big;
  const Eigen::VectorXd qb = clamped_static(m, f, 10);
  for (const double x : {0.1, 0.3, 0.5 * m.length})
    EXPECT_NEAR(resultants(m, qb, x).axial_force / big, 1.0, 1e-6) << x;
}

TEST(Beam, CantileverFrequenciesConvergeToEulerBernoulli) {
  // ω_i = β_i² sqrt(EI/ρAL⁴), β_i L = 1.8751, 4.6941, 7.8548 (clamped–free).
  const double beta[3] = {1.87510407, 4.69409113, 7.85475744};
  double previous[3] = {1, 1, 1};
  for (int n : {2, 4, 8, 16}) {
    const Mesh m = bar(n);
    const std::vector<double> w = bending(m, Support::clamped);
    ASSERT_GE(w.size(), 3u);
    for (int i = 0; i < 3; ++i) {
      const double err = w[i] / (beta[i] * beta[i] * bending_scale(m)) - 1.0;
      std::printf("clamped, %2d elements, mode %d: relative error %.3e\n", n, i + 1, err);
      // Consistent mass and exact stiffness: the Rayleigh quotient bounds from above.
      EXPECT_GT(err, -1e-9) << n << " elements, mode " << i + 1;
      if (n >= 4) {
        EXPECT_LT(err, 0.01) << n << " elements, mode " << i + 1;
      }
      // Hermite cubics: frequency error O(h⁴). Observed order log2(e(h)/e(h/2)) within 0.5 of 4
      // once asymptotic (measured: 3.90/3.86/3.67 at 4→8, 4.00/3.97/3.94 at 8→16).
      if (n >= 8) {
        EXPECT_NEAR(std::log2(previous[i] / err), 4.0, 0.5) << n << ", " << i + 1;
      }
      previous[i] = err;
    }
  }
}

TEST(Beam, AFineMeshKeepsItsLowestFrequencyConverged) {
  // At 256 elements the mesh's error in the first mode is below 1e-12, so what is left is the
  // eigenvalue solve's: about ε ω_max² / ω₁², which made the first mode 3.4e-6 off (a table of
  // `lash modes` that got worse as the mesh was refined); the eigenvector's Rayleigh quotient
  // brings it to 1e-7.
  Mesh m;  // the steel cantilever of `lash modes` (1 m, 20 × 20 mm)
  m.section = rectangle(0.02, 0.02, 207e9, 7800.0);
  m.length = 1.0;
  m.elements = 256;
  const std::vector<double> w = bending(m, Support::clamped);
  ASSERT_FALSE(w.empty());
  const double exact = 1.87510407 * 1.87510407 * bending_scale(m);
  EXPECT_NEAR(w[0] / exact, 1.0, 5e-7);
}

TEST(Beam, FreeFreeFrequencies) {
  // Three rigid-body modes, then β_i L = 4.7300, 7.8532, 10.9956 (free–free); 8 elements give
  // them within 8.1e-5, 5.8e-4, 2.1e-3.
  const Mesh m = bar(8);
  const std::vector<Mode> all = modes(m, Support::free);
  int rigid = 0;
  for (const Mode& mode : all) rigid += mode.omega < 1e-3 * bending_scale(m);
  EXPECT_EQ(rigid, 3);
  const std::vector<double> w = bending(m, Support::free);
  const double beta[3] = {4.73004074, 7.85320462, 10.99560784};
  for (int i = 0; i < 3; ++i) {
    std::printf("free-free, 8 elements, mode %d: relative error %.3e\n", i + 1,
                w[i] / (beta[i] * beta[i] * bending_scale(m)) - 1.0);
    EXPECT_NEAR(w[i] / (beta[i] * beta[i] * bending_scale(m)), 1.0, 3e-3) << "mode " << i + 1;
  }
}

TEST(Beam, LargeDeflectionMatchesTheElastica) {
  // Cantilever with a vertical tip load, α = PL²/EI. Published (Mattiasson 1981, "Numerical
  // results from large deflection beam and frame problems analysed by means of elliptic
  // integrals", Int. J. Numer. Meth. Eng. 17): α = 1: vertical tip deflection 0.30172 L,
  // horizontal 0.05643 L. The shooting solution above must reproduce them, and the beam must
  // match it at α = 3 (tip rotation near 1 rad) with 16 elements.
  const Eigen::Vector3d ref1 = elastica(1.0);
  EXPECT_NEAR(-ref1[1], 0.30172, 1e-5);
  EXPECT_NEAR(1.0 - ref1[0], 0.05643, 1e-5);
  const Eigen::Vector3d ref3 = elastica(3.0);
  EXPECT_GT(-ref3[2], 0.95);
  for (double alpha : {1.0, 3.0}) {
    const Eigen::Vector3d ref = alpha == 1.0 ? ref1 : ref3;
    const Mesh m = bar(16);
    const double ei = m.section.youngs_modulus * m.section.inertia;
    const Eigen::VectorXd q = clamped_static(m, tip_load(m, alpha * ei), 10);
    const Vec2 tip = q.segment<2>(4 * m.elements);
    const Vec2 tip_slope = q.segment<2>(4 * m.elements + 2);
    // Axial strain (P/EA ~ 3e-5 here) shifts the tip by that order beyond the inextensible
    // elastica.
    EXPECT_NEAR(tip.x(), ref[0], 2e-4) << "alpha " << alpha;
    EXPECT_NEAR(tip.y(), ref[1], 2e-4) << "alpha " << alpha;
    EXPECT_NEAR(std::atan2(tip_slope.y(), tip_slope.x()), ref[2], 2e-4) << "alpha " << alpha;
  }
}

namespace {
// Classical RK4 step of q̈ = M⁻¹ Q(q) on the free coordinates.
void rk4(const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& acc, Eigen::VectorXd& q,
         Eigen::VectorXd& v, double h) {
  const Eigen::VectorXd a1 = acc(q);
  const Eigen::VectorXd q2 = q + 0.5 * h * v, v2 = v + 0.5 * h * a1;
  const Eigen::VectorXd a2 = acc(q2);
  const Eigen::VectorXd q3 = q + 0.5 * h * v2, v3 = v + 0.5 * h * a2;
  const Eigen::VectorXd a3 = acc(q3);
  const Eigen::VectorXd q4 = q + h * v3, v4 = v + h * a3;
  const Eigen::VectorXd a4 = acc(q4);
  q += h / 6 * (v + 2 * v2 + 2 * v3 + v4);
  v += h / 6 * (a1 + 2 * a2 + 2 * a3 + a4);
}

double highest_frequency(const Mesh& m) {
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(
      stiffness_matrix(m, straight_coordinates(m, Vec2::Zero(), 0.0)), mass_matrix(m),
      Eigen::EigenvaluesOnly);
  return std::sqrt(eig.eigenvalues().maxCoeff());
}
}  // namespace

TEST(Beam, FreeBeamConservesEnergy) {
  // A free beam thrown spinning with a bending velocity field: ½ q̇ᵀMq̇ + U stays constant
  // (RK4, h = 0.5/ω_max: its energy error is O(h⁴)).
  Mesh m = bar(4);
  m.section.youngs_modulus = 1e9;  // soft, so that it deforms visibly
  const Eigen::MatrixXd mm = mass_matrix(m);
  const Eigen::LLT<Eigen::MatrixXd> llt(mm);
  Eigen::VectorXd q = straight_coordinates(m, Vec2::Zero(), 0.0);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(m.coordinates());
  for (int i = 0; i < m.nodes(); ++i) {
    const double x = i * m.element_length();
    v[4 * i + 1] = 5.0 * x + 2.0 * std::sin(kPi * x);  // spin about end A plus a bending field
    v[4 * i + 3] = 5.0 + 2.0 * kPi * std::cos(kPi * x);
  }
  auto energy = [&] { return 0.5 * v.dot(mm * v) + strain_energy(m, q); };
  const double e0 = energy();
  const double h = 0.5 / highest_frequency(m);
  double worst = 0.0, largest_u = 0.0;
  auto acc = [&](const Eigen::VectorXd& qq) { return Eigen::VectorXd(llt.solve(elastic_force(m, qq))); };
  for (double t = 0; t < 0.5; t += h) {
    rk4(acc, q, v, h);
    worst = std::max(worst, std::abs(energy() / e0 - 1));
    largest_u = std::max(largest_u, strain_energy(m, q) / e0);
  }
  EXPECT_GT(largest_u, 0.01);  // the beam did deform and exchange energy
  EXPECT_LT(worst, 1e-6);
  // It turned through more than one revolution: a large rotation.
  EXPECT_LT(q[4 * m.elements], q[0]);
}

TEST(Beam, StiffPendulumTendsToTheRigidOne) {
  // A bar pinned at end A (its position fixed, slope free) falls from horizontal under gravity.
  // A rigid uniform rod: θ̈ = −(3g/2L) cos θ. The beam's chord angle at t = 0.3 s approaches it
  // as E grows, the difference falling about in proportion to 1/E (static sag ∝ ρAgL⁴/EI).
  constexpr double kG = 9.81, kT = 0.3;
  // Rigid reference.
  double th = 0, om = 0;
  {
    const int n = 30000;
    const double h = kT / n;
    auto f = [&](double a) { return -1.5 * kG * std::cos(a); };
    for (int i = 0; i < n; ++i) {
      const double k1t = om, k1o = f(th), k2t = om + 0.5 * h * k1o, k2o = f(th + 0.5 * h * k1t),
                   k3t = om + 0.5 * h * k2o, k3o = f(th + 0.5 * h * k2t), k4t = om + h * k3o,
                   k4o = f(th + h * k3t);
      th += h / 6 * (k1t + 2 * k2t + 2 * k3t + k4t);
      om += h / 6 * (k1o + 2 * k2o + 2 * k3o + k4o);
    }
  }
  std::vector<double> errors;
  for (double e_mod : {1e8, 1e9, 1e10}) {
    Mesh m = bar(4);
    m.section.youngs_modulus = e_mod;
    const int n = m.coordinates() - 2;  // node A's position is fixed
    const Eigen::MatrixXd mm = mass_matrix(m).bottomRightCorner(n, n);
    const Eigen::LLT<Eigen::MatrixXd> llt(mm);
    // Gravity: Q = ∫ρA Sᵀ(0, −g) dx = −g M u with u the unit y-translation field.
    Eigen::VectorXd uy = Eigen::VectorXd::Zero(m.coordinates());
    for (int i = 0; i < m.nodes(); ++i) uy[4 * i + 1] = 1.0;
    const Eigen::VectorXd grav = (-kG * (mass_matrix(m) * uy)).tail(n);
    Eigen::VectorXd full = straight_coordinates(m, Vec2::Zero(), 0.0);
    Eigen::VectorXd q = full.tail(n), v = Eigen::VectorXd::Zero(n);
    auto acc = [&](const Eigen::VectorXd& qq) {
      full.tail(n) = qq;
      return Eigen::VectorXd(llt.solve(elastic_force(m, full).tail(n) + grav));
    };
    const int steps = static_cast<int>(std::ceil(kT * highest_frequency(m) / 0.5));
    for (int i = 0; i < steps; ++i) rk4(acc, q, v, kT / steps);
    full.tail(n) = q;
    const Vec2 tip = full.segment<2>(4 * m.elements);
    errors.push_back(std::abs(std::atan2(tip.y(), tip.x()) - th));
  }
  EXPECT_LT(th, -0.3);  // the rod has swung a good part of the way down
  EXPECT_GT(errors[0] / errors[1], 5.0);
  EXPECT_GT(errors[1] / errors[2], 5.0);
  EXPECT_LT(errors[2], 2e-3);
}
