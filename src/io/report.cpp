#include "io/report.hpp"

#include <dlfcn.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "core/elements/registry.hpp"
#include "io/files.hpp"
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
    json body = {{"name", b.name}, {"mass", b.mass}, {"inertia", b.inertia}, {"markers", mk}};
    if (b.flexible())
      body["flexible"] = {{"length", b.mesh.length}, {"elements", b.mesh.elements},
                          {"youngs_modulus", b.mesh.section.youngs_modulus}};
    j["bodies"].push_back(body);
  }
  // Ground points used by joints and loads (the ground has no marker list in the Model).
  json gm = json::object();
  for (const auto& jt : m.joints)
    for (const PointRef* p : {&jt.a, &jt.b})
      if (p->body == kGround) {
        // Named as in the ground's markers: list ("ground.O" is "O"); "ground" is its origin.
        const auto dot = p->label.find('.');
        gm[dot == std::string::npos ? "origin" : p->label.substr(dot + 1)] = {p->s.x(), p->s.y()};
      }
  j["ground_markers"] = gm;
  j["joints"] = json::array();
  for (const auto& jt : m.joints) {
    json x = {{"name", jt.name}, {"type", kind_of(jt).name}, {"a", point_json(m, jt.a)},
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

/// {name: values} of every channel of a series, rounded.
json channels_json(const DecimatedSeries& s) {
  json j = json::object();
  for (size_t i = 0; i < s.channels.size(); ++i) j[s.channels[i].name] = r6(s.values[i]);
  return j;
}

/// null (not estimated), the no-free-direction note, or the estimate with its history.
json lyapunov_json(const std::optional<LyapunovEstimate>& l) {
  if (!l) return nullptr;
  if (!l->estimated)
    return {{"exponent", nullptr}, {"unit", "1/s"}, {"renormalisations", 0},
            {"history", json::array()}, {"message", l->message}};
  json hist = json::array();
  for (const auto& [t, e] : l->history) hist.push_back({r6(t), r6(e)});
  json j = {{"method", l->method},
            {"exponent", l->ok ? json(l->exponent) : json(nullptr)},
            {"unit", "1/s"}, {"renormalisations", l->renormalisations},
            {"interval", l->interval}, {"history", hist}, {"message", l->message}};
  if (!l->note.empty()) j["note"] = l->note;
  if (l->method == "two-trajectory") {
    j["d0"] = l->d0;
  } else {
    // The whole spectrum with its convergence: [time, λ1, λ2, …] rows.
    j["spectrum"] = l->ok ? json(r6(l->spectrum)) : json(nullptr);
    json sh = json::array();
    for (size_t h = 0; h < l->spectrum_history.size(); ++h) {
      json row = json::array({r6(l->history[h].first)});
      for (double v : l->spectrum_history[h]) row.push_back(r6(v));
      sh.push_back(row);
    }
    j["spectrum_history"] = sh;
    j["events_mapped"] = l->events_mapped;
    j["events_unmapped"] = l->events_unmapped;
  }
  return j;
}

/// The figures tool, found relative to the installed files rather than a path built in: at
/// ../share/lash/lash_figures.py from the file holding this code (liblash.so, or the program
/// linked with the static libraries) or from the running program (/proc/self/exe); in the build
/// tree, build/share/lash/ (copied at configure time) serves build/lash (share/ beside it) and
/// the test programs in build/tests/ (../share). "" if none exists.
std::string figures_script() {
  namespace fs = std::filesystem;
  std::vector<fs::path> binaries;
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&figures_script), &info) != 0 && info.dli_fname &&
      info.dli_fname[0] == '/')
    binaries.emplace_back(info.dli_fname);
  binaries.emplace_back("/proc/self/exe");
  for (const auto& b : binaries) {
    std::error_code ec;
    const fs::path dir = fs::canonical(b, ec).parent_path();
    if (ec) continue;
    // P/bin/lash or build/tests/test_x: ../share; build/lash (the build tree's top): share;
    // the installed library or program: its install folder's path to the data folder
    // (P/lib/x86_64-linux-gnu/liblash.so: ../../share).
    for (const fs::path& share : {dir.parent_path() / "share", dir / "share",
                                  (dir / LASH_LIB_TO_DATA).lexically_normal(),
                                  (dir / LASH_BIN_TO_DATA).lexically_normal()}) {
      const fs::path script = share / "lash" / "lash_figures.py";
      if (fs::is_regular_file(script, ec)) return script.string();
    }
  }
  return {};
}

}  // namespace

