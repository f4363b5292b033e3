#include "core/finalize.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "core/elements/registry.hpp"

namespace lash {

namespace {

/// A value for a message: %g (std::to_string's fixed six decimals read 5e-10 m as 0.000000).
std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string join_problems(const std::vector<ModelProblem>& p) {
  std::string s;
  for (const auto& x : p) s += (s.empty() ? "" : "\n") + x.element + ": " + x.message;
  return s;
}

/// Pose of a point at the model's initial poses: world position and its body's rotation.
Vec2 initial_point(const Model& m, const PointRef& p) {
  if (p.body == kGround) return p.s;
  const Body& b = m.bodies[p.body];
  return b.r0 + rotation(b.phi0) * p.s;
}
double initial_angle(const Model& m, int body) {
  return body == kGround ? 0.0 : m.bodies[body].phi0;
}

class Checker {
 public:
  explicit Checker(Model& m) : m_(m) {}

  void run() {
    names();
    for (Body& b : m_.bodies) body(b);
    for (Joint& j : m_.joints) joint(j);
    for (Driver& d : m_.drivers) driver(d);
    for (Load& l : m_.loads) load(l);
    for (Sensor& s : m_.sensors) sensor(s);
    if (!p_.empty()) throw InvalidModel(p_);
    mount_sensor_masses();
  }

 private:
  void error(const std::string& element, const std::string& msg) { p_.push_back({element, msg}); }
  bool valid_body(int b) const { return b == kGround || (b >= 0 && b < int(m_.bodies.size())); }
  bool rotates(int b) const { return b == kGround || m_.bodies[b].rotates(); }
  bool flexible(int b) const { return b != kGround && m_.bodies[b].flexible(); }
  /// An angle to drive, load or lock: the ground, a rigid body, or a flexible link (its axis at
  /// a point, kinematics.hpp: point_angle); not a point mass.
  bool has_angle(int b) const { return rotates(b) || flexible(b); }
  std::string body_name(int b) const { return b == kGround ? "ground" : m_.bodies[b].name; }

  void names() {
    // Names are unique within a kind (a driver names its joint by name) and never a reserved
    // prefix; channel names across kinds are checked once the model is laid out (finalize).
    auto check = [&](const std::string& kind, const auto& list) {
      std::set<std::string> seen;
      for (const auto& x : list) {
        const std::string& n = x.name;
        const std::string el = kind + " '" + n + "'";
        if (n.empty()) error(el, "a name must not be empty");
        for (char c : n)
          if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) {
            error(el, "a name must be letters, digits and '_' (it names CSV columns), got '" +
                          n + "'");
            break;
          }
        if (reserved_name(n)) error(el, "the name '" + n + "' is reserved");
        if (!seen.insert(n).second) error(el, "a second " + kind + " named '" + n + "'");
      }
    };
    check("body", m_.bodies);
    check("joint", m_.joints);
    check("driver", m_.drivers);
    check("load", m_.loads);
    check("sensor", m_.sensors);
  }

  void body(Body& b) {
    const std::string el = "body '" + b.name + "'";
    if (b.flexible()) return flexible_body(b, el);
    if (!(b.mass > 0 && std::isfinite(b.mass))) error(el, "mass must be > 0 kg");
    if (b.rotates() && !(b.inertia > 0 && std::isfinite(b.inertia)))
      error(el, "inertia must be > 0 kg·m² (leave it out for a point mass)");
    if (!b.rotates()) {
      if (b.phi0 != 0.0 || b.omega0 != 0.0)
        error(el, "a point mass has no angle: remove 'angle'/'angular_velocity' or give "
                  "'inertia'");
      for (const Marker& mk : b.markers)
        if (mk.s_P_B.squaredNorm() != 0.0)
          error(el, "marker '" + mk.name + "' is off the point mass (a point mass has no "
                    "extent: its markers must be at [0, 0]); give 'inertia' for a rigid body");
    }
  }

