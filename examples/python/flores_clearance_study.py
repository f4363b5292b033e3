"""Peak contact force against clearance for the Flores slider-crank, notebook style.

Run from the repository root after `make python` (or after `make install`, without PYTHONPATH):

    PYTHONPATH=build/python /usr/bin/python3 examples/python/flores_clearance_study.py

It runs examples/flores_slider_crank.yaml (clearance at the rod-slider joint, 5000 rpm, two crank
revolutions) at several clearances, prints the peak contact force, the number of impacts and the
peak slider acceleration of each, the same numbers against the ideal mechanism, and writes
out/python_study/clearance_study.png (matplotlib) and clearance_study.csv.
"""
# %% Set-up: the model as the CLI reads it.
import csv
import os
import sys

import numpy as np

import lash

root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
model = lash.load(os.path.join(root, "examples", "flores_slider_crank.yaml"))
print(model.name, "channels:", len(model.channels))

# %% The ideal twin: every joint ideal (clearance 0 makes a revolute joint ideal again, as --set
# does on the command line).
ideal_model = model.copy().set("joints.rod_slider.clearance", 0)
ideal = lash.simulate(ideal_model)
ideal_ax = np.abs(ideal["slider.ax"]).max()
print(f"ideal: peak |slider.ax| = {ideal_ax:.4g} m/s^2")

# %% The study: one run per clearance; each run releases the GIL and stops on Ctrl-C.
clearances_mm = [0.05, 0.1, 0.25, 0.5, 1.0]
rows = []
for c_mm in clearances_mm:
    m = model.copy().set("joints.rod_slider.clearance", c_mm * 1e-3)
    r = lash.simulate(m)
    if not r.ok:
        print(f"c = {c_mm} mm: run {r.status['outcome']}: {r.status['message']}", file=sys.stderr)
    joint = r.summary["clearance_joints"]["rod_slider"]
    row = {"clearance_mm": c_mm,
           "peak_Fn_N": float(r["rod_slider.Fn"].max()),
           "impacts": joint["impacts"],
           "contact_share": joint["contact_share"],
           "peak_slider_ax": float(np.abs(r["slider.ax"]).max()),
           "wall_s": r.integrator["wall_seconds"]}
    rows.append(row)
    print(f"c = {c_mm:5.2f} mm: peak Fn = {row['peak_Fn_N']:9.1f} N, "
          f"{row['impacts']:3d} impacts, contact {100 * row['contact_share']:5.1f} %, "
          f"peak |slider.ax| = {row['peak_slider_ax']:9.1f} m/s^2 "
          f"({row['peak_slider_ax'] / ideal_ax:5.1f} x ideal), {row['wall_s']:.2f} s")

# %% Save the table and a figure.
out = os.path.join(root, "out", "python_study")
os.makedirs(out, exist_ok=True)
with open(os.path.join(out, "clearance_study.csv"), "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=list(rows[0]))
    w.writeheader()
    w.writerows(rows)
try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib not installed: no figure")
else:
    fig, ax = plt.subplots(1, 2, figsize=(9, 3.5))
    ax[0].plot(clearances_mm, [r["peak_Fn_N"] for r in rows], "o-")
    ax[0].set(xlabel="radial clearance (mm)", ylabel="peak contact force (N)", xscale="log")
    ax[1].plot(clearances_mm, [r["peak_slider_ax"] / ideal_ax for r in rows], "o-")
    ax[1].set(xlabel="radial clearance (mm)", ylabel="peak |slider.ax| / ideal", xscale="log")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "clearance_study.png"), dpi=120)
    print("wrote", os.path.join(out, "clearance_study.png"))
