#include "analysis/signal.hpp"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace lash {

namespace {
/// FFTW's planner (plan creation and fftw_destroy_plan) shares global state and is not
/// thread-safe; fftw_execute is. FFTW ≥ 3.3.5 serializes the planner itself once
/// fftw_make_planner_thread_safe() (libfftw3_threads) has been called: it installs hooks that
/// take one global mutex around every planner call and every plan destruction. Installing the
/// hooks races with planning, so it happens exactly once, before this file's first plan
/// (a function-local static: thread-safe initialisation in C++11).
void make_fftw_planner_thread_safe() {
  static const bool done = (fftw_make_planner_thread_safe(), true);
  (void)done;
}
}  // namespace

void ChannelStats::add(double t, double v) {
  if (t < t0 || t > t1) return;
  if (n == 0 || v < min) min = v, t_min = t;
  if (n == 0 || v > max) max = v, t_max = t;
  sum += v;
  sum_sq += v * v;
  ++n;
}
double ChannelStats::peak() const { return std::max(std::abs(min), std::abs(max)); }
double ChannelStats::rms() const { return n ? std::sqrt(sum_sq / n) : 0.0; }
double ChannelStats::mean() const { return n ? sum / n : 0.0; }
double ChannelStats::crest() const { return rms() > 0 ? peak() / rms() : 0.0; }

Spectrum amplitude_spectrum(const std::vector<double>& x, double dt, Window window) {
  const size_t n = x.size();
  if (n < 4) throw std::invalid_argument("a spectrum needs >= 4 samples");
  // dt finite and 1/dt too (a subnormal dt: frequencies of inf and nan).
  if (!(dt > 0) || !std::isfinite(dt) || !std::isfinite(1.0 / dt)) {
    char got[32];
    std::snprintf(got, sizeof got, "%g", dt);
    throw std::invalid_argument(std::string("a spectrum needs a sample interval dt > 0, finite, "
                                            "with 1/dt finite; got dt = ") + got);
  }
  double mean = 0;
  for (double v : x) mean += v;
  mean /= n;
  std::vector<double> in(n);
  double sw = 0, sw2 = 0;
  for (size_t i = 0; i < n; ++i) {
    // Periodic Hann window, computed on the fly (no second n-sized array).
    const double w = window == Window::hann ? 0.5 - 0.5 * std::cos(2 * M_PI * i / n) : 1.0;
    in[i] = (x[i] - mean) * w;
    sw += w;
    sw2 += w * w;
  }
  const size_t nf = n / 2 + 1;
  fftw_complex* out = fftw_alloc_complex(nf);
  make_fftw_planner_thread_safe();
  fftw_plan plan = fftw_plan_dft_r2c_1d(static_cast<int>(n), in.data(), out, FFTW_ESTIMATE);
  fftw_execute(plan);
  Spectrum s;
  s.window = window == Window::hann ? "hann" : "rectangular";
  s.frequency.resize(nf);
  s.amplitude.resize(nf);
  s.psd.resize(nf);
  const double fs = 1.0 / dt;
  for (size_t k = 0; k < nf; ++k) {
    const double mag2 = out[k][0] * out[k][0] + out[k][1] * out[k][1];
    const bool edge = k == 0 || (n % 2 == 0 && k == nf - 1);  // DC and Nyquist are not doubled
    s.frequency[k] = k * fs / n;
    s.amplitude[k] = (edge ? 1.0 : 2.0) * std::sqrt(mag2) / sw;
    s.psd[k] = (edge ? 1.0 : 2.0) * mag2 / (fs * sw2);
  }
  fftw_destroy_plan(plan);
  fftw_free(out);
  return s;
}

void decimate_min_max(const std::vector<double>& t, const std::vector<double>& v, size_t buckets,
                      std::vector<double>& t_out, std::vector<double>& v_out) {
  t_out.clear();
  v_out.clear();
  const size_t n = std::min(t.size(), v.size());
  if (n <= 2 * buckets || buckets == 0) {
    t_out.assign(t.begin(), t.begin() + n);
    v_out.assign(v.begin(), v.begin() + n);
    return;
  }
  const double per = static_cast<double>(n) / buckets;
  for (size_t b = 0; b < buckets; ++b) {
    const size_t i0 = static_cast<size_t>(b * per), i1 = std::min(n, static_cast<size_t>((b + 1) * per));
    size_t imin = i0, imax = i0;
    for (size_t i = i0; i < i1; ++i) {
      if (v[i] < v[imin]) imin = i;
      if (v[i] > v[imax]) imax = i;
    }
    const size_t a = std::min(imin, imax), c = std::max(imin, imax);
    t_out.push_back(t[a]);
    v_out.push_back(v[a]);
    if (c != a) {
      t_out.push_back(t[c]);
      v_out.push_back(v[c]);
    }
  }
}

double broadband_share(const Spectrum& s) {
  const std::vector<double>& p = s.psd;
  const int n = static_cast<int>(p.size());
  if (n < 32) return std::nan("");
  double total = 0.0;
  for (int k = 1; k < n; ++k) total += p[k];
  if (!(total > 0.0)) return std::nan("");
  std::vector<char> line(n, 0);
  std::vector<double> around;
  for (int k = 1; k + 1 < n; ++k) {
    if (p[k] < p[k - 1] || p[k] < p[k + 1] || !(p[k] > 0.0)) continue;
    around.clear();
    for (int j = k - 16; j <= k + 16; ++j)
      if (j >= 1 && j < n && std::abs(j - k) >= 4) around.push_back(p[j]);
    if (around.empty()) continue;
    std::nth_element(around.begin(), around.begin() + around.size() / 2, around.end());
    if (p[k] > kLineProminence * around[around.size() / 2])
      for (int j = std::max(1, k - 3); j <= std::min(n - 1, k + 3); ++j) line[j] = 1;
  }
  double in_lines = 0.0;
  for (int k = 1; k < n; ++k)
    if (line[k]) in_lines += p[k];
  return 1.0 - in_lines / total;
}

}  // namespace lash
