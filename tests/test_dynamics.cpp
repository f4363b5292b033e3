// Rigid-body dynamics with ideal joints against closed forms and against itself.
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>

#include "test_support.hpp"

// Counts heap allocations (malloc: Eigen's and operator new's) while `g_counting` is set, by
// interposing glibc's malloc. Sanitizer builds keep their own allocator and skip the test.
static std::atomic<bool> g_counting{false};
static std::atomic<long> g_allocations{0};
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kCountAllocations = false;
#else
constexpr bool kCountAllocations = true;
extern "C" void* __libc_malloc(std::size_t);
extern "C" void* malloc(std::size_t n) {
  if (g_counting) ++g_allocations;
  return __libc_malloc(n);
}
#endif

using namespace lash;
using namespace lash::test;

namespace {
std::string num(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}
double agm(double a, double b) {
  for (int i = 0; i < 40; ++i) {
    const double an = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = an;
  }
  return a;
}
}  // namespace

TEST(Pendulum, LargeAmplitudePeriodMatchesEllipticClosedForm) {
  // Physical pendulum: a 0.4 m bar pivoted at one end, released from rest at θ0 = 1 rad.
  // ω0² = m g d / (I_cm + m d²); exact period T = 2π / (ω0 AGM(1, cos(θ0/2))).
  const double m = 2.0, len = 0.4, d = len / 2, icm = m * len * len / 12, g = 9.81, th0 = 1.0;
  const double w0 = std::sqrt(m * g * d / (icm + m * d * d));
  const double period = 2 * M_PI / (w0 * agm(1.0, std::cos(th0 / 2)));
  const std::string yaml = R"Y(
gravity: [0, -9.81]
bodies:
  bar:
    mass: )Y" + num(m) + R"Y(
    inertia: )Y" + num(icm) + R"Y(
    position: [)Y" + num(d * std::sin(th0)) + ", " + num(-d * std::cos(th0)) + R"Y(]
    angle: )Y" + num(th0) + R"Y(
    markers: {P: [0, )Y" + num(d) + R"Y(]}
joints:
  pivot: {type: revolute, journal: bar.P, bearing: ground}
solver:
  rtol: 1e-10
  atol: 1e-12
  end_time: )Y" + num(period) + R"Y(
  output_interval: )Y" + num(period / 4) + R"Y(
  initial_state: given
)Y";
  const SimRun r = run_text(yaml);
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const auto& phi = r.rec->data.at("bar.phi");
  const auto& omega = r.rec->data.at("bar.omega");
  ASSERT_EQ(phi.size(), 5u);
  EXPECT_NEAR(phi[2], -th0, 1e-7);  // half period: the other extreme
  EXPECT_NEAR(phi[4], th0, 1e-7);   // full period: back at rest at θ0
  EXPECT_NEAR(omega[4], 0.0, 1e-6);
  EXPECT_NEAR(phi[1], 0.0, 1e-7);   // quarter period: through the bottom
  // Energy: the pivot does no work, so kinetic + potential stays put.
  const auto& bal = r.rec->data.at("energy.balance");
  EXPECT_NEAR(bal.back(), bal.front(), 1e-9);
  EXPECT_LT(r.result.max_constraint_violation, 1e-10);
}

namespace {
// Ideal slider-crank, crank r, rod l, constant ω: closed-form slider position and acceleration.
struct SliderCrank {
  double r = 0.05, l = 0.12, w = 5000 * 2 * M_PI / 60;
  double x(double t) const {
    const double th = w * t;
    return r * std::cos(th) + std::sqrt(l * l - r * r * std::sin(th) * std::sin(th));
  }
  double ax(double t) const {
    const double th = w * t, s = std::sin(th), c = std::cos(th);
    const double root = std::sqrt(l * l - r * r * s * s), u = r * r * s * c;
    return -r * c * w * w - r * r * std::cos(2 * th) * w * w / root -
           u * u * w * w / (root * root * root);
  }
};
}  // namespace

