#include "bench/floor_slider_crank.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lash::bench {

namespace {

/// Lankarani–Nikravesh hysteresis factor 3(1 − cₑ²)/4 (Lankarani & Nikravesh 1990).
double ln_factor(double ce) { return 3.0 * (1.0 - ce * ce) / 4.0; }

#ifndef LASH_FLOOR_STANDALONE  // the stand-alone floor program (floor_flores) takes no Model
void require(bool ok, const std::string& what) {
  if (!ok) throw std::runtime_error("floor_params_from_model: " + what);
}

bool near(double a, double b) { return std::abs(a - b) <= 1e-12 * std::max(1.0, std::abs(b)); }

/// The joint's other body, given one of its two.
int other(const Joint& j, int body) { return j.a.body == body ? j.b.body : j.a.body; }

/// Marker offset of `body` in joint j (a or b side).
Vec2 offset_on(const Joint& j, int body) { return j.a.body == body ? j.a.s : j.b.s; }

#endif
}  // namespace

#ifndef LASH_FLOOR_STANDALONE
FloorParams floor_params_from_model(const Model& model) {
  FloorParams p;
  require(model.loads.empty(), "the floor has no applied loads");
  require(model.drivers.size() == 1 &&
              model.drivers[0].profile == DriverProfile::constant_speed,
          "expected one constant-speed driver (the crank)");
  require(model.clearance_joint_count() == 1, "expected exactly one clearance joint");
  require(model.solver.integrator == IntegratorKind::dopri5 && model.solver.max_step == 0.0 &&
              model.solver.initial_state == InitialStateRule::ideal,
          "expected dopri5, no max_step and initial_state: ideal");

  // Crank: the driven revolute joint, crank as its journal, ground as its bearing at the origin.
  const Driver& drv = model.drivers[0];
  const Joint& pivot = model.joints[drv.joint];
  require(pivot.type == JointType::revolute && pivot.is_constraint() &&
              pivot.b.body == kGround && pivot.a.body != kGround && pivot.b.s.norm() == 0.0,
          "the driver must turn a revolute joint 'crank.P' in 'ground' at the origin");
  const int crank = pivot.a.body;

  // Clearance joint: journal on the rod, bearing on the slider at the slider's centre of mass.
  const Joint* clear = nullptr;
  const Joint* pin = nullptr;
  const Joint* guide = nullptr;
  for (const Joint& j : model.joints) {
    if (!j.is_constraint()) clear = &j;
    else if (j.type == JointType::translational) guide = &j;
    else if (&j != &pivot && j.type == JointType::revolute &&
             (j.a.body == crank || j.b.body == crank))
      pin = &j;
  }
  require(clear && pin && guide && model.joints.size() == 4,
          "expected joints: crank pivot, crank–rod pin, rod–slider clearance, slider guide");
  const int rod = other(*pin, crank);
  require(rod != kGround && clear->a.body == rod && clear->b.body != kGround &&
              clear->b.body != crank,
          "the clearance joint's journal must be on the rod, its bearing on the slider");
  const int slider = clear->b.body;
  require(clear->b.s.norm() == 0.0, "the bearing must be at the slider's centre of mass");

  // Slider guide: ground to slider along x through the origin, rotation locked at 0.
  require(guide->a.body == kGround && guide->b.body == slider && guide->a.s.norm() == 0.0 &&
              guide->b.s.norm() == 0.0 && guide->axis == Vec2::UnitX() && guide->angle0 == 0.0,
          "the slider must slide along the world x axis through the crank pivot");

  // Crank: length from pivot to pin; θ is the direction of that vector in world.
  const Vec2 d_crank = offset_on(*pin, crank) - pivot.a.s;
  p.crank_length = d_crank.norm();
  p.crank_speed = drv.speed;
  p.crank_angle0 = drv.initial + std::atan2(d_crank.y(), d_crank.x());

  // Rod: pin end A to journal end B along the rod's x axis, centre of mass at mid-length.
  const Vec2 s_A = offset_on(*pin, rod), s_B = clear->a.s;
  require(near(s_A.y(), 0.0) && near(s_B.y(), 0.0) && s_B.x() > s_A.x() &&
              near(s_A.x() + s_B.x(), 0.0),
          "the rod's pin and journal must lie on its x axis, its centre of mass midway");
  p.rod_length = s_B.x() - s_A.x();
  p.rod_mass = model.bodies[rod].mass;
  p.rod_inertia = model.bodies[rod].inertia;
  p.slider_mass = model.bodies[slider].mass;
  p.gx = model.gravity.x();
  p.gy = model.gravity.y();

  const Clearance& cl = *clear->clearance;
  require(cl.normal_law == NormalLaw::lankarani_nikravesh && cl.contact.exponent == 1.5 &&
              cl.friction_law == FrictionLaw::none,
          "the clearance joint must be Lankarani–Nikravesh, exponent 1.5, frictionless");
  p.clearance = cl.clearance;
  p.journal_radius = cl.journal_radius;
  p.stiffness = cl.contact.stiffness;
  p.restitution = cl.contact.restitution;
  p.min_impact_velocity = cl.min_impact_velocity;

  p.rtol = model.solver.rtol;
  p.atol = model.solver.atol;
  p.end_time = model.solver.end_time;
  p.output_interval = model.solver.output_interval;
  return p;
}
#endif

