// The variational Lyapunov spectrum's model-free pieces (analysis/lyapunov_spectrum.hpp) on
// flows with known spectra: a damped linear oscillator (exact), the Lorenz system (published
// values, exact sum), and a harmonically forced impact oscillator with restitution, whose
// saltation matrices have det S = e² exactly, so the sum of its exponents is −2ζ + 2 ln(e) ×
// (impacts per unit time). The reference trajectories are integrated by the engine's DOPRI5 and
// the tangent vectors ride on its accepted steps, as the engine's estimate does.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "analysis/dynamics_analysis.hpp"
#include "analysis/lyapunov_spectrum.hpp"
#include "core/integrator.hpp"

namespace lash {
namespace {

/// Integrates `f` from (0, y0) to t_end with DOPRI5 (with optional events handled by `jump`,
/// which changes y and returns D = ∂g/∂y), carrying tangent vectors over every accepted step by
/// RK4 on the dense output, mapping them through events with the saltation matrix and
/// renormalising every `interval` after `t_start`. Returns the spectrum; `impacts` counts
/// events after t_start, `log_det` sums ln|det S| over them.
struct Ride {
  int n = 0;
  FlowRhs f;
  std::function<void(double, const double*, double*)> events;  // one event function or none
  std::function<Eigen::MatrixXd(Eigen::VectorXd&)> jump;
  Eigen::VectorXd grad_h;
  double rtol = 1e-9, atol = 1e-12;
  std::function<Eigen::MatrixXd(double, const Eigen::VectorXd&)> jacobian;  // exact J, optional
  int impacts = 0;
  double log_det = 0.0;

