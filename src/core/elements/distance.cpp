// Distance joint: a massless rigid rod pinned at point a and point b, |r_b − r_a| = L.
// Row Φ = (d·d − L²)/(2L) with d = r_b − r_a, so Φ_q = d·∂d/∂q / L and
// γ = −(ḋ·ḋ + d·(a_vel,b − a_vel,a))/L with a_vel = −ω² s on a rigid body (Nikravesh 1988,
// §4.4, "revolute–revolute"), 0 on a point mass or a flexible link (kinematics.hpp).
#include <cmath>

#include "core/elements/registry.hpp"

namespace lash::distance {
namespace {

int rows(const Model&, const Joint&) { return 1; }

void constrain(const Model&, const Workspace& ws, const Joint& j, int row, ConstraintOut& out) {
  const PointKin pa = point_kin(ws.kin_of(j.a.body), j.a.s);
  const PointKin pb = point_kin(ws.kin_of(j.b.body), j.b.s);
  const double len = j.length;
  const Vec2 d = pb.r - pa.r, dd = pb.v - pa.v;
  out.phi[row] = (d.dot(d) - len * len) / (2.0 * len);
  const Vec2 u = d / len;
  put_point_row(out.phi_q, row, pa, -u);
  put_point_row(out.phi_q, row, pb, u);
  if (out.phi_dot) (*out.phi_dot)[row] = u.dot(dd);
  if (out.gamma) (*out.gamma)[row] = -(dd.dot(dd) + d.dot(pb.a_vel - pa.a_vel)) / len;
}

void channels(const Model&, const Workspace& ws, const Joint& j, int row, ChannelSink& s) {
  const BodyKin &ka = ws.kin_of(j.a.body), &kb = ws.kin_of(j.b.body);
  const Vec2 d = point_kin(kb, j.b.s).r - point_kin(ka, j.a.s).r;
  const double lam = ws.lambda[row];
  const Vec2 f_a = -lam * d / j.length;  // generalised force Φ_qᵀλ on body a's point
  s.add("Fx", "N", "rod force on body a, x", f_a.x());
  s.add("Fy", "N", "rod force on body a, y", f_a.y());
  s.add("F", "N", "rod force magnitude", f_a.norm());
  s.add("tension", "N", "rod tension (> 0 pulls the points together)", -lam * d.norm() / j.length);
}

}  // namespace

const JointKind kKind{"distance", rows, constrain, channels};

}  // namespace lash::distance
