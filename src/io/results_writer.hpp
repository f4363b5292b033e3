#pragma once
/// @file results_writer.hpp
/// Streams a run's results into an output folder: timeseries.csv (one column per channel
/// `<element>.<quantity>`), events.csv (contact onsets and separations) and summary.json
/// (per-channel peaks, per-joint contact statistics, integrator statistics, model and settings).
/// Rows are flushed as they come, so a failed run keeps everything written before the failure.
#include <fmt/format.h>

#include <cstdio>
#include <string>
#include <vector>

#include "core/elements/registry.hpp"
#include "core/simulate.hpp"

namespace lash {

class ResultsWriter : public Observer {
 public:
  /// Creates `folder` if needed; throws std::runtime_error if it cannot be written.
  ResultsWriter(const Model& model, const std::string& folder);
  ~ResultsWriter() override;

  void output(double t, const Eigen::VectorXd& y, const Workspace& ws) override;
  void event(const ContactEvent& e, const Workspace& ws) override;

  /// Writes summary.json (with every channel's unit and description) and final_state.json, and
  /// closes the files. `resolved_yaml` is the model as run.
  /// `from` names the state file the run continued from ("" for a run from t = 0).
  void finish(const RunResult& result, const std::string& resolved_yaml,
              const std::vector<std::string>& overrides, const std::string& from = "");

 private:
  struct Peak {
    double min = 0, max = 0, t_min = 0, t_max = 0;
  };
  struct JointStats {
    long impacts = 0, separations = 0;
    double contact_time = 0.0, onset_time = 0.0, max_impact_velocity = 0.0;
    bool in_contact = false;
  };
  void append_number(double v);  ///< %.9g into row_

  const Model& model_;
  std::string folder_;
  std::FILE* ts_ = nullptr;
  std::FILE* ev_ = nullptr;
  std::vector<ChannelInfo> channels_;
  std::vector<double> values_;
  fmt::memory_buffer row_;
  std::vector<Peak> peaks_;
  std::vector<JointStats> joints_;
  long rows_ = 0;
  double t_first_ = 0.0, t_last_ = 0.0;
};

}  // namespace lash