json report_data(const Model& model, const RunAnalysis& a) {
  json d;
  d["version"] = 1;
  d["model"] = model_json(model);
  const RunResult& r = a.result;
  d["status"] = {{"ok", r.status.ok}, {"time", r.status.t},
                 {"element", r.status.element}, {"message", r.status.message}};
  d["integrator"] = {{"name", r.integrator}, {"steps", r.stats.steps},
                     {"rejected_steps", r.stats.rejected_steps},
                     {"rhs_evaluations", r.stats.rhs_evaluations},
                     {"events", r.stats.events}, {"projections", r.stats.projections},
                     {"wall_seconds", r.wall_seconds}, {"outputs", r.outputs}};
  d["max_constraint_violation"] = r.max_constraint_violation;
  // Which parts were read from what the run wrote and which were simulated now.
  d["provenance"] = {{"read", a.provenance.read},
                     {"resimulated", a.provenance.resimulated},
                     {"skipped", a.provenance.skipped}};

  // Series (decimated) and the ideal twin on the same time base.
  json series;
  series["time"] = r6(a.series.time);
  series["crank_angle"] = a.period_driver.empty() ? json(nullptr) : json(r6(a.crank_angle_deg));
  series["channels"] = channels_json(a.series);
  // Units and descriptions, as the element kinds declare them (report.js and the figures read
  // them from here and never guess from a name).
  json info = json::object();
  for (const auto& c : a.series.channels)
    info[c.name] = {{"unit", c.unit}, {"description", c.description}};
  d["channel_info"] = info;
  if (a.ideal_twin) {
    // The twin's channels that the run has too (the twin has no clearance channels).
    const DecimatedSeries& ts = a.ideal_twin->series;
    json ideal = json::object();
    for (size_t c = 0; c < ts.channels.size(); ++c)
      if (a.series.index(ts.channels[c].name) >= 0) ideal[ts.channels[c].name] = r6(ts.values[c]);
    series["ideal"] = ideal;
  } else {
    series["ideal"] = nullptr;
  }
  d["series"] = series;

  // Animation frames.
  json frames;
  frames["time"] = r6(a.frames.time);
  json fb = json::object(), fc = json::object();
  for (size_t b = 0; b < a.frames.bodies.size(); ++b) {
    json arr = json::array();
    for (const auto& p : a.frames.pose[b]) arr.push_back({r6(p[0]), r6(p[1]), r6(p[2])});
    fb[a.frames.bodies[b]] = arr;
  }
  for (size_t c = 0; c < a.frames.clearance_joints.size(); ++c) {
    json arr = json::array();
    for (const auto& e : a.frames.eccentricity[c]) arr.push_back({r6(e.x()), r6(e.y())});
    fc[a.frames.clearance_joints[c]] = arr;
  }
  frames["bodies"] = fb;
  frames["clearance"] = fc;
  // Flexible links: their mid-length deflection from the chord, per frame (the page draws them
  // bent by it, magnified).
  json fd = json::object();
  for (size_t b = 0; b < a.frames.deflection.size() && b < a.frames.bodies.size(); ++b)
    if (!a.frames.deflection[b].empty())
      fd[a.frames.bodies[b]] = r6(a.frames.deflection[b]);
  frames["deflection"] = fd;
  d["frames"] = frames;

  // Statistics and the comparison with the ideal twin.
  json an, st = json::object();
  for (const auto& c : a.statistics)
    st[c.channel] = {{"min", c.min}, {"max", c.max}, {"peak", c.peak}, {"rms", c.rms},
                     {"crest", c.crest}, {"t_min", c.t_min}, {"t_max", c.t_max},
                     {"extrema", c.exact ? "exact" : "samples"}, {"window", {c.t0, c.t1}},
                     {"angle_range", std::isnan(c.angle0_deg)
                                         ? json(nullptr)
                                         : json({c.angle0_deg, c.angle1_deg})}};
  an["statistics"] = st;
  if (a.ideal_twin) {
    json cmp = json::object();
    for (const auto& c : a.ideal_twin->comparison)
      cmp[c.channel] = {{"rms_deviation", c.rms_deviation}, {"max_deviation", c.max_deviation},
                        {"ideal_peak", c.ideal_peak},
                        {"peak_ratio", std::isnan(c.peak_ratio) ? json(nullptr) : json(c.peak_ratio)}};
    an["comparison"] = cmp;
  } else {
    an["comparison"] = nullptr;
  }

  // Clearance joints: orbit, modes, impact velocities.
  json cj = json::object();
  for (const auto& j : a.clearance) {
    std::vector<double> ex, ey;
    for (const auto& e : j.orbit) ex.push_back(e.x()), ey.push_back(e.y());
    const ModeSummary& ms = j.modes;
    json episodes = json::array();
    for (const auto& e : ms.episodes)
      episodes.push_back({e.start, e.end, e.continuous ? "continuous" : "impact"});
    cj[j.joint] = {{"clearance", j.clearance},
                   {"orbit", {{"ex", r6(ex)}, {"ey", r6(ey)}}},
                   {"modes", {{"free_flight_share", ms.free_flight_share},
                              {"impact_share", ms.impact_share},
                              {"continuous_share", ms.continuous_share},
                              {"impacts", ms.impacts},
                              {"continuous_contact_time", j.continuous_contact_time},
                              {"episodes", episodes}}},
                   {"impact_velocities", ms.impact_velocities},
                   {"histogram", {{"edges", j.histogram.edges}, {"counts", j.histogram.counts}}}};
  }
  an["clearance"] = cj;

  // Poincaré sections: the first two coordinates of each point.
  if (a.poincare) {
    const PoincareSections& p = *a.poincare;
    json pts = json::array();
    for (const auto& x : p.points)
      pts.push_back(std::vector<double>(x.begin(), x.begin() + std::min<size_t>(2, x.size())));
    an["poincare"] = {{"kind", p.kind},
                      {"plane", p.planes.empty() ? json(nullptr) : json(p.planes)},
                      {"period", p.period},
                      {"discarded_periods", p.discarded_periods}, {"variables", p.variables},
                      {"coordinates", p.coordinates},
                      {"points", pts}, {"times", p.times}, {"distinct", p.distinct},
                      {"tolerance", p.tolerance}};
    json joints = json::array();
    for (const JointSections& js : p.joints) {
      json jp = json::array();
      for (const Vec2& e : js.points) jp.push_back({e.x(), e.y()});
      joints.push_back({{"joint", js.joint}, {"variables", js.variables}, {"points", jp},
                        {"distinct", js.distinct}, {"tolerance", js.tolerance}});
    }
    an["poincare"]["joints"] = joints;
  } else {
    an["poincare"] = nullptr;
  }

  json sp = json::object();
  for (const auto& s : a.spectra)
    sp[s.channel] = {{"frequency", r6(s.frequency)}, {"amplitude", r6(s.amplitude)},
                     {"window", s.window}, {"discarded_time", s.discarded_time}};
  an["spectra"] = sp;

  json phase = json::array();
  for (const auto& p : a.phase) phase.push_back({{"x", p.x}, {"y", p.y}});
  an["phase"] = phase;

  an["lyapunov"] = lyapunov_json(a.lyapunov);
  an["verdict"] = {{"class", a.verdict.kind}, {"evidence", a.verdict.evidence},
                   {"rule", a.verdict.rule}};
  an["period"] = {{"value", a.period > 0 ? json(a.period) : json(nullptr)},
                  {"driver", a.period_driver.empty() ? json(nullptr) : json(a.period_driver)},
                  {"source", a.period_source}};
  d["analysis"] = an;
  return d;
}

