#include "core/contact_laws.hpp"

#include <algorithm>
#include <cmath>

#include "core/adams_functions.hpp"

namespace lash {

namespace {
// Hysteresis factors of the damped laws: F_N = K δⁿ (1 + factor(cₑ) · δ̇/δ̇⁻).
double hunt_crossley_factor(double ce) { return 3.0 * (1.0 - ce) / 2.0; }
double lankarani_nikravesh_factor(double ce) { return 3.0 * (1.0 - ce * ce) / 4.0; }
double flores_factor(double ce) { return 8.0 * (1.0 - ce) / (5.0 * ce); }

/// F_N of `law` at δ > 0 from its elastic part K δⁿ, which every law shares.
double from_elastic(NormalLaw law, double elastic, double delta, double delta_dot,
                    double delta_dot_impact, const ContactParams& p) {
  auto damped = [&](double factor) {
    return std::max(0.0, elastic * (1.0 + factor * delta_dot / delta_dot_impact));
  };
  switch (law) {
    case NormalLaw::hertz: return elastic;
    case NormalLaw::hunt_crossley: return damped(hunt_crossley_factor(p.restitution));
    case NormalLaw::lankarani_nikravesh: return damped(lankarani_nikravesh_factor(p.restitution));
    case NormalLaw::flores: return damped(flores_factor(p.restitution));
    case NormalLaw::impact:
      return std::max(
          0.0, elastic + step(delta, 0.0, 0.0, p.damping_depth, p.damping_max) * delta_dot);
  }
  return 0.0;
}
}  // namespace

double hertz_cylinder_stiffness(double r_bearing, double r_journal, double e_bearing,
                                double nu_bearing, double e_journal, double nu_journal) {
  const double sigma_b = (1.0 - nu_bearing * nu_bearing) / e_bearing;
  const double sigma_j = (1.0 - nu_journal * nu_journal) / e_journal;
  return 4.0 / (3.0 * (sigma_b + sigma_j)) *
         std::sqrt(r_bearing * r_journal / (r_bearing - r_journal));
}

double hertz(double delta, const ContactParams& p) {
  return normal_force(NormalLaw::hertz, delta, 0.0, 1.0, p).total;
}

double hunt_crossley(double delta, double delta_dot, double delta_dot_impact,
                     const ContactParams& p) {
  return normal_force(NormalLaw::hunt_crossley, delta, delta_dot, delta_dot_impact, p).total;
}

double lankarani_nikravesh(double delta, double delta_dot, double delta_dot_impact,
                           const ContactParams& p) {
  return normal_force(NormalLaw::lankarani_nikravesh, delta, delta_dot, delta_dot_impact, p)
      .total;
}

double flores(double delta, double delta_dot, double delta_dot_impact, const ContactParams& p) {
  return normal_force(NormalLaw::flores, delta, delta_dot, delta_dot_impact, p).total;
}

double impact_law(double delta, double delta_dot, const ContactParams& p) {
  return normal_force(NormalLaw::impact, delta, delta_dot, 1.0, p).total;
}

std::optional<NormalLaw> normal_law_from_name(std::string_view name) {
  for (const auto& info : kNormalLaws)
    if (info.name == name) return info.law;
  return std::nullopt;
}

std::string_view normal_law_name(NormalLaw law) {
  for (const auto& info : kNormalLaws)
    if (info.law == law) return info.name;
  return "?";
}

NormalForce normal_force(NormalLaw law, double delta, double delta_dot, double delta_dot_impact,
                         const ContactParams& p) {
  if (delta <= 0.0) return {};
  NormalForce f;
  f.elastic = p.stiffness * std::pow(delta, p.exponent);
  f.total = from_elastic(law, f.elastic, delta, delta_dot, delta_dot_impact, p);
  f.potential = f.elastic * delta / (p.exponent + 1.0);
  return f;
}

}  // namespace lash
