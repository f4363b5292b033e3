// Study files, their runs and one run's record (sweep.hpp; format: docs/studies.md).
#include "study/sweep.hpp"

#include <fmt/core.h>

#include <cctype>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numeric>
#include <optional>
#include <set>

#include "core/dynamics.hpp"
#include "core/elements/registry.hpp"
#include "core/extrema.hpp"
#include "io/diagnostics.hpp"
#include "io/files.hpp"
#include "io/model_loader.hpp"
#include "io/number_format.hpp"
#include "study/run_analysis.hpp"

namespace lash {
namespace {

using Diagnostics = std::vector<Diagnostic>;

/// Override values and messages: the shortest exact text (io/number_format.hpp).
std::string number_text(double v) { return shortest_number(v); }

struct Reader {
  std::string file;
  Diagnostics list;
  void error(const YAML::Node& n, const std::string& message) {
    const YAML::Mark m = n.Mark();
    list.push_back({file, m.line + 1, m.column + 1, "", message});
  }
  /// Keys of `map` outside `allowed` are reported with the closest allowed one.
  void keys(const YAML::Node& map, const std::vector<std::string>& allowed, const std::string& where) {
    for (const auto& kv : map) {
      const std::string k = kv.first.as<std::string>("");
      if (std::find(allowed.begin(), allowed.end(), k) != allowed.end()) continue;
      const std::string near = closest_match(k, allowed);
      error(kv.first, where + ": unknown key '" + k + "'" +
                          (near.empty() ? "" : ", did you mean '" + near + "'?"));
    }
  }
  bool number(const YAML::Node& n, const std::string& what, double& out) {
    if (!n.IsScalar()) {
      error(n, what + ": expected a number");
      return false;
    }
    char* end = nullptr;
    const std::string s = n.Scalar();
    out = std::strtod(s.c_str(), &end);
    if (s.empty() || *end != '\0' || !std::isfinite(out)) {
      error(n, what + ": expected a finite number, got '" + s + "'");
      return false;
    }
    return true;
  }
  bool integer(const YAML::Node& n, const std::string& what, long lo, long hi, long& out) {
    double v = 0;
    if (!number(n, what, v)) return false;
    if (v != std::floor(v) || v < lo || v > hi) {
      error(n, what + ": expected a whole number from " + std::to_string(lo) + " to " +
                   std::to_string(hi) + ", got '" + n.Scalar() + "'");
      return false;
    }
    out = static_cast<long>(v);
    return true;
  }
  std::vector<std::string> names(const YAML::Node& n, const std::string& what) {
    std::vector<std::string> out;
    if (n.IsScalar()) return {n.Scalar()};
    if (!n.IsSequence()) {
      error(n, what + ": expected a channel name or a list of them");
      return out;
    }
    for (const auto& e : n) {
      if (!e.IsScalar()) {
        error(e, what + ": expected a channel name");
      } else if (std::find(out.begin(), out.end(), e.Scalar()) != out.end()) {
        // Kept twice: its metrics' rows would collide in the database (every resume failing
        // alike), its sections and series be stored twice.
        error(e, what + ": '" + e.Scalar() + "' is listed twice; list each channel once");
      } else {
        out.push_back(e.Scalar());
      }
    }
    return out;
  }
};

/// Text of a scalar or a flow-written list/map, as an override's value.
std::string override_text(const YAML::Node& n) {
  if (n.IsScalar()) return n.Scalar();
  YAML::Emitter e;
  e << YAML::Flow << n;
  return e.c_str();
}

/// A model's problems as a study's: an override's ("--set a.b") point at the key of the study
/// file that sets that path, and a value the study set is said to come from the study.
Diagnostics study_diagnostics(const std::vector<Diagnostic>& in, const StudySpec& spec) {
  Diagnostics out;
  for (auto d : in) {
    if (d.file.rfind("--set", 0) == 0) {
      const std::string path = d.file.size() > 6 ? d.file.substr(6) : "";
      d.file = spec.file;
      d.line = d.column = 0;
      if (const auto m = spec.path_marks.find(path); m != spec.path_marks.end())
        d.line = m->second.first, d.column = m->second.second;
      if (!path.empty()) d.message = "'" + path + "': " + d.message;
    }
    const std::string tail = " (value set with --set)";
    if (d.message.size() > tail.size() &&
        d.message.compare(d.message.size() - tail.size(), tail.size(), tail) == 0) {
      d.message.replace(d.message.size() - tail.size(), tail.size(), " (a value the study " + spec.file + " sets)");
      // A refused value is reported where the model reads it; point at the study's key that
      // set it: the one path whose segments after the first ("rtol" of solver.rtol;
      // "rod_slider" and "clearance" of joints.rod_slider.clearance) the message names.
      // Not the keys the message lists or suggests ("unknown key 'foo', expected one of: type,
      // journal, ..., clearance, ..." names every key of the joint).
      std::string said = d.element + " " + d.message;
      for (const char* list : {", expected one of", ", did you mean"})
        if (const size_t at = said.find(list); at != std::string::npos) said.erase(at);
      auto names = [&](const std::string& word) {
        for (size_t at = said.find(word); at != std::string::npos; at = said.find(word, at + 1)) {
          const auto part = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
          if ((at == 0 || !part(said[at - 1])) &&
              (at + word.size() == said.size() || !part(said[at + word.size()])))
            return true;
        }
        return false;
      };
      const std::pair<int, int>* mark = nullptr;
      int found = 0;
      for (const auto& [path, m] : spec.path_marks) {
        // A top-level value (gravity, name, description; not a section such as `ground` or
        // `solver`, whose keys set below it are named instead) is named itself ("'gravity'
        // must be a pair ...").
        const bool leaf = path == "gravity" || path == "name" || path == "description";
        bool all = path.find('.') != std::string::npos || (leaf && names(path));
        for (size_t a = path.find('.'); all && a != std::string::npos;) {
          const size_t b = path.find('.', a + 1);
          all = names(path.substr(a + 1, b == std::string::npos ? std::string::npos : b - a - 1));
          a = b;
        }
        if (all) mark = &m, ++found;
      }
      if (found == 1 && d.line == 0) {
        d.file = spec.file;
        d.line = mark->first;
        d.column = mark->second;
      }
    }
    out.push_back(std::move(d));
  }
  return out;
}

constexpr int kMaxRuns = 1000000;

/// A number's text for comparing levels: 5000 and 5.0e3 alike, 0 and -0 alike.
std::string number_key(double x) {
  return fmt::format("n:{}", x == 0.0 ? 0.0 : x);  // (fmt: the shortest text that reads back)
}

/// A level written in a study as canonical text: levels with one text are one value. Numbers
/// as numbers (number_key), other scalars as text, lists entry by entry, maps by their sorted
/// keys ([0, -9.81] and [0.0, -9.81] are one level).
std::string level_key(const YAML::Node& n) {
  if (n.IsScalar()) {
    char* end = nullptr;
    const double x = std::strtod(n.Scalar().c_str(), &end);
    return !n.Scalar().empty() && *end == '\0' ? number_key(x) : "s:" + n.Scalar();
  }
  std::string out;
  if (n.IsSequence()) {
    out = "[";
    for (const auto& e : n) out += level_key(e) + '\x1e';
    return out + "]";
  }
  if (n.IsMap()) {
    std::map<std::string, std::string> entries;
    for (const auto& kv : n) entries[kv.first.IsScalar() ? kv.first.Scalar() : level_key(kv.first)] = level_key(kv.second);
    out = "{";
    for (const auto& [k, v] : entries) out += k + '\x1d' + v + '\x1e';
    return out + "}";
  }
  return "~";
}

void read_parameter(Reader& r, const YAML::Node& key, const YAML::Node& v, StudySpec& spec,
                    const std::function<std::string(const std::string&)>& load_model) {
  StudyParameter p;
  p.name = key.as<std::string>("");
  const std::string where = "parameter '" + p.name + "'";
  if (!v.IsMap()) {
    r.error(v, where + ": expected {values: [...]}, {from, to, count}, {min, max} or {cases: {...}}");
    return;
  }
  r.keys(v, {"values", "from", "to", "count", "scale", "min", "max", "cases"}, where);
  const std::string scale = v["scale"] ? v["scale"].as<std::string>("") : "linear";
  if (scale != "linear" && scale != "log") r.error(v["scale"], where + ": scale must be linear or log");
  p.log = scale == "log";
  const int kinds = (v["values"] ? 1 : 0) + (v["from"] || v["to"] || v["count"] ? 1 : 0) +
                    (v["min"] || v["max"] ? 1 : 0) + (v["cases"] ? 1 : 0);
  if (kinds != 1) {
    r.error(v, where + ": give exactly one of values, from/to/count, min/max or cases");
    return;
  }
  if (v["values"]) {
    if (v["scale"])
      r.error(v["scale"], where + ": scale applies to from/to/count and min/max ranges, not to "
                                  "values (listed as they are)");
    if (!v["values"].IsSequence() || v["values"].size() == 0) {
      r.error(v["values"], where + ": values must be a non-empty list");
      return;
    }
    for (const auto& e : v["values"]) {
      if (e.IsNull())  // (it became the text level '~', refused only when its run started)
        r.error(e, where + ": a level is empty (~ or nothing), expected a value");
      p.values.push_back(override_text(e));
      char* end = nullptr;
      const double d = std::strtod(p.values.back().c_str(), &end);
      p.numbers.push_back(!p.values.back().empty() && *end == '\0' ? d : std::nan(""));
    }
  } else if (v["from"] || v["to"] || v["count"]) {
    double a = 0, b = 0;
    long n = 0;
    bool ok = true;
    for (const char* k : {"from", "to", "count"})
      if (!v[k]) {
        r.error(v, where + ": a range needs from, to and count");
        ok = false;
      }
    if (!ok) return;
    ok = r.number(v["from"], where + ": from", a) & r.number(v["to"], where + ": to", b) &
         r.integer(v["count"], where + ": count", 1, kMaxRuns, n);
    if (!ok) return;
    if (p.log && (a <= 0 || b <= 0)) {
      r.error(v, where + ": a logarithmic range needs from > 0 and to > 0");
      return;
    }
    if (n == 1 && a != b) {
      r.error(v["count"], where + ": count 1 gives from only, but to (" + number_text(b) +
                              ") differs; give count >= 2 for both ends, or values: [" + number_text(a) + "]");
      return;
    }
    for (long i = 0; i < n; ++i) {
      const double f = n == 1 ? 0.0 : static_cast<double>(i) / (n - 1);
      // (a·(n−1−i) + b·i)/(n−1): 0.05e-3 to 0.5e-3 in 10 steps gives 1e-4, not 9.9999999999999991e-05.
      // Logarithmic levels in decades (log10, pow of 10): 1e-5 to 1e-3 in 3 gives 1e-4 exactly,
      // where exp and log gave 9.99999999999999e-05.
      double x = p.log ? std::pow(10.0, std::log10(a) + f * (std::log10(b) - std::log10(a)))
                       : n == 1 ? a : (a * (n - 1 - i) + b * i) / (n - 1);
      // Near the largest double that sum overflows (from: 1e308 gave inf); this form cannot.
      if (!std::isfinite(x)) x = a * (1.0 - f) + b * f;
      // Rounded to 15 significant digits, the levels are the decimal numbers meant (1e-4, not
      // 9.999999999999999e-05); the end point exactly as written.
      char buf[32];
      double rounded = x;
      char* end = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::general, 15).ptr;
      // Past the largest double the rounded text reads back out of range: x then.
      if (std::from_chars(buf, end, rounded).ec != std::errc()) rounded = x;
      const double xv = i == n - 1 && n > 1 ? b : std::isfinite(rounded) ? rounded : x;
      p.numbers.push_back(xv);
      p.values.push_back(number_text(xv));
    }
  } else if (v["min"] || v["max"]) {
    if (!v["min"] || !v["max"]) {
      r.error(v, where + ": a sampled parameter needs min and max");
      return;
    }
    p.sampled = true;
    if (!r.number(v["min"], where + ": min", p.min) || !r.number(v["max"], where + ": max", p.max)) {
      // Still a drawn parameter (the study is refused): `sampling:` is not then said to have
      // nothing to draw.
      spec.parameters.push_back(std::move(p));
      return;
    }
    if (!(p.min < p.max)) r.error(v, where + ": min must be less than max");
    if (p.log && p.min <= 0) r.error(v, where + ": a logarithmic range needs min > 0");
    p.sampled = true;
  } else {
    const YAML::Node cases = v["cases"];
    if (!cases.IsMap() || cases.size() == 0) {
      r.error(cases, where + ": cases must be a map of case name to {path: value, ...}");
      return;
    }
    for (const auto& c : cases) {
      const std::string cname = c.first.as<std::string>("");
      p.values.push_back(cname);
      p.numbers.push_back(std::nan(""));
      std::vector<std::string> ov;
      std::string model;
      if (!c.second.IsMap() && !c.second.IsNull()) {
        r.error(c.second, where + ": case '" + cname + "': expected a map of path: value");
      } else if (c.second.IsMap()) {
        for (const auto& kv : c.second) {
          const std::string k = kv.first.as<std::string>("");
          if (k == "model") {
            model = (std::filesystem::path(spec.file).parent_path() / kv.second.as<std::string>(""))
                        .lexically_normal()
                        .string();
            try {
              spec.model_texts.emplace(model, load_model(model));
            } catch (const std::exception& e) {
              r.error(kv.second, where + ": case '" + cname + "': " + e.what());
            }
          } else {
            ov.push_back(k + "=" + override_text(kv.second));
          }
        }
      }
      p.case_overrides.push_back(ov);
      p.case_models.push_back(model);
    }
  }
  spec.parameters.push_back(std::move(p));
}

/// Case `name` of the cases parameter `parameter`: its key (the name, for messages; `params`
/// when absent) and its node (null when absent).
std::pair<YAML::Node, YAML::Node> find_case(const YAML::Node& params, const std::string& parameter,
                                            const std::string& name) {
  for (const auto& kv : params)
    if (kv.first.as<std::string>("") == parameter && kv.second.IsMap() && kv.second["cases"].IsMap())
      for (const auto& c : kv.second["cases"])
        if (c.first.as<std::string>("") == name) return {c.first, c.second};
  return {params, YAML::Node()};
}

/// A fixed 64-bit generator (splitmix64): the same sequence everywhere.
struct SplitMix {
  unsigned long long s;
  double uniform() {  // [0, 1)
    unsigned long long z = (s += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z ^= z >> 31;
    return static_cast<double>(z >> 11) * 0x1.0p-53;
  }
  size_t below(size_t n) { return std::min(n - 1, static_cast<size_t>(uniform() * n)); }
};

}  // namespace

StudySpec load_study_text(const std::string& text, const std::string& file,
                          const std::function<std::string(const std::string&)>& read) {
  StudySpec spec;
  spec.file = file;
  spec.text = text;
  Reader r{file, {}};
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ModelError({yaml_syntax_problem(file, text, e.mark.line + 1, e.mark.column + 1, e.msg)});
  }
  if (!root.IsMap())
    throw ModelError({{file, 1, 1, "", "expected a study (a map with study, model, parameters, ...)"}});
  if (auto problems = yaml_structure_problems(text, file); !problems.empty()) throw ModelError(problems);
  // A model file given where a study goes: one problem, not one per model section.
  if (!root["study"] && !root["model"] && (root["bodies"] || root["joints"]))
    throw ModelError({{file, 1, 1, "",
                       "this is a model file (it has bodies or joints), not a study: `lash run` "
                       "runs it; a study names it with `model:` (docs/studies.md)"}});
  r.keys(root, {"study", "model", "set", "parameters", "combine", "sampling", "keep", "transient",
                "lyapunov", "continuation"},
         "study");
  spec.name = root["study"] && root["study"].IsScalar() ? root["study"].Scalar() : "study";
  if (const YAML::Node n = root["study"]; n && !(n.IsScalar() && !n.Scalar().empty()))
    r.error(n, std::string("study: expected a name (text), got ") +
                   (n.IsSequence() ? "a list" : n.IsMap() ? "a map" : "nothing"));
  if (const YAML::Node m = root["model"]; !m || !m.IsScalar() || m.Scalar().empty()) {
    if (m && !m.IsNull())
      r.error(m, std::string("model: expected the base model file's name (relative to this file), got ") +
                     (m.IsSequence() ? "a list" : m.IsMap() ? "a map" : "nothing"));
    else
      r.error(m ? m : root, "study: 'model' (the base model file, relative to this file) is missing");
    throw ModelError(r.list);
  }
  spec.model = (std::filesystem::path(file).parent_path() / root["model"].Scalar()).lexically_normal().string();
  try {
    spec.model_texts.emplace(spec.model, read(spec.model));
  } catch (const std::exception& e) {
    r.error(root["model"], std::string("model: ") + e.what());
    throw ModelError(r.list);
  }
  if (const YAML::Node set = root["set"]) {
    if (!set.IsMap()) r.error(set, "set: expected a map of model path: value");
    else
      for (const auto& kv : set) spec.fixed.push_back(kv.first.as<std::string>("") + "=" + override_text(kv.second));
  }
  const YAML::Node params = root["parameters"];
  if (!params || !params.IsMap() || params.size() == 0) {
    r.error(params ? params : root, params && params.IsMap()
                                        ? "parameters: empty; give at least one model path (or case name) and its levels"
                                        : "parameters: expected a map of model path (or case name) to its levels");
    throw ModelError(r.list);
  }
  for (const auto& kv : params) read_parameter(r, kv.first, kv.second, spec, read);
  // Parameters are columns of the study database: no two alike (SQL names ignore case) and none
  // named like the columns every run has.
  {
    auto lower = [](std::string t) {
      for (char& c : t) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      return t;
    };
    // (k, t, channel and value: the columns of sections.csv, beside the parameters there.)
    std::set<std::string> seen = {"run", "status", "message", "verdict", "t_reached", "wall_seconds",
                                   "steps", "rhs_evaluations", "events", "worker", "finished",
                                   "k", "t", "channel", "value"};
    const std::set<std::string> reserved = seen;
    auto metric_like = [](const std::string& n) {  // metric names share the rows of runs.csv
      for (const char* tail : {".peak", ".max", ".min", ".rms", ".impacts", ".impact_share",
                               ".continuous_share", ".free_flight_share", ".max_impact_velocity"}) {
        const std::string t = tail;
        if (n.size() > t.size() && n.compare(n.size() - t.size(), t.size(), t) == 0) return true;
      }
      return n == "sections" || n == "distinct_points" || n == "lyapunov_exponent" || n == "direction";
    };
    for (const auto& kv : params) {
      const std::string n = kv.first.as<std::string>("");
      if (n.empty()) r.error(kv.first, "parameters: an empty name");
      else if (metric_like(lower(n)))
        r.error(kv.first, "parameter '" + n + "': named like a metric or column of the results "
                                              "(docs/studies.md); call it otherwise");
      else if (!seen.insert(lower(n)).second)
        r.error(kv.first, "parameter '" + n + "': " +
                              (reserved.count(lower(n)) ? "a name every run's row has already; call it otherwise"
                                                        : "given twice (names are compared ignoring case)"));
    }
  }
  // Where each model path is set: `set` gives every run's base, which a parameter or a case may
  // override (docs/studies.md). Two parameters must not set one path (nor one a part of the
  // other's): the run's row would name one level and the model hold the other's value.
  if (const YAML::Node set = root["set"]; set && set.IsMap())
    for (const auto& kv : set)
      spec.path_marks[kv.first.as<std::string>("")] = {kv.first.Mark().line + 1, kv.first.Mark().column + 1};
  {
    struct Setter {
      std::string path, who;
      YAML::Node key;
      size_t parameter;
    };
    std::vector<Setter> setters;
    for (size_t j = 0; j < spec.parameters.size() && j < params.size(); ++j) {
      const StudyParameter& p = spec.parameters[j];
      if (p.case_overrides.empty()) {
        for (const auto& kv : params)
          if (kv.first.as<std::string>("") == p.name)
            setters.push_back({p.name, "parameter '" + p.name + "'", kv.first, j});
        continue;
      }
      for (size_t k = 0; k < p.values.size(); ++k) {
        const YAML::Node c = find_case(params, p.name, p.values[k]).second;
        if (!c.IsMap()) continue;
        for (const auto& o : c)
          setters.push_back({o.first.as<std::string>(""),
                             "case '" + p.values[k] + "' of parameter '" + p.name + "'", o.first, j});
      }
    }
    auto overlap = [](const std::string& a, const std::string& b) {
      const std::string& s = a.size() <= b.size() ? a : b;
      const std::string& l = a.size() <= b.size() ? b : a;
      return l.compare(0, s.size(), s) == 0 && (l.size() == s.size() || l[s.size()] == '.');
    };
    for (size_t b = 0; b < setters.size(); ++b)
      for (size_t a = 0; a < b; ++a)
        if (setters[a].parameter != setters[b].parameter && overlap(setters[a].path, setters[b].path)) {
          const YAML::Mark m = setters[a].key.Mark();
          r.error(setters[b].key,
                  "'" + setters[b].path + "' is set by " + setters[b].who + " and " +
                      (setters[a].path == setters[b].path ? "" : "'" + setters[a].path + "' ") + "by " +
                      setters[a].who + " (line " + std::to_string(m.line + 1) + ", column " +
                      std::to_string(m.column + 1) + "); a run's row would name one and the model "
                      "hold the other's value: set each model path in one parameter only");
          break;
        }
    for (const auto& st : setters)
      spec.path_marks[st.path] = {st.key.Mark().line + 1, st.key.Mark().column + 1};
  }
  if (const YAML::Node c = root["combine"]) {
    spec.combine = c.as<std::string>("");
    if (spec.combine != "cross" && spec.combine != "zip")
      r.error(c, "combine: expected cross (every combination) or zip (level by level), got '" + spec.combine + "'");
  }
  const bool any_sampled = std::any_of(spec.parameters.begin(), spec.parameters.end(),
                                       [](const StudyParameter& p) { return p.sampled; });
  if (const YAML::Node s = root["sampling"]; s && !s.IsMap()) {
    r.error(s, "sampling: expected {method: latin_hypercube | random, count: N, seed: S}");
  } else if (s) {
    r.keys(s, {"method", "count", "seed"}, "sampling");
    spec.sampling = s["method"] ? s["method"].as<std::string>("") : "latin_hypercube";
    if (spec.sampling != "random" && spec.sampling != "latin_hypercube")
      r.error(s, "sampling: method must be random or latin_hypercube");
    long n = 0, seed = 1;
    if (!s["count"]) r.error(s, "sampling: count is missing");
    else if (r.integer(s["count"], "sampling: count", 1, kMaxRuns, n)) spec.samples = static_cast<int>(n);
    if (s["seed"] && r.integer(s["seed"], "sampling: seed", 0, std::numeric_limits<long>::max(), seed))
      spec.seed = static_cast<unsigned long long>(seed);
  }
  if (any_sampled && spec.sampling.empty()) {
    // At the first parameter with min/max (the file's start said nothing). A function: a
    // YAML::Node assigned to another one writes into it.
    const auto drawn = [&]() -> YAML::Node {
      if (params && params.IsMap())
        for (const auto& kv : params)
          if (kv.second.IsMap() && (kv.second["min"] || kv.second["max"])) return kv.first;
      return root;
    };
    r.error(drawn(), "parameters with min/max are drawn: add sampling: {method: latin_hypercube, count: N}");
  }
  if (!any_sampled && !spec.sampling.empty())
    r.error(root["sampling"], "sampling: no parameter has min/max to draw");
  if (any_sampled && spec.combine == "zip")
    r.error(root["combine"], "combine: zip is for listed levels; sampled parameters are drawn together");
  if (spec.combine == "zip" && !any_sampled) {
    for (const auto& p : spec.parameters)
      if (p.values.size() != spec.parameters.front().values.size())
        r.error(params, "combine: zip needs the same number of levels for every parameter ('" +
                            p.name + "' has " + std::to_string(p.values.size()) + ", '" +
                            spec.parameters.front().name + "' has " +
                            std::to_string(spec.parameters.front().values.size()) + ")");
  }
  if (const YAML::Node k = root["keep"]; k && !k.IsMap()) {
    r.error(k, "keep: expected {channels: [...], sections: [...], series: {channels: [...], points: N}}");
  } else if (k) {
    r.keys(k, {"channels", "sections", "series"}, "keep");
    if (k["channels"]) spec.channels = r.names(k["channels"], "keep: channels");
    if (k["sections"]) spec.section_channels = r.names(k["sections"], "keep: sections");
    if (const YAML::Node s = k["series"]; s && !s.IsMap()) {
      r.error(s, "keep: series: expected {channels: [...], points: N}");
    } else if (s) {
      r.keys(s, {"channels", "points"}, "keep: series");
      if (s["channels"]) spec.series = r.names(s["channels"], "keep: series: channels");
      long n = 0;
      if (s["points"] && r.integer(s["points"], "keep: series: points", 2, 100000, n))
        spec.series_points = static_cast<int>(n);
    }
  }
  if (const YAML::Node t = root["transient"]; t && !t.IsMap()) {
    r.error(t, "transient: expected {periods: N} or {time: S}");
  } else if (t) {
    r.keys(t, {"periods", "time"}, "transient");
    if (t["periods"] && t["time"])
      r.error(t, "transient: give periods (crank periods) or time (seconds), not both");
    long n = 0;
    if (t["periods"] && r.integer(t["periods"], "transient: periods", 0, 1000000, n))
      spec.discard_periods = static_cast<int>(n);
    double s = 0;
    if (t["time"] && r.number(t["time"], "transient: time", s)) {
      if (s < 0) r.error(t["time"], "transient: time must be >= 0 s");
      spec.discard_time = s;
    }
  }
  if (const YAML::Node l = root["lyapunov"]) {
    if (l.Scalar() != "true" && l.Scalar() != "false") r.error(l, "lyapunov: expected true or false");
    spec.lyapunov = l.Scalar() == "true";
  }
  if (const YAML::Node c = root["continuation"]) {
    spec.continuation = c.IsScalar() ? c.Scalar() : std::string("?");
    if (spec.continuation == "none") spec.continuation.clear();
    if (!spec.continuation.empty() && spec.continuation != "up" && spec.continuation != "down" &&
        spec.continuation != "both")
      r.error(c, "continuation: expected none, up, down or both, got '" + spec.continuation + "'");
    else if (!spec.continuation.empty() &&
             (spec.parameters.size() != 1 || spec.parameters[0].sampled ||
              !spec.parameters[0].case_overrides.empty()))
      r.error(c, "continuation: needs exactly one parameter with listed levels (values or "
                 "from/to/count), run in order");
  }
  // A level listed twice would make its runs twice (the same model, the same results) and give
  // a report two rows or points for one value: a slip in the list, refused where it is. Numbers
  // compare as numbers (5000 and 5.0e3 are one level). Under zip a parameter may repeat a level
  // (it pairs with different levels of the others): there a whole row of levels must not repeat.
  // A continuation chain may come back to a level (8000, 2000, 8000): from another state.
  // Each level's canonical text (level_key) is looked up in a map: n log n, where comparing
  // every pair took 80 s for a range of 16 000 levels.
  if (spec.continuation.empty() && !(spec.combine == "zip" && any_sampled)) {
    struct Levels {
      bool listed = false;            ///< written as `values:`
      YAML::Node list;                ///< that sequence
      std::vector<std::string> keys;  ///< level_key of each level
    };
    std::vector<Levels> levels;
    for (const auto& p : spec.parameters) {
      Levels l;
      if (const YAML::Node v = params[p.name];
          v && v.IsMap() && v["values"] && v["values"].IsSequence() && v["values"].size() == p.values.size()) {
        l.listed = true;
        l.list = v["values"];
      }
      for (size_t k = 0; k < p.values.size(); ++k)
        l.keys.push_back(l.listed ? level_key(l.list[k]) : std::isnan(p.numbers[k]) ? "s:" + p.values[k]
                                                                                 : number_key(p.numbers[k]));
      levels.push_back(std::move(l));
    }
    const auto node_of = [&](size_t i, size_t k) -> YAML::Node {
      if (levels[i].listed) return levels[i].list[k];
      const YAML::Node v = params[spec.parameters[i].name];
      return v ? v : params;
    };
    // The first level whose key came before, as (earlier, this), or (0, 0).
    const auto twice = [](const std::vector<std::string>& keys) -> std::pair<size_t, size_t> {
      std::map<std::string, size_t> first;
      for (size_t k = 0; k < keys.size(); ++k)
        if (const auto [it, fresh] = first.emplace(keys[k], k); !fresh) return {it->second, k};
      return {0, 0};
    };
    const size_t n_levels = spec.parameters.empty() ? 0 : spec.parameters.front().values.size();
    bool sizes_agree = true;
    for (const auto& p : spec.parameters) sizes_agree = sizes_agree && p.values.size() == n_levels;
    if (spec.combine == "zip") {
      std::vector<std::string> rows(sizes_agree ? n_levels : 0);
      for (size_t k = 0; k < rows.size(); ++k)
        for (const auto& l : levels) rows[k] += l.keys[k] + '\x1f';
      if (const auto [j, k] = twice(rows); k > 0)
        r.error(node_of(0, k), "combine: zip: levels " + std::to_string(j + 1) + " and " + std::to_string(k + 1) +
                                   " are the same in every parameter (" + spec.parameters.front().name + ": " +
                                   spec.parameters.front().values[k] + "); that run would be made twice");
    } else {
      for (size_t i = 0; i < spec.parameters.size(); ++i) {
        const StudyParameter& p = spec.parameters[i];
        if (p.sampled || !p.case_overrides.empty()) continue;  // (case names are map keys)
        if (const auto [j, k] = twice(levels[i].keys); k > 0)
          r.error(node_of(i, k), "parameter '" + p.name + "': level " + p.values[k] +
                                     (levels[i].listed ? " is listed twice" : " comes twice from the range") +
                                     " (levels " + std::to_string(j + 1) + " and " + std::to_string(k + 1) +
                                     "); its runs would be made twice");
      }
    }
  }
  if (!r.list.empty()) throw ModelError(r.list);

