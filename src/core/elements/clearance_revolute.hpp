#pragma once
/// @file clearance_revolute.hpp
/// The revolute clearance joint: a journal (point a of its joint, radius R_J) inside a bearing
/// (point b, radius R_B = R_J + c). It adds no constraint; it adds contact forces, one event
/// function (the gap), the map applied at an event (mode flip, δ̇⁻, bristle reset) and its
/// auxiliary states: δ̇⁻, and LuGre's bristle deflection z when that law is chosen.
///   e = r_J − r_B, n = e/|e|, δ = |e| − c, δ̇ = ė·n, t = perp(n),
///   v_T = ė·t + R_J ω_J − R_B ω_B.
/// Force on the journal: −F_N n through its centre plus F_T t at its contact point r_J + R_J n;
/// the bearing gets the opposite at r_B + R_B n, so the friction power is exactly F_T v_T.
#include <Eigen/Core>

#include "core/elements/registry.hpp"

namespace lash {

/// Declares the joint's auxiliary states in ws (called by the Workspace constructor).
void clearance_layout(const Model& model, Workspace& ws, int k);

/// Penetration δ and its rate δ̇ of clearance joint k (index into ws.clearance_joints), read
/// directly from y.
void clearance_gap(const Model& model, const Workspace& ws, int k, const double* y, double& delta,
                   double& delta_dot);

/// Contact forces of joint k into ws.g, its energy terms, ws.clearance_out[k], and the rates of
/// its auxiliary states into ydot. ws.kin must hold y's kinematics.
void clearance_forces(const Model& model, Workspace& ws, int k, const double* y, double* ydot);

/// The map applied at a located crossing of joint k's gap: flips the mode; at an onset stores
/// δ̇⁻ = δ̇ and unloads the bristles (z = 0). Returns δ̇ at the crossing.
double clearance_event(const Model& model, Workspace& ws, int k, Eigen::VectorXd& y);

/// Channels of joint k (ws evaluated at y).
void clearance_channels(const Model& model, const Workspace& ws, int k, ChannelSink& s);

}  // namespace lash