  void flexible_body(Body& b, const std::string& el) {
    const beam::Mesh& m = b.mesh;
    const beam::Section& s = m.section;
    auto positive = [](double v) { return v > 0 && std::isfinite(v); };
    if (!positive(m.length)) error(el, "length must be > 0 m");
    if (m.elements < 1 || m.elements > 1000) error(el, "elements must be 1 … 1000");
    if (!positive(s.youngs_modulus)) error(el, "youngs_modulus must be > 0 Pa");
    if (!positive(s.area) || !positive(s.inertia)) {
      std::ostringstream got;
      got << "the section's area and second moment of area must be finite and > 0, got A = "
          << s.area << " m², I = " << s.inertia << " m⁴";
      error(el, got.str());
    }
    if (!(s.fibre >= 0 && std::isfinite(s.fibre))) error(el, "fibre distance must be >= 0 m");
    if (!(b.structural_damping >= 0 && std::isfinite(b.structural_damping)))
      error(el, "damping (retardation time) must be >= 0 s");
    // Mass and density: one follows from the other; both given must agree (not said again for a
    // length or section already refused: "give the density or the mass" beside a given mass).
    if (!positive(m.length) || !positive(s.area)) return;
    if (!positive(s.density) && positive(b.mass) && positive(m.length) && positive(s.area))
      b.mesh.section.density = b.mass / (s.area * m.length);
    const double from_section = b.mesh.section.density * s.area * m.length;
    if (!positive(from_section)) return error(el, "give the density or the mass");
    if (b.mass == 0.0) b.mass = from_section;
    if (std::abs(b.mass - from_section) > 1e-6 * from_section)
      error(el, "mass " + num(b.mass) + " kg differs from density × area × length = " +
                    num(from_section) + " kg; give one of them");
    b.inertia = b.mass * m.length * m.length / 12.0;  // of the undeformed link, for reports
    for (const Marker& mk : b.markers)
      if (std::abs(mk.s_P_B.y()) > 1e-12 * m.length ||
          std::abs(mk.s_P_B.x()) > 0.5 * m.length * (1 + 1e-12))
        error(el, "marker '" + mk.name + "' at [" + num(mk.s_P_B.x()) + ", " +
                      num(mk.s_P_B.y()) +
                      "] is off the link's axis: markers of a flexible link lie at [x, 0] with "
                      "|x| <= length/2 = " + num(0.5 * m.length) + " m");
  }

  void joint(Joint& j) {
    const std::string el = "joint '" + j.name + "'";
    if (!valid_body(j.a.body) || !valid_body(j.b.body)) return error(el, "body out of range");
    if (j.a.body == j.b.body) error(el, "joins body '" + body_name(j.a.body) + "' to itself");
    if (flexible(j.a.body) && j.type == JointType::translational)
      return error(el, "a flexible link cannot be a translational joint's guide (the slider would "
                       "run along its deforming axis); make the link the slider, or clamp a rigid "
                       "guide to it");
    if (j.clearance) {
      Clearance& c = *j.clearance;
      if (j.type != JointType::revolute) error(el, "only a revolute joint can have clearance");
      if (!(c.clearance > 0)) error(el, "clearance must be > 0 m");
      if (!(c.journal_radius > 0)) error(el, "journal_radius must be > 0 m");
      c.bearing_radius = c.journal_radius + c.clearance;
      if (!(c.bearing_radius > c.journal_radius))
        error(el, "clearance is lost in the journal radius (journal_radius + clearance rounds to "
                  "journal_radius)");
      if (c.contact.stiffness == 0.0 && c.journal_material && c.bearing_material)
        c.contact.stiffness = hertz_cylinder_stiffness(
            c.bearing_radius, c.journal_radius, c.bearing_material->youngs_modulus,
            c.bearing_material->poisson_ratio, c.journal_material->youngs_modulus,
            c.journal_material->poisson_ratio);
      if (!(c.contact.stiffness > 0))
        error(el, "contact stiffness must be > 0: give 'stiffness' or the two materials");
      return;
    }
    switch (j.type) {
      case JointType::revolute: break;
      case JointType::translational:
        if (!rotates(j.a.body))
          error(el, "the guide (first body) is a point mass, which has no axes to slide along");
        if (std::abs(j.axis.norm() - 1.0) > 1e-12) error(el, "axis must be a unit vector");
        break;
      case JointType::fixed:
        if (flexible(j.a.body) || flexible(j.b.body)) {
          // A clamped end: the link's axis at the point keeps its initial angle to the other body.
          const int rigid = flexible(j.a.body) ? j.b.body : j.a.body;
          if (!has_angle(rigid))
            error(el, "a fixed joint clamps a flexible link to a rigid body or the ground, not to "
                      "a point mass");
          break;
        }
        if (!rotates(j.a.body) || !rotates(j.b.body))
          error(el, "a fixed joint needs two rotating bodies (use a revolute joint to pin a "
                    "point mass)");
        break;
      case JointType::distance:
        if (std::isnan(j.length))
          j.length = (initial_point(m_, j.b) - initial_point(m_, j.a)).norm();
        if (!(j.length > 0)) error(el, "length must be > 0 m (the points coincide initially)");
        break;
    }
  }

