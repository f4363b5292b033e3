"""The Python module lash against the CLI (same numbers to the last printed digit), its errors,
Ctrl-C, models built in code, the analysis functions. Run by ctest (tests/CMakeLists.txt) with
PYTHONPATH=build/python, LASH_BINARY and LASH_SOURCE_DIR set."""
import csv
import json
import math
import os
import re
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import lash

SOURCE = os.environ.get("LASH_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
LASH = os.environ.get("LASH_BINARY", os.path.join(SOURCE, "build", "lash"))
FLORES = os.path.join(SOURCE, "examples", "flores_slider_crank.yaml")
T_END = 0.006  # s: 1/2 crank revolution at 5000 rpm, with impacts at 0.25 mm clearance
CLEARANCE = 0.25e-3


def cli_run(tmp_path, *sets):
    out = tmp_path / "cli"
    args = [LASH, "run", FLORES, "-o", str(out), "-q"]
    for s in sets:
        args += ["--set", s]
    subprocess.run(args, check=True, capture_output=True)
    return out


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The same model run by `lash run` and by lash.simulate."""
    tmp = tmp_path_factory.mktemp("flores")
    out = cli_run(tmp, f"joints.rod_slider.clearance={CLEARANCE!r}", f"solver.end_time={T_END!r}")
    model = lash.load(FLORES)
    model.set("joints.rod_slider.clearance", CLEARANCE)
    result = lash.simulate(model, t_end=T_END)
    return out, result


def test_timeseries_equals_cli_csv_to_the_last_digit(runs):
    out, result = runs
    with open(out / "timeseries.csv", newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["time"] + result.channels
    assert len(rows) - 1 == len(result.time) == int(round(T_END / 1e-5)) + 1
    # The CSV prints %.9g (std::to_chars general, precision 9): format the arrays the same way.
    table = np.column_stack([result.time, result.values])
    mismatches = [(i, j) for i, row in enumerate(rows[1:]) for j, text in enumerate(row)
                  if text != "%.9g" % table[i, j]]
    assert mismatches == [], f"{len(mismatches)} cells differ, first {mismatches[:3]}"
    assert result["slider.ax"].shape == result.time.shape
    assert np.shares_memory(result["slider.ax"], result.values)  # a view, no copy


def test_events_and_summary_equal_cli(runs):
    out, result = runs
    with open(out / "events.csv", newline="") as f:
        rows = list(csv.reader(f))[1:]
    ev = result.events
    assert len(rows) == len(ev["time"]) > 0
    for row, t, joint, kind, v in zip(rows, ev["time"], ev["joint"], ev["event"], ev["velocity"]):
        assert row == ["%.12g" % t, joint, kind, "%.9g" % v]
    summary = json.loads((out / "summary.json").read_text())
    mine = result.summary
    assert mine["status"]["outcome"] == summary["status"]["outcome"] == "completed"
    for name, peaks in summary["channels"].items():
        for key in ("min", "t_min", "max", "t_max", "peak", "unit", "description"):
            assert mine["channels"][name][key] == peaks[key], (name, key)
    for joint, stats in summary["clearance_joints"].items():
        for key in ("impacts", "separations", "max_impact_velocity", "clearance", "stiffness",
                    "normal_law", "friction_law"):
            assert mine["clearance_joints"][joint][key] == stats[key], (joint, key)
        assert mine["clearance_joints"][joint]["contact_share"] == pytest.approx(
            stats["contact_share"], abs=1e-12)
    for key in ("steps", "rejected_steps", "rhs_evaluations", "events", "projections",
                "missed_events"):
        assert mine["integrator"][key] == summary["integrator"][key], key
    # Every key of summary.json but the files' ("output") and the start, integrator and model
    # blocks alike (projections and the model's counts and resolved text were left out).
    assert set(mine) == set(summary) - {"output", "start"}
    assert set(mine["integrator"]) == set(summary["integrator"])
    for key in ("name", "bodies", "joints", "clearance_joints", "resolved"):
        assert mine["model"][key] == summary["model"][key], key
    state = json.loads((out / "final_state.json").read_text())
    assert result.final_state["names"] == state["names"]
    assert result.final_state["modes"] == {j: bool(m) for j, m in state["modes"].items()}
    # The blocks not computed from the arrays: the solver as run and how the peaks were found.
    assert mine["solver"] == summary["solver"]
    assert mine["peaks"] == summary["peaks"]


def test_model_error_carries_file_line_column_like_the_cli(tmp_path):
    text = open(FLORES).read().replace("clearance: 0.5e-3}", "clearance: -0.5e-3}")
    bad = tmp_path / "bad.yaml"
    bad.write_text(text)
    line = next(i for i, l in enumerate(text.splitlines(), 1) if "clearance: -0.5e-3" in l)
    with pytest.raises(lash.ModelError) as err:
        lash.load(bad)
    assert isinstance(err.value, ValueError)
    message = str(err.value)
    assert f"{bad}:{line}:" in message and "clearance must be >= 0, got -0.0005" in message
    file, l, column, element, what = err.value.diagnostics[0]
    assert (file, l, element) == (str(bad), line, "joint 'rod_slider'") and column > 0
    cli = subprocess.run([LASH, "check", str(bad)], capture_output=True, text=True)
    assert cli.returncode == 2
    for d in err.value.diagnostics:  # the same sentences as `lash check`
        assert f"{d[0]}:{d[1]}:{d[2]}: {d[3]}: {d[4]}" in cli.stderr
    # A loaded file changed through `data` is loaded from that data written again: its lines
    # are those of Model.text(), and the name says so (the file's name with those lines pointed
    # at a comment, or past the file's end).
    edited = lash.load(FLORES)
    edited.data["bodies"]["crank"]["mass"] = -5
    with pytest.raises(lash.ModelError) as err:
        edited.check()
    file, l, column, element, what = err.value.diagnostics[0]
    assert file == f"<{FLORES}, edited: lines of Model.text()>"
    assert "mass: -5" in edited.text().splitlines()[l - 1]


def test_bad_override_and_bad_arguments():
    model = lash.load(FLORES)
    model.set("joints.rod_slidr.clearance", 1e-4)
    with pytest.raises(lash.ModelError, match="did you mean 'rod_slider'"):
        lash.simulate(model, t_end=0.001)
    with pytest.raises(ValueError, match="t_end must be"):
        lash.simulate(lash.load(FLORES), t_end=-1.0)
    with pytest.raises(OSError):
        lash.load("/nonexistent/model.yaml")
    result = lash.simulate(FLORES, t_end=0.0005)
    with pytest.raises(KeyError, match="did you mean 'slider.ax'"):
        result["slider.axx"]


def test_ctrl_c_stops_a_long_run_with_keyboard_interrupt():
    model = lash.load(FLORES)
    timer = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            # About 1 s of wall time per simulated second: 30 s uninterrupted.
            lash.simulate(model, t_end=30.0, output_interval=1e-3)
    finally:
        timer.cancel()
    assert time.monotonic() - start < 5.0


def test_simulate_releases_the_gil():
    counter = [0]
    done = threading.Event()

    def count():
        while not done.is_set():
            counter[0] += 1

    t = threading.Thread(target=count)
    t.start()
    try:
        lash.simulate(FLORES, t_end=0.012)
    finally:
        done.set()
        t.join()
    assert counter[0] > 10000  # the counting thread ran while the engine did


def flores_in_code():
    m = lash.Model.new("flores_slider_crank", gravity=[0, -9.81])
    m.add_ground_marker("O", [0, 0])
    m.add_body("crank", mass=0.30, inertia=1.0e-4, position=[0.025, 0], angle=0,
               markers={"O": [-0.025, 0], "A": [0.025, 0]})
    m.add_body("rod", mass=0.21, inertia=2.5e-4, position=[0.11, 0], angle=0,
               markers={"A": [-0.06, 0], "B": [0.06, 0]})
    m.add_body("slider", mass=0.14, inertia=1.0e-4, position=[0.17, 0], markers={"O": [0, 0]})
    m.set_clearance_defaults(journal_radius=9.5e-3,
                             material={"youngs_modulus": 207e9, "poisson_ratio": 0.3},
                             normal_law="lankarani_nikravesh", restitution=0.9,
                             friction={"law": "none"})
    m.add_joint("crank_pivot", "revolute", journal="crank.O", bearing="ground.O")
    m.add_joint("crank_rod", "revolute", journal="crank.A", bearing="rod.A")
    m.add_clearance_joint("rod_slider", journal="rod.B", bearing="slider.O", clearance=0.5e-3)
    m.add_joint("slider_guide", "translational", guide="ground.O", slider="slider.O", axis=[1, 0])
    m.add_driver("crank", joint="crank_pivot", speed_rpm=5000)
    m.set_solver(integrator="dopri5", rtol=1.0e-8, atol=1.0e-11, end_time=0.024,
                 output_interval=1.0e-5, initial_state="ideal")
    return m


def test_model_built_in_code_runs_like_the_file_and_saves(tmp_path):
    m = flores_in_code()
    path = tmp_path / "built.yaml"
    m.save(str(path))
    again = lash.load(path)
    a = lash.simulate(m, t_end=0.003)
    b = lash.simulate(again, t_end=0.003)
    c = lash.simulate(FLORES, t_end=0.003)
    assert a.channels == c.channels
    assert np.array_equal(a.values, c.values) and np.array_equal(b.values, c.values)
    # A clearance set in code changes the run like --set does.
    m.set("joints.rod_slider.clearance", CLEARANCE)
    d = lash.simulate(m, t_end=0.003)
    e = lash.simulate(FLORES, t_end=0.003, overrides=[f"joints.rod_slider.clearance={CLEARANCE!r}"])
    assert np.array_equal(d.values, e.values) and not np.array_equal(d.values, c.values)
    with pytest.raises(ValueError, match="exists already"):
        m.add_body("rod", mass=1.0, inertia=1.0)


def test_a_model_built_in_code_with_a_mistake_names_the_element():
    m = flores_in_code()
    m.add_joint("extra", "revolute", journal="rod.Q", bearing="ground.O")
    with pytest.raises(lash.ModelError, match="joint 'extra'"):
        m.check()


def test_analysis():
    model = lash.load(FLORES)
    a = lash.analysis.analyze(model, lyapunov=False)
    assert a["period"] == pytest.approx(2 * math.pi / (5000 * 2 * math.pi / 60))
    p = a["poincare"]
    assert p["kind"] == "stroboscopic" and p["points"].shape[1] == 2 and len(p["times"]) >= 1
    assert a["verdict"]["kind"] in {"periodic", "quasi-periodic", "chaotic", "undetermined"}
    assert "slider.ax" in a["spectra"] and a["ideal_twin"] is not None
    assert a["ideal_twin"]["slider.ax"]["peak_ratio"] > 1
    # The ideal twin dissipates nothing (no clearance joint): no ratio (None, not 0).
    dissipated = a["ideal_twin"]["energy.dissipated"]
    assert dissipated["ideal_peak"] == 0 and dissipated["peak_ratio"] is None
    # The model-free functions: a sine of amplitude 3 on bin 8 reads 3 there.
    n, dt = 256, 1e-3
    t = np.arange(n) * dt
    s = lash.analysis.amplitude_spectrum(3.0 * np.sin(2 * np.pi * 8 / (n * dt) * t), dt, "rectangular")
    k = int(np.argmax(s["amplitude"]))
    assert s["frequency"][k] == pytest.approx(8 / (n * dt)) and s["amplitude"][k] == pytest.approx(3.0)
    assert lash.analysis.count_distinct([[0, 0], [1e-9, 0], [1, 1]], 1e-6) == 2
    kind, evidence = lash.analysis.classify_motion(float("nan"), 0.012, 1, 20)
    assert kind == "periodic" and evidence
    # A lightly damped oscillator's points (λT = -0.05): returns shrinking to exp(-0.05 * 22)
    # make the verdict converging ("periodic"); returns that keep their size, quasi-periodic.
    decaying = [[math.exp(-0.05 * i) * math.cos(5.0 * i), math.exp(-0.05 * i) * math.sin(5.0 * i)]
                for i in range(40)]
    c = lash.analysis.section_contraction(decaying)
    assert c == pytest.approx(math.exp(-0.05 * 22), rel=1e-12)
    assert lash.analysis.classify_motion(-0.1, 0.5, 40, 40, 1, 0.0, 0, c)[0] == "periodic"
    assert lash.analysis.classify_motion(-0.1, 0.5, 40, 40, 1, 0.0, 0, 0.9)[0] == "quasi-periodic"
    assert math.isnan(lash.analysis.section_contraction([[0.0, 0.0]] * 5))
    with pytest.raises(ValueError, match="contraction must be a finite ratio"):
        lash.analysis.classify_motion(-0.1, 0.5, 40, 40, 1, 0.0, 0, -1.0)
    with pytest.raises(ValueError, match="window"):
        lash.analysis.amplitude_spectrum(np.ones(8), 1e-3, "hamming")


def test_analysis_functions_refuse_inconsistent_arguments():
    """Lists of unequal length, unsorted times, ragged points and negative tolerances raise
    ValueError naming the arguments, rather than crashing or returning a silent result."""
    A = lash.analysis
    # Two events with no velocity each read past the end of velocities (a crash once): in a
    # child process, so that a crash fails this test and not the whole run.
    child = subprocess.run(
        [sys.executable, "-c",
         "import numpy as np, lash.analysis as A\n"
         "try:\n"
         "    A.contact_modes(np.array([0.1, 0.2]), np.array([True, False]), np.zeros(0),"
         " False, 0, 1, 0.1)\n"
         "except ValueError as e:\n"
         "    print(e)\n"],
        capture_output=True, text=True, env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert child.returncode == 0, child.stderr
    assert "times 2, onset 2, velocities 0" in child.stdout
    with pytest.raises(ValueError, match="times, onset and velocities .*times 3, onset 1"):
        A.contact_modes([0.1, 0.2, 0.3], [True], [1.0, 0.0, 1.0], False, 0, 1, 0.1)
    with pytest.raises(ValueError, match=r"times must be non-decreasing, got times\[1\] = 0.1 after"):
        A.contact_modes([0.2, 0.1], [True, False], [1.0, 0.0], False, 0, 1, 0.01)
    with pytest.raises(ValueError, match="t0 <= t1"):
        A.contact_modes([], [], [], False, 1, 0, 0.01)
    with pytest.raises(ValueError, match="continuous_time must be a finite time >= 0"):
        A.contact_modes([], [], [], False, 0, 1, -0.01)
    modes = A.contact_modes([0.1, 0.2, 0.5, 0.51], [True, False, True, False], [2.0, 0, 3.0, 0],
                            False, 0, 1, 0.05)
    assert modes["episodes"] == [(0.1, 0.2, True), (0.5, 0.51, False)] and modes["impacts"] == 2
    assert modes["continuous_share"] == pytest.approx(0.1)
    assert modes["impact_share"] == pytest.approx(0.01)

    with pytest.raises(ValueError, match="t and v must have the same length, got t 3, v 2"):
        A.decimate_min_max([0, 1, 2], [0, 1], 1)
    with pytest.raises(ValueError, match="buckets must be >= 0"):
        A.decimate_min_max([0, 1], [0, 1], -1)
    t, v = A.decimate_min_max(np.arange(100.0), np.sin(np.arange(100.0)), 10)
    assert len(t) == len(v) <= 20
    with pytest.raises(ValueError, match=r"points\[0\] with 2 and points\[1\] with 1"):
        A.count_distinct([[1, 2], [1]], 0.1)
    with pytest.raises(ValueError, match="tol must be a distance >= 0, got -1"):
        A.count_distinct([[1, 2], [1, 2]], -1)
    with pytest.raises(ValueError, match="0 <= distinct <= sections"):
        A.classify_motion(float("nan"), 0.012, 5, 2)
    with pytest.raises(ValueError, match=r"x: expected a 1-D sequence.*\(2, 4\)"):
        A.amplitude_spectrum(np.ones((2, 4)), 1e-3)
    # A NaN made every amplitude NaN, with no word.
    with pytest.raises(ValueError, match=r"^x: expected finite numbers, got nan at index 3 \(and 1 more\)$"):
        A.amplitude_spectrum([0, 1, 0, math.nan, 0, -1, math.inf, 1], 1e-3)


def test_overrides_may_be_one_string():
    """A single "path=value" string is one override, not a list of its characters."""
    a = lash.simulate(FLORES, t_end=0.0005, overrides="solver.rtol=1e-6")
    b = lash.simulate(FLORES, t_end=0.0005, overrides=["solver.rtol=1e-6"])
    assert a.ok and np.array_equal(a.values, b.values)
    assert a.model.overrides == []  # simulate does not change the model
    assert lash.load(FLORES, overrides="solver.rtol=1e-6").overrides == ["solver.rtol=1e-6"]
    assert lash.Model(overrides="solver.rtol=1e-6").overrides == ["solver.rtol=1e-6"]
    with pytest.raises(TypeError, match="KEY.PATH=VALUE"):
        lash.simulate(FLORES, t_end=0.0005, overrides=[1e-6])
    with pytest.raises(TypeError, match="list of"):
        lash.simulate(FLORES, t_end=0.0005, overrides=3)
    # A keyword and an override setting one value: refused (the keyword won unseen, and the
    # override's "abc" was never checked).
    with pytest.raises(ValueError, match=r"^t_end sets solver.end_time, and so does the override "
                                         r"'solver.end_time=abc': give one of them$"):
        lash.simulate(FLORES, t_end=0.0005, overrides=["solver.end_time=abc"])
    with pytest.raises(ValueError, match=r"^integrator sets solver.integrator"):
        lash.simulate(FLORES, t_end=0.0005, integrator="bdf", overrides="solver.integrator=dopri5")


def test_messages_name_what_was_passed(tmp_path):
    m = lash.Model.new("x")
    m.add_body("b", mass=1.0, inertia=1.0)
    with pytest.raises(ValueError, match="^body 'b' exists already$"):
        m.add_body("b", mass=1.0, inertia=1.0)
    m.add_driver("d", joint="j", speed_rpm=1)
    with pytest.raises(ValueError, match="^driver 'd' exists already$"):
        m.add_driver("d", joint="j", speed_rpm=1)
    # A model built in code with no solver settings runs for t_end (it was "no 'solver' in
    # the model"); without t_end it says what it lacks.
    bob = lash.Model.new("bob", gravity=[0, -9.81]).add_ground_marker("O", [0, 0])
    bob.add_body("bob", mass=1, inertia=1e-6, position=[0.1, -1], markers={"P": [-0.1, 1]})
    bob.add_joint("piv", journal="bob.P", bearing="ground.O")
    assert lash.simulate(bob, 0.01).time[-1] == pytest.approx(0.01)
    with pytest.raises(lash.ModelError, match="missing required key 'end_time'"):
        lash.simulate(bob, output_interval=1e-3)
    # t_end is a keyword argument, not a --set option.
    with pytest.raises(lash.ModelError) as err:
        lash.simulate(bob, 0.01, overrides="solver.bad.key=1")
    assert str(err.value) == "override solver.bad.key: no 'solver.bad' in the model\n"
    with pytest.raises(lash.ModelError) as err:
        lash.simulate(FLORES, 0.01, output_interval=0.02)
    assert str(err.value).endswith("output_interval must be <= end_time, got 0.02 > 0.01 (values "
                                   "of the argument t_end and the argument output_interval)\n")
    with pytest.raises(lash.ModelError, match=r"unknown integrator 'rk4'.*\(value of the argument "
                       r"integrator\)\n$"):
        lash.simulate(FLORES, t_end=0.0005, integrator="rk4")
    # The caller's own override string keeps its name: an override, not the CLI's --set.
    # A map or a list set in code reaches the model as one (a map was read as a string).
    m = lash.load(FLORES).set("joints.rod_slider.friction", {"law": "coulomb", "mu": 0.1})
    assert "law: coulomb" in m.resolved_yaml()
    m.set("bodies.slider.position", np.array([0.2, 0.0]))
    assert lash.simulate(m, t_end=1e-4).ok
    # NumPy values in a model's data (a TypeError from the YAML writer before).
    data = lash.load(FLORES).data
    data["gravity"] = np.array([0.0, -9.81])
    data["bodies"]["slider"]["mass"] = np.float64(data["bodies"]["slider"]["mass"])
    built = lash.Model(data=data)
    assert "gravity: [0.0, -9.81]" in built.text(), built.text()
    assert lash.simulate(built, t_end=1e-4).ok
    # A value refused for what a keyword argument made of it names that argument (it was
    # "set by an override"), here the output count that output_interval gives.
    with pytest.raises(lash.ModelError, match=r"more than max_outputs.*\(value of the argument "
                       r"output_interval\)\n$"):
        lash.simulate(FLORES, output_interval=1e-12)
    # Not text at all: a TypeError, as for load (a ModelError "got nothing" before).
    with pytest.raises(TypeError, match="^text: expected the text of a model file"):
        lash.loads(None)
    # So do the values Model.set and load's overrides change.
    bad = lash.load(FLORES).set("joints.rod_slider.clearance", -1)
    with pytest.raises(lash.ModelError) as err:
        bad.check()
    assert str(err.value).endswith("joint 'rod_slider': clearance must be >= 0, got -1 "
                                   "(value set by an override)\n"), str(err.value)
    assert "--set" not in str(err.value)
    with pytest.raises(lash.ModelError, match="^override joints.rod_slidr.clearance: no "
                       "'joints.rod_slidr' in the model, did you mean 'rod_slider'"):
        lash.load(FLORES, overrides="joints.rod_slidr.clearance=1")
    with pytest.raises(lash.ModelError, match="^override: expected KEY.PATH=VALUE, got 'x'"):
        lash.load(FLORES, overrides="x")
    result = lash.simulate(FLORES, t_end=0.0005)
    with pytest.raises(TypeError, match="channel name such as 'crank.x', got 0 \\(int\\)"):
        result[0]
    with pytest.raises(TypeError, match="path: expected a dotted path string.*got NoneType"):
        lash.load(FLORES).set(None, 1)
    with pytest.raises(TypeError, match="jobs: expected a number of threads"):
        lash.sweep(FLORES, tmp_path / "out", jobs="2")
    missing = tmp_path / "missing.yaml"
    with pytest.raises(FileNotFoundError) as err:
        lash.sweep(missing, tmp_path / "out")
    assert str(missing) in str(err.value)
    assert not (tmp_path / "out").exists()


def test_to_pandas(runs):
    pd = pytest.importorskip("pandas")
    _, result = runs
    df = result.to_pandas()
    assert list(df.columns) == result.channels and df.index.name == "time"
    assert np.array_equal(df["slider.ax"].to_numpy(), result["slider.ax"])
    # An ordinary frame: edited in place (it raised "assignment destination is read-only"), the
    # result's own arrays unchanged.
    df.loc[df.index[0], "slider.ax"] = 1.0
    df["slider.x"] *= 2
    assert df["slider.ax"].iloc[0] == 1.0 and result["slider.ax"][0] != 1.0


def test_models_and_results_pickle(runs):
    import pickle
    _, result = runs
    model = lash.load(FLORES).set("joints.rod_slider.clearance", CLEARANCE)
    model.check()  # a compiled model cached: dropped when pickled, loaded again after
    again = pickle.loads(pickle.dumps(model))
    assert again.overrides == model.overrides and again.channels == model.channels
    back = pickle.loads(pickle.dumps(result))
    assert np.array_equal(back.values, result.values) and back.channels == result.channels
    assert back.summary == result.summary
    assert not back.values.flags.writeable and not back["slider.ax"].flags.writeable
    assert lash.analysis.spectrum(back, "slider.ax")["frequency"].size > 0


def test_builders_check_their_arguments():
    m = lash.Model.new("m")
    m.add_ground_marker("O", [0, 0])
    with pytest.raises(ValueError, match="^ground marker 'O' exists already$"):
        m.add_ground_marker("O", [5, 5])
    for kwargs, message in [({"position": None}, r"^position: expected a point \[x, y\] \(m\), got None"),
                            ({"markers": {"A": None}}, r"^marker 'A': expected a point"),
                            ({"markers": {"A": 0.1}}, r"^marker 'A': expected a point"),
                            ({"markers": [("A", [0, 0])]}, r"^markers: expected a dict of marker name"),
                            # Text for a number was written into the model unquoted, as a number.
                            ({"mass": "1"}, r"^mass: expected a number \(kg\), got '1' \(str\)"),
                            ({"inertia": "0.1"}, r"^inertia: expected a number"),
                            ({"angle": True}, r"^angle: expected a number \(rad\), got True")]:
        with pytest.raises(TypeError, match=message):
            m.add_body("b", **{"mass": 1.0, **kwargs})
    # None in the settings' sections removes the key: its default (an empty value in a model
    # file is an error).
    m.set_solver(end_time=1.0, rtol=1e-6)
    m.set_solver(rtol=None)
    assert m.data["solver"] == {"end_time": 1.0}
    m.set_clearance_defaults(restitution=0.5, friction=None)
    assert m.data["clearance_defaults"] == {"restitution": 0.5}
    with pytest.raises(TypeError, match=r"^clearance: expected a number \(m\), got None"):
        m.add_clearance_joint("pin", journal="b.O", bearing="ground.O", clearance=None)
    with pytest.raises(TypeError, match=r"^name: expected the model's name"):
        lash.Model.new(None)
    # NumPy floats narrower than a double are the decimals they print as, everywhere.
    m.add_body("c", mass=np.float32(0.3), position=np.array([0.1, 0.2], dtype=np.float32))
    assert "mass: 0.3\n" in m.text() or "mass: 0.3," in m.text() or "mass: 0.3}" in m.text(), m.text()
    assert "[0.1, 0.2]" in m.text(), m.text()
    f = lash.load(FLORES).set("joints.rod_slider.clearance", np.float32(2.5e-4))
    assert f.overrides[-1] == "joints.rod_slider.clearance=0.00025"
    g = lash.Model.new("g", gravity=np.array([0, -9.81], dtype=np.float32))
    assert "-9.81]" in g.text()
    # 0-d arrays are their scalars, and any mapping holds markers (both refused for a while).
    import types
    z = lash.Model.new("z").add_body("b", mass=np.array(1.0), inertia=1.0, position=[0, 0],
                                     markers=types.MappingProxyType({"A": [0.1, 0]}))
    z.add_clearance_joint("pin", journal="b.A", bearing="ground.O", clearance=np.array(5e-4))
    assert "mass: 1" in z.text() and "clearance: 0.0005" in z.text(), z.text()
    f.data["bodies"]["slider"]["inertia"] = np.array(2e-4)
    assert "2e-4" in f.text().lower() or "0.0002" in f.text()


def test_messages_name_only_what_the_message_is_about():
    # An unknown solver key lists every key; the arguments setting two of them are not its cause.
    m = lash.load(FLORES).set("solver.foo", 1)
    with pytest.raises(lash.ModelError) as e:
        lash.simulate(m, t_end=0.003, output_interval=1e-4)
    assert str(e.value).rstrip().endswith("(value of the override solver.foo)"), str(e.value)
    b = lash.Model.new("m").add_body("a", mass=1.0).set_solver(end_time=0.01, foo=1)
    with pytest.raises(lash.ModelError) as e:
        lash.simulate(b, t_end=0.003)
    assert "argument t_end" not in str(e.value), str(e.value)
    with pytest.raises(ValueError, match=r"^t_end: 10000.* is beyond the largest number"):
        lash.simulate(FLORES, t_end=10**400)
    with pytest.raises(TypeError, match=r"^spectrum: expected a lash.Result"):
        lash.analysis.spectrum(lash.load(FLORES), "slider.ax")


def test_analysis_functions_refuse_non_finite_times():
    x = np.sin(np.arange(64) * 0.3)
    for dt in (float("inf"), 1e-320):
        with pytest.raises(ValueError, match="sample interval dt > 0, finite"):
            lash.analysis.amplitude_spectrum(x, dt)
    with pytest.raises(ValueError, match="lyapunov must be a finite exponent"):
        lash.analysis.classify_motion(float("inf"), 0.01, 100, 100)
    with pytest.raises(ValueError, match="period: expected a finite period"):
        lash.analysis.classify_motion(0.0, float("inf"), 1, 4)
    with pytest.raises(ValueError, match="t0 and t1 must be finite"):
        lash.analysis.contact_modes([0.1, 0.2], [True, False], [1.0, -1.0], False, 0.0,
                                    float("inf"), 0.01)


def test_an_empty_poincare_section_has_a_column_per_variable():
    # Five periods discarded of a run of one: no section point, and still (0, 2) as (n, 2k) says.
    m = lash.load(FLORES).set("solver.end_time", 0.012)
    p = lash.analysis.poincare(m, discard_periods=5)
    assert p["points"].shape == (0, len(p["coordinates"])) == (0, 2)
    assert p["coordinates"] == ["rod_slider.ex", "rod_slider.ey"]


def test_every_public_function_has_a_docstring():
    import inspect
    for mod in (lash, lash.analysis):
        for name in mod.__all__:
            obj = getattr(mod, name)
            if inspect.isfunction(obj) or inspect.isclass(obj):
                assert obj.__doc__ and len(obj.__doc__) > 40, name
    assert "KeyboardInterrupt" in lash.simulate.__doc__
    stub = os.path.join(os.path.dirname(lash.__file__), "__init__.pyi")
    assert os.path.exists(stub)


def test_sweep_from_python_equals_the_cli(tmp_path):
    """lash.sweep runs a study file like `lash sweep` and gives the same table; a second call
    without resume is refused, with resume it runs nothing new."""
    study = tmp_path / "study.yaml"
    study.write_text(
        f"study: py\nmodel: {FLORES}\n"
        "set: {solver.end_time: 0.03}\n"
        "parameters:\n  joints.rod_slider.clearance: {values: [2.0e-4, 3.0e-4, -1.0e-4]}\n"
        "transient: {periods: 1}\nkeep: {sections: [rod_slider.ex]}\n")
    s = lash.sweep(study, tmp_path / "py", jobs=2)
    assert len(s) == 3
    assert list(s["status"]) == ["completed", "completed", "error"]
    assert s.parameters == ["joints.rod_slider.clearance"]
    np.testing.assert_array_equal(s["joints.rod_slider.clearance"], [2e-4, 3e-4, -1e-4])
    assert s["rod_slider.Fn.peak"][0] > 0 and math.isnan(s["rod_slider.Fn.peak"][2])
    assert set(s.sections["rod_slider.ex"]["run"]) == {0, 1}
    subprocess.run([LASH, "sweep", str(study), "-q", "-o", str(tmp_path / "cli")], check=True)
    c = lash.read_study(tmp_path / "cli")
    keep = lambda rows: [{k: v for k, v in r.items() if k != "wall_seconds"} for r in rows]
    assert keep(c.rows) == keep(s.rows)
    with pytest.raises(ValueError, match="pass resume=True"):
        lash.sweep(study, tmp_path / "py")
    assert len(lash.sweep(study, tmp_path / "py", resume=True, jobs=None)) == 3  # None: every core
    with pytest.raises(TypeError, match=r"takes a column name \(str\), got 1 \(int\); one run's "
                       r"values are study.rows\[i\]"):
        s[1]  # was KeyError "1: no run has it"
    bad = tmp_path / "bad.yaml"
    bad.write_text(f"study: bad\nmodel: {FLORES}\nparameters: {{drivers.crank.speed_rpm: {{vals: [1]}}}}\n")
    with pytest.raises(lash.ModelError, match="bad.yaml:3"):
        lash.sweep(bad, tmp_path / "bad")


def test_sweep_takes_paths_that_are_not_utf8(tmp_path):
    """Bytes paths that are not UTF-8 (Latin-1 é, 0xE9) reach the engine as bytes (pybind11 could
    not pass the surrogate-escaped str: TypeError), and a message naming one shows its byte as
    \\xE9 (it raised UnicodeDecodeError instead of the ModelError)."""
    base = os.fsencode(tmp_path)
    study = base + b"/st_\xe9.yaml"
    with open(study, "w") as f:
        f.write(f"study: latin1\nmodel: {FLORES}\nset: {{solver.end_time: 0.03}}\n"
                "transient: {periods: 1}\nparameters:\n  joints.rod_slider.clearance: {values: [2.0e-4, -1.0e-4]}\n")
    s = lash.sweep(study, base + b"/out_\xff", jobs=1)
    assert list(s["status"]) == ["completed", "error"]
    assert list(lash.read_study(base + b"/out_\xff")["status"]) == ["completed", "error"]
    assert "st_\\xe9.yaml:6:3: joint 'rod_slider': clearance must be >= 0" in s.rows[1]["message"]
    bad = base + b"/bad_\xe9.yaml"
    with open(bad, "w") as f:
        f.write("study: bad\nmodel: nothere.yaml\nparameters:\n  a: {values: [1]}\n")
    with pytest.raises(lash.ModelError, match=r"bad_\\xe9.yaml:2:8: model: .*nothere.yaml: cannot open") as e:
        lash.sweep(bad, base + b"/bad", jobs=1)
    assert e.value.diagnostics[0][0].endswith("bad_\\xe9.yaml")


def python_in_child(code, timeout=60):
    """Runs `code` in a child interpreter with lash importable, its address space limited to 2 GB
    (so that reading /dev/zero whole ends in MemoryError, not in the OOM killer); returns the
    CompletedProcess, or None when it did not end within `timeout` s."""
    import resource

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    try:
        return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              timeout=timeout, preexec_fn=limit, env=env)
    except subprocess.TimeoutExpired:
        return None


def test_load_refuses_what_lash_check_refuses_before_reading(tmp_path):
    """A device, a FIFO, a folder and a file over 16 MiB: ModelError with `lash check`'s words,
    before anything is read (no hang on the FIFO, no memory exhausted on /dev/zero)."""
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    big = tmp_path / "big.yaml"
    with open(big, "wb") as f:  # sparse: 17 MiB by its size, nothing written
        f.truncate(17 << 20)
    for path in ["/dev/zero", str(fifo), str(big)]:
        cli = subprocess.run([LASH, "check", path], capture_output=True, text=True)
        assert cli.returncode == 2, cli.stderr
        for call in ("lash.load(p)", "lash.simulate(p)", "lash.analysis.spectra(p)"):
            code = (f"import lash\np = {path!r}\ntry:\n    {call}\n"
                    "except lash.ModelError as e:\n    print(e, end='')\n"
                    "    print(repr(e.diagnostics))\n")
            child = python_in_child(code)
            assert child is not None, f"{call} on {path}: no answer within 60 s"
            assert child.returncode == 0, f"{call} on {path}: {child.stderr[-2000:]}"
            message, diagnostics = child.stdout.splitlines()
            assert message in cli.stderr.splitlines(), (message, cli.stderr)
            assert "cannot read the model file: " in message
            assert eval(diagnostics)[0][:4] == (path, 0, 0, "")
    assert "not a regular file (expected a text file)" in str(
        pytest.raises(lash.ModelError, lash.load, "/dev/zero").value)
    # A folder (which the CLI's argument parser refuses before the loader sees it).
    assert str(pytest.raises(lash.ModelError, lash.load, tmp_path).value) == (
        f"{tmp_path}: cannot read the model file: not a regular file (expected a text file)\n")
    assert f"{17 << 20} bytes, more than the {16 << 20} bytes" in str(
        pytest.raises(lash.ModelError, lash.load, big).value)
    with pytest.raises(FileNotFoundError, match="missing.yaml"):
        lash.load(tmp_path / "missing.yaml")
    # Not UTF-8 inside: the loader's message with line and column, as `lash check`.
    latin = tmp_path / "latin.yaml"
    latin.write_bytes(b"name: mod\xe9le\n")
    with pytest.raises(lash.ModelError, match=r"latin.yaml:1:10: not UTF-8 text \(byte 0xE9\)"):
        lash.load(latin)


def test_a_file_name_that_is_not_utf8_loads_as_with_the_cli(tmp_path):
    """A name with a Latin-1 byte is a valid file name: it loads from str (os.fsdecode's surrogate
    escapes), bytes and pathlib, and messages name the file with the byte as \\xe9."""
    raw = os.fsencode(tmp_path) + b"/mod\xe9le.yaml"
    name = os.fsdecode(raw)
    with open(FLORES, "rb") as f, open(raw, "wb") as g:
        g.write(f.read())
    assert subprocess.run([LASH, "check", raw], capture_output=True).returncode == 0
    for path in (name, raw, tmp_path / os.fsdecode(b"mod\xe9le.yaml")):
        model = lash.load(path)
        assert model.name == "flores_slider_crank" and model.filename == name
    assert lash.simulate(name, t_end=0.0005).ok
    shown = f"{tmp_path}/mod\\xe9le.yaml"
    with pytest.raises(lash.ModelError) as err:
        lash.load(name, overrides="joints.rod_slider.clearance=-1")
    assert str(err.value).startswith(f"{shown}:"), str(err.value)
    assert len(str(err.value)) < 500 and "Flores slider-crank" not in str(err.value)
    assert err.value.diagnostics[0][0] == shown
    with pytest.raises(lash.ModelError, match=r"^<mod\\xe9le>:1:1: solver: missing"):
        lash.loads("name: x\nbodies: {b: {mass: 1}}\n", filename=os.fsdecode(b"<mod\xe9le>"))


def test_simulate_takes_numpy_numbers_for_times():
    """t_end and output_interval: any real number, NumPy's included; a float32 is the decimal it
    prints as. A bool, a str or a list is a TypeError naming the argument."""
    for t_end in (np.float32(0.002), np.float64(0.002), np.arange(1, 3)[0] * 0.002):
        result = lash.simulate(FLORES, t_end=t_end, output_interval=np.float32(5e-4))
        assert result.ok and result.time[-1] == 0.002 and len(result) == 5, (t_end, result.time)
    assert lash.simulate(FLORES, t_end=np.arange(1, 3)[0] * 5e-4).time[-1] == 5e-4  # np.int64
    for bad, kind in (("abc", "str"), ([1], "list"), (True, "bool")):
        with pytest.raises(TypeError, match=rf"^t_end: expected a number \(s\), got .* \({kind}\)$"):
            lash.simulate(FLORES, t_end=bad)
        with pytest.raises(TypeError, match=rf"^output_interval: expected a number \(s\), got .*{kind}"):
            lash.simulate(FLORES, t_end=0.001, output_interval=bad)
    with pytest.raises(ValueError, match=r"^t_end must be a finite time > 0 s, got -1.0$"):
        lash.simulate(FLORES, t_end=np.int64(-1))


def test_analysis_options_are_checked_and_named_as_python_arguments():
    """Wrong types: TypeError naming the keyword, before anything runs; values out of range or
    naming what does not exist: ValueError naming the keyword (not the CLI's --option); a single
    string is one channel or plane, not its characters."""
    A = lash.analysis
    model = lash.load(FLORES).set("solver.end_time", 0.012)
    type_errors = [
        (lambda: A.analyze(model, discard_periods=2.5), r"^discard_periods: expected a whole number of periods, got 2.5 \(float\)$"),
        (lambda: A.analyze(model, discard_periods="3"), r"^discard_periods: .* got '3' \(str\)$"),
        (lambda: A.analyze(model, lyapunov_d0="1e-7"), r"^lyapunov_d0: expected a separation \(m\), got '1e-7' \(str\)$"),
        (lambda: A.analyze(model, ideal_twin=1), r"^ideal_twin: expected True or False, got 1 \(int\)$"),
        (lambda: A.analyze(model, fft_channels=[1]), r"^fft_channels: expected channel names"),
        (lambda: A.analyze(model, stats_window=3), r"^stats_window: expected a pair of times"),
        (lambda: A.poincare(model, driver=3), r"^driver: expected a driver name"),
        (lambda: A.poincare(model, planes=None), r"^planes: expected a list of section planes"),
        (lambda: A.spectra(model, channels=5), r"^channels: expected a list of channel names"),
        (lambda: A.amplitude_spectrum(np.ones(8), 0.1, window=None), r"^window: expected \"hann\" or \"rectangular\", got None \(NoneType\)$"),
        (lambda: A.amplitude_spectrum("abc", 0.1), r"^x: expected a 1-D sequence of numbers, got 'abc' \(str\)$"),
        (lambda: A.amplitude_spectrum(np.ones(8), "0.1"), r"^dt: expected a time step \(s\)"),
        (lambda: A.count_distinct(5, 0.1), r"^points: expected a sequence of points"),
        (lambda: A.count_distinct([[1, 2]], None), r"^tol: expected a distance, got None"),
        (lambda: A.decimate_min_max([0, 1], [0, 1], 2.5), r"^buckets: expected a number of buckets"),
        (lambda: A.classify_motion(0.0, 0.01, "1", 4), r"^distinct: expected a whole number"),
        (lambda: A.contact_modes([], [], [], "no", 0, 1, 0), r"^in_contact_at_t0: expected True or False"),
        (lambda: lash.loads(5), r"^text: expected the text of a model file \(str\), got 5 \(int\)$"),
        (lambda: lash.Model.new("m", gravity=5), r"^gravity: expected a pair of numbers \[x, y\] \(m/s\^2\), got 5 \(int\)$"),
        (lambda: lash.Model.new("m", gravity="0 -9.81"), r"^gravity: expected a pair of numbers"),
        (lambda: lash.loads("x: 1", filename=3), r"^filename: expected a file name"),
    ]
    for call, message in type_errors:
        with pytest.raises(TypeError, match=message) as err:
            call()
        assert len(str(err.value)) < 200, str(err.value)
    value_errors = [
        (lambda: A.poincare(model, discard_periods=10**12), r"^discard_periods=1000000000000: expected a whole number of periods in \[0, 1e6\]$"),
        (lambda: A.analyze(model, discard_periods=-1), r"^discard_periods=-1: expected"),
        (lambda: A.analyze(model, fft_channels=["slider.axx"]), r"^fft_channels: 'slider.axx': no such channel$"),
        (lambda: A.spectra(model, channels="slider.axx"), r"^channels: 'slider.axx': no such channel$"),
        (lambda: A.analyze(model, lyapunov_d0=1.0), r"^lyapunov_d0=1.0: expected a separation"),
        (lambda: A.analyze(model, lyapunov_method="qr"), r"^lyapunov_method='qr': expected variational"),
        (lambda: A.analyze(model, stats_window=(0.5, 0.1)), r"^stats_window=\(0.5, 0.1\): T0 must be less than T1$"),
        (lambda: A.poincare(model, driver="crankk"), r"^driver='crankk': no revolute driver"),
        (lambda: A.poincare(model, planes="slider.vq=0"), r"^planes: section plane 'slider.vq=0'"),
        # Two planes were pooled into one map (a period-1 orbit read as period-2).
        (lambda: A.poincare(model, planes=["slider.x=0.1", "slider.x=0.12"]), r"^planes: one section plane per analysis \(2 given\)"),
        (lambda: A.count_distinct([1, 2, 3], 0.1), r"^points\[0\]: expected a 1-D sequence"),
        (lambda: A.count_distinct(np.zeros((2, 2, 2)), 0.1), r"^points\[0\]: expected a 1-D sequence of numbers, got an array of shape \(2, 2\)$"),
        (lambda: A.classify_motion(0.0, 0.01, 2**40, 4), r"^distinct: expected a whole number between"),
        (lambda: A.classify_motion(0.0, -0.01, 1, 4), r"^period: expected a finite period \(s\) > 0, or 0 or NaN for none, got -0.01$"),
    ]
    for call, message in value_errors:
        with pytest.raises(ValueError, match=message):
            call()
    # One string: one channel, one plane.
    assert list(A.spectra(model, channels="slider.ax", discard_periods=0)) == ["slider.ax"]
    assert list(A.spectra(model, ["slider.ax"], np.int64(0))) == ["slider.ax"]
    assert A.poincare(model, planes="slider.vx=0")["planes"] == ["slider.vx=0"]
    assert A.classify_motion(np.float64("nan"), np.float32(0.012), np.int64(1), np.int32(4))[0]


def test_a_result_is_analysed_as_it_ran_and_its_arrays_are_read_only():
    # analyze(result) ran the caller's Model again with only t_end and output_interval: another
    # integrator and clearance (simulate's arguments, a Model.set made after the run) slipped in.
    model = lash.load(FLORES)
    result = lash.simulate(model, 0.003, integrator="bdf",
                           overrides=["joints.rod_slider.clearance=0.0004"])
    model.set("joints.rod_slider.clearance", 3e-4)  # after the run: not part of it
    assert result.summary["model"]["overrides"] == [
        "joints.rod_slider.clearance=0.0004", "solver.end_time=0.003", "solver.integrator=bdf"]
    a = lash.analysis.analyze(result, ideal_twin=False, lyapunov=False)
    assert a["result"]["integrator"]["name"] == "bdf"
    assert a["clearance_joints"]["rod_slider"]["clearance"] == pytest.approx(4e-4, rel=1e-12)
    assert a["result"]["status"]["time"] == pytest.approx(0.003)
    # A write through a view changed every view and the summary computed from them.
    for array in (result.time, result.values, result["slider.ax"], result.events["joint"]):
        with pytest.raises(ValueError, match="read-only"):
            array[...] = 0
    assert result.to_pandas().shape == (len(result.time), len(result.channels))


def test_model_data_keeps_names_that_look_like_numbers_and_edits_in_place_count():
    # "007" read as the number 7 made a driver's joint '7', unknown; an edit through a kept
    # `data` dict after a check was ignored (the cached model was reused).
    with open(FLORES, encoding="utf-8") as f:
        text = f.read().replace("crank_pivot", "007")
    model = lash.loads(text)
    data = model.data
    assert data["drivers"]["crank"]["joint"] == "007"
    assert isinstance(data["solver"]["rtol"], float) and data["solver"]["rtol"] == 1e-8
    model.check()
    data["solver"]["end_time"] = 0.002
    result = lash.simulate(model)
    assert result.status["time"] == pytest.approx(0.002)
    data["description"] = 99999999999999999999  # a whole number of any size, never clamped
    assert lash.loads(lash._lash.emit_yaml(data)).data["description"] == 99999999999999999999


def test_copies_are_independent_and_keys_are_names():
    import copy
    model = lash.load(FLORES)
    for twin in (copy.copy(model), model.copy(), copy.deepcopy(model)):
        twin.set("joints.rod_slider.clearance", 1e-4)  # copy.copy shared the overrides list
        assert model.overrides == [] and len(twin.overrides) == 1
        assert twin.text() == model.text()
    built = lash.Model.new("m")
    twin = copy.copy(built)
    twin.add_body("b", mass=1.0)
    assert "b" not in built.data["bodies"]
    # Keys that are not names were written as "~" or "[1, 2]" into the model's text.
    for key in (None, (1, 2), 3):
        bad = lash.Model.new("m")
        bad.data["bodies"][key] = {"mass": 1.0}
        with pytest.raises(TypeError, match=r"a model's keys are names \(str\), got"):
            bad.text()
    # Text and data together: the data was dropped without a word.
    with pytest.raises(ValueError, match="text or its data, not both"):
        lash.Model("name: m\n", data={"name": "n"})


def test_a_daemon_thread_still_simulating_at_exit_does_not_abort():
    # The waiting thread took the GIL every 50 ms to check for signals; at interpreter exit a
    # daemon thread is ended there, destroying a running std::thread: terminate, SIGABRT.
    code = ("import lash, threading, time\n"
            f"m = lash.load({FLORES!r})\n"
            "threading.Thread(target=lambda: lash.simulate(m, 0.5), daemon=True).start()\n"
            "time.sleep(0.2)\n")
    for _ in range(3):
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              timeout=120)
        assert done.returncode == 0, done.stderr


def test_arguments_are_named_in_what_they_cause(tmp_path):
    # A file's value refused against one an argument set named only the file's line.
    with pytest.raises(lash.ModelError, match=r"output_interval must be <= end_time.*"
                       r"\(end_time from the argument t_end\)\n$"):
        lash.simulate(FLORES, t_end=1e-9)
    # An override's bad value beside t_end blamed t_end alone.
    with pytest.raises(lash.ModelError, match=r"more than max_outputs.*\(values of the argument "
                       r"t_end and the override solver.output_interval\)\n$"):
        lash.simulate(FLORES, t_end=0.002, overrides=["solver.output_interval=1e-300"])
    # A lone surrogate: pybind11's "incompatible function arguments" and the whole text before.
    with pytest.raises(ValueError, match=r"^override 'name=caf\\udce9': not valid UTF-8 text"):
        lash.load(FLORES).set("name", "caf\udce9").check()
    with pytest.raises(TypeError, match="^path: expected a file name"):
        lash.load(FLORES).save(1)  # an int is a file descriptor to open(): stdout was closed
    with pytest.raises(TypeError, match=r"^onset: expected booleans"):
        lash.analysis.contact_modes([0.1, 0.2], ["separation", "separation"], [1.0, 1.0],
                                    False, 0.0, 1.0, 0.05)
    for bad in (-1.0, float("nan")):
        with pytest.raises(ValueError, match=r"^continuous_contact_time=.*expected a time >= 0"):
            lash.analysis.analyze(FLORES, continuous_contact_time=bad)
    with pytest.raises(ValueError, match=r"^jobs=1099511627776: expected"):
        lash.sweep(FLORES, tmp_path / "o", jobs=2**40)
    with pytest.raises(TypeError, match=r"^resume: expected True or False"):
        lash.sweep(FLORES, tmp_path / "o", resume="yes")
    # Aliases that expand without bound ("billion laughs" in a description).
    bomb = "description:\n" + "\n".join(
        ["  - &a0 [1, 1, 1, 1, 1, 1, 1, 1, 1]"] +
        [f"  - &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]" for i in range(1, 9)]) + "\n"
    with open(FLORES, encoding="utf-8") as f:
        model = lash.loads(bomb + f.read())
    with pytest.raises(ValueError, match="more than 10000000 values once its YAML aliases"):
        model.data
    # Not YAML: a ModelError at the file's line and column (yaml-cpp's RuntimeError before).
    with pytest.raises(lash.ModelError, match=r"^x.yaml:2:2: not valid YAML: end of sequence"):
        lash.Model("a: [1, 2\nb: 3\n", filename="x.yaml").data
    # A duplicate key: refused with both places, as lash.loads does (the parser kept the last).
    with pytest.raises(lash.ModelError, match=r"^x.yaml:2:1: duplicate key 'a' \(first at line 1"):
        lash.Model("a: 1\na: 2\n", filename="x.yaml").data
    # A channel's name in another case: that channel is the hint ("slider.y" before).
    with pytest.raises(KeyError, match="did you mean 'slider.ax'"):
        lash.simulate(FLORES, 1e-4)["slider.AX"]


def test_the_spectrum_of_a_result_leaves_out_an_output_off_the_grid():
    # end_time 0.01005 with outputs every 1e-3 s: the last output, 5e-5 s after the one before,
    # was taken as one more 1e-3 s sample.
    result = lash.simulate(FLORES, 0.01005, output_interval=1e-3)
    assert result.time[-1] - result.time[-2] == pytest.approx(5e-5)
    s = lash.analysis.spectrum(result, "slider.ax")
    on_grid = lash.analysis.amplitude_spectrum(result["slider.ax"][:-1], 1e-3)
    np.testing.assert_array_equal(s["amplitude"], on_grid["amplitude"])


def test_an_assembly_failure_names_the_model_file(tmp_path):
    # A 1 m link pinned to ground points 10 m apart cannot be assembled: RuntimeError, named with
    # its file as `lash run` names it (it had no file name).
    path = tmp_path / "apart.yaml"
    path.write_text("ground: {markers: {O: [0, 0], P: [10, 0]}}\n"
                    "bodies:\n  link: {mass: 1, inertia: 0.1, position: [0.5, 0], "
                    "markers: {A: [-0.5, 0], B: [0.5, 0]}}\n"
                    "joints:\n  a: {type: revolute, journal: link.A, bearing: ground.O}\n"
                    "  b: {type: revolute, journal: link.B, bearing: ground.P}\n"
                    "solver: {end_time: 0.01}\n")
    with pytest.raises(RuntimeError, match=rf"^{re.escape(str(path))}:6:6: joint 'b': initial "
                       r"assembly failed"):
        lash.simulate(lash.load(path))
    # lash.analysis named no file; Model.check() passed a model `lash check` refuses.
    for call in (lambda: lash.analysis.analyze(lash.load(path)), lambda: lash.load(path).check()):
        with pytest.raises(RuntimeError, match=rf"^{re.escape(str(path))}:6:6: joint 'b'"):
            call()
    # What assembly warns of, check() issues as a Python warning, as `lash check` prints it.
    moved = lash.load(FLORES).set("bodies.slider.position", [0.5, 0.0])
    with pytest.warns(UserWarning, match=r"body 'slider': assembly moved it 0\.33 m"):
        moved.check()



def test_a_run_continues_from_a_result_or_a_state_file(tmp_path):
    # Half a revolution, then the rest from where it ended: from the Result, and from the
    # final_state.json `lash run` wrote for the same half, bit for bit the same; against the run
    # made in one go, within the tolerance (the integrator restarts at the seam, as at an event).
    whole = lash.simulate(FLORES, t_end=0.012)
    half = lash.simulate(FLORES, t_end=0.006)
    rest = lash.simulate(FLORES, t_end=0.012, start=half)
    assert rest.time[0] == pytest.approx(0.006) and rest.time[-1] == pytest.approx(0.012)
    assert abs(rest["slider.x"][-1] - whole["slider.x"][-1]) < 1e-8
    cli = subprocess.run([LASH, "run", FLORES, "-q", "-o", str(tmp_path / "half"),
                          "--set", "solver.end_time=0.006"], capture_output=True, text=True)
    assert cli.returncode == 0, cli.stderr
    from_file = lash.simulate(FLORES, t_end=0.012, start=tmp_path / "half" / "final_state.json")
    assert np.array_equal(from_file.values, rest.values)
    assert np.array_equal(lash.simulate(FLORES, t_end=0.012, start=half.final_state).values,
                          rest.values)
    # What does not fit is said as `lash run --from` says it, in Python's terms.
    with pytest.raises(ValueError, match="^start: the state is at t = 0.006 s, not before the "
                       "model's end_time = 0.006 s; give a later t_end$"):
        lash.simulate(FLORES, t_end=0.006, start=half)
    lugre = os.path.join(SOURCE, "examples", "flores_slider_crank_lugre.yaml")
    with pytest.raises(ValueError, match="^start: the state does not match the model: entry 19 "
                       "is 'energy.dissipated' in the state but 'rod_slider.bristle'"):
        lash.simulate(lugre, t_end=0.012, start=half)
    with pytest.raises(TypeError, match="^start: expected a Result"):
        lash.simulate(FLORES, t_end=0.012, start=5)
    # A final_state dict edited by hand: each entry named.
    for key, value, error, said in [("y", "abc", TypeError, "'y' must be a list of numbers"),
                                    ("time", None, TypeError, "'time' must be a number"),
                                    ("step", float("nan"), ValueError, "'step' must be a finite"),
                                    ("y", [0.0], ValueError, "'y' has 1 entries and 'names' 22"),
                                    ("modes", {"rod_slider": True, "pin": False}, ValueError,
                                     "'pin' in 'modes' is no clearance joint"),
                                    # Said as -0.000000 (which looks allowed), and a bool taken as 1 s.
                                    ("step", -1e-9, ValueError, "'step' must be a finite step size >= 0 s, got -1e-09"),
                                    ("step", True, TypeError, "'step' must be a number (s), got bool")]:
        state = dict(half.final_state, **{key: value})
        with pytest.raises(error, match=f"^start: {re.escape(said)}"):
            lash.simulate(FLORES, t_end=0.012, start=state)


def test_a_missing_state_file_is_an_oserror_and_odd_text_is_named(tmp_path):
    # start='nope.json' raised ValueError (kept for a state that does not fit the model).
    with pytest.raises(lash.IoError, match="nope.json: cannot open"):
        lash.simulate(FLORES, t_end=0.012, start=str(tmp_path / "nope.json"))
    # A lone surrogate in a model built in code: pybind11's "Unable to cast Python instance".
    with pytest.raises(ValueError, match=r"not valid UTF-8 text \(character 1, '\\udcff'\)"):
        lash.Model.new("x").add_body("b\udcff", mass=1, inertia=1).text()
    # A NUL in a key: the message went on past it (str() ended at the NUL); in an override it
    # is a NUL byte, not "not UTF-8".
    m = lash.Model(data={"name": "x", "bodies": {"b": {"mass": 1, "inertia": 1}},
                         "solver": {"end_time": 0.01}, "a\0b": 1})
    with pytest.raises(lash.ModelError) as err:
        m.check()
    assert "unknown key 'a\0b', expected one of" in str(err.value), str(err.value)
    with pytest.raises(lash.ModelError, match="a NUL byte in"):
        m.set("solver.a\0b", 1).check()


def test_modes_as_lash_modes_computes_them():
    # A point mass on a 1e-4 m distance joint: sqrt(g/L)/2pi; hanging on a spring given at its
    # free length, at the static equilibrium: moved m g / k, sqrt(k/m) unchanged.
    bob = lash.Model.new("bob", gravity=[0, -9.81])
    bob.add_ground_marker("P", [0, 0])
    bob.add_body("bob", mass=1.0, position=[0, -1e-4])
    bob.add_joint("rod", "distance", **{"from": "ground.P", "to": "bob"})
    bob.set_solver(end_time=1.0)
    m = lash.analysis.modes(bob)
    assert m["dof"] == 1 and m["equilibrium"] is None
    assert m["modes"][0]["frequency"] == pytest.approx(math.sqrt(9.81 / 1e-4) / (2 * math.pi), rel=1e-7)
    hanging = lash.loads("gravity: [0, -9.81]\nground: {markers: {A: [0, 0]}}\n"
                         "bodies: {block: {mass: 2.0, inertia: 0.01, position: [0, -0.3]}}\n"
                         "joints: {guide: {type: translational, guide: ground.A, slider: block, "
                         "axis: [0, 1]}}\nloads: {spring: {type: spring_damper, from: ground.A, "
                         "to: block, stiffness: 800, free_length: 0.3}}\nsolver: {end_time: 1}\n",
                         "hanging.yaml")
    e = lash.analysis.modes(hanging, equilibrium=True)
    assert e["equilibrium"]["largest_move"] == pytest.approx(2 * 9.81 / 800, rel=1e-9)
    assert e["equilibrium"]["largest_move_coordinate"] == "block.y"
    assert e["modes"][0]["frequency"] == pytest.approx(20 / (2 * math.pi), rel=1e-9)
    with pytest.raises(RuntimeError, match=r"^hanging.yaml: no static equilibrium found"):
        lash.analysis.modes(hanging.copy().set("loads.spring.stiffness", 0), equilibrium=True)
    with pytest.raises(TypeError, match="equilibrium"):
        lash.analysis.modes(hanging, equilibrium="yes")


def test_threads_starting_their_first_sweeps_together_finish(tmp_path):
    """Threads whose first lash.sweep calls start together: the module's record of Python's
    main thread was a function-local static initialised by calling Python, and one thread
    waited in its guard holding the GIL while the other held the guard waiting for the GIL
    (5 of 8 fresh interpreters hung). Each try is a fresh interpreter, where nothing has run."""
    study = tmp_path / "study.yaml"
    study.write_text(f"study: t\nmodel: {FLORES}\nset: {{solver.end_time: 1.0e-4}}\n"
                     "parameters:\n  joints.rod_slider.clearance: {values: [2.0e-4]}\n")
    script = (
        "import sys, threading, lash\n"
        "sys.setswitchinterval(1e-6)  # the GIL changes hands often\n"
        "start = threading.Barrier(4)  # and the four calls start together: 5 of 8 hung\n"
        "def go(out):\n"
        "    start.wait()\n"
        "    lash.sweep(sys.argv[1], out, jobs=1)\n"
        "ts = [threading.Thread(target=go, args=(sys.argv[2] + str(i),)) for i in range(4)]\n"
        "[t.start() for t in ts]; [t.join() for t in ts]; print('done')\n")
    for attempt in range(5):
        out = tmp_path / f"o{attempt}_"
        p = subprocess.run([sys.executable, "-c", script, str(study), str(out)],
                           capture_output=True, text=True, timeout=30)
        assert p.returncode == 0 and p.stdout.strip() == "done", p.stderr
        for i in range(4):
            assert len(lash.read_study(f"{out}{i}")) == 1
