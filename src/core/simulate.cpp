#include "core/simulate.hpp"

#include <cstdio>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/constraint_solver.hpp"
#include "core/elements/clearance_revolute.hpp"
#include "core/elements/registry.hpp"

namespace lash {

const char* outcome_name(RunOutcome o) {
  switch (o) {
    case RunOutcome::completed: return "completed";
    case RunOutcome::failed: return "failed";
    case RunOutcome::interrupted: return "interrupted";
    case RunOutcome::write_error: return "write_error";
  }
  return "failed";
}

namespace {

/// A run stops when more than kMaxEventBurst contact events fall within kEventBurstSpan·max(1, |t|)
/// seconds of the first of them: no mechanism has that many at one instant (a few per joint).
constexpr long kMaxEventBurst = 1000;
constexpr double kEventBurstSpan = 1e-12;

/// A gap beyond this (m) on the wrong side of a joint's mode is a missed crossing.
constexpr double kModeTolerance = 1e-12;

/// A contact mode the gap δ contradicts by more than round-off: in contact with δ < 0 (free),
/// or free with δ > 0 (pressed in).
bool mode_contradicts(bool in_contact, double delta) {
  return in_contact ? delta < -kModeTolerance : delta > kModeTolerance;
}

/// The state a failure message gives: each clearance joint's gap, speed and force; without
/// clearance joints, the body with the largest acceleration (its position, velocity and
/// acceleration at the last evaluation).
std::string describe_contacts(const Model& model, const Workspace& ws) {
  std::ostringstream s;
  // The load with the largest force or torque first (a NaN one before all): a load that
  // diverges is as likely a cause as a contact.
  int strongest = -1;
  double most = -1.0;
  for (size_t l = 0; l < ws.load_out.size() && l < model.loads.size(); ++l) {
    const LoadOutput& o = ws.load_out[l];
    const double size = std::max(std::hypot(o.force.x(), o.force.y()), std::abs(o.torque));
    if (!(size <= most)) most = size, strongest = static_cast<int>(l);
  }
  if (strongest >= 0 && most != 0.0) {
    const LoadOutput& o = ws.load_out[strongest];
    s << "load '" << model.loads[strongest].name << "' (the largest): force (" << o.force.x()
      << ", " << o.force.y() << ") N, torque " << o.torque << " N·m";
    if (ws.nc > 0) s << "; ";
  }
  for (int k = 0; k < ws.nc; ++k) {
    const auto& o = ws.clearance_out[k];
    s << (k ? "; " : "") << "joint '" << model.joints[ws.clearance_joints[k]].name
      << "': delta = " << o.delta << " m, delta_dot = " << o.delta_dot << " m/s, Fn = " << o.f_n
      << " N";
    // Plain Coulomb at a slip about 0: ±μF_N is discontinuous there (a sticking contact, or a
    // head-on impact whose slip is round-off), and a run that stalls or underflows there says so.
    // The slip chatters about 0 as the force flips (about 1e-4 m/s on a journal that stopped
    // spinning under 100 N), hence a bound of 1 mm/s rather than round-off's.
    const Clearance& cl = *model.joints[ws.clearance_joints[k]].clearance;
    if (o.f_n > 0.0 && cl.friction_law == FrictionLaw::coulomb && std::abs(o.v_t) < 1e-3)
      s << ", vt = " << o.v_t
        << " m/s (plain Coulomb friction is discontinuous at zero slip, which a sticking or "
           "head-on contact meets: the ambrosio or adams_stepped law smooths it)";
  }
  if (ws.nc > 0 || ws.nb == 0) return s.str();
  if (strongest >= 0 && most != 0.0) s << "; ";
  int fastest = 0;
  double largest = -1.0;
  for (int b = 0; b < ws.nb; ++b) {
    const int o = ws.blocks[b].offset;
    const double a = std::hypot(ws.qdd[o], ws.qdd[o + 1]);
    if (!(a <= largest)) largest = a, fastest = b;  // a NaN acceleration is the one to name
  }
  const BodyKin& k = ws.kin[fastest];
  const int o = ws.blocks[fastest].offset;
  s << "body '" << model.bodies[fastest].name << "' (the largest acceleration): position ("
    << k.r.x() << ", " << k.r.y() << ") m, velocity (" << k.v.x() << ", " << k.v.y()
    << ") m/s, acceleration (" << ws.qdd[o] << ", " << ws.qdd[o + 1] << ") m/s^2";
  return s.str();
}

/// The element a failed integration names (RunStatus::element): where the step's largest
/// weighted error lies (`component` of y, −1 if unknown). An auxiliary state names its element;
/// a body's coordinate names the clearance joint or load with the largest force on that body
/// (a contact too stiff for the step, a load that diverges), else the body. Otherwise the
/// element describe_contacts puts first: the largest load, else the clearance joint with the
/// largest force or, with none in contact, the one nearest its wall, else the body accelerated
/// most. ws holds the evaluation at the failure.
std::string fault_element(const Model& model, const Workspace& ws, int component) {
  const int nq = ws.nq;
  if (component >= 2 * nq && component < 2 * nq + ws.na) {
    const std::string& a = ws.aux_names[component - 2 * nq];
    return a.substr(0, a.find('.'));
  }
  int body = -2;  // none: every element counts
  if (component >= 0 && component < 2 * nq)
    for (int b = 0; b < ws.nb; ++b) {
      const BodyBlock& bl = ws.blocks[b];
      if (component % nq >= bl.offset && component % nq < bl.offset + bl.size) body = b;
    }
  // The largest force (a NaN one counts as infinite: it is what failed); zero names nothing.
  std::string name;
  double most = 0.0;
  auto consider = [&](const std::string& n, double size) {
    if (std::isnan(size)) size = std::numeric_limits<double>::infinity();
    if (size > most) most = size, name = n;
  };
  for (size_t l = 0; l < ws.load_out.size() && l < model.loads.size(); ++l) {
    const Load& load = model.loads[l];
    const LoadOutput& o = ws.load_out[l];
    if (body == -2 || load.a.body == body || load.b.body == body || load.body_a == body ||
        load.body_b == body)
      consider(load.name, std::max(std::hypot(o.force.x(), o.force.y()), std::abs(o.torque)));
  }
  if (body == -2 && !name.empty()) return name;  // describe_contacts: the largest load first
  for (int k = 0; k < ws.nc; ++k) {
    const Joint& j = model.joints[ws.clearance_joints[k]];
    if (body == -2 || j.a.body == body || j.b.body == body)
      consider(j.name, ws.clearance_out[k].f_n);
  }
  if (!name.empty()) return name;
  if (body >= 0) return model.bodies[body].name;
  // No force anywhere: the journal nearest its wall, else the body accelerated most.
  double nearest = -std::numeric_limits<double>::infinity();
  for (int k = 0; k < ws.nc; ++k)
    if (!(ws.clearance_out[k].delta <= nearest))
      nearest = ws.clearance_out[k].delta, name = model.joints[ws.clearance_joints[k]].name;
  double largest = 0.0;
  if (ws.nc == 0)
    for (int b = 0; b < ws.nb; ++b) {
      const int o = ws.blocks[b].offset;
      const double a = std::hypot(ws.qdd[o], ws.qdd[o + 1]);
      if (!(a <= largest)) largest = a, name = model.bodies[b].name;
    }
  return name;
}

/// The status of a run stopped by an expression failing mid-run: the load or driver it
/// belongs to as the element, and named in the message.
RunStatus expression_failure(const Model& model, const ExpressionError& e) {
  for (const Load& l : model.loads)
    if (l.fx == e.text() || l.fy == e.text() || l.torque == e.text())
      return {false, e.time(), l.name, "load '" + l.name + "': " + e.what()};
  for (const Driver& d : model.drivers)
    if (d.expression == e.text())
      return {false, e.time(), d.name, "driver '" + d.name + "': " + e.what()};
  return {false, e.time(), "", e.what()};
}

/// Clearance joint k's journal more than its own radius into the bearing wall: it went through.
/// ws holds the evaluation at t.
RunStatus through_bearing(const Model& model, const Workspace& ws, int k, double t) {
  const Joint& j = model.joints[ws.clearance_joints[k]];
  const auto& o = ws.clearance_out[k];
  std::ostringstream s;
  s << "joint '" << j.name << "': journal driven through its bearing: penetration " << o.delta
    << " m reached the journal radius " << j.clearance->journal_radius
    << " m (delta_dot = " << o.delta_dot << " m/s, Fn = " << o.f_n
    << " N); the contact is too soft for the load or the step too large";
  return {false, t, j.name, s.str()};
}

/// The joints no longer hold: |Φ| beyond ws.violation_limit. A driver that asks for what the
/// mechanism cannot do (drivers_out_of_reach: a motion past its reach, or on through a position
/// where it locks) names the element; otherwise the row worst off. ws holds the evaluation at
/// (t, y).
RunStatus pulled_apart(const Model& model, Workspace& ws, double t, const Eigen::VectorXd& y) {
  Eigen::Index row = 0;
  const double worst = ws.phi.cwiseAbs().maxCoeff(&row);
  const RowElement e = constraint_row_element(model, ws, static_cast<int>(row));
  const std::vector<int> drivers = drivers_out_of_reach(model, ws, t, y);
  std::ostringstream s;
  s.precision(9);  // a step's end just past the limit: 0.00100000034, not "0.001"
  if (!drivers.empty()) {
    const std::string& first = model.drivers[drivers[0]].name;
    s << "driver '" << first << "'";
    for (size_t k = 1; k < drivers.size(); ++k) s << ", driver '" << model.drivers[drivers[k]].name << "'";
    s << ": the mechanism cannot follow " << (drivers.size() > 1 ? "them" : "it") << " at t = "
      << t << " s: " << e.what << " is pulled apart (constraint residual " << worst
      << " m or rad, beyond the " << ws.violation_limit
      << " a run allows), and the joints close again without "
      << (drivers.size() > 1 ? "any one of these drivers" : "this driver")
      << ": it prescribes a motion past the mechanism's reach, or on through a position where "
         "the mechanism locks";
    return {false, t, first, s.str()};
  }
  s << e.what << ": pulled apart: its constraint residual is " << worst << " (m or rad) at t = "
    << t << " s, beyond the " << ws.violation_limit
    << " a run allows: the mechanism cannot follow its joints and drivers here (a driver "
       "forcing a locked or singular position, a loop that does not close, or steps too "
       "large for the constraint stabilization: a smaller solver.rtol than "
    << model.solver.rtol << " may cure that)";
  return {false, t, e.element, s.str()};
}

/// A channel that is not finite at an output whose state is: the element it belongs to (its
/// name's first part, where that is an element) or else the one fault_element picks.
RunStatus overflowing_channel(const Model& model, const Workspace& ws, const std::string& channel,
                              double value, double t) {
  std::string element = channel.substr(0, channel.find('.'));
  bool known = false;
  for (const Body& b : model.bodies) known = known || b.name == element;
  for (const Joint& j : model.joints) known = known || j.name == element;
  for (const Driver& d : model.drivers) known = known || d.name == element;
  for (const Load& l : model.loads) known = known || l.name == element;
  for (const Sensor& n : model.sensors) known = known || n.name == element;
  if (!known) element = fault_element(model, ws, -1);
  std::ostringstream s;
  s.precision(9);
  s << "channel '" << channel << "' is " << value << " at t = " << t
    << " s while the state is finite: a quantity beyond the range of double (a velocity or "
       "force of about 1e154 or more in SI units); " << describe_contacts(model, ws);
  return {false, t, element, s.str()};
}

/// The dense output of the step being reported, evaluated into the run's workspace.
class DenseProbe final : public StepProbe {
 public:
  DenseProbe(const Model& model, Workspace& ws, Integrator& integrator)
      : y_end(ws.ny), model_(model), ws_(ws), integrator_(integrator), y_(ws.ny), ydot_(ws.ny) {}
  bool at(double t) override {
    integrator_.dense_at(t, y_);
    return evaluate(model_, ws_, t, y_.data(), ydot_.data());
  }
  bool at_end() override {
    y_ = y_end;
    return evaluate(model_, ws_, t_end, y_.data(), ydot_.data());
  }
  const Eigen::VectorXd& state() const override { return y_; }
  const Workspace& workspace() const override { return ws_; }
  double t_end = 0.0;
  Eigen::VectorXd y_end;  ///< the state at the step's end, as reported

