#pragma once
/// @file state_file.hpp
/// final_state.json: a run's State at full precision (every double printed with 17 significant
/// digits, which reads back bit for bit), with the names of its entries so a state can be
/// checked against the model it is continued with (`lash run MODEL --from DIR/final_state.json`).
#include <string>

#include "core/simulate.hpp"

namespace lash {

/// Writes `state` to `path` (through a temporary file renamed into place). Throws
/// std::runtime_error if it cannot be written.
void write_state(const std::string& path, const Model& model, const Workspace& ws,
                 const State& state);

/// Reads a state written by write_state and checks it against the model's layout: the same
/// entries with the same names, the same clearance joints. Throws std::runtime_error naming the
/// file and, on a mismatch, what differs.
State read_state(const std::string& path, const Model& model, const Workspace& ws);

}  // namespace lash
