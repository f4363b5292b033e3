"""studies/results.py's figures, on a small study database written with the schema of
src/study/study_db.cpp: one dot per kept section value, one line per kept series, section
maps pairing the k-th values of two channels, and the axes covering the data."""
import importlib.util
import json
import os
import re
import sqlite3
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SPEC = importlib.util.spec_from_file_location(
    "study_results", os.path.join(HERE, "..", "..", "studies", "results.py"))
results = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(results)


def make_db(folder):
    db = sqlite3.connect(os.path.join(folder, "study.db"))
    db.executescript("""
      CREATE TABLE study(key TEXT PRIMARY KEY, value TEXT);
      CREATE TABLE parameters(position INTEGER PRIMARY KEY, name TEXT NOT NULL);
      CREATE TABLE runs(run INTEGER PRIMARY KEY, "speed" REAL, "direction", status TEXT NOT NULL,
        message TEXT, verdict TEXT, t_reached REAL, wall_seconds REAL, steps INTEGER,
        rhs_evaluations INTEGER, events INTEGER, worker TEXT, finished TEXT);
      CREATE TABLE metrics(run INTEGER NOT NULL, name TEXT NOT NULL, value REAL, PRIMARY KEY(run, name));
      CREATE TABLE sections(run INTEGER NOT NULL, k INTEGER NOT NULL, t REAL NOT NULL,
        channel TEXT NOT NULL, value REAL);
      CREATE TABLE series(run INTEGER NOT NULL, channel TEXT NOT NULL, time TEXT NOT NULL, value TEXT NOT NULL);
    """)
    db.executemany("insert into study values(?, ?)", [("name", "synthetic"), ("runs", "4")])
    db.executemany("insert into parameters values(?, ?)", [(0, "speed"), (1, "direction")])
    runs = [(0, 1000.0, "up", "completed"), (1, 2000.0, "up", "completed"),
            (2, 1000.0, "down", "completed"), (3, 2000.0, "down", "failed")]
    for run, speed, direction, status in runs:
        db.execute("insert into runs(run, speed, direction, status, wall_seconds) values(?,?,?,?,1)",
                   (run, speed, direction, status))
        db.execute("insert into metrics values(?, 'x.peak', ?)", (run, speed / 10))
        for k in range(run + 2):  # 2, 3, 4, 5 sections
            db.execute("insert into sections values(?, ?, ?, 'j.ex', ?)", (run, k, 0.1 * k, 1e-4 * k))
            db.execute("insert into sections values(?, ?, ?, 'j.ey', ?)", (run, k, 0.1 * k, -2e-4 * k))
        db.execute("insert into series values(?, 'x', ?, ?)",
                   (run, json.dumps([0.0, 0.5, 1.0]), json.dumps([0.0, speed, -speed])))
    db.commit()
    db.close()


class StudyFigures(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        make_db(self.tmp.name)
        _, _, self.runs = results.read_study(self.tmp.name)

    def tearDown(self):
        self.tmp.cleanup()

    def test_sections_give_one_dot_per_value_of_completed_runs(self):
        svg = results.figure({"kind": "sections", "file": "b.svg", "title": "t", "channel": "j.ex",
                              "x": "speed", "series": "direction", "ylabel": "m"},
                             self.runs, self.tmp.name)
        self.assertTrue(svg.startswith("<svg"))
        self.assertEqual(svg.count("<circle"), 2 + 3 + 4)  # run 3 failed: left out
        self.assertIn(">up<", svg)
        self.assertIn(">down<", svg)

    def test_section_map_pairs_the_kth_values(self):
        svg = results.figure({"kind": "section_map", "file": "p.svg", "title": "t",
                              "x_channel": "j.ex", "y_channel": "j.ey", "series": "direction",
                              "xlabel": "x", "ylabel": "y"}, self.runs, self.tmp.name)
        self.assertEqual(svg.count("<circle"), 9)
        # ey = -2 ex: every dot on one straight line through the origin
        pts = [(float(a), float(b)) for a, b in re.findall(r'cx="([-\d.]+)" cy="([-\d.]+)"', svg)]
        (x0, y0), (x1, y1) = min(pts), max(pts)
        for x, y in pts:
            self.assertAlmostEqual((y - y0) * (x1 - x0), (y1 - y0) * (x - x0), delta=2.0 * (x1 - x0))

    def test_series_draw_one_line_per_selected_run(self):
        svg = results.figure({"kind": "series", "file": "s.svg", "title": "t", "channel": "x",
                              "series": "direction", "ylabel": "u"}, self.runs, self.tmp.name)
        self.assertEqual(svg.count("<polyline"), 3)
        svg = results.figure({"kind": "series", "file": "s.svg", "title": "t", "channel": "x",
                              "series": "speed", "ylabel": "u", "where": {"direction": "up"}},
                             self.runs, self.tmp.name)
        self.assertEqual(svg.count("<polyline"), 2)
        # the y axis covers ±2000: its tick labels include both ends
        self.assertIn(">2000<", svg)
        self.assertIn(">-2000<", svg)

    def test_metric_line_without_a_series_parameter(self):
        svg = results.figure({"file": "m.svg", "title": "t", "metric": "x.peak", "ylabel": "u",
                              "x": "speed"}, self.runs, self.tmp.name)
        self.assertEqual(svg.count("<polyline"), 1)

    def test_nice_ticks_cover_the_range(self):
        for lo, hi in ((0.0, 1.0), (-3.2e-4, 5.1e-4), (1000.0, 5000.0), (7.0, 7.0)):
            t = results.nice_ticks(lo, hi)
            self.assertTrue(2 <= len(t) <= 12, t)
            step = t[1] - t[0]
            self.assertLessEqual(t[0], lo)            # the first tick at or below the data
            self.assertGreater(t[-1] + step, hi)      # the last within a step of its top
            self.assertLess(t[0] + step, max(hi, lo + step) + 1e-12 * step)


if __name__ == "__main__":
    unittest.main()
