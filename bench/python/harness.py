"""The one harness of the Python benchmarks (bench/python/README.md).

* Timing: the process CPU clock (time.process_time, CLOCK_PROCESS_CPUTIME_ID as in
  bench/wp_common.h), the median of repetitions; a run shorter than MIN_REP seconds is repeated
  inside one repetition so that every repetition lasts at least MIN_REP (wp_common.h's rule).
* Runners on one problem description (problem_*.py: `Problem`): CEODE through the `ceode`
  module (fixed step, or error control) and scipy.integrate.solve_ivp on the first-order form
  y = (x, x') of the very same f (`first_order`), each to the problem's output instants.
* One CSV schema, the C scenes' one: scene,solver,config,h_or_tol,error,drift,steps,rhs_evals,
  seconds; the equal-error rule is scripts/wp_curves.py's time_to_reach (log-log interpolation).
"""
import csv
import math
import os
import statistics
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "scripts"))
from wp_curves import read_curves, time_to_reach  # noqa: E402

FIELDS = ["scene", "solver", "config", "h_or_tol", "error", "drift", "steps", "rhs_evals",
          "seconds"]
MIN_REP = 0.05   # seconds a repetition lasts at least
REPS = 5         # repetitions of a configuration (3 from FEW_REP_SECONDS, 1 from ONE_RUN_SECONDS)
FEW_REP_SECONDS = 0.5
ONE_RUN_SECONDS = 2.0


def cpu():
    return time.process_time()


def time_median(run, reps=REPS):
    """(median seconds of one run(), spread max/min - 1, run()'s last result)."""
    t0 = cpu()
    out = run()
    first = cpu() - t0
    if first >= ONE_RUN_SECONDS:
        return first, 0.0, out
    calls = 1 if first >= MIN_REP else math.ceil(MIN_REP / max(first, 1e-7))
    reps = 3 if first >= FEW_REP_SECONDS else reps
    per_call = []
    for _ in range(reps):
        t0 = cpu()
        for _ in range(calls):
            out = run()
        per_call.append((cpu() - t0) / calls)
    return statistics.median(per_call), max(per_call) / min(per_call) - 1, out


def first_order(f2, n):
    """solve_ivp's form of a CEODE right-hand side: y = (x, v), y' = (v, f(t, x, v))."""
    def f1(t, y):
        dy = np.empty_like(y)
        dy[:n] = y[n:]
        f2(t, y[:n], y[n:], dy[n:])
        return dy
    return f1


class Outcome:
    """The states at the output instants and the counts of one run."""

    def __init__(self, X, V, steps, rhs_evals):
        self.X, self.V, self.steps, self.rhs_evals = X, V, int(steps), int(rhs_evals)
        self.python_calls = self.rhs_evals


def ceode_run(ceode, p, method, h=None, tol=None):
    """CEODE to every output instant: fixed step h with the guard off (the C scenes' fixed-step
    rule), or error control at rtol = tol, atol = tol * p.atol_scale with the guard at its
    default. f is declared velocity-independent when the problem's f does not read v."""
    s = ceode.Integrator(p.f2, p.t0, p.x0, p.v0, method=method)
    s.set_velocity_dependence(p.uses_v)
    if h is not None:
        s.set_fixed_step(h)
        s.set_stability_guard(mode="off")
    else:
        s.set_tolerances(tol, tol * p.atol_scale)
    X = np.empty((len(p.t_out), p.n))
    V = np.empty_like(X)
    for k, t in enumerate(p.t_out):
        _, X[k], V[k] = s.evolve(t)
    st = s.stats()
    # Every f evaluation, as the C scenes count them: the steps', difference quotients', guard's.
    evals = st["rhs_evals"] + st.get("rhs_evals_jac_dq", 0) + st.get("guard_rhs_evals", 0)
    out = Outcome(X, V, st["steps"], evals)
    out.python_calls = st.get("python_calls", evals)  # f's calls from C++, probes included
    return out


def scipy_run(p, method, rtol, t_eval=True):
    """solve_ivp (method RK45 or DOP853) at rtol, atol = rtol * p.atol_scale, on first_order(f)."""
    y0 = np.concatenate((p.x0, p.v0))
    sol = solve_ivp(p.f1, (p.t0, p.t_out[-1]), y0, method=method, rtol=rtol,
                    atol=rtol * p.atol_scale, t_eval=p.t_out if t_eval else None)
    if sol.status != 0:
        raise RuntimeError(f"solve_ivp {method} rtol {rtol}: {sol.message}")
    return Outcome(sol.y[:p.n].T, sol.y[p.n:].T, len(sol.t) - 1, sol.nfev), sol


def scipy_steps(p, method, rtol):
    """solve_ivp's accepted steps (t_eval leaves them unseen; the same run without it, untimed)."""
    return scipy_run(p, method, rtol, t_eval=False)[0].steps


def row(p, solver, config, h_or_tol, out, seconds):
    err, drift = p.error(out.X, out.V)
    return {"scene": p.scene, "solver": solver, "config": config, "h_or_tol": f"{h_or_tol:.6e}",
            "error": f"{err:.6e}", "drift": f"{drift:.6e}", "steps": out.steps,
            "rhs_evals": out.rhs_evals, "seconds": f"{seconds:.6e}"}


def write_csv(path, rows, fields=FIELDS):
    """Rows (dicts) to a CSV file with the columns `fields` (default: the work-precision columns)."""
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        w.writerows(rows)


def equal_error(path, level):
    """{(solver, config): seconds at error level} of the curves that reach it (time_to_reach)."""
    _, curves = read_curves(path)
    out = {}
    for key, pts in curves.items():
        r = time_to_reach(pts, level)
        if r is not None:
            out[key] = r[0]
    return out


def best(times, pick):
    """(seconds, 'solver config') of the fastest picked curve, or None."""
    found = [(t, f"{s} {c}") for (s, c), t in times.items() if pick(s, c)]
    return min(found) if found else None


def fixed_steps(interval, fractions, h_ref):
    """Steps fractions * h_ref rounded down to divide the output interval (outputs on steps)."""
    return [interval / math.ceil(interval / (fr * h_ref)) for fr in fractions]


def reference(p, rtol=1e-13):
    """Sets p.ref to solve_ivp DOP853 at rtol (atol = rtol * p.atol_scale); returns the error of
    the same at 10 rtol against it, an upper estimate of the reference's own error."""
    p.ref = None
    out, _ = scipy_run(p, "DOP853", rtol)
    p.ref = (out.X, out.V)
    coarse, _ = scipy_run(p, "DOP853", 10 * rtol)
    return p.error(coarse.X, coarse.V)[0]
