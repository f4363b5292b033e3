"""Claims of studies/amiri_four_bar_absorbers.yaml (with and without the two absorbers); see
amiri_common.py. Used by studies/results.py."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import amiri_common  # noqa: E402

COLUMNS = amiri_common.columns("coupler_rocker", "coupler_accel.a")
FIGURES = [
    {"kind": "series", "file": "acceleration.svg",
     "title": "four-bar: the link's transverse acceleration, with and without absorbers",
     "channel": "coupler_accel.a", "series": "absorbers", "ylabel": "m/s²"},
    {"kind": "section_map", "file": "poincare.svg",
     "title": "four-bar: Poincaré map of the coupler_rocker journal (once per crank revolution)",
     "x_channel": "coupler_rocker.ex", "y_channel": "coupler_rocker.ey", "series": "absorbers",
     "xlabel": "eccentricity x (m)", "ylabel": "eccentricity y (m)"},
]


def claims(runs):
    return amiri_common.absorbers_claims(runs, "coupler_accel.a", "coupler_rocker")
