#pragma once
/// @file run_analysis.hpp
/// A run with the analyses of a study: the model is simulated with an observer that gathers what
/// the analyses need, beside it the ideal twin (every clearance joint made ideal) and, for the
/// largest Lyapunov exponent, two trajectories restarted from constraint-projected states; the
/// model-free math of src/analysis is applied to them. Results are plain typed structs in SI
/// units with channel names, units and descriptions from `channel_info`; turning them into
/// report_data.json (docs/report-data.md) is io's business (`io/report.hpp`).
#include <array>
#include <atomic>
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "analysis/dynamics_analysis.hpp"
#include "core/elements/registry.hpp"
#include "core/extrema.hpp"
#include "core/math.hpp"
#include "core/simulate.hpp"

namespace lash {

/// What to analyse and how finely to keep it.
struct AnalysisOptions {
  bool ideal_twin = true;           ///< run the model with every clearance joint ideal
  bool lyapunov = true;             ///< estimate the Lyapunov exponents
  /// "variational" (the spectrum, saltation matrices at events) or "two-trajectory" (the
  /// largest exponent from a pair of runs; a cross-check).
  std::string lyapunov_method = "variational";
  double lyapunov_d0 = 0.0;         ///< two-trajectory separation, m (0: 2e-4 × the smallest clearance, ≤ 1e-7)
  std::string poincare_driver;      ///< driver whose period sets the sections ("" = first rotary)
  /// Event-based sections instead of stroboscopic ones: "<body>.<x|y|phi|vx|vy|omega>=V[,down]".
  std::vector<std::string> section_planes;
  /// The period of the motion, s (`--period`); 0: a constant-speed driver's 2π/|ω|, else a
  /// rotary expression driver's mean speed over the run's last half when that is well defined.
  double period = 0.0;
  int discard_periods = 1;          ///< transient periods skipped by sections, spectra, Lyapunov
  std::vector<std::string> fft_channels;   ///< default: translational bodies' ax, each Fn
  /// The channels whose statistics need their exact extrema (tracked between outputs over the
  /// window, core/extrema.hpp); the others' min and max are their samples'. Default (empty):
  /// every channel. A sweep names the channels whose metrics it keeps.
  std::vector<std::string> exact_channels;
  /// The channels the run writes (`lash run --channels`): the analyses of the main run see only
  /// these, as a report from its folder would, and name what they leave out. None: every one.
  std::optional<std::vector<std::string>> channels;
  std::vector<std::pair<std::string, std::string>> phase;  ///< default: each joint's (ex, ey)
  double continuous_contact_time = 0.0;    ///< s; 0: 10% of the period, or 1 ms without one
  size_t display_points = 800;      ///< buckets for decimated series (2 points each)
  size_t frames = 400;              ///< animation frames
  size_t spectrum_points = 1000;    ///< buckets for decimated spectra (2 points each)
  double stats_t0 = -1e300, stats_t1 = 1e300;  ///< statistics window (s)
  /// Statistics only where the crank angle (deg, of the period driver) lies in [a0, a1],
  /// wrapping through 360 when a0 > a1; NaN: everywhere.
  double stats_angle0 = std::nan(""), stats_angle1 = std::nan("");
  /// Checked at every output of the runs (RunOptions::interrupt): a signal stops them there.
  const std::atomic<int>* interrupt = nullptr;
  /// Continue from this state (RunOptions::from) instead of the initial state: the transient is
  /// counted from its time, and there is no ideal twin (it would start elsewhere).
  const State* from = nullptr;
};

/// Throws std::invalid_argument naming the option (as the command line spells it) when one is
/// out of range: a window with T1 <= T0 or not finite, negative discarded periods, a separation
/// that is not a finite positive number. analyze_run() calls it first.
void check_options(const AnalysisOptions& o);

/// Channels on a shared, min/max-decimated time base: each bucket of outputs becomes two points
/// (its first and last time) carrying each channel's extremes in time order, so impact spikes
/// survive display.
struct DecimatedSeries {
  std::vector<double> time;               ///< s
  std::vector<ChannelInfo> channels;      ///< name, unit, description of each column
  std::vector<std::vector<double>> values;  ///< values[channel][sample], SI units
  /// Index of the channel `name` in `channels`, or −1.
  int index(const std::string& name) const;
};

/// One channel of the run against the same channel of the ideal twin, sample by sample.
struct ChannelComparison {
  std::string channel;
  double rms_deviation = 0.0;   ///< sqrt(mean (v − v_ideal)²), channel units
  double max_deviation = 0.0;   ///< max |v − v_ideal|
  double ideal_peak = 0.0;      ///< max |v_ideal| over the whole twin run
  double peak_ratio = 0.0;      ///< peak with clearance (statistics window) / ideal_peak; NaN
                                ///< (null in report_data, None in Python) if that is 0
};

/// The model with every clearance joint made ideal, run to completion.
struct IdealTwin {
  RunResult result;
  /// The twin's channels, decimated with the main run's bucket size (its sample times are the
  /// output grid, so they coincide with `RunAnalysis::series.time` while both runs complete).
  DecimatedSeries series;
  /// Channels of the main run that the twin has too, in the main run's column order.
  std::vector<ChannelComparison> comparison;
};

/// min, max, peak, RMS and crest factor of one channel over the statistics window.
struct ChannelStatistics {
  std::string channel;
  long samples = 0;
  double min = 0.0, max = 0.0, peak = 0.0, rms = 0.0, crest = 0.0;
  double t_min = 0.0, t_max = 0.0;  ///< when min and max occurred, s
  /// min, max, peak (and crest = peak / RMS) are exact: tracked between outputs on the dense
  /// output over the window (core/extrema.hpp). False over a crank-angle range: there they are
  /// the output samples' (RMS always is: it needs the uniform grid).
  bool exact = false;
  double t0 = 0.0, t1 = 0.0;    ///< the time window clipped to [0, end_time], s
  /// The crank-angle range (deg) the statistics were restricted to; NaN: none.
  double angle0_deg = std::nan(""), angle1_deg = std::nan("");
};

/// Histogram of a joint's impact velocities: `counts.size()` bins from 0 to the largest.
struct ImpactHistogram {
  std::vector<double> edges;    ///< m/s, counts.size() + 1 of them
  std::vector<int> counts;
};

/// One clearance joint: its journal orbit and its contact modes.
struct ClearanceJointAnalysis {
  std::string joint;
  double clearance = 0.0;               ///< m
  std::vector<Vec2> orbit;              ///< eccentricity e = r_J − r_B, every k-th output, m
  double continuous_contact_time = 0.0; ///< s: longer contact episodes are continuous contact
  ModeSummary modes;                    ///< episodes, shares, impacts and their velocities δ̇⁻
  /// `modes` cover the statistics window (a sweep's: after its transient); false when the run
  /// ended before the window began, and they cover the whole run instead.
  bool modes_in_window = true;
  ImpactHistogram histogram;
};

/// Poses for the animation, every k-th output.
struct AnimationFrames {
  std::vector<double> time;                              ///< s
  std::vector<std::string> bodies;                       ///< body names (ground excluded)
  std::vector<std::vector<std::array<double, 3>>> pose;  ///< pose[body][frame] = x, y (m), φ (rad)
  std::vector<std::string> clearance_joints;             ///< clearance joint names
  std::vector<std::vector<Vec2>> eccentricity;           ///< eccentricity[joint][frame], m
  /// Flexible links only (empty for other bodies): deflection[body][frame] at mid-length from the
  /// chord (m, the `<body>.deflection` channel) and the link's length (m; 0 for other bodies).
  std::vector<std::vector<double>> deflection;
  std::vector<double> length;
};

/// One clearance joint's section points: its eccentricity (ex, ey) at every section.
struct JointSections {
  std::string joint;
  std::vector<std::string> variables;     ///< "<joint>.ex", "<joint>.ey"
  std::vector<Vec2> points;               ///< m, one per section (PoincareSections::times)
  int distinct = 0;                       ///< distinct points within `tolerance`
  double tolerance = 0.0;                 ///< m: 1% of this joint's clearance
};

/// Poincaré sections after the transient: stroboscopic (once per driver period) or event-based
/// (a plane in state space, located by the integrator's root finding).
struct PoincareSections {
  std::string kind;                       ///< "stroboscopic" or "event"
  std::vector<std::string> planes;        ///< the plane specifications (event sections)
  double period = 0.0;                    ///< s, 0 without a period driver
  int discarded_periods = 0;
  /// Each section point: (ex, ey) of every clearance joint, m; without a clearance joint each
  /// body's x, y (m) and 1 cm × (cos φ, sin φ).
  std::vector<std::vector<double>> points;
  std::vector<double> times;              ///< s, one per point
  std::vector<std::string> variables;     ///< channel names of the first two coordinates
  /// What every coordinate of a point is, in order: `<joint>.ex`, `<joint>.ey` per clearance
  /// joint; without one `<body>.x`, `<body>.y`, `<body>.lever_x`, `<body>.lever_y` per body
  /// (the lever: 0.01 m × (cos φ, sin φ)). The distinct count is over all of them.
  std::vector<std::string> coordinates;
  int distinct = 0;                       ///< distinct points (count_distinct) within `tolerance`
  double tolerance = 0.0;                 ///< m: 1% of the smallest clearance, 1 µm without one
  /// Every clearance joint's own points and distinct count (the first two coordinates of
  /// `points` are the first joint's); empty without a clearance joint.
  std::vector<JointSections> joints;
};

/// Amplitude spectrum of one channel after the transient, decimated for display.
struct ChannelSpectrum {
  std::string channel;
  std::vector<double> frequency;   ///< Hz
  std::vector<double> amplitude;   ///< channel units
  std::string window;              ///< "hann"
  double discarded_time = 0.0;     ///< s of transient left out
};

/// A pair of channels to plot against each other.
struct PhasePortrait {
  std::string x, y;
};

/// The Lyapunov exponents with their inputs: by the variational equations with saltation
/// matrices (the spectrum, study/variational_lyapunov.hpp), or the largest by two trajectories
/// (analysis/dynamics_analysis.hpp).
struct LyapunovEstimate {
  std::string method = "two-trajectory";  ///< "variational" or "two-trajectory"
  /// Variational only: the 2·DOF exponents, descending, 1/s, and their running estimates at
  /// every history time; the contact events mapped by saltation matrices and those corrected at
  /// an output (no located crossing, not mapped).
  std::vector<double> spectrum;
  std::vector<std::vector<double>> spectrum_history;
  int events_mapped = 0, events_unmapped = 0;
  /// False when the drivers fix every coordinate: no free direction, nothing was run (`message`
  /// says so); the fields below are then unset.
  bool estimated = false;
  bool ok = false;                 ///< the estimate completed; `exponent` is valid
  double exponent = std::nan("");  ///< 1/s
  int renormalisations = 0;
  double interval = 0.0;           ///< s between renormalisations (period / 20)
  int intervals = 0;               ///< renormalisation intervals asked for
  double d0 = 0.0;                 ///< two-trajectory: separation in configuration space, m and rad
  double t0 = 0.0;                 ///< start: the first section after the transient, s
  std::vector<std::pair<double, double>> history;  ///< (time s, running estimate 1/s)
  std::string message;
  /// Why `method` is not the one asked for ("" when it is): the variational equations need a
  /// right-hand side that is smooth between located events, which Coulomb friction is not.
  std::string note;
};

/// periodic / quasi-periodic / chaotic / undetermined, and what it rests on.
struct MotionVerdict {
  std::string kind;                    ///< periodic, quasi-periodic, chaotic, undetermined
  std::vector<std::string> evidence;   ///< the numbers the rule used, as sentences
  std::string rule;                    ///< the rule, verdict_rule() (analysis/dynamics_analysis.hpp)
  double lyapunov_exponent = std::nan("");  ///< 1/s, NaN when not estimated
  double period = 0.0;                      ///< s, 0 without a period driver
  int distinct_points = 0;                  ///< distinct Poincaré points
  int sections = 0;                         ///< Poincaré sections taken
  int off_harmonic_peaks = -1;              ///< strong spectral peaks off the harmonics; −1: not computed
};

/// Where each part of a RunAnalysis came from, as sentences (printed by `lash report` and
/// `lash analyze`, and kept in report_data.json as `provenance`).
struct Provenance {
  std::vector<std::string> read;         ///< taken from what the run wrote (or observed it while it ran)
  std::vector<std::string> resimulated;  ///< computed by simulating now
  std::vector<std::string> skipped;      ///< left out, with the reason (a channel not written)
};

/// Everything a run with its analyses produced.
struct RunAnalysis {
  Provenance provenance;
  RunResult result;                    ///< the main run
  std::string period_driver;           ///< the driver whose period is used ("" none)
  double period = 0.0;                 ///< s, 2π/|ω| of that driver, 0 without one
  /// Where `period` came from, as a sentence: the driver's constant speed, --period, or the
  /// expression driver's mean speed over the run's last half; "" without a period.
  std::string period_source;
  DecimatedSeries series;              ///< every channel of the main run
  std::vector<double> crank_angle_deg; ///< the period driver's angle in [0, 360) at series.time; empty without one
  std::optional<IdealTwin> ideal_twin; ///< absent if not asked for, no clearance joint, or the twin failed
  AnimationFrames frames;
  std::vector<ChannelStatistics> statistics;  ///< channels with samples in the window, column order
  std::vector<ClearanceJointAnalysis> clearance;
  std::optional<PoincareSections> poincare;   ///< absent without a period driver or a plane
  std::vector<ChannelSpectrum> spectra;       ///< channels with at least 16 samples after the transient
  std::vector<PhasePortrait> phase;
  std::optional<LyapunovEstimate> lyapunov;   ///< absent if not asked for; else the exponent, or its message says why there is none
  MotionVerdict verdict;
};

/// The driver that sets the period: the constant-speed rotary driver named `name`, else (name
/// empty) the first one; nullptr if there is none (or `name` is not one).
const Driver* period_driver(const Model& model, const std::string& name);

/// The rotary driver named `name` (else the first rotary one) whatever its profile; nullptr if
/// there is none.
const Driver* rotary_driver(const Model& model, const std::string& name);

/// Mean angular speed (rad/s) of driver `d` over [t0, t1] from its prescribed motion (the
/// expression or its constant speed); NaN unless its speed keeps one sign there (a start-up
/// ramp that has not reversed) and the mean is not zero.
double mean_driver_speed(const Model& model, const Driver& d, double t0, double t1);

/// `model` with every clearance joint made ideal.
Model ideal_model(const Model& model);

/// Runs `model` with the analyses. `extra`, when given, also observes the main run (outputs,
/// events, progress): a results writer, a progress line. Throws std::invalid_argument for an
/// option naming what does not exist (driver, channel, plane), std::runtime_error if no initial
/// state exists.
RunAnalysis analyze_run(const Model& model, const AnalysisOptions& options,
                        Observer* extra = nullptr);

/// One located contact event of a recorded run (events.csv).
struct RecordedEvent {
  int joint = 0;          ///< index among the model's clearance joints
  double t = 0.0;         ///< s
  bool onset = true;      ///< onset (true) or separation
  double velocity = 0.0;  ///< δ̇ at the event, m/s
};

/// A finished run as its folder holds it (io/run_folder.hpp reads one): the status from its
/// summary, the time series row by row, its events.
struct RecordedRun {
  RunResult result;                  ///< status and integrator statistics (summary.json)
  std::string series_file;           ///< the time series' path, for messages
  std::vector<std::string> columns;  ///< channels of each row (a subset after `lash run --channels`)
  /// Reads the next row: its time and one value per column; false after the last. Throws
  /// (naming the file and line) on a damaged row.
  std::function<bool(double& t, double* values)> next_row;
  std::vector<RecordedEvent> events;  ///< in time order
  /// Every channel's exact extrema over the whole run, by name (summary.json `channels`).
  std::map<std::string, ChannelExtremum> extrema;
  std::vector<std::string> read;      ///< what was read, as sentences (Provenance::read)
  std::string model_file;             ///< the model file the run was given (summary.json), or ""
};

/// The analyses of analyze_run() from what a run wrote instead of running it again: the same
/// code (one observer or one reader hands rows of channel values to the same analyses). Made
/// again, and said so in `provenance`: the ideal twin, the Lyapunov trajectories with the main
/// run up to their start, and sections the rows cannot give (a plane, or channels not written);
/// stroboscopic sections are interpolated between the rows. Analyses of channels not written
/// are left out with a note. Throws std::invalid_argument for options as analyze_run() does and
/// whatever `run.next_row` throws.
RunAnalysis analyze_recorded_run(const Model& model, const AnalysisOptions& options,
                                 RecordedRun& run);

}  // namespace lash
