#!/usr/bin/env python3
"""Draws the work-precision figure of each scene CSV: error against CPU time on log-log axes, in
panels of at most about ten curves, every method in its own colour and marker (plot_style.py).

Panels of one scene, sharing both axes:
  * the headline CEODE curves (the fastest at each error level, the recommended sets G5_O4,
    G8_O8 and G4_A34 and the fastest error-control curve, whichever the scene ran; at most 5)
    against every SUNDIALS curve;
  * the same CEODE curves against Boost.Odeint, GSL and the other peers (scenes that ran them);
  * every CEODE configuration with the hand-written loop, split by mode (fixed step, the
    AUTO implicit step, error control) when there are more than ten.
A CSV holding several problems (wp_high_order: pendulum, FPU chain) gets one row of panels per
problem. Writes <csv stem>.png beside the CSV (or into --outdir).

Usage: plot_results.py [--outdir DIR] [--skip-existing] FILE.csv ...
  --skip-existing  leaves a plot alone when its PNG already exists.
scripts/plot_dae.py draws pendulum_dae's constraint drift and the chain's N-scaling.
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
from wp_curves import time_to_reach  # noqa: E402

# Errors above this are runs past a stability limit: listed in the CSV, not drawn.
MAX_DRAWN_ERROR = 10.0
# An error of exactly 0 (agreement with the reference to the last bit) is drawn here.
ZERO_ERROR = 1e-17
MAX_CURVES = 10
MAX_HEADLINE = 5
RECOMMENDED = ("G5_O4", "G8_O8", "G4_A34")

# What the error column measures, per scene.
YLABEL = {
    "pendulum_ode": "max |E - E0| over 10 s [J]",
    "spinning_top": "max |E - E0| over 10 s [J]",
    "forced_vibration": "max |x - x_exact| over 1000 s [m]",
    "chain_dae_wp": "max |E - E0| over 2 s [J]",
    "damped_pendulum": "|theta(10) - ref| [rad]",
    "pendulum_dae": "max |E - E0| over 10 s [J]",
    "kepler": "|q(t_f) - q(0)| after 10 orbits [length units]",
    "events": "max |t_k - k pi| over the 20 events of 10 Kepler orbits [time units]",
    "pendulum": "|theta(10) - ref| [rad] (extrapolated reference)",
    "fpu_chain_16": "error at t = 10 against the extrapolated reference",
    "fpu_chain": "max_i |x_i(100) - ref_i| (1000 masses, extrapolated reference)",
}
FE_YLABEL = "relative position error (FE plate, against the modal solution)"
FE_LEVELS = (1e-4, 1e-6)
LEVELS = (1e-6, 1e-9, 1e-11)


def ylabel(scene):
    if scene.startswith("fe_"):
        return FE_YLABEL
    return YLABEL.get(scene, "error (the scene's measure)")


# wp_high_order's problems: its ratios are taken at 1e-9 and 1e-11 (results_page.py).
HIGH_ORDER_LEVELS = {"pendulum": (1e-9, 1e-11), "fpu_chain_16": (1e-9, 1e-11),
                     "events": (1e-6, 1e-8), "fpu_chain": (1e-6, 1e-8, 1e-10)}


def levels(scene):
    return FE_LEVELS if scene.startswith("fe_") else HIGH_ORDER_LEVELS.get(scene, LEVELS)


def read_scenes(path):
    """OrderedDict scene -> OrderedDict (solver, config) -> points, names normalised."""
    scenes = OrderedDict()
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            try:
                pt = {"h_or_tol": float(row["h_or_tol"]), "error": float(row["error"]),
                      "seconds": float(row["seconds"]), "drift": float(row.get("drift") or "nan")}
            except (KeyError, ValueError):
                continue
            if pt["error"] == 0:
                pt["error"] = ZERO_ERROR
            name = ps.normalise(row["solver"], row["config"])
            scenes.setdefault(row["scene"], OrderedDict()).setdefault(name, []).append(pt)
    return scenes


def drawable(pts):
    return [p for p in pts if math.isfinite(p["error"]) and 0 < p["error"] <= MAX_DRAWN_ERROR
            and math.isfinite(p["seconds"]) and p["seconds"] > 0]


def fastest(curves, lv):
    """The (solver, config) of the fastest curve to reach lv, or None."""
    best = None
    for name, pts in curves.items():
        t = time_to_reach(pts, lv)
        if t and (best is None or t[0] < best[0]):
            best = (t[0], name)
    return best[1] if best else None


def headline(ceode, scene):
    """The CEODE curves of the first panels: the fastest at each level, then the recommended sets
    (their fastest curve at the middle level, else their first), then the fastest error-control
    curve; at most MAX_HEADLINE."""
    lvs = levels(scene)
    picks = [fastest(ceode, lv) for lv in lvs]
    mid = lvs[len(lvs) // 2]
    for s in RECOMMENDED:
        of_set = OrderedDict((n, p) for n, p in ceode.items() if ps.ceode_set(n[1]) == s)
        if of_set:
            picks.append(fastest(of_set, mid) or next(iter(of_set)))
    adaptive = OrderedDict((n, p) for n, p in ceode.items() if ps.is_adaptive(n[1]))
    if adaptive:
        picks.append(fastest(adaptive, mid) or next(iter(adaptive)))
    out = []
    for p in picks:
        if p and p not in out:
            out.append(p)
    return out[:MAX_HEADLINE] or list(ceode)[:MAX_HEADLINE]


def mode(config):
    if ps.is_adaptive(config):
        return "error control (h_or_tol = tolerance)"
    if "auto" in config.lower():
        return "fixed h, AUTO implicit step"
    return "fixed h"


def chunks(items, size):
    return [items[i:i + size] for i in range(0, len(items), size)]


def panels(curves):
    """[(title, [(solver, config, points)])] of one scene."""
    scene_curves = [(s, c, drawable(p)) for (s, c), p in curves.items()]
    scene_curves = [x for x in scene_curves if x[2]]
    by_fam = {f: [x for x in scene_curves if ps.family(x[0]) == f]
              for f in ("ceode", "hand", "sundials", "peer")}
    ceode = OrderedDict(((s, c), p) for s, c, p in by_fam["ceode"])
    return ceode, by_fam


def scene_panels(scene, curves):
    ceode, by_fam = panels(curves)
    head = [(s, c, ceode[(s, c)]) for s, c in headline(ceode, scene)] if ceode else []
    out = []
    if by_fam["sundials"]:
        out.append(("best and recommended CEODE against SUNDIALS", head + by_fam["sundials"]))
    if by_fam["peer"]:
        out.append(("best and recommended CEODE against Boost.Odeint, GSL and other peers",
                    head + by_fam["peer"]))
    rest = by_fam["ceode"] + by_fam["hand"]
    if len(rest) > len(head) or by_fam["hand"] or not out:
        groups = OrderedDict()
        for x in by_fam["ceode"]:
            groups.setdefault(mode(x[1]), []).append(x)
        if len(rest) <= MAX_CURVES:
            out.append(("every CEODE configuration" + (" and the hand-written loop"
                                                        if by_fam["hand"] else ""), rest))
        else:
            for g, items in groups.items():
                for i, part in enumerate(chunks(items, MAX_CURVES)):
                    out.append((f"CEODE, {g}" + (f" ({i + 1})" if i else ""), part))
            if by_fam["hand"]:
                out[-1] = (out[-1][0] + " and the hand-written loop", out[-1][1] + by_fam["hand"])
    return out


def draw_scene(axes, scene, curves, title_prefix=""):
    for ax, (title, items) in zip(axes, scene_panels(scene, curves)):
        ps.draw_curves(ax, items)
        for lv in levels(scene):
            ax.axhline(lv, color="0.6", lw=0.6, ls=":", zorder=0)
        ax.set_title(f"{title_prefix}{title}", fontsize=9)
        ax.set_xlabel(ps.TIME_LABEL, fontsize=8)
        ax.set_ylabel(ylabel(scene), fontsize=8)
        ax.tick_params(labelbottom=True, labelleft=True)  # shared axes keep their numbers
        ps.grid(ax)
        ps.legend_below(ax)


def plot(path, outdir, skip_existing, out_png=None):
    scenes = read_scenes(path)
    if not scenes:
        print(f"{path}: no rows, skipped")
        return None
    stem = os.path.splitext(os.path.basename(path))[0]
    png = out_png or os.path.join(outdir or os.path.dirname(path), stem + ".png")
    if skip_existing and os.path.exists(png):
        print(f"{png} exists, left alone")
        return png
    layout = [(scene, curves, len(scene_panels(scene, curves))) for scene, curves in scenes.items()]
    if len(layout) == 1:  # one problem: panels two by two
        n = layout[0][2]
        ncol = min(n, 2)
        nrow = (n + ncol - 1) // ncol
        fig, axes = plt.subplots(nrow, ncol, figsize=(6.2 * ncol, 6.6 * nrow), squeeze=False,
                                 sharex="all", sharey="all")
        rows = [(layout[0][0], layout[0][1], n, list(axes.flat))]
    else:  # one row of panels per problem
        ncol = max(n for _, _, n in layout)
        fig, axes = plt.subplots(len(layout), ncol, figsize=(5.8 * ncol, 6.6 * len(layout)),
                                 squeeze=False, sharex="row", sharey="row")
        rows = [(s, c, n, list(ax)) for (s, c, n), ax in zip(layout, axes)]
    for scene, curves, n, row in rows:
        draw_scene(row, scene, curves, f"{scene}: " if len(layout) > 1 else "")
        for ax in row[n:]:
            ax.set_visible(False)
    name = layout[0][0] if len(layout) == 1 else stem[:-3] if stem.endswith("_o3") else stem
    build = "SUNDIALS -O3" if stem.endswith("_o3") else "SUNDIALS package (-O0)"
    fig.suptitle(f"{name}: work-precision, lower left is better ({build}; dotted lines: the error "
                 "levels of the ratios)", fontsize=11)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    ps.save(fig, png)
    return png


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv", nargs="+")
    ap.add_argument("--outdir")
    ap.add_argument("--skip-existing", action="store_true")
    args = ap.parse_args()
    for p in args.csv:
        if not os.path.exists(p):
            print(f"{p}: missing, skipped")
            continue
        plot(p, args.outdir, args.skip_existing)
    return 0


if __name__ == "__main__":
    sys.exit(main())
