// Bifurcation diagrams from section points (bifurcation.hpp).
#include "analysis/bifurcation.hpp"

#include <algorithm>

#include "analysis/dynamics_analysis.hpp"

namespace lash {

int column_period(const std::vector<double>& points, double tol, int max_period) {
  if (points.size() < 2) return 0;
  std::vector<std::vector<double>> p;
  p.reserve(points.size());
  for (double v : points) p.push_back({v});
  const int distinct = count_distinct(p, tol);
  if (distinct > max_period) return 0;
  // Each point of a period-k orbit must have come back at least once.
  if (points.size() < 2 * static_cast<size_t>(distinct)) return 0;
  return distinct;
}

std::vector<PeriodChange> period_changes(std::vector<BifurcationColumn> columns, double tol,
                                         int max_period) {
  std::sort(columns.begin(), columns.end(),
            [](const BifurcationColumn& a, const BifurcationColumn& b) { return a.parameter < b.parameter; });
  std::vector<PeriodChange> out;
  for (size_t i = 1; i < columns.size(); ++i) {
    const int a = column_period(columns[i - 1].points, tol, max_period);
    const int b = column_period(columns[i].points, tol, max_period);
    if (a != b) out.push_back({columns[i - 1].parameter, columns[i].parameter, a, b});
  }
  return out;
}

}  // namespace lash
