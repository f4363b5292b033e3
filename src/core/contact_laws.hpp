#pragma once
/// @file contact_laws.hpp
/// Normal contact force laws for revolute clearance joints, all on one screen
/// (docs/architecture.md, "Clearance joints"; each law cites its paper).
///
/// Symbols: δ penetration (m), δ̇ its rate (m/s, > 0 while approaching), δ̇⁻ the normal approach
/// velocity at the located instant the impact began (m/s, > 0), K generalized stiffness
/// (N/m^n), n the exponent (1.5 for Hertz). Every law returns F_N ≥ 0 in newtons, and 0 for δ ≤ 0.
#include <array>
#include <optional>
#include <string_view>

namespace lash {

/// Parameters shared by the normal laws. Unused fields are ignored by a law.
struct ContactParams {
  double stiffness = 0.0;       ///< K, N/m^n
  double exponent = 1.5;        ///< n, dimensionless
  double restitution = 1.0;     ///< cₑ ∈ (0, 1]
  double damping_max = 0.0;     ///< C_max of the IMPACT law, N·s/m
  double damping_depth = 0.0;   ///< d_max of the IMPACT law, m (> 0)
};

/// Hertz cylinder-in-hole stiffness (Johnson, Contact Mechanics, 1985; as in Meng et al., Shock and Vibration (2015), UHV circuit-breaker mechanism, eq. 9, and Erkaya, Doğan & Ulus, Mech. Mach. Theory 88 (2015), eq. 6–7):
/// K = 4 / (3(σ_B + σ_J)) · sqrt(R_B R_J / (R_B − R_J)), σ_k = (1 − ν_k²)/E_k.
/// Radii in m, moduli in Pa; requires R_B > R_J > 0. Returns N/m^1.5.
double hertz_cylinder_stiffness(double r_bearing, double r_journal, double e_bearing,
                                double nu_bearing, double e_journal, double nu_journal);

/// Hertz (elastic): F_N = K δⁿ.
double hertz(double delta, const ContactParams& p);

/// Hunt–Crossley: F_N = K δⁿ (1 + 3(1 − cₑ)/2 · δ̇/δ̇⁻), clipped at ≥ 0.
double hunt_crossley(double delta, double delta_dot, double delta_dot_impact,
                     const ContactParams& p);

/// Lankarani–Nikravesh (1990; Erkaya, Doğan & Ulus, Mech. Mach. Theory 88 (2015), eq. 5/8): F_N = K δⁿ (1 + 3(1 − cₑ²)/4 · δ̇/δ̇⁻),
/// clipped at ≥ 0.
double lankarani_nikravesh(double delta, double delta_dot, double delta_dot_impact,
                           const ContactParams& p);

/// Flores, Machado, Silva, Martins (2011): F_N = K δⁿ (1 + 8(1 − cₑ)/(5cₑ) · δ̇/δ̇⁻),
/// clipped at ≥ 0.
double flores(double delta, double delta_dot, double delta_dot_impact, const ContactParams& p);

/// Adams IMPACT as a clearance law (MSC Adams; Erkaya, Doğan & Ulus, Mech. Mach. Theory 88 (2015), eq. 9–10; Meng et al., Shock and Vibration (2015), UHV circuit-breaker mechanism, eq. 6–8):
/// F_N = max(0, K δⁿ + STEP(δ, 0, 0, d_max, C_max) · δ̇).
double impact_law(double delta, double delta_dot, const ContactParams& p);

/// The normal laws a model can name.
enum class NormalLaw { hertz, hunt_crossley, lankarani_nikravesh, flores, impact };

/// Registry: model-file name of each law, and whether it reads δ̇⁻.
struct NormalLawInfo {
  NormalLaw law;
  std::string_view name;
  bool needs_impact_velocity;
};
inline constexpr std::array<NormalLawInfo, 5> kNormalLaws{{
    {NormalLaw::hertz, "hertz", false},
    {NormalLaw::hunt_crossley, "hunt_crossley", true},
    {NormalLaw::lankarani_nikravesh, "lankarani_nikravesh", true},
    {NormalLaw::flores, "flores", true},
    {NormalLaw::impact, "impact", false},
}};

std::optional<NormalLaw> normal_law_from_name(std::string_view name);
std::string_view normal_law_name(NormalLaw law);

/// A normal law's force at one instant, with the parts the energy bookkeeping needs.
struct NormalForce {
  double total = 0.0;      ///< F_N of the law, N (≥ 0)
  double elastic = 0.0;    ///< its conservative part K δⁿ, N (the same for every law)
  double potential = 0.0;  ///< elastic energy stored, K δ^(n+1)/(n+1) = K δⁿ · δ/(n+1), J
};

/// The named law at (δ, δ̇, δ̇⁻); all zero for δ ≤ 0. The rest of F_N beyond the elastic part is
/// dissipative.
NormalForce normal_force(NormalLaw law, double delta, double delta_dot, double delta_dot_impact,
                         const ContactParams& p);

}  // namespace lash
