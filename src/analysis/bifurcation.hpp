#pragma once
/// @file bifurcation.hpp
/// Bifurcation diagrams, model-free: for each value of a swept parameter, the points a Poincaré
/// section collected after the transient. The period of each column is its number of distinct
/// points (count_distinct), and a period doubling is where that number goes from p to 2p
/// between neighbouring parameter values.
#include <vector>

namespace lash {

/// One parameter value of the diagram with its section points (one coordinate).
struct BifurcationColumn {
  double parameter = 0.0;
  std::vector<double> points;
};

/// Period of a column: its distinct points within `tol`, or 0 when there are more than
/// `max_period` of them (or fewer than 2 × that many points to tell: a period-k orbit must
/// show each point twice), i.e. not a periodic orbit this diagram can name.
int column_period(const std::vector<double>& points, double tol, int max_period = 8);

/// A change of period between two neighbouring columns (sorted by parameter).
struct PeriodChange {
  double from_parameter = 0.0, to_parameter = 0.0;  ///< the two columns' parameters
  int from_period = 0, to_period = 0;               ///< 0: not periodic (more than max_period)
  bool doubling() const { return from_period > 0 && to_period == 2 * from_period; }
};

/// Every change of period along the diagram, columns taken in increasing parameter order.
std::vector<PeriodChange> period_changes(std::vector<BifurcationColumn> columns, double tol,
                                         int max_period = 8);

}  // namespace lash
