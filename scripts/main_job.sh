#!/usr/bin/env bash
# The main job: every work-precision scene, CEODE side by side with ARKODE,
# CVODE and IDA, from a clean checkout to docs/results/ in one command.
#
#   scripts/main_job.sh            # deps, Release build in ./build, all scenes, plots, ratios
#
# Steps: scripts/install_deps.sh; pick a Python that imports matplotlib (after
# the install, so that a fresh machine's first run draws the plots too);
# configure and build (Release, ./build) the bench programs; run every scene
# (run_all_scenes: one progress line per scene, its table saved as
# docs/results/<scene>.txt, its rows as docs/results/<scene>.csv): each
# bench/wp_<name> program is scene <name> (wp_chain_dae is chain_dae_wp) and
# bench/chain_scaling is chain_dae (time per step against N, CEODE only); the
# per-step Google Benchmark; one log-log work-precision plot per scene (PNG +
# SVG; scripts/plot_dae.py draws pendulum_dae and the chain's N-scaling); the
# CEODE / best-SUNDIALS time ratios at equal error for every work-precision
# scene (docs/results/ratios.csv; the N-scaling CSV has no SUNDIALS curve and
# is left out).
# Then, when ../shared/third_party/sundials-6.4.1-src.tar.xz is present (or
# SUNDIALS_O3_PREFIX names an install), the same scenes against SUNDIALS 6.4.1
# built -O3 (scripts/build_sundials.sh, prefix ./build/sundials-6.4.1-O3), with
# CEODE rebuilt on it in ./build/o3: outputs docs/results/<scene>_o3.*, and
# ratios.csv gets one row per build (sundials_build column).
# Then, when the Python module is configured (pybind11 found), the Python benchmarks of
# bench/python/ and examples/python/plate_tip.py: docs/results/python_*.{csv,txt,png}.
# Exit code: 0 when every step and every scene's own checks passed.
# Environment: JOBS (build parallelism, default 2), PYTHON (needs matplotlib),
# SUNDIALS_O3_PREFIX (an existing -O3 SUNDIALS 6.4.1 install, e.g. /opt/sundials-6.4.1-O3).
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
OUT=$ROOT/docs/results
BUILD=$ROOT/build
JOBS=${JOBS:-2}
T0=$(date +%s)
status=0
elapsed() { echo $(( $(date +%s) - T0 )); }
step() { printf '[main_job %4ss] %s\n' "$(elapsed)" "$*"; }

step "dependencies (scripts/install_deps.sh)"
scripts/install_deps.sh || { echo "install_deps.sh failed"; exit 1; }

# Debian's python3 carries python3-matplotlib (just installed if it was
# missing); a pyenv/venv python3 earlier on PATH may not, so the first
# interpreter that really imports matplotlib is used.
if [ -z "${PYTHON:-}" ]; then
  for PYTHON in /usr/bin/python3 python3 ""; do
    [ -n "$PYTHON" ] && "$PYTHON" -c 'import matplotlib' 2>/dev/null && break
  done
fi
if [ -z "$PYTHON" ] || ! "$PYTHON" -c 'import matplotlib' 2>/dev/null; then
  echo "no python3 that imports matplotlib (set PYTHON=...); plots and ratios would fail"
  exit 1
fi
step "python: $PYTHON"

step "configure Release in ./build"
# Python3_EXECUTABLE: the Python module (when pybind11 is found) is built for the interpreter
# that runs the plots and the Python benchmarks.
cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DCEODE_BUILD_TESTS=ON -DCEODE_BUILD_BENCHMARKS=ON \
  -DPython3_EXECUTABLE="$(command -v "$PYTHON")" > "$BUILD.configure.log" 2>&1 || { cat "$BUILD.configure.log"; exit 1; }
rm -f "$BUILD.configure.log"