  Eigen::VectorXd run(Eigen::VectorXd y, double t_start, double t_end, double interval) {
    OdeProblem p;
    p.n = n;
    p.n_events = events ? 1 : 0;
    p.rhs = [this](double t, const double* yy, double* dy) {
      Eigen::VectorXd yv = Eigen::Map<const Eigen::VectorXd>(yy, n), d(n);
      if (!f(t, yv, d)) return false;
      Eigen::Map<Eigen::VectorXd>(dy, n) = d;
      return true;
    };
    if (events) p.events = events;
    IntegratorOptions opt;
    opt.rtol = rtol;
    opt.atol = atol;
    auto integ = make_dopri5(p, opt);
    Eigen::VectorXd w = Eigen::VectorXd::Ones(n);
    std::unique_ptr<TangentSpectrum> ts;
    double next = 0.0;
    Eigen::VectorXd yt(n), ft(n);
    TangentMap jv = [&](double t, const Eigen::MatrixXd& V, Eigen::MatrixXd& JV) {
      integ->dense_at(t, yt);
      if (jacobian) {
        JV = jacobian(t, yt) * V;
        return true;
      }
      if (!f(t, yt, ft)) return false;
      return forward_difference_jv(f, t, yt, ft, V, w, 1e-8, JV);
    };
    integ->set_step_hook([&](double t0, double t1) {
      if (!ts) return;
      ASSERT_TRUE(tangent_rk4_step(jv, t0, t1, ts->vectors()));
      if (t1 >= next) {
        ASSERT_TRUE(ts->renormalise(t1));
        next = t1 + interval;
      }
    });
    integ->reset(0.0, y);
    double t = 0.0;
    auto go = [&](double target) {
      while (t < target) {
        const Advance a = integ->advance(target, y);
        EXPECT_NE(a.kind, Advance::failure) << a.message;
        if (a.kind == Advance::failure) return;
        t = a.t;
        if (a.kind == Advance::event) {
          Eigen::VectorXd fm(n), fp(n);
          f(t, y, fm);
          const Eigen::MatrixXd D = jump(y);
          f(t, y, fp);
          const Eigen::MatrixXd S = saltation_matrix(D, fm, fp, grad_h);
          if (ts) {
            ts->vectors() = S * ts->vectors();
            ++impacts;
            log_det += std::log(std::abs(S.determinant()));
          }
          integ->reset(t, y);
        }
      }
    };
    go(t_start);
    ts = std::make_unique<TangentSpectrum>(Eigen::MatrixXd::Identity(n, n), w, t_start);
    next = t_start + interval;
    go(t_end);
    ts->renormalise(t);
    return ts->exponents();
  }
};

TEST(LyapunovSpectrum, DampedOscillatorUnderdampedBothMinusZetaOmega) {
  // x'' + 2ζω x' + ω² x = 0, ζ < 1: both exponents −ζω (the eigenvalues' real part).
  const double zeta = 0.1, omega = 2.0;
  Ride r;
  r.n = 2;
  r.f = [&](double, const Eigen::VectorXd& y, Eigen::VectorXd& d) {
    d << y[1], -2 * zeta * omega * y[1] - omega * omega * y[0];
    return true;
  };
  // The exact Jacobian here (the other flows use forward differences).
  r.jacobian = [&](double, const Eigen::VectorXd&) {
    Eigen::MatrixXd J(2, 2);
    J << 0, 1, -omega * omega, -2 * zeta * omega;
    return J;
  };
  // The trajectory decays as e^{−ζωt}: an absolute tolerance far below it keeps the steps
  // accuracy-limited (at the stability limit, where a tiny state lets them grow, DOPRI5 and the
  // tangent vectors' RK4 damp differently).
  Eigen::VectorXd y0(2);
  y0 << 1.0, 1.0;
  r.atol = 1e-40;
  const Eigen::VectorXd l = r.run(y0, 0.0, 200.0, 0.5);
  // The bounded oscillation of the tangent vectors' lengths is ln(cond) / T ≈ 0.005 here.
  EXPECT_NEAR(l[0], -zeta * omega, 0.01);
  EXPECT_NEAR(l[1], -zeta * omega, 0.01);
  // The sum is the trace −2ζω for any T (Liouville), up to the error of the tangent RK4 on
  // DOPRI5's steps (measured 3e-5).
  EXPECT_NEAR(l.sum(), -2 * zeta * omega, 1e-4);
}

TEST(LyapunovSpectrum, DampedOscillatorOverdampedRealEigenvalues) {
  // ζ > 1: exponents −ζω ± ω√(ζ²−1).
  const double zeta = 2.0, omega = 2.0;
  Ride r;
  r.n = 2;
  r.f = [&](double, const Eigen::VectorXd& y, Eigen::VectorXd& d) {
    d << y[1], -2 * zeta * omega * y[1] - omega * omega * y[0];
    return true;
  };
  // The trajectory decays to the origin at e^{−0.54 t}: a tiny absolute tolerance keeps the
  // steps accuracy-limited (above).
  Eigen::VectorXd y0(2);
  y0 << 1.0, 1.0;
  r.atol = 1e-30;
  const Eigen::VectorXd l = r.run(y0, 0.0, 60.0, 0.25);
  const double s = omega * std::sqrt(zeta * zeta - 1);
  EXPECT_NEAR(l[0], -zeta * omega + s, 0.02 * std::abs(-zeta * omega + s));
  EXPECT_NEAR(l[1], -zeta * omega - s, 0.02 * std::abs(-zeta * omega - s));
}

TEST(LyapunovSpectrum, LorenzPublishedSpectrumAndExactSum) {
  // σ = 10, ρ = 28, β = 8/3: λ ≈ 0.9056, 0, −14.5723 (Sprott, Chaos and Time-Series Analysis,
  // 2003); the sum is −(σ + 1 + β) exactly (constant divergence). Forward-difference J·V.
  const double sg = 10, rho = 28, beta = 8.0 / 3.0;
  Ride r;
  r.n = 3;
  r.f = [&](double, const Eigen::VectorXd& y, Eigen::VectorXd& d) {
    d << sg * (y[1] - y[0]), y[0] * (rho - y[2]) - y[1], y[0] * y[1] - beta * y[2];
    return true;
  };
  Eigen::VectorXd y0(3);
  y0 << 1.0, 1.0, 20.0;
  const Eigen::VectorXd l = r.run(y0, 20.0, 1020.0, 0.1);
  // Finite-time estimates over 1000 time units scatter by about ±0.01 (largest).
  EXPECT_NEAR(l[0], 0.9056, 0.03);
  EXPECT_NEAR(l[1], 0.0, 0.02);
  EXPECT_NEAR(l[2], -14.5723, 0.05);
  EXPECT_NEAR(l.sum(), -(sg + 1 + beta), 1e-4);
}

/// Forced impact oscillator: x'' + 2ζx' + x = a cos θ, θ' = ω, a rigid stop at x = d with
/// Newton's restitution v⁺ = −e v⁻. State (x, v, θ); event h = x − d rising.
struct ImpactOscillator {
  // Chaotic at these values: λ₁ ≈ 0.167 variational, 0.163 two-trajectory (measured here).
  double zeta = 0.05, a = 1.0, omega = 2.8, d = 0.0, e = 0.8;
  Ride ride() const {
    Ride r;
    r.n = 3;
    r.f = [*this](double, const Eigen::VectorXd& y, Eigen::VectorXd& dy) {
      dy << y[1], -2 * zeta * y[1] - y[0] + a * std::cos(y[2]), omega;
      return true;
    };
    r.events = [*this](double, const double* y, double* g) { g[0] = y[0] - d; };
    r.jump = [*this](Eigen::VectorXd& y) {
      y[1] = -e * y[1];
      Eigen::MatrixXd D = Eigen::MatrixXd::Identity(3, 3);
      D(1, 1) = -e;
      return D;
    };
    r.grad_h = Eigen::Vector3d(1, 0, 0);
    return r;
  }
};

TEST(LyapunovSpectrum, SaltationDeterminantOfRestitutionIsESquared) {
  // S = D + (f⁺ − D f⁻)∇hᵀ/(∇hᵀ f⁻): for the impact oscillator det S = e² whatever the state.
  const ImpactOscillator io;
  Ride r = io.ride();
  Eigen::VectorXd y(3), fm(3), fp(3);
  y << io.d, 0.7, 1.3;
  r.f(0, y, fm);
  const Eigen::MatrixXd D = r.jump(y);
  r.f(0, y, fp);
  const Eigen::MatrixXd S = saltation_matrix(D, fm, fp, r.grad_h);
  EXPECT_NEAR(S.determinant(), io.e * io.e, 1e-12);
  // A perturbation along the flow maps to the flow after the jump: S f⁻ = f⁺.
  EXPECT_LT((S * fm - fp).norm(), 1e-12);
  EXPECT_THROW(saltation_matrix(D, Eigen::Vector3d(0, 1, 1), fp, r.grad_h), std::invalid_argument);
}

TEST(LyapunovSpectrum, ImpactOscillatorSumRuleAndTwoTrajectoryAgreement) {
  // Sum rule: Σλ = ⟨tr ∂f/∂y⟩ + Σ ln|det S| / T = −2ζ + 2 ln(e) N / T.
  const ImpactOscillator io;
  Ride r = io.ride();
  Eigen::VectorXd y0(3);
  y0 << 0.0, 0.0, 0.0;
  const double t0 = 100.0, t1 = 1100.0;
  const Eigen::VectorXd l = r.run(y0, t0, t1, 0.5);
  ASSERT_GT(r.impacts, 100);
  const double expected = -2 * io.zeta + 2 * std::log(io.e) * r.impacts / (t1 - t0);
  EXPECT_NEAR(r.log_det, 2 * std::log(io.e) * r.impacts, 1e-9 * r.impacts);
  EXPECT_NEAR(l.sum(), expected, 2e-4);
  // The phase direction (the flow itself) has exponent 0.
  double smallest = 1e300;
  for (int i = 0; i < 3; ++i) smallest = std::min(smallest, std::abs(l[i]));
  EXPECT_LT(smallest, 5e-3);

  // Two trajectories with renormalisation (Benettin's original method) from the same state
  // after the transient: the largest exponent agrees within 10% (or 0.01 near 0).
  Ride r0 = io.ride();
  Eigen::VectorXd ys = y0;
  {
    // The state at t0: run the reference alone.
    OdeProblem p;
    p.n = 3;
    p.n_events = 1;
    p.rhs = [&](double t, const double* yy, double* dy) {
      Eigen::VectorXd yv = Eigen::Map<const Eigen::VectorXd>(yy, 3), d(3);
      r0.f(t, yv, d);
      Eigen::Map<Eigen::VectorXd>(dy, 3) = d;
      return true;
    };
    p.events = r0.events;
    IntegratorOptions opt{1e-10, 1e-12};
    auto make = [&]() { return make_dopri5(p, opt); };
    auto flow_to = [&](std::unique_ptr<Integrator>& in, Eigen::VectorXd& y, double ta, double tb) {
      in->reset(ta, y);
      double t = ta;
      while (t < tb) {
        const Advance a = in->advance(tb, y);
        if (a.kind == Advance::failure) return false;
        t = a.t;
        if (a.kind == Advance::event) {
          r0.jump(y);
          in->reset(t, y);
        }
      }
      return true;
    };
    auto i0 = make(), i1 = make();
    ASSERT_TRUE(flow_to(i0, ys, 0.0, t0));
    auto flow = [&](int which, Eigen::VectorXd& y, double ta, double tb) {
      return flow_to(which == 0 ? i0 : i1, y, ta + t0, tb + t0);
    };
    auto norm = [](const Eigen::VectorXd& a, const Eigen::VectorXd& b) { return (a - b).norm(); };
    LyapunovOptions lo;
    lo.d0 = 1e-7;
    lo.interval = 0.5;
    lo.intervals = static_cast<int>((t1 - t0) / lo.interval);
    const LyapunovResult two = largest_lyapunov(flow, ys, norm, lo);
    ASSERT_TRUE(two.ok) << two.message;
    // The measured values, in the XML output (--gtest_output=xml).
    RecordProperty("variational_l1", std::to_string(l.maxCoeff()));
    RecordProperty("two_trajectory", std::to_string(two.exponent));
    RecordProperty("sum", std::to_string(l.sum()));
    RecordProperty("sum_rule", std::to_string(expected));
    EXPECT_NEAR(two.exponent, l.maxCoeff(), std::max(0.1 * std::abs(l.maxCoeff()), 0.01))
        << "variational " << l.transpose() << ", two-trajectory " << two.exponent;
  }
}

TEST(LyapunovSpectrum, CollapsedVectorsAreRefused) {
  Eigen::MatrixXd V(2, 2);
  V << 1, 2, 1, 2;
  EXPECT_THROW(TangentSpectrum(V, Eigen::VectorXd::Ones(2), 0.0), std::invalid_argument);
  TangentSpectrum ts(Eigen::MatrixXd::Identity(2, 2), Eigen::VectorXd::Ones(2), 0.0);
  ts.vectors().col(1).setZero();
  EXPECT_FALSE(ts.renormalise(1.0));
  EXPECT_EQ(ts.renormalisations(), 0);
}

}  // namespace
}  // namespace lash
