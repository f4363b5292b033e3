// Model-file expressions: muparser with the Adams functions, and their time derivatives.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include "core/adams_functions.hpp"
#include "core/expression.hpp"

using namespace lash;

TEST(Expression, AdamsFunctionsAndTime) {
  ExpressionVariables v;
  Expression e("step5(time, 0, 0, 0.085, 0.230)", v);
  v.time = 0.03;
  EXPECT_DOUBLE_EQ(e.eval(), step5(0.03, 0, 0, 0.085, 0.230));
  Expression upper("STEP(t, 0, 0, 1, 2) + IMPACT(0.5, 0, 1, 10, 1, 0, 0.1)", v);
  v.time = 0.5;
  EXPECT_DOUBLE_EQ(upper.eval(), 1.0 + 5.0);
  EXPECT_FALSE(e.depends_on_state());
}

TEST(Expression, BodyStateVariables) {
  ExpressionVariables v;
  v.body_names = {"crank", "slider"};
  Expression e("-100*slider.vx + crank.phi", v);
  EXPECT_TRUE(e.depends_on_state());
  v.body_state[6 * 1 + 3] = 0.5;  // slider.vx
  v.body_state[2] = 0.25;         // crank.phi
  EXPECT_DOUBLE_EQ(e.eval(), -50.0 + 0.25);
}

namespace {
// f, ḟ, f̈ of `text` at time t, differentiated exactly.
std::array<double, 3> derivatives(const std::string& text, double t) {
  ExpressionVariables v;
  Expression e(text, v, 2);
  std::array<double, 3> out;
  e.eval_derivatives(t, out.data());
  return out;
}
// Agreement to `rel` relative to the closed form (absolute below 1).
void expect_derivatives(const std::string& text, double t, double f, double fd, double fdd,
                        double rel = 1e-12) {
  const auto got = derivatives(text, t);
  const double want[3] = {f, fd, fdd};
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(got[k], want[k], rel * std::max(1.0, std::abs(want[k])))
        << "d^" << k << "/dt^" << k << " of '" << text << "' at t = " << t;
}
}  // namespace

TEST(ExpressionDerivatives, SineExactNotFiniteDifferences) {
  // 5-point differences (h = 1e-5 s) were limited by round-off, ~10ε|f|/h² in f̈ (the old test
  // allowed 1e-3); the symbolic derivatives are exact up to rounding.
  const double t = 0.013, a = 50 * t;
  expect_derivatives("0.1*sin(50*time)", t, 0.1 * std::sin(a), 5.0 * std::cos(a),
                     -250.0 * std::sin(a));
  expect_derivatives("0.5*sin(20*t)", 0.3, 0.5 * std::sin(6.0), 10 * std::cos(6.0), -200 * std::sin(6.0));
  // cos, tan and a constant phase with pi.
  expect_derivatives("cos(pi*t + 0.2)", 0.7, std::cos(M_PI * 0.7 + 0.2),
                     -M_PI * std::sin(M_PI * 0.7 + 0.2), -M_PI * M_PI * std::cos(M_PI * 0.7 + 0.2));
  const double c = std::cos(0.4);
  expect_derivatives("tan(2*t)", 0.2, std::tan(0.4), 2 / (c * c),
                     8 * std::tan(0.4) / (c * c));
}

TEST(ExpressionDerivatives, Polynomials) {
  for (double t : {-1.3, 0.0, 0.25, 2.0}) {
    expect_derivatives("3*t^4 - 2*t^3 + t - 7", t, 3 * std::pow(t, 4) - 2 * t * t * t + t - 7,
                       12 * t * t * t - 6 * t * t + 1, 36 * t * t - 12 * t);
    expect_derivatives("t^2", t, t * t, 2 * t, 2);  // also at t = 0 (no 0·∞)
    expect_derivatives("(1 + 2*t)^3", t, std::pow(1 + 2 * t, 3), 6 * std::pow(1 + 2 * t, 2),
                       24 * (1 + 2 * t));
  }
  // Precedence as muparser reads it: -t^2 is −(t²); t/2/4 is t/8.
  expect_derivatives("-t^2 + t/2/4", 0.5, -0.25 + 0.0625, -1 + 0.125, -2);
}

