#!/usr/bin/env python3
"""Write RESULTS.md for a finished `lash sweep` study, from its study.db alone.

    python3 studies/results.py STUDY_DIR [--copy-to DIR]

Reads STUDY_DIR/study.db (schema in docs/studies.md) and writes STUDY_DIR/RESULTS.md: how the
study was run, one table row per run (its parameters, status and metrics) and, when the study has a
claims module, the comparison with the paper's statements. With --copy-to the same file is also
written to DIR/RESULTS.md (`make studies` copies it next to the study file, studies/NAME/).

A claims module is studies/claims/<study name>.py. It may define
  COLUMNS: a list of (metric, header, scale, format) for the table (default: every `.peak` and
           every contact share and impact count);
  claims(runs) -> list of Markdown paragraphs, computed from the numbers: `runs` is a list of
           dicts {"run", "params" (name → level), "status", "verdict", "metrics" (name → value)};
  folder_claims(folder, runs) -> the same, for claims that need more of study.db than the
           metrics (the kept series: the breaker studies' stroke deviation); used instead of
           claims when defined;
  FIGURES: a list of SVG figures, each written beside RESULTS.md and shown in it, one of
           {"file", "title", "metric", "ylabel", "x", "series"}: a run metric against the levels
               of parameter "x", one line per level of parameter "series" (optional: one line);
           {"kind": "sections", "file", "title", "channel", "x", "ylabel", "series"}: every
               kept section value of `channel` against the numeric parameter "x", dots, one
               colour per level of "series" (optional) — a bifurcation diagram;
           {"kind": "section_map", "file", "title", "x_channel", "y_channel", "series",
               "xlabel", "ylabel"}: the kept section values of two channels against each other
               (a Poincaré map), dots, one colour per level of "series";
           {"kind": "series", "file", "title", "channel", "series", "ylabel", "where"}: the kept
               decimated time series of `channel`, one line per level of parameter "series",
               only the runs whose parameters equal "where" ({name: level}, optional).
Nothing in RESULTS.md is typed by hand: every number comes from study.db.
Standard library only (sqlite3), so it runs wherever Python 3 does.
"""
import argparse
import importlib.util
import json
import math
import os
import sqlite3
import sys


def read_study(folder):
    """The study's description, parameters and runs (with their metrics) from study.db."""
    path = os.path.join(folder, "study.db")
    if not os.path.isfile(path):
        sys.exit(f"error: {path}: no study database (run `lash sweep` first)")
    db = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
    info = dict(db.execute("select key, value from study"))
    params = [r[0] for r in db.execute("select name from parameters order by position")]
    cols = [r[1] for r in db.execute("pragma table_info(runs)")]
    runs = []
    for row in db.execute("select * from runs order by run"):
        r = dict(zip(cols, row))
        runs.append({"run": r["run"], "params": {p: r[p] for p in params}, "status": r["status"],
                     "verdict": r["verdict"] or "", "message": r["message"] or "",
                     "wall_seconds": r["wall_seconds"] or 0.0, "metrics": {}})
    by_index = {r["run"]: r for r in runs}
    for run, name, value in db.execute("select run, name, value from metrics"):
        if run in by_index:
            by_index[run]["metrics"][name] = value
    db.close()
    return info, params, runs


