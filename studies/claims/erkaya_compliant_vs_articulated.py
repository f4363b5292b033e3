"""The statements of Erkaya, Doğan & Ulus (Mechanism and Machine Theory 88 (2015) 125–140) set
beside the numbers of studies/erkaya_compliant_vs_articulated.yaml. Used by studies/results.py.

Every verdict below is computed from the runs; the paper's statements are quoted as text, with
their section, never as numbers of ours. Case names follow the study file: mechanism cases
MECHANISM_cCLEARANCE_MM (e.g. articulated_c0.50), speed cases rpmSPEED (e.g. rpm200).
"""
import re

SENSORS = ["acc1", "acc2", "acc3", "acc4", "acc5"]
SENSOR_WORDS = {"acc1": "1 (crank bearing, x)", "acc2": "2 (crank bearing, y)",
                "acc3": "3 (piston guide, y)", "acc4": "4 (piston, x)", "acc5": "5 (rod, ⊥)"}

COLUMNS = [
    ("crank_rod.Fn.peak", "crank–rod F_N peak (N)", 1.0, ".0f"),
    ("rod_piston.Fn.peak", "rod–piston F_N peak (N)", 1.0, ".0f"),
    ("crank_pivot.F.peak", "F21 peak (N)", 1.0, ".0f"),
    ("piston_guide.F.peak", "F41 peak (N)", 1.0, ".0f"),
    ("acc1.a.rms", "a1 RMS (m/s²)", 1.0, ".3g"),
    ("acc2.a.rms", "a2 RMS", 1.0, ".3g"),
    ("acc3.a.rms", "a3 RMS", 1.0, ".3g"),
    ("acc4.a.rms", "a4 RMS", 1.0, ".3g"),
    ("acc5.a.rms", "a5 RMS", 1.0, ".3g"),
    ("acc5.a.peak", "a5 peak", 1.0, ".3g"),
    ("crank_rod.impacts", "crank–rod impacts", 1.0, ".0f"),
    ("rod_piston.impacts", "rod–piston impacts", 1.0, ".0f"),
    ("crank_rod.free_flight_share", "crank–rod free flight", 1.0, ".3f"),
    ("crank_rod.continuous_share", "crank–rod continuous", 1.0, ".3f"),
    ("distinct_points", "distinct section points", 1.0, ".0f"),
    ("sections", "sections", 1.0, ".0f"),
]

FIGURES = [
    {"file": "sensor5_rms.svg", "title": "Sensor 5 (rod, perpendicular): RMS acceleration",
     "metric": "acc5.a.rms", "ylabel": "m/s²", "x": "speed", "series": "mechanism"},
    {"file": "f21_peak.svg", "title": "Crank–frame bearing force F21: peak",
     "metric": "crank_pivot.F.peak", "ylabel": "N", "x": "speed", "series": "mechanism"},
]

PREAMBLE = (
    "Metrics after the first 3 of 10 crank revolutions: peaks exact between outputs, RMS over "
    "the outputs (every 50 µs). F21 = `crank_pivot.F` (crank–frame bearing force), F41 = "
    "`piston_guide.F` (piston–frame normal force), a1…a5 the paper's five accelerometers "
    "(kinematic acceleration, 25 g each). Sensors 1–3 sit on bearing housings whose mounts are "
    "assumed (examples/erkaya_articulated.yaml), so their values are not the paper's; only their "
    "trends are compared. Impacts are counted over the 7 revolutions kept; 'continuous' is the "
    "share of time in contact episodes longer than 10 % of a revolution (docs/analysis.md).")


def _key(run):
    """(mechanism, clearance in mm, speed in rpm) from the case names, or None."""
    m = re.fullmatch(r"(articulated|compliant)_c([0-9.]+)", str(run["params"].get("mechanism")))
    s = re.fullmatch(r"rpm([0-9.]+)", str(run["params"].get("speed")))
    if not m or not s:
        return None
    return m.group(1), float(m.group(2)), float(s.group(1))