 private:
  const Model& model_;
  Workspace& ws_;
  Integrator& integrator_;
  Eigen::VectorXd y_, ydot_;
};

}  // namespace

void Simulator::hook_steps(Observer* observer) {
  // Steps are watched for an observer that wants them, and for the plane crossings it is told of.
  if (!(observer && (observer->wants_steps() || !planes_.empty()))) observer = nullptr;
  if (observer == stepping_) return;
  stepping_ = observer;
  if (!observer) return integrator_->set_step_hook({});
  auto probe = std::make_shared<DenseProbe>(model_, ws_, *integrator_);
  integrator_->set_step_hook([this, observer, probe](double t0, double t1) {
    if (!planes_.empty()) plane_crossings(t0, t1, observer);
    if (!observer->wants_steps()) return;
    // The step's end, evaluated as an output would be (the integrator's last evaluation may
    // have been exactly there), then whatever the observer probes.
    probe->t_end = t1;
    if (const Eigen::VectorXd* y1 = integrator_->evaluated_end()) {
      probe->y_end = *y1;
      report_multipliers(ws_);  // the integrator's own evaluation, now observed
    } else {
      if (!probe->at(t1)) return;  // not finite: the run loop reports it
      probe->y_end = probe->state();
    }
    observer->step(t0, t1, probe->y_end, ws_, *probe);
  });
}

void Simulator::problem_events(const double* y, double* g) const {
  // Contact, then through the bearing: δ reaching the journal's radius, located like any
  // event, so that a journal driven through its bearing and back between two outputs still
  // stops the run.
  event_functions(model_, ws_, y, g, g + ws_.nc);
}

void Simulator::plane_crossings(double t0, double t1, Observer* observer) {
  // Each plane's function sampled at kPlaneSamples + 1 points of the step's dense output (a
  // state component: no evaluation), a rising sign change located by bisection to round-off of
  // the time, then the state there evaluated and reported. The integration is not touched: a
  // section is an observation, and restarting the integrator at each (as a contact event does)
  // made another trajectory of a chaotic run than the one without the plane.
  constexpr int kPlaneSamples = 8;
  const int np = static_cast<int>(planes_.size());
  auto g = [&](int p, double t) {
    integrator_->dense_at(t, plane_y_);
    return planes_[p].direction * (plane_y_[planes_[p].index] - planes_[p].value);
  };
  std::vector<double> found;
  for (int p = 0; p < np; ++p) {
    double a = t0, ga = g(p, t0);
    for (int k = 1; k <= kPlaneSamples; ++k) {
      const double b = k == kPlaneSamples ? t1 : t0 + (t1 - t0) * k / kPlaneSamples;
      const double gb = g(p, b);
      if (ga < 0.0 && gb >= 0.0) {
        double lo = a, hi = b;
        for (int it = 0; it < 200 && hi - lo > 4 * std::numeric_limits<double>::epsilon() * std::abs(hi); ++it) {
          const double mid = 0.5 * (lo + hi);
          (g(p, mid) < 0.0 ? lo : hi) = mid;
        }
        found.push_back(hi);
      }
      a = b, ga = gb;
    }
  }
  std::sort(found.begin(), found.end());
  for (const double t : found) {
    integrator_->dense_at(t, plane_y_);
    if (!evaluate(model_, ws_, t, plane_y_.data(), ydot_.data())) continue;
    observer->section(t, plane_y_, ws_);
  }
}

Simulator::Simulator(const Model& model, Workspace& ws, std::vector<SectionPlane> planes)
    : model_(model), ws_(ws), planes_(std::move(planes)) {
  const SolverSettings& s = model.solver;
  OdeProblem problem;
  problem.n = ws.ny;
  // Per clearance joint its contact function, then its through-the-bearing function
  // (problem_events); the section planes are located on each step's dense output instead
  // (plane_crossings).
  problem.n_events = 2 * ws.nc;
  problem.n_diagnosed = 2 * ws.nq + ws.na;  // not the energy accounts
  problem.rhs = [this](double t, const double* yy, double* dy) {
    struct Integrating {  // cleared however evaluate() leaves (an ExpressionError throws)
      Workspace& ws;
      ~Integrating() { ws.integrating = false; }
    } guard{ws_};
    ws_.integrating = true;
    const bool ok = evaluate(model_, ws_, t, yy, dy);
    rhs_violation_ = ws_.constraint_violation;
    return ok;
  };
  problem.events = [this](double, const double* yy, double* g) { problem_events(yy, g); };
  // Near a singular position (core/constraint_solver.hpp, kNearSingular): back onto the
  // constraints after each DOPRI5 step, and once on entering the near-singular window under
  // BDF, whose every projection restarts CVODE at first order (projecting each step there took
  // 10⁵ steps per passage); unless that would move an event function across zero (a contact
  // onset or separation that no step located).
  const bool every_step = s.integrator != IntegratorKind::bdf;
  problem.project = [this, every_step](double t, Eigen::VectorXd& yy) {
    if (!ws_.solver || !ws_.solver->ldlt.near_singular()) {
      near_singular_ = false;
      return false;
    }
    if (near_singular_ && !every_step) {
      ws_.solver->ldlt.clear_near_singular();
      return false;
    }
    near_singular_ = true;
    const Eigen::VectorXd before = yy;
    const int n_events = static_cast<int>(g_event_.size());
    Eigen::VectorXd g_before(n_events), g_after(n_events);
    if (n_events > 0) problem_events(before.data(), g_before.data());
    if (!project_onto_constraints(model_, ws_, t, yy)) return false;
    if (n_events > 0) {
      problem_events(yy.data(), g_after.data());
      for (int k = 0; k < n_events; ++k)
        if ((g_after[k] > 0.0) != (g_before[k] > 0.0)) {
          yy = before;
          return false;
        }
    }
    ++projections_;
    return true;
  };
  // Joints pulled apart at a step's end stop the run there, not at the next output: a run
  // whose constraints no longer hold could otherwise creep on for minutes to reach it (BDF at
  // a stiffness of 1e18 N/m on a driven rod: 3 million steps of 4e-11 s with the driver's
  // residual at 1e-2). The last right-hand side's residual screens each step (DOPRI5's is the
  // step's end); the step's end itself decides.
  problem.halt = [this](double t, const Eigen::VectorXd& yy) {
    pulled_apart_ = rhs_violation_ > ws_.violation_limit &&
                    constraint_residual(model_, ws_, t, yy.data()) > ws_.violation_limit;
    return pulled_apart_;
  };
  IntegratorOptions opt{s.rtol, s.atol, s.max_step, s.max_steps};
  opt.end_time = s.end_time;
  integrator_ = s.integrator == IntegratorKind::bdf ? make_cvode_bdf(problem, opt)
                                                    : make_dopri5(problem, opt);
  y_.resize(ws.ny);
  y_try_.resize(ws.ny);
  plane_y_.resize(ws.ny);
  ydot_.resize(ws.ny);
  g_event_.resize(problem.n_events);
}

Simulator::~Simulator() = default;

IntegratorStats Simulator::stats() const {
  IntegratorStats s = integrator_->stats();
  s.projections = projections_;
  s.events -= through_events_;  // contact events: events.csv's rows
  return s;
}
const char* Simulator::integrator_name() const { return integrator_->name(); }

void Simulator::start(double t, const Eigen::VectorXd& y, const std::vector<ContactState>* modes) {
  pulled_apart_ = false;
  // Discrete state: a journal already pressed into its bearing starts in contact.
  for (int k = 0; k < ws_.nc; ++k) {
    double delta, delta_dot;
    clearance_gap(model_, ws_, k, y.data(), delta, delta_dot);
    if (modes && (*modes)[k].in_contact == (delta > 0.0))
      ws_.contact[k] = (*modes)[k];
    else
      ws_.contact[k] = {delta > 0.0};
  }
  t_ = t;
  y_ = y;
  for (int k = 0; k < ws_.nc; ++k) {
    double delta, delta_dot;
    clearance_gap(model_, ws_, k, y.data(), delta, delta_dot);
    if (ws_.contact[k].in_contact && !(modes && (*modes)[k].in_contact))
      y_[ws_.aux_impact[k]] = std::abs(delta_dot);
  }
  status_ = RunStatus{};
  integrator_->reset(t, y_);
}

void Simulator::resume(const State& state) {
  pulled_apart_ = false;
  ws_.contact = state.modes;
  t_ = state.t;
  y_ = state.y;
  for (int k = 0; k < ws_.nc; ++k) {
    double delta, delta_dot;
    clearance_gap(model_, ws_, k, y_.data(), delta, delta_dot);
    if (!mode_contradicts(ws_.contact[k].in_contact, delta)) continue;
    ws_.contact[k].in_contact = delta > 0.0;
    if (delta > 0.0) y_[ws_.aux_impact[k]] = std::abs(delta_dot);
  }
  status_ = RunStatus{};
  integrator_->reset(t_, y_, state.step);
}

State Simulator::snapshot() const { return {t_, y_, ws_.contact, integrator_->step_hint(), {}}; }

void Simulator::set_interrupt(const std::atomic<int>* flag) {
  interrupt_ = flag;
  integrator_->set_stop_flag(flag);
}

void Simulator::set_end_time(double t) { integrator_->set_end_time(t); }

// A function-try-block: an expression failing mid-run (ExpressionError) is a numerical failure.
bool Simulator::advance_to(double t_target, Observer* observer) try {
  hook_steps(observer);
  while (t_ < t_target) {
    const Advance adv = integrator_->advance(t_target, y_try_);
    if (adv.kind == Advance::failure) {
      // The state stays at the last point returned (time and values together), so that
      // final_state.json holds a consistent state; the status names the time of the failure.
      // The message and the element describe the last point the integrator reached, up to an
      // output interval later: the state at the last output was the cause's as it stood then
      // (a load diverging as 1/(0.5 − t) said 10 N, of 1e14 at the failure).
      std::string where;
      if (adv.component >= 0 && adv.component < ws_.ny)
        where = "; the last step's largest error was in " +
                state_names(model_, ws_)[adv.component];
      double t_reached = t_;
      Eigen::VectorXd y_reached;
      bool later = integrator_->reached_state(t_reached, y_reached) && t_reached > t_ &&
                   y_reached.size() == y_.size() && y_reached.allFinite();
      try {  // (an expression failing there must not take the integrator's message's place)
        later = later && evaluate(model_, ws_, t_reached, y_reached.data(), ydot_.data());
      } catch (const std::exception&) {
        later = false;
      }
      if (!later) evaluate(model_, ws_, t_, y_.data(), ydot_.data());
      char at[48];
      std::snprintf(at, sizeof at, "; state at t = %.9g s: ", later ? t_reached : t_);
      status_ = {false, adv.t, fault_element(model_, ws_, adv.component),
                 std::string("integrator ") + integrator_->name() + " failed: " + adv.message +
                     where + at + describe_contacts(model_, ws_)};
      if (later) evaluate(model_, ws_, t_, y_.data(), ydot_.data());
      return false;
    }
    t_ = adv.t;
    y_ = y_try_;
    if (adv.kind == Advance::stopped) {  // at a step's end, between outputs
      evaluate(model_, ws_, t_, y_.data(), ydot_.data());
      if (pulled_apart_) {
        status_ = pulled_apart(model_, ws_, t_, y_);
        return false;
      }
      char at[64];
      std::snprintf(at, sizeof at, "%.9g", t_);
      status_ = {false, t_, "",
                 "interrupted by signal " + std::to_string(interrupt_->load()) + " at t = " + at +
                     " s, between outputs; results up to this time are kept, and "
                     "final_state.json continues the run from there with --from",
                 RunOutcome::interrupted};
      return false;
    }
    if (adv.kind == Advance::reached) {
      t_ = t_target;
      // Safety net: a crossing no event function saw (entered and left within one step, or lost
      // at a grazing restart) leaves a mode that contradicts its gap. Correct it here and say so.
      bool fixed = false;
      for (int c = 0; c < ws_.nc; ++c) {
        double delta, delta_dot;
        clearance_gap(model_, ws_, c, y_.data(), delta, delta_dot);
        const ContactState& cs = ws_.contact[c];
        if (mode_contradicts(cs.in_contact, delta)) {
          clearance_event(model_, ws_, c, y_);
          ++ws_.missed_events;
          if (observer) observer->event({t_, c, cs.in_contact, delta_dot}, ws_);
          fixed = true;
        }
      }
      if (fixed) integrator_->reset(t_, y_);
      return true;
    }
    // The integrator located an event function rising through zero. A contact event flips
    // every joint now on the far side (g_k ≥ 0), and at round-off (δ = ±1e-17) the joint with
    // the largest g_k. δ̇⁻ is read here.
    problem_events(y_.data(), g_event_.data());
    // The function the integrator located, else the one furthest past zero.
    int first = adv.index;
    if (first < 0 || first >= g_event_.size()) {
      first = 0;
      for (int c = 1; c < g_event_.size(); ++c)
        if (g_event_[c] > g_event_[first]) first = c;
    }
    if (first >= ws_.nc) {  // a journal through its bearing: the run stops here
      evaluate(model_, ws_, adv.t, y_.data(), ydot_.data());
      status_ = through_bearing(model_, ws_, first - ws_.nc, adv.t);
      ++through_events_;
      return false;
    }
    // Contact events that do not advance time (onset, separation, onset, ... at one instant:
    // the contact force turns the gap's rate round within round-off) would go on for ever.
    if (adv.t - burst_t_ <= kEventBurstSpan * std::max(1.0, std::abs(adv.t))) {
      if (++burst_events_ > kMaxEventBurst) {
        const Joint& j = model_.joints[ws_.clearance_joints[first]];
        char msg[400];
        std::snprintf(msg, sizeof msg,
                      "%ld contact events within %.1e s of t = %.9g s: the journal's contact "
                      "opens and closes without time advancing (a stiffness too large for the "
                      "masses and clearance, or a contact grazing at round-off)",
                      burst_events_, kEventBurstSpan * std::max(1.0, std::abs(adv.t)), burst_t_);
        status_ = {false, adv.t, j.name,
                   "joint '" + j.name + "': " + msg + "; state: " + describe_contacts(model_, ws_)};
        return false;
      }
    } else {
      burst_t_ = adv.t;
      burst_events_ = 1;
    }
    for (int c = 0; c < ws_.nc; ++c) {
      if (!(g_event_[c] >= 0.0 || c == first)) continue;
      const double delta_dot = clearance_event(model_, ws_, c, y_);
      if (observer) observer->event({adv.t, c, ws_.contact[c].in_contact, delta_dot}, ws_);
    }
    integrator_->reset(adv.t, y_);
  }
  return true;
} catch (const ExpressionError& e) {
  status_ = expression_failure(model_, e);
  return false;
}

SectionPlane parse_section_plane(const Model& model, const std::string& spec) {
  static const char* fields[6] = {"x", "y", "phi", "vx", "vy", "omega"};
  const auto eq = spec.find('=');
  const auto dot = spec.find('.');
  if (eq == std::string::npos || dot == std::string::npos || dot > eq)
    throw std::invalid_argument("section plane '" + spec +
                                "': expected <body>.<x|y|phi|vx|vy|omega>=VALUE[,down]");
  const std::string body = spec.substr(0, dot), field = spec.substr(dot + 1, eq - dot - 1);
  std::string value = spec.substr(eq + 1);
  SectionPlane p;
  if (const auto comma = value.find(','); comma != std::string::npos) {
    const std::string dir = value.substr(comma + 1);
    if (dir != "up" && dir != "down")
      throw std::invalid_argument("section plane '" + spec + "': direction must be up or down");
    p.direction = dir == "down" ? -1 : 1;
    value = value.substr(0, comma);
  }
  int b = -1;
  for (size_t i = 0; i < model.bodies.size(); ++i)
    if (model.bodies[i].name == body) b = static_cast<int>(i);
  int f = -1;
  for (int i = 0; i < 6; ++i)
    if (field == fields[i]) f = i;
  if (b >= 0 && model.bodies[b].flexible())
    throw std::invalid_argument("section plane '" + spec + "': body '" + body +
                                "' is a flexible link; put the plane on a rigid body or a "
                                "point mass");
  if (b >= 0 && !model.bodies[b].rotates() && (f == 2 || f == 5))
    throw std::invalid_argument("section plane '" + spec + "': body '" + body +
                                "' is a point mass, which has no angle");
  if (b < 0 || f < 0)
    throw std::invalid_argument("section plane '" + spec + "': no body '" + body +
                                "' or no quantity '" + field + "' (x, y, phi, vx, vy, omega)");
  try {
    size_t used = 0;
    p.value = std::stod(value, &used);
    if (used != value.size() || !std::isfinite(p.value)) throw std::invalid_argument(value);
  } catch (const std::exception&) {
    throw std::invalid_argument("section plane '" + spec + "': value '" + value +
                                "' is not a finite number");
  }
  // Indices into y follow the coordinate blocks (rigid: x, y, φ; point mass: x, y).
  int offset = 0, nq = 0;
  for (size_t i = 0; i < model.bodies.size(); ++i) {
    const int size = kind_of(model.bodies[i]).coordinates(model.bodies[i]);
    if (static_cast<int>(i) == b) offset = nq;
    nq += size;
  }
  p.index = f < 3 ? offset + f : nq + offset + (f - 3);
  return p;
}

std::string state_mismatch(const Workspace& ws, const State& state) {
  std::ostringstream s;
  if (state.y.size() != ws.ny)
    s << "the state has " << state.y.size() << " values but this model needs " << ws.ny
      << " (" << ws.nq << " coordinates, " << ws.nq << " velocities, " << ws.na
      << " auxiliary states, 3 energy integrals)";
  else if (static_cast<int>(state.modes.size()) != ws.nc)
    s << "the state has " << state.modes.size() << " contact modes but this model has " << ws.nc
      << " clearance joints";
  else if (!state.y.allFinite() || !std::isfinite(state.t))
    s << "the state holds a value that is not finite";
  return s.str();
}

std::string resume_problem(const Model& model, Workspace& ws, const State& state) {
  if (std::string bad = state_mismatch(ws, state); !bad.empty()) return bad;
  std::ostringstream s;
  if (state.t < 0.0) {
    s << "the state is at t = " << state.t << " s; a run starts at t >= 0";
    return s.str();
  }
  if (!(state.t < model.solver.end_time)) {
    s << "the state is at t = " << state.t << " s, not before the model's end_time = "
      << model.solver.end_time << " s; raise it with --set solver.end_time=...";
    return s.str();
  }
  // The integrators' smallest step at t (DOPRI5's underflow bound; 0 lets them choose).
  if (state.step > 0.0 &&
      state.step < 16.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(state.t))) {
    s << "the step size " << state.step << " s is below the smallest step an integrator can take "
      << "at t = " << state.t << " s (set \"step\": 0 to let it choose)";
    return s.str();
  }
  if (std::string bad = constraint_problem(model, ws, state.t, state.y, true); !bad.empty())
    return bad;
  for (int c = 0; c < ws.nc; ++c) {
    const Joint& j = model.joints[ws.clearance_joints[c]];
    // δ̇⁻ is a speed into the wall (a run writes |δ̇| at onset, >= 0): a negative one was edited.
    // Earlier versions stored the located δ̇ as it was, a rounding below 0 at a grazing onset:
    // those read as 0 (the force law floors δ̇⁻ at min_impact_velocity either way).
    if (const double v = state.y[ws.aux_impact[c]]; v < -kStateToleranceVelocity) {
      s << "joint '" << j.name << "': the state's impact velocity " << v
        << " m/s is negative; it is the speed at which the journal met its bearing's wall, >= 0";
      return s.str();
    }
    double delta, delta_dot;
    clearance_gap(model, ws, c, state.y.data(), delta, delta_dot);
    if (delta >= j.clearance->journal_radius) {
      s << "joint '" << j.name << "': the journal lies " << delta << " m into its bearing's wall, "
        << "as deep as its own radius " << j.clearance->journal_radius
        << " m or deeper: the state does not fit this joint (the final state of a run stopped "
           "with its journal through its bearing, or one written with another clearance or "
           "geometry)";
      return s.str();
    }
  }
  return "";
}

