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

/// Φ = θ_b − θ_a − f (1 row), θ the angle of the material at points a and b (kinematics.hpp:
/// point_angle): a rigid body's φ (the ground's 0), or on a flexible link the direction of its
/// axis there, θ = atan2(r'_y, r'_x) with ∂θ/∂e = perp(r')ᵀS'/|r'|², θ̇ = r' × ṙ'/|r'|² and the
/// velocity part of θ̈ −2θ̇ (r'·ṙ')/|r'|². With a link, Φ is taken within (−π, π]
/// (relative_angle).
inline void angle_row(const Workspace& ws, const PointRef& a, const PointRef& b, double f,
                      double fd, double fdd, int row, ConstraintOut& out) {
  const BodyKin &ka = ws.kin_of(a.body), &kb = ws.kin_of(b.body);
  const PointKin pa = point_kin(ka, a.s), pb = point_kin(kb, b.s);
  out.phi[row] = relative_angle(ka, pa, kb, pb, f);
  auto side = [&](const BodyKin& k, const PointKin& p, double sign) {
    if (!p.beam) {
      put_row(out.phi_q, row, k, 0, 0, sign);
      return 0.0;
    }
    const double n2 = p.slope.squaredNorm();
    put_slope_row(out.phi_q, row, p, perp(p.slope) * (sign / n2));
    return -2.0 * p.omega * p.slope.dot(p.slope_rate) / n2;  // θ̈'s velocity part
  };
  const double acc_a = side(ka, pa, -1.0), acc_b = side(kb, pb, 1.0);
  if (out.phi_dot) (*out.phi_dot)[row] = pb.omega - pa.omega - fd;
  if (out.gamma) (*out.gamma)[row] = fdd - (acc_b - acc_a);
}

/// Φ = d_a × d_b (1 row): the directions at points a and b stay parallel, where one of the two
/// bodies (or both) is a flexible link. On a link d is its slope r' at the point (ḋ = ṙ', no
/// velocity-dependent acceleration), turned by angle0 on link a when b is a link too; on a rigid
/// body or the ground a unit vector fixed in it, A w (ḋ = ω perp(d), d̈ = α perp(d) − ω² d), with
/// w at angle `angle0` (rigid body a) or −angle0 (rigid body b) from its x axis, angle0 = φ_b − φ_a
/// at the initial poses (a link's φ: its axis). ∂Φ/∂d_a = −perp(d_b), ∂Φ/∂d_b = perp(d_a).
inline void slope_row(const Workspace& ws, const PointRef& a, const PointRef& b, double angle0,
                      int row, ConstraintOut& out) {
  const BodyKin &ka = ws.kin_of(a.body), &kb = ws.kin_of(b.body);
  const PointKin pa = point_kin(ka, a.s), pb = point_kin(kb, b.s);
  struct Side {
    Vec2 d, d_dot, d_acc_vel;  // direction, its rate, the velocity part of its acceleration
    Eigen::Matrix2d turn = Eigen::Matrix2d::Identity();  // a link's d = turn · r'
  };
  auto side = [](const BodyKin& k, const PointKin& p, double w_angle, bool turn_link) {
    Side s;
    if (p.beam) {
      if (turn_link) s.turn = rotation(w_angle);
      s.d = s.turn * p.slope, s.d_dot = s.turn * p.slope_rate, s.d_acc_vel = Vec2::Zero();
    } else {
      s.d = k.A * Vec2(std::cos(w_angle), std::sin(w_angle));
      s.d_dot = k.omega * perp(s.d);
      s.d_acc_vel = -k.omega * k.omega * s.d;
    }
    return s;
  };
  const Side sa = side(ka, pa, angle0, pb.beam), sb = side(kb, pb, -angle0, false);
  out.phi[row] = cross(sa.d, sb.d);
  const Vec2 ga = -perp(sb.d), gb = perp(sa.d);  // ∂Φ/∂d_a, ∂Φ/∂d_b
  if (pa.beam) put_slope_row(out.phi_q, row, pa, sa.turn.transpose() * ga);
  else put_row(out.phi_q, row, ka, 0, 0, ga.dot(perp(sa.d)));
  if (pb.beam) put_slope_row(out.phi_q, row, pb, gb);
  else put_row(out.phi_q, row, kb, 0, 0, gb.dot(perp(sb.d)));
  if (out.phi_dot) (*out.phi_dot)[row] = cross(sa.d_dot, sb.d) + cross(sa.d, sb.d_dot);
  if (out.gamma)
    (*out.gamma)[row] = -(cross(sa.d_acc_vel, sb.d) + 2.0 * cross(sa.d_dot, sb.d_dot) +
                          cross(sa.d, sb.d_acc_vel));
}

/// Φ = (A_a v')·(r_b − r_a) − f with v' fixed in body a (1 row). Body a rigid or the ground, b
/// any body (on a flexible link r_b moves with its nodes, kinematics.hpp: put_point_row).
inline void dot_row(const Workspace& ws, const PointRef& a, const PointRef& b, const Vec2& v_body,
             double f, double fd, double fdd, int row, ConstraintOut& out) {
  const BodyKin &ka = ws.kin_of(a.body), &kb = ws.kin_of(b.body);
  const PointKin pa = point_kin(ka, a.s), pb = point_kin(kb, b.s);
  const Vec2 v = ka.A * v_body, pv = perp(v);
  const Vec2 d = pb.r - pa.r, dd = pb.v - pa.v;
  out.phi[row] = v.dot(d) - f;
  put_row(out.phi_q, row, ka, -v.x(), -v.y(), pv.dot(pb.r - ka.r));
  put_point_row(out.phi_q, row, pb, v);
  if (out.phi_dot) (*out.phi_dot)[row] = ka.omega * pv.dot(d) + v.dot(dd) - fd;
  if (out.gamma) {
    const double quad = -v.dot(d) * ka.omega * ka.omega + 2.0 * ka.omega * pv.dot(dd) +
                        v.dot(pb.a_vel + pa.s * ka.omega * ka.omega);
    (*out.gamma)[row] = fdd - quad;
  }
}

}  // namespace lash
