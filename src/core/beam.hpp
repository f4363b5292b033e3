#pragma once
/// @file beam.hpp
/// The planar Euler–Bernoulli beam in the absolute nodal coordinate formulation (ANCF): the
/// mathematics of a flexible link, independent of the mechanism engine (the body kind built on it
/// is core/elements/flexible_link.cpp; docs/architecture.md, "Flexible links").
///
/// Each node carries its world position r and slope ∂r/∂x (4 coordinates [rx, ry, r'x, r'y]);
/// an element of length l interpolates them with the cubic Hermite polynomials of ξ = x/l ∈ [0, 1]
/// (Shabana, Dynamics of Multibody Systems, 3rd ed. 2005, sec. 7.6; Berzeri and Shabana 2000,
/// "Development of simple models for the elastic forces in the absolute nodal co-ordinate
/// formulation", J. Sound Vib. 235(4)):
///   r(x) = S(ξ) e,  S = [s1 I, s2 I, s3 I, s4 I],
///   s1 = 1 − 3ξ² + 2ξ³,  s2 = l(ξ − 2ξ² + ξ³),  s3 = 3ξ² − 2ξ³,  s4 = l(ξ³ − ξ²),
/// with e = [r1, r1', r2, r2'] (8 coordinates). The mass matrix ∫ρA SᵀS dx is constant; the
/// strain energy is
///   U = ½ ∫ EA ε² dx + ½ ∫ EI κ² dx,  ε = ½(r'·r' − 1),  κ = (r' × r'') / |r'|³
/// (axial Green strain from the slope, exact curvature of the centre line), so rigid motions of
/// any size store no energy and the beam takes large rotations with small strains. SI units.
#include <Eigen/Core>
#include <vector>

#include "core/math.hpp"

