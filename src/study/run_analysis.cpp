#include "study/run_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>

#include "analysis/signal.hpp"
#include "study/variational_lyapunov.hpp"

namespace lash {

namespace {

/// The driver's angle at (t, y) in [0, 360) degrees: initial + ωt for a constant speed, else its
/// prescribed motion (a speed expression's angle is the state integrated with the run).
double driver_angle_deg(const Model& model, const Workspace& ws, const Driver& d, double t,
                        const double* y) {
  double rad;
  if (d.profile == DriverProfile::constant_speed) {
    rad = d.initial + d.speed * t;
  } else {
    double fd, fdd;
    driver_motion(model, ws, static_cast<int>(&d - model.drivers.data()), t, y, rad, fd, fdd);
  }
  const double deg = std::fmod(rad * 180.0 / M_PI, 360.0);
  return deg < 0 ? deg + 360.0 : deg;
}

/// Min/max decimation on a shared time base, streaming: each bucket of `size` outputs becomes
/// two points (its first and last time) carrying each channel's extremes in time order.
class Decimator {
 public:
  Decimator(size_t channels, size_t size) : data(channels), size_(std::max<size_t>(1, size)) {
    mn_.resize(channels);
    mx_.resize(channels);
    imn_.resize(channels);
    imx_.resize(channels);
  }
  void add(double t, const std::vector<double>& v) {
    if (n_ == 0) t_first_ = t;
    t_last_ = t;
    for (size_t c = 0; c < v.size(); ++c) {
      if (n_ == 0 || v[c] < mn_[c]) mn_[c] = v[c], imn_[c] = n_;
      if (n_ == 0 || v[c] > mx_[c]) mx_[c] = v[c], imx_[c] = n_;
    }
    if (++n_ == size_) flush();
  }
  void flush() {
    if (n_ == 0) return;
    time.push_back(t_first_);
    if (n_ > 1) time.push_back(t_last_);
    for (size_t c = 0; c < data.size(); ++c) {
      const bool min_first = imn_[c] <= imx_[c];
      data[c].push_back(min_first ? mn_[c] : mx_[c]);
      if (n_ > 1) data[c].push_back(min_first ? mx_[c] : mn_[c]);
    }
    n_ = 0;
  }
  std::vector<double> time;
  std::vector<std::vector<double>> data;

 private:
  size_t size_, n_ = 0;
  double t_first_ = 0, t_last_ = 0;
  std::vector<double> mn_, mx_;
  std::vector<size_t> imn_, imx_;
};

/// The channels of a model, in column order.
std::vector<ChannelInfo> channels_of(const Model& m) { return channel_info(m); }

/// Keeps every output of every channel (the ideal twin, compared sample by sample) and every
/// channel's exact extrema over the run.
class Keeper : public Observer {
 public:
  explicit Keeper(const Model& m)
      : model_(m), channels(channels_of(m)), extrema(m), v_(channels.size()) {
    data.resize(channels.size());
  }
  void output(double t, const Eigen::VectorXd& y, const Workspace& ws) override {
    channel_values(model_, ws, y, v_.data());
    for (size_t i = 0; i < v_.size(); ++i) data[i].push_back(v_[i]);
    extrema.sample(t, v_.data());
  }
  void event(const ContactEvent&, const Workspace&) override { extrema.restart(); }
  bool wants_steps() const override { return true; }
  void step(double t0, double t1, const Eigen::VectorXd& y, const Workspace& ws,
            StepProbe& probe) override {
    extrema.step(t0, t1, y, ws, probe);
  }
  const Model& model_;
  std::vector<ChannelInfo> channels;
  std::vector<std::vector<double>> data;
  ChannelExtrema extrema;

 private:
  std::vector<double> v_;
};

/// Located onsets and separations of one clearance joint.
struct JointEvents {
  std::vector<double> t, v;
  std::vector<bool> onset;
  bool in_contact_at_start = false;
};

/// A section point from a row of channel values: (ex, ey) of every clearance joint, else each
/// body's x, y and a 1 cm lever (cos φ, sin φ) (angles mod 2π, comparable to positions).
class SectionPoint {
 public:
  SectionPoint(const Model& m, const std::vector<int>& clearance_joints,
               const std::vector<ChannelInfo>& cols) {
    auto index = [&](const std::string& name) {
      for (size_t i = 0; i < cols.size(); ++i)
        if (cols[i].name == name) return static_cast<int>(i);
      return -1;
    };
    for (int j : clearance_joints) {
      ecc_.push_back({index(m.joints[j].name + ".ex"), index(m.joints[j].name + ".ey")});
      complete_ = complete_ && ecc_.back()[0] >= 0 && ecc_.back()[1] >= 0;
    }
    if (ecc_.empty())
      for (const auto& b : m.bodies) {
        pose_.push_back({index(b.name + ".x"), index(b.name + ".y"), index(b.name + ".phi")});
        complete_ = complete_ && pose_.back()[0] >= 0 && pose_.back()[1] >= 0 &&
                    (pose_.back()[2] >= 0 || !b.rotates());
      }
  }
  /// Whether the columns hold every coordinate of a point.
  bool complete() const { return complete_; }
  std::vector<double> at(const double* v) const {
    std::vector<double> p;
    for (const auto& e : ecc_) {
      p.push_back(v[e[0]]);
      p.push_back(v[e[1]]);
    }
    for (const auto& q : pose_) {
      const double phi = q[2] >= 0 ? v[q[2]] : 0.0;
      p.push_back(v[q[0]]);
      p.push_back(v[q[1]]);
      p.push_back(std::cos(phi) * 1e-2);
      p.push_back(std::sin(phi) * 1e-2);
    }
    return p;
  }

 private:
  std::vector<std::array<int, 2>> ecc_;
  std::vector<std::array<int, 3>> pose_;
  bool complete_ = true;
};

/// The analyses' inputs gathered from the main run's outputs one row at a time: fed by an
/// observer of the run (Collector) or by the rows a run wrote to its folder
/// (analyze_recorded_run), so both paths go through this one piece of code. `channels` are the
/// columns of a row: every channel of the model during a run, those the run wrote otherwise.
/// Poses, eccentricities and section points are read from the channels (body x, y, phi; joint
/// ex, ey), so they are the same numbers whichever way the rows came.
class SampleAnalysis {
 public:
  SampleAnalysis(const Model& m, std::vector<ChannelInfo> cols, const AnalysisOptions& o,
                 size_t n_out, const std::vector<int>& clearance_joints)
      : channels(std::move(cols)),
        dec(channels.size(), (n_out + o.display_points - 1) / o.display_points),
        stats(channels.size()) {
    frame_every_ = std::max<size_t>(1, n_out / std::max<size_t>(1, o.frames));
    orbit_every_ = std::max<size_t>(1, n_out / 4000);
    for (auto& s : stats) s.t0 = o.stats_t0, s.t1 = o.stats_t1;
    const int nc = static_cast<int>(clearance_joints.size());
    events.resize(nc);
    orbit.resize(nc);
    eccentricity.resize(nc);
    // Columns of the poses (φ = 0 for a point mass, which has no angle) and eccentricities.
    for (const auto& b : m.bodies) {
      pose_index.push_back({index(b.name + ".x"), index(b.name + ".y"), index(b.name + ".phi")});
      const auto& q = pose_index.back();
      if (q[0] < 0 || q[1] < 0 || (q[2] < 0 && b.rotates())) missing_pose.push_back(b.name);
    }
    poses.resize(m.bodies.size());
    deflections.resize(m.bodies.size());
    for (const auto& b : m.bodies)
      deflection_index.push_back(b.flexible() ? index(b.name + ".deflection") : -1);
    for (int c = 0; c < nc; ++c) {
      const std::string& n = m.joints[clearance_joints[c]].name;
      ecc_index.push_back({index(n + ".ex"), index(n + ".ey")});
      if (ecc_index.back()[0] < 0 || ecc_index.back()[1] < 0) missing_ecc.push_back(n);
    }
  }
  int index(const std::string& name) const {
    for (size_t i = 0; i < channels.size(); ++i)
      if (channels[i].name == name) return static_cast<int>(i);
    return -1;
  }
  /// One output row; `angle_deg` is the period driver's angle (NaN without one).
  void output(double t, const double* v, double angle_deg) {
    dec.add(t, std::vector<double>(v, v + channels.size()));
    if (!std::isnan(angle_deg)) angle.push_back(angle_deg);
    const bool in_window = in_angle_range(angle_deg);
    if (in_window)
      for (size_t i = 0; i < channels.size(); ++i) stats[i].add(t, v[i]);
    // The ideal twin compared over the same rows as the statistics (window and angle range):
    // deviations and its own peak there.
    if (twin && in_window && !stats.empty() && t >= stats[0].t0 && t <= stats[0].t1) {
      for (size_t i = 0; i < channels.size(); ++i) {
        const int ti = twin_index[i];
        if (ti < 0 || k_ >= twin->data[ti].size()) continue;
        const double ideal = twin->data[ti][k_];
        const double d = v[i] - ideal;
        dev_sq[i] += d * d;
        dev_max[i] = std::max(dev_max[i], std::abs(d));
        twin_peak[i] = std::max(twin_peak[i], std::abs(ideal));
        ++dev_n[i];
      }
    }
    for (size_t s = 0; s < fft_index.size(); ++s)
      if (t >= t_discard - 1e-12) fft_data[s].push_back(v[fft_index[s]]);
    if (k_ % frame_every_ == 0 && missing_pose.empty() && missing_ecc.empty()) {
      frame_t.push_back(t);
      for (size_t b = 0; b < pose_index.size(); ++b) {
        const auto& p = pose_index[b];
        poses[b].push_back({v[p[0]], v[p[1]], p[2] >= 0 ? v[p[2]] : 0.0});
        if (deflection_index[b] >= 0) deflections[b].push_back(v[deflection_index[b]]);
      }
      for (size_t c = 0; c < ecc_index.size(); ++c) eccentricity[c].push_back(ecc(c, v));
    }
    if (k_ % orbit_every_ == 0 && missing_ecc.empty())
      for (size_t c = 0; c < ecc_index.size(); ++c) orbit[c].push_back(ecc(c, v));
    ++k_;
  }
  void event(int c, double t, bool onset, double velocity) {
    JointEvents& je = events[c];
    je.t.push_back(t);
    je.v.push_back(velocity);
    je.onset.push_back(onset);
  }
  /// A section point at time t (SectionPoint), kept after the transient.
  void section(double t, std::vector<double> p) {
    if (t < t_discard - 1e-12) return;
    sections.push_back(std::move(p));
    section_t.push_back(t);
  }

