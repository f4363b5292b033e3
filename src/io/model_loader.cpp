#include "io/model_loader.hpp"

#include "core/finalize.hpp"
#include "io/number_format.hpp"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <map>
#include <tuple>
#include <algorithm>
#include <set>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>

#include "core/expression.hpp"
#include "io/files.hpp"

namespace lash {

namespace {

std::string fmt_num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + v[i];
  return s;
}

/// Collects diagnostics; knows the file name.
struct Reporter {
  std::string file;
  std::vector<Diagnostic> list;
  bool through_alias = false;  ///< an override went through a YAML alias (apply_override)
  void error(const YAML::Node& at, const std::string& element, const std::string& message) {
    const YAML::Mark m = at.IsDefined() ? at.Mark() : YAML::Mark::null_mark();
    const bool from_override = m.line < 0;
    list.push_back({file, from_override ? 0 : m.line + 1, from_override ? 0 : m.column + 1,
                    element, message + (from_override ? " (value set with --set)" : "")});
  }
};

/// A YAML map of one element, with the keys it accepts.
class Section {
 public:
  // yaml-cpp trap: assigning to or from an undefined ("zombie") Node throws or rebinds the
  // target's content, so the node is chosen once, in the initializer.
  Section(Reporter& r, const YAML::Node& node, const YAML::Node& parent, std::string element,
          std::vector<std::string> allowed)
      : r_(r), node_(usable(node) ? node : YAML::Node(YAML::NodeType::Map)),
        anchor_(has_position(node) ? node : parent), element_(std::move(element)),
        allowed_(std::move(allowed)) {
    if (!node.IsDefined() || node.IsNull()) return;
    if (!node.IsMap()) {
      r_.error(node, element_, "expected a map of keys (key: value), got " + kind(node));
      refused_ = true;
      return;
    }
    for (const auto& kv : node_) {
      const auto key = kv.first.as<std::string>("");
      if (std::find(allowed_.begin(), allowed_.end(), key) != allowed_.end()) continue;
      const std::string near = closest_match(key, allowed_);
      r_.error(kv.first, element_,
               "unknown key '" + key + "'" +
                   (near.empty() ? ", expected one of: " + join(allowed_)
                                 : ", did you mean '" + near + "'?"));
    }
  }

  /// Not 0 and below the smallest normal double (1e-320): its arithmetic has lost its precision,
  /// and a stiffness or mass that small made runs that completed with nothing holding a link.
  /// A value written as 1e-400 reads as 0 (below even the subnormals): it counts too ("mass must
  /// be > 0, got 0" answered a mass that was given).
  static bool subnormal(const YAML::Node& n, double v) {
    if (v != 0.0) return std::abs(v) < std::numeric_limits<double>::min();
    if (!n.IsScalar()) return false;
    const std::string& text = n.Scalar();
    for (char c : text) {
      if (c == 'e' || c == 'E') break;
      if (c >= '1' && c <= '9') return true;
    }
    return false;
  }
  static bool usable(const YAML::Node& n) { return n.IsDefined() && n.IsMap(); }
  /// (An empty value's position is the next token's, often on a later line: not its own.)
  static bool has_position(const YAML::Node& n) {
    return n.IsDefined() && !n.IsNull() && n.Mark().line >= 0;
  }
  static std::string join_scalars(const YAML::Node& n) {
    std::string out;
    for (size_t i = 0; i < n.size(); ++i)
      out += (i ? ", " : "") + (n[i].IsScalar() ? n[i].Scalar() : std::string("..."));
    return out;
  }
  static std::string kind(const YAML::Node& n) {
    if (n.IsScalar()) return "'" + n.Scalar() + "'";
    if (n.IsSequence()) return "a list";
    if (n.IsMap()) return "a map";
    return "an empty value";
  }

  /// The key is given. An empty value (`key:` with nothing after it, or `~`) counts as given,
  /// so that reading it says what was expected (a forgotten clearance made the joint ideal, a
  /// forgotten stiffness a spring of 0 N/m, without a word); only a collection of elements or
  /// markers, the solver's map and the description may be empty.
  bool has(const std::string& key) const {
    const YAML::Node n = node_[key];
    if (!n.IsDefined()) return false;
    return !n.IsNull() || !may_be_empty(key);
  }
  /// Keys whose empty value means an empty collection (or no description).
  static bool may_be_empty(const std::string& key) {
    static const char* const keys[] = {"ground", "bodies", "joints", "clearance_defaults",
                                       "drivers", "loads", "sensors", "solver",
                                       "markers", "output_channels", "description"};
    return std::any_of(std::begin(keys), std::end(keys), [&](const char* k) { return key == k; });
  }
  YAML::Node get(const std::string& key) const { return node_[key]; }
  /// A key whose value must be a map (friction, material, flexible, section, baumgarte): true,
  /// reported, where it was left empty.
  bool empty_map(const std::string& key) {
    const YAML::Node n = node_[key];
    if (!n.IsDefined() || !n.IsNull()) return false;
    r_.error(at(key), element_, "'" + key + "' must be a map of keys (key: value), got an empty value");
    return true;
  }
  /// Where a problem with the key's value is reported: the value, or the key itself where the
  /// value is empty (an empty value's position is the next token's, often on a later line).
  YAML::Node at(const std::string& key) const {
    const YAML::Node n = node_[key];
    if (!n.IsDefined() || !n.IsNull()) return n;
    for (const auto& kv : node_)
      if (kv.first.as<std::string>("") == key) return kv.first;
    return n;
  }
  const YAML::Node& node() const { return node_; }
  /// Where a problem of the whole element is reported: the map itself, or where it was expected
  /// (node() is an empty map without a position when the element is not a map).
  const YAML::Node& where() const { return anchor_; }
  /// The element was not a map (already reported): nothing more to say about it.
  bool refused() const { return refused_; }
  const std::string& element() const { return element_; }
  Reporter& reporter() { return r_; }

  /// A number; `check` returns "" or what was expected (e.g. "> 0").
  std::optional<double> number(const std::string& key, const std::string& units,
                               const std::function<std::string(double)>& check = {}) {
    if (!has(key)) return std::nullopt;
    const YAML::Node n = node_[key];
    double v = 0.0;
    if (!n.IsScalar() || !YAML::convert<double>::decode(n, v) || !std::isfinite(v)) {
      r_.error(at(key), element_, "'" + key + "' must be a number" + units + ", got " + kind(n));
      return std::nullopt;
    }
    if (subnormal(n, v)) {
      r_.error(n, element_, "'" + key + "' is " + n.Scalar() + ", below the smallest normal double (" +
                                fmt_num(std::numeric_limits<double>::min()) +
                                "), where arithmetic has lost its precision");
      return std::nullopt;
    }
    if (check) {
      const std::string expected = check(v);
      if (!expected.empty()) {
        r_.error(n, element_, key + " must be " + expected + ", got " + fmt_num(v));
        return std::nullopt;
      }
    }
    return v;
  }
  double required_number(const std::string& key, const std::string& units,
                         const std::function<std::string(double)>& check, double fallback) {
    if (!has(key)) {
      r_.error(anchor_, element_, "missing required key '" + key + "'" + units);
      return fallback;
    }
    return number(key, units, check).value_or(fallback);
  }
  std::optional<std::string> text(const std::string& key) {
    if (!has(key)) return std::nullopt;
    const YAML::Node n = node_[key];
    if (!n.IsScalar()) {
      r_.error(at(key), element_, "'" + key + "' must be a single value, got " + kind(n));
      return std::nullopt;
    }
    return n.Scalar();
  }
  std::optional<Vec2> vec2(const std::string& key, const std::string& units) {
    if (!has(key)) return std::nullopt;
    const YAML::Node n = node_[key];
    double x, y;
    if (n.IsSequence() && n.size() == 2 && YAML::convert<double>::decode(n[0], x) &&
        YAML::convert<double>::decode(n[1], y) && (subnormal(n[0], x) || subnormal(n[1], y))) {
      r_.error(at(key), element_, "'" + key + "' is [" + join_scalars(n) + "]: " +
                                      (subnormal(n[0], x) ? n[0] : n[1]).Scalar() +
                                      " is below the smallest normal double (" +
                                      fmt_num(std::numeric_limits<double>::min()) +
                                      "), where arithmetic has lost its precision");
      return std::nullopt;
    }
    if (!n.IsSequence() || n.size() != 2 || !YAML::convert<double>::decode(n[0], x) ||
        !YAML::convert<double>::decode(n[1], y) || !std::isfinite(x) || !std::isfinite(y)) {
      r_.error(at(key), element_, "'" + key + "' must be a pair of finite numbers [x, y]" + units +
                                ", got " + (n.IsSequence() ? "[" + join_scalars(n) + "]" : kind(n)));
      return std::nullopt;
    }
    return Vec2(x, y);
  }

