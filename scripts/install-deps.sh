#!/usr/bin/env bash
# Installs the Debian packages Lash builds against, only those that are missing.
# Why each one is there: see README.md, "Dependencies".
set -euo pipefail
pkgs=(cmake ninja-build g++ make pkg-config
      libeigen3-dev libyaml-cpp-dev libcli11-dev libfmt-dev libmuparser-dev
      libsundials-dev nlohmann-json3-dev libgtest-dev libgmock-dev libbenchmark-dev
      clang libclang-rt-14-dev)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then exit 0; fi
echo "Installing missing packages: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
