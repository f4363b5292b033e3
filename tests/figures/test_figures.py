"""Tests of tools/lash_figures.py (and of the sample builder tests/figures/make_sample.py).

Run from the repository root with Debian's interpreter, which has python3-numpy and
python3-matplotlib:

    /usr/bin/python3 -m unittest discover -s tests/figures -v

Nothing here needs build/lash: setUpClass writes a small synthetic run folder (an analytic
slider-crank with a clearance joint: timeseries.csv, events.csv, model_resolved.yaml,
summary.json) and its ideal twin, builds report_data.json from them with make_sample.py, and runs
lash_figures.py on it the way a user does.
"""

import copy
import importlib.util
import json
import math
import os
import shutil
import struct
import subprocess
import tempfile
import unittest
import xml.etree.ElementTree as ET
import zlib

import matplotlib
import numpy as np

matplotlib.use("Agg")

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SCRIPT = os.path.join(ROOT, "tools", "lash_figures.py")
PYTHON = "/usr/bin/python3"       # Debian's interpreter: python3-numpy, python3-matplotlib

# Synthetic mechanism: Flores-like slider-crank, crank r, rod l, 5000 rpm, two revolutions.
CRANK_R, ROD_L, OMEGA = 0.05, 0.12, 5000 * 2 * math.pi / 60
PERIOD = 2 * math.pi / OMEGA
CLEARANCE = 0.5e-3
DT, END = 2.0e-5, 2 * PERIOD
MAX_POINTS = 300                  # decimation of the sample: stride 5 over ~1200 rows
SPIKE_ROW, SPIKE_AX = 7, -4.0e5   # a spike only full resolution sees (row 7 is not decimated)
IMPACTS = [(0.8e-3, 0.86e-3, 3.1), (2.0e-3, 2.05e-3, 1.7), (3.0e-3, 6.5e-3, 0.9),
           (13.0e-3, 13.04e-3, 2.4), (14.0e-3, 19.0e-3, 0.6)]   # (onset, separation, δ̇⁻)

EXPECTED = ["acceleration_peak", "acceleration_translational", "contact_force_rod_slider",
            "orbit_rod_slider", "modes", "impact_velocity", "poincare", "spectra",
            "phase_rod_slider-ex_vs_rod_slider-ey",
            "phase_rod_slider-delta_vs_rod_slider-delta_dot", "phase_slider-x_vs_slider-vx",
            "lyapunov", "driver_torque_crank", "energy"]

# Unit and description of each channel by quantity, as the engine writes them into summary.json
# (channels.<name>.unit/.description); only this test uses the table, to play the engine's part.
ENGINE_UNITS = {
    "x": ("m", "position of the centre of mass along x"),
    "y": ("m", "position of the centre of mass along y"),
    "phi": ("rad", "angle"), "vx": ("m/s", "velocity along x"), "vy": ("m/s", "velocity along y"),
    "omega": ("rad/s", "angular velocity"), "ax": ("m/s²", "acceleration along x"),
    "ay": ("m/s²", "acceleration along y"), "alpha": ("rad/s²", "angular acceleration"),
    "Fx": ("N", "reaction force along x"), "Fy": ("N", "reaction force along y"),
    "F": ("N", "reaction force magnitude"), "ex": ("m", "eccentricity along x"),
    "ey": ("m", "eccentricity along y"), "e": ("m", "eccentricity"),
    "delta": ("m", "penetration"), "delta_dot": ("m/s", "penetration rate"),
    "Fn": ("N", "normal contact force"), "Ft": ("N", "friction force"),
    "vt": ("m/s", "slip velocity"), "mode": ("", "contact mode (1 in contact)"),
    "torque": ("N·m", "driving torque"), "kinetic": ("J", "kinetic energy"),
    "potential": ("J", "potential energy"), "dissipated": ("J", "dissipated energy"),
    "input": ("J", "input work"), "balance": ("J", "energy balance"),
}
# Sensor channels whose names say nothing of their unit: an accelerometer (no known suffix) and
# a load cell whose '.x' a suffix table would have read as a position in m.
SENSORS = {"acc1.a": ("m/s²", "accelerometer acc1 on the slider"),
           "load_cell.x": ("N", "guide load cell force")}

