// GiNaC's reading of muparser texts, and the derivatives it prints back, computed twice.
#include <gtest/gtest.h>

#include <limits>

#include <muParser.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/expression.hpp"
#include "core/symbolic_derivatives.hpp"

using namespace lash;

namespace {
// Every function a driver expression may use, and muparser's precedence corners.
const std::vector<std::string> kTexts = {
    "-t^2", "2^-t", "-2^t", "t/2/4", "t-1-2", "-t*-t", "+t", "1e-3*t + .5*t + 2.5e+2 + 3E1*t",
    "(t + 1)^(1/3)", "t^0.5", "sin(t)*cos(t)/tan(t + 1)", "asin(t/3) + acos(t/3) + atan(t)",
    "atan2(t, 2) + atan2(1, t + 2)", "sinh(t) + cosh(t) + tanh(t)",
    "asinh(t) + acosh(t + 2) + atanh(t/3)", "exp(t) + ln(t + 1) + log(t + 2) + log2(t + 3) + log10(t + 4)",
    "sqrt(t + 1)", "abs(t - 0.3) + sign(t - 0.3) + rint(4*t)", "min(t, 0.5, 1 - t) + max(t, 0.2)",
    "sum(t, 2*t, t^2) + avg(t, 1, t^3)", "_pi*t + pi + _e", "STEP(t, 0, 1, 1, 2) + step5(t, 0.1, 0, 0.9, 1)",
    "IMPACT(t, 2, 0.5, 1e3, 1.5, 10, 0.2)", "bistop(t, -1, 0.1, 0.6, 1e3, 2, 10, 0.05)"};
const double kTimes[] = {-0.61, 0.0, 0.07, 0.33, 0.45, 0.8, 1.7};

// A derivative text evaluated by a bare muparser with only the helper functions added.
double eval_text(const std::string& text, double t) {
  mu::Parser p;
  double time = t;
  p.DefineVar("time", &time);
  define_derivative_functions(p);
  p.SetExpr(text);
  return p.Eval();
}
}  // namespace

TEST(SymbolicDerivatives, GiNaCReadsTextsAsMuparserDoes) {
  // The value as GiNaC read it (element 0, printed back) equals muparser's value of the text.
  for (const std::string& text : kTexts) {
    ExpressionVariables v;
    Expression original(text, v);
    ExpressionVariables w;
    const std::string printed = symbolic_time_derivatives(text, 0).value;
    Expression reread(printed, w);
    for (double t : kTimes) {
      v.time = t;
      w.time = t;
      // Outside its domain an expression throws (ExpressionError: not finite); both must.
      auto value = [](const Expression& e) {
        try {
          return e.eval();
        } catch (const ExpressionError&) {
          return std::numeric_limits<double>::quiet_NaN();
        }
      };
      const double a = value(original), b = value(reread);
      if (std::isnan(a)) {
        EXPECT_TRUE(std::isnan(b)) << text << " → " << printed << " at " << t;
        continue;
      }
      EXPECT_NEAR(b, a, 1e-13 * std::max(1.0, std::abs(a))) << text << " → " << printed << " at " << t;
    }
  }
}

TEST(SymbolicDerivatives, DerivativesAgreeWithFiniteDifferencesOfTheValue) {
  // Computed twice: ḟ and f̈ against central differences of f and ḟ (h = 1e-6, away from kinks).
  const double h = 1e-6;
  for (const std::string& text : kTexts) {
    ExpressionVariables v;
    Expression e(text, v, 2);
    for (double t : {0.07, 0.33, 0.45}) {
      double lo[3], mid[3], hi[3];
      e.eval_derivatives(t - h, lo);
      e.eval_derivatives(t, mid);
      e.eval_derivatives(t + h, hi);
      for (int k = 0; k < 2; ++k) {
        const double fd = (hi[k] - lo[k]) / (2 * h);
        EXPECT_NEAR(mid[k + 1], fd, 1e-5 * std::max(1.0, std::abs(fd)))
            << "d^" << k + 1 << " of " << text << " at " << t;
      }
    }
  }
}