 private:
  Reporter& r_;
  YAML::Node node_;
  YAML::Node anchor_;  ///< where to point when a key is missing: the map, or its parent
  bool refused_ = false;
  std::string element_;
  std::vector<std::string> allowed_;
};

/// [A-Za-z_][A-Za-z0-9_]*: a name expressions can use (std::regex would compile a pattern per
/// body, about half a million instructions each).
bool is_identifier(const std::string& s) {
  auto letter = [](char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_'; };
  if (s.empty() || !letter(s[0])) return false;
  for (char c : s)
    if (!letter(c) && !(c >= '0' && c <= '9')) return false;
  return true;
}

// Checks used with Section::number.
std::string positive(double v) { return v > 0 ? "" : "> 0"; }
std::string non_negative(double v) { return v >= 0 ? "" : ">= 0"; }
std::string unit_interval(double v) { return v > 0 && v <= 1 ? "" : "in (0, 1]"; }
std::string poisson(double v) { return v > -1 && v < 0.5 ? "" : "in (-1, 0.5)"; }
/// A relative tolerance the error control can honour: above 0.1 no digit of the result is
/// controlled (at 0.5 DOPRI5's first step already fails), below 1e-14 the error estimate is
/// round-off (2.2e-16 per operation).
std::string relative_tolerance(double v) {
  return v >= 1e-14 && v <= 0.1 ? "" : "in [1e-14, 0.1] (1e-6 to 1e-10 is usual)";
}

/// Below 1e-18 the error test of a state that starts at zero (an energy account, a coordinate
/// on an axis) sees only round-off: the Flores example stopped at t = 0 with atol 1e-20 and
/// 1e-300 ("step size underflow"), and took 80 000 steps at 1e-18 against 4 300 at 1e-11.
std::string absolute_tolerance(double v) {
  return v >= 1e-18 && v <= 1.0 ? "" : "in [1e-18, 1] (1e-9 to 1e-12 is usual, in SI units)";
}

class Loader {
 public:
  Loader(const std::string& file) { r_.file = file; }

  /// Every key left without a value that no reader has reported (one the element's type or law
  /// does not read: a `material:` beside a contact `stiffness`): an empty value is never the
  /// default (Section::has). Each map is walked once (`seen`: where maps start), so that an
  /// alias of a map, or an alias inside itself, is not walked again.
  void report_empty(const YAML::Node& map, const std::string& path,
                    std::set<std::pair<int, int>>* seen = nullptr) {
    std::set<std::pair<int, int>> own;
    if (!seen) seen = &own;
    if (!map.IsMap()) return;
    if (map.Mark().line >= 0 ? !seen->insert({map.Mark().line, map.Mark().column}).second
                             : std::count(path.begin(), path.end(), '.') > 32)
      return;  // walked already (a map set with --set has no place: its depth is bounded)
    for (const auto& kv : map) {
      const std::string key = kv.first.as<std::string>("");
      if (!kv.second.IsNull()) {
        report_empty(kv.second, path.empty() ? key : path + "." + key, seen);
        continue;
      }
      if (Section::may_be_empty(key)) continue;
      const YAML::Mark at = kv.first.Mark();
      const bool said = std::any_of(r_.list.begin(), r_.list.end(), [&](const Diagnostic& d) {
        return d.line == at.line + 1 && d.column == at.column + 1;
      });
      if (!said)
        r_.error(kv.first, path.empty() ? "model" : path,
                 "'" + key + "' has an empty value: give one, or leave the key out for its default");
    }
  }

  /// Where each element read is written (LoadedModel::positions).
  std::map<std::string, std::pair<int, int>> positions() const {
    std::map<std::string, std::pair<int, int>> out;
    for (const auto& [element, node] : nodes_)
      if (node.IsDefined() && node.Mark().line >= 0)
        out[element] = {node.Mark().line + 1, node.Mark().column + 1};
    return out;
  }

  Model load(YAML::Node root) {
    Model m;
    Section top(r_, root, root, "model",
                {"name", "description", "gravity", "ground", "bodies", "joints",
                 "clearance_defaults", "drivers", "loads", "sensors", "solver"});
    if (!root.IsMap()) throw ModelError(r_.list);
    m.name = top.text("name").value_or("model");
    m.gravity = top.vec2("gravity", " (m/s²)").value_or(Vec2::Zero());
    read_ground(top.get("ground"), root);
    read_bodies(m, top.get("bodies"), root);
    if (top.has("clearance_defaults")) defaults_.reset(top.get("clearance_defaults"));
    if (defaults_.IsDefined() && !defaults_.IsNull() && !defaults_.IsMap())
      r_.error(defaults_, "clearance_defaults", "expected a map, got " + Section::kind(defaults_));
    read_joints(m, top.get("joints"), root);
    read_drivers(m, top.get("drivers"));
    read_loads(m, top.get("loads"));
    read_sensors(m, top.get("sensors"));
    read_solver(m, top.get("solver"), root);
    report_empty(root, "");
    if (!r_.list.empty()) throw ModelError(r_.list);
    // Derived values and the element kinds' own checks: the same for every source of a model.
    try {
      finalize(m);
    } catch (const InvalidModel& e) {
      for (const auto& p : e.problems()) {
        const auto it = nodes_.find(p.element);
        r_.error(it != nodes_.end() ? it->second : root, p.element, p.message);
      }
      throw ModelError(r_.list);
    }
    // The channels the model's output_channels select, now that the channels are known: each
    // pattern that matches none is reported at its entry (lash check finds what lash run would
    // refuse).
    for (const auto& [node, pattern] : output_patterns_) {
      try {
        select_channels(m.channels, {pattern});
      } catch (const std::invalid_argument& e) {
        r_.error(node, "solver", std::string("output_channels: ") + e.what());
      }
    }
    if (!r_.list.empty()) throw ModelError(r_.list);
    return m;
  }

  Reporter& reporter() { return r_; }
  const OutputSettings& output() const { return output_; }

 private:
  // --- references --------------------------------------------------------------------------
  int body_index(const std::string& name) const {
    if (name == "ground") return kGround;
    for (size_t i = 0; i < body_names_.size(); ++i)
      if (body_names_[i] == name) return static_cast<int>(i);
    return -2;
  }
  std::vector<std::string> body_choices() const {
    std::vector<std::string> c{"ground"};
    c.insert(c.end(), body_names_.begin(), body_names_.end());
    return c;
  }

  /// "body.marker" or "body" (its centre of mass; the origin for the ground).
  std::optional<PointRef> point(Section& s, const std::string& key, bool required = true) {
    if (!s.has(key)) {
      if (required)
        r_.error(s.where(), s.element(), "missing required key '" + key + "' (body.marker)");
      return std::nullopt;
    }
    const auto text = s.text(key);
    if (!text) return std::nullopt;
    return resolve_point(s.get(key), s.element(), *text);
  }
  std::optional<PointRef> resolve_point(const YAML::Node& at, const std::string& element,
                                        const std::string& text) {
    const auto dot = text.find('.');
    const std::string body = text.substr(0, dot);
    const int b = body_index(body);
    if (b == -2) {
      const std::string near = closest_match(body, body_choices());
      r_.error(at, element, "unknown body '" + body + "' in '" + text + "', expected one of: " +
                                join(body_choices()) +
                                (near.empty() ? "" : " (did you mean '" + near + "'?)"));
      return std::nullopt;
    }
    PointRef p;
    p.body = b;
    p.label = text;
    if (dot == std::string::npos) return p;
    const std::string marker = text.substr(dot + 1);
    const auto& markers = b == kGround ? ground_markers_ : markers_[b];
    std::vector<std::string> names;
    for (const auto& mk : markers) {
      if (mk.name == marker) {
        p.s = mk.s_P_B;
        return p;
      }
      names.push_back(mk.name);
    }
    const std::string near = closest_match(marker, names);
    r_.error(at, element,
             "unknown marker '" + marker + "' on body '" + body + "', expected one of: " +
                 (names.empty() ? "(none defined)" : join(names)) +
                 (near.empty() ? "" : " (did you mean '" + near + "'?)"));
    return std::nullopt;
  }
  /// The body named by `key` (a body's name, or ground).
  std::optional<int> body_ref(Section& s, const std::string& key) {
    const YAML::Node n = s.get(key);
    if (!n.IsScalar()) {
      r_.error(s.at(key), s.element(), "'" + key + "' must be a body name, got " + Section::kind(n));
      return std::nullopt;
    }
    const int b = body_index(n.Scalar());
    if (b == -2) {
      const std::string near = closest_match(n.Scalar(), body_choices());
      r_.error(n, s.element(), "unknown body '" + n.Scalar() + "', expected one of: " +
                                   join(body_choices()) +
                                   (near.empty() ? "" : " (did you mean '" + near + "'?)"));
      return std::nullopt;
    }
    return b;
  }

  std::vector<Marker> read_markers(Section& s) {
    std::vector<Marker> out;
    if (!s.has("markers")) return out;
    const YAML::Node n = s.get("markers");
    if (!n.IsMap()) {
      r_.error(n, s.element(), "'markers' must be a map name: [x, y], got " + Section::kind(n));
      return out;
    }
    for (const auto& kv : n) {
      Marker mk;
      mk.name = kv.first.as<std::string>("");
      double x, y;
      if (!kv.second.IsSequence() || kv.second.size() != 2 ||
          !YAML::convert<double>::decode(kv.second[0], x) ||
          !YAML::convert<double>::decode(kv.second[1], y) || !std::isfinite(x) ||
          !std::isfinite(y) || Section::subnormal(kv.second[0], x) ||
          Section::subnormal(kv.second[1], y)) {
        r_.error(kv.second, s.element(),
                 "marker '" + mk.name + "' must be [x, y], finite numbers in body coordinates (m), got " +
                     (kv.second.IsSequence() ? "[" + Section::join_scalars(kv.second) + "]"
                                             : Section::kind(kv.second)));
        // Still a marker: the joints naming it get no second problem ("unknown marker").
        mk.s_P_B = Vec2::Zero();
        out.push_back(mk);
        continue;
      }
      mk.s_P_B = Vec2(x, y);
      out.push_back(mk);
    }
    return out;
  }

  // --- sections ----------------------------------------------------------------------------
  void read_ground(const YAML::Node& n, const YAML::Node& root) {
    Section s(r_, n, root, "ground", {"markers"});
    ground_markers_ = read_markers(s);
  }

  void read_bodies(Model& m, const YAML::Node& n, const YAML::Node& root) {
    if (!n.IsDefined() || !n.IsMap() || n.size() == 0) {
      r_.error(n.IsDefined() ? n : root, "model",
               "'bodies' must be a map of at least one body (name: {mass, inertia, ...})");
      return;
    }
    for (const auto& kv : n) body_names_.push_back(kv.first.as<std::string>(""));
    for (const auto& kv : n) {
      const std::string name = kv.first.as<std::string>("");
      Section s(r_, kv.second, kv.first, "body '" + name + "'",
                {"mass", "inertia", "position", "angle", "angle_deg", "velocity",
                 "angular_velocity", "markers", "flexible"});
      if (name == "ground") r_.error(kv.first, s.element(), "'ground' is reserved; rename the body");
      if (!is_identifier(name))
        r_.error(kv.first, s.element(),
                 "a body name must be letters, digits and '_', starting with a letter or '_' "
                 "(it is used in expressions as <body>.x), got '" + name + "'");
      Body b;
      b.name = name;
      if (!s.has("flexible")) b.mass = s.required_number("mass", " (kg)", positive, 1.0);
      nodes_["body '" + name + "'"] = kv.second;
      if (s.has("flexible")) {
        // A flexible link: `mass` may be left out (density × area × length) and `inertia`,
        // if given (the same body as a rigid link), is not used.
        b.type = BodyType::flexible;
        b.mass = s.number("mass", " (kg)", positive).value_or(0.0);
        read_flexible(s, b);
      } else if (s.has("inertia")) {
        b.inertia = s.required_number("inertia", " (kg·m² about the centre of mass)", positive, 1.0);
      } else {
        b.type = BodyType::point_mass;  // no inertia: a point mass, coordinates [x, y]
        for (const char* k : {"angle", "angle_deg", "angular_velocity"})
          if (s.has(k))
            r_.error(s.at(k), s.element(),
                     std::string("a body without 'inertia' is a point mass, which has no angle; "
                                 "remove '") + k + "' or give 'inertia'");
      }
      b.r0 = s.vec2("position", " (m)").value_or(Vec2::Zero());
      if (s.has("angle") && s.has("angle_deg"))
        r_.error(s.at("angle_deg"), s.element(), "give 'angle' (rad) or 'angle_deg', not both");
      b.phi0 = s.number("angle", " (rad)").value_or(0.0);
      if (auto deg = s.number("angle_deg", " (degrees)")) b.phi0 = *deg * M_PI / 180.0;
      b.v0 = s.vec2("velocity", " (m/s)").value_or(Vec2::Zero());
      b.omega0 = s.number("angular_velocity", " (rad/s)").value_or(0.0);
      b.markers = read_markers(s);
      markers_.push_back(b.markers);
      m.bodies.push_back(b);
    }
  }

  /// A body's `flexible:` map: an ANCF beam (core/beam.hpp) along the body's x axis.
  void read_flexible(Section& body, Body& b) {
    if (body.empty_map("flexible")) return;
    Section f(r_, body.get("flexible"), body.where(), body.element() + " flexible",
              {"length", "elements", "section", "youngs_modulus", "density", "damping"});
    beam::Mesh& m = b.mesh;
    m.length = f.required_number("length", " (m, end A at x = -length/2, B at +length/2)",
                                 positive, 1.0);
    const double elements = f.number("elements", "", positive).value_or(4.0);
    if (elements != std::floor(elements) || elements > 1000)
      r_.error(f.at("elements"), f.element(), "elements must be a whole number 1 … 1000");
    else
      m.elements = static_cast<int>(elements);
    const double e = f.required_number("youngs_modulus", " (Pa)", positive, 1.0);
    const double rho = f.number("density", " (kg/m³)", positive).value_or(0.0);
    b.structural_damping =
        f.number("damping", " (s, Kelvin–Voigt retardation time)", non_negative).value_or(0.0);
    if (!f.has("section")) {
      r_.error(f.at("length").IsDefined() ? body.at("flexible") : body.where(), f.element(),
               "missing required key 'section': {rectangle: [width, height]}, {tube: [outer "
               "diameter, inner diameter]}, {circle: diameter} or {area, inertia, fibre}");
      return;
    }
    if (f.empty_map("section")) return;
    Section sec(r_, f.get("section"), f.where(), f.element() + " section",
                {"rectangle", "tube", "circle", "area", "inertia", "fibre"});
    const int shapes = sec.has("rectangle") + sec.has("tube") + sec.has("circle") + sec.has("area");
    if (shapes != 1) {
      r_.error(f.at("section"), sec.element(),
               "give exactly one of rectangle: [width, height], tube: [outer diameter, inner "
               "diameter], circle: diameter, or area with inertia and fibre");
      return;
    }
    beam::Section& s = m.section;
    if (auto r = sec.vec2("rectangle", " (m: width across the plane, height in it)")) {
      if (!(r->x() > 0 && r->y() > 0))
        r_.error(sec.at("rectangle"), sec.element(), "width and height must be > 0 m");
      s = beam::rectangle(r->x(), r->y(), e, rho);
    } else if (auto t = sec.vec2("tube", " (m: outer and inner diameter)")) {
      if (!(t->x() > t->y() && t->y() >= 0))
        r_.error(sec.at("tube"), sec.element(), "outer diameter must exceed the inner one (>= 0)");
      const double d4 = std::pow(t->x(), 4) - std::pow(t->y(), 4);
      s.area = M_PI / 4.0 * (t->x() * t->x() - t->y() * t->y());
      s.inertia = M_PI / 64.0 * d4;
      s.fibre = 0.5 * t->x();
    } else if (auto d = sec.number("circle", " (m, diameter)", positive)) {
      s.area = M_PI / 4.0 * *d * *d;
      s.inertia = M_PI / 64.0 * std::pow(*d, 4);
      s.fibre = 0.5 * *d;
    } else if (sec.has("area")) {
      s.area = sec.required_number("area", " (m²)", positive, 1.0);
      s.inertia = sec.required_number("inertia", " (m⁴, second moment of area)", positive, 1.0);
      s.fibre = sec.required_number("fibre", " (m, outermost fibre from the neutral axis)",
                                    non_negative, 0.0);
    }
    s.youngs_modulus = e;
    s.density = rho;
  }

  /// A clearance parameter: from the joint, else from clearance_defaults.
  YAML::Node param(Section& j, const std::string& key) const {
    if (j.has(key)) return j.get(key);
    if (defaults_.IsDefined() && defaults_.IsMap() && defaults_[key].IsDefined())
      return defaults_[key];
    return j.get(key);  // undefined: absent in both
  }

  static inline const std::vector<std::string> kClearanceKeys = {
      "clearance", "journal_radius", "bearing_radius", "normal_law", "restitution",
      "stiffness", "exponent", "material", "journal_material", "bearing_material",
      "damping_max", "damping_depth", "friction", "min_impact_velocity"};

  /// An element's `axis`, made a unit vector. Scaled by its largest entry first: [1e200, 1e200]'s
  /// norm overflows, [1e-200, 0]'s underflows; any non-zero direction is one.
  std::optional<Vec2> direction(Section& s, const std::string& units) {
    const auto ax = s.vec2("axis", units);
    if (!ax) return std::nullopt;
    const double largest = ax->cwiseAbs().maxCoeff();
    if (!(largest > 0.0)) {
      r_.error(s.at("axis"), s.element(), "axis must be a non-zero vector, got [0, 0]");
      return std::nullopt;
    }
    return Vec2((*ax / largest).normalized());
  }

  void read_joints(Model& m, const YAML::Node& n, const YAML::Node& root) {
    if (!n.IsDefined() || n.IsNull()) return;
    if (!n.IsMap()) {
      r_.error(n, "model", "'joints' must be a map name: {type: ...}, got " + Section::kind(n));
      return;
    }
    if (defaults_.IsDefined() && defaults_.IsMap())
      Section(r_, defaults_, root, "clearance_defaults", kClearanceKeys);
    for (const auto& kv : n) {
      const std::string name = kv.first.as<std::string>("");
      const std::string element = "joint '" + name + "'";
      if (!element_map(kv, element, "{type: revolute, journal: ..., bearing: ...}")) continue;
      // (A key that is missing gives a node every accessor but IsDefined throws on.)
      const YAML::Node type_node = kv.second["type"];
      const std::string type = type_node.IsDefined() && type_node.IsScalar() ? type_node.Scalar() : "";
      Joint j;
      j.name = name;
      std::vector<std::string> keys{"type"};
      if (type == "revolute") {
        j.type = JointType::revolute;
        keys.insert(keys.end(), {"journal", "bearing"});
        keys.insert(keys.end(), kClearanceKeys.begin(), kClearanceKeys.end());
      } else if (type == "translational") {
        j.type = JointType::translational;
        keys.insert(keys.end(), {"guide", "slider", "axis"});
      } else if (type == "fixed") {
        j.type = JointType::fixed;
        keys.insert(keys.end(), {"base", "attached"});
      } else if (type == "distance") {
        j.type = JointType::distance;
        keys.insert(keys.end(), {"from", "to", "length"});
      } else {
        const std::vector<std::string> types{"revolute", "translational", "fixed", "distance"};
        const std::string near = closest_match(type, types);
        r_.error(type_node.IsDefined() ? type_node : kv.second, element,
                 type.empty() ? (type_node.IsDefined() && !type_node.IsNull()
                                     ? "'type' must be one word, got " + Section::kind(type_node) + "; expected one of: "
                                     : std::string("missing 'type', expected one of: ")) + join(types)
                              : "unknown joint type '" + type + "', expected one of: " +
                                    join(types) +
                                    (near.empty() ? "" : " (did you mean '" + near + "'?)"));
        continue;
      }
      Section s(r_, kv.second, kv.first, element, keys);
      std::optional<PointRef> a, b;
      if (j.type == JointType::revolute) {
        a = point(s, "journal");
        b = point(s, "bearing");
      } else if (j.type == JointType::translational) {
        a = point(s, "guide");
        b = point(s, "slider");
        if (auto ax = direction(s, " (unit vector in the guide's frame)")) j.axis = *ax;
      } else if (j.type == JointType::distance) {
        a = point(s, "from");
        b = point(s, "to");
        j.length = s.number("length", " (m)", positive).value_or(NAN);
      } else {
        a = point(s, "base");
        b = point(s, "attached");
      }
      if (a && b) {
        j.a = *a;
        j.b = *b;
        if (a->body == b->body)
          r_.error(kv.second, element,
                   "both ends are on body '" + (a->body == kGround ? std::string("ground")
                                                                    : body_names_[a->body]) +
                       "', expected two different bodies");
        const double phi_a = a->body == kGround ? 0.0 : m.bodies[a->body].phi0;
        const double phi_b = b->body == kGround ? 0.0 : m.bodies[b->body].phi0;
        j.angle0 = phi_b - phi_a;
      }
      if (j.type == JointType::revolute) read_clearance(s, j);
      joint_nodes_.push_back(kv.second);
      nodes_[element] = kv.second;
      m.joints.push_back(j);
    }
  }

  std::optional<lash::Material> material(Section& j, const std::string& key) {
    if (!j.has(key) || j.empty_map(key)) return std::nullopt;  // `j`: the joint and its defaults
    const YAML::Node n = j.get(key);
    Section s(r_, n, j.where(), j.element() + " " + key, {"youngs_modulus", "poisson_ratio"});
    lash::Material mat;
    mat.youngs_modulus = s.required_number("youngs_modulus", " (Pa)", positive, 207e9);
    mat.poisson_ratio = s.required_number("poisson_ratio", "", poisson, 0.3);
    return mat;
  }

  void read_clearance(Section& s, Joint& j) {
    const bool is_clearance = s.has("clearance") || s.has("bearing_radius");
    if (!is_clearance) return;
    // Joint keys first, then clearance_defaults: wrap both in one lookup section.
    YAML::Node merged(YAML::NodeType::Map);
    for (const auto& k : kClearanceKeys) {
      const YAML::Node v = param(s, k);
      if (!v.IsDefined()) continue;
      // The key node itself where the value is empty, so that a problem with it is reported
      // at the key (in the joint or in clearance_defaults), the only place it has.
      bool placed = false;
      if (v.IsNull())
        for (const YAML::Node& map : {s.node(), defaults_})
          if (!placed && map.IsDefined() && map.IsMap() && map[k].IsDefined())
            for (const auto& kv : map)
              if (!placed && kv.first.as<std::string>("") == k) {
                merged.force_insert(kv.first, v);
                placed = true;
              }
      if (!placed) merged[k] = v;
    }
    // Geometry: when the joint itself gives two of the three, the defaults do not take part.
    const int own_geometry = s.has("clearance") + s.has("journal_radius") + s.has("bearing_radius");
    if (own_geometry >= 2)
      for (const char* k : {"clearance", "journal_radius", "bearing_radius"})
        if (!s.has(k)) merged.remove(k);
    // Materials: the joint's own `material` beats per-side materials from the defaults.
    if (s.has("material"))
      for (const char* k : {"journal_material", "bearing_material"})
        if (!s.has(k)) merged.remove(k);
    Section c(r_, merged, s.where(), s.element(), kClearanceKeys);
    Clearance cl;
    const auto clearance = c.number("clearance", " (m)", non_negative);
    const auto rj = c.number("journal_radius", " (m)", positive);
    const auto rb = c.number("bearing_radius", " (m)", positive);
    if (c.has("clearance") && !clearance) return;  // already reported
    if (s.has("clearance") && clearance && *clearance == 0.0) return;  // clearance: 0 → ideal
    if (clearance && rj) {
      cl.clearance = *clearance;
      cl.journal_radius = *rj;
      cl.bearing_radius = *rj + *clearance;
      if (rb && std::abs(*rb - cl.bearing_radius) > 1e-12) {
        r_.error(c.at("bearing_radius"), s.element(),
                 "bearing_radius " + fmt_num(*rb) + " disagrees with journal_radius + clearance = " +
                     fmt_num(cl.bearing_radius) + "; give two of the three");
      }
    } else if (clearance && rb) {
      cl.clearance = *clearance;
      cl.bearing_radius = *rb;
      cl.journal_radius = *rb - *clearance;
    } else if (rj && rb) {
      cl.journal_radius = *rj;
      cl.bearing_radius = *rb;
      cl.clearance = *rb - *rj;
    } else {
      r_.error(s.where(), s.element(),
               "a clearance joint needs two of clearance, journal_radius, bearing_radius "
               "(here or in clearance_defaults)");
      return;
    }
    // At the clearance's value where it has one (an override's is said to be one), else the joint.
    const YAML::Node at = c.has("clearance") ? c.at("clearance") : s.where();
    if (!(cl.clearance > 0) || !(cl.journal_radius > 0)) {
      r_.error(at, s.element(),
               "clearance must be > 0 and smaller than the bearing radius, got clearance " +
                   fmt_num(cl.clearance) + " m, journal radius " + fmt_num(cl.journal_radius) +
                   " m");
      return;
    }
    if (!(cl.journal_radius + cl.clearance > cl.journal_radius)) {
      r_.error(at, s.element(),
               "clearance " + fmt_num(cl.clearance) + " m is lost in journal radius " +
                   fmt_num(cl.journal_radius) +
                   " m (their sum rounds to the journal radius in double precision); give the "
                   "radii in metres, e.g. journal_radius: 9.5e-3");
      return;
    }
    // Normal law.
    const std::string law = c.text("normal_law").value_or("lankarani_nikravesh");
    if (auto l = normal_law_from_name(law)) {
      cl.normal_law = *l;
    } else {
      std::vector<std::string> names;
      for (const auto& i : kNormalLaws) names.emplace_back(i.name);
      const std::string near = closest_match(law, names);
      r_.error(c.at("normal_law"), s.element(),
               "unknown normal_law '" + law + "', expected one of: " + join(names) +
                   (near.empty() ? "" : " (did you mean '" + near + "'?)"));
    }
    cl.contact.exponent = c.number("exponent", "", positive).value_or(1.5);
    if (auto k = c.number("stiffness", " (N/m^exponent)", positive)) {
      cl.contact.stiffness = *k;
    } else if (!c.has("stiffness")) {
      auto common = material(c, "material");
      auto mj = material(c, "journal_material");
      auto mb = material(c, "bearing_material");
      if (!mj) mj = common;
      if (!mb) mb = common;
      bool empty = false;  // an empty material: already reported
      for (const char* k : {"material", "journal_material", "bearing_material"})
        empty = empty || (c.get(k).IsDefined() && c.get(k).IsNull());
      if ((!mj || !mb) && !empty) {
        r_.error(s.where(), s.element(),
                 "give the contact 'stiffness' or a 'material' {youngs_modulus, poisson_ratio} "
                 "(here or in clearance_defaults)");
      } else if (cl.contact.exponent != 1.5) {
        // The materials' K is in N/m^1.5: used with another n it was a wrong force, silently.
        r_.error(c.has("exponent") ? c.at("exponent") : s.where(), s.element(),
                 "exponent " + shortest_number(cl.contact.exponent) +
                     " needs the contact 'stiffness' (N/m^exponent): the stiffness derived from "
                     "the materials is Hertz's, in N/m^1.5, for exponent 1.5 only");
      } else {  // the stiffness is derived from the materials by finalize
        cl.journal_material = mj;
        cl.bearing_material = mb;
      }
    }
    const bool damped = cl.normal_law == NormalLaw::hunt_crossley ||
                        cl.normal_law == NormalLaw::lankarani_nikravesh ||
                        cl.normal_law == NormalLaw::flores;
    if (damped) {
      if (!c.has("restitution"))
        r_.error(s.where(), s.element(), "normal_law " + law + " needs 'restitution' in (0, 1]");
      cl.contact.restitution = c.number("restitution", "", unit_interval).value_or(1.0);
    }
    if (cl.normal_law == NormalLaw::impact) {
      cl.contact.damping_max = c.required_number("damping_max", " (C_max, N·s/m)", non_negative, 0);
      cl.contact.damping_depth = c.required_number("damping_depth", " (d_max, m)", positive, 1e-5);
    }
    cl.min_impact_velocity = c.number("min_impact_velocity", " (m/s)", positive).value_or(1e-3);
    read_friction(c, s.element(), cl);
    j.clearance = cl;
  }

  void read_friction(Section& c, const std::string& element, Clearance& cl) {
    if (!c.has("friction") || c.empty_map("friction")) return;
    Section f(r_, c.get("friction"), c.where(), element + " friction",
              {"law", "mu", "v0", "v1", "mu_static", "mu_dynamic", "v_static", "v_dynamic",
               "sigma0", "sigma1", "sigma2", "v_stribeck", "v_damping"});
    const std::string law = f.text("law").value_or("none");
    const auto l = friction_law_from_name(law);
    if (!l) {
      std::vector<std::string> names;
      for (const auto& i : kFrictionLaws) names.emplace_back(i.name);
      const std::string near = closest_match(law, names);
      r_.error(f.at("law"), f.element(),
               "unknown friction law '" + law + "', expected one of: " + join(names) +
                   (near.empty() ? "" : " (did you mean '" + near + "'?)"));
      return;
    }
    cl.friction_law = *l;
    auto& p = cl.friction;
    switch (*l) {
      case FrictionLaw::none: break;
      case FrictionLaw::coulomb: p.mu = f.required_number("mu", "", non_negative, 0); break;
      case FrictionLaw::ambrosio:
        p.mu = f.required_number("mu", "", non_negative, 0);
        p.v0 = f.required_number("v0", " (m/s)", non_negative, 0);
        p.v1 = f.required_number("v1", " (m/s)", positive, 1);
        if (p.v1 <= p.v0)
          r_.error(f.at("v1"), f.element(), "v1 must be > v0, got v0 = " + fmt_num(p.v0) +
                                                 ", v1 = " + fmt_num(p.v1));
        break;
      case FrictionLaw::adams_stepped:
        p.mu_static = f.required_number("mu_static", "", non_negative, 0);
        p.mu_dynamic = f.required_number("mu_dynamic", "", non_negative, 0);
        p.v_static = f.required_number("v_static", " (m/s)", positive, 1e-4);
        p.v_dynamic = f.required_number("v_dynamic", " (m/s)", positive, 1e-2);
        if (p.v_dynamic <= p.v_static)
          r_.error(f.at("v_dynamic"), f.element(),
                   "v_dynamic must be > v_static, got v_static = " + fmt_num(p.v_static) +
                       ", v_dynamic = " + fmt_num(p.v_dynamic));
        break;
      case FrictionLaw::lugre: {
        LuGreParams& g = cl.lugre;
        g.sigma0 = f.required_number("sigma0", " (bristle stiffness per newton of normal force, 1/m)", positive, 1e5);
        g.sigma1 = f.required_number("sigma1", " (bristle damping per newton, s/m)", non_negative, 0);
        g.sigma2 = f.number("sigma2", " (viscous friction per newton, s/m)", non_negative).value_or(0.0);
        g.mu_static = f.required_number("mu_static", "", positive, 0.1);
        g.mu_dynamic = f.required_number("mu_dynamic", "", positive, 0.1);
        g.v_stribeck = f.required_number("v_stribeck", " (m/s)", positive, 1e-3);
        g.v_damping = f.number("v_damping", " (m/s)", non_negative).value_or(0.0);
        if (g.mu_static < g.mu_dynamic)
          r_.error(f.at("mu_static"), f.element(), "mu_static must be >= mu_dynamic, got " +
                                                        fmt_num(g.mu_static) + " < " + fmt_num(g.mu_dynamic));
        break;
      }
    }
  }

  /// An element of a map of elements (a joint, a load) must itself be a map: `name: [1, 2]` or
  /// `name: revolute` is reported at it, with what was expected, and the element is skipped.
  template <class KeyValue>
  bool element_map(const KeyValue& kv, const std::string& element, const std::string& example) {
    if (kv.second.IsMap()) return true;
    const YAML::Node at = Section::has_position(kv.second) ? kv.second : kv.first;
    // A value with no place in the file is a --set's (`--set joints.rod_slider=5`): said so,
    // where the key's place alone read as the file's own text.
    const bool set = !Section::has_position(kv.second) && kv.second.IsDefined() && !kv.second.IsNull();
    r_.error(set ? kv.second : at, element, "expected a map of keys such as " + example + ", got " +
                                               Section::kind(kv.second));
    return false;
  }

  void read_drivers(Model& m, const YAML::Node& n) {
    if (!n.IsDefined() || n.IsNull()) return;
    if (!n.IsMap()) {
      r_.error(n, "model", "'drivers' must be a map name: {joint: ...}, got " + Section::kind(n));
      return;
    }
    for (const auto& kv : n) {
      const std::string name = kv.first.as<std::string>("");
      Section s(r_, kv.second, kv.first, "driver '" + name + "'",
                {"joint", "body", "coordinate", "speed_rpm", "speed", "motion", "initial"});
      if (s.refused()) continue;
      nodes_[s.element()] = kv.second;
      Driver d;
      d.name = name;
      if (s.has("joint") == s.has("body")) {
        r_.error(s.where(), s.element(),
                 "give either 'joint' (drive a joint coordinate) or 'body' (drive a body's "
                 "coordinate relative to the ground), got " +
                     std::string(s.has("joint") ? "both" : "neither"));
        continue;
      }
      if (s.has("body")) {
        d.target = DriverTarget::body;
        const auto b = body_ref(s, "body");
        if (!b) continue;
        if (*b == kGround) {
          r_.error(s.at("body"), s.element(), "the ground cannot be driven");
          continue;
        }
        d.body = *b;
        const std::string coord = s.text("coordinate").value_or("phi");
        if (coord == "x") d.coordinate = BodyCoordinate::x;
        else if (coord == "y") d.coordinate = BodyCoordinate::y;
        else if (coord == "phi") d.coordinate = BodyCoordinate::phi;
        else {
          r_.error(s.at("coordinate"), s.element(),
                   "unknown coordinate '" + coord + "', expected one of: x, y, phi");
          continue;
        }
        if (d.coordinate == BodyCoordinate::phi && !m.bodies[d.body].rotates()) {
          r_.error(s.at("body"), s.element(),
                   "body '" + m.bodies[d.body].name +
                       "' is a point mass (no inertia): it has no angle to drive; give "
                       "coordinate: x or y");
          continue;
        }
      } else {
        if (s.has("coordinate"))
          r_.error(s.at("coordinate"), s.element(), "'coordinate' goes with 'body', not 'joint'");
        const auto joint = s.text("joint");
        if (!joint) continue;
        std::vector<std::string> names;
        for (size_t i = 0; i < m.joints.size(); ++i) {
          names.push_back(m.joints[i].name);
          if (m.joints[i].name == *joint) d.joint = static_cast<int>(i);
        }
        if (d.joint < 0) {
          const std::string near = closest_match(*joint, names);
          r_.error(s.at("joint"), s.element(),
                   "unknown joint '" + *joint + "'" +
                       (near.empty() ? "" : ", did you mean '" + near + "'?"));
          continue;
        }
        const Joint& j = m.joints[d.joint];
        if ((j.type != JointType::revolute && j.type != JointType::translational) ||
            j.clearance) {
          r_.error(s.at("joint"), s.element(),
                   "joint '" + *joint + "' is " +
                       (j.clearance ? std::string("a clearance joint") : "not revolute or translational") +
                       ", expected an ideal revolute or translational joint; to drive a body "
                       "whose joint has clearance, give 'body' and 'coordinate' instead");
          continue;
        }
      }
      const int given = s.has("speed_rpm") + s.has("speed") + s.has("motion");
      if (given != 1) {
        r_.error(s.where(), s.element(),
                 "give exactly one of speed_rpm, speed (rad/s or m/s, or an expression of time) "
                 "or motion (expression of time), got " + std::to_string(given));
        continue;
      }
      const bool rotary = driver_is_rotary(m, d);
      // A position profile needs two exact time derivatives, a speed profile one (expression.hpp).
      auto time_expression = [&](const std::string& key, const std::string& text, int derivatives) {
        std::string err = check_expression(text, {});
        if (!err.empty() && check_expression(text, body_names_).empty())
          err = "a prescribed motion must be a function of time only";
        if (err.empty()) err = check_expression(text, {}, derivatives);
        if (!err.empty()) r_.error(s.at(key), s.element(), "bad expression in '" + key + "': " + err);
      };
      if (auto rpm = s.number("speed_rpm", " (rev/min)")) {
        if (!rotary) r_.error(s.at("speed_rpm"), s.element(), "speed_rpm needs an angle to drive");
        d.speed = *rpm * 2.0 * M_PI / 60.0;
      }
      if (s.has("speed")) {
        double v;
        const YAML::Node sn = s.get("speed");
        if (sn.IsScalar() && YAML::convert<double>::decode(sn, v) && std::isfinite(v)) {
          d.speed = v;
        } else if (sn.IsScalar()) {  // a speed profile: an expression of time, integrated
          d.profile = DriverProfile::speed;
          d.expression = sn.Scalar();
          time_expression("speed", d.expression, 1);
        } else {
          r_.error(sn, s.element(), "speed must be a number (rad/s or m/s) or an expression of time");
        }
      }
      if (auto ex = s.text("motion")) {
        d.profile = DriverProfile::position;
        d.expression = *ex;
        time_expression("motion", *ex, 2);
      }
      // Initial coordinate: given, else derived from the initial poses by finalize.
      if (auto init = s.number("initial", " (rad or m)")) d.initial = *init;
      m.drivers.push_back(d);
    }
  }

  void read_loads(Model& m, const YAML::Node& n) {
    if (!n.IsDefined() || n.IsNull()) return;
    if (!n.IsMap()) {
      r_.error(n, "model", "'loads' must be a map name: {type: ...}, got " + Section::kind(n));
      return;
    }
    for (const auto& kv : n) {
      const std::string name = kv.first.as<std::string>("");
      const std::string element = "load '" + name + "'";
      if (!element_map(kv, element, "{type: force, point: ..., fx: ..., fy: ...}")) continue;
      const YAML::Node tn = kv.second["type"];
      const std::string type = tn.IsDefined() && tn.IsScalar() ? tn.Scalar() : "";
      const std::vector<std::string> types{"force", "torque", "spring_damper",
                                           "torsional_spring_damper", "bushing"};
      nodes_[element] = kv.second;
      Load l;
      l.name = name;
      auto expr = [&](Section& s, const std::string& key, std::string& out) {
        if (!s.has(key)) return;
        if (!s.get(key).IsScalar()) {
          r_.error(s.at(key), element, "'" + key + "' must be a number or an expression (text), got " +
                                            Section::kind(s.get(key)));
          return;
        }
        out = s.get(key).Scalar();
        const std::string err = check_expression(out, body_names_);
        if (!err.empty()) r_.error(s.at(key), element, "bad expression in '" + key + "': " + err);
      };
      if (type == "force") {
        Section s(r_, kv.second, kv.first, element, {"type", "point", "fx", "fy"});
        l.type = LoadType::force;
        if (auto p = point(s, "point")) l.a = *p;
        expr(s, "fx", l.fx);
        expr(s, "fy", l.fy);
      } else if (type == "torque") {
        Section s(r_, kv.second, kv.first, element, {"type", "body", "torque"});
        l.type = LoadType::torque;
        // "body", or "link.marker": the point of a flexible link the torque acts on.
        if (!s.has("body")) r_.error(s.where(), element, "missing required key 'body'");
        else if (auto t = s.text("body"))
          if (auto a = resolve_point(s.get("body"), element, *t)) l.a = *a, l.body_a = a->body;
        expr(s, "torque", l.torque);
      } else if (type == "spring_damper") {
        Section s(r_, kv.second, kv.first, element,
                  {"type", "from", "to", "stiffness", "damping", "free_length"});
        l.type = LoadType::spring_damper;
        auto a = point(s, "from"), b = point(s, "to");
        l.stiffness = s.number("stiffness", " (N/m)", non_negative).value_or(0.0);
        l.damping = s.number("damping", " (N·s/m)", non_negative).value_or(0.0);
        if (a && b) l.a = *a, l.b = *b;  // free_length: the initial length unless given
        if (auto fl = s.number("free_length", " (m)", non_negative)) l.free_length = *fl;
      } else if (type == "torsional_spring_damper") {
        Section s(r_, kv.second, kv.first, element,
                  {"type", "bodies", "stiffness", "damping", "free_angle"});
        l.type = LoadType::torsional_spring_damper;
        const YAML::Node bn = s.get("bodies");
        if (!bn.IsDefined() || !bn.IsSequence() || bn.size() != 2) {
          r_.error(bn.IsDefined() ? bn : s.where(), element,
                   "'bodies' must be a pair [body_a, body_b]");
        } else {
          // Each "body", or "link.marker": the point of a flexible link whose angle counts.
          std::optional<PointRef> a, b;
          for (auto [node, out] : {std::pair{bn[0], &a}, std::pair{bn[1], &b}}) {
            if (!node.IsScalar())
              r_.error(node, element, "expected a body name, got " + Section::kind(node));
            else
              *out = resolve_point(node, element, node.Scalar());
          }
          if (a && b) l.a = *a, l.b = *b, l.body_a = a->body, l.body_b = b->body;  // free_angle: initial unless given
        }
        l.stiffness = s.number("stiffness", " (N·m/rad)", non_negative).value_or(0.0);
        l.damping = s.number("damping", " (N·m·s/rad)", non_negative).value_or(0.0);
        if (auto fa = s.number("free_angle", " (rad)")) l.angle0 = *fa;
      } else if (type == "bushing") {
        Section s(r_, kv.second, kv.first, element,
                  {"type", "from", "to", "frame", "stiffness", "damping", "torsional_stiffness",
                   "torsional_damping", "free_angle"});
        l.type = LoadType::bushing;
        auto a = point(s, "from"), b = point(s, "to");
        if (a && b) l.a = *a, l.b = *b;
        // Axes of the frame body (default: the `from` body); stiffness and damping per axis.
        l.frame_body = a ? a->body : kGround;
        if (s.has("frame"))
          if (auto fb = body_ref(s, "frame")) l.frame_body = *fb;
        auto pair = [&](const std::string& key, const char* unit) -> Vec2 {
          if (!s.has(key)) return Vec2::Zero();
          const YAML::Node n = s.get(key);
          // One problem, saying what was given: a number (both axes) or a pair.
          const std::string expected = "'" + key + "' must be a number >= 0 or a pair [x, y] of them" + unit;
          if (n.IsScalar()) {
            if (auto v = s.number(key, unit, [](double x) { return x >= 0 ? "" : ">= 0"; }))
              return Vec2(*v, *v);
            return Vec2::Zero();
          }
          if (!n.IsSequence()) {
            r_.error(s.at(key), element, expected + ", got " + Section::kind(n));
            return Vec2::Zero();
          }
          if (auto p = s.vec2(key, unit)) {
            if ((p->array() >= 0).all()) return *p;
            r_.error(n, element, expected + ", got [" + fmt_num(p->x()) + ", " + fmt_num(p->y()) + "]");
          }
          return Vec2::Zero();
        };
        l.stiffness_xy = pair("stiffness", " (N/m)");
        l.damping_xy = pair("damping", " (N·s/m)");
        l.stiffness = s.number("torsional_stiffness", " (N·m/rad)", non_negative).value_or(0.0);
        l.damping = s.number("torsional_damping", " (N·m·s/rad)", non_negative).value_or(0.0);
        if (auto fa = s.number("free_angle", " (rad)")) l.angle0 = *fa;
      } else {
        const std::string near = closest_match(type, types);
        r_.error(tn.IsDefined() ? tn : kv.second, element,
                 (type.empty() ? std::string(tn.IsDefined() && !tn.IsNull() ? "'type' must be one word, got " + Section::kind(tn)
                                                                           : "missing 'type'")
                               : "unknown load type '" + type + "'") +
                     ", expected one of: " + join(types) +
                     (near.empty() || type.empty() ? "" : " (did you mean '" + near + "'?)"));
        continue;
      }
      m.loads.push_back(l);
    }
  }

  void read_sensors(Model& m, const YAML::Node& n) {
    if (!n.IsDefined() || n.IsNull()) return;
    if (!n.IsMap()) {
      r_.error(n, "model", "'sensors' must be a map name: {type: ..., at: body.marker}, got " +
                               Section::kind(n));
      return;
    }
    const std::vector<std::string> types{"accelerometer", "velocity", "displacement"};
    for (const auto& kv : n) {
      const std::string name = kv.first.as<std::string>("");
      const std::string element = "sensor '" + name + "'";
      Section s(r_, kv.second, kv.first, element,
                {"type", "at", "axis", "frame", "gravity", "mass"});
      if (s.refused()) continue;
      nodes_[element] = kv.second;
      Sensor sn;
      sn.name = name;
      const std::string type = s.text("type").value_or("");
      const auto it = std::find(types.begin(), types.end(), type);
      if (it == types.end()) {
        const std::string near = closest_match(type, types);
        r_.error(s.has("type") ? s.at("type") : s.where(), element,
                 (type.empty() ? std::string("missing 'type'") : "unknown sensor type '" + type + "'") +
                     ", expected one of: " + join(types) +
                     (near.empty() || type.empty() ? "" : " (did you mean '" + near + "'?)"));
        continue;
      }
      sn.type = static_cast<SensorType>(it - types.begin());
      if (auto p = point(s, "at")) {
        sn.at = *p;
        if (p->body == kGround) r_.error(s.at("at"), element, "a sensor must be on a body, not the ground");
      }
      if (auto ax = direction(s, " (direction)")) sn.axis = *ax;
      const std::string frame = s.text("frame").value_or("body");
      if (frame == "ground") sn.body_axis = false;
      else if (frame != "body")
        r_.error(s.at("frame"), element, "frame must be 'body' (axis turns with the body) or "
                                          "'ground', got '" + frame + "'");
      if (s.has("gravity")) {
        bool g;
        if (YAML::convert<bool>::decode(s.get("gravity"), g)) sn.gravity = g;
        else r_.error(s.at("gravity"), element, "gravity must be true (specific force, as a real "
                                                 "accelerometer reads) or false (kinematic acceleration)");
        if (sn.type != SensorType::accelerometer)
          r_.error(s.at("gravity"), element, "'gravity' applies to accelerometers only");
      }
      sn.mass = s.number("mass", " (kg, added at the sensor's point)", non_negative).value_or(0.0);
      m.sensors.push_back(sn);
    }
  }

  void read_solver(Model& m, const YAML::Node& n, const YAML::Node& root) {
    Section s(r_, n, root, "solver",
              {"integrator", "rtol", "atol", "end_time", "output_interval", "max_step",
               "max_steps", "max_outputs", "initial_state", "baumgarte", "output_channels",
               "output_format"});
    SolverSettings& st = m.solver;
    if (auto integ = s.text("integrator")) {
      if (*integ == "dopri5") st.integrator = IntegratorKind::dopri5;
      else if (*integ == "bdf" || *integ == "cvode") st.integrator = IntegratorKind::bdf;
      else
        r_.error(s.at("integrator"), "solver",
                 "unknown integrator '" + *integ + "', expected one of: dopri5, bdf");
    }
    st.rtol = s.number("rtol", "", relative_tolerance).value_or(st.rtol);
    st.atol = s.number("atol", "", absolute_tolerance).value_or(st.atol);
    const size_t problems_before = r_.list.size();
    st.end_time = s.required_number("end_time", " (s)", positive, 1.0);
    // A refused end_time (its stand-in is 1 s) is not compared with output_interval: "-5" was
    // followed by "output_interval must be <= end_time, got 2 > 1".
    const bool end_time_given = r_.list.size() == problems_before;
    st.output_interval = s.number("output_interval", " (s)", positive).value_or(st.end_time / 1000);
    st.max_step = s.number("max_step", " (s)", non_negative).value_or(0.0);
    // A step limit below what an integrator can take at end_time (16 ε·max(1, t)): the run
    // failed with "step size underflow (h = 1e-300)", max_step unnamed. (A limit this run can
    // take but so small that the steps would outnumber max_steps stops it as stalled.)
    if (const double floor = 16.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, st.end_time);
        st.max_step > 0.0 && st.max_step < floor)
      r_.error(s.at("max_step"), "solver",
               "max_step " + fmt::format("{:g}", st.max_step) + " s is below the smallest step an integrator "
               "can take at end_time (" + fmt::format("{:.3g}", floor) + " s); 0 leaves the step unlimited");
    if (auto ms = s.number("max_steps", "", [](double v) {
          return v >= 1 && v <= 1e15 && v == std::floor(v) ? "" : "a whole number in [1, 1e15]";
        }))
      st.max_steps = static_cast<long>(*ms);
    if (auto rule = s.text("initial_state")) {
      if (*rule == "ideal") st.initial_state = InitialStateRule::ideal;
      else if (*rule == "given") st.initial_state = InitialStateRule::given;
      else
        r_.error(s.at("initial_state"), "solver",
                 "unknown initial_state '" + *rule + "', expected one of: ideal, given");
    }
    if (s.has("output_channels")) {
      // A list of glob patterns, or one string of comma-separated patterns (as --channels).
      const YAML::Node oc = s.get("output_channels");
      std::vector<std::string> patterns;
      if (oc.IsScalar()) {
        patterns = split_channel_patterns(oc.Scalar());
        for (const auto& p : patterns) output_patterns_.emplace_back(oc, p);
      } else if (oc.IsSequence()) {
        for (const auto& e : oc) {
          if (!e.IsScalar()) {
            r_.error(e, "solver", "output_channels: each entry must be a pattern such as 'slider.*'");
            continue;
          }
          for (auto& p : split_channel_patterns(e.Scalar())) {
            output_patterns_.emplace_back(e, p);
            patterns.push_back(p);
          }
        }
      } else {
        r_.error(oc, "solver", "output_channels must be a list of patterns such as ['slider.*']");
      }
      if (patterns.empty() && (oc.IsScalar() || oc.IsSequence()))
        r_.error(oc, "solver", "output_channels: no pattern given (leave it out to write all channels)");
      output_.channels = patterns;
    }
    if (auto f = s.text("output_format")) {
      if (*f == "csv") output_.format = OutputFormat::csv;
      else if (*f == "hdf5") output_.format = OutputFormat::hdf5;
      else
        r_.error(s.at("output_format"), "solver",
                 "unknown output_format '" + *f + "', expected one of: csv, hdf5");
    }
    if (s.has("baumgarte") && !s.empty_map("baumgarte")) {
      Section b(r_, s.get("baumgarte"), s.where(), "solver baumgarte", {"alpha", "beta"});
      st.baumgarte_alpha = b.number("alpha", " (1/s)", non_negative).value_or(st.baumgarte_alpha);
      st.baumgarte_beta = b.number("beta", " (1/s)", non_negative).value_or(st.baumgarte_beta);
    }
    if (auto mo = s.number("max_outputs", "", [](double v) {
          return v >= 1 && v <= 1e12 && v == std::floor(v) ? "" : "a whole number in [1, 1e12]";
        }))
      st.max_outputs = static_cast<long>(*mo);
    if (!end_time_given) {
      // (said at end_time)
    } else if (st.output_interval > st.end_time) {
      r_.error(s.at("output_interval"), "solver",
               "output_interval must be <= end_time, got " + fmt_num(st.output_interval) +
                   " > " + fmt_num(st.end_time));
    } else if (const double n = st.end_time / st.output_interval;
               !(n <= static_cast<double>(st.max_outputs))) {
      r_.error(s.has("output_interval") ? s.get("output_interval") : s.get("end_time"), "solver",
               "end_time / output_interval = " + fmt_num(n) + " outputs, more than max_outputs = " +
                   std::to_string(st.max_outputs) +
                   "; choose a longer output_interval, or raise solver.max_outputs if the disk "
                   "can take it");
    }
  }

  Reporter r_;
  OutputSettings output_;
  /// Each pattern of solver.output_channels with the node of its entry (checked after finalize).
  std::vector<std::pair<YAML::Node, std::string>> output_patterns_;
  YAML::Node defaults_;
  std::vector<std::string> body_names_;
  std::vector<std::vector<Marker>> markers_;
  std::vector<Marker> ground_markers_;
  std::vector<YAML::Node> joint_nodes_;
  std::map<std::string, YAML::Node> nodes_;  ///< element ("joint 'x'") → its node, for finalize
};

/// Copies a parsed node without its source marks, so diagnostics say "value set with --set".
YAML::Node unmarked(const YAML::Node& n) {
  if (n.IsSequence()) {
    YAML::Node out(YAML::NodeType::Sequence);
    for (const auto& e : n) out.push_back(unmarked(e));
    return out;
  }
  if (n.IsMap()) {
    YAML::Node out(YAML::NodeType::Map);
    for (const auto& kv : n) out[kv.first.as<std::string>("")] = unmarked(kv.second);
    return out;
  }
  return YAML::Node(n.IsScalar() ? n.Scalar() : std::string());
}

/// An override's value: a flow list or map ("[0.1, 0]", "{law: coulomb, mu: 0.1}") becomes that
/// structure; anything else is the scalar text as written.
YAML::Node override_value(const std::string& value) {
  if (!value.empty() && (value.front() == '[' || value.front() == '{')) {
    try {
      const YAML::Node parsed = YAML::Load(value);
      if (parsed.IsSequence() || parsed.IsMap()) return unmarked(parsed);
    } catch (const YAML::Exception&) {
      // not YAML: keep the text, the loader reports it with its expectation
    }
  }
  return YAML::Node(value);
}

/// Applies "a.b.c=value": the parents must exist; the last key may be new. A section made of
/// settings with defaults (`solver`, `clearance_defaults`) is made where the file has none, so
/// `--set solver.end_time=1` works on a model that states no solver settings.
/// For each node on the path `keys` from `root` (each map on it and the value at its end, as far
/// as they exist): whether it is also reached from another place in the tree. An anchor's node
/// and its aliases are one node (yaml-cpp), so writing through one path writes through all.
/// Collections are walked once each (an alias of one is not walked again, so self-references
/// and exponential aliases cost nothing).
std::vector<bool> shared_on_path(const YAML::Node& root, const std::vector<std::string>& keys) {
  std::vector<YAML::Node> on_path;
  YAML::Node n = root;
  for (const auto& k : keys) {
    if (!n.IsMap() || !n[k].IsDefined()) break;
    n.reset(n[k]);
    on_path.push_back(n);
  }
  std::vector<int> seen(on_path.size(), 0);
  std::vector<YAML::Node> todo{root}, walked;  // walked: collections without a place in the text
  std::set<std::size_t> walked_at;              // those with one, by their offset in the text
  while (!todo.empty()) {
    const YAML::Node c = todo.back();
    todo.pop_back();
    if (!c.IsMap() && !c.IsSequence()) continue;
    if (c.Mark().pos >= 0) {
      if (!walked_at.insert(static_cast<std::size_t>(c.Mark().pos)).second) continue;
    } else if (std::any_of(walked.begin(), walked.end(), [&](const YAML::Node& w) { return w.is(c); })) {
      continue;
    } else {
      walked.push_back(c);
    }
    for (auto it = c.begin(); it != c.end(); ++it) {
      const YAML::Node child = c.IsMap() ? YAML::Node(it->second) : YAML::Node(*it);
      for (size_t i = 0; i < on_path.size(); ++i)
        if (child.is(on_path[i])) ++seen[i];
      todo.push_back(child);
    }
  }
  std::vector<bool> shared(keys.size(), false);
  for (size_t i = 0; i < on_path.size(); ++i) shared[i] = seen[i] > 1;
  return shared;
}

void apply_override(YAML::Node root, const std::string& spec, Reporter& r) {
  const auto eq = spec.find('=');
  if (eq == std::string::npos || eq == 0) {
    r.list.push_back({"--set", 0, 0, "", "expected KEY.PATH=VALUE, got '" + spec + "'"});
    return;
  }
  const std::string path = spec.substr(0, eq), value = spec.substr(eq + 1);
  std::vector<std::string> keys;
  std::stringstream ss(path);
  for (std::string k; std::getline(ss, k, '.');) keys.push_back(k);
  if (path.back() == '.' || std::find(keys.begin(), keys.end(), "") != keys.end()) {
    r.list.push_back({"--set", 0, 0, "", "empty key in '" + path + "', expected KEY.PATH=VALUE"});
    return;
  }
  YAML::Node node = root;
  std::string walked;
  if (keys.size() > 1 && (keys[0] == "solver" || keys[0] == "clearance_defaults") && root.IsMap() &&
      !root[keys[0]].IsDefined())
    root[keys[0]] = YAML::Node(YAML::NodeType::Map);
  for (size_t i = 0; i + 1 < keys.size(); ++i) {
    walked += (i ? "." : "") + keys[i];
    if (!node.IsMap() || !node[keys[i]].IsDefined()) {
      std::vector<std::string> names;
      if (node.IsMap())
        for (const auto& kv : node) names.push_back(kv.first.as<std::string>(""));
      const std::string near = closest_match(keys[i], names);
      r.list.push_back({"--set " + path, 0, 0, "",
                        "no '" + walked + "' in the model" +
                            (near.empty() ? "" : ", did you mean '" + near + "'?")});
      return;
    }
    node.reset(node[keys[i]]);
  }
  if (!node.IsMap()) {
    r.list.push_back({"--set " + path, 0, 0, "", "'" + walked + "' is not a map"});
    return;
  }
  const std::vector<bool> shared = shared_on_path(root, keys);
  if (std::none_of(shared.begin(), shared.end(), [](bool b) { return b; })) {
    node[keys.back()] = override_value(value);
    return;
  }
  // A map on the path, or the value, is an alias's too (`bearing_material: *steel`): written
  // through, the value would change wherever the anchor is used. Such a map is copied (its
  // entries the original's nodes, so their places in the file stay known), and the copy takes
  // its slot in its parent: the entries from that slot on are taken out and put back in order
  // (yaml-cpp's maps keep their order; a slot's node may be the alias's too, so it cannot be
  // written in place). The maps themselves keep their places in the file; a copy has none.
  r.through_alias = true;
  const auto replace_slot = [](YAML::Node parent, const std::string& key, const YAML::Node& with) {
    std::vector<std::pair<YAML::Node, YAML::Node>> tail;
    for (auto it = parent.begin(); it != parent.end(); ++it)
      if (!tail.empty() || (it->first.IsScalar() && it->first.Scalar() == key))
        tail.emplace_back(it->first, it->second);
    for (const auto& kv : tail) parent.remove(kv.first);
    if (tail.empty()) parent[key] = with;
    for (size_t j = 0; j < tail.size(); ++j) parent[tail[j].first] = j == 0 ? with : tail[j].second;
  };
  YAML::Node cur = root;
  for (size_t i = 0; i < keys.size(); ++i) {
    if (i + 1 == keys.size()) {
      if (shared[i]) replace_slot(cur, keys[i], override_value(value));
      else cur[keys[i]] = override_value(value);
      break;
    }
    YAML::Node child = cur[keys[i]];
    if (shared[i]) {
      YAML::Node copy(YAML::NodeType::Map);
      copy.SetStyle(child.Style());
      for (const auto& kv : child) copy[kv.first] = kv.second;
      replace_slot(cur, keys[i], copy);
      child.reset(copy);
    }
    cur.reset(child);
  }
}

/// Every key that appears twice in one map, with both places (yaml-cpp keeps both, and a lookup
/// would silently take the first). Read from the parser's events, where an alias is one event:
/// no node is visited twice, so self-referencing and exponential aliases cost nothing.
/// Counts the documents of a YAML stream (and where the second starts); ignores their content.
class DocumentCounter : public YAML::EventHandler {
 public:
  int documents = 0;
  YAML::Mark second_document;
  void OnDocumentStart(const YAML::Mark& m) override {
    if (++documents == 2) second_document = m;
  }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}
};

