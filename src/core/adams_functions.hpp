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

/// IMPACT(x, ẋ, x1, k, e, cmax, d), in Adams' argument order: a one-sided contact that acts
/// while x < x1: max(0, k(x1 − x)^e − STEP(x, x1 − d, cmax, x1, 0)·ẋ); 0 for x ≥ x1.
double impact(double x, double xdot, double x1, double k, double e, double cmax, double d);

/// BISTOP(x, ẋ, x1, x2, k, e, cmax, d): a gap element free on [x1, x2].
/// x < x1:  max(0, k(x1 − x)^e − STEP(x, x1 − d, cmax, x1, 0)·ẋ);
/// x > x2:  min(0, −k(x − x2)^e − STEP(x, x2, 0, x2 + d, cmax)·ẋ);  0 in between.
double bistop(double x, double xdot, double x1, double x2, double k, double e, double cmax,
              double d);

}  // namespace lash
