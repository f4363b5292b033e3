// Model-file expressions: muparser with the Adams functions, and their time derivatives.
#include <gtest/gtest.h>

#include <cmath>

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

TEST(Expression, DerivativesOfSmoothMotion) {
  ExpressionVariables v;
  Expression e("0.1*sin(50*time)", v);
  double f, fd, fdd;
  e.eval_derivatives(0.013, f, fd, fdd);
  EXPECT_NEAR(f, 0.1 * std::sin(0.65), 1e-15);
  EXPECT_NEAR(fd, 5.0 * std::cos(0.65), 1e-6);
  EXPECT_NEAR(fdd, -250.0 * std::sin(0.65), 1e-3);
}

TEST(Expression, ErrorsNameTheProblem) {
  EXPECT_NE(check_expression("foo(time)", {}).find("foo"), std::string::npos);
  EXPECT_NE(check_expression("step(time, 1, 0, 0, 1)", {}).find("x1 > x0"), std::string::npos);
  EXPECT_NE(check_expression("rod.x", {"crank"}).find("rod.x"), std::string::npos);
  EXPECT_EQ(check_expression("rod.x + 1", {"rod"}), "");
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
  // The derivative stencil reports the first failing sample and restores the time variable.
  double f, fd, fdd;
  v.time = 0.0;
  EXPECT_THROW(e.eval_derivatives(1e-3, f, fd, fdd), ExpressionError);
  EXPECT_EQ(static_cast<double>(v.time), 0.0);
  // A lash exception derived from std::runtime_error, not mu::ParserError.
  v.time = 1.0;
  EXPECT_THROW(e.eval(), std::runtime_error);
}
