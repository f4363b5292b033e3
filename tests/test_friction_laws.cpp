// Friction laws: the static laws against their formulas; LuGre's steady state, Canudas de Wit's
// stick–slip and presliding examples, and its energy balance.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/adams_functions.hpp"
#include "core/friction_laws.hpp"
#include "core/integrator.hpp"

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

TEST(AdamsStepped, StaticToDynamicValues) {
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
  for (const auto& info : kFrictionLaws) {
    if (info.n_states > 0) continue;  // a law with a state: see the LuGre energy tests
    for (double v : {-3.0, -5e-3, -5e-4, 0.0, 5e-4, 5e-3, 3.0})
      EXPECT_LE(friction_force(info.law, v, 20.0, p) * v, 0.0) << info.name << " v=" << v;
  }
}

// ---------------------------------------------------------------------------------------------
// LuGre (Canudas de Wit, Olsson, Åström, Lischinsky 1995)
// ---------------------------------------------------------------------------------------------

namespace {

// Canudas de Wit et al. (1995), the stick–slip example's parameters per newton of normal force:
// σ0 = 1e5 N/m, σ1 = √1e5 N·s/m, σ2 = 0.4 N·s/m, F_C = 1 N, F_S = 1.5 N, v_s = 1e-3 m/s, F_N = 1 N.
constexpr double kSigma0 = 1e5;        // 1/m
const double kSigma1 = std::sqrt(1e5);  // s/m
constexpr double kSigma2 = 0.4;        // s/m
constexpr double kMuStatic = 1.5;
constexpr double kMuDynamic = 1.0;
constexpr double kVStribeck = 1e-3;  // m/s
constexpr double kNormalForce = 1.0;  // N
// Olsson et al. (1998) micro-damping cut-off used in the energy tests: v_d = v_s, well below the
// passive limit 4√(2e) μ_d/σ1 ≈ 0.0295 m/s.
constexpr double kVDamping = 1e-3;  // m/s

LuGreParams canudas_1995(double v_damping = 0.0) {
  LuGreParams p;
  p.sigma0 = kSigma0;
  p.sigma1 = kSigma1;
  p.sigma2 = kSigma2;
  p.mu_static = kMuStatic;
  p.mu_dynamic = kMuDynamic;
  p.v_stribeck = kVStribeck;
  p.v_damping = v_damping;
  return p;
}

/// The Stribeck curve recomputed here from its formula, independently of lugre_stribeck.
double stribeck(double v) {
  const double r = v / kVStribeck;
  return kMuDynamic + (kMuStatic - kMuDynamic) * std::exp(-r * r);
}

double sgn(double v) { return v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0); }

/// Integrates the bristle state at an imposed sliding velocity v(t), with the friction work
/// W = ∫ −F_T v dt and the dissipation Q = ∫ D dt as extra states: y = [z, W, Q].
struct ImposedRun {
  std::vector<double> t, z, v, force, dissipation, bristle_energy, work, dissipated;
  double min_rhs_dissipation = INFINITY;
};

ImposedRun run_imposed(const LuGreParams& p, double f_n, double z0,
                       const std::function<double(double)>& velocity, double t_end, int samples,
                       double rtol, double atol) {
  ImposedRun r;
  OdeProblem ode;
  ode.n = 3;
  ode.rhs = [&](double t, const double* y, double* dy) {
    const double v = velocity(t);
    const LuGreOutput o = lugre_friction(y[0], v, f_n, p);
    dy[0] = o.z_dot;
    dy[1] = -o.force * v;
    dy[2] = o.dissipation;
    r.min_rhs_dissipation = std::min(r.min_rhs_dissipation, o.dissipation);
    return true;
  };
  IntegratorOptions opt;
  opt.rtol = rtol;
  opt.atol = atol;
  auto integ = make_dopri5(ode, opt);
  Eigen::VectorXd y(3);
  y << z0, 0, 0;
  integ->reset(0, y);
  for (int i = 0; i <= samples; ++i) {
    const double t = t_end * i / samples;
    if (i > 0) {
      const Advance a = integ->advance(t, y);
      EXPECT_EQ(a.kind, Advance::reached) << a.message;
    }
    const double v = velocity(t);
    const LuGreOutput o = lugre_friction(y[0], v, f_n, p);
    r.t.push_back(t);
    r.z.push_back(y[0]);
    r.v.push_back(v);
    r.force.push_back(o.force);
    r.dissipation.push_back(o.dissipation);
    r.bristle_energy.push_back(o.bristle_energy);
    r.work.push_back(y[1]);
    r.dissipated.push_back(y[2]);
  }
  return r;
}

