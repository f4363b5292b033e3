"""Figures of studies/flores_clearance.yaml (no statement of a paper is checked here). Used by
studies/results.py."""

FIGURES = [
    {"file": "contact_force_peak.svg", "title": "Rod–slider contact force: peak after the transient",
     "metric": "rod_slider.Fn.peak", "ylabel": "N", "x": "joints.rod_slider.clearance"},
    {"kind": "sections", "file": "sections.svg",
     "title": "Rod–slider journal eccentricity at each crank revolution against the clearance",
     "channel": "rod_slider.ex", "x": "joints.rod_slider.clearance", "ylabel": "e_x (m)"},
]
