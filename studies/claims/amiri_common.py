"""Shared by the claims modules of the Amiri studies (studies/amiri_*.yaml): the statements of
Amiri, Dardel & Daniali, "Effects of passive vibration absorbers on the mechanisms having clearance
joints", Multibody System Dynamics 47 (2019) 363–395, set beside the numbers. Our mechanisms and
absorbers are representative designs (examples/amiri_*.yaml), not the paper's."""


def columns(joint, accel):
    return [
        (f"{accel}.rms", "link acceleration RMS (m/s²)", 1.0, ".4g"),
        (f"{accel}.peak", "link acceleration peak (m/s²)", 1.0, ".4g"),
        (f"{joint}.Fn.peak", "F_N peak (N)", 1.0, ".0f"),
        (f"{joint}.impacts", "impacts", 1.0, ".0f"),
        (f"{joint}.free_flight_share", "free flight", 1.0, ".3f"),
        ("distinct_points", "distinct section points", 1.0, ".0f"),
        ("lyapunov_exponent", "Lyapunov exponent (1/s)", 1.0, ".4g"),
    ]


def figures(title, joint, accel):
    """The with/without study's figures: the link's acceleration and the joint's Poincaré map."""
    return [
        {"kind": "series", "file": "acceleration.svg",
         "title": f"{title}: the link's transverse acceleration, with and without absorbers",
         "channel": accel, "series": "absorbers", "ylabel": "m/s²"},
        {"kind": "section_map", "file": "poincare.svg",
         "title": f"{title}: Poincaré map of the {joint} journal (once per crank revolution)",
         "x_channel": f"{joint}.ex", "y_channel": f"{joint}.ey", "series": "absorbers",
         "xlabel": "eccentricity x (m)", "ylabel": "eccentricity y (m)"},
    ]


def _word(held, n):
    if n == 0:
        return "unknown"
    return ("agrees" if held == n else "disagrees" if held == 0 else
            "agrees in part" if 2 * held >= n else "mostly disagrees")


def absorbers_claims(runs, accel, joint):
    """The with/without study: 'the oscillations are notably reduced' by the two absorbers."""
    m = {r["params"].get("absorbers"): r["metrics"] for r in runs if r["status"] == "completed"}
    if "with" not in m or "without" not in m:
        return ["The with/without pair did not both complete: **unknown**."]
    out = []
    for stat, what in (("rms", "RMS"), ("peak", "peak")):
        a, b = m["with"].get(f"{accel}.{stat}"), m["without"].get(f"{accel}.{stat}")
        if a is None or b is None:
            continue
        change = 100.0 * (a - b) / b
        out.append(f"{what} of the link's transverse acceleration: {b:.4g} m/s² without, "
                   f"{a:.4g} m/s² with the absorbers ({change:+.0f} %)")
    held = sum(1 for stat in ("rms", "peak")
               if m["with"].get(f"{accel}.{stat}") is not None
               and m["without"].get(f"{accel}.{stat}") is not None
               and m["with"][f"{accel}.{stat}"] < m["without"][f"{accel}.{stat}"])
    return ["**Two perpendicular absorbers notably reduce the oscillations** (abstract): "
            + "; ".join(out) + f" — **{_word(held, 2)}** (both lower: agrees)."]


def robustness_claims(runs, accel):
    """The robustness study: 'good robustness with variations to changes in different
    parameters' — each off-design case against the same mechanism without absorbers (at the same
    speed or clearance where the case changes them, else at the design point)."""
    m = {r["params"].get("case"): r["metrics"] for r in runs if r["status"] == "completed"}
    rows, held, n = [], 0, 0
    for case in sorted(m):
        if case.endswith("_without") or case == "design":
            continue
        ref = case + "_without" if case + "_without" in m else "design_without"
        a, b = m[case].get(f"{accel}.rms"), m.get(ref, {}).get(f"{accel}.rms")
        if a is None or b is None:
            continue
        n += 1
        held += a < b
        rows.append(f"{case} {100.0 * (a - b) / b:+.0f} %")
    design = ""
    if "design" in m and "design_without" in m:
        a, b = m["design"].get(f"{accel}.rms"), m["design_without"].get(f"{accel}.rms")
        if a is not None and b is not None:
            design = f" (at the design point: {100.0 * (a - b) / b:+.0f} %)"
    return [f"**The absorbers stay effective away from their design point** (abstract: \"good "
            f"robustness with variations to changes in different parameters\"): the RMS of the "
            f"link's transverse acceleration is lower with the absorbers than without in {held} "
            f"of {n} off-design cases{design} — **{_word(held, n)}**. Change against the same "
            f"mechanism without absorbers: " + ", ".join(rows) + "."]
