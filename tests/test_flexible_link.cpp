// Flexible links in the engine (core/elements/flexible_link.cpp): a planar ANCF beam coupled by
// joints with rigid bodies. The beam's own mathematics is tested in test_beam.cpp; here: energy
// balance, the rigid limit, a bending frequency of a pinned beam in a model, the flexible-rod
// slider-crank against the rigid one, and the model file's checks.
#include <cmath>

#include "test_support.hpp"

namespace lash::test {
namespace {

// Aluminium bar 1 m × 20 mm (across the plane) × 10 mm (in it): EI = 116.7 N·m², ρA = 0.54 kg/m.
constexpr double kE = 70e9, kRho = 2700, kB = 0.02, kH = 0.01, kL = 1.0;

std::string bar(double youngs_modulus, int elements, const std::string& extra = "") {
  std::ostringstream s;
  s << "    position: [0.5, 0]\n"
       "    markers: {A: [-0.5, 0], M: [0, 0], B: [0.5, 0]}\n"
       "    flexible:\n"
       "      length: 1.0\n"
       "      elements: " << elements << "\n"
       "      section: {rectangle: [0.02, 0.01]}\n"
       "      youngs_modulus: " << youngs_modulus << "\n"
       "      density: 2700\n" << extra;
  return s.str();
}

/// A bar pinned at end A to the ground, released horizontal under gravity.
std::string pendulum(double youngs_modulus, int elements, double end_time) {
  std::ostringstream s;
  s << "gravity: [0, -9.81]\nground: {markers: {O: [0, 0]}}\nbodies:\n  bar:\n"
    << bar(youngs_modulus, elements)
    << "joints:\n  pin: {type: revolute, journal: bar.A, bearing: ground.O}\n"
       "solver: {rtol: 1.0e-9, atol: 1.0e-12, end_time: " << end_time
    << ", output_interval: 0.01}\n";
  return s.str();
}

TEST(FlexibleLink, AFallingPinnedBarKeepsItsEnergyWithoutDamping) {
  const SimRun r = run_text(pendulum(7e9, 4, 0.4));
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const auto& bal = (*r.rec)["energy.balance"];
  const auto& kin = (*r.rec)["energy.kinetic"];
  const double scale = 0.54 * 9.81 * 0.5;  // m g L/2: the energy the fall turns over
  EXPECT_GT(kin.back(), 0.3 * scale);      // it did fall
  EXPECT_LT(max_abs_diff(bal, std::vector<double>(bal.size(), bal.front())), 1e-6 * scale);
  // It bends: the bar is not rigid, and its strain energy is part of the balance.
  double strain = 0.0;
  for (double u : (*r.rec)["bar.strain_energy"]) strain = std::max(strain, u);
  EXPECT_GT(strain, 1e-7 * scale);
  EXPECT_EQ((*r.rec)["energy.dissipated"].back(), 0.0);
}

TEST(FlexibleLink, TheBarsMotionConvergesToTheRigidPendulumsAsItStiffens) {
  // The rigid bar: a rigid body with I = mL²/12, pinned at its end (two independent
  // computations of one motion).
  const std::string rigid =
      "gravity: [0, -9.81]\nground: {markers: {O: [0, 0]}}\nbodies:\n  bar:\n"
      "    mass: 0.54\n    inertia: 0.045\n    position: [0.5, 0]\n"
      "    markers: {A: [-0.5, 0]}\n"
      "joints:\n  pin: {type: revolute, journal: bar.A, bearing: ground.O}\n"
      "solver: {rtol: 1.0e-10, atol: 1.0e-12, end_time: 0.3, output_interval: 0.01}\n";
  const SimRun ref = run_text(rigid);
  ASSERT_TRUE(ref.result.status.ok) << ref.result.status.message;
  std::vector<double> err;
  for (double e : {7e9, 7e10, 7e11}) {
    const SimRun r = run_text(pendulum(e, 2, 0.3));
    ASSERT_TRUE(r.result.status.ok) << r.result.status.message << e;
    err.push_back(max_abs_diff((*r.rec)["bar.phi"], (*ref.rec)["bar.phi"]));
  }
  // The difference is the bar's bending under the inertia and gravity loads of the fall, ∝ 1/E:
  // it falls by about 10 per decade (2.6e-3 rad at 7e9 Pa).
  EXPECT_GT(err[0], 5 * err[1]);
  EXPECT_GT(err[1], 5 * err[2]);
  EXPECT_LT(err[2], 1e-4);
}

TEST(FlexibleLink, APinnedPinnedBarRingsAtItsFirstBendingFrequency) {
  // Pinned at both ends, no gravity; a 2 ms smooth pulse at mid-length (short against the first
  // mode's 43 ms, long against the third's 4.8 ms) starts it ringing with an amplitude of about
  // 0.1 mm (a hundredth of its height, so the stretching of its axis is negligible).
  // Euler–Bernoulli: ω₁ = π² √(EI/(ρA L⁴)).
  std::ostringstream s;
  s << "ground: {markers: {O: [0, 0], E: [1, 0]}}\nbodies:\n  bar:\n" << bar(kE, 4)
    << "joints:\n  a: {type: revolute, journal: bar.A, bearing: ground.O}\n"
       "  b: {type: revolute, journal: bar.B, bearing: ground.E}\n"
       "loads:\n  kick: {type: force, point: bar.M, fx: 0, "
       "fy: \"-4*(step5(time, 0, 0, 1e-3, 1) - step5(time, 1e-3, 0, 2e-3, 1))\"}\n"
       "solver: {rtol: 1.0e-9, atol: 1.0e-13, end_time: 0.2, output_interval: 5.0e-5}\n";
  const SimRun r = run_text(s.str());
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const auto& w = (*r.rec)["bar.deflection"];
  const auto& t = r.rec->time;
  double amplitude = 0.0;
  for (double x : w) amplitude = std::max(amplitude, std::abs(x));
  // Upward zero crossings, interpolated, each after the signal has been below −amplitude/2 (the
  // higher modes' ripple does not count).
  std::vector<double> up;
  bool armed = false;
  for (size_t i = 1; i < w.size(); ++i) {
    if (w[i] < -0.5 * amplitude) armed = true;
    if (armed && t[i] > 2e-3 && w[i - 1] < 0 && w[i] >= 0) {
      up.push_back(t[i - 1] + (t[i] - t[i - 1]) * (-w[i - 1]) / (w[i] - w[i - 1]));
      armed = false;
    }
  }
  ASSERT_GE(up.size(), 3u);
  const double period = (up.back() - up.front()) / (up.size() - 1);
  const double ei = kE * kB * kH * kH * kH / 12.0, rho_a = kRho * kB * kH;
  const double omega1 = M_PI * M_PI * std::sqrt(ei / (rho_a * std::pow(kL, 4)));
  EXPECT_NEAR(2 * M_PI / period / omega1, 1.0, 5e-3);
  EXPECT_GT(amplitude, 2e-5);
  EXPECT_LT(amplitude, 1e-3);
}

TEST(FlexibleLink, AStiffFlexibleRodDrivesTheSliderCrankLikeTheRigidRod) {
  std::string text = read_file(example_path("flores_slider_crank_ideal.yaml"));
  const std::string anchor = "    markers: {A: [-0.06, 0], B: [0.06, 0]}\n";
  const size_t at = text.find(anchor);
  ASSERT_NE(at, std::string::npos);
  const SimRun rigid = run_text(text);
  ASSERT_TRUE(rigid.result.status.ok) << rigid.result.status.message;
  // The rod as a steel bar 11.2 × 20 mm of the same mass (density from mass / (area × length)).
  auto flexible = [&](double youngs_modulus) {
    std::string t = text;
    t.insert(at + anchor.size(),
             "    flexible: {length: 0.12, elements: 4, section: {rectangle: [0.0112, 0.02]}, "
             "youngs_modulus: " + std::to_string(youngs_modulus) + "}\n");
    return run_text(t);
  };
  const SimRun soft = flexible(20.7e9), steel = flexible(207e9);
  ASSERT_TRUE(soft.result.status.ok) << soft.result.status.message;
  ASSERT_TRUE(steel.result.status.ok) << steel.result.status.message;
  // The slider follows the rigid motion but for the rod's axial strain, ∝ 1/E.
  const double dx_soft = max_abs_diff((*soft.rec)["slider.x"], (*rigid.rec)["slider.x"]);
  const double dx_steel = max_abs_diff((*steel.rec)["slider.x"], (*rigid.rec)["slider.x"]);
  EXPECT_GT(dx_soft, 5 * dx_steel);
  EXPECT_LT(dx_soft, 20 * dx_steel);
  // Bounded by the static shortening under the rigid run's largest rod force (at the crank),
  // F L/(EA), with a factor 3 for the dynamic overshoot of the undamped axial modes.
  double f_max = 0.0;
  for (double f : (*rigid.rec)["crank_rod.F"]) f_max = std::max(f_max, f);
  EXPECT_LT(dx_steel, 3 * f_max * 0.12 / (207e9 * 0.0112 * 0.02));
  EXPECT_GT(dx_steel, 0.1 * f_max * 0.12 / (207e9 * 0.0112 * 0.02));
  double stress = 0.0;
  for (double v : (*steel.rec)["rod.stress_max"]) stress = std::max(stress, v);
  EXPECT_GT(stress, 0.5 * f_max / (0.0112 * 0.02));  // at least the axial stress …
  EXPECT_LT(stress, 5e8);                             // … within steel's range
}

TEST(FlexibleLink, TheModelFileNamesWhatAFlexibleLinkCannotTake) {
  static const std::string kSolver = "solver: {end_time: 0.1}\n";
  auto problems = [](const std::string& yaml) {
    try {
      load_model_text(yaml + kSolver, "flex.yaml");
    } catch (const ModelError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string head = "ground: {markers: {O: [0, 0]}}\nbodies:\n  bar:\n";
  // A marker off the axis.
  EXPECT_NE(problems(head + "    markers: {P: [0, 0.01]}\n    flexible: {length: 1, section: "
                            "{circle: 0.01}, youngs_modulus: 1e9, density: 1000}\n")
                .find("off the link's axis"),
            std::string::npos);
  // A fixed joint.
  EXPECT_NE(problems(head + bar(1e9, 2) +
                     "joints:\n  j: {type: fixed, base: ground.O, attached: bar.A}\n")
                .find("fixed joint needs the axes of a rigid body"),
            std::string::npos);
  // A torque.
  EXPECT_NE(problems(head + bar(1e9, 2) + "loads:\n  t: {type: torque, body: bar, torque: 1}\n")
                .find("torque load needs a rigid body"),
            std::string::npos);
  // Mass and density that disagree.
  EXPECT_NE(problems(head + "    mass: 1.0\n" + bar(1e9, 2)).find("differs from density"),
            std::string::npos);
  // No section.
  EXPECT_NE(problems(head + "    flexible: {length: 1, youngs_modulus: 1e9, density: 1000}\n")
                .find("missing required key 'section'"),
            std::string::npos);
  // A good one loads, with its mass from the density.
  const Model m = load_model_text(head + bar(1e9, 2) + kSolver, "flex.yaml").model;
  EXPECT_NEAR(m.bodies[0].mass, kRho * kB * kH * kL, 1e-12);
}

}  // namespace
}  // namespace lash::test
