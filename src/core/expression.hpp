#pragma once
/// @file expression.hpp
/// Expressions of time (and of body state) in model files, evaluated with muparser and extended
/// with the Adams functions step, step5, impact and bistop (core/adams_functions.hpp).
#include <memory>
#include <string>
#include <vector>

namespace lash {

/// Names an expression may read besides `time` (alias `t`): `<body>.<x|y|phi|vx|vy|omega>`.
struct ExpressionVariables {
  double time = 0.0;
  std::vector<std::string> body_names;
  std::vector<double> body_state;  ///< 6 per body: x, y, phi, vx, vy, omega
};

/// A compiled expression bound to an ExpressionVariables block.
class Expression {
 public:
  /// Compiles `text`; throws std::invalid_argument with muparser's message on a syntax error or
  /// an unknown name. `vars` must outlive the expression.
  Expression(const std::string& text, ExpressionVariables& vars);
  ~Expression();
  Expression(Expression&&) noexcept;
  Expression& operator=(Expression&&) noexcept;

  double eval() const;
  /// Value, first and second time derivative at time t (5-point central differences; the
  /// body-state variables are held fixed). Only meaningful for expressions of time alone.
  void eval_derivatives(double t, double& f, double& fdot, double& fddot) const;
  const std::string& text() const { return text_; }
  bool depends_on_state() const { return uses_state_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  ExpressionVariables* vars_;
  std::string text_;
  bool uses_state_ = false;
};

/// Checks an expression compiles with the given body names; returns "" or the error message.
std::string check_expression(const std::string& text, const std::vector<std::string>& body_names);

}  // namespace lash
