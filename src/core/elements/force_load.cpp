// Force load: (fx, fy) expressions of time and body state, in world axes, at point a. Its
// power f·v_a is input work.
#include "core/elements/registry.hpp"

namespace lash::force_load {
namespace {

void apply(const Model&, Workspace& ws, const Load& l, int index) {
  const PointKin p = point_kin(ws.kin_of(l.a.body), l.a.s);
  const Vec2 f(ws.load_expr[index][0].eval(), ws.load_expr[index][1].eval());
  LoadOutput& out = ws.load_out[index];
  out.force = f;
  out.power = apply_force(ws.g, p, f);
  ws.input_power += out.power;
}

void channels(const Load&, const LoadOutput& o, ChannelSink& s) {
  s.add("Fx", "N", "applied force, x", o.force.x());
  s.add("Fy", "N", "applied force, y", o.force.y());
  s.add("F", "N", "applied force magnitude", magnitude(o.force));
  s.add("power", "W", "power delivered to the mechanism", o.power);
}

}  // namespace

const LoadKind kKind{"force", apply, channels};

}  // namespace lash::force_load
