#!/usr/bin/env python3
"""Builds a realistic report_data.json (docs/report-data.md) from a `lash run` output folder.

This is the report page's development and test fixture, not the analysis layer: the analysis keys
are simple stand-ins computed with plain Python (no numpy), so that the page sees data of the
right shape, size and order of magnitude. The C++ `lash report` computes the real ones.

    make_sample_data.py RUN_DIR [--ideal IDEAL_RUN_DIR] [-o report_data.json]
                        [--sparse]            # null/absent analysis, ideal and crank angle
                        [--no-channel-info]   # no channel_info: a file from an older engine

channel_info (the unit and description of every channel) is copied from summary.json's
channels.<name>.unit/.description, which the engine writes. The fixture adds two sensor channels
whose names say nothing of their unit (acc1.a in m/s², load_cell.x in N, which a suffix rule would
read as metres), so that the page test can tell units taken from the data from guessed ones.

RUN_DIR holds timeseries.csv, events.csv, summary.json and model_resolved.yaml, e.g. from
`build/lash run examples/flores_slider_crank.yaml -o /tmp/run -q --set solver.end_time=0.12`.
"""
import argparse
import bisect
import cmath
import csv
import json
import math
import os
import sys

MAX_POINTS = 4000   # decimated series length (contract: <= ~4000)
MAX_FRAMES = 600    # animation frames (contract: <= ~600)

# Sensor channels the fixture adds: name -> (source column, unit, description).
SENSORS = {"acc1.a": ("slider.ax", "m/s²", "accelerometer acc1 on the slider"),
           "load_cell.x": ("slider_guide.F", "N", "guide load cell force")}



# --- a small YAML subset reader: block maps, flow maps/lists, scalars, comments ----------------
# model_resolved.yaml is written by lash in this subset; PyYAML is not assumed to be installed.
def _scalar(text):
    text = text.strip()
    if len(text) >= 2 and text[0] == text[-1] and text[0] in "'\"":
        return text[1:-1]
    low = text.lower()
    if low in ("true", "false"):
        return low == "true"
    if low in ("null", "~", ""):
        return None
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


def _flow(text, i):
    """Parses a flow value starting at text[i]; returns (value, next index)."""
    while text[i] == " ":
        i += 1
    if text[i] in "[{":
        close = "]" if text[i] == "[" else "}"
        is_map = text[i] == "{"
        out = {} if is_map else []
        i += 1
        while True:
            while text[i] in " ,":
                i += 1
            if text[i] == close:
                return out, i + 1
            if is_map:
                colon = text.index(":", i)
                key = text[i:colon].strip()
                value, i = _flow(text, colon + 1)
                out[key] = value
            else:
                value, i = _flow(text, i)
                out.append(value)
    j = i
    while j < len(text) and text[j] not in ",]}":
        j += 1
    return _scalar(text[i:j]), j


def _strip_comment(line):
    quote = None
    for k, ch in enumerate(line):
        if ch in "'\"":
            quote = None if quote == ch else (ch if quote is None else quote)
        elif ch == "#" and quote is None and (k == 0 or line[k - 1] in " \t"):
            return line[:k]
    return line


def load_yaml_subset(text):
    lines = []
    for raw in text.splitlines():
        line = _strip_comment(raw).rstrip()
        if line.strip():
            lines.append((len(line) - len(line.lstrip(" ")), line.strip()))
    root = {}
    stack = [(-1, root)]
    for n, (indent, body) in enumerate(lines):
        while stack[-1][0] >= indent:
            stack.pop()
        parent = stack[-1][1]
        key, _, rest = body.partition(":")
        rest = rest.strip()
        if rest:
            parent[key.strip()] = _flow(rest, 0)[0] if rest[0] in "[{" else _scalar(rest)
        else:
            child = {}
            parent[key.strip()] = child
            stack.append((indent, child))
    return root


# --- reading a run folder -----------------------------------------------------------------------
def read_timeseries(path):
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = next(reader)
        cols = [[] for _ in header]
        for row in reader:
            for k, v in enumerate(row):
                cols[k].append(float(v))
    return dict(zip(header, cols))


def read_events(path):
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        return [{"time": float(r["time"]), "joint": r["joint"], "event": r["event"],
                 "velocity": float(r["velocity"])} for r in csv.DictReader(f)]


def stride_indices(n, most):
    step = max(1, math.ceil(n / most))
    idx = list(range(0, n, step))
    if idx[-1] != n - 1:
        idx.append(n - 1)
    return idx


