#include "io/channel_select.hpp"

#include <fnmatch.h>

#include <algorithm>
#include <cctype>
#include <stdexcept>

#include "io/diagnostics.hpp"

namespace lash {

std::vector<std::string> split_channel_patterns(const std::string& list) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= list.size()) {
    const size_t comma = std::min(list.find(',', start), list.size());
    std::string p = list.substr(start, comma - start);
    const auto first = p.find_first_not_of(" \t");
    if (first != std::string::npos) out.push_back(p.substr(first, p.find_last_not_of(" \t") - first + 1));
    start = comma + 1;
  }
  return out;
}

namespace {

/// Whether every `[` of a glob opens a set that a `]` closes (a `]` first in the set, after an
/// optional `!` or `^`, is one of its characters): fnmatch takes an unclosed `[` as itself, so
/// `[a-` would match no channel and be reported as a name not found.
bool sets_closed(const std::string& p) {
  for (size_t i = 0; i < p.size(); ++i) {
    if (p[i] != '[') continue;
    size_t j = i + 1;
    if (j < p.size() && (p[j] == '!' || p[j] == '^')) ++j;
    if (j < p.size() && p[j] == ']') ++j;
    j = p.find(']', j);
    if (j == std::string::npos) return false;
    i = j;
  }
  return true;
}

}  // namespace

std::vector<std::size_t> select_channels(const std::vector<ChannelInfo>& channels,
                                         const std::vector<std::string>& patterns) {
  std::vector<std::size_t> picked;
  if (patterns.empty()) {
    for (std::size_t i = 0; i < channels.size(); ++i) picked.push_back(i);
    return picked;
  }
  std::vector<char> selected(channels.size(), 0);
  std::string unmatched;  // every pattern that matches nothing, each with its closest names
  for (const auto& p : patterns) {
    if (!sets_closed(p))
      throw std::invalid_argument("channel pattern '" + p +
                                  "': a '[' opens a set of characters that no ']' closes");
    bool any = p == "time";  // always written; naming it is not an error
    for (std::size_t i = 0; i < channels.size(); ++i)
      if (fnmatch(p.c_str(), channels[i].name.c_str(), 0) == 0) selected[i] = 1, any = true;
    if (any) continue;
    // The closest names (time among them) by edit distance to the pattern without its
    // wildcards, case ignored: 'TIME' is closest to time, 'Slider.X' to slider.x.
    auto lower = [](std::string w) {
      for (char& c : w) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      return w;
    };
    std::string bare;
    for (char c : p)
      if (c != '*' && c != '?' && c != '[' && c != ']') bare += c;
    bare = lower(bare);
    std::vector<std::string> names;
    for (const auto& c : channels) names.push_back(c.name);
    names.push_back("time");  // last: a tie goes to a channel
    std::vector<std::pair<int, std::size_t>> ranked;
    for (std::size_t i = 0; i < names.size(); ++i)
      ranked.push_back({edit_distance(bare, lower(names[i])), i});
    std::stable_sort(ranked.begin(), ranked.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    std::string closest;
    for (std::size_t k = 0; k < std::min<std::size_t>(3, ranked.size()); ++k)
      closest += (k ? ", " : "") + names[ranked[k].second];
    unmatched += (unmatched.empty() ? "" : "; ") + ("channel pattern '" + p +
                 "' matches no channel (names are case-sensitive); the closest are: " + closest);
  }
  if (!unmatched.empty()) throw std::invalid_argument(unmatched);
  for (std::size_t i = 0; i < channels.size(); ++i)
    if (selected[i]) picked.push_back(i);
  return picked;
}

}  // namespace lash