def load_claims(study_name):
    """The study's claims module (studies/claims/<name>.py) or None."""
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "claims", study_name + ".py")
    if not os.path.isfile(path):
        return None
    spec = importlib.util.spec_from_file_location("claims_" + study_name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def default_columns(runs):
    """Every peak and every contact-mode number the runs hold, in first-seen order."""
    names = []
    for r in runs:
        for n in r["metrics"]:
            if n not in names and (n.endswith(".peak") or n.endswith(".impacts")
                                   or n.endswith("_share")):
                names.append(n)
    return [(n, n, 1.0, ".4g") for n in names]


def cell(value, scale, fmt):
    return "–" if value is None else format(value * scale, fmt)


def table(params, runs, columns):
    head = params + ["status"] + [c[1] for c in columns]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in runs:
        row = [str(r["params"][p]) for p in params] + [r["status"]]
        row += [cell(r["metrics"].get(m), s, f) for m, _, s, f in columns]
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


PALETTE = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"]


def line_chart_svg(title, xlabels, series, ylabel):
    """A self-contained SVG: one line with markers per series over the categorical x levels."""
    w, h, left, right, top, bottom = 700, 400, 70, 200, 40, 50
    values = [v for vs in series.values() for v in vs if v is not None]
    ymax = max(values) * 1.08 if values and max(values) > 0 else 1.0
    px = lambda i: left + (i + 0.5) * (w - left - right) / max(1, len(xlabels))
    py = lambda v: top + (h - top - bottom) * (1 - v / ymax)
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" '
           f'font-family="sans-serif" font-size="12">',
           f'<rect width="{w}" height="{h}" fill="white"/>',
           f'<text x="{w / 2}" y="22" text-anchor="middle" font-size="14">{title}</text>',
           f'<line x1="{left}" y1="{h - bottom}" x2="{w - right}" y2="{h - bottom}" stroke="black"/>',
           f'<line x1="{left}" y1="{top}" x2="{left}" y2="{h - bottom}" stroke="black"/>',
           f'<text transform="translate(16,{(top + h - bottom) / 2}) rotate(-90)" '
           f'text-anchor="middle">{ylabel}</text>']
    for k in range(6):
        v = ymax * k / 5
        out.append(f'<line x1="{left - 4}" y1="{py(v):.1f}" x2="{w - right}" y2="{py(v):.1f}" '
                   f'stroke="#ddd"/><text x="{left - 6}" y="{py(v) + 4:.1f}" '
                   f'text-anchor="end">{v:.3g}</text>')
    for i, x in enumerate(xlabels):
        out.append(f'<text x="{px(i):.1f}" y="{h - bottom + 18}" text-anchor="middle">{x}</text>')
    for n, (name, vs) in enumerate(series.items()):
        c = PALETTE[n % len(PALETTE)]
        pts = [(px(i), py(v)) for i, v in enumerate(vs) if v is not None]
        if len(pts) > 1:
            out.append('<polyline fill="none" stroke="%s" stroke-width="2" points="%s"/>'
                       % (c, " ".join(f"{a:.1f},{b:.1f}" for a, b in pts)))
        out += [f'<circle cx="{a:.1f}" cy="{b:.1f}" r="4" fill="{c}"/>' for a, b in pts]
        ly = top + 10 + 18 * n
        out.append(f'<line x1="{w - right + 12}" y1="{ly}" x2="{w - right + 32}" y2="{ly}" '
                   f'stroke="{c}" stroke-width="2"/><text x="{w - right + 38}" y="{ly + 4}">{name}</text>')
    out.append("</svg>")
    return "\n".join(out) + "\n"


def nice_ticks(lo, hi, n=5):
    """About n round tick values covering [lo, hi]."""
    if not (hi > lo):
        hi = lo + (abs(lo) if lo else 1.0)
    raw = (hi - lo) / n
    mag = 10 ** math.floor(math.log10(raw))
    step = next(m * mag for m in (1, 2, 2.5, 5, 10) if m * mag >= raw)
    first = math.floor(lo / step) * step
    ticks, k = [], 0
    while first + k * step <= hi + 1e-9 * step:
        ticks.append(first + k * step)
        k += 1
    return ticks


