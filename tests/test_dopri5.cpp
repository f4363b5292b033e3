// The integrators on problems with known solutions: convergence order, dense output, events.
#include <gtest/gtest.h>

#include <cmath>

#include "core/integrator.hpp"

using namespace lash;

namespace {

// y' = −1e9 (y − cos t): stiff; y follows cos t within 1e-9. DOPRI5's stability bound holds
// its step near 3.3e-9 s.
OdeProblem stiff_problem() {
  OdeProblem p;
  p.n = 1;
  p.rhs = [](double t, const double* y, double* dy) {
    dy[0] = -1e9 * (y[0] - std::cos(t));
    return true;
  };
  return p;
}

// y'' = −y: y = cos t.
OdeProblem oscillator() {
  OdeProblem p;
  p.n = 2;
  p.rhs = [](double, const double* y, double* dy) {
    dy[0] = y[1];
    dy[1] = -y[0];
    return true;
  };
  return p;
}

// Max error |y − (cos t, −sin t)| over outputs every 0.37 s to t = 10, stepping at fixed h.
double fixed_step_error(std::unique_ptr<Integrator> (*make)(OdeProblem, IntegratorOptions),
                        double h) {
  IntegratorOptions o;
  o.rtol = 1e10;  // never reject: the step is max_step
  o.atol = 1e10;
  o.max_step = h;
  auto integ = make(oscillator(), o);
  Eigen::VectorXd y(2);
  y << 1, 0;
  integ->reset(0, y);
  double err = 0;
  for (double t = 0.37; t <= 10; t += 0.37) {
    const Advance a = integ->advance(t, y);
    EXPECT_EQ(a.kind, Advance::reached);
    err = std::max(err, std::hypot(y[0] - std::cos(t), y[1] + std::sin(t)));
  }
  return err;
}

}  // namespace

TEST(Dopri5, FifthOrderConvergenceThroughDenseOutput) {
  // Outputs fall between steps, so this measures the dense output as well (4th-order
  // interpolant, local error O(h⁵)): the observed global order must be 4 to 5.
  const double e1 = fixed_step_error(make_dopri5, 0.1), e2 = fixed_step_error(make_dopri5, 0.05);
  const double order = std::log2(e1 / e2);
  EXPECT_GT(order, 3.5) << e1 << " " << e2;
  EXPECT_LT(order, 5.5) << e1 << " " << e2;
  EXPECT_LT(e2, 1e-6);
}

TEST(Dopri5, StepEndpointsAreFifthOrder) {
  // Outputs exactly on the step grid (h = 0.1, output every 0.5): order 5 within 0.5.
  auto err_at = [](double h) {
    IntegratorOptions o;
    o.rtol = o.atol = 1e10;
    o.max_step = h;
    o.first_step = h;
    auto integ = make_dopri5(oscillator(), o);
    Eigen::VectorXd y(2);
    y << 1, 0;
    integ->reset(0, y);
    integ->advance(5.0, y);
    return std::hypot(y[0] - std::cos(5.0), y[1] + std::sin(5.0));  // amplitude and phase
  };
  const double order = std::log2(err_at(0.1) / err_at(0.05));
  EXPECT_NEAR(order, 5.0, 0.5);
}

TEST(Dopri5, AdaptiveToleranceIsMet) {
  IntegratorOptions o;
  o.rtol = 1e-9;
  o.atol = 1e-12;
  auto integ = make_dopri5(oscillator(), o);
  Eigen::VectorXd y(2);
  y << 1, 0;
  integ->reset(0, y);
  integ->advance(20.0, y);
  EXPECT_NEAR(y[0], std::cos(20.0), 1e-7);
  EXPECT_GT(integ->stats().steps, 10);
}

namespace {
// A ball dropped from 1 m: event when height falls through zero (g = −height rising).
OdeProblem falling_ball() {
  OdeProblem p;
  p.n = 2;
  p.n_events = 1;
  p.rhs = [](double, const double* y, double* dy) {
    dy[0] = y[1];
    dy[1] = -9.81;
    return true;
  };
  p.events = [](double, const double* y, double* g) { g[0] = -y[0]; };
  return p;
}

void check_event(std::unique_ptr<Integrator> integ, double tol) {
  Eigen::VectorXd y(2);
  y << 1, 0;
  integ->reset(0, y);
  const Advance a = integ->advance(2.0, y);
  ASSERT_EQ(a.kind, Advance::event);
  EXPECT_NEAR(a.t, std::sqrt(2 / 9.81), tol);
  EXPECT_LE(y[0], 0.0);  // returned just past the crossing
  EXPECT_NEAR(y[1], -std::sqrt(2 * 9.81), 1e3 * tol);
}
}  // namespace

