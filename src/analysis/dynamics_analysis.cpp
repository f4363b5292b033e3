#include "analysis/dynamics_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace lash {

namespace {

double squared_distance(const std::vector<double>& a, const std::vector<double>& b) {
  double d2 = 0;
  for (size_t i = 0; i < a.size(); ++i) d2 += (a[i] - b[i]) * (a[i] - b[i]);
  return d2;
}

/// Greedy clustering within `tol`: each point joins the first centre within tol, or becomes
/// one. Returns the number of points of each centre, in the order the centres were found.
std::vector<int> cluster_sizes(const std::vector<std::vector<double>>& points, double tol) {
  std::vector<const std::vector<double>*> centres;
  std::vector<int> sizes;
  for (const auto& p : points) {
    size_t found = centres.size();
    for (size_t k = 0; k < centres.size() && found == centres.size(); ++k) {
      if (squared_distance(p, *centres[k]) <= tol * tol) found = k;
    }
    if (found == centres.size()) {
      centres.push_back(&p);
      sizes.push_back(1);
    } else {
      ++sizes[found];
    }
  }
  return sizes;
}

}  // namespace

int count_distinct(const std::vector<std::vector<double>>& points, double tol) {
  return static_cast<int>(cluster_sizes(points, tol).size());
}

int count_recurring(const std::vector<std::vector<double>>& points, double tol) {
  int recurring = 0;
  for (int n : cluster_sizes(points, tol)) recurring += n >= 2;
  return recurring;
}

double section_contraction(const std::vector<std::vector<double>>& points) {
  const int n = static_cast<int>(points.size()) - kVerdictMaxPeriod;  // points with 8 successors
  if (n < 4) return std::nan("");
  std::vector<double> returns(n);
  for (int i = 0; i < n; ++i) {
    double best = std::numeric_limits<double>::infinity();
    for (int j = i + 1; j <= i + kVerdictMaxPeriod; ++j)
      best = std::min(best, squared_distance(points[i], points[j]));
    returns[i] = std::sqrt(best);
  }
  const int third = n / 3;
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
  };
  const double first = median({returns.begin(), returns.begin() + third});
  const double last = median({returns.end() - third, returns.end()});
  return first > 0 ? last / first : std::nan("");
}

LyapunovResult largest_lyapunov(
    const std::function<bool(int, Eigen::VectorXd&, double, double)>& flow, Eigen::VectorXd y0,
    const std::function<double(const Eigen::VectorXd&, const Eigen::VectorXd&)>& norm,
    const LyapunovOptions& o,
    const std::function<Eigen::VectorXd(const Eigen::VectorXd&, double)>& perturb) {
  LyapunovResult r;
  double t = 0.0;
  Eigen::VectorXd y = std::move(y0);
  for (int i = 0; i < o.transient; ++i, t += o.interval)
    if (!flow(0, y, t, t + o.interval)) return {0, 0, {}, false, "the transient run failed"};
  Eigen::VectorXd yp = y;
  if (perturb) {
    yp = perturb(y, o.d0);
  } else {
    yp[0] += o.d0;
  }
  const double t_start = t;
  double sum = 0.0;
  for (int i = 0; i < o.intervals; ++i, t += o.interval) {
    if (!flow(0, y, t, t + o.interval) || !flow(1, yp, t, t + o.interval)) {
      r.ok = false;
      r.message = "a trajectory failed at t = " + std::to_string(t);
      break;
    }
    const double d = norm(y, yp);
    if (!(d > 1e-12 * o.d0)) {
      r.ok = false;
      r.message = "the two trajectories coincide at t = " + std::to_string(t + o.interval) +
                  " (no free direction to perturb, or strongly contracting)";
      break;
    }
    sum += std::log(d / o.d0);
    yp = y + (yp - y) * (o.d0 / d);
    ++r.renormalisations;
    r.history.emplace_back(t + o.interval, sum / (t + o.interval - t_start));
  }
  r.exponent = r.renormalisations ? sum / (r.renormalisations * o.interval) : 0.0;
  return r;
}