TEST(SymbolicDerivatives, DerivativeTextsAreMuparserText) {
  const SymbolicDerivatives d = symbolic_time_derivatives("0.5*sin(20*time)", 2);
  ASSERT_EQ(d.derivatives.size(), 2u);
  // 20·t is shared by cos(20t) in ḟ and sin(20t) in f̈: one temporary.
  ASSERT_EQ(d.temporaries.size(), 1u);
  EXPECT_EQ(d.temporaries[0].second, "(time*20)");
  EXPECT_EQ(d.derivatives[0], "(cos(_tmp0)*10)");
  EXPECT_EQ(d.derivatives[1], "(sin(_tmp0)*(-200))");
  EXPECT_EQ(muparser_text(d, "0.5*sin(20*time)"),
            "_tmp0 = (time*20), (0.5*sin(20*time)), (cos(_tmp0)*10), (sin(_tmp0)*(-200))");
  // Numbers keep the exact double the text names (printed with 17 digits).
  EXPECT_EQ(symbolic_time_derivatives("0.1*t", 1).derivatives[0], "0.10000000000000001");
  EXPECT_EQ(eval_text(symbolic_time_derivatives("step5(t, 0, 0, 2, 1)", 1).derivatives[0], 1.0),
            0.9375);
}

TEST(SymbolicDerivatives, NestedFunctionsShareTheirSubexpressions) {
  // The chain rule repeats every inner function; temporaries keep each one evaluated once (as
  // a tree, 30 nested sines gave a 76 000-character f̈, too long for muparser; f̈ still has 30
  // terms of up to 30 factors).
  std::string text = "t";
  for (int i = 0; i < 30; ++i) text = "sin(" + text + ")";
  const SymbolicDerivatives d = symbolic_time_derivatives(text, 2);
  EXPECT_LT(muparser_text(d, text).size(), 10000u);
  ExpressionVariables v;
  Expression e(text, v, 2);
  double out[3];
  e.eval_derivatives(0.4, out);
  // ḟ = Π cos(uₖ) with u₀ = t, uₖ₊₁ = sin(uₖ); f̈ = ḟ Σ −tan(uₖ) u̇ₖ, u̇ₖ = Π_{j<k} cos(uⱼ).
  double u = 0.4, fd = 1, sum = 0, ud = 1;
  for (int i = 0; i < 30; ++i) {
    sum += -std::tan(u) * ud;
    fd *= std::cos(u);
    ud *= std::cos(u);
    u = std::sin(u);
  }
  EXPECT_NEAR(out[0], u, 1e-15);
  EXPECT_NEAR(out[1], fd, 1e-13 * std::abs(fd));
  EXPECT_NEAR(out[2], fd * sum, 1e-12 * std::abs(fd * sum));
}

TEST(SymbolicDerivatives, TooLargeDerivativesAreRejectedNotAttempted) {
  // d²/dt² of a product of n distinct factors has n² terms of n factors each.
  std::string text;
  for (int i = 1; i <= 200; ++i) text += (i > 1 ? "*" : "") + std::string("sin(") + std::to_string(i) + "*t)";
  try {
    symbolic_time_derivatives(text, 2);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("simplify it"), std::string::npos) << e.what();
  }
}

TEST(SymbolicDerivatives, RejectionsNameTheExpressionAndTheReason) {
  auto message = [](const std::string& text) {
    try {
      symbolic_time_derivatives(text, 2);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_EQ(message("t > 1 ? 1 : 0"),
            "cannot differentiate 't > 1 ? 1 : 0' in time: comparisons, '&&', '||' and "
            "'c ? a : b' have no derivative; switch between motions smoothly with step() or "
            "step5(), or use min, max, abs");
  EXPECT_EQ(message("slider.vx*t"),
            "cannot differentiate 'slider.vx*t' in time: 'slider.vx' is not time (only "
            "expressions of time alone are differentiated)");
  EXPECT_EQ(message("2^t^2"),
            "cannot differentiate '2^t^2' in time: a^b^c is ambiguous to GiNaC; write a^(b^c), "
            "as muparser reads it");
  EXPECT_EQ(message("foo(t)"), "cannot differentiate 'foo(t)' in time: the function 'foo' has no "
                               "derivative here");
  // No C++ source location from GiNaC's parser leaks into the message.
  EXPECT_EQ(message("sin(t").find("parser.cpp"), std::string::npos);
  // Exact arithmetic on huge numbers cannot start (numbers are doubles): no hang, an error.
  EXPECT_NE(message("10^(10^10)*t").find("not finite"), std::string::npos);
}