std::string stiffness_warning(const IntegratorStats& stats, const std::string& integrator) {
  if (stats.stiff_steps < kStiffWarningSteps || 2 * stats.stiff_steps < stats.steps) return "";
  char msg[600];
  std::snprintf(msg, sizeof msg,
                "the model is stiff for %s: %ld of its %ld steps (from t = %.6g s, of about "
                "%.3g s) had their size set by the method's stability, not by rtol (Hairer's "
                "stiffness test); solver.integrator: bdf takes steps that accuracy sets (stiff "
                "elements: a contact's or friction's large damping, LuGre's bristles, a stiff "
                "bushing or spring)",
                integrator.c_str(), stats.stiff_steps, stats.steps, stats.stiff_from,
                stats.stiff_step);
  return msg;
}

std::vector<std::string> resume_warnings(const Model& model, Workspace& ws, const State& state) {
  std::vector<std::string> out;
  if (state.file_names_no_model)
    out.push_back("the continued state names no model that wrote it (its 'model' is missing: "
                  "a file edited by hand?); its coordinates match this model's by name and "
                  "number, so it runs; check that it is the state you meant");
  else if (!state.model.empty() && state.model != model.name)  // (a state made in memory: "")
    out.push_back("the continued state was written by model '" + state.model + "', and this is '" +
                  model.name + "': its coordinates match this model's by name and number, so it "
                  "runs; check that it is the state you meant");
  for (int c = 0; c < ws.nc && static_cast<int>(state.modes.size()) == ws.nc; ++c) {
    double delta, delta_dot;
    clearance_gap(model, ws, c, state.y.data(), delta, delta_dot);
    if (!mode_contradicts(state.modes[c].in_contact, delta)) continue;
    char msg[400];
    std::snprintf(msg, sizeof msg,
                  "joint '%s': the continued state's mode is %s but its gap is %.6g m; the run "
                  "starts %s, as the gap says",
                  model.joints[ws.clearance_joints[c]].name.c_str(),
                  state.modes[c].in_contact ? "contact" : "free flight", delta,
                  delta > 0.0 ? "in contact" : "in free flight");
    out.push_back(msg);
  }
  if (static_cast<int>(state.gaps.size()) != ws.nc) return out;
  for (int c = 0; c < ws.nc; ++c) {
    const Joint& j = model.joints[ws.clearance_joints[c]];
    double delta, delta_dot;
    clearance_gap(model, ws, c, state.y.data(), delta, delta_dot);
    const double saved = state.gaps[c];
    if (std::abs(delta - saved) <= 1e-9 + 1e-6 * j.clearance->clearance) continue;
    char msg[400];
    std::snprintf(msg, sizeof msg,
                  "joint '%s': the continued state's gap is %.6g m under this model but was "
                  "%.6g m when it was saved (the clearance or the geometry changed); the run "
                  "starts from that gap%s",
                  j.name.c_str(), delta, saved,
                  delta > 0.0 ? ", with the contact force of that penetration" : "");
    out.push_back(msg);
  }
  return out;
}

