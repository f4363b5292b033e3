// Flexible links in the engine (core/elements/flexible_link.cpp): a planar ANCF beam coupled by
// joints with rigid bodies. The beam's own mathematics is tested in test_beam.cpp; here: energy
// balance, the rigid limit, a bending frequency of a pinned beam in a model, the flexible-rod
// slider-crank against the rigid one, and the model file's checks.
#include <algorithm>
#include <cmath>
#include <cstdlib>

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

/// Mean period of a ringing signal w(t) after t_min from its upward zero crossings, interpolated,
/// each counted only after the signal has been below −amplitude/2 (the higher modes' ripple does
/// not count); 0 with fewer than three crossings.
double ringing_period(const std::vector<double>& t, const std::vector<double>& w, double t_min) {
  double amplitude = 0.0;
  for (double x : w) amplitude = std::max(amplitude, std::abs(x));
  std::vector<double> up;
  bool armed = false;
  for (size_t i = 1; i < w.size(); ++i) {
    if (w[i] < -0.5 * amplitude) armed = true;
    if (armed && t[i] > t_min && w[i - 1] < 0 && w[i] >= 0) {
      up.push_back(t[i - 1] + (t[i] - t[i - 1]) * (-w[i - 1]) / (w[i] - w[i - 1]));
      armed = false;
    }
  }
  return up.size() < 3 ? 0.0 : (up.back() - up.front()) / (up.size() - 1);
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
      "solver: {rtol: 1.0e-10, atol: 1.0e-12, end_time: 0.2, output_interval: 0.01}\n";
  const SimRun ref = run_text(rigid);
  ASSERT_TRUE(ref.result.status.ok) << ref.result.status.message;
  std::vector<double> err;
  for (double e : {7e9, 7e10, 7e11}) {
    const SimRun r = run_text(pendulum(e, 2, 0.2));
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
  // Euler–Bernoulli: ω₁ = π² √(EI/(ρA L⁴)); two elements hold it within 1e-3.
  std::ostringstream s;
  s << "ground: {markers: {O: [0, 0], E: [1, 0]}}\nbodies:\n  bar:\n" << bar(kE, 2)
    << "joints:\n  a: {type: revolute, journal: bar.A, bearing: ground.O}\n"
       "  b: {type: revolute, journal: bar.B, bearing: ground.E}\n"
       "loads:\n  kick: {type: force, point: bar.M, fx: 0, "
       "fy: \"-4*(step5(time, 0, 0, 1e-3, 1) - step5(time, 1e-3, 0, 2e-3, 1))\"}\n"
       "solver: {rtol: 1.0e-8, atol: 1.0e-12, end_time: 0.2, output_interval: 5.0e-5}\n";
  const SimRun r = run_text(s.str());
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const auto& w = (*r.rec)["bar.deflection"];
  double amplitude = 0.0;
  for (double x : w) amplitude = std::max(amplitude, std::abs(x));
  const double period = ringing_period(r.rec->time, w, 2e-3);
  ASSERT_GT(period, 0.0);
  const double ei = kE * kB * kH * kH * kH / 12.0, rho_a = kRho * kB * kH;
  const double omega1 = M_PI * M_PI * std::sqrt(ei / (rho_a * std::pow(kL, 4)));
  EXPECT_NEAR(2 * M_PI / period / omega1, 1.0, 5e-3);
  EXPECT_GT(amplitude, 2e-5);
  EXPECT_LT(amplitude, 1e-3);
}

TEST(FlexibleLink, AClampedBarRingsAtItsFirstCantileverFrequency) {
  // Clamped to the ground at end A by a fixed joint (position and the slope's direction), pulled
  // down at the tip over 60 ms and let go over 30 ms: ω₁ = 1.8751² √(EI/(ρA L⁴)) = 51.7 rad/s
  // (period 122 ms). The smooth ramps, long against the second mode's 19 ms, leave it nearly
  // still (a 10 ms kick rang it at a sixth of the first mode's amplitude and moved the zero
  // crossings by 1.4 %). Two elements hold ω₁ within 1e-3 (`lash modes`).
  std::ostringstream s;
  s << "ground: {markers: {O: [0, 0]}}\nbodies:\n  bar:\n" << bar(kE, 2)
    << "joints:\n  clamp: {type: fixed, base: ground.O, attached: bar.A}\n"
       "loads:\n  kick: {type: force, point: bar.B, fx: 0, "
       "fy: \"-1*(step5(time, 0, 0, 0.06, 1) - step5(time, 0.06, 0, 0.09, 1))\"}\n"
       "sensors:\n  tip: {type: displacement, at: bar.B, axis: [0, 1], frame: ground}\n"
       "solver: {rtol: 1.0e-8, atol: 1.0e-12, end_time: 0.6, output_interval: 2.0e-4}\n";
  const SimRun r = run_text(s.str());
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const double period = ringing_period(r.rec->time, (*r.rec)["tip.x"], 0.1);
  ASSERT_GT(period, 0.0);
  const double ei = kE * kB * kH * kH * kH / 12.0, rho_a = kRho * kB * kH;
  const double omega1 = 1.8751 * 1.8751 * std::sqrt(ei / (rho_a * std::pow(kL, 4)));
  EXPECT_NEAR(2 * M_PI / period / omega1, 1.0, 2e-3);
  // The clamp holds: the root stays at the origin (its reaction balances the pulse).
  EXPECT_LT(r.result.max_constraint_violation, 1e-9);
}

TEST(FlexibleLink, ASpunUpBeamStaysBoundedAndStretchesAsTheClosedFormSays) {
  // examples/spin_up_beam.yaml (Simo and Vu-Quoc 1986), 2 elements to keep the test short.
  const SimRun r = run_example("spin_up_beam.yaml",
                               {"bodies.beam.flexible.elements=2", "solver.rtol=1e-7",
                                "solver.atol=1e-9", "solver.end_time=18"});
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const auto& t = r.rec->time;
  const auto& phi = (*r.rec)["hub.phi"];
  const auto& x = (*r.rec)["tip_x.x"];
  const auto& y = (*r.rec)["tip_y.x"];
  double lag = 0.0, after = 0.0, stretch = 0.0;
  int n_after = 0;
  for (size_t i = 0; i < t.size(); ++i) {
    // The tip in the hub's axes: along the beam (minus its length) and across it.
    const double c = std::cos(phi[i]), s = std::sin(phi[i]);
    const double along = x[i] * c + y[i] * s - 10.0, across = -x[i] * s + y[i] * c;
    if (t[i] <= 15.0) lag = std::max(lag, -across);
    if (t[i] > 16.0) {
      after = std::max(after, std::abs(across));
      stretch += along;
      ++n_after;
    }
  }
  // The published trend: the tip lags by a fraction of the length during the spin-up (0.55 m
  // here, 0.57 m with 4 elements) and swings back to near zero once the speed is constant,
  // although ω_s = 6 rad/s is above the first bending frequency (3.80 rad/s).
  EXPECT_GT(lag, 0.2);
  EXPECT_LT(lag, 1.0);
  EXPECT_LT(after, 0.02 * lag);
  // Centrifugal stretch ρA ω² L³/(3 EA) = 1.2·36·1000/(3·2.8e7) m (the cubic elements hold the
  // cubic axial displacement of a uniform rotating bar exactly).
  EXPECT_NEAR(stretch / n_after, 1.2 * 36 * 1000 / (3 * 2.8e7), 2e-3 * 5.143e-4);
}

TEST(FlexibleLink, ADriverOfTheLinksOwnPinSpinsItUpAsAClampedHubDoes) {
  // examples/spin_up_beam.yaml drives a rigid hub to which the beam is clamped. The same motion
  // prescribed to the beam's own pin (the driver holds the beam's axis at A at the hub's angle)
  // is the same mechanism: the tips agree to the integration tolerance.
  const std::vector<std::string> o = {"bodies.beam.flexible.elements=2", "solver.rtol=1e-9",
                                      "solver.atol=1e-11", "solver.end_time=6"};
  const SimRun hub = run_example("spin_up_beam.yaml", o);
  ASSERT_TRUE(hub.result.status.ok) << hub.result.status.message;
  std::string text = read_file(example_path("spin_up_beam.yaml"));
  auto replace = [&](const std::string& from, const std::string& to) {
    const size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  };
  replace("  hub: {mass: 1.0, inertia: 1.0, position: [0, 0], markers: {O: [0, 0]}}\n", "");
  replace("hub_pin: {type: revolute, journal: hub.O, bearing: ground.O}",
          "hub_pin: {type: revolute, journal: beam.A, bearing: ground.O}");
  replace("  root: {type: fixed, base: hub.O, attached: beam.A}   # the clamped end\n", "");
  const SimRun own = run_text(text, o);
  ASSERT_TRUE(own.result.status.ok) << own.result.status.message;
  for (const char* c : {"tip_x.x", "tip_y.x"}) {
    SCOPED_TRACE(c);
    ASSERT_EQ((*own.rec)[c].size(), (*hub.rec)[c].size());
    EXPECT_LT(max_abs_diff((*own.rec)[c], (*hub.rec)[c]), 1e-5);
  }
  // The tip did lag behind the hub (the spin-up bends the beam).
  EXPECT_GT(max_abs_diff((*own.rec)["spin.torque"], std::vector<double>((*own.rec)["spin.torque"].size(), 0.0)), 1.0);
}

TEST(FlexibleLink, AStiffFlexibleRodDrivesTheSliderCrankLikeTheRigidRod) {
  std::string text = read_file(example_path("flores_slider_crank_ideal.yaml"));
  const std::string anchor = "    markers: {A: [-0.06, 0], B: [0.06, 0]}\n";
  const size_t at = text.find(anchor);
  ASSERT_NE(at, std::string::npos);
  const std::vector<std::string> one_revolution{"solver.end_time=0.012"};
  const SimRun rigid = run_text(text, one_revolution);
  ASSERT_TRUE(rigid.result.status.ok) << rigid.result.status.message;
  // The rod as a steel bar 11.2 × 20 mm of the same mass (density from mass / (area × length)).
  auto flexible = [&](double youngs_modulus) {
    std::string t = text;
    t.insert(at + anchor.size(),
             "    flexible: {length: 0.12, elements: 4, section: {rectangle: [0.0112, 0.02]}, "
             "youngs_modulus: " + std::to_string(youngs_modulus) + "}\n");
    return run_text(t, one_revolution);
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

/// Every row of `m` at a perturbed, moving state: Φ̇ = Φ_q q̇, Φ_q q̇ is the derivative of Φ
/// along q̇, and γ is minus the derivative of Φ_q q̇ along q̇ (q̈ = 0), each against central
/// differences. Drivers' rows are skipped unless their motion is constant (they depend on time).
void expect_rows_agree_with_differences(const Model& m, bool drivers_constant) {
  Workspace ws(m);
  Eigen::VectorXd y = initial_state(m, ws);
  std::srand(7);
  const Eigen::VectorXd dq = 1e-3 * Eigen::VectorXd::Random(ws.nq);
  y.head(ws.nq) += dq;
  y.segment(ws.nq, ws.nq) += Eigen::VectorXd::Random(ws.nq);
  std::vector<double> ydot(ws.ny);
  auto rows = [&](const Eigen::VectorXd& at, Eigen::VectorXd& phi, Eigen::VectorXd& rate,
                  Eigen::VectorXd& phi_dot, Eigen::VectorXd& gamma) {
    ASSERT_TRUE(evaluate(m, ws, 0.0, at.data(), ydot.data()));
    phi = ws.phi;
    rate = ws.phi_q * at.segment(ws.nq, ws.nq);
    phi_dot = ws.phi_dot;
    gamma = ws.gamma;
  };
  Eigen::VectorXd phi, rate, phi_dot, gamma, p1, r1, d1, g1, p2, r2, d2, g2;
  rows(y, phi, rate, phi_dot, gamma);
  const double h = 1e-6;
  Eigen::VectorXd y1 = y, y2 = y;
  y1.head(ws.nq) += h * y.segment(ws.nq, ws.nq);
  y2.head(ws.nq) -= h * y.segment(ws.nq, ws.nq);
  rows(y1, p1, r1, d1, g1);
  rows(y2, p2, r2, d2, g2);
  const Eigen::VectorXd dphi = (p1 - p2) / (2 * h), drate = (r1 - r2) / (2 * h);
  int checked = 0;
  for (int i = 0; i < ws.m; ++i) {
    if (!drivers_constant &&
        std::find(ws.row_of_driver.begin(), ws.row_of_driver.end(), i) != ws.row_of_driver.end())
      continue;  // the driver's row depends on time
    const double scale = 1.0 + std::abs(rate[i]), scale2 = 1.0 + std::abs(gamma[i]);
    EXPECT_NEAR(phi_dot[i], rate[i], 1e-9 * scale) << "row " << i;
    EXPECT_NEAR(dphi[i], rate[i], 1e-5 * scale) << "row " << i;
    EXPECT_NEAR(-drate[i], gamma[i], 1e-4 * scale2) << "row " << i;
    ++checked;
  }
  EXPECT_GT(checked, 0);
}

TEST(FlexibleLink, ConstraintRowsOnALinkAgreeWithFiniteDifferences) {
  // Links clamped (fixed joints) and pinned (revolute joints).
  expect_rows_agree_with_differences(load_model_file(example_path("erkaya_compliant_beam.yaml")).model,
                                     false);
  // A driver of the link's own pin (its axis at the pin held at a constant angle here, so the
  // row does not depend on time): the angle row through the link's slope.
  std::string text = read_file(example_path("spin_up_beam.yaml"));
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"  hub: {mass: 1.0, inertia: 1.0, position: [0, 0], markers: {O: [0, 0]}}\n", ""},
           {"journal: hub.O", "journal: beam.A"},
           {"  root: {type: fixed, base: hub.O, attached: beam.A}   # the clamped end\n", ""}}) {
    const size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  }
  const size_t speed = text.find("    speed: ");
  ASSERT_NE(speed, std::string::npos);
  text.replace(speed, text.find('\n', speed) - speed, "    motion: \"0\"");
  expect_rows_agree_with_differences(load_model_text(text, "own_pin.yaml").model, true);
  // A link sliding on a guide that turns (its angle row and its dot row through the link's nodes).
  expect_rows_agree_with_differences(
      load_model_text("ground: {markers: {O: [0, 0]}}\nbodies:\n"
                      "  arm: {mass: 1, inertia: 0.1, position: [0, 0], markers: {O: [0, 0]}}\n"
                      "  bar:\n" + bar(kE, 2) +
                      "joints:\n  pivot: {type: revolute, journal: arm.O, bearing: ground.O}\n"
                      "  slide: {type: translational, guide: arm.O, slider: bar.M, axis: [1, 0]}\n"
                      "solver: {end_time: 0.1}\n", "slide.yaml").model,
      false);
  // Two links welded into an L (fixed joint, 90° between their axes), pinned to the ground.
  expect_rows_agree_with_differences(
      load_model_text("ground: {markers: {O: [0, 0]}}\nbodies:\n  bar:\n" + bar(kE, 2) +
                      "  post:\n    position: [1, 0.25]\n    angle_deg: 90\n"
                      "    markers: {A: [-0.25, 0], B: [0.25, 0]}\n"
                      "    flexible: {length: 0.5, elements: 1, section: {rectangle: [0.02, 0.01]}, "
                      "youngs_modulus: 7e10, density: 2700}\n"
                      "joints:\n  pin: {type: revolute, journal: bar.A, bearing: ground.O}\n"
                      "  corner: {type: fixed, base: bar.B, attached: post.A}\n"
                      "solver: {end_time: 0.1}\n", "ell.yaml").model,
      false);
}

