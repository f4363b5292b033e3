// Torque load: an expression of time and body state acting on one rotating body, or on a flexible
// link's material at a point (its axis there, kinematics.hpp: apply_point_torque). Its power τω
// is input work.
#include "core/elements/registry.hpp"

namespace lash::torque_load {
namespace {

void apply(const Model&, Workspace& ws, const Load& l, int index) {
  LoadOutput& out = ws.load_out[index];
  out.torque = ws.load_expr[index][0].eval();
  out.power = apply_point_torque(ws.g, point_kin(ws.kin_of(l.body_a), l.a.s), out.torque);
  ws.input_power += out.power;
}

void channels(const Load&, const LoadOutput& o, ChannelSink& s) {
  s.add("torque", "N·m", "applied torque", o.torque);
  s.add("power", "W", "power delivered to the mechanism", o.power);
}

}  // namespace

const LoadKind kKind{"torque", apply, channels};

}  // namespace lash::torque_load
