#!/usr/bin/env python3
"""Plots of the constrained (DAE) scenes beyond work-precision (plot_results.py draws that).

For each CSV given (rows: scene,solver,config,h_or_tol,error,drift,steps,rhs_evals,seconds):
  * scene pendulum_dae or chain_dae_wp: the constraint drift of every run (its drift column:
    the largest position-level constraint residual over the run) against CPU time, log-log, to
    OUTDIR/<csv stem>_drift.png. The scenes record the largest drift of a run, not the drift at
    each instant, so this is drift against cost, not against simulated time;
  * scene chain_dae (bench/chain_scaling): CPU time per step against the number of bodies N,
    with the least-squares log-log slope and a linear-growth guide, to OUTDIR/<csv stem>.png.
A CSV given but absent is skipped with a message.

Usage:
  /usr/bin/python3 scripts/plot_dae.py [CSV ...] [--outdir docs/results]
Defaults: docs/results/{pendulum_dae,chain_dae_wp,chain_dae}[_o3].csv, those that exist.
"""
import argparse
import csv
import math
import os
import sys
from collections import OrderedDict

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import plot_style as ps  # noqa: E402
from plot_style import plt  # noqa: E402

# A drift of exactly 0 (the constraint met to the last bit) is drawn here.
ZERO_DRIFT = 1e-18
DRIFT_LABEL = {
    "pendulum_dae": "max |x² + y² − L²| over the run [m²]",
    "chain_dae_wp": "max |Φ(q)| over the run (position constraints of the 8 links)",
}


def read_rows(paths):
    rows = []
    for path in paths:
        with open(path, newline="") as f:
            for r in csv.DictReader(f):
                try:
                    r["h_or_tol"] = float(r["h_or_tol"])
                    r["error"] = float(r["error"])
                    r["drift"] = float(r["drift"])
                    r["steps"] = int(float(r["steps"]))
                    r["seconds"] = float(r["seconds"])
                except (KeyError, ValueError) as exc:
                    sys.exit(f"{path}: malformed row {r}: {exc}")
                rows.append(r)
    return rows


def plot_drift(rows, scene, png):
    curves = OrderedDict()
    for r in rows:
        if math.isfinite(r["drift"]) and r["seconds"] > 0:
            pt = {"seconds": r["seconds"], "drift": max(r["drift"], ZERO_DRIFT)}
            curves.setdefault(ps.normalise(r["solver"], r["config"]), []).append(pt)
    fig, ax = plt.subplots(figsize=(7.5, 6.2))
    ps.draw_curves(ax, [(s, c, p) for (s, c), p in curves.items()], ykey="drift")
    ax.axhline(2.2e-16, color="0.5", lw=0.8, ls=":")
    ax.text(ax.get_xlim()[0], 2.6e-16, " double-precision ε", fontsize=7, color="0.4")
    ax.set_xlabel(ps.TIME_LABEL)
    ax.set_ylabel(DRIFT_LABEL.get(scene, "max constraint residual over the run"))
    build = "SUNDIALS -O3" if os.path.basename(png).startswith(f"{scene}_o3") else "SUNDIALS -O0"
    ax.set_title(f"{scene}: constraint drift of each run against its cost ({build})\n"
                 "lower is better; the scene records each run's largest drift, not a time series",
                 fontsize=9)
    ps.grid(ax)
    ps.legend_below(ax)
    ps.save(fig, png)


def chain_slope(rows):
    """([(N, seconds per step, config)] sorted by N, least-squares log-log slope) of chain_dae rows."""
    pts = []
    for r in rows:
        try:
            n = int(r["config"].split()[0].split("=")[1])
        except (IndexError, ValueError):
            sys.exit(f"chain_dae row with unexpected config {r['config']!r}")
        pts.append((n, r["seconds"] / r["steps"], r["config"].split(" ", 1)[-1]))
    pts.sort()
    ns = [p[0] for p in pts]
    ts = [p[1] for p in pts]
    lx = [math.log(n) for n in ns]
    ly = [math.log(t) for t in ts]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    sxx = sum((x - mx) ** 2 for x in lx)
    slope = sum((x - mx) * (y - my) for x, y in zip(lx, ly)) / sxx if sxx > 0 else float("nan")
    return pts, slope


def plot_chain(rows, png):
    pts, slope = chain_slope(rows)
    ns = [p[0] for p in pts]
    ts = [p[1] for p in pts]
    fig, ax = plt.subplots(figsize=(6.5, 5))
    st = ps.style("CEODE", pts[0][2])
    ax.loglog(ns, ts, label=f"CEODE {pts[0][2]} + KLU (slope {slope:.2f})", **st)
    ax.loglog(ns, [ts[-1] * n / ns[-1] for n in ns], "k:", label="linear growth")
    ax.set_xlabel("N (masses; n + nc = 3N)")
    ax.set_ylabel("CPU time per step [s]")
    ax.set_title("Planar chain, index-3 DAE: cost per step")
    ps.grid(ax)
    ax.legend(fontsize=8)
    ps.save(fig, png)


def plot_file(path, outdir):
    if not os.path.exists(path):
        print(f"{path}: missing, skipped")
        return 0
    rows = read_rows([path])
    stem = os.path.splitext(os.path.basename(path))[0]
    scenes = {r["scene"] for r in rows}
    n = 0
    for scene in ("pendulum_dae", "chain_dae_wp"):
        if scene in scenes:
            plot_drift([r for r in rows if r["scene"] == scene], scene,
                       os.path.join(outdir, f"{stem}_drift.png"))
            n += 1
    chain = [r for r in rows if r["scene"] == "chain_dae"]
    if chain:
        plot_chain(chain, os.path.join(outdir, f"{stem}.png"))
        n += 1
    if not n:
        print(f"{path}: no pendulum_dae, chain_dae_wp or chain_dae rows, skipped")
    return n


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("csv", nargs="*", help="CSV files written with --csv")
    ap.add_argument("--outdir", default="docs/results")
    args = ap.parse_args()
    paths = args.csv or [os.path.join("docs/results", f"{s}{sfx}.csv")
                         for s in ("pendulum_dae", "chain_dae_wp", "chain_dae") for sfx in ("", "_o3")
                         if os.path.exists(os.path.join("docs/results", f"{s}{sfx}.csv"))]
    os.makedirs(args.outdir, exist_ok=True)
    for p in paths:
        plot_file(p, args.outdir)
    return 0


if __name__ == "__main__":
    sys.exit(main())