TEST(FlexibleLink, ABushingInTheLinksAxesKeepsTheEnergyBalance) {
  // A 50 g absorber on a bushing at the bar's free end, in the bar's axes there (k_x ≠ k_y, so
  // the axes matter), the bar pinned at A and swinging, no gravity, no damping: the springs
  // turn with the bending link, and only with the torque of their turning on the link's axis
  // (−Σ k_i d_i perp(u_i)·d) is the energy kept. With damping the balance holds too, and energy
  // is dissipated.
  auto model = [](double damping) {
    std::ostringstream s;
    s << "ground: {markers: {O: [0, 0]}}\nbodies:\n  bar:\n" << bar(7e9, 2)
      << "    angular_velocity: 2.0\n"
         "  absorber: {mass: 0.05, position: [1.0, 0], velocity: [0.3, 2.5]}\n"
         "joints:\n  pin: {type: revolute, journal: bar.A, bearing: ground.O}\n"
         "loads:\n  mount: {type: bushing, from: bar.B, to: absorber, frame: bar, "
         "stiffness: [4000, 1500], damping: [" << damping << ", " << damping << "]}\n"
         "solver: {rtol: 1.0e-10, atol: 1.0e-13, end_time: 0.3, output_interval: 0.005, "
         "initial_state: given}\n";
    return s.str();
  };
  for (double c : {0.0, 0.5}) {
    SCOPED_TRACE(c);
    const SimRun r = run_text(model(c));
    ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
    const auto& bal = (*r.rec)["energy.balance"];
    const double scale = (*r.rec)["energy.kinetic"].front();
    EXPECT_LT(max_abs_diff(bal, std::vector<double>(bal.size(), bal.front())), 1e-7 * scale);
    // The absorber did move in the bar's axes, both ways.
    double dx = 0, dy = 0;
    for (double v : (*r.rec)["mount.dx"]) dx = std::max(dx, std::abs(v));
    for (double v : (*r.rec)["mount.dy"]) dy = std::max(dy, std::abs(v));
    EXPECT_GT(dx, 1e-4);
    EXPECT_GT(dy, 1e-4);
    if (c > 0) {
      EXPECT_GT((*r.rec)["energy.dissipated"].back(), 1e-3 * scale);
    }
  }
}

