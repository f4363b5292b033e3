#include "study/variational_lyapunov.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>

#include "analysis/lyapunov_spectrum.hpp"
#include "core/elements/clearance_revolute.hpp"

namespace lash {

namespace {

/// Largest h·ρ of one tangent RK4 step over the leading vectors (ρ = ‖JV‖/‖V‖, the
/// kLeadingVectors first columns, the slowest to contract after each QR): RK4's local error is
/// about (h·ρ)⁵/120, 2.6e-4 at 0.5; on an oscillatory direction its amplitude error (hρ)⁶/144
/// per step is an exponent error of about (hρ)⁵ ρ/144, 0.004 1/s for ρ = 20 rad/s. The trailing
/// vectors follow stiff, fast-contracting directions (a contact's), where that error decays;
/// over them only RK4's stability is kept: h·ρ ≤ kTangentStable (the interval on the negative
/// real axis is 2.79). docs/analysis.md gives what each bound changes on the examples.
constexpr double kTangentSubstep = 0.5;
constexpr int kLeadingVectors = 2;
constexpr double kTangentStable = 2.7;

/// Tangent vectors carried along the accepted steps of one run (Observer::step): each step
/// [t0, t1] advances them by one RK4 step of V' = J(t) V, J·V by forward differences of the
/// right-hand side at the step's dense output; each contact event maps them with its saltation
/// matrix; every `interval` they are projected onto the constraint manifold's tangent space and
/// renormalised by QR.
class TangentRider final : public Observer {
 public:
  TangentRider(const Model& model, double t0, const Eigen::VectorXd& y0, double interval,
               double time_scale, double tangent_step)
      : model_(model), ws_(model), nq_(ws_.nq), nt_(2 * ws_.nq + ws_.na), ny_(ws_.ny),
        step_(tangent_step), interval_(interval), next_(t0 + interval), y_prev_(y0),
        t_prev_(t0) {
    weights_ = Eigen::VectorXd::Zero(nt_);
    weights_.head(nq_).setOnes();
    weights_.segment(nq_, nq_).setConstant(time_scale);
    f_ = [this](double t, const Eigen::VectorXd& v, Eigen::VectorXd& out) {
      // The tangent part of y (no energy integrals) with the rest of the reference state.
      pad_ = y_ref_;
      pad_.head(nt_) = v;
      if (!evaluate(model_, ws_, t, pad_.data(), ydot_.data())) return false;
      out = ydot_.head(nt_);
      return true;
    };
    pad_.resize(ny_);
    ydot_.resize(ny_);
    spectrum_ = std::make_unique<TangentSpectrum>(initial_basis(t0, y0), weights_, t0);
  }

  int dimension() const { return spectrum_->size(); }
  const TangentSpectrum& spectrum() const { return *spectrum_; }
  bool failed() const { return !message_.empty(); }
  const std::string& message() const { return message_; }
  int mapped_events() const { return mapped_; }
  int unmapped_events() const { return unmapped_; }

  void output(double, const Eigen::VectorXd&, const Workspace&) override {}
  bool wants_steps() const override { return true; }

