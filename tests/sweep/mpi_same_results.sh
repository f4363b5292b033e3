#!/usr/bin/env bash
# One study on the local cores and under `mpirun --oversubscribe -n 3` (rank 0 hands out runs,
# ranks 1 and 2 run them): the two study databases must hold the same results (timing and the
# worker's name aside).
set -euo pipefail
lash="$1"; src="$2"
dir="$(mktemp -d)"; trap 'rm -rf "$dir"' EXIT
cat > "$dir/study.yaml" <<YAML
study: mpi_check
model: $src/examples/flores_slider_crank.yaml
set: {solver.end_time: 0.05, solver.output_interval: 1.0e-4}
parameters:
  drivers.crank.speed_rpm: {from: 3000, to: 5000, count: 7}
transient: {periods: 2}
keep: {sections: [rod_slider.ex], channels: [rod_slider.Fn, slider.ax], series: {channels: [slider.ax], points: 20}}
YAML
"$lash" sweep "$dir/study.yaml" -q -j 1 -o "$dir/local"
# mpirun refuses root unless told (containers, CI); a cluster user is not root.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
mpirun --oversubscribe -n 3 "$lash" sweep "$dir/study.yaml" -q -o "$dir/mpi"
/usr/bin/python3 - "$dir/local/study.db" "$dir/mpi/study.db" <<'PY'
import sqlite3, sys
def content(path):
    c = sqlite3.connect(path)
    runs = c.execute('select run, "drivers.crank.speed_rpm", status, message, verdict, t_reached, '
                     'steps, rhs_evaluations, events from runs order by run').fetchall()
    workers = {r[0] for r in c.execute("select worker from runs")}
    rest = [c.execute(q).fetchall() for q in (
        "select * from metrics order by run, name",
        "select * from sections order by run, k, channel",
        "select * from series order by run, channel")]
    return runs, rest, workers
a_runs, a_rest, a_workers = content(sys.argv[1])
b_runs, b_rest, b_workers = content(sys.argv[2])
assert len(a_runs) == 7, a_runs
assert a_runs == b_runs, "runs differ:\n%s\n%s" % (a_runs, b_runs)
assert a_rest == b_rest, "metrics, sections or series differ"
assert b_workers <= {"rank 1", "rank 2"} and len(b_workers) == 2, b_workers
print("local and MPI (3 processes) results identical: %d runs, %d metrics, %d section values"
      % (len(a_runs), len(a_rest[0]), len(a_rest[1])))
PY

# A continuation study is refused under mpirun before its folder is made: the plain `lash sweep`
# the message recommends then runs (a study.db left behind refused it, "add --resume").
cat > "$dir/cont.yaml" <<YAML
study: cont
model: $src/examples/flores_slider_crank.yaml
set: {solver.end_time: 0.03, solver.output_interval: 1.0e-4}
parameters:
  drivers.crank.speed_rpm: {values: [4000, 5000]}
continuation: up
transient: {periods: 1}
YAML
if mpirun --oversubscribe -n 2 "$lash" sweep "$dir/cont.yaml" -q -o "$dir/cont" 2>"$dir/cont.err"; then
  echo "a continuation study ran under mpirun"; exit 1
fi
grep -q "run it without mpirun" "$dir/cont.err" || { cat "$dir/cont.err"; exit 1; }
[ ! -e "$dir/cont" ] || { echo "the refused study left $(ls -A "$dir/cont")"; exit 1; }
"$lash" sweep "$dir/cont.yaml" -q -o "$dir/cont"

# A signal to one worker rank stops the sweep as one to rank 0 would: exit 130 and `--resume`,
# not exit 0 with the runs it was then handed lost (they came back interrupted, unrecorded).
sed -e 's/solver.end_time: 0.05/solver.end_time: 0.4/' -e 's/count: 7/count: 12/' \
  "$dir/study.yaml" > "$dir/long.yaml"
set +e
mpirun --oversubscribe -n 3 "$lash" sweep "$dir/long.yaml" -q -o "$dir/long" 2>"$dir/long.err" &
launcher=$!
worker=""
for _ in $(seq 100); do  # rank 2's process, once it has started
  for p in $(pgrep -f "sweep $dir/long.yaml"); do
    grep -qz '^OMPI_COMM_WORLD_RANK=2$' "/proc/$p/environ" 2>/dev/null && worker=$p
  done
  [ -n "$worker" ] && break
  sleep 0.1
done
sleep 1
kill -TERM "$worker"
wait "$launcher"; rc=$?
set -e
recorded=$(/usr/bin/python3 -c "import sqlite3,sys; print(sqlite3.connect(sys.argv[1]).execute('select count(*) from runs').fetchone()[0])" "$dir/long/study.db")
if [ "$recorded" -lt 12 ]; then
  [ "$rc" -ne 0 ] || { echo "runs missing ($recorded of 12) and exit 0"; cat "$dir/long.err"; exit 1; }
  grep -q "resume" "$dir/long.err" || { cat "$dir/long.err"; exit 1; }
fi
echo "continuation refused with no folder; a worker's signal stopped the sweep (exit $rc, $recorded of 12 recorded)"

# A study and a model whose file names are not UTF-8 (Latin-1 é): the study travels to the
# workers as MessagePack, byte for byte (JSON's writer refused such names).
latin="$(printf 'st_\xe9')"; mlatin="$(printf 'm_\xe9.yaml')"
cp "$src/examples/flores_slider_crank.yaml" "$dir/$mlatin"
printf 'study: latin1\nmodel: %s\nset: {solver.end_time: 0.03}\ntransient: {periods: 1}\nparameters:\n  joints.rod_slider.clearance: {values: [1.0e-4, 3.0e-4]}\n' \
  "$mlatin" > "$dir/$latin.yaml"
mpirun --oversubscribe -n 2 "$lash" sweep "$dir/$latin.yaml" -q -o "$dir/latin"
n="$(python3 -c 'import sqlite3, sys; print(sqlite3.connect(sys.argv[1]).execute("select count(*) from runs where status = ?", ("completed",)).fetchone()[0])' "$dir/latin/study.db")"
[ "$n" = 2 ] || { echo "Latin-1 names under mpirun: $n of 2 runs completed"; exit 1; }
echo "Latin-1 file names under mpirun: 2 of 2 runs completed"
