// Physics of the element kinds in core/elements: point masses, distance joints, sensors,
// bushings, body and speed-profile drivers, clearance-joint force channels, LuGre friction in a
// clearance joint, restartable state and finalize's checks.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <tuple>
#include <vector>

#include "core/elements/registry.hpp"
#include "core/finalize.hpp"
#include "io/state_file.hpp"
#include "test_support.hpp"

namespace lash::test {
namespace {

constexpr double kG = 9.81;

/// Largest |balance − balance(0)| relative to the largest energy magnitude seen.
double balance_drift(const Recorder& r) {
  const auto& b = r["energy.balance"];
  double drift = 0, scale = 1e-300;
  for (size_t i = 0; i < b.size(); ++i) {
    drift = std::max(drift, std::abs(b[i] - b[0]));
    for (const char* c : {"energy.kinetic", "energy.potential", "energy.input"})
      scale = std::max(scale, std::abs(r[c][i]));
  }
  return drift / scale;
}

TEST(Sensors, AccelerometerOnAUniformlyRotatingDiscReadsCentripetalAndGravity) {
  // A disc turning at ω about its centre pinned to the ground; accelerometers at r = 0.1 m on
  // the body's x axis. Kinematic reading along the body axis: −ω² r (ω² r inward). With gravity
  // (specific force a − g, g = (0, −9.81)): −ω² r + g sin φ. Along the ground's x axis:
  // −ω² r cos φ.
  const double omega = 30.0, r = 0.1;
  const std::string yaml = R"(
name: disc
gravity: [0, -9.81]
bodies:
  disc: {mass: 2, inertia: 0.01, position: [0, 0], markers: {O: [0, 0], P: [0.1, 0]}}
joints:
  pivot: {type: revolute, journal: disc.O, bearing: ground}
drivers:
  spin: {joint: pivot, speed: 30}
sensors:
  acc_kin: {type: accelerometer, at: disc.P, axis: [1, 0], gravity: false}
  acc_sf:  {type: accelerometer, at: disc.P, axis: [1, 0]}
  acc_w:   {type: accelerometer, at: disc.P, axis: [1, 0], frame: ground, gravity: false}
  vel:     {type: velocity, at: disc.P, axis: [0, 1]}
  pos:     {type: displacement, at: disc.P, axis: [1, 0], frame: ground}
solver: {end_time: 0.3, output_interval: 1e-3}
)";
  const SimRun s = run_text(yaml);
  ASSERT_TRUE(s.result.status.ok) << s.result.status.message;
  const Recorder& rec = *s.rec;
  for (size_t i = 0; i < rec.time.size(); ++i) {
    const double phi = rec["disc.phi"][i];
    EXPECT_NEAR(rec["acc_kin.a"][i], -omega * omega * r, 1e-6);
    EXPECT_NEAR(rec["acc_sf.a"][i], -omega * omega * r + kG * std::sin(phi), 1e-6);
    EXPECT_NEAR(rec["acc_w.a"][i], -omega * omega * r * std::cos(phi), 1e-6);
    EXPECT_NEAR(rec["vel.v"][i], omega * r, 1e-8);  // body y axis: the tangential velocity
    EXPECT_NEAR(rec["pos.x"][i], r * std::cos(phi), 1e-9);
  }
}

TEST(Sensors, ASensorsMassIsAPointMassPinnedAtItsPoint) {
  // A 25 g accelerometer at the tip of a swinging rod moves exactly as an explicit 25 g point
  // mass pinned there, and the small-swing period follows the compound pendulum with the tip
  // mass: T = 2π sqrt((I_O + m_s L²)/((m l + m_s L) g)).
  const std::string base = R"(
name: rod_with_sensor
gravity: [0, -9.81]
bodies:
  rod: {mass: 0.2, inertia: 0.0016666666666666668, position: [0.009995833854135688, -0.19975005207899327], angle: -1.5207963267948965,
        markers: {O: [-0.2, 0], tip: [0.2, 0]}}
joints:
  pivot: {type: revolute, journal: rod.O, bearing: ground}
solver: {end_time: 4, output_interval: 1e-3, initial_state: given, rtol: 1e-10, atol: 1e-12}
)";
  const SimRun with_sensor = run_text(base + R"(sensors:
  acc: {type: accelerometer, at: rod.tip, axis: [0, 1], mass: 0.025}
)");
  // The same, built by hand: the point mass after the rod, its pin after the pivot.
  std::string by_hand = base;
  by_hand.replace(by_hand.find("joints:"), 0,
                  "  acc_mass: {mass: 0.025, position: [0.019991667708271377, -0.39950010415798654]}\n");
  by_hand.replace(by_hand.find("solver:"), 0,
                  "  acc_mount: {type: revolute, journal: acc_mass, bearing: rod.tip}\n");
  const SimRun explicit_mass = run_text(by_hand);
  ASSERT_TRUE(with_sensor.result.status.ok && explicit_mass.result.status.ok);
  EXPECT_LT(max_abs_diff((*with_sensor.rec)["rod.phi"], (*explicit_mass.rec)["rod.phi"]), 1e-9);
  // Small-swing period from upward crossings of the mean angle.
  const auto& phi = (*with_sensor.rec)["rod.phi"];
  const auto& t = with_sensor.rec->time;
  const double mid = -M_PI / 2;
  std::vector<double> up;
  for (size_t i = 1; i < phi.size(); ++i)
    if (phi[i - 1] < mid && phi[i] >= mid)
      up.push_back(t[i - 1] + (t[i] - t[i - 1]) * (mid - phi[i - 1]) / (phi[i] - phi[i - 1]));
  ASSERT_GE(up.size(), 2u);
  const double period = (up.back() - up.front()) / (up.size() - 1);
  const double m = 0.2, ms = 0.025, l = 0.2, L = 0.4, I_O = 0.0016666666666666668 + m * l * l;
  const double small = 2 * M_PI * std::sqrt((I_O + ms * L * L) / ((m * l + ms * L) * kG));
  // The swing is 0.05 rad: the finite-amplitude correction θ0²/16 is 1.6e-4.
  EXPECT_NEAR(period / small, 1.0 + 0.05 * 0.05 / 16, 2e-5);
}