std::vector<std::string> write_report(const json& data, const std::string& folder,
                                      const std::atomic<int>* interrupt) {
  namespace fs = std::filesystem;
  std::vector<std::string> notes;
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw IoError(folder, "cannot create the folder: " + ec.message());
  // A figures/ that lash did not write stops the report before any file is written (it wrote
  // report.html and report_data.json first, and then said nothing was done).
  remove_earlier_output(folder + "/figures", kFiguresMarker, /*check_only=*/true);
  const std::string text = data.dump(-1, ' ', false, json::error_handler_t::replace);
  write_file_atomic(folder + "/report_data.json", text + "\n");
  notes.push_back("wrote " + folder + "/report_data.json");
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
  write_file_atomic(folder + "/report.html", html);
  notes.push_back("wrote " + folder + "/report.html");
  // Figures for papers, with Debian's matplotlib; started without a shell, so no folder name can
  // run a command, and with an absolute path, so no name is read as an option ("-h").
  const std::string script = figures_script();
  const std::string python = "/usr/bin/python3";
  const std::string figures = folder + "/figures";
  if (script.empty() || !fs::exists(python)) {
    notes.push_back("figures skipped: " +
                    (script.empty() ? std::string("share/lash/lash_figures.py (beside the lash "
                                                  "installation) not found")
                                    : python + " not found"));
    return notes;
  }
  // An earlier report's figures/ goes (a folder lash did not write stays, and so do they).
  remove_earlier_output(figures, kFiguresMarker);
  fs::create_directories(figures, ec);
  if (ec) throw IoError(figures, "cannot create the folder: " + ec.message());
  write_file_atomic(figures + "/" + kFiguresMarker,
                    "written by lash report; removed with this folder by the next run\n");
  const int rc = run_program({python, script, fs::absolute(folder).string()}, folder + "/figures.log",
                              interrupt);
  notes.push_back(rc == 0 ? "wrote " + figures + "/ (see figures.log)"
                          : "figures failed (exit " + std::to_string(rc) + "), see " + folder +
                                "/figures.log");
  return notes;
}

void remove_report(const std::string& folder) {
  remove_earlier_output(folder + "/figures", kFiguresMarker);
  for (const char* f : {"report.html", "report_data.json", "figures.log"})
    remove_earlier_output(folder + "/" + f);
}

}  // namespace lash