TEST(FlexibleLink, TwoWeldedHalvesBendAsOneCantilever) {
  // Two 0.5 m halves of the bar welded end to end (a fixed joint between two links), clamped to
  // the ground at A, a transverse tip force F = 1 N raised over 0.3 s, Kelvin–Voigt damping (BDF):
  // the tip settles at FL³/(3EI), as one 1 m cantilever's.
  const double force = 1.0, ei = kE * kB * kH * kH * kH / 12.0;
  auto half = [](const char* name, double x) {
    std::ostringstream s;
    s << "  " << name << ":\n    position: [" << x << ", 0]\n    markers: {A: [-0.25, 0], B: [0.25, 0]}\n"
      << "    flexible: {length: 0.5, elements: 1, section: {rectangle: [0.02, 0.01]}, "
         "youngs_modulus: " << kE << ", density: 2700, damping: 0.01}\n";
    return s.str();
  };
  std::ostringstream s;
  s << "ground: {markers: {O: [0, 0]}}\nbodies:\n" << half("inner", 0.25) << half("outer", 0.75)
    << "joints:\n  clamp: {type: fixed, base: ground.O, attached: inner.A}\n"
       "  weld: {type: fixed, base: inner.B, attached: outer.A}\n"
       "loads:\n  push: {type: force, point: outer.B, fy: \"step5(time, 0, 0, 0.3, " << force << ")\"}\n"
       "sensors:\n  tip: {type: displacement, at: outer.B, axis: [0, 1], frame: ground}\n"
       "solver: {integrator: bdf, rtol: 1.0e-8, atol: 1.0e-11, end_time: 1.0, output_interval: 0.01}\n";
  const SimRun r = run_text(s.str());
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const double tip = force * kL * kL * kL / (3 * ei);
  EXPECT_NEAR((*r.rec)["tip.x"].back(), tip, 5e-3 * tip);
  // Two links welded at 90° (an L, clamped at its foot, no load) keep their angle: at rest and
  // unstrained, as built.
  const SimRun ell = run_text(
      "ground: {markers: {O: [0, 0]}}\nbodies:\n  bar:\n" + bar(kE, 2) +
      "  post:\n    position: [1, 0.25]\n    angle_deg: 90\n"
      "    markers: {A: [-0.25, 0], B: [0.25, 0]}\n"
      "    flexible: {length: 0.5, elements: 1, section: {rectangle: [0.02, 0.01]}, "
      "youngs_modulus: 7e10, density: 2700}\n"
      "joints:\n  foot: {type: fixed, base: ground.O, attached: bar.A}\n"
      "  corner: {type: fixed, base: bar.B, attached: post.A}\n"
      "solver: {end_time: 0.01, output_interval: 0.005}\n");
  ASSERT_TRUE(ell.result.status.ok) << ell.result.status.message;
  for (const char* c : {"bar.strain_energy", "post.strain_energy"})
    EXPECT_LT(max_abs_diff((*ell.rec)[c], std::vector<double>((*ell.rec)[c].size(), 0.0)), 1e-12) << c;
  EXPECT_NEAR((*ell.rec)["post.phi"].back(), M_PI / 2, 1e-9);
}

