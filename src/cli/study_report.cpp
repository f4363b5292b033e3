// study_report.html from a study database (sweep.hpp): self-contained, plots as inline SVG.
#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include "cli/sweep.hpp"
#include "io/files.hpp"
#include "study/study_db.hpp"

namespace lash::cli {
namespace {

std::string esc(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '&': o += "&amp;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

std::string num(double v) {
  if (!std::isfinite(v)) return "–";
  return fmt::format("{:.4g}", v);
}

/// About 5 round tick values covering [a, b].
std::vector<double> ticks(double a, double b) {
  const double span = b - a;
  const double raw = span / 5;
  const double mag = std::pow(10, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  std::vector<double> t;
  for (double v = std::ceil(a / step) * step; v <= b + 1e-9 * span; v += step) t.push_back(std::abs(v) < 1e-12 * step ? 0 : v);
  return t;
}

/// A scatter (dots) or line plot as an SVG element.
/// Colours of the groups (a text parameter's values), colour-blind safe (Okabe–Ito).
const char* kColours[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000"};

/// A scatter (dots) or line plot as an SVG element; `group[i]` picks point i's colour and line
/// (one line per group), `groups` names them in a legend (none with fewer than two).
std::string plot(const std::string& title, const std::string& xlabel, const std::string& ylabel,
                 const std::vector<std::pair<double, double>>& pts, bool line, bool log_x,
                 const std::vector<int>& group = {}, const std::vector<std::string>& groups = {}) {
  const double W = 640, H = 360, L = 70, R = 16, T = 30, B = 48;
  std::vector<std::pair<double, double>> p;
  std::vector<int> g;
  for (size_t i = 0; i < pts.size(); ++i) {
    const auto [x, y] = pts[i];
    if (std::isfinite(x) && std::isfinite(y) && (!log_x || x > 0)) {
      p.push_back({log_x ? std::log10(x) : x, y});
      g.push_back(group.empty() ? 0 : group[i]);
    }
  }
  const int n_groups = std::max<int>(1, static_cast<int>(groups.size()));
  std::ostringstream s;
  s << "<figure><svg viewBox=\"0 0 " << W << " " << H << "\" role=\"img\"><title>" << esc(title)
    << "</title>";
  s << "<text x=\"" << W / 2 << "\" y=\"18\" text-anchor=\"middle\" class=\"t\">" << esc(title) << "</text>";
  if (p.empty()) {
    s << "<text x=\"" << W / 2 << "\" y=\"" << H / 2 << "\" text-anchor=\"middle\">no finite values</text></svg></figure>";
    return s.str();
  }
  double x0 = p[0].first, x1 = x0, y0 = p[0].second, y1 = y0;
  for (const auto& [x, y] : p) {
    x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
  }
  if (x1 == x0) {  // one value: an axis around it on its own scale (±0.5 put 2e-4 on the 0 tick)
    const double half = log_x || x0 == 0.0 ? 0.5 : 0.5 * std::abs(x0);
    x0 -= half, x1 += half;
  }
  if (y1 == y0) y0 -= 0.5 * (std::abs(y0) + 1e-12), y1 += 0.5 * (std::abs(y1) + 1e-12);
  const double pad = 0.04 * (y1 - y0);
  y0 -= pad, y1 += pad;
  auto X = [&](double x) { return L + (x - x0) / (x1 - x0) * (W - L - R); };
  auto Y = [&](double y) { return H - B - (y - y0) / (y1 - y0) * (H - T - B); };
  s << "<rect x=\"" << L << "\" y=\"" << T << "\" width=\"" << W - L - R << "\" height=\"" << H - T - B
    << "\" class=\"frame\"/>";
  for (double t : ticks(x0, x1))
    s << "<text x=\"" << X(t) << "\" y=\"" << H - B + 16 << "\" text-anchor=\"middle\">"
      << (log_x ? num(std::pow(10, t)) : num(t)) << "</text>";
  for (double t : ticks(y0, y1))
    s << "<text x=\"" << L - 6 << "\" y=\"" << Y(t) + 4 << "\" text-anchor=\"end\">" << num(t)
      << "</text><line x1=\"" << L << "\" x2=\"" << W - R << "\" y1=\"" << Y(t) << "\" y2=\"" << Y(t)
      << "\" class=\"grid\"/>";
  s << "<text x=\"" << (L + W - R) / 2 << "\" y=\"" << H - 8 << "\" text-anchor=\"middle\">" << esc(xlabel)
    << "</text>";
  s << "<text transform=\"translate(14," << (T + H - B) / 2 << ") rotate(-90)\" text-anchor=\"middle\">"
    << esc(ylabel) << "</text>";
  const double r = line ? 2.5 : (p.size() > 5000 ? 0.8 : 1.4);
  for (int k = 0; k < n_groups; ++k) {
    const char* colour = kColours[k % 7];
    if (line) {
      std::vector<std::pair<double, double>> q;
      for (size_t i = 0; i < p.size(); ++i)
        if (g[i] == k) q.push_back(p[i]);
      std::sort(q.begin(), q.end());
      s << "<polyline class=\"line\" style=\"stroke:" << colour << "\" points=\"";
      for (const auto& [x, y] : q) s << fmt::format("{:.1f},{:.1f} ", X(x), Y(y));
      s << "\"/>";
    }
    s << "<g class=\"dots\" style=\"fill:" << colour << "\">";
    for (size_t i = 0; i < p.size(); ++i)
      if (g[i] == k)
        s << fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"{}\"/>", X(p[i].first), Y(p[i].second), r);
    s << "</g>";
  }
  if (groups.size() > 1)
    for (size_t k = 0; k < groups.size(); ++k)
      s << "<circle cx=\"" << L + 12 << "\" cy=\"" << T + 12 + 14 * k << "\" r=\"4\" style=\"fill:"
        << kColours[k % 7] << "\"/><text x=\"" << L + 20 << "\" y=\"" << T + 16 + 14 * k << "\">"
        << esc(groups[k]) << "</text>";
  s << "</svg></figure>";
  return s.str();
}

/// The metrics the report plots: peaks, impacts, contact shares, impact velocities, the exponent.
bool plotted_metric(const std::string& n) {
  auto ends = [&](const std::string& tail) {
    return n.size() > tail.size() && n.compare(n.size() - tail.size(), tail.size(), tail) == 0;
  };
  return ends(".peak") || ends(".impacts") || ends("_share") || ends(".max_impact_velocity") ||
         n == "lyapunov_exponent" || n == "distinct_points";
}

}  // namespace

std::string write_study_report(const std::string& folder) {
  StudyTable t;
  try {
    t = read_study(folder + "/study.db");
  } catch (const IoError& e) {  // a damaged database is bad input, not a failed write
    throw std::invalid_argument(std::string(e.what()) + " (a damaged study.db: run the study again)");
  }
  // The x axis: the first parameter with numbers.
  int xp = -1;
  for (size_t p = 0; p < t.parameters.size() && xp < 0; ++p)
    for (const auto& row : t.rows)
      if (!std::isnan(row.numbers[p])) {
        xp = static_cast<int>(p);
        break;
      }
  bool log_x = false;
  if (xp >= 0) {  // a logarithmic axis when the values span more than two decades
    double lo = 1e300, hi = -1e300;
    for (const auto& row : t.rows) lo = std::min(lo, row.numbers[xp]), hi = std::max(hi, row.numbers[xp]);
    log_x = lo > 0 && hi / lo > 100;
  }
  int failed = 0;
  for (const auto& row : t.rows) failed += row.status != "completed";
  std::ostringstream h;
  h << "<!doctype html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>" << esc(t.name)
    << " — lash study</title><style>"
       "body{font:15px/1.45 system-ui,sans-serif;margin:2em auto;max-width:1320px;padding:0 1em;color:#1d2530}"
       "h1{font-size:1.6em;margin-bottom:.2em}h2{font-size:1.2em;margin-top:2em;border-bottom:1px solid #d5dbe3}"
       ".grid{stroke:#e7ebf0}.frame{fill:none;stroke:#9aa5b1}.dots circle{fill-opacity:.75}"
       ".line{fill:none;stroke-width:1.4}svg{width:100%;max-width:640px;font-size:11px}"
       ".t{font-size:13px;font-weight:600}figure{display:inline-block;margin:.5em;width:640px;max-width:100%}"
       "table{border-collapse:collapse;font-size:13px}td,th{padding:.25em .6em;border-bottom:1px solid #e7ebf0;text-align:left}"
       "td.n{text-align:right;font-variant-numeric:tabular-nums}.muted{color:#5b6673}"
       "</style></head><body>";
  h << "<h1>" << esc(t.name) << "</h1><p class=\"muted\">" << t.rows.size() << " of " << t.total_runs
    << " runs recorded, " << failed << " failed. Parameters: ";
  for (size_t p = 0; p < t.parameters.size(); ++p) h << (p ? ", " : "") << "<code>" << esc(t.parameters[p]) << "</code>";
  // The CSV files are written at the end of a sweep: one killed before it has study.db only.
  std::string data = "study.db";
  for (const char* csv : {"runs.csv", "sections.csv"})
    if (std::filesystem::is_regular_file(std::filesystem::path(folder) / csv)) data += std::string(", ") + csv;
  h << ". Values after the transient; data in " << data
    << " (runs.csv and sections.csv are written at the end of every sweep). Runs that did "
       "not complete are not plotted (their values cover part of the run): they are listed under "
       "Failed runs.</p>";
  std::set<int> completed;
  for (const auto& row : t.rows)
    if (row.status == "completed") completed.insert(row.run);
  // Metrics plotted or tabulated: peaks, impacts, contact shares, the exponent.
  std::vector<std::string> names;
  for (const auto& row : t.rows)
    for (const auto& [n, v] : row.metrics)
      if (std::find(names.begin(), names.end(), n) == names.end() && plotted_metric(n)) names.push_back(n);

  if (xp >= 0) {
    const std::string xlabel = t.parameters[xp];
    std::map<int, double> x_of;
    for (const auto& row : t.rows) x_of[row.run] = row.numbers[xp];
    // Colours: the values of the first text parameter (a case, or the continuation's direction).
    int gp = -1;
    for (size_t p = 0; p < t.parameters.size() && gp < 0; ++p)
      if (!t.rows.empty() && std::isnan(t.rows.front().numbers[p])) gp = static_cast<int>(p);
    std::vector<std::string> groups;
    std::map<int, int> group_of;
    for (const auto& row : t.rows) {
      int k = 0;
      if (gp >= 0) {
        const auto it = std::find(groups.begin(), groups.end(), row.values[gp]);
        k = static_cast<int>(it - groups.begin());
        if (it == groups.end()) groups.push_back(row.values[gp]);
      }
      group_of[row.run] = k;
    }
    if (gp < 0) groups.clear();
    if (!t.section_channels.empty()) {
      h << "<h2>Bifurcation diagram</h2><p class=\"muted\">Each run's chosen channel at every "
           "Poincaré section after the transient, over <code>"
        << esc(xlabel) << "</code>: one dot per period for a period-1 orbit, k for period k, a cloud for chaos.</p>";
      for (size_t c = 0; c < t.section_channels.size(); ++c) {
        std::vector<std::pair<double, double>> pts;
        std::vector<int> g;
        for (const auto& [run, v] : t.points[c])
          if (completed.count(run)) pts.push_back({x_of[run], v}), g.push_back(group_of[run]);
        h << plot(t.section_channels[c] + " at the sections", xlabel, t.section_channels[c], pts, false,
                  log_x, g, groups);
      }
    }
    // Metrics against the parameter.
    if (!names.empty()) h << "<h2>Metrics</h2>";
    // Lines when the numeric parameter alone (with the colour's) tells the runs apart.
    const bool several = t.parameters.size() > (gp >= 0 ? 2u : 1u);
    for (const auto& n : names) {
      std::vector<std::pair<double, double>> pts;
      std::vector<int> g;
      for (const auto& row : t.rows)
        for (const auto& [m, v] : row.metrics)
          if (m == n && row.status == "completed")
            pts.push_back({row.numbers[xp], v}), g.push_back(group_of[row.run]);
      h << plot(n, xlabel, n, pts, !several, log_x, g, groups);
    }
  } else if (!names.empty()) {
    // No numeric parameter (cases only): no axis to plot against; the metrics as a table, one
    // row per completed run.
    h << "<h2>Metrics</h2><table><tr><th>run</th>";
    for (const auto& p : t.parameters) h << "<th>" << esc(p) << "</th>";
    for (const auto& n : names) h << "<th>" << esc(n) << "</th>";
    h << "</tr>";
    for (const auto& row : t.rows) {
      if (row.status != "completed") continue;
      h << "<tr><td class=\"n\">" << row.run << "</td>";
      for (const auto& v : row.values) h << "<td>" << esc(v) << "</td>";
      for (const auto& n : names) {
        const auto it = std::find_if(row.metrics.begin(), row.metrics.end(),
                                     [&](const auto& mv) { return mv.first == n; });
        h << "<td class=\"n\">" << (it != row.metrics.end() ? num(it->second) : std::string()) << "</td>";
      }
      h << "</tr>";
    }
    h << "</table>";
  }

  h << "<h2>Failed runs</h2>";
  if (failed == 0) {
    h << "<p>None.</p>";
  } else {
    h << "<table><tr><th>run</th>";
    for (const auto& p : t.parameters) h << "<th>" << esc(p) << "</th>";
    h << "<th>status</th><th>error</th></tr>";
    for (const auto& row : t.rows)
      if (row.status != "completed") {
        h << "<tr><td class=\"n\">" << row.run << "</td>";
        for (const auto& v : row.values) h << "<td>" << esc(v) << "</td>";
        h << "<td>" << esc(row.status) << "</td><td>" << esc(row.message) << "</td></tr>";
      }
    h << "</table>";
  }
  h << "<h2>Runs</h2><table><tr><th>run</th>";
  for (const auto& p : t.parameters) h << "<th>" << esc(p) << "</th>";
  h << "<th>status</th><th>verdict</th><th>wall s</th></tr>";
  for (const auto& row : t.rows) {
    h << "<tr><td class=\"n\">" << row.run << "</td>";
    for (const auto& v : row.values) h << "<td class=\"n\">" << esc(v) << "</td>";
    h << "<td>" << esc(row.status) << "</td><td>" << esc(row.verdict) << "</td><td class=\"n\">"
      << num(row.wall_seconds) << "</td></tr>";
  }
  h << "</table></body></html>\n";
  const std::string path = folder + "/study_report.html";
  write_file_atomic(path, h.str());
  return path;
}

}  // namespace lash::cli
