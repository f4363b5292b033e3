"""The clearance in the crank–rod or in the rod–slider joint of the Flores slider-crank
(studies/flores_clearance_location.yaml), set beside the statement of Muvengei, Kihiu & Ikua
(2012, "Numerical study of parametric effects on the dynamic response of planar multi-body
systems with differently located frictionless revolute clearance joints", Mechanism and Machine
Theory 53): "the dynamic response ... depends on the location of the joint". Used by
studies/results.py."""

FIGURES = [
    {"file": "acceleration.svg", "title": "Slider acceleration after the transient, by clearance location",
     "metric": "slider.ax.peak", "ylabel": "m/s²", "x": "clearance_at"},
]

SAME = 0.10  # peaks within 10 % of each other: the location would not matter


def claims(runs):
    m = {r["params"]["clearance_at"]: r["metrics"] for r in runs if r["status"] == "completed"}
    a, b = m.get("crank_rod", {}).get("slider.ax.peak"), m.get("rod_slider", {}).get("slider.ax.peak")
    if a is None or b is None:
        return ["Both locations did not complete: **unknown**."]
    ia = m["crank_rod"].get("crank_rod.impacts")
    ib = m["rod_slider"].get("rod_slider.impacts")
    differ = abs(a - b) / max(a, b)
    word = "agrees" if differ > SAME else "disagrees"
    return [f"**The response depends on which joint has the clearance** (Muvengei et al. 2012): "
            f"peak slider acceleration {a:.4g} m/s² with the clearance at the crank–rod joint, "
            f"{b:.4g} m/s² at the rod–slider joint ({100 * differ:.0f} % apart; "
            f"{ia if ia is None else int(ia)} and {ib if ib is None else int(ib)} impacts) — "
            f"**{word}** (more than {100 * SAME:.0f} % apart counts as depending on it)."]