TEST(PointMass, PendulumPeriodMatchesTheEllipticClosedForm) {
  // A point-mass bob on a massless rod (distance joint) of L = 1 m released from θ0 = 60°:
  // T = 4 sqrt(L/g) K(sin(θ0/2)) (complete elliptic integral of the first kind).
  const double L = 1.0, theta0 = M_PI / 3;
  const std::string yaml = "name: pendulum\ngravity: [0, -9.81]\nbodies:\n  bob: {mass: 0.5, position: [" +
                           std::to_string(L * std::sin(theta0)) + ", " +
                           std::to_string(-L * std::cos(theta0)) + R"(]}
joints:
  rod: {type: distance, from: ground, to: bob, length: 1.0}
solver: {end_time: 6, output_interval: 1e-3, initial_state: given, rtol: 1e-10, atol: 1e-12}
)";
  const SimRun s = run_text(yaml);
  ASSERT_TRUE(s.result.status.ok) << s.result.status.message;
  const Recorder& r = *s.rec;
  // Upward crossings of x = 0, located by linear interpolation.
  std::vector<double> up;
  const auto& x = r["bob.x"];
  for (size_t i = 1; i < x.size(); ++i)
    if (x[i - 1] < 0 && x[i] >= 0)
      up.push_back(r.time[i - 1] + (r.time[i] - r.time[i - 1]) * (-x[i - 1]) / (x[i] - x[i - 1]));
  ASSERT_GE(up.size(), 2u);
  const double period = (up.back() - up.front()) / (up.size() - 1);
  const double exact = 4.0 * std::sqrt(L / kG) * std::comp_ellint_1(std::sin(theta0 / 2));
  EXPECT_NEAR(period / exact, 1.0, 1e-6) << period << " vs " << exact;
  // Rod length held, energy conserved, and the rod tension at the bottom m(g + v²/L).
  EXPECT_LT(s.result.max_constraint_violation, 1e-9);
  EXPECT_LT(balance_drift(r), 1e-8);
  double tension_max = 0;
  for (double t : r["rod.tension"]) tension_max = std::max(tension_max, t);
  const double v2 = 2 * kG * L * (1 - std::cos(theta0));
  EXPECT_NEAR(tension_max, 0.5 * (kG + v2 / L), 1e-3 * 0.5 * (kG + v2 / L));
}