TEST(SliderCrank, IdealKinematicsMatchClosedForm) {
  // The Flores example with its clearance closed (clearance: 0 makes the joint ideal).
  const SimRun r = run_example("flores_slider_crank.yaml", {"joints.rod_slider.clearance=0",
                                                         "solver.end_time=0.012"});
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const SliderCrank sc;
  double ex = 0, ea = 0;
  for (size_t i = 0; i < r.rec->time.size(); ++i) {
    const double t = r.rec->time[i];
    ex = std::max(ex, std::abs(r.rec->data.at("slider.x")[i] - sc.x(t)));
    ea = std::max(ea, std::abs(r.rec->data.at("slider.ax")[i] - sc.ax(t)));
  }
  // The example's tolerances (rtol 1e-8, atol 1e-11): errors well inside the tolerance.
  EXPECT_LT(ex, 2e-7);   // m, of x ~0.17 m
  EXPECT_LT(ea, 0.05);   // m/s², of peaks ~2e4
  // mechanisms.md hand-calculated check values.
  EXPECT_NEAR(r.rec->data.at("slider.ax")[0], -19419, 1.0);
  EXPECT_NEAR(sc.ax(M_PI / sc.w), 7996, 1.0);
  EXPECT_NEAR(r.rec->data.at("crank.omega")[0], 523.6, 0.01);
  EXPECT_LT(r.result.max_constraint_violation, 1e-7);
}

TEST(SliderCrank, DrivingTorqueEqualsRateOfMechanicalEnergy) {
  // Two computations of the driver's effort: its multiplier λ, and d(T + V)/dt / ω.
  const SimRun r = run_example("flores_slider_crank.yaml", {"joints.rod_slider.clearance=0",
                                                         "solver.end_time=0.012",
                                                         "solver.rtol=1e-10",
                                                         "solver.atol=1e-13"});
  ASSERT_TRUE(r.result.status.ok);
  const auto& t = r.rec->time;
  const auto& ke = r.rec->data.at("energy.kinetic");
  const auto& pe = r.rec->data.at("energy.potential");
  const auto& tq = r.rec->data.at("crank.torque");
  const double w = 5000 * 2 * M_PI / 60;
  double peak = 0, err = 0;
  for (size_t i = 2; i + 2 < t.size(); ++i) {
    const double h = t[i + 1] - t[i];
    // 4th-order central difference of the mechanical energy.
    auto e = [&](size_t k) { return ke[k] + pe[k]; };
    const double de = (e(i - 2) - 8 * e(i - 1) + 8 * e(i + 1) - e(i + 2)) / (12 * h);
    peak = std::max(peak, std::abs(tq[i]));
    err = std::max(err, std::abs(de / w - tq[i]));
  }
  EXPECT_GT(peak, 1.0);
  EXPECT_LT(err, 1e-4 * peak) << "peak torque " << peak;
  // And the energy balance closes: T + V + dissipated − input stays constant.
  const auto& bal = r.rec->data.at("energy.balance");
  EXPECT_NEAR(bal.back(), bal.front(), 1e-8 * ke[0]);
}

TEST(Springs, MassOnSpringOscillatesAtItsNaturalFrequency) {
  // A 2 kg slider on a frictionless guide, 800 N/m spring to the ground, pulled 10 mm:
  // x(t) = x0 cos(√(k/m) t). And a torsional spring on a pivoted disc: φ = φ0 cos(√(k/I) t).
  const std::string yaml = R"Y(
bodies:
  block: {mass: 2.0, inertia: 0.01, position: [0.11, 0]}
  disc:  {mass: 1.0, inertia: 0.02, position: [0, 1], angle: 0.1}
ground:
  markers: {A: [0, 0], C: [0, 1]}
joints:
  guide: {type: translational, guide: ground.A, slider: block, axis: [1, 0]}
  hinge: {type: revolute, journal: disc, bearing: ground.C}
loads:
  spring: {type: spring_damper, from: ground.A, to: block, stiffness: 800, free_length: 0.1}
  coil: {type: torsional_spring_damper, bodies: [ground, disc], stiffness: 5.0, free_angle: 0}
solver: {rtol: 1e-10, atol: 1e-13, end_time: 1.0, output_interval: 0.01, initial_state: given}
)Y";
  const SimRun r = run_text(yaml);
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  double ex = 0, ep = 0;
  for (size_t i = 0; i < r.rec->time.size(); ++i) {
    const double t = r.rec->time[i];
    ex = std::max(ex, std::abs(r.rec->data.at("block.x")[i] - (0.1 + 0.01 * std::cos(20 * t))));
    ep = std::max(ep, std::abs(r.rec->data.at("disc.phi")[i] - 0.1 * std::cos(std::sqrt(250.0) * t)));
  }
  EXPECT_LT(ex, 1e-9);
  EXPECT_LT(ep, 1e-8);
}

