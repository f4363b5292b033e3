// Revolute joint (ideal pin): r_a = r_b, 2 rows. Its multipliers are the force on body a
// (the journal's) from body b.
#include "core/elements/constraint_rows.hpp"

namespace lash::revolute {
namespace {

int rows(const Model&, const Joint&) { return 2; }

void constrain(const Model&, const Workspace& ws, const Joint& j, int row, ConstraintOut& out) {
  revolute_rows(ws, j.a, j.b, row, out);
}

void channels(const Model&, const Workspace& ws, const Joint&, int row, ChannelSink& s) {
  const Vec2 f = ws.lambda.segment<2>(row);
  s.add("Fx", "N", "reaction on the journal body, x", f.x());
  s.add("Fy", "N", "reaction on the journal body, y", f.y());
  s.add("F", "N", "reaction magnitude", magnitude(f));
}

}  // namespace

const JointKind kKind{"revolute", rows, constrain, channels};

}  // namespace lash::revolute
