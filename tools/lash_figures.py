#!/usr/bin/python3
"""Publication figures (PNG at 300 dpi, SVG) from a Lash output folder.

    lash_figures.py OUT_DIR [--format png,svg] [--only NAME ...]

Reads OUT_DIR/report_data.json (docs/report-data.md) and, for the curves whose spikes a decimated
series would clip (body accelerations, contact forces, driver efforts), OUT_DIR/timeseries.csv in
one streaming pass over the columns it needs: each column is reduced on the fly to its minimum and
maximum in each of ENVELOPE_BUCKETS time buckets, so memory does not grow with the number of rows.
Writes OUT_DIR/figures/<name>.<format> for every figure the data allows and prints the files it
wrote; a figure whose data is absent or null is skipped with a note on stderr.

Figures (family: file names), in the order of FAMILIES below:
  acceleration_peak           the body acceleration channel (*.ax, *.ay) with the largest peak
  acceleration_translational  a_x of every body on the slider side of a translational joint
  contact_force               contact_force_<joint>: F_N of each clearance joint
  orbit                       orbit_<joint>: journal-centre path (e_x, e_y) and the clearance circle
  modes                       free flight / impact / continuous contact along time, with shares
  impact_velocity             histogram of the impact velocities of each clearance joint
  poincare                    Poincaré-section points (poincare_<joint>: each further clearance
                              joint's eccentricity at the same section times)
  spectra                     amplitude spectra, logarithmic amplitude axis
  phase                       phase_<x>_vs_<y>: each pair of analysis.phase
  lyapunov                    running estimates of the Lyapunov exponents (the spectrum)
  driver_torque               driver_torque_<driver> (or driver_force_<driver>)
  energy                      kinetic, potential, dissipated, input energy and the balance drift
Curves against the crank angle use the time axis instead when there is no crank angle or the run
is too long to read (more than MAX_REVOLUTIONS_ON_ANGLE_AXIS revolutions). The ideal twin is
drawn dashed grey wherever series.ideal has the channel. When the statistics were taken over a
window narrower than the run (`lash report --window T0,T1`: analysis.statistics.*.window), the
curves against the motion, the contact modes and the energy show that window only, so figures
and statistics describe the same time. When they were taken over a crank-angle range as well
(`--angle-range A0,A1`: analysis.statistics.*.angle_range), the curves against the motion are
drawn against the crank angle folded into that range, every revolution of the window on top of
the others ("the last revolutions in steady state"), whatever the number of revolutions.

Each channel's unit and description come from report_data.json's channel_info, which the engine
writes; the display scale (mm, kN, 10³ m/s²) is chosen from that unit. A channel that
channel_info does not describe is labelled with its name and no unit: units are never guessed
from channel names.

--only takes family names or file names (without extension). Exit status: 0 when at least one
figure was written, 1 when the data allowed none, 2 on bad input (no folder, no or invalid
report_data.json, unknown --format or --only value).

Needs numpy and matplotlib: Debian's python3-numpy and python3-matplotlib, which install for
/usr/bin/python3.
"""

import argparse
import json
import math
import os
import re
import sys

PROG = "lash_figures"
FORMATS = ("png", "svg", "pdf")
PNG_DPI = 300
ENVELOPE_BUCKETS = 2000          # min/max buckets per full-resolution curve (~2 per pixel column)
CSV_CHUNK_BYTES = 8 << 20        # bytes of timeseries.csv parsed at a time
MAX_REVOLUTIONS_ON_ANGLE_AXIS = 20
MIN_SAMPLES_PER_REVOLUTION = 8   # fewer decimated samples than this: the angle cannot be unwrapped
MAX_LINE_POINTS = 4000           # smooth curves given with more points are thinned to this
MAX_VECTOR_MARKERS = 5000        # scatter plots with more points are rasterized in SVG/PDF
SINGLE_COLUMN_IN = 3.5           # figure widths of a two-column paper, inches
DOUBLE_COLUMN_IN = 7.0

# Colours (Okabe–Ito, readable in grey and by colour-blind readers); one colour per meaning.
BLUE, VERMILION, GREEN, ORANGE, PURPLE, SKY = (
    "#0072B2", "#D55E00", "#009E73", "#E69F00", "#CC79A7", "#56B4E9")
COLOR_CLEARANCE = BLUE
IDEAL_STYLE = {"color": "0.45", "linestyle": (0, (4, 2)), "linewidth": 0.9}
MODE_COLORS = {"free_flight": "0.88", "impact": VERMILION, "continuous": BLUE, "contact": BLUE}
MODE_LABELS = {"free_flight": "Free flight", "impact": "Impact", "continuous": "Continuous contact",
               "contact": "Contact"}
ENERGY_COLORS = {"kinetic": BLUE, "potential": GREEN, "dissipated": VERMILION, "input": ORANGE}

STYLE = {
    "font.family": "serif",
    "font.serif": ["STIXGeneral", "DejaVu Serif"],
    "mathtext.fontset": "stix",
    "font.size": 8, "axes.labelsize": 8, "legend.fontsize": 7,
    "xtick.labelsize": 7, "ytick.labelsize": 7,
    "axes.linewidth": 0.6, "lines.linewidth": 0.7,
    "xtick.direction": "in", "ytick.direction": "in", "xtick.top": True, "ytick.right": True,
    "xtick.major.size": 3, "ytick.major.size": 3, "xtick.minor.size": 1.5,
    "ytick.minor.size": 1.5, "xtick.major.width": 0.6, "ytick.major.width": 0.6,
    "xtick.minor.width": 0.4, "ytick.minor.width": 0.4,
    "xtick.minor.visible": True, "ytick.minor.visible": True,
    "legend.frameon": False, "legend.handlelength": 2.2, "legend.borderaxespad": 0.3,
    "axes.formatter.useoffset": False, "axes.formatter.limits": (-4, 5),
    "savefig.bbox": "tight", "savefig.pad_inches": 0.03,
    "svg.fonttype": "path", "svg.hashsalt": "lash",
}

class InputError(Exception):
    """Bad input: exit status 2 with this message."""


class Skip(Exception):
    """The data lacks what a figure needs; the message says what."""


def fail(message, status=2):
    print(f"{PROG}: error: {message}", file=sys.stderr)
    return status


# ----------------------------------------------------------------------------------------------
# Input


