// Poincaré clustering, Lyapunov exponents and contact modes on systems with known answers.
#include <gtest/gtest.h>

#include <cmath>

#include "analysis/dynamics_analysis.hpp"
#include "core/integrator.hpp"

using namespace lash;

TEST(Poincare, PeriodicAndPeriodTwoOrbits) {
  // Stroboscopic samples of x = cos(ωt) at t = kT (T = 2π/ω): one point; of cos(ωt/2): two.
  std::vector<std::vector<double>> p1, p2, q;
  for (int k = 0; k < 20; ++k) {
    const double t = k * 2 * M_PI;
    p1.push_back({std::cos(t), -std::sin(t)});
    p2.push_back({std::cos(t / 2), -std::sin(t / 2) / 2});
    q.push_back({std::cos(std::sqrt(2.0) * t), std::sin(std::sqrt(2.0) * t)});  // quasi-periodic
  }
  EXPECT_EQ(count_distinct(p1, 1e-9), 1);
  EXPECT_EQ(count_distinct(p2, 1e-9), 2);
  EXPECT_EQ(count_distinct(q, 1e-3), 20);
}

namespace {
// Flow of an ODE by DOPRI5 at tight tolerances.
std::function<bool(int, Eigen::VectorXd&, double, double)> ode_flow(OdeProblem p) {
  return [p](int, Eigen::VectorXd& y, double t0, double t1) {
    IntegratorOptions o;
    o.rtol = 1e-10;
    o.atol = 1e-12;
    auto in = make_dopri5(p, o);
    in->reset(t0, y);
    return in->advance(t1, y).kind == Advance::reached;
  };
}
double euclid(const Eigen::VectorXd& a, const Eigen::VectorXd& b) { return (a - b).norm(); }
}  // namespace

TEST(Lyapunov, LorenzAtStandardParameters) {
  // σ = 10, ρ = 28, β = 8/3: λ₁ ≈ 0.9056 (Sprott, Chaos and Time-Series Analysis, 2003).
  OdeProblem p;
  p.n = 3;
  p.rhs = [](double, const double* y, double* d) {
    d[0] = 10 * (y[1] - y[0]);
    d[1] = y[0] * (28 - y[2]) - y[1];
    d[2] = y[0] * y[1] - 8.0 / 3.0 * y[2];
    return true;
  };
  Eigen::VectorXd y0(3);
  y0 << 1, 1, 20;
  LyapunovOptions o;
  o.d0 = 1e-8;
  o.interval = 0.5;
  o.transient = 20;
  o.intervals = 1200;
  const LyapunovResult r = largest_lyapunov(ode_flow(p), y0, euclid, o);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_NEAR(r.exponent, 0.9056, 0.05 * 0.9056);
}

TEST(Lyapunov, LogisticMapAtRFourIsLnTwo) {
  // x → 4x(1 − x): λ = ln 2 per iteration.
  auto map = [](int, Eigen::VectorXd& y, double t0, double t1) {
    for (int i = 0; i < static_cast<int>(std::lround(t1 - t0)); ++i) y[0] = 4 * y[0] * (1 - y[0]);
    return true;
  };
  Eigen::VectorXd y0(1);
  y0 << 0.3;
  LyapunovOptions o;
  o.d0 = 1e-10;
  o.interval = 1.0;
  o.transient = 100;
  o.intervals = 20000;
  const LyapunovResult r = largest_lyapunov(map, y0, euclid, o);
  EXPECT_NEAR(r.exponent, std::log(2.0), 0.03 * std::log(2.0));
}

TEST(Lyapunov, DampedOscillatorIsNotPositive) {
  // ẍ + 2ζω ẋ + ω² x = 0, ζ = 0.05, ω = 2π: λ = −ζω ≈ −0.314.
  OdeProblem p;
  p.n = 2;
  p.rhs = [](double, const double* y, double* d) {
    const double w = 2 * M_PI;
    d[0] = y[1];
    d[1] = -2 * 0.05 * w * y[1] - w * w * y[0];
    return true;
  };
  Eigen::VectorXd y0(2);
  y0 << 1, 0;
  LyapunovOptions o;
  o.d0 = 1e-8;
  o.interval = 0.25;
  o.intervals = 200;
  const LyapunovResult r = largest_lyapunov(ode_flow(p), y0, euclid, o);
  EXPECT_LE(r.exponent, 0.0);
  EXPECT_NEAR(r.exponent, -0.05 * 2 * M_PI, 0.05);
}