TEST(FlexibleLink, ALinkSlidingOnAGuideOscillatesOnItsSpringAsARigidOne) {
  // The bar as the slider of a translational joint along the ground's x axis (its axis at the
  // middle kept parallel to it), pulled back by a spring of 800 N/m from 10 mm out: it moves as
  // a whole, x = x0 + 0.01 cos ωt with ω = √(k/m) (the bar's axial modes, kHz, do not enter);
  // its transverse position stays 0.
  const double k = 800.0, mass = kRho * kB * kH * kL;
  std::ostringstream s;
  s << "ground: {markers: {O: [0, 0]}}\nbodies:\n  bar:\n" << bar(kE, 2)
    << "joints:\n  slide: {type: translational, guide: ground.O, slider: bar.M, axis: [1, 0]}\n"
       "loads:\n  spring: {type: spring_damper, from: ground.O, to: bar.M, stiffness: "
    << k << ", free_length: 0.49}\n"
       "solver: {rtol: 1.0e-9, atol: 1.0e-12, end_time: 0.2, output_interval: 0.005, "
       "initial_state: given}\n";
  const SimRun r = run_text(s.str());
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const double omega = std::sqrt(k / mass);
  const auto& t = r.rec->time;
  const auto& x = (*r.rec)["bar.x"];
  double worst = 0.0;
  for (size_t i = 0; i < t.size(); ++i)
    worst = std::max(worst, std::abs(x[i] - (0.49 + 0.01 * std::cos(omega * t[i]))));
  EXPECT_LT(worst, 1e-5);
  EXPECT_LT(max_abs_diff((*r.rec)["bar.y"], std::vector<double>(t.size(), 0.0)), 1e-9);
  EXPECT_LT(max_abs_diff((*r.rec)["bar.phi"], std::vector<double>(t.size(), 0.0)), 1e-9);
}