  // How many runs: refused past kMaxRuns before anything is listed.
  double n = 1;
  if (any_sampled) n = spec.samples;
  if (spec.combine == "zip") n *= spec.parameters.front().values.size();
  else
    for (const auto& p : spec.parameters)
      if (!p.sampled) n *= static_cast<double>(p.values.size());
  if (n > kMaxRuns)
    throw ModelError({{file, 1, 1, "", "the study has " + number_text(n) + " runs; at most " +
                                           std::to_string(kMaxRuns) + " in one study"}});

  // The study must make at least one model: the first runs are loaded until one is, so a typo in
  // a path fails now rather than in every run. Every level of every listed parameter (each case
  // too) is loaded once more in the first run that has it: a path the model lacks is refused
  // wherever it is, a case none of whose first runs loads is refused, and the kept channels must
  // exist in at least one of these models (a run whose model lacks one keeps the rest).
  const auto runs = study_runs(spec);
  std::map<size_t, std::optional<LoadedModel>> loaded;  // run index → its model, if it loads
  std::map<size_t, std::vector<Diagnostic>> load_errors;
  auto load = [&](size_t i) -> bool {
    if (loaded.count(i)) return loaded[i].has_value();
    try {
      loaded[i] = load_model_text(spec.model_texts.at(runs[i].model), runs[i].model, runs[i].overrides);
    } catch (const ModelError& e) {
      loaded[i] = std::nullopt;
      for (const auto& d : study_diagnostics(e.diagnostics(), spec))
        load_errors[i].push_back(d);
    }
    return loaded[i].has_value();
  };
  // The runs of each level: (parameter, level) → the first few runs that have it.
  constexpr size_t kTriesPerCase = 20, kMaxProbes = 400;
  std::map<std::pair<size_t, std::string>, std::vector<size_t>> level_runs;
  for (size_t i = 0; i < runs.size(); ++i)
    for (size_t j = 0; j < spec.parameters.size(); ++j) {
      if (spec.parameters[j].sampled) continue;
      auto& v = level_runs[{j, runs[i].values[j]}];
      if (v.size() < (spec.parameters[j].case_overrides.empty() ? 1 : kTriesPerCase)) v.push_back(i);
    }
  // A model that loads: among the first 100 runs, then the first run of each level (a value
  // bad in the first 100 runs, e.g. the outer parameter's first level, is those runs' error).
  size_t first_ok = runs.size();
  for (size_t i = 0; i < runs.size() && i < 100 && first_ok == runs.size(); ++i)
    if (load(i)) first_ok = i;
  for (auto it = level_runs.begin(); it != level_runs.end() && first_ok == runs.size() &&
                                     loaded.size() < kMaxProbes; ++it)
    if (load(it->second.front())) first_ok = it->second.front();
  if (first_ok == runs.size()) {
    Diagnostics list;
    for (auto d : load_errors.begin()->second) {
      d.message += " (in run " + std::to_string(runs[load_errors.begin()->first].index) + ")";
      list.push_back(d);
    }
    throw ModelError(list);
  }
  std::set<std::string> reported;  // path problems, once each
  auto report_paths = [&](size_t i) {
    // A path the model lacks; a value refused in this run only is that run's error (below).
    for (const auto& d : load_errors[i])
      if (d.file == file && d.line > 0 && d.message.find(" (a value the study ") == std::string::npos &&
          reported.insert(d.str()).second)
        r.list.push_back(d);
  };
  size_t probes = 0;
  for (size_t j = 0; j < spec.parameters.size(); ++j) {
    const StudyParameter& p = spec.parameters[j];
    if (p.sampled) continue;
    const bool cases = !p.case_overrides.empty();
    // Continuation runs every level in one chain: each is loaded, whatever their number.
    if (!cases && spec.continuation.empty() && probes >= kMaxProbes) continue;
    for (size_t k = 0; k < p.values.size(); ++k) {
      // (Within one parameter too: 10⁵ levels of one parameter took two minutes to load.)
      if (!cases && spec.continuation.empty() && probes >= kMaxProbes) break;
      const auto it = level_runs.find({j, p.values[k]});
      if (it == level_runs.end()) continue;
      bool ok = false;
      for (size_t i : it->second) {
        ++probes;
        ok = load(i);
        report_paths(i);
        if (ok || !cases) break;
      }
      if (ok || !cases) continue;
      // A case none of whose runs loads: its model's problems, said to come from the case.
      const YAML::Node key = find_case(params, p.name, p.values[k]).first;
      for (const auto& d : load_errors[it->second.front()])
        if (!(d.file == file && d.line > 0) || d.message.find(" (a value the study ") != std::string::npos)
          r.error(key, "parameter '" + p.name + "': case '" + p.values[k] + "' makes no valid model (" +
                           d.str() + ", in run " + std::to_string(runs[it->second.front()].index) + ")");
    }
  }
  const LoadedModel& lm0 = *loaded[first_ok];
  // (A run whose driver stands still, speed 0, has no period but the study's others may: its
  // own error, transient_end.)
  const Driver* drv0 = rotary_driver(lm0.model, "");
  const bool constant_speed = drv0 && drv0->profile == DriverProfile::constant_speed;
  if (!constant_speed && spec.discard_time < 0 && root["transient"] && root["transient"]["periods"])
    r.error(root["transient"], "transient: periods needs a constant-speed rotary driver, which the "
                               "model has not; give the transient in seconds: {time: S}");
  if (!spec.section_channels.empty() && !constant_speed)
    r.error(root["keep"]["sections"], "keep: sections are taken once per period of a constant-speed "
                                      "rotary driver, which the model has not; keep channels or series "
                                      "instead");
  if (!spec.continuation.empty() && !constant_speed)
    r.error(root["continuation"], "continuation: needs a constant-speed rotary driver (the hand-over "
                                  "keeps the crank angle), which the model has not");
  // Continuation hands the crank angle from level to level: every level must turn the driver, and
  // the same way (checked here, or every later run of the chain would be an error).
  if (!spec.continuation.empty() && constant_speed) {
    const StudyParameter& p = spec.parameters.front();
    const YAML::Node key = params.begin()->first;
    for (size_t k = 0; k < p.values.size(); ++k) {
      const auto it = level_runs.find({0, p.values[k]});
      if (it == level_runs.end() || !loaded.count(it->second.front())) continue;
      const auto& m = loaded[it->second.front()];
      if (!m) {
        r.error(key, "continuation: level '" + p.values[k] + "' of '" + p.name +
                         "' makes no valid model, and every later run of the chain would start from it: " +
                         load_errors[it->second.front()].front().str());
        continue;
      }
      const Driver* d = period_driver(m->model, "");
      if (!d || d->profile != DriverProfile::constant_speed || d->speed == 0.0 ||
          d->speed * drv0->speed < 0.0)
        r.error(key, "continuation: level '" + p.values[k] + "' of '" + p.name + "' " +
                         (d && d->profile == DriverProfile::constant_speed && d->speed == 0.0
                              ? "stops the driver (speed 0)"
                              : d && d->profile == DriverProfile::constant_speed
                                    ? "turns the driver the other way"
                                    : "gives no turning constant-speed rotary driver (a speed of 0 stops it)") +
                         "; continuation needs every level to turn it the same way (expected the "
                         "sign of the first level's speed, " + number_text(drv0->speed) + " rad/s)");
    }
  }
  // Kept channels: each must be in at least one checked run's model.
  std::set<std::string> present;
  std::vector<std::string> names;
  for (const auto& [i, m] : loaded) {
    if (!m) continue;
    for (const auto& c : channel_info(m->model))
      if (present.insert(c.name).second) names.push_back(c.name);
  }
  // Each unknown name is reported at its own entry (the list's first with that name).
  const YAML::Node keep = root["keep"];
  auto entry_of = [&](const YAML::Node& list, const std::string& c) -> YAML::Node {
    if (list && list.IsSequence())
      for (const auto& e : list)
        if (e.IsScalar() && e.Scalar() == c) return e;
    return list ? list : keep;
  };
  const std::pair<const std::vector<std::string>*, YAML::Node> groups[] = {
      {&spec.channels, keep ? keep["channels"] : YAML::Node()},
      {&spec.section_channels, keep ? keep["sections"] : YAML::Node()},
      {&spec.series, keep && keep["series"] ? keep["series"]["channels"] : YAML::Node()}};
  for (const auto& [group, list] : groups)
    for (const auto& c : *group)
      if (!present.count(c)) {
        const std::string near = closest_match(c, names);
        r.error(entry_of(list, c), "keep: no channel '" + c + "' in the model" +
                                       (near.empty() ? "" : ", did you mean '" + near + "'?") +
                                       " (nor in any other run's checked)");
      }
  if (!r.list.empty()) throw ModelError(r.list);
  return spec;
}

