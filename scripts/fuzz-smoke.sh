#!/usr/bin/env bash
# Builds the model-loader fuzzer (clang + libFuzzer + ASan/UBSan) in build-fuzz/ and runs it for a
# bounded time on a scratch copy of fuzz/corpus/. Exits non-zero if it finds a crash, a sanitizer
# report, an unexpected exception, a timeout or an out-of-memory; the input that caused it is left
# in build-fuzz/crashes/ (crash-*, timeout-*, oom-*). Minimise it with
#   build-fuzz/fuzz/fuzz_model_loader -minimize_crash=1 -runs=10000 build-fuzz/crashes/crash-...
# and add it to tests/fuzz_regressions/.
#
# Environment:
#   LASH_FUZZ_SECONDS  fuzzing time, default 30
#   LASH_FUZZ_JOBS     parallel compile jobs for the build, default: number of cores
#   CXX                the clang++ to use, default clang++ (Debian: scripts/install-deps.sh)
# Needs clang and libclang-rt-14-dev (the libFuzzer runtime), which scripts/install-deps.sh
# installs. Run from anywhere.
#
# Options: --build-only builds the fuzzer and stops; --run-only runs a fuzzer already built (it
# fails if there is none). `make test` runs the two halves as the ctests fuzz_model_loader_build
# and fuzz_model_loader_smoke, so that the build (minutes on a cold machine) and the bounded
# fuzzing run each have their own time-out.
set -euo pipefail

mode=all
case "${1:-}" in
  "") ;;
  --build-only) mode=build ;;
  --run-only) mode=run ;;
  *) echo "fuzz-smoke: unknown option '$1' (expected --build-only or --run-only)" >&2; exit 2 ;;
esac

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$root/build-fuzz"
seconds="${LASH_FUZZ_SECONDS:-30}"
jobs="${LASH_FUZZ_JOBS:-$(nproc)}"
cxx="${CXX:-clang++}"
case "$cxx" in *clang*) ;; *) cxx=clang++ ;; esac  # a g++ in CXX cannot build libFuzzer targets

if ! command -v "$cxx" >/dev/null; then
  echo "fuzz-smoke: $cxx not found; run scripts/install-deps.sh (clang, libclang-rt-14-dev)" >&2
  exit 1
fi

fuzzer="$build/fuzz/fuzz_model_loader"
if [ "$mode" != run ]; then
  # Build: only the fuzzer and the libraries it links.
  echo "fuzz-smoke: building $fuzzer"
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_CXX_COMPILER="$cxx" \
        -DCMAKE_BUILD_TYPE=RelWithDebInfo -DLASH_FUZZ=ON -DLASH_TESTS=OFF -DLASH_BENCH=OFF >/dev/null
  cmake --build "$build" --target fuzz_model_loader -j "$jobs"
  if [ "$mode" = build ]; then exit 0; fi
elif [ ! -x "$fuzzer" ]; then
  echo "fuzz-smoke: $fuzzer is not built; run scripts/fuzz-smoke.sh --build-only first" >&2
  exit 1
fi

# Sanitizers: stop at the first report, with a stack; libFuzzer then saves the input.
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}abort_on_error=1:detect_leaks=1:symbolize=1"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:+$UBSAN_OPTIONS:}print_stacktrace=1:halt_on_error=1:symbolize=1"
# tests/lsan.supp: CLN's one allocation at load time that it never frees, and GiNaC's parser's leak
# when a formula divides by zero.
export LSAN_OPTIONS="${LSAN_OPTIONS:+$LSAN_OPTIONS:}suppressions=$root/tests/lsan.supp"

crashes="$build/crashes"
mkdir -p "$crashes"
work="$(mktemp -d "${TMPDIR:-/tmp}/lash-fuzz.XXXXXX")"
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/corpus"
cp "$root"/fuzz/corpus/* "$work/corpus/"

# Known crashes first: they must stay fixed (tests/test_fuzz_regressions checks the same files
# without sanitizers; this run adds ASan/UBSan).
failed=0
shopt -s nullglob
regressions=()
for f in "$root"/tests/fuzz_regressions/*; do [[ $f == *.md ]] || regressions+=("$f"); done
for input in "${regressions[@]}"; do
  if ! "$fuzzer" "$input" >"$work/replay.log" 2>&1; then
    tail -n 40 "$work/replay.log" >&2
    echo "fuzz-smoke: FAILED: tests/fuzz_regressions/$(basename "$input") still crashes (above)" >&2
    failed=1
  fi
done
echo "fuzz-smoke: replayed ${#regressions[@]} inputs from tests/fuzz_regressions/"

echo "fuzz-smoke: fuzzing for ${seconds}s"
status=0
"$fuzzer" "$work/corpus" \
    -dict="$root/fuzz/yaml.dict" \
    -max_total_time="$seconds" \
    -max_len=4096 -timeout=10 -rss_limit_mb=2048 \
    -artifact_prefix="$crashes/" -print_final_stats=1 \
    >"$work/fuzz.log" 2>&1 || status=$?
if [ "$status" -ne 0 ]; then
  tail -n 80 "$work/fuzz.log" >&2
  echo "fuzz-smoke: FAILED (exit $status); the input is in $crashes/:" >&2
  ls -t "$crashes" | head -n 3 >&2
  exit 1
fi
grep -E "^(stat::number_of_executed_units|stat::new_units_added)" "$work/fuzz.log" || true
echo "fuzz-smoke: no new crash in ${seconds}s"
exit "$failed"