TEST(Springs, DampingDissipatesAndTheBalanceCloses) {
  const std::string yaml = R"Y(
gravity: [0, -9.81]
bodies:
  bob: {mass: 1.0, inertia: 0.001, position: [0.3, -0.2]}
ground:
  markers: {O: [0, 0]}
loads:
  spring: {type: spring_damper, from: ground.O, to: bob, stiffness: 200, damping: 1.5, free_length: 0.25}
solver: {rtol: 1e-10, atol: 1e-12, end_time: 2.0, output_interval: 0.005, initial_state: given}
)Y";
  const SimRun r = run_text(yaml);
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const auto& diss = r.rec->data.at("energy.dissipated");
  const auto& bal = r.rec->data.at("energy.balance");
  for (size_t i = 1; i < diss.size(); ++i) ASSERT_GE(diss[i], diss[i - 1]);
  EXPECT_GT(diss.back(), 0.5);  // most of the initial ~3 J elastic + gravity energy
  double drift = 0;
  for (double b : bal) drift = std::max(drift, std::abs(b - bal.front()));
  EXPECT_LT(drift, 1e-7);
}

TEST(Drivers, TranslationalExpressionDriverForceIsMassTimesAcceleration) {
  // A 3 kg carriage moved by step5(time, 0, 0, 0.085, 0.230) (the closing stroke of the UHV circuit breaker of Meng et al., Shock and Vibration (2015), UHV circuit-breaker mechanism).
  const std::string yaml = R"Y(
bodies:
  carriage: {mass: 3.0, inertia: 0.1, position: [0, 0]}
joints:
  rail: {type: translational, guide: ground, slider: carriage, axis: [1, 0]}
drivers:
  stroke: {joint: rail, motion: "step5(time, 0, 0, 0.085, 0.230)"}
solver: {end_time: 0.1, output_interval: 0.001}
)Y";
  const SimRun r = run_text(yaml);
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  double ex = 0, ef = 0;
  for (size_t i = 0; i < r.rec->time.size(); ++i) {
    const double t = r.rec->time[i], T = 0.085, s = std::min(t / T, 1.0);
    const double x = 0.230 * s * s * s * (10 - 15 * s + 6 * s * s);
    const double a = t < T ? 0.230 * (60 * s - 180 * s * s + 120 * s * s * s) / (T * T) : 0.0;
    ex = std::max(ex, std::abs(r.rec->data.at("carriage.x")[i] - x));
    ef = std::max(ef, std::abs(r.rec->data.at("stroke.force")[i] - 3.0 * a));
  }
  EXPECT_LT(ex, 1e-7);
  EXPECT_LT(ef, 1e-3 * 3.0 * 0.230 * 5.77 / (0.085 * 0.085));  // 0.1% of the peak force
}

TEST(Drivers, MotionAccelerationIsTheExactSecondDerivative) {
  // A crank pinned 0.05 m from its centre of mass, under gravity, driven by θ(t) = 0.5 sin(20t):
  // its angular acceleration is the driver's f̈ = −200 sin(20t), exactly (5-point differences
  // with h = 1e-5 s were off by ~1e-5 rad/s² here).
  const std::string yaml = R"Y(
gravity: [0, -9.81]
bodies:
  crank: {mass: 1.5, inertia: 2e-3, position: [0.05, 0], markers: {P: [-0.05, 0]}}
joints:
  pivot: {type: revolute, journal: crank.P, bearing: ground}
drivers:
  wobble: {joint: pivot, motion: "0.5*sin(20*time)"}
solver: {rtol: 1e-11, atol: 1e-13, end_time: 0.5, output_interval: 0.005}
)Y";
  const SimRun r = run_text(yaml);
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const auto& alpha = r.rec->data.at("crank.alpha");
  const auto& phi = r.rec->data.at("crank.phi");
  double e_alpha = 0, e_phi = 0;
  for (size_t i = 0; i < r.rec->time.size(); ++i) {
    const double t = r.rec->time[i];
    e_alpha = std::max(e_alpha, std::abs(alpha[i] - (-200.0 * std::sin(20.0 * t))));
    e_phi = std::max(e_phi, std::abs(phi[i] - 0.5 * std::sin(20.0 * t)));
  }
  EXPECT_LT(e_alpha, 1e-9 * 200.0);
  EXPECT_LT(e_phi, 1e-9);
}

