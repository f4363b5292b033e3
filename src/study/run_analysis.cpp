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
std::vector<ChannelInfo> channels_of(const Model& m) { return channel_info(m, Workspace(m)); }

/// Keeps every output of every channel (the ideal twin, compared sample by sample).
class Keeper : public Observer {
 public:
  explicit Keeper(const Model& m) : model_(m), channels(channels_of(m)), v_(channels.size()) {
    data.resize(channels.size());
  }
  void output(double, const Eigen::VectorXd& y, const Workspace& ws) override {
    channel_values(model_, ws, y, v_.data());
    for (size_t i = 0; i < v_.size(); ++i) data[i].push_back(v_[i]);
  }
  const Model& model_;
  std::vector<ChannelInfo> channels;
  std::vector<std::vector<double>> data;

 private:
  std::vector<double> v_;
};

/// Located onsets and separations of one clearance joint.
struct JointEvents {
  std::vector<double> t, v;
  std::vector<bool> onset;
  bool in_contact_at_start = false;
};

/// The main run's observer: forwards to `extra` and collects the analyses' inputs.
class Collector : public Observer {
 public:
  Collector(const Model& m, const Workspace& ws, const AnalysisOptions& o, size_t n_out,
            Observer* extra)
      : model_(m), channels(channel_info(m, ws)), v_(channels.size()),
        dec(channels.size(), (n_out + o.display_points - 1) / o.display_points),
        stats(channels.size()), extra_(extra) {
    frame_every_ = std::max<size_t>(1, n_out / std::max<size_t>(1, o.frames));
    orbit_every_ = std::max<size_t>(1, n_out / 4000);
    for (auto& s : stats) s.t0 = o.stats_t0, s.t1 = o.stats_t1;
    events.resize(ws.nc);
    orbit.resize(ws.nc);
    poses.resize(ws.nb);
    eccentricity.resize(ws.nc);
  }
  int index(const std::string& name) const {
    for (size_t i = 0; i < channels.size(); ++i)
      if (channels[i].name == name) return static_cast<int>(i);
    return -1;
  }
  std::string stop_reason() const override { return extra_ ? extra_->stop_reason() : std::string(); }
  void output(double t, const Eigen::VectorXd& y, const Workspace& ws) override {
    if (extra_) extra_->output(t, y, ws);
    channel_values(model_, ws, y, v_.data());
    if (k_ == 0)
      for (int c = 0; c < ws.nc; ++c) events[c].in_contact_at_start = ws.contact[c].in_contact;
    dec.add(t, v_);
    if (angle_driver) angle_deg.push_back(driver_angle_deg(model_, ws, *angle_driver, t, y.data()));
    if (in_angle_range(t))
      for (size_t i = 0; i < v_.size(); ++i) stats[i].add(t, v_[i]);
    if (twin) {
      for (size_t i = 0; i < v_.size(); ++i) {
        const int ti = twin_index[i];
        if (ti < 0 || k_ >= twin->data[ti].size()) continue;
        const double d = v_[i] - twin->data[ti][k_];
        dev_sq[i] += d * d;
        dev_max[i] = std::max(dev_max[i], std::abs(d));
        ++dev_n[i];
      }
    }
    for (size_t s = 0; s < fft_index.size(); ++s)
      if (t >= t_discard - 1e-12) fft_data[s].push_back(v_[fft_index[s]]);
    if (k_ % frame_every_ == 0) {
      frame_t.push_back(t);
      for (int b = 0; b < ws.nb; ++b)  // x, y, φ per body (φ = 0 for a point mass)
        poses[b].push_back({ws.kin[b].r.x(), ws.kin[b].r.y(), ws.kin[b].phi});
      for (int c = 0; c < ws.nc; ++c) eccentricity[c].push_back(ws.clearance_out[c].e);
    }
    if (k_ % orbit_every_ == 0)
      for (int c = 0; c < ws.nc; ++c) orbit[c].push_back(ws.clearance_out[c].e);
    ++k_;
  }
  bool in_angle_range(double t) const {
    if (!angle_driver || std::isnan(angle0) || std::isnan(angle1)) return true;
    const double deg = angle_deg.empty() ? 0.0 : angle_deg.back();
    return angle0 <= angle1 ? (deg >= angle0 && deg <= angle1) : (deg >= angle0 || deg <= angle1);
  }
  void event(const ContactEvent& e, const Workspace& ws) override {
    if (extra_) extra_->event(e, ws);
    JointEvents& je = events[e.clearance];
    je.t.push_back(e.t);
    je.v.push_back(e.velocity);
    je.onset.push_back(e.onset);
  }
  void progress(double t, double t_end) override {
    if (extra_) extra_->progress(t, t_end);
  }
  bool wants_steps() const override { return extra_ && extra_->wants_steps(); }
  void step(double t0, double t1, const Eigen::VectorXd& y, const Workspace& ws,
            StepProbe& probe) override {
    if (extra_) extra_->step(t0, t1, y, ws, probe);
  }
  void section(double t, const Eigen::VectorXd& y, const Workspace& ws) override {
    if (extra_) extra_->section(t, y, ws);
    if (t < t_discard - 1e-12) return;
    if (!have_lyapunov_start) {
      lyapunov_start = y;
      lyapunov_t0 = t;
      have_lyapunov_start = true;
    }
    std::vector<double> p;
    for (int c = 0; c < ws.nc; ++c) {
      p.push_back(ws.clearance_out[c].e.x());
      p.push_back(ws.clearance_out[c].e.y());
    }
    if (ws.nc == 0)  // no clearance joint: the bodies' positions, angles as cos/sin (mod 2π)
      for (int b = 0; b < ws.nb; ++b) {
        const BodyKin k = body_kin(ws, b, y.data());
        p.push_back(k.r.x());
        p.push_back(k.r.y());
        p.push_back(std::cos(k.phi) * 1e-2);  // 1 cm lever: comparable to positions
        p.push_back(std::sin(k.phi) * 1e-2);
      }
    sections.push_back(std::move(p));
    section_t.push_back(t);
  }

