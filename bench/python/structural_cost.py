#!/usr/bin/env python3
"""The structural path's cost: ceode.LinearStructure on the Q4 plate of bench/fe_plate_model.h
(~10^5 DOF) against the C scene on the identical K and M, time per step side by side.

The model: exported by bench/fe_plate_c_scene and read by problem_plate.py (which checks that
scipy's K reproduces the C product). The steps: wp_fe_plate's scaling rule, G3_CD at 0.9 and
G4_A34 at 0.8 x 0.9 of G3_CD's stable step from the guard (Python's get_stable_step; the C
program's own guard figure is printed beside it). Both sides integrate from the scaling scene's
start with the guard off and f velocity-independent, one untimed chunk of steps first, then
chunks timed on the process CPU clock (each side its own process); rounds alternate Python and
C, set by set, so that a burst of load falls on both. Reported: the median seconds per step over
every chunk of every round and the spread (max/min - 1) of each side, and the ratio Python / C as
the median over the rounds of each round's ratio of medians (with its range), and the fastest
chunk's over the fastest chunk's (load only adds time: the least disturbed figure of each side).
Writes <out>/python_structural.csv.

Usage: structural_cost.py --c-scene PATH [--out DIR] [--ny 112] [--rounds 5] [--quick]
"""
import argparse
import csv
import os
import statistics
import sys

import numpy as np

import harness as H
import problem_plate

SETS = (("G3_CD", 0.9), ("G4_A34", 0.8 * 0.9))  # wp_fe_plate: kScaleFrac x 0.9 x G3_CD's step
FIELDS = ["set", "dof", "h", "python_s_per_step", "python_spread", "c_s_per_step", "c_spread",
          "ratio_python_over_c", "ratio_min", "ratio_max", "ratio_of_best", "chunks"]


def py_chunks(ceode, model, plate, method, h, chunk, reps):
    """Seconds per step of `reps` timed chunks after one untimed chunk."""
    s = ceode.Integrator(model, 0.0, plate.x0, np.zeros(plate.n), method=method)
    s.set_velocity_dependence(False)
    s.set_fixed_step(h)
    s.set_stability_guard(mode="off")
    t, _, _ = s.evolve(chunk * h)
    out = []
    for _ in range(reps):
        n0 = s.stats()["steps"]
        c0 = H.cpu()
        t, _, _ = s.evolve(t + chunk * h)
        sec = H.cpu() - c0
        out.append(sec / (s.stats()["steps"] - n0))
    return out


def spread(v):
    return max(v) / min(v) - 1


def report(method, h, dof, py, c, ratios):
    """One CSV row: medians and spreads of each side; the ratio is the median over the rounds of
    each round's ratio (Python and C measured seconds apart, so a change of load between rounds
    falls on both)."""
    mp, mc, r = statistics.median(py), statistics.median(c), statistics.median(ratios)
    print(f"{method:<7} h = {h:.4g}: Python {1e3 * mp:.3f} ms/step (spread {100 * spread(py):.0f} "
          f"%), C {1e3 * mc:.3f} ms/step (spread {100 * spread(c):.0f} %); ratio Python / C: "
          f"{r:.3f} (median of the rounds' {', '.join(f'{x:.2f}' for x in ratios)}); "
          f"best chunk over best chunk {min(py) / min(c):.3f}")
    return {"set": method, "dof": dof, "h": f"{h:.6e}", "python_s_per_step": f"{mp:.6e}",
            "python_spread": f"{spread(py):.3f}", "c_s_per_step": f"{mc:.6e}",
            "c_spread": f"{spread(c):.3f}", "ratio_python_over_c": f"{r:.3f}",
            "ratio_min": f"{min(ratios):.3f}", "ratio_max": f"{max(ratios):.3f}",
            "ratio_of_best": f"{min(py) / min(c):.3f}",
            "chunks": len(py)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--c-scene", required=True)
    ap.add_argument("--out", default=".")
    ap.add_argument("--ny", type=int, default=112)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    import ceode
    ny = 24 if args.quick else args.ny
    nx = 4 * ny
    plate = problem_plate.load(args.c_scene, nx, ny)
    model = ceode.LinearStructure(plate.mass, plate.K)
    g3 = ceode.Integrator(model, 0.0, plate.x0, np.zeros(plate.n), method="G3_CD")
    h_cd = g3.get_stable_step()
    _, c_stable = problem_plate.c_time(args.c_scene, nx, ny, "G3_CD", h_cd, 1, 1)
    chunk = max(20, min(200, int(1e7 / plate.n)))
    reps = 3
    print(f"Q4 plate {nx} x {ny}: {plate.n} DOF, {plate.K.nnz} nonzeros (K checked against the "
          f"C product); G3_CD stable step: Python get_stable_step {h_cd:.6g}, C guard at safety "
          f"1 {c_stable:.6g}; {args.rounds} rounds x {reps} chunks of {chunk} steps a side")
    times = {m: ([], [], []) for m, _ in SETS}  # Python chunks, C chunks, ratio of each round
    for _ in range(args.rounds):
        for method, frac in SETS:
            h = frac * h_cd
            py = py_chunks(ceode, model, plate, method, h, chunk, reps)
            c = problem_plate.c_time(args.c_scene, nx, ny, method, h, chunk, reps)[0]
            times[method][0].extend(py)
            times[method][1].extend(c)
            times[method][2].append(statistics.median(py) / statistics.median(c))
    rows = [report(method, frac * h_cd, plate.n, *times[method]) for method, frac in SETS]
    os.makedirs(args.out, exist_ok=True)
    path = os.path.join(args.out, "python_structural.csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
