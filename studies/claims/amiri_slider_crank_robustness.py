"""Claims of studies/amiri_slider_crank_robustness.yaml (absorber mass and stiffness, crank speed and
clearance moved by ±10 and ±20 %); see amiri_common.py. Used by studies/results.py."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import amiri_common  # noqa: E402

COLUMNS = amiri_common.columns("rod_slider", "rod_accel.a")
FIGURES = []


def claims(runs):
    return amiri_common.robustness_claims(runs, "rod_accel.a")