TEST(ContactModes, SharesOfAConstructedHistory) {
  // Over [0, 1] s: impact 0.10–0.11, continuous contact 0.3–0.6, impact 0.8–0.805.
  const std::vector<double> t{0.10, 0.11, 0.3, 0.6, 0.8, 0.805};
  const std::vector<bool> on{true, false, true, false, true, false};
  const std::vector<double> v{2.0, -1.8, 0.5, -0.1, 1.0, -0.9};
  const ModeSummary m = contact_modes(t, on, v, false, 0.0, 1.0, 0.05);
  ASSERT_EQ(m.episodes.size(), 3u);
  EXPECT_EQ(m.impacts, 3);
  EXPECT_FALSE(m.episodes[0].continuous);
  EXPECT_TRUE(m.episodes[1].continuous);
  EXPECT_NEAR(m.impact_share, 0.015, 1e-12);
  EXPECT_NEAR(m.continuous_share, 0.3, 1e-12);
  EXPECT_NEAR(m.free_flight_share, 0.685, 1e-12);
  EXPECT_EQ(m.impact_velocities, (std::vector<double>{2.0, 0.5, 1.0}));
  // Starting in contact and never separating: all continuous.
  const ModeSummary c = contact_modes({}, {}, {}, true, 0.0, 1.0, 0.05);
  EXPECT_NEAR(c.continuous_share, 1.0, 1e-12);
  // A window of 0.02 s inside the 0.3 s contact: continuous, no impact (clipped to the window
  // first, the episode was shorter than 0.05 s and counted as an impact). Windows that cut the
  // contact at one end only, likewise; the short impact cut by a window stays an impact.
  const ModeSummary w = contact_modes(t, on, v, true, 0.40, 0.42, 0.05);
  ASSERT_EQ(w.episodes.size(), 1u);
  EXPECT_TRUE(w.episodes[0].continuous);
  EXPECT_EQ(w.impacts, 0);
  EXPECT_NEAR(w.continuous_share, 1.0, 1e-12);
  EXPECT_EQ(w.impact_share, 0.0);
  EXPECT_TRUE(contact_modes(t, on, v, true, 0.58, 0.7, 0.05).episodes[0].continuous);
  const ModeSummary head = contact_modes(t, on, v, false, 0.29, 0.31, 0.05);
  ASSERT_EQ(head.episodes.size(), 1u);
  EXPECT_TRUE(head.episodes[0].continuous);
  EXPECT_EQ(head.impacts, 1);
  // Windows whose edges fall on an event: an episode that begins at t0 or ends at t1 is whole
  // inside, and a neighbour's times do not count (a 2 ms impact at 0.3 s was "continuous").
  const std::vector<double> t2{0.1, 0.2, 0.3, 0.302, 0.4, 0.6};
  const std::vector<bool> on2{true, false, true, false, true, false};
  const std::vector<double> v2(6, 1.0);
  for (const auto& [a, b] : std::vector<std::pair<double, double>>{{0.3, 0.35}, {0.25, 0.302}, {0.25, 0.35}}) {
    const ModeSummary e = contact_modes(t2, on2, v2, false, a, b, 0.05);
    ASSERT_EQ(e.episodes.size(), 1u) << a << " " << b;
    EXPECT_FALSE(e.episodes[0].continuous) << a << " " << b;
  }
  const ModeSummary cut = contact_modes(t, on, v, true, 0.105, 0.2, 0.05);
  ASSERT_EQ(cut.episodes.size(), 1u);
  EXPECT_FALSE(cut.episodes[0].continuous);
  EXPECT_NEAR(cut.impact_share, 0.005 / 0.095, 1e-12);
}