def load_report(out_dir):
    """report_data.json of OUT_DIR as a dict; raises InputError with a message for the user."""
    if not os.path.isdir(out_dir):
        raise InputError(f"no such folder: {out_dir}")
    path = os.path.join(out_dir, "report_data.json")
    if not os.path.isfile(path):
        raise InputError(f"{path} not found (it is written by `lash report {out_dir}`)")
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
    except json.JSONDecodeError as e:
        raise InputError(f"{path}:{e.lineno}:{e.colno}: invalid JSON: {e.msg}") from None
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"{path}: cannot read: {e}") from None
    if not isinstance(data, dict):
        raise InputError(f"{path}: expected a JSON object (docs/report-data.md), "
                         f"got {type(data).__name__}")
    version = data.get("version", 1)
    if version != 1:
        raise InputError(f"{path}: report_data version {version!r} is not supported "
                         f"(this script reads version 1)")
    return data


def as_array(values):
    """A JSON list of numbers (null = missing) as a float array, or None."""
    import numpy as np
    if values is None:
        return None
    try:
        return np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        return np.asarray([math.nan if v is None else v for v in values], dtype=float)


def get(d, *keys):
    """d[k0][k1]... or None when any level is missing, null or not a dict."""
    for k in keys:
        if not isinstance(d, dict):
            return None
        d = d.get(k)
    return d


class Envelope:
    """A full-resolution channel reduced to its minimum lo and maximum hi per time bucket.

    t is the mean time of the two samples (the bucket's only sample when it holds one), so a band
    between lo and hi, outlined with the line width, draws every spike and, where buckets hold one
    sample, the same line as the samples; peak = max |value|, rows = samples read.
    """

    def __init__(self, t, lo, hi, peak, rows):
        self.t, self.lo, self.hi, self.peak, self.rows = t, lo, hi, peak, rows


def read_envelopes(csv_path, columns, t0, t1, buckets=ENVELOPE_BUCKETS):
    """Min/max envelopes of the named columns of timeseries.csv over [t0, t1], in one pass.

    Parses about CSV_CHUNK_BYTES of whole lines at a time with numpy.loadtxt(usecols=...), so
    memory is that of one chunk plus 4 x buckets values per column, whatever the number of rows.
    Returns {name: Envelope} for the columns the file has; raises ValueError on a malformed file.
    """
    import numpy as np
    with open(csv_path, "rb") as f:
        header = f.readline().decode("utf-8", "replace").strip().split(",")
        index = {name: i for i, name in enumerate(header)}
        if header[0] != "time":
            raise ValueError(f"first column is '{header[0]}', expected 'time'")
        names = [c for c in dict.fromkeys(columns) if c in index]
        if not names:
            return {}
        usecols = [0] + [index[c] for c in names]
        n = len(names)
        lo = np.full((n, buckets), np.inf)
        hi = np.full((n, buckets), -np.inf)
        t_lo = np.zeros((n, buckets))
        t_hi = np.zeros((n, buckets))
        span = (t1 - t0) if t1 > t0 else 1.0
        rows = 0
        while True:
            lines = f.readlines(CSV_CHUNK_BYTES)
            if not lines:
                break
            block = np.loadtxt(lines, delimiter=",", usecols=usecols, ndmin=2)
            rows += len(block)
            t = block[:, 0]
            b = np.clip(((t - t0) / span * buckets).astype(np.int64), 0, buckets - 1)
            if np.any(np.diff(b) < 0):                      # time out of order: sort the chunk
                order = np.argsort(b, kind="stable")
                b, t, block = b[order], t[order], block[order]
            starts = np.concatenate(([0], np.flatnonzero(np.diff(b)) + 1))
            seg = b[starts]
            lengths = np.diff(np.append(starts, len(b)))
            for k in range(n):
                v = block[:, k + 1]
                nan = np.isnan(v)
                for sign, acc, acc_t in ((1.0, lo, t_lo), (-1.0, hi, t_hi)):
                    # Segment extremum (NaN ignored), then the first sample that reaches it.
                    w = np.where(nan, np.inf, sign * v)
                    m = np.minimum.reduceat(w, starts)
                    hits = np.flatnonzero(w == np.repeat(m, lengths))
                    first = hits[np.searchsorted(hits, starts)]
                    better = m < sign * acc[k, seg]
                    acc[k, seg[better]] = sign * m[better]
                    acc_t[k, seg[better]] = t[first[better]]
    out = {}
    for k, name in enumerate(names):
        ok = np.isfinite(lo[k])
        peak = float(np.max(np.maximum(np.abs(lo[k, ok]), np.abs(hi[k, ok])), initial=0.0))
        out[name] = Envelope(0.5 * (t_lo[k, ok] + t_hi[k, ok]), lo[k, ok], hi[k, ok], peak, rows)
    return out


# ----------------------------------------------------------------------------------------------
# The report as figure builders see it


class XAxis:
    """The abscissa of curves against the motion: unwrapped crank angle (deg) or time."""

    def __init__(self, time, angle_deg, window=None, angle_range=None):
        import numpy as np
        self.time = time
        self.window = window              # (t0, t1) s shown, or None: the whole run
        self.fold = None                  # (a0, span) deg: angles folded into [a0, a0 + span]
        self.kind = "time"
        self.t_scale, self.t_label = time_unit(time)
        if angle_deg is not None and len(angle_deg) == len(time) and len(time) > 1 \
                and np.all(np.isfinite(angle_deg)):
            unwrapped = np.degrees(np.unwrap(np.radians(angle_deg)))
            revolutions = abs(unwrapped[-1] - unwrapped[0]) / 360.0
            if 0 < revolutions and len(time) >= MIN_SAMPLES_PER_REVOLUTION * revolutions and \
                    (revolutions <= MAX_REVOLUTIONS_ON_ANGLE_AXIS or angle_range is not None):
                self.kind, self.angle = "angle", unwrapped
                if angle_range is not None:
                    a0, a1 = angle_range
                    span = (a1 - a0) % 360.0
                    self.fold = (a0, span if span > 0 else 360.0)

    def of_time(self, t):
        """Abscissa values of times t (s)."""
        import numpy as np
        if self.kind == "angle":
            a = np.interp(t, self.time, self.angle)
            if self.fold is not None:
                a = self.fold[0] + np.mod(a - self.fold[0], 360.0)
            return a
        return np.asarray(t) * self.t_scale

    def curve(self, t, *values):
        """(x, values...) of samples at times t: the abscissa, and with a folded crank angle only
        the samples inside the range, a NaN row where one revolution ends and the next begins
        (so that no line joins them)."""
        import numpy as np
        x = self.of_time(t)
        if self.fold is None:
            return (x,) + values
        a0, span = self.fold
        inside = x <= a0 + span + 1e-9
        x = np.where(inside, x, np.nan)
        values = tuple(None if v is None else np.where(inside, v, np.nan) for v in values)
        breaks = np.nonzero(np.diff(x) < 0)[0] + 1       # the angle fell back: a new revolution
        if len(breaks):
            x = np.insert(x, breaks, np.nan)
            values = tuple(None if v is None else np.insert(v.astype(float), breaks, np.nan)
                           for v in values)
        return (x,) + values

    def label(self):
        return "Crank angle (°)" if self.kind == "angle" else self.t_label

    def apply(self, ax):
        """Label, limits and ticks of an axis against this abscissa."""
        import numpy as np
        from matplotlib.ticker import MultipleLocator
        ax.set_xlabel(self.label())
        x = self.of_time(np.asarray(self.window) if self.window else self.time[[0, -1]])
        if self.fold is not None:
            x = [self.fold[0], self.fold[0] + self.fold[1]]
        if self.kind == "angle":
            span = abs(x[1] - x[0])
            step = next((s for s in (45, 90, 180, 360, 720, 1440) if span / s <= 8), 1440)
            ax.xaxis.set_major_locator(MultipleLocator(step))
            ax.xaxis.set_minor_locator(MultipleLocator(step / 2))
            # An end a hair short of a tick (719.99° after two revolutions) ends on the tick.
            x = [round(v / step) * step if abs(v - round(v / step) * step) < 0.01 * step else v
                 for v in x]
        else:
            x = [snap(v) for v in x]
        ax.set_xlim(x[0], x[1])


