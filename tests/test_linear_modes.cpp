// The mechanism linearised at its initial configuration (study/linear_modes.hpp) against closed
// forms and the flexible link's own finite-element modes.
#include <cmath>

#include "core/beam.hpp"
#include "study/linear_modes.hpp"
#include "test_support.hpp"

namespace lash::test {
namespace {

// A 1 m steel strip 20 mm wide and `height` thick in the plane, clamped at its end A to the
// ground, in 8 elements: Kelvin–Voigt damping `damping` (s), under gravity or not.
Model clamped_strip(double height, double damping, bool gravity) {
  char yaml[600];
  std::snprintf(yaml, sizeof yaml, R"Y(
gravity: [0, %g]
ground: {markers: {A: [0, 0]}}
bodies:
  strip:
    position: [0.5, 0]
    markers: {A: [-0.5, 0], B: [0.5, 0]}
    flexible: {length: 1.0, elements: 8, section: {rectangle: [0.02, %.17g]}, youngs_modulus: 207e9, density: 7800, damping: %.17g}
joints:
  clamp: {type: fixed, base: ground.A, attached: strip.A}
solver: {end_time: 1.0}
)Y", gravity ? -9.81 : 0.0, height, damping);
  return load_model_text(yaml, "strip.yaml").model;
}

TEST(LinearModes, APendulumHangingFromItsPinSwingsAtItsClosedForm) {
  // A 1 m bar of 0.54 kg (I = 0.045 kg·m² about its centre) hanging from a pin at one end:
  // ω² = m g (L/2) / (I + m (L/2)²); one degree of freedom, one undamped mode.
  const Model m = load_model_text(R"Y(
gravity: [0, -9.81]
ground: {markers: {O: [0, 0]}}
bodies:
  bar: {mass: 0.54, inertia: 0.045, position: [0, -0.5], angle_deg: -90, markers: {A: [-0.5, 0]}}
joints:
  pin: {type: revolute, journal: bar.A, bearing: ground.O}
solver: {end_time: 1}
)Y", "pendulum.yaml").model;
  const LinearModes lm = linear_modes(m);
  ASSERT_EQ(lm.dof, 1);
  ASSERT_EQ(lm.modes.size(), 1u);
  const double omega = std::sqrt(0.54 * 9.81 * 0.5 / (0.045 + 0.54 * 0.25));
  EXPECT_NEAR(lm.modes[0].frequency, omega / (2 * M_PI), 1e-6 * omega);
  EXPECT_NEAR(lm.modes[0].damping_ratio, 0.0, 1e-6);
  EXPECT_FALSE(std::signbit(lm.modes[0].damping_ratio));  // `lash modes` printed "-0"
}

TEST(LinearModes, ASpringDamperOnAGuideHasItsFrequencyAndDampingRatio) {
  // 2 kg on a guide, k = 800 N/m, c = 8 N·s/m: ω_n = 20 rad/s, ζ = c / (2√(km)) = 0.1.
  const Model m = load_model_text(R"Y(
ground: {markers: {A: [0, 0]}}
bodies:
  block: {mass: 2.0, inertia: 0.01, position: [0.1, 0]}
joints:
  guide: {type: translational, guide: ground.A, slider: block, axis: [1, 0]}
loads:
  spring: {type: spring_damper, from: ground.A, to: block, stiffness: 800, damping: 8}
solver: {end_time: 1}
)Y", "spring.yaml").model;
  const LinearModes lm = linear_modes(m);
  ASSERT_EQ(lm.dof, 1);
  ASSERT_EQ(lm.modes.size(), 1u);
  EXPECT_NEAR(lm.modes[0].frequency, 20.0 / (2 * M_PI), 1e-6);
  EXPECT_NEAR(lm.modes[0].damping_ratio, 0.1, 1e-6);
}

TEST(LinearModes, OverdampedRootsOfADampedLinkAreRealNotModes) {
  // A steel cantilever (1 m, 20 × 20 mm, 8 elements) with Kelvin–Voigt damping η: each mode's
  // roots solve s² + ηω_i²s + ω_i² = 0, so ζ_i = ηω_i/2, and every overdamped mode has a slow
  // root near −1/η. Those clustered roots came out as seven "modes" at 1/(2πη) = 15.9 Hz with
  // ζ = 1, listed before the first bending mode (16.64 Hz, ζ = 0.523).
  const Model m = clamped_strip(0.02, 0.01, false);
  const LinearModes lm = linear_modes(m);
  ASSERT_FALSE(lm.modes.empty());
  // Euler–Bernoulli: ω₁ = 1.8751²·√(EI/(ρA L⁴)), EI = 207e9·0.02⁴/12, ρA = 7800·4e-4.
  const double w1 = 1.8751040687 * 1.8751040687 * std::sqrt(207e9 * 0.02 * 0.02 * 0.02 * 0.02 / 12 / (7800 * 4e-4));
  EXPECT_NEAR(lm.modes[0].frequency, w1 / (2 * M_PI), 1e-3 * w1 / (2 * M_PI));
  EXPECT_NEAR(lm.modes[0].damping_ratio, 0.01 * lm.modes[0].frequency * 2 * M_PI / 2, 1e-3);
  for (const LinearMode& mode : lm.modes) EXPECT_LT(mode.damping_ratio, 1.0 - kCriticalShare);
  // The slow roots are real, near −1/η = −100 1/s.
  int near_slow = 0;
  for (double r : lm.real_rates) near_slow += std::abs(r + 100.0) < 10.0;
  EXPECT_GE(near_slow, 5);
}

TEST(LinearModes, AClampedLinkInTheMechanismHasItsOwnCantileverModes) {
  // examples/spin_up_beam.yaml at rest: the beam clamped to a hub that the driver holds is a
  // cantilever; the mechanism's modes are the mesh's clamped–free ones (beam::modes), computed
  // independently, and the first two are within 1 % of Euler–Bernoulli's 1.8751² and 4.6941²
  // × √(EI/ρAL⁴).
  const Model m = load_model_file(example_path("spin_up_beam.yaml")).model;
  const LinearModes lm = linear_modes(m);
  const Body* beam = nullptr;
  for (const Body& b : m.bodies)
    if (b.flexible()) beam = &b;
  ASSERT_NE(beam, nullptr);
  const std::vector<beam::Mode> own = beam::modes(beam->mesh, beam::Support::clamped);
  ASSERT_EQ(lm.dof, static_cast<int>(own.size()));
  ASSERT_EQ(lm.modes.size(), own.size());
  for (size_t k = 0; k < own.size(); ++k)
    EXPECT_NEAR(lm.modes[k].frequency, own[k].omega / (2 * M_PI), 1e-5 * lm.modes[k].frequency)
        << "mode " << k + 1;
  const beam::Section& s = beam->mesh.section;
  const double scale = std::sqrt(s.youngs_modulus * s.inertia /
                                 (s.density * s.area * std::pow(beam->mesh.length, 4))) / (2 * M_PI);
  EXPECT_NEAR(lm.modes[0].frequency, 1.87510407 * 1.87510407 * scale, 0.01 * 3.516 * scale);
  EXPECT_NEAR(lm.modes[1].frequency, 4.69409113 * 4.69409113 * scale, 0.01 * 22.03 * scale);
}

TEST(LinearModes, ADrivenMechanismHeldByItsDriversHasNoFreedom) {
  // The Flores slider-crank: one degree of freedom once its clearance joint is ideal, which the
  // crank driver holds.
  const LinearModes lm = linear_modes(load_model_file(example_path("flores_slider_crank.yaml")).model);
  EXPECT_EQ(lm.dof, 0);
  EXPECT_TRUE(lm.modes.empty());
}


TEST(LinearModes, AShortRodFarFromTheOriginSwingsAtItsOwnFrequency) {
  // A point mass on a 1e-4 m distance joint, pivoted at x = 0 and at x = 1 m: √(g/L)/(2π) =
  // 49.85 Hz at both. At x = 1 m it was 36.47 Hz: the row's gradient d/L at the configurations
  // drawn for Φ_q's pattern made its pivot there 1e10 times its own, and it was softened. And
  // at every x it was 49.8464 Hz: a fixed difference step of 1e-6 m is 1 % of the rod.
  for (const double x : {0.0, 1.0, 100.0}) {
    char yaml[400];
    std::snprintf(yaml, sizeof yaml, R"Y(
gravity: [0, -9.81]
ground: {markers: {P: [%g, 0]}}
bodies:
  bob: {mass: 1, position: [%g, -1e-4]}
joints:
  rod: {type: distance, from: ground.P, to: bob}
solver: {end_time: 1}
)Y", x, x);
    const LinearModes modes =
        linear_modes(load_model_text(yaml, "bob.yaml").model);
    ASSERT_EQ(modes.modes.size(), 1u) << x;
    const double f = std::sqrt(9.81 / 1e-4) / (2 * M_PI);
    EXPECT_NEAR(modes.modes[0].frequency, f, 1e-7 * f) << x;
  }
}

TEST(LinearModes, AFlexibleRodBetweenAHeldCrankAndASliderHasItsClosedFormModes) {
  // The flexible-rod slider-crank example, undamped, its rod in 16 elements, the crank held: the
  // rod is pinned at the crank and pinned at B to the slider on its guide, so it bends as a
  // simply supported beam, ω_n = (nπ)² √(EI/(ρA L⁴)), and stretches with the slider as an end
  // mass, x tan x = m_rod/m_slider, ω = (x/L) √(E/ρ) (Blevins, Formulas for Natural Frequency
  // and Mode Shape, Tables 8-1 and 12-1). The linearised matrix spans 1e8 to 1e13 1/s²: before
  // it was balanced, its eigenvalues carried the difference quotients' error (3 236–3 270 Hz
  // for the first mode as the step changed, "unstable" roots at 16 elements), and a tableau
  // begun at too large a step lost the axial mode (7 359 Hz).
  std::string text = read_file(example_path("flores_slider_crank_flexible_rod.yaml"));
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"elements: 4\n", "elements: 16\n"},
                                 {"damping: 1.0e-6 ", "damping: 0 "}}) {
    const size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  }
  const LinearModes lm = linear_modes(load_model_text(text, "rod16.yaml").model);
  ASSERT_GE(lm.modes.size(), 3u);
  const double e = 207e9, length = 0.12, rho_a = 0.21 / length;
  const double inertia = 0.0112 * 0.020 * 0.020 * 0.020 / 12, area = 0.0112 * 0.020;
  const double bending = std::sqrt(e * inertia / (rho_a * std::pow(length, 4))) / (2 * M_PI);
  double lo = 0.5, hi = 1.5;  // x tan x = 1.5 on (0, π/2)
  for (int i = 0; i < 100; ++i) {
    const double x = 0.5 * (lo + hi);
    (x * std::tan(x) > 0.21 / 0.14 ? hi : lo) = x;
  }
  const double axial = lo / length * std::sqrt(e / (rho_a / area)) / (2 * M_PI);  // 6 746.7 Hz
  EXPECT_NEAR(lm.modes[0].frequency, M_PI * M_PI * bending, 1e-4 * M_PI * M_PI * bending);
  EXPECT_NEAR(lm.modes[1].frequency, axial, 1e-5 * axial);
  EXPECT_NEAR(lm.modes[2].frequency, 4 * M_PI * M_PI * bending, 1e-4 * 4 * M_PI * M_PI * bending);
  for (const LinearMode& mode : lm.modes) EXPECT_NEAR(mode.damping_ratio, 0.0, 1e-6);
  for (double r : lm.real_rates) EXPECT_LE(r, 1e-6);  // nothing unstable
}