TEST(Verdict, WeighsTheEvidence) {
  EXPECT_EQ(classify_motion(5.0, 0.012, 30, 30, 4).kind, "quasi-periodic");   // λT = 0.06
  EXPECT_EQ(classify_motion(50.0, 0.012, 30, 30, 4).kind, "chaotic");         // λT = 0.6
  EXPECT_EQ(classify_motion(-3.0, 0.012, 2, 20, 0).kind, "periodic");
  EXPECT_EQ(classify_motion(std::nan(""), 0.012, 1, 2, -1).kind, "undetermined");
  // The rule's edges (verdict_rule()): 16 sections at least; k <= 8 points, each recurring.
  EXPECT_EQ(classify_motion(-3.0, 0.012, 1, 15, 0).kind, "undetermined");
  EXPECT_EQ(classify_motion(-3.0, 0.012, 1, 15, 0, 0.204).evidence.back(),
            "not enough periods: 15 sections after the transient, 16 needed; run to end_time >= 0.204 s");
  EXPECT_EQ(classify_motion(-3.0, 0.012, 1, 16, 0).kind, "periodic");
  EXPECT_EQ(classify_motion(-3.0, 0.012, 8, 16, 0).kind, "periodic");
  EXPECT_EQ(classify_motion(-3.0, 0.012, 9, 40, 0).kind, "quasi-periodic");   // k > 8
  EXPECT_EQ(classify_motion(-3.0, 0.012, 8, 15, 0).kind, "undetermined");     // too few
  EXPECT_EQ(classify_motion(-3.0, 0.012, 9, 17, 0).kind, "quasi-periodic");   // 9 > 17/2
  // Recurring points decide on their own, even against a positive exponent.
  EXPECT_EQ(classify_motion(50.0, 0.012, 2, 20, 0).kind, "periodic");
  // Points that do not recur and no exponent: undetermined, and it says why.
  const Verdict none = classify_motion(std::nan(""), 0.012, 30, 30, 4);
  EXPECT_EQ(none.kind, "undetermined");
  EXPECT_NE(none.evidence.back().find("no Lyapunov exponent"), std::string::npos);
  // λT exactly at the threshold is not chaotic.
  EXPECT_EQ(classify_motion(0.1 / 0.5, 0.5, 30, 30, 0).kind, "quasi-periodic");
  // Without an exponent the spectrum decides: broadband share above 0.5 chaotic, below 0.1
  // quasi-periodic, in between undetermined; with one, the exponent decides and the spectrum's
  // agreement is stated.
  const double nan = std::nan("");
  EXPECT_EQ(classify_motion(nan, 0.012, 30, 30, 4, 0.0, 0.9).kind, "chaotic");
  EXPECT_EQ(classify_motion(nan, 0.012, 30, 30, 4, 0.0, 0.02).kind, "quasi-periodic");
  EXPECT_EQ(classify_motion(nan, 0.012, 30, 30, 4, 0.0, 0.3).kind, "undetermined");
  EXPECT_EQ(classify_motion(nan, 0.012, 30, 30, 4, 0.0, 0.51).kind, "chaotic");
  EXPECT_EQ(classify_motion(nan, 0.012, 30, 30, 4, 0.0, 0.099).kind, "quasi-periodic");
  const Verdict against = classify_motion(50.0, 0.012, 30, 30, 4, 0.0, 0.02);
  EXPECT_EQ(against.kind, "chaotic");
  EXPECT_EQ(against.evidence.back(), "the spectrum disagrees; the exponent decides");
  EXPECT_EQ(classify_motion(50.0, 0.012, 30, 30, 4, 0.0, 0.9).evidence.back(),
            "the spectrum agrees; the exponent decides");
  // Recurring points still decide first.
  EXPECT_EQ(classify_motion(nan, 0.012, 2, 20, 0, 0.0, 0.9).kind, "periodic");
  // A transient decaying onto its orbit: 7 points met once, then the orbit's one point 17 times
  // (a forced damped rotor). It was "period-8 orbit: every point recurs"; it is period-1.
  const Verdict settling = classify_motion(-2.5, 0.2, 8, 24, 0, 0.0, nan, 1);
  EXPECT_EQ(settling.kind, "periodic");
  EXPECT_EQ(settling.evidence.back(),
            "period-1 orbit: its points recur, after 7 points met once (a transient: --discard "
            "leaves them out)");
  // One leading point before a recurring cluster: period-1 whatever the exponent says.
  EXPECT_EQ(classify_motion(nan, 0.012, 2, 25, 0, 0.0, nan, 1).kind, "periodic");
  EXPECT_EQ(classify_motion(30.0, 0.012, 2, 25, 0, 0.0, nan, 1).kind, "periodic");
  // Most points met once: not periodic, whichever few recur; the exponent decides.
  EXPECT_EQ(classify_motion(nan, 0.2, 20, 24, 0, 0.0, nan, 2).kind, "undetermined");
  EXPECT_EQ(classify_motion(50.0, 0.2, 20, 24, 0, 0.0, nan, 2).kind, "chaotic");
  EXPECT_EQ(classify_motion(-0.3, 0.2, 20, 24, 0, 0.0, nan, 2).kind, "quasi-periodic");  // λT −0.06
  // A clearly negative exponent with points that do not recur: converging, not quasi-periodic.
  const Verdict converging = classify_motion(-2.5, 0.2, 20, 24, 0, 0.0, nan, 2);
  EXPECT_EQ(converging.kind, "periodic");
  EXPECT_NE(converging.evidence.back().find("converging"), std::string::npos);
  // A damped oscillator decaying to rest: λ = −1 1/s, T = 0.314 s, nothing recurs.
  EXPECT_EQ(classify_motion(-1.0, 0.314, 28, 38, 0).kind, "periodic");
  // A lightly damped one (λ = −0.1 1/s, T = 0.5 s: λT = −0.05, inside the quasi-periodic band)
  // was "quasi-periodic" at rest-convergence; the returns shrinking to 0.24 make it converging,
  // while returns that keep their size (0.9: a torus) leave it quasi-periodic.
  const Verdict slow = classify_motion(-0.1, 0.5, 40, 40, 1, 0.0, nan, 0, 0.24);
  EXPECT_EQ(slow.kind, "periodic");
  EXPECT_NE(slow.evidence.back().find("converging: lambda*T < 0 and the points' returns shrank to 0.24"),
            std::string::npos) << slow.evidence.back();
  EXPECT_EQ(classify_motion(-0.1, 0.5, 40, 40, 1, 0.0, nan, 0, 0.9).kind, "quasi-periodic");
  EXPECT_EQ(classify_motion(-0.1, 0.5, 40, 40, 1, 0.0, nan, 0, nan).kind, "quasi-periodic");
  // Shrinking returns with a positive exponent (inside the band): not converging.
  EXPECT_EQ(classify_motion(0.1, 0.5, 40, 40, 1, 0.0, nan, 0, 0.24).kind, "quasi-periodic");
}