  void step(double t0, double t1, const Eigen::VectorXd& y, const Workspace& ws,
            StepProbe& probe) override {
    if (failed()) return;
    ws_.contact = ws.contact;  // the step's modes
    // The reference state at t0: the previous step's end, or after an event its mapped state.
    Eigen::VectorXd y0 = y_prev_;
    if (t_prev_ != t0) {
      if (!probe.at(t0)) return fail(t0, "the dense output cannot be evaluated");
      y0 = probe.state();
    }
    // RK4 is accurate while h·ρ is small (ρ: how fast J turns the tangent vectors, ‖JV‖/‖V‖ at
    // the last step's start). The integrator's steps are not bounded by that: a damped motion
    // that has settled takes steps of many periods, where one RK4 step over h·ρ = 6 gave a
    // damped oscillator's exponents as −4.9 where they are −1. Such a step is cut into RK4 steps
    // on the dense output: h·ρ ≤ kTangentSubstep over the leading vectors, ≤ kTangentStable over
    // all.
    const double h = t1 - t0;
    const int substeps = static_cast<int>(std::clamp(
        std::max(std::ceil(h * rho_lead_ / kTangentSubstep), std::ceil(h * rho_all_ / kTangentStable)),
        1.0, 10000.0));
    // f at each node once: a substep's start is the last one's end, its middle serves two stages.
    struct Node {
      double t = 0.0;
      Eigen::VectorXd y, f;
      bool have_f = false;
    };
    Node a, m, b;
    a.t = t0;
    a.y = y0;
    if (have_f_prev_ && t_prev_ == t0) a.f = f_prev_, a.have_f = true;
    for (int i = 0; i < substeps; ++i) {
      m = Node{}, b = Node{};
      b.t = i + 1 == substeps ? t1 : t0 + (t1 - t0) * (i + 1) / substeps;
      m.t = 0.5 * (a.t + b.t);
      for (Node* n : {&m, &b}) {
        if (n->t == t1) {
          n->y = y;
        } else {
          if (!probe.at(n->t)) return fail(n->t, "the dense output cannot be evaluated");
          n->y = probe.state();
        }
      }
      bool first = true;
      TangentMap jv = [&](double t, const Eigen::MatrixXd& V, Eigen::MatrixXd& JV) {
        Node& n = t == a.t ? a : (t == b.t ? b : m);
        y_ref_ = n.y;
        const Eigen::VectorXd yt = n.y.head(nt_);
        if (!n.have_f && !(n.have_f = f_(t, yt, n.f))) return false;
        if (!forward_difference_jv(f_, t, yt, n.f, V, weights_, step_, JV)) return false;
        if (first && i == 0) {  // ρ for the next step: the leading vectors', and every one's
          rho_lead_ = rho_all_ = 0.0;
          for (int c = 0; c < V.cols(); ++c) {
            const double len = V.col(c).cwiseProduct(weights_).norm();
            if (!(len > 0.0)) continue;
            const double r = JV.col(c).cwiseProduct(weights_).norm() / len;
            rho_all_ = std::max(rho_all_, r);
            if (c < kLeadingVectors) rho_lead_ = std::max(rho_lead_, r);
          }
        }
        first = false;
        return true;
      };
      if (!tangent_rk4_step(jv, a.t, b.t, spectrum_->vectors()))
        return fail(b.t, "the right-hand side cannot be evaluated beside the trajectory");
      a = std::move(b);
    }
    y_prev_ = y;
    t_prev_ = t1;
    f_prev_ = a.f;
    have_f_prev_ = a.have_f;
    if (t1 >= next_) {
      project(t1, y, spectrum_->vectors());
      if (!spectrum_->vectors().allFinite())
        return fail(t1, "the tangent vectors are not finite (they grew without bound: the "
                        "tangent RK4 step may be unstable on steps limited by stability; try "
                        "a smaller rtol)");
      if (!spectrum_->renormalise(t1)) return fail(t1, "the tangent vectors collapsed");
      while (next_ <= t1) next_ += interval_;
    }
  }

