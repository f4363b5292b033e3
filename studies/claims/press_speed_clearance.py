"""What examples/press_slider_crank.yaml predicts by hand, set beside the numbers of
studies/press_speed_clearance.yaml. Used by studies/results.py.

The slide's acceleration at top dead centre is r ω² (1 + r/L) downwards; it exceeds g above
ω = sqrt(g / (r (1 + r/L))): 90.2 rpm for r = 0.1 m, L = 1.0 m. Below that speed the joint forces
keep their sense and the journals, once settled, stay on their bearing walls; above it they must
cross their clearance every stroke. The study's press is a representative model (every number an
assumption, stated in the example); its source paper's own numbers are not known to us.
"""
import math

R, L, G = 0.1, 1.0, 9.81
THRESHOLD_RPM = math.sqrt(G / (R * (1 + R / L))) * 60 / (2 * math.pi)
JOINTS = ("crank_rod", "rod_slide")
FREE = 0.05  # a free-flight share above this: the journal leaves its wall every stroke

COLUMNS = [
    ("crank_rod.free_flight_share", "crank–rod free flight", 1.0, ".3f"),
    ("rod_slide.free_flight_share", "rod–slide free flight", 1.0, ".3f"),
    ("crank_rod.continuous_share", "crank–rod continuous", 1.0, ".3f"),
    ("rod_slide.continuous_share", "rod–slide continuous", 1.0, ".3f"),
    ("crank_rod.impacts", "crank–rod impacts", 1.0, ".0f"),
    ("rod_slide.impacts", "rod–slide impacts", 1.0, ".0f"),
    ("crank_rod.Fn.peak", "crank–rod F_N peak (kN)", 1e-3, ".0f"),
    ("rod_slide.Fn.peak", "rod–slide F_N peak (kN)", 1e-3, ".0f"),
    ("slide.ay.peak", "slide a_y peak (m/s²)", 1.0, ".1f"),
]

FIGURES = [
    {"file": "free_flight.svg", "title": "Rod–slide journal: share of time in free flight",
     "metric": "rod_slide.free_flight_share", "ylabel": "share", "x": "drivers.crank.speed_rpm",
     "series": "clearance"},
    {"file": "contact_force_peak.svg", "title": "Rod–slide contact force: peak",
     "metric": "rod_slide.Fn.peak", "ylabel": "N", "x": "drivers.crank.speed_rpm",
     "series": "clearance"},
]

PREAMBLE = (
    "Metrics after the first 2 strokes of 12 s (8 strokes at 40 rpm, 32 at 160 rpm): peaks exact "
    "between outputs, shares of time in free flight, impacts (contact episodes shorter than 10 % "
    "of a stroke) and continuous contact (docs/analysis.md).")


def claims(runs):
    done = [r for r in runs if r["status"] == "completed"]
    if not done:
        return ["No completed run: nothing to compare (**unknown**)."]
    below, above = [], []
    for r in done:
        rpm = float(r["params"]["drivers.crank.speed_rpm"])
        shares = [r["metrics"].get(j + ".free_flight_share") for j in JOINTS]
        if any(s is None for s in shares):
            continue
        (below if rpm < THRESHOLD_RPM else above).append((rpm, r["params"]["clearance"], max(shares)))
    quiet = sum(1 for _, _, s in below if s <= FREE)
    flying = sum(1 for _, _, s in above if s > FREE)
    word = ("agrees" if quiet == len(below) and flying == len(above) else
            "disagrees" if quiet == 0 and flying == 0 else "agrees in part")
    out = [
        f"**The journals leave their walls only above {THRESHOLD_RPM:.1f} rpm** (hand calculation "
        f"in the example: r ω² (1 + r/L) = g). Below it, {quiet} of {len(below)} runs keep both "
        f"journals' free-flight share at or below {FREE:.2f} (largest "
        f"{max((s for _, _, s in below), default=float('nan')):.3f}); above it, {flying} of "
        f"{len(above)} runs exceed it (each run's larger share of its two journals; smallest "
        f"{min((s for _, _, s in above), default=float('nan')):.3f}) — **{word}**."]
    # Clearance and speed raise the peak contact force above the threshold (the source paper's
    # abstract: clearance size and driving speed influence the dynamic behaviour).
    by = {(r["params"]["clearance"], float(r["params"]["drivers.crank.speed_rpm"])): r["metrics"]
          for r in done}
    clears = sorted({c for c, _ in by})
    speeds = sorted({s for _, s in by if s > THRESHOLD_RPM})
    pairs_speed = [(by[(c, a)].get("rod_slide.Fn.peak"), by[(c, b)].get("rod_slide.Fn.peak"))
                   for c in clears for a, b in zip(speeds, speeds[1:]) if (c, a) in by and (c, b) in by]
    pairs_clear = [(by[(a, s)].get("rod_slide.Fn.peak"), by[(b, s)].get("rod_slide.Fn.peak"))
                   for s in speeds for a, b in zip(clears, clears[1:]) if (a, s) in by and (b, s) in by]

    def tally(pairs):
        pairs = [p for p in pairs if None not in p]
        held = sum(1 for a, b in pairs if b > a)
        w = ("unknown" if not pairs else "agrees" if held == len(pairs) else
             "agrees in part" if 2 * held >= len(pairs) else "mostly disagrees")
        return held, len(pairs), w

    hs, ns, ws = tally(pairs_speed)
    hc, nc, wc = tally(pairs_clear)
    out.append(
        f"**Above the threshold, speed and clearance raise the peak contact force** at the wrist "
        f"pin: the next higher speed gives a larger peak in {hs} of {ns} comparisons — **{ws}**; "
        f"the next larger clearance (cases in name order: {', '.join(clears)}) in {hc} of {nc} — "
        f"**{wc}**. Each run is one trajectory of an impacting motion, so single comparisons can "
        f"go either way.")
    return out