  void driver(Driver& d) {
    const std::string el = "driver '" + d.name + "'";
    if (d.target == DriverTarget::body) {
      if (d.body < 0 || d.body >= int(m_.bodies.size())) return error(el, "body out of range");
      const Body& b = m_.bodies[d.body];
      if (b.flexible())
        return error(el, "body '" + b.name + "' is a flexible link, which has no single "
                         "coordinate to drive; drive a joint or a rigid body");
      if (d.coordinate == BodyCoordinate::phi && !b.rotates())
        return error(el, "body '" + b.name + "' is a point mass: it has no angle to drive");
      if (std::isnan(d.initial))
        d.initial = d.coordinate == BodyCoordinate::x   ? b.r0.x()
                    : d.coordinate == BodyCoordinate::y ? b.r0.y()
                                                        : b.phi0;
    } else {
      if (d.joint < 0 || d.joint >= int(m_.joints.size())) return error(el, "joint out of range");
      const Joint& j = m_.joints[d.joint];
      if (j.clearance || (j.type != JointType::revolute && j.type != JointType::translational))
        return error(el, "joint '" + j.name + "' is " +
                             (j.clearance ? std::string("a clearance joint")
                                          : "not revolute or translational") +
                             "; drive an ideal revolute or translational joint, or drive the "
                             "body itself (body: NAME, coordinate: phi)");
      if (j.type == JointType::revolute && (!has_angle(j.a.body) || !has_angle(j.b.body)))
        return error(el, "joint '" + j.name + "' holds a point mass, which has no angle to drive");
      if (std::isnan(d.initial)) {
        if (j.type == JointType::revolute) {
          d.initial = initial_angle(m_, j.a.body) - initial_angle(m_, j.b.body);
        } else {
          const Vec2 axis = rotation(initial_angle(m_, j.a.body)) * j.axis;
          d.initial = (initial_point(m_, j.b) - initial_point(m_, j.a)).dot(axis);
        }
      }
    }
    if (d.profile != DriverProfile::constant_speed && d.expression.empty())
      error(el, "an expression is required for a position or speed profile");
  }