void floor_gap(const FloorParams& p, double t, const double* y, double& delta,
               double& delta_dot) {
  const double th = p.crank_angle0 + p.crank_speed * t;
  const double ct = std::cos(th), st = std::sin(th), cp = std::cos(y[0]), sp = std::sin(y[0]);
  // e = r_J − r_B with r_J = a u(θ) + L u(φ), r_B = (x, 0).
  const double ex = p.crank_length * ct + p.rod_length * cp - y[1];
  const double ey = p.crank_length * st + p.rod_length * sp;
  const double ex_dot = -p.crank_length * p.crank_speed * st - p.rod_length * y[2] * sp - y[3];
  const double ey_dot = p.crank_length * p.crank_speed * ct + p.rod_length * y[2] * cp;
  const double e = std::sqrt(ex * ex + ey * ey);
  delta = e - p.clearance;
  delta_dot = e > 0.0 ? (ex_dot * ex + ey_dot * ey) / e : 0.0;
}

bool floor_rhs(const FloorParams& p, const FloorContact& contact, double t, const double* y,
               double* ydot) {
  const double a = p.crank_length, L = p.rod_length, w = p.crank_speed;
  const double phi = y[0], phi_dot = y[2];
  const double th = p.crank_angle0 + w * t;
  const double ct = std::cos(th), st = std::sin(th), cp = std::cos(phi), sp = std::sin(phi);

  // Rod: inertial term of the accelerating crank pin, ½ m_r a L ω² sin(θ − φ), and gravity
  // m_r g·(L/2) t(φ) with t(φ) = (−sin φ, cos φ).
  const double sin_th_phi = st * cp - ct * sp;
  double q_phi = 0.5 * p.rod_mass * a * L * w * w * sin_th_phi +
                 p.rod_mass * 0.5 * L * (-p.gx * sp + p.gy * cp);
  double q_x = p.slider_mass * p.gx;

  // Clearance contact: journal r_J = a u(θ) + L u(φ), bearing r_B = (x, 0).
  const double ex = a * ct + L * cp - y[1], ey = a * st + L * sp;
  const double e = std::sqrt(ex * ex + ey * ey);
  const double delta = e - p.clearance;
  if (delta > 0.0) {
    const double nx = ex / e, ny = ey / e;
    const double ex_dot = -a * w * st - L * phi_dot * sp - y[3];
    const double ey_dot = a * w * ct + L * phi_dot * cp;
    const double delta_dot = ex_dot * nx + ey_dot * ny;
    // δ̇⁻: the located value in contact; a stage that overshoots an unlocated onset uses δ̇.
    const double v_impact =
        std::max(contact.in_contact ? contact.impact_velocity : delta_dot, p.min_impact_velocity);
    // Lankarani–Nikravesh, n = 1.5: F_N = K δ^1.5 (1 + 3(1 − cₑ²)/4 · δ̇/δ̇⁻), F_N ≥ 0.
    const double f_n = std::max(0.0, p.stiffness * delta * std::sqrt(delta) *
                                         (1.0 + ln_factor(p.restitution) * delta_dot / v_impact));
    // Journal receives −F_N n at its centre, the slider +F_N n at its centre.
    q_phi -= f_n * L * (-nx * sp + ny * cp);
    q_x += f_n * nx;
  }

  const double j_rod = p.rod_inertia + 0.25 * p.rod_mass * L * L;
  ydot[0] = y[2];
  ydot[1] = y[3];
  ydot[2] = q_phi / j_rod;
  ydot[3] = q_x / p.slider_mass;
  return std::isfinite(ydot[2]) && std::isfinite(ydot[3]);
}

