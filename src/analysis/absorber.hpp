#pragma once
/// @file absorber.hpp
/// Tuned-mass absorber (dynamic vibration absorber) design by Den Hartog's classical rules. A pure
/// function of a few numbers; no model.
///
/// The system: a primary mass M on a spring K (natural frequency ω_p = sqrt(K/M) = 2π f_p, no
/// damping), driven by a harmonic force F0 sin ωt, carries an absorber mass m_a on a spring k_a and
/// a viscous damper c_a. μ = m_a/M, x_st = F0/K. Den Hartog's tuning makes the two invariant
/// points of |X|/x_st (the frequencies where the response is the same for every c_a) equally high
/// and puts the response's maxima near them ("equal peaks"):
///
///   f_opt = ω_a/ω_p = 1/(1+μ),                 ω_a = sqrt(k_a/m_a)
///   ζ_opt = c_a/(2 m_a ω_p) = sqrt(3μ / (8(1+μ)³))
///   k_a = m_a ω_a²,  c_a = 2 ζ_opt m_a ω_p   (= 2 ζ_a m_a ω_a with ζ_a = sqrt(3μ / (8(1+μ))))
///   |X|/x_st at the peaks = sqrt(1 + 2/μ)
///
/// J. P. Den Hartog, Mechanical Vibrations, 4th ed., McGraw-Hill 1956, §3.3; S. S. Rao,
/// Mechanical Vibrations, §9.11. Den Hartog refers the damping ratio to the *primary* frequency
/// (critical damping c_c = 2 m_a ω_p); referred to the absorber's own frequency the same damper
/// has ζ_a = (1+μ) ζ_opt, reported as `absorber_damping_ratio`.
#include <optional>
#include <string>
#include <vector>

namespace lash {

/// Citation of the rules computed by den_hartog_absorber().
inline constexpr const char* kDenHartogCitation =
    "J. P. Den Hartog, Mechanical Vibrations, 4th ed., McGraw-Hill, 1956, §3.3 "
    "(also S. S. Rao, Mechanical Vibrations, §9.11)";

/// What the absorber is designed for. Give exactly one of the two masses; the other follows from
/// the mass ratio.
struct AbsorberInput {
  double mass_ratio = 0.0;              ///< μ = m_a/M, > 0 (typically 0.01 … 0.25)
  double primary_frequency_hz = 0.0;    ///< f_p, natural frequency of the mode to absorb, Hz, > 0
  std::optional<double> primary_mass;   ///< M, kg (modal mass of that mode at the attachment point)
  std::optional<double> absorber_mass;  ///< m_a, kg
};

/// Den Hartog's optimally tuned absorber; SI units.
struct AbsorberDesign {
  double mass_ratio = 0.0;              ///< μ = m_a/M
  double primary_frequency_hz = 0.0;    ///< f_p, Hz
  double primary_mass = 0.0;            ///< M, kg
  double primary_stiffness = 0.0;       ///< K = M ω_p², N/m (the primary as an equivalent spring)
  double absorber_mass = 0.0;           ///< m_a = μ M, kg
  double frequency_ratio = 0.0;         ///< f_opt = ω_a/ω_p = 1/(1+μ)
  double absorber_frequency_hz = 0.0;   ///< tuned frequency f_a = f_opt f_p, Hz
  double damping_ratio = 0.0;           ///< ζ_opt = c_a/(2 m_a ω_p) = sqrt(3μ/(8(1+μ)³))
  double absorber_damping_ratio = 0.0;  ///< ζ_a = c_a/(2 m_a ω_a) = (1+μ) ζ_opt
  double stiffness = 0.0;               ///< k_a = m_a ω_a², N/m
  double damping = 0.0;                 ///< c_a = 2 ζ_opt m_a ω_p, N·s/m
  double peak_amplification = 0.0;      ///< |X|/x_st at the two (equal) peaks = sqrt(1 + 2/μ)
  std::vector<std::string> formulas;    ///< the rules above as text, one per line, with the values
};

/// Den Hartog's tuned-mass absorber for an undamped primary system (see the file comment for the
/// formulas and their source). The peak amplification is the height of the two invariant points,
/// which the true maxima exceed slightly: by 0.1 % at μ = 0.05, 0.4 % at μ = 0.25
/// (tests/test_absorber.cpp).
/// @throws std::invalid_argument "expected …, got …" unless μ and f_p are finite and > 0 and
///         exactly one of the masses is given, finite and > 0.
AbsorberDesign den_hartog_absorber(const AbsorberInput& input);

}  // namespace lash
