#pragma once
/// @file sweep.hpp
/// Parameter studies: a study file (docs/studies.md) names a base model, the model values to
/// vary (by path, as `--set` does), how to combine them, and what to keep from each run. This
/// file turns it into a list of runs and runs one of them into a RunRecord: status, metrics,
/// the chosen channels at the Poincaré sections after the transient (the bifurcation diagram's
/// points) and decimated series. Scheduling (threads, MPI) and the database are the caller's.
#include <atomic>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/simulate.hpp"
#include "nlohmann/json.hpp"

namespace lash {

/// One varied model value.
struct StudyParameter {
  std::string name;                  ///< the model path (drivers.crank.speed_rpm) or a case name
  std::vector<std::string> values;   ///< override texts, one per level ("3000", "hertz")
  std::vector<double> numbers;       ///< the same as numbers (NaN for text values)
  double min = 0.0, max = 0.0;       ///< sampled parameters: the range
  bool sampled = false;              ///< drawn by `sampling` between min and max
  bool log = false;                  ///< sampled on a logarithmic scale
  /// Cases: each level is a named set of overrides (and optionally another model file).
  std::vector<std::vector<std::string>> case_overrides;
  std::vector<std::string> case_models;  ///< "" = the study's model
};

struct StudySpec {
  std::string file;                  ///< the study file, as named on the command line
  std::string text;                  ///< its text
  std::string name;
  std::string model;                 ///< the base model file (resolved against the study's folder)
  std::map<std::string, std::string> model_texts;  ///< every model file the study uses, by path
  std::vector<std::string> fixed;    ///< overrides applied to every run ("a.b=v")
  std::vector<StudyParameter> parameters;
  std::string combine = "cross";     ///< cross (every combination) or zip (level by level)
  std::string sampling;              ///< "", random or latin_hypercube
  int samples = 0;
  unsigned long long seed = 1;
  std::vector<std::string> channels;          ///< metrics (peak, max, min, rms) of these channels
  std::vector<std::string> section_channels;  ///< channels kept at each Poincaré section
  std::vector<std::string> series;            ///< channels kept as decimated series
  int series_points = 200;
  int discard_periods = 5;           ///< transient: periods of the period driver skipped
  /// Transient in s (`transient: {time: S}`); when >= 0 it is used whether or not the model has a
  /// period driver (then the verdict's sections start at the first period at or after it).
  double discard_time = -1.0;
  bool lyapunov = false;
  /// "", up, down or both: each run starts from the previous run's final state (one parameter,
  /// its levels in order; both: up, then down), to reveal hysteresis. docs/studies.md.
  std::string continuation;
  /// Override path → line and column (1-based) of the key that sets it in the study file, so a
  /// run's model error points into the study rather than at "--set".
  std::map<std::string, std::pair<int, int>> path_marks;
};

/// Reads `text`, the study file `file`; `read(path)` returns the text of a model file it names
/// (paths resolved against the study file's folder). Throws ModelError with file:line:column for
/// every problem found, including the base model's own and parameter paths it does not have.
StudySpec load_study_text(const std::string& text, const std::string& file,
                          const std::function<std::string(const std::string&)>& read);
/// As load_study_text, reading the files from disk.
StudySpec load_study_file(const std::string& file);

/// One run of a study: its index (stable: the study's runs in a fixed order), the level of each
/// parameter, and the overrides that make its model.
struct StudyRun {
  int index = 0;
  std::vector<std::string> values;    ///< per parameter, as written into the model (case name for cases)
  std::vector<double> numbers;        ///< per parameter, NaN for text
  std::string model;                  ///< model file
  std::vector<std::string> overrides; ///< fixed ones first
  int previous = -1;                  ///< continuation: the run whose final state this one starts from
};
/// The columns a run's parameter values fill (StudyRun::values): the parameters' names, and
/// "direction" (up/down) in a continuation study.
std::vector<std::string> parameter_columns(const StudySpec& spec);

/// Every run of the study, in index order. Sampled parameters are drawn from `seed` with a
/// generator whose sequence is fixed here (not the standard library's distributions), so a study
/// gives the same runs on every machine.
std::vector<StudyRun> study_runs(const StudySpec& spec);

/// What a study keeps of one run.
struct RunRecord {
  int index = 0;
  std::string status;                 ///< completed, failed (integrator), error (model, parameters)
  std::string message;                ///< why it failed
  double t_reached = 0.0;             ///< s
  double wall_seconds = 0.0;
  long steps = 0, rhs_evaluations = 0, events = 0;
  std::string verdict;                ///< periodic, quasi-periodic, chaotic, undetermined, or ""
  std::vector<std::pair<std::string, double>> metrics;  ///< in a fixed order
  std::vector<std::string> section_channels;
  std::vector<double> section_times;               ///< s, after the transient
  std::vector<std::vector<double>> section_values; ///< [section][channel]
  std::vector<std::string> series_channels;
  std::vector<double> series_time;
  std::vector<std::vector<double>> series_values;  ///< [channel][sample]
  /// Continuation studies: where the run ended (the next run starts there) and the period
  /// driver's speed it ran at (rad/s). Empty y: not kept.
  State final_state;
  double driver_speed = 0.0;
};
nlohmann::json to_json(const RunRecord& r);
/// A State as JSON (null when empty), doubles exactly; and back.
nlohmann::json state_json(const State& state);
State state_from_json(const nlohmann::json& j);
RunRecord record_from_json(const nlohmann::json& j);

/// What the sweep would record as the run's error before simulating it: its model refused (a
/// value the study gives, pointed at the study's key) or its transient not shorter than the run;
/// "" when it would start. A continued run is checked as if it started at t = 0 (it runs for
/// end_time from where the run before it ends); whether that run ends well is not known here.
/// `lash check` of a study.
std::string study_run_error(const StudySpec& spec, const StudyRun& run);

/// Runs one point of the study. Never throws for a bad parameter combination or a failing run:
/// the record says what happened. `interrupt` (a signal number when set) stops the run within
/// one integrator step; the record is then "interrupted" and must not be kept.
/// With `previous` (a continuation study), the run starts from the previous run's final state:
/// at the time t₀ = t₁·ω₁/ω where the constant-speed driver's angle is the one it ended at, its
/// velocities projected onto the new speed's constraints, and runs for end_time from there.
RunRecord run_study_point(const StudySpec& spec, const StudyRun& run,
                          const std::atomic<int>* interrupt = nullptr,
                          const RunRecord* previous = nullptr);

}  // namespace lash