TEST(Bushing, FramedOnARotatingBodyConservesEnergyAndDissipatesOnlyWithDamping) {
  // A point mass hung from a swinging rigid arm by a two-axis bushing in the arm's frame: the
  // bushing's axes turn with the arm, so its moment on the arm must include that turning for
  // T + V to be conserved (core/elements/bushing.cpp).
  const std::string yaml = R"(
name: arm_absorber
gravity: [0, -9.81]
bodies:
  arm: {mass: 1.0, inertia: 0.02, position: [0.2, 0], markers: {O: [-0.2, 0], P: [0.2, 0]}}
  tmd: {mass: 0.1, position: [0.42, 0.01]}
joints:
  pivot: {type: revolute, journal: arm.O, bearing: ground}
loads:
  mount: {type: bushing, from: arm.P, to: tmd, stiffness: [400, 900], damping: DAMP}
solver: {end_time: 2, output_interval: 1e-3, initial_state: given, rtol: 1e-10, atol: 1e-12}
)";
  auto with = [&](const std::string& damp) {
    std::string y = yaml;
    y.replace(y.find("DAMP"), 4, damp);
    return run_text(y);
  };
  const SimRun free = with("0");
  ASSERT_TRUE(free.result.status.ok) << free.result.status.message;
  EXPECT_LT(balance_drift(*free.rec), 1e-8);
  EXPECT_NEAR(free.rec->operator[]("energy.dissipated").back(), 0.0, 1e-12);
  const SimRun damped = with("[0.5, 2]");
  ASSERT_TRUE(damped.result.status.ok);
  EXPECT_LT(balance_drift(*damped.rec), 1e-8);
  const auto& d = (*damped.rec)["energy.dissipated"];
  EXPECT_GT(d.back(), 1e-4);
  for (size_t i = 1; i < d.size(); ++i) EXPECT_GE(d[i], d[i - 1] - 1e-15);
  // The power channel is the rate of the bushing's work: −d(V)/dt − dissipation, i.e. its
  // integral equals −(ΔV_bushing + dissipated); check against the trapezoid of the channel.
  const auto& p = (*damped.rec)["mount.power"];
  double work = 0;
  for (size_t i = 1; i < p.size(); ++i) work += 0.5 * (p[i] + p[i - 1]) * 1e-3;
  const auto& dx = (*damped.rec)["mount.dx"];
  const auto& dy = (*damped.rec)["mount.dy"];
  auto v = [&](size_t i) { return 0.5 * 400 * dx[i] * dx[i] + 0.5 * 900 * dy[i] * dy[i]; };
  EXPECT_NEAR(work, -(v(p.size() - 1) - v(0)) - d.back(), 2e-3 * d.back());
}

TEST(ClearanceJoint, ForceChannelsEqualTheContactForceRecomputed) {
  // Fx, Fy are the force on the journal, −F_N n + F_T t with n = e/|e| and t = perp(n).
  const SimRun s = run_example("flores_slider_crank.yaml",
                               {"solver.end_time=0.012",
                                "clearance_defaults.friction={law: coulomb, mu: 0.1}"});
  ASSERT_TRUE(s.result.status.ok);
  const Recorder& r = *s.rec;
  int in_contact = 0;
  for (size_t i = 0; i < r.time.size(); ++i) {
    const Vec2 e(r["rod_slider.ex"][i], r["rod_slider.ey"][i]);
    const Vec2 n = e / e.norm(), t = perp(n);
    const Vec2 f = -r["rod_slider.Fn"][i] * n + r["rod_slider.Ft"][i] * t;
    const double tol = 1e-7 * std::max(1.0, f.norm());  // the CSV-free path: doubles
    EXPECT_NEAR(r["rod_slider.Fx"][i], f.x(), tol);
    EXPECT_NEAR(r["rod_slider.Fy"][i], f.y(), tol);
    EXPECT_NEAR(r["rod_slider.F"][i], f.norm(), tol);
    in_contact += r["rod_slider.Fn"][i] > 0 && std::abs(r["rod_slider.Ft"][i]) > 0;
  }
  EXPECT_GT(in_contact, 10);
}

TEST(ClearanceJoint, LuGreFrictionKeepsTheEnergyBalance) {
  // LuGre in the Flores joint (Canudas de Wit et al. 1995 values scaled to μ_d = 0.1): the
  // balance T + V + dissipated − input stays constant, and the dissipated energy never falls
  // by more than the largest energy the bristles can hold, F_N σ0 z²/2 with |z| ≤ μ_s/σ0.
  const SimRun s = run_example(
      "flores_slider_crank.yaml",
      {"solver.end_time=0.012",
       "clearance_defaults.friction={law: lugre, sigma0: 1e5, sigma1: 316, sigma2: 0.004, "
       "mu_static: 0.15, mu_dynamic: 0.1, v_stribeck: 0.001, v_damping: 0.001}"});
  ASSERT_TRUE(s.result.status.ok) << s.result.status.message;
  const Recorder& r = *s.rec;
  EXPECT_LT(balance_drift(r), 1e-6);
  double fn_max = 0, ft_max = 0;
  for (size_t i = 0; i < r.time.size(); ++i) {
    fn_max = std::max(fn_max, r["rod_slider.Fn"][i]);
    ft_max = std::max(ft_max, std::abs(r["rod_slider.Ft"][i]));
  }
  ASSERT_GT(fn_max, 0);
  EXPECT_GT(ft_max, 0);
  const double bristle_max = fn_max * 0.15 * 0.15 / (2 * 1e5);
  const auto& d = r["energy.dissipated"];
  for (size_t i = 1; i < d.size(); ++i) EXPECT_GE(d[i], d[i - 1] - bristle_max);
}

