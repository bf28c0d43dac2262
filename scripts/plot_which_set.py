#!/usr/bin/env python3
"""'Which set' chart: for every named CEODE set, its order in x against its stability limit
Omega_max (undamped, and the limit at damping ratio 0.05 joined to it), each point marked with
the set's long-run behaviour on the pendulum and the oscillator (docs/data/long_run_*.csv).

The orders and limits come from the library itself: with --lib (default build/libceode.so when
it exists) the script calls CEodeGetNumMethods, CEodeGetMethodName, CEodeGetMethodParams,
CEodeMethodOrder and CEodeStabilityLimit through ctypes and writes docs/data/set_summary.csv;
without the library it reads that CSV. Either missing: the chart is skipped with a message.

Long-run class of a set, the worst over both problems and both steps of the study: unstable
(|dE| passed 1), growing, linear drift, bounded; "round-off" when the study's error after 10^4 s
stays below 1e-10 on both problems at both steps (no drift above round-off).

Usage: plot_which_set.py [--lib build/libceode.so] [--data docs/data]
                         [--out docs/results/which_set.png]
"""
import argparse
import csv
import ctypes
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import plot_style as ps  # noqa: E402
from plot_style import plt  # noqa: E402

COLUMNS = ["set", "degree", "order_x", "order_v", "omega_max_xi0", "omega_max_xi005"]
RANK = {"bounded": 0, "round-off": 0, "linear drift": 1, "growing": 2, "unstable": 3}
CLASS_STYLE = {  # long-run class -> (ring colour, label)
    "bounded": ("#1a9850", "bounded (energy error stays at its first ripple)"),
    "round-off": ("#4575b4", "no drift above round-off"),
    "linear drift": ("#fdae61", "linear drift (truncation)"),
    "growing": ("#d73027", "grows (weakly unstable)"),
    "unstable": ("#7f0000", "blows up in the long run"),
}


def from_library(lib_path):
    lib = ctypes.CDLL(lib_path)
    lib.CEodeGetMethodName.restype = ctypes.c_char_p
    rows = []
    for i in range(lib.CEodeGetNumMethods()):
        name = lib.CEodeGetMethodName(i)
        degree = ctypes.c_int()
        params = (ctypes.c_double * 16)()
        if lib.CEodeGetMethodParams(name, ctypes.byref(degree), params, 16) != 0:
            continue
        ox, ov = ctypes.c_int(), ctypes.c_int()
        if lib.CEodeMethodOrder(degree, params, ctypes.byref(ox), ctypes.byref(ov)) != 0:
            continue
        limits = []
        for xi in (0.0, 0.05):
            om = ctypes.c_double()
            flag = lib.CEodeStabilityLimit(degree, params, ctypes.c_double(xi), ctypes.byref(om))
            limits.append(om.value if flag == 0 else float("nan"))
        rows.append({"set": name.decode(), "degree": degree.value, "order_x": ox.value,
                     "order_v": ov.value, "omega_max_xi0": f"{limits[0]:.6g}",
                     "omega_max_xi005": f"{limits[1]:.6g}"})
    return rows


def long_run_class(data_dir, name):
    worst, late = None, []
    for problem in ("pendulum", "oscillator"):
        path = os.path.join(data_dir, f"long_run_{problem}.csv")
        if not os.path.exists(path):
            continue
        with open(path, newline="") as f:
            for r in csv.DictReader(f):
                if r["set"] != name:
                    continue
                for v in (r["verdict"], r["verdict_h2"]):
                    if v in RANK and (worst is None or RANK[v] > RANK[worst]):
                        worst = v
                late += [float(r["late"] or "nan"), float(r["late_h2"] or "nan")]
    if worst in ("linear drift", "bounded") and late and all(0 <= x < 1e-10 for x in late):
        return "round-off"
    return worst


def draw(rows, data_dir, out):
    fig, ax = plt.subplots(figsize=(10.5, 7))
    classes = set()
    at = {}
    for r in rows:
        name, order = r["set"], int(r["order_x"])
        om0, om5 = float(r["omega_max_xi0"]), float(r["omega_max_xi005"])
        colour, marker = ps.CEODE_SETS.get(name, ("#333333", "o"))
        cls = long_run_class(data_dir, name)
        ring = CLASS_STYLE[cls][0] if cls else "white"
        classes.add(cls)
        stack = at.setdefault((round(om0, 2), order), 0)
        at[(round(om0, 2), order)] += 1
        y = order + 0.22 * stack
        ax.plot([om0], [y], marker="o", ms=21, mfc="none", mec=ring, mew=3.5, zorder=2)
        ax.plot([om0], [y], marker=marker, ms=10, color=colour, zorder=3)
        if abs(om5 - om0) > 1e-3:  # damped limit: an arrow just below the point, one per set
            arrows = at.setdefault(("arrow", order), 0)
            at[("arrow", order)] += 1
            ya = y - 0.2 - 0.1 * arrows
            ax.annotate("", xy=(om5, ya), xytext=(om0, ya), zorder=1,
                        arrowprops=dict(arrowstyle="->", color=colour, lw=1.2, ls="--"))
        ax.text(om0 + 0.045, y + 0.1, f"{name}  (x' order {r['order_v']})", fontsize=8,
                color=colour, zorder=4)
    for cls, (ring, text) in CLASS_STYLE.items():
        if cls in classes:
            ax.plot([], [], "o", ms=12, mfc="none", mec=ring, mew=3, label=f"ring: {text}")
    ax.plot([], [], color="0.3", ls="--", label="arrow: Ω_max at damping ratio ξ = 0.05 "
            "(implicit velocity step)")
    ax.set_xlabel("Ω_max = ω_max h at the stability limit (undamped; larger: longer stable step)")
    ax.set_ylabel("order in x")
    ax.set_xlim(-0.15, 2.5)
    ax.set_yticks(range(2, 10))
    ax.set_ylim(1.5, 9.2)
    ax.grid(True, alpha=0.3)
    ax.set_title("Which set: order against stability interval, with long-run behaviour "
                 "(docs/stability.md)", fontsize=10)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=2, fontsize=8, frameon=False)
    fig.tight_layout()
    ps.save(fig, out)


def main():
    root = os.path.dirname(HERE)
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lib", default=os.path.join(root, "build", "libceode.so"))
    ap.add_argument("--data", default=os.path.join(root, "docs", "data"))
    ap.add_argument("--out", default=os.path.join(root, "docs", "results", "which_set.png"))
    args = ap.parse_args()
    summary = os.path.join(args.data, "set_summary.csv")
    rows = []
    if os.path.exists(args.lib):
        rows = from_library(args.lib)
        with open(summary, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=COLUMNS)
            w.writeheader()
            w.writerows(rows)
        print(f"wrote {summary} ({len(rows)} sets, from {args.lib})")
    elif os.path.exists(summary):
        with open(summary, newline="") as f:
            rows = list(csv.DictReader(f))
        print(f"{args.lib}: absent; orders and limits from {summary}")
    if not rows:
        print("no library and no set_summary.csv: which-set chart not drawn")
        return 0
    draw(rows, args.data, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
