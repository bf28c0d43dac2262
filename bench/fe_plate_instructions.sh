#!/usr/bin/env bash
# Work per step of the FE plate's scaling part, counted by callgrind (not a timing): instructions
# and simulated last-level-cache misses per step and DOF of the hand loop and CEODE G3_CD, G4_A34,
# G5_O4 on the 4 ny x ny meshes of wp_fe_plate's part 3, and the log-log slope of instructions per
# step against N. Each figure is the difference of two runs (S1 and S2 steps after the same set-up,
# `wp_fe_plate --count`) divided by S2 - S1, so creation and the start cancel.
#
# Why: issue 11 asks for time per step linear in N (slope 1.0 +- 0.05 from 10^4 to 10^6). Timed,
# every solver on this machine, the hand loop too, comes out near 1.2 (docs/results.md). These
# counts separate the work (instructions, which a library could add) from the memory system
# (misses, which the working set brings at 10^6 whoever runs the loop).
#
#   bench/fe_plate_instructions.sh BUILD_DIR [NY ...]     default NY: 35 112 354 (10^4 .. 10^6 DOF)
# Needs valgrind. Took about 8 minutes for NY = 35 354 (session 11). The simulated misses follow
# the cache that valgrind reads from cpuid; a VM that reports the host's whole L3 (512 MB here) gives
# none at any size, so read them only where that size is real (or pass --LL= by hand).
set -euo pipefail
bin=$1/bench/wp_fe_plate
shift
nys=("$@")
[ ${#nys[@]} -gt 0 ] || nys=(35 112 354)
command -v valgrind > /dev/null || { echo "valgrind not found (apt-get install valgrind)"; exit 1; }
[ -x "$bin" ] || { echo "$bin not built (cmake --build $(dirname "$bin")/.. --target wp_fe_plate)"; exit 1; }

# Prints "Ir LLmisses" of one run: solver ny steps
count() {
  local out
  out=$(valgrind --tool=callgrind --cache-sim=yes --callgrind-out-file=/dev/null \
    "$bin" --count "$1" "$2" "$3" 2>&1) || { echo "run failed: $1 $2 $3" >&2; echo "$out" >&2; exit 1; }
  # Events: Ir Dr Dw I1mr D1mr D1mw ILmr DLmr DLmw
  echo "$out" | sed -n 's/.*Collected : //p' | awk '{print $1, $8 + $9}'
}

valgrind --tool=callgrind --cache-sim=yes --callgrind-out-file=/dev/null "$bin" --count hand 4 1 \
  2>&1 | grep -iE 'cache|LL' | sed 's/^==[0-9]*== */simulated: /' || true
printf '%9s %-7s %16s %16s\n' DOF solver "instr/(DOF step)" "LL miss/(DOF st)"
declare -A first_ir last_ir
for ny in "${nys[@]}"; do
  dof=$(( 2 * 4 * ny * (ny + 1) ))
  if [ "$dof" -ge 500000 ]; then s1=2 s2=6; elif [ "$dof" -ge 50000 ]; then s1=5 s2=15; else s1=20 s2=60; fi
  for solver in hand G3_CD G4_A34 G5_O4; do
    read -r ir1 ll1 <<< "$(count "$solver" "$ny" "$s1")"
    read -r ir2 ll2 <<< "$(count "$solver" "$ny" "$s2")"
    ir=$(awk -v a="$ir1" -v b="$ir2" -v s="$(( s2 - s1 ))" 'BEGIN {printf "%.6e", (b - a) / s}')
    ll=$(awk -v a="$ll1" -v b="$ll2" -v s="$(( s2 - s1 ))" 'BEGIN {printf "%.6e", (b - a) / s}')
    awk -v n="$dof" -v sv="$solver" -v ir="$ir" -v ll="$ll" \
      'BEGIN {printf "%9d %-7s %16.3f %16.4f\n", n, sv, ir / n, ll / n}'
    key=$solver
    if [ -z "${first_ir[$key]:-}" ]; then
      first_ir[$key]="$dof $ir"
    else
      last_ir[$key]="$dof $ir"
    fi
  done
done
[ ${#nys[@]} -ge 2 ] || exit 0
printf 'log-log slope of instructions per step against N (%s to %s DOF):' \
  "$(echo "${first_ir[hand]}" | cut -d' ' -f1)" "$(echo "${last_ir[hand]}" | cut -d' ' -f1)"
for solver in hand G3_CD G4_A34 G5_O4; do
  read -r n0 i0 <<< "${first_ir[$solver]}"
  read -r n1 i1 <<< "${last_ir[$solver]}"
  awk -v s="$solver" -v n0="$n0" -v n1="$n1" -v i0="$i0" -v i1="$i1" \
    'BEGIN {printf " %s %.3f", s, log(i1 / i0) / log(n1 / n0)}'
done
echo
