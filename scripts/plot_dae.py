#!/usr/bin/env python3
"""Plot the results of the constrained (DAE) bench scenes.

Reads the CSV written by `bench/wp_pendulum_dae --csv FILE` (and, optionally, by
`bench/chain_scaling --csv FILE`; rows: scene,solver,config,h_or_tol,error,drift,steps,
rhs_evals,seconds) and writes

  * for scene pendulum_dae: a log-log work-precision plot, max energy error
    against run time, one curve per solver/configuration, points joined from
    the largest step/tolerance to the smallest, to OUTDIR/pendulum_dae.png;
  * for scene chain_dae: time per step against the number of bodies N, with
    the least-squares log-log slope and a linear-growth guide, to
    OUTDIR/chain_dae.png.

Usage:
  python3 scripts/plot_dae.py [CSV ...] [--outdir docs/results]
Defaults: docs/results/pendulum_dae.csv and docs/results/chain_dae.csv (the
ones that exist). Needs matplotlib (Debian: python3-matplotlib; run it with
/usr/bin/python3 if another python3 comes first on PATH).
"""
import argparse
import csv
import math
import os
import sys
from collections import OrderedDict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {
    "ARKODE": dict(marker="s", linestyle="--"),
    "IDA": dict(marker="^", linestyle=":"),
    "CEODE": dict(marker="o", linestyle="-"),
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
                    r["steps"] = int(r["steps"])
                    r["seconds"] = float(r["seconds"])
                except (KeyError, ValueError) as exc:
                    sys.exit(f"{path}: malformed row {r}: {exc}")
                rows.append(r)
    return rows


def save(fig, outdir, stem):
    os.makedirs(outdir, exist_ok=True)
    path = os.path.join(outdir, f"{stem}.png")
    fig.savefig(path, dpi=150, bbox_inches="tight")
    plt.close(fig)
    return [path]


def plot_pendulum(rows, outdir):
    curves = OrderedDict()
    for r in rows:
        curves.setdefault((r["solver"], r["config"]), []).append(r)
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    for (solver, config), pts in curves.items():
        pts = sorted(pts, key=lambda r: -r["h_or_tol"])  # cheapest first
        pts = [p for p in pts if p["error"] > 0 and p["seconds"] > 0]
        if not pts:
            continue
        style = STYLE.get(solver, dict(marker="x", linestyle="-"))
        kind = "tol" if solver == "IDA" else "h"
        lo, hi = pts[-1]["h_or_tol"], pts[0]["h_or_tol"]
        label = f"{solver} {config} ({kind} {hi:.0e}..{lo:.0e})"
        ax.loglog([p["seconds"] for p in pts], [p["error"] for p in pts], label=label, **style)
    ax.set_xlabel("CPU time per run [s] (median of 5 repetitions of >= 50 ms)")
    ax.set_ylabel("max |E - E0| over 10 s [J]")
    ax.set_title("DAE pendulum (index 3, I_zz = 0): work-precision")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return save(fig, outdir, "pendulum_dae")


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


def plot_chain(rows, outdir):
    pts, slope = chain_slope(rows)
    ns = [p[0] for p in pts]
    ts = [p[1] for p in pts]
    fig, ax = plt.subplots(figsize=(6.5, 5))
    ax.loglog(ns, ts, "o-", label=f"CEODE {pts[0][2]} + KLU (slope {slope:.2f})")
    ax.loglog(ns, [ts[-1] * n / ns[-1] for n in ns], "k:", label="linear growth")
    ax.set_xlabel("N (masses; n + nc = 3N)")
    ax.set_ylabel("CPU time per step [s]")
    ax.set_title("Planar chain, index-3 DAE: cost per step")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return save(fig, outdir, "chain_dae")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("csv", nargs="*", help="CSV files written with --csv")
    ap.add_argument("--outdir", default="docs/results")
    args = ap.parse_args()
    paths = args.csv or [
        p for p in ("docs/results/pendulum_dae.csv", "docs/results/chain_dae.csv") if os.path.exists(p)
    ]
    if not paths:
        sys.exit("no CSV given and none found in docs/results")
    rows = read_rows(paths)
    written = []
    pend = [r for r in rows if r["scene"] == "pendulum_dae"]
    chain = [r for r in rows if r["scene"] == "chain_dae"]
    if pend:
        written += plot_pendulum(pend, args.outdir)
    if chain:
        written += plot_chain(chain, args.outdir)
    if not written:
        sys.exit("no pendulum_dae or chain_dae rows found")
    for w in written:
        print("wrote", w)


if __name__ == "__main__":
    main()
