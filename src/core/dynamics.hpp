#pragma once
/// @file dynamics.hpp
/// Equations of motion in planar body coordinates (Nikravesh, Computer-Aided Analysis of
/// Mechanical Systems, 1988, ch. 13):
///   M q̈ = g(q, q̇, t) + Φ_qᵀ λ,   Φ_q q̈ = γ − 2αΦ̇ − β²Φ  (Baumgarte),
/// q made of one coordinate block per body (core/kinematics.hpp). q̈ and λ come from the sparse
/// augmented system of core/constraint_solver.hpp. Every element kind lives in
/// core/elements/ and is listed in core/elements/registry.hpp. The ODE state is
///   y = [q (nq), q̇ (nq), auxiliary states (na), E_dissipated, W_input, W_stabilization].
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/constraint_solver.hpp"
#include "core/expression.hpp"
#include "core/kinematics.hpp"
#include "core/model.hpp"

namespace lash {

/// Everything a clearance joint reports at one instant (docs/architecture.md).
struct ClearanceOutput {
  Vec2 e = Vec2::Zero();       ///< eccentricity r_J − r_B, m
  double e_len = 0.0;          ///< |e|, m
  double delta = 0.0;          ///< penetration |e| − c, m (< 0 in free flight)
  double delta_dot = 0.0;      ///< ė·n, m/s
  double f_n = 0.0;            ///< normal force, N (≥ 0)
  double f_t = 0.0;            ///< tangential force on the journal along t, N
  double v_t = 0.0;            ///< relative tangential velocity, m/s
  Vec2 force = Vec2::Zero();   ///< force on the journal in world axes, −F_N n + F_T t, N
  double potential = 0.0;      ///< elastic energy, J
  double dissipation = 0.0;    ///< dissipated power, W
};

/// What a load did at the last evaluation (its channels).
struct LoadOutput {
  Vec2 force = Vec2::Zero();   ///< force on its second body (first for force loads), N
  double torque = 0.0;         ///< torque on its first body, N·m
  Vec2 deflection = Vec2::Zero();  ///< bushing: b − a in the frame's axes, m
  double power = 0.0;          ///< power of its forces on the bodies, W
};

/// Discrete state of a clearance joint: changed only at located events.
struct ContactState {
  bool in_contact = false;
};

/// The mutable companion of a finalized Model: coordinate and row layout, discrete state,
/// compiled expressions, preallocated matrices and the quantities of the last evaluation.
/// One per concurrent run; any number over one shared model, from any threads.
struct Workspace {
  /// Lays out coordinates, constraint rows and auxiliary states. The model must have been
  /// finalized (core/finalize.hpp); throws std::invalid_argument otherwise.
  explicit Workspace(const Model& model);

  int nb = 0;   ///< bodies
  int nq = 0;   ///< coordinates (sum of the block sizes)
  int m = 0;    ///< constraint equations
  int na = 0;   ///< auxiliary states
  int ny = 0;   ///< ODE state size, 2 nq + na + 2
  int nc = 0;   ///< clearance joints
  int i_dissipated = 0, i_input = 0;  ///< indices of E_dissipated and W_input in y
  int i_stabilization = 0;            ///< index of W_stabilization (Baumgarte forces' work) in y
  std::vector<BodyBlock> blocks;   ///< per body
  std::vector<int> row_of_joint;   ///< first constraint row of each joint (−1: clearance joint)
  std::vector<int> row_of_driver;  ///< constraint row of each driver
  /// The (at most two) bodies each constraint row touches, −1 for none/ground: Φ_q is sparse and
  /// the constraint solver's pattern is built from this structure.
  std::vector<std::array<int, 2>> row_bodies;
  std::vector<BodyKin> kin;        ///< per body, filled at the start of each evaluation
  std::vector<int> clearance_joints;  ///< joint indices of clearance joints
  std::vector<ContactState> contact;  ///< per clearance joint
  std::vector<int> aux_impact;     ///< per clearance joint: y index of its δ̇⁻
  std::vector<int> aux_bristle;    ///< per clearance joint: y index of LuGre's z, or −1
  std::vector<int> aux_driver;     ///< per driver: y index of its integrated speed, or −1
  std::vector<std::string> aux_names;  ///< per auxiliary state, `<element>.<state>`

