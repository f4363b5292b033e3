"""Shared by the claims modules of the circuit-breaker studies (studies/breaker_*.yaml): the
published trends of Meng et al. (Shock and Vibration 2015, sections 5.3–5.5) set beside the
measures studies/breaker_metrics.py derives from each run and its ideal twin. Our linkage's
layout is designed from the paper's description, its links are rigid (the paper's studies use
flexible ones), and Table 3's contact stiffness is read in Adams' mm units: we expect trends to
agree, not values."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import breaker_metrics  # noqa: E402

MEASURES = [("stroke_deviation_mm", "stroke deviation (mm)"),
            ("velocity_delay_ms", "velocity delay at start (ms)"),
            ("peak_vx_m_s", "peak velocity (m/s)"),
            ("peak_ax_m_s2", "peak acceleration (m/s²)"),
            ("peak_J_force_N", "peak force at J (N)")]


def measures(folder):
    """[(params dict, {measure: float or None})] of the runs with an ideal twin."""
    header, table = breaker_metrics.derived(folder)
    out = []
    for row in table:
        d = dict(zip(header, row))
        vals = {}
        for key, _ in MEASURES:
            try:
                vals[key] = float(d[key])
            except (TypeError, ValueError):
                vals[key] = None
        out.append((d, vals))
    return out


def markdown_table(folder, params):
    rows = measures(folder)
    head = params + [label for _, label in MEASURES]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for d, vals in rows:
        cells = [str(d[p]) for p in params] + [
            "–" if vals[k] is None else f"{vals[k]:.4g}" for k, _ in MEASURES]
        lines.append("| " + " | ".join(cells) + " |")
    return ("Measures against each run's ideal twin (studies/breaker_metrics.py):\n\n"
            + "\n".join(lines))


def trend(values, rising=True):
    """How many consecutive pairs of `values` (None skipped) move the expected way."""
    v = [x for x in values if x is not None]
    pairs = list(zip(v, v[1:]))
    held = sum(1 for a, b in pairs if (b > a) == rising)
    n = len(pairs)
    word = ("unknown" if n == 0 else "agrees" if held == n else "disagrees" if held == 0 else
            "agrees in part")
    return held, n, word


def sentence(title, paper, values_text, held, n, word):
    # The verdict is on the trend only: the layout and the contact stiffness differ from the
    # paper's (examples/breaker_linkage.yaml), and its figures come from its rigid-flexible
    # model, so the values are set beside each other, not compared.
    return (f"**{title}** (paper: {paper}): ours {values_text}; the trend holds in {held} of {n} "
            f"steps — the trend **{word}** (the values are not expected to match: our layout "
            f"and contact stiffness are not the paper's).")