  const Model& model_;
  std::vector<ChannelInfo> channels;
  std::vector<double> v_;
  Decimator dec;
  std::vector<ChannelStats> stats;
  const Keeper* twin = nullptr;
  std::vector<int> twin_index;
  std::vector<double> dev_sq, dev_max;
  std::vector<long> dev_n;
  std::vector<int> fft_index;
  std::vector<std::vector<double>> fft_data;
  double t_discard = 0.0;
  const Driver* angle_driver = nullptr;
  std::vector<double> angle_deg;  ///< the angle driver's angle at every output, deg
  double angle0 = std::nan(""), angle1 = std::nan("");
  std::vector<double> frame_t;
  std::vector<std::vector<std::array<double, 3>>> poses;
  std::vector<std::vector<Vec2>> eccentricity;
  std::vector<std::vector<Vec2>> orbit;
  std::vector<JointEvents> events;
  std::vector<std::vector<double>> sections;
  std::vector<double> section_t;
  Eigen::VectorXd lyapunov_start;
  double lyapunov_t0 = 0.0;
  bool have_lyapunov_start = false;

 private:
  Observer* extra_;
  size_t frame_every_ = 1, orbit_every_ = 1, k_ = 0;
};

/// Strong spectral peaks (> 10% of the largest) that are not within two bins of a harmonic of f0.
int non_harmonic_peaks(const Spectrum& s, double f0) {
  if (s.amplitude.size() < 3 || !(f0 > 0)) return -1;
  double top = 0;
  for (size_t k = 1; k < s.amplitude.size(); ++k) top = std::max(top, s.amplitude[k]);
  const double df = s.frequency[1] - s.frequency[0];
  int n = 0;
  for (size_t k = 1; k + 1 < s.amplitude.size(); ++k) {
    const double a = s.amplitude[k];
    if (a < 0.1 * top || a < s.amplitude[k - 1] || a < s.amplitude[k + 1]) continue;
    const double h = s.frequency[k] / f0;
    if (std::abs(h - std::round(h)) * f0 > 2 * df) ++n;
  }
  return n;
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
    driver_motion(model, ws, di, t, y.data(), f, fd, fdd);
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
  return ideal;
}