  /// Saltation matrix of a contact onset or separation of joint k (Müller 1995), with the
  /// impact velocity δ̇⁻ as a state reset at onset: its row of the jump map's Jacobian D is
  /// ∇δ̇ᵀ (and LuGre's z, set to 0, a zero row). The event function is the gap δ (its sign
  /// cancels in S); ∇δᵀ f⁻ = δ̇ at the crossing, ∂δ/∂t = 0.
  void event(const ContactEvent& e, const Workspace& ws) override {
    if (failed()) return;
    if (t_prev_ != e.t) {  // a mode corrected at an output (no located crossing): not mapped
      ++unmapped_;
      return;
    }
    const int k = e.clearance;
    const Eigen::VectorXd y_minus = y_prev_;
    Eigen::VectorXd y_plus = y_minus;
    const int iv = ws_.aux_impact[k], iz = ws_.aux_bristle[k];
    if (e.onset) {
      y_plus[iv] = e.velocity;
      if (iz >= 0) y_plus[iz] = 0.0;
    }
    // f⁻ with the mode before the event, f⁺ with the mode after.
    Eigen::VectorXd f_minus(nt_), f_plus(nt_);
    y_ref_ = y_minus;
    ws_.contact = ws.contact;
    ws_.contact[k].in_contact = !ws.contact[k].in_contact;
    if (!f_(e.t, y_minus.head(nt_), f_minus)) return fail(e.t, "f⁻ cannot be evaluated");
    y_ref_ = y_plus;
    ws_.contact = ws.contact;
    if (!f_(e.t, y_plus.head(nt_), f_plus)) return fail(e.t, "f⁺ cannot be evaluated");
    // Directional derivatives of the gap δ and its rate δ̇ (central differences).
    auto gap_derivative = [&](const Eigen::VectorXd& v, double& d_delta, double& d_rate) {
      const double len = std::max(v.cwiseProduct(weights_).norm(), 1e-300);
      const double s = step_ / len;
      Eigen::VectorXd a = y_minus, b = y_minus;
      a.head(nt_) += s * v;
      b.head(nt_) -= s * v;
      double da, ra, db, rb;
      clearance_gap(model_, ws_, k, a.data(), da, ra);
      clearance_gap(model_, ws_, k, b.data(), db, rb);
      d_delta = (da - db) / (2 * s);
      d_rate = (ra - rb) / (2 * s);
    };
    double delta, rate;
    clearance_gap(model_, ws_, k, y_minus.data(), delta, rate);
    if (!(std::abs(rate) > 0.0)) return fail(e.t, "a grazing contact (δ̇ = 0) has no saltation matrix");
    // D f⁻ and D V: identity but for the reset rows.
    auto apply_d = [&](Eigen::VectorXd v) {
      if (e.onset) {
        double dd, dr;
        gap_derivative(v, dd, dr);
        v[iv] = dr;
        if (iz >= 0) v[iz] = 0.0;
      }
      return v;
    };
    const Eigen::VectorXd jump_rate = f_plus - apply_d(f_minus);
    Eigen::MatrixXd& V = spectrum_->vectors();
    for (int c = 0; c < V.cols(); ++c) {
      double dd, dr;
      gap_derivative(V.col(c), dd, dr);
      V.col(c) = apply_d(V.col(c)) + jump_rate * (dd / rate);
    }
    // Orthonormalise at once (not recorded): a near-grazing crossing (small δ̇) stretches
    // every vector toward one direction, and the next renormalisation may be T/20 away.
    if (!spectrum_->renormalise(e.t, false))
      return fail(e.t, "the tangent vectors collapsed at a contact event");
    y_prev_ = y_plus;
    have_f_prev_ = false;
    ++mapped_;
  }

 private:
  /// Φ_q and Φ̇ at (t, y) from one evaluation (ws_ holds them afterwards).
  bool constraints_at(double t, const Eigen::VectorXd& y) {
    return evaluate(model_, ws_, t, y.data(), ydot_.data());
  }

  /// ∂Φ̇/∂q · δq by central differences of Φ̇(q, q̇, t).
  Eigen::VectorXd phi_dot_q(double t, const Eigen::VectorXd& y, const Eigen::VectorXd& dq) {
    const double len = std::max(dq.norm(), 1e-300), s = step_ / len;
    Eigen::VectorXd a = y, b = y;
    a.head(nq_) += s * dq;
    b.head(nq_) -= s * dq;
    constraints_at(t, a);
    const Eigen::VectorXd pa = ws_.phi_dot;
    constraints_at(t, b);
    return (pa - ws_.phi_dot) / (2 * s);
  }

  /// Projects tangent vectors onto the tangent space of {Φ(q, t) = 0, Φ̇(q, q̇, t) = 0}:
  /// δq ← δq − Φ_q⁺ Φ_q δq, then δq̇ ← δq̇ − Φ_q⁺ (Φ_q δq̇ + ∂Φ̇/∂q δq) (Φ_q⁺ the
  /// pseudo-inverse, so redundant rows do no harm). Auxiliary entries stay.
  void project(double t, const Eigen::VectorXd& y, Eigen::MatrixXd& V) {
    if (ws_.m == 0) return;
    constraints_at(t, y);
    const Eigen::MatrixXd phi_q = ws_.phi_q;
    const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(phi_q);
    for (int c = 0; c < V.cols(); ++c) {
      Eigen::VectorXd dq = V.col(c).head(nq_);
      dq -= cod.solve(phi_q * dq);
      const Eigen::VectorXd r = phi_q * V.col(c).segment(nq_, nq_) + phi_dot_q(t, y, dq);
      V.col(c).head(nq_) = dq;
      V.col(c).segment(nq_, nq_) -= cod.solve(r);
    }
  }

