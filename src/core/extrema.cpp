#include "core/extrema.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include <boost/math/tools/minima.hpp>

#include "core/elements/registry.hpp"

namespace lash {

namespace {

/// Largest value on [0, 1] of the cubic Hermite interpolant through (0, v0, slope h·d0) and
/// (1, v1, h·d1): an estimate of a turning point's height inside a step. The cubic
/// p(s) = αs³ + βs² + γs + v0 turns where p'(s) = 3αs² + 2βs + γ = 0.
double hermite_max(double v0, double d0, double v1, double d1, double h) {
  const double gamma = h * d0, beta = 3.0 * (v1 - v0) - 2.0 * gamma - h * d1,
               alpha = 2.0 * (v0 - v1) + gamma + h * d1;
  double best = std::max(v0, v1);
  auto at = [&](double s) {
    if (s > 0.0 && s < 1.0) best = std::max(best, ((alpha * s + beta) * s + gamma) * s + v0);
  };
  const double disc = beta * beta - 3.0 * alpha * gamma;  // of p'/1, a quarter of 4β² − 12αγ
  if (disc < 0.0) return best;
  // Both roots without cancellation: q = −(β + sign(β)√disc), s = q/(3α) and s = γ/q.
  const double q = -(beta + std::copysign(std::sqrt(disc), beta));
  if (alpha != 0.0) at(q / (3.0 * alpha));
  if (q != 0.0) at(gamma / q);
  return best;
}

}  // namespace

ChannelExtrema::ChannelExtrema(const Model& model, std::vector<int> tracked)
    : model_(model), tracked_(std::move(tracked)), resolution_(model.solver.rtol),
      end_(model.solver.end_time), to_(end_) {
  const std::vector<ChannelInfo> info = channel_info(model);
  const size_t n = info.size();
  ext_.assign(n, ChannelExtremum{});
  if (tracked_.empty())
    for (size_t i = 0; i < n; ++i) tracked_.push_back(static_cast<int>(i));
  std::sort(tracked_.begin(), tracked_.end());
  tracked_.erase(std::unique(tracked_.begin(), tracked_.end()), tracked_.end());
  if (!tracked_.empty() && (tracked_.front() < 0 || tracked_.back() >= static_cast<int>(n)))
    throw std::invalid_argument("ChannelExtrema: a tracked channel index is out of range");
  std::vector<std::string> units;
  for (const ChannelInfo& c : info) {
    const auto u = std::find(units.begin(), units.end(), c.unit);
    unit_.push_back(static_cast<int>(u - units.begin()));
    if (u == units.end()) units.push_back(c.unit);
  }
  scale_.assign(units.size(), 0.0);
  for (auto* v : {&v0_, &d0_, &v1_, &d1_, &tmp_}) v->assign(n, 0.0);
}

void ChannelExtrema::sample(double t, const double* values) {
  if (t < from_ || t > to_) return;
  if (keep_last_step_ && !in_step_ && t <= step_end_) {  // an output inside the last step: end_at counts it again
    since_t_.push_back(t);
    since_values_.insert(since_values_.end(), values, values + ext_.size());
  }
  for (const int i : tracked_) {
    const double v = values[i];
    ChannelExtremum& e = ext_[i];
    if (!std::isfinite(v)) {
      e.non_finite = true;
      continue;
    }
    if (!e.seen || v < e.min) e.min = v, e.t_min = t;
    if (!e.seen || v > e.max) e.max = v, e.t_max = t;
    e.seen = true;
  }
}

void ChannelExtrema::sample(double t, const Eigen::VectorXd& y, const Workspace& ws) {
  channel_values(model_, ws, y, tmp_.data());
  sample(t, tmp_.data());
}

bool ChannelExtrema::probe_values(StepProbe& probe, double t, std::vector<double>& out) {
  ++evaluations_;
  if (!probe.at(t)) return false;
  channel_values(model_, probe.workspace(), probe.state(), out.data());
  sample(t, out.data());
  return true;
}

void ChannelExtrema::end_at(double t) {
  if (!(t < step_end_)) return;
  ext_ = before_step_;
  step_end_ = -std::numeric_limits<double>::infinity();  // sample() records nothing now
  const std::vector<double> times = std::move(since_t_), values = std::move(since_values_);
  since_t_.clear();
  since_values_.clear();
  for (size_t k = 0; k < times.size(); ++k)
    if (times[k] <= t) sample(times[k], values.data() + k * ext_.size());
}

void ChannelExtrema::step(double t0, double t1, const Eigen::VectorXd& y1, const Workspace& ws1,
                          StepProbe& probe) {
  // What end_at needs to forget this step: the extrema before it.
  if (keep_last_step_) {
    before_step_ = ext_;
    step_end_ = t1;
    since_t_.clear();
    since_values_.clear();
  }
  in_step_ = true;
  struct Done {
    bool& flag;
    ~Done() { flag = false; }
  } done{in_step_};
  const double h = t1 - t0;
  if (t1 < from_ || t0 > to_) {  // outside the window: nothing to track
    have_slope_ = false;
    return;
  }
  channel_values(model_, ws1, y1, v1_.data());
  sample(t1, v1_.data());
  if (!(h > 0.0)) return;
  const double eps = kSlopeFraction * h;
  // A window end inside the step: its value counts (an extremum over the window may sit there).
  for (const double edge : {from_, to_})
    if (edge > t0 && edge < t1 && !probe_values(probe, edge, tmp_)) return;
  // The slope at t0: the previous step's left slope, or a forward difference after a restart.
  if (!have_slope_ || t0 != t_last_) {
    if (!probe_values(probe, t0, v0_)) return;
    if (!probe_values(probe, t0 + eps, tmp_)) return;
    for (const int i : tracked_) d0_[i] = (tmp_[i] - v0_[i]) / eps;
  }
  // The left slope at t1.
  if (!probe_values(probe, t1 - eps, tmp_)) return;
  for (const int i : tracked_) d1_[i] = (v1_[i] - tmp_[i]) / eps;
  // A slope changing sign: a turning point inside the step, refined where it may matter. The
  // units' largest magnitudes are brought up to date once per step, and only where needed.
  bool scaled = false;
  auto unit_scale = [&](int u) {
    if (!scaled) {
      for (const int k : tracked_)
        if (ext_[k].seen)
          scale_[unit_[k]] =
              std::max({scale_[unit_[k]], std::abs(ext_[k].min), std::abs(ext_[k].max)});
      scaled = true;
    }
    return scale_[u];
  };
  const double res = resolution_;
  for (const int i : tracked_) {
    const double a = d0_[i], b = d1_[i];
    if (!(std::isfinite(a) && std::isfinite(b))) continue;
    const double own = std::max(std::abs(ext_[i].min), std::abs(ext_[i].max));
    for (const double sign : {1.0, -1.0}) {
      if (!(sign * a > 0.0 && sign * b < 0.0)) continue;
      const double est = hermite_max(sign * v0_[i], sign * a, sign * v1_[i], sign * b, h);
      const double bulge = est - std::max(sign * v0_[i], sign * v1_[i]);
      const double best = sign > 0 ? ext_[i].max : -ext_[i].min;
      if (est + bulge >= best && bulge > res * own && own > res * unit_scale(unit_[i]))
        refine(probe, i, sign, std::max(t0, from_), std::min(t1, to_),
               t1 <= to_ ? -sign * v1_[i] : std::numeric_limits<double>::quiet_NaN());
    }
  }
  std::swap(v0_, v1_);
  std::swap(d0_, d1_);
  t_last_ = t1;
  have_slope_ = true;
}

void ChannelExtrema::refine(StepProbe& probe, int i, double sign, double a, double b, double fb) {
  ++refinements_;
  // Brent's method (Boost.Math) for the largest sign·v on [a, b], in the step's fraction
  // s ∈ [0, 1]: it starts at b, whose value is known (fb, NaN if not), then golden-section or
  // parabolic steps. Every point evaluated updates all channels; the minimiser's own answer is
  // not needed.
  bool ok = true;
  const double h = b - a;
  auto f = [&](double s) {
    if (s == 1.0 && !std::isnan(fb)) return fb;
    if (!ok || !probe_values(probe, a + s * h, tmp_)) {
      ok = false;  // the dense output is not finite there: stop evaluating
      return 0.0;
    }
    return -sign * tmp_[i];
  };
  std::uintmax_t iterations = kRefineIterations;
  boost::math::tools::brent_find_minima(f, 0.0, 1.0, kRefineBits, iterations);
}

}  // namespace lash