TEST(FlexibleLink, ATorsionalSpringAtItsPinHoldsATipLoadAsTheClosedFormSays) {
  // The bar pinned at end A to the ground, no gravity, a torsional spring-damper between the
  // ground and the bar's axis at A (k = 100 N·m/rad, c near critical for the swing), a transverse
  // force F = 1 N at its end B raised smoothly over 0.3 s, Kelvin–Voigt damping (BDF). Static
  // equilibrium: the spring turns the axis at A by θ_A = FL/k and the bar bends as a cantilever
  // from there, so the tip sits at L θ_A + FL³/(3EI) and the spring's torque is FL.
  const double k = 100.0, force = 1.0, ei = kE * kB * kH * kH * kH / 12.0;
  std::ostringstream s;
  s << "ground: {markers: {O: [0, 0]}}\nbodies:\n  bar:\n" << bar(kE, 2, "      damping: 0.01\n")
    << "joints:\n  pin: {type: revolute, journal: bar.A, bearing: ground.O}\n"
       "loads:\n  spring: {type: torsional_spring_damper, bodies: [ground, bar.A], stiffness: "
    << k << ", damping: 8.5}\n"
       "  push: {type: force, point: bar.B, fy: \"step5(time, 0, 0, 0.3, " << force << ")\"}\n"
       "sensors:\n  tip: {type: displacement, at: bar.B, axis: [0, 1], frame: ground}\n"
       "solver: {integrator: bdf, rtol: 1.0e-8, atol: 1.0e-11, end_time: 1.0, output_interval: 0.01}\n";
  const SimRun r = run_text(s.str());
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const double tip = kL * force * kL / k + force * kL * kL * kL / (3 * ei);
  EXPECT_NEAR((*r.rec)["tip.x"].back(), tip, 5e-3 * tip);
  EXPECT_NEAR((*r.rec)["spring.torque"].back(), force * kL, 5e-3 * force * kL);
  // Energy: what the force put in is stored in the spring and the bar or dissipated.
  const auto& bal = (*r.rec)["energy.balance"];
  EXPECT_LT(max_abs_diff(bal, std::vector<double>(bal.size(), bal.front())),
            1e-6 * force * tip);
}