FloorResult simulate_floor(const FloorParams& p, FloorObserver& observer) {
  FloorResult result;
  FloorContact contact;

  // Ideal initial state: journal on the guide line (a sin θ + L sin φ = 0) and centred.
  Eigen::VectorXd y(4);
  {
    const double a = p.crank_length, L = p.rod_length, w = p.crank_speed;
    const double th = p.crank_angle0;
    const double phi = -std::asin(a * std::sin(th) / L);
    const double phi_dot = -a * w * std::cos(th) / (L * std::cos(phi));
    y << phi, a * std::cos(th) + L * std::cos(phi), phi_dot,
        -a * w * std::sin(th) - L * std::sin(phi) * phi_dot;
  }

  OdeProblem problem;
  problem.n = 4;
  problem.n_events = 1;
  problem.rhs = [&](double t, const double* yy, double* dy) {
    return floor_rhs(p, contact, t, yy, dy);
  };
  problem.events = [&](double t, const double* yy, double* g) {
    double delta, delta_dot;
    floor_gap(p, t, yy, delta, delta_dot);
    g[0] = contact.in_contact ? -delta : delta;
  };
  auto integrator = make_dopri5(problem, IntegratorOptions{p.rtol, p.atol, 0.0, 50'000'000});

  // Discrete state at t = 0 (a centred journal starts in free flight).
  {
    double delta, delta_dot;
    floor_gap(p, 0.0, y.data(), delta, delta_dot);
    contact = {delta > 0.0, std::abs(delta_dot)};
  }
  integrator->reset(0.0, y);

  // Outputs every interval, and at end_time when it is not a multiple of the interval.
  const long n_out = static_cast<long>(std::ceil(p.end_time / p.output_interval - 1e-9));
  observer.output(0.0, y.data(), contact);
  ++result.outputs;
  for (long k = 1; k <= n_out;) {
    const double t_out = std::min(k * p.output_interval, p.end_time);
    const Advance adv = integrator->advance(t_out, y);
    if (adv.kind == Advance::failure) {
      result.ok = false;
      result.message = "dopri5 failed at t = " + std::to_string(adv.t) + ": " + adv.message;
      break;
    }
    if (adv.kind == Advance::event) {
      // The integrator located g = ±δ rising through zero: flip the mode (also at a round-off
      // crossing, as simulate.cpp does with a single joint); read δ̇⁻ at the crossing.
      double delta, delta_dot;
      floor_gap(p, adv.t, y.data(), delta, delta_dot);
      contact.in_contact = !contact.in_contact;
      if (contact.in_contact) contact.impact_velocity = delta_dot;
      integrator->reset(adv.t, y);
      continue;
    }
    observer.output(t_out, y.data(), contact);
    ++result.outputs;
    double delta, delta_dot;
    floor_gap(p, t_out, y.data(), delta, delta_dot);
    if (!y.allFinite() || delta > p.journal_radius) {
      result.ok = false;
      result.message = "state not finite or journal through its bearing at t = " +
                       std::to_string(t_out);
      break;
    }
    ++k;
  }
  result.stats = integrator->stats();
  return result;
}

}  // namespace lash::bench
