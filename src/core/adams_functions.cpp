#include "core/adams_functions.hpp"

#include <algorithm>
#include <cmath>

namespace lash {

double step(double x, double x0, double h0, double x1, double h1) {
  if (x <= x0) return h0;
  if (x >= x1) return h1;
  const double d = (x - x0) / (x1 - x0);
  return h0 + (h1 - h0) * d * d * (3.0 - 2.0 * d);
}

double step5(double x, double x0, double h0, double x1, double h1) {
  if (x <= x0) return h0;
  if (x >= x1) return h1;
  const double d = (x - x0) / (x1 - x0);
  return h0 + (h1 - h0) * d * d * d * (10.0 - 15.0 * d + 6.0 * d * d);
}

double impact(double x, double xdot, double x1, double k, double e, double cmax, double d) {
  if (x >= x1) return 0.0;
  const double force = k * std::pow(x1 - x, e) - step(x, x1 - d, cmax, x1, 0.0) * xdot;
  return std::max(0.0, force);
}

double bistop(double x, double xdot, double x1, double x2, double k, double e, double cmax,
              double d) {
  if (x < x1) {
    const double force = k * std::pow(x1 - x, e) - step(x, x1 - d, cmax, x1, 0.0) * xdot;
    return std::max(0.0, force);
  }
  if (x > x2) {
    const double force = -k * std::pow(x - x2, e) - step(x, x2, 0.0, x2 + d, cmax) * xdot;
    return std::min(0.0, force);
  }
  return 0.0;
}

}  // namespace lash
