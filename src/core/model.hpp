#pragma once
/// @file model.hpp
/// The immutable, validated, SI-unit description of a planar mechanism. Built by the loader
/// (io/model_loader.hpp) or by hand in C++; never changed during a run. Notation and sign
/// conventions: docs/architecture.md.
#include <optional>
#include <string>
#include <vector>

#include "core/contact_laws.hpp"
#include "core/friction_laws.hpp"
#include "core/math.hpp"

namespace lash {

/// Index of the ground in body references.
inline constexpr int kGround = -1;

/// A named point fixed in a body, in body coordinates (m).
struct Marker {
  std::string name;
  Vec2 s_P_B = Vec2::Zero();
};

/// A rigid body. Its frame has its origin at the centre of mass.
struct Body {
  std::string name;
  double mass = 0.0;                   ///< kg, > 0
  double inertia = 0.0;                ///< kg·m² about the centre of mass, > 0
  Vec2 r0 = Vec2::Zero();              ///< initial position of the centre of mass in world, m
  double phi0 = 0.0;                   ///< initial orientation, rad
  Vec2 v0 = Vec2::Zero();              ///< initial velocity (initial_state: given), m/s
  double omega0 = 0.0;                 ///< initial angular velocity (initial_state: given), rad/s
  std::vector<Marker> markers;
};

/// A point on a body (or on the ground, in world coordinates).
struct PointRef {
  int body = kGround;
  Vec2 s = Vec2::Zero();  ///< body coordinates (world coordinates on the ground), m
  std::string label;      ///< as written in the model, e.g. "rod.B"
};

enum class JointType { revolute, translational, fixed };

/// A revolute clearance joint: the journal (point `a` of its joint) moves inside the bearing
/// (point `b`); contact per shared/reference/formulas.md.
struct Clearance {
  double clearance = 0.0;        ///< c = R_B − R_J, m
  double journal_radius = 0.0;   ///< R_J, m
  double bearing_radius = 0.0;   ///< R_B, m
  NormalLaw normal_law = NormalLaw::lankarani_nikravesh;
  ContactParams contact;
  FrictionLaw friction_law = FrictionLaw::none;
  FrictionParams friction;
  /// Floor on the located impact velocity δ̇⁻ used by the damped laws, m/s: a grazing contact
  /// would otherwise divide by ~0.
  double min_impact_velocity = 1e-3;
};

/// A joint between two bodies. Revolute: `a` is the journal point, `b` the bearing point and the
/// constraint is r_a = r_b. Translational: `a` is on the guide body, whose frame holds `axis`;
/// `b` on the sliding body; relative rotation locked. Fixed: r_a = r_b and rotation locked.
struct Joint {
  std::string name;
  JointType type = JointType::revolute;
  PointRef a, b;
  Vec2 axis = Vec2::UnitX();     ///< translational: unit slide axis in body a's frame
  double angle0 = 0.0;           ///< translational/fixed: locked φ_b − φ_a, rad
  std::optional<Clearance> clearance;  ///< set: a revolute clearance joint (no constraint)
  bool is_constraint() const { return !clearance.has_value(); }
};

enum class DriverProfile { constant_speed, expression };

/// Prescribed motion of a revolute joint angle θ = φ_a − φ_b or a translational slide
/// s = (r_b − r_a)·axis: coordinate(t) = initial + f(t), f(t) = speed·t or an expression.
struct Driver {
  std::string name;
  int joint = -1;
  DriverProfile profile = DriverProfile::constant_speed;
  double speed = 0.0;            ///< rad/s or m/s (constant_speed)
  std::string expression;        ///< f(time) in rad or m (expression)
  double initial = 0.0;          ///< coordinate at t = 0, rad or m
};

enum class LoadType { force, torque, spring_damper, torsional_spring_damper };

/// An applied load. force: (fx, fy) expressions in world axes at point `a`. torque: expression on
/// body `body_a`. spring_damper: between points a and b, tension f = k(L − L0) + c L̇.
/// torsional_spring_damper: T = k(θ − θ0) + c θ̇ with θ = φ_b − φ_a, acting +T on a, −T on b.
struct Load {
  std::string name;
  LoadType type = LoadType::force;
  PointRef a, b;
  int body_a = kGround, body_b = kGround;
  std::string fx = "0", fy = "0", torque = "0";
  double stiffness = 0.0, damping = 0.0, free_length = 0.0, angle0 = 0.0;
};

enum class IntegratorKind { dopri5, bdf };
enum class InitialStateRule { ideal, given };

struct SolverSettings {
  IntegratorKind integrator = IntegratorKind::dopri5;
  /// Defaults tight enough for a converged impact sequence on the Flores benchmark (at 1e-6/1e-9
  /// grazing contacts come and go with the tolerance; bench/README.md).
  double rtol = 1e-8;
  double atol = 1e-11;
  double end_time = 1.0;
  double output_interval = 1e-3;
  double max_step = 0.0;       ///< 0: no limit
  long max_steps = 50'000'000;
  InitialStateRule initial_state = InitialStateRule::ideal;
  double baumgarte_alpha = 100.0;  ///< Φ̈ + 2αΦ̇ + β²Φ = 0, 1/s
  double baumgarte_beta = 100.0;
};

struct Model {
  std::string name;
  std::string source;          ///< the file it was read from, if any
  std::vector<Body> bodies;
  std::vector<Joint> joints;
  std::vector<Driver> drivers;
  std::vector<Load> loads;
  Vec2 gravity = Vec2::Zero();
  SolverSettings solver;

  /// Number of clearance joints.
  int clearance_joint_count() const;
};

}  // namespace lash
