#pragma once
/// @file symbolic_derivatives.hpp
/// Exact time derivatives of an expression of time: GiNaC parses the muparser text, differentiates
/// it symbolically, and the derivatives are printed back as muparser text, compiled and evaluated
/// by muparser like any expression (core/expression.hpp). GiNaC runs only here, when an expression
/// is compiled, under one process-wide mutex: GiNaC's reference counts and global tables are not
/// thread-safe (a program that also uses GiNaC itself on other threads must not do so while Lash
/// compiles driver expressions). Evaluation never touches GiNaC.
///
/// Differentiable: numbers, `time`/`t`, `pi`/`_pi`/`_e`; `+ - * / ^` (a^b^c needs parentheses);
/// sin cos tan asin acos atan atan2 sinh cosh tanh asinh acosh atanh exp sqrt ln log log2 log10;
/// abs sign rint min max sum avg; step step5 impact bistop (either case). Functions with a kink or
/// a jump (abs, sign, rint, min, max, step, impact, bistop) are differentiated piecewise: at the
/// kink itself the derivative is that of the branch the function's value takes there.
/// Not differentiable (rejected): comparisons, `&&`, `||`, `?:`, body-state variables.
#include <string>
#include <utility>
#include <vector>

namespace mu {
class Parser;
}

namespace lash {

/// An expression of time differentiated symbolically, as muparser texts in `time`.
struct SymbolicDerivatives {
  /// The expression as GiNaC read it, printed back: evaluated by muparser it must agree with the
  /// original text (a check that the two parsers read it alike).
  std::string value;
  /// Subexpressions the derivatives share, (name `_tmpK`, text) in evaluation order: each is
  /// assigned (`name = text`) before the derivatives are evaluated, and may read earlier ones.
  std::vector<std::pair<std::string, std::string>> temporaries;
  /// derivatives[k − 1] = d^k/dt^k; may read `time` and the temporaries.
  std::vector<std::string> derivatives;
};

/// Differentiates `text` (an expression of `time` alone in the syntax of core/expression.hpp
/// that muparser has already accepted) `order` times in time. The texts may call the functions
/// define_derivative_functions() adds. Thread-safe (serialised internally). Throws
/// std::invalid_argument "cannot differentiate 'TEXT' in time: REASON[; HINT]" when the text uses
/// something that is not differentiable (list above), GiNaC fails on it, or the derivatives grow
/// too large for muparser (mu::MaxLenExpression characters for all of muparser_text()).
SymbolicDerivatives symbolic_time_derivatives(const std::string& text, int order);

/// One muparser text giving, as its last 1 + order results, `value` (the original text) and the
/// derivatives: "_tmp0 = ..., _tmp1 = ..., (value), d/dt, d²/dt²". The temporaries must be
/// defined as variables of the parser that compiles it.
std::string muparser_text(const SymbolicDerivatives& d, const std::string& value);

/// Defines in `parser` the helper functions the derivative texts call besides muparser's own and
/// the Adams functions: `_step_d(n, x, x0, h0, x1, h1)` and `_step5_d(...)`, the n-th derivative
/// of step/step5 in x (step_derivative(), step5_derivative() in core/adams_functions.hpp). Every
/// expression parser has them (core/expression.cpp); they are not part of the documented syntax.
void define_derivative_functions(mu::Parser& parser);

}  // namespace lash