ModeSummary contact_modes(const std::vector<double>& times, const std::vector<bool>& onset,
                          const std::vector<double>& velocities, bool in_contact_at_t0,
                          double t0, double t1, double continuous_time) {
  ModeSummary m;
  bool in = in_contact_at_t0;
  double start = t0;
  // An episode is classified by its whole duration: the one under way at t0 began at the last
  // onset before it, the one under way at t1 ends at the first separation after it (where the
  // events say; else at the window's edge). Clipped first, the middle of a long contact seen
  // through a short window counted as an impact.
  bool first = true;  // the next episode closed is the one under way at t0, if any
  auto close = [&](double end, bool past_t1) {
    double from = start, to = end;
    if (first && in_contact_at_t0) {
      for (size_t i = 0; i < times.size() && times[i] < t0; ++i)
        if (onset[i]) from = times[i];
    }
    if (past_t1) {
      for (size_t i = 0; i < times.size(); ++i)
        if (times[i] > t1 && !onset[i]) {
          to = times[i];
          break;
        }
    }
    first = false;
    m.episodes.push_back({start, end, to - from >= continuous_time});
  };
  for (size_t i = 0; i < times.size(); ++i) {
    if (times[i] < t0 || times[i] > t1) continue;
    if (onset[i] && !in) {
      in = true;
      start = times[i];
      ++m.impacts;
      m.impact_velocities.push_back(velocities[i]);
    } else if (!onset[i] && in) {
      in = false;
      close(times[i], false);
    }
    if (onset[i]) first = false;  // an onset in the window: no episode was under way at t0
  }
  if (in) close(t1, true);
  const double span = t1 - t0;
  double impact = 0, continuous = 0;
  for (const auto& e : m.episodes) (e.continuous ? continuous : impact) += e.end - e.start;
  if (span > 0) {
    m.impact_share = impact / span;
    m.continuous_share = continuous / span;
    m.free_flight_share = 1.0 - m.impact_share - m.continuous_share;
  }
  return m;
}

const char* verdict_rule() {
  return "after the transient, with at least 16 Poincaré sections (fewer: undetermined, not "
         "enough periods): periodic (period-k) if k <= 8 points recur (each met at least "
         "twice), 2k <= the sections on them, and the points met once (a transient) are at "
         "most half the sections; otherwise chaotic if the largest Lyapunov "
         "exponent gives lambda*T > 0.1 per period T, periodic (converging) if lambda*T < -0.1, "
         "or if lambda*T < 0 and the points' returns (each one's distance to the nearest of the "
         "next 8) shrink to at most half from the first third of the sections to the last, "
         "quasi-periodic otherwise when |lambda*T| <= 0.1; without an exponent, "
         "chaotic if the spectrum's broadband share exceeds 0.5 (continuous), quasi-periodic if it "
         "is below 0.1 (discrete), else undetermined";
}