TEST(Drivers, SpeedProfileIsIntegratedExactly) {
  // ω(t) = step5(t, 0, 0, 0.01, 100) rad/s; θ(t) = ∫ω = 100·L·(2.5Δ⁴ − 3Δ⁵ + Δ⁶) on the ramp
  // (Δ = t/L, L = 0.01 s), 100·(t − L/2) after it.
  const std::string yaml = R"Y(
bodies:
  rotor: {mass: 1.0, inertia: 1e-3, position: [0, 0]}
joints:
  shaft: {type: revolute, journal: rotor, bearing: ground}
drivers:
  spin: {joint: shaft, speed: "step5(time, 0, 0, 0.01, 100)"}
solver: {rtol: 1e-11, atol: 1e-13, end_time: 0.03, output_interval: 2.5e-4}
)Y";
  const SimRun r = run_text(yaml);
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const auto& omega = r.rec->data.at("rotor.omega");
  const auto& phi = r.rec->data.at("rotor.phi");
  const auto& alpha = r.rec->data.at("rotor.alpha");
  const double L = 0.01;
  double e_omega = 0, e_phi = 0, e_alpha = 0;
  for (size_t i = 0; i < r.rec->time.size(); ++i) {
    const double t = r.rec->time[i], d = std::min(t / L, 1.0);
    const double w = 100.0 * d * d * d * (10 - 15 * d + 6 * d * d);
    const double a = t < L ? 100.0 * 30 * d * d * (1 - d) * (1 - d) / L : 0.0;
    const double th = t < L ? 100.0 * L * (2.5 * std::pow(d, 4) - 3 * std::pow(d, 5) + std::pow(d, 6))
                            : 100.0 * (t - L / 2);
    e_omega = std::max(e_omega, std::abs(omega[i] - w));
    e_phi = std::max(e_phi, std::abs(phi[i] - th));
    e_alpha = std::max(e_alpha, std::abs(alpha[i] - a));
  }
  EXPECT_LT(e_omega, 1e-7);  // to integration tolerance (ω itself is a state)
  EXPECT_LT(e_phi, 1e-9);
  // f̈ = ω̇ enters the constraint exactly; what is left is Baumgarte's correction of the
  // integration error (about 1e-5 rad/s²; 5-point differences gave 1e-4). Peak 1.875·100/L.
  EXPECT_LT(e_alpha, 2e-5);
}

TEST(Assembly, RedundantConstraintsAreReported) {
  // A second revolute joint at the same pin: both its equations are dropped with a warning
  // naming it and the joint it repeats. A second driver on the same angle is refused, naming it.
  const std::string yaml = R"Y(
bodies:
  b: {mass: 1, inertia: 1, markers: {P: [0, 0]}}
joints:
  j1: {type: revolute, journal: b.P, bearing: ground}
  j2: {type: revolute, journal: b.P, bearing: ground}
solver: {end_time: 0.1}
)Y";
  const Model m = load_model_text(yaml, "r.yaml").model;
  Workspace ws(m);
  initial_state(m, ws);
  ASSERT_EQ(ws.warnings.size(), 1u);
  EXPECT_EQ(ws.warnings[0].rfind("joint 'j2': all 2 of its equations are redundant with joint 'j1';", 0), 0u)
      << ws.warnings[0];
  const Model m2 = load_model_text(yaml + "drivers:\n  d1: {joint: j1, speed: 1}\n  d2: {body: b, coordinate: phi, speed: 1}\n", "r.yaml").model;
  Workspace ws2(m2);
  try {
    initial_state(m2, ws2);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("driver 'd2': its equation is redundant with driver 'd1'"), std::string::npos) << e.what();
  }
}