// Canudas de Wit et al. (1995), stick–slip: a unit mass on a spring k whose far end moves at
// v_drive; m ẍ = k (v_drive t − x) + F_T(z, ẋ), ż from the LuGre law, all starting at rest.
constexpr double kMass = 1.0;          // kg
constexpr double kSpring = 2.0;        // N/m
constexpr double kDriveSpeed = 0.1;    // m/s
constexpr double kStickSlipEnd = 30.0; // s: four slips
constexpr double kSampleStep = 1e-3;   // s

/// y = [x, ẋ, z, W, Q] with W = ∫ −F_T ẋ dt and Q = ∫ D dt; sampled every kSampleStep.
struct StickSlipRun {
  std::vector<double> t, x, v, z, spring, force, dissipation, bristle_energy, work, dissipated;
  double min_rhs_dissipation = INFINITY;
};

StickSlipRun run_stick_slip(const LuGreParams& p) {
  StickSlipRun r;
  OdeProblem ode;
  ode.n = 5;
  ode.rhs = [&](double t, const double* y, double* dy) {
    const LuGreOutput o = lugre_friction(y[2], y[1], kNormalForce, p);
    dy[0] = y[1];
    dy[1] = (kSpring * (kDriveSpeed * t - y[0]) + o.force) / kMass;
    dy[2] = o.z_dot;
    dy[3] = -o.force * y[1];
    dy[4] = o.dissipation;
    r.min_rhs_dissipation = std::min(r.min_rhs_dissipation, o.dissipation);
    return true;
  };
  IntegratorOptions opt;
  opt.rtol = 1e-8;
  opt.atol = 1e-12;  // one scalar atol: z is ~1e-5 m
  auto integ = make_dopri5(ode, opt);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(5);
  integ->reset(0, y);
  const int n = static_cast<int>(std::lround(kStickSlipEnd / kSampleStep));
  for (int i = 0; i <= n; ++i) {
    const double t = i * kSampleStep;
    if (i > 0) {
      const Advance a = integ->advance(t, y);
      EXPECT_EQ(a.kind, Advance::reached) << a.message;
      if (a.kind != Advance::reached) break;
    }
    const LuGreOutput o = lugre_friction(y[2], y[1], kNormalForce, p);
    r.t.push_back(t);
    r.x.push_back(y[0]);
    r.v.push_back(y[1]);
    r.z.push_back(y[2]);
    r.spring.push_back(kSpring * (kDriveSpeed * t - y[0]));
    r.force.push_back(o.force);
    r.dissipation.push_back(o.dissipation);
    r.bristle_energy.push_back(o.bristle_energy);
    r.work.push_back(y[3]);
    r.dissipated.push_back(y[4]);
  }
  return r;
}

/// [first, last] sample indices of the runs where |ẋ| < speed.
std::vector<std::pair<size_t, size_t>> stick_phases(const std::vector<double>& v, double speed) {
  std::vector<std::pair<size_t, size_t>> out;
  for (size_t i = 0; i < v.size();) {
    if (std::abs(v[i]) >= speed) {
      ++i;
      continue;
    }
    size_t j = i;
    while (j + 1 < v.size() && std::abs(v[j + 1]) < speed) ++j;
    out.emplace_back(i, j);
    i = j + 1;
  }
  return out;
}

}  // namespace