Verdict classify_motion(double lyapunov, double period, int distinct, int sections,
                        int non_harmonic_peaks, double min_end_time, double broadband,
                        int recurring, double contraction) {
  if (recurring < 0) recurring = distinct;
  Verdict v;
  std::ostringstream s;
  const bool have_lyap = std::isfinite(lyapunov);
  const double growth = have_lyap && period > 0 ? lyapunov * period : std::nan("");
  if (have_lyap) {
    s << "largest Lyapunov exponent " << lyapunov << " 1/s";
    if (period > 0) s << " (lambda*T = " << growth << " per period)";
    v.evidence.push_back(s.str());
    s.str("");
  }
  s << distinct << " distinct Poincaré point" << (distinct == 1 ? "" : "s") << " in " << sections
    << " section" << (sections == 1 ? "" : "s");
  v.evidence.push_back(s.str());
  s.str("");
  if (non_harmonic_peaks >= 0) {
    s << non_harmonic_peaks << " strong spectral peak" << (non_harmonic_peaks == 1 ? "" : "s")
      << " off the driving harmonics";
    v.evidence.push_back(s.str());
    s.str("");
  }
  const bool have_spectrum = std::isfinite(broadband);
  const char* spectrum_kind = !have_spectrum                              ? ""
                              : broadband < kVerdictDiscreteSpectrum      ? "discrete"
                              : broadband > kVerdictBroadbandSpectrum     ? "continuous"
                                                                          : "mixed";
  if (have_spectrum) {
    s << "broadband share of the spectrum " << broadband << " (" << spectrum_kind << ")";
    v.evidence.push_back(s.str());
    s.str("");
  }
  if (sections < kVerdictMinSections) {
    v.kind = "undetermined";
    s << "not enough periods: " << sections << " section" << (sections == 1 ? "" : "s")
      << " after the transient, " << kVerdictMinSections << " needed";
    if (min_end_time > 0) s << "; run to end_time >= " << min_end_time << " s";
    v.evidence.push_back(s.str());
    return v;
  }
  // A period-k orbit: k recurring points (each met at least twice) hold all but a transient's
  // points met once, and those are at most half the sections. (k distinct points with k <=
  // sections/2 alone called a forced rotor's 7 decaying points and its orbit "period-8".)
  const int once = distinct - recurring;
  if (recurring >= 1 && recurring <= kVerdictMaxPeriod && 2 * recurring <= sections - once &&
      2 * once <= sections) {
    v.kind = "periodic";
    v.evidence.push_back(
        "period-" + std::to_string(recurring) + " orbit: " +
        (once == 0 ? std::string("every point recurs")
                   : "its points recur, after " + std::to_string(once) + " point" +
                         (once == 1 ? "" : "s") + " met once (a transient: --discard leaves " +
                         (once == 1 ? "it" : "them") + " out)"));
    return v;
  }
  if (std::isfinite(growth)) {
    v.kind = growth > kVerdictChaosThreshold    ? "chaotic"
             : growth < -kVerdictChaosThreshold ? "periodic"
                                                : "quasi-periodic";
    if (v.kind == "periodic") {
      s << "converging: lambda*T < -" << kVerdictChaosThreshold
        << ", nearby trajectories close in on an attracting orbit (or rest) whose points have "
           "not all recurred yet";
      v.evidence.push_back(s.str());
      s.str("");
    } else if (v.kind == "quasi-periodic" && growth < 0 && contraction <= kVerdictContraction) {
      // A slow convergence (light damping, or a period short beside the decay time): λT is
      // within the finite-time tolerance of 0, but the points close in period after period.
      v.kind = "periodic";
      s << "converging: lambda*T < 0 and the points' returns shrank to " << contraction
        << " of their size from the first third of the sections to the last (<= "
        << kVerdictContraction << "): an attracting orbit (or rest) whose points have not all "
           "recurred yet";
      v.evidence.push_back(s.str());
      s.str("");
    }
    if (have_spectrum && std::string(spectrum_kind) != "mixed") {
      const bool agrees = (v.kind == "chaotic") == (std::string(spectrum_kind) == "continuous");
      v.evidence.push_back(std::string("the spectrum ") + (agrees ? "agrees" : "disagrees") +
                           "; the exponent decides");
    }
  } else if (have_spectrum && std::string(spectrum_kind) != "mixed") {
    v.kind = std::string(spectrum_kind) == "continuous" ? "chaotic" : "quasi-periodic";
    v.evidence.push_back("no Lyapunov exponent: the spectrum decides");
  } else {
    v.kind = "undetermined";
    v.evidence.push_back(have_spectrum
                             ? "the points do not recur, the spectrum is neither discrete nor "
                               "continuous, and no Lyapunov exponent was computed"
                             : "the points do not recur, and no Lyapunov exponent was computed to "
                               "tell quasi-periodic from chaotic motion");
  }
  return v;
}

}  // namespace lash