/// Whether `text` has a line that starts with a document marker ("---" or "...", then a blank
/// or the line's end). Without one a YAML stream holds a single document.
bool has_document_marker(std::string_view text) {
  for (std::size_t at = 0; at < text.size();) {
    const std::string_view line = text.substr(at, 4);
    if ((line.substr(0, 3) == "---" || line.substr(0, 3) == "...") &&
        (line.size() == 3 || line[3] == ' ' || line[3] == '\t' || line[3] == '\r' || line[3] == '\n'))
      return true;
    const std::size_t eol = text.find('\n', at);
    if (eol == std::string_view::npos) break;
    at = eol + 1;
  }
  return false;
}

/// Checks the structure yaml-cpp's Load does not: no key twice in a map of `root` (Load keeps
/// both entries, and node[key] would see only the first), and no second document in `text`
/// (Load reads the first only). Duplicates are found by walking the loaded tree, a collection
/// reached again through an alias once; the stream is parsed a second time only when it has a
/// document marker, and then at most two documents are read (on some malformed inputs
/// yaml-cpp's parser returns empty documents forever, which is why YAML::LoadAll is not used).
void check_structure(const std::string& text, const YAML::Node& root, Reporter& r) {
  std::vector<Diagnostic> found;
  std::vector<YAML::Node> todo{root};
  std::set<std::size_t> walked;  // collections, by their offset in the text
  while (!todo.empty()) {
    const YAML::Node n = todo.back();
    todo.pop_back();
    if (!n.IsMap() && !n.IsSequence()) continue;
    if (!walked.insert(static_cast<std::size_t>(n.Mark().pos)).second) continue;
    std::map<std::string, YAML::Mark> keys;
    for (auto it = n.begin(); it != n.end(); ++it) {
      if (n.IsSequence()) {
        todo.push_back(*it);
        continue;
      }
      const YAML::Node key = it->first;
      if (!key.IsScalar()) {  // (yaml-cpp reads a null key, `~:`, as the name "null")
        const YAML::Mark m = key.Mark();
        found.push_back({r.file, m.line + 1, m.column + 1, "",
                         std::string("a key must be a name, got ") +
                             (key.IsNull() ? "nothing (~, null or an empty key)" : key.IsSequence() ? "a list" : "a map")});
      }
      if (key.IsScalar()) {
        const YAML::Mark m = key.Mark();
        const auto [first, fresh] = keys.emplace(key.Scalar(), m);
        if (!fresh)
          found.push_back({r.file, m.line + 1, m.column + 1, "",
                           "duplicate key '" + key.Scalar() + "' (first at line " +
                               std::to_string(first->second.line + 1) + ", column " +
                               std::to_string(first->second.column + 1) +
                               "); each key and each element name may appear once in a map"});
      }
      todo.push_back(key);
      todo.push_back(it->second);
    }
  }
  std::sort(found.begin(), found.end(), [](const Diagnostic& a, const Diagnostic& b) {
    return std::tie(a.line, a.column) < std::tie(b.line, b.column);
  });
  r.list.insert(r.list.end(), found.begin(), found.end());
  if (!has_document_marker(text)) return;
  std::istringstream in(text);
  YAML::Parser parser(in);
  DocumentCounter counter;
  try {
    for (int k = 0; k < 2 && parser.HandleNextDocument(counter); ++k) {
    }
  } catch (const YAML::Exception&) {
    // a syntax error after the first document: reported below as a second document
    if (counter.documents < 2) counter.documents = 2, counter.second_document = YAML::Mark::null_mark();
  }
  if (counter.documents > 1) {
    const YAML::Mark& m = counter.second_document;
    r.list.push_back({r.file, m.line >= 0 ? m.line + 1 : 0, m.line >= 0 ? m.column + 1 : 0, "",
                      "a second YAML document ('---'): a model file holds one model; split it "
                      "into two files"});
  }
}

