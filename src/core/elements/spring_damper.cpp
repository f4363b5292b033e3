// Translational spring–damper between points a and b: tension f = k(L − L0) + c L̇ along the
// line a→b, potential ½k(L − L0)², dissipated power c L̇².
#include "core/elements/registry.hpp"

namespace lash::spring_damper {
namespace {

void apply(const Model&, Workspace& ws, const Load& l, int index) {
  const PointKin pa = point_kin(ws.kin_of(l.a.body), l.a.s);
  const PointKin pb = point_kin(ws.kin_of(l.b.body), l.b.s);
  const Vec2 d = pb.r - pa.r;
  const double len = d.norm();
  const Vec2 u = len > 0.0 ? Vec2(d / len) : Vec2::UnitX();
  const double len_dot = u.dot(pb.v - pa.v);
  const double stretch = len - l.free_length;
  const double tension = l.stiffness * stretch + l.damping * len_dot;
  LoadOutput& out = ws.load_out[index];
  out.force = -tension * u;  // on body b
  out.power = apply_force(ws.g, pa, tension * u) + apply_force(ws.g, pb, out.force);
  ws.potential += 0.5 * l.stiffness * stretch * stretch;
  ws.dissipated_power += l.damping * len_dot * len_dot;
}

void channels(const Load&, const LoadOutput& o, ChannelSink& s) {
  s.add("Fx", "N", "force on body b, x", o.force.x());
  s.add("Fy", "N", "force on body b, y", o.force.y());
  s.add("F", "N", "force magnitude", magnitude(o.force));
  s.add("power", "W", "power of its forces on the bodies", o.power);
}

}  // namespace

const LoadKind kKind{"spring_damper", apply, channels};

}  // namespace lash::spring_damper
