#!/usr/bin/env python3
"""Work-precision at equal error: CEODE (the `ceode` module, Python f) against scipy's solve_ivp
RK45 and DOP853 on the same f (harness.first_order), on the pendulum (problem_pendulum.py) and
the 1000-mass FPU-beta chain (problem_chain.py).

CEODE: fixed steps (pendulum: h dividing the output interval; chain: fractions of each set's
stable step from the guard, get_stable_step) and error control; solve_ivp at several rtol.
Every configuration timed by harness.time_median (process CPU time, median of repetitions).
Writes <out>/python_<problem>.csv (schema of docs/results/*.csv) and .png, and
<out>/python_ratios.csv: the fastest CEODE curve's time over RK45's and DOP853's at each error
level, interpolated in log-log (scripts/wp_curves.py time_to_reach, as scripts/ratios.py does).

Usage: work_precision.py [--out DIR] [--quick] [--problem pendulum|chain]...
Exit code 0 when every run succeeded (timings decide nothing).
"""
import argparse
import os
import sys

import harness as H
import problem_chain
import problem_pendulum

PROBLEMS = {"pendulum": problem_pendulum.Problem, "chain": problem_chain.Problem}
SCIPY = "scipy solve_ivp"


def ceode_rows(ceode, p, quick):
    rows = []
    for method, hs in fixed_plan(ceode, p).items():
        for h in hs[: 3 if quick else None]:
            sec, _, out = H.time_median(lambda: H.ceode_run(ceode, p, method, h=h))
            rows.append(H.row(p, "CEODE", method, h, out, sec))
    for method, tols in p.adaptive.items():
        for tol in tols[: 2 if quick else None]:
            sec, _, out = H.time_median(lambda: H.ceode_run(ceode, p, method, tol=tol))
            rows.append(H.row(p, "CEODE", f"{method} adaptive", tol, out, sec))
    return rows


def fixed_plan(ceode, p):
    """{set: steps}: the problem's own steps, or fractions of each set's stable step."""
    interval = p.t_out[1] - p.t_out[0]
    if hasattr(p, "fixed"):
        return {m: H.fixed_steps(interval, hs, 1.0) for m, hs in p.fixed.items()}
    plan = {}
    for method, fr in p.fractions.items():
        hs = ceode.Integrator(p.f2, p.t0, p.x0, p.v0, method=method).get_stable_step()
        print(f"  {method}: stable step from the guard {hs:.6g}")
        plan[method] = H.fixed_steps(interval, fr, hs)
    return plan


def scipy_rows(p, quick):
    rows = []
    for method in ("RK45", "DOP853"):
        for rtol in p.rtols[: 3 if quick else None]:
            sec, _, out = H.time_median(lambda: H.scipy_run(p, method, rtol)[0])
            out.steps = H.scipy_steps(p, method, rtol)
            rows.append(H.row(p, SCIPY, method, rtol, out, sec))
    return rows


def ratios(p, path):
    """Rows of python_ratios.csv: CEODE's fastest at each level against RK45 and DOP853."""
    out = []
    for lv in p.levels:
        t = H.equal_error(path, lv)
        c = H.best(t, lambda s, _: s == "CEODE")
        r = {m: H.best(t, lambda s, cfg, m=m: s == SCIPY and cfg == m) for m in ("RK45", "DOP853")}
        row = {"scene": p.scene, "error_level": f"{lv:.0e}",
               "ceode_best": c[1] if c else "not reached", "ceode_seconds": f"{c[0]:.3e}" if c else ""}
        for m, v in r.items():
            row[f"{m.lower()}_seconds"] = f"{v[0]:.3e}" if v else ""
            row[f"ratio_ceode_over_{m.lower()}"] = f"{c[0] / v[0]:.3g}" if c and v else ""
        out.append(row)
    return out


def plot(path, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    scene, curves = H.read_curves(path)
    fig, ax = plt.subplots(figsize=(7, 4.6))
    for (solver, config), pts in curves.items():
        pts = [q for q in pts if 0 < q["error"] < 1]
        style = "-o" if solver == "CEODE" else "--s"
        ax.loglog([q["seconds"] for q in pts], [q["error"] for q in pts], style, ms=4,
                  label=f"{solver} {config}")
    ax.set_xlabel("CPU seconds (median of repetitions)")
    ax.set_ylabel("error")
    ax.set_title(f"{scene}: CEODE (Python f) against solve_ivp")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)


def run_problem(ceode, name, out_dir, quick):
    p = PROBLEMS[name]()
    ref_err = H.reference(p)
    print(f"== {p.scene}: reference DOP853 rtol 1e-13 (its error estimate {ref_err:.2e}) ==")
    rows = ceode_rows(ceode, p, quick) + scipy_rows(p, quick)
    path = os.path.join(out_dir, f"{p.scene}.csv")
    H.write_csv(path, rows)
    print(f"{'solver':<16} {'config':<16} {'h or tol':>10} {'error':>10} {'steps':>7} "
          f"{'f evals':>8} {'seconds':>10}")
    for r in rows:
        print(f"{r['solver']:<16} {r['config']:<16} {float(r['h_or_tol']):>10.3g} "
              f"{float(r['error']):>10.3e} {r['steps']:>7} {r['rhs_evals']:>8} "
              f"{float(r['seconds']):>10.3e}")
    plot(path, os.path.join(out_dir, f"{p.scene}.png"))
    return ratios(p, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=".")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--problem", action="append", choices=sorted(PROBLEMS))
    args = ap.parse_args()
    import ceode
    os.makedirs(args.out, exist_ok=True)
    rows = []
    for name in args.problem or ["pendulum", "chain"]:
        rows += run_problem(ceode, name, args.out, args.quick)
    path = os.path.join(args.out, "python_ratios.csv")
    H.write_csv(path, rows, list(rows[0].keys()))
    print("\nequal error (time_to_reach, log-log): ratio = CEODE time / solve_ivp time "
          "(< 1: CEODE faster)")
    for r in rows:
        print(f"{r['scene']:<18} {r['error_level']:>6}  {r['ceode_best']:<26} "
              f"{r['ceode_seconds']:>10}  RK45 {r['rk45_seconds']:>10} ratio "
              f"{r['ratio_ceode_over_rk45'] or '-':>6}  DOP853 {r['dop853_seconds']:>10} ratio "
              f"{r['ratio_ceode_over_dop853'] or '-':>6}")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
