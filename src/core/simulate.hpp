#pragma once
/// @file simulate.hpp
/// The run loop: consistent initial state, integration to each output time of the user's fixed
/// interval (from dense output, independent of the steps), located contact onsets and
/// separations, and numerical failures turned into a status.
#include <limits>
#include <Eigen/Core>
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "core/dynamics.hpp"
#include "core/integrator.hpp"
#include "core/model.hpp"

namespace lash {

/// Everything a run needs to continue: time, the ODE state y (coordinates, velocities,
/// auxiliary states, energy integrals; layout in Workspace) and the discrete modes of the
/// clearance joints, plus the integrator's next step size so that a continued run takes the
/// same steps as one that never stopped.
struct State {
  double t = 0.0;
  Eigen::VectorXd y;
  std::vector<ContactState> modes;  ///< per clearance joint
  double step = 0.0;                ///< next step size to try, s (0: the integrator chooses)
  /// Per clearance joint, its gap δ (m) when the state was saved, if the state file says
  /// (empty otherwise): continuing under another clearance or geometry is then said.
  std::vector<double> gaps;
  /// The name of the model that wrote the state, if the state file says ("" otherwise):
  /// continuing another model's state (the same coordinates by chance) is then said.
  std::string model;
  /// A state file without `model` (edited by hand): continuing it is said too.
  bool file_names_no_model = false;
};

/// A located contact onset or separation of one clearance joint.
struct ContactEvent {
  double t = 0.0;
  int clearance = 0;       ///< index into Workspace::clearance_joints
  bool onset = true;       ///< false: separation
  double velocity = 0.0;   ///< δ̇ at the located crossing (the impact velocity δ̇⁻ at onset), m/s
};

/// Evaluates the workspace at any time of the integrator step being reported to
/// Observer::step(), from the integrator's dense output.
class StepProbe {
 public:
  virtual ~StepProbe() = default;
  /// Evaluates the workspace (forces, accelerations: everything the outputs show) at t in the
  /// step [t0, t1]; the state there is state(). False if it cannot be evaluated there.
  virtual bool at(double t) = 0;
  /// Evaluates the workspace again at the step's end, the (t1, y) that step() was given.
  virtual bool at_end() = 0;
  virtual const Eigen::VectorXd& state() const = 0;
  virtual const Workspace& workspace() const = 0;
};

/// Receives results as they are produced (so nothing needs to be kept in memory).
class Observer {
 public:
  virtual ~Observer() = default;
  /// Called at every output time; `ws` holds the quantities evaluated at (t, y).
  virtual void output(double t, const Eigen::VectorXd& y, const Workspace& ws) = 0;
  virtual void event(const ContactEvent&, const Workspace&) {}
  /// Called after each output; `t_end` is the final time.
  virtual void progress(double /*t*/, double /*t_end*/) {}
  /// Called at every stroboscopic section time (see SectionSchedule); `ws` is evaluated there.
  virtual void section(double /*t*/, const Eigen::VectorXd& /*y*/, const Workspace& /*ws*/) {}
  /// True if step() is wanted; otherwise the run loop does nothing per step (no cost).
  virtual bool wants_steps() const { return false; }
  /// Called after every accepted integrator step [t0, t1] (a step that located an event ends at
  /// the event, before the event is handled); `ws` is evaluated at (t1, y). `probe` evaluates
  /// the workspace anywhere in [t0, t1] from the dense output (it changes `ws`).
  virtual void step(double /*t0*/, double /*t1*/, const Eigen::VectorXd& /*y*/,
                    const Workspace& /*ws*/, StepProbe& /*probe*/) {}
  /// Checked after every output: a non-empty reason (the results can no longer be written) stops
  /// the run there with outcome write_error.
  virtual std::string stop_reason() const { return {}; }
};

/// Stroboscopic Poincaré sections at t = start + k·period (k ≥ 0), taken from the integrator's
/// dense output like the regular outputs. period 0: none.
struct SectionSchedule {
  double period = 0.0;
  double start = 0.0;
};

/// An event-based Poincaré section: the plane y[index] = value in state space, crossed upwards
/// (direction +1) or downwards (−1), located by the integrator's root finding.
struct SectionPlane {
  int index = 0;       ///< into the ODE state y (q then q̇)
  double value = 0.0;
  int direction = 1;
};

/// How a run ended (summary.json `status.outcome`; the CLI's exit code follows it).
enum class RunOutcome { completed, failed, interrupted, write_error };
const char* outcome_name(RunOutcome o);

struct RunStatus {
  bool ok = true;
  double t = 0.0;
  std::string element;   ///< the element at fault, if one is
  std::string message;   ///< what happened, with the state that shows it
  RunOutcome outcome = RunOutcome::completed;  ///< failed whenever !ok, unless more is known
};

struct RunResult {
  RunStatus status;
  IntegratorStats stats;
  std::string integrator;
  double wall_seconds = 0.0;
  double max_constraint_violation = 0.0;
  long outputs = 0;
  long missed_events = 0;  ///< mode corrections at outputs (crossings no event function saw)
  State final_state;       ///< where the run stopped (the failure time on a failure)
  /// What assembly accepted with a caveat: redundant joint equations dropped (named).
  std::vector<std::string> warnings;
};

/// Options of one run beyond the model's solver settings.
struct RunOptions {
  const State* from = nullptr;   ///< continue from this state instead of the initial state
  /// Times (on the output grid) at which the integrator restarts as it does at an event; a run
  /// that stops at such a time and is continued with `from` gives bit-identical results.
  std::vector<double> restarts;
  /// Checked at every output and before every integrator step: when it holds a non-zero value
  /// (a signal number, set by a signal handler), the run stops there, at most one step later,
  /// with outcome interrupted, keeping everything up to it; final_state holds the state reached.
  const std::atomic<int>* interrupt = nullptr;
};

/// Integrates one model forward with its contact events, from a state the caller sets: the
/// building block of simulate() and of analyses that restart from modified states (Lyapunov).
class Simulator {
 public:
  Simulator(const Model& model, Workspace& ws, std::vector<SectionPlane> planes = {});
  ~Simulator();
  /// Starts from y at time t; each joint's mode follows the sign of its gap (δ̇⁻ = |δ̇| if in
  /// contact), or `modes` (e.g. a nearby trajectory's) where they agree with that sign.
  void start(double t, const Eigen::VectorXd& y, const std::vector<ContactState>* modes = nullptr);
  /// Continues from a saved state exactly: its modes and its step size as they are, except a
  /// mode that contradicts its joint's gap by more than round-off (a state edited by hand, or
  /// saved under another clearance): that joint starts in the mode of its gap (resume_warnings
  /// says so), with δ̇⁻ = |δ̇| if that is contact.
  void resume(const State& state);
  /// The current state, ready to be saved and resumed.
  State snapshot() const;
  /// Integrates to t_target, handling contact events and plane crossings (reported to
  /// `observer` when given: event() and section()).
  /// Returns false on a numerical failure, or when the interrupt flag was raised (outcome
  /// interrupted, at the last accepted step); status() says what happened.
  bool advance_to(double t_target, Observer* observer);
  /// The time no integrator step passes (the model's end_time at the start): a model need not
  /// be defined past it, and a run continued from there repeats this one's last steps.
  void set_end_time(double t);
  /// A flag (a signal number, 0: none) checked before every integrator step.
  void set_interrupt(const std::atomic<int>* flag);
  double time() const { return t_; }
  const Eigen::VectorXd& state() const { return y_; }
  const RunStatus& status() const { return status_; }
  IntegratorStats stats() const;
  const char* integrator_name() const;