TEST(LuGre, FormulaSignConventionAndRegistry) {
  const double f_n = 7.5;
  for (double v_d : {0.0, kVDamping}) {
    const LuGreParams p = canudas_1995(v_d);
    for (double v : {-0.3, -2e-3, -1e-4, 0.0, 5e-4, 1e-3, 0.02}) {
      for (double s : {-1.4, -0.5, 0.0, 0.7, 1.5}) {
        const double g = stribeck(v), z = s * g / kSigma0;
        const double sigma1 = v_d > 0 ? kSigma1 * std::exp(-(v / v_d) * (v / v_d)) : kSigma1;
        const LuGreOutput o = lugre_friction(z, v, f_n, p);
        const double z_dot = v - kSigma0 * std::abs(v) * z / g;
        const double scale = f_n * (std::abs(kSigma0 * z) + sigma1 * std::abs(z_dot) +
                                    kSigma2 * std::abs(v)) + 1e-300;
        EXPECT_NEAR(o.z_dot, z_dot, 1e-14 * (std::abs(v) + 1e-300));
        EXPECT_NEAR(o.force, -f_n * (kSigma0 * z + sigma1 * z_dot + kSigma2 * v), 1e-14 * scale);
        EXPECT_NEAR(o.bristle_energy, 0.5 * f_n * kSigma0 * z * z, 1e-15 * o.bristle_energy);
        // D two ways: the power balance −F_T v − F_N σ0 z ż, and the quadratic in
        // s = σ0 z sign(v)/g derived at lugre_friction: F_N |v| (g s² − σ1|v| s + (σ1 + σ2)|v|).
        const double balance = -o.force * v - f_n * kSigma0 * z * o.z_dot;
        const double sv = kSigma0 * z * sgn(v) / g;
        const double quadratic =
            f_n * std::abs(v) * (g * sv * sv - sigma1 * std::abs(v) * sv +
                                 (sigma1 + kSigma2) * std::abs(v));
        EXPECT_NEAR(o.dissipation, balance, 1e-12 * scale * std::abs(v));
        EXPECT_NEAR(o.dissipation, quadratic, 1e-12 * scale * std::abs(v));
      }
      // In steady sliding friction opposes the motion: F_T v < 0.
      if (v != 0.0) {
        EXPECT_LT(lugre_friction(lugre_steady_state_z(v, p), v, f_n, p).force * v, 0.0);
      }
    }
  }
  EXPECT_EQ(friction_law_from_name("lugre"), FrictionLaw::lugre);
  EXPECT_EQ(friction_law_states(FrictionLaw::lugre), 1);
  EXPECT_EQ(friction_law_states(FrictionLaw::coulomb), 0);
  EXPECT_THROW(friction_force(FrictionLaw::lugre, 0.1, 1.0, FrictionParams{}), std::logic_error);
  EXPECT_NO_THROW(check_lugre_params(canudas_1995(kVDamping)));
  LuGreParams bad = canudas_1995();
  bad.v_stribeck = 0.0;
  try {
    check_lugre_params(bad);
    ADD_FAILURE() << "v_stribeck = 0 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("v_stribeck (m/s) must be > 0, got 0"), std::string::npos)
        << e.what();
  }
}

TEST(LuGre, SteadyStateIsTheStribeckCurve) {
  // At constant v, ż = v − σ0|v| z/g relaxes at the rate σ0|v|/g: after 40 time constants
  // (e^−40 ≈ 4e-18) z is z_ss = v g/(σ0|v|) and F_T = −F_N (g(v) sign v + σ2 v) (1995, eq. 5),
  // to 1e-9 relative, with or without Olsson's micro-damping (ż = 0 there).
  const double f_n = 3.7;
  for (double v_d : {0.0, kVDamping}) {
    const LuGreParams p = canudas_1995(v_d);
    for (double v : {-1.0, -0.01, -1e-3, -1e-4, 1e-4, 5e-4, 1e-3, 2e-3, 0.01, 1.0}) {
      const double g = stribeck(v), tau = g / (kSigma0 * std::abs(v));
      const ImposedRun r = run_imposed(p, f_n, 0.0, [v](double) { return v; }, 40 * tau, 100,
                                       1e-12, 1e-20);
      const double z = r.z.back(), z_ss = v * g / (kSigma0 * std::abs(v));
      const double f_ss = -f_n * (g * sgn(v) + kSigma2 * v);
      EXPECT_NEAR(z, z_ss, 1e-9 * std::abs(z_ss)) << "v = " << v;
      EXPECT_NEAR(r.force.back(), f_ss, 1e-9 * std::abs(f_ss)) << "v = " << v;
      EXPECT_NEAR(lugre_steady_state_z(v, p), z_ss, 1e-15 * std::abs(z_ss));
      EXPECT_NEAR(lugre_steady_state_force(v, f_n, p), f_ss, 1e-14 * std::abs(f_ss));
      // Property 1 of the paper: starting from 0, |z| never exceeds μ_s/σ0.
      for (double zi : r.z) EXPECT_LE(std::abs(zi), kMuStatic / kSigma0);
    }
  }
}