def _tally(pairs):
    """How many (smaller, larger) pairs hold, and the verdict word for it."""
    pairs = [p for p in pairs if p[0] is not None and p[1] is not None]
    held = sum(1 for a, b in pairs if b > a)
    n = len(pairs)
    if n == 0:
        return 0, 0, "unknown (no completed pair)"
    word = "agrees" if held == n else ("disagrees" if held == 0 else
                                       "agrees in part" if 2 * held >= n else "mostly disagrees")
    return held, n, word


def _impacts(met):
    return sum(met.get(j + ".impacts", 0.0) for j in ("crank_rod", "rod_piston"))


def _peak_contact(met):
    v = [met.get(j + ".Fn.peak") for j in ("crank_rod", "rod_piston")]
    v = [x for x in v if x is not None]
    return max(v) if v else None


def claims(runs):
    data = {}
    for r in runs:
        k = _key(r)
        if k and r["status"] == "completed":
            data[k] = r["metrics"]
    mechs = sorted({k[0] for k in data})
    clears = sorted({k[1] for k in data})
    speeds = sorted({k[2] for k in data})
    out = []
    if not data:
        return ["No completed run has the study's case names: nothing to compare (**unknown**)."]

    # (ii) Clearance and speed raise the accelerations (§4; conclusion ii).
    found = []
    for stat, what in (("rms", "RMS"), ("peak", "peak")):
        by_speed = [(data[(m, c, s0)].get(f"{a}.a.{stat}"), data[(m, c, s1)].get(f"{a}.a.{stat}"))
                    for m in mechs for c in clears for a in SENSORS
                    for s0, s1 in zip(speeds, speeds[1:])
                    if (m, c, s0) in data and (m, c, s1) in data]
        by_clear = [(data[(m, c0, s)].get(f"{a}.a.{stat}"), data[(m, c1, s)].get(f"{a}.a.{stat}"))
                    for m in mechs for s in speeds for a in SENSORS
                    for c0, c1 in zip(clears, clears[1:])
                    if (m, c0, s) in data and (m, c1, s) in data]
        hs, ns, ws = _tally(by_speed)
        hc, nc, wc = _tally(by_clear)
        found.append(f"{what} values: the next higher speed gives a larger value in {hs} of {ns} "
                     f"comparisons (both mechanisms, both clearances, five sensors) — **{ws}**; "
                     f"the larger clearance in {hc} of {nc} — **{wc}**")
    out.append(
        "**Speed and clearance raise the accelerations** (§4: \"Acceleration amplitudes increase, "
        "when the clearance value and/or running speed increase\"; conclusion ii). Sensor "
        + "; sensor ".join(found) + ".")

    # Per-sensor breakdown for speed (RMS), so a reader sees where it fails.
    rows = []
    for a in SENSORS:
        pairs = [(data[(m, c, s0)].get(f"{a}.a.rms"), data[(m, c, s1)].get(f"{a}.a.rms"))
                 for m in mechs for c in clears for s0, s1 in zip(speeds, speeds[1:])
                 if (m, c, s0) in data and (m, c, s1) in data]
        pc = [(data[(m, c0, s)].get(f"{a}.a.rms"), data[(m, c1, s)].get(f"{a}.a.rms"))
              for m in mechs for s in speeds for c0, c1 in zip(clears, clears[1:])
              if (m, c0, s) in data and (m, c1, s) in data]
        h1, n1, _ = _tally(pairs)
        h2, n2, _ = _tally(pc)
        rows.append(f"sensor {SENSOR_WORDS[a]}: speed {h1}/{n1}, clearance {h2}/{n2}")
    out.append("RMS comparisons that hold, per sensor: " + "; ".join(rows) + ".")

    # Figs. 9–10 (200 rpm): the compliant mechanism's force peaks are smaller and less frequent.
    def versus(metric_of, label):
        pairs = [(metric_of(data[("compliant", c, s)]), metric_of(data[("articulated", c, s)]))
                 for c in clears for s in speeds
                 if ("compliant", c, s) in data and ("articulated", c, s) in data]
        at_top = [(metric_of(data[("compliant", c, speeds[-1])]),
                   metric_of(data[("articulated", c, speeds[-1])]))
                  for c in clears if speeds and ("compliant", c, speeds[-1]) in data
                  and ("articulated", c, speeds[-1]) in data]
        h, n, w = _tally(pairs)
        ht, nt, wt = _tally(at_top)
        return (f"{label}: smaller in the compliant mechanism in {h} of {n} (clearance, speed) "
                f"pairs — **{w}**; at {speeds[-1]:.0f} rpm {ht} of {nt} — **{wt}**")
    out.append(
        "**The compliant mechanism has smaller and less frequent force peaks** (§4, Figs. 9 and "
        "10 at 200 rpm: \"peak value and frequency of forces in compliant mechanism are smaller "
        "than that of classic articulated mechanism\"). "
        + "; ".join([versus(_peak_contact, "largest contact-force peak"),
                     versus(lambda m: m.get("crank_pivot.F.peak"), "F21 peak"),
                     versus(lambda m: m.get("piston_guide.F.peak"), "F41 peak"),
                     versus(_impacts, "impacts over the kept revolutions (both clearance joints "
                                      "of the articulated mechanism against the compliant one's)"),
                     versus(lambda m: m.get("crank_rod.impacts"),
                            "impacts at the crank–rod joint alone")])
        + ".")

    # (iii) The pivot keeps the crank–rod journal in contact, continuous contact at 200 rpm.
    if speeds:
        top = speeds[-1]
        parts, checks = [], []
        for c in clears:
            cm, am = data.get(("compliant", c, top)), data.get(("articulated", c, top))
            if not cm or not am:
                continue
            cf, af = cm.get("crank_rod.free_flight_share"), am.get("crank_rod.free_flight_share")
            cc, ac = cm.get("crank_rod.continuous_share"), am.get("crank_rod.continuous_share")
            parts.append(f"{c:.2f} mm: crank–rod free flight {cf:.3f} compliant against "
                         f"{af:.3f} articulated, continuous contact {cc:.3f} against {ac:.3f}")
            checks += [(cf, af), (ac, cc)]
        h, n, w = _tally(checks)
        cont = [data[("compliant", c, top)].get("crank_rod.continuous_share", 0.0)
                for c in clears if ("compliant", c, top) in data]
        mostly = all(v > 0.5 for v in cont) if cont else False
        out.append(
            f"**The flexural pivot keeps the crank–rod journal in contact** (§4: at 200 rpm "
            f"\"the torsional spring character ... has a role to ensure the continuous contact\"; "
            f"conclusion iii: free flight and impacts decrease). At {top:.0f} rpm, "
            + "; ".join(parts) + f". Less free flight and more continuous contact in the compliant "
            f"mechanism: {h} of {n} — **{w}**. Continuous contact for most of the time (share "
            f"above 0.5) in the compliant mechanism at {top:.0f} rpm at every clearance: "
            f"**{'agrees' if mostly else 'disagrees'}**.")

    # Sensor 5 periodic in the compliant mechanism, not in the articulated one (§4, Figs. 11–15).
    def periodic(m):
        n, d = m.get("sections"), m.get("distinct_points")
        return None if not n else (d is not None and 0 < d <= n / 2)
    comp = [periodic(data[k]) for k in data if k[0] == "compliant"]
    art = [periodic(data[k]) for k in data if k[0] == "articulated"]
    nsec = sorted({int(data[k].get("sections", 0)) for k in data})
    cp, ap = sum(bool(x) for x in comp), sum(bool(x) for x in art)
    w_comp = "agrees" if cp == len(comp) else ("disagrees" if cp == 0 else "agrees in part")
    w_art = "agrees" if ap == 0 else ("disagrees" if ap == len(art) else "agrees in part")
    out.append(
        f"**Compliant periodic, articulated not** (§4: the compliant mechanism \"has a periodical "
        f"motion\", the articulated one \"does not have an exact periodical character\"). Here a "
        f"run counts as periodic when its crank–rod journal returns to at most half as many "
        f"distinct points as there are stroboscopic sections (tolerance 1 % of the clearance, "
        f"the rule of docs/analysis.md; {', '.join(map(str, nsec))} sections per run, fewer than "
        f"the 16 the full verdict needs, so this is indicative only). Compliant periodic: "
        f"{cp} of {len(comp)} runs — **{w_comp}**; articulated not periodic: {len(art) - ap} of "
        f"{len(art)} runs — **{w_art}**.")
    return out
