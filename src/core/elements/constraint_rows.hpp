#pragma once
/// @file constraint_rows.hpp
/// Constraint rows shared by joint and driver kinds: coincident points, relative angle, and a
/// point's distance along a body-fixed direction (Nikravesh 1988, §4.4 and §11.2). Inline: they
/// are the inner loop of every right-hand side.
#include "core/elements/registry.hpp"

namespace lash {

/// Φ = r_a − r_b (2 rows).
inline void revolute_rows(const Workspace& ws, const PointRef& a, const PointRef& b, int row,
                   ConstraintOut& out) {
  const BodyKin &ka = ws.kin_of(a.body), &kb = ws.kin_of(b.body);
  const PointKin pa = point_kin(ka, a.s), pb = point_kin(kb, b.s);
  out.phi.segment<2>(row) = pa.r - pb.r;
  put_point_row(out.phi_q, row, pa, Vec2(1, 0));
  put_point_row(out.phi_q, row + 1, pa, Vec2(0, 1));
  put_point_row(out.phi_q, row, pb, Vec2(-1, 0));
  put_point_row(out.phi_q, row + 1, pb, Vec2(0, -1));
  if (out.phi_dot) out.phi_dot->segment<2>(row) = pa.v - pb.v;
  if (out.gamma) out.gamma->segment<2>(row) = pb.a_vel - pa.a_vel;
}

/// Φ = φ_b − φ_a − angle0 − f (1 row). Rigid bodies and the ground only (finalize).
inline void angle_row(const Workspace& ws, int body_a, int body_b, double angle0, double f, double fd,
               double fdd, int row, ConstraintOut& out) {
  const BodyKin &ka = ws.kin_of(body_a), &kb = ws.kin_of(body_b);
  out.phi[row] = kb.phi - ka.phi - angle0 - f;
  put_row(out.phi_q, row, ka, 0, 0, -1);
  put_row(out.phi_q, row, kb, 0, 0, 1);
  if (out.phi_dot) (*out.phi_dot)[row] = kb.omega - ka.omega - fd;
  if (out.gamma) (*out.gamma)[row] = fdd;
}

/// Φ = (A_a v')·(r_b − r_a) − f with v' fixed in body a (1 row). Body a rigid or the ground, b
/// rigid, a point mass or the ground (finalize).
inline void dot_row(const Workspace& ws, const PointRef& a, const PointRef& b, const Vec2& v_body,
             double f, double fd, double fdd, int row, ConstraintOut& out) {
  const BodyKin &ka = ws.kin_of(a.body), &kb = ws.kin_of(b.body);
  const PointKin pa = point_kin(ka, a.s), pb = point_kin(kb, b.s);
  const Vec2 v = ka.A * v_body, pv = perp(v);
  const Vec2 d = pb.r - pa.r, dd = pb.v - pa.v;
  out.phi[row] = v.dot(d) - f;
  put_row(out.phi_q, row, ka, -v.x(), -v.y(), pv.dot(pb.r - ka.r));
  put_row(out.phi_q, row, kb, v.x(), v.y(), v.dot(perp(pb.s)));
  if (out.phi_dot) (*out.phi_dot)[row] = ka.omega * pv.dot(d) + v.dot(dd) - fd;
  if (out.gamma) {
    const double quad = -v.dot(d) * ka.omega * ka.omega + 2.0 * ka.omega * pv.dot(dd) +
                        v.dot(pa.s * ka.omega * ka.omega - pb.s * kb.omega * kb.omega);
    (*out.gamma)[row] = fdd - quad;
  }
}

}  // namespace lash