TEST(ExpressionDerivatives, ExponentialLogarithmAndRoots) {
  const double t = 0.4, e = std::exp(-3 * t);
  expect_derivatives("2*exp(-3*time)", t, 2 * e, -6 * e, 18 * e);
  expect_derivatives("ln(1 + t) + log(2*t)", t, std::log(1.4) + std::log(0.8), 1 / 1.4 + 1 / t,
                     -1 / (1.4 * 1.4) - 1 / (t * t));
  expect_derivatives("log10(t)", t, std::log10(t), 1 / (t * std::log(10.0)),
                     -1 / (t * t * std::log(10.0)));
  expect_derivatives("sqrt(1 + t)", t, std::sqrt(1.4), 0.5 / std::sqrt(1.4),
                     -0.25 / std::pow(1.4, 1.5));
  expect_derivatives("atan2(t, 1)", t, std::atan(t), 1 / (1 + t * t),
                     -2 * t / ((1 + t * t) * (1 + t * t)));
}

TEST(ExpressionDerivatives, Step5InsideAndAtTheEdgesOfItsRamp) {
  // step5(time, 0.1, 1, 0.3, 3): 1 + 2 S(Δ), Δ = (t − 0.1)/0.2, S = Δ³(10 − 15Δ + 6Δ²).
  const std::string text = "step5(time, 0.1, 1, 0.3, 3)";
  auto closed = [](double t) {
    const double d = (t - 0.1) / 0.2;
    return std::array<double, 3>{1 + 2 * d * d * d * (10 - 15 * d + 6 * d * d),
                                 2 * 30 * d * d * (1 - d) * (1 - d) / 0.2,
                                 2 * 60 * d * (1 - d) * (1 - 2 * d) / 0.04};
  };
  for (double t : {0.1 + 1e-9, 0.13, 0.2, 0.27, 0.3 - 1e-9}) {
    const auto c = closed(t);
    expect_derivatives(text, t, c[0], c[1], c[2]);
  }
  // At and beyond the edges: level, slope and curvature are continuous (C²): 1 or 3, 0, 0.
  for (double t : {0.0, 0.1, 0.3, 0.5})
    expect_derivatives(text, t, t <= 0.1 ? 1.0 : 3.0, 0.0, 0.0, 0.0);
}

TEST(ExpressionDerivatives, StepInsideAndAtTheEdgesOfItsRamp) {
  // step(t, 0, 0, 2, 1) = 0.75t² − 0.25t³; the cubic's f̈ jumps at the edges (1.5 to 0 and
  // −1.5 to 0) and takes the value outside there, like step() itself.
  for (double t : {1e-9, 0.5, 1.0, 1.7, 2 - 1e-9})
    expect_derivatives("step(t, 0, 0, 2, 1)", t, 0.75 * t * t - 0.25 * t * t * t,
                       1.5 * t - 0.75 * t * t, 1.5 - 1.5 * t);
  expect_derivatives("step(t, 0, 0, 2, 1)", 0.0, 0.0, 0.0, 0.0, 0.0);
  expect_derivatives("STEP(t, 0, 0, 2, 1)", 2.0, 1.0, 0.0, 0.0, 0.0);
}

