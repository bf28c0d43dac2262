#!/usr/bin/env python3
"""Summary chart of the speed ratios at equal error: for every scene and error level, the fastest
CEODE curve's CPU time over the fastest curve of each kind of competitor (SUNDIALS, Boost.Odeint,
GSL; the hand-written loop of CEODE's own method where the scene has one), one horizontal bar
each, log scale; below 1 CEODE is faster.

Reads the same scene CSVs as scripts/ratios.py (the -O3 build's <scene>_o3.csv where it exists,
else <scene>.csv) and interpolates each curve's time at the level the same way
(wp_curves.time_to_reach). wp_high_order's problems are taken at 1e-9 and 1e-11, the FE scenes
(relative errors) at 1e-4 and 1e-6, the others at 1e-6, 1e-9 and 1e-11. Scenes whose CSV is
absent are skipped with a message.

Usage: plot_summary.py [--results docs/results] [--out docs/results/summary_ratios.png]
"""
import argparse
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import plot_style as ps  # noqa: E402
from plot_results import levels, read_scenes  # noqa: E402
from plot_style import plt  # noqa: E402
from wp_curves import time_to_reach  # noqa: E402

# Scenes in the order of docs/results.md; chain_dae (N-scaling, CEODE only) has no ratio.
SCENES = ["pendulum_ode", "spinning_top", "damped_pendulum", "forced_vibration", "kepler",
          "events", "fpu_chain",
          "pendulum_dae", "chain_dae_wp", "fe_plate", "fe_nonlinear", "fe_damped_mass",
          "fe_damped_stiff", "wp_high_order"]
KINDS = ["SUNDIALS", "Boost.Odeint", "GSL", "hand loop"]


def kind(solver):
    fam = ps.family(solver)
    if fam == "sundials":
        return "SUNDIALS"
    if fam == "hand":
        return "hand loop"
    if fam == "peer":
        return {"odeint": "Boost.Odeint", "GSL": "GSL"}.get(solver)
    return None


def best(curves, pick, lv):
    out = None
    for (solver, config), pts in curves.items():
        if not pick(solver):
            continue
        t = time_to_reach([dict(p, steps=0) for p in pts], lv)
        if t and (out is None or t[0] < out[0]):
            out = (t[0], ps.label(solver, config))
    return out


def rows_of(path):
    """[(row label, {kind: (ratio, competitor's name)}, CEODE's best name)] of one CSV."""
    out = []
    for scene, curves in read_scenes(path).items():
        for lv in levels(scene):
            c = best(curves, lambda s: ps.family(s) == "ceode", lv)
            if not c:
                reached = any(best(curves, lambda s, k=k: kind(s) == k, lv) for k in KINDS)
                if reached:
                    out.append((f"{scene} @ {lv:.0e}", {}, "does not reach it; a competitor does"))
                continue
            ratios = {}
            for k in KINDS:
                o = best(curves, lambda s, k=k: kind(s) == k, lv)
                if o:
                    ratios[k] = (c[0] / o[0], o[1])
            out.append((f"{scene} @ {lv:.0e}", ratios,
                        c[1] if ratios else c[1] + " (no competitor reaches it)"))
    return out


def collect(results):
    rows = []
    for scene in SCENES:
        path = next((os.path.join(results, f"{scene}{sfx}.csv") for sfx in ("_o3", "")
                     if os.path.exists(os.path.join(results, f"{scene}{sfx}.csv"))), None)
        if path is None:
            print(f"{scene}: no CSV in {results}, left out of the summary chart")
            continue
        build = " (-O0)" if not path.endswith("_o3.csv") else ""
        rows += [(lab + build, r, c) for lab, r, c in rows_of(path)]
    return rows


def draw(rows, out):
    height = 0.2
    fig, ax = plt.subplots(figsize=(11, 0.52 * len(rows) + 2))
    for i, (lab, ratios, cname) in enumerate(rows):
        y = len(rows) - 1 - i
        present = [k for k in KINDS if k in ratios]
        for j, k in enumerate(present):
            r, who = ratios[k]
            yy = y + (j - (len(present) - 1) / 2) * height
            ax.barh(yy, math.log10(r), height=height * 0.9, left=0,
                    color=ps.FAMILY_COLOURS[k], edgecolor="black" if r > 1 else "none",
                    hatch="//" if r > 1 else None, lw=0.6)
            ax.text(math.log10(r) + (0.03 if r >= 1 else -0.03), yy, f"{r:.2g}  {who}"
                    if r >= 1 else f"{who}  {r:.2g}", va="center",
                    ha="left" if r >= 1 else "right", fontsize=6.2)
        if not ratios:
            ax.text(0, y, " " + cname, va="center", fontsize=7,
                    color="#b00000" if "does not reach" in cname else "black")
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels([f"{r[0]}\nCEODE: {r[2].replace('CEODE ', '')}" for r in reversed(rows)],
                       fontsize=7)
    ax.axvline(0, color="black", lw=1)
    lo, hi = ax.get_xlim()
    lim = max(abs(lo), abs(hi), 1.0) + 0.9
    ax.set_xlim(-lim, lim)
    ticks = [t for t in range(-4, 5) if -lim <= t <= lim]
    ax.set_xticks(ticks)
    ax.set_xticklabels([f"{10.0 ** t:g}" for t in ticks])
    ax.set_xlabel("CEODE's CPU time / the competitor's at equal error (log scale; < 1: CEODE "
                  "faster, hatched > 1: CEODE slower)")
    ax.set_ylim(-0.7, len(rows) - 0.3)
    ax.grid(True, axis="x", alpha=0.3)
    handles = [plt.Rectangle((0, 0), 1, 1, color=ps.FAMILY_COLOURS[k]) for k in KINDS]
    ax.legend(handles, [f"fastest {k} curve" if k != "hand loop" else
                        "hand-written loop of CEODE's method" for k in KINDS],
              loc="upper center", bbox_to_anchor=(0.5, -0.5 / len(rows) * 4), ncol=4,
              fontsize=8, frameon=False)
    ax.set_title("Fastest CEODE configuration against the fastest of each kind, at equal error "
                 "(SUNDIALS -O3 build; '(-O0)': only the package build ran)", fontsize=10)
    fig.tight_layout()
    ps.save(fig, out)


def main():
    root = os.path.dirname(HERE)
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--results", default=os.path.join(root, "docs", "results"))
    ap.add_argument("--out")
    args = ap.parse_args()
    rows = collect(args.results)
    if not rows:
        print("no scene CSVs: summary chart not drawn")
        return 0
    draw(rows, args.out or os.path.join(args.results, "summary_ratios.png"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
