#include "io/diagnostics.hpp"

#include <algorithm>
#include <numeric>

namespace lash {

std::string Diagnostic::str() const {
  std::string s = file;
  if (line > 0) s += ":" + std::to_string(line) + ":" + std::to_string(column);
  s += ": ";
  if (!element.empty()) s += element + ": ";
  return s + message;
}

namespace {
std::string join(const std::vector<Diagnostic>& d) {
  std::string s;
  for (const auto& x : d) s += x.str() + "\n";
  return s;
}
}  // namespace

ModelError::ModelError(std::vector<Diagnostic> diagnostics)
    : std::runtime_error(join(diagnostics)), diagnostics_(std::move(diagnostics)) {}

Diagnostic yaml_syntax_problem(const std::string& file, const std::string& text, int line,
                               int column, const std::string& message) {
  int n = 1;
  for (size_t start = 0; start < text.size() && n <= line + 1; ++n) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    size_t first = start;  // the line's first character that is not indentation
    while (first < end && (text[first] == ' ' || text[first] == '\t')) ++first;
    const bool content = first < end && text[first] != '#' && text[first] != '\r';
    for (size_t i = start; content && i < first; ++i)
      if (text[i] == '\t')
        return {file, n, static_cast<int>(i - start) + 1, "",
                "not valid YAML: a tab in the indentation (YAML indents with spaces only; the "
                "parser said '" + message + "' at " + std::to_string(line) + ":" +
                    std::to_string(column) + ")"};
    start = end + 1;
  }
  return {file, line, column, "", "not valid YAML: " + message};
}

int edit_distance(const std::string& a, const std::string& b) {
  std::vector<int> prev(b.size() + 1), cur(b.size() + 1);
  std::iota(prev.begin(), prev.end(), 0);
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = static_cast<int>(i);
    for (size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1])});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string closest_match(const std::string& word, const std::vector<std::string>& candidates) {
  // Close enough to be a typo: at most a third of the word (at least one edit), and never a
  // change of the whole word (no 'A' for 'C').
  std::string best;
  int best_d = std::max<int>(1, static_cast<int>(word.size()) / 3) + 1;
  for (const auto& c : candidates) {
    const int d = edit_distance(word, c);
    if (d < best_d && d < static_cast<int>(std::min(word.size(), c.size()))) {
      best_d = d;
      best = c;
    }
  }
  return best;
}

}  // namespace lash
