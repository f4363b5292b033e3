"""Expectations from the contact and friction laws themselves, set beside the numbers of
studies/flores_contact_laws.yaml. Used by studies/results.py.

Hertz's law (K δⁿ) dissipates nothing, so a journal that hits its bearing rebounds with the speed
it came with and keeps bouncing: it should have the most impacts of the five laws. Friction takes
energy out of every contact that slides: with it the journal should settle into contact sooner,
with fewer impacts than without. Each run is one trajectory of an impacting (mostly chaotic)
motion, so these are tendencies checked run by run, not exact values.
"""

LAWS = ["hertz", "hunt_crossley", "lankarani_nikravesh", "flores", "impact"]
FRICTIONS = ["none", "coulomb", "ambrosio"]

COLUMNS = [
    ("rod_slider.Fn.peak", "F_N peak (N)", 1.0, ".0f"),
    ("rod_slider.impacts", "impacts", 1.0, ".0f"),
    ("rod_slider.free_flight_share", "free flight", 1.0, ".3f"),
    ("rod_slider.continuous_share", "continuous", 1.0, ".3f"),
    ("rod_slider.max_impact_velocity", "largest δ̇⁻ (m/s)", 1.0, ".3f"),
    ("slider.ax.peak", "slider a_x peak (m/s²)", 1.0, ".0f"),
    ("distinct_points", "distinct section points", 1.0, ".0f"),
    ("lyapunov_exponent", "Lyapunov exponent (1/s)", 1.0, ".0f"),
]

FIGURES = [
    {"file": "impacts.svg", "title": "Impacts after the transient", "metric": "rod_slider.impacts",
     "ylabel": "impacts", "x": "contact", "series": "friction"},
    {"file": "contact_force_peak.svg", "title": "Contact force peak", "metric": "rod_slider.Fn.peak",
     "ylabel": "N", "x": "contact", "series": "friction"},
]

PREAMBLE = (
    "Metrics after the first 4 of 24 crank revolutions at 5000 rpm, rod–slider clearance 0.5 mm: "
    "peaks exact between outputs, impacts and shares of time as in docs/analysis.md, the largest "
    "Lyapunov exponent by two trajectories.")


def claims(runs):
    m = {(r["params"]["contact"], r["params"]["friction"]): r["metrics"]
         for r in runs if r["status"] == "completed"}
    if not m:
        return ["No completed run: nothing to compare (**unknown**)."]
    out = []
    held, n = 0, 0
    for f in FRICTIONS:
        if ("hertz", f) not in m:
            continue
        others = [m[(law, f)].get("rod_slider.impacts") for law in LAWS[1:] if (law, f) in m]
        if not others:
            continue
        n += 1
        held += m[("hertz", f)].get("rod_slider.impacts", 0) > max(others)
    word = "unknown" if n == 0 else "agrees" if held == n else "agrees in part" if held else "disagrees"
    out.append(f"**Undamped Hertz contact bounces most**: Hertz has more impacts than each of the "
               f"four dissipative laws in {held} of {n} friction cases — **{word}**.")
    pairs = [(m[(law, f)].get("rod_slider.impacts"), m[(law, "none")].get("rod_slider.impacts"))
             for law in LAWS for f in FRICTIONS[1:] if (law, f) in m and (law, "none") in m]
    fewer = sum(1 for a, b in pairs if a is not None and b is not None and a < b)
    word = ("unknown" if not pairs else "agrees" if fewer == len(pairs) else
            "agrees in part" if 2 * fewer >= len(pairs) else "mostly disagrees")
    out.append(f"**Friction means fewer impacts**: with Coulomb or Ambrósio friction the journal "
               f"has fewer impacts than without in {fewer} of {len(pairs)} (law, friction) pairs — "
               f"**{word}**.")
    return out
