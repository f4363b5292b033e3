"""Figures of studies/flores_speed_bifurcation.yaml (no statement of a paper is checked here: the
diagram is the result). Used by studies/results.py."""

FIGURES = [
    {"kind": "sections", "file": "bifurcation.svg",
     "title": "Rod–slider journal eccentricity at each crank revolution against crank speed",
     "channel": "rod_slider.ex", "x": "drivers.crank.speed_rpm", "ylabel": "e_x (m)"},
]