TEST(Drivers, ASpeedProfileOfAConstantEqualsTheConstantSpeedDriver) {
  const SimRun a = run_example("flores_slider_crank_ideal.yaml", {"solver.end_time=0.006"});
  std::string yaml = read_file(example_path("flores_slider_crank_ideal.yaml"));
  const size_t at = yaml.find("speed_rpm: 5000");
  ASSERT_NE(at, std::string::npos);
  yaml.replace(at, 15, "speed: \"5000*2*_pi/60 + 0*time\"");
  const SimRun b = run_text(yaml, {"solver.end_time=0.006"});
  ASSERT_TRUE(a.result.status.ok && b.result.status.ok) << b.result.status.message;
  EXPECT_LT(max_abs_diff((*a.rec)["slider.x"], (*b.rec)["slider.x"]), 1e-9);
  EXPECT_LT(max_abs_diff((*a.rec)["crank.torque"], (*b.rec)["crank.torque"]), 1e-6);
}

TEST(Drivers, ABodyDriverLetsTheDrivenJointHaveClearance) {
  // The crank's angle prescribed relative to the ground, and its own pivot a clearance joint.
  std::string yaml = read_file(example_path("flores_slider_crank.yaml"));
  const size_t at = yaml.find("joint: crank_pivot");
  ASSERT_NE(at, std::string::npos);
  yaml.replace(at, 18, "body: crank\n    coordinate: phi");
  const SimRun s = run_text(yaml, {"solver.end_time=0.012", "joints.crank_pivot.clearance=0.2e-3"});
  ASSERT_TRUE(s.result.status.ok) << s.result.status.message;
  const Recorder& r = *s.rec;
  for (size_t i = 0; i < r.time.size(); ++i)
    EXPECT_NEAR(r["crank.phi"][i], 5000 * 2 * M_PI / 60 * r.time[i], 1e-8);
  int pivot_events = 0;
  for (const auto& e : r.events) pivot_events += e.clearance == 0;
  EXPECT_GT(pivot_events, 0);
  EXPECT_LT(balance_drift(r), 1e-6);
}

TEST(State, AContinuedRunIsBitIdenticalToOneRestartedThere) {
  // Run 1: 0 → T with an integrator restart at T/2. Run 2: 0 → T/2, state saved to
  // final_state.json and read back. Run 3: T/2 → T from that file. Runs 1 and 3 agree bit for
  // bit after T/2 (chaotic Flores motion: any difference would grow).
  Model m = load_model_file(example_path("flores_slider_crank.yaml"), {"solver.end_time=0.024"}).model;
  const double half = 0.012;
  Workspace w1(m);
  Recorder r1(m);
  RunOptions restart;
  restart.restarts = {half};
  ASSERT_TRUE(simulate(m, w1, r1, {}, {}, restart).status.ok);

  Model m_half = m;
  m_half.solver.end_time = half;
  Workspace w2(m_half);
  Recorder r2(m_half);
  const RunResult first = simulate(m_half, w2, r2);
  ASSERT_TRUE(first.status.ok);
  const std::string path = ::testing::TempDir() + "lash_state_test.json";
  write_state(path, m_half, w2, first.final_state);
  Workspace w3(m);
  const State st = read_state(path, m, w3);
  EXPECT_EQ(st.t, half);
  ASSERT_EQ(st.y.size(), first.final_state.y.size());
  for (int i = 0; i < st.y.size(); ++i) EXPECT_EQ(st.y[i], first.final_state.y[i]) << i;
  Recorder r3(m);
  RunOptions from;
  from.from = &st;
  ASSERT_TRUE(simulate(m, w3, r3, {}, {}, from).status.ok);

  ASSERT_EQ(r3.time.front(), half);
  const size_t k0 = std::find(r1.time.begin(), r1.time.end(), half) - r1.time.begin();
  ASSERT_LT(k0, r1.time.size());
  ASSERT_EQ(r1.time.size() - k0, r3.time.size());
  for (const auto& [name, v3] : r3.data) {
    const auto& v1 = r1[name];
    for (size_t i = 0; i < v3.size(); ++i) ASSERT_EQ(v1[k0 + i], v3[i]) << name << " at " << r3.time[i];
  }
  std::filesystem::remove(path);
}

