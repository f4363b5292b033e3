// Point mass: coordinates [x, y], no orientation; mass block diag(m, m); kinetic energy
// ½ m |v|². A body given without `inertia` (absorber masses, pistons, pendulum bobs).
#include "core/elements/registry.hpp"

namespace lash::point_mass {
namespace {

void mass_inverse(const Body& b, double* minv) { minv[0] = minv[1] = 1.0 / b.mass; }

double kinetic_energy(const Body& b, const BodyKin& k) { return 0.5 * b.mass * k.v.squaredNorm(); }

void channels(const BodyKin& k, const double* qdd, ChannelSink& s) {
  s.add("x", "m", "x position", k.r.x());
  s.add("y", "m", "y position", k.r.y());
  s.add("vx", "m/s", "x velocity", k.v.x());
  s.add("vy", "m/s", "y velocity", k.v.y());
  s.add("ax", "m/s²", "x acceleration", qdd[0]);
  s.add("ay", "m/s²", "y acceleration", qdd[1]);
}

}  // namespace

const BodyKind kKind{"point_mass", 2, mass_inverse, kinetic_energy, channels};

}  // namespace lash::point_mass
