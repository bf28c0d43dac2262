#!/usr/bin/env bash
# Installs every build, test and report dependency from Debian's packages.
# Skips apt when everything is already present, so repeated runs are fast.
set -euo pipefail
pkgs=(build-essential cmake pkg-config libsundials-dev libeigen3-dev libsuitesparse-dev
      libgtest-dev libgmock-dev libbenchmark-dev libopenmpi-dev openmpi-bin
      libgsl-dev libboost-dev gnuplot-nox python3 python3-matplotlib python3-numpy valgrind
      pybind11-dev python3-dev python3-scipy python3-pytest)
missing=()
for p in "${pkgs[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if ((${#missing[@]})); then
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  echo "Installing: ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