TEST(Assembly, ImpossibleClosureIsReported) {
  // A 0.1 m link cannot reach a point 1 m away.
  const std::string yaml = R"Y(
ground: {markers: {A: [0, 0], B: [1, 0]}}
bodies:
  link: {mass: 1, inertia: 1, position: [0.05, 0], markers: {L: [-0.05, 0], R: [0.05, 0]}}
joints:
  a: {type: revolute, journal: link.L, bearing: ground.A}
  b: {type: revolute, journal: link.R, bearing: ground.B}
solver: {end_time: 0.1}
)Y";
  const Model m = load_model_text(yaml, "c.yaml").model;
  Workspace ws(m);
  EXPECT_THROW(initial_state(m, ws), std::runtime_error);
}

TEST(RightHandSide, AllocatesNothing) {
  if (!kCountAllocations) GTEST_SKIP() << "sanitizer build: malloc is the sanitizer's";
  // The Flores example with one clearance joint in contact and one expression load.
  std::string yaml = read_file(example_path("flores_slider_crank.yaml"));
  yaml += "loads:\n  push: {type: force, point: slider.O, fx: \"-100*slider.vx\", fy: \"0\"}\n";
  const Model m = load_model_text(yaml, "m.yaml").model;
  Workspace ws(m);
  Eigen::VectorXd y = initial_state(m, ws), ydot(ws.ny);
  y[ws.blocks[2].offset] += 0.6e-3;  // push the slider so the journal penetrates its bearing
  ws.contact[0] = {true};
  y[ws.aux_impact[0]] = 1.0;
  ASSERT_TRUE(evaluate(m, ws, 0.0, y.data(), ydot.data()));
  ASSERT_GT(ws.clearance_out[0].f_n, 0.0);
  g_allocations = 0;
  g_counting = true;
  for (int i = 0; i < 100; ++i) evaluate(m, ws, 1e-6 * i, y.data(), ydot.data());
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  // The counter works: a vector allocates.
  g_counting = true;
  { std::vector<double> v(1000); }
  g_counting = false;
  EXPECT_GT(g_allocations.load(), 0);
}

TEST(RightHandSide, ExactDriverDerivativesAllocateNothing) {
  if (!kCountAllocations) GTEST_SKIP() << "sanitizer build: malloc is the sanitizer's";
  // A position and a speed profile, whose derivatives share temporaries (symbolic_derivatives).
  const std::string yaml = R"Y(
bodies:
  crank: {mass: 1.5, inertia: 2e-3, position: [0.05, 0], markers: {P: [-0.05, 0]}}
  rotor: {mass: 1.0, inertia: 1e-3, position: [1, 0]}
ground: {markers: {R: [1, 0]}}
joints:
  pivot: {type: revolute, journal: crank.P, bearing: ground}
  shaft: {type: revolute, journal: rotor, bearing: ground.R}
drivers:
  wobble: {joint: pivot, motion: "0.1*sin(2*pi*5*t)*exp(-t/0.2)*step5(t, 0, 0, 0.05, 1)"}
  spin: {joint: shaft, speed: "100*step(time, 0, 0, 0.01, 1)"}
solver: {end_time: 0.1, output_interval: 0.01}
)Y";
  const Model m = load_model_text(yaml, "m.yaml").model;
  Workspace ws(m);
  Eigen::VectorXd y = initial_state(m, ws), ydot(ws.ny);
  ASSERT_TRUE(evaluate(m, ws, 0.0, y.data(), ydot.data()));
  g_allocations = 0;
  g_counting = true;
  for (int i = 0; i < 100; ++i) evaluate(m, ws, 1e-3 * i, y.data(), ydot.data());
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
}

