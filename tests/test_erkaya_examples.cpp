// examples/erkaya_articulated.yaml and examples/erkaya_compliant.yaml (Erkaya, Doğan & Ulus,
// Mechanism and Machine Theory 88 (2015) 125–140) against what can be derived for them by hand.
#include <cmath>

#include "test_support.hpp"

using namespace lash;
using namespace lash::test;

namespace {

constexpr double kCrank = 0.150;                        // m, Table 1
constexpr double kSpeed = 150 * 2 * M_PI / 60;          // rad/s, the files' 150 rpm
constexpr double kRevolution = 2 * M_PI / kSpeed;       // s

struct Example {
  const char* file;
  double coupler;                        // m: crank pin to piston pin (or pseudo-pin)
  std::vector<std::string> ideal;        // overrides that close every clearance joint
};

const Example kExamples[] = {
    {"erkaya_articulated.yaml", 0.564,
     {"joints.crank_rod.clearance=0", "joints.rod_piston.clearance=0"}},
    {"erkaya_compliant.yaml", 0.475, {"joints.crank_rod.clearance=0"}},
};

double max_abs(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

}  // namespace

TEST(ErkayaExamples, IdealTwinsFollowTheSliderCrankClosedForm) {
  // With the clearances closed, the piston follows x = r cos θ + sqrt(L² − r² sin² θ), θ = ω t,
  // up to the deflection of the bearing housings' mounts (force / 1e8 N/m: micrometres).
  for (const Example& e : kExamples) {
    SCOPED_TRACE(e.file);
    std::vector<std::string> ov = e.ideal;
    ov.push_back("solver.end_time=" + std::to_string(kRevolution));
    ov.push_back("solver.output_interval=1.0e-3");
    const SimRun r = run_example(e.file, ov);
    ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
    const auto& t = r.rec->time;
    const auto& x = (*r.rec)["piston.x"];
    ASSERT_GE(t.size(), 400u);
    double err = 0;
    for (size_t i = 0; i < t.size(); ++i) {
      const double th = kSpeed * t[i], s = std::sin(th);
      const double exact = kCrank * std::cos(th) + std::sqrt(e.coupler * e.coupler - kCrank * kCrank * s * s);
      err = std::max(err, std::abs(x[i] - exact));
    }
    EXPECT_LT(err, 2e-5);                                           // m, against a 0.3 m stroke
    EXPECT_LT(max_abs((*r.rec)["crank_mount.dx"]), 2e-5);          // the mounts barely move
    EXPECT_LT(max_abs((*r.rec)["guide_mount.dy"]), 2e-5);
  }
}

TEST(ErkayaExamples, FlexureSpringIsTheBeamStiffnessAndPeaksAtTheLargestRodAngle) {
  // Pseudo-rigid-body spring of the flexural pivot (Howell 2001; the paper's eq. 2):
  // K_b = E I / l with E = 953 N/mm², a 30 mm × 4.15 mm section bent about its thin side, l = 40 mm.
  const double e_mod = 953e6, depth = 0.030, thickness = 0.00415, length = 0.040;
  const double k_b = e_mod * depth * std::pow(thickness, 3) / 12 / length;
  ASSERT_NEAR(k_b, 4.2571, 1e-4);
  const Example& e = kExamples[1];
  std::vector<std::string> ov = e.ideal;
  ov.push_back("solver.end_time=" + std::to_string(kRevolution));
  ov.push_back("solver.output_interval=1.0e-3");
  const SimRun r = run_example(e.file, ov);
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const auto& torque = (*r.rec)["flexure_spring.torque"];
  const auto& rod = (*r.rec)["rod.phi"];
  const auto& piston = (*r.rec)["piston.phi"];
  int checked = 0;
  for (size_t i = 0; i < torque.size(); ++i) {
    const double theta = rod[i] - piston[i];  // Θ = θ3 − θ30 with θ30 = 0 (eq. 1)
    if (std::abs(theta) < 0.05) continue;
    EXPECT_NEAR(torque[i] / theta, k_b, 1e-6 * k_b);  // on the piston, +K_b Θ
    ++checked;
  }
  EXPECT_GT(checked, 100);
  // The rod turns at most asin(r / L) from the stroke, at crank angles ±90°.
  const double peak = k_b * std::asin(kCrank / e.coupler);
  EXPECT_NEAR(max_abs(torque), peak, 2e-3 * peak);
}

TEST(ErkayaExamples, EnergyBalanceHoldsThroughTheImpacts) {
  // With the clearances open the journals impact within the first 0.1 s; kinetic + potential +
  // dissipated − input − stabilisation must stay constant (measured drift: below 1e-6 J).
  for (const Example& e : kExamples) {
    SCOPED_TRACE(e.file);
    const SimRun r = run_example(e.file, {"solver.end_time=0.1", "solver.output_interval=1.0e-3"});
    ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
    EXPECT_GE(r.rec->events.size(), 10u);
    const auto& b = (*r.rec)["energy.balance"];
    double drift = 0;
    for (double v : b) drift = std::max(drift, std::abs(v - b.front()));
    EXPECT_LT(drift, 1e-5);  // J, against a kinetic energy of about 1 J
  }
}
