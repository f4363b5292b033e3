#include "io/report.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>

#include "analysis/dynamics_analysis.hpp"
#include "analysis/signal.hpp"
#include "io/results_writer.hpp"
#include "report_assets.hpp"

namespace lash {

namespace {

using nlohmann::json;

/// Six significant digits: enough for display, and short in JSON.
double r6(double v) {
  if (v == 0.0 || !std::isfinite(v)) return std::isfinite(v) ? 0.0 : v;
  const double scale = std::pow(10.0, 5 - static_cast<int>(std::floor(std::log10(std::abs(v)))));
  return std::round(v * scale) / scale;
}
std::vector<double> r6(std::vector<double> v) {
  for (double& x : v) x = r6(x);
  return v;
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

/// The channel names of a model, in column order.
std::vector<std::string> names_of(const Model& m) {
  std::vector<std::string> n;
  for (const auto& c : channel_info(m, Workspace(m))) n.push_back(c.name);
  return n;
}

/// Keeps every output of every channel (the ideal twin, compared sample by sample).
class Keeper : public Observer {
 public:
  explicit Keeper(const Model& m) : model_(m), names(names_of(m)), v_(names.size()) {
    data.resize(names.size());
  }
  void output(double, const Eigen::VectorXd& y, const Workspace& ws) override {
    channel_values(model_, ws, y, v_.data());
    for (size_t i = 0; i < v_.size(); ++i) data[i].push_back(v_[i]);
  }
  const Model& model_;
  std::vector<std::string> names;
  std::vector<std::vector<double>> data;

 private:
  std::vector<double> v_;
};

struct JointEvents {
  std::vector<double> t, v;
  std::vector<bool> onset;
  bool in_contact_at_start = false;
};

/// The main run's observer: streams to the results writer and collects the analyses' inputs.
class Collector : public Observer {
 public:
  Collector(const Model& m, const Workspace& ws, const ReportOptions& o, size_t n_out,
            ResultsWriter* writer, Observer* progress)
      : model_(m), names(names_of(m)), v_(names.size()),
        dec(names.size(), (n_out + o.display_points - 1) / o.display_points),
        stats(names.size()), writer_(writer), progress_(progress) {
    frame_every_ = std::max<size_t>(1, n_out / std::max<size_t>(1, o.frames));
    orbit_every_ = std::max<size_t>(1, n_out / 4000);
    for (auto& s : stats) s.t0 = o.stats_t0, s.t1 = o.stats_t1;
    events.resize(ws.nc);
    orbit.resize(ws.nc);
  }
  int index(const std::string& name) const {
    for (size_t i = 0; i < names.size(); ++i)
      if (names[i] == name) return static_cast<int>(i);
    return -1;
  }
  void output(double t, const Eigen::VectorXd& y, const Workspace& ws) override {
    if (writer_) writer_->output(t, y, ws);
    if (progress_) progress_->output(t, y, ws);
    channel_values(model_, ws, y, v_.data());
    if (k_ == 0)
      for (int c = 0; c < ws.nc; ++c) events[c].in_contact_at_start = ws.contact[c].in_contact;
    dec.add(t, v_);
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
      std::vector<double> f;
      for (int b = 0; b < ws.nb; ++b) {  // x, y, φ per body (φ = 0 for a point mass)
        f.push_back(ws.kin[b].r.x());
        f.push_back(ws.kin[b].r.y());
        f.push_back(ws.kin[b].phi);
      }
      for (int c = 0; c < ws.nc; ++c) {
        f.push_back(ws.clearance_out[c].e.x());
        f.push_back(ws.clearance_out[c].e.y());
      }
      frames.push_back(std::move(f));
    }
    if (k_ % orbit_every_ == 0)
      for (int c = 0; c < ws.nc; ++c) orbit[c].push_back(ws.clearance_out[c].e);
    ++k_;
  }
  bool in_angle_range(double t) const {
    if (!angle_driver || std::isnan(angle0) || std::isnan(angle1)) return true;
    double deg = std::fmod((angle_driver->initial + angle_driver->speed * t) * 180.0 / M_PI, 360.0);
    if (deg < 0) deg += 360.0;
    return angle0 <= angle1 ? (deg >= angle0 && deg <= angle1) : (deg >= angle0 || deg <= angle1);
  }
  void event(const ContactEvent& e, const Workspace& ws) override {
    if (writer_) writer_->event(e, ws);
    JointEvents& je = events[e.clearance];
    je.t.push_back(e.t);
    je.v.push_back(e.velocity);
    je.onset.push_back(e.onset);
  }
  void progress(double t, double t_end) override {
    if (progress_) progress_->progress(t, t_end);
  }
  void section(double t, const Eigen::VectorXd& y, const Workspace& ws) override {
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
  std::vector<std::string> names;
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
  double angle0 = std::nan(""), angle1 = std::nan("");
  std::vector<double> frame_t;
  std::vector<std::vector<double>> frames;
  std::vector<std::vector<Vec2>> orbit;
  std::vector<JointEvents> events;
  std::vector<std::vector<double>> sections;
  std::vector<double> section_t;
  Eigen::VectorXd lyapunov_start;
  double lyapunov_t0 = 0.0;
  bool have_lyapunov_start = false;

 private:
  ResultsWriter* writer_;
  Observer* progress_;
  size_t frame_every_ = 1, orbit_every_ = 1, k_ = 0;
};

json point_json(const Model& m, const PointRef& p) {
  return {{"body", p.body == kGround ? std::string("ground") : m.bodies[p.body].name},
          {"point", {p.s.x(), p.s.y()}}};
}

json model_json(const Model& m) {
  json j;
  j["name"] = m.name;
  j["file"] = m.source;
  j["bodies"] = json::array();
  for (const auto& b : m.bodies) {
    json mk = json::object();
    for (const auto& x : b.markers) mk[x.name] = {x.s_P_B.x(), x.s_P_B.y()};
    j["bodies"].push_back({{"name", b.name}, {"mass", b.mass}, {"inertia", b.inertia}, {"markers", mk}});
  }
  // Ground points used by joints and loads (the ground has no marker list in the Model).
  json gm = json::object();
  for (const auto& jt : m.joints)
    for (const PointRef* p : {&jt.a, &jt.b})
      if (p->body == kGround) gm[p->label.empty() ? "O" : p->label] = {p->s.x(), p->s.y()};
  j["ground_markers"] = gm;
  j["joints"] = json::array();
  for (const auto& jt : m.joints) {
    const char* type = jt.type == JointType::revolute ? "revolute"
                       : jt.type == JointType::translational ? "translational" : "fixed";
    json x = {{"name", jt.name}, {"type", type}, {"a", point_json(m, jt.a)},
              {"b", point_json(m, jt.b)}, {"axis", {jt.axis.x(), jt.axis.y()}}};
    if (jt.clearance)
      x["clearance"] = {{"clearance", jt.clearance->clearance},
                        {"journal_radius", jt.clearance->journal_radius},
                        {"bearing_radius", jt.clearance->bearing_radius},
                        {"stiffness", jt.clearance->contact.stiffness},
                        {"normal_law", std::string(normal_law_name(jt.clearance->normal_law))},
                        {"friction_law", std::string(friction_law_name(jt.clearance->friction_law))}};
    else
      x["clearance"] = nullptr;
    j["joints"].push_back(x);
  }
  j["drivers"] = json::array();
  for (const auto& d : m.drivers)
    j["drivers"].push_back(
        {{"name", d.name},
         {"joint", d.target == DriverTarget::joint ? m.joints[d.joint].name : std::string()},
         {"body", d.target == DriverTarget::body ? m.bodies[d.body].name : std::string()},
         {"speed", d.speed},
         {"profile", d.profile == DriverProfile::constant_speed ? "constant_speed"
                     : d.profile == DriverProfile::position     ? "position"
                                                                : "speed"},
         {"expression", d.expression}});
  const SolverSettings& s = m.solver;
  j["solver"] = {{"integrator", s.integrator == IntegratorKind::bdf ? "bdf" : "dopri5"},
                 {"rtol", s.rtol}, {"atol", s.atol}, {"end_time", s.end_time},
                 {"output_interval", s.output_interval}};
  return j;
}

/// The rotary driver that sets the period: named, else the first constant-speed revolute one.
const Driver* period_driver(const Model& m, const std::string& name) {
  for (const auto& d : m.drivers) {
    const bool rotary = driver_is_rotary(m, d) && d.profile == DriverProfile::constant_speed &&
                        d.speed != 0.0;
    if (name.empty() ? rotary : d.name == name) return rotary ? &d : nullptr;
  }
  return nullptr;
}

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

}  // namespace

ReportRun run_with_analysis(const LoadedModel& loaded, const ReportOptions& o,
                            ResultsWriter* writer, Observer* progress) {
  const Model& model = loaded.model;
  const SolverSettings& s = model.solver;
  const size_t n_out = static_cast<size_t>(std::ceil(s.end_time / s.output_interval - 1e-9)) + 1;
  const Driver* drv = period_driver(model, o.poincare_driver);
  if (!o.poincare_driver.empty() && !drv)
    throw std::invalid_argument("--poincare " + o.poincare_driver +
                                ": no constant-speed revolute driver of that name");
  const double period = drv ? 2 * M_PI / std::abs(drv->speed) : 0.0;
  const double t_discard = period > 0 ? o.discard_periods * period : 0.0;

  // The ideal twin first: the main run compares with it sample by sample.
  Model twin_model = model;
  for (auto& j : twin_model.joints) j.clearance.reset();
  std::unique_ptr<Keeper> twin;
  if (o.ideal_twin && model.clearance_joint_count() > 0) {
    Workspace tws(twin_model);
    twin = std::make_unique<Keeper>(twin_model);
    const RunResult tr = simulate(twin_model, tws, *twin);
    if (!tr.status.ok) twin.reset();
  }

  Workspace ws(model);
  Collector col(model, ws, o, n_out, writer, progress);
  col.t_discard = t_discard;
  col.angle_driver = drv;
  col.angle0 = o.stats_angle0;
  col.angle1 = o.stats_angle1;
  if (!std::isnan(o.stats_angle0) && !drv)
    throw std::invalid_argument("--angle-range needs a constant-speed revolute driver");
  if (twin) {
    col.twin = twin.get();
    for (const auto& n : col.names) {
      int ti = -1;
      for (size_t i = 0; i < twin->names.size(); ++i)
        if (twin->names[i] == n) ti = static_cast<int>(i);
      col.twin_index.push_back(ti);
    }
    col.dev_sq.assign(col.names.size(), 0.0);
    col.dev_max.assign(col.names.size(), 0.0);
    col.dev_n.assign(col.names.size(), 0);
  }
  // Spectra: the requested channels, else translational bodies' ax and each clearance Fn.
  std::vector<std::string> fft = o.fft_channels;
  if (fft.empty()) {
    for (const auto& j : model.joints) {
      if (j.type == JointType::translational && j.b.body != kGround)
        fft.push_back(model.bodies[j.b.body].name + ".ax");
      if (j.clearance) fft.push_back(j.name + ".Fn");
    }
  }
  for (const auto& f : fft) {
    const int i = col.index(f);
    if (i < 0) throw std::invalid_argument("--fft " + f + ": no such channel");
    col.fft_index.push_back(i);
  }
  col.fft_data.resize(col.fft_index.size());

  ReportRun out;
  std::vector<SectionPlane> planes;
  for (const auto& spec : o.section_planes) planes.push_back(parse_section_plane(model, spec));
  out.result = simulate(model, ws, col, SectionSchedule{planes.empty() ? period : 0.0, 0.0}, planes);
  col.dec.flush();

  json d;
  d["version"] = 1;
  d["model"] = model_json(model);
  d["status"] = {{"ok", out.result.status.ok}, {"time", out.result.status.t},
                 {"element", out.result.status.element}, {"message", out.result.status.message}};
  d["integrator"] = {{"name", out.result.integrator}, {"steps", out.result.stats.steps},
                     {"rejected_steps", out.result.stats.rejected_steps},
                     {"rhs_evaluations", out.result.stats.rhs_evaluations},
                     {"events", out.result.stats.events},
                     {"wall_seconds", out.result.wall_seconds}, {"outputs", out.result.outputs}};
  d["max_constraint_violation"] = out.result.max_constraint_violation;

  // Series (decimated) and the ideal twin on the same time base.
  json series;
  series["time"] = r6(col.dec.time);
  if (drv) {
    std::vector<double> angle;
    for (double t : col.dec.time) {
      const double deg = std::fmod((drv->initial + drv->speed * t) * 180.0 / M_PI, 360.0);
      angle.push_back(r6(deg < 0 ? deg + 360.0 : deg));
    }
    series["crank_angle"] = angle;
  } else {
    series["crank_angle"] = nullptr;
  }
  json channels = json::object();
  for (size_t i = 0; i < col.names.size(); ++i) channels[col.names[i]] = r6(col.dec.data[i]);
  // Units and descriptions, as the element kinds declare them (report.js and the figures read
  // them from here and never guess from a name).
  json info = json::object();
  for (const auto& c : channel_info(model, ws))
    info[c.name] = {{"unit", c.unit}, {"description", c.description}};
  d["channel_info"] = info;
  series["channels"] = channels;
  if (twin) {
    Decimator td(twin->names.size(), (n_out + o.display_points - 1) / o.display_points);
    std::vector<double> row(twin->names.size());
    const size_t n = twin->data.empty() ? 0 : twin->data[0].size();
    for (size_t k = 0; k < n; ++k) {
      for (size_t c = 0; c < row.size(); ++c) row[c] = twin->data[c][k];
      td.add(std::min(k * s.output_interval, s.end_time), row);
    }
    td.flush();
    json ideal = json::object();
    for (size_t c = 0; c < twin->names.size(); ++c)
      if (col.index(twin->names[c]) >= 0) ideal[twin->names[c]] = r6(td.data[c]);
    series["ideal"] = ideal;
  } else {
    series["ideal"] = nullptr;
  }
  d["series"] = series;

  // Animation frames.
  json frames;
  frames["time"] = r6(col.frame_t);
  json fb = json::object(), fc = json::object();
  for (int b = 0; b < ws.nb; ++b) {
    json arr = json::array();
    for (const auto& f : col.frames) arr.push_back({r6(f[3 * b]), r6(f[3 * b + 1]), r6(f[3 * b + 2])});
    fb[model.bodies[b].name] = arr;
  }
  for (int c = 0; c < ws.nc; ++c) {
    json arr = json::array();
    for (const auto& f : col.frames)
      arr.push_back({r6(f[3 * ws.nb + 2 * c]), r6(f[3 * ws.nb + 2 * c + 1])});
    fc[model.joints[ws.clearance_joints[c]].name] = arr;
  }
  frames["bodies"] = fb;
  frames["clearance"] = fc;
  d["frames"] = frames;

  // Statistics and the comparison with the ideal twin.
  json an, st = json::object(), cmp = json::object();
  for (size_t i = 0; i < col.names.size(); ++i) {
    const ChannelStats& c = col.stats[i];
    if (c.n == 0) continue;
    st[col.names[i]] = {{"min", c.min}, {"max", c.max}, {"peak", c.peak()}, {"rms", c.rms()},
                        {"crest", c.crest()},
                        {"window", {std::max(c.t0, 0.0), std::min(c.t1, s.end_time)}},
                        {"angle_range", std::isnan(o.stats_angle0)
                                            ? json(nullptr)
                                            : json({o.stats_angle0, o.stats_angle1})}};
    if (twin && col.twin_index[i] >= 0 && col.dev_n[i] > 0) {
      const auto& tv = twin->data[col.twin_index[i]];
      double ideal_peak = 0;
      for (double v : tv) ideal_peak = std::max(ideal_peak, std::abs(v));
      cmp[col.names[i]] = {{"rms_deviation", std::sqrt(col.dev_sq[i] / col.dev_n[i])},
                           {"max_deviation", col.dev_max[i]},
                           {"ideal_peak", ideal_peak},
                           {"peak_ratio", ideal_peak > 0 ? c.peak() / ideal_peak : 0.0}};
    }
  }
  an["statistics"] = st;
  an["comparison"] = twin ? cmp : json(nullptr);

  // Clearance joints: orbit, modes, impact velocities.
  const double t_end = out.result.status.ok ? s.end_time : out.result.status.t;
  const double cont_time = o.continuous_contact_time > 0 ? o.continuous_contact_time
                           : period > 0               ? 0.1 * period
                                                      : 1e-3;
  json cj = json::object();
  for (int c = 0; c < ws.nc; ++c) {
    const Joint& jt = model.joints[ws.clearance_joints[c]];
    const JointEvents& je = col.events[c];
    const ModeSummary ms = contact_modes(je.t, je.onset, je.v, je.in_contact_at_start, 0.0, t_end,
                                         cont_time);
    std::vector<double> ex, ey;
    for (const auto& e : col.orbit[c]) ex.push_back(e.x()), ey.push_back(e.y());
    json episodes = json::array();
    for (const auto& e : ms.episodes)
      episodes.push_back({e.start, e.end, e.continuous ? "continuous" : "impact"});
    // Histogram of impact velocities: 12 bins from 0 to the largest.
    double vmax = 0;
    for (double v : ms.impact_velocities) vmax = std::max(vmax, v);
    const int bins = 12;
    std::vector<double> edges;
    std::vector<int> counts(bins, 0);
    for (int b = 0; b <= bins; ++b) edges.push_back(vmax * b / bins);
    for (double v : ms.impact_velocities)
      if (vmax > 0) ++counts[std::min(bins - 1, static_cast<int>(v / vmax * bins))];
    cj[jt.name] = {{"clearance", jt.clearance->clearance},
                   {"orbit", {{"ex", r6(ex)}, {"ey", r6(ey)}}},
                   {"modes", {{"free_flight_share", ms.free_flight_share},
                              {"impact_share", ms.impact_share},
                              {"continuous_share", ms.continuous_share},
                              {"impacts", ms.impacts},
                              {"continuous_contact_time", cont_time},
                              {"episodes", episodes}}},
                   {"impact_velocities", ms.impact_velocities},
                   {"histogram", {{"edges", edges}, {"counts", counts}}}};
  }
  an["clearance"] = cj;

  // Poincaré sections: distinct points within 1% of the smallest clearance (1 µm without one).
  double tol = 1e-6;
  for (int c = 0; c < ws.nc; ++c)
    tol = c == 0 ? 0.01 * model.joints[ws.clearance_joints[c]].clearance->clearance
                 : std::min(tol, 0.01 * model.joints[ws.clearance_joints[c]].clearance->clearance);
  const int distinct = count_distinct(col.sections, tol);
  if (period > 0 || !planes.empty()) {
    json pts = json::array();
    for (const auto& p : col.sections)
      pts.push_back(std::vector<double>(p.begin(), p.begin() + std::min<size_t>(2, p.size())));
    std::vector<std::string> vars;
    if (ws.nc > 0) {
      const std::string& n = model.joints[ws.clearance_joints[0]].name;
      vars = {n + ".ex", n + ".ey"};
    } else {
      vars = {model.bodies[0].name + ".x", model.bodies[0].name + ".y"};
    }
    an["poincare"] = {{"kind", planes.empty() ? "stroboscopic" : "event"},
                      {"plane", planes.empty() ? json(nullptr) : json(o.section_planes)},
                      {"period", period},
                      {"discarded_periods", o.discard_periods}, {"variables", vars},
                      {"points", pts}, {"times", r6(col.section_t)}, {"distinct", distinct},
                      {"tolerance", tol}};
  } else {
    an["poincare"] = nullptr;
  }

  // Spectra of the kept channels after the transient.
  json sp = json::object();
  int off_harmonic = -1;
  for (size_t i = 0; i < col.fft_index.size(); ++i) {
    if (col.fft_data[i].size() < 16) continue;
    const Spectrum spec = amplitude_spectrum(col.fft_data[i], s.output_interval);
    if (i == 0 && period > 0) off_harmonic = non_harmonic_peaks(spec, 1.0 / period);
    std::vector<double> f, a;
    decimate_min_max(spec.frequency, spec.amplitude, 1000, f, a);
    sp[col.names[col.fft_index[i]]] = {{"frequency", r6(f)}, {"amplitude", r6(a)}, {"window", spec.window},
                                       {"discarded_time", t_discard}};
  }
  an["spectra"] = sp;

  json phase = json::array();
  if (o.phase.empty()) {
    for (int c = 0; c < ws.nc; ++c) {
      const std::string& n = model.joints[ws.clearance_joints[c]].name;
      phase.push_back({{"x", n + ".ex"}, {"y", n + ".ey"}});
      phase.push_back({{"x", n + ".delta"}, {"y", n + ".delta_dot"}});
    }
  } else {
    for (const auto& [x, y] : o.phase) {
      if (col.index(x) < 0 || col.index(y) < 0)
        throw std::invalid_argument("phase portrait " + x + "," + y + ": no such channel");
      phase.push_back({{"x", x}, {"y", y}});
    }
  }
  an["phase"] = phase;

  // Largest Lyapunov exponent: two trajectories from the state after the transient, each
  // perturbation projected onto the constraints; separation measured in configuration space
  // (body coordinates, m and rad; velocities would weigh the stiff contact oscillation, whose
  // bounded ringing is not divergence), renormalised 20 times per period.
  double lyap = std::nan("");
  if (o.lyapunov && ws.nq - ws.m == 0) {
    an["lyapunov"] = {{"exponent", nullptr}, {"unit", "1/s"}, {"renormalisations", 0},
                      {"history", json::array()},
                      {"message", "no free degree of freedom: the drivers fix every coordinate"}};
  } else if (o.lyapunov && out.result.status.ok && col.have_lyapunov_start && period > 0) {
    const double interval = period / 20.0;
    const int intervals = static_cast<int>((s.end_time - col.lyapunov_t0) / interval);
    if (intervals >= 20) {
      Workspace w0(model), w1(model);
      Simulator s0(model, w0), s1(model, w1);
      Workspace wp(model);
      const int nq = ws.nq;
      auto flow = [&](int which, Eigen::VectorXd& y, double t0, double t1) {
        // Times are relative to the start of the estimate; the perturbed trajectory restarts
        // from its renormalised state every interval, the reference only once.
        Simulator& sim = which == 0 ? s0 : s1;
        if (which == 1 || t0 == 0.0) {
          if (which == 1) {
            try {
              project_state(model, wp, t0 + col.lyapunov_t0, y);
            } catch (const std::exception&) {
              return false;
            }
          }
          // The perturbed copy keeps the reference's contact modes and δ̇⁻ where its gaps agree.
          sim.start(t0 + col.lyapunov_t0, y, which == 1 ? &w0.contact : nullptr);
        }
        if (!sim.advance_to(t1 + col.lyapunov_t0, nullptr)) return false;
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
          project_state(model, wp, col.lyapunov_t0, yp);
        } catch (const std::exception&) {
          return Eigen::VectorXd(y);
        }
        const double d = norm(y, yp);
        return d > 1e-3 * d0 ? Eigen::VectorXd(y + (yp - y) * (d0 / d)) : Eigen::VectorXd(y);
      };
      // d0: far above the integration error (rtol·|q| ~ 1e-9 m here), far below the clearance.
      double d0_lyap = 1e-7;
      for (int c = 0; c < ws.nc; ++c)
        d0_lyap = std::min(d0_lyap, 2e-4 * model.joints[ws.clearance_joints[c]].clearance->clearance);
      if (o.lyapunov_d0 > 0) d0_lyap = o.lyapunov_d0;
      LyapunovOptions lo;
      lo.d0 = d0_lyap;
      lo.interval = interval;
      lo.intervals = intervals;
      const LyapunovResult lr =
          largest_lyapunov(flow, col.lyapunov_start, norm, lo, perturb);
      if (lr.ok) lyap = lr.exponent;
      json hist = json::array();
      for (const auto& [t, e] : lr.history) hist.push_back({r6(t + col.lyapunov_t0), r6(e)});
      an["lyapunov"] = {{"exponent", lr.ok ? json(lr.exponent) : json(nullptr)},
                        {"unit", "1/s"}, {"renormalisations", lr.renormalisations},
                        {"interval", interval}, {"d0", lo.d0}, {"history", hist},
                        {"message", lr.message}};
    } else {
      an["lyapunov"] = nullptr;
    }
  } else {
    an["lyapunov"] = nullptr;
  }

