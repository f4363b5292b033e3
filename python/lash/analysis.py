"""lash.analysis: the analysis layer of Lash (docs/analysis.md).

A run with its analyses (C++ `lash::analyze_run`, what `lash run --report` and `lash analyze`
compute) — `analyze`, and `poincare`, `verdict`, `spectra` taking the parts of it — and the
model-free functions of src/analysis one to one: `amplitude_spectrum`, `count_distinct`,
`section_contraction`, `classify_motion`, `verdict_rule`, `contact_modes`, `decimate_min_max`.
"""
from __future__ import annotations

import math
import re
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from . import _lash, _flag, _integer, _real, _short, _string, _strings

__all__ = ["analyze", "poincare", "verdict", "spectra", "modes", "spectrum", "amplitude_spectrum",
           "count_distinct", "section_contraction", "classify_motion", "verdict_rule", "contact_modes",
           "decimate_min_max"]


def _vector(name: str, x) -> np.ndarray:
    """`x` as a 1-D float array; TypeError naming the argument when it holds what is not a number
    (or is a str), ValueError when it has another shape or an entry that is not finite (every
    function here that takes samples or points)."""
    try:
        if isinstance(x, (str, bytes)):
            raise TypeError
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name}: expected a 1-D sequence of numbers, got {_short(x)} "
                        f"({type(x).__name__})") from None
    if a.ndim != 1:
        raise ValueError(f"{name}: expected a 1-D sequence of numbers, got an array of shape "
                         f"{a.shape}")
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:  # a NaN made every bin of a spectrum NaN, unsaid
        raise ValueError(f"{name}: expected finite numbers, got {a[bad[0]]} at index {bad[0]}"
                         + (f" (and {bad.size - 1} more)" if bad.size > 1 else ""))
    return a


def _c_int(name: str, value: Any) -> int:
    """`value` as a whole number that fits C's int (what the C++ function takes)."""
    n = _integer(name, value)
    if not -2**31 <= n < 2**31:
        raise ValueError(f"{name}: expected a whole number between -2**31 and 2**31 - 1, got {n}")
    return n


def _model_of(model_or_result):
    from . import Model, Result, _as_model
    if isinstance(model_or_result, Result):
        # The model as the run ran it: its text with every override applied (simulate's t_end,
        # integrator and overrides included), not the caller's Model, which may have changed.
        return Model(model_or_result._resolved_yaml,
                     filename=model_or_result.model.filename)
    return _as_model(model_or_result)


# The C++ checks name the CLI's options ("--discard 3000000: expected ..."); these are the
# analyze() arguments they set, which the messages name instead.
_CLI_OPTIONS = {"--discard": "discard_periods", "--lyapunov-d0": "lyapunov_d0",
                "--lyapunov-method": "lyapunov_method", "--window": "stats_window",
                "--poincare": "poincare_driver", "--fft": "fft_channels"}


