#pragma once
/// @file fuzz_contract.hpp
/// What fuzz/fuzz_model_loader.cpp and tests/test_fuzz_regressions.cpp both check, so the
/// fuzzer and the replay of its findings agree on what a bug is:
///   - leading `#set KEY=VALUE` lines of an input are overrides (as `lash run --set`);
///   - a Model the loader accepts is in the ranges core/model.hpp documents;
///   - a model that assembles also runs, for a bounded effort, to an end that says what happened.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/model.hpp"
#include "core/simulate.hpp"

namespace lash::fuzz {

/// Leading `#set KEY=VALUE` lines (YAML comments, so the text stays a model) → overrides.
inline std::vector<std::string> overrides_of(const std::string& text) {
  static const std::string kTag = "#set ";
  std::vector<std::string> out;
  size_t pos = 0;
  while (text.compare(pos, kTag.size(), kTag) == 0) {
    const size_t end = text.find('\n', pos);
    const size_t stop = end == std::string::npos ? text.size() : end;
    out.push_back(text.substr(pos + kTag.size(), stop - pos - kTag.size()));
    if (end == std::string::npos) break;
    pos = end + 1;
  }
  return out;
}

/// "" if `m` satisfies the ranges of core/model.hpp, else the first violation found. Only what
/// the loader promises ("a validated, SI-unit Model"): finite numbers, positive masses and
/// tolerances, valid indices, a consistent clearance geometry.
inline std::string model_invariant_violation(const Model& m) {
  auto finite = [](double v) { return std::isfinite(v); };
  auto finite2 = [](const Vec2& v) { return std::isfinite(v.x()) && std::isfinite(v.y()); };
  const int nb = static_cast<int>(m.bodies.size());
  auto body_ok = [nb](int b) { return b == kGround || (b >= 0 && b < nb); };

  if (nb == 0) return "no bodies";
  if (!finite2(m.gravity)) return "gravity not finite";
  for (const Body& b : m.bodies) {
    const std::string at = "body '" + b.name + "': ";
    if (!(finite(b.mass) && b.mass > 0)) return at + "mass not finite and > 0";
    if (b.rotates() && !(finite(b.inertia) && b.inertia > 0)) return at + "inertia not finite and > 0";
    if (!finite2(b.r0) || !finite(b.phi0) || !finite2(b.v0) || !finite(b.omega0))
      return at + "initial pose or velocity not finite";
    for (const Marker& mk : b.markers)
      if (!finite2(mk.s_P_B)) return at + "marker '" + mk.name + "' not finite";
  }
  for (const Joint& j : m.joints) {
    const std::string at = "joint '" + j.name + "': ";
    if (!body_ok(j.a.body) || !body_ok(j.b.body)) return at + "body index out of range";
    if (j.a.body == j.b.body) return at + "both ends on one body";
    if (!finite2(j.a.s) || !finite2(j.b.s) || !finite(j.angle0)) return at + "geometry not finite";
    if (j.type == JointType::translational && !(std::abs(j.axis.norm() - 1.0) < 1e-9))
      return at + "axis not a unit vector";
    if (!j.clearance) continue;
    if (j.type != JointType::revolute) return at + "clearance on a non-revolute joint";
    const Clearance& c = *j.clearance;
    if (!(finite(c.clearance) && c.clearance > 0)) return at + "clearance not finite and > 0";
    if (!(finite(c.journal_radius) && c.journal_radius > 0))
      return at + "journal_radius not finite and > 0";
    if (!(finite(c.bearing_radius) && c.bearing_radius > c.journal_radius))
      return at + "bearing_radius not finite and > journal_radius";
    if (!(std::abs(c.bearing_radius - c.journal_radius - c.clearance) <= 1e-9 * c.bearing_radius))
      return at + "bearing_radius != journal_radius + clearance";
    if (!(finite(c.contact.stiffness) && c.contact.stiffness > 0))
      return at + "contact stiffness not finite and > 0";
    if (!(finite(c.contact.exponent) && c.contact.exponent > 0))
      return at + "contact exponent not finite and > 0";
    if (!(c.contact.restitution > 0 && c.contact.restitution <= 1))
      return at + "restitution not in (0, 1]";
    if (!(finite(c.min_impact_velocity) && c.min_impact_velocity > 0))
      return at + "min_impact_velocity not finite and > 0";
  }
  const int nj = static_cast<int>(m.joints.size());
  for (const Driver& d : m.drivers) {
    const std::string at = "driver '" + d.name + "': ";
    if (d.target == DriverTarget::joint ? (d.joint < 0 || d.joint >= nj)
                                        : (d.body < 0 || d.body >= static_cast<int>(m.bodies.size())))
      return at + "joint or body index out of range";
    if (!finite(d.speed) || !finite(d.initial)) return at + "speed or initial not finite";
  }
  for (const Load& l : m.loads) {
    const std::string at = "load '" + l.name + "': ";
    if (!body_ok(l.a.body) || !body_ok(l.b.body) || !body_ok(l.body_a) || !body_ok(l.body_b))
      return at + "body index out of range";
    if (!(finite(l.stiffness) && l.stiffness >= 0 && finite(l.damping) && l.damping >= 0))
      return at + "stiffness or damping not finite and >= 0";
    // Derived by finalize for the kinds that use them (NaN elsewhere: unused).
    if (l.type == LoadType::spring_damper && !(finite(l.free_length) && l.free_length >= 0))
      return at + "free length not finite and >= 0";
    if ((l.type == LoadType::torsional_spring_damper || l.type == LoadType::bushing) &&
        !finite(l.angle0))
      return at + "rest angle not finite";
  }
  const SolverSettings& s = m.solver;
  if (!(finite(s.rtol) && s.rtol > 0 && finite(s.atol) && s.atol > 0))
    return "solver: rtol or atol not finite and > 0";
  if (!(finite(s.end_time) && s.end_time > 0)) return "solver: end_time not finite and > 0";
  if (!(s.output_interval > 0 && s.output_interval <= s.end_time))
    return "solver: output_interval not in (0, end_time]";
  if (!(finite(s.max_step) && s.max_step >= 0)) return "solver: max_step not finite and >= 0";
  if (!(s.max_steps >= 1)) return "solver: max_steps < 1 (got " + std::to_string(s.max_steps) + ")";
  if (!(finite(s.baumgarte_alpha) && s.baumgarte_alpha >= 0 && finite(s.baumgarte_beta) &&
        s.baumgarte_beta >= 0))
    return "solver: baumgarte not finite and >= 0";
  return "";
}

/// Steps and outputs a fuzzed run may take: enough to pass impacts and expression bounds, small
/// enough for many runs per second.
constexpr long kRunSteps = 2000;
constexpr double kRunOutputs = 20;

/// Runs an accepted model that assembles, with at most kRunSteps steps and kRunOutputs outputs,
/// and returns "" if the run kept its contract (core/simulate.hpp): simulate() returns rather
/// than throws, a completed run reached end_time, a stopped one is "failed" with a message, and
/// the final state has the size of the model's state. Else the first violation.
inline std::string run_contract_violation(Model m) {
  SolverSettings& s = m.solver;
  s.max_steps = std::min(s.max_steps, kRunSteps);
  s.end_time = std::min(s.end_time, kRunOutputs * s.output_interval);
  struct Null : Observer {
    void output(double, const Eigen::VectorXd&, const Workspace&) override {}
  } null;
  RunResult r;
  int size = 0;
  try {
    Workspace ws(m);
    size = ws.ny;
    r = simulate(m, ws, null);
  } catch (const std::runtime_error&) {
    return "";  // no consistent initial state: the loader's and initial_state's business
  } catch (const std::exception& e) {
    return std::string("simulate threw: ") + e.what();
  }
  if (r.status.ok != (r.status.outcome == RunOutcome::completed))
    return "status.ok and status.outcome disagree";
  if (r.status.ok && !(r.status.t == s.end_time)) return "completed before end_time";
  if (!r.status.ok && r.status.outcome != RunOutcome::failed)
    return std::string("stopped as ") + outcome_name(r.status.outcome) + " with no signal or writer";
  if (!r.status.ok && r.status.message.empty()) return "stopped without a message";
  if (r.final_state.y.size() != size) return "final state of the wrong size";
  return "";
}

}  // namespace lash::fuzz