def snap(v):
    """v rounded to 3 significant digits when that moves it by less than 1e-4 of itself, so that
    an axis ending at 99.99999 s ends on its 100 s tick."""
    r = float(f"{v:.3g}")
    return r if abs(r - v) <= 1e-4 * abs(v) else float(v)


def time_unit(time):
    """(scale, axis label) for times in s: ms for runs up to 2 s."""
    end = float(time[-1]) if time is not None and len(time) else 1.0
    return (1e3, "Time (ms)") if end <= 2.0 else (1.0, "Time (s)")


class Report:
    """report_data.json with numpy series and the names of what the model holds."""

    def __init__(self, out_dir, data):
        self.out_dir, self.data = out_dir, data
        series = data.get("series") if isinstance(data.get("series"), dict) else {}
        self.time = as_array(series.get("time"))
        if self.time is not None and (self.time.ndim != 1 or len(self.time) < 2):
            self.time = None
        self._channels = series.get("channels") if isinstance(series.get("channels"), dict) else {}
        self._ideal = series.get("ideal") if isinstance(series.get("ideal"), dict) else {}
        self.xaxis = None
        self.analysis = data.get("analysis") if isinstance(data.get("analysis"), dict) else {}
        self.window = self._statistics_window()
        if self.time is not None:
            self.xaxis = XAxis(self.time, as_array(series.get("crank_angle")), self.window,
                               self._statistics_angle_range())
        self.model = data.get("model") if isinstance(data.get("model"), dict) else {}
        info = data.get("channel_info")
        self._info = info if isinstance(info, dict) else {}
        self.full = {}                      # name -> Envelope, filled by read_full_resolution

    def _statistics_window(self):
        """(t0, t1) of the statistics window when it is narrower than the series, else None."""
        stats = self.analysis.get("statistics")
        if self.time is None or not isinstance(stats, dict):
            return None
        for v in stats.values():
            w = v.get("window") if isinstance(v, dict) else None
            if isinstance(w, list) and len(w) == 2 and all(isinstance(x, (int, float)) for x in w):
                t0, t1 = max(float(w[0]), float(self.time[0])), min(float(w[1]), float(self.time[-1]))
                span = float(self.time[-1] - self.time[0])
                if t1 > t0 and (t0 - self.time[0] > 1e-9 * span or self.time[-1] - t1 > 1e-9 * span):
                    return (t0, t1)
                return None
        return None

    def _statistics_angle_range(self):
        """(a0, a1) deg of the statistics' crank-angle range, or None."""
        stats = self.analysis.get("statistics")
        for v in (stats.values() if isinstance(stats, dict) else []):
            r = v.get("angle_range") if isinstance(v, dict) else None
            if isinstance(r, list) and len(r) == 2 and all(isinstance(x, (int, float)) for x in r):
                return (float(r[0]), float(r[1]))
            return None
        return None

    def clip(self, t, *values):
        """t and the arrays sampled at t restricted to the statistics window (all of them
        without one)."""
        if self.window is None or t is None:
            return (t,) + values
        keep = (t >= self.window[0]) & (t <= self.window[1])
        return (t[keep],) + tuple(v[keep] if v is not None else None for v in values)

    def channel_names(self):
        return list(self._channels)

    def unit(self, name):
        """SI unit of a channel from channel_info (written by the engine); '' when the data does
        not give one. Never guessed from the name."""
        u = get(self._info, name, "unit")
        return u if isinstance(u, str) else ""

    def description(self, name):
        """Short description of a channel from channel_info; the channel name when there is none."""
        d = get(self._info, name, "description")
        return d if isinstance(d, str) and d.strip() else name

    def channel(self, name):
        """Decimated channel on self.time, or None when absent or of the wrong length."""
        return self._series(self._channels, name)

    def ideal(self, name):
        return self._series(self._ideal, name)

    def _series(self, table, name):
        v = as_array(table.get(name))
        if v is None or self.time is None or v.shape != self.time.shape:
            return None
        return v

    def curve(self, name):
        """(t, lo, hi): the full-resolution envelope when timeseries.csv had the channel, else
        the decimated series with lo = hi; (None, None, None) when there is neither."""
        if name in self.full:
            e = self.full[name]
            return e.t, e.lo, e.hi
        v = self.channel(name)
        return (self.time, v, v) if v is not None else (None, None, None)

    def peak(self, name):
        """Largest |value| of a channel: statistics, else full resolution, else decimated."""
        import numpy as np
        p = get(self.analysis, "statistics", name, "peak")
        if isinstance(p, (int, float)):
            return float(p)
        if name in self.full:
            return self.full[name].peak
        v = self.channel(name)
        return float(np.nanmax(np.abs(v))) if v is not None and np.any(np.isfinite(v)) else -1.0

    def bodies(self):
        """Body names: the model's, else the owners of *.ax channels."""
        names = [b.get("name") for b in self.model.get("bodies") or [] if isinstance(b, dict)]
        names = [n for n in names if n]
        return names or sorted({c[:-3] for c in self._channels if c.endswith(".ax")})

    def joints(self):
        return [j for j in self.model.get("joints") or [] if isinstance(j, dict) and j.get("name")]

    def clearance_joints(self):
        """Clearance joints: the model's, analysis.clearance's and owners of *.Fn channels."""
        names = [j["name"] for j in self.joints() if j.get("clearance")]
        names += list(get(self.analysis, "clearance") or {})
        names += [c[:-3] for c in self._channels if c.endswith(".Fn")]
        return list(dict.fromkeys(names))

    def clearance_of(self, joint):
        """Radial clearance of a joint, m, or None."""
        for c in (get(self.analysis, "clearance", joint, "clearance"),
                  next((get(j, "clearance", "clearance") for j in self.joints()
                        if j["name"] == joint), None)):
            if isinstance(c, (int, float)) and c > 0:
                return float(c)
        return None

    def translational_bodies(self):
        """Bodies on the moving side of each translational joint."""
        out = []
        for j in self.joints():
            if j.get("type") != "translational":
                continue
            a, b = get(j, "a", "body"), get(j, "b", "body")
            body = b if b and b != "ground" else a
            if body and body != "ground":
                out.append(body)
        return list(dict.fromkeys(out))

    def drivers(self):
        """[(driver, effort channel)] for drivers with a .torque or .force channel."""
        names = [d.get("name") for d in self.model.get("drivers") or [] if isinstance(d, dict)]
        names = [n for n in names if n] or sorted(
            {c.rsplit(".", 1)[0] for c in self._channels if c.endswith((".torque", ".force"))})
        out = []
        for d in names:
            for suffix in (".torque", ".force"):
                if d + suffix in self._channels:
                    out.append((d, d + suffix))
                    break
        return out


