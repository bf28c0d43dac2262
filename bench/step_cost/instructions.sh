#!/usr/bin/env bash
# Instruction counts of the bench programs under callgrind (not timings): each figure is the
# difference of two runs of a program's --count mode, so that start-up and set-up cancel.
#
#   bench/step_cost/instructions.sh step BUILD_DIR [METHOD N]...        bench_step: per step of each variant,
#                                                                        all and beyond f
#   bench/step_cost/instructions.sh passes BUILD_DIR METHOD             bench_step: N_Vector data passes per step
#   bench/step_cost/instructions.sh adaptive BUILD_DIR [METHOD N]...    bench_step: per accepted adaptive step
#                                                                       against the fixed step
#   bench/step_cost/instructions.sh implicit BUILD_DIR CONFIG[:SET[:normal]]...   bench_implicit_step: per step
#                                                                       of a velocity-dependent configuration
#   bench/step_cost/instructions.sh high-order BUILD_DIR [METHOD[+comp]]...   wp_high_order: per run and per step
#   bench/step_cost/instructions.sh rk8pd BUILD_DIR                     wp_high_order: G8_O8 against GSL rk8pd
#   bench/step_cost/instructions.sh fe-plate BUILD_DIR [NY ...]         wp_fe_plate: per step and DOF, and LL misses
#   bench/step_cost/instructions.sh membrane BUILD_DIR [N ...]          membrane_driver: per step, CEODE against
#                                                                       the hand leapfrog (outputs every 30 steps)
#
# Needs valgrind. The simulated last-level-cache misses (fe-plate) follow the cache valgrind reads
# from cpuid; read them only where that size is real (or pass --LL= by hand).
set -euo pipefail
mode=${1:?mode: step, passes, adaptive, implicit, high-order, rk8pd, fe-plate or membrane}
build=${2:?BUILD_DIR}
shift 2
command -v valgrind > /dev/null || { echo "valgrind not found (apt-get install valgrind)"; exit 1; }

# count PROGRAM ARGS...: "Ir" of one --count run (with CACHE=1: "Ir LLmisses").
count() {
  local bin=$build/bench/$1 out
  shift
  [ -x "$bin" ] || { echo "$bin not built" >&2; exit 1; }
  out=$(valgrind --tool=callgrind ${CACHE:+--cache-sim=yes} --callgrind-out-file=/dev/null \
    "$bin" --count "$@" 2>&1) || { echo "run failed: $bin $*" >&2; echo "$out" >&2; exit 1; }
  # Events: Ir [Dr Dw I1mr D1mr D1mw ILmr DLmr DLmw]
  echo "$out" | sed -n 's/.*Collected : //p' | awk '{ if (NF > 1) print $1, $8 + $9; else print $1 }'
}
# per A B STEPS: (B - A) / STEPS; fails (the caller's assignment, under set -e, ends the script)
# when a count is missing, as after a failed run.
per() {
  [ -n "$1" ] && [ -n "$2" ] || { echo "a count is missing (a run failed)" >&2; return 1; }
  awk -v a="$1" -v b="$2" -v s="$3" 'BEGIN {printf "%.6e", (b - a) / s}'
}