TEST(Dopri5, LocatesEventOnDenseOutput) {
  IntegratorOptions o;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  check_event(make_dopri5(falling_ball(), o), 1e-9);
}

TEST(CvodeBdf, OscillatorAndEvent) {
  IntegratorOptions o;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  auto integ = make_cvode_bdf(oscillator(), o);
  Eigen::VectorXd y(2);
  y << 1, 0;
  integ->reset(0, y);
  integ->advance(3.0, y);
  EXPECT_NEAR(y[0], std::cos(3.0), 1e-6);
  check_event(make_cvode_bdf(falling_ball(), o), 1e-7);
}

TEST(Dopri5, ReportsStepUnderflowInsteadOfHanging) {
  // y' = 1/(1 − t) blows up at t = 1.
  OdeProblem p;
  p.n = 1;
  p.rhs = [](double t, const double*, double* dy) {
    dy[0] = 1.0 / (1.0 - t);
    return std::isfinite(dy[0]) && t < 1.0;
  };
  IntegratorOptions o;
  auto integ = make_dopri5(p, o);
  Eigen::VectorXd y(1);
  y << 0;
  integ->reset(0, y);
  const Advance a = integ->advance(2.0, y);
  EXPECT_EQ(a.kind, Advance::failure);
  EXPECT_NEAR(a.t, 1.0, 1e-3);
  EXPECT_FALSE(a.message.empty());
}

TEST(Failure, ARightHandSideThatKeepsFailingStopsBothIntegratorsInBoundedTime) {
  // The oscillator whose right-hand side cannot be evaluated past t = 0.5 (as a constraint
  // system that no regularisation can factor): both integrators return a failure near 0.5,
  // after a bounded number of evaluations, with a message saying why.
  for (auto make : {&make_dopri5, &make_cvode_bdf}) {
    OdeProblem p = oscillator();
    long calls = 0;
    const auto f = p.rhs;
    p.rhs = [&calls, f](double t, const double* y, double* dy) {
      ++calls;
      return t <= 0.5 && f(t, y, dy);
    };
    IntegratorOptions o;
    o.rtol = 1e-8;
    o.atol = 1e-10;
    auto integ = make(p, o);
    SCOPED_TRACE(integ->name());
    Eigen::VectorXd y(2);
    y << 1, 0;
    integ->reset(0, y);
    const Advance a = integ->advance(2.0, y);
    ASSERT_EQ(a.kind, Advance::failure);
    EXPECT_NEAR(a.t, 0.5, 0.05);
    EXPECT_LT(calls, 5000);
    if (std::string(integ->name()) == "dopri5") {
      // The step size in exponent form: "h = 1.234e-16 s".
      EXPECT_NE(a.message.find("step size underflow (h = "), std::string::npos) << a.message;
      EXPECT_NE(a.message.find("e-"), std::string::npos) << a.message;
    } else {
      EXPECT_NE(a.message.find("right-hand side failed 60 times"), std::string::npos) << a.message;
    }
  }
}

TEST(Dopri5, EventFunctionsAreEvaluatedOncePerCheckedPointNotOncePerFunction) {
  // 20 event functions that never cross zero, on the oscillator at fixed steps: each accepted
  // step checks them at its end and three interior points of the dense output, and each
  // evaluation gives all 20 at once. Evaluating them anew for every function (61 evaluations a
  // step here) made the cost grow with the square of the number of clearance joints.
  OdeProblem p = oscillator();
  p.n_events = 20;
  long calls = 0;
  p.events = [&](double, const double* y, double* g) {
    ++calls;
    for (int k = 0; k < 20; ++k) g[k] = -1.0 - k - y[0] * y[0];
  };
  IntegratorOptions o;
  o.rtol = o.atol = 1e10;
  o.max_step = 0.1;
  auto integ = make_dopri5(p, o);
  Eigen::VectorXd y(2);
  y << 1, 0;
  integ->reset(0, y);
  ASSERT_EQ(integ->advance(10.0, y).kind, Advance::reached);
  const long steps = integ->stats().steps;
  EXPECT_GE(steps, 100);
  EXPECT_LE(calls, 4 * steps + 1) << calls << " evaluations for " << steps << " steps";
  EXPECT_NEAR(y[0], std::cos(10.0), 1e-5);
}