TEST(ExpressionDerivatives, TimeInsideTheArgumentsOfStep) {
  // Chain rule through x: step5(2t, 0, 0, 1, 1) = step5(t, 0, 0, 0.5, 1).
  for (double t : {0.1, 0.25, 0.4}) {
    const auto a = derivatives("step5(2*time, 0, 0, 1, 1)", t);
    const auto b = derivatives("step5(time, 0, 0, 0.5, 1)", t);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], 1e-12 * std::max(1.0, std::abs(b[k])));
  }
  // Through the upper edge x1 = a − t: Δ = t/(a − t), Δ' = a/(a − t)², Δ'' = 2a/(a − t)³;
  // f = S(Δ), ḟ = S'Δ', f̈ = S''Δ'² + S'Δ'' with S = 3Δ² − 2Δ³.
  const double a = 1e-3, t = 2e-4, d = t / (a - t), d1 = a / ((a - t) * (a - t)),
               d2 = 2 * a / ((a - t) * (a - t) * (a - t));
  const double s = 3 * d * d - 2 * d * d * d, s1 = 6 * d - 6 * d * d, s2 = 6 - 12 * d;
  expect_derivatives("step(time, 0, 0, 1e-3 - time, 1)", t, s, s1 * d1, s2 * d1 * d1 + s1 * d2);
}

TEST(ExpressionDerivatives, KinksAreDifferentiatedPiecewise) {
  expect_derivatives("abs(t - 0.2)^3", 0.1, 1e-3, -3e-2, 0.6);
  expect_derivatives("max(sin(t), 0.5)", 0.2, 0.5, 0.0, 0.0);
  expect_derivatives("max(sin(t), 0.5)", 1.0, std::sin(1.0), std::cos(1.0), -std::sin(1.0));
  expect_derivatives("min(t, 2*t, 3)", 0.5, 0.5, 1.0, 0.0);
  // impact(x, ẋ, x1, k, e, cmax, d) of x = t with ẋ = 0: k(x1 − t)^e while t < x1, else 0.
  expect_derivatives("impact(t, 0, 0.5, 100, 3, 0, 0.1)", 0.3, 100 * 0.008, -300 * 0.04, 600 * 0.2);
  expect_derivatives("impact(t, 0, 0.5, 100, 3, 0, 0.1)", 0.7, 0.0, 0.0, 0.0, 0.0);
  expect_derivatives("sign(t)*rint(3*t)", -0.9, 3.0, 0.0, 0.0);
}

TEST(ExpressionDerivatives, WhatCannotBeDifferentiatedIsRejectedByName) {
  auto error = [](const std::string& text) { return check_expression(text, {}, 2); };
  const std::string ternary = error("t < 0.1 ? sin(t) : 0");
  EXPECT_NE(ternary.find("cannot differentiate 't < 0.1 ? sin(t) : 0' in time"), std::string::npos) << ternary;
  EXPECT_NE(ternary.find("step()"), std::string::npos) << ternary;  // the hint
  EXPECT_NE(error("(t > 1) * t").find("comparisons"), std::string::npos);
  EXPECT_NE(error("t && 1").find("comparisons"), std::string::npos);
  EXPECT_NE(error("2^3^t").find("write a^(b^c)"), std::string::npos);
  EXPECT_NE(check_expression("rod.x + t", {"rod"}, 1).find("'rod.x' is not time"), std::string::npos);
  // Loads need no derivative: the same texts are fine as values.
  EXPECT_EQ(check_expression("t < 0.1 ? sin(t) : 0", {}), "");
  EXPECT_EQ(check_expression("2^3^t", {}), "");
  EXPECT_EQ(error("step5(t, 0, 0, 0.1, 1)"), "");
}

TEST(ExpressionDerivatives, CompiledOnManyThreadsAtOnce) {
  // GiNaC is serialised by a mutex inside; every thread must get the same exact results.
  const std::string text = "0.3*sin(7*time)*exp(-time) + step5(time, 0, 0, 0.2, 1)";
  const auto serial = derivatives(text, 0.11);
  std::vector<std::array<double, 3>> got(8);
  std::vector<std::thread> threads;
  for (int i = 0; i < 8; ++i)
    threads.emplace_back([&, i] {
      for (int k = 0; k < 10; ++k) got[i] = derivatives(text, 0.11);
    });
  for (auto& th : threads) th.join();
  for (const auto& g : got) EXPECT_EQ(g, serial);
}

