#!/bin/sh
# Instructions of CEODE on the pendulum of bench/wp_high_order (n = 1, guard off), counted by
# callgrind (not a timing): the fixed cost of one whole run (create, init, start, free) and the
# cost per step, from three counts: 1 step x 1 run, 1 step x 11 runs, 842 steps x 1 run.
#   bench/high_order_instructions.sh BUILD_DIR [METHOD[+comp]]...   e.g.  build G8_O8 G8_O8+comp
set -e
bin=$1/bench/wp_high_order
shift
count() {  # method steps runs [comp]
  valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bin" --count "$@" 2>&1 |
    sed -n 's/.*Collected : \([0-9]*\).*/\1/p'
}
for mc in "$@"; do
  m=${mc%+comp}
  c=
  [ "$m" != "$mc" ] && c=comp
  a=$(count "$m" 1 1 $c)
  r=$(count "$m" 1 11 $c)
  s=$(count "$m" 842 1 $c)
  printf '%-11s fixed per run %8d instructions, per step %5d instructions\n' "$mc" \
    $(((r - a) / 10)) $(((s - a) / 841))
done