TEST(LuGre, CanudasStickSlip) {
  // Canudas de Wit et al. (1995), "Stick–slip motion": the spring loads while the mass sticks,
  // the mass breaks away near F_S = μ_s F_N = 1.5 N, slides on the Stribeck curve and sticks
  // again with the spring force well below F_C. Samples every 1 ms.
  const StickSlipRun r = run_stick_slip(canudas_1995());
  ASSERT_EQ(r.t.size(), static_cast<size_t>(std::lround(kStickSlipEnd / kSampleStep)) + 1);
  const double f_s = kMuStatic * kNormalForce, f_c = kMuDynamic * kNormalForce;
  // Stick: the mass moves at under 1% of the drive speed.
  const auto sticks = stick_phases(r.v, 0.01 * kDriveSpeed);
  // The first stick starts at rest at t = 0; the last may be cut by the end of the run.
  ASSERT_GE(sticks.size(), 4u);
  EXPECT_EQ(sticks.front().first, 0u);
  std::vector<double> slip_starts, peaks, minima;
  for (size_t k = 0; k < sticks.size(); ++k) {
    const auto [a, b] = sticks[k];
    if (b + 1 >= r.t.size()) break;  // cut by the end of the run
    // A stick lasts seconds (≈ 3.5 s: the spring force rises by ≈ 0.7 N at k v_drive).
    EXPECT_GT(r.t[b] - r.t[a], 1.0) << "stick " << k;
    // While stuck the mass creeps by bristle deflections (~1e-5 m), so the spring force rises
    // at k v_drive = 0.2 N/s: to 1e-3 relative.
    EXPECT_NEAR((r.spring[b] - r.spring[a]) / (r.t[b] - r.t[a]), kSpring * kDriveSpeed,
                1e-3 * kSpring * kDriveSpeed)
        << "stick " << k;
    // LuGre has no sharp breakaway: creep accelerates as σ0 z approaches g(v), and the mass
    // passes 1% of the drive speed at 0.99 F_S here. Within 2% of F_S.
    EXPECT_NEAR(r.spring[b], f_s, 0.02 * f_s) << "breakaway " << k;
    slip_starts.push_back(r.t[b + 1]);

    // The slip that follows, up to the next stick (or the end of the run).
    const size_t s0 = b + 1, s1 = k + 1 < sticks.size() ? sticks[k + 1].first : r.t.size();
    size_t i_peak = s0, i_vmax = s0;
    for (size_t i = s0; i < s1; ++i) {
      if (r.spring[i] > r.spring[i_peak]) i_peak = i;
      if (std::abs(r.v[i]) > std::abs(r.v[i_vmax])) i_vmax = i;
    }
    // The spring force peaks (ḟ = k (v_drive − ẋ) = 0) when the mass catches up with the
    // drive, at ≈ F_S: the spring loads on while the mass accelerates. Within 1% of F_S, and
    // ẋ = v_drive to 1e-3 m/s (sampling: |ẍ| ≲ 0.5 m/s², 0.5 ms to the nearest sample).
    EXPECT_NEAR(r.spring[i_peak], f_s, 0.01 * f_s) << "slip " << k;
    EXPECT_NEAR(r.v[i_peak], kDriveSpeed, 1e-3) << "slip " << k;
    peaks.push_back(r.spring[i_peak]);
    // At the fastest slip the bristles (relaxation time g/(σ0|v|) ≈ 3e-5 s) are in steady state:
    // friction is the Stribeck value −F_N (g(v) + σ2 v), to 1e-4 relative; and ẍ = 0 there, so
    // the spring force balances it to 2e-3 N (ẍ at the nearest 1 ms sample).
    const double v_max = r.v[i_vmax];
    EXPECT_GT(v_max, kDriveSpeed) << "slip " << k;
    const double f_ss = -kNormalForce * (stribeck(v_max) + kSigma2 * v_max);
    EXPECT_NEAR(r.force[i_vmax], f_ss, 1e-4 * std::abs(f_ss)) << "slip " << k;
    EXPECT_NEAR(r.spring[i_vmax], -r.force[i_vmax], 2e-3) << "slip " << k;
    if (k + 1 >= sticks.size()) break;
    // Slipping unloads the spring below F_C before the mass sticks again. Lower bound: a
    // Coulomb slider (friction F_C throughout the slip) swings about F_C with amplitude
    // √((F_S − F_C)² + m (k v_drive)²/k), to 0.480 N; the Stribeck and viscous terms only add
    // friction during the slip, so the swing here is smaller.
    double f_min = r.spring[s0];
    for (size_t i = s0; i <= s1 && i < r.t.size(); ++i) f_min = std::min(f_min, r.spring[i]);
    const double coulomb_swing =
        std::sqrt((f_s - f_c) * (f_s - f_c) + kMass * std::pow(kSpring * kDriveSpeed, 2) / kSpring);
    EXPECT_LT(f_min, f_c) << "slip " << k;
    EXPECT_GT(f_min, f_c - coulomb_swing) << "slip " << k;
    minima.push_back(f_min);
  }
  // Repeated stick–slip: at least three full slips within 30 s, on a limit cycle (periods to
  // 0.01 s, i.e. 10 samples, and the peaks and minima to 1e-4 N).
  ASSERT_GE(slip_starts.size(), 4u);
  ASSERT_GE(minima.size(), 3u);
  for (size_t k = 2; k < slip_starts.size(); ++k)
    EXPECT_NEAR(slip_starts[k] - slip_starts[k - 1], slip_starts[1] - slip_starts[0], 0.01);
  for (size_t k = 1; k < peaks.size(); ++k) EXPECT_NEAR(peaks[k], peaks[0], 1e-4);
  for (size_t k = 1; k < minima.size(); ++k) EXPECT_NEAR(minima[k], minima[0], 1e-4);
}

