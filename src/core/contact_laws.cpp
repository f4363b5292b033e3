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

double damped_hertz(double delta, double delta_dot, double delta_dot_impact, double factor,
                    const ContactParams& p) {
  if (delta <= 0.0) return 0.0;
  const double elastic = p.stiffness * std::pow(delta, p.exponent);
  return std::max(0.0, elastic * (1.0 + factor * delta_dot / delta_dot_impact));
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
  return delta > 0.0 ? p.stiffness * std::pow(delta, p.exponent) : 0.0;
}

double hunt_crossley(double delta, double delta_dot, double delta_dot_impact,
                     const ContactParams& p) {
  return damped_hertz(delta, delta_dot, delta_dot_impact, hunt_crossley_factor(p.restitution), p);
}

double lankarani_nikravesh(double delta, double delta_dot, double delta_dot_impact,
                           const ContactParams& p) {
  return damped_hertz(delta, delta_dot, delta_dot_impact,
                      lankarani_nikravesh_factor(p.restitution), p);
}

double flores(double delta, double delta_dot, double delta_dot_impact, const ContactParams& p) {
  return damped_hertz(delta, delta_dot, delta_dot_impact, flores_factor(p.restitution), p);
}

double impact_law(double delta, double delta_dot, const ContactParams& p) {
  if (delta <= 0.0) return 0.0;
  const double damping = step(delta, 0.0, 0.0, p.damping_depth, p.damping_max);
  return std::max(0.0, p.stiffness * std::pow(delta, p.exponent) + damping * delta_dot);
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

double normal_force(NormalLaw law, double delta, double delta_dot, double delta_dot_impact,
                    const ContactParams& p) {
  switch (law) {
    case NormalLaw::hertz: return hertz(delta, p);
    case NormalLaw::hunt_crossley: return hunt_crossley(delta, delta_dot, delta_dot_impact, p);
    case NormalLaw::lankarani_nikravesh:
      return lankarani_nikravesh(delta, delta_dot, delta_dot_impact, p);
    case NormalLaw::flores: return flores(delta, delta_dot, delta_dot_impact, p);
    case NormalLaw::impact: return impact_law(delta, delta_dot, p);
  }
  return 0.0;
}

double contact_potential(double delta, const ContactParams& p) {
  if (delta <= 0.0) return 0.0;
  return p.stiffness * std::pow(delta, p.exponent + 1.0) / (p.exponent + 1.0);
}

}  // namespace lash
