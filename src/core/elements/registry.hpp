#pragma once
/// @file registry.hpp
/// Every element kind of the engine, on one screen. A kind provides only what it has —
/// coordinates and mass (bodies), constraint rows (joints, drivers), applied forces with their
/// potential energy and power (loads), readings (sensors) — and the channels it emits: name,
/// unit, description and value written in one place (`ChannelSink`), read by the CSV, the JSON
/// summary, the report and the figures alike. Clearance joints (gap and event functions, the
/// map applied at an event, auxiliary states) are in clearance_revolute.hpp. Adding a kind: one
/// file in core/elements/, one line in a table below, one test.
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "core/dynamics.hpp"

namespace lash {


/// Collects channels: either their descriptions (once per model) or their values (per output).
/// Elements call add() in a fixed order, so names and values cannot drift apart.
class ChannelSink {
 public:
  explicit ChannelSink(std::vector<ChannelInfo>* info) : info_(info) {}
  explicit ChannelSink(double* values) : values_(values) {}
  /// Prefix of the following channels (an element's name); "" for none.
  void element(const std::string& name) { prefix_ = &name; }
  void add(const char* quantity, const char* unit, const char* description, double value) {
    if (info_)
      describe(quantity, unit, description);
    else
      values_[n_] = value;
    ++n_;
  }
  size_t count() const { return n_; }
  /// True while collecting descriptions: values passed to add() are not read (an element whose
  /// values are costly, or need a state, may pass 0).
  bool describing() const { return info_ != nullptr; }