TEST(LuGre, PreslidingHysteresis) {
  // Canudas de Wit et al. (1995), presliding displacement: an imposed x = A sin(ωt) with A well
  // below the breakaway deflection L = μ_s/σ0 = 1.5e-5 m. With |v| ≤ Aω ≪ v_s, g = μ_s to
  // (Aω/v_s)² ≈ 4e-5 and dz/dx = 1 − sign(v) z/L, so each branch is an exponential in x and the
  // closed loop has, with u = A/L (exact, rate-independent part):
  //   turning points z = ±L tanh u, secant stiffness F_N σ0 tanh(u)/u,
  //   bristle hysteresis per cycle ∮ F_N σ0 z dx = 4 F_N σ0 L² (u − tanh u).
  // From z = 0 the first turning point lies on the virgin curve, z = L (1 − e^−u); the loop
  // then closes by e^−2u per half cycle (60 cycles: to ~1e-13 relative).
  constexpr double kAmplitude = 1e-6;     // m
  constexpr double kOmega = 2 * M_PI;     // rad/s
  constexpr int kCycles = 60, kPerCycle = 1000;
  const double f_n = 2.0, L = kMuStatic / kSigma0, u = kAmplitude / L;
  const auto x_of = [&](double t) { return kAmplitude * std::sin(kOmega * t); };
  for (bool bristles_only : {false, true}) {
    LuGreParams p = canudas_1995();
    if (bristles_only) p.sigma1 = p.sigma2 = 0.0;  // the rate-independent part alone
    SCOPED_TRACE(bristles_only ? "sigma1 = sigma2 = 0" : "Canudas 1995");
    const ImposedRun r = run_imposed(
        p, f_n, 0.0, [&](double t) { return kAmplitude * kOmega * std::cos(kOmega * t); },
        kCycles * 2 * M_PI / kOmega, kCycles * kPerCycle, 1e-10, 1e-18);
    const auto up = [&](int c) { return static_cast<size_t>(c * kPerCycle + kPerCycle / 4); };
    const auto down = [&](int c) { return static_cast<size_t>(c * kPerCycle + 3 * kPerCycle / 4); };
    // Virgin curve to the first turning point, 1e-6 relative.
    EXPECT_NEAR(r.z[up(0)], L * (1 - std::exp(-u)), 1e-6 * L * u);
    // After the transient the loop is closed (the last two cycles agree to 1e-6 relative) ...
    const int last = kCycles - 1;
    EXPECT_NEAR(r.z[up(last)], r.z[up(last - 1)], 1e-6 * L * u);
    EXPECT_NEAR(r.z[down(last)], r.z[down(last - 1)], 1e-6 * L * u);
    // ... with its turning points at ±L tanh u (1e-6 relative; the first cycle was 3% off) ...
    EXPECT_NEAR(r.z[up(last)], L * std::tanh(u), 1e-6 * L * u);
    EXPECT_NEAR(r.z[down(last)], -L * std::tanh(u), 1e-6 * L * u);
    // ... and F_T ≈ −F_N σ0 x, a spring: secant stiffness F_N σ0 tanh(u)/u to 1e-6 relative,
    // which is σ0 F_N within 1% (0.15% here); least-squares slope over the cycle within 1%.
    const double k_secant =
        -(r.force[up(last)] - r.force[down(last)]) / (x_of(r.t[up(last)]) - x_of(r.t[down(last)]));
    EXPECT_NEAR(k_secant, f_n * kSigma0 * std::tanh(u) / u, 1e-6 * f_n * kSigma0);
    EXPECT_NEAR(k_secant, f_n * kSigma0, 0.01 * f_n * kSigma0);
    const size_t a = static_cast<size_t>(last * kPerCycle), b = a + kPerCycle;
    double sxx = 0, sxf = 0, area = 0;
    for (size_t i = a; i < b; ++i) {
      const double x = x_of(r.t[i]);
      sxx += x * x;
      sxf += x * r.force[i];
      // Loop area ∮ −F_T dx by the trapezoid rule on the samples.
      area += -0.5 * (r.force[i] + r.force[i + 1]) * (x_of(r.t[i + 1]) - x);
    }
    EXPECT_NEAR(-sxf / sxx, f_n * kSigma0, 0.01 * f_n * kSigma0);
    // Energy dissipated per cycle: the friction work over the closed loop, which is also ∫ D
    // (the bristle energy returns to its value; bookkeeping to 1e-6 relative) and the loop
    // area (trapezoid on 1000 samples, 1e-4 relative); positive.
    const double work = r.work[b] - r.work[a], dissipated = r.dissipated[b] - r.dissipated[a];
    EXPECT_GT(work, 0.0);
    EXPECT_NEAR(dissipated + (r.bristle_energy[b] - r.bristle_energy[a]), work, 1e-6 * work);
    EXPECT_NEAR(area, work, 1e-4 * work);
    const double hysteresis = 4 * f_n * kSigma0 * L * L * (u - std::tanh(u));
    if (bristles_only) {
      // The rate-independent loop, closed form to 1e-4 (g = μ_s to 4e-5 along the branches).
      EXPECT_NEAR(work, hysteresis, 1e-4 * hysteresis);
    } else {
      // Plus the micro-damping and viscous losses, (σ1 + σ2) F_N ∮ v dx = (σ1 + σ2) F_N π A² ω
      // to first order (ż = v (1 − sign(v) σ0 z/g); the O(u) term cancels over the symmetric
      // loop, the O(u²) one is 0.4%): within 1%.
      const double viscous = (kSigma1 + kSigma2) * f_n * M_PI * kAmplitude * kAmplitude * kOmega;
      EXPECT_NEAR(work, hysteresis + viscous, 0.01 * (hysteresis + viscous));
    }
  }
}