TEST(FixedJoint, WeldedBodiesSwingAsOnePendulum) {
  // Two 1 kg point-like blocks welded end to end hang from a pivot: a compound pendulum with
  // I_O = Σ(I + m d²) and m g d_cm = g (0.1 + 0.3). Small-amplitude period 2π√(I_O / (m_tot g d_cm)).
  const std::string yaml = R"Y(
gravity: [0, -9.81]
bodies:
  upper: {mass: 1.0, inertia: 1e-3, position: [0, -0.1], markers: {P: [0, 0.1], W: [0, -0.1]}}
  lower: {mass: 1.0, inertia: 1e-3, position: [0, -0.3], markers: {W: [0, 0.1]}}
joints:
  pivot: {type: revolute, journal: upper.P, bearing: ground}
  weld: {type: fixed, base: upper.W, attached: lower.W}
solver: {rtol: 1e-10, atol: 1e-13, end_time: 4.5, output_interval: 1e-3, initial_state: given}
)Y";
  // Start with a small angular velocity: amplitude ~ 0.02 rad keeps the linear period accurate.
  const SimRun r = run_text(yaml, {"bodies.upper.angular_velocity=0.05",
                                   "bodies.upper.velocity=[0.005, 0]"});
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const double io = 2 * 1e-3 + 1.0 * 0.1 * 0.1 + 1.0 * 0.3 * 0.3;
  const double period = 2 * M_PI * std::sqrt(io / (9.81 * (0.1 + 0.3)));
  // Zero crossings of the angle, rising: their spacing is the period.
  const auto& phi = r.rec->data.at("upper.phi");
  const auto& phi_low = r.rec->data.at("lower.phi");
  std::vector<double> rising;
  for (size_t i = 1; i < phi.size(); ++i)
    if (phi[i - 1] < 0 && phi[i] >= 0)
      rising.push_back(r.rec->time[i - 1] + (r.rec->time[i] - r.rec->time[i - 1]) *
                                                 (-phi[i - 1]) / (phi[i] - phi[i - 1]));
  ASSERT_GE(rising.size(), 3u);
  EXPECT_NEAR((rising.back() - rising.front()) / (rising.size() - 1), period, 2e-4 * period);
  // The weld holds: both bodies turn together.
  EXPECT_LT(max_abs_diff(phi, phi_low), 1e-9);
}

TEST(Loads, ImpactExpressionIsAOneSidedStop) {
  // A block slides at 0.2 m/s into an IMPACT stop at x = 0.05 m written as a force expression of
  // its own state (K = 1e6 N/m^1.5, no damping): it comes back at the same speed.
  const std::string yaml = R"Y(
bodies:
  block: {mass: 0.5, inertia: 1e-3, velocity: [0.2, 0]}
joints:
  rail: {type: translational, guide: ground, slider: block, axis: [1, 0]}
loads:
  stop: {type: force, point: block, fx: "-impact(-block.x, -block.vx, -0.05, 1e6, 1.5, 0, 1e-4)"}
solver: {rtol: 1e-10, atol: 1e-13, end_time: 0.6, output_interval: 1e-5, initial_state: given}
)Y";
  const SimRun r = run_text(yaml);
  ASSERT_TRUE(r.result.status.ok) << r.result.status.message;
  const auto& x = r.rec->data.at("block.x");
  const auto& vx = r.rec->data.at("block.vx");
  // Deepest penetration where the kinetic energy is stored: ½mv² = K δ^2.5 / 2.5.
  const double delta_max = std::pow(2.5 * 0.5 * 0.5 * 0.2 * 0.2 / 1e6, 1 / 2.5);
  EXPECT_NEAR(*std::max_element(x.begin(), x.end()), 0.05 + delta_max, 1e-8);
  EXPECT_NEAR(vx.back(), -0.2, 1e-6);                          // elastic rebound
  const auto& bal = r.rec->data.at("energy.balance");
  // The stop is an applied force, so its work is input: kinetic − input stays constant.
  EXPECT_NEAR(bal.back(), bal.front(), 1e-9);
}

