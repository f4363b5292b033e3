#pragma once
/// @file signal.hpp
/// Channel statistics and spectra. Pure functions and small accumulators over samples; no model.
#include <string>
#include <vector>

namespace lash {

/// Streaming statistics of one channel over a window [t0, t1] (inclusive).
struct ChannelStats {
  double t0 = -1e300, t1 = 1e300;
  long n = 0;
  double min = 0.0, max = 0.0, sum = 0.0, sum_sq = 0.0;
  double t_min = 0.0, t_max = 0.0;      ///< times of min and max
  void add(double t, double v);
  double peak() const;                  ///< max |v|
  double rms() const;                   ///< sqrt(mean v²)
  double mean() const;
  double crest() const;                 ///< peak / rms (0 when rms is 0)
};

/// One-sided amplitude spectrum of uniformly sampled data.
struct Spectrum {
  std::vector<double> frequency;  ///< Hz, 0 … f_Nyquist
  std::vector<double> amplitude;  ///< same units as the signal: a sinusoid of amplitude A on a bin reads A
  std::vector<double> psd;        ///< power spectral density, units²/Hz (one-sided)
  std::string window;
};

enum class Window { rectangular, hann };

/// Amplitude spectrum and PSD of `x` sampled every `dt` seconds (FFTW, real-to-complex), after
/// removing the mean and applying the window. The amplitude is corrected by the window's
/// coherent gain (Σw/N), the PSD by its energy (Σw²). Throws std::invalid_argument for < 4
/// samples or dt ≤ 0.
Spectrum amplitude_spectrum(const std::vector<double>& x, double dt, Window window = Window::hann);

/// Share of a spectrum's power (its PSD, the mean bin excluded) that lies outside its lines: a
/// line is a local maximum more than kLineProminence times the median of the bins 4 to 16 bins
/// away on either side, and owns the bins within 3 of it (the Hann window's main lobe and its
/// first side lobe). Near 0 for periodic and quasi-periodic signals (all power in lines), near 1
/// for noise; a chaotic signal's continuous spectrum lies in between or high. NaN for fewer than
/// 32 bins or no power.
double broadband_share(const Spectrum& s);
constexpr double kLineProminence = 10.0;

/// Reduces (t, v) to at most ~2·buckets points keeping each bucket's minimum and maximum in time
/// order, so spikes survive decimation for display.
void decimate_min_max(const std::vector<double>& t, const std::vector<double>& v, size_t buckets,
                      std::vector<double>& t_out, std::vector<double>& v_out);

}  // namespace lash