def _run_analysis(model, keywords: Dict[str, str], *, ideal_twin: bool = True,
                  lyapunov: bool = True, poincare_driver: str = "",
                  section_planes: Sequence[str] = (), discard_periods: int = 1,
                  fft_channels: Sequence[str] = (),
                  stats_window: Optional[Tuple[float, float]] = None, lyapunov_d0: float = 0.0,
                  continuous_contact_time: float = 0.0,
                  lyapunov_method: str = "variational") -> Dict[str, Any]:
    """analyze() with each option checked by type (TypeError) and named in messages as the
    caller's argument: `keywords` maps analyze()'s names to the caller's ("section_planes" to
    poincare()'s "planes"); the others keep theirs."""
    def name(option: str) -> str:
        return keywords.get(option, option)

    given = {"discard_periods": discard_periods, "lyapunov_d0": lyapunov_d0,
             "lyapunov_method": lyapunov_method, "stats_window": stats_window,
             "poincare_driver": poincare_driver}
    discard = _integer(name("discard_periods"), discard_periods, "a whole number of periods")
    opts: Dict[str, Any] = {
        "ideal_twin": _flag(name("ideal_twin"), ideal_twin),
        "lyapunov": _flag(name("lyapunov"), lyapunov),
        "poincare_driver": _string(name("poincare_driver"), poincare_driver,
                                   "a driver name (str; \"\": the first rotary driver)"),
        "section_planes": _strings(name("section_planes"), section_planes,
                                   "section planes \"<body>.<x|y|phi|vx|vy|omega>=VALUE[,down]\""),
        # A count beyond C's int is out of the C++ check's range as well: clamped, it is
        # reported there, with the value given.
        "discard_periods": max(min(discard, 2**31 - 1), -2**31),
        "fft_channels": _strings(name("fft_channels"), fft_channels,
                                 "channel names such as \"slider.ax\""),
        "lyapunov_d0": _real(name("lyapunov_d0"), lyapunov_d0, "a separation (m)"),
        "lyapunov_method": _string(name("lyapunov_method"), lyapunov_method,
                                   "\"variational\" or \"two-trajectory\""),
        "continuous_contact_time": _real(name("continuous_contact_time"),
                                         continuous_contact_time, "a time (s)")}
    if stats_window is not None:
        try:
            window = None if isinstance(stats_window, (str, bytes)) else list(stats_window)
        except TypeError:
            window = None
        if window is None or len(window) != 2:
            raise TypeError(f"{name('stats_window')}: expected a pair of times (t0, t1) in s, "
                            f"got {_short(stats_window)} ({type(stats_window).__name__})")
        opts["stats_window"] = (_real(f"{name('stats_window')}[0]", window[0], "a time (s)"),
                                _real(f"{name('stats_window')}[1]", window[1], "a time (s)"))
    cct = opts["continuous_contact_time"]
    if not (math.isfinite(cct) and cct >= 0):  # the C++ side reads anything <= 0 as "default"
        raise ValueError(f"{name('continuous_contact_time')}={continuous_contact_time!r}: expected "
                         f"a time >= 0 s (0: the default, 10% of the driver period)")
    compiled = _model_of(model).compiled()
    try:
        return _lash.analyze(compiled, opts)
    except ValueError as e:
        if isinstance(e, _lash.ModelError):
            raise
        message = str(e)
    # "--fft slider.axx: no such channel" -> "fft_channels: 'slider.axx': no such channel",
    # "--discard 3000000: expected ..." -> "discard_periods=3000000: expected ...".
    m = re.fullmatch(r"(--[a-z0-9-]+) (.*?): (.*)", message, re.S)
    if m and m.group(1) in _CLI_OPTIONS:
        option = _CLI_OPTIONS[m.group(1)]
        if option == "fft_channels":
            message = f"{name(option)}: '{m.group(2)}': {m.group(3)}"
        else:
            message = f"{name(option)}={given[option]!r}: {m.group(3)}"
    elif message.startswith("section plane "):
        message = f"{name('section_planes')}: {message}"
    elif message.startswith("--plane: "):
        message = f"{name('section_planes')}: {message[len('--plane: '):]}"
    raise ValueError(message) from None


def analyze(model, *, ideal_twin: bool = True, lyapunov: bool = True,
            poincare_driver: str = "", section_planes: Sequence[str] = (),
            discard_periods: int = 1, fft_channels: Sequence[str] = (),
            stats_window: Optional[Tuple[float, float]] = None,
            lyapunov_d0: float = 0.0, continuous_contact_time: float = 0.0,
            lyapunov_method: str = "variational") -> Dict[str, Any]:
    """Runs `model` (a Model, a model file path, or a Result, whose model and settings are run
    again) with the analyses of a study (C++ lash::analyze_run): the main run, its ideal twin
    (every clearance joint ideal), Poincare sections (stroboscopic once per period of
    `poincare_driver`, default the first constant-speed rotary driver, or event sections on
    `section_planes` such as "slider.vx=0"), spectra of `fft_channels` (default: translational
    bodies' ax and each clearance joint's Fn) after `discard_periods` transient periods,
    statistics over `stats_window` (t0, t1) s, contact modes, the Lyapunov exponents
    (`lyapunov_method` "variational": the spectrum with saltation matrices at contact events;
    "two-trajectory": the largest exponent, separation `lyapunov_d0`) and the periodic /
    quasi-periodic / chaotic verdict.

    Returns a dict: result (status, integrator), period_driver, period (s), verdict (kind,
    evidence, rule, lyapunov_exponent, ...), poincare (kind, points ndarray (n, 2k), times,
    variables, distinct, tolerance; None without a period or plane), spectra {channel:
    {frequency Hz, amplitude}, reduced to at most 2000 bins as spectra() says}, statistics {channel: {min, max, peak, rms, crest, ...}},
    clearance_joints {joint: contact modes}, lyapunov (None when not estimated), ideal_twin
    {channel: comparison} (None without). Releases the GIL; Ctrl-C raises KeyboardInterrupt.
    `section_planes` and `fft_channels` are lists of strings (a single string is one plane or
    channel); one plane at most (the crossings of several would be pooled into one map).
    Raises TypeError for an option of the wrong type, ValueError for one out of range or naming
    what does not exist, each naming the argument."""
    return _run_analysis(model, {}, ideal_twin=ideal_twin, lyapunov=lyapunov,
                         poincare_driver=poincare_driver, section_planes=section_planes,
                         discard_periods=discard_periods, fft_channels=fft_channels,
                         stats_window=stats_window, lyapunov_d0=lyapunov_d0,
                         continuous_contact_time=continuous_contact_time,
                         lyapunov_method=lyapunov_method)