namespace {

/// The work of the constraint stabilization against the energy a run moves (its outputs'
/// values): the largest kinetic energy, the range of the potential energy, and the work put in
/// and dissipated since the start. Baumgarte's terms do work only on the drift, which a run that
/// follows its joints keeps to the tolerance's level; a share of kStabilizationWarning or more
/// means the joints were held by the stabilization instead of by the motion.
class EnergyScale {
 public:
  EnergyScale(int ny, double t0, const Eigen::VectorXd& y0)
      : ny_(ny), dissipated0_(y0[ny - 3]), input0_(y0[ny - 2]), stabilization0_(y0[ny - 1]),
        t_last_(t0) {}
  void add(const Workspace& ws, const Eigen::VectorXd& y) {
    kinetic_ = std::max(kinetic_, ws.kinetic);
    potential_lo_ = std::min(potential_lo_, ws.potential);
    potential_hi_ = std::max(potential_hi_, ws.potential);
    level_ = std::max(level_, std::abs(ws.kinetic) + std::abs(ws.potential));
    input_ = std::max(input_, std::abs(y[ny_ - 2] - input0_));
    dissipated_ = std::max(dissipated_, std::abs(y[ny_ - 3] - dissipated0_));
    const double w = y[ny_ - 1] - stabilization0_, t = ws.vars.time;
    stabilization_ = std::max(stabilization_, std::abs(w));
    if (std::abs(w - w_last_) > jump_) jump_ = std::abs(w - w_last_), jump_from_ = t_last_, jump_to_ = t;
    w_last_ = w, t_last_ = t;
  }
  std::string warning() const {
    const double scale =
        kinetic_ + std::max(0.0, potential_hi_ - potential_lo_) + input_ + dissipated_;
    // Round-off is no warning: a mechanism at rest moves no energy, and its stabilization's
    // work of 1e-13 to 1e-12 J (a bar hanging from a pin) was 57–100 % of nothing.
    const double noise = std::max(kStabilizationFloor, kStabilizationFloorShare * level_);
    if (!(stabilization_ >= kStabilizationWarning * scale) || !(stabilization_ > noise)) return "";
    char b[768];
    std::snprintf(b, sizeof b,
                  "the constraint stabilization did %.3g J of work, %.3g %% of the energy the "
                  "run moves (%.3g J: the largest kinetic energy, the range of the potential "
                  "energy, the work put in and dissipated), the most of it (%.3g J) between "
                  "outputs at t = %.6g and %.6g s: the joints were held by "
                  "Baumgarte's terms rather than by the motion, so the results there are not "
                  "to be trusted (a singular position the run could not follow, or a driver "
                  "forcing the mechanism through a position where it locks; a smaller rtol or "
                  "integrator dopri5 may help with the first; energy.stabilization has its "
                  "history)",
                  stabilization_, 100.0 * stabilization_ / scale, scale, jump_, jump_from_,
                  jump_to_);
    return b;
  }