TEST(State, AContinuedRunAgreesWithAnUninterruptedOneOnARegularModel) {
  Model m = load_model_file(example_path("flores_slider_crank_ideal.yaml"), {"solver.end_time=0.012"}).model;
  Workspace w1(m);
  Recorder r1(m);
  ASSERT_TRUE(simulate(m, w1, r1).status.ok);
  Model m_half = m;
  m_half.solver.end_time = 0.006;
  Workspace w2(m_half);
  Recorder r2(m_half);
  const RunResult first = simulate(m_half, w2, r2);
  Workspace w3(m);
  Recorder r3(m);
  RunOptions from;
  from.from = &first.final_state;
  ASSERT_TRUE(simulate(m, w3, r3, {}, {}, from).status.ok);
  const size_t k0 = r1.time.size() - r3.time.size();
  for (const char* c : {"slider.x", "rod.phi", "crank_pivot.F"})
    for (size_t i = 0; i < r3.time.size(); ++i)
      EXPECT_NEAR(r1[c][k0 + i], r3[c][i], 1e-7 * (1 + std::abs(r1[c][k0 + i]))) << c;
}

TEST(State, AnInterruptStopsTheRunAtTheNextStepNotTheNextOutput) {
  // One output interval for the whole run (0.012 s, one crank revolution): the flag a signal
  // handler would set is raised during the 40th integrator step. The run stops at that step's
  // end, not at the output 0.012 s later, and its final state continues the run to the same end
  // as an uninterrupted run, within the tolerances.
  struct RaiseAt : Recorder {
    RaiseAt(const Model& m, std::atomic<int>& flag) : Recorder(m), flag_(flag) {}
    bool wants_steps() const override { return true; }
    void step(double, double t1, const Eigen::VectorXd&, const Workspace&, StepProbe&) override {
      if (++steps == 40) flag_.store(15), t_raised = t1;
    }
    std::atomic<int>& flag_;
    int steps = 0;
    double t_raised = 0.0;
  };
  for (const char* integrator : {"dopri5", "bdf"}) {
    SCOPED_TRACE(integrator);
    Model m = load_model_file(example_path("flores_slider_crank.yaml"),
                              {"solver.end_time=0.012", "solver.output_interval=0.012",
                               std::string("solver.integrator=") + integrator})
                  .model;
    Workspace w1(m);
    Recorder whole(m);
    ASSERT_TRUE(simulate(m, w1, whole).status.ok);
    std::atomic<int> flag{0};
    Workspace w2(m);
    RaiseAt raising(m, flag);
    RunOptions o;
    o.interrupt = &flag;
    const RunResult cut = simulate(m, w2, raising, {}, {}, o);
    EXPECT_EQ(cut.status.outcome, RunOutcome::interrupted);
    EXPECT_NE(cut.status.message.find("interrupted by signal 15 at t = "), std::string::npos)
        << cut.status.message;
    EXPECT_EQ(raising.steps, 40);  // no step after the one that raised the flag
    EXPECT_EQ(cut.status.t, raising.t_raised);
    EXPECT_EQ(cut.final_state.t, raising.t_raised);
    EXPECT_LT(cut.final_state.t, 0.006);
    // The start, then the state the run stopped in (off the output grid).
    EXPECT_EQ(raising.time, (std::vector<double>{0.0, raising.t_raised}));
    EXPECT_EQ(resume_problem(m, w2, cut.final_state), "");
    Workspace w3(m);
    Recorder rest(m);
    RunOptions from;
    from.from = &cut.final_state;
    ASSERT_TRUE(simulate(m, w3, rest, {}, {}, from).status.ok);
    ASSERT_EQ(rest.time.back(), 0.012);
    for (const char* c : {"slider.x", "rod.phi"})
      EXPECT_NEAR(rest[c].back(), whole[c].back(), 1e-5 * (1 + std::abs(whole[c].back()))) << c;
  }
}

