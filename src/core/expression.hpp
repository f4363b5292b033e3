#pragma once
/// @file expression.hpp
/// Expressions of time (and of body state) in model files, evaluated with muparser and extended
/// with the Adams functions step, step5, impact and bistop (core/adams_functions.hpp).
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

/// A compiled expression bound to an ExpressionVariables block.
class Expression {
 public:
  /// Compiles `text`; throws std::invalid_argument with muparser's message on a syntax error or
  /// an unknown name. `vars` (or the block it is moved into) must outlive the expression.
  Expression(const std::string& text, ExpressionVariables& vars);
  ~Expression();
  Expression(Expression&&) noexcept;
  Expression& operator=(Expression&&) noexcept;

  /// Value at the current variables. Throws ExpressionError if muparser fails.
  double eval() const;
  /// Value, first and second time derivative at time t (5-point central differences; the
  /// body-state variables are held fixed). Only meaningful for expressions of time alone.
  /// Throws ExpressionError if muparser fails (the time variable is restored).
  void eval_derivatives(double t, double& f, double& fdot, double& fddot) const;
  const std::string& text() const { return text_; }
  bool depends_on_state() const { return uses_state_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  double* time_;  ///< the bound time variable (ExpressionVariables::time's pinned storage)
  std::string text_;
  bool uses_state_ = false;
};

/// Checks an expression compiles with the given body names; returns "" or the error message.
std::string check_expression(const std::string& text, const std::vector<std::string>& body_names);

}  // namespace lash
