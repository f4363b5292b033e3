// Time derivatives of muparser expressions by GiNaC (symbolic_derivatives.hpp).
// 1. translate(): a tokenizer checks the text uses only what can be differentiated and rewrites
//    it for GiNaC's parser: time → t, every number → a named constant kN bound to a GiNaC
//    numeric(double) (the exact double muparser reads; no exact big-number arithmetic can start,
//    so "10^(10^10)" cannot hang the loader), pi/_pi/_e → constants.
// 2. GiNaC parses it with a function table of our own (reader_table) and differentiates; the
//    functions GiNaC lacks (Adams functions, abs, min, ...) are GiNaC functions declared below
//    with their derivative rules.
// 3. Printer writes each result back as fully parenthesised muparser text, subexpressions the
//    derivatives share as temporaries evaluated once.
#include "core/symbolic_derivatives.hpp"

#include <ginac/ginac.h>
#include <muParser.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>

#include "core/adams_functions.hpp"

namespace lash {
namespace {

using GiNaC::ex;
using GiNaC::exvector;
using GiNaC::symbol;

// GiNaC functions for what GiNaC lacks. Each is printed back by print() under the muparser name
// in its comment. Functions with a kink or a jump are differentiated piecewise.
DECLARE_FUNCTION_6P(lash_stepn)       // _step_d(n, x, x0, h0, x1, h1): ∂ⁿstep/∂xⁿ, n = 0 is step
DECLARE_FUNCTION_6P(lash_step5n)      // _step5_d(n, x, x0, h0, x1, h1)
DECLARE_FUNCTION_2P(lash_gate)        // (c ? v : 0), selects (a product 0·NaN would not)
DECLARE_FUNCTION_2P(lash_less)        // (a < b): 1 or 0
DECLARE_FUNCTION_2P(lash_less_equal)  // (a <= b)
DECLARE_FUNCTION_1P(lash_abs)         // abs
DECLARE_FUNCTION_1P(lash_sign)        // sign
DECLARE_FUNCTION_1P(lash_rint)        // rint
DECLARE_FUNCTION_2P(lash_min)         // min(a, b) = b < a ? b : a (std::min, as muparser)
DECLARE_FUNCTION_2P(lash_max)         // max(a, b) = a < b ? b : a (std::max)
DECLARE_FUNCTION_7P(lash_impact)      // impact(x, ẋ, x1, k, e, cmax, d)
DECLARE_FUNCTION_8P(lash_bistop)      // bistop(x, ẋ, x1, x2, k, e, cmax, d)

// ∂/∂(argument i) of D_n = ∂ⁿ step/∂xⁿ(x, x0, h0, x1, h1), L = x1 − x0, from
// D_n = h0·[n = 0] + (h1 − h0) S⁽ⁿ⁾(Δ)/Lⁿ, Δ = (x − x0)/L:
//   ∂x: D_{n+1};  ∂h1: D_n(h0 = 0, h1 = 1);  ∂h0: [n = 0] − D_n(h0 = 0, h1 = 1);
//   ∂x0: ((x − x1) D_{n+1} + n D_n)/L;  ∂x1: −((x − x0) D_{n+1} + n D_n)/L.
// Every argument may depend on time (e.g. step(time, 0, 0, 1e-3 - time, 1)).
template <bool kQuintic>
ex ramp_partial(const ex& n, const ex& x, const ex& x0, const ex& h0, const ex& x1, const ex& h1,
                unsigned i) {
  auto d = [&](const ex& order, const ex& a, const ex& b) -> ex {
    return kQuintic ? ex(lash_step5n(order, x, x0, a, x1, b)) : ex(lash_stepn(order, x, x0, a, x1, b));
  };
  switch (i) {
    case 1: return d(n + 1, h0, h1);
    case 2: return ((x - x1) * d(n + 1, h0, h1) + n * d(n, h0, h1)) / (x1 - x0);
    case 3: return (n.is_zero() ? ex(1) : ex(0)) - d(n, 0, 1);
    case 4: return -((x - x0) * d(n + 1, h0, h1) + n * d(n, h0, h1)) / (x1 - x0);
    case 5: return d(n, 0, 1);
    default: return 0;  // the order n is a constant
  }
}
ex stepn_partial(const ex& n, const ex& x, const ex& x0, const ex& h0, const ex& x1,
                 const ex& h1, unsigned i) {
  return ramp_partial<false>(n, x, x0, h0, x1, h1, i);
}
ex step5n_partial(const ex& n, const ex& x, const ex& x0, const ex& h0, const ex& x1,
                  const ex& h1, unsigned i) {
  return ramp_partial<true>(n, x, x0, h0, x1, h1, i);
}

ex gate_eval(const ex& c, const ex& v) {
  if (v.is_zero()) return 0;
  if (GiNaC::is_exactly_a<GiNaC::numeric>(c)) return c.is_zero() ? ex(0) : v;
  return lash_gate(c, v).hold();
}
ex gate_derivative(const ex& c, const ex& v, const symbol& s) { return lash_gate(c, v.diff(s)); }
ex zero_partial_1(const ex&, unsigned) { return 0; }
ex zero_partial_2(const ex&, const ex&, unsigned) { return 0; }
ex abs_partial(const ex& u, unsigned) { return lash_sign(u); }  // sign(0) = 0 at the kink
ex min_derivative(const ex& a, const ex& b, const symbol& s) {
  return lash_gate(lash_less(b, a), b.diff(s)) + lash_gate(lash_less_equal(a, b), a.diff(s));
}
ex max_derivative(const ex& a, const ex& b, const symbol& s) {
  return lash_gate(lash_less(a, b), b.diff(s)) + lash_gate(lash_less_equal(b, a), a.diff(s));
}
// One contact side of impact/bistop: F while `inside` and F pushes the right way, else 0.
ex active_derivative(const ex& inside, const ex& pushes, const ex& force, const symbol& s) {
  return lash_gate(inside, lash_gate(pushes, force.diff(s)));
}
// impact: max(0, F) for x < x1, F = k(x1 − x)^e − STEP(x, x1 − d, cmax, x1, 0)·ẋ.
ex impact_derivative(const ex& x, const ex& xd, const ex& x1, const ex& k, const ex& e,
                     const ex& cmax, const ex& d, const symbol& s) {
  const ex force = k * pow(x1 - x, e) - lash_stepn(0, x, x1 - d, cmax, x1, 0) * xd;
  return active_derivative(lash_less(x, x1), lash_less(0, force), force, s);
}
// bistop: the impact side below x1, and min(0, −k(x − x2)^e − STEP(x, x2, 0, x2 + d, cmax)·ẋ)
// above x2.
ex bistop_derivative(const ex& x, const ex& xd, const ex& x1, const ex& x2, const ex& k,
                     const ex& e, const ex& cmax, const ex& d, const symbol& s) {
  const ex lower = k * pow(x1 - x, e) - lash_stepn(0, x, x1 - d, cmax, x1, 0) * xd;
  const ex upper = -k * pow(x - x2, e) - lash_stepn(0, x, x2, 0, x2 + d, cmax) * xd;
  return active_derivative(lash_less(x, x1), lash_less(0, lower), lower, s) +
         active_derivative(lash_less(x2, x), lash_less(upper, 0), upper, s);
}

}  // namespace

REGISTER_FUNCTION(lash_stepn, derivative_func(stepn_partial))
REGISTER_FUNCTION(lash_step5n, derivative_func(step5n_partial))
REGISTER_FUNCTION(lash_gate, eval_func(gate_eval).expl_derivative_func(gate_derivative))
REGISTER_FUNCTION(lash_less, derivative_func(zero_partial_2))
REGISTER_FUNCTION(lash_less_equal, derivative_func(zero_partial_2))
REGISTER_FUNCTION(lash_abs, derivative_func(abs_partial))
REGISTER_FUNCTION(lash_sign, derivative_func(zero_partial_1))
REGISTER_FUNCTION(lash_rint, derivative_func(zero_partial_1))
REGISTER_FUNCTION(lash_min, expl_derivative_func(min_derivative))
REGISTER_FUNCTION(lash_max, expl_derivative_func(max_derivative))
REGISTER_FUNCTION(lash_impact, expl_derivative_func(impact_derivative))
REGISTER_FUNCTION(lash_bistop, expl_derivative_func(bistop_derivative))

namespace {

// Something the text uses that cannot be differentiated; becomes std::invalid_argument.
struct Rejection {
  std::string reason, hint;
};

// ---- 1. muparser text → GiNaC text --------------------------------------------------------------

// The muparser functions that can be differentiated (GiNaC's reader table below has each).
bool differentiable_function(const std::string& name) {
  static const char* const kNames[] = {
      "sin",  "cos",   "tan",   "asin",  "acos", "atan",  "atan2", "sinh",   "cosh",
      "tanh", "asinh", "acosh", "atanh", "exp",  "sqrt",  "ln",    "log",    "log2",
      "log10", "abs",  "sign",  "rint",  "min",  "max",   "sum",   "avg",    "step",
      "STEP", "step5", "STEP5", "impact", "IMPACT", "bistop", "BISTOP"};
  for (const char* n : kNames)
    if (name == n) return true;
  return false;
}

// The value of one of muparser's built-in constants (_pi, _e).
double muparser_constant(const std::string& name) {
  static const mu::valmap_type constants = mu::Parser().GetConst();
  return constants.at(name);
}

struct Translation {
  std::string text;              // for GiNaC's parser: t, kN, function names, + - * / ^ ( ) ,
  std::vector<double> constants;  // kN's value
};

constexpr int kMaxDepth = 100;

Translation translate(const std::string& text) {
  Translation out;
  int depth = 0;
  std::map<double, size_t> index;  // one constant per distinct value
  auto constant = [&](double v) {
    auto [it, added] = index.emplace(v, out.constants.size());
    if (added) out.constants.push_back(v);
    out.text += "k" + std::to_string(it->second);
  };
  auto digit = [&](size_t i) { return i < text.size() && std::isdigit(static_cast<unsigned char>(text[i])); };
  const size_t n = text.size();
  for (size_t i = 0; i < n;) {
    const char c = text[i];
    if (std::isspace(static_cast<unsigned char>(c))) {
      out.text += ' ';
      ++i;
    } else if (digit(i) || (c == '.' && digit(i + 1))) {  // a number: 12, 1.5, .5, 2e-3
      size_t j = i;
      while (digit(j)) ++j;
      if (j < n && text[j] == '.') ++j;
      while (digit(j)) ++j;
      if (j < n && (text[j] == 'e' || text[j] == 'E')) {
        size_t k = j + 1;
        if (k < n && (text[k] == '+' || text[k] == '-')) ++k;
        if (digit(k)) {
          j = k;
          while (digit(j)) ++j;
        }
      }
      constant(std::strtod(text.substr(i, j - i).c_str(), nullptr));
      i = j;
    } else if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {  // a name
      size_t j = i;
      while (j < n && (std::isalnum(static_cast<unsigned char>(text[j])) || text[j] == '_' ||
                       text[j] == '.'))
        ++j;
      const std::string name = text.substr(i, j - i);
      size_t k = j;
      while (k < n && std::isspace(static_cast<unsigned char>(text[k]))) ++k;
      if (k < n && text[k] == '(') {
        if (!differentiable_function(name))
          throw Rejection{"the function '" + name + "' has no derivative here", ""};
        out.text += name;
      } else if (name == "time" || name == "t") {
        out.text += "t";
      } else if (name == "pi") {
        constant(M_PI);
      } else if (name == "_pi" || name == "_e") {
        constant(muparser_constant(name));  // muparser 2.3.3's _pi is 3.141592653589, not π
      } else {
        throw Rejection{"'" + name + "' is not time (only expressions of time alone are differentiated)",
                        ""};
      }
      i = j;
    } else if (c != '\0' && std::strchr("+-*/^(),", c)) {
      // GiNaC parses and differentiates recursively: bound the nesting (muparser's own limit
      // on the length, 20 000 characters, would still allow thousands of levels).
      depth += c == '(' ? 1 : c == ')' ? -1 : 0;
      if (depth > kMaxDepth)
        throw Rejection{"it nests deeper than " + std::to_string(kMaxDepth) + " parentheses", ""};
      out.text += c;
      ++i;
    } else if (c != '\0' && std::strchr("<>=!&|?:", c)) {
      throw Rejection{"comparisons, '&&', '||' and 'c ? a : b' have no derivative",
                      "switch between motions smoothly with step() or step5(), or use min, max, abs"};
    } else {
      throw Rejection{std::string("unexpected character '") + c + "'", ""};
    }
  }
  return out;
}

// GiNaC's parser reads function names through this table (name, number of arguments; 0: any).
ex fold_min(const exvector& a) {
  ex r = a[0];
  for (size_t i = 1; i < a.size(); ++i) r = lash_min(r, a[i]);
  return r;
}
ex fold_max(const exvector& a) {
  ex r = a[0];
  for (size_t i = 1; i < a.size(); ++i) r = lash_max(r, a[i]);
  return r;
}
ex sum_of(const exvector& a) {
  ex r = 0;
  for (const ex& x : a) r += x;
  return r;
}

const GiNaC::prototype_table& reader_table() {
  using A = const exvector&;
  static const GiNaC::prototype_table table = {
      {{"sin", 1}, [](A a) -> ex { return sin(a[0]); }},
      {{"cos", 1}, [](A a) -> ex { return cos(a[0]); }},
      {{"tan", 1}, [](A a) -> ex { return tan(a[0]); }},
      {{"asin", 1}, [](A a) -> ex { return asin(a[0]); }},
      {{"acos", 1}, [](A a) -> ex { return acos(a[0]); }},
      {{"atan", 1}, [](A a) -> ex { return atan(a[0]); }},
      {{"atan2", 2}, [](A a) -> ex { return atan2(a[0], a[1]); }},
      {{"sinh", 1}, [](A a) -> ex { return sinh(a[0]); }},
      {{"cosh", 1}, [](A a) -> ex { return cosh(a[0]); }},
      {{"tanh", 1}, [](A a) -> ex { return tanh(a[0]); }},
      {{"asinh", 1}, [](A a) -> ex { return asinh(a[0]); }},
      {{"acosh", 1}, [](A a) -> ex { return acosh(a[0]); }},
      {{"atanh", 1}, [](A a) -> ex { return atanh(a[0]); }},
      {{"exp", 1}, [](A a) -> ex { return exp(a[0]); }},
      {{"sqrt", 1}, [](A a) -> ex { return sqrt(a[0]); }},
      {{"ln", 1}, [](A a) -> ex { return log(a[0]); }},
      {{"log", 1}, [](A a) -> ex { return log(a[0]); }},  // muparser's log is ln
      {{"log2", 1}, [](A a) -> ex { return log(a[0]) / log(GiNaC::numeric(2.0)); }},
      {{"log10", 1}, [](A a) -> ex { return log(a[0]) / log(GiNaC::numeric(10.0)); }},
      {{"abs", 1}, [](A a) -> ex { return lash_abs(a[0]); }},
      {{"sign", 1}, [](A a) -> ex { return lash_sign(a[0]); }},
      {{"rint", 1}, [](A a) -> ex { return lash_rint(a[0]); }},
      {{"min", 0}, fold_min},
      {{"max", 0}, fold_max},
      {{"sum", 0}, sum_of},
      {{"avg", 0}, [](A a) -> ex { return sum_of(a) / GiNaC::numeric(static_cast<double>(a.size())); }},
      {{"step", 5}, [](A a) -> ex { return lash_stepn(0, a[0], a[1], a[2], a[3], a[4]); }},
      {{"STEP", 5}, [](A a) -> ex { return lash_stepn(0, a[0], a[1], a[2], a[3], a[4]); }},
      {{"step5", 5}, [](A a) -> ex { return lash_step5n(0, a[0], a[1], a[2], a[3], a[4]); }},
      {{"STEP5", 5}, [](A a) -> ex { return lash_step5n(0, a[0], a[1], a[2], a[3], a[4]); }},
      {{"impact", 7}, [](A a) -> ex { return lash_impact(a[0], a[1], a[2], a[3], a[4], a[5], a[6]); }},
      {{"IMPACT", 7}, [](A a) -> ex { return lash_impact(a[0], a[1], a[2], a[3], a[4], a[5], a[6]); }},
      {{"bistop", 8},
       [](A a) -> ex { return lash_bistop(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]); }},
      {{"BISTOP", 8},
       [](A a) -> ex { return lash_bistop(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]); }},
  };
  return table;
}

