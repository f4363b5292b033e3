#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/integrator.hpp"

namespace lash {

namespace {

/// Failed right-hand sides, with no success past the latest failure's time in between, after
/// which the run stops. CVODE answers each failure with a smaller step and, when the right-hand
/// side fails from some time on, creeps toward that time with ever smaller successful steps,
/// without end.
constexpr long kMaxRhsFailures = 60;

/// CVODE's name of a return flag ("CV_TOO_MUCH_WORK"). CVodeGetReturnFlagName returns a string
/// it allocated with malloc, which the caller frees.
std::string flag_name(int flag) {
  char* name = CVodeGetReturnFlagName(flag);
  std::string s = name ? name : "flag " + std::to_string(flag);
  std::free(name);
  return s;
}

/// Every SUNDIALS call goes through here: a negative flag becomes an exception naming the call.
void check(int flag, const char* call) {
  if (flag < 0)
    throw std::runtime_error(std::string("SUNDIALS ") + call + " failed: " + flag_name(flag));
}
template <class T>
T* check_ptr(T* p, const char* call) {
  if (!p) throw std::runtime_error(std::string("SUNDIALS ") + call + " returned null");
  return p;
}

class CvodeBdf final : public Integrator {
 public:
  CvodeBdf(OdeProblem p, IntegratorOptions o) : p_(std::move(p)), o_(o) {
    check(SUNContext_Create(nullptr, &ctx_), "SUNContext_Create");
    y_ = check_ptr(N_VNew_Serial(p_.n, ctx_), "N_VNew_Serial");
    mem_ = check_ptr(CVodeCreate(CV_BDF, ctx_), "CVodeCreate");
  }
  ~CvodeBdf() override {
    if (mem_) CVodeFree(&mem_);
    if (ls_) SUNLinSolFree(ls_);
    if (a_) SUNMatDestroy(a_);
    if (y_) N_VDestroy(y_);
    if (ctx_) SUNContext_Free(&ctx_);
  }

  const char* name() const override { return "bdf"; }

  void reset(double t, const Eigen::VectorXd& y, double /*step: CVODE chooses its own*/) override {
    for (int i = 0; i < p_.n; ++i) NV_Ith_S(y_, i) = y[i];
    if (!initialised_) {
      check(CVodeInit(mem_, rhs_cb, t, y_), "CVodeInit");
      check(CVodeSetUserData(mem_, this), "CVodeSetUserData");
      check(CVodeSStolerances(mem_, o_.rtol, o_.atol), "CVodeSStolerances");
      check(CVodeSetErrHandlerFn(mem_, err_cb, this), "CVodeSetErrHandlerFn");
      check(CVodeSetMaxNumSteps(mem_, o_.max_steps), "CVodeSetMaxNumSteps");
      if (o_.max_step > 0) check(CVodeSetMaxStep(mem_, o_.max_step), "CVodeSetMaxStep");
      a_ = check_ptr(SUNDenseMatrix(p_.n, p_.n, ctx_), "SUNDenseMatrix");
      ls_ = check_ptr(SUNLinSol_Dense(y_, a_, ctx_), "SUNLinSol_Dense");
      check(CVodeSetLinearSolver(mem_, ls_, a_), "CVodeSetLinearSolver");
      if (p_.project || p_.halt) projected_.resize(p_.n);
      if (p_.n_events > 0) {
        check(CVodeRootInit(mem_, p_.n_events, root_cb), "CVodeRootInit");
        std::vector<int> dir(p_.n_events, 1);  // events are g rising through zero
        check(CVodeSetRootDirection(mem_, dir.data()), "CVodeSetRootDirection");
      }
      initialised_ = true;
    } else {
      accumulated_ = current();  // CVodeReInit zeroes CVODE's counters
      check(CVodeReInit(mem_, t, y_), "CVodeReInit");
      if (restarted_) CVodeSetInitStep(mem_, 0.0);  // CVODE's own estimate again
      restarted_ = false;
    }
    t_ = t;
    t_step_ = t;
    root_pending_ = false;
  }

  void dense_at(double t, Eigen::VectorXd& y) override {
    N_Vector v = N_VMake_Serial(p_.n, y.data(), ctx_);
    CVodeGetDky(mem_, t, 0, v);
    N_VDestroy(v);
  }