StudySpec load_study_file(const std::string& file) {
  std::string text;
  try {
    text = read_input_file(file, kMaxModelFileBytes);
  } catch (const std::exception& e) {
    std::string what = e.what();
    if (what.rfind(file + ": ", 0) == 0) what.erase(0, file.size() + 2);
    throw ModelError({{file, 0, 0, "", "cannot read the study file: " + what}});
  }
  return load_study_text(text, file, [](const std::string& path) {
    return read_input_file(path, kMaxModelFileBytes);
  });
}

std::vector<std::string> parameter_columns(const StudySpec& spec) {
  std::vector<std::string> out;
  for (const auto& p : spec.parameters) out.push_back(p.name);
  if (!spec.continuation.empty()) out.push_back("direction");
  return out;
}

std::vector<StudyRun> study_runs(const StudySpec& spec) {
  if (!spec.continuation.empty()) {  // one parameter; chains up and/or down, each run after the one before
    const StudyParameter& p = spec.parameters.front();
    std::vector<StudyRun> runs;
    for (const std::string dir : {"up", "down"}) {
      if (spec.continuation != "both" && spec.continuation != dir) continue;
      const size_t n = p.values.size();
      for (size_t k = 0; k < n; ++k) {
        const size_t level = dir == "up" ? k : n - 1 - k;
        StudyRun run;
        run.index = static_cast<int>(runs.size());
        run.model = spec.model;
        run.overrides = spec.fixed;
        run.values = {p.values[level], dir};
        run.numbers = {p.numbers[level], std::nan("")};
        run.overrides.push_back(p.name + "=" + p.values[level]);
        // Down after up continues from the top: the whole study is one chain.
        run.previous = k == 0 && (dir == "up" || spec.continuation == "down") ? -1 : run.index - 1;
        runs.push_back(std::move(run));
      }
    }
    return runs;
  }
  const size_t np = spec.parameters.size();
  // Level index of each parameter, per run; sampled parameters carry the drawn value instead.
  std::vector<std::vector<size_t>> levels;
  std::vector<std::vector<double>> drawn;  // per run, per parameter (sampled ones)
  std::vector<size_t> listed;
  for (size_t i = 0; i < np; ++i)
    if (!spec.parameters[i].sampled) listed.push_back(i);
  std::vector<std::vector<size_t>> combos(1, std::vector<size_t>(np, 0));
  if (spec.combine == "zip") {
    combos.clear();
    for (size_t k = 0; k < spec.parameters.front().values.size(); ++k) combos.push_back(std::vector<size_t>(np, k));
  } else {
    // Cross: the first parameter varies slowest (row-major), so a one-parameter sweep keeps its order.
    for (size_t i : listed) {
      std::vector<std::vector<size_t>> next;
      for (const auto& c : combos)
        for (size_t k = 0; k < spec.parameters[i].values.size(); ++k) {
          auto d = c;
          d[i] = k;
          next.push_back(d);
        }
      combos = std::move(next);
    }
  }
  const int n_samples = spec.sampling.empty() ? 1 : spec.samples;
  std::vector<std::vector<double>> samples(n_samples, std::vector<double>(np, 0.0));
  if (!spec.sampling.empty()) {
    SplitMix g{spec.seed};
    for (size_t i = 0; i < np; ++i) {
      const StudyParameter& p = spec.parameters[i];
      if (!p.sampled) continue;
      std::vector<size_t> strata(n_samples);
      std::iota(strata.begin(), strata.end(), 0);
      if (spec.sampling == "latin_hypercube")  // Fisher–Yates with the fixed generator
        for (size_t k = strata.size(); k > 1; --k) std::swap(strata[k - 1], strata[g.below(k)]);
      for (int s = 0; s < n_samples; ++s) {
        const double u = spec.sampling == "latin_hypercube" ? (strata[s] + g.uniform()) / n_samples : g.uniform();
        samples[s][i] = p.log ? std::exp(std::log(p.min) + u * (std::log(p.max) - std::log(p.min)))
                              : p.min + u * (p.max - p.min);
      }
    }
  }
  std::vector<StudyRun> runs;
  for (const auto& c : combos)
    for (int s = 0; s < n_samples; ++s) {
      StudyRun run;
      run.index = static_cast<int>(runs.size());
      run.model = spec.model;
      run.overrides = spec.fixed;
      for (size_t i = 0; i < np; ++i) {
        const StudyParameter& p = spec.parameters[i];
        if (p.sampled) {
          run.numbers.push_back(samples[s][i]);
          run.values.push_back(number_text(samples[s][i]));
          run.overrides.push_back(p.name + "=" + run.values.back());
        } else if (!p.case_overrides.empty()) {
          run.values.push_back(p.values[c[i]]);
          run.numbers.push_back(std::nan(""));
          if (!p.case_models[c[i]].empty()) run.model = p.case_models[c[i]];
          for (const auto& o : p.case_overrides[c[i]]) run.overrides.push_back(o);
        } else {
          run.values.push_back(p.values[c[i]]);
          run.numbers.push_back(p.numbers[c[i]]);
          run.overrides.push_back(p.name + "=" + p.values[c[i]]);
        }
      }
      runs.push_back(std::move(run));
    }
  return runs;
}