  std::vector<ChannelInfo> channels;
  Decimator dec;
  std::vector<ChannelStats> stats;
  const Keeper* twin = nullptr;
  std::vector<int> twin_index;
  std::vector<double> dev_sq, dev_max, twin_peak;
  std::vector<long> dev_n;
  std::vector<int> fft_index;
  std::vector<std::vector<double>> fft_data;
  double t_discard = 0.0;
  double angle0 = std::nan(""), angle1 = std::nan("");
  std::vector<double> angle;  ///< the period driver's angle at every output, deg
  std::vector<double> frame_t;
  std::vector<std::vector<std::array<double, 3>>> poses;
  std::vector<std::vector<double>> deflections;  ///< per body: flexible links' mid deflection
  std::vector<int> deflection_index;             ///< column of `<body>.deflection`, or −1
  std::vector<std::vector<Vec2>> eccentricity;
  std::vector<std::vector<Vec2>> orbit;
  std::vector<JointEvents> events;
  std::vector<std::vector<double>> sections;
  std::vector<double> section_t;
  std::vector<std::array<int, 3>> pose_index;  ///< columns of x, y, phi per body (−1: absent)
  std::vector<std::array<int, 2>> ecc_index;   ///< columns of ex, ey per clearance joint
  std::vector<std::string> missing_pose, missing_ecc;  ///< bodies and joints without their columns

 private:
  Vec2 ecc(size_t c, const double* v) const { return {v[ecc_index[c][0]], v[ecc_index[c][1]]}; }
  bool in_angle_range(double deg) const {
    if (std::isnan(deg) || std::isnan(angle0) || std::isnan(angle1)) return true;
    return angle0 <= angle1 ? (deg >= angle0 && deg <= angle1) : (deg >= angle0 || deg <= angle1);
  }
  size_t frame_every_ = 1, orbit_every_ = 1, k_ = 0;
};

/// An observer of the main run (or of a run made again for what its folder lacks): hands the
/// outputs, events and sections to a SampleAnalysis as rows of channel values, forwards to
/// `extra`, and keeps the state at the first section after the transient (where the Lyapunov
/// trajectories start).
class Collector : public Observer {
 public:
  Collector(const Model& m, const Workspace& ws, SampleAnalysis& sa, Observer* extra)
      : model_(m), sa_(sa), extra_(extra) {
    // The SampleAnalysis' columns among the model's channels (all of them during a run).
    const std::vector<ChannelInfo> all = channel_info(m, ws);
    point_ = std::make_unique<SectionPoint>(m, std::vector<int>(ws.clearance_joints.begin(),
                                                                ws.clearance_joints.begin() + ws.nc),
                                            all);
    v_.resize(all.size());
    for (const auto& c : sa.channels)
      for (size_t i = 0; i < all.size(); ++i)
        if (all[i].name == c.name) pick_.push_back(i);
    row_.resize(pick_.size());
  }
  bool feed_outputs = true;         ///< outputs and events to the SampleAnalysis
  bool feed_sections = true;        ///< sections to the SampleAnalysis
  const Driver* angle_driver = nullptr;
  /// Exact extrema over the statistics window (null: the statistics keep the samples' extrema).
  ChannelExtrema* extrema = nullptr;
  /// A run made again for what a folder lacks stops once it has it: the Lyapunov start state
  /// (when `need_lyapunov_start`) and every output up to `need_until`.
  bool stop_when_done = false;
  bool need_lyapunov_start = false;
  double need_until = -std::numeric_limits<double>::infinity();

  std::string stop_reason() const override {
    if (stop_when_done && (!need_lyapunov_start || have_lyapunov_start) && t_output_ > need_until)
      return "what is needed is simulated";
    return extra_ ? extra_->stop_reason() : std::string();
  }
  void output(double t, const Eigen::VectorXd& y, const Workspace& ws) override {
    if (extra_) extra_->output(t, y, ws);
    if (extrema) extrema->sample(t, y, ws);
    t_output_ = t;
    if (!feed_outputs) return;
    channel_values(model_, ws, y, v_.data());
    if (first_)
      for (int c = 0; c < ws.nc; ++c) sa_.events[c].in_contact_at_start = ws.contact[c].in_contact;
    first_ = false;
    sa_.output(t, row(),
               angle_driver ? driver_angle_deg(model_, ws, *angle_driver, t, y.data()) : std::nan(""));
  }
  void event(const ContactEvent& e, const Workspace& ws) override {
    if (extra_) extra_->event(e, ws);
    if (extrema) extrema->restart();
    if (feed_outputs) sa_.event(e.clearance, e.t, e.onset, e.velocity);
  }
  void progress(double t, double t_end) override {
    if (extra_) extra_->progress(t, t_end);
  }
  bool wants_steps() const override { return extrema || (extra_ && extra_->wants_steps()); }
  void step(double t0, double t1, const Eigen::VectorXd& y, const Workspace& ws,
            StepProbe& probe) override {
    if (!(extra_ && extra_->wants_steps())) {
      if (extrema) extrema->step(t0, t1, y, ws, probe);
      return;
    }
    extra_->step(t0, t1, y, ws, probe);
    // The probe moved `ws` away from t1: evaluate it there again for the second user.
    if (extrema && probe.at_end()) extrema->step(t0, t1, probe.state(), probe.workspace(), probe);
  }
  void section(double t, const Eigen::VectorXd& y, const Workspace& ws) override {
    if (extra_) extra_->section(t, y, ws);
    if (t < sa_.t_discard - 1e-12) return;
    if (!have_lyapunov_start) {
      lyapunov_start = y;
      lyapunov_t0 = t;
      have_lyapunov_start = true;
    }
    if (!feed_sections) return;
    channel_values(model_, ws, y, v_.data());
    sa_.section(t, point_->at(v_.data()));
  }

  Eigen::VectorXd lyapunov_start;
  double lyapunov_t0 = 0.0;
  bool have_lyapunov_start = false;

 private:
  /// The SampleAnalysis' columns of the channel values in v_.
  const double* row() {
    if (pick_.size() == v_.size()) return v_.data();  // every channel, in order
    for (size_t i = 0; i < pick_.size(); ++i) row_[i] = v_[pick_[i]];
    return row_.data();
  }
  const Model& model_;
  SampleAnalysis& sa_;
  std::vector<double> v_, row_;
  std::vector<size_t> pick_;
  std::unique_ptr<SectionPoint> point_;  ///< over every channel
  Observer* extra_;
  bool first_ = true;
  double t_output_ = -std::numeric_limits<double>::infinity();
};

/// Stroboscopic sections at k·T from output rows: each section's point by cubic Lagrange
/// interpolation through the four outputs around it (two before, two after; the last four at
/// the end of the run), exact on an output time. Its error is estimated as the largest
/// difference between the cubic and the two quadratics through three of the four outputs (the
/// size of the cubic term): O(Δt³) where the motion is smooth, large where a contact rings
/// between outputs. `largest_estimate()` is the worst over all sections, in the points' units (m).
class SectionInterpolator {
 public:
  SectionInterpolator(SampleAnalysis& sa, const SectionPoint& point, double period, size_t width)
      : sa_(sa), point_(point), period_(period), width_(width) {}
  void row(double t, const double* v) {
    rows_.push_back({t, std::vector<double>(v, v + width_)});
    if (rows_.size() > 4) rows_.erase(rows_.begin());
    if (rows_.size() < 4) return;
    // Every section up to the third row: between the middle two rows once the run is under way.
    while (k_ * period_ <= rows_[2].first * (1 + 1e-12)) emit(k_++ * period_);
  }
  /// After the last row: the sections left up to its time, through the last rows.
  void finish() {
    if (rows_.empty()) return;
    while (k_ * period_ <= rows_.back().first * (1 + 1e-12)) emit(k_++ * period_);
  }
  double largest_estimate() const { return estimate_; }
  /// A section fell in a run of fewer than 4 outputs, where no error can be estimated.
  bool unestimated() const { return unestimated_; }
  /// Sections that fell on an output time (taken from the row, not interpolated), and all.
  long on_outputs() const { return on_outputs_; }
  long sections() const { return k_; }

