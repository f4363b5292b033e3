#include "core/friction_laws.hpp"

#include <cmath>

#include "core/adams_functions.hpp"

namespace lash {

namespace {
double sign(double v) { return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0); }
}  // namespace

double coulomb_friction(double v_t, double f_n, const FrictionParams& p) {
  return -p.mu * f_n * sign(v_t);
}

double ambrosio_friction(double v_t, double f_n, const FrictionParams& p) {
  const double speed = std::abs(v_t);
  double c_d = 1.0;
  if (speed <= p.v0)
    c_d = 0.0;
  else if (speed < p.v1)
    c_d = (speed - p.v0) / (p.v1 - p.v0);
  return -p.mu * c_d * f_n * sign(v_t);
}

double adams_stepped_friction(double v_t, double f_n, const FrictionParams& p) {
  const double speed = std::abs(v_t);
  if (speed <= p.v_static)
    return -step(v_t, -p.v_static, -p.mu_static, p.v_static, p.mu_static) * f_n;
  const double mu = speed >= p.v_dynamic
                        ? p.mu_dynamic
                        : step(speed, p.v_static, p.mu_static, p.v_dynamic, p.mu_dynamic);
  return -mu * f_n * sign(v_t);
}

std::optional<FrictionLaw> friction_law_from_name(std::string_view name) {
  for (const auto& info : kFrictionLaws)
    if (info.name == name) return info.law;
  return std::nullopt;
}

std::string_view friction_law_name(FrictionLaw law) {
  for (const auto& info : kFrictionLaws)
    if (info.law == law) return info.name;
  return "?";
}

double friction_force(FrictionLaw law, double v_t, double f_n, const FrictionParams& p) {
  switch (law) {
    case FrictionLaw::none: return 0.0;
    case FrictionLaw::coulomb: return coulomb_friction(v_t, f_n, p);
    case FrictionLaw::ambrosio: return ambrosio_friction(v_t, f_n, p);
    case FrictionLaw::adams_stepped: return adams_stepped_friction(v_t, f_n, p);
  }
  return 0.0;
}

}  // namespace lash