# ----------------------------------------------------------------------------------------------
# Labels and units


def scaled_unit(unit, peak):
    """(factor, unit label) that brings values of this peak to readable numbers."""
    if unit == "m":
        if 1e-4 <= peak < 1.0:
            return 1e3, "mm"
        return (1e6, "µm") if 0 < peak < 1e-4 else (1.0, "m")
    if unit in ("N", "N·m", "J"):
        if peak >= 1e6:
            return 1e-6, "M" + unit
        if peak >= 1e4 or (unit != "J" and peak >= 2e3):
            return 1e-3, "k" + unit
        if unit == "J" and 0 < peak < 1e-4:
            return 1e6, "µJ"
        if unit == "J" and 0 < peak < 1e-1:
            return 1e3, "mJ"
        return 1.0, unit
    if unit and peak >= 1e4:
        k = int(math.log10(peak) // 3) * 3
        return 10.0 ** -k, f"$10^{{{k}}}$ {unit}"
    return 1.0, unit


def pretty(name):
    """'rod_slider' -> 'Rod slider' for axis labels."""
    s = name.replace("_", " ")
    return s[:1].upper() + s[1:]


def owner_of(channel):
    """'rod_slider' of 'rod_slider.Fn': the element a channel belongs to ('' when none)."""
    return channel.rpartition(".")[0]


def quantity_text(rep, channel):
    """What a channel is, for an axis label: its description from the data, preceded by its
    element ('Slider acceleration ...') unless the description names it already."""
    desc = rep.description(channel)
    if desc == channel:                   # no description in the data: the name as it is
        return channel.replace("$", r"\$")
    owner = owner_of(channel)
    named = any(n in desc.lower() for n in (owner.lower(), owner.replace("_", " ").lower()))
    text = desc if not owner or named else f"{pretty(owner)} {desc}"
    # A '$' in the data is text, not the start of matplotlib mathtext.
    return (text[:1].upper() + text[1:]).replace("$", r"\$")


def axis_label(rep, channel, unit_label):
    """'Slider acceleration (10³ m/s²)' for 'slider.ax' described as 'acceleration' in m/s²."""
    text = quantity_text(rep, channel)
    return f"{text} ({unit_label})" if unit_label else text


# ----------------------------------------------------------------------------------------------
# Figure families. Each planner returns [Plan]; a Plan names its file, the full-resolution columns
# it would like from timeseries.csv, and draws itself.


class Plan:
    def __init__(self, family, name, draw, columns=()):
        self.family, self.name, self.draw, self.columns = family, name, draw, list(columns)


def new_figure(width=SINGLE_COLUMN_IN, height=2.3, rows=1, sharex=True, **kw):
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(rows, 1, figsize=(width, height), sharex=sharex, squeeze=False, **kw)
    return fig, list(axes[:, 0])


def legend_above(ax, **kw):
    """A legend on top of the axes, left-aligned, so that it never hides a curve."""
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.01), borderaxespad=0.0,
              columnspacing=1.5, **kw)


def need_xaxis(rep):
    if rep.xaxis is None:
        raise Skip("series.time is missing")


def draw_vs_motion(rep, ax, channel, ideal=None, legend=True):
    """Plots a channel (full resolution when read) and its ideal twin against the crank angle.

    ideal names the twin's channel when it differs (the reaction F of the ideal joint against
    the contact force F_N of the clearance joint)."""
    import numpy as np
    from matplotlib.lines import Line2D
    t, lo, hi = rep.curve(channel)
    if lo is None:
        raise Skip(f"no channel {channel}")
    same = lo is hi
    t, lo, hi = rep.clip(t, lo, hi)
    if same:
        hi = lo
    ideal_t, ideal_v = rep.clip(rep.time, rep.ideal(ideal or channel))
    peak = max(np.nanmax(np.abs(np.concatenate([lo, hi]))) if np.any(np.isfinite(lo)) else 0.0,
               np.nanmax(np.abs(ideal_v)) if ideal_v is not None else 0.0)
    scale, unit_label = scaled_unit(rep.unit(channel), peak)
    x, lo, hi = rep.xaxis.curve(t, lo, hi)
    if same:
        hi = lo
    if lo is hi:
        ax.plot(x, lo * scale, color=COLOR_CLEARANCE, linewidth=0.6, zorder=2)
    else:
        # A min/max band outlined with the line width: a line where a bucket holds one sample.
        ax.fill_between(x, lo * scale, hi * scale, facecolor=COLOR_CLEARANCE,
                        edgecolor=COLOR_CLEARANCE, linewidth=0.6, zorder=2)
    ax.add_line(Line2D([], [], color=COLOR_CLEARANCE, linewidth=0.6, label="Clearance joint"))
    if ideal_v is not None:
        ideal_x, ideal_v = rep.xaxis.curve(ideal_t, ideal_v)
        ax.plot(ideal_x, ideal_v * scale, label="Ideal joint", zorder=3,
                **IDEAL_STYLE)
    if legend and ideal_v is not None:
        legend_above(ax, ncol=2)
    rep.xaxis.apply(ax)
    ax.set_ylabel(axis_label(rep, channel, unit_label))
    return unit_label


def body_acceleration_channels(rep):
    names = set(rep.channel_names())
    return [f"{b}.{s}" for b in rep.bodies() for s in ("ax", "ay") if f"{b}.{s}" in names]