TEST(Failure, APaceThatCannotReachTheEndStopsAtOnceNotAfterTheStepBudget) {
  // y' = -1e9 (y - cos t) is stiff: DOPRI5's stability bound holds its step near 3e-9 s, so
  // t = 1 s would take about 3e8 steps, beyond max_steps (5e7). It crept through the whole
  // budget first (minutes); now it stops after one window of 100 000 steps, saying why. BDF
  // takes the same problem in large steps.
  const OdeProblem p = stiff_problem();
  for (auto make : {&make_dopri5, &make_cvode_bdf}) {
    IntegratorOptions o;
    o.rtol = 1e-6;
    o.atol = 1e-9;
    auto integ = make(p, o);
    SCOPED_TRACE(integ->name());
    Eigen::VectorXd y(1);
    y << 1.0;
    integ->reset(0, y);
    const Advance a = integ->advance(1.0, y);
    if (std::string(integ->name()) == "dopri5") {
      ASSERT_EQ(a.kind, Advance::failure);
      EXPECT_NE(a.message.find("stalled: the last 100000 steps advanced t by "), std::string::npos)
          << a.message;
      EXPECT_NE(a.message.find("than the 49900000 that solver.max_steps leaves"),
                std::string::npos) << a.message;
      EXPECT_EQ(integ->stats().steps, 100000);
      EXPECT_LT(a.t, 1e-3);
    } else {
      ASSERT_EQ(a.kind, Advance::reached) << a.message;
      EXPECT_NEAR(y[0], std::cos(1.0), 1e-5);
      EXPECT_LT(integ->stats().steps, 10000);
    }
  }
}

TEST(Failure, AStallIsMeasuredAgainstTheRunsEnd) {
  // The same stiff problem with a budget of 2e6 steps: t = 1e-3 s takes about 3e5 and is
  // reached when the integrator knows no other goal; told that the run ends at 1 s (3e8 steps
  // away at that pace), it stops after its first window.
  const OdeProblem p = stiff_problem();
  for (const double end : {0.0, 1.0}) {
    IntegratorOptions o;
    o.rtol = 1e-6;
    o.atol = 1e-9;
    o.max_steps = 2'000'000;
    o.end_time = end;
    auto integ = make_dopri5(p, o);
    Eigen::VectorXd y(1);
    y << 1.0;
    integ->reset(0, y);
    const Advance a = integ->advance(1e-3, y);
    if (end == 0.0) {
      EXPECT_EQ(a.kind, Advance::reached) << a.message;
      EXPECT_GT(integ->stats().steps, 200000);
    } else {
      ASSERT_EQ(a.kind, Advance::failure);
      EXPECT_NE(a.message.find("at either pace t = 1 s is more steps away"), std::string::npos)
          << a.message;
      EXPECT_EQ(integ->stats().steps, 100000);
    }
  }
}

TEST(EndTime, NoStageIsEvaluatedPastTheRunsEnd) {
  // A model need not be defined past its end_time (a load of sqrt(1 − time) with end_time
  // 0.9999 s): the last step overshot it and the run failed at t = 1.00005 s, losing the rows
  // before. Now the step that would pass end_time ends on it, under both integrators, and the
  // value there is as accurate as anywhere.
  for (auto make : {&make_dopri5, &make_cvode_bdf}) {
    double latest = 0.0;
    OdeProblem p = oscillator();
    const auto rhs = p.rhs;
    p.rhs = [&](double t, const double* y, double* dy) {
      latest = std::max(latest, t);
      return rhs(t, y, dy);
    };
    IntegratorOptions o;
    o.rtol = 1e-9;
    o.atol = 1e-12;
    o.end_time = 0.9999;
    auto integ = make(p, o);
    SCOPED_TRACE(integ->name());
    integ->set_step_hook([](double, double) {});
    Eigen::VectorXd y(2);
    y << 1.0, 0.0;
    integ->reset(0, y);
    for (int k = 1; k <= 10; ++k) {
      const Advance a = integ->advance(std::min(0.1 * k, o.end_time), y);
      ASSERT_EQ(a.kind, Advance::reached) << a.message;
    }
    EXPECT_LE(latest, o.end_time);
    EXPECT_NEAR(y[0], std::cos(o.end_time), 1e-7);
    // A caller going on past end_time gets there (BDF without a step hook returned "reached"
    // at its stop time, end_time).
    auto plain = make(oscillator(), o);
    y << 1.0, 0.0;
    plain->reset(0, y);
    const Advance past = plain->advance(1.5, y);
    ASSERT_EQ(past.kind, Advance::reached) << past.message;
    EXPECT_EQ(past.t, 1.5);
    EXPECT_NEAR(y[0], std::cos(1.5), 1e-6);
  }
  // The last step never exceeds max_step to reach end_time (it ended 1 % past it).
  IntegratorOptions o;
  o.max_step = 0.1;
  o.end_time = 0.1005;
  double widest = 0.0;
  auto integ = make_dopri5(oscillator(), o);
  integ->set_step_hook([&](double t0, double t1) { widest = std::max(widest, t1 - t0); });
  Eigen::VectorXd y(2);
  y << 1.0, 0.0;
  integ->reset(0, y);
  ASSERT_EQ(integ->advance(o.end_time, y).kind, Advance::reached);
  EXPECT_LE(widest, 0.1);
}