TEST(Workspace, MovedWorkspacesKeepTheirExpressions) {
  // A free 2 kg block pushed by fx = 1000·t (no gravity): ẍ = F/m = 500·t m/s², exactly, from
  // a Workspace that was moved, move-assigned, or moved by a std::vector that reallocated.
  const std::string yaml = R"Y(
gravity: [0, 0]
bodies:
  block: {mass: 2.0, inertia: 1e-3}
loads:
  push: {type: force, point: block, fx: "1000*time", fy: "0"}
solver: {end_time: 1.0, output_interval: 0.1, initial_state: given}
)Y";
  const Model m = load_model_text(yaml, "free_block.yaml").model;
  auto check = [&](Workspace& ws, double t, const std::string& how) {
    const Eigen::VectorXd y = initial_state(m, ws);
    Eigen::VectorXd ydot(ws.ny);
    ASSERT_TRUE(evaluate(m, ws, t, y.data(), ydot.data())) << how;
    EXPECT_EQ(ydot[ws.nq + 0], 1000.0 * t / 2.0) << how;  // ẍ = F/m
    EXPECT_EQ(ydot[ws.nq + 1], 0.0) << how;
  };
  Workspace original(m);
  check(original, 0.5, "in place");
  Workspace moved(std::move(original));
  check(moved, 0.25, "move-constructed");
  Workspace assigned(m);
  assigned = std::move(moved);
  check(assigned, 0.75, "move-assigned");

  std::vector<Workspace> pool;
  std::vector<size_t> capacities;
  for (int i = 0; i < 9; ++i) {
    pool.emplace_back(m);
    capacities.push_back(pool.capacity());
  }
  ASSERT_NE(capacities.front(), capacities.back()) << "the vector never reallocated";
  for (size_t i = 0; i < pool.size(); ++i)
    check(pool[i], 0.1 * (i + 1), "vector element " + std::to_string(i));
  pool.erase(pool.begin());  // move-assigns every later element one slot down
  for (size_t i = 0; i < pool.size(); ++i)
    check(pool[i], 0.2 + 0.1 * i, "after erase, element " + std::to_string(i));
}

TEST(InitialState, ADriverBetweenTwoFreeBodiesSplitsItsSpeedWithZeroAngularMomentum) {
  // A rotor and a stator on one pivot, the stator free to turn on the ground, the driver setting
  // the rotor's angle relative to the stator at ω = 10 rad/s. Started from rest by the drive (the
  // least kinetic energy, Gauss's principle), their angular momentum stays zero:
  // ω_stator = −I_r ω / (I_r + I_s) = −2.5, ω_rotor = I_s ω / (I_r + I_s) = 7.5 rad/s — whatever
  // the units of the coordinates (a Euclidean minimum norm would give ∓5 rad/s).
  const std::string yaml = R"(
ground: {markers: {O: [0, 0]}}
bodies:
  stator: {mass: 2.0, inertia: 3.0, position: [0, 0], markers: {O: [0, 0]}}
  rotor: {mass: 1.0, inertia: 1.0, position: [0, 0], markers: {O: [0, 0]}}
joints:
  bearing: {type: revolute, journal: stator.O, bearing: ground.O}
  shaft: {type: revolute, journal: rotor.O, bearing: stator.O}
drivers:
  motor: {joint: shaft, speed: 10}
solver: {end_time: 0.1, output_interval: 0.01}
)";
  const Model m = load_model_text(yaml, "motor.yaml").model;
  Workspace ws(m);
  const Eigen::VectorXd y = initial_state(m, ws);
  const double omega_stator = y[ws.nq + ws.blocks[0].rot], omega_rotor = y[ws.nq + ws.blocks[1].rot];
  EXPECT_NEAR(omega_stator, -2.5, 1e-12);
  EXPECT_NEAR(omega_rotor, 7.5, 1e-12);
  // And the run keeps it so (no torque acts on the pair from outside).
  struct Momentum : Observer {
    void output(double, const Eigen::VectorXd& y, const Workspace& w) override {
      worst = std::max(worst, std::abs(3.0 * y[w.nq + w.blocks[0].rot] + 1.0 * y[w.nq + w.blocks[1].rot]));
    }
    double worst = 0.0;
  } momentum;
  Workspace run(m);
  ASSERT_TRUE(simulate(m, run, momentum).status.ok);
  EXPECT_LT(momentum.worst, 1e-9);
}