MODEL_YAML = """name: synthetic_slider_crank
gravity: [0, -9.81]
ground:
  markers: {O: [0, 0]}
bodies:
  crank: {mass: 0.3, inertia: 1.0e-4, position: [0.025, 0],
          markers: {O: [-0.025, 0], A: [0.025, 0]}}
  rod: {mass: 0.21, inertia: 2.5e-4, position: [0.11, 0], markers: {A: [-0.06, 0], B: [0.06, 0]}}
  slider: {mass: 0.14, inertia: 1.0e-4, position: [0.17, 0], markers: {O: [0, 0]}}
clearance_defaults: {journal_radius: 9.5e-3, normal_law: lankarani_nikravesh, friction: {law: none}}
joints:
  crank_pivot: {type: revolute, journal: crank.O, bearing: ground.O}
  crank_rod: {type: revolute, journal: crank.A, bearing: rod.A}
  rod_slider: {type: revolute, journal: rod.B, bearing: slider.O, clearance: 0.5e-3}
  slider_guide: {type: translational, guide: ground.O, slider: slider.O, axis: [1, 0]}
drivers:
  crank: {joint: crank_pivot, speed_rpm: 5000}
solver: {integrator: dopri5, end_time: 0.024, output_interval: 2.0e-5}
"""


def load_module(name, path):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


make_sample = load_module("make_sample", os.path.join(HERE, "make_sample.py"))
lash_figures = load_module("lash_figures", SCRIPT)


def write_csv(path, columns):
    names = list(columns)
    data = np.column_stack([columns[n] for n in names])
    np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.9g")


def ideal_kinematics(t):
    """Closed-form slider-crank: crank angle θ = ωt, slider on the x axis."""
    th = OMEGA * t
    s = np.sqrt(ROD_L ** 2 - (CRANK_R * np.sin(th)) ** 2)
    x_slider = CRANK_R * np.cos(th) + s
    beta = -np.arcsin(CRANK_R * np.sin(th) / ROD_L)          # rod angle
    return th, x_slider, beta


def write_run(folder, clearance):
    """A synthetic `lash run` folder; with clearance=False the ideal twin."""
    os.makedirs(folder, exist_ok=True)
    t = np.arange(0.0, END + 0.5 * DT, DT)
    th, xs, beta = ideal_kinematics(t)
    d = lambda v: np.gradient(v, t)                           # noqa: E731
    cols = {"time": t}
    bodies = {"crank": (0.5 * CRANK_R * np.cos(th), 0.5 * CRANK_R * np.sin(th), th),
              "rod": (CRANK_R * np.cos(th) + 0.5 * (xs - CRANK_R * np.cos(th)),
                      0.5 * CRANK_R * np.sin(th), beta),
              "slider": (xs, 0 * t, 0 * t)}
    for b, (x, y, phi) in bodies.items():
        cols.update({f"{b}.x": x, f"{b}.y": y, f"{b}.phi": phi,
                     f"{b}.vx": d(x), f"{b}.vy": d(y), f"{b}.omega": d(phi),
                     f"{b}.ax": d(d(x)), f"{b}.ay": d(d(y)), f"{b}.alpha": d(d(phi))})
    inertia = 0.14 * cols["slider.ax"]
    torque = 0.02 * np.sin(2 * th) * 1e3
    if clearance:
        # Contact pulses at the impacts, a journal that rides the bearing wall between them.
        fn = np.zeros_like(t)
        mode = np.zeros_like(t)
        for t0, t1, v in IMPACTS:
            inside = (t >= t0) & (t <= t1)
            mode[inside] = 1.0
            fn += 1.0e4 * v * np.exp(-((t - t0) / 2.0e-5) ** 2)
            fn[inside] += np.abs(inertia[inside])
        angle = np.pi + 0.8 * np.sin(th) + 0.2 * np.sin(7 * th)
        radius = CLEARANCE * np.where(mode > 0, 1.02, 0.9 + 0.1 * np.cos(40 * th))
        ex, ey = radius * np.cos(angle), radius * np.sin(angle)
        e = np.hypot(ex, ey)
        cols["slider.ax"] = cols["slider.ax"] + fn / 0.14 * np.sign(np.cos(angle)) * 0.3
        cols["slider.ax"][SPIKE_ROW] = SPIKE_AX
        cols.update({"rod_slider.ex": ex, "rod_slider.ey": ey, "rod_slider.e": e,
                     "rod_slider.delta": e - CLEARANCE, "rod_slider.delta_dot": d(e),
                     "rod_slider.Fn": fn, "rod_slider.Ft": 0 * t, "rod_slider.vt": d(angle) * e,
                     "rod_slider.mode": mode})
        torque = torque + 5e-3 * fn
        cols.update({"acc1.a": 1.02 * cols["slider.ax"], "load_cell.x": 300.0 * np.sin(th)})
    else:
        cols.update({"rod_slider.Fx": inertia, "rod_slider.Fy": 0.1 * inertia,
                     "rod_slider.F": np.abs(inertia) * 1.005})
    kinetic = 0.5 * 0.14 * cols["slider.vx"] ** 2 + 60.0
    dissipated = np.cumsum(np.abs(cols.get("rod_slider.Fn", 0 * t))) * 1e-6
    inp = kinetic - kinetic[0] + dissipated
    cols.update({"crank.torque": torque, "energy.kinetic": kinetic,
                 "energy.potential": 0.1 * np.sin(th), "energy.dissipated": dissipated,
                 "energy.input": inp,
                 "energy.balance": kinetic + 0.1 * np.sin(th) + dissipated - inp + 1e-6 * t})
    write_csv(os.path.join(folder, "timeseries.csv"), cols)
    with open(os.path.join(folder, "events.csv"), "w") as f:
        f.write("time,joint,event,velocity\n")
        for t0, t1, v in IMPACTS if clearance else []:
            f.write(f"{t0!r},rod_slider,onset,{v!r}\n{t1!r},rod_slider,separation,{-0.8 * v!r}\n")
    with open(os.path.join(folder, "model_resolved.yaml"), "w") as f:
        f.write(MODEL_YAML if clearance else MODEL_YAML.replace(", clearance: 0.5e-3", ""))
    channels = {}
    for name, v in cols.items():
        if name == "time":
            continue
        unit, description = SENSORS.get(name) or ENGINE_UNITS[name.rpartition(".")[2]]
        channels[name] = {"min": float(v.min()), "max": float(v.max()),
                          "peak": float(np.abs(v).max()), "unit": unit,
                          "description": description}
    with open(os.path.join(folder, "summary.json"), "w") as f:
        json.dump({"status": {"ok": True, "time": float(t[-1]), "element": "", "message": ""},
                   "channels": channels,
                   "clearance_joints": {"rod_slider": {"clearance": CLEARANCE}}}, f)


