// Fixed joint (weld): r_a = r_b and φ_b − φ_a = angle0, 3 rows. With a flexible link on one side
// (a clamped end) the angle row keeps the link's slope at the point parallel to a direction fixed
// in the other body (slope_row).
#include "core/elements/constraint_rows.hpp"

namespace lash::fixed_joint {
namespace {

int rows(const Model&, const Joint&) { return 3; }

void constrain(const Model&, const Workspace& ws, const Joint& j, int row, ConstraintOut& out) {
  revolute_rows(ws, j.a, j.b, row, out);
  if (ws.kin_of(j.a.body).mesh || ws.kin_of(j.b.body).mesh)
    slope_row(ws, j.a, j.b, j.angle0, row + 2, out);
  else
    angle_row(ws, j.a, j.b, j.angle0, 0, 0, row + 2, out);
}

void channels(const Model&, const Workspace& ws, const Joint&, int row, ChannelSink& s) {
  const Vec2 f = ws.lambda.segment<2>(row);
  s.add("Fx", "N", "reaction on body a, x", f.x());
  s.add("Fy", "N", "reaction on body a, y", f.y());
  s.add("F", "N", "reaction magnitude", magnitude(f));
}

}  // namespace

const JointKind kKind{"fixed", rows, constrain, channels};

}  // namespace lash::fixed_joint