TEST(Verdict, SectionContractionMeasuresHowTheReturnsShrink) {
  // A damped oscillator sampled every 0.5 s (ω = 10 rad/s, λ = −0.1 1/s): its points rotate by
  // 5 rad and shrink by exp(−0.05) per section, so the returns shrink by exp(−0.05 · 22) = 0.33
  // from the first third of the 32 returns (points 0–9) to the last (22–31): the medians' ratio.
  std::vector<std::vector<double>> decaying, torus;
  for (int i = 0; i < 40; ++i) {
    const double r = std::exp(-0.05 * i), a = 5.0 * i;
    decaying.push_back({r * std::cos(a), r * std::sin(a)});
    torus.push_back({std::cos(a), std::sin(a)});  // the same rotation, no decay
  }
  EXPECT_NEAR(section_contraction(decaying), std::exp(-0.05 * 22), 1e-12);
  EXPECT_NEAR(section_contraction(torus), 1.0, 1e-12);
  // A period-2 orbit approached geometrically: each point's return is to the point two later.
  std::vector<std::vector<double>> two;
  for (int i = 0; i < 30; ++i) two.push_back({(i % 2 ? 1.0 : -1.0) + 0.5 * std::exp(-0.2 * i), 0.0});
  EXPECT_LT(section_contraction(two), 0.05);
  // Too few points (fewer than 4 with 8 successors), or a first third already at rest: NaN.
  EXPECT_TRUE(std::isnan(section_contraction(std::vector<std::vector<double>>(11, {1.0, 2.0}))));
  EXPECT_TRUE(std::isnan(section_contraction(std::vector<std::vector<double>>(30, {1.0, 2.0}))));
}

TEST(Verdict, CountsTheDistinctPointsThatRecur) {
  // Three points of a transient, then a period-2 orbit: 5 distinct, 2 of them recurring.
  const std::vector<std::vector<double>> p = {{3, 0}, {2, 0}, {1.5, 0}, {1, 0}, {-1, 0},
                                              {1, 1e-9}, {-1, 0}, {1, 0}, {-1, 0}};
  EXPECT_EQ(count_distinct(p, 1e-6), 5);
  EXPECT_EQ(count_recurring(p, 1e-6), 2);
  EXPECT_EQ(count_recurring({}, 1e-6), 0);
}
