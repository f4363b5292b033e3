#include "io/state_file.hpp"

#include "core/elements/clearance_revolute.hpp"
#include "io/files.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <unordered_set>

namespace lash {

namespace {
constexpr const char* kFormat = "lash-state-1";
}

void write_state(const std::string& path, const Model& model, const Workspace& ws,
                 const State& state) {
  using nlohmann::json;
  json j;
  j["format"] = kFormat;
  j["model"] = model.name;
  j["t"] = state.t;
  j["step"] = state.step;
  j["names"] = state_names(model, ws);
  j["y"] = std::vector<double>(state.y.data(), state.y.data() + state.y.size());
  json modes = json::object();
  for (int k = 0; k < ws.nc; ++k)
    modes[model.joints[ws.clearance_joints[k]].name] = state.modes[k].in_contact ? 1 : 0;
  j["modes"] = modes;
  // Each clearance joint's gap δ (m) as saved: a run continued under another clearance or
  // geometry is then told so (resume_warnings).
  json gaps = json::object();
  for (int k = 0; k < ws.nc; ++k) {
    double delta, delta_dot;
    clearance_gap(model, ws, k, state.y.data(), delta, delta_dot);
    gaps[model.joints[ws.clearance_joints[k]].name] = delta;
  }
  j["gaps"] = gaps;
  write_file_atomic(path, j.dump(1, ' ', false, json::error_handler_t::replace) + "\n");
}

State read_state(const std::string& path, const Model& model, const Workspace& ws) {
  using nlohmann::json;
  auto fail = [&](const std::string& what) {
    return std::runtime_error(path + ": " + what);
  };
  std::string text;
  try {
    text = read_input_file(path, kMaxModelFileBytes);
  } catch (const IoError&) {  // cannot be read (no such file, no permission): as it is
    throw;
  } catch (const std::exception& e) {
    throw std::runtime_error(e.what());
  }
  json j;
  // A key written twice in one object (a file edited by hand) is refused: the JSON library keeps
  // the last, so the first would be silently ignored.
  std::vector<std::unordered_set<std::string>> keys;  // per open object, its keys so far
  std::string twice;
  const json::parser_callback_t check = [&](int, json::parse_event_t event, json& parsed) {
    if (event == json::parse_event_t::object_start) keys.emplace_back();
    else if (event == json::parse_event_t::object_end) keys.pop_back();
    else if (event == json::parse_event_t::key && !keys.empty()) {
      std::string k = parsed.get<std::string>();
      if (!keys.back().insert(k).second && twice.empty()) twice = std::move(k);
    }
    return true;
  };
  try {
    j = json::parse(text, check);
  } catch (const json::exception& e) {
    throw fail(std::string("not a valid state file (JSON): ") + e.what());
  }
  if (!twice.empty())
    throw fail("'" + twice + "' is given twice in one object (a file edited by hand?); keep one");
  if (!j.is_object() || j.value("format", "") != kFormat)
    throw fail(std::string("not a Lash state file (expected \"format\": \"") + kFormat + "\")");
  State st;
  // Each entry checked by name: "'t' must be a number (s), got \"x\"", not a JSON library's
  // "type must be number, but is string".
  auto member = [&](const char* key) -> const json& {
    if (!j.contains(key)) throw fail(std::string("'") + key + "' is missing");
    return j.at(key);
  };
  auto list_of = [&](const char* key, bool numbers) {
    const json& v = member(key);
    if (!v.is_array())
      throw fail(std::string("'") + key + "' must be a list of " + (numbers ? "numbers" : "names") +
                 ", got " + v.dump().substr(0, 40));
    for (size_t i = 0; i < v.size(); ++i)
      if (numbers ? !v[i].is_number() : !v[i].is_string())
        throw fail(std::string("entry ") + std::to_string(i) + " of '" + key + "' must be a " +
                   (numbers ? "number" : "name") + ", got " + v[i].dump().substr(0, 40));
    return v;
  };
  try {
    if (!member("t").is_number()) throw fail("'t' must be a number (s), got " + j.at("t").dump().substr(0, 40));
    st.t = j.at("t").get<double>();
    if (j.contains("step") && !j.at("step").is_number())
      throw fail("'step' must be a number (s), got " + j.at("step").dump().substr(0, 40));
    st.step = j.value("step", 0.0);
    if (j.contains("model")) {  // the name of the model that wrote it (a warning if another)
      if (!j.at("model").is_string())  // ("" is the name of a model named "")
        throw fail("'model' must be the name of the model that wrote the state, got " +
                   j.at("model").dump().substr(0, 40));
      st.model = j.at("model").get<std::string>();
    } else {
      st.file_names_no_model = true;
    }
    if (!std::isfinite(st.step) || st.step < 0)
      throw fail("'step' must be a finite step size >= 0 s, got " + j.at("step").dump());
    const auto names = list_of("names", false).get<std::vector<std::string>>();
    const auto y = list_of("y", true).get<std::vector<double>>();
    const auto expected = state_names(model, ws);
    if (names.size() != y.size()) throw fail("'names' and 'y' differ in length");
    if (names != expected) {
      std::string diff;
      for (size_t i = 0; i < std::max(names.size(), expected.size()) && diff.empty(); ++i) {
        const std::string a = i < names.size() ? names[i] : "(nothing)";
        const std::string b = i < expected.size() ? expected[i] : "(nothing)";
        if (a != b)
          diff = "entry " + std::to_string(i) + " is '" + a + "' in the state but '" + b +
                 "' in the model";
      }
      throw fail("the state does not match the model: " + diff + " (" +
                 std::to_string(names.size()) + " entries in the state, " +
                 std::to_string(expected.size()) + " in the model)");
    }
    st.y = Eigen::Map<const Eigen::VectorXd>(y.data(), static_cast<Eigen::Index>(y.size()));
    const json& modes = member("modes");
    if (!modes.is_object())
      throw fail("'modes' must map each clearance joint to 1 (contact) or 0 (free flight), got " +
                 modes.dump().substr(0, 40));
    for (int k = 0; k < ws.nc; ++k) {
      const std::string& name = model.joints[ws.clearance_joints[k]].name;
      if (!modes.contains(name))
        throw fail("the state has no contact mode for clearance joint '" + name +
                   "' (was it a clearance joint in the run that wrote it?)");
      const json& mode = modes.at(name);
      if (!mode.is_number_integer() || (mode.get<int>() != 0 && mode.get<int>() != 1))
        throw fail("the contact mode of clearance joint '" + name +
                   "' must be 1 (contact) or 0 (free flight), got " + mode.dump());
      st.modes.push_back({mode.get<int>() == 1});
    }
    if (j.contains("gaps")) {  // optional (older state files have none)
      const json& gaps = j.at("gaps");
      if (!gaps.is_object()) throw fail("'gaps' must map each clearance joint to its gap (m)");
      for (int k = 0; k < ws.nc; ++k) {
        const std::string& name = model.joints[ws.clearance_joints[k]].name;
        if (!gaps.contains(name)) break;  // another set of joints: the modes say what differs
        const json& g = gaps.at(name);
        if (!g.is_number() || !std::isfinite(g.get<double>()))
          throw fail("the gap of clearance joint '" + name + "' must be a finite number (m), got " +
                     g.dump());
        st.gaps.push_back(g.get<double>());
      }
      if (static_cast<int>(st.gaps.size()) != ws.nc) st.gaps.clear();
    }
    if (static_cast<int>(modes.size()) != ws.nc)
      throw fail("the state has " + std::to_string(modes.size()) +
                 " contact modes but the model has " + std::to_string(ws.nc) +
                 " clearance joints");
  } catch (const json::exception& e) {
    throw fail(std::string("a value is missing or has the wrong type: ") + e.what());
  }
  if (const std::string bad = state_mismatch(ws, st); !bad.empty()) throw fail(bad);
  return st;
}

}  // namespace lash