namespace {

/// The channels whose metrics a run records: the study's `keep: channels`, else each clearance
/// joint's Fn (names; a run's model may lack some, see Keep::missing).
std::vector<std::string> metric_channel_names(const Model& model, const StudySpec& spec) {
  std::vector<std::string> names = spec.channels;
  if (names.empty())
    for (const Joint& j : model.joints)
      if (j.clearance) names.push_back(j.name + ".Fn");
  return names;
}

/// Keeps the study's channels at every section and, decimated, at the outputs.
class Keep : public Observer {
 public:
  /// The run starts at t_begin (a continuation run: where the previous one ended).
  Keep(const Model& model, const Workspace& ws, const StudySpec& spec, RunRecord& rec, double t_begin,
       double t_transient)
      : model_(model), rec_(rec), t_transient_(t_transient) {
    const auto info = channel_info(model, ws);
    // A kept channel this run's model lacks (a clearance joint made ideal) is left out of its
    // record; the run keeps everything else.
    auto index = [&](const std::string& n) {
      for (size_t i = 0; i < info.size(); ++i)
        if (info[i].name == n) return static_cast<int>(i);
      return -1;
    };
    for (const auto* group : {&spec.channels, &spec.section_channels, &spec.series})
      for (const auto& c : *group)
        if (index(c) < 0 && std::find(missing.begin(), missing.end(), c) == missing.end()) missing.push_back(c);
    for (const auto& c : spec.section_channels)
      if (const int i = index(c); i >= 0) section_index_.push_back(i), rec_.section_channels.push_back(c);
    for (const auto& c : spec.series)
      if (const int i = index(c); i >= 0) series_index_.push_back(i), rec_.series_channels.push_back(c);
    values_.assign(info.size(), 0.0);
    // The run's outputs, from its start (a continuation run's end_time is counted from t = 0).
    const double n_out =
        std::ceil((model.solver.end_time - t_begin) / model.solver.output_interval - 1e-9) + 1;
    every_ = std::max<long>(1, static_cast<long>(std::ceil(n_out / std::max(1, spec.series_points))));
    rec_.series_values.assign(series_index_.size(), {});
  }
  std::vector<std::string> missing;  ///< kept channels this run's model has not
  void output(double t, const Eigen::VectorXd& y, const Workspace& ws) override {
    if (series_index_.empty() || count_++ % every_ != 0) return;
    channel_values(model_, ws, y, values_.data());
    rec_.series_time.push_back(t);
    for (size_t k = 0; k < series_index_.size(); ++k) rec_.series_values[k].push_back(values_[series_index_[k]]);
  }
  void section(double t, const Eigen::VectorXd& y, const Workspace& ws) override {
    if (section_index_.empty() || t < t_transient_ - 1e-12) return;
    channel_values(model_, ws, y, values_.data());
    rec_.section_times.push_back(t);
    std::vector<double> v;
    for (int i : section_index_) v.push_back(values_[i]);
    rec_.section_values.push_back(std::move(v));
  }

