#pragma once
/// @file model.hpp
/// The immutable, validated, SI-unit description of a planar mechanism. Built by the loader
/// (io/model_loader.hpp) or by hand in C++, then passed through `finalize` (core/finalize.hpp),
/// which validates it and computes derived values; never changed during a run. Notation and
/// sign conventions: docs/architecture.md.
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "core/beam.hpp"
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

/// Body kinds (core/elements/rigid_body.cpp, point_mass.cpp, flexible_link.cpp): a rigid body
/// has coordinates [x, y, φ] and a diagonal mass block (m, m, I); a point mass has [x, y] and
/// (m, m); a flexible link is a planar ANCF beam (core/beam.hpp) with 4 coordinates per node
/// [rx, ry, r'x, r'y] and its constant, banded mass matrix.
enum class BodyType { rigid, point_mass, flexible };

/// A body. A rigid body's frame has its origin at the centre of mass; a point mass has no
/// orientation (its markers all lie at its position). A flexible link's frame is that of its
/// undeformed state: origin at the middle of its axis, x along the axis from end A to end B;
/// its markers lie on the axis (y = 0, |x| ≤ length/2) and move with the deformed beam.
struct Body {
  std::string name;
  BodyType type = BodyType::rigid;
  double mass = 0.0;                   ///< kg, > 0
  double inertia = 0.0;                ///< kg·m² about the centre of mass, > 0 (rigid only)
  Vec2 r0 = Vec2::Zero();              ///< initial position of the centre of mass in world, m
  double phi0 = 0.0;                   ///< initial orientation, rad (rigid only)
  Vec2 v0 = Vec2::Zero();              ///< initial velocity (initial_state: given), m/s
  double omega0 = 0.0;                 ///< initial angular velocity (initial_state: given), rad/s
  std::vector<Marker> markers;
  beam::Mesh mesh;                     ///< flexible only: length, elements, section, material
  /// Flexible only: Kelvin–Voigt retardation time η (s): stresses E(ε + η ε̇), E I(κ + η κ̇).
  double structural_damping = 0.0;
  bool rotates() const { return type == BodyType::rigid; }
  bool flexible() const { return type == BodyType::flexible; }
};

/// A point on a body (or on the ground, in world coordinates).
struct PointRef {
  int body = kGround;
  Vec2 s = Vec2::Zero();  ///< body coordinates (world coordinates on the ground), m
  std::string label;      ///< as written in the model, e.g. "rod.B"
};

/// Hertz material of one side of a contact.
struct Material {
  double youngs_modulus = 0.0;  ///< E, Pa
  double poisson_ratio = 0.0;   ///< ν
};

/// A revolute clearance joint: the journal (point `a` of its joint) moves inside the bearing
/// (point `b`); contact per docs/architecture.md, "Clearance joints".
struct Clearance {
  double clearance = 0.0;        ///< c = R_B − R_J, m
  double journal_radius = 0.0;   ///< R_J, m
  double bearing_radius = 0.0;   ///< R_B, m
  NormalLaw normal_law = NormalLaw::lankarani_nikravesh;
  /// Contact parameters; a stiffness of 0 is derived by `finalize` from the materials.
  ContactParams contact;
  std::optional<Material> journal_material, bearing_material;
  FrictionLaw friction_law = FrictionLaw::none;
  FrictionParams friction;
  LuGreParams lugre;             ///< friction_law == lugre
  /// Floor on the located impact velocity δ̇⁻ used by the damped laws, m/s: a grazing contact
  /// would otherwise divide by ~0.
  double min_impact_velocity = 1e-3;
};

/// Joint kinds (core/elements/<kind>.cpp). Revolute: `a` is the journal point, `b` the bearing
/// point and r_a = r_b. Translational: `a` is on the guide body, whose frame holds `axis`; `b` on
/// the sliding body; relative rotation locked (unless the slider is a point mass). Fixed: r_a =
/// r_b and rotation locked. Distance: |r_b − r_a| = length (a massless rod with pins at a, b).
enum class JointType { revolute, translational, fixed, distance };

struct Joint {
  std::string name;
  JointType type = JointType::revolute;
  PointRef a, b;
  Vec2 axis = Vec2::UnitX();     ///< translational: unit slide axis in body a's frame
  double angle0 = 0.0;           ///< translational/fixed: locked φ_b − φ_a, rad
  double length = NAN;           ///< distance: rod length, m (NaN: the initial distance)
  std::optional<Clearance> clearance;  ///< set: a revolute clearance joint (no constraint)
  bool is_constraint() const { return !clearance.has_value(); }
};

