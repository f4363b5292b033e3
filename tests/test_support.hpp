#pragma once
// Helpers shared by the tests: load a model from text, run it, keep channels in memory.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "core/simulate.hpp"
#include "io/model_loader.hpp"
#include "io/results_writer.hpp"

namespace lash::test {

inline std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline std::string example_path(const std::string& name) {
  return std::string(LASH_SOURCE_DIR) + "/examples/" + name;
}

/// Keeps every channel of every output in memory (tests only: runs are short).
class Recorder : public Observer {
 public:
  explicit Recorder(const Model& m) : model_(m) {
    for (const auto& c : channel_info(m, Workspace(m))) names_.push_back(c.name);
    values_.resize(names_.size());
  }
  void output(double t, const Eigen::VectorXd& y, const Workspace& ws) override {
    channel_values(model_, ws, y, values_.data());
    time.push_back(t);
    for (size_t i = 0; i < names_.size(); ++i) data[names_[i]].push_back(values_[i]);
  }
  void event(const ContactEvent& e, const Workspace&) override { events.push_back(e); }
  const std::vector<double>& operator[](const std::string& name) const {
    auto it = data.find(name);
    if (it == data.end()) throw std::runtime_error("no channel " + name);
    return it->second;
  }
  std::vector<double> time;
  std::map<std::string, std::vector<double>> data;
  std::vector<ContactEvent> events;

 private:
  const Model& model_;
  std::vector<std::string> names_;
  std::vector<double> values_;
};

struct SimRun {
  Model model;
  RunResult result;
  std::unique_ptr<Recorder> rec;
};

inline SimRun run_text(const std::string& yaml, const std::vector<std::string>& overrides = {}) {
  SimRun r;
  r.model = load_model_text(yaml, "test.yaml", overrides).model;
  Workspace ws(r.model);
  r.rec = std::make_unique<Recorder>(r.model);
  r.result = simulate(r.model, ws, *r.rec);
  return r;
}

inline SimRun run_example(const std::string& name, const std::vector<std::string>& overrides = {}) {
  return run_text(read_file(example_path(name)), overrides);
}

inline double max_abs_diff(const std::vector<double>& a, const std::vector<double>& b,
                           size_t n = static_cast<size_t>(-1)) {
  double m = 0;
  for (size_t i = 0; i < std::min({a.size(), b.size(), n}); ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}

/// A parallelogram linkage under gravity: `cranks` unit cranks (mass m, inertia I about the
/// centre) pivoted on the ground at x = 0, 1, 2, … and pinned to one rigid coupler, released at
/// rest at −30° (it swings between −30° and −150°, clear of the in-line positions 0 and 180°).
/// With three cranks one equation is redundant. `first_crank_scale` multiplies the
/// first crank's mass and inertia: every crank has the same angle, speed and height, so two
/// cranks with the first doubled move exactly as three. `world_turn` (rad) turns the whole
/// model, gravity included, about the origin: the same motion seen in turned axes.
inline std::string parallelogram_yaml(int cranks, double first_crank_scale, double th = -M_PI / 6,
                                      double world_turn = 0.0) {
  const double c = std::cos(th), s = std::sin(th), m = 1.0, inertia = 1.0 / 12;
  const double cw = std::cos(world_turn), sw = std::sin(world_turn);
  // Turned: every number to 17 digits (a loop closed to 1e-6 m locks a redundant linkage).
  auto num = [&](double v) {
    if (world_turn == 0.0) return std::to_string(v);
    char b[32];
    std::snprintf(b, sizeof b, "%.17g", v);
    return std::string(b);
  };
  auto point = [&](double x, double y) {
    return "[" + num(cw * x - sw * y) + ", " + num(sw * x + cw * y) + "]";
  };
  std::string y = "gravity: " + point(0, -9.81) + "\nground:\n  markers: {";
  for (int i = 0; i < cranks; ++i)
    y += (i ? ", G" : "G") + std::to_string(i) + ": " +
         (world_turn == 0.0 ? "[" + std::to_string(i) + ", 0]" : point(i, 0));
  y += "}\nbodies:\n";
  for (int i = 0; i < cranks; ++i) {
    const double k = i == 0 ? first_crank_scale : 1.0;
    y += "  crank_" + std::to_string(i) + ": {mass: " + std::to_string(k * m) +
         ", inertia: " + std::to_string(k * inertia) + ", position: " + point(i + 0.5 * c, 0.5 * s) +
         ", angle: " + num(th + world_turn) + ", markers: {O: [-0.5, 0], A: [0.5, 0]}}\n";
  }
  const double half = 0.5 * (cranks - 1);
  y += "  coupler: {mass: 2, inertia: 0.5, position: " + point(half + c, s) +
       ", angle: " + num(world_turn) + ", markers: {";
  for (int i = 0; i < cranks; ++i) y += (i ? ", P" : "P") + std::to_string(i) + ": [" + std::to_string(i - half) + ", 0]";
  y += "}}\njoints:\n";
  for (int i = 0; i < cranks; ++i) {
    const std::string n = std::to_string(i);
    y += "  pivot_" + n + ": {type: revolute, journal: crank_" + n + ".O, bearing: ground.G" + n + "}\n";
    y += "  coupler_" + n + ": {type: revolute, journal: crank_" + n + ".A, bearing: coupler.P" + n + "}\n";
  }
  y += "solver: {end_time: 2, output_interval: 0.01, rtol: 1.0e-9, atol: 1.0e-12}\n";
  return y;
}

/// A 1 kg puck released 1 mm from rest on a 1 N/m spring with a 1e6 N·s/m damper: λ = −c/m =
/// −1e6 1/s makes it stiff for DOPRI5 (steps of 3.3e-6 s for 0.05 s), not for BDF.
inline const char* const kStiffPuck = R"Y(
gravity: [0, 0]
bodies:
  puck: {mass: 1, inertia: 1, position: [0.001, 0], markers: {O: [0, 0]}}
ground: {markers: {O: [0, 0]}}
loads:
  tie: {type: spring_damper, from: ground.O, to: puck.O, stiffness: 1, damping: 1e6, free_length: 0}
solver: {end_time: 0.05, output_interval: 1e-3, initial_state: given, rtol: 1e-6, atol: 1e-9}
)Y";

}  // namespace lash::test
