#!/usr/bin/python3
"""Builds a stand-in report_data.json (docs/report-data.md) from a `lash run` output folder.

The real file is written by the C++ analysis layer (`lash report`). Until that exists, and in the
figure tests, this script makes a realistic sample from what `lash run` already writes:

* series      timeseries.csv decimated to at most --max-points rows; crank angle from the first
              revolute driver (θ = φ_journal − φ_bearing, degrees in [0, 360)); the ideal twin
              from --ideal DIR (a run with `--set joints.<j>.clearance=0`) interpolated onto the
              same time base.
* frames      bodies (x, y, φ) and journal eccentricities at <= 600 instants.
* analysis    statistics and comparison per channel (full resolution); per clearance joint the
              orbit (ex, ey), contact episodes from events.csv (an episode shorter than
              IMPACT_DURATION_S is an impact, a longer one continuous contact), the onset
              velocities and their histogram; a stroboscopic Poincaré section of (ex, ey) once per
              --period after the first; Hann-windowed amplitude spectra of the peak body
              acceleration after the first period; phase pairs (e_x, e_y) and (δ, δ̇) per
              clearance joint and (x, vx) per translational body; a *fake* Lyapunov history
              (marked "stand-in").
* channel_info  unit and description of every channel, copied from summary.json's
              channels.<name>.unit/.description (written by the engine); a channel summary.json
              does not describe is left out, as the report page and figures then show it
              without a unit. Units are never guessed from channel names.

Only the standard library and numpy are needed; the model section uses PyYAML (Debian's
python3-yaml) on model_resolved.yaml when it is installed and is inferred from the column names
otherwise.

Usage: make_sample.py RUN_DIR [--ideal IDEAL_DIR] [-o FILE] [--period 0.012]
"""

import argparse
import csv
import json
import math
import os
import sys

import numpy as np

MAX_SERIES_POINTS = 4000      # docs/report-data.md: series are decimated to <= ~4000 samples
MAX_FRAMES = 600              # docs/report-data.md: <= ~600 animation frames
IMPACT_DURATION_S = 2.0e-4    # stand-in rule: contact episodes shorter than this are impacts
HISTOGRAM_BIN_M_S = 0.5       # bin width of the impact-velocity histogram, m/s
DISTINCT_TOLERANCE_M = 1.0e-6 # Poincaré points closer than this count as one


def read_timeseries(path):
    """Returns (header, data) of a timeseries.csv; data is rows x columns, float64."""
    with open(path, newline="") as f:
        header = next(csv.reader(f))
        data = np.loadtxt(f, delimiter=",", ndmin=2)
    return header, data


def read_events(path):
    """Returns the rows of events.csv as dicts with time and velocity as floats."""
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r["time"] = float(r["time"])
        r["velocity"] = float(r["velocity"])
    return rows


def load_model_yaml(run_dir):
    """The resolved model as a dict, or None when there is no file or no PyYAML."""
    path = os.path.join(run_dir, "model_resolved.yaml")
    if not os.path.exists(path):
        return None
    try:
        import yaml
    except ImportError:
        return None
    with open(path) as f:
        return yaml.safe_load(f)


def number(v):
    """A YAML scalar as a float (PyYAML reads '2e-4', without a dot, as a string); None stays."""
    return None if v is None else float(v)


def split_point(ref):
    """'rod.B' -> ('rod', 'B')."""
    body, _, marker = str(ref).partition(".")
    return body, marker