def plan_acceleration_peak(rep):
    need_xaxis(rep)
    candidates = body_acceleration_channels(rep)
    if not candidates:
        raise Skip("no body acceleration channels (*.ax, *.ay)")
    stats = get(rep.analysis, "statistics") or {}
    known = all(isinstance(get(stats, c, "peak"), (int, float)) for c in candidates)
    columns = [max(candidates, key=rep.peak)] if known else candidates

    def draw():
        top = max(candidates, key=rep.peak)
        fig, (ax,) = new_figure()
        draw_vs_motion(rep, ax, top)
        return fig
    return [Plan("acceleration_peak", "acceleration_peak", draw, columns)]


def plan_acceleration_translational(rep):
    need_xaxis(rep)
    names = set(rep.channel_names())
    channels = [b + ".ax" for b in rep.translational_bodies() if b + ".ax" in names]
    if not channels:
        raise Skip("no translational joint with a body a_x channel")

    def draw():
        fig, axes = new_figure(height=0.4 + 1.9 * len(channels), rows=len(channels))
        for ax, c in zip(axes, channels):
            draw_vs_motion(rep, ax, c, legend=ax is axes[0])
            if ax is not axes[-1]:
                ax.set_xlabel("")
        fig.align_ylabels(axes)
        return fig
    return [Plan("acceleration_translational", "acceleration_translational", draw, channels)]


def plan_contact_force(rep):
    need_xaxis(rep)
    plans = []
    for j in rep.clearance_joints():
        channel = j + ".Fn"
        if rep.channel(channel) is None:
            continue
        ideal = next((c for c in (channel, j + ".F") if rep.ideal(c) is not None), None)

        def draw(channel=channel, ideal=ideal):
            fig, (ax,) = new_figure()
            draw_vs_motion(rep, ax, channel, ideal=ideal)
            return fig
        plans.append(Plan("contact_force", "contact_force_" + j, draw, [channel]))
    if not plans:
        raise Skip("no clearance joint with an Fn channel")
    return plans


def clearance_circle(ax, c_mm):
    import numpy as np
    a = np.linspace(0.0, 2.0 * np.pi, 361)
    ax.plot(c_mm * np.cos(a), c_mm * np.sin(a), color="black", linewidth=0.8, zorder=3)


def eccentricity_axes(ax, c_mm, extent_mm, xlabel="$e_x$ (mm)", ylabel="$e_y$ (mm)"):
    """Square axes around the origin with the clearance circle and thin centre lines."""
    lim = 1.12 * max(c_mm or 0.0, extent_mm)
    ax.axhline(0.0, color="0.8", linewidth=0.4, zorder=0)
    ax.axvline(0.0, color="0.8", linewidth=0.4, zorder=0)
    if c_mm:
        clearance_circle(ax, c_mm)
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)


def plan_orbit(rep):
    import numpy as np
    plans = []
    for j in rep.clearance_joints():
        ex = as_array(get(rep.analysis, "clearance", j, "orbit", "ex"))
        ey = as_array(get(rep.analysis, "clearance", j, "orbit", "ey"))
        if ex is None or ey is None or ex.shape != ey.shape or len(ex) < 2:
            ex, ey = rep.channel(j + ".ex"), rep.channel(j + ".ey")
        if ex is None or ey is None:
            continue

        def draw(j=j, ex=ex, ey=ey):
            c = rep.clearance_of(j)
            fig, (ax,) = new_figure(width=2.8, height=2.8)
            ax.plot(ex * 1e3, ey * 1e3, color=COLOR_CLEARANCE, linewidth=0.5, zorder=2)
            extent = float(np.nanmax(np.hypot(ex, ey))) * 1e3 if np.any(np.isfinite(ex)) else 0
            eccentricity_axes(ax, c * 1e3 if c else None, extent)
            return fig
        plans.append(Plan("orbit", "orbit_" + j, draw))
    if not plans:
        raise Skip("no journal orbit (analysis.clearance.<joint>.orbit or <joint>.ex/.ey)")
    return plans


def contact_spans(rep, joint):
    """([(t0, t1, kind)], shares {kind: fraction}) of a clearance joint."""
    import numpy as np
    modes = get(rep.analysis, "clearance", joint, "modes") or {}
    spans = []
    for e in modes.get("episodes") or []:
        if isinstance(e, (list, tuple)) and len(e) >= 3 and e[2] in ("impact", "continuous") \
                and all(isinstance(x, (int, float)) for x in e[:2]):
            spans.append((float(e[0]), float(e[1]), e[2]))
    if not modes.get("episodes"):
        # Without episodes: contact intervals of the (decimated) mode channel, not classified.
        mode = rep.channel(joint + ".mode")
        if mode is not None:
            on = np.concatenate(([0], (mode > 0.5).astype(int), [0]))
            edges = np.flatnonzero(np.diff(on))
            t = rep.time
            spans = [(t[a], t[min(b, len(t) - 1)], "contact")
                     for a, b in zip(edges[::2], edges[1::2])]
    shares = {}
    for k in ("free_flight", "impact", "continuous"):
        v = modes.get(k + "_share")
        if isinstance(v, (int, float)):
            shares[k] = float(v)
    if not shares and spans and rep.time is not None:
        total = float(rep.time[-1] - rep.time[0]) or 1.0
        for kind in {s[2] for s in spans}:
            shares[kind] = sum(b - a for a, b, k in spans if k == kind) / total
        shares["free_flight"] = max(0.0, 1.0 - sum(shares.values()))
    return spans, shares