TEST(State, AFailedRunSavesAConsistentStateToContinueFrom) {
  // A step budget that runs out mid-run: the saved state is the last point reached, its time
  // and values together, so it satisfies the constraints and a run can continue from it.
  Model m = load_model_file(example_path("flores_slider_crank.yaml"),
                            {"solver.end_time=0.005", "solver.max_steps=300"}).model;
  Workspace ws(m);
  Recorder r(m);
  const RunResult res = simulate(m, ws, r);
  ASSERT_FALSE(res.status.ok);
  EXPECT_LE(res.final_state.t, res.status.t);
  EXPECT_EQ(resume_problem(m, ws, res.final_state), "");
  const double omega = 5000 * 2 * M_PI / 60;
  const int crank = 0;
  EXPECT_NEAR(res.final_state.y[ws.blocks[crank].rot], omega * res.final_state.t, 1e-8);
}

TEST(State, AStateOfAnotherModelIsRefusedWithWhatDiffers) {
  Model flores = load_model_file(example_path("flores_slider_crank.yaml"), {"solver.end_time=0.001"}).model;
  Model ideal = load_model_file(example_path("flores_slider_crank_ideal.yaml")).model;
  Workspace wf(flores), wi(ideal);
  Recorder r(flores);
  const RunResult res = simulate(flores, wf, r);
  const std::string path = ::testing::TempDir() + "lash_state_other.json";
  write_state(path, flores, wf, res.final_state);
  try {
    read_state(path, ideal, wi);
    FAIL() << "accepted a state of another model";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("does not match the model"), std::string::npos) << msg;
    EXPECT_NE(msg.find("rod_slider.impact_velocity"), std::string::npos) << msg;
  }
  // A value of the wrong type is named ("type must be number, but is string" named none).
  const nlohmann::json good = nlohmann::json::parse(std::ifstream(path));
  for (const auto& [key, value, said] : std::vector<std::tuple<std::string, nlohmann::json, std::string>>{
           {"t", "x", "'t' must be a number (s), got \"x\""},
           {"t", true, "'t' must be a number (s), got true"},
           {"step", "1e-6", "'step' must be a number (s)"},
           {"y", nlohmann::json::array({1, "2"}), "entry 1 of 'y' must be a number, got \"2\""},
           {"names", 5, "'names' must be a list of names, got 5"}}) {
    nlohmann::json bad = good;
    bad[key] = value;
    std::ofstream(path) << bad.dump();
    try {
      read_state(path, flores, wf);
      ADD_FAILURE() << "accepted " << key << " = " << value.dump();
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(said), std::string::npos) << e.what();
    }
  }
  // A key given twice (the JSON library keeps the last one) is refused, at any depth.
  std::string text = good.dump();
  for (const auto& [from, to, said] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"{", "{\"t\":0.5,", "'t' is given twice"},
           {"\"modes\":{", "\"modes\":{\"rod_slider\":1,", "'rod_slider' is given twice"}}) {
    std::string twice = text;
    twice.replace(twice.find(from), from.size(), to);
    std::ofstream(path) << twice;
    try {
      read_state(path, flores, wf);
      ADD_FAILURE() << "accepted " << twice;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(said), std::string::npos) << e.what();
    }
  }
  // A negative impact velocity (a run writes |δ̇| >= 0 at onset; the force law would floor it
  // silently) is refused when the run continues.
  {
    std::ofstream(path) << good.dump();
    const State st = read_state(path, flores, wf);
    Model longer = flores;  // the state is at end_time: continued one more millisecond
    longer.solver.end_time = 0.002;
    EXPECT_EQ(resume_problem(longer, wf, st), "");
    State grazing = st;  // an earlier version's located δ̇ a rounding below 0: read as 0
    grazing.y[wf.aux_impact[0]] = -1e-15;
    EXPECT_EQ(resume_problem(longer, wf, grazing), "");
    State neg = st;
    neg.y[wf.aux_impact[0]] = -0.5;
    const std::string said = resume_problem(longer, wf, neg);
    EXPECT_NE(said.find("'rod_slider': the state's impact velocity -0.5 m/s is negative"),
              std::string::npos) << said;
  }
  nlohmann::json no_t = good;
  no_t.erase("t");
  std::ofstream(path) << no_t.dump();
  EXPECT_THROW(
      {
        try {
          read_state(path, flores, wf);
        } catch (const std::runtime_error& e) {
          EXPECT_NE(std::string(e.what()).find("'t' is missing"), std::string::npos) << e.what();
          throw;
        }
      },
      std::runtime_error);
  std::filesystem::remove(path);
}

