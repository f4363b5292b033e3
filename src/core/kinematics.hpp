#pragma once
/// @file kinematics.hpp
/// Coordinate blocks and the kinematics every element reads. A body owns one block of the
/// coordinate vector q: its address (offset) and size are the only things the rest of the
/// engine knows about it. Rigid bodies have [x, y, φ], point masses [x, y], flexible links
/// [rx, ry, r'x, r'y] per node; the ground has none.
#include <Eigen/Core>

#include "core/beam.hpp"
#include "core/math.hpp"

namespace lash {

/// Where a body's coordinates live in q (and its velocities in q̇): q[offset, offset + size).
/// `rot` is the index of φ in q, or −1 for a body without rotation (point mass, ground).
struct BodyBlock {
  int offset = -1;
  int size = 0;
  int rot = -1;
};

/// Calls f(k) for every coordinate index k of a block, unrolled for the rigid body's 3.
template <typename F>
inline void for_block(const BodyBlock& bl, F&& f) {
  if (bl.size == 3) {
    f(bl.offset), f(bl.offset + 1), f(bl.offset + 2);
  } else {
    for (int k = bl.offset; k < bl.offset + bl.size; ++k) f(k);
  }
}

/// Pose and velocity of one body at the current evaluation (the ground: all zero, A = I). For a
/// flexible link, r, v, φ, ω are those of the chord from end A to end B (origin at its middle)
/// and `mesh`, `q`, `qd` give its nodal coordinates and velocities (core/beam.hpp).
struct BodyKin {
  Vec2 r = Vec2::Zero(), v = Vec2::Zero();
  double phi = 0.0, omega = 0.0;
  Eigen::Matrix2d A = Eigen::Matrix2d::Identity();
  BodyBlock block;  ///< offset −1 for the ground
  const beam::Mesh* mesh = nullptr;  ///< flexible link only
  const double* q = nullptr;         ///< flexible link: its block of q
  const double* qd = nullptr;        ///< flexible link: its block of q̇
};

/// A material point of a body at the current evaluation: position r, velocity v, the rotation
/// rate ω of the material there, the velocity-dependent part of its acceleration
/// (a_P = J_P q̈ + a_vel), and what its Jacobian J_P = ∂r_P/∂q needs:
///   rigid body  r_P = r + A s_B:  J_P = [I, perp(s)] on (x, y, φ),  a_vel = −ω² s;
///   point mass  r_P = r:          J_P = I on (x, y),               a_vel = 0;
///   flexible    r_P = S(ξ) e:     J_P = S(ξ) on its element's 8,   a_vel = 0
/// (s = A s_B is the world offset from the body's origin).
struct PointKin {
  Vec2 s = Vec2::Zero(), r = Vec2::Zero(), v = Vec2::Zero(), a_vel = Vec2::Zero();
  double omega = 0.0;
  int offset = -1;   ///< first coordinate of J_P's columns (−1: the ground)
  int rot = -1;      ///< rigid body: index of φ
  bool beam = false;
  double n[4] = {0, 0, 0, 0};   ///< flexible: shape functions s1…s4 at ξ
  double dn[4] = {0, 0, 0, 0};  ///< flexible: their x-derivatives
  Vec2 slope = Vec2::UnitX();   ///< flexible: r' at the point
  Vec2 slope_rate = Vec2::Zero();  ///< flexible: ṙ' at the point
};

/// The kinematics of the point at body coordinates s_body (on a flexible link's axis, s_body.x
/// from its middle).
inline PointKin point_kin(const BodyKin& k, const Vec2& s_body) {
  PointKin p;
  p.offset = k.block.offset;
  p.rot = k.block.rot;
  if (!k.mesh) {
    p.s = k.A * s_body;
    p.r = k.r + p.s;
    p.v = k.v + k.omega * perp(p.s);
    p.omega = k.omega;
    p.a_vel = -k.omega * k.omega * p.s;
    return p;
  }
  // The marker lies on the axis (finalize checks it), so locate does not throw.
  const beam::Location at = beam::locate(*k.mesh, 0.5 * k.mesh->length + s_body.x());
  p.beam = true;
  p.offset = k.block.offset + beam::kNodeCoordinates * at.element;
  beam::hermite(at.xi, k.mesh->element_length(), p.n, p.dn);
  const double* q = k.q + beam::kNodeCoordinates * at.element;
  const double* qd = k.qd + beam::kNodeCoordinates * at.element;
  p.r = p.v = p.slope = Vec2::Zero();
  Vec2& slope_rate = p.slope_rate;
  for (int i = 0; i < 4; ++i) {
    p.r += p.n[i] * Vec2(q[2 * i], q[2 * i + 1]);
    p.v += p.n[i] * Vec2(qd[2 * i], qd[2 * i + 1]);
    p.slope += p.dn[i] * Vec2(q[2 * i], q[2 * i + 1]);
    slope_rate += p.dn[i] * Vec2(qd[2 * i], qd[2 * i + 1]);
  }
  p.s = p.r - k.r;
  p.omega = cross(p.slope, slope_rate) / p.slope.squaredNorm();
  return p;
}

/// Adds dᵀ J_P (the derivative of a row that depends on the point's position through d = ∂Φ/∂r_P)
/// to row `row` of Φ_q.
inline void put_point_row(Eigen::MatrixXd& phi_q, int row, const PointKin& p, const Vec2& d) {
  if (p.offset < 0) return;
  if (p.beam) {
    for (int i = 0; i < 4; ++i) {
      phi_q(row, p.offset + 2 * i) += p.n[i] * d.x();
      phi_q(row, p.offset + 2 * i + 1) += p.n[i] * d.y();
    }
    return;
  }
  phi_q(row, p.offset) += d.x();
  phi_q(row, p.offset + 1) += d.y();
  if (p.rot >= 0) phi_q(row, p.rot) += d.dot(perp(p.s));
}

/// Adds dᵀ ∂r'/∂e = dᵀ S'(ξ) (a row that depends on a flexible link's slope at the point) to row
/// `row` of Φ_q.
inline void put_slope_row(Eigen::MatrixXd& phi_q, int row, const PointKin& p, const Vec2& d) {
  for (int i = 0; i < 4; ++i) {
    phi_q(row, p.offset + 2 * i) += p.dn[i] * d.x();
    phi_q(row, p.offset + 2 * i + 1) += p.dn[i] * d.y();
  }
}

/// Acceleration of the point from q̈: J_P q̈ + a_vel.
inline Vec2 point_acceleration(const PointKin& p, const Eigen::VectorXd& qdd) {
  if (p.offset < 0) return Vec2::Zero();
  Vec2 a = p.a_vel;
  if (p.beam) {
    for (int i = 0; i < 4; ++i) a += p.n[i] * Vec2(qdd[p.offset + 2 * i], qdd[p.offset + 2 * i + 1]);
    return a;
  }
  a += Vec2(qdd[p.offset], qdd[p.offset + 1]);
  if (p.rot >= 0) a += qdd[p.rot] * perp(p.s);
  return a;
}

/// Adds the generalised force J_Pᵀ f of a world force f at the point to g. Returns its power f·v_P.
inline double apply_force(Eigen::VectorXd& g, const PointKin& p, const Vec2& f) {
  if (p.offset < 0) return 0.0;
  if (p.beam) {
    for (int i = 0; i < 4; ++i) {
      g[p.offset + 2 * i] += p.n[i] * f.x();
      g[p.offset + 2 * i + 1] += p.n[i] * f.y();
    }
  } else {
    g[p.offset] += f.x();
    g[p.offset + 1] += f.y();
    if (p.rot >= 0) g[p.rot] += cross(p.s, f);
  }
  return f.dot(p.v);
}

/// Adds a torque τ on the material at the point (a rigid body: on the body; a flexible link: on
/// the rotation of its axis there, θ = atan2(r'_y, r'_x), ∂θ/∂e = perp(r')ᵀ S' / |r'|²) to g.
/// Returns its power τω. A point mass takes no torque (returns 0).
inline double apply_point_torque(Eigen::VectorXd& g, const PointKin& p, double tau) {
  if (p.offset < 0) return 0.0;
  if (p.beam) {
    const Vec2 w = perp(p.slope) * (tau / p.slope.squaredNorm());
    for (int i = 0; i < 4; ++i) {
      g[p.offset + 2 * i] += p.dn[i] * w.x();
      g[p.offset + 2 * i + 1] += p.dn[i] * w.y();
    }
  } else if (p.rot >= 0) {
    g[p.rot] += tau;
  } else {
    return 0.0;
  }
  return tau * p.omega;
}

/// The angle of the material at the point: a rigid body's φ (unwrapped, a coordinate); on a
/// flexible link the direction of its axis there, atan2(r'_y, r'_x), in (−π, π]; 0 for a point
/// mass and the ground.
inline double point_angle(const BodyKin& k, const PointKin& p) {
  return p.beam ? std::atan2(p.slope.y(), p.slope.x()) : k.phi;
}

/// θ_b − θ_a − angle0, the angles of the material at points a and b (point_angle). With a
/// flexible link it is taken within (−π, π], so that a link's wrapped angle and a rigid body's
/// unwrapped one compare (continuous where the difference stays small).
inline double relative_angle(const BodyKin& ka, const PointKin& pa, const BodyKin& kb,
                             const PointKin& pb, double angle0) {
  const double theta = point_angle(kb, pb) - point_angle(ka, pa) - angle0;
  return pa.beam || pb.beam ? std::remainder(theta, 2.0 * M_PI) : theta;
}

/// Adds a rigid body's entries to one row of Φ_q: ∂Φ/∂(x, y) = (dx, dy) and ∂Φ/∂φ = dphi.
inline void put_row(Eigen::MatrixXd& phi_q, int row, const BodyKin& k, double dx, double dy,
                    double dphi) {
  if (k.block.offset < 0) return;
  phi_q(row, k.block.offset) += dx;
  phi_q(row, k.block.offset + 1) += dy;
  if (k.block.rot >= 0) phi_q(row, k.block.rot) += dphi;
}

}  // namespace lash