// ---- 3. GiNaC → muparser text -------------------------------------------------------------------

std::string join(const std::vector<std::string>& parts, const char* sep) {
  std::string s;
  for (size_t i = 0; i < parts.size(); ++i) s += (i ? sep : "") + parts[i];
  return s;
}

using ExCount = std::map<ex, int, GiNaC::ex_is_less>;
using ExName = std::map<ex, std::string, GiNaC::ex_is_less>;

// How often each compound subexpression occurs in `e`, counting the operands of a repeated one
// once (they will be evaluated once, in its temporary). Linear in the number of distinct nodes.
void count_uses(const ex& e, ExCount& uses) {
  if (e.nops() == 0) return;  // numbers and time
  auto [it, first] = uses.emplace(e, 0);
  if (++it->second > 1) return;
  for (size_t i = 0; i < e.nops(); ++i) count_uses(e.op(i), uses);
}

// Prints GiNaC expressions as fully parenthesised muparser text. With `uses` given, a compound
// subexpression used more than once is printed once, as a temporary `_tmpK = TEXT` evaluated
// before the derivatives, and named where it is used: the chain rule repeats subexpressions
// (sin(u), u, u', ...), and without this the text of nested functions grows exponentially and
// shared sin/cos/exp would be evaluated again in each derivative.
class Printer {
 public:
  /// `limit`: the longest text allowed for one subexpression (muparser's limit for derivatives).
  explicit Printer(ExCount uses = {}, size_t limit = mu::MaxLenExpression)
      : uses_(std::move(uses)), limit_(limit) {}

