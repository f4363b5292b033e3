#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/integrator.hpp"

namespace lash {

namespace {

// Dormand–Prince 5(4) tableau (Hairer, Nørsett & Wanner, Solving ODEs I, Table II.5.2).
constexpr double c2 = 1.0 / 5, c3 = 3.0 / 10, c4 = 4.0 / 5, c5 = 8.0 / 9;
constexpr double a21 = 1.0 / 5;
constexpr double a31 = 3.0 / 40, a32 = 9.0 / 40;
constexpr double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
constexpr double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561,
                 a54 = -212.0 / 729;
constexpr double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247,
                 a64 = 49.0 / 176, a65 = -5103.0 / 18656;
constexpr double a71 = 35.0 / 384, a73 = 500.0 / 1113, a74 = 125.0 / 192,
                 a75 = -2187.0 / 6784, a76 = 11.0 / 84;
// Error estimate: 5th-order minus embedded 4th-order weights.
constexpr double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920,
                 e5 = -17253.0 / 339200, e6 = 22.0 / 525, e7 = -1.0 / 40;
// Dense output (Hairer's contd5).
constexpr double d1 = -12715105075.0 / 11282082432.0, d3 = 87487479700.0 / 32700410799.0,
                 d4 = -10690763975.0 / 1880347072.0, d5 = 701980252875.0 / 199316789632.0,
                 d6 = -1453857185.0 / 822651844.0, d7 = 69997945.0 / 29380423.0;

class Dopri5 final : public Integrator {
 public:
  Dopri5(OdeProblem p, IntegratorOptions o) : p_(std::move(p)), o_(o) {
    const int n = p_.n;
    for (auto* v : {&y_, &k1_prev_, &k1_, &k2_, &k3_, &k4_, &k5_, &k6_, &k7_, &yt_, &ynew_, &r1_, &r2_,
                    &r3_, &r4_, &r5_})
      v->resize(n);
    g_old_.resize(p_.n_events);
    g_new_.resize(p_.n_events);
    g_tmp_.resize(p_.n_events);
    for (auto& g : g_quarter_) g.resize(p_.n_events);
    ye_.resize(n);
  }

  const char* name() const override { return "dopri5"; }
  IntegratorStats stats() const override { return stats_; }

  void reset(double t, const Eigen::VectorXd& y, double step) override {
    if (step > 0.0) h_ = step;
    t_ = t;
    y_ = y;
    have_step_ = false;
    pending_event_ = false;
    halted_ = false;
    need_k1_ = true;
    if (p_.n_events > 0) p_.events(t_, y_.data(), g_old_.data());
  }

  double step_hint() const override { return h_; }

  bool reached_state(double& t, Eigen::VectorXd& y) override {
    t = t_;
    y = y_;
    return true;
  }

  void set_end_time(double t) override { o_.end_time = t; }

  Advance advance(double t_out, Eigen::VectorXd& y) override {
    for (;;) {
      // Serve the request from the last accepted step where it lies inside.
      if (have_step_) {
        if (pending_event_ && t_out >= t_event_) {
          dense(t_event_, y);
          ++stats_.events;
          return {Advance::event, t_event_, {}, event_k_};
        }
        if (t_out <= t_) {
          dense(t_out, y);
          return {Advance::reached, t_out, {}};
        }
      } else if (t_out <= t_) {
        y = y_;
        return {Advance::reached, t_, {}};
      }
      if (pending_event_) {  // the caller must reset() at the event first
        return {Advance::failure, t_, "internal: advance past an unhandled event"};
      }
      if (halted_ || stop_requested()) {
        y = y_;
        return {Advance::stopped, t_, {}};
      }
      t_out_ = t_out;
      if (auto fail = step(); !fail.empty())
        return {Advance::failure, t_, fail, -1, worst_component_};
    }
  }

 private:
  bool f(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dy) {
    ++stats_.rhs_evaluations;
    return p_.rhs(t, y.data(), dy.data()) && dy.allFinite();
  }