def xy_chart_svg(title, xlabel, ylabel, datasets):
    """A self-contained SVG on numeric axes: datasets are (name, xs, ys, "line" or "dots")."""
    w, h, left, right, top, bottom = 760, 420, 80, 190, 40, 56
    xs = [x for _, dx, _, _ in datasets for x in dx]
    ys = [y for _, _, dy, _ in datasets for y in dy]
    if not xs:
        xs, ys = [0.0, 1.0], [0.0, 1.0]
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    if x1 <= x0:
        x1 = x0 + 1.0
    if y1 <= y0:
        y1 = y0 + 1.0
    # A margin so that no dot or peak sits on the frame (none along a time axis starting at 0).
    y0, y1 = y0 - 0.04 * (y1 - y0), y1 + 0.04 * (y1 - y0)
    if any(style == "dots" for _, _, _, style in datasets):
        x0, x1 = x0 - 0.04 * (x1 - x0), x1 + 0.04 * (x1 - x0)
    xt = [v for v in nice_ticks(x0, x1) if x0 <= v <= x1]
    yt = [v for v in nice_ticks(y0, y1) if y0 <= v <= y1]
    px = lambda x: left + (w - left - right) * (x - x0) / (x1 - x0)
    py = lambda y: top + (h - top - bottom) * (1 - (y - y0) / (y1 - y0))
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" '
           f'font-family="sans-serif" font-size="12">',
           f'<rect width="{w}" height="{h}" fill="white"/>',
           f'<text x="{w / 2}" y="22" text-anchor="middle" font-size="14">{title}</text>',
           f'<rect x="{left}" y="{top}" width="{w - left - right}" height="{h - top - bottom}" '
           f'fill="none" stroke="black"/>',
           f'<text transform="translate(16,{(top + h - bottom) / 2}) rotate(-90)" '
           f'text-anchor="middle">{ylabel}</text>',
           f'<text x="{(left + w - right) / 2}" y="{h - 12}" text-anchor="middle">{xlabel}</text>']
    for v in yt:
        out.append(f'<line x1="{left - 4}" y1="{py(v):.1f}" x2="{w - right}" y2="{py(v):.1f}" '
                   f'stroke="#ddd"/><text x="{left - 6}" y="{py(v) + 4:.1f}" '
                   f'text-anchor="end">{v:.4g}</text>')
    for v in xt:
        out.append(f'<line x1="{px(v):.1f}" y1="{h - bottom}" x2="{px(v):.1f}" y2="{h - bottom + 4}" '
                   f'stroke="black"/><text x="{px(v):.1f}" y="{h - bottom + 18}" '
                   f'text-anchor="middle">{v:.4g}</text>')
    for n, (name, dx, dy, style) in enumerate(datasets):
        c = PALETTE[n % len(PALETTE)]
        pts = [(px(a), py(b)) for a, b in zip(dx, dy)]
        if style == "line" and len(pts) > 1:
            out.append('<polyline fill="none" stroke="%s" stroke-width="1.2" points="%s"/>'
                       % (c, " ".join(f"{a:.1f},{b:.1f}" for a, b in pts)))
        elif style == "dots":
            out += [f'<circle cx="{a:.1f}" cy="{b:.1f}" r="1.3" fill="{c}"/>' for a, b in pts]
        ly = top + 10 + 18 * n
        out.append(f'<line x1="{w - right + 12}" y1="{ly}" x2="{w - right + 32}" y2="{ly}" '
                   f'stroke="{c}" stroke-width="2"/><text x="{w - right + 38}" y="{ly + 4}">{name}</text>')
    out.append("</svg>")
    return "\n".join(out) + "\n"


def read_table(folder, query, args=()):
    db = sqlite3.connect(f"file:{os.path.join(folder, 'study.db')}?mode=ro", uri=True)
    rows = list(db.execute(query, args))
    db.close()
    return rows


