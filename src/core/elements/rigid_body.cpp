// Rigid body: coordinates [x, y, φ] of its centre of mass and orientation; mass block
// diag(m, m, I); kinetic energy ½ m |v|² + ½ I ω².
#include "core/elements/registry.hpp"

namespace lash::rigid_body {
namespace {

void mass_inverse(const Body& b, double* minv) {
  minv[0] = minv[1] = 1.0 / b.mass;
  minv[2] = 1.0 / b.inertia;
}

double kinetic_energy(const Body& b, const BodyKin& k) {
  return 0.5 * (b.mass * k.v.squaredNorm() + b.inertia * k.omega * k.omega);
}

void channels(const BodyKin& k, const double* qdd, ChannelSink& s) {
  s.add("x", "m", "x of the centre of mass", k.r.x());
  s.add("y", "m", "y of the centre of mass", k.r.y());
  s.add("phi", "rad", "orientation", k.phi);
  s.add("vx", "m/s", "x velocity of the centre of mass", k.v.x());
  s.add("vy", "m/s", "y velocity of the centre of mass", k.v.y());
  s.add("omega", "rad/s", "angular velocity", k.omega);
  s.add("ax", "m/s²", "x acceleration of the centre of mass", qdd[0]);
  s.add("ay", "m/s²", "y acceleration of the centre of mass", qdd[1]);
  s.add("alpha", "rad/s²", "angular acceleration", qdd[2]);
}

}  // namespace

const BodyKind kKind{"rigid", 3, mass_inverse, kinetic_energy, channels};

}  // namespace lash::rigid_body
