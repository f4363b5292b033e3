"""Claims of studies/breaker_clearance.yaml (clearance 0.05 / 0.1 / 0.2 mm at A and J, two
readings of Table 3's K); see breaker_common.py. Used by studies/results.py."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import breaker_common as bc  # noqa: E402

FIGURES = [
    {"kind": "series", "file": "acceleration.svg",
     "title": "Moving contact acceleration, K = 3.81e7 N/m^1.5 (the paper's Figure 15e)",
     "channel": "moving_contact.ax", "series": "clearance", "ylabel": "m/s²",
     "where": {"clearance_defaults.stiffness": "38100000"}},
]
CLEARANCES = ["0.05mm", "0.1mm", "0.2mm"]
PAPER = {"stroke_deviation_mm": "0.04 → 0.17 mm as c goes 0.05 → 0.2 mm",
         "peak_ax_m_s2": "345.5 → 612.2 m/s²", "peak_J_force_N": "2032 → 3681 N"}


def folder_claims(folder, runs):
    rows = bc.measures(folder)
    out = [bc.markdown_table(folder, ["clearance_defaults.stiffness", "clearance"])]
    for k in sorted({d["clearance_defaults.stiffness"] for d, _ in rows}, key=float):
        by = {d["clearance"]: v for d, v in rows if d["clearance_defaults.stiffness"] == k}
        for key, label in bc.MEASURES:
            if key not in PAPER:
                continue
            vals = [by.get(c, {}).get(key) for c in CLEARANCES]
            text = " → ".join("–" if x is None else f"{x:.4g}" for x in vals)
            held, n, word = bc.trend(vals)
            out.append(bc.sentence(f"{label[0].upper() + label[1:]} grows with the clearance "
                                   f"(K = {float(k):.4g} N/m^1.5)", PAPER[key], text, held, n, word))
    return out