  /// The weighted RMS norm; `worst` (if given) receives the component with the largest weighted
  /// error (a NaN one first), which a failure names.
  double error_norm(const Eigen::VectorXd& err, const Eigen::VectorXd& y0,
                    const Eigen::VectorXd& y1, int* worst = nullptr) const {
    double sum = 0.0, most = -1.0;
    for (int i = 0; i < p_.n; ++i) {
      const double sc = o_.atol + o_.rtol * std::max(std::abs(y0[i]), std::abs(y1[i]));
      const double e = (err[i] / sc) * (err[i] / sc);
      sum += e;
      if (worst && i < diagnosed_ && !(e <= most)) most = e, *worst = i;
    }
    if (worst && most == 0.0) *worst = -1;
    return std::sqrt(sum / p_.n);
  }

  double initial_step() {
    // Hairer's starting-step heuristic (Solving ODEs I, §II.4).
    const double d0 = error_norm(y_, Eigen::VectorXd::Zero(p_.n), y_);
    const double d1n = error_norm(k1_, Eigen::VectorXd::Zero(p_.n), y_);
    double h0 = (d0 < 1e-5 || d1n < 1e-5) ? 1e-6 : 0.01 * d0 / d1n;
    if (o_.max_step > 0) h0 = std::min(h0, o_.max_step);
    yt_ = y_ + h0 * k1_;
    if (!f(t_ + h0, yt_, k2_)) return h0 * 1e-3;
    const double d2 = error_norm(k2_ - k1_, Eigen::VectorXd::Zero(p_.n), y_) / h0;
    const double dm = std::max(d1n, d2);
    const double h1 = dm <= 1e-15 ? std::max(1e-6, h0 * 1e-3) : std::pow(0.01 / dm, 1.0 / 5);
    double h = std::min(100 * h0, h1);
    if (o_.max_step > 0) h = std::min(h, o_.max_step);
    return h;
  }

