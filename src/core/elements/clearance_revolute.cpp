// Revolute clearance joint (see clearance_revolute.hpp for the kinematics and the force
// application). Energy: the elastic part K δⁿ of every normal law is conservative with potential
// K δⁿ⁺¹/(n+1); the rest of F_N δ̇ and all of −F_T v_T are dissipated power.
#include "core/elements/clearance_revolute.hpp"

#include <algorithm>
#include <cmath>

namespace lash {

void clearance_layout(const Model& model, Workspace& ws, int k) {
  const Joint& j = model.joints[ws.clearance_joints[k]];
  ws.aux_impact[k] = ws.na++;
  ws.aux_names.push_back(j.name + ".impact_velocity");
  ws.aux_bristle[k] = -1;
  if (j.clearance->friction_law == FrictionLaw::lugre) {
    ws.aux_bristle[k] = ws.na++;
    ws.aux_names.push_back(j.name + ".bristle");
  }
}

void clearance_gap(const Model& model, const Workspace& ws, int k, const double* y, double& delta,
                   double& delta_dot) {
  const Joint& j = model.joints[ws.clearance_joints[k]];
  const PointKin pj = point_kin(body_kin(ws, j.a.body, y), j.a.s);
  const PointKin pb = point_kin(body_kin(ws, j.b.body, y), j.b.s);
  const Vec2 e = pj.r - pb.r;
  const double e_len = e.norm();
  delta = e_len - j.clearance->clearance;
  delta_dot = e_len > 0.0 ? (pj.v - pb.v).dot(e) / e_len : 0.0;
}

void clearance_forces(const Model& model, Workspace& ws, int k, const double* y, double* ydot) {
  const Joint& j = model.joints[ws.clearance_joints[k]];
  const Clearance& cl = *j.clearance;
  const PointKin pj = point_kin(ws.kin_of(j.a.body), j.a.s);
  const PointKin pb = point_kin(ws.kin_of(j.b.body), j.b.s);
  ClearanceOutput& out = ws.clearance_out[k];
  out.e = pj.r - pb.r;
  out.e_len = out.e.norm();
  out.delta = out.e_len - cl.clearance;
  const Vec2 n = out.e_len > 0.0 ? Vec2(out.e / out.e_len) : Vec2::UnitX();
  const Vec2 tng = perp(n);
  const Vec2 e_dot = pj.v - pb.v;
  out.delta_dot = out.e_len > 0.0 ? e_dot.dot(n) : 0.0;
  out.v_t = e_dot.dot(tng) + cl.journal_radius * pj.omega - cl.bearing_radius * pb.omega;
  out.f_n = out.f_t = out.potential = out.dissipation = 0.0;
  out.force.setZero();
  const int iz = ws.aux_bristle[k];
  if (iz >= 0) ydot[iz] = 0.0;  // the bristles rest in free flight
  ydot[ws.aux_impact[k]] = 0.0;
  if (out.delta <= 0.0) return;
  // δ̇⁻ is the value located at onset; a stage that overshoots an unlocated onset uses δ̇.
  const double v_impact = std::max(
      ws.contact[k].in_contact ? y[ws.aux_impact[k]] : out.delta_dot, cl.min_impact_velocity);
  const NormalForce nf = normal_force(cl.normal_law, out.delta, out.delta_dot, v_impact, cl.contact);
  out.f_n = nf.total;
  if (iz >= 0) {
    const LuGreOutput lg = lugre_friction(y[iz], out.v_t, out.f_n, cl.lugre);
    out.f_t = lg.force;
    ydot[iz] = lg.z_dot;
  } else {
    out.f_t = friction_force(cl.friction_law, out.v_t, out.f_n, cl.friction);
  }
  out.potential = nf.potential;
  out.dissipation = (out.f_n - nf.elastic) * out.delta_dot - out.f_t * out.v_t;
  // Normal force through the centres; friction at each body's contact point, i.e. the friction
  // force at the centre and its moment R f_t about it (n × t = 1).
  out.force = -out.f_n * n + out.f_t * tng;
  apply_force(ws.g, pj, out.force);
  apply_force(ws.g, pb, -out.force);
  apply_point_torque(ws.g, pj, cl.journal_radius * out.f_t);
  apply_point_torque(ws.g, pb, -cl.bearing_radius * out.f_t);
  ws.potential += out.potential;
  ws.dissipated_power += out.dissipation;
}

double clearance_event(const Model& model, Workspace& ws, int k, Eigen::VectorXd& y) {
  double delta, delta_dot;
  clearance_gap(model, ws, k, y.data(), delta, delta_dot);
  ContactState& cs = ws.contact[k];
  cs.in_contact = !cs.in_contact;
  if (cs.in_contact) {
    // δ̇⁻ >= 0 (a grazing onset may locate a δ̇ a rounding below 0; the force law floors it at
    // min_impact_velocity either way), so a state file never holds a negative one.
    y[ws.aux_impact[k]] = std::max(delta_dot, 0.0);
    if (ws.aux_bristle[k] >= 0) y[ws.aux_bristle[k]] = 0.0;
  }
  return delta_dot;
}

void clearance_channels(const Model& model, const Workspace& ws, int k, ChannelSink& s) {
  (void)model;
  const ClearanceOutput& o = ws.clearance_out[k];
  s.add("ex", "m", "eccentricity of the journal in the bearing, x", o.e.x());
  s.add("ey", "m", "eccentricity of the journal in the bearing, y", o.e.y());
  s.add("e", "m", "eccentricity magnitude", o.e_len);
  s.add("delta", "m", "penetration |e| − c (< 0 in free flight)", o.delta);
  s.add("delta_dot", "m/s", "penetration rate", o.delta_dot);
  s.add("Fn", "N", "normal contact force", o.f_n);
  s.add("Ft", "N", "friction force on the journal along the tangent", o.f_t);
  s.add("vt", "m/s", "relative tangential (sliding) velocity", o.v_t);
  s.add("mode", "", "contact mode: 0 free flight, 1 contact", ws.contact[k].in_contact ? 1 : 0);
  s.add("Fx", "N", "contact force on the journal, x", o.force.x());
  s.add("Fy", "N", "contact force on the journal, y", o.force.y());
  s.add("F", "N", "contact force magnitude", magnitude(o.force));
}

}  // namespace lash
