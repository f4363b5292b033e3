#include "core/simulate.hpp"

#include <chrono>
#include <cmath>
#include <sstream>

namespace lash {

namespace {

std::string describe_contacts(const Model& model, const Workspace& ws) {
  std::ostringstream s;
  for (int k = 0; k < ws.nc; ++k) {
    const auto& o = ws.clearance_out[k];
    s << (k ? "; " : "") << "joint '" << model.joints[ws.clearance_joints[k]].name
      << "': delta = " << o.delta << " m, delta_dot = " << o.delta_dot << " m/s, Fn = " << o.f_n
      << " N";
  }
  return s.str();
}

/// A journal more than its own radius into the bearing wall went through it.
bool journal_through_bearing(const Model& model, const Workspace& ws, RunStatus& st, double t) {
  for (int k = 0; k < ws.nc; ++k) {
    const Joint& j = model.joints[ws.clearance_joints[k]];
    const auto& o = ws.clearance_out[k];
    if (o.delta > j.clearance->journal_radius) {
      std::ostringstream s;
      s << "journal driven through its bearing: penetration " << o.delta
        << " m exceeds the journal radius " << j.clearance->journal_radius
        << " m (delta_dot = " << o.delta_dot << " m/s, Fn = " << o.f_n
        << " N); the contact is too soft for the load or the step too large";
      st = {false, t, j.name, s.str()};
      return true;
    }
  }
  return false;
}

}  // namespace

RunResult simulate(const Model& model, Workspace& ws, Observer& observer) {
  const auto wall0 = std::chrono::steady_clock::now();
  const SolverSettings& s = model.solver;
  RunResult result;
  Eigen::VectorXd y = initial_state(model, ws);
  Eigen::VectorXd ydot(ws.ny), g_event(ws.nc);

  OdeProblem problem;
  problem.n = ws.ny;
  problem.n_events = ws.nc;
  problem.rhs = [&](double t, const double* yy, double* dy) {
    return evaluate(model, ws, t, yy, dy);
  };
  problem.events = [&](double, const double* yy, double* g) {
    event_functions(model, ws, yy, g);
  };
  IntegratorOptions opt{s.rtol, s.atol, s.max_step, s.max_steps};
  auto integrator = s.integrator == IntegratorKind::bdf ? make_cvode_bdf(problem, opt)
                                                        : make_dopri5(problem, opt);
  result.integrator = integrator->name();

  // Discrete state at t = 0: a journal already pressed into its bearing starts in contact.
  for (int k = 0; k < ws.nc; ++k) {
    double delta, delta_dot;
    clearance_gap(model, ws, k, y.data(), delta, delta_dot);
    ws.contact[k] = {delta > 0.0, std::abs(delta_dot)};
  }
  integrator->reset(0.0, y);

  // Outputs every interval, and at end_time when it is not a multiple of the interval.
  const long n_out = static_cast<long>(std::ceil(s.end_time / s.output_interval - 1e-9));
  auto emit = [&](double t) -> bool {
    const bool finite = evaluate(model, ws, t, y.data(), ydot.data());
    result.max_constraint_violation =
        std::max(result.max_constraint_violation, ws.constraint_violation);
    observer.output(t, y, ws);
    ++result.outputs;
    if (!finite) {
      result.status = {false, t, "", "the state or its derivative is not finite (NaN/Inf); " +
                                         describe_contacts(model, ws)};
      return false;
    }
    if (journal_through_bearing(model, ws, result.status, t)) return false;
    observer.progress(t, s.end_time);
    return true;
  };

  if (emit(0.0)) {
    for (long k = 1; k <= n_out;) {
      const double t_out = std::min(k * s.output_interval, s.end_time);
      const Advance adv = integrator->advance(t_out, y);
      if (adv.kind == Advance::failure) {
        evaluate(model, ws, adv.t, y.data(), ydot.data());
        result.status = {false, adv.t, "",
                         "integrator " + result.integrator + " failed: " + adv.message +
                             "; state: " + describe_contacts(model, ws)};
        break;
      }
      if (adv.kind == Advance::event) {
        // The integrator located g_k = s_k δ_k rising through zero: flip every joint now on the
        // far side (g_k ≥ 0); at round-off (δ = ±1e-17) trust the largest g_k. Read δ̇⁻ here.
        event_functions(model, ws, y.data(), g_event.data());
        int first = 0;
        for (int c = 1; c < ws.nc; ++c)
          if (g_event[c] > g_event[first]) first = c;
        for (int c = 0; c < ws.nc; ++c) {
          if (!(g_event[c] >= 0.0 || c == first)) continue;
          double delta, delta_dot;
          clearance_gap(model, ws, c, y.data(), delta, delta_dot);
          ContactState& cs = ws.contact[c];
          cs.in_contact = !cs.in_contact;
          if (cs.in_contact) cs.impact_velocity = delta_dot;
          observer.event({adv.t, c, cs.in_contact, delta_dot}, ws);
        }
        integrator->reset(adv.t, y);
        continue;
      }
      if (!emit(t_out)) break;
      ++k;
    }
  }
  result.stats = integrator->stats();
  result.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return result;
}

}  // namespace lash