TEST(Failure, BdfMaxStepsCountsTheWholeRun) {
  // y' = cos(1e6 t): BDF resolves each period (6.3e-6 s) in tens of steps, about 1e7 steps a
  // second. With a budget of 2e5 steps and outputs every 1e-3 s (a few thousand steps each),
  // every output interval is within the budget; counted per interval, as before, the run to
  // t = 1 s went on for its 1e7 steps (a load of 1e3 sin(1e9 t) took hours). Counted over the
  // run, the pace after the first window (2e4 steps) already puts t = 1 s out of reach.
  OdeProblem p;
  p.n = 1;
  p.rhs = [](double t, const double*, double* dy) {
    dy[0] = std::cos(1e6 * t);
    return true;
  };
  IntegratorOptions o;
  o.rtol = 1e-6;
  o.atol = 1e-9;
  o.max_steps = 200'000;
  o.end_time = 1.0;
  auto integ = make_cvode_bdf(p, o);
  integ->set_step_hook([](double, double) {});
  Eigen::VectorXd y(1);
  y << 0.0;
  integ->reset(0, y);
  Advance a;
  int outputs = 0;
  for (int k = 1; k <= 1000; ++k) {
    a = integ->advance(k * 1e-3, y);
    if (a.kind != Advance::reached) break;
    ++outputs;
  }
  ASSERT_EQ(a.kind, Advance::failure) << "reached t = 1 s in " << integ->stats().steps << " steps";
  EXPECT_NE(a.message.find("stalled: the last 20000 steps advanced t by "), std::string::npos)
      << a.message;
  EXPECT_NE(a.message.find("at either pace t = 1 s is more steps away"), std::string::npos)
      << a.message;
  EXPECT_LE(integ->stats().steps, 20000);
  EXPECT_GE(outputs, 1);  // a single output interval is within the budget
  // Without a step hook (CVODE's normal mode) the budget is the whole run's too: what one
  // call may take is what is left.
  auto plain = make_cvode_bdf(p, o);
  y << 0.0;
  plain->reset(0, y);
  bool failed = false;
  for (int k = 1; k <= 1000 && !failed; ++k)
    failed = plain->advance(k * 1e-3, y).kind == Advance::failure;
  EXPECT_TRUE(failed);
  EXPECT_LE(plain->stats().steps, 200000 + 10);
}

TEST(Failure, BdfCreepingAtADiscontinuityStopsAsStalled) {
  // y' = -sign(y) chatters about y = 0 once it gets there (t = 1): CVODE's steps shrink to the
  // absolute tolerance and it crept on toward t = 2 until max_steps. One-step mode (a step hook,
  // as every simulation has) measures the pace in windows of max_steps / 10 steps; once the
  // pace since t = 0 too puts t = 2 beyond the steps left (past half the budget), it stops.
  OdeProblem p;
  p.n = 1;
  p.rhs = [](double, const double* y, double* dy) {
    dy[0] = y[0] > 0 ? -1.0 : 1.0;
    return true;
  };
  IntegratorOptions o;
  o.rtol = 1e-8;
  o.atol = 1e-12;
  o.max_steps = 20'000;
  auto integ = make_cvode_bdf(p, o);
  integ->set_step_hook([](double, double) {});
  Eigen::VectorXd y(1);
  y << 1.0;
  integ->reset(0, y);
  const Advance a = integ->advance(2.0, y);
  ASSERT_EQ(a.kind, Advance::failure);
  EXPECT_NE(a.message.find("stalled: the last 2000 steps advanced t by "), std::string::npos)
      << a.message;
  EXPECT_NEAR(a.t, 1.0, 0.01);
  EXPECT_NE(a.message.find("and all 12000 since t = 0 s"), std::string::npos) << a.message;
}
