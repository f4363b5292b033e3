#pragma once
/// @file finalize.hpp
/// Turns a Model built by the loader or by hand into one a Workspace accepts: checks what the
/// element kinds require and computes the derived values, the same way for every source.
#include <stdexcept>
#include <string>
#include <vector>

#include "core/model.hpp"

namespace lash {

/// One problem found by finalize: the element as "<kind> '<name>'" and what is wrong.
struct ModelProblem {
  std::string element;
  std::string message;
};

/// Thrown by finalize with every problem found.
class InvalidModel : public std::invalid_argument {
 public:
  explicit InvalidModel(std::vector<ModelProblem> problems);
  const std::vector<ModelProblem>& problems() const { return problems_; }

 private:
  std::vector<ModelProblem> problems_;
};

/// A name no element may take: ground, energy, constraint, time (they begin channel names and
/// expressions of their own).
bool reserved_name(const std::string& name);

/// Validates `model` and fills its derived values, then marks it finalized:
/// - contact stiffness K from the two materials when no stiffness is given (Hertz cylinder in
///   hole, core/contact_laws.hpp);
/// - free lengths of springs, rest angles of torsional springs and bushings, lengths of distance
///   joints and initial coordinates of drivers left NaN, from the initial poses;
/// - a sensor's own mass as a point-mass body `<sensor>_mass` pinned at its point by a revolute
///   joint `<sensor>_mount` (exact for a rigidly mounted point mass, which has no rotation).
/// Throws InvalidModel listing every problem (unique names, references in range, kinds that
/// need a rotating body, positive masses, unit axes). Finalizing twice is a no-op.
void finalize(Model& model);

}  // namespace lash