  std::string print(const ex& e) {
    if (auto it = names_.find(e); it != names_.end()) return it->second;
    std::string text = print_node(e);
    if (text.size() > limit_)
      throw Rejection{"its derivatives are too long for muparser (over " +
                          std::to_string(limit_) + " characters)",
                      "simplify it"};
    auto u = uses_.find(e);
    if (u == uses_.end() || u->second < 2) return text;
    const std::string name = "_tmp" + std::to_string(temporaries_.size());
    temporaries_.emplace_back(name, text);
    names_.emplace(e, name);
    return name;
  }
  std::vector<std::pair<std::string, std::string>>& temporaries() { return temporaries_; }

 private:
  static std::string number(double v) {
    if (!std::isfinite(v)) throw Rejection{"a constant of its derivative is not finite", ""};
    char b[32];
    std::snprintf(b, sizeof b, "%.17g", v);
    return v < 0 || (v == 0 && std::signbit(v)) ? "(" + std::string(b) + ")" : std::string(b);
  }

  // b^p for p > 0 (a negative power is printed as a division by product()).
  std::string power(const ex& b, const ex& p) {
    if (p.is_equal(1)) return print(b);
    if (p.is_equal(GiNaC::numeric(1, 2))) return "sqrt(" + print(b) + ")";
    return "(" + print(b) + "^" + print(p) + ")";
  }

