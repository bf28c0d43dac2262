#!/usr/bin/python3
"""Spectral radius rho(Omega) of CEODE's named sets beside RK3, RK4, AB4 and HHT-alpha.

Runs the ceode-stability tool for every method (same undamped oscillator, Omega = omega*h),
writes docs/data/stability_<method>.csv and draws docs/stability_g3/g4/g5.png.

Usage: /usr/bin/python3 scripts/plot_stability.py [--tool build/tools/ceode-stability]
Needs Debian's python3-matplotlib (the system interpreter /usr/bin/python3).
"""
import argparse
import csv
import os
import subprocess

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
COMPARISONS = ["RK3", "RK4", "AB4", "HHT"]
LABELS = {"HHT": "HHT-α (α = −0.05)", "RK3": "RK3 (Kutta)", "RK4": "RK4", "AB4": "AB4"}
FIGURES = {
    "g3": (["G3_CD", "G3_A43", "G3_A2"], 3.0, "Degree 3 (β = 1/2)"),
    "g4": (["G4_A54", "G4_A14", "G4_A34", "G3_CD"], 3.0, "Degree 4 (β = 1/3, γ = 1/2)"),
    "g5": (["G5", "G5_TOP", "G5_ONES", "G5_O4", "G4_A34"], 3.0, "Degree 5"),
}


def run_tool(tool, method, omega_max, points, out):
    cmd = [tool, "--method", method, "--omega-max", str(omega_max), "--points", str(points),
           "--csv", out]
    text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    for line in text.splitlines():
        if line.startswith("Omega_max"):
            return float(line.split()[1])
    raise RuntimeError("no Omega_max in the output of " + " ".join(cmd))


def read(path):
    with open(path) as f:
        rows = [r for r in csv.reader(line for line in f if not line.startswith("#"))]
    return [float(r[0]) for r in rows[1:]], [float(r[1]) for r in rows[1:]]


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--tool", default=os.path.join(ROOT, "build", "tools", "ceode-stability"))
    ap.add_argument("--points", type=int, default=1500)
    args = ap.parse_args()
    data = os.path.join(ROOT, "docs", "data")
    os.makedirs(data, exist_ok=True)
    limits = {}
    methods = sorted({m for ms, _, _ in FIGURES.values() for m in ms} | set(COMPARISONS))
    for m in methods:
        limits[m] = run_tool(args.tool, m, 3.0, args.points,
                             os.path.join(data, "stability_%s.csv" % m))
    with open(os.path.join(data, "stability_limits.csv"), "w") as f:
        f.write("method,Omega_max\n")
        for m in methods:
            f.write("%s,%.10g\n" % (m, limits[m]))
    for key, (sets, wmax, title) in FIGURES.items():
        fig, (ax, axz) = plt.subplots(1, 2, figsize=(11, 4.2), gridspec_kw={"width_ratios": [3, 2]})
        for m in sets + COMPARISONS:
            om, rho = read(os.path.join(data, "stability_%s.csv" % m))
            dashed = m in COMPARISONS or (key != "g3" and m.startswith("G3")) or (
                key == "g5" and m.startswith("G4"))
            lim = limits[m]
            label = "%s  (Ω_max = %s)" % (LABELS.get(m, m),
                                           "∞" if lim >= 20 else ("0" if lim == 0 else "%.4g" % lim))
            style = dict(lw=1.2, ls="--" if dashed else "-")
            ax.plot(om, rho, label=label, **style)
            sel = [(o, r - 1) for o, r in zip(om, rho) if o <= 1.0]
            axz.plot([o for o, _ in sel], [d for _, d in sel], **style)
        ax.axhline(1.0, color="k", lw=0.6)
        ax.set_xlim(0, wmax)
        ax.set_ylim(0.0, 1.6)
        ax.set_xlabel("Ω = ω h")
        ax.set_ylabel("spectral radius ρ")
        ax.set_title(title + ": x'' + ω² x = 0")
        ax.legend(fontsize=7.5, loc="lower left")
        axz.axhline(0.0, color="k", lw=0.6)
        axz.set_yscale("symlog", linthresh=1e-8)
        axz.set_xlim(0, 1.0)
        axz.set_xlabel("Ω = ω h")
        axz.set_ylabel("ρ − 1 (symlog)")
        axz.set_title("near ρ = 1")
        fig.tight_layout()
        fig.savefig(os.path.join(ROOT, "docs", "stability_%s.png" % key), dpi=110)
        plt.close(fig)
    for m in methods:
        print("%-8s Omega_max = %.10g" % (m, limits[m]))


if __name__ == "__main__":
    main()