  /// One accepted step (with retries). Returns "" or a failure message.
  std::string step() {
    if (need_k1_) {
      if (!f(t_, y_, k1_)) {
        worst_component_ = -1;
        return "the right-hand side is not finite or the constraints are singular";
      }
      need_k1_ = false;
      if (h_ <= 0.0) h_ = o_.first_step > 0 ? o_.first_step : initial_step();
    }
    bool rejected_last = false;
    for (;;) {
      if (stats_.steps >= o_.max_steps)
        return "maximum number of steps (" + std::to_string(o_.max_steps) + ") reached";
      double h = h_;
      if (o_.max_step > 0) h = std::min(h, o_.max_step);
      // No stage past the run's end: a model need not be defined there (a load of
      // sqrt(1 − time) with end_time 1 s failed at t = 1.00005 s and lost the rows before it).
      // A step that would end within 1 % of a step of it ends on it, unless that passes
      // max_step; a remainder below the smallest step (after an event just before the end) is
      // stepped over as before.
      const double left = o_.end_time - t_;
      const bool to_end = left > 16.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(t_)) &&
                          1.01 * h >= left && (o_.max_step <= 0 || left <= o_.max_step);
      if (to_end) h = left;
      if (h < 16.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(t_)))
      {
        char msg[96];
        std::snprintf(msg, sizeof msg, "step size underflow (h = %.3e s at t = %.9g s)", h, t_);
        return msg;
      }
      const bool ok = stages(y_, k1_, t_, h);
      // Stiffness (Hairer, Nørsett & Wanner, Solving ODEs II, §IV.2, eq. 2.27): k7 and k6 are
      // f at t + h of ynew_ and of the 6th stage's state yt_, so |k7 − k6| / |ynew_ − yt_|
      // estimates the Jacobian's dominant |λ|; h·|λ| near 3.3 is the edge of DOPRI5's
      // stability region on the negative real axis. Tested every kStiffEvery steps and at every
      // step once a test held. yt_ is the error estimate's next.
      // The components diagnosed only (OdeProblem::n_diagnosed): the energy accounts' rows,
      // dE/dt = P(q, q̇), are no eigenvalues of the motion.
      double h_lambda = 0.0;
      if (ok && (stiff_run_ > 0 || stats_.steps % kStiffEvery == 0)) {
        const double den = (ynew_ - yt_).head(diagnosed_).squaredNorm();
        if (den > 0.0) h_lambda = h * std::sqrt((k7_ - k6_).head(diagnosed_).squaredNorm() / den);
      }
      if (!ok) {  // a stage left the domain: shrink hard and retry
        ++stats_.rejected_steps;
        worst_component_ = -1;  // not known: the right-hand side failed
        h_ = 0.25 * h;
        rejected_last = true;
        continue;
      }
      yt_ = h * (e1 * k1_ + e3 * k3_ + e4 * k4_ + e5 * k5_ + e6 * k6_ + e7 * k7_);
      const double err = error_norm(yt_, y_, ynew_, &worst_component_);
      double fac = err > 0 ? 0.9 * std::pow(err, -0.2) : 5.0;
      if (err > 1.0 || !std::isfinite(err)) {
        ++stats_.rejected_steps;
        h_ = h * std::clamp(std::isfinite(err) ? fac : 0.2, 0.2, 1.0);
        rejected_last = true;
        continue;
      }
      // Accepted: dense-output coefficients over [t, t + h].
      r1_ = y_;
      dense_coefficients(k1_, h);
      t_old_ = t_;
      h_step_ = h;
      t_ = to_end ? o_.end_time : t_ + h;
      y_ = ynew_;
      k1_prev_ = k1_;
      k1_ = k7_;
      have_step_ = true;
      end_evaluated_ = true;  // k7 = f(t_, y_); a step cut at an event clears it
      ++stats_.steps;
      stats_.last_step = h;
      count_stiffness(h_lambda);
      h_ = h * std::clamp(fac, 0.2, rejected_last ? 1.0 : 10.0);
      locate_events();
      if (hook_) hook_(t_old_, t_);  // the step, cut at a located event
      if (!pending_event_ && p_.project && p_.project(t_, y_)) {
        need_k1_ = true;  // the next step starts from the moved state
        end_evaluated_ = false;
        if (p_.n_events > 0) p_.events(t_, y_.data(), g_old_.data());
      }
      if (!pending_event_ && p_.halt && p_.halt(t_, y_)) {
        halted_ = true;
        return "";
      }
      // max_steps counts the whole run: the goal is its end where it is known.
      return stall_.after_step(t_old_, t_, std::max(t_out_, o_.end_time),
                               static_cast<double>(o_.max_steps - stats_.steps));
    }
  }

  /// Hairer's rule: h·|λ| > 3.25 at 15 tests (no 6 below it in a row between them) starts a
  /// stiff stretch; 6 tests in a row below it end it. The steps of a stretch, from the one that
  /// started it, count in stats_.stiff_steps (h·|λ| hovers about the boundary there: rejected
  /// steps push it above, the controller's growth below).
  void count_stiffness(double h_lambda) {
    if (h_lambda > 3.25) {
      non_stiff_ = 0;
      if (++stiff_run_ >= 15 && !in_stiff_stretch_) {
        in_stiff_stretch_ = true;
        if (stats_.stiff_steps == 0) stats_.stiff_from = t_old_, stats_.stiff_step = h_step_;
      }
    } else if (stiff_run_ > 0 && ++non_stiff_ == 6) {
      stiff_run_ = 0;
      in_stiff_stretch_ = false;
    }
    if (in_stiff_stretch_) ++stats_.stiff_steps;
  }

  void dense_at(double t, Eigen::VectorXd& y) override { dense(t, y); }
  const Eigen::VectorXd* evaluated_end() const override { return end_evaluated_ ? &y_ : nullptr; }

  void dense(double t, Eigen::VectorXd& y) const {
    const double th = (t - t_old_) / h_step_, th1 = 1.0 - th;
    y = r1_ + th * (r2_ + th1 * (r3_ + th * (r4_ + th1 * r5_)));
  }