  // A product, with the factors of negative numeric power as one division.
  std::string product(const ex& e) {
    std::vector<std::string> num, den;
    auto factor = [&](const ex& f) {
      if (GiNaC::is_a<GiNaC::power>(f) && GiNaC::is_a<GiNaC::numeric>(f.op(1)) &&
          GiNaC::ex_to<GiNaC::numeric>(f.op(1)).is_negative())
        den.push_back(power(f.op(0), -f.op(1)));
      else
        num.push_back(print(f));
    };
    if (GiNaC::is_a<GiNaC::mul>(e))
      for (size_t i = 0; i < e.nops(); ++i) factor(e.op(i));
    else
      factor(e);
    std::string s = num.empty() ? "1" : join(num, "*");
    if (!den.empty()) s = "(" + s + ")/(" + join(den, "*") + ")";
    return "(" + s + ")";
  }

  std::string function(const GiNaC::function& f) {
    std::vector<std::string> a;
    for (size_t i = 0; i < f.nops(); ++i) a.push_back(print(f.op(i)));
    const std::string name = f.get_name();
    static const std::map<std::string, std::string> kRenamed = {
        {"lash_stepn", "_step_d"}, {"lash_step5n", "_step5_d"}, {"lash_abs", "abs"},
        {"lash_sign", "sign"},     {"lash_rint", "rint"},       {"lash_min", "min"},
        {"lash_max", "max"},       {"lash_impact", "impact"},   {"lash_bistop", "bistop"},
        {"log", "ln"}};
    static const char* const kSame[] = {"sin",  "cos",   "tan",   "asin",  "acos",
                                        "atan", "atan2", "sinh",  "cosh",  "tanh",
                                        "asinh", "acosh", "atanh", "exp"};
    if (name == "lash_gate") return "((" + a[0] + ") ? " + a[1] + " : 0)";
    if (name == "lash_less") return "(" + a[0] + " < " + a[1] + ")";
    if (name == "lash_less_equal") return "(" + a[0] + " <= " + a[1] + ")";
    if (auto it = kRenamed.find(name); it != kRenamed.end())
      return it->second + "(" + join(a, ", ") + ")";
    for (const char* s : kSame)
      if (name == s) return name + "(" + join(a, ", ") + ")";
    throw Rejection{"GiNaC's result uses '" + name + "', which muparser lacks", ""};
  }

