#pragma once
/// @file integrator.hpp
/// The integrator interface the simulation loop drives: advance to an output time, stopping
/// early at a located event (an event function rising through zero).
#include <Eigen/Core>
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>

namespace lash {

/// An ODE ẏ = f(t, y) with event functions g(t, y) (events: g_k rising through 0).
struct OdeProblem {
  int n = 0;
  int n_events = 0;
  /// The leading components a failure may name as the one with the largest error
  /// (Advance::component); the others (integrals of powers, such as energy accounts) follow
  /// from them. 0: all n.
  int n_diagnosed = 0;
  /// Returns false if f cannot be evaluated (NaN, singular constraints).
  std::function<bool(double t, const double* y, double* ydot)> rhs;
  std::function<void(double t, const double* y, double* g)> events;
  /// Optional, called at the end of every accepted step not cut at an event: may move y (for
  /// the constraints of a state near a singular position); returns true if it did.
  std::function<bool(double t, Eigen::VectorXd& y)> project;
  /// Optional, called at the end of every accepted step not cut at an event (after `project`):
  /// true stops the run there, as the stop flag does (advance() returns `stopped` with y at
  /// that end), for a state the caller will not go on from (joints pulled apart).
  std::function<bool(double t, const Eigen::VectorXd& y)> halt;
};

struct IntegratorOptions {
  double rtol = 1e-6;
  double atol = 1e-9;
  double max_step = 0.0;    ///< 0: unlimited
  long max_steps = 50'000'000;
  double first_step = 0.0;  ///< 0: chosen automatically
  /// The run's end (0: unknown): both integrators, whose max_steps counts the whole run,
  /// measure a stall (StallCheck) against the steps left to reach it.
  double end_time = 0.0;
};

/// A run whose pace cannot reach its goal within its step budget stops at once, not after the
/// budget's steps (50 million by default: minutes to hours of creeping at a singular position,
/// or DOPRI5 on a problem too stiff for it). At the end of every window of accepted steps
/// (max_steps / 10, between 1 000 and 100 000), two paces are measured: the window's, and that
/// of every step since the budget's count began (begin(); else the first step). When at both
/// the goal lies more steps away than the budget leaves, the run has stalled. Both: a run whose
/// last window went at a pace that would see it through goes on, and so does one whose pace
/// since the start would (a legitimate crawl through a hard passage, such as stick-slip under
/// DOPRI5, followed by its usual pace).
class StallCheck {
 public:
  explicit StallCheck(long max_steps)
      : window_(std::max(1000L, std::min(100'000L, max_steps / 10))) {}
  /// Starts the count the budget is measured over at t (else at the first step's start).
  void begin(double t) {
    origin_ = t;
    total_ = 0;
    in_window_ = 0;
    begun_ = true;
  }
  /// After an accepted step [t0, t1]: "" or the failure message.
  std::string after_step(double t0, double t1, double goal, double budget) {
    if (!begun_) begin(t0);
    if (in_window_ == 0) from_ = t0;
    ++total_;
    if (++in_window_ < window_) return "";
    const long n = in_window_;
    in_window_ = 0;
    if (!(goal > t1)) return "";
    // (goal − t1) / pace with pace = advanced / steps; no advance at all is an infinite need.
    const double recent = (goal - t1) / (t1 - from_) * static_cast<double>(n),
                 overall = (goal - t1) / (t1 - origin_) * static_cast<double>(total_);
    if (!(recent > budget && overall > budget)) return "";
    char msg[400];
    std::snprintf(msg, sizeof msg,
                  "stalled: the last %ld steps advanced t by %.3e s, to %.9g s, and all %ld "
                  "since t = %.9g s by %.3e s; at either pace t = %.9g s is more steps away "
                  "(%.3g, %.3g) than the %.0f that solver.max_steps leaves",
                  n, t1 - from_, t1, total_, origin_, t1 - origin_, goal, recent, overall, budget);
    return msg;
  }

 private:
  long window_;
  long in_window_ = 0, total_ = 0;
  double from_ = 0.0, origin_ = 0.0;
  bool begun_ = false;
};

struct IntegratorStats {
  long steps = 0;
  long rejected_steps = 0;
  long rhs_evaluations = 0;
  long events = 0;
  double last_step = 0.0;
  /// States moved onto the constraints near a singular position (OdeProblem::project).
  long projections = 0;
  /// DOPRI5's stiffness test (Hairer, Nørsett & Wanner, Solving ODEs II, §IV.2): accepted steps
  /// taken while the test held, i.e. whose size stability, not accuracy, set (h·|λ| at the
  /// boundary of the method's stability region); the first such step's time and size.
  long stiff_steps = 0;
  double stiff_from = 0.0, stiff_step = 0.0;
};

/// Outcome of Integrator::advance.
struct Advance {
  /// stopped: the stop flag (set_stop_flag) was raised; y holds the last accepted step's end.
  enum Kind { reached, event, failure, stopped } kind = reached;
  double t = 0.0;           ///< time reached (t_out, the located event, the failure or stop time)
  std::string message;      ///< failure reason
  int index = -1;           ///< event: the event function that rose through zero (-1: unknown)
  /// failure: the component of y with the largest weighted local error in the last step tried
  /// (−1: unknown, e.g. a right-hand side that could not be evaluated)
  int component = -1;
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  /// (Re)starts from (t, y), e.g. after an event changed the right-hand side. A positive
  /// `step` is the first step size to try (a saved step_hint(), so a restarted run continues
  /// exactly as one that never stopped); otherwise the integrator keeps its own.
  virtual void reset(double t, const Eigen::VectorXd& y, double step = 0.0) = 0;
  /// The step size the integrator would try next (0 if it has none).
  virtual double step_hint() const { return 0.0; }
  /// Integrates toward t_out; y receives the state at the returned time. An event returns the
  /// first point found just past the crossing (g_k > 0 there).
  virtual Advance advance(double t_out, Eigen::VectorXd& y) = 0;
  /// Moves the time no step passes (IntegratorOptions::end_time; 0: none).
  virtual void set_end_time(double t) = 0;
  virtual IntegratorStats stats() const = 0;
  virtual const char* name() const = 0;

  /// Called after every accepted step with its interval [t0, t1] (a step that located an event
  /// ends at the event); dense_at() is valid on that interval while the hook runs. Without a
  /// hook (the default) nothing extra is done, and CVODE runs in its normal mode.
  using StepHook = std::function<void(double t0, double t1)>;
  void set_step_hook(StepHook hook) { hook_ = std::move(hook); }
  bool has_step_hook() const { return static_cast<bool>(hook_); }
  /// A flag checked before every step: once it is nonzero, advance() returns `stopped` at the
  /// last accepted step instead of going on to t_out (a signal handler stores the signal there).
  /// CVODE then steps in its one-step mode, which takes the same steps as its normal mode.
  void set_stop_flag(const std::atomic<int>* flag) { stop_ = flag; }
  /// The state at t in the last accepted step [t0, t1], from the integrator's dense output
  /// (Dormand–Prince: its 4th-order continuous extension; CVODE: CVodeGetDky on its
  /// interpolating polynomial).
  virtual void dense_at(double t, Eigen::VectorXd& y) = 0;
  /// While the hook runs: the state at the step's end t1 if the right-hand side's most recent
  /// evaluation was exactly (t1, that state), so whatever it filled in still describes t1;
  /// otherwise nullptr (then evaluate at dense_at(t1)). Dormand–Prince's last stage is its step
  /// end (first same as last), except where a step was cut at an event.
  virtual const Eigen::VectorXd* evaluated_end() const { return nullptr; }
  /// The last point the integration reached (the last accepted step's end), which after a
  /// failure lies past the point advance() last returned; false if there is none.
  virtual bool reached_state(double& t, Eigen::VectorXd& y) = 0;

 protected:
  bool stop_requested() const { return stop_ && stop_->load(std::memory_order_relaxed) != 0; }
  StepHook hook_;
  const std::atomic<int>* stop_ = nullptr;
};

/// Dormand–Prince 5(4) with error control, 4th-order dense output (Hairer, Nørsett & Wanner,
/// Solving ODEs I, §II.5–6) and event location on the dense output (Illinois method).
std::unique_ptr<Integrator> make_dopri5(OdeProblem problem, IntegratorOptions options);

/// SUNDIALS CVODE, variable-order BDF with Newton iterations on a dense finite-difference
/// Jacobian, and its root finding for events.
std::unique_ptr<Integrator> make_cvode_bdf(OdeProblem problem, IntegratorOptions options);

}  // namespace lash
