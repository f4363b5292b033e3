#!/usr/bin/env python3
"""Sweep throughput: a 200-point crank-speed sweep of the Flores example (1000-5000 rpm, 0.05 s
each) on 1 and 2 local cores (threads) and under MPI with 2 worker processes (mpirun -n 3: rank 0
dispatches and writes the database). Prints runs per minute, the speed-up over one core, and the
sweep machinery's overhead per run: the one-core sweep's wall time beyond the sum of its runs' own
wall times (reading the study, database transactions, scheduling, the CSV export, start-up).

Usage: bench/bench_sweep.py [build/lash]
"""
import os
import shutil
import sqlite3
import subprocess
import sys
import tempfile
import time

lash = os.path.realpath(sys.argv[1] if len(sys.argv) > 1 else "build/lash")
src = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
RUNS = 200

with tempfile.TemporaryDirectory() as d:
    study = os.path.join(d, "study.yaml")
    with open(study, "w") as f:
        f.write(f"""study: bench_speed_sweep
model: {src}/examples/flores_slider_crank.yaml
set: {{solver.end_time: 0.05, solver.output_interval: 1.0e-4}}
parameters:
  drivers.crank.speed_rpm: {{from: 1000, to: 5000, count: {RUNS}}}
transient: {{periods: 1}}
keep: {{sections: [rod_slider.ex], channels: [rod_slider.Fn, slider.ax]}}
""")

    def timed(name, cmd, env=None):
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, env=env)
        return name, time.perf_counter() - t0

    results = [timed("threads, -j 1", [lash, "sweep", study, "-q", "-j", "1", "-o", f"{d}/j1"]),
               timed("threads, -j 2", [lash, "sweep", study, "-q", "-j", "2", "-o", f"{d}/j2"])]
    if shutil.which("mpirun"):
        env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
        results.append(timed("MPI, 2 workers (mpirun -n 3)",
                             ["mpirun", "--oversubscribe", "-n", "3", lash, "sweep", study, "-q",
                              "-o", f"{d}/mpi"], env))
    inside, n = sqlite3.connect(f"{d}/j1/study.db").execute(
        "select sum(wall_seconds), count(*) from runs").fetchone()
    assert n == RUNS, n
    t1 = results[0][1]
    print(f"{'configuration':34s} {'wall s':>8s} {'runs/min':>10s} {'speed-up':>9s}")
    for name, t in results:
        print(f"{name:34s} {t:8.2f} {RUNS * 60 / t:10.0f} {t1 / t:9.2f}")
    print(f"sweep machinery overhead (1 core): {t1 - inside:.2f} s over {inside:.2f} s of runs "
          f"= {100 * (t1 - inside) / inside:.2f} % per run")