case $mode in
step)  # instructions per step of each bench_step variant: S1 and S2 steps after the same set-up,
       # and beyond f: less f_only's (the benchmark's f alone, called as often)
  while [ $# -ge 2 ]; do
    m=$1 n=$2
    shift 2
    if [ "$n" -ge 100000 ]; then s1=4 s2=12; elif [ "$n" -ge 1000 ]; then s1=20 s2=120; else s1=1000 s2=11000; fi
    f=$(per "$(count bench_step f_only "$m" "$n" $s1)" "$(count bench_step f_only "$m" "$n" $s2)" $((s2 - s1)))
    vs="ceode ceode_1step ceode_freq ceode_freq_mid hand_fpass hand_fused"
    [ "$m" = G8_O8 ] && vs="$vs hand_d8"
    for v in $vs; do
      i=$(per "$(count bench_step $v "$m" "$n" $s1)" "$(count bench_step $v "$m" "$n" $s2)" $((s2 - s1)))
      awk -v m="$m" -v n="$n" -v v="$v" -v i="$i" -v f="$f" \
        'BEGIN {printf "%-7s n=%-8s %-15s %12.1f instructions/step %12.1f beyond f\n", m, n, v, i, i - f}'
    done
  done ;;
adaptive)  # instructions per accepted step with tolerances 1e-8 (ceode_adaptive), and per fixed step
  # The window: from the first output time (1, 2, 5, 10, 20, ... fixed steps of 1e-3 ahead) after at
  # least 20 accepted steps (the start and the first step sizes behind) to the first one at least
  # W accepted steps later (W = 1000 for n < 1000, 20 otherwise); the steps are counted by a run
  # outside valgrind (the same arithmetic, the same steps).
  while [ $# -ge 2 ]; do
    m=$1 n=$2
    shift 2
    steps() { "$build/bench/bench_step" --count ceode_adaptive "$m" "$n" "$1" | sed -n 's/^steps //p'; }
    if [ "$n" -ge 1000 ]; then w=20; else w=1000; fi
    k1= k2= s1= s2=
    for k in 1 2 5 10 20 50 100 200 500 1000 2000 5000 10000 20000 50000 100000 200000; do
      s=$(steps $k)
      if [ -z "$k1" ]; then
        [ "$s" -ge 20 ] && k1=$k s1=$s
      elif [ $((s - s1)) -ge $w ]; then
        k2=$k s2=$s
        break
      fi
    done
    [ -n "$k2" ] || { echo "$m n=$n: no window of $w steps found" >&2; exit 1; }
    a=$(per "$(count bench_step ceode_adaptive "$m" "$n" $k1)" "$(count bench_step ceode_adaptive "$m" "$n" $k2)" $((s2 - s1)))
    if [ "$n" -ge 100000 ]; then f1=2 f2=12; elif [ "$n" -ge 1000 ]; then f1=20 f2=120; else f1=1000 f2=11000; fi
    f=$(per "$(count bench_step ceode "$m" "$n" $f1)" "$(count bench_step ceode "$m" "$n" $f2)" $((f2 - f1)))
    awk -v m="$m" -v n="$n" -v a="$a" -v f="$f" -v s="$((s2 - s1))" \
      'BEGIN {printf "%-7s n=%-8s adaptive %12.1f  fixed %12.1f instructions/step  ratio %.2f  (%d accepted steps)\n", m, n, a, f, a / f, s}'
  done ;;
passes)  # N_Vector operations that pass over the data, per step (callgrind's call counts)
  out=$(mktemp)
  calls() {
    valgrind --tool=callgrind --callgrind-out-file="$out" "$build/bench/bench_step" --count "$@" \
      > /dev/null 2>&1
    # calls of N_V*_Serial other than the accessors
    awk '/^c?fn=\([0-9]+\)/ { match($0, /\([0-9]+\)/); id = substr($0, RSTART, RLENGTH)
           name = substr($0, RSTART + RLENGTH + 1); if (name != "") names[id] = name
           if ($0 ~ /^cfn=/) cur = names[id] }
         /^calls=/ { split($0, c, /[= ]/)
           if (cur ~ /N_V[A-Za-z]*_Serial/ && cur !~ /GetArrayPointer|GetLength|GetVectorID|Clone|Destroy|New|Make|Space|GetCommunicator/) t += c[2] }
         END { print t + 0 }' "$out"
  }
  for v in ceode ceode_generic; do
    a=$(calls $v "$1" 1000 100)
    b=$(calls $v "$1" 1000 200)
    echo "$1 $v: $(( (b - a) / 100 )) N_Vector data operations per step"
  done
  rm -f "$out" ;;
implicit)  # bench_implicit_step per step: 2000 and 12000 steps, both started again every 1000.
  # CONFIG is "problem/name" (e.g. "top/auto"); SET replaces the problem's set; ":normal" takes
  # each block in one CE_NORMAL call instead of CE_ONE_STEP calls ("pendulum/auto:G7_O7:normal").
  bin=$build/bench/bench_implicit_step
  [ -x "$bin" ] || { echo "$bin not built" >&2; exit 1; }
  for spec in "$@"; do
    IFS=: read -r cfg set calls <<< "$spec"
    args=(--only "$cfg")
    [ -n "$set" ] && args+=(--set "$set")
    [ "$calls" = normal ] && args+=(--normal)
    ir() {
      local out
      out=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bin" "${args[@]}" \
        --steps "$1" 2>&1) || { echo "run failed: $bin ${args[*]} --steps $1" >&2; echo "$out" >&2; return 1; }
      echo "$out" | sed -n 's/.*Collected : //p'
    }
    a=$(ir 2000)
    z=$(ir 12000)
    i=$(per "$a" "$z" 10000)
    awk -v s="$spec" -v i="$i" 'BEGIN {printf "%-30s %8.1f instructions/step\n", s, i}'
  done ;;
high-order)  # fixed cost of a whole run and cost per step: 1 step x 1 run, 1 x 11, 842 x 1
  for mc in "$@"; do
    m=${mc%+comp} c=
    [ "$m" != "$mc" ] && c=comp
    a=$(count wp_high_order "$m" 1 1 $c)
    r=$(count wp_high_order "$m" 1 11 $c)
    s=$(count wp_high_order "$m" 842 1 $c)
    printf '%-11s fixed per run %8d instructions, per step %5d instructions\n' "$mc" \
      $(((r - a) / 10)) $(((s - a) / 841))
  done ;;
