"""Figures of studies/flores_clearance_location.yaml (no statement of a paper is checked here).
Used by studies/results.py."""

FIGURES = [
    {"file": "acceleration.svg", "title": "Slider acceleration after the transient, by clearance location",
     "metric": "slider.ax.peak", "ylabel": "m/s²", "x": "clearance_at"},
]
