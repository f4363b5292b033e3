"""Figures of studies/flores_speed_hysteresis.yaml (the bifurcation diagram swept up and down by
continuation; no statement of a paper is checked here). Used by studies/results.py."""

FIGURES = [
    {"kind": "sections", "file": "bifurcation.svg",
     "title": "Rod–slider journal eccentricity per revolution, speed swept up and down",
     "channel": "rod_slider.ex", "x": "drivers.crank.speed_rpm", "series": "direction",
     "ylabel": "e_x (m)"},
]