  std::string print_node(const ex& e) {
    using namespace GiNaC;
    if (is_a<numeric>(e)) {
      const numeric& v = ex_to<numeric>(e);
      if (!v.is_real()) throw Rejection{"its derivative is complex", ""};
      return number(v.to_double());
    }
    if (is_a<symbol>(e)) return "time";  // the only symbol (constants are numerics)
    if (is_a<constant>(e)) return number(ex_to<numeric>(e.evalf()).to_double());  // e.g. Pi
    if (is_a<add>(e)) {
      std::vector<std::string> terms;
      for (size_t i = 0; i < e.nops(); ++i) terms.push_back(print(e.op(i)));
      return "(" + join(terms, " + ") + ")";
    }
    if (is_a<mul>(e)) return product(e);
    if (is_a<GiNaC::power>(e)) {
      if (is_a<numeric>(e.op(1)) && ex_to<numeric>(e.op(1)).is_negative()) return product(e);
      return power(e.op(0), e.op(1));
    }
    if (is_a<GiNaC::function>(e)) return function(ex_to<GiNaC::function>(e));
    throw Rejection{"GiNaC's result is a " + std::string(ex_to<basic>(e).class_name()) +
                        ", which muparser cannot evaluate", ""};
  }

  ExCount uses_;
  size_t limit_;
  ExName names_;
  std::vector<std::pair<std::string, std::string>> temporaries_;
};