TEST(FlexibleLink, ATipTorqueBendsAClampedLinkIntoTheClosedFormArc) {
  // The bar clamped at A to the ground (E = 70 GPa, EI = 116.7 N·m²), a torque M at its end B
  // raised smoothly over 0.3 s, Kelvin–Voigt damping to let it settle (BDF). Pure bending: a
  // circular arc of radius ρ = EI/M, so the tip turns by θ = ML/EI = 0.05 rad and sits at
  // (ρ sin θ, ρ(1 − cos θ)) from A. Sensors read the tip along the ground's y and along the
  // link's own transverse axis there, which turns with it: −x_B sin θ + y_B cos θ.
  const double ei = kE * kB * kH * kH * kH / 12.0, theta = 0.05, moment = theta * ei / kL;
  const double rho = ei / moment;
  std::ostringstream s;
  s << "ground: {markers: {O: [0, 0]}}\nbodies:\n  bar:\n" << bar(kE, 4, "      damping: 0.01\n")
    << "joints:\n  clamp: {type: fixed, base: ground.O, attached: bar.A}\n"
       "loads:\n  tip: {type: torque, body: bar.B, torque: \"step5(time, 0, 0, 0.3, " << moment
    << ")\"}\n"
       "sensors:\n"
       "  tip_y: {type: displacement, at: bar.B, axis: [0, 1], frame: ground}\n"
       "  tip_n: {type: displacement, at: bar.B, axis: [0, 1]}\n"
       "solver: {integrator: bdf, rtol: 1.0e-8, atol: 1.0e-11, end_time: 1.5, output_interval: 0.01}\n";
  const SimRun r = run_text(s.str());
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const double x = rho * std::sin(theta), y = rho * (1 - std::cos(theta));
  EXPECT_NEAR((*r.rec)["tip_y.x"].back(), y, 5e-3 * y);
  EXPECT_NEAR((*r.rec)["tip_n.x"].back(), -x * std::sin(theta) + y * std::cos(theta), 5e-3 * y);
  // The torque's work is stored as strain energy, M²L/(2EI), once it has settled.
  EXPECT_NEAR((*r.rec)["bar.strain_energy"].back(), moment * moment * kL / (2 * ei),
              1e-2 * moment * moment * kL / (2 * ei));
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
  // A link as a translational joint's guide.
  EXPECT_NE(problems("ground: {markers: {O: [0, 0]}}\nbodies:\n  block: {mass: 1, inertia: 1}\n"
                     "  bar:\n" + bar(1e9, 2) +
                     "joints:\n  j: {type: translational, guide: bar.A, slider: block}\n")
                .find("cannot be a translational joint's guide"),
            std::string::npos);
  // A torque, or a torsional spring, on the link without the point it acts at.
  EXPECT_NE(problems(head + bar(1e9, 2) + "loads:\n  t: {type: torque, body: bar, torque: 1}\n")
                .find("name the point it acts at, as bar.MARKER"),
            std::string::npos);
  EXPECT_NE(problems(head + bar(1e9, 2) +
                     "loads:\n  t: {type: torsional_spring_damper, bodies: [ground, bar], stiffness: 1}\n")
                .find("name the point it acts at"),
            std::string::npos);
  // A fixed joint from a link to a point mass.
  EXPECT_NE(problems("ground: {markers: {O: [0, 0]}}\nbodies:\n  dot: {mass: 1, position: [0, 0]}\n"
                     "  bar:\n" + bar(1e9, 2) +
                     "joints:\n  j: {type: fixed, base: dot, attached: bar.A}\n")
                .find("not to a point mass"),
            std::string::npos);
  // Mass and density that disagree.
  EXPECT_NE(problems(head + "    mass: 1.0\n" + bar(1e9, 2)).find("differs from density"),
            std::string::npos);
  // A marker off a 1 nm link's axis: the limit in significant digits (it read 0.000000 m).
  const std::string tiny =
      problems(head + "    markers: {P: [0.5, 0]}\n    flexible: {length: 1.0e-9, section: "
                      "{circle: 0.01}, youngs_modulus: 1e9, density: 1000}\n");
  EXPECT_NE(tiny.find("marker 'P' at [0.5, 0] is off the link's axis"), std::string::npos) << tiny;
  EXPECT_NE(tiny.find("|x| <= length/2 = 5e-10 m"), std::string::npos) << tiny;
  // No section.
  EXPECT_NE(problems(head + "    flexible: {length: 1, youngs_modulus: 1e9, density: 1000}\n")
                .find("missing required key 'section'"),
            std::string::npos);
  // A section whose area overflows: one problem with the values, not "give the density or the
  // mass" beside a mass that is given.
  const std::string huge = problems(head + "    mass: 1.0\n    flexible: {length: 1, section: {circle: 1e200}, "
                                           "youngs_modulus: 1e9}\n");
  EXPECT_NE(huge.find("must be finite and > 0, got A = inf m²"), std::string::npos) << huge;
  EXPECT_EQ(huge.find("give the density or the mass"), std::string::npos) << huge;
  // A good one loads, with its mass from the density.
  const Model m = load_model_text(head + bar(1e9, 2) + kSolver, "flex.yaml").model;
  EXPECT_NEAR(m.bodies[0].mass, kRho * kB * kH * kL, 1e-12);
}

}  // namespace
}  // namespace lash::test
