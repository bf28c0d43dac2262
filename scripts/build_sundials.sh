#!/usr/bin/env bash
# Build one SUNDIALS release from the shared source tarball into a prefix.
#
#   scripts/build_sundials.sh <version> <prefix> "<C flags>"
#   e.g. scripts/build_sundials.sh 6.4.1 build-sundials-O3/install "-O3"
#
# Source: ../shared/third_party/sundials-<version>-src.tar.xz relative to the
# repository root (see that directory's README). The configure line is the
# README's (shared libraries, KLU, OpenMP, MPI, no CVODES/IDAS/KINSOL, no
# examples) with CMAKE_BUILD_TYPE=Release and the given flags as the Release
# C flags, so the only difference to Debian's package is the optimisation.
# About 25 s on 2 cores for 6.4.1. An existing prefix with lib/cmake/sundials is
# reused, not rebuilt. Exit 0 on success, 2 when the tarball is missing.
set -euo pipefail
[ $# -eq 3 ] || { echo "usage: $0 <version> <prefix> <C flags>" >&2; exit 1; }
version=$1
prefix=$2
flags=$3
root=$(cd "$(dirname "$0")/.." && pwd)
tarball=$root/../shared/third_party/sundials-$version-src.tar.xz
if [ -e "$prefix/lib/cmake/sundials/SUNDIALSConfig.cmake" ]; then
  echo "SUNDIALS $version already installed in $prefix"
  exit 0
fi
[ -e "$tarball" ] || { echo "no tarball $tarball" >&2; exit 2; }
mkdir -p "$prefix"
prefix=$(cd "$prefix" && pwd)
work=$prefix.src
rm -rf "$work"
mkdir -p "$work"
tar -xJf "$tarball" -C "$work"
src=$work/sundials-$version
cmake -S "$src" -B "$src/build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_FLAGS_RELEASE="$flags" \
  -DCMAKE_INSTALL_PREFIX="$prefix" -DCMAKE_INSTALL_LIBDIR=lib \
  -DBUILD_SHARED_LIBS=ON -DBUILD_STATIC_LIBS=OFF -DENABLE_KLU=ON \
  -DKLU_INCLUDE_DIR=/usr/include/suitesparse -DKLU_LIBRARY_DIR=/usr/lib/x86_64-linux-gnu \
  -DENABLE_OPENMP=ON -DENABLE_MPI=ON -DBUILD_CVODES=OFF -DBUILD_IDAS=OFF -DBUILD_KINSOL=OFF \
  -DEXAMPLES_ENABLE_C=OFF -DEXAMPLES_ENABLE_CXX=OFF -DEXAMPLES_INSTALL=OFF > "$work/configure.log" 2>&1 ||
  { tail -30 "$work/configure.log" >&2; exit 1; }
cmake --build "$src/build" -j"${JOBS:-2}" > "$work/build.log" 2>&1 ||
  { tail -30 "$work/build.log" >&2; exit 1; }
cmake --install "$src/build" > "$work/install.log" 2>&1 || { tail -30 "$work/install.log" >&2; exit 1; }
rm -rf "$src"
echo "SUNDIALS $version ($flags) installed in $prefix"
