#pragma once
/// @file extrema.hpp
/// Exact extrema of every output channel, independent of the output interval: tracked at every
/// output, every accepted integrator step and every located event, and refined inside a step on
/// the integrator's dense output where a channel turns (docs/analysis.md, "How peaks are found").
#include <Eigen/Core>
#include <algorithm>
#include <limits>
#include <vector>

#include "core/model.hpp"
#include "core/simulate.hpp"

namespace lash {

/// A channel's smallest and largest value over a run and when they occurred.
struct ChannelExtremum {
  double min = 0.0, t_min = 0.0, max = 0.0, t_max = 0.0;
  bool seen = false;  ///< false until a first finite value arrived
  bool non_finite = false;  ///< a value was NaN or ±inf (not counted in min and max)
};

/// Tracks the extrema of all channels (`channel_values`) of a run.
///
/// At the end of each accepted step [t0, t1] the channels are evaluated at t1 and at
/// t1 − ε·h (ε = kSlopeFraction), giving each channel's value and left slope there; the slope at
/// t0 is the previous step's (or, after an event, a forward difference at t0). A channel whose
/// slope changes sign over the step has a turning point inside it, which Brent's method
/// (golden-section and parabolic steps, Boost.Math's brent_find_minima) on the dense output
/// locates (kRefineBits, at most kRefineIterations evaluations), unless a cubic Hermite estimate
/// through the end values and slopes shows it cannot beat the extremum already found, or that it
/// lies below the integrator's resolution (rtol): it rises above the step's ends by at most rtol
/// times the channel's largest magnitude so far, or that magnitude is at most rtol times the
/// largest of any channel with the same unit (a channel zero in exact arithmetic, such as a
/// constant-speed crank's angular acceleration). Searching there would refine integration error.
/// Every workspace evaluated, refinement points included, updates every channel.
class ChannelExtrema {
 public:
  /// Relative offset of the slope sample at a step's end (fraction of the step).
  static constexpr double kSlopeFraction = 1e-3;
  /// Most evaluations of one turning point's search.
  static constexpr int kRefineIterations = 18;
  /// Precision of a turning point's time, as Boost's brent_find_minima takes it (tolerance
  /// τ = 2^(1 − bits) relative): the search stops once its bracket is narrower than
  /// 4τ(s + 1/4) ≤ 2.5e-3 of the step (s ∈ [0, 1], the best point's place in the step).
  static constexpr int kRefineBits = 12;

  /// Tracks every channel, or only those of `tracked` (indices into channel_info; a sweep keeps
  /// a few): the others stay unseen, and neither their turning points nor their values cost
  /// anything. A unit's largest magnitude (the resolution test below) is then over the tracked
  /// channels of that unit.
  explicit ChannelExtrema(const Model& model, std::vector<int> tracked = {});

  /// Only values at times in [from, to] count (default: up to the model's end_time; `to` is
  /// never later). A step across an end samples the end itself and refines inside the window
  /// only, so the extrema over the window are as exact as over a whole run. (The integrator's
  /// steps end on end_time, never past it; a window's end inside a step is cut as above.)
  void set_window(double from, double to) { from_ = from, to_ = std::min(to, end_); }
  /// The relative resolution below which a turning point is not searched (default: the model's
  /// rtol; 0 searches every one that may beat the extremum found so far).
  void set_resolution(double relative) { resolution_ = relative; }

  /// A value of every channel at time t (an output or an event): updates the extrema only.
  void sample(double t, const double* values);
  /// Channels evaluated from `ws` at (t, y).
  void sample(double t, const Eigen::VectorXd& y, const Workspace& ws);
  /// One accepted step (Observer::step): samples t1, finds turning points inside and refines.
  void step(double t0, double t1, const Eigen::VectorXd& y1, const Workspace& ws1,
            StepProbe& probe);
  /// The right-hand side may jump here (an event): the next step takes its start slope anew.
  void restart() { have_slope_ = false; }
  /// The run stopped at t, before the end of the last step it tracked (an output it could not
  /// write, an interruption at an output: the step had passed it): what that step found is
  /// forgotten and the samples since, up to t, count again; the extrema are then over the run
  /// up to t, less any turning point inside the last step before t (not searched again).
  void end_at(double t);
  /// Keeps what end_at needs (a copy of the extrema before each step, the samples since): only
  /// for an observer that may stop the run at an output (the results writer).
  void keep_last_step() { keep_last_step_ = true; }

  const std::vector<ChannelExtremum>& extrema() const { return ext_; }
  long refinements() const { return refinements_; }      ///< turning-point searches run
  long evaluations() const { return evaluations_; }      ///< workspace evaluations made

 private:
  /// Evaluates all channels at t on the dense output into `out`; false if not finite.
  bool probe_values(StepProbe& probe, double t, std::vector<double>& out);
  /// Brent's search for channel i's extremum (sign +1: max, −1: min) in [a, b]; fb is
  /// −sign·(value at b) if known, else NaN.
  void refine(StepProbe& probe, int i, double sign, double a, double b, double fb);

  const Model& model_;
  std::vector<ChannelExtremum> ext_;
  std::vector<int> tracked_;     ///< the channels tracked, ascending
  std::vector<int> unit_;        ///< per channel: its unit's index into scale_
  std::vector<double> scale_;    ///< per unit: the largest |value| of its channels so far
  double resolution_;            ///< relative; see set_resolution
  std::vector<double> v0_, d0_, v1_, d1_, tmp_;
  double t_last_ = 0.0;
  double from_ = -std::numeric_limits<double>::infinity();
  double end_;  ///< the model's end_time
  double to_;
  bool have_slope_ = false;
  long refinements_ = 0, evaluations_ = 0;
  /// For end_at: the extrema before the last step, that step's end, and the samples since
  /// (times, and every channel's value per sample); in_step_ while a step probes.
  std::vector<ChannelExtremum> before_step_;
  double step_end_ = -std::numeric_limits<double>::infinity();
  std::vector<double> since_t_, since_values_;
  bool in_step_ = false;
  bool keep_last_step_ = false;
};

}  // namespace lash