namespace {
std::string fmt_g(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
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
    if (!std::isfinite(o.stats_angle0) || !std::isfinite(o.stats_angle1))
      bad("--angle-range " + fmt_g(o.stats_angle0) + "," + fmt_g(o.stats_angle1),
          "both angles must be finite numbers (degrees)");
  }
  if (!std::isfinite(o.period) || o.period < 0)
    bad("--period " + fmt_g(o.period), "expected a positive period in seconds");
  if (o.discard_periods < 0 || o.discard_periods > 1000000)
    bad("--discard " + std::to_string(o.discard_periods), "expected a whole number of periods in [0, 1e6]");
  if (o.lyapunov_method != "variational" && o.lyapunov_method != "two-trajectory")
    bad("--lyapunov-method " + o.lyapunov_method, "expected variational or two-trajectory");
  if (!std::isfinite(o.lyapunov_d0) || o.lyapunov_d0 < 0 || o.lyapunov_d0 > 1e-3)
    bad("--lyapunov-d0 " + fmt_g(o.lyapunov_d0),
        "expected a separation > 0 m and at most 1e-3 m, far below the clearance (or 0 for the "
        "default)");
}

RunAnalysis analyze_run(const Model& model, const AnalysisOptions& o, Observer* extra) {
  const SolverSettings& s = model.solver;
  const double t_start = o.from ? o.from->t : 0.0;
  const size_t n_out =
      static_cast<size_t>(std::ceil((s.end_time - t_start) / s.output_interval - 1e-9)) + 1;
  const size_t bucket = (n_out + o.display_points - 1) / o.display_points;

  // The options first: nothing runs when one of them is out of range or names what does not exist.
  check_options(o);
  if (o.stats_t0 > -1e300 && o.stats_t0 >= s.end_time)
    throw std::invalid_argument("--window " + fmt_g(o.stats_t0) + "," + fmt_g(o.stats_t1) +
                                ": starts at or after the run's end_time (" + fmt_g(s.end_time) +
                                " s)");
  // The period: a constant-speed driver's, else --period, else the mean speed of a rotary
  // expression driver (a start-up ramp) over the run's last half; the crank angle follows the
  // driver's prescribed motion in every case.
  const Driver* drv = period_driver(model, o.poincare_driver);
  if (!drv) drv = rotary_driver(model, o.poincare_driver);
  if (!o.poincare_driver.empty() && !drv)
    throw std::invalid_argument("--poincare " + o.poincare_driver +
                                ": no revolute driver of that name");
  double period = 0.0;
  std::string period_source;
  if (o.period > 0) {
    period = o.period;
    period_source = "--period " + fmt_g(o.period) + " s";
  } else if (drv && drv->profile == DriverProfile::constant_speed && drv->speed != 0.0) {
    period = 2 * M_PI / std::abs(drv->speed);
    period_source = "constant speed of driver '" + drv->name + "'";
  } else if (drv) {
    const double w = mean_driver_speed(model, *drv, 0.5 * s.end_time, s.end_time);
    if (std::isfinite(w)) {
      period = 2 * M_PI / std::abs(w);
      period_source = "mean speed of driver '" + drv->name + "' over the run's last half (t = " +
                      fmt_g(0.5 * s.end_time) + " to " + fmt_g(s.end_time) + " s): " + fmt_g(w) +
                      " rad/s";
    }
  }
  if (!std::isnan(o.stats_angle0) && !drv)
    throw std::invalid_argument("--angle-range needs a revolute driver");
  const double t_discard = t_start + (period > 0 ? o.discard_periods * period : 0.0);

  Workspace ws(model);
  const std::vector<ChannelInfo> channels = channel_info(model, ws);
  auto channel_index = [&](const std::string& name) {
    for (size_t i = 0; i < channels.size(); ++i)
      if (channels[i].name == name) return static_cast<int>(i);
    return -1;
  };
  // Spectra: the requested channels, else translational bodies' ax and each clearance Fn.
  std::vector<std::string> fft = o.fft_channels;
  if (fft.empty()) {
    for (const auto& j : model.joints) {
      if (j.type == JointType::translational && j.b.body != kGround)
        fft.push_back(model.bodies[j.b.body].name + ".ax");
      if (j.clearance) fft.push_back(j.name + ".Fn");
    }
  }
  std::vector<int> fft_index;
  for (const auto& f : fft) {
    const int i = channel_index(f);
    if (i < 0) throw std::invalid_argument("--fft " + f + ": no such channel");
    fft_index.push_back(i);
  }
  std::vector<SectionPlane> planes;
  for (const auto& spec : o.section_planes) planes.push_back(parse_section_plane(model, spec));
  // Phase portraits: the requested pairs, else each clearance joint's ex–ey and δ–δ̇.
  std::vector<PhasePortrait> phase;
  if (o.phase.empty()) {
    for (int c = 0; c < ws.nc; ++c) {
      const std::string& n = model.joints[ws.clearance_joints[c]].name;
      phase.push_back({n + ".ex", n + ".ey"});
      phase.push_back({n + ".delta", n + ".delta_dot"});
    }
  } else {
    for (const auto& [x, y] : o.phase) {
      if (channel_index(x) < 0 || channel_index(y) < 0)
        throw std::invalid_argument("phase portrait " + x + "," + y + ": no such channel");
      phase.push_back({x, y});
    }
  }

  // The ideal twin first: the main run compares with it sample by sample.
  const Model twin_model = ideal_model(model);
  std::unique_ptr<Keeper> twin;
  RunResult twin_result;
  if (o.ideal_twin && !o.from && model.clearance_joint_count() > 0) {
    Workspace tws(twin_model);
    twin = std::make_unique<Keeper>(twin_model);
    RunOptions ro;
    ro.interrupt = o.interrupt;
    twin_result = simulate(twin_model, tws, *twin, {}, {}, ro);
    if (!twin_result.status.ok) twin.reset();
  }

  // The main run.
  Collector col(model, ws, o, n_out, extra);
  col.t_discard = t_discard;
  col.angle_driver = drv;
  col.angle0 = o.stats_angle0;
  col.angle1 = o.stats_angle1;
  if (twin) {
    col.twin = twin.get();
    for (const auto& c : col.channels) {
      int ti = -1;
      for (size_t i = 0; i < twin->channels.size(); ++i)
        if (twin->channels[i].name == c.name) ti = static_cast<int>(i);
      col.twin_index.push_back(ti);
    }
    col.dev_sq.assign(col.channels.size(), 0.0);
    col.dev_max.assign(col.channels.size(), 0.0);
    col.dev_n.assign(col.channels.size(), 0);
  }
  col.fft_index = fft_index;
  col.fft_data.resize(fft_index.size());

  RunAnalysis out;
  RunOptions run_options;
  run_options.interrupt = o.interrupt;
  run_options.from = o.from;
  out.result = simulate(model, ws, col, SectionSchedule{planes.empty() ? period : 0.0, 0.0}, planes,
                        run_options);
  col.dec.flush();
  out.period_driver = drv ? drv->name : std::string();
  out.period = period;
  out.period_source = period_source;
  out.phase = std::move(phase);

  // Series (decimated), with the crank angle, and the ideal twin on the same time base.
  out.series.time = std::move(col.dec.time);
  out.series.channels = channels;
  out.series.values = std::move(col.dec.data);
  if (drv && !col.angle_deg.empty()) {
    // The series' times are output times (first and last of each bucket): the angle there.
    const double dt = s.output_interval;
    for (double t : out.series.time) {
      const size_t k = std::min(col.angle_deg.size() - 1,
                                static_cast<size_t>(std::max(0.0, std::round(t / dt))));
      out.crank_angle_deg.push_back(col.angle_deg[k]);
    }
  }
  if (twin) {
    IdealTwin it;
    it.result = twin_result;
    Decimator td(twin->channels.size(), bucket);
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
  out.frames.time = std::move(col.frame_t);
  for (int b = 0; b < ws.nb; ++b) out.frames.bodies.push_back(model.bodies[b].name);
  out.frames.pose = std::move(col.poses);
  for (int c = 0; c < ws.nc; ++c)
    out.frames.clearance_joints.push_back(model.joints[ws.clearance_joints[c]].name);
  out.frames.eccentricity = std::move(col.eccentricity);

  // Statistics and the comparison with the ideal twin.
  for (size_t i = 0; i < channels.size(); ++i) {
    const ChannelStats& c = col.stats[i];
    if (c.n == 0) continue;
    ChannelStatistics st;
    st.channel = channels[i].name;
    st.samples = c.n;
    st.min = c.min;
    st.max = c.max;
    st.peak = c.peak();
    st.rms = c.rms();
    st.crest = c.crest();
    st.t0 = std::max(c.t0, 0.0);
    st.t1 = std::min(c.t1, s.end_time);
    st.angle0_deg = o.stats_angle0;
    st.angle1_deg = o.stats_angle1;
    out.statistics.push_back(st);
    if (twin && col.twin_index[i] >= 0 && col.dev_n[i] > 0) {
      const auto& tv = twin->data[col.twin_index[i]];
      double ideal_peak = 0;
      for (double v : tv) ideal_peak = std::max(ideal_peak, std::abs(v));
      ChannelComparison cmp;
      cmp.channel = channels[i].name;
      cmp.rms_deviation = std::sqrt(col.dev_sq[i] / col.dev_n[i]);
      cmp.max_deviation = col.dev_max[i];
      cmp.ideal_peak = ideal_peak;
      cmp.peak_ratio = ideal_peak > 0 ? c.peak() / ideal_peak : 0.0;
      out.ideal_twin->comparison.push_back(cmp);
    }
  }

  // Clearance joints: orbit, modes, impact velocities.
  const double t_end = out.result.status.ok ? s.end_time : out.result.status.t;
  const double cont_time = o.continuous_contact_time > 0 ? o.continuous_contact_time
                           : period > 0               ? 0.1 * period
                                                      : 1e-3;
  for (int c = 0; c < ws.nc; ++c) {
    const Joint& jt = model.joints[ws.clearance_joints[c]];
    const JointEvents& je = col.events[c];
    ClearanceJointAnalysis ja;
    ja.joint = jt.name;
    ja.clearance = jt.clearance->clearance;
    ja.orbit = std::move(col.orbit[c]);
    ja.continuous_contact_time = cont_time;
    ja.modes = contact_modes(je.t, je.onset, je.v, je.in_contact_at_start, t_start, t_end, cont_time);
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
  for (int c = 0; c < ws.nc; ++c)
    tol = c == 0 ? 0.01 * model.joints[ws.clearance_joints[c]].clearance->clearance
                 : std::min(tol, 0.01 * model.joints[ws.clearance_joints[c]].clearance->clearance);
  const int distinct = count_distinct(col.sections, tol);
  const int n_sections = static_cast<int>(col.sections.size());
  // The period the exponent is weighed against, and the run that would give enough sections:
  // stroboscopic sections fall at k·T for k >= the discarded periods; event-based ones at the
  // rate seen so far.
  double verdict_period = period, min_end_time = 0.0;
  if (period > 0 && planes.empty()) {
    min_end_time = t_start + (kVerdictMinSections - 1 + o.discard_periods) * period;
  } else if (n_sections >= 2) {
    verdict_period = (col.section_t.back() - col.section_t.front()) / (n_sections - 1);
    min_end_time = t_discard + (kVerdictMinSections + 1) * verdict_period;
  }
  if (period > 0 || !planes.empty()) {
    PoincareSections p;
    p.kind = planes.empty() ? "stroboscopic" : "event";
    p.planes = o.section_planes;
    p.period = period;
    p.discarded_periods = o.discard_periods;
    if (ws.nc > 0) {
      const std::string& n = model.joints[ws.clearance_joints[0]].name;
      p.variables = {n + ".ex", n + ".ey"};
    } else {
      p.variables = {model.bodies[0].name + ".x", model.bodies[0].name + ".y"};
    }
    for (int c = 0; c < ws.nc; ++c) {
      JointSections js;
      js.joint = model.joints[ws.clearance_joints[c]].name;
      js.variables = {js.joint + ".ex", js.joint + ".ey"};
      js.tolerance = 0.01 * model.joints[ws.clearance_joints[c]].clearance->clearance;
      std::vector<std::vector<double>> own;
      for (const auto& x : col.sections) {
        js.points.push_back({x[2 * c], x[2 * c + 1]});
        own.push_back({x[2 * c], x[2 * c + 1]});
      }
      js.distinct = count_distinct(own, js.tolerance);
      p.joints.push_back(std::move(js));
    }
    p.points = std::move(col.sections);
    p.times = std::move(col.section_t);
    p.distinct = distinct;
    p.tolerance = tol;
    out.poincare = std::move(p);
  }

  // Spectra of the kept channels after the transient.
  int off_harmonic = -1;
  for (size_t i = 0; i < col.fft_index.size(); ++i) {
    if (col.fft_data[i].size() < 16) continue;
    const Spectrum spec = amplitude_spectrum(col.fft_data[i], s.output_interval);
    if (i == 0 && period > 0) off_harmonic = non_harmonic_peaks(spec, 1.0 / period);
    ChannelSpectrum cs;
    cs.channel = channels[col.fft_index[i]].name;
    decimate_min_max(spec.frequency, spec.amplitude, o.spectrum_points, cs.frequency, cs.amplitude);
    cs.window = spec.window;
    cs.discarded_time = t_discard;
    out.spectra.push_back(std::move(cs));
  }

  // Lyapunov exponents (variational spectrum, or the largest by two trajectories),
  // renormalised 20 times per period, over the run after the
  // transient (at least one period of it).
  double lyap = std::nan("");
  if (o.lyapunov && ws.nq - ws.m == 0) {
    LyapunovEstimate e;
    e.message = "no free degree of freedom: the drivers fix every coordinate";
    out.lyapunov = e;
  } else if (o.lyapunov && out.result.status.ok && col.have_lyapunov_start && period > 0) {
    const double interval = period / 20.0;
    const int intervals = static_cast<int>((s.end_time - col.lyapunov_t0) / interval);
    if (intervals >= 20) {
      out.lyapunov =
          o.lyapunov_method == "two-trajectory"
              ? lyapunov_from(model, col.lyapunov_start, col.lyapunov_t0, interval, intervals,
                              o.lyapunov_d0, o.interrupt)
              : variational_lyapunov(model, col.lyapunov_start, col.lyapunov_t0, interval,
                                     intervals, period / (2 * M_PI), o.interrupt);
      lyap = out.lyapunov->exponent;
    }
  }

  const Verdict v =
      classify_motion(lyap, verdict_period, distinct, n_sections, off_harmonic, min_end_time);
  out.verdict.kind = v.kind;
  out.verdict.evidence = v.evidence;
  out.verdict.rule = verdict_rule();
  out.verdict.lyapunov_exponent = lyap;
  out.verdict.period = period;
  out.verdict.distinct_points = distinct;
  out.verdict.sections = n_sections;
  out.verdict.off_harmonic_peaks = off_harmonic;
  return out;
}

}  // namespace lash
