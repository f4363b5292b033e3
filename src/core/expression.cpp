#include "core/expression.hpp"

#include <muParser.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "core/adams_functions.hpp"
#include "core/symbolic_derivatives.hpp"

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
  define_derivative_functions(p);  // _step_d, _step5_d: what derivative texts call
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

// GiNaC and muparser must read a text alike (operator precedence, function names): the value
// as GiNaC read it is compared with muparser's at a few times. Gross misreadings (-2^2 read as 4)
// differ by far more than the rounding of reordered sums this tolerates.
void check_same_reading(const std::string& text, const mu::Parser& original,
                        const std::string& symbolic, ExpressionVariables& vars) {
  if (symbolic.size() > static_cast<size_t>(mu::MaxLenExpression)) return;  // cannot compile it
  mu::Parser p;
  configure(p, vars);
  p.SetExpr(symbolic);
  double* time = vars.time.address();
  const double saved = *time;
  for (const double t : {0.0, 0.0123, 0.37, 1.9, -0.61, 13.7}) {
    *time = t;
    double a, b;
    try {
      a = original.Eval();
      b = p.Eval();
    } catch (const mu::Parser::exception_type&) {
      continue;  // e.g. a step whose bounds are invalid at this time
    }
    if (!std::isfinite(a) || !std::isfinite(b)) continue;
    if (std::abs(a - b) > 1e-9 * std::max(std::abs(a), std::abs(b)) + 1e-12) {
      *time = saved;
      char msg[160];
      std::snprintf(msg, sizeof msg, "GiNaC reads it differently from muparser (%.17g instead of "
                    "%.17g at time %g s); please report this expression", b, a, t);
      throw std::invalid_argument("cannot differentiate '" + text + "' in time: " + msg);
    }
  }
  *time = saved;
}
}  // namespace

struct Expression::Impl {
  mu::Parser parser;  // the value
  // "_tmp0 = ..., (value), d/dt, d²/dt²": one evaluation gives them all (symbolic_derivatives.hpp)
  mu::Parser derivatives;
  std::vector<double> temporaries;  // bound by `derivatives`; never resized after compiling
};

ExpressionError::ExpressionError(const std::string& text, double time, const std::string& message)
    : std::runtime_error(describe_failure(text, time, message)), text_(text), time_(time) {}

Expression::Expression(const std::string& text, ExpressionVariables& vars, int time_derivatives)
    : impl_(std::make_unique<Impl>()), time_(nullptr), text_(text),
      n_derivatives_(std::max(time_derivatives, 0)) {
  // muparser reads `=`, `+=`, `-=`, `*=`, `/=` as assignments to its variables: `t=0.001 ? 1 : 0`
  // would set the time every other expression reads. A model's expressions compute a value,
  // so an `=` that is not part of `==`, `<=`, `>=` or `!=` is refused before anything is
  // evaluated; so is a list of several expressions (`1, 2`), of which only one value is used.
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '=') continue;
    const char before = i > 0 ? text[i - 1] : ' ', after = i + 1 < text.size() ? text[i + 1] : ' ';
    if (after == '=') {
      ++i;  // ==
      continue;
    }
    if (before == '<' || before == '>' || before == '!') continue;
    throw std::invalid_argument("'=' at character " + std::to_string(i + 1) +
                                " would assign to a variable; an expression computes a value "
                                "(compare with '==')");
  }
  try {
    configure(impl_->parser, vars);
    time_ = vars.time.address();
    impl_->parser.SetExpr(text);
    int results = 0;
    impl_->parser.Eval(results);  // compile now so errors surface at load time
    if (results != 1)
      throw std::invalid_argument("expected one expression, got a list of " +
                                  std::to_string(results) + " separated by ','");
    for (const auto& [name, ptr] : impl_->parser.GetUsedVar())
      if (name != "time" && name != "t") uses_state_ = true;
    if (n_derivatives_ == 0) return;
    // Differentiate symbolically once (throws std::invalid_argument), compile the results.
    const SymbolicDerivatives sym = symbolic_time_derivatives(text, n_derivatives_);
    check_same_reading(text, impl_->parser, sym.value, vars);
    configure(impl_->derivatives, vars);
    impl_->temporaries.assign(sym.temporaries.size(), 0.0);
    for (size_t i = 0; i < sym.temporaries.size(); ++i)
      impl_->derivatives.DefineVar(sym.temporaries[i].first, &impl_->temporaries[i]);
    impl_->derivatives.SetExpr(muparser_text(sym, text));
    int n = 0;
    impl_->derivatives.Eval(n);
  } catch (const mu::Parser::exception_type& e) {
    throw std::invalid_argument(e.GetMsg());
  }
}

Expression::~Expression() = default;
Expression::Expression(Expression&&) noexcept = default;
Expression& Expression::operator=(Expression&&) noexcept = default;

double Expression::eval() const {
  double v;
  try {
    v = impl_->parser.Eval();
  } catch (const mu::Parser::exception_type& e) {  // mu::ParserError: no std::exception
    throw ExpressionError(text_, *time_, e.GetMsg());
  }
  // A NaN or infinity would only show up later as a step-size underflow with no culprit.
  if (!std::isfinite(v)) throw ExpressionError(text_, *time_, "the value is not finite (" + std::to_string(v) + ")");
  return v;
}

void Expression::eval_derivatives(double t, double* out) const {
  const double saved = *time_;
  *time_ = t;
  try {
    if (n_derivatives_ == 0) {
      out[0] = impl_->parser.Eval();
    } else {
      int n = 0;  // the temporaries' values, then the n_derivatives_ + 1 wanted
      const double* v = impl_->derivatives.Eval(n) + (n - n_derivatives_ - 1);
      for (int k = 0; k <= n_derivatives_; ++k) out[k] = v[k];
    }
  } catch (const mu::Parser::exception_type& e) {
    *time_ = saved;
    throw ExpressionError(text_, t, e.GetMsg());
  }
  *time_ = saved;
  for (int k = 0; k <= n_derivatives_; ++k)
    if (!std::isfinite(out[k]))
      throw ExpressionError(text_, t,
                            k == 0 ? std::string("the value is not finite")
                                   : "its time derivative of order " + std::to_string(k) +
                                         " is not finite");
}

std::string check_expression(const std::string& text, const std::vector<std::string>& body_names,
                             int time_derivatives) {
  ExpressionVariables vars;
  vars.body_names = body_names;
  try {
    Expression e(text, vars, time_derivatives);
    e.eval();  // throws ExpressionError if the value at time 0 is not finite
    if (time_derivatives > 0) {  // and the derivatives a driver needs there (sqrt(t): 1/(2√t))
      std::vector<double> d(static_cast<size_t>(time_derivatives) + 1);
      e.eval_derivatives(0.0, d.data());
    }
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

}  // namespace lash