def model_section(model, header, run_dir):
    """The `model` object of report_data.json, from the YAML model or inferred from the columns."""
    bodies_in_columns = sorted({c[:-3] for c in header if c.endswith(".ax")})
    clearance_in_columns = sorted({c[:-3] for c in header if c.endswith(".ex")})
    drivers_in_columns = sorted({c.rsplit(".", 1)[0] for c in header
                                 if c.endswith(".torque") or c.endswith(".force")})
    if model is None:
        # Without the YAML file: names from the columns, and a body that never turns while it
        # moves is taken as the slider of a translational joint.
        return {
            "name": os.path.basename(os.path.normpath(run_dir)),
            "file": "",
            "bodies": [{"name": b} for b in bodies_in_columns],
            "ground_markers": {},
            "joints": [{"name": j, "type": "revolute", "clearance": {}}
                       for j in clearance_in_columns],
            "drivers": [{"name": d} for d in drivers_in_columns],
            "solver": {},
        }
    bodies = []
    for name, b in (model.get("bodies") or {}).items():
        bodies.append({"name": name, "mass": number(b.get("mass")),
                       "inertia": number(b.get("inertia")),
                       "markers": b.get("markers", {})})
    markers = {name: b.get("markers", {}) for name, b in (model.get("bodies") or {}).items()}
    markers["ground"] = (model.get("ground") or {}).get("markers", {})
    defaults = model.get("clearance_defaults") or {}
    point_keys = {"revolute": ("journal", "bearing"), "translational": ("guide", "slider"),
                  "fixed": ("base", "attached")}
    joints = []
    for name, j in (model.get("joints") or {}).items():
        kind = j.get("type", "revolute")
        ka, kb = point_keys.get(kind, ("a", "b"))
        ends = {}
        for key, side in ((ka, "a"), (kb, "b")):
            body, marker = split_point(j.get(key, ""))
            ends[side] = {"body": body, "point": markers.get(body, {}).get(marker)}
        entry = {"name": name, "type": kind, "a": ends["a"], "b": ends["b"]}
        if kind == "translational":
            entry["axis"] = j.get("axis", [1, 0])
        c = j.get("clearance", None)
        if kind == "revolute" and (c or j.get("bearing_radius")):
            merged = dict(defaults, **j)
            c = number(c)
            rj, rb = number(merged.get("journal_radius")), number(merged.get("bearing_radius"))
            if c is not None and rj is not None:
                rb = rj + c
            elif c is not None and rb is not None:
                rj = rb - c
            elif rj is not None and rb is not None:
                c = rb - rj
            entry["clearance"] = {
                "clearance": c, "journal_radius": rj, "bearing_radius": rb,
                "normal_law": merged.get("normal_law"),
                "friction_law": (merged.get("friction") or {}).get("law", "none")}
        joints.append(entry)
    drivers = []
    for name, d in (model.get("drivers") or {}).items():
        speed = number(d.get("speed"))
        if "speed_rpm" in d:
            speed = number(d["speed_rpm"]) * 2.0 * math.pi / 60.0
        drivers.append({"name": name, "joint": d.get("joint"), "speed": speed,
                        "profile": "constant_speed" if speed is not None else "motion"})
    return {"name": model.get("name", "model"), "file": "", "bodies": bodies,
            "ground_markers": markers["ground"], "joints": joints, "drivers": drivers,
            "solver": model.get("solver", {})}


def crank_angle_deg(model, col):
    """Crank angle in degrees, [0, 360), of the first revolute driver; None when there is none."""
    joints = {j["name"]: j for j in model["joints"]}
    for d in model["drivers"]:
        j = joints.get(d.get("joint"))
        if j is None or j["type"] != "revolute":
            continue
        phi_a = col(j["a"]["body"] + ".phi")
        phi_b = col(j["b"]["body"] + ".phi") if j["b"]["body"] != "ground" else 0.0
        if phi_a is None or phi_b is None:
            continue
        return np.mod(np.degrees(phi_a - phi_b), 360.0)
    # Inferred model: a driver named like a body turns that body against the ground.
    for d in model["drivers"]:
        phi = col(d["name"] + ".phi")
        if phi is not None:
            return np.mod(np.degrees(phi), 360.0)
    return None


def translational_bodies(model, col):
    """Bodies on the slider side of a translational joint (or, inferred, bodies that never turn)."""
    found = [j["b"]["body"] if j["b"]["body"] != "ground" else j["a"]["body"]
             for j in model["joints"] if j.get("type") == "translational"]
    if any("a" in j for j in model["joints"]):
        return found
    out = []
    for b in model["bodies"]:
        phi, x = col(b["name"] + ".phi"), col(b["name"] + ".x")
        if phi is not None and x is not None and np.ptp(phi) < 1e-9 and np.ptp(x) > 0:
            out.append(b["name"])
    return out


def channel_info(summary, names):
    """{name: {"unit", "description"}} from summary.json's channels, for the named channels that
    summary.json gives a unit; the others are left out."""
    described = summary.get("channels") if isinstance(summary.get("channels"), dict) else {}
    info = {}
    for name in names:
        entry = described.get(name)
        if isinstance(entry, dict) and isinstance(entry.get("unit"), str):
            info[name] = {"unit": entry["unit"],
                          "description": str(entry.get("description") or name)}
    return info


def tolist(a):
    """numpy array -> JSON list with NaN/inf as null."""
    return [None if not math.isfinite(v) else float(v) for v in np.asarray(a, dtype=float)]


def contact_episodes(events, joint, t_end):
    """[[t_start, t_end, kind], ...] and the onset velocities of one joint from events.csv."""
    episodes, onsets, start = [], [], None
    for e in events:
        if e["joint"] != joint:
            continue
        if e["event"] == "onset":
            start = e["time"]
            onsets.append(e["velocity"])
        elif e["event"] == "separation" and start is not None:
            episodes.append([start, e["time"]])
            start = None
    if start is not None:
        episodes.append([start, t_end])
    out = [[a, b, "impact" if b - a < IMPACT_DURATION_S else "continuous"] for a, b in episodes]
    return out, onsets


