#!/usr/bin/env python3
"""Long-run energy error against time, every named set, from the long-run study's data
(docs/data/long_run_pendulum.csv and long_run_oscillator.csv; docs/stability.md, "Long runs").

The study runs 10^7 steps of h = 1e-3 (T = 10^4 s) and keeps, per set, the largest |E - E0| over
three windows: the first 1 % of the run (column ripple, drawn at t = T/100), the 1 % before T/2
(mid) and the last 1 % (late, drawn at T); a run that blew up (|dE| > 1) has its time in t_fail,
drawn as a cross at |dE| = 1. Those three windows are all the study keeps: the curves join the
measured windows, they are not a sampled time series. On log-log axes a bounded error is flat,
a linear drift rises with slope 1 and a growing error faster. The paper's sets and the finder's
sets are drawn in separate panels (G3_CD, the bounded one, in both), one row per problem.

Usage: plot_long_run.py [--data docs/data] [--out docs/results/long_run_energy.png]
"""
import argparse
import csv
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import plot_style as ps  # noqa: E402
from plot_style import plt  # noqa: E402

PROBLEMS = [("pendulum", "pendulum θ'' = −g cos θ, released from the horizontal"),
            ("oscillator", "linear oscillator x'' = −g x")]
PAPER = ["G3_CD", "G3_A43", "G3_A2", "G4_A14", "G4_A34", "G4_A54", "G5", "G5_TOP", "G5_ONES"]
FINDER = ["G3_CD", "G5_O4", "G6_O5", "G6_O6", "G7_O7", "G8_O8"]


def read(path):
    with open(path, newline="") as f:
        return {r["set"]: r for r in csv.DictReader(f)}


def points(r):
    """[(t, |dE|)] of the measured windows, then (t_fail, 1) if the run blew up."""
    T = float(r["T"])
    pts = []
    for t, col in ((T / 100, "ripple"), (T / 2, "mid"), (T, "late")):
        v = float(r[col])
        if math.isfinite(v) and v > 0:
            pts.append((t, v))
    t_fail = float(r["t_fail"] or 0)
    if t_fail > 0:
        pts = [p for p in pts if p[0] < t_fail] + [(t_fail, 1.0)]
    return pts, t_fail


def panel(ax, data, sets, title):
    for name in sets:
        r = data.get(name)
        if r is None:
            continue
        pts, t_fail = points(r)
        st = ps.style("CEODE", name)
        verdict = r["verdict"] + (f" at t = {t_fail:.0f} s" if t_fail > 0 else "")
        if r.get("verdict_h2") and r["verdict_h2"] != r["verdict"]:
            verdict += f"; {r['verdict_h2']} at h = {r['h2']}"
        elif float(r["late"] or 0) and float(r["late"]) < 1e-10:
            verdict += " at the round-off level"
        ax.loglog([p[0] for p in pts], [p[1] for p in pts], label=f"{name}: {verdict}", **st)
        if t_fail > 0:
            ax.plot([t_fail], [1.0], "x", color=st["color"], ms=12, mew=2.5)
    t = [100, 1e4]
    ax.loglog(t, [1e-13 * x / t[0] for x in t], color="0.55", lw=0.8, ls=":")
    ax.text(t[0] * 1.1, 1.3e-13, "slope 1 (linear drift)", fontsize=7, color="0.45")
    ax.axhline(1.0, color="#b00000", lw=0.6, ls="--")
    ax.set_title(title, fontsize=9)
    ax.set_xlabel("simulated time t [s] (windows: first 1 %, the 1 % before T/2, last 1 %)",
                  fontsize=8)
    ax.set_ylabel("max |E − E0| over the window", fontsize=8)
    ax.tick_params(labelbottom=True, labelleft=True)
    ps.grid(ax)
    ps.legend_below(ax, ncol=2, fontsize=7)


def main():
    root = os.path.dirname(HERE)
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=os.path.join(root, "docs", "data"))
    ap.add_argument("--out", default=os.path.join(root, "docs", "results", "long_run_energy.png"))
    args = ap.parse_args()
    found = [(p, t, os.path.join(args.data, f"long_run_{p}.csv")) for p, t in PROBLEMS]
    found = [x for x in found if os.path.exists(x[2]) or print(f"{x[2]}: missing, skipped")]
    if not found:
        print("no long-run data: chart not drawn")
        return 0
    fig, axes = plt.subplots(len(found), 2, figsize=(13, 6.6 * len(found)), squeeze=False,
                             sharex=True, sharey=True)
    for row, (problem, title, path) in zip(axes, found):
        data = read(path)
        h = next(iter(data.values()))["h"]
        panel(row[0], data, PAPER, f"{title}: the paper's sets, h = {h}")
        panel(row[1], data, FINDER, f"{title}: the finder's sets, h = {h}")
    fig.suptitle("Energy error over 10⁴ s (10⁷ steps), explicit path, no compensated summation; "
                 "× marks a blow-up (|dE| > 1)", fontsize=11)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    ps.save(fig, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
