#!/usr/bin/env bash
# Installs dependencies, builds CEODE and runs every test: once optimised, once
# under AddressSanitizer + UndefinedBehaviorSanitizer (Debian's SUNDIALS 6.4), then
# optimised against SUNDIALS 7.5.0 (scripts/test_sundials7.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
jobs=$(nproc)
# The Release leg also builds and tests the Python module (Debian's python3, label python).
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DCEODE_BUILD_TESTS=ON -DCEODE_BUILD_BENCHMARKS=ON \
  -DCEODE_BUILD_PYTHON=ON -DPython3_EXECUTABLE=/usr/bin/python3
cmake --build build -j"$jobs"
(cd build && ctest --output-on-failure -j"$jobs")
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug -DCEODE_SANITIZE=ON -DCEODE_BUILD_TESTS=ON \
  -DCEODE_BUILD_BENCHMARKS=OFF -DCEODE_BUILD_PYTHON=OFF
cmake --build build-asan -j"$jobs"
(cd build-asan && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
   ctest --output-on-failure -j"$jobs" -LE slow)
# Second leg: the same suite against SUNDIALS 7.5.0 built from ../shared/third_party.
bash scripts/test_sundials7.sh