TEST(LuGre, PassivityConditionFromTheQuadraticForm) {
  // D = F_N |v| (g s² − σ1(v)|v| s + (σ1(v) + σ2)|v|) with s = σ0 z sign(v)/g, minimal at
  // s* = σ1|v|/(2g) with value F_N v² (σ1 + σ2 − σ1²|v|/(4g)). So |v| σ1(v) ≤ 4 g(v)
  // (kLuGrePassivityFactor) gives D ≥ 0 for every z; beyond |v| = 4 g (σ1 + σ2)/σ1², D < 0 at s*.
  const double f_n = 1.0;
  const LuGreParams constant = canudas_1995();
  int negatives = 0;
  for (double sign : {-1.0, 1.0})
    for (double mag = 1e-6; mag < 3.0; mag *= 1.1) {
      const double v = sign * mag, g = stribeck(v);
      double d_min = INFINITY;
      for (double s = -3.0; s <= 3.0; s += 0.01)
        d_min = std::min(d_min,
                         lugre_friction(s * g * sign / kSigma0, v, f_n, constant).dissipation);
      if (mag * kSigma1 <= kLuGrePassivityFactor * g) {
        EXPECT_GE(d_min, 0.0) << "v = " << v;
      }
      if (mag * kSigma1 * kSigma1 > kLuGrePassivityFactor * g * (kSigma1 + kSigma2)) {
        const double s_star = kSigma1 * mag / (2 * g);
        const double d_star =
            lugre_friction(s_star * g * sign / kSigma0, v, f_n, constant).dissipation;
        const double expected =
            f_n * v * v * (kSigma1 + kSigma2 - kSigma1 * kSigma1 * mag / (4 * g));
        EXPECT_NEAR(d_star, expected, 1e-9 * std::abs(expected)) << "v = " << v;
        EXPECT_LT(d_star, 0.0) << "v = " << v;
        ++negatives;
      }
    }
  EXPECT_GT(negatives, 0);  // constant σ1 is not passive beyond 4 g/σ1 ≈ 0.013 m/s

  // Olsson's σ1(v) = σ1 exp(−(v/v_d)²): |v| exp(−(v/v_d)²) ≤ v_d/√(2e), so every
  // v_d ≤ 4√(2e) min(μ_s, μ_d)/σ1 is passive at all v; the bound is tight when μ_s = μ_d.
  const double limit = lugre_passive_v_damping_limit(constant);
  EXPECT_NEAR(limit, 4 * std::sqrt(2 * std::exp(1.0)) * kMuDynamic / kSigma1, 1e-15);
  EXPECT_NEAR(limit, 0.029493, 1e-6);  // m/s, for Canudas' values
  for (double v_d : {kVDamping, limit}) {
    const LuGreParams olsson = canudas_1995(v_d);
    for (double sign : {-1.0, 1.0})
      for (double mag = 1e-6; mag < 3.0; mag *= 1.1) {
        const double v = sign * mag, g = stribeck(v);
        EXPECT_LE(mag * lugre_micro_damping(v, olsson), kLuGrePassivityFactor * g * (1 + 1e-12));
        for (double s = -3.0; s <= 3.0; s += 0.05)
          EXPECT_GE(lugre_friction(s * g * sign / kSigma0, v, f_n, olsson).dissipation, 0.0)
              << "v_d = " << v_d << " v = " << v << " s = " << s;
      }
  }
  LuGreParams flat = canudas_1995();
  flat.mu_static = flat.mu_dynamic;  // g ≡ μ_d
  flat.v_damping = 1.01 * lugre_passive_v_damping_limit(flat);
  const double v_worst = flat.v_damping / std::sqrt(2.0);
  EXPECT_GT(v_worst * lugre_micro_damping(v_worst, flat), kLuGrePassivityFactor * kMuDynamic);
}

