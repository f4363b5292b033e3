// Drivers: prescribed motion of one coordinate, coordinate(t) = initial + f(t), as one
// constraint row whose multiplier is the driving torque or force.
// - joint target: revolute θ = φ_a − φ_b (the angle row with a and b swapped; on a flexible link
//   the angle of its axis at the joint) or translational
//   s = (r_b − r_a)·(A_a axis) (the dot row along the axis);
// - body target: x, y or φ of a body relative to the ground (Φ = q_i − initial − f), so the
//   body's own joints may have clearance.
// Profiles: constant speed f = ωt; position f = expression(t); speed ḟ = expression(t), whose
// integral f is the auxiliary state p (ṗ = ḟ). The expressions' time derivatives (ḟ, f̈ of a
// position; f̈ of a speed) are exact, differentiated symbolically when the workspace compiles them
// (core/symbolic_derivatives.hpp).
#include "core/elements/constraint_rows.hpp"

namespace lash {

bool driver_is_rotary(const Model& model, const Driver& d) {
  return d.target == DriverTarget::body ? d.coordinate == BodyCoordinate::phi
                                        : model.joints[d.joint].type == JointType::revolute;
}

void driver_motion(const Model& model, const Workspace& ws, int d, double t, const double* y,
                   double& f, double& fd, double& fdd) {
  const Driver& drv = model.drivers[d];
  switch (drv.profile) {
    case DriverProfile::constant_speed:
      f = drv.speed * t;
      fd = drv.speed;
      fdd = 0.0;
      break;
    case DriverProfile::position: {
      double v[3];  // f, ḟ, f̈
      ws.driver_expr[d]->eval_derivatives(t, v);
      f = v[0], fd = v[1], fdd = v[2];
      break;
    }
    case DriverProfile::speed: {
      double v[2];  // ḟ, f̈
      ws.driver_expr[d]->eval_derivatives(t, v);
      fd = v[0], fdd = v[1];
      f = y[ws.aux_driver[d]];
      break;
    }
  }
  f += drv.initial;
}

void driver_constrain(const Model& model, const Workspace& ws, int d, double t, const double* y,
                      int row, ConstraintOut& out) {
  const Driver& drv = model.drivers[d];
  double f = 0.0, fd = 0.0, fdd = 0.0;
  driver_motion(model, ws, d, t, y, f, fd, fdd);
  if (drv.target == DriverTarget::body) {
    const BodyKin& k = ws.kin_of(drv.body);
    int i = k.block.offset;
    double q = k.r.x(), qd = k.v.x();
    if (drv.coordinate == BodyCoordinate::y) i += 1, q = k.r.y(), qd = k.v.y();
    if (drv.coordinate == BodyCoordinate::phi) i = k.block.rot, q = k.phi, qd = k.omega;
    out.phi[row] = q - f;
    out.phi_q(row, i) += 1.0;
    if (out.phi_dot) (*out.phi_dot)[row] = qd - fd;
    if (out.gamma) (*out.gamma)[row] = fdd;
    return;
  }
  const Joint& j = model.joints[drv.joint];
  if (j.type == JointType::revolute)
    angle_row(ws, j.b, j.a, f, fd, fdd, row, out);  // on a link: its axis at the joint
  else
    dot_row(ws, j.a, j.b, j.axis, f, fd, fdd, row, out);
}

void driver_channels(const Model& model, const Workspace& ws, int d, ChannelSink& s) {
  const double lam = ws.lambda[ws.row_of_driver[d]];
  if (driver_is_rotary(model, model.drivers[d]))
    s.add("torque", "N·m", "driving torque", lam);
  else
    s.add("force", "N", "driving force", lam);
}

}  // namespace lash
