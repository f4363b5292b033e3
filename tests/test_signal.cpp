// Statistics, spectra and decimation against signals whose answers are known.
#include <gtest/gtest.h>

#include <cmath>
#include <thread>

#include "analysis/signal.hpp"

using namespace lash;

TEST(Spectrum, SumOfSinusoidsOnBins) {
  // 1 kHz sampling, 1 s: 50 Hz amplitude 3 and 120 Hz amplitude 0.5 plus an offset of 7.
  const double dt = 1e-3;
  std::vector<double> x(1000);
  for (size_t i = 0; i < x.size(); ++i) {
    const double t = i * dt;
    x[i] = 7 + 3 * std::sin(2 * M_PI * 50 * t) + 0.5 * std::cos(2 * M_PI * 120 * t);
  }
  for (Window w : {Window::rectangular, Window::hann}) {
    const Spectrum s = amplitude_spectrum(x, dt, w);
    ASSERT_EQ(s.frequency.size(), 501u);
    EXPECT_DOUBLE_EQ(s.frequency[50], 50.0);
    EXPECT_NEAR(s.amplitude[50], 3.0, 1e-9);
    EXPECT_NEAR(s.amplitude[120], 0.5, 1e-9);
    EXPECT_NEAR(s.amplitude[0], 0.0, 1e-9);  // the mean is removed
    if (w == Window::rectangular) {
      EXPECT_NEAR(s.amplitude[80], 0.0, 1e-9);
    }
  }
  // Parseval with the rectangular window: Σ PSD·df = variance of the signal.
  const Spectrum s = amplitude_spectrum(x, dt, Window::rectangular);
  double power = 0;
  for (double p : s.psd) power += p * (s.frequency[1] - s.frequency[0]);
  EXPECT_NEAR(power, 3.0 * 3.0 / 2 + 0.5 * 0.5 / 2, 1e-9);
}

TEST(Spectrum, RejectsTooShortInput) {
  EXPECT_THROW(amplitude_spectrum({1, 2, 3}, 1e-3), std::invalid_argument);
  EXPECT_THROW(amplitude_spectrum({1, 2, 3, 4}, 0.0), std::invalid_argument);
}

TEST(ChannelStats, PeakRmsCrestOfASine) {
  ChannelStats s;
  for (int i = 0; i < 100000; ++i) s.add(i * 1e-5, 2.0 * std::sin(2 * M_PI * i / 1000.0));
  EXPECT_NEAR(s.peak(), 2.0, 1e-6);
  EXPECT_NEAR(s.rms(), 2.0 / std::sqrt(2.0), 1e-6);
  EXPECT_NEAR(s.crest(), std::sqrt(2.0), 1e-6);
  ChannelStats w;
  w.t0 = 0.5;
  w.t1 = 0.6;
  for (int i = 0; i <= 100; ++i) w.add(i * 0.01, i);
  EXPECT_EQ(w.n, 11);
  EXPECT_DOUBLE_EQ(w.min, 50);
  EXPECT_DOUBLE_EQ(w.max, 60);
}

TEST(Decimation, KeepsSpikes) {
  std::vector<double> t(100000), v(100000, 0.0);
  for (size_t i = 0; i < t.size(); ++i) t[i] = i;
  v[31337] = 1e6;
  v[77777] = -5e5;
  std::vector<double> to, vo;
  decimate_min_max(t, v, 500, to, vo);
  EXPECT_LE(to.size(), 1000u);
  EXPECT_EQ(*std::max_element(vo.begin(), vo.end()), 1e6);
  EXPECT_EQ(*std::min_element(vo.begin(), vo.end()), -5e5);
  for (size_t i = 1; i < to.size(); ++i) ASSERT_GT(to[i], to[i - 1]);
}

