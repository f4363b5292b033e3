#pragma once
/// @file kinematics.hpp
/// Coordinate blocks and the kinematics every element reads. A body owns one block of the
/// coordinate vector q: its address (offset) and size are the only things the rest of the
/// engine knows about it. Rigid bodies have [x, y, φ], point masses [x, y]; the ground has none.
#include <Eigen/Core>

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

/// Pose and velocity of one body at the current evaluation (the ground: all zero, A = I).
struct BodyKin {
  Vec2 r = Vec2::Zero(), v = Vec2::Zero();
  double phi = 0.0, omega = 0.0;
  Eigen::Matrix2d A = Eigen::Matrix2d::Identity();
  BodyBlock block;  ///< offset −1 for the ground
};

/// A point of a body: world offset s from the body's origin, position and velocity.
struct PointKin {
  Vec2 s, r, v;
};

inline PointKin point_kin(const BodyKin& k, const Vec2& s_body) {
  PointKin p;
  p.s = k.A * s_body;
  p.r = k.r + p.s;
  p.v = k.v + k.omega * perp(p.s);
  return p;
}

/// Adds the generalised force of a world force f applied at world offset s from the body's
/// origin to g. Returns its power f·v_P.
inline double apply_force(Eigen::VectorXd& g, const BodyKin& k, const Vec2& s, const Vec2& f) {
  if (k.block.offset < 0) return 0.0;
  g[k.block.offset] += f.x();
  g[k.block.offset + 1] += f.y();
  if (k.block.rot >= 0) g[k.block.rot] += cross(s, f);
  return f.dot(k.v + k.omega * perp(s));
}

/// Adds a torque τ on a rotating body to g. Returns its power τω.
inline double apply_torque(Eigen::VectorXd& g, const BodyKin& k, double tau) {
  if (k.block.rot < 0) return 0.0;
  g[k.block.rot] += tau;
  return tau * k.omega;
}

/// Adds a body's entries to one row of Φ_q: ∂Φ/∂(x, y) = (dx, dy) and ∂Φ/∂φ = dphi.
inline void put_row(Eigen::MatrixXd& phi_q, int row, const BodyKin& k, double dx, double dy,
                    double dphi) {
  if (k.block.offset < 0) return;
  phi_q(row, k.block.offset) += dx;
  phi_q(row, k.block.offset + 1) += dy;
  if (k.block.rot >= 0) phi_q(row, k.block.rot) += dphi;
}

}  // namespace lash