  bool reached_state(double& t, Eigen::VectorXd& y) override {
    if (CVodeGetCurrentTime(mem_, &t) != CV_SUCCESS) return false;
    y.resize(p_.n);
    N_Vector v = N_VMake_Serial(p_.n, y.data(), ctx_);
    const bool ok = CVodeGetDky(mem_, t, 0, v) == CV_SUCCESS;
    N_VDestroy(v);
    return ok;
  }

  void set_end_time(double t) override { o_.end_time = t; }

  Advance advance(double t_out, Eigen::VectorXd& y) override {
    if (t_out <= t_) {
      for (int i = 0; i < p_.n; ++i) y[i] = NV_Ith_S(y_, i);
      return {Advance::reached, t_, {}};
    }
    double t_ret = t_;
    last_error_.clear();
    // The smallest step: 16 ε·|t|. Below it a step no longer moves t by more than round-off,
    // and CVODE would creep on for its whole max_steps per output (tens of millions of steps,
    // minutes) where the right-hand side blows up (a load that diverges at an instant, a
    // stiffness of 1e300); with it CVODE fails there. Not DOPRI5's 16 ε·max(1, |t|): CVODE's
    // first steps after an event's restart go below that near t = 0, and clamping them changed
    // the runs that use BDF.
    CVodeSetMinStep(mem_, 16.0 * std::numeric_limits<double>::epsilon() * std::abs(t_));
    // max_steps counts the whole run, as under DOPRI5: CV_NORMAL mode, which counts the steps of
    // one call, is given what is left of it.
    const long used = current().steps;
    if (used >= o_.max_steps) {
      last_error_ = "maximum number of steps (" + std::to_string(o_.max_steps) + ") reached";
      for (int i = 0; i < p_.n; ++i) y[i] = NV_Ith_S(y_, i);
      return {Advance::failure, t_, last_error_};
    }
    CVodeSetMaxNumSteps(mem_, o_.max_steps - used);
    // No step past the run's end (a model need not be defined there): CVODE's stop time, set
    // again at each call (a restart or reaching it clears it).
    if (double t_now = t_; o_.end_time > 0 && CVodeGetCurrentTime(mem_, &t_now) == CV_SUCCESS &&
                           t_now < o_.end_time)
      CVodeSetStopTime(mem_, o_.end_time);
    int flag = hook_ || stop_ || p_.project || p_.halt ? one_step_to(t_out, t_ret)
                                                       : CVode(mem_, t_out, y_, &t_ret, CV_NORMAL);
    // Asked past end_time (a caller of its own going on): the stop time returned there, and,
    // reached, it no longer holds.
    while (flag == CV_TSTOP_RETURN && t_ret < t_out && !pending_)
      flag = CVode(mem_, t_out, y_, &t_ret, CV_NORMAL);
    if (pending_) {  // the right-hand side threw (e.g. an ExpressionError): CVODE has stopped
      std::exception_ptr e = pending_;
      pending_ = nullptr;
      std::rethrow_exception(e);
    }
    for (int i = 0; i < p_.n; ++i) y[i] = NV_Ith_S(y_, i);
    if (flag == kStopped) {
      t_ = t_ret;
      return {Advance::stopped, t_ret, {}};
    }
    if (flag == CV_ROOT_RETURN) {
      ++events_;
      t_ = t_ret;
      // The function that crossed: the lowest index among those CVODE found (all rising).
      roots_found_.assign(p_.n_events, 0);
      int which = -1;
      if (CVodeGetRootInfo(mem_, roots_found_.data()) == CV_SUCCESS)
        for (int k = 0; k < p_.n_events && which < 0; ++k)
          if (roots_found_[k] != 0) which = k;
      return {Advance::event, t_ret, {}, which};
    }
    if (flag < 0) {
      double t_cur = t_ret;
      CVodeGetCurrentTime(mem_, &t_cur);
      if (rhs_failures_ >= kMaxRhsFailures) {
        char msg[200];
        double h = 0.0;
        CVodeGetCurrentStep(mem_, &h);
        std::snprintf(msg, sizeof msg,
                      "the right-hand side failed %ld times without getting past t = %.9g s (last "
                      "step h = %.3e s): the state or its derivative is not finite, or the "
                      "constraints cannot be solved",
                      rhs_failures_, failed_at_, h);
        return {Advance::failure, failed_at_, msg};
      }
      return {Advance::failure, t_cur,
              flag_name(flag) + (last_error_.empty() ? "" : ": " + last_error_), -1,
              worst_component()};
    }
    t_ = t_ret;
    return {Advance::reached, t_ret, {}};
  }

