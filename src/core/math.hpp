#pragma once
/// @file math.hpp
/// Small planar-geometry helpers shared by the engine. Notation: docs/architecture.md.
#include <Eigen/Core>
#include <cmath>

namespace lash {

using Vec2 = Eigen::Vector2d;

/// Rotation matrix A(φ) taking body coordinates to world coordinates.
inline Eigen::Matrix2d rotation(double phi) {
  const double c = std::cos(phi), s = std::sin(phi);
  Eigen::Matrix2d a;
  a << c, -s, s, c;
  return a;
}

/// The vector turned by +90°: perp(v) = (−v_y, v_x) = k × v.
inline Vec2 perp(const Vec2& v) { return Vec2(-v.y(), v.x()); }

/// Planar cross product a × b (the z component).
inline double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

/// |v| without overflow or underflow of the squares: a force of 1e155 N is 1e155 N, not inf
/// (Eigen's norm() squares first). For channels, which a failing run's message reports.
inline double magnitude(const Vec2& v) {
  const double n = v.norm();  // (hypot costs 2 % of a run where it is every evaluation)
  return std::isfinite(n) || !v.allFinite() ? n : std::hypot(v.x(), v.y());
}

}  // namespace lash
