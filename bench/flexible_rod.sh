#!/usr/bin/env bash
# Time per simulated second of the Flores slider-crank with a flexible connecting rod
# (examples/flores_slider_crank_flexible_rod.yaml) for 4, 8 and 16 elements under each
# integrator; results recorded in bench/README.md ("Flexible links").
# Usage: bench/flexible_rod.sh [LASH_BINARY] [END_TIME_S]
set -euo pipefail
lash=${1:-build/lash}
end=${2:-0.006}
model=examples/flores_slider_crank_flexible_rod.yaml
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
printf '%-9s %-7s %10s %10s %12s %14s\n' elements solver wall_s steps rhs_evals "s per sim s"
for n in 4 8 16; do
  for integrator in dopri5 bdf; do
    line=$("$lash" run "$model" -o "$out/r" --set "bodies.rod.flexible.elements=$n" \
      --set "solver.integrator=$integrator" --set "solver.end_time=$end" | tail -1)
    wall=$(sed -E 's/.* in ([0-9.]+) s .*/\1/' <<<"$line")
    steps=$(sed -E 's/.*\(([0-9]+) steps.*/\1/' <<<"$line")
    rhs=$(sed -E 's/.* ([0-9]+) rhs evaluations.*/\1/' <<<"$line")
    printf '%-9s %-7s %10s %10s %12s %14.0f\n' "$n" "$integrator" "$wall" "$steps" "$rhs" \
      "$(echo "$wall / $end" | bc -l)"
  done
done
