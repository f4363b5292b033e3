#include "core/expression.hpp"

#include <muParser.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "core/adams_functions.hpp"

namespace lash {

namespace {
// Variable suffixes of body state, in the order of ExpressionVariables::body_state.
constexpr const char* kBodyFields[6] = {"x", "y", "phi", "vx", "vy", "omega"};

double mu_step(double x, double x0, double h0, double x1, double h1) {
  if (!(x1 > x0)) throw mu::ParserError("step(x, x0, h0, x1, h1) needs x1 > x0");
  return step(x, x0, h0, x1, h1);
}
double mu_step5(double x, double x0, double h0, double x1, double h1) {
  if (!(x1 > x0)) throw mu::ParserError("step5(x, x0, h0, x1, h1) needs x1 > x0");
  return step5(x, x0, h0, x1, h1);
}
double mu_impact(double x, double xd, double x1, double k, double e, double cmax, double d) {
  return impact(x, xd, x1, k, e, cmax, d);
}
double mu_bistop(double x, double xd, double x1, double x2, double k, double e, double cmax,
                 double d) {
  return bistop(x, xd, x1, x2, k, e, cmax, d);
}

void configure(mu::Parser& p, ExpressionVariables& vars) {
  p.DefineNameChars("0123456789_.abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ");
  for (const char* name : {"step", "STEP"}) p.DefineFun(name, mu_step);
  for (const char* name : {"step5", "STEP5"}) p.DefineFun(name, mu_step5);
  for (const char* name : {"impact", "IMPACT"}) p.DefineFun(name, mu_impact);
  for (const char* name : {"bistop", "BISTOP"}) p.DefineFun(name, mu_bistop);
  p.DefineConst("pi", M_PI);
  vars.time = static_cast<double>(vars.time);  // storage for a moved-from block, if need be
  p.DefineVar("time", vars.time.address());
  p.DefineVar("t", vars.time.address());
  vars.body_state.resize(6 * vars.body_names.size(), 0.0);
  for (size_t b = 0; b < vars.body_names.size(); ++b)
    for (int f = 0; f < 6; ++f)
      p.DefineVar(vars.body_names[b] + "." + kBodyFields[f], &vars.body_state[6 * b + f]);
}

std::string describe_failure(const std::string& text, double time, const std::string& message) {
  char at[32];
  std::snprintf(at, sizeof at, "%.9g", time);
  return "expression '" + text + "' failed at time " + at + " s: " + message;
}
}  // namespace

struct Expression::Impl {
  mu::Parser parser;
};

ExpressionError::ExpressionError(const std::string& text, double time, const std::string& message)
    : std::runtime_error(describe_failure(text, time, message)), text_(text), time_(time) {}

Expression::Expression(const std::string& text, ExpressionVariables& vars)
    : impl_(std::make_unique<Impl>()), time_(nullptr), text_(text) {
  try {
    configure(impl_->parser, vars);
    time_ = vars.time.address();
    impl_->parser.SetExpr(text);
    impl_->parser.Eval();  // compile now so errors surface at load time
    for (const auto& [name, ptr] : impl_->parser.GetUsedVar())
      if (name != "time" && name != "t") uses_state_ = true;
  } catch (const mu::Parser::exception_type& e) {
    throw std::invalid_argument(e.GetMsg());
  }
}

Expression::~Expression() = default;
Expression::Expression(Expression&&) noexcept = default;
Expression& Expression::operator=(Expression&&) noexcept = default;

double Expression::eval() const {
  try {
    return impl_->parser.Eval();
  } catch (const mu::Parser::exception_type& e) {  // mu::ParserError: no std::exception
    throw ExpressionError(text_, *time_, e.GetMsg());
  }
}

void Expression::eval_derivatives(double t, double& f, double& fdot, double& fddot) const {
  // 5-point central differences: truncation O(h⁴ f⁽⁶⁾) (O(h f''') across a kink such as the ends
  // of step5), round-off ~10ε|f|/h² ≈ 2e-5 |f| s⁻² at h = 1e-5 s.
  constexpr double h = 1e-5;
  const double saved = *time_;
  double v[5];
  for (int k = -2; k <= 2; ++k) {
    *time_ = t + k * h;
    try {
      v[k + 2] = impl_->parser.Eval();
    } catch (const mu::Parser::exception_type& e) {
      const double at = *time_;
      *time_ = saved;
      throw ExpressionError(text_, at, e.GetMsg());
    }
  }
  *time_ = saved;
  f = v[2];
  fdot = (v[0] - 8.0 * v[1] + 8.0 * v[3] - v[4]) / (12.0 * h);
  fddot = (-v[0] + 16.0 * v[1] - 30.0 * v[2] + 16.0 * v[3] - v[4]) / (12.0 * h * h);
}

std::string check_expression(const std::string& text, const std::vector<std::string>& body_names) {
  ExpressionVariables vars;
  vars.body_names = body_names;
  try {
    Expression e(text, vars);
    const double v = e.eval();
    if (!std::isfinite(v)) return "evaluates to " + std::to_string(v) + " at time 0";
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

}  // namespace lash