 private:
  int ny_;
  double dissipated0_, input0_, stabilization0_;
  double kinetic_ = 0.0, potential_lo_ = std::numeric_limits<double>::infinity(),
         potential_hi_ = -std::numeric_limits<double>::infinity(), input_ = 0.0,
         dissipated_ = 0.0, stabilization_ = 0.0;
  double level_ = 0.0;  ///< the largest kinetic plus |potential| energy at an output
  /// The largest change between two outputs, and the outputs' times.
  double t_last_, w_last_ = 0.0, jump_ = 0.0, jump_from_ = 0.0, jump_to_ = 0.0;
};

}  // namespace

RunResult simulate(const Model& model, Workspace& ws, Observer& observer,
                   const SectionSchedule& sections, const std::vector<SectionPlane>& planes,
                   const RunOptions& options) {
  const auto wall0 = std::chrono::steady_clock::now();
  const SolverSettings& s = model.solver;
  RunResult result;
  Simulator sim(model, ws, planes);
  sim.set_interrupt(options.interrupt);
  result.integrator = sim.integrator_name();
  double t0 = 0.0;
  if (options.from) {
    if (const std::string bad = resume_problem(model, ws, *options.from); !bad.empty())
      throw std::invalid_argument("cannot continue from the given state: " + bad);
    t0 = options.from->t;
    sim.resume(*options.from);
  } else {
    sim.start(0.0, initial_state(model, ws));
  }
  Eigen::VectorXd y = sim.state();
  Eigen::VectorXd ydot(ws.ny);
  result.warnings = ws.warnings;
  if (options.from)
    for (auto& w : resume_warnings(model, ws, *options.from)) result.warnings.push_back(std::move(w));

  // Outputs at k·interval on one global grid (so a continued run lands on the same times), and
  // at end_time when it is not a multiple of the interval; stroboscopic sections merged in.
  const double dt = s.output_interval;
  const long n_out = static_cast<long>(std::ceil(s.end_time / dt - 1e-9));
  long k_first = static_cast<long>(std::floor(t0 / dt + 1e-9)) + 1;
  long k_section = 0;
  auto next_section = [&]() {
    return sections.period > 0.0 ? sections.start + k_section * sections.period
                                 : std::numeric_limits<double>::infinity();
  };
  while (sections.period > 0.0 && next_section() < t0) ++k_section;
  auto is_restart = [&](double t) {
    for (double r : options.restarts)
      if (std::abs(r - t) <= 1e-12 * std::max(1.0, std::abs(t))) return true;
    return false;
  };

  auto evaluate_here = [&](double t) {
    bool finite = false;
    try {
      finite = evaluate(model, ws, t, y.data(), ydot.data());
    } catch (const ExpressionError& e) {  // an expression failing mid-run: a numerical failure
      result.status = expression_failure(model, e);
      return false;
    }
    if (!finite)
      result.status = {false, t, fault_element(model, ws, -1),
                       "the state or its derivative is not finite (NaN/Inf); " +
                                         describe_contacts(model, ws)};
    return finite;
  };
  double t_emitted = -std::numeric_limits<double>::infinity();
  EnergyScale energy(ws.ny, t0, y);
  const std::vector<ChannelInfo> channels = channel_info(model);
  auto emit = [&](double t) -> bool {
    t_emitted = t;
    const bool finite = evaluate_here(t);
    result.max_constraint_violation =
        std::max(result.max_constraint_violation, ws.constraint_violation);
    // A state that is not finite is told of in the status, not written: the files hold the
    // rows up to the last finite one (the readers refuse NaN, and a row of NaN shows nothing
    // the message does not say).
    if (!finite) return false;
    // Nor a row whose state is finite but a channel of it is not: a quantity beyond the range
    // of double (a state file's velocity of 1e200 m/s squared in energy.kinetic).
    ws.output_row.resize(channels.size());
    channel_values(model, ws, y, ws.output_row.data());
    if (!Eigen::Map<const Eigen::ArrayXd>(ws.output_row.data(), ws.output_row.size()).allFinite())
      for (size_t i = 0; i < channels.size(); ++i)
        if (!std::isfinite(ws.output_row[i])) {
          result.status = overflowing_channel(model, ws, channels[i].name, ws.output_row[i], t);
          return false;
        }
    energy.add(ws, y);
    {
      struct Delivered {  // the row belongs to this output only, however output() ends
        Workspace& w;
        ~Delivered() { w.output_row_y = nullptr; }
      } delivered{ws};
      ws.output_row_y = y.data();
      observer.output(t, y, ws);
    }
    ++result.outputs;
    if (ws.constraint_violation > ws.violation_limit) {
      result.status = pulled_apart(model, ws, t, y);
      return false;
    }
    // A journal past its own radius into the wall at an output: the start state (a --from
    // state), whose event function starts past zero, or a crossing no step located (a journal
    // radius of 1e-18 m is crossed within the contact onset's own location, and such a run
    // completed with the journal 3 cm through its bearing).
    for (int k = 0; k < ws.nc; ++k)
      if (ws.clearance_out[k].delta >= model.joints[ws.clearance_joints[k]].clearance->journal_radius) {
        result.status = through_bearing(model, ws, k, t);
        return false;
      }
    observer.progress(t, s.end_time);
    return true;
  };

  bool ok = true;
  if (next_section() <= t0) {
    if ((ok = evaluate_here(t0))) observer.section(t0, y, ws);
    ++k_section;
  }
  ok = ok && emit(t0);
  for (long k = k_first; ok && k <= n_out && t0 < s.end_time;) {
    const double t_out = std::min(k * dt, s.end_time);
    const double t_sec = next_section();
    const bool is_section = t_sec < t_out - 1e-12 * t_out && t_sec <= s.end_time;
    const double target = is_section ? t_sec : t_out;
    if (!options.restarts.empty()) {
      // No step passes a restart: the run continued from a state saved there took its last
      // step to it (a run's steps end on end_time), and so does this one.
      double stop = s.end_time;
      for (double r : options.restarts)
        if (r > sim.time() && r < stop) stop = r;
      sim.set_end_time(stop);
    }
    if (!sim.advance_to(target, &observer)) {
      result.status = sim.status();
      y = sim.state();
      // Interrupted, or a journal through its bearing, between outputs: the last row is the
      // state the run stopped in (the one final_state.json holds), off the output grid; not
      // within 1e-8 of the time of the row before, which the CSV's 9 significant digits could
      // print the same (their spacing is 1e-9 to 1e-8 of the value: 6.8e-12 s after an output
      // at 1.36e-3 s printed as 0.00136174085 twice).
      if (result.status.t == sim.time() &&
          sim.time() - t_emitted > 1e-8 * std::max(std::abs(sim.time()), 1e-300)) {
        // An interruption stays one whatever that row shows (it is checked as any output).
        const RunStatus stopped = result.status;
        if (emit(sim.time()) || stopped.outcome == RunOutcome::interrupted) result.status = stopped;
      }
      break;
    }
    y = sim.state();
    if (is_section) {
      if (!(ok = evaluate_here(target))) break;
      observer.section(target, y, ws);
      ++k_section;
      continue;
    }
    if (std::abs(t_sec - t_out) <= 1e-12 * t_out) {  // a section on an output time
      if (!(ok = evaluate_here(target))) break;
      observer.section(target, y, ws);
      ++k_section;
    }
    ok = emit(t_out);
    if (ok && is_restart(t_out)) sim.resume(sim.snapshot());  // as at an event
    if (ok && options.interrupt && options.interrupt->load() != 0) {
      result.status = {false, t_out, "",
                       "interrupted by signal " + std::to_string(options.interrupt->load()) +
                           "; results up to this time are kept, and final_state.json continues "
                           "the run with --from",
                       RunOutcome::interrupted};
      ok = false;
    }
    if (ok) {
      if (std::string why = observer.stop_reason(); !why.empty()) {
        result.status = {false, t_out, "", std::move(why), RunOutcome::write_error};
        ok = false;
      }
    }
    ++k;
  }
  if (std::string w = energy.warning(); !w.empty()) result.warnings.push_back(std::move(w));
  if (result.status.ok) result.status.t = s.end_time;  // the time reached
  else if (result.status.outcome == RunOutcome::completed) result.status.outcome = RunOutcome::failed;
  result.final_state = sim.snapshot();
  // Each journal's gap under this model: a continuation under another model can tell whether
  // the parameter changed the joint (resume_warnings, continuation in a study).
  if (result.final_state.y.size() == ws.ny)
    for (int c = 0; c < ws.nc; ++c) {
      double delta, delta_dot;
      clearance_gap(model, ws, c, result.final_state.y.data(), delta, delta_dot);
      result.final_state.gaps.push_back(delta);
    }
  result.stats = sim.stats();
  if (std::string w = stiffness_warning(result.stats, result.integrator); !w.empty())
    result.warnings.push_back(std::move(w));
  result.missed_events = ws.missed_events;
  result.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return result;
}

}  // namespace lash
