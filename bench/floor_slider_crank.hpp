#pragma once
/// @file floor_slider_crank.hpp
/// The benchmark floor: the Flores slider-crank (examples/flores_slider_crank.yaml) with its
/// rod–slider clearance joint, written by hand in minimal coordinates.
///
/// The crank angle is prescribed, θ(t) = θ₀ + ω t, and the rod is pinned ideally to the crank
/// pin, so the free coordinates are q = [φ, x]: the rod angle (rad) and the slider position along
/// the guide (m). The ODE state is y = [φ, x, φ̇, ẋ].
///
/// Lagrange (derivation in bench/README.md, "The floor"): with a the crank length, L the rod
/// length, m_r, I_r the rod's mass and inertia about its centre of mass (at mid-length), m_s the
/// slider mass, the kinetic energy
///   T = ½ m_r (a²ω² + (L/2)² φ̇² + a L ω φ̇ cos(θ − φ)) + ½ I_r φ̇² + ½ m_s ẋ²
/// gives a constant diagonal mass matrix M = diag(J_r, m_s), J_r = I_r + m_r L²/4, and
///   J_r φ̈ = ½ m_r a L ω² sin(θ − φ) + Q_φ,     m_s ẍ = Q_x,
/// where Q holds gravity and the clearance contact force as generalized forces:
///   Q_φ = m_r g·(L/2) t(φ) − F_N L n·t(φ),   Q_x = m_s g_x + F_N n_x,
/// t(φ) = (−sin φ, cos φ), n the unit eccentricity (journal centre minus bearing centre).
/// The contact is Lankarani–Nikravesh with exponent 1.5 (Lankarani & Nikravesh 1990), δ̇⁻ read
/// at the located onset, exactly as Lash's engine does (src/core/dynamics.cpp, simulate.cpp).
///
/// Everything is SI. Free functions over an immutable parameter set and a small mutable state,
/// like the engine (STYLE.md §1).
#include <string>

#include "core/integrator.hpp"
#include "core/model.hpp"

namespace lash::bench {

/// Physical and solver parameters of the floor. Built from the Lash model so both solve the
/// same problem (floor_params_from_model).
struct FloorParams {
  double crank_length = 0.0;     ///< a, m (crank pivot to crank pin)
  double crank_speed = 0.0;      ///< ω, rad/s
  double crank_angle0 = 0.0;     ///< θ₀, rad
  double rod_length = 0.0;       ///< L, m (crank pin to journal centre)
  double rod_mass = 0.0;         ///< m_r, kg
  double rod_inertia = 0.0;      ///< I_r about the centre of mass (mid-length), kg·m²
  double slider_mass = 0.0;      ///< m_s, kg
  double gx = 0.0, gy = 0.0;     ///< gravity, m/s²
  double clearance = 0.0;        ///< c = R_B − R_J, m
  double journal_radius = 0.0;   ///< R_J, m (only for the "through the bearing" check)
  double stiffness = 0.0;        ///< K, N/m^1.5
  double restitution = 1.0;      ///< cₑ
  double min_impact_velocity = 1e-3;  ///< floor on δ̇⁻, m/s
  double rtol = 1e-6, atol = 1e-9;
  double end_time = 0.0;         ///< s
  double output_interval = 0.0;  ///< s
};

/// Reads the floor's parameters from a loaded Lash model of the Flores layout (bodies crank,
/// rod, slider; a constant-speed crank driver; one Lankarani–Nikravesh clearance joint between
/// rod and slider with exponent 1.5 and no friction; the slider on the x axis). Throws
/// std::runtime_error naming the first assumption the model breaks.
FloorParams floor_params_from_model(const Model& model);

/// Discrete contact state of the clearance joint, changed only at located events.
struct FloorContact {
  bool in_contact = false;
  double impact_velocity = 0.0;  ///< δ̇⁻ at the located onset, m/s
};

/// Penetration δ = |e| − c (m) and its rate δ̇ = ė·n (m/s) at (t, y).
void floor_gap(const FloorParams& p, double t, const double* y, double& delta, double& delta_dot);

/// ẏ = f(t, y). Returns false if the result is not finite.
bool floor_rhs(const FloorParams& p, const FloorContact& contact, double t, const double* y,
               double* ydot);

/// Receives the state y = [φ, x, φ̇, ẋ] at every output time.
class FloorObserver {
 public:
  virtual ~FloorObserver() = default;
  virtual void output(double t, const double* y) = 0;
  /// The same with the contact state in force at t (for outputs that need the contact force or
  /// the accelerations); by default forwards to output(t, y).
  virtual void output(double t, const double* y, const FloorContact& contact) { output(t, y); }
};

struct FloorResult {
  bool ok = true;
  std::string message;       ///< why it stopped, when !ok
  IntegratorStats stats;     ///< DOPRI5 steps, rejections, rhs evaluations, events
  long outputs = 0;
};

/// Runs the same loop as lash::simulate with DOPRI5: ideal initial state (journal centred,
/// velocities of the ideal mechanism), outputs every output_interval from dense output, contact
/// onsets and separations located as g = ±δ rising through zero, δ̇⁻ stored at onset.
FloorResult simulate_floor(const FloorParams& p, FloorObserver& observer);

}  // namespace lash::bench