def poincare(model, *, driver: str = "", planes: Sequence[str] = (),
             discard_periods: int = 1) -> Optional[Dict[str, Any]]:
    """Poincare sections of `model` (Model, path or Result): stroboscopic once per period of
    `driver` (default: the first constant-speed rotary driver), or event-based on `planes`
    ("<body>.<x|y|phi|vx|vy|omega>=VALUE[,down]"; one plane at most). Returns analyze()'s "poincare" dict (points
    (n, 2k) array of each clearance joint's eccentricity (ex, ey) in m, times, distinct, ...),
    or None when there is neither a period nor a plane. Runs without ideal twin and Lyapunov."""
    return _run_analysis(model, {"poincare_driver": "driver", "section_planes": "planes"},
                         ideal_twin=False, lyapunov=False, poincare_driver=driver,
                         section_planes=planes, discard_periods=discard_periods)["poincare"]


def verdict(model, **options: Any) -> Dict[str, Any]:
    """The periodic / quasi-periodic / chaotic / undetermined verdict of analyze() with its
    evidence and rule (needs the Lyapunov runs: this is the slow part of analyze)."""
    return analyze(model, **options)["verdict"]


def spectra(model, channels: Sequence[str] = (), discard_periods: int = 1) -> Dict[str, Any]:
    """Amplitude spectra (Hann window, after `discard_periods` periods) of `channels` of
    `model`, as analyze() computes them: {channel: {frequency (Hz), amplitude, ...}}. Reduced for
    plotting as the report's are: a spectrum of more than 2000 bins keeps the smallest and largest
    amplitude of each of 1000 groups of neighbouring bins (so its frequencies are not evenly
    spaced, and every peak stays); spectrum(result, channel) gives every bin of a Result."""
    return _run_analysis(model, {"fft_channels": "channels"}, ideal_twin=False, lyapunov=False,
                         fft_channels=channels, discard_periods=discard_periods)["spectra"]


def modes(model, *, equilibrium: bool = False) -> Dict[str, Any]:
    """Natural frequencies of `model` (Model, path or Result) linearised at rest, as `lash modes`
    computes them: every clearance joint ideal, every driver holding its coordinate where its
    motion starts, at the initial configuration or, with `equilibrium=True`, at the static
    equilibrium nearest it (`lash modes --equilibrium`; RuntimeError when there is none).

    Returns a dict: dof, modes (ascending: frequency Hz, damping_ratio, eigenvalue 1/s),
    real_rates (1/s: free, overdamped or unstable directions), equilibrium (None, or
    newton_steps, residual, largest_move (m) with its coordinate, largest_turn (rad) with its
    coordinate)."""
    return _lash.linear_modes(_model_of(model).compiled(), _flag("equilibrium", equilibrium))


def spectrum(result, channel: str, *, t0: float = 0.0, window: str = "hann") -> Dict[str, Any]:
    """Amplitude spectrum of one channel of a Result from time `t0` (s) on, from its uniformly
    spaced outputs (no new run): amplitude_spectrum(result[channel][time >= t0], dt)."""
    from . import Result
    if not isinstance(result, Result):
        raise TypeError(f"spectrum: expected a lash.Result (lash.simulate's), got "
                        f"{type(result).__name__}; spectra(model, channels) runs a model")
    t0 = _real("t0", t0, "a time (s)")
    keep = result.time >= t0
    t = result.time[keep]
    if len(t) < 4:
        raise ValueError(f"spectrum of '{channel}': fewer than 4 outputs after t0 = {t0} s")
    # The last output is at end_time, off the output grid when end_time is not a whole number
    # of intervals: left out, as the FFT takes evenly spaced samples.
    dt = float(t[1] - t[0])
    even = np.abs(np.diff(t) - dt) <= 1e-6 * dt
    if not even[:-1].all():
        raise ValueError(f"spectrum of '{channel}': the outputs after t0 = {t0} s are not evenly "
                         f"spaced (at t = {float(t[int(np.argmin(even))]):g} s)")
    x = result[channel][keep]
    if not even[-1]:
        x = x[:-1]
    return amplitude_spectrum(x, dt, window)


def amplitude_spectrum(x, dt: float, window: str = "hann") -> Dict[str, Any]:
    """One-sided amplitude spectrum and PSD of `x` sampled every `dt` s, mean removed, window
    "hann" or "rectangular" (C++ lash::amplitude_spectrum, FFTW): a sinusoid of amplitude A on a
    bin reads A. Returns {frequency (Hz), amplitude, psd (units^2/Hz), window}. Raises ValueError
    for fewer than 4 samples, a sample that is not finite, or dt <= 0."""
    return _lash.amplitude_spectrum(_vector("x", x), _real("dt", dt, "a time step (s)"),
                                    _string("window", window, "\"hann\" or \"rectangular\""))