  double g_at(int k, double t) {
    dense(t, ye_);
    p_.events(t, ye_.data(), g_tmp_.data());
    return g_tmp_[k];
  }

  /// Finds the first event in the accepted step [t_old_, t_]: g_k rising through zero, checked
  /// at four points of the dense output, then bracketed by the Illinois method. The event
  /// functions are evaluated once per point for all of them (each evaluation computes every
  /// g_k: per point and function it made the cost grow with the square of their number).
  void locate_events() {
    if (p_.n_events == 0) return;
    p_.events(t_, y_.data(), g_new_.data());
    bool have_quarter[3] = {false, false, false};
    auto quarter = [&](int s) -> const Eigen::VectorXd& {  // g at t_old_ + s·h/4, s = 1, 2, 3
      Eigen::VectorXd& g = g_quarter_[s - 1];
      if (!have_quarter[s - 1]) {
        const double t = t_old_ + 0.25 * s * h_step_;
        dense(t, ye_);
        p_.events(t, ye_.data(), g.data());
        have_quarter[s - 1] = true;
      }
      return g;
    };
    double best = std::numeric_limits<double>::infinity();
    int best_k = -1;
    for (int k = 0; k < p_.n_events; ++k) {
      double ta = t_old_, ga = g_old_[k];
      for (int s = 1; s <= 4; ++s) {
        const double tb = s == 4 ? t_ : t_old_ + 0.25 * s * h_step_;
        const double gb = s == 4 ? g_new_[k] : quarter(s)[k];
        if (ga <= 0.0 && gb > 0.0) {
          const double tk = bracket(k, ta, ga, tb, gb);
          if (tk < best) best = tk, best_k = k;
          break;
        }
        ta = tb;
        ga = gb;
      }
    }
    g_old_ = g_new_;
    if (std::isfinite(best)) {
      t_event_ = best;
      event_k_ = best_k;
      pending_event_ = true;
      redo_step_to(best, best_k);  // may move t_event_ just past the redone crossing
    }
  }

  /// Recomputes the accepted step so it ends at the located event t_e: stages past the crossing
  /// already felt the new contact state and would bias the state read at the crossing (δ̇⁻).
  /// The redone state must lie past the crossing too (g_k > 0); at a grazing crossing it may not,
  /// and then the original step's dense output at t_e, which does by construction, is kept.
  void redo_step_to(double t_e, int k) {
    end_evaluated_ = false;
    auto keep_dense = [&]() {
      dense(t_e, ye_);
      y_ = ye_;
      t_ = t_e;
      need_k1_ = true;
    };
    // The redone trajectory crosses slightly apart from the dense output it was located on:
    // step past its own crossing with a secant estimate (at most three tries).
    double slope = 0.0;
    if (k >= 0) {
      const double dt = 1e-3 * h_step_;
      slope = (g_at(k, t_e) - g_at(k, t_e - dt)) / dt;
    }
    double t_try = t_e;
    for (int attempt = 0; attempt < 4; ++attempt) {
      const double h = t_try - t_old_;
      if (!(h > 0.0) || t_try > t_old_ + h_step_) return keep_dense();
      if (!stages(r1_, k1_prev_, t_old_, h)) return keep_dense();
      if (k < 0) break;
      p_.events(t_try, ynew_.data(), g_tmp_.data());
      if (g_tmp_[k] > 0.0) break;
      if (attempt == 3 || !(slope > 0.0)) return keep_dense();
      t_try += std::max(2.0 * -g_tmp_[k] / slope,
                        8 * std::numeric_limits<double>::epsilon() * std::abs(t_try));
    }
    const double h = t_try - t_old_;
    dense_coefficients(k1_prev_, h);
    h_step_ = h;
    t_ = t_try;
    t_event_ = t_try;
    y_ = ynew_;
    k1_ = k7_;
  }

