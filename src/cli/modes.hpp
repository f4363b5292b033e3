#pragma once
/// @file modes.hpp
/// `lash modes MODEL`: natural frequencies of each flexible link from its mesh (clamped–free and
/// free–free), beside the Euler–Bernoulli closed forms.
#include <ostream>

#include "core/model.hpp"

namespace lash::cli {

/// Prints the first `count` elastic modes of every flexible link of `model` for each support,
/// then the first `count` modes of the mechanism linearised at its initial configuration, or at
/// the static equilibrium nearest it (`at_equilibrium`, said with where it lies). Returns the
/// number of flexible links. Throws std::runtime_error when the mechanism cannot be assembled
/// or linearised, or has no equilibrium there.
int print_modes(const Model& model, int count, bool at_equilibrium, std::ostream& out);

}  // namespace lash::cli