/// How a driver's coordinate moves: coordinate(t) = initial + f(t) with f = speed·t
/// (constant_speed), f = expression(t) (position), or f = ∫₀ᵗ expression (speed).
enum class DriverProfile { constant_speed, position, speed };

/// What a driver prescribes: a joint coordinate (revolute θ = φ_a − φ_b, translational
/// s = (r_b − r_a)·axis) or one coordinate of a body relative to the ground (x, y or φ), which
/// lets the body's joints have clearance.
enum class DriverTarget { joint, body };
enum class BodyCoordinate { x, y, phi };

struct Driver {
  std::string name;
  DriverTarget target = DriverTarget::joint;
  int joint = -1;                ///< target joint
  int body = -1;                 ///< target body
  BodyCoordinate coordinate = BodyCoordinate::phi;
  DriverProfile profile = DriverProfile::constant_speed;
  double speed = 0.0;            ///< rad/s or m/s (constant_speed)
  std::string expression;        ///< f(time) (position) or ḟ(time) (speed), rad or m [/s]
  double initial = NAN;          ///< coordinate at t = 0, rad or m (NaN: from the initial poses)

};

/// Load kinds (core/elements/<kind>.cpp). force: (fx, fy) expressions in world axes at point
/// `a`. torque: expression on body `body_a`. spring_damper: between points a and b, tension
/// f = k(L − L0) + c L̇. torsional_spring_damper: T = k(θ − θ0) + c θ̇ with θ = φ_b − φ_a, acting
/// +T on a, −T on b. bushing: spring–dampers along the two axes of `frame_body`'s frame between
/// point a and point b, plus an optional torsional part.
enum class LoadType { force, torque, spring_damper, torsional_spring_damper, bushing };

struct Load {
  std::string name;
  LoadType type = LoadType::force;
  PointRef a, b;
  int body_a = kGround, body_b = kGround;
  std::string fx = "0", fy = "0", torque = "0";
  double stiffness = 0.0, damping = 0.0;
  double angle0 = NAN;           ///< torsional part: rest angle φ_b − φ_a, rad (NaN: initial)
  double free_length = NAN;      ///< spring_damper: L0, m (NaN: the initial length)
  int frame_body = kGround;      ///< bushing: body whose axes the pairs follow
  Vec2 stiffness_xy = Vec2::Zero(), damping_xy = Vec2::Zero();  ///< bushing, N/m and N·s/m
};

/// Sensor kinds (core/elements/sensors.cpp): a point `at` of a body and a unit `axis`, fixed in
/// the body's frame or in the ground's.
enum class SensorType { accelerometer, velocity, displacement };

struct Sensor {
  std::string name;
  SensorType type = SensorType::accelerometer;
  PointRef at;
  Vec2 axis = Vec2::UnitX();     ///< unit vector, in the body's or the ground's axes
  bool body_axis = true;         ///< axis fixed in the body (false: in the ground)
  bool gravity = true;           ///< accelerometer: reads specific force a − g, as a real one
  double mass = 0.0;             ///< kg added at `at` (a point mass pinned there by finalize)
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
  /// Upper bound on end_time / output_interval, checked before running: a typo in either cannot
  /// fill a disk (about 1 GB of CSV at the default for a 30-channel model).
  long max_outputs = 2'000'000;
  InitialStateRule initial_state = InitialStateRule::ideal;
  double baumgarte_alpha = 100.0;  ///< Φ̈ + 2αΦ̇ + β²Φ = 0, 1/s
  double baumgarte_beta = 100.0;
};

/// One output channel: `<element>.<quantity>`, its SI unit ("" dimensionless) and meaning.
struct ChannelInfo {
  std::string name, unit, description;
};

struct Model;
/// Whether driver d drives an angle (rad, its multiplier a torque) rather than a length (m).
bool driver_is_rotary(const Model& model, const Driver& d);

struct Model {
  std::string name;
  std::string source;          ///< the file it was read from, if any
  std::vector<Body> bodies;
  std::vector<Joint> joints;
  std::vector<Driver> drivers;
  std::vector<Load> loads;
  std::vector<Sensor> sensors;
  Vec2 gravity = Vec2::Zero();
  SolverSettings solver;
  bool finalized = false;      ///< set by finalize()
  /// Every channel in column order, set by finalize() (channel_info(model) reads it; building a
  /// Workspace to list them compiles every expression of the model). Code that changes the
  /// elements of a finalized model (the ideal twin drops its clearances) lists them again.
  std::vector<ChannelInfo> channels;

  /// Number of clearance joints.
  int clearance_joint_count() const;
};

}  // namespace lash
