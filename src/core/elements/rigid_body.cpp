// Rigid body: coordinates [x, y, φ] of its centre of mass and orientation; mass block
// diag(m, m, I); gravity m g at the centre of mass.
#include "core/elements/registry.hpp"

namespace lash::rigid_body {
namespace {

int coordinates(const Body&) { return 3; }

void mass(const Body& b, Eigen::Ref<Eigen::MatrixXd> m) {
  m(0, 0) = m(1, 1) = b.mass;
  m(2, 2) = b.inertia;
}

void initial(const Body& b, double* q, double* qd) {
  q[0] = b.r0.x(), q[1] = b.r0.y(), q[2] = b.phi0;
  if (qd) qd[0] = b.v0.x(), qd[1] = b.v0.y(), qd[2] = b.omega0;
}

void channels(const Body&, const BodyKin& k, const double* qdd, ChannelSink& s) {
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

const BodyKind kKind{"rigid", coordinates, mass, initial, point_gravity, channels};

}  // namespace lash::rigid_body