def interp(ts, ys, t):
    k = bisect.bisect_left(ts, t)
    if k <= 0:
        return ys[0]
    if k >= len(ts):
        return ys[-1]
    t0, t1 = ts[k - 1], ts[k]
    w = 0.0 if t1 == t0 else (t - t0) / (t1 - t0)
    return ys[k - 1] + w * (ys[k] - ys[k - 1])


def rounded(values, digits=6):
    """Keeps the JSON small: 6 significant digits are plenty for display."""
    return [float(f"{v:.{digits}g}") for v in values]


# --- the model section ----------------------------------------------------------------------------
def split_ref(ref):
    body, _, marker = ref.partition(".")
    return body, marker


def marker_point(model_yaml, ref):
    body, marker = split_ref(ref)
    if body == "ground":
        return model_yaml.get("ground", {}).get("markers", {}).get(marker, [0, 0])
    return model_yaml["bodies"][body].get("markers", {}).get(marker, [0, 0])


def build_model(model_yaml, summary):
    defaults = model_yaml.get("clearance_defaults", {}) or {}
    bodies = [{"name": name, "mass": b.get("mass"), "inertia": b.get("inertia"),
               "markers": b.get("markers", {})}
              for name, b in model_yaml.get("bodies", {}).items()]
    joints = []
    for name, j in model_yaml.get("joints", {}).items():
        jtype = j.get("type", "revolute")
        if jtype == "translational":
            a_ref, b_ref = j["guide"], j["slider"]
        elif jtype == "revolute":
            a_ref, b_ref = j["journal"], j["bearing"]
        else:
            a_ref, b_ref = j.get("a", "ground.O"), j.get("b", "ground.O")
        entry = {"name": name, "type": jtype,
                 "a": {"body": split_ref(a_ref)[0], "point": marker_point(model_yaml, a_ref)},
                 "b": {"body": split_ref(b_ref)[0], "point": marker_point(model_yaml, b_ref)},
                 "axis": j.get("axis"), "clearance": None}
        if "clearance" in j or "bearing_radius" in j:
            rj = j.get("journal_radius", defaults.get("journal_radius"))
            c = j.get("clearance")
            rb = j.get("bearing_radius", rj + c if c is not None else None)
            if c is None:
                c = rb - rj
            friction = j.get("friction", defaults.get("friction", {})) or {}
            entry["clearance"] = {"clearance": c, "journal_radius": rj, "bearing_radius": rb,
                                  "normal_law": j.get("normal_law", defaults.get("normal_law")),
                                  "friction_law": friction.get("law", "none")}
        joints.append(entry)
    drivers = []
    for name, d in (model_yaml.get("drivers", {}) or {}).items():
        speed = d.get("speed")
        if speed is None and d.get("speed_rpm") is not None:
            speed = d["speed_rpm"] * 2 * math.pi / 60
        drivers.append({"name": name, "joint": d.get("joint"), "speed": speed,
                        "profile": d.get("profile", "constant_speed")})
    s = summary.get("solver", {})
    solver = {k: s.get(k) for k in ("integrator", "rtol", "atol", "end_time", "output_interval")}
    return {"name": summary["model"]["name"], "file": summary["model"].get("file", ""),
            "bodies": bodies, "ground_markers": model_yaml.get("ground", {}).get("markers", {}),
            "joints": joints, "drivers": drivers, "solver": solver}


# --- stand-in analyses ----------------------------------------------------------------------------
def statistics(t, y, window):
    sel = [v for ti, v in zip(t, y) if window[0] <= ti <= window[1]] or y
    lo, hi = min(sel), max(sel)
    peak = max(abs(lo), abs(hi))
    rms = math.sqrt(sum(v * v for v in sel) / len(sel))
    return {"min": lo, "max": hi, "peak": peak, "rms": rms,
            "crest": peak / rms if rms > 0 else None, "window": window}


