#pragma once
/// @file adams_functions.hpp
/// Adams-compatible smoothing and contact functions (MSC Adams
/// function reference; as used by Erkaya, Doğan & Ulus, Mech. Mach. Theory 88 (2015), eq. 9–10, and Meng et al., Shock and Vibration (2015), UHV circuit-breaker mechanism, eq. 6–8, 14).
/// All are pure functions of their arguments; units are those of the arguments.

namespace lash {

/// STEP(x, x0, h0, x1, h1): h0 for x ≤ x0, h1 for x ≥ x1, otherwise the cubic
/// h0 + (h1 − h0)Δ²(3 − 2Δ), Δ = (x − x0)/(x1 − x0). Requires x1 > x0.
double step(double x, double x0, double h0, double x1, double h1);

/// STEP5(x, x0, h0, x1, h1): as step() with the quintic h0 + (h1 − h0)Δ³(10 − 15Δ + 6Δ²)
/// (Meng et al., Shock and Vibration (2015), UHV circuit-breaker mechanism, eq. 14), continuous in the second derivative.
double step5(double x, double x0, double h0, double x1, double h1);

/// n-th derivative of step() with respect to x (n ≥ 0; n = 0 is step() itself), exact:
/// (h1 − h0) S⁽ⁿ⁾(Δ) / (x1 − x0)ⁿ inside the ramp x0 < x < x1, with S(Δ) = Δ²(3 − 2Δ),
/// S' = 6Δ(1 − Δ), S'' = 6 − 12Δ, S''' = −12 and S⁽ⁿ⁾ = 0 for n ≥ 4; 0 outside the ramp.
/// At x = x0 and x = x1 it takes the value outside the ramp, as step() does: S' is continuous
/// there (0), S'' jumps (from 0 to ±6). Units: those of h per unit of x to the n.
double step_derivative(int n, double x, double x0, double h0, double x1, double h1);

/// n-th derivative of step5() with respect to x, as step_derivative() with the quintic
/// S = Δ³(10 − 15Δ + 6Δ²): S' = 30Δ²(1 − Δ)², S'' = 60Δ(1 − Δ)(1 − 2Δ), S''' = 60(1 − 6Δ + 6Δ²),
/// S⁽⁴⁾ = 360(2Δ − 1), S⁽⁵⁾ = 720, 0 beyond. S', S'' are continuous at the ends (0); S''' jumps.
double step5_derivative(int n, double x, double x0, double h0, double x1, double h1);

/// IMPACT(x, ẋ, x1, k, e, cmax, d), in Adams' argument order: a one-sided contact that acts
/// while x < x1: max(0, k(x1 − x)^e − STEP(x, x1 − d, cmax, x1, 0)·ẋ); 0 for x ≥ x1.
double impact(double x, double xdot, double x1, double k, double e, double cmax, double d);

/// BISTOP(x, ẋ, x1, x2, k, e, cmax, d): a gap element free on [x1, x2].
/// x < x1:  max(0, k(x1 − x)^e − STEP(x, x1 − d, cmax, x1, 0)·ẋ);
/// x > x2:  min(0, −k(x − x2)^e − STEP(x, x2, 0, x2 + d, cmax)·ẋ);  0 in between.
double bistop(double x, double xdot, double x1, double x2, double k, double e, double cmax,
              double d);

}  // namespace lash