def figure(spec, runs, folder):
    """The SVG text of one FIGURES entry."""
    kind = spec.get("kind", "metric")
    by_run = {r["run"]: r for r in runs if r["status"] == "completed"}
    level = lambda r, p: str(r["params"][p]) if p else spec.get("channel", spec.get("metric", ""))
    if kind == "sections":
        groups = {}
        for run, value in read_table(folder, "select run, value from sections where channel = ? "
                                             "order by run, k", (spec["channel"],)):
            if run in by_run:
                r = by_run[run]
                g = groups.setdefault(level(r, spec.get("series")), ([], []))
                g[0].append(float(r["params"][spec["x"]]))
                g[1].append(value)
        # Several series at the same levels (up and down): each shifted by a fraction of the
        # levels' spacing, so that neither hides the other.
        levels = sorted({x for xs, _ in groups.values() for x in xs})
        gaps = [b - a for a, b in zip(levels, levels[1:]) if b > a]
        dodge = 0.25 * min(gaps) / max(1, len(groups) - 1) if gaps and len(groups) > 1 else 0.0
        return xy_chart_svg(spec["title"], spec["x"], spec["ylabel"],
                            [(k, [x + (i - (len(groups) - 1) / 2) * dodge for x in xs], ys, "dots")
                             for i, (k, (xs, ys)) in enumerate(groups.items())])
    if kind == "section_map":
        points = {}
        for run, k, channel, value in read_table(
                folder, "select run, k, channel, value from sections where channel in (?, ?)",
                (spec["x_channel"], spec["y_channel"])):
            if run in by_run:
                points.setdefault((run, k), {})[channel] = value
        groups = {}
        for (run, _), p in sorted(points.items()):
            if spec["x_channel"] in p and spec["y_channel"] in p:
                g = groups.setdefault(level(by_run[run], spec.get("series")), ([], []))
                g[0].append(p[spec["x_channel"]])
                g[1].append(p[spec["y_channel"]])
        return xy_chart_svg(spec["title"], spec["xlabel"], spec["ylabel"],
                            [(k, xs, ys, "dots") for k, (xs, ys) in groups.items()])
    if kind == "series":
        where = {k: str(v) for k, v in spec.get("where", {}).items()}
        datasets = []
        for run, t, v in read_table(folder, "select run, time, value from series where channel = ? "
                                            "order by run", (spec["channel"],)):
            r = by_run.get(run)
            if r is None or any(str(r["params"][k]) != v for k, v in where.items()):
                continue
            datasets.append((level(r, spec.get("series")), json.loads(t), json.loads(v), "line"))
        return xy_chart_svg(spec["title"], "time (s)", spec["ylabel"], datasets)
    xs, ss = [], []
    for r in runs:
        x, s = str(r["params"][spec["x"]]), level(r, spec.get("series"))
        if x not in xs:
            xs.append(x)
        if s not in ss:
            ss.append(s)
    val = {(str(r["params"][spec["x"]]), level(r, spec.get("series"))): r["metrics"].get(spec["metric"])
           for r in by_run.values()}
    series = {s: [val.get((x, s)) for x in xs] for s in ss}
    return line_chart_svg(spec["title"], xs, series, spec["ylabel"])


def write(folder, copy_to=None):
    info, params, runs = read_study(folder)
    name = info.get("name", os.path.basename(os.path.normpath(folder)))
    module = load_claims(name)
    columns = getattr(module, "COLUMNS", None) or default_columns(runs)
    done = sum(r["status"] == "completed" for r in runs)
    total = int(float(info.get("runs", len(runs))))
    wall = sum(r["wall_seconds"] for r in runs)
    out = [f"# {name}: results", "",
           f"Generated by `python3 studies/results.py` from `study.db` of "
           f"`lash sweep {info.get('study_file', '')}` (`make studies`); do not edit by hand.",
           "", f"{done} of {total} runs completed ({len(runs)} recorded); "
           f"{wall:.0f} s of run time in all.", ""]
    failed = [r for r in runs if r["status"] != "completed"]
    for r in failed:
        out.append(f"- run {r['run']} {r['params']}: {r['status']}: {r['message']}")
    if failed:
        out.append("")
    if module and hasattr(module, "PREAMBLE"):
        out += [module.PREAMBLE, ""]
    out += ["## Table", "", table(params, runs, columns), ""]
    svgs = {}
    for spec in getattr(module, "FIGURES", []) if module else []:
        svgs[spec["file"]] = figure(spec, runs, folder)
        out += [f"![{spec['title']}]({spec['file']})", ""]
    if module and (hasattr(module, "folder_claims") or hasattr(module, "claims")):
        out += ["## Against the paper", ""]
        paragraphs = (module.folder_claims(folder, runs) if hasattr(module, "folder_claims")
                      else module.claims(runs))
        for paragraph in paragraphs:
            out += [paragraph, ""]
    text = "\n".join(out)
    targets = [os.path.join(folder, "RESULTS.md")]
    if copy_to:
        os.makedirs(copy_to, exist_ok=True)
        targets.append(os.path.join(copy_to, "RESULTS.md"))
    for t in targets:
        with open(t, "w", encoding="utf-8") as f:
            f.write(text)
        for name, svg in svgs.items():
            with open(os.path.join(os.path.dirname(t), name), "w", encoding="utf-8") as f:
                f.write(svg)
        print(f"wrote {t}" + (f" and {len(svgs)} figure(s)" if svgs else ""))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("study_dir", help="a folder written by `lash sweep` (holds study.db)")
    ap.add_argument("--copy-to", help="also write RESULTS.md into this folder")
    a = ap.parse_args()
    write(a.study_dir, a.copy_to)


if __name__ == "__main__":
    main()