/// The first byte sequence that is not UTF-8 (overlong forms, surrogates and code points above
/// U+10FFFF included), with its line and column (1-based, in bytes).
struct BadByte {
  int line = 1, column = 1;
  std::size_t offset = 0;
  std::string byte;  ///< "0xC3"
};
std::optional<BadByte> first_invalid_utf8(std::string_view s) {
  int line = 1, column = 1;
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    std::size_t n = 0;
    std::uint32_t cp = 0;
    if (c == 0) n = 0;  // NUL: not text
    else if (c < 0x80) n = 1, cp = c;
    else if ((c & 0xE0) == 0xC0) n = 2, cp = c & 0x1F;
    else if ((c & 0xF0) == 0xE0) n = 3, cp = c & 0x0F;
    else if ((c & 0xF8) == 0xF0) n = 4, cp = c & 0x07;
    bool ok = n > 0 && i + n <= s.size();
    for (std::size_t k = 1; ok && k < n; ++k) {
      const auto cc = static_cast<unsigned char>(s[i + k]);
      ok = (cc & 0xC0) == 0x80;
      cp = (cp << 6) | (cc & 0x3F);
    }
    if (ok) {
      static const std::uint32_t min_cp[5] = {0, 0, 0x80, 0x800, 0x10000};
      ok = cp >= min_cp[n] && cp <= 0x10FFFF && !(cp >= 0xD800 && cp <= 0xDFFF);
    }
    if (!ok) return BadByte{line, column, i, fmt::format("0x{:02X}", c)};
    if (c == '\n') ++line, column = 1;
    else ++column;
    i += n;
  }
  return std::nullopt;
}