 private:
  /// The point at ts by Lagrange interpolation through rows [a, b).
  std::vector<double> through(double ts, int a, int b) const {
    std::vector<double> v(width_, 0.0);
    for (int i = a; i < b; ++i) {
      double w = 1.0;
      for (int j = a; j < b; ++j)
        if (j != i) w *= (ts - rows_[j].first) / (rows_[i].first - rows_[j].first);
      for (size_t c = 0; c < width_; ++c) v[c] += w * rows_[i].second[c];
    }
    return point_.at(v.data());
  }
  void emit(double ts) {
    for (const auto& [t, v] : rows_)
      if (std::abs(t - ts) <= 1e-12 * std::max(1.0, std::abs(ts))) {  // on an output time
        sa_.section(ts, point_.at(v.data()));
        ++on_outputs_;
        return;
      }
    const int n = static_cast<int>(rows_.size());
    std::vector<double> p = through(ts, 0, n);
    if (n == 4) {
      for (const auto& q : {through(ts, 0, 3), through(ts, 1, 4)})
        for (size_t i = 0; i < p.size(); ++i)
          if (ts >= sa_.t_discard - 1e-12) estimate_ = std::max(estimate_, std::abs(q[i] - p[i]));
    } else if (ts >= sa_.t_discard - 1e-12) {
      // A run of fewer than 4 outputs: no second interpolant to compare with, so no estimate;
      // never kept (the sections are taken again by the integrator).
      unestimated_ = true;
      estimate_ = std::numeric_limits<double>::infinity();
    }
    sa_.section(ts, std::move(p));
  }
  SampleAnalysis& sa_;
  const SectionPoint& point_;
  double period_;
  size_t width_;
  long k_ = 0, on_outputs_ = 0;
  double estimate_ = 0.0;
  bool unestimated_ = false;
  std::vector<std::pair<double, std::vector<double>>> rows_;
};

/// Strong spectral peaks (> 10% of the largest) that are not within two bins of a harmonic of f0;
/// -1 (not counted) where no frequency is: two bins reach half-way between harmonics (fewer
/// than about 4 periods analysed), so "0 peaks off the harmonics" would say nothing.
int non_harmonic_peaks(const Spectrum& s, double f0) {
  if (s.amplitude.size() < 3 || !(f0 > 0)) return -1;
  const double df = s.frequency[1] - s.frequency[0];
  if (2 * df >= 0.5 * f0 * (1 - 1e-9)) return -1;  // (exactly 4 periods: none either)
  double top = 0;
  for (size_t k = 1; k < s.amplitude.size(); ++k) top = std::max(top, s.amplitude[k]);
  int n = 0;
  for (size_t k = 1; k + 1 < s.amplitude.size(); ++k) {
    const double a = s.amplitude[k];
    if (a < 0.1 * top || a < s.amplitude[k - 1] || a < s.amplitude[k + 1]) continue;
    const double h = s.frequency[k] / f0;
    if (std::abs(h - std::round(h)) * f0 > 2 * df) ++n;
  }
  return n;
}

/// How an exponent was computed, for the provenance list.
std::string lyapunov_provenance(const LyapunovEstimate& l) {
  return l.method == "variational" ? "variational spectrum (tangent equations, saltation matrices)"
                                   : "two trajectories";
}

/// Largest Lyapunov exponent: two trajectories from `y_start` at `t_start` (the state after the
/// transient), each perturbation projected onto the constraints; separation measured in
/// configuration space (body coordinates, m and rad; velocities would weigh the stiff contact
/// oscillation, whose bounded ringing is not divergence), renormalised `intervals` times, every
/// `interval`.
LyapunovEstimate lyapunov_from(const Model& model, const Eigen::VectorXd& y_start,
                               double t_start, double interval, int intervals, double d0_option,
                               const std::atomic<int>* interrupt) {
  Workspace w0(model), w1(model);
  Simulator s0(model, w0), s1(model, w1);
  Workspace wp(model);
  const int nq = wp.nq;
  auto flow = [&](int which, Eigen::VectorXd& y, double t0, double t1) {
    // Times are relative to the start of the estimate; the perturbed trajectory restarts
    // from its renormalised state every interval, the reference only once.
    if (interrupt && interrupt->load() != 0) return false;  // a signal: stop here
    Simulator& sim = which == 0 ? s0 : s1;
    if (which == 1 || t0 == 0.0) {
      if (which == 1) {
        try {
          project_state(model, wp, t0 + t_start, y);
        } catch (const std::exception&) {
          return false;
        }
      }
      // The perturbed copy keeps the reference's contact modes and δ̇⁻ where its gaps agree.
      sim.start(t0 + t_start, y, which == 1 ? &w0.contact : nullptr);
    }
    if (!sim.advance_to(t1 + t_start, nullptr)) return false;
    y = sim.state();
    return true;
  };
  auto norm = [&](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    double sum = 0;
    for (int i = 0; i < nq; ++i) sum += (a[i] - b[i]) * (a[i] - b[i]);
    return std::sqrt(sum);
  };
  auto perturb = [&](const Eigen::VectorXd& y, double d0) {
    std::mt19937 rng(12345);
    std::normal_distribution<double> g(0.0, 1.0);
    Eigen::VectorXd dir = Eigen::VectorXd::Zero(y.size());
    for (int i = 0; i < nq; ++i) dir[i] = g(rng);
    // Project onto the constraints, then rescale to d0: a perturbation along the free
    // directions only (none for a mechanism whose drivers fix every coordinate).
    Eigen::VectorXd yp = y + d0 * dir / dir.head(nq).norm();
    try {
      project_state(model, wp, t_start, yp);
    } catch (const std::exception&) {
      return Eigen::VectorXd(y);
    }
    const double d = norm(y, yp);
    return d > 1e-3 * d0 ? Eigen::VectorXd(y + (yp - y) * (d0 / d)) : Eigen::VectorXd(y);
  };
  // d0: far above the integration error (rtol·|q| ~ 1e-9 m here), far below the clearance.
  double d0 = 1e-7;
  for (int c = 0; c < wp.nc; ++c)
    d0 = std::min(d0, 2e-4 * model.joints[wp.clearance_joints[c]].clearance->clearance);
  if (d0_option > 0) d0 = d0_option;
  LyapunovOptions lo;
  lo.d0 = d0;
  lo.interval = interval;
  lo.intervals = intervals;
  const LyapunovResult lr = largest_lyapunov(flow, y_start, norm, lo, perturb);

  LyapunovEstimate e;
  e.method = "two-trajectory";
  e.estimated = true;
  e.ok = lr.ok;
  if (lr.ok) e.exponent = lr.exponent;
  e.renormalisations = lr.renormalisations;
  e.interval = interval;
  e.intervals = intervals;
  e.d0 = lo.d0;
  e.t0 = t_start;
  for (const auto& [t, v] : lr.history) e.history.emplace_back(t + t_start, v);
  e.message = lr.message;
  return e;
}

}  // namespace

int DecimatedSeries::index(const std::string& name) const {
  for (size_t i = 0; i < channels.size(); ++i)
    if (channels[i].name == name) return static_cast<int>(i);
  return -1;
}

const Driver* period_driver(const Model& m, const std::string& name) {
  for (const auto& d : m.drivers) {
    const bool rotary = driver_is_rotary(m, d) && d.profile == DriverProfile::constant_speed &&
                        d.speed != 0.0;
    if (name.empty() ? rotary : d.name == name) return rotary ? &d : nullptr;
  }
  return nullptr;
}

const Driver* rotary_driver(const Model& m, const std::string& name) {
  for (const auto& d : m.drivers)
    if (driver_is_rotary(m, d) && (name.empty() || d.name == name)) return &d;
  return nullptr;
}

double mean_driver_speed(const Model& model, const Driver& d, double t0, double t1) {
  if (d.profile == DriverProfile::constant_speed) return d.speed != 0.0 ? d.speed : std::nan("");
  // The prescribed speed ḟ(t) sampled at 2001 points; trapezoidal mean.
  Workspace ws(model);
  const Eigen::VectorXd y = Eigen::VectorXd::Zero(ws.ny);
  const int di = static_cast<int>(&d - model.drivers.data());
  constexpr int kSamples = 2000;
  double sum = 0.0, lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int k = 0; k <= kSamples; ++k) {
    const double t = t0 + (t1 - t0) * k / kSamples;
    double f, fd, fdd;
    try {
      driver_motion(model, ws, di, t, y.data(), f, fd, fdd);
    } catch (const std::exception&) {
      // An expression that cannot be evaluated there (sqrt(0.01 − time) past 0.01 s, where the
      // run stops with that error): no period, rather than no run and no report.
      return std::nan("");
    }
    if (!std::isfinite(fd)) return std::nan("");
    sum += (k == 0 || k == kSamples) ? 0.5 * fd : fd;
    lo = std::min(lo, fd);
    hi = std::max(hi, fd);
  }
  const double mean = sum / kSamples;
  if (!(lo > 0.0 || hi < 0.0) || mean == 0.0) return std::nan("");
  return mean;
}