def fft(values):
    """Radix-2 Cooley–Tukey; len(values) must be a power of two."""
    n = len(values)
    if n == 1:
        return list(values)
    even, odd = fft(values[0::2]), fft(values[1::2])
    out = [0j] * n
    for k in range(n // 2):
        w = cmath.exp(-2j * math.pi * k / n) * odd[k]
        out[k], out[k + n // 2] = even[k] + w, even[k] - w
    return out


def spectrum(t, y, t_from, f_max):
    """Single-sided Hann-windowed amplitude spectrum of y(t >= t_from), resampled to 2^m points."""
    t0, t1 = t_from, t[-1]
    n = 1
    while n * 2 <= sum(1 for ti in t if ti >= t0):
        n *= 2
    n = min(n, 8192)
    dt = (t1 - t0) / n
    samples = [interp(t, y, t0 + k * dt) for k in range(n)]
    mean = sum(samples) / n
    hann = [0.5 - 0.5 * math.cos(2 * math.pi * k / n) for k in range(n)]
    coeffs = fft([(s - mean) * w for s, w in zip(samples, hann)])
    freq, amp = [], []
    for k in range(1, n // 2):
        f = k / (n * dt)
        if f > f_max:
            break
        freq.append(f)
        amp.append(4.0 * abs(coeffs[k]) / n)   # 2 for single-sided, 2 for the Hann gain
    return {"frequency": rounded(freq, 6), "amplitude": rounded(amp, 5), "window": "hann",
            "discarded_time": t_from}


def clearance_analysis(name, clearance, t, cols, events, end_time, period):
    ex, ey = cols[name + ".ex"], cols[name + ".ey"]
    idx = stride_indices(len(t), 2000)
    onsets = [e for e in events if e["joint"] == name and e["event"] == "onset"]
    episodes = []
    pending = None
    for e in (e for e in events if e["joint"] == name):
        if e["event"] == "onset":
            pending = e["time"]
        elif e["event"] == "separation" and pending is not None:
            episodes.append([pending, e["time"]])
            pending = None
    if pending is not None:
        episodes.append([pending, end_time])
    # An episode shorter than 1 % of a period is an impact; longer contact is continuous.
    threshold = 0.01 * period if period else 1e-4
    for ep in episodes:
        ep.append("impact" if ep[1] - ep[0] < threshold else "continuous")
    impact_time = sum(b - a for a, b, k in episodes if k == "impact")
    continuous_time = sum(b - a for a, b, k in episodes if k == "continuous")
    total = end_time - t[0]
    velocities = [e["velocity"] for e in onsets]
    vmax = max(velocities) if velocities else 1.0
    bins = 12
    width = vmax / bins if vmax > 0 else 1.0
    edges = [k * width for k in range(bins + 1)]
    counts = [0] * bins
    for v in velocities:
        counts[min(bins - 1, int(v / width))] += 1
    return {
        "clearance": clearance,
        "orbit": {"ex": rounded([ex[k] for k in idx]), "ey": rounded([ey[k] for k in idx])},
        "modes": {"free_flight_share": (total - impact_time - continuous_time) / total,
                  "impact_share": impact_time / total, "continuous_share": continuous_time / total,
                  "impacts": len(onsets), "continuous_contact_time": continuous_time,
                  "episodes": [[float(f"{a:.9g}"), float(f"{b:.9g}"), k] for a, b, k in episodes]},
        "impact_velocities": rounded(velocities, 6),
        "histogram": {"edges": rounded(edges, 6), "counts": counts},
    }


def poincare(t, cols, joint, period, discard):
    points = []
    k = discard
    while k * period <= t[-1] + 1e-12:
        tk = min(k * period, t[-1])
        points.append([interp(t, cols[joint + ".ex"], tk), interp(t, cols[joint + ".ey"], tk)])
        k += 1
    distinct = []
    for p in points:
        if not any(math.hypot(p[0] - q[0], p[1] - q[1]) < 2e-6 for q in distinct):
            distinct.append(p)
    return {"kind": "stroboscopic", "period": period, "discarded_periods": discard,
            "variables": [joint + ".ex", joint + ".ey"],
            "points": [rounded(p) for p in points], "distinct": len(distinct)}


def lyapunov_stand_in(t, cols, joint, period, interval):
    """Running mean of the log growth of the distance between the journal orbit and the same orbit
    one period earlier: a stand-in with the shape of a Lyapunov estimate, not a real one."""
    ex, ey = cols[joint + ".ex"], cols[joint + ".ey"]
    def gap(tk):
        return math.hypot(interp(t, ex, tk) - interp(t, ex, tk - period),
                          interp(t, ey, tk) - interp(t, ey, tk - period)) + 1e-12
    history, total, n = [], 0.0, 0
    tk = period
    while tk + interval <= t[-1]:
        total += math.log(gap(tk + interval) / gap(tk))
        n += 1
        tk += interval
        history.append([float(f"{tk:.9g}"), float(f"{total / (n * interval):.6g}")])
    stride = max(1, len(history) // 400)
    return {"exponent": history[-1][1] if history else None, "unit": "1/s",
            "renormalisations": n, "interval": interval, "history": history[::stride]}


def channel_info(summary, names):
    """{name: {"unit", "description"}} for every channel: the sensors', else summary.json's (the
    engine writes a unit and description for every channel it outputs)."""
    described = summary.get("channels") if isinstance(summary.get("channels"), dict) else {}
    info = {}
    for name in names:
        entry = described.get(name)
        if name in SENSORS:
            unit, description = SENSORS[name][1:]
        elif isinstance(entry, dict) and isinstance(entry.get("unit"), str):
            unit, description = entry["unit"], entry.get("description") or name
        else:
            sys.exit(f"make_sample_data: summary.json gives no unit for channel '{name}'")
        info[name] = {"unit": unit, "description": description}
    return info


# --- assembling ------------------------------------------------------------------------------------
def build(run_dir, ideal_dir, sparse, with_channel_info=True):
    summary = json.load(open(os.path.join(run_dir, "summary.json")))
    yaml_path = os.path.join(run_dir, "model_resolved.yaml")
    yaml_text = open(yaml_path).read() if os.path.exists(yaml_path) else summary["model"]["resolved"]
    model_yaml = load_yaml_subset(yaml_text)
    cols = read_timeseries(os.path.join(run_dir, "timeseries.csv"))
    events = read_events(os.path.join(run_dir, "events.csv"))
    for name, (source, _, _) in SENSORS.items():
        if source in cols:
            cols[name] = [1.02 * v for v in cols[source]]
    t = cols["time"]
    idx = stride_indices(len(t), MAX_POINTS)
    model = build_model(model_yaml, summary)
    channels = {name: rounded([v[k] for k in idx]) for name, v in cols.items() if name != "time"}

    # Crank angle of the first rotary driver whose bearing is the ground, in degrees [0, 360).
    crank_angle = None
    driver_speed = None
    for d in model["drivers"]:
        joint = next((j for j in model["joints"] if j["name"] == d["joint"]), None)
        if joint and joint["type"] == "revolute" and joint["b"]["body"] == "ground":
            phi = cols[joint["a"]["body"] + ".phi"]
            crank_angle = [float(f"{math.degrees(phi[k]) % 360.0:.6g}") for k in idx]
            driver_speed = d["speed"]
            break
    period = 2 * math.pi / driver_speed if driver_speed else None

    ideal = None
    if ideal_dir:
        icols = read_timeseries(os.path.join(ideal_dir, "timeseries.csv"))
        ideal = {name: rounded([interp(icols["time"], icols[name], t[k]) for k in idx])
                 for name in icols if name != "time" and name in cols}

    fidx = stride_indices(len(t), MAX_FRAMES)
    clearance_joints = [j for j in model["joints"] if j["clearance"]]
    frames = {"time": [t[k] for k in fidx],
              "bodies": {b["name"]: [rounded([cols[b["name"] + s][k] for s in (".x", ".y", ".phi")])
                                     for k in fidx] for b in model["bodies"]},
              "clearance": {j["name"]: [rounded([cols[j["name"] + ".ex"][k],
                                                 cols[j["name"] + ".ey"][k]]) for k in fidx]
                            for j in clearance_joints}}

    end_time = t[-1]
    t_steady = period if period and period < end_time / 2 else 0.0
    stat_names = [n for n in ("slider.ax", "slider.vx", "crank.torque", "crank_pivot.F",
                              "crank_rod.F", "slider_guide.F", "energy.kinetic") + tuple(SENSORS)
                  if n in cols]
    for j in clearance_joints:
        stat_names += [j["name"] + s for s in (".Fn", ".e", ".delta_dot")]
    analysis = {
        "statistics": {n: statistics(t, cols[n], [t_steady, end_time]) for n in stat_names},
        "comparison": None,
        "clearance": {j["name"]: clearance_analysis(j["name"], j["clearance"]["clearance"], t,
                                                    cols, events, end_time, period)
                      for j in clearance_joints},
        "poincare": None, "spectra": None, "lyapunov": None, "verdict": None,
        "phase": [{"x": "slider.x", "y": "slider.vx"}],
    }
    if ideal_dir:
        comparison = {}
        for n in stat_names:
            if n in icols:
                yi = [interp(icols["time"], icols[n], tk) for tk in t]
                dev = [a - b for a, b in zip(cols[n], yi)]
                ideal_peak = max(abs(v) for v in yi)
                comparison[n] = {
                    "rms_deviation": math.sqrt(sum(d * d for d in dev) / len(dev)),
                    "max_deviation": max(abs(d) for d in dev),
                    "peak_ratio": max(abs(v) for v in cols[n]) / ideal_peak if ideal_peak else None,
                    "ideal_peak": ideal_peak}
        analysis["comparison"] = comparison
    spectra_names = [n for n in ("slider.ax", "crank.torque") if n in cols]
    for j in clearance_joints:
        spectra_names.append(j["name"] + ".Fn")
    analysis["spectra"] = {n: spectrum(t, cols[n], t_steady, 20000.0) for n in spectra_names}
    if clearance_joints and period:
        first = clearance_joints[0]["name"]
        analysis["phase"].insert(0, {"x": first + ".ex", "y": first + ".vt"})
        analysis["phase"].append({"x": first + ".e", "y": first + ".delta_dot"})
        analysis["poincare"] = poincare(t, cols, first, period, 1)
        analysis["lyapunov"] = lyapunov_stand_in(t, cols, first, period, 1e-4)
        pc = analysis["poincare"]
        n_points = len(pc["points"])
        lam = analysis["lyapunov"]["exponent"]
        if n_points < 4:
            cls = "undetermined"
        elif pc["distinct"] == 1:
            cls = "periodic"
        elif pc["distinct"] < n_points // 2:
            cls = "periodic" if lam is not None and lam <= 0 else "quasi-periodic"
        else:
            cls = "chaotic" if lam is not None and lam > 0 else "quasi-periodic"
        modes = analysis["clearance"][first]["modes"]
        analysis["verdict"] = {"class": cls, "evidence": [
            f"{pc['distinct']} distinct Poincaré point(s) over {n_points} periods "
            f"(stroboscopic at T = {period * 1e3:.3f} ms, {pc['discarded_periods']} discarded)",
            f"largest Lyapunov exponent estimate {lam:.3g} 1/s "
            f"({analysis['lyapunov']['renormalisations']} renormalisations)",
            f"{modes['impacts']} impacts; free flight {100 * modes['free_flight_share']:.1f} % "
            f"of the time",
            "sample data: the analysis values are stand-ins from tests/report/make_sample_data.py",
        ]}

    status = dict(summary.get("status") or {"ok": True, "element": "", "message": ""})
    if status.get("ok") and not status.get("time"):
        status["time"] = end_time   # summary.json leaves 0 on success; the contract wants the end
    data = {
        "version": 1,
        "model": model,
        "status": status,
        "integrator": summary.get("integrator"),
        "max_constraint_violation": summary.get("max_constraint_violation"),
        "series": {"time": [float(f"{t[k]:.9g}") for k in idx], "crank_angle": crank_angle,
                   "channels": channels, "ideal": ideal},
        "frames": frames,
        "analysis": analysis,
    }
    if with_channel_info:
        data["channel_info"] = channel_info(summary, [n for n in cols if n != "time"])
    if sparse:
        # The shape a report has when nothing optional was computed: every consumer must cope.
        data["series"]["crank_angle"] = None
        data["series"]["ideal"] = None
        data["analysis"] = {"statistics": data["analysis"]["statistics"], "comparison": None,
                            "clearance": None, "poincare": None, "phase": None, "lyapunov": None}
        data["frames"]["clearance"] = {}
        data["integrator"] = None
    return data


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run_dir")
    ap.add_argument("--ideal", help="run folder of the ideal twin (same time base)")
    ap.add_argument("-o", "--output", default="report_data.json")
    ap.add_argument("--sparse", action="store_true",
                    help="leave out every optional section (tests graceful 'not computed')")
    ap.add_argument("--no-channel-info", action="store_true",
                    help="leave out channel_info, as a file from an engine without channel units")
    args = ap.parse_args()
    data = build(args.run_dir, args.ideal, args.sparse, not args.no_channel_info)
    with open(args.output, "w") as f:
        json.dump(data, f, separators=(",", ":"), allow_nan=False)
    print(f"wrote {args.output} ({os.path.getsize(args.output) / 1024:.0f} KiB)", file=sys.stderr)


if __name__ == "__main__":
    main()
