"""lash.analysis: the analysis layer of Lash (docs/analysis.md).

A run with its analyses (C++ `lash::analyze_run`, what `lash run --report` and `lash analyze`
compute) — `analyze`, and `poincare`, `verdict`, `spectra` taking the parts of it — and the
model-free functions of src/analysis one to one: `amplitude_spectrum`, `count_distinct`,
`classify_motion`, `verdict_rule`, `contact_modes`, `decimate_min_max`.
"""
from __future__ import annotations

from typing import Any, Dict, Optional, Sequence, Tuple

import numpy as np

from . import _lash

__all__ = ["analyze", "poincare", "verdict", "spectra", "spectrum", "amplitude_spectrum",
           "count_distinct", "classify_motion", "verdict_rule", "contact_modes",
           "decimate_min_max"]


def _vector(name: str, x) -> np.ndarray:
    """`x` as a 1-D float array; ValueError naming the argument when it is not one."""
    a = np.asarray(x, dtype=float)
    if a.ndim != 1:
        raise ValueError(f"{name}: expected a 1-D sequence of numbers, got an array of shape "
                         f"{a.shape}")
    return a


def _model_of(model_or_result):
    from . import Model, Result, _as_model
    if isinstance(model_or_result, Result):
        # The same model and settings as the run (t_end included).
        m = model_or_result.model.copy()
        m.set("solver.end_time", model_or_result._compiled.end_time)
        m.set("solver.output_interval", model_or_result._compiled.output_interval)
        return m
    return _as_model(model_or_result)


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
    {frequency Hz, amplitude}}, statistics {channel: {min, max, peak, rms, crest, ...}},
    clearance_joints {joint: contact modes}, lyapunov (None when not estimated), ideal_twin
    {channel: comparison} (None without). Releases the GIL; Ctrl-C raises KeyboardInterrupt.
    Raises ValueError for an option naming what does not exist."""
    opts: Dict[str, Any] = {"ideal_twin": ideal_twin, "lyapunov": lyapunov,
                            "poincare_driver": poincare_driver,
                            "section_planes": list(section_planes),
                            "discard_periods": discard_periods, "fft_channels": list(fft_channels),
                            "lyapunov_d0": lyapunov_d0, "lyapunov_method": lyapunov_method,
                            "continuous_contact_time": continuous_contact_time}
    if stats_window is not None:
        opts["stats_window"] = tuple(stats_window)
    return _lash.analyze(_model_of(model).compiled(), opts)


def poincare(model, *, driver: str = "", planes: Sequence[str] = (),
             discard_periods: int = 1) -> Optional[Dict[str, Any]]:
    """Poincare sections of `model` (Model, path or Result): stroboscopic once per period of
    `driver` (default: the first constant-speed rotary driver), or event-based on `planes`
    ("<body>.<x|y|phi|vx|vy|omega>=VALUE[,down]"). Returns analyze()'s "poincare" dict (points
    (n, 2k) array of each clearance joint's eccentricity (ex, ey) in m, times, distinct, ...),
    or None when there is neither a period nor a plane. Runs without ideal twin and Lyapunov."""
    return analyze(model, ideal_twin=False, lyapunov=False, poincare_driver=driver,
                   section_planes=planes, discard_periods=discard_periods)["poincare"]


def verdict(model, **options: Any) -> Dict[str, Any]:
    """The periodic / quasi-periodic / chaotic / undetermined verdict of analyze() with its
    evidence and rule (needs the Lyapunov runs: this is the slow part of analyze)."""
    return analyze(model, **options)["verdict"]


def spectra(model, channels: Sequence[str] = (), discard_periods: int = 1) -> Dict[str, Any]:
    """Amplitude spectra (Hann window, after `discard_periods` periods) of `channels` of
    `model`, as analyze() computes them: {channel: {frequency (Hz), amplitude, ...}}."""
    return analyze(model, ideal_twin=False, lyapunov=False, fft_channels=channels,
                   discard_periods=discard_periods)["spectra"]


def spectrum(result, channel: str, *, t0: float = 0.0, window: str = "hann") -> Dict[str, Any]:
    """Amplitude spectrum of one channel of a Result from time `t0` (s) on, from its uniformly
    spaced outputs (no new run): amplitude_spectrum(result[channel][time >= t0], dt)."""
    keep = result.time >= t0
    t = result.time[keep]
    if len(t) < 4:
        raise ValueError(f"spectrum of '{channel}': fewer than 4 outputs after t0 = {t0} s")
    return amplitude_spectrum(result[channel][keep], float(t[1] - t[0]), window)


def amplitude_spectrum(x, dt: float, window: str = "hann") -> Dict[str, Any]:
    """One-sided amplitude spectrum and PSD of `x` sampled every `dt` s, mean removed, window
    "hann" or "rectangular" (C++ lash::amplitude_spectrum, FFTW): a sinusoid of amplitude A on a
    bin reads A. Returns {frequency (Hz), amplitude, psd (units^2/Hz), window}. Raises ValueError
    for fewer than 4 samples or dt <= 0."""
    return _lash.amplitude_spectrum(_vector("x", x), float(dt), window)


def count_distinct(points, tol: float) -> int:
    """Number of distinct points (greedy clustering within Euclidean distance `tol`): a period-k
    orbit sampled stroboscopically gives k (C++ lash::count_distinct). Raises ValueError for
    points of different dimensions or tol < 0."""
    return _lash.count_distinct([list(map(float, p)) for p in points], float(tol))


def classify_motion(lyapunov: float, period: float, distinct: int, sections: int,
                    non_harmonic_peaks: int = -1, min_end_time: float = 0.0) -> Tuple[str, list]:
    """The verdict rule (verdict_rule()) on its inputs: largest Lyapunov exponent (1/s, NaN if not
    computed), period (s), distinct Poincare points, sections taken. Returns (kind, evidence)."""
    return _lash.classify_motion(lyapunov, period, distinct, sections, non_harmonic_peaks,
                                 min_end_time)


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
    return _lash.contact_modes(_vector("times", times).tolist(), [bool(o) for o in onset],
                               _vector("velocities", velocities).tolist(), in_contact_at_t0,
                               t0, t1, continuous_time)


def decimate_min_max(t, v, buckets: int) -> Tuple[np.ndarray, np.ndarray]:
    """Reduces (t, v) to about 2*buckets points keeping each bucket's min and max in time order,
    so impact spikes survive plotting. Raises ValueError unless t and v have the same length and
    buckets >= 0 (0 keeps every point)."""
    return _lash.decimate_min_max(_vector("t", t), _vector("v", v), int(buckets))