Model ideal_model(const Model& model) {
  Model ideal = model;
  for (auto& j : ideal.joints) j.clearance.reset();
  ideal.channels = channel_info(ideal, Workspace(ideal));  // no contact channels now
  return ideal;
}

namespace {
std::string fmt_g(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

/// Why the statistics table is empty ("" when it is not): no output row in its window.
/// With no output row in the window but exact extrema, only RMS and crest factor are missing.
std::string no_statistics(const RunAnalysis& out, const AnalysisOptions& o) {
  const bool extrema_only = !out.statistics.empty() && out.statistics.front().samples == 0;
  if (!out.statistics.empty() && !extrema_only) return "";
  if (out.series.channels.empty() && !out.series.time.empty())
    return "statistics: the time series holds no channel besides time (a run with --channels "
           "time): run again with the channels to analyse";
  std::string why = extrema_only ? "statistics: RMS and crest factor: no output row lies in the window"
                                 : "statistics: no output row lies in the window";
  if (o.stats_t0 > -1e299 || o.stats_t1 < 1e299)
    why += " (--window " + fmt_g(std::max(o.stats_t0, 0.0)) + "," + fmt_g(o.stats_t1) + " s)";
  if (!std::isnan(o.stats_angle0))
    why += " (--angle-range " + fmt_g(o.stats_angle0) + "," + fmt_g(o.stats_angle1) + " deg)";
  return why + (extrema_only ? "; min, max and peak are the exact ones, tracked between outputs; "
                               "widen the window to hold an output for the others"
                             : "; widen it to hold at least one output");
}
}  // namespace

void check_options(const AnalysisOptions& o) {
  auto bad = [](const std::string& option, const std::string& what) {
    throw std::invalid_argument(option + ": " + what);
  };
  const bool window = o.stats_t0 > -1e300 || o.stats_t1 < 1e300;
  if (window) {
    const std::string w = "--window " + fmt_g(o.stats_t0) + "," + fmt_g(o.stats_t1);
    if (!std::isfinite(o.stats_t0) || !std::isfinite(o.stats_t1))
      bad(w, "both times must be finite numbers (s)");
    if (o.stats_t0 < 0) bad(w, "T0 must be >= 0 s");
    if (o.stats_t1 <= o.stats_t0) bad(w, "T0 must be less than T1");
  }
  if (!std::isnan(o.stats_angle0) || !std::isnan(o.stats_angle1)) {
    // The crank angle is taken in [0°, 360°): a bound outside [0, 360] selected part of the
    // range silently (−30,30 meant 0,30) or broke the figures' folding (±1e300).
    if (!(o.stats_angle0 >= 0 && o.stats_angle0 <= 360 && o.stats_angle1 >= 0 && o.stats_angle1 <= 360))
      bad("--angle-range " + fmt_g(o.stats_angle0) + "," + fmt_g(o.stats_angle1),
          "both angles must be numbers in [0, 360] degrees (a range across 0 is written as "
          "300,60)");
    // One angle twice selects no interval (a window T0 = T1 is refused too); 360 is 0.
    else if (std::fmod(o.stats_angle0, 360.0) == std::fmod(o.stats_angle1, 360.0) &&
             !(o.stats_angle0 == 0 && o.stats_angle1 == 360))
      bad("--angle-range " + fmt_g(o.stats_angle0) + "," + fmt_g(o.stats_angle1),
          "the two angles must differ (the whole turn is 0,360)");
  }
  if (!std::isfinite(o.period) || o.period < 0)
    bad("--period " + fmt_g(o.period), "expected a positive period in seconds");
  if (o.discard_periods < 0 || o.discard_periods > 1000000)
    bad("--discard " + std::to_string(o.discard_periods), "expected a whole number of periods in [0, 1e6]");
  if (o.lyapunov_method != "variational" && o.lyapunov_method != "two-trajectory")
    bad("--lyapunov-method " + o.lyapunov_method, "expected variational or two-trajectory");
  // 0 is the default's sentinel; below 1e-12 m the separation is lost in the positions'
  // round-off (1e-16 of a metre-sized mechanism) and the integration error.
  if (!std::isfinite(o.lyapunov_d0) || (o.lyapunov_d0 != 0 && o.lyapunov_d0 < 1e-12) ||
      o.lyapunov_d0 < 0 || o.lyapunov_d0 > 1e-3)
    bad("--lyapunov-d0 " + fmt_g(o.lyapunov_d0),
        "expected a separation in [1e-12, 1e-3] m, far below the clearance and far above the "
        "integration error (or 0 for the default)");
}

namespace {

/// What both paths settle before the main run's rows: the period and its driver, the transient,
/// the spectra, section planes and phase portraits asked for.
struct Plan {
  const Driver* drv = nullptr;
  double period = 0.0;
  std::string period_source;
  double t_start = 0.0, t_discard = 0.0;
  size_t n_out = 0, bucket = 1;
  std::vector<ChannelInfo> channels;  ///< every channel of the model
  std::vector<std::string> fft;
  std::vector<SectionPlane> planes;
  std::vector<PhasePortrait> phase;
  std::vector<int> clearance_joints;  ///< joint indices, in the workspace's order
  int free_coordinates = 0;
};

/// Degrees of freedom at the run's start: coordinates less the independent constraint rows, as
/// the constraint solver keeps them at assembly (a redundant joint equation is no restriction:
/// a free double parallelogram of three cranks has nq − m = 0 but one degree of freedom). Where
/// the start cannot be assembled, nq − m (the run fails and says why).
int free_degrees(const Model& model, const AnalysisOptions& o) {
  Workspace ws(model);
  if (ws.m == 0) return ws.nq;
  try {
    if (o.from) {
      if (!constraint_problem(model, ws, o.from->t, o.from->y, false).empty()) return ws.nq - ws.m;
    } else {
      initial_state(model, ws);
    }
  } catch (const std::exception&) {
    return ws.nq - ws.m;
  }
  if (!ws.solver) return ws.nq - ws.m;
  return ws.nq - static_cast<int>(ws.solver->active.size());
}

/// Checks the options and settles the plan; throws std::invalid_argument naming the option.
Plan plan_analysis(const Model& model, const AnalysisOptions& o) {
  const SolverSettings& s = model.solver;
  Plan p;
  p.t_start = o.from ? o.from->t : 0.0;
  p.n_out = static_cast<size_t>(std::ceil((s.end_time - p.t_start) / s.output_interval - 1e-9)) + 1;
  p.bucket = (p.n_out + o.display_points - 1) / o.display_points;

  // The options first: nothing runs when one of them is out of range or names what does not exist.
  check_options(o);
  if (o.stats_t0 > -1e300 && o.stats_t0 >= s.end_time)
    throw std::invalid_argument("--window " + fmt_g(o.stats_t0) + "," + fmt_g(o.stats_t1) +
                                ": starts at or after the run's end_time (" + fmt_g(s.end_time) +
                                " s)");
  // The period: a constant-speed driver's, else --period, else the mean speed of a rotary
  // expression driver (a start-up ramp) over the run's last half; the crank angle follows the
  // driver's prescribed motion in every case.
  p.drv = period_driver(model, o.poincare_driver);
  if (!p.drv) p.drv = rotary_driver(model, o.poincare_driver);
  if (!o.poincare_driver.empty() && !p.drv)
    throw std::invalid_argument("--poincare " + o.poincare_driver +
                                ": no revolute driver of that name");
  // A period below the output interval: the time series cannot resolve one period, and the
  // sections (one per period) and the exponent's renormalisations (20 per period) would number
  // more than the rows the run holds — without bound as the period shrinks.
  if (o.period > 0 && o.period < s.output_interval)
    throw std::invalid_argument("--period " + fmt_g(o.period) +
                                ": shorter than the run's output interval (" +
                                fmt_g(s.output_interval) +
                                " s), which cannot resolve one period; expected at least " +
                                fmt_g(s.output_interval) + " s");
  if (o.period > 0) {
    p.period = o.period;
    p.period_source = "--period " + fmt_g(o.period) + " s";
  } else if (p.drv && p.drv->profile == DriverProfile::constant_speed && p.drv->speed != 0.0) {
    p.period = 2 * M_PI / std::abs(p.drv->speed);
    p.period_source = "constant speed of driver '" + p.drv->name + "'";
  } else if (p.drv) {
    const double w = mean_driver_speed(model, *p.drv, 0.5 * s.end_time, s.end_time);
    if (std::isfinite(w)) {
      p.period = 2 * M_PI / std::abs(w);
      p.period_source = "mean speed of driver '" + p.drv->name +
                        "' over the run's last half (t = " + fmt_g(0.5 * s.end_time) + " to " +
                        fmt_g(s.end_time) + " s): " + fmt_g(w) + " rad/s";
    }
  }
  if (!std::isnan(o.stats_angle0) && !p.drv)
    throw std::invalid_argument("--angle-range needs a revolute driver");
  p.t_discard = p.t_start + (p.period > 0 ? o.discard_periods * p.period : 0.0);

  const Workspace ws(model);
  p.channels = channel_info(model, ws);
  p.clearance_joints.assign(ws.clearance_joints.begin(), ws.clearance_joints.begin() + ws.nc);
  p.free_coordinates = free_degrees(model, o);
  auto known = [&](const std::string& name) {
    for (const auto& c : p.channels)
      if (c.name == name) return true;
    return false;
  };
  // Spectra: the requested channels, else the translational bodies' ax, then each clearance
  // joint's Fn (the first one's spectrum gives the verdict its broadband share: a body's motion,
  // where there is one, rather than a contact force, impulsive whatever the motion).
  p.fft = o.fft_channels;
  if (p.fft.empty()) {
    for (const auto& j : model.joints)
      if (j.type == JointType::translational && j.b.body != kGround)
        p.fft.push_back(model.bodies[j.b.body].name + ".ax");
    for (const auto& j : model.joints)
      if (j.clearance) p.fft.push_back(j.name + ".Fn");
  }
  for (const auto& f : p.fft)
    if (!known(f)) throw std::invalid_argument("--fft " + f + ": no such channel");
  // One plane: the crossings of several would be pooled into one map, whose distinct points
  // and period would then count planes (a period-1 orbit read as period-2 on two planes).
  if (o.section_planes.size() > 1)
    throw std::invalid_argument("--plane: one section plane per analysis (" +
                                std::to_string(o.section_planes.size()) +
                                " given): the crossings of several would be pooled into one "
                                "Poincaré map; analyse each plane on its own");
  for (const auto& spec : o.section_planes) p.planes.push_back(parse_section_plane(model, spec));
  // Phase portraits: the requested pairs, else each clearance joint's ex–ey and δ–δ̇.
  if (o.phase.empty()) {
    for (int j : p.clearance_joints) {
      const std::string& n = model.joints[j].name;
      p.phase.push_back({n + ".ex", n + ".ey"});
      p.phase.push_back({n + ".delta", n + ".delta_dot"});
    }
  } else {
    for (const auto& [x, y] : o.phase) {
      if (!known(x) || !known(y))
        throw std::invalid_argument("phase portrait " + x + "," + y + ": no such channel");
      p.phase.push_back({x, y});
    }
  }
  return p;
}

/// The ideal twin, run to completion (null when not asked for, not possible or failed). Says so
/// in `prov`: `done` and the twin's own warnings (a redundant joint of the twin: its clearance
/// joint closed a loop), or why it is missing.
std::unique_ptr<Keeper> run_twin(const Model& model, const Model& twin_model,
                                 const AnalysisOptions& o, RunResult& result, Provenance& prov,
                                 const std::string& done) {
  if (!o.ideal_twin || o.from || model.clearance_joint_count() == 0) return nullptr;
  auto twin = std::make_unique<Keeper>(twin_model);
  try {
    Workspace tws(twin_model);
    RunOptions ro;
    ro.interrupt = o.interrupt;
    result = simulate(twin_model, tws, *twin, {}, {}, ro);
  } catch (const std::exception& e) {
    prov.skipped.push_back(std::string("ideal twin (every clearance joint ideal): ") + e.what());
    return nullptr;
  }
  if (!result.status.ok) {
    if (result.status.outcome != RunOutcome::interrupted)
      prov.skipped.push_back("ideal twin (every clearance joint ideal): stopped at t = " +
                             fmt_g(result.status.t) + " s: " + result.status.message);
    return nullptr;
  }
  std::string line = done;
  for (const std::string& w : result.warnings) line += "; warning: " + w;
  prov.resimulated.push_back(line);
  return twin;
}

/// Wires the twin and the spectra's channels into `sa`; a spectrum whose channel is not among
/// the rows is left out with a note in `skipped`.
/// The channels named, as the model declares them (a run's written columns); a name that is no
/// channel of the model is an error naming `what`.
std::vector<ChannelInfo> written_columns(const Plan& p, const std::vector<std::string>& names,
                                         const std::string& what) {
  std::vector<ChannelInfo> cols;
  for (const auto& name : names) {
    const auto it = std::find_if(p.channels.begin(), p.channels.end(),
                                 [&](const ChannelInfo& c) { return c.name == name; });
    if (it == p.channels.end())
      throw std::invalid_argument(what + " '" + name + "' is not a channel of the run's model");
    cols.push_back(*it);
  }
  return cols;
}

void connect(SampleAnalysis& sa, Plan& p, const Keeper* twin, std::vector<std::string>& skipped) {
  sa.t_discard = p.t_discard;
  if (twin) {
    sa.twin = twin;
    for (const auto& c : sa.channels) {
      int ti = -1;
      for (size_t i = 0; i < twin->channels.size(); ++i)
        if (twin->channels[i].name == c.name) ti = static_cast<int>(i);
      sa.twin_index.push_back(ti);
    }
    sa.dev_sq.assign(sa.channels.size(), 0.0);
    sa.dev_max.assign(sa.channels.size(), 0.0);
    sa.twin_peak.assign(sa.channels.size(), 0.0);
    sa.dev_n.assign(sa.channels.size(), 0);
  }
  for (const auto& f : p.fft) {
    const int i = sa.index(f);
    if (i >= 0) {
      sa.fft_index.push_back(i);
    } else {
      skipped.push_back("spectrum of " + f + ": the channel was not written (lash run --channels)");
    }
  }
  sa.fft_data.resize(sa.fft_index.size());
  // What needs channels the run did not write (lash run --channels) is left out and named, the
  // same during the run and from its folder.
  if (!sa.missing_pose.empty())
    skipped.push_back("animation frames: the pose (x, y, phi) of " + sa.missing_pose.front() +
                      (sa.missing_pose.size() > 1 ? " and others" : "") + " not written");
  if (!sa.missing_ecc.empty())
    skipped.push_back("journal orbits" +
                      std::string(sa.missing_pose.empty() ? " and animation frames" : "") + ": " +
                      sa.missing_ecc.front() + ".ex/ey not written (lash run --channels)");
  std::vector<PhasePortrait> kept;
  for (const auto& ph : p.phase) {
    if (sa.index(ph.x) >= 0 && sa.index(ph.y) >= 0)
      kept.push_back(ph);
    else
      skipped.push_back("phase portrait " + ph.x + " / " + ph.y + ": not written");
  }
  p.phase = std::move(kept);
}

/// Extrema by channel name: the channels of `model` in `ext`'s order.
std::map<std::string, ChannelExtremum> extrema_by_name(const Model& model, const ChannelExtrema& ext) {
  std::map<std::string, ChannelExtremum> out;
  const std::vector<ChannelInfo> names = channels_of(model);
  for (size_t i = 0; i < names.size() && i < ext.extrema().size(); ++i)
    if (ext.extrema()[i].seen) out[names[i].name] = ext.extrema()[i];
  return out;
}

/// Starts `ext` tracking the exact extrema over the statistics window (a run feeds it).
void track_window_extrema(std::optional<ChannelExtrema>& ext, const Model& model,
                          const AnalysisOptions& o) {
  std::vector<int> tracked;
  if (!o.exact_channels.empty()) {
    const std::vector<ChannelInfo> info = channel_info(model);
    for (const std::string& name : o.exact_channels)
      for (size_t i = 0; i < info.size(); ++i)
        if (info[i].name == name) tracked.push_back(static_cast<int>(i));
    if (tracked.empty()) tracked.push_back(0);  // none of them in this model: one, as cheap as any
  }
  ext.emplace(model, std::move(tracked));
  ext->set_window(o.stats_t0, o.stats_t1);
}

/// The analyses of the gathered rows: series, twin comparison, frames, statistics, contact
/// modes, sections, spectra, the Lyapunov exponent (from `lyapunov_start` at `lyapunov_t0`, when
/// given) and the verdict. `exact`: the channels' exact extrema over the statistics window (null:
/// the samples' extrema).
RunAnalysis analyze_samples(const Model& model, const AnalysisOptions& o, Plan& p,
                            SampleAnalysis& sa, std::unique_ptr<Keeper> twin,
                            const RunResult& twin_result, RunResult main,
                            const Eigen::VectorXd* lyapunov_start, double lyapunov_t0,
                            const std::map<std::string, ChannelExtremum>* exact) {
  const SolverSettings& s = model.solver;
  const int nc = static_cast<int>(p.clearance_joints.size());
  RunAnalysis out;
  out.result = std::move(main);
  sa.dec.flush();
  out.period_driver = p.drv ? p.drv->name : std::string();
  out.period = p.period;
  out.period_source = p.period_source;
  out.phase = std::move(p.phase);

  // Series (decimated), with the crank angle, and the ideal twin on the same time base.
  out.series.time = std::move(sa.dec.time);
  out.series.channels = sa.channels;
  out.series.values = std::move(sa.dec.data);
  if (p.drv && !sa.angle.empty()) {
    // The series' times are output times (first and last of each bucket): the angle there.
    const double dt = s.output_interval;
    for (double t : out.series.time) {
      const size_t k = std::min(sa.angle.size() - 1,
                                static_cast<size_t>(std::max(0.0, std::round((t - p.t_start) / dt))));
      out.crank_angle_deg.push_back(sa.angle[k]);
    }
  }
  if (twin) {
    IdealTwin it;
    it.result = twin_result;
    Decimator td(twin->channels.size(), p.bucket);
    std::vector<double> row(twin->channels.size());
    const size_t n = twin->data.empty() ? 0 : twin->data[0].size();
    for (size_t k = 0; k < n; ++k) {
      for (size_t c = 0; c < row.size(); ++c) row[c] = twin->data[c][k];
      td.add(std::min(k * s.output_interval, s.end_time), row);
    }
    td.flush();
    it.series.time = std::move(td.time);
    it.series.channels = twin->channels;
    it.series.values = std::move(td.data);
    out.ideal_twin = std::move(it);
  }

  // Animation frames.
  out.frames.time = std::move(sa.frame_t);
  for (const auto& b : model.bodies) out.frames.bodies.push_back(b.name);
  out.frames.pose = std::move(sa.poses);
  out.frames.deflection = std::move(sa.deflections);
  for (const auto& b : model.bodies) out.frames.length.push_back(b.flexible() ? b.mesh.length : 0.0);
  for (int j : p.clearance_joints) out.frames.clearance_joints.push_back(model.joints[j].name);
  out.frames.eccentricity = std::move(sa.eccentricity);

  // Statistics and the comparison with the ideal twin.
  for (size_t i = 0; i < sa.channels.size(); ++i) {
    const ChannelStats& c = sa.stats[i];
    if (c.n == 0) {
      // No output row in the window (narrower than the output interval): its exact extrema,
      // tracked between the outputs, are kept; RMS and crest factor need samples (NaN: null).
      if (!exact || !std::isnan(o.stats_angle0)) continue;
      const auto e = exact->find(sa.channels[i].name);
      if (e == exact->end()) continue;
      ChannelStatistics st;
      st.channel = sa.channels[i].name;
      st.min = e->second.min, st.t_min = e->second.t_min;
      st.max = e->second.max, st.t_max = e->second.t_max;
      st.exact = true;
      st.peak = std::max(std::abs(st.min), std::abs(st.max));
      st.rms = st.crest = std::nan("");
      st.t0 = std::max(o.stats_t0, 0.0);
      st.t1 = std::min(o.stats_t1, s.end_time);
      out.statistics.push_back(st);
      continue;
    }
    ChannelStatistics st;
    st.channel = sa.channels[i].name;
    st.samples = c.n;
    st.min = c.min;
    st.max = c.max;
    st.t_min = c.t_min;
    st.t_max = c.t_max;
    if (exact) {
      const auto e = exact->find(st.channel);
      if (e != exact->end()) {
        // Between outputs a channel can only reach further than its samples (a NaN sample is
        // not tracked): the exact extrema include the samples'. A sample read back from the
        // CSV's 9 digits may lie a rounding beyond them (30.2977414 against 30.297741356 m/s):
        // the exact one is kept then too, with its time; a sample further out is kept.
        auto rounding = [](double v) { return 5e-9 * std::abs(v) + 1e-300; };
        if (e->second.min <= c.min + rounding(c.min)) st.min = e->second.min, st.t_min = e->second.t_min;
        if (e->second.max >= c.max - rounding(c.max)) st.max = e->second.max, st.t_max = e->second.t_max;
        st.exact = true;
      }
    }
    st.peak = std::max(std::abs(st.min), std::abs(st.max));
    st.rms = c.rms();
    st.crest = st.rms > 0 ? st.peak / st.rms : 0.0;
    st.t0 = std::max(c.t0, 0.0);
    st.t1 = std::min(c.t1, s.end_time);
    st.angle0_deg = o.stats_angle0;
    st.angle1_deg = o.stats_angle1;
    out.statistics.push_back(st);
    if (twin && sa.twin_index[i] >= 0 && sa.dev_n[i] > 0) {
      // Over the statistics' rows; over the whole run with the twin's exact extrema too (those
      // are the whole run's: a window's peak against them was a ratio of two different spans).
      double ideal_peak = sa.twin_peak[i];
      const bool whole_run = std::isnan(o.stats_angle0) && o.stats_t0 <= 0.0 && o.stats_t1 >= s.end_time;
      const ChannelExtremum& te = twin->extrema.extrema()[sa.twin_index[i]];
      if (te.seen && whole_run) ideal_peak = std::max({ideal_peak, std::abs(te.min), std::abs(te.max)});
      ChannelComparison cmp;
      cmp.channel = sa.channels[i].name;
      cmp.rms_deviation = std::sqrt(sa.dev_sq[i] / sa.dev_n[i]);
      cmp.max_deviation = sa.dev_max[i];
      cmp.ideal_peak = ideal_peak;
      cmp.peak_ratio = ideal_peak > 0 ? st.peak / ideal_peak : std::nan("");
      out.ideal_twin->comparison.push_back(cmp);
    }
  }

  // Clearance joints: orbit, modes, impact velocities.
  const double t_end = out.result.status.ok ? s.end_time : out.result.status.t;
  const double cont_time = o.continuous_contact_time > 0 ? o.continuous_contact_time
                           : p.period > 0             ? 0.1 * p.period
                                                      : 1e-3;
  for (int c = 0; c < nc; ++c) {
    const Joint& jt = model.joints[p.clearance_joints[c]];
    const JointEvents& je = sa.events[c];
    ClearanceJointAnalysis ja;
    ja.joint = jt.name;
    ja.clearance = jt.clearance->clearance;
    ja.orbit = std::move(sa.orbit[c]);
    ja.continuous_contact_time = cont_time;
    // Over the statistics window (a sweep's: after its transient; the whole run by default or
    // when the window misses the run); the mode at its start is the last event's before it.
    double w0 = std::max(p.t_start, o.stats_t0), w1 = std::min(t_end, o.stats_t1);
    if (!(w0 < w1)) w0 = p.t_start, w1 = t_end, ja.modes_in_window = false;
    bool in_at_w0 = je.in_contact_at_start;
    for (size_t k = 0; k < je.t.size() && je.t[k] < w0; ++k) in_at_w0 = je.onset[k];
    ja.modes = contact_modes(je.t, je.onset, je.v, in_at_w0, w0, w1, cont_time);
    // Histogram of impact velocities: 12 bins from 0 to the largest.
    double vmax = 0;
    for (double v : ja.modes.impact_velocities) vmax = std::max(vmax, v);
    const int bins = 12;
    ja.histogram.counts.assign(bins, 0);
    for (int b = 0; b <= bins; ++b) ja.histogram.edges.push_back(vmax * b / bins);
    for (double v : ja.modes.impact_velocities)
      if (vmax > 0) ++ja.histogram.counts[std::min(bins - 1, static_cast<int>(v / vmax * bins))];
    out.clearance.push_back(std::move(ja));
  }

  // Poincaré sections: distinct points within 1% of the smallest clearance (1 µm without one).
  double tol = 1e-6;
  for (int c = 0; c < nc; ++c) {
    const double own = 0.01 * model.joints[p.clearance_joints[c]].clearance->clearance;
    tol = c == 0 ? own : std::min(tol, own);
  }
  const int distinct = count_distinct(sa.sections, tol);
  const int recurring = count_recurring(sa.sections, tol);
  const double contraction = section_contraction(sa.sections);  // (sa.sections moves on below)
  const int n_sections = static_cast<int>(sa.sections.size());
  // The period the exponent is weighed against, and the run that would give enough sections:
  // stroboscopic sections fall at k·T for k >= the discarded periods; event-based ones at the
  // rate seen so far.
  double verdict_period = p.period, min_end_time = 0.0;
  if (p.period > 0 && p.planes.empty()) {
    min_end_time = p.t_start + (kVerdictMinSections - 1 + o.discard_periods) * p.period;
  } else if (n_sections >= 2) {
    verdict_period = (sa.section_t.back() - sa.section_t.front()) / (n_sections - 1);
    min_end_time = p.t_discard + (kVerdictMinSections + 1) * verdict_period;
  }
  if (p.period > 0 || !p.planes.empty()) {
    PoincareSections ps;
    ps.kind = p.planes.empty() ? "stroboscopic" : "event";
    ps.planes = o.section_planes;
    ps.period = p.period;
    ps.discarded_periods = o.discard_periods;
    if (nc > 0) {
      const std::string& n = model.joints[p.clearance_joints[0]].name;
      ps.variables = {n + ".ex", n + ".ey"};
      for (int c = 0; c < nc; ++c)
        for (const char* e : {".ex", ".ey"})
          ps.coordinates.push_back(model.joints[p.clearance_joints[c]].name + e);
    } else {
      ps.variables = {model.bodies[0].name + ".x", model.bodies[0].name + ".y"};
      for (const auto& b : model.bodies)
        for (const char* e : {".x", ".y", ".lever_x", ".lever_y"}) ps.coordinates.push_back(b.name + e);
    }
    for (int c = 0; c < nc; ++c) {
      JointSections js;
      js.joint = model.joints[p.clearance_joints[c]].name;
      js.variables = {js.joint + ".ex", js.joint + ".ey"};
      js.tolerance = 0.01 * model.joints[p.clearance_joints[c]].clearance->clearance;
      std::vector<std::vector<double>> own;
      for (const auto& x : sa.sections) {
        js.points.push_back({x[2 * c], x[2 * c + 1]});
        own.push_back({x[2 * c], x[2 * c + 1]});
      }
      js.distinct = count_distinct(own, js.tolerance);
      ps.joints.push_back(std::move(js));
    }
    ps.points = std::move(sa.sections);
    ps.times = std::move(sa.section_t);
    ps.distinct = distinct;
    ps.tolerance = tol;
    out.poincare = std::move(ps);
  }

  // Spectra of the kept channels after the transient.
  int off_harmonic = -1;
  double broadband = std::nan("");
  for (size_t i = 0; i < sa.fft_index.size(); ++i) {
    const std::string& name = sa.channels[sa.fft_index[i]].name;
    if (sa.fft_data[i].size() < 16) {
      out.provenance.skipped.push_back(
          "spectrum of " + name + ": " + std::to_string(sa.fft_data[i].size()) +
          " outputs after the transient (t >= " + fmt_g(p.t_discard) +
          " s), 16 needed: lower --discard or run longer");
      continue;
    }
    // A channel constant to round-off (a constant-speed crank's ω) has only noise to show: no
    // spectrum, and no broadband share for the verdict.
    const auto [lo, hi] = std::minmax_element(sa.fft_data[i].begin(), sa.fft_data[i].end());
    if (!(*hi - *lo > 1e-9 * std::max(std::abs(*lo), std::abs(*hi)))) {
      out.provenance.skipped.push_back("spectrum of " + name +
                                       ": constant to 1e-9 of its magnitude after the transient "
                                       "(round-off only)");
      continue;
    }
    const Spectrum spec = amplitude_spectrum(sa.fft_data[i], s.output_interval);
    if (i == 0 && p.period > 0) off_harmonic = non_harmonic_peaks(spec, 1.0 / p.period);
    if (i == 0) broadband = broadband_share(spec);
    ChannelSpectrum cs;
    cs.channel = name;
    decimate_min_max(spec.frequency, spec.amplitude, o.spectrum_points, cs.frequency, cs.amplitude);
    cs.window = spec.window;
    cs.discarded_time = p.t_discard;
    out.spectra.push_back(std::move(cs));
  }

  // Lyapunov exponents (variational spectrum, or the largest by two trajectories),
  // renormalised 20 times per period, over the run after the
  // transient (at least one period of it).
  double lyap = std::nan("");
  if (o.lyapunov && p.free_coordinates == 0) {
    LyapunovEstimate e;
    e.message = "no free degree of freedom: the drivers fix every coordinate";
    out.lyapunov = e;
  } else if (o.lyapunov && out.result.status.ok && lyapunov_start && p.period > 0) {
    const double interval = p.period / 20.0;
    const int intervals = static_cast<int>((s.end_time - lyapunov_t0) / interval);
    if (intervals >= 20) {
      // Coulomb friction jumps where a journal's sliding velocity changes sign, a crossing no
      // event locates: the variational equations do not hold across it (their Jacobian-vector
      // products straddle the jump), so the two-trajectory method is used instead, and said so.
      std::string coulomb;
      for (const Joint& j : model.joints)
        if (coulomb.empty() && j.clearance && j.clearance->friction_law == FrictionLaw::coulomb)
          coulomb = j.name;
      const bool two = o.lyapunov_method == "two-trajectory" || !coulomb.empty();
      out.lyapunov = two ? lyapunov_from(model, *lyapunov_start, lyapunov_t0, interval, intervals,
                                         o.lyapunov_d0, o.interrupt)
                         : variational_lyapunov(model, *lyapunov_start, lyapunov_t0, interval,
                                                intervals, p.period / (2 * M_PI), o.interrupt);
      if (o.lyapunov_method != "two-trajectory" && !coulomb.empty())
        out.lyapunov->note = "two trajectories instead of the variational spectrum: joint '" +
                             coulomb + "' has Coulomb friction, whose force jumps where the "
                             "sliding velocity changes sign (a continuous law — ambrosio, "
                             "adams_stepped, lugre — allows the variational method)";
      lyap = out.lyapunov->exponent;
    } else {
      LyapunovEstimate e;
      e.message = "the run leaves " + fmt_g(s.end_time - lyapunov_t0) + " s after its first "
                  "section past the transient, at least one period (" + fmt_g(p.period) +
                  " s) needed: run longer or discard less";
      out.lyapunov = e;
    }
  } else if (o.lyapunov && !out.result.status.ok) {
    // A run that stopped early: said, as the other reasons are, not left out silently.
    LyapunovEstimate e;
    e.message = "the run stopped at t = " + fmt_g(out.result.status.t) +
                " s before its end_time; the exponent is taken over a completed run";
    out.lyapunov = e;
  } else if (o.lyapunov && out.result.status.ok && p.free_coordinates > 0) {
    // Asked for and the run completed, yet nothing to start from: said, not left out silently.
    LyapunovEstimate e;
    e.message = p.period > 0 ? "the run ends before its first section past the transient: run "
                               "longer or discard less"
                             : "no period (no rotary driver with a constant mean speed; "
                               "--period sets one)";
    out.lyapunov = e;
  }

  const Verdict v =
      classify_motion(lyap, verdict_period, distinct, n_sections, off_harmonic, min_end_time,
                      broadband, recurring, contraction);
  out.verdict.kind = v.kind;
  out.verdict.evidence = v.evidence;
  out.verdict.rule = verdict_rule();
  out.verdict.lyapunov_exponent = lyap;
  out.verdict.period = p.period;
  out.verdict.distinct_points = distinct;
  out.verdict.sections = n_sections;
  out.verdict.off_harmonic_peaks = off_harmonic;
  return out;
}

/// The period driver's angle at the times of a recorded run's rows, from its prescribed
/// motion; a speed expression's angle (an auxiliary state of the run, not written) is its
/// speed integrated by composite Simpson's rule (16 panels per output interval) from t = 0.
class RecordedAngle {
 public:
  RecordedAngle(const Model& m, const Driver* d)
      : model_(m), d_(d), ws_(m), y_(Eigen::VectorXd::Zero(ws_.ny)) {}
  double at(double t) {
    if (!d_) return std::nan("");
    const int di = static_cast<int>(d_ - model_.drivers.data());
    if (d_->profile == DriverProfile::speed) {
      constexpr int kPanels = 16;
      const double h = (t - t_) / kPanels;
      double sum = 0.0;
      for (int i = 0; i <= kPanels; ++i) {
        double f, fd, fdd;
        driver_motion(model_, ws_, di, t_ + i * h, y_.data(), f, fd, fdd);
        sum += (i == 0 || i == kPanels ? 1.0 : i % 2 ? 4.0 : 2.0) * fd;
      }
      y_[ws_.aux_driver[di]] += sum * h / 3.0;
      t_ = t;
    }
    return driver_angle_deg(model_, ws_, *d_, t, y_.data());
  }

