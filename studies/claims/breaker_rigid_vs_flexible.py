"""Claims of studies/breaker_rigid_vs_flexible.yaml (rigid links against the insulating pole and
the upper linking board as flexible links, 0.1 mm at A and J, each with its ideal twin); see
breaker_common.py. Meng et al. (Shock and Vibration 2015, §5.2, Figures 13 and 14): the peak
acceleration of the moving contact falls from 563.5 m/s² (rigid) to 460.2 m/s² (flexible), "the
flexible components act as a suspension". Used by studies/results.py."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import breaker_common as bc  # noqa: E402

FIGURES = [
    {"kind": "series", "file": "acceleration.svg",
     "title": "Moving contact acceleration, 0.1 mm at A and J (the paper's Figures 13e and 14e)",
     "channel": "moving_contact.ax", "series": "links", "ylabel": "m/s²",
     "where": {"clearance": "A_J_0.1mm"}},
]
PAPER = {"peak_ax_m_s2": "563.5 m/s² rigid, 460.2 m/s² flexible (−18 %)"}


def folder_claims(folder, runs):
    rows = bc.measures(folder)
    out = [bc.markdown_table(folder, ["links", "clearance"])]
    by = {d["links"]: v for d, v in rows if d["clearance"] != "ideal"}
    for key, label in bc.MEASURES:
        if key not in ("peak_ax_m_s2", "peak_J_force_N"):
            continue
        rigid, flexible = by.get("rigid", {}).get(key), by.get("flexible", {}).get(key)
        held, n, word = bc.trend([rigid, flexible], rising=False)
        text = ("–" if rigid is None else f"{rigid:.4g}") + " rigid, " + \
            ("–" if flexible is None else f"{flexible:.4g}") + " flexible"
        if rigid and flexible:
            text += f" ({100.0 * (flexible - rigid) / rigid:+.0f} %)"
        paper = PAPER.get(key, "not given; the suspension effect implies lower")
        out.append(bc.sentence(f"The flexible links lower the {label}", paper, text, held, n, word))
    return out
