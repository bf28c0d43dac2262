#!/usr/bin/env bash
# Second CI leg: SUNDIALS 7.5.0 built from ../shared/third_party (the build line of
# its README, into a prefix under build-sundials7/), then CEODE against it: every
# test and the installed-package consumer. Skipped, saying so, without the tarball.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
tarball=../shared/third_party/sundials-7.5.0-src.tar.xz
if [ ! -f "$tarball" ]; then
  echo "=== SUNDIALS 7 leg SKIPPED: $tarball not found (it sits in shared/ beside the repository)."
  exit 0
fi
jobs=$(nproc)
root=$PWD/build-sundials7
prefix=$root/prefix
if [ ! -f "$prefix/lib/cmake/sundials/SUNDIALSConfig.cmake" ]; then
  echo "=== Building SUNDIALS 7.5.0 into $prefix"
  rm -rf "$root/sundials-7.5.0"
  mkdir -p "$root"
  tar -xJf "$tarball" -C "$root"
  cmake -S "$root/sundials-7.5.0" -B "$root/sundials-7.5.0/build" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_INSTALL_PREFIX="$prefix" \
    -DBUILD_SHARED_LIBS=ON -DBUILD_STATIC_LIBS=OFF -DENABLE_KLU=ON \
    -DKLU_INCLUDE_DIR=/usr/include/suitesparse -DKLU_LIBRARY_DIR=/usr/lib/x86_64-linux-gnu \
    -DENABLE_OPENMP=ON -DENABLE_MPI=ON -DBUILD_CVODES=OFF -DBUILD_IDAS=OFF -DBUILD_KINSOL=OFF \
    -DEXAMPLES_ENABLE_C=OFF -DEXAMPLES_ENABLE_CXX=OFF -DEXAMPLES_INSTALL=OFF
  cmake --build "$root/sundials-7.5.0/build" -j"$jobs"
  cmake --install "$root/sundials-7.5.0/build"
fi
echo "=== CEODE against SUNDIALS 7.5.0 ($prefix)"
cmake -S . -B build-s7 -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" \
  -DCEODE_BUILD_TESTS=ON -DCEODE_BUILD_BENCHMARKS=ON -DCEODE_BUILD_PYTHON=OFF
# The build must use this prefix, not a SUNDIALS installed elsewhere on the machine.
found=$(sed -n 's/^SUNDIALS_DIR:PATH=//p' build-s7/CMakeCache.txt)
if [ "$(realpath "$found")" != "$(realpath "$prefix/lib/cmake/sundials")" ]; then
  echo "SUNDIALS 7 leg: configured against $found, not $prefix" >&2
  exit 1
fi
cmake --build build-s7 -j"$jobs"
(cd build-s7 && ctest --output-on-failure -j"$jobs")