/// A copy of `n` into `out` with every alias written out in full (new nodes, nothing shared):
/// false when it would take more than `budget` nodes or nest deeper than 64.
bool expanded(const YAML::Node& n, YAML::Node& out, long& budget, int depth) {
  if (--budget < 0 || depth > 64) return false;
  if (n.IsScalar()) {
    out = YAML::Node(n.Scalar());
    out.SetTag(n.Tag());
    return true;
  }
  if (n.IsSequence() || n.IsMap()) {
    out = YAML::Node(n.IsMap() ? YAML::NodeType::Map : YAML::NodeType::Sequence);
    out.SetStyle(n.Style());
    for (auto it = n.begin(); it != n.end(); ++it) {
      YAML::Node k, v;
      if (n.IsMap() ? !(expanded(it->first, k, budget, depth + 1) && expanded(it->second, v, budget, depth + 1))
                    : !expanded(*it, v, budget, depth + 1))
        return false;
      if (n.IsMap()) out.force_insert(k, v);
      else out.push_back(v);
    }
    return true;
  }
  out = YAML::Node(YAML::NodeType::Null);
  return true;
}

LoadedModel load_root(YAML::Node root, const std::string& filename,
                      const std::vector<std::string>& overrides) {
  Reporter over;
  over.file = filename;
  for (const auto& o : overrides) apply_override(root, o, over);
  if (!over.list.empty()) throw ModelError(over.list);
  Loader loader(filename);
  LoadedModel out;
  out.model = loader.load(root);
  out.output = loader.output();
  out.positions = loader.positions();
  out.model.source = filename;
  if (!overrides.empty()) {
    // Through an alias, the copied map shares its entries' nodes with the anchor's: written as
    // they are, they come out as anchors and aliases of single keys and numbers ("*1 : *2").
    // Written out in full instead, if that stays small (not an alias bomb).
    YAML::Node plain;
    long budget = 100000;
    out.resolved_yaml = YAML::Dump(over.through_alias && expanded(root, plain, budget, 0) ? plain : root);
  }
  return out;
}

}  // namespace

