#!/bin/sh
# Instructions per step of each bench_step variant, counted by callgrind (not a timing):
# the difference of two runs (S1 and S2 steps after the same set-up) divided by S2 - S1.
#   bench/step_instructions.sh BUILD_DIR [METHOD N]...   e.g.  build G3_CD 1 G8_O8 1 G3_CD 10000
set -e
bin=$1/bench/bench_step
shift
count() {  # variant method n steps
  valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bin" --count "$@" 2>&1 |
    sed -n 's/.*Collected : \([0-9]*\).*/\1/p'
}
while [ $# -ge 2 ]; do
  m=$1 n=$2
  shift 2
  if [ "$n" -ge 100000 ]; then s1=2 s2=12; elif [ "$n" -ge 1000 ]; then s1=20 s2=120; else s1=1000 s2=11000; fi
  for v in ceode ceode_1step hand_fpass hand_fused; do
    a=$(count $v "$m" "$n" $s1)
    b=$(count $v "$m" "$n" $s2)
    printf '%-7s n=%-8s %-12s %12.1f instructions/step\n' "$m" "$n" "$v" \
      "$(echo "($b - $a) / ($s2 - $s1)" | bc -l)"
  done
done