  const Verdict v = classify_motion(lyap, period, distinct,
                                    static_cast<int>(col.sections.size()), off_harmonic);
  an["verdict"] = {{"class", v.kind}, {"evidence", v.evidence}};
  d["analysis"] = an;
  out.data = std::move(d);
  return out;
}

std::vector<std::string> write_report(const json& data, const std::string& folder) {
  namespace fs = std::filesystem;
  std::vector<std::string> notes;
  fs::create_directories(folder);
  const std::string text = data.dump();
  std::ofstream(folder + "/report_data.json") << text << "\n";
  notes.push_back(folder + "/report_data.json");
  // The page: the template with the data inlined. Every '<' (only possible inside JSON strings:
  // model names, paths, expressions) becomes \u003c, so no text can close or reopen the script.
  std::string escaped;
  escaped.reserve(text.size());
  for (char c : text) {
    if (c == '<')
      escaped += "\\u003c";
    else
      escaped += c;
  }
  std::string html(report_html_template());
  const std::string token = "__LASH_REPORT_DATA__";
  const auto pos = html.find(token);
  if (pos != std::string::npos) html.replace(pos, token.size(), escaped);
  std::ofstream(folder + "/report.html") << html;
  notes.push_back(folder + "/report.html");
  // Figures for papers, with Debian's matplotlib.
  const std::string script = std::string(LASH_SOURCE_DIR) + "/tools/lash_figures.py";
  const char* python = "/usr/bin/python3";
  if (!fs::exists(script) || !fs::exists(python)) {
    notes.push_back("figures skipped: " + script + " or " + python + " not found");
  } else {
    const std::string cmd = std::string(python) + " '" + script + "' '" + folder + "' > '" +
                            folder + "/figures.log' 2>&1";
    const int rc = std::system(cmd.c_str());
    notes.push_back(rc == 0 ? folder + "/figures/ (see figures.log)"
                            : "figures failed (exit " + std::to_string(rc) + "), see " + folder +
                                  "/figures.log");
  }
  return notes;
}

}  // namespace lash