TEST(LuGre, StickSlipEnergyBookkeeping) {
  // Over the stick–slip run, with F_N constant: D ≥ 0 at every right-hand-side evaluation and
  // every sample, ∫D non-decreasing, and E_b(t) − E_b(0) + ∫D = ∫ −F_T v dt (the friction work)
  // to 1e-10 J (1e-5 of the largest bristle energy μ_s² F_N/(2σ0) ≈ 1.1e-5 J; the work is ≈ 2.8 J).
  // With Olsson's micro-damping this is guaranteed (PassivityConditionFromTheQuadraticForm).
  // With Canudas' constant σ1 it holds here too, but only because the breakaway is slow: the mass
  // accelerates at ≲ 0.5 m/s² while the bristles relax in g/(σ0|v|) ≲ 1 ms, so z tracks z_ss
  // and s ≈ 1; a sudden velocity jump breaks it (ConstantMicroDampingCreatesEnergyAfterAJump).
  for (double v_d : {kVDamping, 0.0}) {
    SCOPED_TRACE("v_damping = " + std::to_string(v_d));
    const StickSlipRun r = run_stick_slip(canudas_1995(v_d));
    EXPECT_GE(r.min_rhs_dissipation, 0.0);
    double max_bristle = 0;
    for (size_t i = 0; i < r.t.size(); ++i) {
      EXPECT_GE(r.dissipation[i], 0.0) << "t = " << r.t[i];
      // The quadrature of D ≥ 0 is monotone up to round-off (DOPRI5 has one negative weight).
      if (i > 0) {
        EXPECT_GE(r.dissipated[i] - r.dissipated[i - 1], -1e-15) << "t = " << r.t[i];
      }
      EXPECT_NEAR(r.bristle_energy[i] - r.bristle_energy[0] + r.dissipated[i], r.work[i], 1e-10)
          << "t = " << r.t[i];
      max_bristle = std::max(max_bristle, r.bristle_energy[i]);
    }
    EXPECT_LE(max_bristle, kMuStatic * kMuStatic * kNormalForce / (2 * kSigma0));
    EXPECT_GT(r.work.back(), 2.0);  // J: ≈ 1.1 N over ≈ 2.5 m of slip
  }
}