  void load(Load& l) {
    const std::string el = "load '" + l.name + "'";
    // A torque or a torsional spring on a flexible link acts at a point of it (its axis there).
    auto at_point = [&](int body, const PointRef& p) {
      if (valid_body(body) && flexible(body) && (p.body != body || p.label.find('.') == std::string::npos))
        error(el, "body '" + body_name(body) + "' is a flexible link: name the point it acts at, "
                  "as " + body_name(body) + ".MARKER (its axis there turns)");
    };
    if (l.type == LoadType::torque) at_point(l.body_a, l.a);
    if (l.type == LoadType::torsional_spring_damper) at_point(l.body_a, l.a), at_point(l.body_b, l.b);
    switch (l.type) {
      case LoadType::force:
        if (!valid_body(l.a.body)) error(el, "body out of range");
        break;
      case LoadType::torque:
        if (!valid_body(l.body_a)) return error(el, "body out of range");
        if (!has_angle(l.body_a))
          error(el, "body '" + body_name(l.body_a) + "' is a point mass: it takes no torque");
        break;
      case LoadType::spring_damper:
        if (!valid_body(l.a.body) || !valid_body(l.b.body)) return error(el, "body out of range");
        if (l.a.body == l.b.body)
          error(el, "both ends are on body '" + body_name(l.a.body) + "'; a spring acts between two bodies");
        if (std::isnan(l.free_length))
          l.free_length = (initial_point(m_, l.b) - initial_point(m_, l.a)).norm();
        if (!(l.free_length >= 0)) error(el, "free_length must be >= 0 m");
        break;
      case LoadType::torsional_spring_damper:
        if (!valid_body(l.body_a) || !valid_body(l.body_b)) return error(el, "body out of range");
        if (l.body_a == l.body_b)
          return error(el, "both ends are on body '" + body_name(l.body_a) +
                               "'; a torsional spring acts between two bodies");
        if (!has_angle(l.body_a) || !has_angle(l.body_b))
          error(el, "a torsional spring needs two rotating bodies (a point mass has no angle)");
        if (std::isnan(l.angle0))
          l.angle0 = initial_angle(m_, l.body_b) - initial_angle(m_, l.body_a);
        break;
      case LoadType::bushing: {
        if (!valid_body(l.a.body) || !valid_body(l.b.body)) return error(el, "body out of range");
        if (l.a.body == l.b.body)
          return error(el, "both ends are on body '" + body_name(l.a.body) +
                               "'; a bushing acts between two bodies");
        l.body_a = l.a.body;
        l.body_b = l.b.body;
        if (l.frame_body != kGround && l.frame_body != l.a.body && l.frame_body != l.b.body)
          error(el, "frame must be one of the two bodies it joins, or ground");
        else if (!has_angle(l.frame_body))
          error(el, "frame '" + body_name(l.frame_body) + "' is a point mass, which has no axes");
        if ((l.stiffness != 0.0 || l.damping != 0.0) &&
            (!has_angle(l.a.body) || !has_angle(l.b.body)))
          error(el, "a torsional part needs two rotating bodies (a point mass has no angle)");
        if (std::isnan(l.angle0))
          l.angle0 = initial_angle(m_, l.body_b) - initial_angle(m_, l.body_a);
        break;
      }
    }
    if (l.stiffness < 0 || l.damping < 0 || (l.stiffness_xy.array() < 0).any() ||
        (l.damping_xy.array() < 0).any())
      error(el, "stiffness and damping must be >= 0");
  }

  void sensor(Sensor& s) {
    const std::string el = "sensor '" + s.name + "'";
    if (s.at.body == kGround) error(el, "a sensor must be on a body, not the ground");
    else if (!valid_body(s.at.body)) error(el, "body out of range");
    const double n = s.axis.norm();
    if (!(n > 0) || !std::isfinite(n)) error(el, "axis must be a non-zero vector");
    else s.axis /= n;
    if (s.mass < 0 || !std::isfinite(s.mass)) error(el, "mass must be >= 0 kg");
  }

  void mount_sensor_masses() {
    for (const Sensor& s : m_.sensors) {
      if (s.mass <= 0) continue;
      Body pm;
      pm.name = s.name + "_mass";
      pm.type = BodyType::point_mass;
      pm.mass = s.mass;
      pm.r0 = initial_point(m_, s.at);
      pm.v0 = m_.bodies[s.at.body].v0 +
              m_.bodies[s.at.body].omega0 * perp(rotation(m_.bodies[s.at.body].phi0) * s.at.s);
      m_.bodies.push_back(pm);
      Joint mount;
      mount.name = s.name + "_mount";
      mount.type = JointType::revolute;
      mount.a = {static_cast<int>(m_.bodies.size()) - 1, Vec2::Zero(), pm.name};
      mount.b = s.at;
      m_.joints.push_back(mount);
    }
  }

  Model& m_;
  std::vector<ModelProblem> p_;
};

}  // namespace