def plan_modes(rep):
    rows = []
    for j in rep.clearance_joints():
        spans, shares = contact_spans(rep, j)
        if spans or shares:
            rows.append((j, spans, shares))
    if not rows or rep.time is None:
        raise Skip("no contact episodes (analysis.clearance.<joint>.modes) or mode channel")

    def draw():
        from matplotlib.patches import Patch
        from matplotlib.ticker import NullLocator
        fig, (ax,) = new_figure(width=DOUBLE_COLUMN_IN, height=0.75 + 0.32 * len(rows))
        scale, t_label = time_unit(rep.time)
        t0, t1 = rep.window or (float(rep.time[0]), float(rep.time[-1]))
        kinds = []
        for i, (j, spans, shares) in enumerate(rows):
            y = len(rows) - 1 - i
            ax.broken_barh([(t0 * scale, (t1 - t0) * scale)], (y - 0.35, 0.7),
                           facecolor=MODE_COLORS["free_flight"], edgecolor="none")
            for kind in ("continuous", "contact", "impact"):
                bars = [(a * scale, max(b - a, 0.0) * scale) for a, b, k in spans if k == kind]
                if bars:
                    ax.broken_barh(bars, (y - 0.35, 0.7), facecolor=MODE_COLORS[kind],
                                   edgecolor=MODE_COLORS[kind], linewidth=0.3)
                    kinds.append(kind)
            if len(rows) > 1 and shares:
                text = ", ".join(f"{MODE_LABELS[k].split()[0].lower()} {100 * v:.0f}%"
                                 for k, v in shares.items())
                ax.text(1.01, (y + 0.5) / len(rows), text, transform=ax.transAxes,
                        va="center", ha="left", fontsize=6.5)
        # Legend: one entry per mode, with its share when there is one joint.
        shares = rows[0][2] if len(rows) == 1 else {}
        handles = []
        for kind in ["free_flight"] + [k for k in ("impact", "continuous", "contact")
                                       if k in kinds or k in shares]:
            label = MODE_LABELS[kind]
            if kind in shares:
                label += f" ({100 * shares[kind]:.1f}%)"
            handles.append(Patch(facecolor=MODE_COLORS[kind], edgecolor="none", label=label))
        legend_above(ax, handles=handles, ncol=4, handlelength=1.4)
        ax.set_yticks(range(len(rows)))
        ax.set_yticklabels([pretty(j) for j, _, _ in reversed(rows)])
        ax.set_ylim(-0.5, len(rows) - 0.5)
        ax.tick_params(axis="y", which="both", length=0)
        ax.yaxis.set_minor_locator(NullLocator())
        ax.set_xlim(snap(t0 * scale), snap(t1 * scale))
        ax.set_xlabel(t_label)
        for side in ("left", "right", "top"):
            ax.spines[side].set_visible(False)
        ax.tick_params(axis="x", which="both", top=False)
        return fig
    return [Plan("modes", "modes", draw)]


def plan_impact_velocity(rep):
    import numpy as np
    hists = []
    for j in rep.clearance_joints():
        h = get(rep.analysis, "clearance", j, "histogram") or {}
        edges, counts = as_array(h.get("edges")), as_array(h.get("counts"))
        if edges is None or counts is None or len(edges) != len(counts) + 1 or len(counts) == 0:
            v = as_array(get(rep.analysis, "clearance", j, "impact_velocities"))
            if v is None or len(v) == 0:
                continue
            counts, edges = np.histogram(v[np.isfinite(v)], bins="auto")
        if np.nansum(counts) > 0:
            hists.append((j, edges, counts))
    if not hists:
        raise Skip("no impact velocities (analysis.clearance.<joint>.histogram)")

    def draw():
        from matplotlib.ticker import MaxNLocator, NullLocator
        fig, axes = new_figure(height=0.4 + 1.8 * len(hists), rows=len(hists))
        for ax, (j, edges, counts) in zip(axes, hists):
            ax.bar(edges[:-1], counts, width=np.diff(edges), align="edge",
                   color=COLOR_CLEARANCE, edgecolor="white", linewidth=0.4)
            ax.set_ylabel("Impacts" if len(hists) == 1 else f"Impacts, {pretty(j).lower()}")
            ax.yaxis.set_major_locator(MaxNLocator(integer=True))
            ax.yaxis.set_minor_locator(NullLocator())
            ax.set_ylim(0, float(np.nanmax(counts)) * 1.08)
        axes[-1].set_xlim(min(0.0, min(float(e[0]) for _, e, _ in hists)),
                          max(float(e[-1]) for _, e, _ in hists))
        axes[-1].set_xlabel(r"Impact velocity $\dot{\delta}^{-}$ (m/s)")
        return fig
    return [Plan("impact_velocity", "impact_velocity", draw)]


def plan_poincare(rep):
    import numpy as np
    p = get(rep.analysis, "poincare") or {}
    pts = p.get("points")
    try:
        pts = np.asarray(pts, dtype=float)
    except (TypeError, ValueError):
        pts = None
    if pts is None or pts.ndim != 2 or pts.shape[1] < 2 or len(pts) == 0:
        raise Skip("no analysis.poincare.points")
    var = p.get("variables") or ["", ""]
    var = [str(v) for v in var[:2]] + [""] * (2 - len(var[:2]))
    plans = [Plan("poincare", "poincare", section_drawing(rep, pts, var))]
    # Every other clearance joint's eccentricity at the same section times (analysis.poincare.joints).
    for js in p.get("joints") or []:
        if not isinstance(js, dict) or not isinstance(js.get("joint"), str):
            continue
        jvar = [str(v) for v in (js.get("variables") or [])[:2]]
        try:
            jpts = np.asarray(js.get("points"), dtype=float)
        except (TypeError, ValueError):
            continue
        if jvar == var or len(jvar) != 2 or jpts.ndim != 2 or jpts.shape[1] < 2 or len(jpts) == 0:
            continue
        plans.append(Plan("poincare", "poincare_" + safe_name(js["joint"]),
                          section_drawing(rep, jpts, jvar)))
    return plans


def section_drawing(rep, pts, var):
    """The drawing of one set of Poincaré points over the variables var (two channel names)."""
    import numpy as np

    def draw():
        fig, (ax,) = new_figure(width=2.8, height=2.8)
        ox, oy = owner_of(var[0]), owner_of(var[1])
        x, y = pts[:, 0], pts[:, 1]
        dense = len(pts) > MAX_VECTOR_MARKERS
        eccentricity = ox == oy and var[0].endswith(".ex") and var[1].endswith(".ey") \
            and rep.unit(var[0]) == rep.unit(var[1]) == "m"
        if eccentricity:
            c = rep.clearance_of(ox)
            ax.scatter(x * 1e3, y * 1e3, s=7, color=COLOR_CLEARANCE, linewidths=0, zorder=4,
                       rasterized=dense)
            extent = float(np.nanmax(np.hypot(x, y))) * 1e3
            eccentricity_axes(ax, c * 1e3 if c else None, extent)
        else:
            sx, lx = scaled_unit(rep.unit(var[0]), float(np.nanmax(np.abs(x))))
            sy, ly = scaled_unit(rep.unit(var[1]), float(np.nanmax(np.abs(y))))
            ax.scatter(x * sx, y * sy, s=7, color=COLOR_CLEARANCE, linewidths=0, zorder=4,
                       rasterized=dense)
            ax.set_xlabel(axis_label(rep, var[0], lx) if var[0] else "First variable")
            ax.set_ylabel(axis_label(rep, var[1], ly) if var[1] else "Second variable")
        return fig
    return draw