# Only what the job runs: the bench programs (the unit tests and the examples
# are scripts/test.sh's business).
targets=()
for src in bench/*/wp_*.cpp; do
  [ -e "$src" ] && targets+=("$(basename "${src%.*}")")
done
targets+=(chain_scaling)
[ -e bench/step_cost/bench_step.cpp ] && targets+=(bench_step)
step "build (${targets[*]})"
if ! cmake --build "$BUILD" -j"$JOBS" --target "${targets[@]}" > "$BUILD/main_job_build.log" 2>&1; then
  tail -40 "$BUILD/main_job_build.log"
  echo "build failed (log: $BUILD/main_job_build.log)"
  exit 1
fi

mkdir -p "$OUT"
scenes=()
run_scene() {  # name, executable, extra arguments
  local name=$1 exe=$2 t1 rc
  shift 2
  t1=$(date +%s)
  step "scene $name ..."
  "$exe" --csv "$OUT/$name.csv" "$@" > "$OUT/$name.txt" 2> "$OUT/$name.stderr.txt"
  rc=$?
  [ -s "$OUT/$name.stderr.txt" ] || rm -f "$OUT/$name.stderr.txt"
  if [ $rc -eq 0 ]; then
    step "scene $name done in $(( $(date +%s) - t1 )) s: $(grep -c . "$OUT/$name.csv") CSV lines"
  else
    step "scene $name FAILED its checks (exit $rc) after $(( $(date +%s) - t1 )) s; see $OUT/$name.txt"
    status=1
  fi
  scenes+=("$OUT/$name.csv")
}
# Every scene and the per-step benchmark of one build dir; outputs <scene><suffix>.*
run_build() {  # build dir, suffix
  local bd=$1 sfx=$2 t name
  for t in "${targets[@]}"; do
    case $t in
      wp_chain_dae) name=chain_dae_wp ;;
      wp_high_order) continue ;;  # its own schema and plot: run once below
      # The FE variants take minutes each (implicit SUNDIALS curves at 3 360 DOF): run them in
      # the -O3 half only, the headline, when that half runs.
      wp_fe_nonlinear | wp_fe_damped_*) [ -z "$sfx" ] && [ "$O3_WILL_RUN" = 1 ] && continue
        name=${t#wp_} ;;
      wp_*) name=${t#wp_} ;;
      chain_scaling) name=chain_dae ;;
      *) continue ;;
    esac
    run_scene "$name$sfx" "$bd/bench/$t"
  done
  if [ -x "$bd/bench/bench_step" ]; then
    step "per-step cost$sfx (Google Benchmark, median of 11, repetitions interleaved at random)"
    if ! "$bd/bench/bench_step" --benchmark_min_time=0.05 --benchmark_repetitions=11 \
        --benchmark_enable_random_interleaving=true \
        --benchmark_report_aggregates_only=true --benchmark_out="$OUT/bench_step$sfx.json" \
        --benchmark_out_format=json > "$OUT/bench_step$sfx.txt" 2>&1; then
      step "bench_step$sfx FAILED"
      status=1
    fi
    grep -E '_median' "$OUT/bench_step$sfx.txt" | sed 's/^/    /'
  fi
}
O3_WILL_RUN=0
if [ -e "${SUNDIALS_O3_PREFIX:-$BUILD/sundials-6.4.1-O3}/lib/cmake/sundials/SUNDIALSConfig.cmake" ] ||
    [ -e "$ROOT/../shared/third_party/sundials-6.4.1-src.tar.xz" ]; then
  O3_WILL_RUN=1
fi
run_build "$BUILD" ""

# ---- wp_high_order ---------------------------------------------------------------------------
# CEODE's high-degree sets against the order-8 integrators users pick outside
# SUNDIALS (GSL rk8pd, Boost.Odeint rkf78 and Bulirsch-Stoer; ARKODE ERK 8).
# Run on both builds: outputs wp_high_order.* and, on the -O3 SUNDIALS build, wp_high_order_o3.*
high_order() {  # build dir, suffix
  local bd=$1 sfx=$2 n=wp_high_order$2
  [ -x "$bd/bench/wp_high_order" ] || return
  step "scene $n ..."
  if "$bd/bench/wp_high_order" --csv "$OUT/$n.csv" > "$OUT/$n.txt" 2>&1; then
    "$PYTHON" scripts/plot_wp_high_order.py "$OUT/$n.csv" "$OUT/$n.png" || status=1
    step "scene $n done"
  else
    step "scene $n FAILED its checks; see $OUT/$n.txt"
    status=1
  fi
}
high_order "$BUILD" ""
# ---- end wp_high_order ----------------------------------------------------------------------

# The same scenes against SUNDIALS 6.4.1 built -O3 (Debian's package is -O0):
# CEODE and the scenes are configured again on it, so CEODE's own N_Vector
# calls go through the optimised build too. SUNDIALS_O3_PREFIX may point at an
# existing install; else scripts/build_sundials.sh builds one under ./build.
O3_PREFIX=${SUNDIALS_O3_PREFIX:-$BUILD/sundials-6.4.1-O3}
O3_BUILD=$BUILD/o3
o3_note="SUNDIALS -O3: not run (no ../shared/third_party/sundials-6.4.1-src.tar.xz and no prefix)"
if [ -e "$O3_PREFIX/lib/cmake/sundials/SUNDIALSConfig.cmake" ] ||
    [ -e "$ROOT/../shared/third_party/sundials-6.4.1-src.tar.xz" ]; then
  step "SUNDIALS 6.4.1 -O3 in $O3_PREFIX (scripts/build_sundials.sh)"
  if scripts/build_sundials.sh 6.4.1 "$O3_PREFIX" "-O3" &&
      cmake -S "$ROOT" -B "$O3_BUILD" -DCMAKE_BUILD_TYPE=Release -DCEODE_BUILD_TESTS=ON -DCEODE_BUILD_BENCHMARKS=ON \
        -DCMAKE_PREFIX_PATH="$O3_PREFIX" > "$BUILD/main_job_o3.log" 2>&1 &&
      cmake --build "$O3_BUILD" -j"$JOBS" --target "${targets[@]}" >> "$BUILD/main_job_o3.log" 2>&1; then
    run_build "$O3_BUILD" _o3
    high_order "$O3_BUILD" _o3
    o3_note="SUNDIALS -O3: every scene also run against $O3_PREFIX (outputs *_o3.*)"
  else
    step "SUNDIALS -O3 build FAILED (log: $BUILD/main_job_o3.log)"
    o3_note="SUNDIALS -O3: build FAILED, see $BUILD/main_job_o3.log"
    status=1
  fi
fi
step "$o3_note"

# ---- MPI (docs/mpi.md) ---------------------------------------------------------------------
# Two partitioned models on NVECTOR_PARALLEL at N = 10^6, halo exchange in f, against
# NVECTOR_SERIAL: the membrane (bench/mpi_membrane: one row strip per rank) and the Q4 plate of
# wp_fe_plate (bench/mpi_fe_plate: one block of node columns per rank). Bitwise equality (the
# program's own check, exit 1 when it fails) and the 1 -> 2 rank speedup, measured side by side
# in one `mpiexec -n 2` run each (the 1-rank runs happen on rank 0 while rank 1 sleeps; 200 steps,
# best of 3, interleaved). Outputs docs/results/mpi_scaling.{csv,txt} (membrane) and
# mpi_fe_plate.{csv,txt}, and *_o3.* on the -O3 SUNDIALS build.
# Not run (and not a failure) when there is no mpiexec or the build has no MPI/nvecparallel.
mpi_scene() {  # build dir, suffix, program, output name
  local bd=$1 sfx=$2 prog=$3 name=$4 t1
  if ! cmake --build "$bd" -j"$JOBS" --target "$prog" >> "$BUILD/main_job_mpi.log" 2>&1; then
    step "$name$sfx: $prog not built (no MPI or nvecparallel? $BUILD/main_job_mpi.log)"
    return
  fi
  t1=$(date +%s)
  step "scene $name$sfx (mpiexec -n 2, N = 10^6) ..."
  if OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 \
      mpiexec -n 2 "$bd/bench/$prog" --n 1000000 --steps 200 --reps 3 \
      --csv "$OUT/$name$sfx.csv" > "$OUT/$name$sfx.txt" 2>&1; then
    step "scene $name$sfx done in $(( $(date +%s) - t1 )) s: $(grep -E '^speedup' "$OUT/$name$sfx.txt")"
  else
    step "scene $name$sfx FAILED its checks after $(( $(date +%s) - t1 )) s; see $OUT/$name$sfx.txt"
    status=1
  fi
}
mpi_scaling() {  # build dir, suffix
  mpi_scene "$1" "$2" mpi_membrane mpi_scaling
  mpi_scene "$1" "$2" mpi_fe_plate mpi_fe_plate
}
if command -v mpiexec > /dev/null; then
  mpi_scaling "$BUILD" ""
  if [ -f "$O3_BUILD/CMakeCache.txt" ]; then mpi_scaling "$O3_BUILD" _o3; fi
else
  step "mpi_scaling: no mpiexec, not run"
fi
# ---- end MPI --------------------------------------------------------------------------------

# ---- MRI inner cost (docs/porting.md "CEODE inside ARKODE") ---------------------------------
# CEODE against ARKStep RK4 as MRIStep's inner stepper at equal error, omega = 10 and 100 on the
# slow manifold and omega = 100 with the fast mode excited, in one run (bench/mri_inner_cost
# equal-error): fast f evaluations are exact counts, not timings, so one run per build. Its own
# checks (exit 1 when one fails): RK4 and a CEODE set reach the target, the guard's estimate is
# omega in <= 3 evaluations and leaves the integration unchanged, the reference order where
# H omega <= 2. Outputs docs/results/mri_inner_cost.{txt,csv}, and
# mri_inner_cost_o3.* on the -O3 SUNDIALS build.
mri_inner_cost() {  # build dir, suffix
  local bd=$1 sfx=$2 t1
  if ! cmake --build "$bd" -j"$JOBS" --target mri_inner_cost >> "$BUILD/main_job_mri.log" 2>&1; then
    step "mri_inner_cost$sfx: build FAILED (log: $BUILD/main_job_mri.log)"
    status=1
    return
  fi
  t1=$(date +%s)
  step "scene mri_inner_cost$sfx (equal error, omega = 10 and 100 on the slow manifold, 100 excited) ..."
  if "$bd/bench/mri_inner_cost" equal-error --csv "$OUT/mri_inner_cost$sfx.csv" \
      > "$OUT/mri_inner_cost$sfx.txt" 2>&1; then
    step "scene mri_inner_cost$sfx done in $(( $(date +%s) - t1 )) s: $(grep -E '^# omega [0-9]+, A [0-9.]+: best' "$OUT/mri_inner_cost$sfx.txt" | tr '\n' ' ')"
  else
    step "scene mri_inner_cost$sfx FAILED its checks after $(( $(date +%s) - t1 )) s; see $OUT/mri_inner_cost$sfx.txt"
    status=1
  fi
}
mri_inner_cost "$BUILD" ""
if [ -f "$O3_BUILD/CMakeCache.txt" ]; then mri_inner_cost "$O3_BUILD" _o3; fi
# ---- end MRI inner cost ----------------------------------------------------------------------

# ---- Python (bench/python/README.md) ---------------------------------------------------------
# When ./build has the Python module (CEODE_BUILD_PYTHON: on when pybind11 and NumPy are found):
# the structural path against the C scene on the same plate at ~10^5 DOF
# (bench/fe_plate_c_scene), a Python right-hand side's overhead against solve_ivp's, work-precision
# against solve_ivp RK45 and DOP853 on the pendulum and the FPU chain, and the example
# examples/python/plate_tip.py (its own check). Outputs docs/results/python_*.{csv,txt,png};
# about two minutes. Not run (and not a failure) when the module is not configured.
py_run() {  # name, script and arguments
  local name=$1 t1
  shift
  t1=$(date +%s)
  step "python $name ..."
  if PYTHONPATH=$BUILD/python "$PYTHON" "$@" > "$OUT/python_$name.txt" 2>&1; then
    step "python $name done in $(( $(date +%s) - t1 )) s"
  else
    step "python $name FAILED after $(( $(date +%s) - t1 )) s; see $OUT/python_$name.txt"
    status=1
  fi
}
python_benches() {
  if ! grep -q '^CEODE_BUILD_PYTHON:BOOL=ON' "$BUILD/CMakeCache.txt" 2>/dev/null; then
    step "python: the module is not configured (pybind11 or NumPy missing), benchmarks not run"
    return
  fi
  if ! cmake --build "$BUILD" -j"$JOBS" --target ceode_python fe_plate_c_scene \
      > "$BUILD/main_job_python.log" 2>&1 ||
      ! PYTHONPATH=$BUILD/python "$PYTHON" -c 'import ceode, scipy' >> "$BUILD/main_job_python.log" 2>&1; then
    step "python: module build or import FAILED (log: $BUILD/main_job_python.log)"
    status=1
    return
  fi
  py_run structural bench/python/structural_cost.py --c-scene "$BUILD/bench/fe_plate_c_scene" --out "$OUT"
  py_run callback bench/python/callback_overhead.py --out "$OUT"
  py_run work_precision bench/python/work_precision.py --out "$OUT"
  py_run example examples/python/plate_tip.py --out "$OUT/python_plate_tip.png"
}
python_benches
# ---- end Python ------------------------------------------------------------------------------

step "plots"
mine=()
dae=()
wp=()
for c in "${scenes[@]}"; do
  case $(basename "$c") in
    chain_dae.csv | chain_dae_o3.csv) dae+=("$c") ;;  # N-scaling: plot_dae.py only
    pendulum_dae*.csv | chain_dae_wp*.csv) dae+=("$c"); mine+=("$c") ;;
    *) mine+=("$c") ;;
  esac
  # chain_dae.csv is the N-scaling study (CEODE only): no ratio to compute
  case $(basename "$c") in chain_dae.csv | chain_dae_o3.csv) ;; *) wp+=("$c") ;; esac
done
# Work-precision figures of every scene (panels of <= 10 curves, scripts/plot_style.py)
if ((${#mine[@]})); then "$PYTHON" scripts/plot_results.py "${mine[@]}" || status=1; fi
# pendulum_dae and chain_dae_wp: constraint drift against cost; chain_dae: time per step against N
if ((${#dae[@]})); then "$PYTHON" scripts/plot_dae.py --outdir "$OUT" "${dae[@]}" || status=1; fi
# Charts from every scene and docs/data/ (each skips what is absent): speed ratios at equal
# error, long-run energy error against time, order against stability limit for every set
# (orders and limits from ./build/libceode.so, written to docs/data/set_summary.csv)
"$PYTHON" scripts/plot_summary.py --results "$OUT" --out "$OUT/summary_ratios.png" || status=1
"$PYTHON" scripts/plot_long_run.py --out "$OUT/long_run_energy.png" || status=1
"$PYTHON" scripts/plot_which_set.py --lib "$BUILD/libceode.so" --out "$OUT/which_set.png" || status=1

step "ratios at equal error"
"$PYTHON" scripts/ratios.py --out "$OUT/ratios.csv" --scene-levels fe_=1e-4,1e-6 \
  --scene-levels fpu_chain=1e-6,1e-8,1e-10 "${wp[@]}" ||
  status=1
# docs/results.md's summary table, regenerated from ratios.csv
"$PYTHON" scripts/summary_table.py "$OUT/ratios.csv" --out "$OUT/summary.md" > /dev/null || status=1

echo
for c in "${scenes[@]}"; do
  n=$(basename "$c" .csv)
  printf '%-18s %s\n' "$n" "$(grep -E 'Table 7|G5 at h|problem|checks off|[0-9]+ checks,|work-precision:' "$OUT/$n.txt" | tr '\n' ' ')"
done
echo "$o3_note"
# ---- results page (docs/results.md) ---------------------------------------------------------
# How this run was made (docs/results/run_info.json: commit, dates, machine, compiler and flags,
# SUNDIALS builds, command, repetitions), then docs/results.md regenerated from docs/results/ by
# scripts/results_page.py. Nothing in results.md is edited by hand.
run_info() {
  local cache=$BUILD/CMakeCache.txt cxx sdir pkg o3v=""
  cxx=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$cache" 2>/dev/null)
  sdir=$(sed -n 's/^SUNDIALS_DIR:[A-Z]*=//p' "$cache" 2>/dev/null)
  pkg=$(dpkg-query -W -f='libsundials-dev ${Version}' libsundials-dev 2>/dev/null || echo "system SUNDIALS")
  [ -e "$O3_PREFIX/lib/cmake/sundials/SUNDIALSConfigVersion.cmake" ] &&
    o3v=$(sed -n 's/^set(PACKAGE_VERSION "\(.*\)")/\1/p' "$O3_PREFIX/lib/cmake/sundials/SUNDIALSConfigVersion.cmake")
  RI_COMMIT="$(git rev-parse --short HEAD 2>/dev/null)$( [ -n "$(git status --porcelain -- src include bench 2>/dev/null)" ] && echo ' (with local changes)')" \
  RI_START=$(date -u -d "@$T0" '+%F %H:%M') RI_END=$(date -u '+%F %H:%M') RI_SECONDS=$(elapsed) RI_EXIT=$status \
  RI_MACHINE="$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -1) (family $(lscpu 2>/dev/null | sed -n 's/^CPU family: *//p' | head -1)), $(nproc) CPUs$(lscpu 2>/dev/null | grep -q '^Hypervisor' && echo ', virtual machine')" \
  RI_OS="$(. /etc/os-release 2>/dev/null && echo "$PRETTY_NAME")" \
  RI_COMPILER="$("${cxx:-c++}" --version 2>/dev/null | head -1)" \
  RI_FLAGS="CMAKE_BUILD_TYPE=$(sed -n 's/^CMAKE_BUILD_TYPE:[A-Z]*=//p' "$cache") ($(sed -n 's/^CMAKE_CXX_FLAGS_RELEASE:[A-Z]*=//p' "$cache"))" \
  RI_PKG="$(sed -n 's/^set(PACKAGE_VERSION "\(.*\)")/\1/p' "$sdir/SUNDIALSConfigVersion.cmake" 2>/dev/null), $pkg, compiled ${SUNDIALS_PACKAGE_FLAGS:--O0}" \
  RI_O3="$( [ -n "$o3v" ] && [ -f "$O3_BUILD/CMakeCache.txt" ] && echo "$o3v from the source tarball, Release, C flags -O3 (scripts/build_sundials.sh, $O3_PREFIX); CEODE rebuilt on it" || echo "not run")" \
  RI_COMMAND="$( [ -n "${SUNDIALS_O3_PREFIX:-}" ] && echo "SUNDIALS_O3_PREFIX=$SUNDIALS_O3_PREFIX ")scripts/main_job.sh" \
  "$PYTHON" - "$OUT/run_info.json" <<'PY'
import json, os, sys
e = os.environ.get
info = {"commit": e("RI_COMMIT"), "start": e("RI_START"), "end": e("RI_END"),
        "seconds": int(e("RI_SECONDS")), "exit": int(e("RI_EXIT")), "machine": e("RI_MACHINE"),
        "os": e("RI_OS"), "compiler": e("RI_COMPILER"), "ceode_flags": e("RI_FLAGS"),
        "sundials_o3": e("RI_O3"), "sundials_package": e("RI_PKG"), "command": e("RI_COMMAND"),
        "repetitions": "work-precision points: median of 5 repetitions of at least 50 ms (3 from "
                       "0.5 s, 1 from 2 s), FE scenes in interleaved rounds; per-step benchmark: "
                       "median of 11, interleaved at random; MPI: best of 3"}
with open(sys.argv[1], "w") as f:
    json.dump(info, f, indent=2, ensure_ascii=False)
    f.write("\n")
PY
}
step "results page (docs/results/run_info.json, docs/results.md)"
run_info || status=1
"$PYTHON" scripts/results_page.py --results "$OUT" --out "$ROOT/docs/results.md" || status=1
# ---- end results page -----------------------------------------------------------------------
step "total $(elapsed) s; results in docs/results/ (exit $status)"
exit $status