// ---- 2. parse and differentiate, under the lock ---------------------------------------------

// GiNaC is not thread-safe (ptr.h: "This implementation of reference counting is not
// thread-safe"; global function registry, CLN caches), and even shared constants such as _ex1
// are reference-counted: every GiNaC object is created and destroyed while this is held.
std::mutex& ginac_mutex() {
  static std::mutex m;
  return m;
}

// GiNaC's parse errors read "GiNaC: parse error at line 0, column 0: MESSAGE\n[C++ location]".
std::string clean(const std::string& what) {
  std::string s = what.substr(0, what.find('\n'));
  const std::string prefix = "parse error at line 0, column 0: ";
  if (const size_t p = s.find(prefix); p != std::string::npos) s = s.substr(p + prefix.size());
  if (s.rfind("GiNaC: ", 0) == 0) s = s.substr(7);
  return s;
}

// Whether `e`, as a tree (shared operands counted each time), has at most `budget` nodes; stops
// counting past it. GiNaC differentiates the tree, so this bounds the work of the next
// derivative (the product rule multiplies it: d²/dt² of a product of n factors has n² terms).
bool tree_within(const ex& e, long& budget) {
  if (--budget < 0) return false;
  for (size_t i = 0; i < e.nops(); ++i)
    if (!tree_within(e.op(i), budget)) return false;
  return true;
}
constexpr long kMaxTreeNodes = 20000;