def _points(points: Any) -> List[List[float]]:
    """`points` (a sequence of points, each a sequence of numbers) as lists of floats; TypeError
    naming the argument otherwise."""
    if isinstance(points, (str, bytes)) or not hasattr(points, "__iter__"):
        raise TypeError(f"points: expected a sequence of points (each a sequence of numbers), "
                        f"got {_short(points)} ({type(points).__name__})")
    return [_vector(f"points[{i}]", p).tolist() for i, p in enumerate(points)]


def count_distinct(points, tol: float) -> int:
    """Number of distinct points (greedy clustering within Euclidean distance `tol`): a period-k
    orbit sampled stroboscopically gives k (C++ lash::count_distinct). Raises ValueError for
    points of different dimensions or tol < 0."""
    return _lash.count_distinct(_points(points), _real("tol", tol, "a distance"))


def classify_motion(lyapunov: float, period: float, distinct: int, sections: int,
                    non_harmonic_peaks: int = -1, min_end_time: float = 0.0,
                    recurring: int = -1, contraction: float = math.nan) -> Tuple[str, list]:
    """The verdict rule (verdict_rule()) on its inputs: largest Lyapunov exponent (1/s, NaN if not
    computed), period (s; 0 or NaN: none), distinct Poincare points, sections taken, how many
    of the distinct points recur (-1: all), and how their returns shrink (section_contraction;
    NaN: not computed). Returns (kind, evidence). Raises ValueError for a negative period."""
    period = _real("period", period, "a period (s)")
    if period < 0 or math.isinf(period):
        raise ValueError(f"period: expected a finite period (s) > 0, or 0 or NaN for none, got {period!r}")
    return _lash.classify_motion(_real("lyapunov", lyapunov, "an exponent (1/s)"),
                                 period,
                                 _c_int("distinct", distinct), _c_int("sections", sections),
                                 _c_int("non_harmonic_peaks", non_harmonic_peaks),
                                 _real("min_end_time", min_end_time, "a time (s)"),
                                 _c_int("recurring", recurring),
                                 _real("contraction", contraction, "a ratio"))


def section_contraction(points: Any) -> float:
    """How Poincare points' returns shrink: each point's distance to the nearest of the next 8,
    the median over the last third of the points that have 8 successors divided by the median
    over the first third (docs/analysis.md, the verdict rule). About 1 on a torus, below 1 where
    the points close in on an orbit or rest; NaN with fewer than 12 points. Raises ValueError
    for points of different dimensions."""
    return _lash.section_contraction(_points(points))


def verdict_rule() -> str:
    """The rule classify_motion applies, in words."""
    return _lash.verdict_rule()


def contact_modes(times, onset, velocities, in_contact_at_t0: bool, t0: float, t1: float,
                  continuous_time: float) -> Dict[str, Any]:
    """Contact episodes from located onsets/separations over [t0, t1] s: episodes longer than
    `continuous_time` are continuous contact, shorter ones impacts (C++ lash::contact_modes).
    Pass a Result's events: contact_modes(ev["time"], ev["event"] == "onset", ev["velocity"], ...).
    Raises ValueError unless times, onset and velocities have one entry per event each, times
    are non-decreasing, t0 <= t1 and continuous_time >= 0."""
    onset = np.asarray(onset)
    if onset.ndim != 1:
        raise ValueError(f"onset: expected a 1-D sequence of booleans, got an array of shape "
                         f"{onset.shape}")
    if onset.size and onset.dtype != np.bool_:
        # bool("separation") is True: the event names passed as they are would all count as onsets.
        raise TypeError(f"onset: expected booleans (ev[\"event\"] == \"onset\"), got "
                        f"{onset.dtype} values such as {onset[0]!r}")
    return _lash.contact_modes(_vector("times", times).tolist(), [bool(o) for o in onset],
                               _vector("velocities", velocities).tolist(),
                               _flag("in_contact_at_t0", in_contact_at_t0),
                               _real("t0", t0, "a time (s)"), _real("t1", t1, "a time (s)"),
                               _real("continuous_time", continuous_time, "a time (s)"))


def decimate_min_max(t, v, buckets: int) -> Tuple[np.ndarray, np.ndarray]:
    """Reduces (t, v) to about 2*buckets points keeping each bucket's min and max in time order,
    so impact spikes survive plotting. Raises ValueError unless t and v have the same length and
    buckets >= 0 (0 keeps every point)."""
    buckets = _integer("buckets", buckets, "a number of buckets")
    if not 0 <= buckets < 2**63:
        raise ValueError(f"decimate_min_max: buckets must be >= 0 (and below 2**63), got {buckets}")
    return _lash.decimate_min_max(_vector("t", t), _vector("v", v), buckets)