TEST(Spectrum, ConcurrentSpectraEqualSerialOnes) {
  // FFTW's planner is serialized (fftw_make_planner_thread_safe): four threads planning,
  // executing and destroying plans of different sizes at once get exactly the serial results.
  std::vector<std::vector<double>> signals;
  for (size_t n : {64, 100, 257, 1000, 1024, 4096, 999, 3000}) {
    std::vector<double> x(n);
    for (size_t i = 0; i < n; ++i) x[i] = std::sin(0.37 * i) + 0.1 * std::cos(2.1 * i) + 1e-3 * i;
    signals.push_back(std::move(x));
  }
  auto spectra_of_all = [&] {
    std::vector<Spectrum> out;
    for (int repeat = 0; repeat < 20; ++repeat)
      for (const auto& x : signals)
        for (Window w : {Window::rectangular, Window::hann})
          out.push_back(amplitude_spectrum(x, 1e-3, w));
    return out;
  };
  const std::vector<Spectrum> serial = spectra_of_all();
  std::vector<std::vector<Spectrum>> parallel(4);
  std::vector<std::thread> threads;
  for (auto& p : parallel) threads.emplace_back([&p, &spectra_of_all] { p = spectra_of_all(); });
  for (auto& t : threads) t.join();
  for (size_t k = 0; k < parallel.size(); ++k) {
    ASSERT_EQ(parallel[k].size(), serial.size());
    for (size_t i = 0; i < serial.size(); ++i) {
      // Exact equality of every double: the same plans, the same arithmetic.
      EXPECT_EQ(parallel[k][i].amplitude, serial[i].amplitude) << "thread " << k << ", #" << i;
      EXPECT_EQ(parallel[k][i].psd, serial[i].psd) << "thread " << k << ", #" << i;
      EXPECT_EQ(parallel[k][i].frequency, serial[i].frequency);
    }
  }
}

TEST(Spectrum, BroadbandShareTellsLinesFromAContinuousSpectrum) {
  // 16384 samples every 10 ms. Periodic and quasi-periodic signals put their power in lines;
  // white noise and the Lorenz system's x (σ = 10, ρ = 28, β = 8/3, chaotic) spread it.
  const int n = 16384;
  const double dt = 0.01;
  std::vector<double> qp(n), spikes(n), noise(n), lorenz(n);
  unsigned long long seed = 12345;
  auto uniform = [&] {  // a 64-bit linear congruential generator (Knuth's MMIX constants)
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(seed >> 11) / 9007199254740992.0 - 0.5;
  };
  for (int i = 0; i < n; ++i) {
    const double t = i * dt;
    qp[i] = std::sin(2 * M_PI * 3.1 * t) + 0.5 * std::sin(2 * M_PI * 3.1 * std::sqrt(2.0) * t);
    const double phase = std::fmod(t, 0.37) - 0.185;  // an impact every 0.37 s, 10 ms wide
    spikes[i] = std::exp(-phase * phase / (2 * 0.005 * 0.005));
    noise[i] = uniform();
  }
  // Lorenz by classical Runge–Kutta, 10 steps per sample, after a transient of 50 time units.
  double y[3] = {1, 1, 20};
  auto f = [](const double* a, double* d) {
    d[0] = 10 * (a[1] - a[0]);
    d[1] = a[0] * (28 - a[2]) - a[1];
    d[2] = a[0] * a[1] - 8.0 / 3.0 * a[2];
  };
  auto step = [&](double h) {
    double k1[3], k2[3], k3[3], k4[3], tmp[3];
    f(y, k1);
    for (int j = 0; j < 3; ++j) tmp[j] = y[j] + 0.5 * h * k1[j];
    f(tmp, k2);
    for (int j = 0; j < 3; ++j) tmp[j] = y[j] + 0.5 * h * k2[j];
    f(tmp, k3);
    for (int j = 0; j < 3; ++j) tmp[j] = y[j] + h * k3[j];
    f(tmp, k4);
    for (int j = 0; j < 3; ++j) y[j] += h / 6 * (k1[j] + 2 * k2[j] + 2 * k3[j] + k4[j]);
  };
  for (int i = 0; i < 50000; ++i) step(1e-3);
  for (int i = 0; i < n; ++i) {
    lorenz[i] = y[0];
    for (int k = 0; k < 10; ++k) step(dt / 10);
  }
  const double b_qp = broadband_share(amplitude_spectrum(qp, dt));
  const double b_spikes = broadband_share(amplitude_spectrum(spikes, dt));
  const double b_noise = broadband_share(amplitude_spectrum(noise, dt));
  const double b_lorenz = broadband_share(amplitude_spectrum(lorenz, dt));
  std::printf("broadband share: quasi-periodic %.4f, impact train %.4f, noise %.4f, Lorenz %.4f\n",
              b_qp, b_spikes, b_noise, b_lorenz);
  EXPECT_LT(b_qp, 0.01);
  EXPECT_LT(b_spikes, 0.05);
  EXPECT_GT(b_noise, 0.9);
  EXPECT_GT(b_lorenz, 0.5);
  EXPECT_TRUE(std::isnan(broadband_share(amplitude_spectrum(std::vector<double>(16, 1.0), dt))));
}