  IntegratorStats stats() const override { return current(); }

  /// The component with the largest weighted local error estimate of CVODE's last step
  /// (CVodeGetEstLocalErrors times CVodeGetErrWeights; a NaN one first), −1 if not available.
  int worst_component() {
    N_Vector w = N_VNew_Serial(p_.n, ctx_), e = N_VNew_Serial(p_.n, ctx_);
    int worst = -1;
    if (w && e && CVodeGetErrWeights(mem_, w) == CV_SUCCESS &&
        CVodeGetEstLocalErrors(mem_, e) == CV_SUCCESS) {
      double most = -1.0;
      for (int i = 0; i < (p_.n_diagnosed > 0 ? p_.n_diagnosed : p_.n); ++i) {
        const double x = std::abs(NV_Ith_S(e, i) * NV_Ith_S(w, i));
        if (!(x <= most)) most = x, worst = i;
      }
      if (most == 0.0) worst = -1;  // no estimate (a failure before any step)
    }
    if (w) N_VDestroy(w);
    if (e) N_VDestroy(e);
    return worst;
  }

 private:
  /// one_step_to's return when the stop flag was raised (CVODE's own flags are 0..99 or < 0).
  static constexpr int kStopped = 1000;

  /// CVode in CV_ONE_STEP mode, step by step up to t_out, calling the step hook (if any) after
  /// each step and checking the stop flag before each: the steps are those of CV_NORMAL mode.
  /// A root located beyond t_out (one-step mode searches the whole step) is kept and returned once t_out passes it, so that outputs and
  /// events come in time order as in CV_NORMAL mode. Returns CVode's flag; y_ holds the state
  /// at t_ret.
  int one_step_to(double t_out, double& t_ret) {
    // max_steps counts the steps of the whole run (since the first reset), as under DOPRI5;
    // one step per call never reaches CVODE's own count.
    long steps = current().steps;
    for (;;) {
      if (root_pending_) {
        if (t_root_ <= t_out) {
          root_pending_ = false;
          check(CVodeGetDky(mem_, t_root_, 0, y_), "CVodeGetDky");
          t_ret = t_root_;
          return CV_ROOT_RETURN;
        }
        check(CVodeGetDky(mem_, t_out, 0, y_), "CVodeGetDky");
        t_ret = t_out;
        return CV_SUCCESS;
      }
      if (t_step_ >= t_out) {  // the last step passed t_out: interpolate there
        check(CVodeGetDky(mem_, t_out, 0, y_), "CVodeGetDky");
        t_ret = t_out;
        return CV_SUCCESS;
      }
      if (stop_requested()) {  // stop at the last step's end
        if (t_step_ > t_) check(CVodeGetDky(mem_, t_step_, 0, y_), "CVodeGetDky");
        t_ret = t_step_;
        return kStopped;
      }
      if (steps++ >= o_.max_steps) {
        char msg[160];
        std::snprintf(msg, sizeof msg,
                      "maximum number of steps (%ld) reached at t = %.9g s",
                      o_.max_steps, t_step_);
        last_error_ = msg;
        t_ret = t_step_;
        return CV_TOO_MUCH_WORK;
      }
      const double t0 = t_step_;
      double t1 = t0;
      const int flag = CVode(mem_, t_out, y_, &t1, CV_ONE_STEP);
      if (pending_ || flag < 0) {
        t_ret = t1;
        return flag;
      }
      if (flag == CV_ROOT_RETURN) {
        if (hook_) hook_(t0, t1);  // the step up to the root; what lies past it is integrated again
        root_pending_ = true;
        t_root_ = t1;
        continue;
      }
      t_step_ = t1;
      if (hook_) hook_(t0, t1);
      // The goal is the run's end where it is known: a pace that reaches each output within
      // the budget can still need hours for the run (a load of 1e3 sin(1e9 t)).
      if (std::string stalled = stall_.after_step(t0, t1, std::max(t_out, o_.end_time),
                                                  static_cast<double>(o_.max_steps - steps));
          !stalled.empty()) {
        last_error_ = stalled;
        t_ret = t1;
        return CV_TOO_MUCH_WORK;
      }
      if (p_.project && t1 < t_out) {
        // A state moved onto the constraints (near a singular position) restarts CVODE there:
        // its history would carry the jump into the next steps' predictor and error test. Not
        // at a step that passed t_out: the output is interpolated in it, which a restart forgets.
        Eigen::VectorXd& p = projected_;
        for (int i = 0; i < p_.n; ++i) p[i] = NV_Ith_S(y_, i);
        if (p_.project(t1, p)) {
          for (int i = 0; i < p_.n; ++i) NV_Ith_S(y_, i) = p[i];
          accumulated_ = current();
          double h = 0.0;  // go on with the step size reached, not CVODE's first-step estimate
          CVodeGetLastStep(mem_, &h);
          check(CVodeReInit(mem_, t1, y_), "CVodeReInit");
          CVodeSetInitStep(mem_, h);
          restarted_ = true;
        }
      }
      // Not at a step that passed t_out: the output there comes first, and is checked itself.
      if (p_.halt && t1 < t_out) {
        Eigen::VectorXd& p = projected_;
        for (int i = 0; i < p_.n; ++i) p[i] = NV_Ith_S(y_, i);
        if (p_.halt(t1, p)) {
          t_ret = t1;
          return kStopped;
        }
      }
    }
  }

