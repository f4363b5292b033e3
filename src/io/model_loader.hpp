#pragma once
/// @file model_loader.hpp
/// Reads a YAML model file (format: docs/model-format.md) into a validated Model. Every problem
/// in the file is collected and thrown together as a ModelError; nothing is run on a bad model.
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/model.hpp"
#include "io/channel_select.hpp"
#include "io/diagnostics.hpp"

namespace lash {

struct LoadedModel {
  Model model;
  std::string resolved_yaml;  ///< the model text after --set overrides, as run
  OutputSettings output;      ///< solver.output_channels, solver.output_format
  /// Where each element is written ("driver 'b'" → 1-based line and column), for the problems
  /// found after loading (assembly: a redundant driver, a loop that does not close); elements
  /// set wholly with --set have none.
  std::map<std::string, std::pair<int, int>> positions;

  /// `message` as a problem of the file: "FILE:LINE:COLUMN: LABEL message" when it opens with
  /// an element written in it ("driver 'b': its equation is redundant ..."), else
  /// "FILE: LABEL message" (LABEL e.g. "warning: ", or none).
  std::string located(const std::string& message, const std::string& label = "") const;
};

/// Loads `path`, applying overrides "dotted.path=value" (e.g. joints.rod_slider.clearance=1e-4)
/// before validation. Throws ModelError (bad model or override) with every problem found.
LoadedModel load_model_file(const std::string& path, const std::vector<std::string>& overrides = {});

/// As load_model_file, from text; `filename` is used in messages.
LoadedModel load_model_text(const std::string& text, const std::string& filename,
                            const std::vector<std::string>& overrides = {});

/// Duplicate keys (with both places) and a second YAML document in `text`, for any YAML file of
/// Lash's (models, studies); empty when there are none.
std::vector<Diagnostic> yaml_structure_problems(const std::string& text, const std::string& filename);

}  // namespace lash