TEST(Expression, ErrorsNameTheProblem) {
  EXPECT_NE(check_expression("foo(time)", {}).find("foo"), std::string::npos);
  EXPECT_NE(check_expression("step(time, 1, 0, 0, 1)", {}).find("x1 > x0"), std::string::npos);
  EXPECT_NE(check_expression("rod.x", {"crank"}).find("rod.x"), std::string::npos);
  EXPECT_EQ(check_expression("rod.x + 1", {"rod"}), "");
}

TEST(Expression, AssignmentsAndListsAreRefusedComparisonsKept) {
  // muparser would assign: `t=0.001 ? 100 : 0` set the time every later expression read (a
  // second load's `1000*t` gave 1e5 at every row), `rod.x=0` a body's coordinate.
  for (const char* text : {"t=0.001 ? 100 : 0", "(rod.x=0)*0", "time+=1", "time*=2", "a = 1"})
    EXPECT_NE(check_expression(text, {"rod"}).find("would assign to a variable"), std::string::npos)
        << text;
  EXPECT_NE(check_expression("1, 2", {}).find("a list of 2"), std::string::npos);
  for (const char* text : {"t == 1", "t<=2 && t>=1", "t != 3 ? 1 : 0", "step(t, 0, 0, 1, 2)"})
    EXPECT_EQ(check_expression(text, {}), "") << text;
  // Nothing was evaluated on the way: the time a refused expression names is untouched.
  ExpressionVariables vars;
  vars.time = 0.5;
  EXPECT_THROW(Expression("t=7", vars), std::invalid_argument);
  EXPECT_EQ(static_cast<double>(vars.time), 0.5);
}

TEST(Expression, SurvivesAMoveOfItsVariables) {
  // muparser holds the addresses of the variables: a moved block must carry them along.
  ExpressionVariables v;
  v.body_names = {"block"};
  Expression e("1000*time + block.vx", v);
  ExpressionVariables moved(std::move(v));
  moved.time = 0.5;
  moved.body_state[3] = 2.0;  // block.vx
  EXPECT_DOUBLE_EQ(e.eval(), 502.0);
  ExpressionVariables assigned;
  assigned = std::move(moved);
  assigned.time = 0.25;
  EXPECT_DOUBLE_EQ(e.eval(), 252.0);
  // A copy is a separate block: the expression stays with the original.
  ExpressionVariables copy = assigned;
  copy.time = 9.0;
  EXPECT_DOUBLE_EQ(e.eval(), 252.0);
}

TEST(Expression, FailureAfterTimeZeroIsAnExpressionError) {
  // Valid at t = 0 (x1 = 1e-3 > x0 = 0), invalid from t = 1e-3 on.
  const std::string text = "step(time, 0, 0, 1e-3 - time, 1)";
  EXPECT_EQ(check_expression(text, {}), "");
  ExpressionVariables v;
  Expression e(text, v);
  v.time = 0.5e-3;
  EXPECT_NO_THROW(e.eval());
  v.time = 2e-3;
  try {
    e.eval();
    FAIL() << "no exception";
  } catch (const ExpressionError& err) {
    EXPECT_EQ(err.text(), text);
    EXPECT_EQ(err.time(), 2e-3);
    const std::string what = err.what();
    EXPECT_NE(what.find("expression '" + text + "'"), std::string::npos) << what;
    EXPECT_NE(what.find("at time 0.002 s"), std::string::npos) << what;
    EXPECT_NE(what.find("x1 > x0"), std::string::npos) << what;  // muparser's message
  }
  // Derivatives report the failing time and restore the time variable.
  v.time = 0.0;
  Expression d(text, v, 2);
  double out[3];
  EXPECT_THROW(d.eval_derivatives(1e-3, out), ExpressionError);
  EXPECT_EQ(static_cast<double>(v.time), 0.0);
  // A lash exception derived from std::runtime_error, not mu::ParserError.
  v.time = 1.0;
  EXPECT_THROW(e.eval(), std::runtime_error);
}
