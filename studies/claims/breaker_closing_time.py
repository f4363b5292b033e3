"""Claims of studies/breaker_closing_time.yaml (closing in 0.04 / 0.06 / 0.085 s, with 0.1 mm at
A and J); see breaker_common.py. Used by studies/results.py."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import breaker_common as bc  # noqa: E402

FIGURES = [
    {"kind": "series", "file": "velocity.svg",
     "title": "Moving contact velocity, 0.1 mm at A and J (the paper's Figure 17b)",
     "channel": "moving_contact.vx", "series": "closing", "ylabel": "m/s",
     "where": {"joints": "A_J_0.1mm"}},
]
TIMES = ["t040", "t060", "t085"]
PAPER = {"peak_vx_m_s": "13.31 → 6.21 m/s as the closing time goes 0.04 → 0.085 s",
         "peak_ax_m_s2": "1625.6 → 460.2 m/s²", "peak_J_force_N": "9754 → 3820 N"}


def folder_claims(folder, runs):
    rows = bc.measures(folder)
    out = [bc.markdown_table(folder, ["closing", "joints"])]
    by = {d["closing"]: v for d, v in rows if d["joints"] != "ideal"}
    for key, label in bc.MEASURES:
        if key not in PAPER:
            continue
        vals = [by.get(t, {}).get(key) for t in TIMES]
        text = " → ".join("–" if x is None else f"{x:.4g}" for x in vals)
        held, n, word = bc.trend(vals, rising=False)
        out.append(bc.sentence(f"{label[0].upper() + label[1:]} falls as the closing slows",
                               PAPER[key], text, held, n, word))
    return out