TEST(LinearModes, ASlenderCantileversModesAreItsMeshsOwnToFiveDigits) {
  // A 1 m steel strip 0.5 mm thick clamped at one end: axial stiffness over bending stiffness
  // 12 L²/h² = 4.8e7, so the linearised matrix spans about 1e1 to 1e11 1/s². A fixed difference
  // step carried its error into the first mode: 0.416277 Hz
  // against the mesh's 0.416092 (beam::modes, a symmetric generalised eigenproblem, computed
  // independently), with a step of 1e-6. Every mode below 1 kHz agrees to 1e-5.
  const Model m = clamped_strip(0.0005, 0.0, false);
  const LinearModes lm = linear_modes(m);
  const std::vector<beam::Mode> own = beam::modes(m.bodies[0].mesh, beam::Support::clamped);
  ASSERT_EQ(lm.modes.size(), own.size());
  int checked = 0;
  for (size_t k = 0; k < own.size(); ++k) {
    const double f = own[k].omega / (2 * M_PI);
    if (f > 1000.0) continue;
    EXPECT_NEAR(lm.modes[k].frequency, f, 1e-5 * f) << "mode " << k + 1;
    ++checked;
  }
  EXPECT_GE(checked, 16);
}


TEST(LinearModes, ConstraintStabilisationIsNoPartOfTheLinearisation) {
  // Baumgarte's terms answered the difference steps' O(h²) departure from the constraints with a
  // spring of β² (β = 100 1/s): a point mass on a 1e-5 m rod swung at β/2π = 15.9 Hz, and a
  // parallelogram four-bar laid out in line, with nothing acting on it, had a mode at 10.45 Hz.
  for (const double length : {1e-5, 1e-6, 1e-8}) {
    char yaml[300];
    std::snprintf(yaml, sizeof yaml, R"Y(
gravity: [0, -9.81]
ground: {markers: {P: [0, 0]}}
bodies: {bob: {mass: 1, position: [0, %g]}}
joints: {rod: {type: distance, from: ground.P, to: bob}}
solver: {end_time: 1}
)Y", -length);
    const LinearModes lm = linear_modes(load_model_text(yaml, "bob.yaml").model);
    ASSERT_EQ(lm.modes.size(), 1u) << length;
    const double f = std::sqrt(9.81 / length) / (2 * M_PI);
    EXPECT_NEAR(lm.modes[0].frequency, f, 1e-6 * f) << length;
  }
  const LinearModes line = linear_modes(load_model_text(R"Y(
ground: {markers: {A0: [0, 0], B0: [0.7, 0]}}
bodies:
  crank:   {mass: 1, inertia: 0.01333, position: [0.2, 0], markers: {P: [-0.2, 0], Q: [0.2, 0]}}
  coupler: {mass: 3, inertia: 0.1225,  position: [0.75, 0], markers: {P: [-0.35, 0], Q: [0.35, 0]}}
  rocker:  {mass: 1, inertia: 0.01333, position: [0.9, 0], markers: {P: [-0.2, 0], Q: [0.2, 0]}}
joints:
  j0: {type: revolute, journal: crank.P, bearing: ground.A0}
  j1: {type: revolute, journal: crank.Q, bearing: coupler.P}
  j2: {type: revolute, journal: coupler.Q, bearing: rocker.Q}
  j3: {type: revolute, journal: rocker.P, bearing: ground.B0}
solver: {end_time: 1}
)Y", "in_line.yaml").model);
  EXPECT_TRUE(line.modes.empty()) << line.modes.size() << " modes, the first at "
                                  << (line.modes.empty() ? 0.0 : line.modes[0].frequency) << " Hz";
  for (double r : line.real_rates) EXPECT_NEAR(r, 0.0, 1e-6);
}

TEST(LinearModes, ADriverIsHeldWhereItsMotionStarts) {
  // coordinate(t) = initial + f(t) with f(0) = 0.5 m: the base starts at x = 1.5 m, where the
  // mass on its guide feels the spring's sideways stiffness k (1 − L0/x), ω² = k (1 − L0/x)/m.
  // f(0) was dropped, and the spring linearised at x = 1.0 m (0.7958 Hz for 0.9189).
  const LinearModes lm = linear_modes(load_model_text(R"Y(
ground: {markers: {O: [0, 0]}}
bodies: {base: {mass: 1, inertia: 0.1, position: [1.0, 0]}, m: {mass: 2, position: [0, 0]}}
joints:
  bg: {type: translational, guide: ground.O, slider: base, axis: [1, 0]}
  mg: {type: translational, guide: ground.O, slider: m, axis: [0, 1]}
drivers: {push: {joint: bg, motion: "0.5 + 0.1*sin(time)"}}
loads: {s: {type: spring_damper, from: base, to: m, stiffness: 100, free_length: 0.5}}
solver: {end_time: 1}
)Y", "pushed.yaml").model);
  ASSERT_EQ(lm.modes.size(), 1u);
  const double f = std::sqrt(100 * (1 - 0.5 / 1.5) / 2) / (2 * M_PI);
  EXPECT_NEAR(lm.modes[0].frequency, f, 1e-6 * f);
}


TEST(LinearModes, AtTheStaticEquilibriumAStringPendulumCarriesItsTension) {
  // A 1 m steel wire (2 mm, a flexible link) pinned at the top, a 1 kg bob pinned at its end.
  // Unstrained, as given, the wire carries no tension and the swing has no stiffness (about
  // 2e-5 Hz); at the static equilibrium it is stretched by the weight (m g / EA ≈ 1.5e-5) and
  // swings as the rigid compound pendulum, ω² = g (m_b + m_w/2) L / ((m_b + m_w/3) L²).
  const Model m = load_model_text(R"Y(
gravity: [0, -9.81]
ground: {markers: {O: [0, 0]}}
bodies:
  wire:
    position: [0, -0.5]
    angle_deg: -90
    markers: {A: [-0.5, 0], B: [0.5, 0]}
    flexible: {length: 1.0, elements: 4, section: {circle: 0.002}, youngs_modulus: 207e9, density: 7800}
  bob: {mass: 1.0, position: [0, -1.0]}
joints:
  top: {type: revolute, journal: wire.A, bearing: ground.O}
  end: {type: revolute, journal: bob, bearing: wire.B}
solver: {end_time: 1}
)Y", "wire.yaml").model;
  const LinearModes slack = linear_modes(m);
  ASSERT_FALSE(slack.modes.empty());
  EXPECT_LT(slack.modes[0].frequency, 1e-3);
  EXPECT_FALSE(slack.equilibrium);
  const LinearModes taut = linear_modes(m, true);
  ASSERT_TRUE(taut.equilibrium);
  ASSERT_FALSE(taut.modes.empty());
  const double mw = 7800 * M_PI * 0.001 * 0.001 * 1.0, mb = 1.0;
  const double f = std::sqrt(9.81 * (mb + mw / 2) / (mb + mw / 3)) / (2 * M_PI);
  EXPECT_NEAR(taut.modes[0].frequency, f, 2e-4 * f);
  const double ea = 207e9 * M_PI * 0.001 * 0.001;
  EXPECT_NEAR(taut.equilibrium->largest_move, 9.81 * (mb + mw) / ea, 0.05 * 9.81 * mb / ea);
}

TEST(LinearModes, AtTheStaticEquilibriumASpringHangsStretchedByTheWeight) {
  // 2 kg on a vertical guide hanging on k = 800 N/m given at its free length: the equilibrium
  // lies m g / k = 24.5 mm lower, and the frequency √(k/m) is the same there.
  const Model m = load_model_text(R"Y(
gravity: [0, -9.81]
ground: {markers: {A: [0, 0]}}
bodies:
  block: {mass: 2.0, inertia: 0.01, position: [0, -0.3]}
joints:
  guide: {type: translational, guide: ground.A, slider: block, axis: [0, 1]}
loads:
  spring: {type: spring_damper, from: ground.A, to: block, stiffness: 800, damping: 0, free_length: 0.3}
solver: {end_time: 1}
)Y", "hanging.yaml").model;
  const LinearModes lm = linear_modes(m, true);
  ASSERT_TRUE(lm.equilibrium);
  EXPECT_NEAR(lm.equilibrium->largest_move, 2.0 * 9.81 / 800, 1e-12);
  EXPECT_EQ(lm.equilibrium->largest_move_coordinate, "block.y");
  ASSERT_EQ(lm.modes.size(), 1u);
  EXPECT_NEAR(lm.modes[0].frequency, 20.0 / (2 * M_PI), 1e-9);
  // Without the spring nothing holds the block up: no equilibrium, said.
  try {
    linear_modes(load_model_text(R"Y(
gravity: [0, -9.81]
ground: {markers: {A: [0, 0]}}
bodies:
  block: {mass: 2.0, inertia: 0.01, position: [0, -0.3]}
joints:
  guide: {type: translational, guide: ground.A, slider: block, axis: [0, 1]}
solver: {end_time: 1}
)Y", "falling.yaml").model, true);
    ADD_FAILURE() << "no equilibrium, yet none was said";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no static equilibrium found near the initial configuration"),
              std::string::npos) << e.what();
  }
}


TEST(LinearModes, AtTheStaticEquilibriumACantileverSagsAsBeamTheorySays) {
  // A 1 m steel strip 5 mm thick clamped at one end, loaded by its weight w = ρ A g: the tip
  // sags w L⁴ / (8 EI) = 22.2 mm. Judged by whether the accelerations fell, Newton's steps were
  // halved to nothing (each bending step strains the link axially, to second order, which the
  // next step removes), and no equilibrium was found.
  const Model m = clamped_strip(0.005, 0.0, true);
  const LinearModes lm = linear_modes(m, true);
  ASSERT_TRUE(lm.equilibrium);
  const double w = 7800 * 0.02 * 0.005 * 9.81, ei = 207e9 * 0.02 * std::pow(0.005, 3) / 12;
  EXPECT_EQ(lm.equilibrium->largest_move_coordinate, "strip.n8.y");
  EXPECT_NEAR(lm.equilibrium->largest_move, w / (8 * ei), 0.005 * w / (8 * ei));
}

TEST(LinearModes, AtTheStaticEquilibriumAPendulumGoesToTheNearestOne) {
  // A bar pinned at one end, started θ from hanging: below 90° it hangs (0.6105 Hz), past 90°
  // the nearest equilibrium is the inverted one (real eigenvalues ±√(m g (L/2) / I_pin)). From
  // 75° an unlimited Newton step (−tan 75° rad) went to the inverted position, from 89° ten
  // turns round; at 90° (no stiffness) none was found.
  const double i_pin = 0.045 + 0.54 * 0.25;
  for (const double degrees : {30.0, 75.0, 89.0, 90.0, 120.0}) {
    const double phi = -M_PI / 2 + degrees * M_PI / 180;
    char yaml[500];
    std::snprintf(yaml, sizeof yaml, R"Y(
gravity: [0, -9.81]
ground: {markers: {O: [0, 0]}}
bodies:
  bar: {mass: 0.54, inertia: 0.045, position: [%.17g, %.17g], angle: %.17g, markers: {A: [-0.5, 0]}}
joints:
  pin: {type: revolute, journal: bar.A, bearing: ground.O}
solver: {end_time: 1}
)Y", 0.5 * std::cos(phi), 0.5 * std::sin(phi), phi);
    const LinearModes lm = linear_modes(load_model_text(yaml, "bar.yaml").model, true);
    ASSERT_TRUE(lm.equilibrium) << degrees;
    const double rate = std::sqrt(0.54 * 9.81 * 0.5 / i_pin);
    if (degrees <= 90) {
      ASSERT_EQ(lm.modes.size(), 1u) << degrees;
      EXPECT_NEAR(lm.modes[0].frequency, rate / (2 * M_PI), 1e-7) << degrees;
      EXPECT_NEAR(lm.equilibrium->largest_turn, degrees * M_PI / 180, 1e-9) << degrees;
    } else {
      EXPECT_TRUE(lm.modes.empty()) << degrees;
      ASSERT_EQ(lm.real_rates.size(), 2u) << degrees;
      EXPECT_NEAR(lm.real_rates[1], rate, 1e-6 * rate) << degrees;
      EXPECT_NEAR(lm.equilibrium->largest_turn, M_PI - degrees * M_PI / 180, 1e-9) << degrees;
    }
  }
}


TEST(LinearModes, AtTheStaticEquilibriumFarOrFromAPointTheNewtonStepsGrow) {
  // The mechanism's box was its bodies and ground joint points only: a block whose guide point
  // is its own start, hung on a spring from elsewhere, had a box of 0 (taken as 1 mm) and steps
  // of 0.2 mm: no equilibrium in 100 steps. The limit now doubles while cut steps help, and
  // load anchors count: the same m g/k = 24.5 mm drop; a soft spring's 9.81 m (33 sizes); a
  // point mass in a V of two springs from (±1, 1), its drop d solving 2k(L − √2)(1 + d)/L = m g
  // with L = √(1 + (1 + d)²).
  const std::string block = R"Y(
gravity: [0, -9.81]
ground: {markers: {T: [0, 0], G: [0, -0.3]}}
bodies: {block: {mass: 2.0, inertia: 0.01, position: [0, -0.3]}}
joints: {guide: {type: translational, guide: ground.G, slider: block, axis: [0, 1]}}
loads: {spring: {type: spring_damper, from: ground.T, to: block, stiffness: 800, free_length: 0.3}}
solver: {end_time: 1}
)Y";
  for (const double k : {800.0, 2.0}) {
    const LinearModes lm = linear_modes(
        load_model_text(block, "block.yaml", {"loads.spring.stiffness=" + std::to_string(k)}).model, true);
    ASSERT_TRUE(lm.equilibrium) << k;
    EXPECT_NEAR(lm.equilibrium->largest_move, 2.0 * 9.81 / k, 1e-9 * 2.0 * 9.81 / k) << k;
    ASSERT_EQ(lm.modes.size(), 1u) << k;
    EXPECT_NEAR(lm.modes[0].frequency, std::sqrt(k / 2.0) / (2 * M_PI), 1e-8) << k;
  }
  const LinearModes vee = linear_modes(load_model_text(R"Y(
gravity: [0, -9.81]
ground: {markers: {L: [-1, 1], R: [1, 1]}}
bodies: {m: {mass: 1.0, position: [0, 0]}}
loads:
  s1: {type: spring_damper, from: ground.L, to: m, stiffness: 100}
  s2: {type: spring_damper, from: ground.R, to: m, stiffness: 100}
solver: {end_time: 1}
)Y", "vee.yaml").model, true);
  ASSERT_TRUE(vee.equilibrium);
  double lo = 0.0, hi = 1.0;  // the drop d, by bisection
  for (int i = 0; i < 200; ++i) {
    const double d = 0.5 * (lo + hi), l = std::sqrt(1 + (1 + d) * (1 + d));
    (2 * 100 * (l - std::sqrt(2.0)) * (1 + d) / l > 9.81 ? hi : lo) = d;
  }
  EXPECT_NEAR(vee.equilibrium->largest_move, lo, 1e-9);
  EXPECT_EQ(vee.equilibrium->largest_move_coordinate, "m.y");
}

TEST(LinearModes, AStiffnessThatIsNotThereIsNoEquilibrium) {
  // A spring of free length 0.1 m between coincident points pulls along x (no line): the
  // differences saw a stiffness of 1e11 there, the Newton step was negligible and the state,
  // 7.14 m/s² out of balance, was reported as the equilibrium.
  try {
    linear_modes(load_model_text(R"Y(
gravity: [0, -9.81]
ground: {markers: {O: [0, 0], F: [5, 5]}}
bodies:
  m: {mass: 1.0, position: [0, 0]}
  dummy: {mass: 1, inertia: 1, position: [5, 5]}
joints: {pin: {type: fixed, base: ground.F, attached: dummy}}
loads: {s: {type: spring_damper, from: ground.O, to: m, stiffness: 100, free_length: 0.1}}
solver: {end_time: 1}
)Y", "zero_length.yaml").model, true);
    ADD_FAILURE() << "an unbalanced state was taken as the equilibrium";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no static equilibrium found"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lash::test
