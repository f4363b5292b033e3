"""The press with a rigid or a flexible connecting rod (studies/press_rigid_vs_flexible.yaml), at
60 and 120 strokes/min. Used by studies/results.py.

The press paper (a high-speed, heavy-load closed press; Shock and Vibration) states that adding
link flexibility "considerably changes" the response, and cites the mitigating effect of link
flexibility on impact forces. Both are put to the numbers: the change of each peak, and whether
the flexible rod lowers the contact-force peaks. The press is our representative model
(examples/press_slider_crank.yaml states every assumption); the paper's own numbers are not
known to us.
"""

COLUMNS = [
    ("crank_rod.Fn.peak", "crank–rod F_N peak (kN)", 1e-3, ".1f"),
    ("rod_slide.Fn.peak", "rod–slide F_N peak (kN)", 1e-3, ".1f"),
    ("slide.ay.peak", "slide a_y peak (m/s²)", 1.0, ".2f"),
    ("crank_rod.impacts", "crank–rod impacts", 1.0, ".0f"),
    ("rod_slide.impacts", "rod–slide impacts", 1.0, ".0f"),
    ("rod_slide.free_flight_share", "rod–slide free flight", 1.0, ".3f"),
]

FIGURES = [
    {"file": "contact_force_peak.svg", "title": "Rod–slide contact force: peak after the first stroke",
     "metric": "rod_slide.Fn.peak", "ylabel": "N", "x": "drivers.crank.speed_rpm", "series": "rod"},
]

PREAMBLE = ("Metrics after the first stroke of 4 s: peaks exact between outputs, impacts and "
            "free-flight share as in docs/analysis.md.")


def claims(runs):
    m = {(r["params"]["rod"], str(r["params"]["drivers.crank.speed_rpm"])): r["metrics"]
         for r in runs if r["status"] == "completed"}
    speeds = sorted({s for _, s in m}, key=float)
    changes, lower, n = [], 0, 0
    for s in speeds:
        rigid, flex = m.get(("rigid", s)), m.get(("flexible", s))
        if rigid is None or flex is None:
            continue
        parts = []
        for key, what in (("slide.ay.peak", "slide a_y"), ("crank_rod.Fn.peak", "crank–rod F_N"),
                          ("rod_slide.Fn.peak", "rod–slide F_N")):
            a, b = rigid.get(key), flex.get(key)
            if a and b is not None:
                parts.append(f"{what} {100.0 * (b - a) / a:+.0f} %")
                if key.endswith("Fn.peak"):
                    n += 1
                    lower += b < a
        changes.append(f"at {float(s):g} strokes/min: " + ", ".join(parts))
    if n == 0:
        return ["No rigid/flexible pair completed: **unknown**."]
    word = ("agrees" if lower == n else "disagrees" if lower == 0 else "agrees in part")
    return [
        "**Flexibility changes the response** (the paper, in words): peaks of the flexible rod "
        "against the rigid one, " + "; ".join(changes) + ".",
        f"**Link flexibility mitigates the impact forces** (the literature the paper cites): the "
        f"flexible rod has the lower contact-force peak in {lower} of {n} joint-and-speed pairs — "
        f"**{word}**."]