  // Expressions, compiled against `vars` (a moved workspace keeps them bound: expression.hpp).
  ExpressionVariables vars;
  std::vector<std::optional<Expression>> driver_expr;  ///< per driver; none at constant speed
  std::vector<std::vector<Expression>> load_expr;   ///< per load: fx, fy or torque
  bool loads_use_state = false;

  /// The constant mass matrix M: its diagonal, and the entries above it (within a flexible
  /// link's block; rigid bodies and point masses have diagonal blocks).
  struct MassEntry {
    int i, j;
    double value;
  };
  Eigen::VectorXd mass_diag;
  std::vector<MassEntry> mass_coupling;
  /// Flexible links' meshes, per body (the BodyKin of a flexible link points here).
  std::vector<beam::Mesh> meshes;
  /// Flexible links' [q, q̇] blocks of the last update_kin (2 nq, at the blocks' offsets): their
  /// BodyKin points here.
  Eigen::VectorXd flexible_state;
  /// Cholesky factor of M where it is not diagonal and there are no constraints (set lazily).
  std::unique_ptr<Eigen::LLT<Eigen::MatrixXd>> mass_factor;

  // Work arrays (sized once). g: applied generalised forces (no constraint forces); rhs_m: the
  // stabilised constraint accelerations γ_B = γ − 2αΦ̇ − β²Φ.
  Eigen::VectorXd g, phi, phi_dot, gamma, rhs_m, lambda, qdd;
  Eigen::MatrixXd phi_q;
  /// The sparse constraint solver, set up at assembly (initial_state, constraint_problem) or at
  /// the first evaluation; redundant rows are dropped there and named in `warnings`.
  std::unique_ptr<ConstraintSolver> solver;
  std::vector<std::string> warnings;

  // Outputs of the last evaluate().
  std::vector<ClearanceOutput> clearance_out;
  std::vector<LoadOutput> load_out;
  double kinetic = 0.0, potential = 0.0, dissipated_power = 0.0, input_power = 0.0;
  /// Power of the constraint forces on the constraint drift, λ·Φ̇ (Baumgarte's work), W.
  double stabilization_power = 0.0;
  double constraint_violation = 0.0;  ///< max |Φ|, m or rad
  double violation_limit = 1e-3;  ///< run_violation_limit(model), m or rad
  long rhs_evaluations = 0;
  /// Set while the integrator evaluates a right-hand side it alone reads: the multipliers are
  /// left as solved (the powers use those), not replaced by the smallest ones that the
  /// channels report (smallest_multipliers: per redundant row a solve and an orthogonalisation,
  /// 75 % of a 40-crank parallelogram's run); report_multipliers() completes such an
  /// evaluation where its workspace is then observed.
  bool integrating = false;
  bool multipliers_reported = true;  ///< the last evaluation's λ are the reported ones
  /// Every channel at the output being delivered: simulate computes the row once, to refuse a
  /// row that is not finite, and channel_values hands it to the observers (the results writer,
  /// the analyses) while `output_row_y` points at the state it belongs to (null otherwise).
  std::vector<double> output_row;
  const double* output_row_y = nullptr;
  /// Choices of the redundant rows tried during the run (each an SVD of Φ_q:
  /// reselect_redundant_rows), made or refused.
  long row_choices = 0;
  long missed_events = 0;  ///< crossings found only by the mode/gap consistency check

