// Translational joint (prismatic): body b slides along `axis` fixed in body a. Rows: relative
// angle locked (omitted when the slider is a point mass, which has no angle; on a flexible link
// the angle of its axis at the slider's point) and perp(A_a axis)·(r_b − r_a) = 0.
#include "core/elements/constraint_rows.hpp"

namespace lash::translational {
namespace {

bool locks_angle(const Model& m, const Joint& j) {
  return j.b.body == kGround || m.bodies[j.b.body].rotates() || m.bodies[j.b.body].flexible();
}

int rows(const Model& m, const Joint& j) { return locks_angle(m, j) ? 2 : 1; }

void constrain(const Model& m, const Workspace& ws, const Joint& j, int row, ConstraintOut& out) {
  if (locks_angle(m, j)) angle_row(ws, j.a, j.b, j.angle0, 0, 0, row++, out);
  dot_row(ws, j.a, j.b, perp(j.axis), 0, 0, 0, row, out);
}

void channels(const Model& m, const Workspace& ws, const Joint& j, int row, ChannelSink& s) {
  // Normal force on the slider from the guide: λ of the dot row along the guide's normal.
  const int dot = row + (locks_angle(m, j) ? 1 : 0);
  const Vec2 f = ws.lambda[dot] * perp(ws.kin_of(j.a.body).A * j.axis);
  s.add("Fx", "N", "guide's normal force on the slider, x", f.x());
  s.add("Fy", "N", "guide's normal force on the slider, y", f.y());
  s.add("F", "N", "guide's normal force magnitude", magnitude(f));
}

}  // namespace

const JointKind kKind{"translational", rows, constrain, channels};

}  // namespace lash::translational
