#!/usr/bin/env python3
"""What a Python right-hand side costs beyond its own arithmetic: CEODE's ns per step against
solve_ivp's ns per evaluation, on the same f (the pendulum of problem_pendulum.py, n = 1, where
the arithmetic is one cosine and the call machinery is nearly everything).

f's arithmetic: the median ns of one direct call f(t, x, v, out) from a Python loop minus that of
a function with f's signature and an empty body in the same loop (the loop and the call itself
are machinery, the body is f's own work). CEODE (fixed step, guard off, f declared velocity-
independent) and solve_ivp (RK45, DOP853 on harness.first_order(f)) integrate 10 s; each run's
CPU time minus (f evaluations x f's arithmetic) is the machinery: per CEODE step and evaluation,
per solve_ivp evaluation, and for solve_ivp also beyond its first-order wrapper called directly
(the last column: solve_ivp's own per-evaluation cost).
Writes <out>/python_callback.csv and prints the table.

Usage: callback_overhead.py [--out DIR] [--quick]
--quick: fewer direct calls of f to time it alone.
"""
import argparse
import os
import sys

import numpy as np

import harness as H
import problem_pendulum

FIELDS = ["solver", "config", "steps", "rhs_evals", "seconds", "f_ns", "call_ns", "wrapper_ns",
          "overhead_ns_per_step", "overhead_ns_per_eval", "overhead_ns_per_eval_beyond_wrapper"]


def call_ns(fn, args, calls=20000):
    """Median ns of one direct call fn(*args), over repetitions of `calls` calls."""
    def loop():
        for _ in range(calls):
            fn(*args)
    sec, _, _ = H.time_median(loop, reps=7)
    return 1e9 * sec / calls


def line(solver, config, out, sec, ns):
    calls = out.python_calls  # CEODE: the module's count of f's calls; solve_ivp: nfev
    beyond = 1e9 * sec - calls * ns["f"]
    wrapper = (1e9 * sec - calls * ns["wrapper"]) / calls if solver != "CEODE" else None
    return {"solver": solver, "config": config, "steps": out.steps, "rhs_evals": calls,
            "seconds": f"{sec:.6e}", "f_ns": f"{ns['f']:.1f}", "call_ns": f"{ns['call']:.1f}",
            "wrapper_ns": f"{ns['wrapper']:.1f}",
            "overhead_ns_per_step": f"{beyond / out.steps:.1f}",
            "overhead_ns_per_eval": f"{beyond / calls:.1f}",
            "overhead_ns_per_eval_beyond_wrapper": f"{wrapper:.1f}" if wrapper is not None else ""}


def nop(t, x, v, out):
    """f's signature, no body: the cost of the Python call alone."""


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=".")
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    import ceode
    p = problem_pendulum.Problem()
    H.reference(p)
    x, v, out = np.array([0.3]), np.zeros(1), np.zeros(1)
    calls = 5000 if args.quick else 20000
    call_ns_ = call_ns(nop, (0.0, x, v, out), calls)
    ns = {"call": call_ns_, "f": max(call_ns(p.f2, (0.0, x, v, out), calls) - call_ns_, 0.0),
          "wrapper": call_ns(p.f1, (0.0, np.array([0.3, 0.0])), calls)}
    lines = []
    for method, h in (("G4_A34", 1e-3), ("G8_O8", 1e-2)):
        sec, _, o = H.time_median(lambda: H.ceode_run(ceode, p, method, h=h))
        lines.append(line("CEODE", f"{method} h={h:g}", o, sec, ns))
    for method in ("RK45", "DOP853"):
        for rtol in (1e-6, 1e-10):
            sec, _, o = H.time_median(lambda: H.scipy_run(p, method, rtol)[0])
            o.steps = H.scipy_steps(p, method, rtol)
            lines.append(line("scipy solve_ivp", f"{method} rtol={rtol:g}", o, sec, ns))
    path = os.path.join(args.out, "python_callback.csv")
    H.write_csv(path, lines, FIELDS)
    print(f"pendulum f: {ns['f']:.0f} ns of arithmetic beyond a {ns['call']:.0f} ns call from a "
          f"Python loop; its first-order wrapper for solve_ivp (f inside): {ns['wrapper']:.0f} ns")
    print(f"{'solver':<16} {'config':<18} {'steps':>7} {'f evals':>8} {'ns/step':>9} "
          f"{'ns/eval':>9} {'ns/eval beyond wrapper':>23}   (beyond f's arithmetic)")
    for r in lines:
        print(f"{r['solver']:<16} {r['config']:<18} {r['steps']:>7} {r['rhs_evals']:>8} "
              f"{r['overhead_ns_per_step']:>9} {r['overhead_ns_per_eval']:>9} "
              f"{r['overhead_ns_per_eval_beyond_wrapper'] or '-':>23}")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
