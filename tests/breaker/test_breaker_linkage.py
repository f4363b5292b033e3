"""The circuit-breaker example (examples/breaker_linkage.yaml) against hand kinematics and energy.

    LASH=build/lash python3 tests/breaker/test_breaker_linkage.py

The ideal twin (A and J set to clearance 0) is run over the whole closing. Its moving-contact
position is compared with a second, independent computation: the four stages of the linkage
closed stage by stage with circle and line intersections (plane geometry, no Lash code), from the
joint points of the model file at t = 0 and link 1's STEP5 displacement. Then: the constraint
residual, the energy balance, the 280 mm output stroke the layout was designed for, and a short
run of the example itself with its two clearance joints.
"""
import csv
import json
import math
import os
import subprocess
import sys
import tempfile
import unittest

import yaml

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
MODEL = os.path.join(ROOT, "examples", "breaker_linkage.yaml")
LASH = os.environ.get("LASH", os.path.join(ROOT, "build", "lash"))


def step5(x, x0, h0, x1, h1):
    if x <= x0:
        return h0
    if x >= x1:
        return h1
    d = (x - x0) / (x1 - x0)
    return h0 + (h1 - h0) * d ** 3 * (10 - 15 * d + 6 * d * d)


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1])


def dist(a, b):
    return math.hypot(*sub(a, b))


def rotate(p, centre, angle):
    d = sub(p, centre)
    c, s = math.cos(angle), math.sin(angle)
    return (centre[0] + c * d[0] - s * d[1], centre[1] + s * d[0] + c * d[1])


def circles(p, rp, q, rq, near):
    """The intersection of two circles nearest to `near`."""
    d = dist(p, q)
    a = (rp * rp - rq * rq + d * d) / (2 * d)
    h = math.sqrt(rp * rp - a * a)
    u = ((q[0] - p[0]) / d, (q[1] - p[1]) / d)
    m = (p[0] + a * u[0], p[1] + a * u[1])
    s1, s2 = (m[0] + h * u[1], m[1] - h * u[0]), (m[0] - h * u[1], m[1] + h * u[0])
    return s1 if dist(s1, near) < dist(s2, near) else s2


class HandKinematics:
    """Stage-by-stage position analysis of the linkage from the model file's joint points."""

    def __init__(self, model):
        b, g = model["bodies"], model["ground"]["markers"]

        def w(body, marker):  # world point at the file's poses: only a starting guess for branches
            x, y = b[body]["position"]
            a = b[body].get("angle", 0)
            mx, my = b[body]["markers"][marker]
            return (x + math.cos(a) * mx - math.sin(a) * my, y + math.sin(a) * mx + math.cos(a) * my)

        def length(body, m1, m2):  # exact: from the body-fixed markers
            return dist(b[body]["markers"][m1], b[body]["markers"][m2])

        self.L2, self.L4 = length("lower_linkage", "A", "B"), length("lower_linking_board", "D", "E")
        self.L6, self.L8 = length("insulating_pole", "F", "G"), length("upper_linking_board", "I", "J")
        self.seal = length("seal_pole", "E", "F")
        self.rB, self.rD = length("lower_turn_arm", "C", "B"), length("lower_turn_arm", "C", "D")
        self.rG, self.rI = length("upper_turn_arm", "H", "G"), length("upper_turn_arm", "H", "I")
        self.arm3 = b["lower_turn_arm"]["markers"]  # the bell cranks' arm directions, body-fixed
        self.arm7 = b["upper_turn_arm"]["markers"]
        self.C, self.H = tuple(g["C"]), tuple(g["H"])
        self.A0 = (g["S1"][0] + b["driving_link"]["markers"]["A"][0], g["S1"][1])  # link 1 starts at S1
        self.xE = g["S5"][0]                    # vertical guide of the seal pole (E and F on it)
        self.yJ = g["S9"][1]                    # horizontal guide of the moving contact
        self.dJ = -b["moving_contact"]["markers"]["J"][0]  # J to the contact's centre of mass
        self.guess = {k: w(body, k) for body, ks in (("lower_turn_arm", "B"), ("upper_turn_arm", "G")) for k in ks}

    def contact_x(self, s):
        """Moving-contact centre x for link 1 moved by s along +x."""
        A = (self.A0[0] + s, self.A0[1])
        B = circles(A, self.L2, self.C, self.rB, self.guess["B"])
        # turn of the lower bell crank: the angle of CB minus that of its body-fixed arm
        phi3 = math.atan2(B[1] - self.C[1], B[0] - self.C[0]) - math.atan2(self.arm3["B"][1] - self.arm3["C"][1],
                                                                         self.arm3["B"][0] - self.arm3["C"][0])
        D = rotate((self.C[0] + self.arm3["D"][0] - self.arm3["C"][0], self.C[1] + self.arm3["D"][1] - self.arm3["C"][1]),
                   self.C, phi3)
        E = (self.xE, D[1] + math.sqrt(self.L4 ** 2 - (self.xE - D[0]) ** 2))  # on the vertical guide, above D
        F = (self.xE, E[1] + self.seal)
        G = circles(F, self.L6, self.H, self.rG, self.guess["G"])
        phi7 = math.atan2(G[1] - self.H[1], G[0] - self.H[0]) - math.atan2(self.arm7["G"][1] - self.arm7["H"][1],
                                                                         self.arm7["G"][0] - self.arm7["H"][0])
        I = rotate((self.H[0] + self.arm7["I"][0] - self.arm7["H"][0], self.H[1] + self.arm7["I"][1] - self.arm7["H"][1]),
                   self.H, phi7)
        J = (I[0] + math.sqrt(self.L8 ** 2 - (self.yJ - I[1]) ** 2), self.yJ)  # on the horizontal guide, right of I
        return J[0] + self.dJ


