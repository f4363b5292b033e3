// Distance joint: a massless rigid rod pinned at point a and point b, |r_b − r_a| = L.
// Row Φ = |d| − L with d = r_b − r_a and u = d/|d|, so Φ_q = u·∂d/∂q (a unit gradient at every
// configuration), Φ̇ = u·ḋ and γ = −(ḋ·ḋ − (u·ḋ)²)/|d| − u·(a_vel,b − a_vel,a) with
// a_vel = −ω² s on a rigid body, 0 on a point mass or a flexible link (kinematics.hpp); on the
// manifold the same as Nikravesh's (d·d − L²)/(2L) (1988, §4.4, "revolute–revolute"), whose
// gradient d/L grows with |d|: at the configurations drawn around assembly for Φ_q's pattern
// (moves of up to 1 + |q|) a 1e-4 m rod 1 m from the origin had pivots 1e10 times its own, its
// row was taken for a weak one and softened, and a pendulum on it swung at 36 Hz, not 50.
#include <algorithm>
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
  // |d| > 0: finalize refuses a rod of length 0, and the points cannot meet without the joint
  // far apart (a run stops at a residual of 1e-3 m).
  const double dist = std::max(d.norm(), 1e-300);
  out.phi[row] = dist - len;
  const Vec2 u = d / dist;
  put_point_row(out.phi_q, row, pa, -u);
  put_point_row(out.phi_q, row, pb, u);
  const double along = u.dot(dd);
  if (out.phi_dot) (*out.phi_dot)[row] = along;
  if (out.gamma)
    (*out.gamma)[row] = -(dd.dot(dd) - along * along) / dist - u.dot(pb.a_vel - pa.a_vel);
}

void channels(const Model&, const Workspace& ws, const Joint& j, int row, ChannelSink& s) {
  const BodyKin &ka = ws.kin_of(j.a.body), &kb = ws.kin_of(j.b.body);
  const Vec2 d = point_kin(kb, j.b.s).r - point_kin(ka, j.a.s).r;
  const double lam = ws.lambda[row];
  const Vec2 f_a = -lam * d / std::max(d.norm(), 1e-300);  // Φ_qᵀλ on body a's point: −λu
  s.add("Fx", "N", "rod force on body a, x", f_a.x());
  s.add("Fy", "N", "rod force on body a, y", f_a.y());
  s.add("F", "N", "rod force magnitude", magnitude(f_a));
  s.add("tension", "N", "rod tension (> 0 pulls the points together)", -lam);
}

}  // namespace

const JointKind kKind{"distance", rows, constrain, channels};

}  // namespace lash::distance