std::string LoadedModel::located(const std::string& message, const std::string& label) const {
  const std::string& file = model.source;
  const size_t end = message.find("': ");
  if (end != std::string::npos) {
    const auto it = positions.find(message.substr(0, end + 1));
    if (it != positions.end())
      return file + ":" + std::to_string(it->second.first) + ":" + std::to_string(it->second.second) +
             ": " + label + message;
  }
  return file + ": " + label + message;
}

LoadedModel load_model_text(const std::string& text, const std::string& filename,
                            const std::vector<std::string>& overrides) {
  if (auto bad = first_invalid_utf8(text))
    throw ModelError({{filename, bad->line, bad->column, "",
                       bad->byte == "0x00"
                           ? std::string("a NUL byte: not a text file")
                           : "not UTF-8 text (byte " + bad->byte +
                                 "); save the model file with UTF-8 encoding"}});
  for (const auto& o : overrides)
    if (auto bad = first_invalid_utf8(o))
      throw ModelError({{"--set", 0, 0, "",
                         (bad->byte == "0x00" ? std::string("a NUL byte")
                                              : "not UTF-8 text (byte " + bad->byte + ")") +
                             " in '" + std::string(o.begin(), o.begin() + bad->offset) + "...'"}});
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ModelError({yaml_syntax_problem(filename, text, e.mark.line + 1, e.mark.column + 1, e.msg)});
  }
  if (!root.IsMap())
    throw ModelError({{filename, 1, 1, "",
                       "expected a model (a map with bodies, joints, solver, ...), got " +
                           Section::kind(root)}});
  {
    Reporter structure;
    structure.file = filename;
    check_structure(text, root, structure);
    if (!structure.list.empty()) throw ModelError(structure.list);
  }
  LoadedModel out = load_root(root, filename, overrides);
  // Without overrides the model as run is the file's text (comments kept); with them, the tree
  // after them, emitted again. (Emitting costs as much as parsing: ~2 M instructions.)
  if (overrides.empty())
    out.resolved_yaml = !text.empty() && text.back() == '\n' ? text.substr(0, text.size() - 1) : text;
  return out;
}

std::vector<Diagnostic> yaml_structure_problems(const std::string& text, const std::string& filename) {
  Reporter r;
  r.file = filename;
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception&) {
    return {};  // not YAML at all: the caller's own YAML::Load says where
  }
  check_structure(text, root, r);
  return r.list;
}

LoadedModel load_model_file(const std::string& path, const std::vector<std::string>& overrides) {
  std::string text;
  try {
    text = read_input_file(path, kMaxModelFileBytes);
  } catch (const std::exception& e) {
    std::string what = e.what();
    if (what.rfind(path + ": ", 0) == 0) what.erase(0, path.size() + 2);
    throw ModelError({{path, 0, 0, "", "cannot read the model file: " + what}});
  }
  return load_model_text(text, path, overrides);
}

}  // namespace lash