  /// Counters since the first reset: those before the last CVodeReInit plus CVODE's own.
  IntegratorStats current() const {
    IntegratorStats s;
    long v = 0;
    CVodeGetNumSteps(mem_, &v);
    s.steps = accumulated_.steps + v;
    CVodeGetNumErrTestFails(mem_, &v);
    s.rejected_steps = accumulated_.rejected_steps + v;
    long fe = 0, fe_ls = 0;
    CVodeGetNumRhsEvals(mem_, &fe);
    CVodeGetNumLinRhsEvals(mem_, &fe_ls);
    s.rhs_evaluations = accumulated_.rhs_evaluations + fe + fe_ls;
    double h = 0;
    CVodeGetLastStep(mem_, &h);
    s.last_step = h;
    s.events = events_;
    return s;
  }

  static int rhs_cb(double t, N_Vector y, N_Vector ydot, void* data) {
    auto* self = static_cast<CvodeBdf*>(data);
    // No C++ exception may unwind through CVODE's C frames: keep it, make CVODE stop (a negative
    // return is unrecoverable), and rethrow it from advance().
    try {
      const bool ok = self->p_.rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
      if (ok) {
        if (t > self->failed_at_) self->rhs_failures_ = 0;  // got past the failure
        return 0;
      }
      self->failed_at_ = t;
      // 1: recoverable, CVODE retries with a smaller step; bounded here (−1 stops CVODE).
      return ++self->rhs_failures_ >= kMaxRhsFailures ? -1 : 1;
    } catch (...) {
      self->pending_ = std::current_exception();
      return -1;
    }
  }
  static int root_cb(double t, N_Vector y, double* g, void* data) {
    auto* self = static_cast<CvodeBdf*>(data);
    self->p_.events(t, N_VGetArrayPointer(y), g);
    return 0;
  }
  static void err_cb(int, const char*, const char*, char* msg, void* data) {
    static_cast<CvodeBdf*>(data)->last_error_ = msg;
  }

  OdeProblem p_;
  IntegratorOptions o_;
  StallCheck stall_{o_.max_steps};
  SUNContext ctx_ = nullptr;
  N_Vector y_ = nullptr;
  void* mem_ = nullptr;
  SUNMatrix a_ = nullptr;
  SUNLinearSolver ls_ = nullptr;
  bool initialised_ = false;
  double t_ = 0.0;
  double t_step_ = 0.0;       ///< end of the last step taken in one-step mode
  std::vector<int> roots_found_;  ///< CVodeGetRootInfo's answer at the last root
  bool root_pending_ = false; ///< one-step mode: a root at t_root_ not yet returned
  double t_root_ = 0.0;
  long events_ = 0;
  IntegratorStats accumulated_;
  std::string last_error_;
  std::exception_ptr pending_;  ///< thrown by the right-hand side during CVode()
  Eigen::VectorXd projected_;   ///< the step's end handed to p_.project and p_.halt
  bool restarted_ = false;      ///< a projection set CVODE's first step (reset() clears it)
  long rhs_failures_ = 0;       ///< failed right-hand sides since one succeeded past failed_at_
  double failed_at_ = 0.0;      ///< time of the last failed right-hand side
};

}  // namespace

std::unique_ptr<Integrator> make_cvode_bdf(OdeProblem problem, IntegratorOptions options) {
  return std::make_unique<CvodeBdf>(std::move(problem), options);
}

}  // namespace lash