TEST(State, AClearanceJointsPartThatCannotBeIsRefusedAndAChangedGapIsSaid) {
  // The Flores run ends in contact at 6 ms; its state file records the gap (4 µm).
  Model m = load_model_file(example_path("flores_slider_crank.yaml"), {"solver.end_time=0.006"}).model;
  Workspace ws(m);
  Recorder r(m);
  const RunResult first = simulate(m, ws, r);
  ASSERT_TRUE(first.status.ok);
  const std::string path = ::testing::TempDir() + "lash_state_gaps.json";
  write_state(path, m, ws, first.final_state);
  const State saved = read_state(path, m, ws);
  const std::string path_kept = path + ".edited.json";
  std::filesystem::rename(path, path_kept);
  ASSERT_EQ(saved.gaps.size(), 1u);
  EXPECT_GT(saved.gaps[0], 0.0);  // in contact
  // Continued to 7 ms under the same model: nothing to say.
  Model next = load_model_file(example_path("flores_slider_crank.yaml"), {"solver.end_time=0.007"}).model;
  Workspace wn(next);
  EXPECT_EQ(resume_problem(next, wn, saved), "");
  EXPECT_TRUE(resume_warnings(next, wn, saved).empty());
  // The same state under a model of another name (a file edited by hand, or the wrong one):
  // it runs, and is said.
  EXPECT_EQ(saved.model, "flores_slider_crank");
  Model renamed = next;
  renamed.name = "press";
  const std::vector<std::string> renamed_said = resume_warnings(renamed, wn, saved);
  ASSERT_EQ(renamed_said.size(), 1u);
  EXPECT_EQ(renamed_said[0].find("the continued state was written by model 'flores_slider_crank', "
                                 "and this is 'press'"), 0u) << renamed_said[0];
  // A file without `model` (edited by hand) is said as well; one whose `model` is not a name,
  // or without `modes`, is refused by name (not a JSON library's "key 'modes' not found").
  {
    nlohmann::json j = nlohmann::json::parse(std::ifstream(path_kept));
    j.erase("model");
    std::ofstream(path_kept) << j.dump();
    const State unnamed = read_state(path_kept, m, ws);
    EXPECT_TRUE(unnamed.file_names_no_model);
    const std::vector<std::string> said = resume_warnings(next, wn, unnamed);
    ASSERT_EQ(said.size(), 1u);
    EXPECT_EQ(said[0].find("the continued state names no model that wrote it"), 0u) << said[0];
    EXPECT_FALSE(saved.file_names_no_model);
    // A state made in memory (a study's continuation) names no model and is not said.
    State in_memory = saved;
    in_memory.model.clear();
    EXPECT_TRUE(resume_warnings(next, wn, in_memory).empty());
    for (const auto& [key, value, expected] :
         {std::tuple<const char*, nlohmann::json, const char*>{
              "model", 5, "'model' must be the name of the model that wrote the state, got 5"},
          {"modes", nullptr, "'modes' is missing"},
          {"modes", nlohmann::json::array({1}), "'modes' must map each clearance joint"}}) {
      nlohmann::json bad = j;
      if (value.is_null()) bad.erase(key);
      else bad[key] = value;
      std::ofstream(path_kept) << bad.dump();
      try {
        read_state(path_kept, m, ws);
        ADD_FAILURE() << key << " " << value.dump() << ": read";
      } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
      }
    }
    std::filesystem::remove(path_kept);
  }
  // The slider 5 m away along its guide: the ideal joints hold, the journal cannot be there.
  const int slider = 2;
  State far = saved;
  far.y[ws.blocks[slider].offset] = 5.0;  // its x
  EXPECT_NE(resume_problem(next, wn, far).find("joint 'rod_slider': the journal lies 4.9"),
            std::string::npos)
      << resume_problem(next, wn, far);
  // A step no integrator can take at t = 6 ms.
  State tiny = saved;
  tiny.step = 1e-300;
  EXPECT_NE(resume_problem(next, wn, tiny).find("below the smallest step"), std::string::npos);
  // The same state under a clearance of 0.1 mm instead of 0.5: the journal now starts 0.4 mm
  // inside the wall. Allowed (a continuation may change the clearance), and said.
  Model tighter = load_model_file(example_path("flores_slider_crank.yaml"),
                                  {"solver.end_time=0.007", "joints.rod_slider.clearance=0.1e-3"})
                      .model;
  Workspace wt(tighter);
  EXPECT_EQ(resume_problem(tighter, wt, saved), "");
  Recorder rt(tighter);
  RunOptions from;
  from.from = &saved;
  const RunResult cont = simulate(tighter, wt, rt, {}, {}, from);
  ASSERT_EQ(cont.warnings.size(), 1u);
  EXPECT_NE(cont.warnings[0].find("joint 'rod_slider': the continued state's gap is 0.000404"),
            std::string::npos)
      << cont.warnings[0];
  // Without saved gaps (an older state file, or a state kept in memory) nothing is said.
  State unsaved = saved;
  unsaved.gaps.clear();
  EXPECT_TRUE(resume_warnings(tighter, wt, unsaved).empty());
  // A mode the gap contradicts (edited by hand: free flight 4 µm into the wall) starts as the
  // gap says, and is said; the safety net then has no missed crossing to count.
  State edited = unsaved;
  edited.modes[0].in_contact = false;
  const auto said = resume_warnings(next, wn, edited);
  ASSERT_EQ(said.size(), 1u);
  EXPECT_NE(said[0].find("joint 'rod_slider': the continued state's mode is free flight but its "
                         "gap is 4."),
            std::string::npos)
      << said[0];
  EXPECT_NE(said[0].find("the run starts in contact"), std::string::npos) << said[0];
  from.from = &edited;
  Recorder re(next);
  const RunResult fixed = simulate(next, wn, re, {}, {}, from);
  ASSERT_TRUE(fixed.status.ok) << fixed.status.message;
  EXPECT_EQ(wn.missed_events, 0);
  // Under a clearance 0.1 mm larger the saved contact is 96 µm of free flight: both are said.
  Model looser = load_model_file(example_path("flores_slider_crank.yaml"),
                                 {"solver.end_time=0.007", "joints.rod_slider.clearance=0.6e-3"})
                     .model;
  Workspace wl(looser);
  from.from = &saved;
  Recorder rl(looser);
  const RunResult loose = simulate(looser, wl, rl, {}, {}, from);
  ASSERT_TRUE(loose.status.ok) << loose.status.message;
  ASSERT_EQ(loose.warnings.size(), 2u);
  EXPECT_NE(loose.warnings[0].find("mode is contact but its gap is -9.5"), std::string::npos)
      << loose.warnings[0];
  EXPECT_NE(loose.warnings[1].find("the continued state's gap is -9.5"), std::string::npos)
      << loose.warnings[1];
  EXPECT_EQ(wl.missed_events, 0);
}