 private:
  const Model& model_;
  RunRecord& rec_;
  double t_transient_;
  std::vector<int> section_index_, series_index_;
  std::vector<double> values_;
  long every_ = 1, count_ = 0;
};

/// The most driver periods a transient may span (AnalysisOptions::discard_periods' range).
constexpr double kMaxDiscardPeriods = 1e6;

/// The end of a run's transient, the run starting at t_begin: `time` seconds when the study gives
/// it, else `periods` periods of the driver (none without one). Throws std::invalid_argument
/// when it is not shorter than the run.
double transient_end(const StudySpec& spec, const Model& model, const Driver* drv, double t_begin) {
  const double period = drv ? 2 * M_PI / std::abs(drv->speed) : 0.0;
  // A transient in periods of a constant-speed driver this run stops (speed 0) has no length:
  // this run's error, not a run whose statistics silently include its start.
  if (spec.discard_time < 0 && spec.discard_periods > 0 && period == 0.0)
    if (const Driver* still = rotary_driver(model, "");
        still && still->profile == DriverProfile::constant_speed && still->speed == 0.0)
      throw std::invalid_argument(fmt::format(
          "driver '{}' does not turn in this run (speed 0), so a transient of {} periods has no "
          "length; give the transient in seconds (transient: {{time: S}})",
          still->name, spec.discard_periods));
  const double t_transient =
      t_begin + (spec.discard_time >= 0 ? spec.discard_time : period > 0 ? spec.discard_periods * period : 0.0);
  if (t_transient >= model.solver.end_time)
    throw std::invalid_argument(fmt::format("the transient ({:.6g} s) is not shorter than the run ({:.6g} s)",
                                            t_transient - t_begin, model.solver.end_time - t_begin));
  // Sections and the verdict start at the first whole period after a transient in seconds; the
  // analyses count at most 1e6 periods (the run's own option said "--discard" here, and past
  // 2^31 periods the count overflowed).
  if (spec.discard_time >= 0 && period > 0 && !(spec.discard_time / period <= kMaxDiscardPeriods))
    throw std::invalid_argument(fmt::format(
        "the transient ({:.6g} s) is {:.6g} periods of the driver at this speed; at most {:.0f} "
        "(sections and the verdict start at the first period after it): give a shorter transient",
        spec.discard_time, spec.discard_time / period, kMaxDiscardPeriods));
  return t_transient;
}

/// A record's message: no trailing white space (a ModelError's text ends in a line end).
std::string trimmed(std::string message) {
  while (!message.empty() && std::isspace(static_cast<unsigned char>(message.back()))) message.pop_back();
  return message;
}

}  // namespace

