#pragma once
/// @file dynamics.hpp
/// Equations of motion in planar body coordinates (seed 001; Nikravesh):
///   M q̈ = g(q, q̇, t) + Φ_qᵀ λ,   Φ_q q̈ = γ − 2αΦ̇ − β²Φ  (Baumgarte),
/// q = [x, y, φ] per body. M is diagonal, so λ comes from the m×m Schur complement
/// (Φ_q M⁻¹ Φ_qᵀ) λ = γ_B − Φ_q M⁻¹ g, assembled from the sparse row structure and factored by
/// Cholesky. Clearance joints add no
/// constraint; they add contact forces to g. The ODE state is
///   y = [q (3nb), q̇ (3nb), E_dissipated, W_input].
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "core/expression.hpp"
#include "core/model.hpp"

namespace lash {

/// Everything a clearance joint reports at one instant (shared/reference/formulas.md).
struct ClearanceOutput {
  Vec2 e = Vec2::Zero();       ///< eccentricity r_J − r_B, m
  double e_len = 0.0;          ///< |e|, m
  double delta = 0.0;          ///< penetration |e| − c, m (< 0 in free flight)
  double delta_dot = 0.0;      ///< ė·n, m/s
  double f_n = 0.0;            ///< normal force, N (≥ 0)
  double f_t = 0.0;            ///< tangential force on the journal along t, N
  double v_t = 0.0;            ///< relative tangential velocity, m/s
  double potential = 0.0;      ///< elastic energy, J
  double dissipation = 0.0;    ///< dissipated power, W (≥ 0)
};

/// Pose and velocity of one body at the current evaluation (the ground: all zero, A = I).
struct BodyKin {
  Vec2 r = Vec2::Zero(), v = Vec2::Zero();
  double phi = 0.0, omega = 0.0;
  Eigen::Matrix2d A = Eigen::Matrix2d::Identity();
};

/// Discrete state of a clearance joint: changed only at located events.
struct ContactState {
  bool in_contact = false;
  double impact_velocity = 0.0;  ///< δ̇⁻ at the located onset, m/s
};

/// The mutable companion of a Model: discrete state, compiled expressions, preallocated
/// matrices and the quantities of the last evaluation. One per concurrent run.
struct Workspace {
  explicit Workspace(const Model& model);

  int nb = 0;   ///< bodies
  int nq = 0;   ///< 3 nb
  int m = 0;    ///< constraint equations
  int ny = 0;   ///< ODE state size, 2 nq + 2
  int nc = 0;   ///< clearance joints
  std::vector<int> row_of_joint;   ///< first constraint row of each joint (−1: clearance joint)
  std::vector<int> row_of_driver;  ///< constraint row of each driver
  /// The (at most two) bodies each constraint row touches, −1 for none/ground: Φ_q is sparse and
  /// the Schur complement is assembled from this structure.
  std::vector<std::array<int, 2>> row_bodies;
  /// Envelope of W = Φ_q M⁻¹ Φ_qᵀ: the first row j ≤ i sharing a body with row i. Cholesky keeps
  /// the envelope, so a chain's banded W factors in linear time.
  std::vector<int> row_first;
  std::vector<BodyKin> kin;        ///< per body, filled at the start of each evaluation
  std::vector<int> clearance_joints;  ///< joint indices of clearance joints
  std::vector<ContactState> contact;  ///< per clearance joint

  // Expressions (compiled against `vars`).
  ExpressionVariables vars;
  std::vector<Expression> driver_expr;              ///< per driver (or empty slot)
  std::vector<std::vector<Expression>> load_expr;   ///< per load: fx, fy or torque
  bool loads_use_state = false;

  // Work arrays (sized once).
  Eigen::VectorXd minv, g, phi, phi_dot, gamma, rhs_m, rate_m, lambda, qdd;
  Eigen::MatrixXd phi_q, w;

  // Outputs of the last evaluate().
  std::vector<ClearanceOutput> clearance_out;
  double kinetic = 0.0, potential = 0.0, dissipated_power = 0.0, input_power = 0.0;
  double constraint_violation = 0.0;  ///< max |Φ|, m or rad
  long rhs_evaluations = 0;
  long missed_events = 0;  ///< crossings found only by the mode/gap consistency check
};

/// Evaluates ẏ = f(t, y); fills the workspace's outputs (λ, contact quantities, energies).
/// Allocates nothing. Returns false if the constraint matrix is singular or a value is not finite.
bool evaluate(const Model& model, Workspace& ws, double t, const double* y, double* ydot);

/// Event functions, one per clearance joint: g_k = s_k δ_k with s_k = +1 in free flight and −1 in
/// contact, so every event is g rising through zero (onset: δ ↑ 0; separation: δ ↓ 0).
void event_functions(const Model& model, const Workspace& ws, const double* y, double* g);

/// Penetration δ and its rate δ̇ of clearance joint k (index into ws.clearance_joints).
void clearance_gap(const Model& model, const Workspace& ws, int k, const double* y, double& delta,
                   double& delta_dot);

/// Constraint residual Φ(q, t) and max |Φ| (drift monitor).
double constraint_residual(const Model& model, Workspace& ws, double t, const double* y);

/// Builds a consistent initial state y(0) by Newton iteration on the position constraints and a
/// least-squares solve of the velocity constraints. Rule `ideal`: clearance joints are closed
/// (journals centred) and all velocities follow from the drivers (shared/reference/mechanisms.md
/// §1). Rule `given`: the model's poses and velocities are projected onto the actual constraints.
/// Throws std::runtime_error if the constraints cannot be satisfied.
Eigen::VectorXd initial_state(const Model& model, Workspace& ws);

/// Moves y (positions, then velocities) to the nearest state, in the least-squares sense, that
/// satisfies the model's constraints at time t (clearance joints stay free). Used to perturb a
/// state consistently (Lyapunov exponents). Throws std::runtime_error if it does not converge.
void project_state(const Model& model, Workspace& ws, double t, Eigen::VectorXd& y);

/// Driver coordinate target f and its derivatives at t (rad or m).
void driver_motion(const Model& model, Workspace& ws, int d, double t, double& f, double& fd,
                   double& fdd);

}  // namespace lash
