#pragma once
/// @file friction_laws.hpp
/// Tangential (friction) force laws for clearance joints, all on one screen
/// (shared/reference/formulas.md, "Friction laws"). Each returns the signed tangential force
/// F_T (N) on the journal along the tangent t, given the relative tangential velocity v_T (m/s)
/// of the journal's contact point over the bearing's and the normal force F_N ≥ 0 (N).
/// Friction opposes sliding: F_T · v_T ≤ 0 always.
#include <array>
#include <optional>
#include <string_view>

namespace lash {

struct FrictionParams {
  double mu = 0.0;        ///< Coulomb / dynamic coefficient (coulomb, ambrosio)
  double v0 = 0.0;        ///< ambrosio: below |v_T| ≤ v0 no friction, m/s
  double v1 = 0.0;        ///< ambrosio: full friction from |v_T| ≥ v1, m/s
  double mu_static = 0.0; ///< adams_stepped μ_s
  double mu_dynamic = 0.0;///< adams_stepped μ_d
  double v_static = 0.0;  ///< adams_stepped v_s, m/s
  double v_dynamic = 0.0; ///< adams_stepped v_d, m/s (> v_s)
};

/// Coulomb: F_T = −μ F_N sign(v_T) (sign(0) = 0). Discontinuous at v_T = 0; prefer ambrosio
/// or adams_stepped for sticking contacts.
double coulomb_friction(double v_t, double f_n, const FrictionParams& p);

/// Ambrósio's modified Coulomb (seed 000): F_T = −μ c_d F_N sign(v_T), with c_d = 0 for
/// |v_T| ≤ v0, (|v_T| − v0)/(v1 − v0) between, 1 for |v_T| ≥ v1.
double ambrosio_friction(double v_t, double f_n, const FrictionParams& p);

/// Adams stepped static/dynamic friction (seed 002 eq. 12, seed 004 eq. 12): μ_d for
/// |v_T| ≥ v_d; STEP(|v_T|, v_s, μ_s, v_d, μ_d) for v_s < |v_T| < v_d; and
/// STEP(v_T, −v_s, −μ_s, v_s, μ_s) through zero for |v_T| ≤ v_s. F_T = −μ(v_T) F_N.
double adams_stepped_friction(double v_t, double f_n, const FrictionParams& p);

enum class FrictionLaw { none, coulomb, ambrosio, adams_stepped };

struct FrictionLawInfo {
  FrictionLaw law;
  std::string_view name;
};
inline constexpr std::array<FrictionLawInfo, 4> kFrictionLaws{{
    {FrictionLaw::none, "none"},
    {FrictionLaw::coulomb, "coulomb"},
    {FrictionLaw::ambrosio, "ambrosio"},
    {FrictionLaw::adams_stepped, "adams_stepped"},
}};

std::optional<FrictionLaw> friction_law_from_name(std::string_view name);
std::string_view friction_law_name(FrictionLaw law);

/// Dispatches to the named law (none → 0).
double friction_force(FrictionLaw law, double v_t, double f_n, const FrictionParams& p);

}  // namespace lash
