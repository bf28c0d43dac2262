#!/usr/bin/env python3
"""Error against CPU time for bench/wp_high_order's CSV (docs/results/wp_high_order.csv).

usage: /usr/bin/python3 scripts/plot_wp_high_order.py [CSV] [PNG]
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

src = sys.argv[1] if len(sys.argv) > 1 else "docs/results/wp_high_order.csv"
out = sys.argv[2] if len(sys.argv) > 2 else "docs/results/wp_high_order.png"
rows = defaultdict(lambda: defaultdict(list))
with open(src) as f:
    for r in csv.DictReader(f):
        err = max(float(r["error"]), 1e-17)  # exact agreement with the reference: plot at 1e-17
        rows[r["scene"]][r["solver"]].append((float(r["seconds"]), err))
shown = ["G5", "G6_O5", "G7_O7", "G8_O8", "G8_O8+comp", "gsl_rk8pd", "odeint_rkf78", "odeint_bs",
         "arkode_erk8"]
fig, axes = plt.subplots(1, len(rows), figsize=(6 * len(rows), 4.5))
for ax, (scene, solvers) in zip(axes if len(rows) > 1 else [axes], rows.items()):
    for name in shown:
        if name in solvers:
            pts = sorted(solvers[name])
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o-" if name[0] == "G" else "s--",
                      ms=3, label=name)
    ax.axhline(1e-9, color="gray", lw=0.5)
    ax.axhline(1e-11, color="gray", lw=0.5)
    ax.set_title(scene)
    ax.set_xlabel("CPU time per run [s]")
    ax.set_ylabel("error at t = 10")
    ax.grid(True, which="both", lw=0.3)
    ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(out, dpi=110)
print("wrote", out)
