"""Derived measures of the circuit-breaker studies (studies/breaker_*.yaml) from a study folder.

    python3 studies/breaker_metrics.py out/breaker_clearance [--csv out/breaker_clearance/breaker_metrics.csv]

`lash sweep` keeps each run's peaks and a decimated series (docs/studies.md); the quantities of
Meng et al. (Shock and Vibration 2015, sections 5.3-5.5) that compare a run with the ideal
linkage are derived here, each clearance run against its ideal twin:

* ideal twin: the run of the same study whose clearance parameters (named `*clearance` or
  `joints`) are all ideal (a number 0, or the case `ideal` or `none`) and whose other parameters
  (e.g. the closing time, the contact stiffness) are equal;
* closing time T: the first time the ideal twin's moving contact comes within 1 um of its final
  position (the end of the STEP5 input);
* stroke: moving_contact.x(T) - moving_contact.x(0), interpolated linearly in the kept series;
  deviation: stroke - the twin's stroke (mm);
* velocity delay at start: the time the run's moving-contact velocity first reaches 5 % of the
  twin's peak velocity, minus the same time for the twin (ms);
* peak acceleration of the moving contact and peak force at J: the runs' own peaks
  (moving_contact.ax.peak, J.F.peak: the contact force when J has clearance, the reaction force
  when it is ideal).
Only the Python standard library is used.
"""
import argparse
import csv
import json
import os
import sqlite3
import sys


def is_clearance_param(name):
    return name.endswith("clearance") or name == "joints"


def is_ideal_value(name, value):
    if isinstance(value, str):  # a case name
        return value in ("ideal", "none")
    return float(value) == 0.0


def interp(ts, vs, t):
    for k in range(1, len(ts)):
        if ts[k] >= t:
            w = (t - ts[k - 1]) / (ts[k] - ts[k - 1])
            return vs[k - 1] + w * (vs[k] - vs[k - 1])
    return vs[-1]


def first_crossing(ts, vs, level):
    for k in range(1, len(ts)):
        if vs[k] >= level > vs[k - 1]:
            return ts[k - 1] + (level - vs[k - 1]) / (vs[k] - vs[k - 1]) * (ts[k] - ts[k - 1])
    return float("nan")


def derived(folder):
    """(header, rows) of the derived measures of every run of the study in `folder`; a run
    without a completed ideal twin has empty measures."""
    db = sqlite3.connect(f"file:{os.path.join(folder, 'study.db')}?mode=ro", uri=True)
    params = [r[0] for r in db.execute("select name from parameters order by position")]
    cols = ", ".join(f'"{p}"' for p in params)
    runs = {}
    for row in db.execute(f"select run, {cols}, status, wall_seconds from runs order by run"):
        runs[row[0]] = {"params": dict(zip(params, row[1:1 + len(params)])), "status": row[-2],
                        "wall": row[-1]}
    for run, name, value in db.execute("select run, name, value from metrics"):
        runs[run].setdefault("metrics", {})[name] = value
    for run, ch, t, v in db.execute("select run, channel, time, value from series"):
        runs[run].setdefault("series", {})[ch] = (json.loads(t), json.loads(v))

    def key(r):
        return tuple((p, r["params"][p]) for p in params if not is_clearance_param(p))

    twins = {key(r): r for r in runs.values()
             if r["status"] == "completed"
             and all(is_ideal_value(p, r["params"][p]) for p in params if is_clearance_param(p))}
    header = params + ["status", "wall_s", "stroke_mm", "stroke_deviation_mm", "velocity_delay_ms",
                       "peak_vx_m_s", "peak_ax_m_s2", "peak_J_force_N"]
    table = []
    for run, r in sorted(runs.items()):
        row = [r["params"][p] for p in params] + [r["status"], round(r["wall"] or 0, 1)]
        twin = twins.get(key(r))
        if r["status"] != "completed" or twin is None or "series" not in r:
            table.append(row + [""] * 6)
            continue
        tx, x = twin["series"]["moving_contact.x"]
        t_close = next(t for t, v in zip(tx, x) if abs(v - x[-1]) < 1e-6)
        rx, rxv = r["series"]["moving_contact.x"]
        stroke = interp(rx, rxv, t_close) - rxv[0]
        twin_stroke = interp(tx, x, t_close) - x[0]
        level = 0.05 * twin["metrics"]["moving_contact.vx.peak"]
        tv, v = twin["series"]["moving_contact.vx"]
        rv, rvv = r["series"]["moving_contact.vx"]
        delay = first_crossing(rv, rvv, level) - first_crossing(tv, v, level)
        m = r["metrics"]
        table.append(row + [f"{stroke * 1e3:.3f}", f"{(stroke - twin_stroke) * 1e3:.3f}", f"{delay * 1e3:.3f}",
                            f"{m['moving_contact.vx.peak']:.3f}", f"{m['moving_contact.ax.peak']:.1f}",
                            f"{m['J.F.peak']:.0f}"])
    db.close()
    return header, table


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder")
    ap.add_argument("--csv", help="also write the table here")
    a = ap.parse_args()
    header, table = derived(a.folder)
    w = csv.writer(sys.stdout)
    w.writerow(header)
    w.writerows(table)
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            csv.writer(f).writerows([header] + table)


if __name__ == "__main__":
    main()
