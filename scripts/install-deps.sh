#!/usr/bin/env bash
# Installs the Debian packages Lash builds against, only those that are missing.
# Why each one is there: see README.md, "Dependencies".
set -euo pipefail
pkgs=(cmake ninja-build g++ make pkg-config
      libeigen3-dev libboost-dev libyaml-cpp-dev libcli11-dev libfmt-dev libmuparser-dev libginac-dev
      libsundials-dev nlohmann-json3-dev libgtest-dev libgmock-dev libbenchmark-dev libfftw3-dev
      python3-matplotlib python3-numpy
      libsqlite3-dev libopenmpi-dev openmpi-bin libhdf5-dev python3-h5py
      pybind11-dev python3-dev python3-pytest python3-pandas
      clang libclang-rt-14-dev
      chromium fonts-dejavu-core)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "Installing missing packages: ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The report page's npm packages (uPlot, inlined into report.html at build time; playwright-core
# for the page test), exactly as report/package-lock.json pins them.
REPORT_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/report"
if [ ! -d "$REPORT_DIR/node_modules" ]; then
  command -v npm >/dev/null || { echo "install-deps: npm (Node.js) is needed for report/" >&2; exit 1; }
  echo "Installing the report page's npm packages in report/node_modules"
  (cd "$REPORT_DIR" && npm ci --no-audit --no-fund --loglevel=error)
fi
