"""Claims of studies/amiri_slider_crank_absorbers.yaml (with and without the two absorbers); see
amiri_common.py. Used by studies/results.py."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import amiri_common  # noqa: E402

COLUMNS = amiri_common.columns("rod_slider", "rod_accel.a")
FIGURES = [
    {"kind": "series", "file": "acceleration.svg",
     "title": "slider-crank: the link's transverse acceleration, with and without absorbers",
     "channel": "rod_accel.a", "series": "absorbers", "ylabel": "m/s²"},
    {"kind": "section_map", "file": "poincare.svg",
     "title": "slider-crank: Poincaré map of the rod_slider journal (once per crank revolution)",
     "x_channel": "rod_slider.ex", "y_channel": "rod_slider.ey", "series": "absorbers",
     "xlabel": "eccentricity x (m)", "ylabel": "eccentricity y (m)"},
]


def claims(runs):
    return amiri_common.absorbers_claims(runs, "rod_accel.a", "rod_slider")
