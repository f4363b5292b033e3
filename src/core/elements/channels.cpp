// The channel list of a model, element by element, in column order: bodies, joints (ideal and
// clearance), drivers, loads, sensors, then energies and the constraint drift. Names, units and
// values come from the element kinds' own channel functions.
#include "core/elements/clearance_revolute.hpp"
#include "core/elements/registry.hpp"

namespace lash {

namespace {

void emit(const Model& model, const Workspace& ws, const Eigen::VectorXd& y, ChannelSink& s) {
  for (int b = 0; b < ws.nb; ++b) {
    const Body& body = model.bodies[b];
    s.element(body.name);
    kind_of(body).channels(body, ws.kin[b], ws.qdd.data() + ws.blocks[b].offset, s);
  }
  int c = 0;
  for (size_t ji = 0; ji < model.joints.size(); ++ji) {
    const Joint& j = model.joints[ji];
    s.element(j.name);
    if (j.clearance)
      clearance_channels(model, ws, c++, s);
    else
      kind_of(j).channels(model, ws, j, ws.row_of_joint[ji], s);
  }
  for (size_t d = 0; d < model.drivers.size(); ++d) {
    s.element(model.drivers[d].name);
    driver_channels(model, ws, static_cast<int>(d), s);
  }
  for (size_t li = 0; li < model.loads.size(); ++li) {
    const Load& l = model.loads[li];
    s.element(l.name);
    kind_of(l).channels(l, ws.load_out[li], s);
  }
  for (const Sensor& sn : model.sensors) {
    s.element(sn.name);
    const SensorKind& k = kind_of(sn);
    s.add(k.quantity, k.unit, k.description, k.read(model, ws, sn));
  }
  static const std::string energy = "energy", constraint = "constraint";
  const double diss = y[ws.i_dissipated], input = y[ws.i_input], stab = y[ws.i_stabilization];
  s.element(energy);
  s.add("kinetic", "J", "kinetic energy", ws.kinetic);
  s.add("potential", "J", "potential energy (gravity, springs, contact)", ws.potential);
  s.add("dissipated", "J", "energy dissipated since t = 0", diss);
  s.add("input", "J", "work of drivers and applied loads since t = 0", input);
  s.add("stabilization", "J",
        "work of the constraint-stabilisation (Baumgarte) forces since t = 0", stab);
  s.add("balance", "J",
        "kinetic + potential + dissipated − input − stabilization (constant up to the "
        "integration error)",
        ws.kinetic + ws.potential + diss - input - stab);
  s.element(constraint);
  s.add("violation", "m", "largest constraint residual |Φ| (m or rad)", ws.constraint_violation);
}

}  // namespace

std::vector<ChannelInfo> channel_info(const Model& model, const Workspace& ws) {
  std::vector<ChannelInfo> info;
  ChannelSink sink(&info);
  emit(model, ws, Eigen::VectorXd::Zero(ws.ny), sink);
  return info;
}

std::vector<ChannelInfo> channel_info(const Model& model) {
  if (model.finalized) return model.channels;
  return channel_info(model, Workspace(model));
}

void channel_values(const Model& model, const Workspace& ws, const Eigen::VectorXd& y,
                    double* values) {
  if (ws.output_row_y && ws.output_row_y == y.data()) {  // the output being delivered
    std::copy(ws.output_row.begin(), ws.output_row.end(), values);
    return;
  }
  ChannelSink sink(values);
  emit(model, ws, y, sink);
}

}  // namespace lash