namespace lash::beam {

inline constexpr int kNodeCoordinates = 4;     ///< [rx, ry, r'x, r'y]
inline constexpr int kElementCoordinates = 8;  ///< two nodes
using Vec8 = Eigen::Matrix<double, 8, 1>;
using Mat8 = Eigen::Matrix<double, 8, 8>;
using Mat28 = Eigen::Matrix<double, 2, 8>;

/// Cross-section and material of a beam.
struct Section {
  double youngs_modulus = 0.0;  ///< E, Pa
  double area = 0.0;            ///< A, m²
  double inertia = 0.0;         ///< second moment of area I about the bending axis, m⁴
  double density = 0.0;         ///< ρ, kg/m³
  double fibre = 0.0;           ///< c, distance of the outermost fibre from the neutral axis, m
};

/// A full rectangle b × h (h in the plane of bending).
Section rectangle(double width_m, double height_m, double youngs_modulus, double density);

/// A straight uniform beam of `elements` equal elements, nodes 0 … elements from end A to end B.
struct Mesh {
  Section section;
  double length = 0.0;  ///< m
  int elements = 1;
  double element_length() const { return length / elements; }
  int nodes() const { return elements + 1; }
  int coordinates() const { return kNodeCoordinates * nodes(); }
};

/// The four Hermite shape functions s1…s4 at ξ (S = [s1 I, s2 I, s3 I, s4 I]) and their
/// x-derivatives, for an element of length l. Inline: the engine evaluates them at every joint
/// point of a flexible link in every right-hand side.
inline void hermite(double xi, double l, double n[4], double dn[4]) {
  const double x2 = xi * xi, x3 = x2 * xi;
  n[0] = 1 - 3 * x2 + 2 * x3, n[1] = l * (xi - 2 * x2 + x3), n[2] = 3 * x2 - 2 * x3,
  n[3] = l * (x3 - x2);
  dn[0] = (-6 * xi + 6 * x2) / l, dn[1] = 1 - 4 * xi + 3 * x2, dn[2] = (6 * xi - 6 * x2) / l,
  dn[3] = 3 * x2 - 2 * xi;
}

/// S(ξ) (2×8) and its x-derivatives S' and S'' for an element of length l.
Mat28 shape(double xi, double l);
Mat28 shape_x(double xi, double l);
Mat28 shape_xx(double xi, double l);

/// Constant element mass matrix ∫₀ˡ ρA SᵀS dx (Gauss quadrature, exact).
Mat8 element_mass(const Section& s, double l);
/// Strain energy of one element at coordinates e, J.
double element_strain_energy(const Section& s, double l, const Vec8& e);
/// Generalised elastic force −∂U/∂e of one element, N (or N·m per unit slope).
Vec8 element_elastic_force(const Section& s, double l, const Vec8& e);
/// Internal forces of one element of a Kelvin–Voigt beam at coordinates e and velocities ė:
/// Q = −∫ [EA (ε + η ε̇) ∂ε/∂e + EI (κ + η κ̇) ∂κ/∂e] dx, added to `force`; its strain energy
/// (J) and dissipated power ∫ η (EA ε̇² + EI κ̇²) dx (W, ≥ 0) are added to `energy` and
/// `dissipation`. η = 0: the elastic force alone.
void element_forces(const Section& s, double l, const Vec8& e, const Vec8& e_dot, double eta,
                    Vec8& force, double& energy, double& dissipation);
/// Generalised force of a uniform field of acceleration g (gravity) on one element, ∫ρA Sᵀg dx;
/// its potential is −Qᵀe (r is linear in e).
Vec8 element_gravity(const Section& s, double l, const Vec2& g);
/// Tangent stiffness ∂²U/∂e² of one element (analytic).
Mat8 element_stiffness(const Section& s, double l, const Vec8& e);

/// Coordinates of the straight, unstrained mesh with end A at `origin` and its axis at `angle`
/// (rad) from the world x axis.
Eigen::VectorXd straight_coordinates(const Mesh& m, const Vec2& origin, double angle);

/// Assembled (dense, banded) mass matrix, strain energy, elastic force and tangent stiffness.
Eigen::MatrixXd mass_matrix(const Mesh& m);
double strain_energy(const Mesh& m, const Eigen::VectorXd& q);
Eigen::VectorXd elastic_force(const Mesh& m, const Eigen::VectorXd& q);
Eigen::MatrixXd stiffness_matrix(const Mesh& m, const Eigen::VectorXd& q);

/// The element and local coordinate ξ ∈ [0, 1] of the point at arc length x ∈ [0, L] of the
/// reference axis. Throws std::invalid_argument outside [0, L].
struct Location {
  int element = 0;
  double xi = 0.0;
};
Location locate(const Mesh& m, double x);

/// Position and slope r, r' of the point at reference arc length x.
Vec2 position(const Mesh& m, const Eigen::VectorXd& q, double x);
Vec2 slope(const Mesh& m, const Eigen::VectorXd& q, double x);

/// Distance of the point at arc length x from the chord through the two ends, positive to the
/// left of the chord (m).
double chord_deflection(const Mesh& m, const Eigen::VectorXd& q, double x);

/// Stress resultants at one point: axial force N = EA ε λ (ε the Green–Lagrange strain, λ = |r'|
/// the stretch: the force the stretched section carries), bending moment M = EI κ, and the
/// largest normal stress |N/A| + |M| c/I (A, c and I of the undeformed section; shear neglected).
struct Resultants {
  double axial_force = 0.0;     ///< N
  double bending_moment = 0.0;  ///< N·m
  double stress = 0.0;          ///< Pa
};
Resultants resultants(const Mesh& m, const Eigen::VectorXd& q, double x);
/// The point of largest normal stress among each element's ends and Gauss points, with its x.
Resultants largest_stress(const Mesh& m, const Eigen::VectorXd& q, double* x_at = nullptr);

/// Supports for the eigenfrequencies and statics: free–free, or end A clamped (its position and
/// the direction of its slope fixed; the slope's length, the axial strain there, stays free).
enum class Support { free, clamped };

/// One natural mode of the linearised beam about its straight unstrained state.
struct Mode {
  double omega = 0.0;        ///< circular frequency, rad/s (rigid-body modes: ≈ 0)
  double transverse = 0.0;   ///< share of the mode's amplitude across the axis (1: pure bending)
};

/// Natural modes K v = ω² M v, ascending. Rigid-body modes of a free beam come first, with
/// ω ≈ 0 (round-off). Throws std::invalid_argument for a mesh or section that is not positive.
std::vector<Mode> modes(const Mesh& m, Support support);

/// Static equilibrium of a beam clamped at end A (Support::clamped; its straight state, axis
/// along +x from the origin) under constant nodal loads f (size m.coordinates(); entries of clamped coordinates
/// are ignored), by Newton's method with `steps` equal load increments. Returns the
/// coordinates; throws std::runtime_error if an increment does not converge.
Eigen::VectorXd clamped_static(const Mesh& m, const Eigen::VectorXd& f, int steps);

}  // namespace lash::beam
