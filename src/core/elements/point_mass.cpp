// Point mass: coordinates [x, y], no orientation; mass block diag(m, m); gravity m g. A body given without `inertia` (absorber masses, pistons, pendulum bobs).
#include "core/elements/registry.hpp"

namespace lash::point_mass {
namespace {

int coordinates(const Body&) { return 2; }

void mass(const Body& b, Eigen::Ref<Eigen::MatrixXd> m) { m(0, 0) = m(1, 1) = b.mass; }

void initial(const Body& b, double* q, double* qd) {
  q[0] = b.r0.x(), q[1] = b.r0.y();
  if (qd) qd[0] = b.v0.x(), qd[1] = b.v0.y();
}

void channels(const Body&, const BodyKin& k, const double* qdd, ChannelSink& s) {
  s.add("x", "m", "x position", k.r.x());
  s.add("y", "m", "y position", k.r.y());
  s.add("vx", "m/s", "x velocity", k.v.x());
  s.add("vy", "m/s", "y velocity", k.v.y());
  s.add("ax", "m/s²", "x acceleration", qdd[0]);
  s.add("ay", "m/s²", "y acceleration", qdd[1]);
}

}  // namespace

const BodyKind kKind{"point_mass", coordinates, mass, initial, point_gravity, channels};

}  // namespace lash::point_mass
