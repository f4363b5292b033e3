#pragma once
/// @file linear_modes.hpp
/// Natural frequencies of a mechanism linearised at its initial configuration (clearance joints
/// ideal, drivers holding their coordinates where their motions start, at rest, no constraint
/// stabilisation): the eigenvalues of the right-hand side's
/// Jacobian restricted to the tangent space of the constraints (docs/analysis.md, "Linearised
/// mechanism").
#include <atomic>
#include <complex>
#include <optional>
#include <string>
#include <vector>

#include "core/model.hpp"

namespace lash {

struct LinearMode {
  double frequency = 0.0;      ///< undamped natural frequency |λ|/2π, Hz
  double damping_ratio = 0.0;  ///< ζ = −Re λ / |λ|
  std::complex<double> eigenvalue;  ///< λ, 1/s (the one with Im λ ≥ 0 of a pair)
};

/// Where `linear_modes(model, true)` found the static equilibrium.
struct Equilibrium {
  int newton_steps = 0;
  double residual = 0.0;      ///< largest acceleration left in the tangent space, m/s² or rad/s²
  double largest_move = 0.0;  ///< largest position change from the assembled state, m
  std::string largest_move_coordinate;  ///< its name (state_names): a body's or node's x or y
  double largest_turn = 0.0;  ///< largest change of a rigid body's angle, rad
  std::string largest_turn_coordinate;  ///< its name (state_names)
};

struct LinearModes {
  int dof = 0;                    ///< degrees of freedom (nq − rank Φ_q)
  std::vector<LinearMode> modes;  ///< ascending frequency; one per pair of eigenvalues
  std::vector<double> real_rates; ///< real eigenvalues (1/s): overdamped, static or unstable directions
  std::optional<Equilibrium> equilibrium;  ///< set when linearised at the static equilibrium
};

/// A pair of eigenvalues with a damping ratio ζ ≥ 1 − kCriticalShare (|Im λ| below 4.5 % of
/// |λ|) is taken as two real ones: critically damped or beyond, to the linearisation's accuracy.
inline constexpr double kCriticalShare = 1e-3;

/// The mechanism's modes: `model` with every clearance joint made ideal and every driver holding
/// its coordinate at its initial value, assembled (initial_state) and at rest. The Jacobian of
/// the right-hand side (central differences extrapolated to a zero step, balanced before the
/// eigenvalue solve) on a basis (n, 0), (0, n) of the tangent space (n spanning the null space
/// of Φ_q) is exact there: with q̇ = 0 the linearised accelerations of
/// tangent motions satisfy Φ_q δq̈ = 0. Gravity, springs, the links' elasticity and the
/// constraints' curvature (a pendulum's restoring force) all enter. Throws std::runtime_error
/// when the model cannot be assembled or evaluated.
/// With `at_equilibrium`, the linearisation is at the static equilibrium nearest the assembled
/// initial configuration (drivers held, gravity and loads acting, at rest), found by Newton's
/// method on the accelerations in the tangent space; it throws std::runtime_error when there is
/// none (a load along a free direction).
/// `interrupt` (optional) is polled between the linearisation's columns and Newton's steps: when
/// it is set the computation stops with std::runtime_error("interrupted").
LinearModes linear_modes(const Model& model, bool at_equilibrium = false,
                         const std::atomic<int>* interrupt = nullptr);

}  // namespace lash
