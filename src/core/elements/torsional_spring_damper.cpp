// Torsional spring–damper between bodies a and b (a flexural pivot, a return spring):
// T = k(θ − θ0) + c θ̇ with θ = φ_b − φ_a, +T on a and −T on b; potential ½k(θ − θ0)²,
// dissipated power c θ̇². On a flexible link the angle is that of its axis at the spring's point
// (kinematics.hpp: point_angle), and θ − θ0 is taken within (−π, π].
#include "core/elements/registry.hpp"

namespace lash::torsional_spring_damper {
namespace {

void apply(const Model&, Workspace& ws, const Load& l, int index) {
  const BodyKin &ka = ws.kin_of(l.body_a), &kb = ws.kin_of(l.body_b);
  const PointKin pa = point_kin(ka, l.a.s), pb = point_kin(kb, l.b.s);
  const double theta = relative_angle(ka, pa, kb, pb, l.angle0);
  const double theta_dot = pb.omega - pa.omega;
  LoadOutput& out = ws.load_out[index];
  out.torque = l.stiffness * theta + l.damping * theta_dot;
  out.power = apply_point_torque(ws.g, pa, out.torque) + apply_point_torque(ws.g, pb, -out.torque);
  ws.potential += 0.5 * l.stiffness * theta * theta;
  ws.dissipated_power += l.damping * theta_dot * theta_dot;
}

void channels(const Load&, const LoadOutput& o, ChannelSink& s) {
  s.add("torque", "N·m", "torque on body a (−torque on body b)", o.torque);
  s.add("power", "W", "power of its torques on the bodies", o.power);
}

}  // namespace

const LoadKind kKind{"torsional_spring_damper", apply, channels};

}  // namespace lash::torsional_spring_damper
