#!/usr/bin/env bash
# Installs the Lash build tree BUILD into a fresh prefix, checks that no installed file names the
# source or build folder, builds tests/package_consumer against the installed package and runs
# both programs on the Flores example. Usage: run.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1 source=$2
work=$(mktemp -d "${TMPDIR:-/tmp}/lash-package.XXXXXX")
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix
cmake --install "$build" --prefix "$prefix" >/dev/null
for f in include/lash/core/simulate.hpp include/lash/io/model_loader.hpp bin/lash \
         share/lash/lash_figures.py share/doc/lash/README.md share/doc/lash/docs/model-format.md \
         share/doc/lash/docs/studies.md lib/cmake/Lash/LashConfig.cmake \
         lib/cmake/Lash/LashConfigVersion.cmake; do
  [ -f "$prefix/$f" ] || { echo "not installed: $f" >&2; exit 1; }
done
ls "$prefix"/lib*/liblash.so* "$prefix"/lib*/liblash.a >/dev/null
# No path of this checkout in any installed file (text or binary).
src_real=$(cd "$source" && pwd -P) build_real=$(cd "$build" && pwd -P)
if grep -rlaF -e "$src_real" -e "$build_real" "$prefix"; then
  echo "the files above contain $src_real or $build_real" >&2
  exit 1
fi
cmake -S "$source/tests/package_consumer" -B "$work/consumer" -G Ninja \
      -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$work/consumer" >/dev/null
"$work/consumer/consumer" "$source/examples/flores_slider_crank.yaml"
"$work/consumer/consumer_static" "$source/examples/flores_slider_crank.yaml"
# The installed lash finds its figures tool beside it, not in the source tree.
"$prefix/bin/lash" run "$source/examples/flores_slider_crank.yaml" -o "$work/run" -q --report \
    --set solver.end_time=0.012 >/dev/null
ls "$work"/run/figures/*.png >/dev/null || \
  { echo "the installed lash wrote no figures:" >&2; cat "$work/run/figures.log" >&2 || true; exit 1; }
# The Python package, when built, imports from the installed tree (no build folder on the path).
for site in "$prefix"/lib/python3*/dist-packages; do
  [ -f "$site/lash/__init__.py" ] || continue
  (cd "$work" && PYTHONPATH="$site" /usr/bin/python3 -c "
import lash, sys
assert lash.__file__.startswith(sys.argv[1]), lash.__file__
r = lash.simulate(sys.argv[2], t_end=0.001)
assert r.ok and len(r.time) == 101, r
print('installed python module: OK')" "$site" "$source/examples/flores_slider_crank.yaml")
done
echo "package consumer: OK"