 private:
  const Model& model_;
  Workspace& ws_;
  bool near_singular_ = false;  ///< the last step ended near a singular position
  long projections_ = 0;        ///< states moved onto the constraints there
  long through_events_ = 0;     ///< located journals through their bearings (not contact events)
  /// The largest constraint residual of the integrator's last right-hand side (at a DOPRI5
  /// step's end, its state), and whether a step's end was found beyond the workspace's violation_limit.
  double rhs_violation_ = 0.0;
  bool pulled_apart_ = false;
  /// The event functions of the integrated problem: the clearance joints' contact functions,
  /// then their through-the-bearing functions.
  void problem_events(const double* y, double* g) const;
  /// The planes' rising crossings inside the step [t0, t1], on its dense output, reported to
  /// `observer` in time order (the step hook's first task).
  void plane_crossings(double t0, double t1, Observer* observer);
  std::vector<SectionPlane> planes_;
  Eigen::VectorXd plane_y_;
  std::unique_ptr<Integrator> integrator_;
  Eigen::VectorXd y_, y_try_, g_event_, ydot_;
  Observer* stepping_ = nullptr;  ///< the observer the step hook reports to
  /// Sets the integrator's step hook for `observer` (none when it wants no steps).
  void hook_steps(Observer* observer);
  double t_ = 0.0;
  /// Contact events that do not advance time: the first one's time and how many there were.
  double burst_t_ = -std::numeric_limits<double>::infinity();
  long burst_events_ = 0;
  RunStatus status_;
  const std::atomic<int>* interrupt_ = nullptr;
};

/// Runs the model's solver settings from the initial-state rule to end_time.
/// Throws std::runtime_error only when no consistent initial state exists.
RunResult simulate(const Model& model, Workspace& ws, Observer& observer,
                   const SectionSchedule& sections = {},
                   const std::vector<SectionPlane>& planes = {}, const RunOptions& options = {});

/// Checks that `state` fits the model's workspace layout; returns "" or what differs.
std::string state_mismatch(const Workspace& ws, const State& state);

/// Why a run cannot continue from `state`: a layout that differs, a time before 0 or not before
/// end_time, a step size below what the integrator can take there, redundant joints and
/// drivers, constraint residuals beyond kStateTolerance* (a state of a model with other joints,
/// markers or driver motion), or a journal deeper in its bearing's wall than its own radius.
/// "" if it can.
std::string resume_problem(const Model& model, Workspace& ws, const State& state);

/// What is odd but allowed in continuing from `state`: a clearance joint whose gap differs from
/// the one saved with the state (the model's clearance or geometry changed since), with the
/// contact force it then starts with; a mode that contradicts the gap (corrected by resume).
std::vector<std::string> resume_warnings(const Model& model, Workspace& ws, const State& state);
/// A run is said to be stiff for its integrator when at least this many steps, and half of all,
/// were taken while DOPRI5's stiffness test held (IntegratorStats::stiff_steps).
inline constexpr long kStiffWarningSteps = 10'000;
/// "" or the warning that a run was stiff for its (explicit) integrator, naming BDF.
std::string stiffness_warning(const IntegratorStats& stats, const std::string& integrator);

/// Parses "<body>.<x|y|phi|vx|vy|omega>=VALUE[,down]" into a plane; throws
/// std::invalid_argument naming what is wrong.
SectionPlane parse_section_plane(const Model& model, const std::string& spec);

}  // namespace lash