TEST(Finalize, ChecksModelsBuiltInCode) {
  Model m;
  m.name = "code";
  Body a;
  a.name = "a";
  a.mass = 1;
  a.inertia = 0.1;
  Body p;
  p.name = "p";
  p.type = BodyType::point_mass;
  p.mass = 0.2;
  p.markers.push_back({"off", Vec2(0.1, 0)});
  m.bodies = {a, p};
  Load torque;
  torque.name = "twist";
  torque.type = LoadType::torque;
  torque.body_a = 1;
  m.loads.push_back(torque);
  Driver d;
  d.name = "spin";
  d.target = DriverTarget::body;
  d.body = 1;
  d.coordinate = BodyCoordinate::phi;
  m.drivers.push_back(d);
  try {
    finalize(m);
    FAIL();
  } catch (const InvalidModel& e) {
    std::vector<std::string> got;
    for (const auto& x : e.problems()) got.push_back(x.element + ": " + x.message);
    ASSERT_EQ(got.size(), 3u) << e.what();
    EXPECT_NE(got[0].find("body 'p': marker 'off' is off the point mass"), std::string::npos) << got[0];
    EXPECT_NE(got[1].find("driver 'spin': body 'p' is a point mass"), std::string::npos) << got[1];
    EXPECT_NE(got[2].find("load 'twist': body 'p' is a point mass: it takes no torque"), std::string::npos) << got[2];
  }
  EXPECT_THROW(Workspace{m}, std::invalid_argument);  // not finalized
}

TEST(Finalize, DerivesStiffnessFromMaterialsAndFreeLengthsFromPoses) {
  // The Hertz cylinder stiffness of the Flores joint, K = 6.610e10 N/m^1.5 for steel, R_B = 10 mm,
  // R_J = 9.5 mm (docs/architecture.md), computed by finalize, not by the loader.
  Model m = load_model_file(example_path("flores_slider_crank.yaml")).model;
  const Joint& j = m.joints[2];
  ASSERT_TRUE(j.clearance);
  EXPECT_NEAR(j.clearance->contact.stiffness / 6.610e10, 1.0, 1e-3);
}

}  // namespace
}  // namespace lash::test