def build(run_dir, ideal_dir=None, period=0.012, max_points=MAX_SERIES_POINTS):
    """The report_data dict for one run folder."""
    header, data = read_timeseries(os.path.join(run_dir, "timeseries.csv"))
    index = {name: i for i, name in enumerate(header)}
    time = data[:, 0]

    def col(name):
        i = index.get(name)
        return None if i is None else data[:, i]

    events = read_events(os.path.join(run_dir, "events.csv"))
    model = model_section(load_model_yaml(run_dir), header, run_dir)
    summary_path = os.path.join(run_dir, "summary.json")
    summary = {}
    if os.path.exists(summary_path):
        with open(summary_path) as f:
            summary = json.load(f)

    # Decimated series on a common time base.
    stride = max(1, math.ceil(len(time) / max_points))
    pick = np.arange(0, len(time), stride)
    if pick[-1] != len(time) - 1:
        pick = np.append(pick, len(time) - 1)
    t_dec = time[pick]
    angle = crank_angle_deg(model, col)
    channels = {name: tolist(data[pick, i]) for name, i in index.items() if name != "time"}

    ideal = None
    ideal_full = {}
    if ideal_dir:
        ih, idata = read_timeseries(os.path.join(ideal_dir, "timeseries.csv"))
        for i, name in enumerate(ih):
            if name != "time":
                ideal_full[name] = np.interp(time, idata[:, 0], idata[:, i])
        ideal = {name: tolist(v[pick]) for name, v in ideal_full.items()}

    # Animation frames.
    fpick = np.unique(np.linspace(0, len(time) - 1, min(MAX_FRAMES, len(time))).astype(int))
    frames = {"time": tolist(time[fpick]), "bodies": {}, "clearance": {}}
    for b in model["bodies"]:
        xs = [col(b["name"] + s) for s in (".x", ".y", ".phi")]
        if all(x is not None for x in xs):
            frames["bodies"][b["name"]] = np.column_stack([x[fpick] for x in xs]).tolist()

    # Statistics and comparison with the ideal twin, at full resolution.
    statistics, comparison = {}, {}
    for name, i in index.items():
        if name == "time":
            continue
        v = data[:, i]
        peak = float(np.max(np.abs(v))) if len(v) else 0.0
        rms = float(np.sqrt(np.mean(v * v))) if len(v) else 0.0
        statistics[name] = {"min": float(v.min()), "max": float(v.max()), "peak": peak,
                            "rms": rms, "crest": peak / rms if rms > 0 else None,
                            "window": [float(time[0]), float(time[-1])]}
        if name in ideal_full:
            d = v - ideal_full[name]
            ipeak = float(np.max(np.abs(ideal_full[name])))
            comparison[name] = {"rms_deviation": float(np.sqrt(np.mean(d * d))),
                                "max_deviation": float(np.max(np.abs(d))),
                                "peak_ratio": peak / ipeak if ipeak > 0 else None,
                                "ideal_peak": ipeak}

    # Clearance joints.
    clearance = {}
    clearance_joints = [j for j in model["joints"] if j.get("clearance") is not None
                        and col(j["name"] + ".ex") is not None]
    t_span = float(time[-1] - time[0]) or 1.0
    for j in clearance_joints:
        name = j["name"]
        ex, ey = col(name + ".ex"), col(name + ".ey")
        c = (j.get("clearance") or {}).get("clearance")
        if c is None:
            c = (summary.get("clearance_joints", {}).get(name, {}) or {}).get("clearance")
        frames["clearance"][name] = np.column_stack([ex[fpick], ey[fpick]]).tolist()
        episodes, onsets = contact_episodes(events, name, float(time[-1]))
        impact_t = sum(b - a for a, b, k in episodes if k == "impact")
        cont_t = sum(b - a for a, b, k in episodes if k == "continuous")
        n_bins = max(1, math.ceil(max(onsets, default=0.0) / HISTOGRAM_BIN_M_S))
        counts, edges = np.histogram(onsets, bins=n_bins, range=(0.0, n_bins * HISTOGRAM_BIN_M_S))
        clearance[name] = {
            "clearance": c,
            "orbit": {"ex": tolist(ex[pick]), "ey": tolist(ey[pick])},
            "modes": {"free_flight_share": 1.0 - (impact_t + cont_t) / t_span,
                      "impact_share": impact_t / t_span, "continuous_share": cont_t / t_span,
                      "impacts": sum(1 for e in episodes if e[2] == "impact"),
                      "continuous_contact_time": cont_t, "episodes": episodes},
            "impact_velocities": onsets,
            "histogram": {"edges": tolist(edges), "counts": [int(n) for n in counts]},
        }

    # Stroboscopic Poincaré section of the first clearance joint, once per period after the first.
    poincare = None
    if clearance_joints and period > 0:
        name = clearance_joints[0]["name"]
        t_s = np.arange(period, time[-1] + 1e-12 * period, period)
        if len(t_s):
            pts = np.column_stack([np.interp(t_s, time, col(name + ".ex")),
                                   np.interp(t_s, time, col(name + ".ey"))])
            distinct = []
            for p in pts:
                if all(np.hypot(*(p - q)) > DISTINCT_TOLERANCE_M for q in distinct):
                    distinct.append(p)
            poincare = {"kind": "stroboscopic", "period": period, "discarded_periods": 1,
                        "variables": [name + ".ex", name + ".ey"], "points": pts.tolist(),
                        "distinct": len(distinct)}

    # Amplitude spectrum of the body acceleration with the largest peak, after the first period.
    spectra = None
    accel = [c for c in header if c.endswith(".ax") or c.endswith(".ay")]
    if accel:
        top = max(accel, key=lambda c: statistics[c]["peak"])
        keep = time >= time[0] + period
        v = col(top)[keep]
        if len(v) >= 16:
            dt = float(np.median(np.diff(time[keep])))
            w = np.hanning(len(v))
            amp = 2.0 * np.abs(np.fft.rfft((v - v.mean()) * w)) / w.sum()
            f = np.fft.rfftfreq(len(v), dt)[1:]
            amp = amp[1:]
            if len(f) > max_points:       # keep the largest line of each display bin
                edges = np.linspace(0, len(f), max_points + 1).astype(int)
                top_i = [a + int(np.argmax(amp[a:b])) for a, b in zip(edges[:-1], edges[1:])
                         if b > a]
                f, amp = f[top_i], amp[top_i]
            spectra = {top: {"frequency": tolist(f), "amplitude": tolist(amp),
                             "window": "hann", "discarded_time": period}}

    phase = []
    for j in clearance_joints:
        phase.append({"x": j["name"] + ".ex", "y": j["name"] + ".ey"})
        if col(j["name"] + ".delta") is not None and col(j["name"] + ".delta_dot") is not None:
            phase.append({"x": j["name"] + ".delta", "y": j["name"] + ".delta_dot"})
    for b in translational_bodies(model, col):
        if col(b + ".x") is not None and col(b + ".vx") is not None:
            phase.append({"x": b + ".x", "y": b + ".vx"})

    # A fake running estimate that settles like the real one would: marked as a stand-in.
    interval = max(period / 100.0, float(time[-1] - time[0]) / max_points)
    t_l = np.arange(interval, time[-1] + 0.5 * interval, interval)
    lam = 12.0
    hist = lam + 80.0 * np.exp(-t_l / (2.0 * period)) * np.cos(2 * math.pi * t_l / period) \
        + 5.0 * np.sin(7.0 * t_l / period) / np.sqrt(1.0 + t_l / interval)
    lyapunov = {"exponent": float(hist[-1]) if len(hist) else lam, "unit": "1/s",
                "renormalisations": int(len(t_l)), "interval": interval,
                "history": np.column_stack([t_l, hist]).tolist(), "note": "stand-in"}

    status = summary.get("status", {"ok": True, "time": float(time[-1]), "element": "",
                                    "message": ""})
    return {
        "version": 1,
        "model": model,
        "status": status,
        "integrator": summary.get("integrator"),
        "max_constraint_violation": summary.get("max_constraint_violation"),
        "series": {"time": tolist(t_dec),
                   "crank_angle": tolist(angle[pick]) if angle is not None else None,
                   "channels": channels, "ideal": ideal},
        "frames": frames,
        "channel_info": channel_info(summary, list(channels) + list(ideal_full)),
        "analysis": {
            "statistics": statistics, "comparison": comparison or None,
            "clearance": clearance or None, "poincare": poincare, "spectra": spectra,
            "phase": phase or None, "lyapunov": lyapunov,
            "verdict": {"class": "undetermined",
                        "evidence": ["stand-in sample from tests/figures/make_sample.py"]},
        },
    }


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("run_dir", help="output folder of `lash run`")
    p.add_argument("--ideal", help="output folder of the same model run with clearance 0")
    p.add_argument("-o", "--output", help="file to write (default RUN_DIR/report_data.json)")
    p.add_argument("--period", type=float, default=0.012, help="crank period, s")
    p.add_argument("--max-points", type=int, default=MAX_SERIES_POINTS)
    a = p.parse_args(argv)
    report = build(a.run_dir, a.ideal, a.period, a.max_points)
    out = a.output or os.path.join(a.run_dir, "report_data.json")
    with open(out, "w") as f:
        json.dump(report, f, allow_nan=False)
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
