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

namespace {
// S⁽ⁿ⁾(Δ), n ≥ 1, of the cubic and the quintic (adams_functions.hpp); S itself is in step().
double cubic_shape(int n, double d) {
  switch (n) {
    case 1: return 6.0 * d * (1.0 - d);
    case 2: return 6.0 - 12.0 * d;
    case 3: return -12.0;
    default: return 0.0;
  }
}
double quintic_shape(int n, double d) {
  switch (n) {
    case 1: return 30.0 * d * d * (1.0 - d) * (1.0 - d);
    case 2: return 60.0 * d * (1.0 - d) * (1.0 - 2.0 * d);
    case 3: return 60.0 * (1.0 - 6.0 * d + 6.0 * d * d);
    case 4: return 360.0 * (2.0 * d - 1.0);
    case 5: return 720.0;
    default: return 0.0;
  }
}
// (h1 − h0) S⁽ⁿ⁾(Δ)/(x1 − x0)ⁿ inside the ramp, 0 outside (n ≥ 1).
double ramp_derivative(double (*shape)(int, double), int n, double x, double x0, double h0,
                       double x1, double h1) {
  if (x <= x0 || x >= x1) return 0.0;
  const double len = x1 - x0;
  return (h1 - h0) * shape(n, (x - x0) / len) / std::pow(len, n);
}
}  // namespace

double step_derivative(int n, double x, double x0, double h0, double x1, double h1) {
  if (n <= 0) return step(x, x0, h0, x1, h1);
  return ramp_derivative(cubic_shape, n, x, x0, h0, x1, h1);
}

double step5_derivative(int n, double x, double x0, double h0, double x1, double h1) {
  if (n <= 0) return step5(x, x0, h0, x1, h1);
  return ramp_derivative(quintic_shape, n, x, x0, h0, x1, h1);
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