std::string study_run_error(const StudySpec& spec, const StudyRun& run) {
  try {
    const LoadedModel lm = load_model_text(spec.model_texts.at(run.model), run.model, run.overrides);
    // A continued run lasts end_time from where it starts: its transient is checked the same.
    transient_end(spec, lm.model, period_driver(lm.model, ""), 0.0);
    return "";
  } catch (const ModelError& e) {
    return trimmed(ModelError(study_diagnostics(e.diagnostics(), spec)).what());
  } catch (const std::exception& e) {
    return trimmed(e.what());
  }
}

RunRecord run_study_point(const StudySpec& spec, const StudyRun& run, const std::atomic<int>* interrupt,
                          const RunRecord* previous) {
  RunRecord rec;
  rec.index = run.index;
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  try {
    LoadedModel lm = load_model_text(spec.model_texts.at(run.model), run.model, run.overrides);
    const Driver* drv = period_driver(lm.model, "");
    // Continuation: start where the previous run ended. The driver's angle there, φ₁ = φ₀ + ω₁t₁,
    // is reached at the new speed at t₀ = t₁·ω₁/ω; the run lasts end_time from there.
    std::optional<State> from;
    if (previous) {
      if (previous->final_state.y.size() == 0)
        throw std::invalid_argument("run " + std::to_string(run.previous) +
                                    ", which this run continues, has no final state (" +
                                    previous->status + ")");
      if (!drv || drv->profile != DriverProfile::constant_speed || previous->driver_speed == 0.0 ||
          drv->speed * previous->driver_speed <= 0.0)
        throw std::invalid_argument("continuation needs a constant-speed rotary driver turning the "
                                    "same way in every run");
      const double t0 = previous->final_state.t * previous->driver_speed / drv->speed;
      std::vector<std::string> ov = run.overrides;
      ov.push_back("solver.end_time=" + number_text(t0 + lm.model.solver.end_time));
      lm = load_model_text(spec.model_texts.at(run.model), run.model, ov);
      drv = period_driver(lm.model, "");
      from = previous->final_state;
      from->t = t0;
      from->step = 0.0;
      Workspace pw(lm.model);
      project_state(lm.model, pw, t0, from->y);  // the new speed's velocity constraints
      // A parameter that changed the clearance or the geometry can put a journal deeper in its
      // bearing than contact ever drives it: a spurious force spike at the start, refused. A
      // journal as deep as the previous run left it (a soft contact, a parameter such as the
      // speed) is the state the run reached, and continues.
      Eigen::VectorXd ydot(pw.ny);
      evaluate(lm.model, pw, t0, from->y.data(), ydot.data());
      for (int c = 0; c < pw.nc; ++c) {
        const auto& joint = lm.model.joints[pw.clearance_joints[c]];
        const double depth = pw.clearance_out[c].delta, c_len = joint.clearance->clearance;
        const bool same_gap = static_cast<int>(from->gaps.size()) == pw.nc &&
                              std::abs(depth - from->gaps[c]) <= 1e-9 + 1e-6 * c_len;
        if (depth > 0.1 * c_len && !same_gap)
          throw std::invalid_argument(
              "continuation: the previous run ends with joint '" + joint.name + "' " +
              number_text(depth * 1e3) + " mm into this run's bearing (clearance " +
              number_text(c_len * 1e3) + " mm); the parameter changes the joint, so no run can "
              "start there: continue over speed-like parameters only, or drop continuation");
      }
    }
    const Model& model = lm.model;
    const double t_begin = from ? from->t : 0.0;
    const double period = drv ? 2 * M_PI / std::abs(drv->speed) : 0.0;
    const double t_transient = transient_end(spec, model, drv, t_begin);
    AnalysisOptions ao;
    ao.from = from ? &*from : nullptr;
    ao.ideal_twin = false;
    ao.lyapunov = spec.lyapunov;
    // Sections and the verdict start at the first period at or after the transient.
    ao.discard_periods = spec.discard_time >= 0 && period > 0
                             ? static_cast<int>(std::ceil(spec.discard_time / period - 1e-9))
                             : spec.discard_periods;
    ao.interrupt = interrupt;
    ao.stats_t0 = t_transient;
    ao.display_points = 50;
    // The metrics' channels have their extrema tracked exactly over the window; the others
    // were searched for nothing, twice (here and in an observer of the sweep's own): a two-run
    // Flores study keeping Fn took 762 M instructions, now 540 M, its metrics the same to 2e-13.
    ao.exact_channels = metric_channel_names(model, spec);
    ao.frames = 2;
    Workspace ws(model);
    Keep keep(model, ws, spec, rec, t_begin, t_transient);
    const RunAnalysis ra = analyze_run(model, ao, &keep);
    const RunResult& res = ra.result;
    rec.t_reached = res.status.t;
    rec.steps = res.stats.steps;
    rec.rhs_evaluations = res.stats.rhs_evaluations;
    rec.events = res.stats.events;
    // A signal during the analyses after the run (the Lyapunov trajectories) leaves the run
    // completed and its exponent missing: interrupted as well, not recorded, run again.
    if (res.status.outcome == RunOutcome::interrupted || (interrupt && interrupt->load() != 0)) {
      rec.status = "interrupted";
      rec.message = res.status.outcome == RunOutcome::interrupted
                        ? res.status.message
                        : "interrupted during the analyses after the run";
      rec.wall_seconds = elapsed();
      return rec;
    }
    // Only a completed run hands its state on: a failed one stopped where the integrator could
    // not go on, not where the model was at its end time; the chain is an error from there.
    if (!spec.continuation.empty() && res.status.ok) {
      rec.final_state = res.final_state;
      rec.driver_speed = drv ? drv->speed : 0.0;
    }
    rec.status = res.status.ok ? "completed" : "failed";
    // As `lash run` says it: where the run stopped (t_reached, which runs.csv leaves out).
    rec.message = res.status.ok ? "" : "stopped at t = " + number_text(res.status.t) + " s: " +
                                           res.status.message;
    if (!keep.missing.empty()) {
      std::string list;
      for (const auto& c : keep.missing) list += (list.empty() ? "" : ", ") + c;
      rec.message += (rec.message.empty() ? "" : "; ") + std::string("not in this run's model, not kept: ") + list;
    }
    // What `lash run` would print as warnings (a stiff model for DOPRI5, redundant joints
    // dropped, the stabilization's work): a study of thousands of runs keeps them per run.
    for (const std::string& w : res.warnings)
      rec.message += (rec.message.empty() ? "" : "; ") + std::string("warning: ") + w;
    rec.verdict = ra.verdict.kind;
    // Metrics: the kept channels (default: each clearance joint's Fn), the clearance joints'
    // contact modes, the verdict's numbers; all after the transient.
    const std::vector<std::string> channels = metric_channel_names(model, spec);
    // Peaks, max and min exact (between outputs too, docs/analysis.md: the statistics' exact
    // extrema over the window after the transient); rms from the outputs.
    for (const auto& name : channels)
      for (const auto& s : ra.statistics)
        if (s.channel == name) {
          const double mx = s.max, mn = s.min;
          rec.metrics.push_back({name + ".peak", std::max(std::abs(mx), std::abs(mn))});
          rec.metrics.push_back({name + ".max", mx});
          rec.metrics.push_back({name + ".min", mn});
          rec.metrics.push_back({name + ".rms", s.rms});
        }
    for (const auto& c : ra.clearance) {
      // A run that ended in its transient has no contact metrics, as it has no peaks.
      if (!c.modes_in_window) continue;
      double vmax = 0;
      for (double v : c.modes.impact_velocities) vmax = std::max(vmax, std::abs(v));
      rec.metrics.push_back({c.joint + ".impacts", static_cast<double>(c.modes.impacts)});
      rec.metrics.push_back({c.joint + ".impact_share", c.modes.impact_share});
      rec.metrics.push_back({c.joint + ".continuous_share", c.modes.continuous_share});
      rec.metrics.push_back({c.joint + ".free_flight_share", c.modes.free_flight_share});
      rec.metrics.push_back({c.joint + ".max_impact_velocity", vmax});
    }
    rec.metrics.push_back({"sections", static_cast<double>(ra.verdict.sections)});
    rec.metrics.push_back({"distinct_points", static_cast<double>(ra.verdict.distinct_points)});
    if (!std::isnan(ra.verdict.lyapunov_exponent))
      rec.metrics.push_back({"lyapunov_exponent", ra.verdict.lyapunov_exponent});
    else if (spec.lyapunov && res.status.ok)
      rec.message += (rec.message.empty() ? "" : "; ") + std::string("no Lyapunov exponent: ") +
                     (ra.lyapunov && !ra.lyapunov->message.empty() ? ra.lyapunov->message
                                                                     : "not computed");
  } catch (const ModelError& e) {
    rec.status = "error";
    rec.message = ModelError(study_diagnostics(e.diagnostics(), spec)).what();
  } catch (const std::exception& e) {
    rec.status = "error";
    rec.message = e.what();
  }
  rec.message = trimmed(rec.message);
  rec.wall_seconds = elapsed();
  return rec;
}

