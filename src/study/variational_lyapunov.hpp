#pragma once
/// @file variational_lyapunov.hpp
/// The Lyapunov spectrum of a model's motion from the variational equations (Benettin et al.
/// 1980) with saltation matrices at contact events (Müller 1995): tangent vectors ride on the
/// accepted steps of one run, restricted to the tangent space of the constraint manifold, so the
/// spectrum has 2·DOF exponents (docs/analysis.md, "Lyapunov exponents").
#include <atomic>

#include "study/run_analysis.hpp"

namespace lash {

/// Weighted length of the forward-difference perturbation of J·v (m, and rad, and s·m/s):
/// about √ε_machine times the mechanism's positions (0.01–1 m), far below clearances.
inline constexpr double kTangentStep = 1e-9;

/// The variational Lyapunov spectrum from the state `y_start` at `t_start`, renormalised every
/// `interval` seconds `intervals` times. Tangent vectors are (δq, δq̇, δ aux) — the energy
/// integrals are left out — and are measured with ‖δq‖² + τ²‖δq̇‖² (m and rad; τ =
/// `time_scale`, s, e.g. period / 2π); auxiliary states are carried, not measured. Returns
/// method "variational", `spectrum` (descending, 1/s), `exponent` = its first entry and the
/// histories; `estimated` false (and nothing run) when the drivers fix every coordinate.
/// `tangent_step` is the forward differences' perturbation length (kTangentStep; other values
/// only to check that the result does not depend on it).
LyapunovEstimate variational_lyapunov(const Model& model, const Eigen::VectorXd& y_start,
                                      double t_start, double interval, int intervals,
                                      double time_scale, const std::atomic<int>* interrupt,
                                      double tangent_step = kTangentStep);

}  // namespace lash
