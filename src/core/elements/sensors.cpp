// Virtual sensors at a point P of a body, along a unit axis fixed in the body or in the ground:
// accelerometer  a = (a_P − g)·u with gravity (specific force, what a real one reads) or a_P·u,
//                a_P = J_P q̈ + a_vel (kinematics.hpp: r̈ + α perp(s) − ω² s on a rigid body);
// velocity probe v = v_P·u;   displacement probe x = r_P·u.
// The three differ only in the quantity read, so they share this file.
#include "core/elements/registry.hpp"

namespace lash::sensors {
namespace {

/// The axis in the ground's frame: fixed there, or turning with the body (on a flexible link,
/// with its axis at the sensor's point).
Vec2 axis_world(const Workspace& ws, const Sensor& s) {
  if (!s.body_axis) return s.axis;
  const BodyKin& k = ws.kin_of(s.at.body);
  if (!k.mesh) return k.A * s.axis;
  return rotation(point_angle(k, point_kin(k, s.at.s))) * s.axis;
}

double acceleration(const Model& m, const Workspace& ws, const Sensor& s) {
  Vec2 a = point_acceleration(point_kin(ws.kin_of(s.at.body), s.at.s), ws.qdd);
  if (s.gravity) a -= m.gravity;
  return a.dot(axis_world(ws, s));
}

double velocity(const Model&, const Workspace& ws, const Sensor& s) {
  return point_kin(ws.kin_of(s.at.body), s.at.s).v.dot(axis_world(ws, s));
}

double displacement(const Model&, const Workspace& ws, const Sensor& s) {
  return point_kin(ws.kin_of(s.at.body), s.at.s).r.dot(axis_world(ws, s));
}

}  // namespace

const SensorKind kAccelerometer{"accelerometer", acceleration, "a", "m/s²",
                                "acceleration along the sensor axis"};
const SensorKind kVelocity{"velocity", velocity, "v", "m/s", "velocity along the sensor axis"};
const SensorKind kDisplacement{"displacement", displacement, "x", "m",
                               "position along the sensor axis"};

}  // namespace lash::sensors