namespace {

/// One problem per name whose channels clash, at the element written later in the file (or the
/// sensor whose mass adds it), naming every element of that name and the channels in question.
std::vector<ModelProblem> name_clashes(const Model& model,
                                       const std::map<std::string, std::vector<std::string>>& twice) {
  // The sensor whose `mass` added a point mass `<sensor>_mass` and its joint `<sensor>_mount`.
  auto added_by = [&](const std::string& name, const char* suffix) -> const Sensor* {
    for (const Sensor& sn : model.sensors)
      if (sn.mass > 0 && name == sn.name + suffix) return &sn;
    return nullptr;
  };
  struct Owner {
    std::string element;  ///< where the message points: "load 'hang'", "sensor 'probe'"
    std::string what;     ///< how the message names it
  };
  std::vector<std::string> bodies, joints;
  for (const Body& b : model.bodies) bodies.push_back(b.name);
  for (const Joint& j : model.joints) joints.push_back(j.name);
  std::vector<ModelProblem> out;
  for (const auto& clash : twice) {
    const std::string& name = clash.first;  // (a structured binding cannot be captured in C++17)
    const std::vector<std::string>& channels = clash.second;
    std::vector<Owner> owners;
    // Generated elements come after the file's own (finalize appends them): the last body or
    // joint of a generated name is the generated one.
    auto add = [&](const char* kind, const std::vector<std::string>& names, const char* suffix,
                   const char* added) {
      const Sensor* sn = added_by(name, suffix);
      size_t last = names.size();
      for (size_t i = 0; i < names.size(); ++i)
        if (names[i] == name) last = i;
      for (size_t i = 0; i < names.size(); ++i) {
        if (names[i] != name) continue;
        if (sn && i == last)
          owners.push_back({"sensor '" + sn->name + "'", std::string(added) + " '" + name +
                                                             "' added by sensor '" + sn->name +
                                                             "' (its mass)"});
        else
          owners.push_back({std::string(kind) + " '" + name + "'", std::string(kind) + " '" + name + "'"});
      }
    };
    add("body", bodies, "_mass", "the point mass");
    add("joint", joints, "_mount", "the joint");
    for (const Driver& d : model.drivers)
      if (d.name == name) owners.push_back({"driver '" + name + "'", "driver '" + name + "'"});
    for (const Load& l : model.loads)
      if (l.name == name) owners.push_back({"load '" + name + "'", "load '" + name + "'"});
    for (const Sensor& sn : model.sensors)
      if (sn.name == name) owners.push_back({"sensor '" + name + "'", "sensor '" + name + "'"});
    if (name == "energy" || name == "constraint")
      owners.insert(owners.begin(), {"model", "the model's own " + name + " channels"});
    std::string list;
    for (size_t i = 0; i < channels.size() && i < 3; ++i)
      list += (i ? ", '" : "'") + channels[i] + "'";
    if (channels.size() > 3) list += " and " + std::to_string(channels.size() - 3) + " more";
    std::string others;
    for (size_t i = 0; i + 1 < owners.size(); ++i)
      others += (i ? " and " : "") + owners[i].what;
    const Owner& last = owners.empty() ? Owner{"model", "an element"} : owners.back();
    out.push_back({last.element, (owners.size() > 1 ? last.what + " writes " : "channels ") + list +
                                     (owners.size() > 1 ? ", as " + others + " does"
                                                        : " are written twice") +
                                     "; elements may share a name only when their channels "
                                     "differ: rename one of them"});
  }
  return out;
}

}  // namespace

InvalidModel::InvalidModel(std::vector<ModelProblem> problems)
    : std::invalid_argument(join_problems(problems)), problems_(std::move(problems)) {}

bool reserved_name(const std::string& name) {
  return name == "ground" || name == "energy" || name == "constraint" || name == "time";
}

void finalize(Model& model) {
  if (model.finalized) return;
  Checker(model).run();
  model.finalized = true;
  // Two elements of different kinds may share a name, but not a channel.
  std::map<std::string, int> seen;
  std::map<std::string, std::vector<std::string>> twice;  // element name -> channels written twice
  std::vector<ChannelInfo> channels = channel_info(model, Workspace(model));
  for (const auto& c : channels)
    if (++seen[c.name] == 2) twice[c.name.substr(0, c.name.rfind('.'))].push_back(c.name);
  if (twice.empty()) {
    model.channels = std::move(channels);
    return;
  }
  model.finalized = false;
  throw InvalidModel(name_clashes(model, twice));
}

}  // namespace lash