def plan_spectra(rep):
    import numpy as np
    spectra = []
    for name, s in (get(rep.analysis, "spectra") or {}).items():
        f, a = as_array(get(s, "frequency")), as_array(get(s, "amplitude"))
        if f is not None and a is not None and f.shape == a.shape and len(f) > 1:
            ok = np.isfinite(f) & np.isfinite(a) & (a > 0) & (f > 0)
            if ok.sum() > 1:
                spectra.append((name, f[ok], a[ok]))
    if not spectra:
        raise Skip("no analysis.spectra")

    def draw():
        fig, axes = new_figure(height=0.4 + 1.9 * len(spectra), rows=len(spectra))
        f_max = max(float(f[-1]) for _, f, _ in spectra)
        scale, label = (1e-3, "Frequency (kHz)") if f_max > 5e3 else (1.0, "Frequency (Hz)")
        for ax, (name, f, a) in zip(axes, spectra):
            ax.semilogy(f * scale, a, color=COLOR_CLEARANCE, linewidth=0.6)
            text, unit = quantity_text(rep, name) + " amplitude", rep.unit(name)
            ax.set_ylabel(f"{text} ({unit})" if unit else text)
            ax.set_xlim(0, f_max * scale)
            # Decades below 1e-7 of the largest line are numerical floor, not signal.
            top = float(np.max(a))
            ax.set_ylim(max(float(np.min(a)), top * 1e-7) / 2, top * 3)
        axes[-1].set_xlabel(label)
        fig.align_ylabels(axes)
        return fig
    return [Plan("spectra", "spectra", draw)]


def safe_name(channel):
    return re.sub(r"[^A-Za-z0-9_-]+", "-", channel)


def plan_phase(rep):
    import numpy as np
    plans = []
    for pair in get(rep.analysis, "phase") or []:
        if not isinstance(pair, dict):
            continue
        cx, cy = str(pair.get("x")), str(pair.get("y"))
        x, y = rep.channel(cx), rep.channel(cy)
        if x is None or y is None:
            continue

        def draw(cx=cx, cy=cy, x=x, y=y):
            owner = owner_of(cx)
            if cx == owner + ".ex" and cy == owner + ".ey" and rep.unit(cx) == rep.unit(cy) == "m":
                # The journal path: square, in mm, with the clearance circle, like the orbit.
                fig, (ax,) = new_figure(width=2.8, height=2.8)
                ax.plot(x * 1e3, y * 1e3, color=COLOR_CLEARANCE, linewidth=0.5, zorder=2)
                c = rep.clearance_of(owner)
                eccentricity_axes(ax, c * 1e3 if c else None,
                                  float(np.nanmax(np.hypot(x, y))) * 1e3,
                                  axis_label(rep, cx, "mm"), axis_label(rep, cy, "mm"))
                return fig
            fig, (ax,) = new_figure(width=SINGLE_COLUMN_IN, height=2.6)
            sx, lx = scaled_unit(rep.unit(cx), float(np.nanmax(np.abs(x))))
            sy, ly = scaled_unit(rep.unit(cy), float(np.nanmax(np.abs(y))))
            ax.plot(x * sx, y * sy, color=COLOR_CLEARANCE, linewidth=0.5)
            ax.set_xlabel(axis_label(rep, cx, lx))
            ax.set_ylabel(axis_label(rep, cy, ly))
            return fig
        plans.append(Plan("phase", f"phase_{safe_name(cx)}_vs_{safe_name(cy)}", draw))
    if not plans:
        raise Skip("no analysis.phase pair with both channels in series.channels")
    return plans


def plan_lyapunov(rep):
    import numpy as np
    lya = get(rep.analysis, "lyapunov") or {}
    # Every exponent of the variational spectrum ([t, λ1, λ2, ...] rows), else the largest.
    try:
        h = np.asarray(lya.get("spectrum_history") or lya.get("history"), dtype=float)
    except (TypeError, ValueError):
        h = None
    if h is None or h.ndim != 2 or h.shape[1] < 2 or len(h) < 2:
        raise Skip("no analysis.lyapunov.history")
    if len(h) > MAX_LINE_POINTS:          # one estimate per renormalisation can be many
        h = h[np.unique(np.linspace(0, len(h) - 1, MAX_LINE_POINTS).astype(int))]

    def draw():
        fig, (ax,) = new_figure()
        scale, t_label = time_unit(rep.time if rep.time is not None else h[:, 0])
        unit = lya.get("unit") or "1/s"
        ax.axhline(0.0, color="0.7", linewidth=0.5, zorder=0)
        for k in range(1, h.shape[1]):
            ax.plot(h[:, 0] * scale, h[:, k], linewidth=0.8,
                    color=COLOR_CLEARANCE if k == 1 else None,
                    label=rf"$\lambda_{k}$ running estimate" if h.shape[1] > 2 else "Running estimate")
        final = lya.get("exponent")
        if isinstance(final, (int, float)) and math.isfinite(final):
            ax.axhline(final, color="black", linewidth=0.6, linestyle=":",
                       label=rf"$\lambda_1$ = {final:.3g} {unit}")
            legend_above(ax, ncol=2)
        ax.set_xlim(0.0 if h[0, 0] >= 0 else h[0, 0] * scale, snap(h[-1, 0] * scale))
        ax.set_xlabel(t_label)
        ax.set_ylabel(rf"Lyapunov exponents ({unit})" if h.shape[1] > 2
                      else rf"Largest Lyapunov exponent $\lambda_1$ ({unit})")
        return fig
    return [Plan("lyapunov", "lyapunov", draw)]


def plan_driver_torque(rep):
    need_xaxis(rep)
    plans = []
    for d, channel in rep.drivers():
        kind = "torque" if channel.endswith(".torque") else "force"

        def draw(channel=channel):
            fig, (ax,) = new_figure()
            draw_vs_motion(rep, ax, channel)
            return fig
        plans.append(Plan("driver_torque", f"driver_{kind}_{d}", draw, [channel]))
    if not plans:
        raise Skip("no driver effort channel (<driver>.torque or .force)")
    return plans


