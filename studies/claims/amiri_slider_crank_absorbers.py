"""Claims of studies/amiri_slider_crank_absorbers.yaml (with and without the two absorbers); see
amiri_common.py. Used by studies/results.py."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import amiri_common  # noqa: E402

COLUMNS = amiri_common.columns("rod_slider", "rod_accel.a")
FIGURES = amiri_common.figures("slider-crank", "rod_slider", "rod_accel.a")


def claims(runs):
    return amiri_common.absorbers_claims(runs, "rod_accel.a", "rod_slider")
