#pragma once
// Helpers shared by the tests: load a model from text, run it, keep channels in memory.
#include <gtest/gtest.h>

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

}  // namespace lash::test