def plan_energy(rep):
    import numpy as np
    parts = [k for k in ("kinetic", "potential", "dissipated", "input")
             if rep.channel("energy." + k) is not None]
    if not parts:
        raise Skip("no energy channels")
    balance = rep.channel("energy.balance")

    def draw():
        import matplotlib.pyplot as plt
        from matplotlib.ticker import MaxNLocator
        rows = 2 if balance is not None else 1
        fig, axes = plt.subplots(rows, 1, sharex=True, squeeze=False,
                                 figsize=(SINGLE_COLUMN_IN, 2.4 + 0.9 * (rows - 1)),
                                 gridspec_kw={"height_ratios": [3, 1][:rows]})
        axes = list(axes[:, 0])
        scale_t, t_label = time_unit(rep.time)
        shown, *curves = rep.clip(rep.time, *(rep.channel("energy." + k) for k in parts),
                                  balance)
        energy = dict(zip(parts, curves[:len(parts)]))
        shown_balance = curves[len(parts)]
        t = shown * scale_t
        peak = max(float(np.nanmax(np.abs(energy[k]))) for k in parts)
        # One axis for all parts: its unit is theirs when the data gives them one and the same.
        units = {rep.unit("energy." + k) for k in parts}
        scale, unit = scaled_unit(units.pop() if len(units) == 1 else "", peak)
        for k in parts:
            axes[0].plot(t, energy[k] * scale, color=ENERGY_COLORS[k],
                         linewidth=0.8, label=quantity_text(rep, "energy." + k))
        axes[0].set_ylabel(f"Energy ({unit})" if unit else "Energy")
        legend_above(axes[0], ncol=2)
        if balance is not None:
            drift = shown_balance - balance[0]
            s, u = scaled_unit(rep.unit("energy.balance"), float(np.nanmax(np.abs(drift))) or 1.0)
            axes[1].plot(t, drift * s, color="black", linewidth=0.7)
            axes[1].set_ylabel(f"Balance drift ({u})" if u else "Balance drift")
            axes[1].yaxis.set_major_locator(MaxNLocator(nbins=3))
        axes[-1].set_xlabel(t_label)
        axes[-1].set_xlim(snap(t[0]), snap(t[-1]))
        fig.align_ylabels(axes)
        return fig
    return [Plan("energy", "energy", draw)]


# The figure families, in output order: one line per family.
FAMILIES = [
    ("acceleration_peak", plan_acceleration_peak),
    ("acceleration_translational", plan_acceleration_translational),
    ("contact_force", plan_contact_force),
    ("orbit", plan_orbit),
    ("modes", plan_modes),
    ("impact_velocity", plan_impact_velocity),
    ("poincare", plan_poincare),
    ("spectra", plan_spectra),
    ("phase", plan_phase),
    ("lyapunov", plan_lyapunov),
    ("driver_torque", plan_driver_torque),
    ("energy", plan_energy),
]


# ----------------------------------------------------------------------------------------------
# Driver


def note(message):
    print(f"{PROG}: {message}", file=sys.stderr)


def read_full_resolution(rep, columns):
    """Fills rep.full from OUT_DIR/timeseries.csv; on a missing or bad file keeps the series."""
    path = os.path.join(rep.out_dir, "timeseries.csv")
    if not columns or rep.time is None:
        return
    if not os.path.isfile(path):
        note(f"no {path}: curves use the decimated series of report_data.json")
        return
    try:
        rep.full = read_envelopes(path, columns, float(rep.time[0]), float(rep.time[-1]))
    except (ValueError, OSError, StopIteration) as e:
        note(f"{path} unreadable ({e}): curves use the decimated series of report_data.json")
        rep.full = {}


def parse_args(argv):
    p = argparse.ArgumentParser(
        prog="lash_figures.py",
        description="Publication figures (PNG 300 dpi, SVG) from a Lash output folder: reads "
                    "OUT_DIR/report_data.json and OUT_DIR/timeseries.csv, writes "
                    "OUT_DIR/figures/.",
        epilog="Figure families: " + ", ".join(name for name, _ in FAMILIES))
    p.add_argument("out_dir", metavar="OUT_DIR", help="output folder of `lash run`/`lash report`")
    p.add_argument("--format", default="png,svg",
                   help=f"comma-separated formats among {', '.join(FORMATS)} (default png,svg)")
    p.add_argument("--only", nargs="+", metavar="NAME",
                   help="draw only these figures: family names or file names without extension "
                        "(space- or comma-separated)")
    a = p.parse_args(argv)
    a.formats = [f.strip().lower() for f in a.format.split(",") if f.strip()]
    if a.only:
        a.only = [n.strip() for item in a.only for n in item.split(",") if n.strip()]
    bad = [f for f in a.formats if f not in FORMATS]
    if bad or not a.formats:
        p.error(f"--format: unknown format {', '.join(bad) or '(none)'}; "
                f"expected a comma-separated list of {', '.join(FORMATS)}")
    return a


def main(argv=None):
    args = parse_args(argv)
    try:
        import numpy  # noqa: F401
        import matplotlib
    except ImportError as e:
        return fail(f"{e.name} is missing: install Debian's python3-numpy and "
                    f"python3-matplotlib and run with /usr/bin/python3", status=1)
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    try:
        rep = Report(args.out_dir, load_report(args.out_dir))
    except InputError as e:
        return fail(str(e))

    # Plan every figure the data allows; note what it does not allow.
    plans, skipped = [], {}
    for family, planner in FAMILIES:
        try:
            plans += planner(rep)
        except Skip as e:
            skipped[family] = str(e)
    if args.only:
        known = {f for f, _ in FAMILIES} | {p.name for p in plans}
        unknown = [n for n in args.only if n not in known]
        if unknown:
            return fail(f"--only: unknown figure {', '.join(unknown)}; families: "
                        f"{', '.join(f for f, _ in FAMILIES)}; this folder also has: "
                        f"{', '.join(p.name for p in plans) or 'nothing'}")
        wanted = set(args.only)
        plans = [p for p in plans if p.family in wanted or p.name in wanted]
        skipped = {f: r for f, r in skipped.items() if f in wanted}
    for family, reason in skipped.items():
        note(f"skipped {family}: {reason}")

    read_full_resolution(rep, [c for p in plans for c in p.columns])

    fig_dir = os.path.join(args.out_dir, "figures")
    written = []
    with plt.rc_context(STYLE):
        for plan in plans:
            try:
                fig = plan.draw()
            except Skip as e:
                note(f"skipped {plan.name}: {e}")
                continue
            except Exception as e:  # a figure that fails on odd data must not stop the others
                note(f"skipped {plan.name}: {type(e).__name__}: {e}")
                plt.close("all")
                continue
            os.makedirs(fig_dir, exist_ok=True)
            # Marks the folder as lash's own: the next run into OUT_DIR replaces it (a figures/
            # folder without the mark is a user's and is left alone).
            marker = os.path.join(fig_dir, ".lash-figures")
            if not os.path.exists(marker):
                with open(marker, "w") as f:
                    f.write("written by lash_figures.py; removed with this folder by the next run\n")
            for fmt in args.formats:
                path = os.path.join(fig_dir, f"{plan.name}.{fmt}")
                meta = {"Date": None} if fmt in ("svg", "pdf") else {}
                fig.savefig(path, format=fmt, dpi=PNG_DPI, metadata=meta)
                written.append(path)
                print(path, flush=True)
            plt.close(fig)
    if not written:
        return fail(f"no figure could be made from {args.out_dir}/report_data.json", status=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
