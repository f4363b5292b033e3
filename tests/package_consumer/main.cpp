// Loads a model file with Lash's loader and simulates a few milliseconds of it; prints the
// number of outputs and the largest |slider.ax|. Usage: consumer MODEL.yaml
#include <lash/core/elements/registry.hpp>  // either include style works: <lash/...> ...
#include "core/simulate.hpp"                // ... or as Lash's own sources write it
#include "io/model_loader.hpp"

#include <cmath>
#include <iostream>

namespace {
class PeakObserver : public lash::Observer {
 public:
  PeakObserver(const lash::Model& m, int channel) : model_(m), channel_(channel) {}
  void output(double, const Eigen::VectorXd& y, const lash::Workspace& ws) override {
    values_.resize(lash::channel_info(model_, ws).size());
    lash::channel_values(model_, ws, y, values_.data());
    peak = std::max(peak, std::abs(values_[channel_]));
    ++outputs;
  }
  double peak = 0.0;
  long outputs = 0;

 private:
  const lash::Model& model_;
  int channel_;
  std::vector<double> values_;
};
}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: consumer MODEL.yaml\n";
    return 2;
  }
  try {
    lash::LoadedModel loaded = lash::load_model_file(argv[1], {"solver.end_time=0.003"});
    const lash::Model& model = loaded.model;
    lash::Workspace ws(model);
    const auto channels = lash::channel_info(model, ws);
    int ax = -1;
    for (size_t i = 0; i < channels.size(); ++i)
      if (channels[i].name == "slider.ax") ax = static_cast<int>(i);
    if (ax < 0) {
      std::cerr << "no channel slider.ax\n";
      return 1;
    }
    PeakObserver obs(model, ax);
    const lash::RunResult r = lash::simulate(model, ws, obs);
    std::cout << "outcome " << lash::outcome_name(r.status.outcome) << " outputs " << obs.outputs
              << " peak slider.ax " << obs.peak << " m/s^2\n";
    return r.status.ok && obs.outputs == 301 && obs.peak > 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
}
