#include "core/friction_laws.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

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

double lugre_stribeck(double v_t, const LuGreParams& p) {
  const double r = v_t / p.v_stribeck;
  return p.mu_dynamic + (p.mu_static - p.mu_dynamic) * std::exp(-r * r);
}

double lugre_micro_damping(double v_t, const LuGreParams& p) {
  if (p.v_damping <= 0.0) return p.sigma1;
  const double r = v_t / p.v_damping;
  return p.sigma1 * std::exp(-r * r);
}

LuGreOutput lugre_friction(double z, double v_t, double f_n, const LuGreParams& p) {
  const double g = lugre_stribeck(v_t, p);
  const double sigma1 = lugre_micro_damping(v_t, p);
  LuGreOutput out;
  // ż = v − σ0|v| z / g(v)  (1995 eq. 1)
  out.z_dot = v_t - p.sigma0 * std::abs(v_t) * z / g;
  // F = F_N (σ0 z + σ1(v) ż + σ2 v), opposing the sliding: F_T = −F  (eqs. 2–3)
  out.force = -f_n * (p.sigma0 * z + sigma1 * out.z_dot + p.sigma2 * v_t);
  out.bristle_energy = 0.5 * f_n * p.sigma0 * z * z;
  // D = −F_T v − F_N σ0 z ż = F_N (σ0 z (v − ż) + σ1 ż v + σ2 v²), with σ0 z (v − ż)
  // written as σ0²|v| z²/g ≥ 0 (no cancellation between v and ż).
  out.dissipation = f_n * (p.sigma0 * p.sigma0 * std::abs(v_t) * z * z / g +
                           sigma1 * out.z_dot * v_t + p.sigma2 * v_t * v_t);
  return out;
}

double lugre_steady_state_z(double v_t, const LuGreParams& p) {
  return sign(v_t) * lugre_stribeck(v_t, p) / p.sigma0;
}

double lugre_steady_state_force(double v_t, double f_n, const LuGreParams& p) {
  return -f_n * (lugre_stribeck(v_t, p) * sign(v_t) + p.sigma2 * v_t);
}

double lugre_passive_v_damping_limit(const LuGreParams& p) {
  if (p.sigma1 <= 0.0) return std::numeric_limits<double>::infinity();
  // max over v of |v| exp(−(v/v_d)²) is v_d/√(2e), at |v| = v_d/√2.
  const double sqrt_2e = std::sqrt(2.0 * std::exp(1.0));
  return kLuGrePassivityFactor * sqrt_2e * std::min(p.mu_static, p.mu_dynamic) / p.sigma1;
}

void check_lugre_params(const LuGreParams& p) {
  const auto require = [](bool ok, const char* name, double value, const char* rule) {
    if (!ok || !std::isfinite(value))
      throw std::invalid_argument(std::string("LuGre friction: ") + name + " must be " + rule +
                                  ", got " + std::to_string(value));
  };
  require(p.sigma0 > 0.0, "sigma0 (1/m)", p.sigma0, "> 0");
  require(p.sigma1 >= 0.0, "sigma1 (s/m)", p.sigma1, ">= 0");
  require(p.sigma2 >= 0.0, "sigma2 (s/m)", p.sigma2, ">= 0");
  require(p.mu_static > 0.0, "mu_static", p.mu_static, "> 0");
  require(p.mu_dynamic > 0.0, "mu_dynamic", p.mu_dynamic, "> 0");
  require(p.v_stribeck > 0.0, "v_stribeck (m/s)", p.v_stribeck, "> 0");
  require(p.v_damping >= 0.0, "v_damping (m/s)", p.v_damping, ">= 0 (0: constant sigma1)");
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

int friction_law_states(FrictionLaw law) {
  for (const auto& info : kFrictionLaws)
    if (info.law == law) return info.n_states;
  return 0;
}

double friction_force(FrictionLaw law, double v_t, double f_n, const FrictionParams& p) {
  switch (law) {
    case FrictionLaw::none: return 0.0;
    case FrictionLaw::coulomb: return coulomb_friction(v_t, f_n, p);
    case FrictionLaw::ambrosio: return ambrosio_friction(v_t, f_n, p);
    case FrictionLaw::adams_stepped: return adams_stepped_friction(v_t, f_n, p);
    case FrictionLaw::lugre:
      throw std::logic_error(
          "friction law 'lugre' has a state (the bristle deflection z): call "
          "lugre_friction(z, v_t, f_n, LuGreParams), not the stateless friction_force");
  }
  return 0.0;
}

}  // namespace lash
