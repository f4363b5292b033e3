#pragma once
/// @file friction_laws.hpp
/// Tangential (friction) force laws for clearance joints, all on one screen. Each returns the
/// signed tangential force F_T (N) on the journal along the tangent t, given the relative
/// tangential velocity v_T (m/s) of the journal's contact point over the bearing's and the
/// normal force F_N ≥ 0 (N).
/// Friction opposes sliding: F_T · v_T ≤ 0 for the static laws; the dynamic LuGre law obeys it
/// in steady sliding and is dissipative overall (see lugre_friction).
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

/// Ambrósio's modified Coulomb (Ambrósio 2002, "Impact of rigid and flexible multibody
/// systems: deformation description and contact models"): F_T = −μ c_d F_N sign(v_T), with
/// c_d = 0 for |v_T| ≤ v0, (|v_T| − v0)/(v1 − v0) between, 1 for |v_T| ≥ v1.
double ambrosio_friction(double v_t, double f_n, const FrictionParams& p);

/// Adams stepped static/dynamic friction (MSC Adams documentation, friction built from the
/// STEP function; see adams_functions.hpp): μ_d for
/// |v_T| ≥ v_d; STEP(|v_T|, v_s, μ_s, v_d, μ_d) for v_s < |v_T| < v_d; and
/// STEP(v_T, −v_s, −μ_s, v_s, μ_s) through zero for |v_T| ≤ v_s. F_T = −μ(v_T) F_N.
double adams_stepped_friction(double v_t, double f_n, const FrictionParams& p);

// ---------------------------------------------------------------------------------------------
// LuGre dynamic friction (a law with a state)
// ---------------------------------------------------------------------------------------------

/// Parameters of the LuGre law in the form normalised by the normal force F_N: every force of
/// Canudas de Wit et al. (1995) is F_N times the quantity here, so the law follows a varying
/// F_N. Canudas' 1995 values (σ0 = 1e5 N/m, σ1 = √1e5 N·s/m, σ2 = 0.4 N·s/m, F_C = 1 N,
/// F_S = 1.5 N, v_s = 1e-3 m/s) are these numbers with F_N = 1 N, μ_d = 1, μ_s = 1.5.
/// Check with check_lugre_params.
struct LuGreParams {
  double sigma0 = 0.0;      ///< σ0, bristle stiffness per newton of F_N, 1/m (> 0)
  double sigma1 = 0.0;      ///< σ1, bristle (micro-)damping per newton of F_N, s/m (≥ 0)
  double sigma2 = 0.0;      ///< σ2, viscous friction per newton of F_N, s/m (≥ 0)
  double mu_static = 0.0;   ///< μ_s = F_S/F_N, static (breakaway) coefficient (> 0)
  double mu_dynamic = 0.0;  ///< μ_d = F_C/F_N, Coulomb (dynamic) coefficient (> 0)
  double v_stribeck = 0.0;  ///< v_s, Stribeck velocity, m/s (> 0)
  double v_damping = 0.0;   ///< v_d, m/s: σ1(v) = σ1 exp(−(v/v_d)²); 0 keeps σ1 constant
};

/// What lugre_friction returns.
struct LuGreOutput {
  double force = 0.0;           ///< F_T, tangential force on the journal along t, N
  double z_dot = 0.0;           ///< ż, rate of the bristle deflection, m/s
  double bristle_energy = 0.0;  ///< F_N σ0 z²/2, elastic energy in the bristles, J
  double dissipation = 0.0;     ///< D = −F_T v_T − F_N σ0 z ż ≥ 0 when passive (see below), W
};

/// Stribeck curve g(v) = μ_d + (μ_s − μ_d) exp(−(v/v_s)²) (Canudas de Wit et al. 1995, eq. 4,
/// divided by F_N): the steady sliding friction coefficient without the viscous part.
/// Dimensionless, between μ_d and μ_s.
double lugre_stribeck(double v_t, const LuGreParams& p);

/// Micro-damping σ1(v) = σ1 exp(−(v/v_d)²) (Olsson, Åström, Canudas de Wit, Gäfvert,
/// Lischinsky 1998, "Friction models and friction compensation", Eur. J. Control 4(3), the
/// velocity-dependent damping that keeps the model passive); σ1 when v_d = 0. s/m.
double lugre_micro_damping(double v_t, const LuGreParams& p);

/// Coefficient of the passivity bound |v| σ1(v) ≤ 4 g(v) derived at lugre_friction.
inline constexpr double kLuGrePassivityFactor = 4.0;