double mu_step_d(double n, double x, double x0, double h0, double x1, double h1) {
  return step_derivative(static_cast<int>(n), x, x0, h0, x1, h1);
}
double mu_step5_d(double n, double x, double x0, double h0, double x1, double h1) {
  return step5_derivative(static_cast<int>(n), x, x0, h0, x1, h1);
}

}  // namespace

SymbolicDerivatives symbolic_time_derivatives(const std::string& text, int order) {
  try {
    const Translation tr = translate(text);
    SymbolicDerivatives out;
    std::lock_guard<std::mutex> lock(ginac_mutex());  // before any GiNaC object exists
    try {
      const GiNaC::realsymbol time("t");
      GiNaC::symtab symbols{{"t", time}};
      for (size_t i = 0; i < tr.constants.size(); ++i)
        symbols["k" + std::to_string(i)] = GiNaC::numeric(tr.constants[i]);
      GiNaC::parser read(symbols, /*strict=*/true, reader_table());
      std::vector<ex> d{read(tr.text)};
      for (int k = 1; k <= order; ++k) {
        long budget = kMaxTreeNodes;
        if (!tree_within(d.back(), budget))
          throw Rejection{"its derivatives grow too large (over " + std::to_string(kMaxTreeNodes) +
                              " terms)", "simplify it"};
        d.push_back(d.back().diff(time));
      }
      out.value = Printer({}, std::string::npos).print(d[0]);  // only for a check: no limit
      // Subexpressions shared by the derivatives become temporaries, evaluated once.
      ExCount uses;
      for (int k = 1; k <= order; ++k) count_uses(d[k], uses);
      Printer printer(std::move(uses));
      for (int k = 1; k <= order; ++k) out.derivatives.push_back(printer.print(d[k]));
      out.temporaries = std::move(printer.temporaries());
    } catch (const std::exception& err) {  // GiNaC's and CLN's exceptions
      const std::string m = clean(err.what());
      if (m.find("power should have exactly 2 operands") != std::string::npos)
        throw Rejection{"a^b^c is ambiguous to GiNaC", "write a^(b^c), as muparser reads it"};
      throw Rejection{m, ""};
    }
    // All of it is compiled as one muparser text: "_tmp0 = ..., ..., (text), d1, d2".
    size_t length = text.size() + 2;
    for (const auto& [name, t] : out.temporaries) length += name.size() + t.size() + 5;
    for (const auto& t : out.derivatives) length += t.size() + 2;
    if (length > static_cast<size_t>(mu::MaxLenExpression))
      throw Rejection{"its derivatives are too long for muparser (" + std::to_string(length) +
                          " characters with the expression, at most " +
                          std::to_string(mu::MaxLenExpression) + ")",
                      "simplify it"};
    return out;
  } catch (const Rejection& r) {
    const std::string shown = text.size() <= 100 ? text : text.substr(0, 97) + "...";
    throw std::invalid_argument("cannot differentiate '" + shown + "' in time: " + r.reason +
                                (r.hint.empty() ? "" : "; " + r.hint));
  }
}

std::string muparser_text(const SymbolicDerivatives& d, const std::string& value) {
  std::string all;
  for (const auto& [name, text] : d.temporaries) all += name + " = " + text + ", ";
  all += "(" + value + ")";
  for (const auto& t : d.derivatives) all += ", " + t;
  return all;
}

void define_derivative_functions(mu::Parser& parser) {
  parser.DefineFun("_step_d", mu_step_d);
  parser.DefineFun("_step5_d", mu_step5_d);
}

}  // namespace lash