 private:
  /// The description of the next channel (kept out of add(), which runs at every evaluation).
  [[gnu::noinline]] void describe(const char* quantity, const char* unit, const char* description) {
    info_->push_back({prefix_->empty() ? quantity : *prefix_ + "." + quantity, unit, description});
  }
  std::vector<ChannelInfo>* info_ = nullptr;
  double* values_ = nullptr;
  const std::string* prefix_ = &kNone;
  size_t n_ = 0;
  static inline const std::string kNone;
};

/// Constraint rows being written: Φ, Φ_q and optionally Φ̇ and γ (Φ_q q̈ = γ). A row writes only
/// into the coordinate blocks of its (at most two) bodies, and Φ_q depends on the configuration
/// but not on time: the solver's pattern is what is nonzero at assembly or at configurations
/// drawn around it, at the assembly's time (jacobian_pattern in dynamics.cpp); entries outside
/// it are not read, and entries with one value at all of those configurations are read once.
struct ConstraintOut {
  Eigen::VectorXd& phi;
  Eigen::MatrixXd& phi_q;
  Eigen::VectorXd* phi_dot;
  Eigen::VectorXd* gamma;
};

struct BodyKind {
  const char* name;
  int (*coordinates)(const Body&);
  /// Writes the block's constant mass matrix (coordinates × coordinates, zeroed).
  void (*mass)(const Body&, Eigen::Ref<Eigen::MatrixXd> block);
  /// The block of q (and of q̇ unless null) at the body's initial pose and velocity.
  void (*initial)(const Body&, double* q, double* qd);
  /// Adds the body's own generalised forces (gravity; a flexible link's elastic and damping
  /// forces) to ws.g and their energy to ws.potential / ws.dissipated_power.
  void (*forces)(const Model&, const Body&, const BodyKin&, Workspace&);
  /// Channels from the body's kinematics and its block of q̈.
  void (*channels)(const Body&, const BodyKin&, const double* qdd, ChannelSink&);
};

struct JointKind {
  const char* name;
  int (*rows)(const Model&, const Joint&);
  void (*constrain)(const Model&, const Workspace&, const Joint&, int row, ConstraintOut&);
  /// Reaction channels from the multipliers of its rows.
  void (*channels)(const Model&, const Workspace&, const Joint&, int row, ChannelSink&);
};

struct LoadKind {
  const char* name;
  /// Adds its generalised forces to ws.g, its energy to ws.potential / dissipated_power /
  /// input_power and fills ws.load_out[index].
  void (*apply)(const Model&, Workspace&, const Load&, int index);
  void (*channels)(const Load&, const LoadOutput&, ChannelSink&);
};

struct SensorKind {
  const char* name;
  /// The reading, from the workspace evaluated at (t, y) (its q̈ included).
  double (*read)(const Model&, const Workspace&, const Sensor&);
  const char* quantity;
  const char* unit;
  const char* description;
};

/// Gravity on a body whose block starts with the position of its centre of mass (rigid body,
/// point mass): m g on (x, y), potential −m g·r.
inline void point_gravity(const Model& model, const Body& body, const BodyKin& k, Workspace& ws) {
  ws.g.segment<2>(k.block.offset) += body.mass * model.gravity;
  ws.potential -= body.mass * model.gravity.dot(k.r);
}

// --- the kinds (one file each) -------------------------------------------------------------
namespace rigid_body { extern const BodyKind kKind; }
namespace point_mass { extern const BodyKind kKind; }
namespace flexible_link { extern const BodyKind kKind; }
namespace revolute { extern const JointKind kKind; }
namespace translational { extern const JointKind kKind; }
namespace fixed_joint { extern const JointKind kKind; }
namespace distance { extern const JointKind kKind; }
namespace force_load { extern const LoadKind kKind; }
namespace torque_load { extern const LoadKind kKind; }
namespace spring_damper { extern const LoadKind kKind; }
namespace torsional_spring_damper { extern const LoadKind kKind; }
namespace bushing { extern const LoadKind kKind; }
namespace sensors {
extern const SensorKind kAccelerometer, kVelocity, kDisplacement;
}

/// Tables indexed by the model's enums (BodyType, JointType, LoadType, SensorType).
inline const std::array<const BodyKind*, 3> kBodyKinds{&rigid_body::kKind, &point_mass::kKind,
                                                      &flexible_link::kKind};
inline const std::array<const JointKind*, 4> kJointKinds{
    &revolute::kKind, &translational::kKind, &fixed_joint::kKind, &distance::kKind};
inline const std::array<const LoadKind*, 5> kLoadKinds{
    &force_load::kKind, &torque_load::kKind, &spring_damper::kKind,
    &torsional_spring_damper::kKind, &bushing::kKind};
inline const std::array<const SensorKind*, 3> kSensorKinds{
    &sensors::kAccelerometer, &sensors::kVelocity, &sensors::kDisplacement};

inline const BodyKind& kind_of(const Body& b) { return *kBodyKinds[static_cast<int>(b.type)]; }
inline const JointKind& kind_of(const Joint& j) { return *kJointKinds[static_cast<int>(j.type)]; }
inline const LoadKind& kind_of(const Load& l) { return *kLoadKinds[static_cast<int>(l.type)]; }
inline const SensorKind& kind_of(const Sensor& s) {
  return *kSensorKinds[static_cast<int>(s.type)];
}

// Constraint rows shared by several kinds: core/elements/constraint_rows.hpp.

// --- drivers (driver.cpp) ------------------------------------------------------------------
void driver_constrain(const Model&, const Workspace&, int d, double t, const double* y, int row,
                      ConstraintOut& out);
void driver_channels(const Model&, const Workspace&, int d, ChannelSink&);

/// Every channel of a model in column order (without "time"), listed by the elements of `ws`.
std::vector<ChannelInfo> channel_info(const Model& model, const Workspace& ws);
/// The same for a finalized model, as finalize() listed them (Model::channels); listed anew
/// for a model not finalized.
std::vector<ChannelInfo> channel_info(const Model& model);

/// Fills `values` (size channel_info().size()) from a workspace evaluated at (t, y).
void channel_values(const Model& model, const Workspace& ws, const Eigen::VectorXd& y,
                    double* values);

}  // namespace lash
