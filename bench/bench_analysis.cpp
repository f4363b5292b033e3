// Analysis throughput on a 10-million-sample channel: streaming statistics, min/max decimation
// for display, and the amplitude spectrum (FFTW) of the whole record. Reports wall time per
// stage and the peak resident memory (VmHWM), which should be the samples kept (80 MB for 10M
// doubles) plus the FFT's work arrays, nothing more.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "analysis/signal.hpp"

namespace {
double vm_hwm_mib() {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::atof(line.c_str() + 6) / 1024.0;
  return 0.0;
}
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

int main(int argc, char** argv) {
  const size_t n = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 10'000'000;
  const double dt = 1e-5;
  std::printf("samples: %zu (dt = %g s)\n", n, dt);
  auto t0 = std::chrono::steady_clock::now();
  std::vector<double> t(n), x(n);
  for (size_t i = 0; i < n; ++i) {
    t[i] = i * dt;
    // A crank-like 83.3 Hz fundamental, a harmonic, and sparse impact spikes.
    x[i] = 1.9e4 * std::cos(2 * M_PI * 83.33 * t[i]) + 5e3 * std::cos(2 * M_PI * 166.67 * t[i]) +
           (i % 9973 == 0 ? 3e5 : 0.0);
  }
  std::printf("%-28s %8.3f s\n", "generate", seconds_since(t0));

  t0 = std::chrono::steady_clock::now();
  lash::ChannelStats stats;
  for (size_t i = 0; i < n; ++i) stats.add(t[i], x[i]);
  std::printf("%-28s %8.3f s   peak %.4g rms %.4g crest %.3g\n", "statistics (streaming)",
              seconds_since(t0), stats.peak(), stats.rms(), stats.crest());

  t0 = std::chrono::steady_clock::now();
  std::vector<double> td, xd;
  lash::decimate_min_max(t, x, 800, td, xd);
  double kept_peak = 0;
  for (double v : xd) kept_peak = std::max(kept_peak, std::abs(v));
  std::printf("%-28s %8.3f s   %zu points, peak kept %.4g\n", "min/max decimation",
              seconds_since(t0), td.size(), kept_peak);

  t0 = std::chrono::steady_clock::now();
  const lash::Spectrum s = lash::amplitude_spectrum(x, dt);
  size_t top = 1;
  for (size_t k = 1; k < s.amplitude.size(); ++k)
    if (s.amplitude[k] > s.amplitude[top]) top = k;
  std::printf("%-28s %8.3f s   %zu bins, strongest %.3f Hz (%.4g)\n", "spectrum (FFTW, Hann)",
              seconds_since(t0), s.frequency.size(), s.frequency[top], s.amplitude[top]);
  std::printf("peak memory (VmHWM): %.1f MiB; the samples alone: %.1f MiB\n", vm_hwm_mib(),
              2.0 * n * sizeof(double) / (1024.0 * 1024.0));
  return 0;
}