def axis_labels(plan):
    """[(x label, y label)] of each axes of the figure a plan draws, in the figure style."""
    import matplotlib.pyplot as plt
    with plt.rc_context(lash_figures.STYLE):
        fig = plan.draw()
    try:
        return [(ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes]
    finally:
        plt.close(fig)


def run_figures(*args):
    return subprocess.run([PYTHON, SCRIPT, *args], capture_output=True, text=True, timeout=300)


def png_info(path):
    """(width, height, dpi) of a PNG, checking its signature and chunk CRCs."""
    with open(path, "rb") as f:
        data = f.read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG signature"
    pos, width, height, dpi = 8, None, None, None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
        (crc,) = struct.unpack(">I", data[pos + 8 + length:pos + 12 + length])
        assert zlib.crc32(kind + body) == crc, f"bad CRC in chunk {kind!r}"
        if kind == b"IHDR":
            width, height = struct.unpack(">II", body[:8])
        elif kind == b"pHYs":
            ppm_x, _, unit = struct.unpack(">IIB", body)
            dpi = ppm_x * 0.0254 if unit == 1 else None
        pos += 12 + length
        if kind == b"IEND":
            break
    return width, height, dpi


class FiguresOfASyntheticRun(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="lash_figures_test_")
        cls.run_dir = os.path.join(cls.tmp, "run")
        ideal_dir = os.path.join(cls.tmp, "ideal")
        write_run(cls.run_dir, clearance=True)
        write_run(ideal_dir, clearance=False)
        cls.report = make_sample.build(cls.run_dir, ideal_dir, period=PERIOD,
                                       max_points=MAX_POINTS)
        with open(os.path.join(cls.run_dir, "report_data.json"), "w") as f:
            json.dump(cls.report, f, allow_nan=False)
        cls.result = run_figures(cls.run_dir)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def fig(self, name, ext):
        return os.path.join(self.run_dir, "figures", f"{name}.{ext}")

    def test_exits_0_and_lists_every_file_written(self):
        self.assertEqual(self.result.returncode, 0, self.result.stderr)
        listed = self.result.stdout.split()
        expected = [self.fig(n, e) for n in EXPECTED for e in ("png", "svg")]
        self.assertEqual(sorted(listed), sorted(expected))
        self.assertNotIn("skipped", self.result.stderr)
        self.assertNotIn("Traceback", self.result.stderr)

    def test_pngs_are_valid_300_dpi_and_not_blank(self):
        import matplotlib.image
        for name in EXPECTED:
            with self.subTest(name=name):
                width, height, dpi = png_info(self.fig(name, "png"))
                self.assertAlmostEqual(dpi, 300, delta=0.5)
                self.assertGreater(width, 500)
                self.assertGreater(height, 300)
                pixels = matplotlib.image.imread(self.fig(name, "png"))[..., :3]
                self.assertEqual(pixels.shape[:2], (height, width))
                self.assertGreater(float(pixels.var()), 1e-3)       # more than a flat canvas
                self.assertGreater(float((pixels.mean(axis=2) < 0.9).mean()), 0.005)

    def test_svgs_parse_as_xml(self):
        for name in EXPECTED:
            with self.subTest(name=name):
                root = ET.parse(self.fig(name, "svg")).getroot()
                self.assertTrue(root.tag.endswith("svg"))
                self.assertGreater(len(list(root.iter())), 50)

    def test_sample_decimates_and_full_resolution_keeps_the_spike(self):
        series = self.report["series"]
        self.assertLessEqual(len(series["time"]), MAX_POINTS + 1)
        self.assertNotIn(SPIKE_AX, series["channels"]["slider.ax"])     # decimated away
        rep = lash_figures.Report(self.run_dir, self.report)
        lash_figures.read_full_resolution(rep, ["slider.ax"])
        self.assertEqual(rep.full["slider.ax"].peak, abs(SPIKE_AX))
        self.assertEqual(float(rep.full["slider.ax"].lo.min()), SPIKE_AX)

    def test_a_statistics_window_narrows_the_curves_to_it(self):
        # `lash report --window T0,T1` takes the statistics over [T0, T1]; the curves against the
        # motion then show that window only (here the second revolution: 360° to 720°).
        import matplotlib.pyplot as plt
        report = copy.deepcopy(self.report)
        for v in report["analysis"]["statistics"].values():
            v["window"] = [END / 2, END]
        rep = lash_figures.Report(self.run_dir, report)
        self.assertEqual(rep.window, (END / 2, float(rep.time[-1])))
        lo, hi = rep.xaxis.of_time(np.array(rep.window))
        with plt.rc_context(lash_figures.STYLE):
            fig = lash_figures.plan_contact_force(rep)[0].draw()
        try:
            ax = fig.axes[0]
            self.assertAlmostEqual(ax.get_xlim()[0], lo, delta=1e-6 * abs(hi))
            self.assertAlmostEqual(ax.get_xlim()[1], hi, delta=0.01 * abs(hi))
            drawn = [x for line in ax.get_lines() for x in np.asarray(line.get_xdata(), float)]
            drawn += [p[0] for c in ax.collections for path in c.get_paths() for p in path.vertices]
            self.assertGreater(len(drawn), 10)
            self.assertGreaterEqual(min(drawn), lo - 1e-9 * abs(hi))
        finally:
            plt.close(fig)
        # The run's own window (the whole run): no narrowing.
        whole = lash_figures.Report(self.run_dir, self.report)
        self.assertIsNone(whole.window)

    def test_an_angle_range_folds_the_curves_into_it(self):
        # `lash report --angle-range 90,270` takes the statistics over those crank angles; the
        # curves against the motion are then drawn against the angle folded into [90°, 270°],
        # every revolution on top of the others, each revolution its own line.
        import matplotlib.pyplot as plt
        report = copy.deepcopy(self.report)
        for v in report["analysis"]["statistics"].values():
            v["angle_range"] = [90.0, 270.0]
        rep = lash_figures.Report(self.run_dir, report)
        self.assertEqual(rep.xaxis.fold, (90.0, 180.0))
        x, v = rep.xaxis.curve(rep.time, rep.channel("slider.x"))
        shown = np.isfinite(x)
        self.assertTrue(np.all(x[shown] >= 90.0) and np.all(x[shown] <= 270.0 + 1e-9))
        self.assertTrue(np.array_equal(shown, np.isfinite(v)))
        # Two revolutions: the samples inside the range form two runs of finite values.
        starts = np.count_nonzero(shown[1:] & ~shown[:-1]) + int(shown[0])
        self.assertEqual(starts, 2)
        with plt.rc_context(lash_figures.STYLE):
            fig = lash_figures.plan_contact_force(rep)[0].draw()
        try:
            ax = fig.axes[0]
            self.assertAlmostEqual(ax.get_xlim()[0], 90.0, delta=1e-9)
            self.assertAlmostEqual(ax.get_xlim()[1], 270.0, delta=1e-9)
            drawn = [x for line in ax.get_lines() for x in np.asarray(line.get_xdata(), float)]
            drawn += [p[0] for c in ax.collections for path in c.get_paths() for p in path.vertices]
            drawn = [x for x in drawn if np.isfinite(x)]
            self.assertGreater(len(drawn), 10)
            self.assertGreaterEqual(min(drawn), 90.0 - 1e-9)
            self.assertLessEqual(max(drawn), 270.0 + 1e-9)
        finally:
            plt.close(fig)
        # A range across 0° (300° to 60°) folds into [300°, 420°].
        for v in report["analysis"]["statistics"].values():
            v["angle_range"] = [300.0, 60.0]
        rep = lash_figures.Report(self.run_dir, report)
        self.assertEqual(rep.xaxis.fold, (300.0, 120.0))
        x, _ = rep.xaxis.curve(rep.time, rep.channel("slider.x"))
        self.assertTrue(np.nanmin(x) >= 300.0 and np.nanmax(x) <= 420.0 + 1e-9)

    def test_units_and_descriptions_come_from_channel_info(self):
        info = self.report["channel_info"]
        self.assertEqual(info["acc1.a"], {"unit": "m/s²",
                                          "description": "accelerometer acc1 on the slider"})
        self.assertEqual(info["load_cell.x"], {"unit": "N", "description": "guide load cell force"})
        self.assertEqual(set(info), set(self.report["series"]["channels"]))
        report = copy.deepcopy(self.report)
        report["analysis"]["phase"] = [{"x": "acc1.a", "y": "load_cell.x"}]
        spectrum = next(iter(report["analysis"]["spectra"].values()))
        report["analysis"]["spectra"] = {"acc1.a": spectrum}
        rep = lash_figures.Report(self.run_dir, report)
        # A sensor with no telling suffix gets m/s² (scaled by a power of ten), and the load cell
        # named '.x' gets N, not the metres a suffix table would have given it.
        [(x_label, y_label)] = axis_labels(lash_figures.plan_phase(rep)[0])
        self.assertRegex(x_label, r"^Accelerometer acc1 on the slider \(\$10\^\{3\}\$ m/s²\)$")
        self.assertEqual(y_label, "Guide load cell force (N)")
        [(_, y_label)] = axis_labels(lash_figures.plan_spectra(rep)[0])
        self.assertEqual(y_label, "Accelerometer acc1 on the slider amplitude (m/s²)")
        [(_, y_label)] = axis_labels(lash_figures.plan_contact_force(rep)[0])
        self.assertEqual(y_label, "Rod slider normal contact force (kN)")
        labels = axis_labels(lash_figures.plan_energy(rep)[0])
        self.assertEqual([y for _, y in labels], ["Energy (J)", "Balance drift (J)"])

    def test_a_channel_channel_info_lacks_gets_its_name_and_no_unit(self):
        report = copy.deepcopy(self.report)
        for name in ("load_cell.x", "rod_slider.Fn"):
            del report["channel_info"][name]
        report["analysis"]["phase"] = [{"x": "acc1.a", "y": "load_cell.x"}]
        rep = lash_figures.Report(self.run_dir, report)
        [(x_label, y_label)] = axis_labels(lash_figures.plan_phase(rep)[0])
        self.assertIn("m/s²", x_label)
        self.assertEqual(y_label, "load_cell.x")
        [(_, y_label)] = axis_labels(lash_figures.plan_contact_force(rep)[0])
        self.assertEqual(y_label, "rod_slider.Fn")
        # No channel_info at all (a file from an older engine): every figure is still drawn.
        del report["channel_info"]
        rep = lash_figures.Report(self.run_dir, report)
        [(_, y_label)] = axis_labels(lash_figures.plan_acceleration_peak(rep)[0])
        self.assertEqual(y_label, "slider.ax")
        labels = axis_labels(lash_figures.plan_energy(rep)[0])
        self.assertEqual([y for _, y in labels], ["Energy", "Balance drift"])
        [(x_label, y_label)] = axis_labels(lash_figures.plan_poincare(rep)[0])
        self.assertEqual((x_label, y_label), ("rod_slider.ex", "rod_slider.ey"))

    def test_every_clearance_joint_gets_its_poincare_figure(self):
        report = copy.deepcopy(self.report)
        p = report["analysis"]["poincare"]
        main = [[x, y] for x, y in p["points"]]
        p["joints"] = [{"joint": "rod_slider", "variables": p["variables"], "points": main},
                       {"joint": "crank rod", "variables": ["crank_rod.ex", "crank_rod.ey"],
                        "points": [[1e-5, 2e-5], [3e-5, -1e-5]]},
                       {"joint": "empty", "variables": ["e.ex", "e.ey"], "points": []}]
        rep = lash_figures.Report(self.run_dir, report)
        plans = lash_figures.plan_poincare(rep)
        # The main section, then the joint whose variables differ; a joint without points: none.
        self.assertEqual([pl.name for pl in plans], ["poincare", "poincare_crank-rod"])
        [(x_label, y_label)] = axis_labels(plans[1])
        self.assertIn("crank_rod.ex", x_label)

    def test_only_and_format_select_the_files(self):
        out = tempfile.mkdtemp(dir=self.tmp)
        shutil.copy(os.path.join(self.run_dir, "report_data.json"), out)
        r = run_figures(out, "--only", "orbit", "energy", "--format", "svg,pdf")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(sorted(f for f in os.listdir(os.path.join(out, "figures")) if f != ".lash-figures"),
                         ["energy.pdf", "energy.svg", "orbit_rod_slider.pdf",
                          "orbit_rod_slider.svg"])
        # No timeseries.csv in this folder: curves fall back to the decimated series.
        r = run_figures(out, "--only", "contact_force_rod_slider", "--format", "png")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("decimated series", r.stderr)
        self.assertEqual(r.stdout.split(), [os.path.join(out, "figures",
                                                         "contact_force_rod_slider.png")])


class MissingSections(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="lash_figures_test_")
        self.addCleanup(shutil.rmtree, self.tmp, True)

    def write(self, report):
        with open(os.path.join(self.tmp, "report_data.json"), "w") as f:
            json.dump(report, f)

    def figures(self):
        d = os.path.join(self.tmp, "figures")
        return sorted(f for f in os.listdir(d) if f != ".lash-figures") if os.path.isdir(d) else []

    def test_null_and_absent_sections_are_skipped(self):
        t = np.linspace(0.0, 0.01, 200)
        channels = {"slider.ax": list(1e4 * np.sin(600 * t)),
                    "rod_slider.Fn": [None] + list(np.abs(5e3 * np.sin(900 * t[1:]))),
                    "energy.kinetic": list(60 + np.sin(600 * t))}
        self.write({"version": 1, "model": None,
                    "series": {"time": list(t), "crank_angle": None, "channels": channels,
                               "ideal": None},
                    "analysis": {"statistics": None, "clearance": None, "poincare": None,
                                 "spectra": {"slider.ax": None}, "phase": None,
                                 "lyapunov": {"history": None}}})
        r = run_figures(self.tmp, "--format", "png")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(self.figures(), ["acceleration_peak.png", "contact_force_rod_slider.png",
                                          "energy.png"])
        for family in ("poincare", "spectra", "phase", "lyapunov", "orbit", "modes",
                       "impact_velocity", "driver_torque", "acceleration_translational"):
            self.assertIn(f"skipped {family}:", r.stderr)
        self.assertNotIn("Traceback", r.stderr)

    def test_nothing_to_draw_exits_1(self):
        self.write({"version": 1})
        r = run_figures(self.tmp)
        self.assertEqual(r.returncode, 1)
        self.assertIn("no figure could be made", r.stderr)
        self.assertEqual(self.figures(), [])


class BadInput(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="lash_figures_test_")
        self.addCleanup(shutil.rmtree, self.tmp, True)

    def assertExits2(self, args, message):
        r = run_figures(*args)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn(message, r.stderr)
        self.assertNotIn("Traceback", r.stderr)
        self.assertEqual(r.stdout, "")

    def test_missing_folder(self):
        missing = os.path.join(self.tmp, "nope")
        self.assertExits2([missing], f"no such folder: {missing}")

    def test_missing_report(self):
        self.assertExits2([self.tmp], "report_data.json not found")

    def test_invalid_json_points_at_the_line(self):
        with open(os.path.join(self.tmp, "report_data.json"), "w") as f:
            f.write('{"version": 1,\n "series": [1, 2,,]}\n')
        self.assertExits2([self.tmp], "report_data.json:2:")
        self.assertExits2([self.tmp], "invalid JSON")

    def test_not_an_object_and_unknown_version(self):
        path = os.path.join(self.tmp, "report_data.json")
        with open(path, "w") as f:
            f.write("[1, 2]")
        self.assertExits2([self.tmp], "expected a JSON object")
        with open(path, "w") as f:
            f.write('{"version": 7}')
        self.assertExits2([self.tmp], "version 7 is not supported")

    def test_bad_options(self):
        with open(os.path.join(self.tmp, "report_data.json"), "w") as f:
            f.write('{"version": 1}')
        self.assertExits2([self.tmp, "--format", "png,gif"], "unknown format gif")
        self.assertExits2([self.tmp, "--only", "orbitz"], "unknown figure orbitz")


class Envelopes(unittest.TestCase):
    """The streaming min/max reduction, checked against a direct computation."""

    def test_envelope_matches_direct_min_max_across_chunks(self):
        tmp = tempfile.mkdtemp(prefix="lash_figures_test_")
        self.addCleanup(shutil.rmtree, tmp, True)
        rng = np.random.default_rng(3)
        t = np.linspace(0.0, 1.0, 5001)
        v = rng.normal(size=t.size)
        v[1234] = 50.0
        w = np.where(rng.random(t.size) < 0.01, np.nan, rng.normal(size=t.size))
        path = os.path.join(tmp, "timeseries.csv")
        write_csv(path, {"time": t, "a": v, "skipped": 0 * t, "b": w})
        old = lash_figures.CSV_CHUNK_BYTES
        lash_figures.CSV_CHUNK_BYTES = 4096                  # many chunks, buckets split across
        self.addCleanup(setattr, lash_figures, "CSV_CHUNK_BYTES", old)
        buckets = 97
        env = lash_figures.read_envelopes(path, ["b", "a", "missing"], 0.0, 1.0, buckets)
        self.assertEqual(sorted(env), ["a", "b"])
        v_file = np.loadtxt(path, delimiter=",", skiprows=1)
        b = np.clip((v_file[:, 0] * buckets).astype(int), 0, buckets - 1)
        for name, col in (("a", 1), ("b", 3)):
            x = v_file[:, col]
            lo = [np.nanmin(x[b == k]) for k in range(buckets)]
            hi = [np.nanmax(x[b == k]) for k in range(buckets)]
            np.testing.assert_array_equal(env[name].lo, lo)
            np.testing.assert_array_equal(env[name].hi, hi)
            self.assertTrue(np.all(np.diff(env[name].t) > 0))
            self.assertEqual(env[name].rows, t.size)
        self.assertEqual(env["a"].peak, 50.0)


class SampleWithoutYaml(unittest.TestCase):
    """make_sample.py infers the model from the column names when PyYAML is missing."""

    def test_inferred_model_gives_the_same_analysis_keys(self):
        tmp = tempfile.mkdtemp(prefix="lash_figures_test_")
        self.addCleanup(shutil.rmtree, tmp, True)
        write_run(tmp, clearance=True)
        old = make_sample.load_model_yaml
        make_sample.load_model_yaml = lambda run_dir: None
        self.addCleanup(setattr, make_sample, "load_model_yaml", old)
        report = make_sample.build(tmp, None, period=PERIOD, max_points=MAX_POINTS)
        self.assertIsNotNone(report["series"]["crank_angle"])
        self.assertEqual(report["analysis"]["clearance"]["rod_slider"]["clearance"], CLEARANCE)
        self.assertIn({"x": "slider.x", "y": "slider.vx"}, report["analysis"]["phase"])
        self.assertEqual(len(report["analysis"]["clearance"]["rod_slider"]["impact_velocities"]),
                         len(IMPACTS))


if __name__ == "__main__":
    unittest.main()
