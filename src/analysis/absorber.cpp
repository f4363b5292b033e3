#include "analysis/absorber.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace lash {

namespace {

/// The 3/8 of ζ_opt² = 3μ / (8(1+μ)³): the mean of the two damping values that put the maxima
/// exactly on the left and on the right invariant point (Den Hartog §3.3).
constexpr double kEqualPeaksDampingFactor = 3.0 / 8.0;

/// "%.6g" of v.
std::string g6(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

/// Throws unless v is finite and > 0.
void require_positive(const char* name, double v) {
  if (!(std::isfinite(v) && v > 0))
    throw std::invalid_argument(std::string("den_hartog_absorber: ") + name +
                                ": expected a finite number > 0, got " + g6(v));
}

}  // namespace

AbsorberDesign den_hartog_absorber(const AbsorberInput& in) {
  // Inputs: μ and f_p always, exactly one of the masses.
  require_positive("mass_ratio", in.mass_ratio);
  require_positive("primary_frequency_hz", in.primary_frequency_hz);
  if (in.primary_mass.has_value() == in.absorber_mass.has_value())
    throw std::invalid_argument(
        std::string("den_hartog_absorber: expected exactly one of primary_mass and absorber_mass, "
                    "got ") +
        (in.primary_mass ? "both" : "neither"));
  if (in.primary_mass) require_positive("primary_mass", *in.primary_mass);
  if (in.absorber_mass) require_positive("absorber_mass", *in.absorber_mass);

  AbsorberDesign d;
  const double mu = in.mass_ratio;
  d.mass_ratio = mu;
  d.primary_frequency_hz = in.primary_frequency_hz;
  d.primary_mass = in.primary_mass ? *in.primary_mass : *in.absorber_mass / mu;
  d.absorber_mass = in.absorber_mass ? *in.absorber_mass : mu * *in.primary_mass;
  const double omega_p = 2.0 * M_PI * d.primary_frequency_hz;
  d.primary_stiffness = d.primary_mass * omega_p * omega_p;

  // Equal invariant points: ω_a/ω_p = 1/(1+μ).
  d.frequency_ratio = 1.0 / (1.0 + mu);
  d.absorber_frequency_hz = d.frequency_ratio * d.primary_frequency_hz;
  const double omega_a = d.frequency_ratio * omega_p;
  d.stiffness = d.absorber_mass * omega_a * omega_a;

  // Maxima at the invariant points (on average): ζ_opt, referred to c_c = 2 m_a ω_p.
  d.damping_ratio = std::sqrt(kEqualPeaksDampingFactor * mu / std::pow(1.0 + mu, 3));
  d.damping = 2.0 * d.damping_ratio * d.absorber_mass * omega_p;
  d.absorber_damping_ratio = d.damping / (2.0 * d.absorber_mass * omega_a);

  // Height of both invariant points at the optimal frequency ratio.
  d.peak_amplification = std::sqrt(1.0 + 2.0 / mu);

  const std::string m_line = in.primary_mass ? "m_a = μ M = " + g6(d.absorber_mass) + " kg"
                                             : "M = m_a / μ = " + g6(d.primary_mass) + " kg";
  d.formulas = {
      "μ = m_a / M = " + g6(mu) + ",  ω_p = 2π f_p,  f_p = " + g6(d.primary_frequency_hz) + " Hz",
      m_line,
      "f_opt = ω_a / ω_p = 1 / (1 + μ) = " + g6(d.frequency_ratio),
      "f_a = f_opt f_p = " + g6(d.absorber_frequency_hz) + " Hz",
      "k_a = m_a ω_a² = " + g6(d.stiffness) + " N/m",
      "ζ_opt = c_a / (2 m_a ω_p) = sqrt(3μ / (8 (1 + μ)³)) = " + g6(d.damping_ratio),
      "c_a = 2 ζ_opt m_a ω_p = " + g6(d.damping) + " N·s/m",
      "ζ_a = c_a / (2 m_a ω_a) = (1 + μ) ζ_opt = " + g6(d.absorber_damping_ratio),
      "|X| / x_st at the two peaks = sqrt(1 + 2/μ) = " + g6(d.peak_amplification) +
          "  (x_st = F0 / K, K = M ω_p² = " + g6(d.primary_stiffness) + " N/m)",
  };
  return d;
}

}  // namespace lash
