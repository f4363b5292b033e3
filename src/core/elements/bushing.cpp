// Bushing: two spring–dampers along the axes u_x, u_y of a frame body's frame between point a
// and point b, plus an optional torsional part (the tuned-mass absorber's suspension).
//   d = r_b − r_a,  d_i = u_i·d,  ḋ_i = u_i·ḋ + ω_f perp(u_i)·d   (the exact rate of d_i),
//   F = Σ (k_i d_i + c_i ḋ_i) u_i pulls a toward b (−F on b), T = k_t θ + c_t θ̇ (θ = φ_b − φ_a).
// V = Σ ½ k_i d_i² + ½ k_t θ². F acts at the two points and, because u_i turns with the frame
// body, the frame takes the torque −Σ (k_i d_i + c_i ḋ_i) perp(u_i)·d = d × F at its point
// (∂d_i/∂θ = perp(u_i)·d): the generalised force is then exactly −∂V/∂q, and the dissipated power
// is Σ c_i ḋ_i² + c_t θ̇². A flexible link as the frame: its axes are those of its axis at its own
// point (kinematics.hpp: point_angle), and the torque acts on that axis. On a link the torsional
// part's angles are its axis' at the point, θ within (−π, π].
#include "core/elements/registry.hpp"

namespace lash::bushing {
namespace {

void apply(const Model&, Workspace& ws, const Load& l, int index) {
  const BodyKin &ka = ws.kin_of(l.a.body), &kb = ws.kin_of(l.b.body);
  const BodyKin& kf = ws.kin_of(l.frame_body);
  const PointKin pa = point_kin(ka, l.a.s), pb = point_kin(kb, l.b.s);
  const Vec2 d = pb.r - pa.r, d_dot = pb.v - pa.v;
  // The frame's axes: the ground's, a rigid body's, or a link's axis at its own point.
  const PointKin* pf = l.frame_body == kGround ? nullptr : l.frame_body == l.a.body ? &pa : &pb;
  const Eigen::Matrix2d axes = kf.mesh ? rotation(point_angle(kf, *pf)) : kf.A;
  const double omega_f = pf ? pf->omega : 0.0;
  Vec2 f = Vec2::Zero(), defl;
  double dissipated = 0.0, potential = 0.0, turning = 0.0;
  for (int i = 0; i < 2; ++i) {
    const Vec2 u = axes.col(i);
    const double di = u.dot(d), di_dot = u.dot(d_dot) + omega_f * perp(u).dot(d);
    const double k = l.stiffness_xy[i], c = l.damping_xy[i];
    f += (k * di + c * di_dot) * u;
    turning -= (k * di + c * di_dot) * perp(u).dot(d);
    defl[i] = di;
    potential += 0.5 * k * di * di;
    dissipated += c * di_dot * di_dot;
  }
  LoadOutput& out = ws.load_out[index];
  out.force = -f;
  out.deflection = defl;
  out.power = apply_force(ws.g, pa, f) + apply_force(ws.g, pb, -f) +
              (pf ? apply_point_torque(ws.g, *pf, turning) : 0.0);
  // Torsional part.
  const double theta = relative_angle(ka, pa, kb, pb, l.angle0);
  const double theta_dot = pb.omega - pa.omega;
  out.torque = l.stiffness * theta + l.damping * theta_dot;
  out.power += apply_point_torque(ws.g, pa, out.torque) + apply_point_torque(ws.g, pb, -out.torque);
  potential += 0.5 * l.stiffness * theta * theta;
  dissipated += l.damping * theta_dot * theta_dot;
  ws.potential += potential;
  ws.dissipated_power += dissipated;
}

void channels(const Load&, const LoadOutput& o, ChannelSink& s) {
  s.add("Fx", "N", "force on body b, x", o.force.x());
  s.add("Fy", "N", "force on body b, y", o.force.y());
  s.add("F", "N", "force magnitude", magnitude(o.force));
  s.add("dx", "m", "deflection b − a along the frame's x axis", o.deflection.x());
  s.add("dy", "m", "deflection b − a along the frame's y axis", o.deflection.y());
  s.add("torque", "N·m", "torsional part, on body a", o.torque);
  s.add("power", "W", "power of its forces on the bodies", o.power);
}

}  // namespace

const LoadKind kKind{"bushing", apply, channels};

}  // namespace lash::bushing
