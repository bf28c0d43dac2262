#!/bin/sh
# CEODE G8_O8 against GSL rk8pd on the pendulum of bench/wp_high_order at equal theta(10) error,
# in instructions counted by callgrind (not a timing): each point's cost of one whole run as
# timed by wp_high_order (CEODE: vectors, create, init, evolve, free; rk8pd: driver alloc,
# evolve over [0, 10], free), from 11 runs minus 1 run, so that program start-up cancels.
# CEODE at 665 and 1100 steps (errors ~1e-9, ~1e-11); rk8pd at the tolerances that bracket those
# errors; the rk8pd cost at exactly 1e-9 / 1e-11 interpolated log-log in the error, as
# wp::TimeAtError does for times.   bench/high_order_vs_rk8pd.sh BUILD_DIR
set -e
bin=$1/bench/wp_high_order
ref=1.2921156532249163  # theta(10): G8_O8 +comp at 16 000 steps (wp_high_order: error < 1e-15)
count() {  # solver steps|tol runs
  valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bin" --count "$@" 2>&1 |
    sed -n 's/.*Collected : \([0-9]*\).*/\1/p'
}
point() {  # solver steps|tol -> "error instructions-per-run"
  th=$("$bin" --count "$1" "$2" 1 | sed 's/.*= //')
  a=$(count "$1" "$2" 1)
  b=$(count "$1" "$2" 11)
  awk -v t="$th" -v r="$ref" -v a="$a" -v b="$b" 'BEGIN{e=t-r; if(e<0)e=-e; printf "%.4e %d\n", e, (b-a)/10}'
}
c9=$(point G8_O8 665)
c11=$(point G8_O8 1100)
g9a=$(point gsl_rk8pd 1e-9)
g9b=$(point gsl_rk8pd 1e-10)
g11a=$(point gsl_rk8pd 1e-11)
g11b=$(point gsl_rk8pd 1e-12)
echo "G8_O8     665 steps: error instructions $c9"
echo "G8_O8    1100 steps: error instructions $c11"
echo "rk8pd tol 1e-9     : error instructions $g9a"
echo "rk8pd tol 1e-10    : error instructions $g9b"
echo "rk8pd tol 1e-11    : error instructions $g11a"
echo "rk8pd tol 1e-12    : error instructions $g11b"
# rk8pd at the target error (log-log between the bracketing tolerances), ratio to CEODE's point
# (CEODE's own error is within a few per cent of the target: 9.8e-10, 9.9e-12).
awk -v c9="$c9" -v c11="$c11" -v a="$g9a" -v b="$g9b" -v c="$g11a" -v d="$g11b" 'BEGIN{
  split(c9,C9," "); split(c11,C11," "); split(a,A," "); split(b,B," "); split(c,Cc," "); split(d,D," ");
  f9=log(A[1]/1e-9)/log(A[1]/B[1]); i9=exp(log(A[2])+f9*log(B[2]/A[2]));
  f11=log(Cc[1]/1e-11)/log(Cc[1]/D[1]); i11=exp(log(Cc[2])+f11*log(D[2]/Cc[2]));
  printf "rk8pd at error 1e-9: %d instructions, G8_O8 / rk8pd = %.3f\n", i9, C9[2]/i9;
  printf "rk8pd at error 1e-11: %d instructions, G8_O8 / rk8pd = %.3f\n", i11, C11[2]/i11}'
