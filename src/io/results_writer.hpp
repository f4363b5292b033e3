#pragma once
/// @file results_writer.hpp
/// Streams a run's results into an output folder: timeseries.csv (one column per channel
/// `<element>.<quantity>`, 9 significant digits) or, with OutputFormat::hdf5, timeseries.h5
/// (io/hdf5_series.hpp, every double in full), of the selected channels (io/channel_select.hpp);
/// events.csv (contact onsets and separations) and summary.json
/// (per-channel peaks, per-joint contact statistics, integrator statistics, model and settings).
/// A run folder holds one run: the outputs of an earlier run are removed first (summary.json
/// before anything else, so no stale summary ever stands beside new rows). Rows reach the disk
/// whole (io/files.hpp RowFile); a failed write stops the run (Observer::stop_reason) with the
/// rows before it intact, and summary.json, written last and atomically, says what happened.
#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "core/elements/registry.hpp"
#include "core/extrema.hpp"
#include "core/simulate.hpp"
#include "io/channel_select.hpp"
#include "io/files.hpp"
#include "io/hdf5_series.hpp"

namespace lash {

/// summary.json's "solver" block: the integrator and its settings as run.
nlohmann::json solver_summary(const Model& model);
/// The parameters summary.json gives per clearance joint beside its contact statistics
/// (clearance, stiffness, normal and friction law).
nlohmann::json clearance_parameters(const Joint& joint);
/// summary.json's "peaks" block: how the channels' extrema were found.
nlohmann::json peaks_summary(const ChannelExtrema& extrema);

class ResultsWriter : public Observer {
 public:
  /// Creates `folder` if needed, removes an earlier run's outputs and writes model_resolved.yaml
  /// (`resolved_yaml`, the model as run). `overrides` are the --set values; `from` names the
  /// state file the run continues from ("" for a run from t = 0); `output` the channels and
  /// the format of the time series. Throws IoError; std::invalid_argument, before the folder
  /// is touched, for a channel pattern that matches nothing or HDF5 in a build without it.
  ResultsWriter(const Model& model, const std::string& folder, const std::string& resolved_yaml,
                std::vector<std::string> overrides = {}, std::string from = "",
                OutputSettings output = {});

  void output(double t, const Eigen::VectorXd& y, const Workspace& ws) override;
  void event(const ContactEvent& e, const Workspace& ws) override;
  /// Peaks are tracked between outputs too (core/extrema.hpp), so summary.json's min/max/peak
  /// do not depend on the output interval.
  bool wants_steps() const override { return true; }
  void step(double t0, double t1, const Eigen::VectorXd& y, const Workspace& ws,
            StepProbe& probe) override {
    extrema_.step(t0, t1, y, ws, probe);
  }
  /// The first write error, once one happened: the run stops at its next output.
  std::string stop_reason() const override { return write_error_; }
  /// After finish: the time of the last row of the time series on disk (NaN when there is
  /// none). Below the run's last output time when a write failed.
  double last_row_time() const { return last_row_time_; }

  /// Closes the time series and the events (their last rows reach the disk) and writes
  /// final_state.json: before anything reads them (the report's figures). A failure is recorded
  /// (stop_reason) for finish to report. Only the first call does anything.
  void close_files(const RunResult& result);

  /// close_files, then, last and atomically, summary.json (with every channel's unit and
  /// description). Returns the run's status as recorded: `result`'s, or write_error if a write
  /// failed. Throws IoError only when summary.json itself cannot be written; then, on a full
  /// disk (ENOSPC, EDQUOT), the last rows of the CSV make room for it first (not for a file-size
  /// limit, EFBIG: that is per file). May be called again after it threw.
  RunStatus finish(const RunResult& result);

  /// Adds `key` (e.g. "verdict" of a run analysed as it ran) to summary.json.
  void add_to_summary(const std::string& key, nlohmann::json value) { extra_[key] = std::move(value); }

  /// Output files of a run, removed before a new run writes into the same folder.
  static const std::vector<std::string>& run_files();

 private:
  struct JointStats {
    long impacts = 0, separations = 0;
    double contact_time = 0.0, onset_time = 0.0, max_impact_velocity = 0.0;
    bool in_contact = false;
  };
  void write_rows(RowFile& file, std::string_view rows);  ///< records the first error
  /// After the time series has written a block out: the events buffered so far too, so that a
  /// killed run or a full disk leaves both files up to about the same time.
  void flush_events_with_series();
  long long series_rows_out_ = 0;  ///< the series' rows on disk when the events last followed
  void write_series_row(double t);  ///< the selected values_ to timeseries.csv or .h5

  const Model& model_;
  std::string folder_;
  std::string resolved_yaml_;
  std::vector<std::string> overrides_;
  std::string from_;
  RowFile ts_, ev_;
  std::string write_error_;
  double last_row_time_ = std::nan("");
  nlohmann::json extra_ = nlohmann::json::object();
  std::vector<ChannelInfo> channels_;
  OutputSettings output_;
  std::vector<std::size_t> selected_;  ///< indices into channels_ written to the time series
  std::vector<double> picked_;         ///< their values at this output (HDF5)
  std::unique_ptr<Hdf5Series> h5_;     ///< with OutputFormat::hdf5, instead of the CSV
  std::vector<double> values_;
  /// One CSV row: room for time and every selected value at kG9MaxChars + 1 each, so numbers
  /// are formatted straight into it.
  std::vector<char> row_;
  ChannelExtrema extrema_;
  std::vector<JointStats> joints_;
  long rows_ = 0;
  double t_first_ = 0.0, t_last_ = 0.0;
  bool files_closed_ = false;
};

}  // namespace lash
