"""Claims of studies/breaker_clearance_count.yaml (0.1 mm clearance at J, A+J, A+B+I+J and all
10 revolute joints); see breaker_common.py. The paper goes to 15 joints, counting clearance in its
prismatic pairs too; Lash's clearance joints are revolute, so our count stops at 10. Used by
studies/results.py."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import breaker_common as bc  # noqa: E402

FIGURES = [
    {"kind": "series", "file": "acceleration.svg",
     "title": "Moving contact acceleration by clearance joints (the paper's Figure 18e)",
     "channel": "moving_contact.ax", "series": "joints", "ylabel": "m/s²"},
]
COUNTS = ["J", "A_J", "A_B_I_J", "all_10"]
PAPER = {"stroke_deviation_mm": "0.08 → 0.54 mm from 1 to 15 clearance joints",
         "velocity_delay_ms": "1.5 → 4.4 ms", "peak_ax_m_s2": "331.5 → 4260.6 m/s²"}


def folder_claims(folder, runs):
    rows = bc.measures(folder)
    out = [bc.markdown_table(folder, ["joints"])]
    by = {d["joints"]: v for d, v in rows}
    for key, label in bc.MEASURES:
        if key not in PAPER:
            continue
        vals = [by.get(c, {}).get(key) for c in COUNTS]
        text = " → ".join("–" if x is None else f"{x:.4g}" for x in vals)
        held, n, word = bc.trend(vals)
        out.append(bc.sentence(f"{label[0].upper() + label[1:]} grows with the number of "
                               "clearance joints", PAPER[key], text, held, n, word))
    return out