nlohmann::json state_json(const State& st) {
  if (st.y.size() == 0) return nullptr;
  std::vector<bool> modes;
  for (const auto& m : st.modes) modes.push_back(m.in_contact);
  return {{"t", st.t}, {"y", std::vector<double>(st.y.data(), st.y.data() + st.y.size())},
          {"in_contact", modes}, {"step", st.step}, {"gaps", st.gaps}};
}

State state_from_json(const nlohmann::json& j) {
  State st;
  if (j.is_null()) return st;
  st.t = j.at("t");
  const auto y = j.at("y").get<std::vector<double>>();
  st.y = Eigen::Map<const Eigen::VectorXd>(y.data(), static_cast<Eigen::Index>(y.size()));
  for (bool c : j.at("in_contact").get<std::vector<bool>>()) st.modes.push_back(ContactState{c});
  st.step = j.at("step");
  if (j.contains("gaps")) st.gaps = j.at("gaps").get<std::vector<double>>();
  return st;
}

nlohmann::json to_json(const RunRecord& r) {
  nlohmann::json m = nlohmann::json::array();
  for (const auto& [k, v] : r.metrics) m.push_back({k, v});
  return {{"index", r.index},
          {"status", r.status},
          {"message", r.message},
          {"t_reached", r.t_reached},
          {"wall_seconds", r.wall_seconds},
          {"steps", r.steps},
          {"rhs_evaluations", r.rhs_evaluations},
          {"events", r.events},
          {"verdict", r.verdict},
          {"metrics", m},
          {"section_channels", r.section_channels},
          {"section_times", r.section_times},
          {"section_values", r.section_values},
          {"series_channels", r.series_channels},
          {"series_time", r.series_time},
          {"series_values", r.series_values},
          {"final_state", state_json(r.final_state)},
          {"driver_speed", r.driver_speed}};
}

RunRecord record_from_json(const nlohmann::json& j) {
  RunRecord r;
  r.index = j.at("index");
  r.status = j.at("status");
  r.message = j.at("message");
  r.t_reached = j.at("t_reached");
  r.wall_seconds = j.at("wall_seconds");
  r.steps = j.at("steps");
  r.rhs_evaluations = j.at("rhs_evaluations");
  r.events = j.at("events");
  r.verdict = j.at("verdict");
  for (const auto& m : j.at("metrics")) r.metrics.push_back({m.at(0).get<std::string>(), m.at(1).get<double>()});
  r.section_channels = j.at("section_channels").get<std::vector<std::string>>();
  r.section_times = j.at("section_times").get<std::vector<double>>();
  r.section_values = j.at("section_values").get<std::vector<std::vector<double>>>();
  r.series_channels = j.at("series_channels").get<std::vector<std::string>>();
  r.series_time = j.at("series_time").get<std::vector<double>>();
  r.series_values = j.at("series_values").get<std::vector<std::vector<double>>>();
  r.final_state = state_from_json(j.at("final_state"));
  r.driver_speed = j.at("driver_speed");
  return r;
}

}  // namespace lash
