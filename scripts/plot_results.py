#!/usr/bin/env python3
"""Draws one log-log work-precision plot per scene CSV: error against run time,
one curve per (solver, config): CEODE solid, SUNDIALS dashed, the odeint/GSL
peers (bench/peers.h) dash-dotted, the hand loop dotted grey. Writes <csv stem>.png beside the CSV
(or into --outdir).

Usage: plot_results.py [--outdir DIR] [--skip-existing] FILE.csv ...
  --skip-existing  leaves a plot alone when its PNG already exists.
scripts/plot_dae.py draws pendulum_dae (work-precision with drift) and the
chain's N-scaling (chain_dae.csv); chain_dae_wp.csv, the chain's work-precision
scene, is drawn here like the other scenes.
"""
import argparse
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from wp_curves import is_ceode, is_peer, is_sundials, read_curves, usable  # noqa: E402

# Errors above this are runs past a stability limit: listed in the CSV, not drawn.
MAX_DRAWN_ERROR = 10.0

# What the error column measures, per scene (default: "error (scene's measure)").
YLABEL = {
    "pendulum_ode": "max |E - E0| over 10 s [J]",
    "spinning_top": "max |E - E0| over 10 s [J]",
    "forced_vibration": "max |x - x_exact| over 1000 s [m]",
    "chain_dae_wp": "max |E - E0| over 2 s [J] (chain of 8 masses, E0 = -22 J)",
    "damped_pendulum": "|theta(10) - ref| [rad]",
    "pendulum_dae": "max |E - E0| over 10 s [J]",
}


def style(solver, index):
    markers = "os^vD<>ph*"
    if is_ceode(solver):
        return dict(linestyle="-", marker=markers[index % len(markers)])
    if is_sundials(solver):
        return dict(linestyle="--", marker=markers[index % len(markers)], fillstyle="none")
    if is_peer(solver):  # odeint / GSL (bench/peers.h): dash-dot, small filled markers
        return dict(linestyle="-.", marker=markers[index % len(markers)], lw=0.9)
    # The hand-written reference loop: grey, dotted.
    return dict(linestyle=":", marker="x+"[index % 2], color="0.3")


def plot(path, outdir, skip_existing):
    scene, curves = read_curves(path)
    if scene is None:
        print(f"{path}: no rows, skipped")
        return
    stem = os.path.splitext(os.path.basename(path))[0]
    base = os.path.join(outdir or os.path.dirname(path), stem)
    if skip_existing and os.path.exists(base + ".png"):
        print(f"{base}.png exists, left alone")
        return
    # Scenes with the peer curves have ~25 curves: the legend goes beside the axes.
    many = any(is_peer(solver) for solver, _ in curves)
    fig, ax = plt.subplots(figsize=(11, 6) if many else (8, 5.5))
    nc = ns = nh = npeer = 0
    for (solver, config), pts in curves.items():
        pts = [p for p in pts if usable(p) and p["error"] <= MAX_DRAWN_ERROR]
        if not pts:
            continue
        if is_ceode(solver):
            st, nc = style(solver, nc), nc + 1
        elif is_sundials(solver):
            st, ns = style(solver, ns), ns + 1
        elif is_peer(solver):
            st, npeer = style(solver, npeer), npeer + 1
        else:
            st, nh = style(solver, nh), nh + 1
        label = solver if config in ("", solver) else f"{solver} {config}"
        kw = dict(ms=4, lw=1.2)
        kw.update(st)
        ax.loglog([p["seconds"] for p in pts], [p["error"] for p in pts], label=label, **kw)
    ax.set_xlabel("CPU time per solve (s), median of 5 repetitions")
    ax.set_ylabel(YLABEL.get(scene, "error (scene's measure)"))
    ax.set_title(f"{scene}: work-precision (lower left is better)")
    ax.grid(True, which="major", alpha=0.4)
    ax.grid(True, which="minor", alpha=0.12)
    if many:
        ax.legend(fontsize=6.5, ncol=1, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    else:
        ax.legend(fontsize=7, ncol=2, loc="best")
    fig.tight_layout()
    fig.savefig(f"{base}.png", dpi=120)
    plt.close(fig)
    print(f"wrote {base}.png")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv", nargs="+")
    ap.add_argument("--outdir")
    ap.add_argument("--skip-existing", action="store_true")
    args = ap.parse_args()
    for p in args.csv:
        plot(p, args.outdir, args.skip_existing)
    return 0


if __name__ == "__main__":
    sys.exit(main())
