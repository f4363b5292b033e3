#pragma once
/// @file expression.hpp
/// Expressions of time (and of body state) in model files, evaluated with muparser and extended
/// with the Adams functions step, step5, impact and bistop (core/adams_functions.hpp); the time
/// derivatives a driver needs are exact (core/symbolic_derivatives.hpp).
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace lash {

/// A double kept at a fixed heap address that travels with its owner: muparser binds variables by
/// address, so an owner that moves (a Workspace returned by value or in a growing std::vector)
/// must carry the bound storage along rather than leave it behind. Reads and writes like a double.
class PinnedDouble {
 public:
  PinnedDouble(double v = 0.0) : p_(std::make_unique<double>(v)) {}  // NOLINT: implicit
  /// A copy is a new variable (expressions stay bound to the original).
  PinnedDouble(const PinnedDouble& o) : PinnedDouble(static_cast<double>(o)) {}
  /// Moving hands over the bound storage itself.
  PinnedDouble(PinnedDouble&&) noexcept = default;
  PinnedDouble& operator=(PinnedDouble&&) noexcept = default;
  PinnedDouble& operator=(const PinnedDouble& o) { return *this = static_cast<double>(o); }
  PinnedDouble& operator=(double v) {
    if (!p_) p_ = std::make_unique<double>();  // a moved-from variable may be reused
    *p_ = v;
    return *this;
  }
  operator double() const { return p_ ? *p_ : 0.0; }  // NOLINT: implicit
  /// The address expressions bind; stable for the lifetime of the storage, across moves.
  double* address() { return p_.get(); }

 private:
  std::unique_ptr<double> p_;
};

/// Names an expression may read besides `time` (alias `t`): `<body>.<x|y|phi|vx|vy|omega>`.
/// Expressions bind the storage of `time` and the elements of `body_state`; both keep their
/// addresses when the block is moved (PinnedDouble; a std::vector moves its buffer), so a moved
/// block, and the Workspace holding it, keeps its expressions valid. `body_state` must not be
/// resized once an expression is bound to it.
struct ExpressionVariables {
  PinnedDouble time = 0.0;  ///< s
  std::vector<std::string> body_names;
  std::vector<double> body_state;  ///< 6 per body: x, y, phi, vx, vy, omega
};

/// An expression that compiled but failed when evaluated, e.g. a step() whose bounds became
/// invalid as time advanced (muparser throws mu::ParserError, which is no std::exception).
/// what(): "expression 'TEXT' failed at time T s: MESSAGE".
class ExpressionError : public std::runtime_error {
 public:
  ExpressionError(const std::string& text, double time, const std::string& message);
  const std::string& text() const { return text_; }
  double time() const { return time_; }  ///< s, the time the expression was evaluated at

 private:
  std::string text_;
  double time_;
};

/// A compiled expression bound to an ExpressionVariables block, optionally with its first time
/// derivatives, exact: taken symbolically once, when it is compiled (core/symbolic_derivatives.hpp),
/// and evaluated by muparser together with the value.
class Expression {
 public:
  /// Compiles `text`, and with `time_derivatives` = n > 0 also its first n time derivatives.
  /// Throws std::invalid_argument with muparser's message on a syntax error or an unknown name,
  /// and "cannot differentiate 'TEXT' in time: REASON" when n > 0 and the text is not
  /// differentiable (it reads body state, compares, ...; symbolic_derivatives.hpp).
  /// `vars` (or the block it is moved into) must outlive the expression.
  Expression(const std::string& text, ExpressionVariables& vars, int time_derivatives = 0);
  ~Expression();
  Expression(Expression&&) noexcept;
  Expression& operator=(Expression&&) noexcept;

  /// Value at the current variables. Throws ExpressionError if muparser fails.
  double eval() const;
  /// The value and its first time_derivatives() time derivatives at time t, into
  /// out[0 .. time_derivatives()] (units of the value per s^k), exact but for rounding; the
  /// body-state variables are held as they are. The time variable is restored afterwards.
  /// Lock-free and allocation-free. Throws ExpressionError if muparser fails.
  void eval_derivatives(double t, double* out) const;
  /// How many time derivatives eval_derivatives() gives.
  int time_derivatives() const { return n_derivatives_; }
  const std::string& text() const { return text_; }
  bool depends_on_state() const { return uses_state_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  double* time_;  ///< the bound time variable (ExpressionVariables::time's pinned storage)
  std::string text_;
  bool uses_state_ = false;
  int n_derivatives_ = 0;
};

/// Checks an expression compiles with the given body names, that its value at time 0 is finite
/// and, with `time_derivatives` > 0, that it can be differentiated that many times in time with
/// finite derivatives at time 0; returns "" or the error message.
std::string check_expression(const std::string& text, const std::vector<std::string>& body_names,
                             int time_derivatives = 0);

}  // namespace lash
