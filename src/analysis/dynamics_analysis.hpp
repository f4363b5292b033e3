#pragma once
/// @file dynamics_analysis.hpp
/// Nonlinear-dynamics measures: Poincaré point clustering, the largest Lyapunov exponent, contact
/// mode episodes, and the periodic / quasi-periodic / chaotic verdict.
#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

namespace lash {

/// Number of distinct points: greedy clustering, a point joins a cluster whose first member is
/// within `tol` (Euclidean). A period-k orbit sampled stroboscopically gives k.
int count_distinct(const std::vector<std::vector<double>>& points, double tol);
/// Of the distinct points count_distinct finds (the same greedy centres), how many recur: have
/// at least one more point within `tol`. A settled period-k orbit's k points all do; a
/// transient's points, each met once, do not.
int count_recurring(const std::vector<std::vector<double>>& points, double tol);

/// Largest Lyapunov exponent by two nearby trajectories with renormalisation (Benettin et al.,
/// Meccanica 1980): every `interval`, the separation d is measured with `norm`, ln(d/d0) is
/// accumulated and the perturbed state is pulled back to distance d0 along the separation.
struct LyapunovResult {
  double exponent = 0.0;  ///< 1/time unit of `interval` (1/s for flows, per iteration for maps)
  int renormalisations = 0;
  std::vector<std::pair<double, double>> history;  ///< (time, running estimate)
  bool ok = true;
  std::string message;
};

struct LyapunovOptions {
  double d0 = 1e-8;           ///< initial and renormalised separation (in `norm` units)
  double interval = 1.0;      ///< renormalisation interval
  int transient = 0;          ///< intervals discarded before accumulating
  int intervals = 1000;       ///< intervals accumulated
};

/// `flow(which, y, t0, t1)` advances trajectory `which` (0 reference, 1 perturbed) from t0 to t1
/// in place and returns false on failure; the perturbed state handed to it after a
/// renormalisation is a new initial condition.
/// `norm(a, b)` is the separation between two states. `perturb(y, d0)` returns a state at
/// separation d0 from y (default: y + d0 e₀).
LyapunovResult largest_lyapunov(
    const std::function<bool(int, Eigen::VectorXd&, double, double)>& flow, Eigen::VectorXd y0,
    const std::function<double(const Eigen::VectorXd&, const Eigen::VectorXd&)>& norm,
    const LyapunovOptions& options,
    const std::function<Eigen::VectorXd(const Eigen::VectorXd&, double)>& perturb = {});

/// A contact episode of one clearance joint, classified by its duration.
struct ContactEpisode {
  double start = 0.0, end = 0.0;
  bool continuous = false;  ///< longer than the continuous-contact threshold
};

struct ModeSummary {
  std::vector<ContactEpisode> episodes;
  double free_flight_share = 0.0, impact_share = 0.0, continuous_share = 0.0;
  int impacts = 0;                      ///< contact onsets
  std::vector<double> impact_velocities;
};

/// Contact episodes from located onsets/separations (time, onset?, velocity) over [t0, t1]:
/// episodes longer than `continuous_time` are continuous contact (the journal follows the
/// bearing wall), shorter ones impacts; the rest of the time is free flight. An episode is
/// classified by its whole duration, which events outside [t0, t1] show (one under way at t0
/// began at the last onset before it), and counts in the shares with its part inside.
ModeSummary contact_modes(const std::vector<double>& times, const std::vector<bool>& onset,
                          const std::vector<double>& velocities, bool in_contact_at_t0,
                          double t0, double t1, double continuous_time);

struct Verdict {
  std::string kind;  ///< periodic, quasi-periodic, chaotic, undetermined
  std::vector<std::string> evidence;
};

/// Sections after the transient the verdict needs: a period-8 orbit shows each point twice.
constexpr int kVerdictMinSections = 16;
/// Most distinct points a periodic orbit may have (period-k, k ≤ 8).
constexpr int kVerdictMaxPeriod = 8;
/// λ·T above which neighbouring trajectories separate: chaotic.
constexpr double kVerdictChaosThreshold = 0.1;
/// Broadband share of the spectrum (signal.hpp) below which it is discrete (lines only), and
/// above which it is continuous.
constexpr double kVerdictDiscreteSpectrum = 0.1;
constexpr double kVerdictBroadbandSpectrum = 0.5;

/// Returns that shrink to at most this share of their size (section_contraction), with
/// λT < 0, make points that do not recur yet a converging orbit rather than a quasi-periodic one.
constexpr double kVerdictContraction = 0.5;

/// How the Poincaré points' returns shrink: each point's return is its distance to the nearest
/// of the next kVerdictMaxPeriod points (|p_i − p_(i+k)| on a period-k orbit, k <= 8); the
/// median of the returns of the last third of the points that have 8 successors, over the median
/// of the first third's. About 1 on a torus or an attractor the points keep covering; below 1
/// where they close in on an orbit or a rest position (a damped transient: exp(λT·n) after n
/// periods). NaN with fewer than 12 points (4 returns), or returns of 0 in the first third.
double section_contraction(const std::vector<std::vector<double>>& points);

/// The rule classify_motion applies, in the words analyze, report and summary.json print.
const char* verdict_rule();

/// Classifies the motion after the transient by verdict_rule(): `sections` Poincaré sections
/// holding `distinct` distinct points, the largest Lyapunov exponent λ (NaN if not computed)
/// and `period` T (the driver's, or the mean time between sections; λT is the growth per
/// period); `broadband` the spectrum's broadband share (NaN: none computed), which decides
/// between quasi-periodic and chaotic when there is no exponent and is weighed against it when
/// there is; `non_harmonic_peaks` (strong spectral peaks off the driving harmonics, −1: none
/// computed) is listed as evidence only. `min_end_time` (s, 0: unknown) is the end_time that
/// would give enough sections, quoted when there are too few. `recurring` (count_recurring; −1:
/// not computed, taken as `distinct`) is how many of the distinct points recur: k of them make a
/// period-k orbit, the others (met once) a transient, at most half the sections. `contraction`
/// (section_contraction; NaN: not computed) tells a slow convergence (|λT| <= 0.1 but the
/// returns shrinking) from quasi-periodic motion.
Verdict classify_motion(double lyapunov, double period, int distinct, int sections,
                        int non_harmonic_peaks, double min_end_time = 0.0,
                        double broadband = std::nan(""), int recurring = -1,
                        double contraction = std::nan(""));

}  // namespace lash