/// The LuGre friction law (Canudas de Wit, Olsson, Åström, Lischinsky, "A new model for control
/// of systems with friction", IEEE Trans. Automatic Control 40(3), 1995, eqs. 1–5), normalised
/// by the normal force F_N:
///
///   ż   = v − σ0 |v| z / g(v)                               (eq. 1)
///   F   = F_N (σ0 z + σ1(v) ż + σ2 v)                       (eqs. 2–3)
///   F_T = −F                                                (project convention: F_T opposes v)
///
/// with v = v_T the sliding velocity (m/s), z the mean bristle deflection (m), g the Stribeck
/// curve (lugre_stribeck; the paper's Stribeck force F_C + (F_S − F_C) exp(−(v/v_s)²), eq. 4,
/// is F_N g(v) here, and its σ0, σ1, σ2 are F_N times ours) and σ1(v) the micro-damping
/// (lugre_micro_damping). In steady sliding z has the sign of v_T (z > 0 sliding along +t).
///
/// Steady state (eq. 5): at constant v ≠ 0, z → z_ss = v g(v) / (σ0 |v|) = sign(v) g(v)/σ0 at
/// the rate σ0|v|/g(v), and F_T → −F_N (g(v) sign(v) + σ2 v), the Stribeck curve
/// (lugre_steady_state_z, lugre_steady_state_force). |z| ≤ μ_max/σ0, μ_max = max(μ_s, μ_d),
/// holds for all time if it holds at the start (1995, Property 1). For displacements x well
/// below μ_s/σ0 (presliding) F_T ≈ −F_N σ0 x: the bristles act as a spring of stiffness F_N σ0.
///
/// Energy. With E_b = F_N σ0 z²/2 the bristle energy and F_N constant, the power taken from the
/// motion is −F_T v = dE_b/dt + D, and substituting v − ż = σ0|v|z/g gives
///
///   D = F_N (σ0 z (v − ż) + σ1 ż v + σ2 v²)
///     = F_N (a z² + b z ż + c ż² + σ2 v²),  a = σ0²|v|/g, b = σ0 σ1|v|/g, c = σ1.
///
/// The quadratic form in (z, ż) is non-negative iff b² ≤ 4ac, i.e.
///
///   |v| σ1(v) ≤ kLuGrePassivityFactor · g(v),
///
/// which with σ2 ≥ 0 suffices for D ≥ 0 at every (z, v). Since ż is fixed by (z, v), the exact
/// condition follows from D = F_N |v| (g s² − σ1|v| s + (σ1 + σ2)|v|), s = σ0 z sign(v)/g:
/// D ≥ 0 for every z iff σ1(v)² |v| ≤ 4 g(v) (σ1(v) + σ2), the same bound when σ2 = 0. With
/// constant σ1 it fails for |v| > 4 g/σ1 (≈ 0.0126 m/s for Canudas' values), where bristles
/// deflected beyond their steady state (s > 1, e.g. loaded to μ_s/σ0 and then jerked to a speed
/// where g = μ_d) hand back more energy than they release: the flaw Olsson et al. (1998) remove
/// with σ1(v). (Canudas' own stick–slip example stays passive with constant σ1: its breakaway
/// is slow enough for z to follow z_ss.) Because |v| exp(−(v/v_d)²) ≤ v_d/√(2e), any
/// v_d ≤ lugre_passive_v_damping_limit(p) = 4√(2e) min(μ_s, μ_d)/σ1 makes the law passive at
/// every v. When F_N varies, −F_T v = dE_b/dt − Ḟ_N σ0 z²/2 + D: the term Ḟ_N σ0 z²/2 is energy
/// exchanged with the normal load, not friction dissipation; D is still the dissipation.
///
/// Valid for σ0 > 0, μ_s, μ_d > 0, v_s > 0, σ1, σ2, v_d ≥ 0, F_N ≥ 0 (check_lugre_params
/// checks the parameters; this function does not). At F_N = 0 the force is 0 but ż is not: z
/// is kinematic. The caller integrates z; the law is stiff, with the time constant g/(σ0|v|)
/// for z (3e-5 s at 0.3 m/s for Canudas' values) and, on a mass m, the bristle period
/// 2π √(m/(F_N σ0)).
///
/// @param z    bristle deflection, m
/// @param v_t  sliding velocity v_T, m/s
/// @param f_n  normal force F_N ≥ 0, N
LuGreOutput lugre_friction(double z, double v_t, double f_n, const LuGreParams& p);

/// z_ss = sign(v) g(v)/σ0 (m), the bristle deflection of steady sliding at v (1995, eq. 5).
/// At v = 0 every z is stationary; returns 0 there.
double lugre_steady_state_z(double v_t, const LuGreParams& p);

/// F_T,ss = −F_N (g(v) sign(v) + σ2 v) (N), the steady sliding force (1995, eq. 5).
double lugre_steady_state_force(double v_t, double f_n, const LuGreParams& p);

/// 4√(2e) min(μ_s, μ_d)/σ1 (m/s; +∞ when σ1 = 0): with σ1(v) = σ1 exp(−(v/v_d)²), any
/// v_d up to this value satisfies |v| σ1(v) ≤ 4 g(v) at every v, so D ≥ 0 (see lugre_friction).
/// Sufficient; exact when μ_s = μ_d (the worst speed is |v| = v_d/√2).
double lugre_passive_v_damping_limit(const LuGreParams& p);

/// Throws std::invalid_argument naming the offending parameter and its value unless σ0 > 0,
/// σ1 ≥ 0, σ2 ≥ 0, μ_s > 0, μ_d > 0, v_s > 0, v_d ≥ 0, all finite.
void check_lugre_params(const LuGreParams& p);

enum class FrictionLaw { none, coulomb, ambrosio, adams_stepped, lugre };

/// Registry: model-file name of each law, and how many state variables it carries (the engine
/// integrates those; a law with states cannot go through the stateless friction_force).
struct FrictionLawInfo {
  FrictionLaw law;
  std::string_view name;
  int n_states = 0;
};
inline constexpr std::array<FrictionLawInfo, 5> kFrictionLaws{{
    {FrictionLaw::none, "none", 0},
    {FrictionLaw::coulomb, "coulomb", 0},
    {FrictionLaw::ambrosio, "ambrosio", 0},
    {FrictionLaw::adams_stepped, "adams_stepped", 0},
    {FrictionLaw::lugre, "lugre", 1},  // bristle deflection z
}};

std::optional<FrictionLaw> friction_law_from_name(std::string_view name);
std::string_view friction_law_name(FrictionLaw law);
/// Number of state variables of the law (kFrictionLaws' n_states).
int friction_law_states(FrictionLaw law);

/// Dispatches to the named stateless law (none → 0). Throws std::logic_error for a law with
/// states (lugre): call its own function with the state instead.
double friction_force(FrictionLaw law, double v_t, double f_n, const FrictionParams& p);

}  // namespace lash