  /// The stages k2…k7 of a step of size h from (t0, y0) with first stage k1, and the 5th-order
  /// solution ynew_ at t0 + h. False if a stage cannot be evaluated.
  bool stages(const Eigen::VectorXd& y0, const Eigen::VectorXd& k1, double t0, double h) {
    yt_ = y0 + h * a21 * k1;
    if (!f(t0 + c2 * h, yt_, k2_)) return false;
    yt_ = y0 + h * (a31 * k1 + a32 * k2_);
    if (!f(t0 + c3 * h, yt_, k3_)) return false;
    yt_ = y0 + h * (a41 * k1 + a42 * k2_ + a43 * k3_);
    if (!f(t0 + c4 * h, yt_, k4_)) return false;
    yt_ = y0 + h * (a51 * k1 + a52 * k2_ + a53 * k3_ + a54 * k4_);
    if (!f(t0 + c5 * h, yt_, k5_)) return false;
    yt_ = y0 + h * (a61 * k1 + a62 * k2_ + a63 * k3_ + a64 * k4_ + a65 * k5_);
    if (!f(t0 + h, yt_, k6_)) return false;
    ynew_ = y0 + h * (a71 * k1 + a73 * k3_ + a74 * k4_ + a75 * k5_ + a76 * k6_);
    return f(t0 + h, ynew_, k7_);
  }

  /// Dense-output coefficients of the step from r1_ to ynew_ (Hairer's contd5).
  void dense_coefficients(const Eigen::VectorXd& k1, double h) {
    r2_ = ynew_ - r1_;
    r3_ = h * k1 - r2_;
    r4_ = r2_ - h * k7_ - r3_;
    r5_ = h * (d1 * k1 + d3 * k3_ + d4 * k4_ + d5 * k5_ + d6 * k6_ + d7 * k7_);
  }

  double bracket(int k, double a, double ga, double b, double gb) {
    const double tol = std::max(1e-9 * h_step_, 4 * std::numeric_limits<double>::epsilon() *
                                                    std::abs(b));
    int side = 0;
    for (int it = 0; it < 200 && b - a > tol; ++it) {
      double c = b - gb * (b - a) / (gb - ga);
      if (!(c > a && c < b)) c = 0.5 * (a + b);
      const double gc = g_at(k, c);
      if (gc > 0.0) {
        b = c;
        gb = gc;
        if (side == 1) ga *= 0.5;
        side = 1;
      } else {
        a = c;
        ga = gc;
        if (side == -1) gb *= 0.5;
        side = -1;
      }
    }
    return b;  // just past the crossing: g_k > 0 here
  }

  OdeProblem p_;
  IntegratorOptions o_;
  IntegratorStats stats_;
  StallCheck stall_{o_.max_steps};
  double t_out_ = 0.0;  ///< the time the running advance() goes to
  double t_ = 0.0, t_old_ = 0.0, h_ = 0.0, h_step_ = 0.0, t_event_ = 0.0;
  int event_k_ = -1;  ///< the event function of the pending event
  int worst_component_ = -1;  ///< the largest weighted error of the last step tried (Advance)
  int diagnosed_ = p_.n_diagnosed > 0 ? p_.n_diagnosed : p_.n;  ///< OdeProblem::n_diagnosed
  bool have_step_ = false, need_k1_ = true, pending_event_ = false, end_evaluated_ = false;
  bool halted_ = false;  ///< p_.halt stopped the run at the last step's end
  static constexpr long kStiffEvery = 1000;  ///< steps between stiffness tests (Hairer's nstiff)
  long stiff_run_ = 0, non_stiff_ = 0;       ///< tests above 3.25 / in a row below it
  bool in_stiff_stretch_ = false;
  Eigen::VectorXd y_, k1_prev_, k1_, k2_, k3_, k4_, k5_, k6_, k7_, yt_, ynew_, r1_, r2_, r3_, r4_, r5_, ye_;
  Eigen::VectorXd g_old_, g_new_, g_tmp_;
  Eigen::VectorXd g_quarter_[3];  ///< the event functions at a step's quarter points
};

}  // namespace

std::unique_ptr<Integrator> make_dopri5(OdeProblem problem, IntegratorOptions options) {
  return std::make_unique<Dopri5>(std::move(problem), options);
}

}  // namespace lash