  /// The cached kinematics of body b (the ground for kGround).
  const BodyKin& kin_of(int b) const {
    static const BodyKin ground;
    return b == kGround ? ground : kin[b];
  }
};

/// The mass matrix M (nq × nq), dense.
Eigen::MatrixXd mass_matrix(const Workspace& ws);
/// The same, sparse (nq entries and the flexible links' bands): for work on large models.
Eigen::SparseMatrix<double> sparse_mass_matrix(const Workspace& ws);

/// Kinematics of body b read directly from y (the ground for kGround).
BodyKin body_kin(const Workspace& ws, int b, const double* y);

/// Names of the entries of y, in order: `<body>.<x|y|phi>`, `<body>.<vx|vy|omega>`, the
/// auxiliary states' names, `energy.dissipated`, `energy.input`, `energy.stabilization`.
std::vector<std::string> state_names(const Model& model, const Workspace& ws);

/// Fills ws.kin from y.
void update_kin(Workspace& ws, const double* y);

/// Evaluates ẏ = f(t, y); fills the workspace's outputs (λ, contact and load quantities,
/// energies). Allocates nothing (after the first call, which sets up the constraint solver if
/// assembly has not). Returns false if a value is not finite (the constraint system itself
/// always factors: constraint_solver.hpp, kPivotFloor). Throws std::runtime_error if an expression cannot be evaluated.
bool evaluate(const Model& model, Workspace& ws, double t, const double* y, double* ydot);

/// After an evaluation made with ws.integrating set, the multipliers as the channels report
/// them (smallest_multipliers); nothing to do after any other. Call before the workspace's
/// channels are read.
void report_multipliers(Workspace& ws);

/// Event functions, one per clearance joint: g_k = s_k δ_k with s_k = +1 in free flight and −1 in
/// contact, so every event is g rising through zero (onset: δ ↑ 0; separation: δ ↓ 0); and,
/// unless `through` is null, through_k = δ_k − R_k (R_k the journal's radius), which rises
/// through zero where a journal goes through its bearing.
void event_functions(const Model& model, const Workspace& ws, const double* y, double* g,
                     double* through);

/// Constraint residual Φ(q, t) and max |Φ| (drift monitor).
double constraint_residual(const Model& model, Workspace& ws, double t, const double* y);

/// Builds a consistent initial state y(0) by Newton iteration on the position constraints and a
/// least-squares solve of the velocity constraints. Rule `ideal`: clearance joints are closed
/// (journals centred) and all velocities follow from the drivers. Rule `given`: the model's
/// poses and velocities are projected onto the actual constraints. Throws std::runtime_error if
/// the constraints cannot be satisfied.
Eigen::VectorXd initial_state(const Model& model, Workspace& ws);

/// Largest constraint residuals a state to continue from may have: |Φ| (m or rad) and |Φ̇|
/// (m/s or rad/s). A run's own states hold the Baumgarte-bounded drift, orders below these.
inline constexpr double kStateTolerancePosition = 1e-6;
/// A rigid body turned by assembly more than this from its given angle (rad, 10°) is warned of.
inline constexpr double kAssemblyTurnWarning = 0.17453292519943295;
/// A body moved by assembly more than this share of the mechanism's size (the diagonal of the
/// box around its given positions and markers, ground's origin included) is warned of.
inline constexpr double kAssemblyMoveWarning = 0.1;
/// The smallest size that share is taken of, m (moves below 0.1 mm are never warned of).
inline constexpr double kAssemblyMoveFloor = 1e-3;
inline constexpr double kStateToleranceVelocity = 1e-4;
/// Largest constraint residual |Φ| (m or rad) a run may reach: beyond it the joints have come
/// apart (a driver forcing a locked mechanism, a loop that does not close) and the run stops as
/// failed, naming the joint or driver. A run holds its constraints to round-off or to the
/// Baumgarte-bounded drift (1e-14 to 1e-6 on the examples and the singular-position tests).
inline constexpr double kRunViolationLimit = 1e-3;
/// ... or this share of the mechanism's size (the diagonal of the box around its joints' points
/// and bodies' centres at the start), where that is smaller: a 0.3 mm slider-crank driven past
/// its reach ran on with its joints 13 mm apart before it reached 1e-3 m.
inline constexpr double kRunViolationShare = 0.1;
/// The residual beyond which a run of `model` is pulled apart: the smaller of kRunViolationLimit
/// and kRunViolationShare of its size (kRunViolationLimit for a model of no size).
double run_violation_limit(const Model& model);

/// A run whose constraint stabilization did at least this share of the energy it moves (the
/// largest kinetic energy, the range of the potential energy, the work put in and dissipated)
/// ends with a warning: its joints were held by Baumgarte's terms, not by the motion (a
/// singular position not followed, a driver forcing a locked position). The examples stay
/// below 3e-9, parallelograms driven through their in-line positions at 2000 rpm below 2e-3; a
/// four-bar whose crank cannot turn a full revolution, driven through its dead position, did
/// 1e10 J on under 1 J of kinetic energy before it came apart.
inline constexpr double kStabilizationWarning = 1e-2;
/// Below this work (J), or this share of the largest kinetic plus |potential| energy at an
/// output, the stabilization's work is round-off and no warning is given, whatever its share of
/// the energy moved: a bar hanging at rest from a pin did 5.9e-13 J, 57 % of the nothing it
/// moved (a mechanism at rest, or held at a dead centre by a force).
inline constexpr double kStabilizationFloor = 1e-9;
inline constexpr double kStabilizationFloorShare = 1e-9;

/// Why y cannot be run at time t: a redundant driver or, with check_residual, constraint
/// residuals beyond kStateTolerance*. "" when it can. Sets up ws's constraint solver at y
/// (redundant joint equations are dropped and named in ws.warnings).
std::string constraint_problem(const Model& model, Workspace& ws, double t,
                               const Eigen::VectorXd& y, bool check_residual);

/// Near a singular position (the constraint solver's flag, kNearSingular in
/// core/constraint_solver.hpp): moves y onto the constraints, positions by Newton's method and
/// then velocities, each correction the mass-weighted least-squares one (Δq = M⁻¹Φ_qᵀμ, the
/// augmented system with no applied force), and books the change of kinetic plus potential
/// energy as stabilization work, so energy.balance is unchanged. Clears the flag. Returns false
/// (y untouched) away from singular positions, with no constraints, or if the state cannot be
/// evaluated. Leaves the workspace as evaluated at the returned state.
bool project_onto_constraints(const Model& model, Workspace& ws, double t, Eigen::VectorXd& y);

/// Moves y (positions, then velocities) to the nearest state, in the least-squares sense, that
/// satisfies the model's constraints at time t (clearance joints stay free). Used to perturb a
/// state consistently (Lyapunov exponents). Throws std::runtime_error if it does not converge.
void project_state(const Model& model, Workspace& ws, double t, Eigen::VectorXd& y);

/// Where the joints and drivers no longer close at (t, y) (a run pulled apart): the drivers
/// that ask for what the mechanism cannot do, each one without which the joints and the other
/// drivers close (in model order). Empty when a configuration near y satisfies every joint and
/// driver (the run lost it: steps too large for the stabilization), when the joints do not
/// close even without the drivers, or when no single driver is at fault. Gauss–Newton with
/// halving steps from y's positions (at most 60 iterations per trial: one with every row, one
/// without the drivers, one without each driver); restores ws's kinematics to y.
std::vector<int> drivers_out_of_reach(const Model& model, Workspace& ws, double t,
                                      const Eigen::VectorXd& y);

/// Driver coordinate target f and its derivatives at t (rad or m); `y` supplies the integrated
/// position of a speed profile.
void driver_motion(const Model& model, const Workspace& ws, int d, double t, const double* y,
                   double& f, double& fd, double& fdd);

}  // namespace lash
