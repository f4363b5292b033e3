#!/usr/bin/env bash
# Two runs of studies/erkaya_compliant_vs_articulated.yaml (articulated and compliant, 0.5 mm,
# 200 rpm, 2 revolutions instead of 10) through `lash sweep` and studies/results.py: the study's
# cases load, the kept channels exist in both models, and RESULTS.md gets its table, its figures
# and a verdict for every statement of the paper. The full study is `make studies`.
set -euo pipefail
lash="$1"; src="$2"
dir="$(mktemp -d)"; trap 'rm -rf "$dir"' EXIT
# The study file's own cases and keep list, two of its runs, a shorter run length.
/usr/bin/python3 - "$src/studies/erkaya_compliant_vs_articulated.yaml" "$src" > "$dir/study.yaml" <<'PY'
import re, sys
text, src = open(sys.argv[1], encoding="utf-8").read(), sys.argv[2]
text = text.replace("../examples/", src + "/examples/")
text = re.sub(r"\n      articulated_c0\.85:.*?\n.*?\n", "\n", text)        # two lines each
text = re.sub(r"\n      compliant_c0\.85:.*?\n", "\n", text)
text = re.sub(r"\n      rpm100:.*?\n", "\n", text)
text = re.sub(r"\n      rpm150:.*?\n", "\n", text)
text = text.replace("solver.end_time: 3.0}", "solver.end_time: 0.6}")
text = text.replace("transient: {periods: 3}", "transient: {periods: 1}")
print(text)
PY
grep -q "end_time: 0.6}" "$dir/study.yaml"
"$lash" sweep "$dir/study.yaml" -q -j 2 -o "$dir/out"
/usr/bin/python3 "$src/studies/results.py" "$dir/out"
/usr/bin/python3 - "$dir/out" <<'PY'
import os, sqlite3, sys
out = sys.argv[1]
db = sqlite3.connect(os.path.join(out, "study.db"))
runs = db.execute("select mechanism, speed, status from runs order by run").fetchall()
assert runs == [("articulated_c0.50", "rpm200", "completed"),
                ("compliant_c0.50", "rpm200", "completed")], runs
names = {r[0] for r in db.execute("select name from metrics")}
for m in ("crank_rod.Fn.peak", "rod_piston.Fn.peak", "crank_pivot.F.peak", "piston_guide.F.peak",
          "acc1.a.rms", "acc5.a.peak", "crank_rod.continuous_share", "distinct_points"):
    assert m in names, m
text = open(os.path.join(out, "RESULTS.md"), encoding="utf-8").read()
rows = [l for l in text.splitlines() if l.startswith("| articulated_c0.50") or l.startswith("| compliant_c0.50")]
assert len(rows) == 2, rows
claims = text.split("## Against the paper", 1)[1].strip().split("\n\n")
assert len(claims) >= 4, claims
for c in claims:
    if c.startswith("**"):
        assert any(w in c for w in ("**agrees**", "**disagrees**", "**agrees in part**",
                                    "**mostly disagrees**", "**unknown")), c
for f in ("sensor5_rms.svg", "f21_peak.svg"):
    svg = open(os.path.join(out, f), encoding="utf-8").read()
    assert svg.startswith("<svg") and svg.count("<circle") == 2, f
print("erkaya study subset: ok")
PY