rk8pd)  # G8_O8 at 665 and 1100 steps against rk8pd at the tolerances bracketing their errors
  ref=1.2921156532249163  # theta(10): G8_O8 +comp at 16 000 steps (error < 1e-15)
  point() {  # solver steps|tol -> "error instructions-per-run" (11 runs minus 1 run)
    th=$("$build/bench/wp_high_order" --count "$1" "$2" 1 | sed 's/.*= //')
    awk -v t="$th" -v r="$ref" -v a="$(count wp_high_order "$1" "$2" 1)" \
      -v b="$(count wp_high_order "$1" "$2" 11)" \
      'BEGIN {e = t - r; if (e < 0) e = -e; printf "%.4e %d\n", e, (b - a) / 10}'
  }
  c9=$(point G8_O8 665) c11=$(point G8_O8 1100)
  g=() 
  for tol in 1e-9 1e-10 1e-11 1e-12; do g+=("$(point gsl_rk8pd $tol)"); echo "rk8pd tol $tol: error instructions ${g[-1]}"; done
  echo "G8_O8  665 steps: error instructions $c9"
  echo "G8_O8 1100 steps: error instructions $c11"
  # rk8pd at the target error, log-log between the bracketing tolerances (as wp::TimeAtError)
  awk -v c9="$c9" -v c11="$c11" -v a="${g[0]}" -v b="${g[1]}" -v c="${g[2]}" -v d="${g[3]}" 'BEGIN {
    split(c9, C9, " "); split(c11, C11, " "); split(a, A, " "); split(b, B, " "); split(c, C, " "); split(d, D, " ")
    i9 = exp(log(A[2]) + log(A[1] / 1e-9) / log(A[1] / B[1]) * log(B[2] / A[2]))
    i11 = exp(log(C[2]) + log(C[1] / 1e-11) / log(C[1] / D[1]) * log(D[2] / C[2]))
    printf "rk8pd at error 1e-9: %d instructions, G8_O8 / rk8pd = %.3f\n", i9, C9[2] / i9
    printf "rk8pd at error 1e-11: %d instructions, G8_O8 / rk8pd = %.3f\n", i11, C11[2] / i11 }' ;;
fe-plate)  # per step and DOF on the 4 ny x ny meshes (default 35 112 354: 10^4 .. 10^6 DOF)
  nys=("$@")
  [ ${#nys[@]} -gt 0 ] || nys=(35 112 354)
  export CACHE=1
  printf '%9s %-7s %16s %16s\n' DOF solver "instr/(DOF step)" "LL miss/(DOF st)"
  declare -A first last
  for ny in "${nys[@]}"; do
    dof=$((2 * 4 * ny * (ny + 1)))
    if [ "$dof" -ge 500000 ]; then s1=2 s2=6; elif [ "$dof" -ge 50000 ]; then s1=5 s2=15; else s1=20 s2=60; fi
    for solver in hand G3_CD G4_A34 G5_O4; do
      read -r ir1 ll1 <<< "$(count wp_fe_plate "$solver" "$ny" "$s1")"
      read -r ir2 ll2 <<< "$(count wp_fe_plate "$solver" "$ny" "$s2")"
      ir=$(per "$ir1" "$ir2" $((s2 - s1)))
      awk -v n="$dof" -v sv="$solver" -v ir="$ir" -v ll="$(per "$ll1" "$ll2" $((s2 - s1)))" \
        'BEGIN {printf "%9d %-7s %16.3f %16.4f\n", n, sv, ir / n, ll / n}'
      [ -n "${first[$solver]:-}" ] && last[$solver]="$dof $ir" || first[$solver]="$dof $ir"
    done
  done
  [ ${#nys[@]} -ge 2 ] || exit 0
  printf 'log-log slope of instructions per step against N:'
  for solver in hand G3_CD G4_A34 G5_O4; do
    read -r n0 i0 <<< "${first[$solver]}"
    read -r n1 i1 <<< "${last[$solver]}"
    awk -v s="$solver" -v n0="$n0" -v n1="$n1" -v i0="$i0" -v i1="$i1" \
      'BEGIN {printf " %s %.3f", s, log(i1 / i0) / log(n1 / n0)}'
  done
  echo ;;
membrane)  # per step at each N (default 10^5 and 10^6): 60 and 180 steps (two and six output blocks)
  ns=("$@")
  [ ${#ns[@]} -gt 0 ] || ns=(100000 1000000)
  for n in "${ns[@]}"; do
    c=$(per "$(count membrane_driver ceode "$n" 60)" "$(count membrane_driver ceode "$n" 180)" 120)
    l=$(per "$(count membrane_driver leapfrog "$n" 60)" "$(count membrane_driver leapfrog "$n" 180)" 120)
    awk -v n="$n" -v c="$c" -v l="$l" \
      'BEGIN {printf "membrane N=%-8s ceode %14.1f  leapfrog %14.1f instructions/step  ratio %.3f\n", n, c, l, c / l}'
  done ;;
*) echo "unknown mode $mode (step, passes, adaptive, implicit, high-order, rk8pd, fe-plate, membrane)"; exit 2 ;;
esac
