#pragma once
/// @file diagnostics.hpp
/// Problems found in a user's model, each pointing into the file:
///   model.yaml:42:7: joint 'rod_slider': clearance must be >= 0, got -0.001
#include <stdexcept>
#include <string>
#include <vector>

namespace lash {

struct Diagnostic {
  std::string file;
  int line = 0;        ///< 1-based; 0 when the value came from a --set override
  int column = 0;      ///< 1-based
  std::string element; ///< e.g. "joint 'rod_slider'"; may be empty
  std::string message;
  std::string str() const;
};

/// Thrown by the loader with every problem found in the model.
class ModelError : public std::runtime_error {
 public:
  explicit ModelError(std::vector<Diagnostic> diagnostics);
  const std::vector<Diagnostic>& diagnostics() const { return diagnostics_; }

 private:
  std::vector<Diagnostic> diagnostics_;
};

/// A file YAML cannot parse (`message` and the 1-based position it gives): the problem as the
/// user should see it. A tab in a line's indentation at or before that position, which YAML
/// forbids and which its parser reports only as "end of map not found" somewhere after, is
/// reported at the tab instead.
Diagnostic yaml_syntax_problem(const std::string& file, const std::string& text, int line,
                               int column, const std::string& message);

/// Levenshtein distance, for "did you mean".
int edit_distance(const std::string& a, const std::string& b);
/// The closest candidate within a small distance, or "".
std::string closest_match(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace lash