  /// A basis of the tangent space at (t0, y0): for each null vector n of Φ_q, the position
  /// direction (n, −Φ_q⁺ ∂Φ̇/∂q n) and the velocity direction (0, n); auxiliary entries 0.
  Eigen::MatrixXd initial_basis(double t0, const Eigen::VectorXd& y0) {
    Eigen::MatrixXd null;
    if (ws_.m == 0) {
      null = Eigen::MatrixXd::Identity(nq_, nq_);
    } else {
      if (!constraints_at(t0, y0))
        throw std::runtime_error("the start state cannot be evaluated");
      const Eigen::MatrixXd phi_q = ws_.phi_q;
      Eigen::JacobiSVD<Eigen::MatrixXd> svd(phi_q, Eigen::ComputeFullV);
      svd.setThreshold(1e-10);
      const int rank = static_cast<int>(svd.rank());
      null = svd.matrixV().rightCols(nq_ - rank);
    }
    const int dof = static_cast<int>(null.cols());
    Eigen::MatrixXd B = Eigen::MatrixXd::Zero(nt_, 2 * dof);
    for (int i = 0; i < dof; ++i) {
      B.col(i).head(nq_) = null.col(i);
      B.col(dof + i).segment(nq_, nq_) = null.col(i);
    }
    if (dof > 0) project(t0, y0, B);
    return B;
  }

  void fail(double t, const std::string& why) {
    if (message_.empty()) message_ = "variational equations at t = " + std::to_string(t) + " s: " + why;
  }

  const Model& model_;
  Workspace ws_;  ///< the tangent evaluations' own workspace (the run's stays as it reports)
  int nq_, nt_, ny_;
  double step_;  ///< forward-difference perturbation length (weighted norm)
  double interval_, next_;
  Eigen::VectorXd weights_, y_prev_, y_ref_, pad_, ydot_;
  double t_prev_;
  Eigen::VectorXd f_prev_;     ///< f at (t_prev_, y_prev_) when have_f_prev_
  /// ‖JV‖/‖V‖ (weighted, largest column) at the last step's start: of the kLeadingVectors
  /// first vectors, and of all of them.
  double rho_lead_ = 0.0, rho_all_ = 0.0;
  bool have_f_prev_ = false;
  FlowRhs f_;
  std::unique_ptr<TangentSpectrum> spectrum_;
  std::string message_;
  int mapped_ = 0, unmapped_ = 0;
};

}  // namespace

LyapunovEstimate variational_lyapunov(const Model& model, const Eigen::VectorXd& y_start,
                                      double t_start, double interval, int intervals,
                                      double time_scale, const std::atomic<int>* interrupt,
                                      double tangent_step) {
  LyapunovEstimate e;
  e.method = "variational";
  e.interval = interval;
  e.intervals = intervals;
  e.t0 = t_start;
  Workspace ws(model);
  Simulator sim(model, ws);
  sim.start(t_start, y_start);
  std::unique_ptr<TangentRider> rider;
  try {
    rider = std::make_unique<TangentRider>(model, t_start, sim.state(), interval, time_scale,
                                           tangent_step);
  } catch (const std::exception& ex) {
    e.estimated = true;
    e.message = ex.what();
    return e;
  }
  if (rider->dimension() == 0) {
    e.message = "the drivers fix every coordinate: no free direction to perturb";
    return e;
  }
  e.estimated = true;
  // Integrate interval by interval, so that a signal stops the estimate promptly.
  for (int i = 1; i <= intervals; ++i) {
    if (interrupt && interrupt->load() != 0) {
      e.message = "interrupted";
      break;
    }
    if (!sim.advance_to(t_start + i * interval, rider.get())) {
      e.message = sim.status().message;
      break;
    }
    if (rider->failed()) {
      e.message = rider->message();
      break;
    }
  }
  const TangentSpectrum& ts = rider->spectrum();
  e.renormalisations = ts.renormalisations();
  e.events_mapped = rider->mapped_events();
  e.events_unmapped = rider->unmapped_events();
  e.ok = e.message.empty() && ts.renormalisations() > 0;
  for (size_t h = 0; h < ts.history.size(); ++h) {
    std::vector<double> v(ts.history[h].data(), ts.history[h].data() + ts.history[h].size());
    std::sort(v.rbegin(), v.rend());
    e.history.emplace_back(ts.history_time[h], v.front());
    e.spectrum_history.push_back(std::move(v));
  }
  if (e.ok) {
    e.spectrum = e.spectrum_history.back();
    e.exponent = e.spectrum.front();
  }
  return e;
}

}  // namespace lash