 private:
  const Model& model_;
  const Driver* d_;
  Workspace ws_;
  Eigen::VectorXd y_;
  double t_ = 0.0;
};

}  // namespace

RunAnalysis analyze_run(const Model& model, const AnalysisOptions& o, Observer* extra) {
  Plan p = plan_analysis(model, o);

  // The ideal twin first: the main run compares with it sample by sample.
  const Model twin_model = ideal_model(model);
  RunResult twin_result;
  Provenance twin_prov;
  std::unique_ptr<Keeper> twin =
      run_twin(model, twin_model, o, twin_result, twin_prov, "ideal twin: run beside the main run");

  // The main run, observed: every channel, or those the run writes (AnalysisOptions::channels).
  Workspace ws(model);
  SampleAnalysis sa(model,
                    o.channels ? written_columns(p, *o.channels, "written channel") : p.channels,
                    o, p.n_out, p.clearance_joints);
  std::vector<std::string> unwritten;
  connect(sa, p, twin.get(), unwritten);
  sa.angle0 = o.stats_angle0;
  sa.angle1 = o.stats_angle1;
  Collector col(model, ws, sa, extra);
  col.angle_driver = p.drv;
  // Exact extrema over the window; none over a crank-angle range (they hold for times, not angles).
  std::optional<ChannelExtrema> ext;
  if (std::isnan(o.stats_angle0)) track_window_extrema(ext, model, o), col.extrema = &*ext;
  RunOptions run_options;
  run_options.interrupt = o.interrupt;
  run_options.from = o.from;
  RunResult main = simulate(model, ws, col, SectionSchedule{p.planes.empty() ? p.period : 0.0, 0.0},
                            p.planes, run_options);
  const auto exact = ext ? std::optional(extrema_by_name(model, *ext)) : std::nullopt;
  RunAnalysis out = analyze_samples(model, o, p, sa, std::move(twin), twin_result, std::move(main),
                                    col.have_lyapunov_start ? &col.lyapunov_start : nullptr,
                                    col.lyapunov_t0, exact ? &*exact : nullptr);
  out.provenance.read.push_back("the main run's outputs, events and sections, observed while it ran");
  if (const std::string none = no_statistics(out, o); !none.empty())
    out.provenance.skipped.push_back(none);
  for (const std::string& line : twin_prov.resimulated) out.provenance.resimulated.push_back(line);
  for (const std::string& line : twin_prov.skipped) out.provenance.skipped.push_back(line);
  for (std::string& line : unwritten) out.provenance.skipped.push_back(std::move(line));
  if (out.lyapunov && out.lyapunov->estimated)
    out.provenance.resimulated.push_back("Lyapunov exponent: " + lyapunov_provenance(*out.lyapunov) +
                                         " from the run's state at the first section after the "
                                         "transient");
  return out;
}

RunAnalysis analyze_recorded_run(const Model& model, const AnalysisOptions& o, RecordedRun& run) {
  if (o.from)
    throw std::invalid_argument("a recorded run is analysed from its own start (no --from)");
  Plan p = plan_analysis(model, o);
  const SolverSettings& s = model.solver;
  Provenance prov;
  prov.read = run.read;

  const std::vector<ChannelInfo> cols = written_columns(p, run.columns, run.series_file + ": column");

  const Model twin_model = ideal_model(model);
  RunResult twin_result;
  std::unique_ptr<Keeper> twin = run_twin(model, twin_model, o, twin_result, prov,
                                          "ideal twin: not saved by a run, simulated now");

  SampleAnalysis sa(model, cols, o, p.n_out, p.clearance_joints);
  connect(sa, p, twin.get(), prov.skipped);
  sa.angle0 = o.stats_angle0;
  sa.angle1 = o.stats_angle1;

  // Contact modes at the start: a joint whose first event is a separation began in contact.
  for (const RecordedEvent& e : run.events) {
    if (e.joint < 0 || e.joint >= static_cast<int>(sa.events.size())) continue;
    if (sa.events[e.joint].t.empty()) sa.events[e.joint].in_contact_at_start = !e.onset;
    sa.event(e.joint, e.t, e.onset, e.velocity);
  }

  // The rows: every analysis of the main run, and the stroboscopic sections between them.
  const SectionPoint row_point(model, p.clearance_joints, cols);
  bool rows_sections = p.planes.empty() && p.period > 0 && row_point.complete();
  SectionInterpolator strobe(sa, row_point, p.period, cols.size());
  RecordedAngle angle(model, p.drv);
  bool angle_ok = true;
  std::vector<double> v(cols.size());
  double t = 0.0, t_first = 0.0;
  bool first = true;
  while (run.next_row(t, v.data())) {
    if (first && t != 0.0 && p.drv && p.drv->profile == DriverProfile::speed) angle_ok = false;
    if (first) t_first = t;
    first = false;
    sa.output(t, v.data(), angle_ok ? angle.at(t) : std::nan(""));
    if (rows_sections) strobe.row(t, v.data());
    if (o.interrupt && o.interrupt->load() != 0) break;
  }
  // Interpolated sections are kept when their estimated error is below a tenth of the
  // tolerance within which points count as one (1% of the smallest clearance, 1 µm without one).
  std::string strobe_note;
  if (rows_sections) {
    strobe.finish();
    double tol = 1e-6;
    for (size_t c = 0; c < p.clearance_joints.size(); ++c) {
      const double own = 0.01 * model.joints[p.clearance_joints[c]].clearance->clearance;
      tol = c == 0 ? own : std::min(tol, own);
    }
    const std::string estimate =
        strobe.unestimated()
            ? std::string("the run has fewer than 4 outputs, so no interpolation error can be "
                          "estimated")
            : "estimated interpolation error " + fmt_g(strobe.largest_estimate()) + " m, " +
                  (strobe.largest_estimate() <= 0.1 * tol ? "within" : "above") +
                  " a tenth of the " + fmt_g(tol) + " m point tolerance";
    if (strobe.largest_estimate() <= 0.1 * tol) {
      const long n = strobe.sections(), exact = strobe.on_outputs();
      prov.read.push_back(exact == n ? "stroboscopic sections: from the outputs (every section "
                                       "time k·T is an output time)"
                                     : "stroboscopic sections: interpolated between outputs "
                                       "(cubic through 4 outputs; " + estimate + "), " +
                                           std::to_string(n - exact) + " of " +
                                           std::to_string(n) + " sections");
    } else {
      rows_sections = false;
      sa.sections.clear();
      sa.section_t.clear();
      strobe_note = " (interpolated between outputs: " + estimate + ")";
    }
  }
  if (!angle_ok) {
    sa.angle.clear();
    prov.skipped.push_back("crank angle: the run did not start at t = 0 and its driver follows a "
                           "speed expression");
  }

  // Exact extrema over the statistics window: summary.json's when the window is the whole run;
  // over a narrower window the main run is made again with them tracked; none over a
  // crank-angle range (they hold for times, not angles).
  std::optional<std::map<std::string, ChannelExtremum>> exact;
  std::optional<ChannelExtrema> ext;
  if (!std::isnan(o.stats_angle0)) {
    prov.skipped.push_back("exact extrema over a crank-angle range: the statistics' min, max and "
                           "peak there are the output samples'");
  } else if (o.stats_t0 <= t_first && o.stats_t1 >= t && !run.extrema.empty()) {
    exact = run.extrema;
    prov.read.push_back("exact extrema (min, max, peak, tracked between outputs): summary.json");
  } else {
    track_window_extrema(ext, model, o);
  }

  // What the files do not hold: sections on a plane (or of channels not written), the state
  // where the Lyapunov trajectories start and the extrema over a window. The main run is made
  // again as far as needed.
  const bool need_sections = (p.period > 0 || !p.planes.empty()) && !rows_sections;
  const bool want_lyapunov = o.lyapunov && p.free_coordinates > 0 && run.result.status.ok &&
                             p.period > 0 &&
                             (!rows_sections || (!sa.section_t.empty() &&
                                                 (s.end_time - sa.section_t.front()) / (p.period / 20.0) >= 20));
  Eigen::VectorXd start;
  double start_t = 0.0;
  bool have_start = false;
  if (need_sections || want_lyapunov || ext) {
    Workspace ws(model);
    Collector col(model, ws, sa, nullptr);
    col.feed_outputs = false;
    col.feed_sections = need_sections;
    col.stop_when_done = !need_sections;  // sections: to the end
    col.need_lyapunov_start = want_lyapunov;
    if (ext) col.extrema = &*ext, col.need_until = o.stats_t1;
    RunOptions ro;
    ro.interrupt = o.interrupt;
    const RunResult again = simulate(model, ws, col,
                                     SectionSchedule{p.planes.empty() ? p.period : 0.0, 0.0},
                                     p.planes, ro);
    if (need_sections)
      prov.resimulated.push_back(
          std::string(!p.planes.empty()         ? "event sections on the plane"
                      : !row_point.complete() ? "stroboscopic sections (their channels were not written)"
                                              : "stroboscopic sections" + strobe_note) +
          ": the main run made again to t = " + fmt_g(again.status.t) + " s");
    else if (want_lyapunov)
      prov.resimulated.push_back("Lyapunov start state (not written): the main run made again "
                                 "past its first section after the transient, t = " +
                                 fmt_g(col.lyapunov_t0) + " s");
    if (ext) {
      exact = extrema_by_name(model, *ext);
      prov.resimulated.push_back("exact extrema (min, max, peak) over the statistics window: the "
                                 "main run made again to t = " + fmt_g(again.status.t) + " s");
    }
    if (col.have_lyapunov_start) start = col.lyapunov_start, start_t = col.lyapunov_t0, have_start = true;
  }
  RunAnalysis out = analyze_samples(model, o, p, sa, std::move(twin), twin_result, run.result,
                                    have_start ? &start : nullptr, start_t,
                                    exact ? &*exact : nullptr);
  if (out.lyapunov && out.lyapunov->estimated)
    prov.resimulated.push_back("Lyapunov exponent: " + lyapunov_provenance(*out.lyapunov) +
                               ", simulated now");
  if (const std::string none = no_statistics(out, o); !none.empty()) prov.skipped.push_back(none);
  for (std::string& line : out.provenance.skipped) prov.skipped.push_back(std::move(line));
  out.provenance = std::move(prov);
  return out;
}

}  // namespace lash