def run(out, *sets):
    args = [LASH, "run", MODEL, "-o", out, "-q"]
    for s in sets:
        args += ["--set", s]
    subprocess.run(args, check=True)
    with open(os.path.join(out, "timeseries.csv")) as f:
        rows = list(csv.DictReader(f))
    with open(os.path.join(out, "summary.json")) as f:
        return rows, json.load(f)


class BreakerLinkage(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.model = yaml.safe_load(open(MODEL))
        cls.rows, cls.summary = run(os.path.join(cls.tmp.name, "ideal"), "joints.A.clearance=0",
                                    "joints.J.clearance=0", "solver.output_interval=1e-4")

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def test_moving_contact_follows_the_hand_kinematics(self):
        hand = HandKinematics(self.model)
        worst = 0.0
        for r in self.rows:
            t = float(r["time"])
            s = step5(t, 0, 0, 0.085, 0.230)
            worst = max(worst, abs(float(r["moving_contact.x"]) - hand.contact_x(s)))
        # m: the CSV keeps 9 significant digits (5e-10 m at 1.2 m), the integrator tolerances the rest
        self.assertLess(worst, 1e-8)

    def test_output_stroke_is_280_mm(self):
        x = [float(r["moving_contact.x"]) for r in self.rows]
        self.assertAlmostEqual(x[-1] - x[0], 0.280, delta=0.5e-3)
        # every stage moves forward over the whole stroke: no dead centre is crossed
        self.assertTrue(all(b >= a - 1e-12 for a, b in zip(x, x[1:])))

    def test_constraints_hold_and_energy_balances(self):
        self.assertLess(self.summary["max_constraint_violation"], 1e-9)
        balance = [float(r["energy.balance"]) for r in self.rows]
        work = max(abs(float(r["energy.input"])) for r in self.rows)
        self.assertGreater(work, 100.0)  # J: the drive lifts 93.6 kg by 0.23 m and more
        self.assertLess(max(balance) - min(balance), 1e-6 * work)

    def test_example_with_clearance_starts(self):
        rows, summary = run(os.path.join(self.tmp.name, "clearance"), "solver.end_time=0.004")
        self.assertTrue(summary["status"]["ok"])
        self.assertEqual(sorted(summary["clearance_joints"]), ["A", "J"])
        # the journals start centred and lag the ideal motion: contact is reached within 4 ms
        self.assertGreater(max(float(r["A.Fn"]) for r in rows), 0.0)


if __name__ == "__main__":
    unittest.main(verbosity=2)
