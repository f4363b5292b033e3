"""The literature's claim that link flexibility cushions the impacts in clearance joints, set
beside the numbers of studies/flores_rigid_vs_flexible.yaml. Used by studies/results.py.

Meng et al. (Shock and Vibration 2015) report for their circuit breaker a peak acceleration of
563.5 m/s² with rigid links and 460.2 m/s² with flexible ones (−18 %); the flexible-link
literature on slider-cranks with clearance says the same in words: the flexible link acts as a
suspension and the impact peaks fall. Here the rod of the Flores slider-crank is made flexible
(same mass) at three moduli; each flexible run is compared with the rigid run of the same
clearance.
"""

COLUMNS = [
    ("rod_slider.Fn.peak", "rod–slider F_N peak (N)", 1.0, ".0f"),
    ("rod_slider.Fn.rms", "F_N RMS (N)", 1.0, ".0f"),
    ("slider.ax.peak", "slider a_x peak (m/s²)", 1.0, ".0f"),
    ("crank_rod.F.peak", "crank–rod force peak (N)", 1.0, ".0f"),
    ("rod_slider.impacts", "impacts", 1.0, ".0f"),
    ("rod.stress_max.peak", "rod stress peak (MPa)", 1e-6, ".1f"),
    ("rod.deflection.peak", "rod deflection peak (µm)", 1e6, ".2f"),
]

FIGURES = [
    {"file": "acceleration_peak.svg", "title": "Slider acceleration: peak after the transient",
     "metric": "slider.ax.peak", "ylabel": "m/s²", "x": "joints.rod_slider.clearance",
     "series": "rod"},
    {"file": "contact_force_peak.svg", "title": "Rod–slider contact force: peak",
     "metric": "rod_slider.Fn.peak", "ylabel": "N", "x": "joints.rod_slider.clearance",
     "series": "rod"},
]

PREAMBLE = (
    "Metrics over revolutions 3–6 of 6 at 5000 rpm: peaks exact between outputs, RMS over the "
    "outputs, impacts counted as in docs/analysis.md. `rigid` is examples/flores_slider_crank.yaml; "
    "the others its rod as a 4-element flexible link of the same mass at the modulus named.")


def claims(runs):
    done = [r for r in runs if r["status"] == "completed"]
    rigid = {str(r["params"]["joints.rod_slider.clearance"]): r["metrics"]
             for r in done if r["params"]["rod"] == "rigid"}
    if not rigid:
        return ["No completed rigid run: nothing to compare (**unknown**)."]
    out = []
    for metric, what, source in (
            ("slider.ax.peak", "peak slider acceleration", "Meng et al. 2015: −18 % for their breaker"),
            ("rod_slider.Fn.peak", "peak contact force",
             "the flexible-link literature, in words; Meng et al. 2015 give no figure")):
        lower, total, ratios = 0, 0, []
        for r in done:
            if r["params"]["rod"] == "rigid":
                continue
            ref = rigid.get(str(r["params"]["joints.rod_slider.clearance"]), {}).get(metric)
            val = r["metrics"].get(metric)
            if ref is None or val is None or ref == 0:
                continue
            total += 1
            lower += val < ref
            ratios.append(val / ref)
        word = ("unknown" if total == 0 else "agrees" if lower == total else
                "agrees in part" if 2 * lower >= total else "mostly disagrees"
                if lower > 0 else "disagrees")
        span = (f"flexible/rigid from {min(ratios):.2f} to {max(ratios):.2f}" if ratios else "")
        out.append(
            f"**A flexible rod lowers the {what}** ({source}): "
            f"lower than the rigid rod's at the same clearance in {lower} of {total} flexible runs, "
            f"{span} — **{word}**. Each run is one trajectory of an impacting motion, so single "
            f"comparisons can go either way.")
    return out
