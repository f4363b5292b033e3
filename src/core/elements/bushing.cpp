// Bushing: two spring–dampers along the axes u_x, u_y of a frame body's frame between point a
// and point b, plus an optional torsional part (the tuned-mass absorber's suspension).
//   d = r_b − r_a,  d_i = u_i·d,  ḋ_i = u_i·ḋ + ω_f perp(u_i)·d   (the exact rate of d_i),
//   F = Σ (k_i d_i + c_i ḋ_i) u_i pulls a toward b (−F on b), T = k_t θ + c_t θ̇ (θ = φ_b − φ_a).
// V = Σ ½ k_i d_i² + ½ k_t θ². Because u_i turns with the frame body, F acts on the frame body
// at the other body's point: then the generalised force is exactly −∂V/∂q (the moment of F
// about the frame includes the turning of u_i), and the dissipated power is Σ c_i ḋ_i² + c_t θ̇².
#include "core/elements/registry.hpp"

namespace lash::bushing {
namespace {

void apply(const Model&, Workspace& ws, const Load& l, int index) {
  const BodyKin &ka = ws.kin_of(l.a.body), &kb = ws.kin_of(l.b.body);
  const BodyKin& kf = ws.kin_of(l.frame_body);
  const PointKin pa = point_kin(ka, l.a.s), pb = point_kin(kb, l.b.s);
  const Vec2 d = pb.r - pa.r, d_dot = pb.v - pa.v;
  Vec2 f = Vec2::Zero(), defl;
  double dissipated = 0.0, potential = 0.0;
  for (int i = 0; i < 2; ++i) {
    const Vec2 u = kf.A.col(i);
    const double di = u.dot(d), di_dot = u.dot(d_dot) + kf.omega * perp(u).dot(d);
    const double k = l.stiffness_xy[i], c = l.damping_xy[i];
    f += (k * di + c * di_dot) * u;
    defl[i] = di;
    potential += 0.5 * k * di * di;
    dissipated += c * di_dot * di_dot;
  }
  // Application points: the frame body takes its force at the other body's point.
  const bool frame_a = l.frame_body == l.a.body && l.a.body != kGround;
  const bool frame_b = !frame_a && l.frame_body == l.b.body && l.b.body != kGround;
  const PointKin qa = frame_a ? point_kin(ka, ka.A.transpose() * (pb.r - ka.r)) : pa;
  const PointKin qb = frame_b ? point_kin(kb, kb.A.transpose() * (pa.r - kb.r)) : pb;
  LoadOutput& out = ws.load_out[index];
  out.force = -f;
  out.deflection = defl;
  out.power = apply_force(ws.g, qa, f) + apply_force(ws.g, qb, -f);
  // Torsional part.
  const double theta = kb.phi - ka.phi - l.angle0, theta_dot = kb.omega - ka.omega;
  out.torque = l.stiffness * theta + l.damping * theta_dot;
  out.power += apply_torque(ws.g, ka, out.torque) + apply_torque(ws.g, kb, -out.torque);
  potential += 0.5 * l.stiffness * theta * theta;
  dissipated += l.damping * theta_dot * theta_dot;
  ws.potential += potential;
  ws.dissipated_power += dissipated;
}

void channels(const Load&, const LoadOutput& o, ChannelSink& s) {
  s.add("Fx", "N", "force on body b, x", o.force.x());
  s.add("Fy", "N", "force on body b, y", o.force.y());
  s.add("F", "N", "force magnitude", o.force.norm());
  s.add("dx", "m", "deflection b − a along the frame's x axis", o.deflection.x());
  s.add("dy", "m", "deflection b − a along the frame's y axis", o.deflection.y());
  s.add("torque", "N·m", "torsional part, on body a", o.torque);
  s.add("power", "W", "power of its forces on the bodies", o.power);
}

}  // namespace

const LoadKind kKind{"bushing", apply, channels};

}  // namespace lash::bushing