TEST(LuGre, ConstantMicroDampingCreatesEnergyAfterAJump) {
  // The bristles loaded to stiction, z0 = μ_s/σ0, then the velocity jumps to v = 0.05 m/s (as
  // after an impact in a clearance joint). There g(v) = μ_d, so s = σ0 z/g relaxes from
  // s0 = μ_s/μ_d as e = s − 1 = e0 exp(−t/τ), τ = g/(σ0 v), and
  //   D = F_N v ((g + σ2 v) + (2g − σ1 v) e + g e²),
  //   ∫D = F_N v ((g + σ2 v) t + (2g − σ1 v) e0 τ (1 − e^−t/τ) + g e0² τ/2 (1 − e^−2t/τ)).
  // With constant σ1, 2g − σ1 v < 0 and D < 0 at the jump: the friction hands back more energy
  // than the bristles release, ∫D dips below zero. Olsson's σ1(v) (here σ1(v) ≈ 0) removes it.
  constexpr double kJumpSpeed = 0.05;  // m/s
  const double f_n = 1.0, g = stribeck(kJumpSpeed), z0 = kMuStatic / kSigma0;
  const double tau = g / (kSigma0 * kJumpSpeed), e0 = kMuStatic / g - 1;
  const double t_end = 10 * tau;
  const auto closed_q = [&](double t, double sigma1) {
    const double v = kJumpSpeed;
    return f_n * v *
           ((g + kSigma2 * v) * t + (2 * g - sigma1 * v) * e0 * tau * (1 - std::exp(-t / tau)) +
            g * e0 * e0 * tau / 2 * (1 - std::exp(-2 * t / tau)));
  };
  {
    const ImposedRun r = run_imposed(canudas_1995(), f_n, z0, [](double) { return kJumpSpeed; },
                                     t_end, 1000, 1e-10, 1e-18);
    const double d0 = f_n * kJumpSpeed * ((g + kSigma2 * kJumpSpeed) +
                                          (2 * g - kSigma1 * kJumpSpeed) * e0 + g * e0 * e0);
    EXPECT_LT(d0, 0.0);
    EXPECT_NEAR(r.dissipation[0], d0, 1e-12 * std::abs(d0));  // −0.28 W
    double q_min = 0, w_min = 0;
    for (size_t i = 0; i < r.t.size(); ++i) {
      // ∫D and the bookkeeping, to 1e-6 of the bristle energy E_b(0) = μ_s² F_N/(2σ0).
      const double tol = 1e-6 * r.bristle_energy[0];
      EXPECT_NEAR(r.dissipated[i], closed_q(r.t[i], kSigma1), tol) << "t = " << r.t[i];
      EXPECT_NEAR(r.bristle_energy[i] - r.bristle_energy[0] + r.dissipated[i], r.work[i], tol);
      q_min = std::min(q_min, r.dissipated[i]);
      w_min = std::min(w_min, r.work[i]);
    }
    // Energy created: ∫D reaches ≈ −3.8e-5 J at t ≈ 1.9 τ, and the friction hands the slider
    // more energy than the bristles ever held (E_b(0) ≈ 1.1e-5 J).
    EXPECT_LT(q_min, -3 * r.bristle_energy[0]);
    EXPECT_LT(w_min, -r.bristle_energy[0]);
  }
  {
    const ImposedRun r = run_imposed(canudas_1995(kVDamping), f_n, z0,
                                     [](double) { return kJumpSpeed; }, t_end, 1000, 1e-10, 1e-18);
    EXPECT_GE(r.min_rhs_dissipation, 0.0);
    for (size_t i = 1; i < r.t.size(); ++i) {
      EXPECT_GE(r.dissipation[i], 0.0);
      EXPECT_GE(r.dissipated[i], r.dissipated[i - 1]);
      // σ1(0.05) = σ1 e^−2500 = 0: the closed form with σ1 = 0.
      EXPECT_NEAR(r.dissipated[i], closed_q(r.t[i], 0.0), 1e-6 * r.bristle_energy[0]);
    }
  }
}
