#!/usr/bin/env python3
"""The structural path's cost: ceode.LinearStructure on the Q4 plate of bench/fe_plate_model.h
(~10^5 DOF) against the C scene on the identical K and M, time per step side by side.

The model: exported by bench/fe_plate_c_scene and read by problem_plate.py (which checks that
scipy's K reproduces the C product). The steps: wp_fe_plate's scaling rule, G3_CD at 0.9 and
G4_A34 at 0.8 x 0.9 of G3_CD's stable step from the guard (Python's get_stable_step; the C
program's own guard figure is printed beside it). Both sides integrate from the scaling scene's
start with the guard off and f velocity-independent, one untimed chunk of steps first, then
chunks timed on the process CPU clock, each side in its own process: the C program
(`fe_plate_c_scene serve`) runs a chunk whenever this script asks, so Python's chunks and C's
alternate one by one (the order swapped every pair), each side idle while the other runs, and a
change of load falls on both chunks of a pair. Reported per set: the median seconds per step
and the spread (max/min - 1) of each side, and the ratio Python / C as the median over the pairs
of each pair's ratio (with its quartiles), and the fastest chunk's over the fastest chunk's (load
only adds time: the least disturbed figure of each side). Writes <out>/python_structural.csv.

Usage: structural_cost.py --c-scene PATH [--out DIR] [--ny 112] [--pairs 15] [--quick]
"""
import argparse
import os
import statistics
import subprocess
import sys

import numpy as np

import harness as H
import problem_plate

SETS = (("G3_CD", 0.9), ("G4_A34", 0.8 * 0.9))  # wp_fe_plate: kScaleFrac x 0.9 x G3_CD's step
FIELDS = ["set", "dof", "h", "python_s_per_step", "python_spread", "c_s_per_step", "c_spread",
          "ratio_python_over_c", "ratio_q1", "ratio_q3", "ratio_of_best", "pairs"]


class PyScene:
    """The Python side: one integrator, an untimed chunk, then chunk() = seconds per step."""

    def __init__(self, ceode, model, plate, method, h, chunk):
        self.s = ceode.Integrator(model, 0.0, plate.x0, np.zeros(plate.n), method=method)
        self.s.set_velocity_dependence(False)
        self.s.set_fixed_step(h)
        self.s.set_stability_guard(mode="off")
        self.h, self.n = h, chunk
        self.t, _, _ = self.s.evolve(chunk * h)

    def chunk(self):
        n0 = self.s.stats()["steps"]
        c0 = H.cpu()
        self.t, _, _ = self.s.evolve(self.t + self.n * self.h)
        sec = H.cpu() - c0
        return sec / (self.s.stats()["steps"] - n0)


class CScene:
    """The C side: fe_plate_c_scene serve, one timed chunk per request."""

    def __init__(self, exe, nx, ny, method, h, chunk):
        self.p = subprocess.Popen([exe, "serve", str(nx), str(ny), method, repr(h), str(chunk)],
                                  stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        self.stable_step = float(self.p.stdout.readline().split()[1])

    def chunk(self):
        self.p.stdin.write("chunk\n")
        self.p.stdin.flush()
        words = self.p.stdout.readline().split()
        if len(words) != 3:
            raise RuntimeError("fe_plate_c_scene serve stopped")
        return float(words[2])

    def close(self):
        self.p.stdin.close()
        if self.p.wait() != 0:
            raise RuntimeError(f"fe_plate_c_scene serve failed (exit {self.p.returncode})")


def measure(py, c, pairs):
    """(Python's, C's seconds per step, the pairs' ratios): chunks alternating, order swapped."""
    tp, tc, ratios = [], [], []
    for k in range(pairs):
        if k % 2 == 0:
            a = py.chunk()
            b = c.chunk()
        else:
            b = c.chunk()
            a = py.chunk()
        tp.append(a)
        tc.append(b)
        ratios.append(a / b)
    return tp, tc, ratios


def spread(v):
    return max(v) / min(v) - 1


def report(method, h, dof, py, c, ratios):
    """One CSV row: medians and spreads of each side, the median pair ratio and its quartiles."""
    mp, mc = statistics.median(py), statistics.median(c)
    q1, r, q3 = statistics.quantiles(ratios, n=4)
    print(f"{method:<7} h = {h:.4g}: Python {1e3 * mp:.3f} ms/step (spread {100 * spread(py):.0f} "
          f"%), C {1e3 * mc:.3f} ms/step (spread {100 * spread(c):.0f} %); ratio Python / C: "
          f"{r:.3f} (median of {len(ratios)} pairs, quartiles {q1:.3f} .. {q3:.3f}); best chunk "
          f"over best chunk {min(py) / min(c):.3f}")
    return {"set": method, "dof": dof, "h": f"{h:.6e}", "python_s_per_step": f"{mp:.6e}",
            "python_spread": f"{spread(py):.3f}", "c_s_per_step": f"{mc:.6e}",
            "c_spread": f"{spread(c):.3f}", "ratio_python_over_c": f"{r:.3f}",
            "ratio_q1": f"{q1:.3f}", "ratio_q3": f"{q3:.3f}",
            "ratio_of_best": f"{min(py) / min(c):.3f}", "pairs": len(ratios)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--c-scene", required=True)
    ap.add_argument("--out", default=".")
    ap.add_argument("--ny", type=int, default=112)
    ap.add_argument("--pairs", type=int, default=15)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    import ceode
    ny = 24 if args.quick else args.ny
    nx = 4 * ny
    plate = problem_plate.load(args.c_scene, nx, ny)
    model = ceode.LinearStructure(plate.mass, plate.K)
    h_cd = ceode.Integrator(model, 0.0, plate.x0, np.zeros(plate.n), method="G3_CD").get_stable_step()
    chunk = max(20, min(200, int(1e7 / plate.n)))
    print(f"Q4 plate {nx} x {ny}: {plate.n} DOF, {plate.K.nnz} nonzeros (K checked against the "
          f"C product); G3_CD stable step from Python's get_stable_step {h_cd:.6g}; "
          f"{args.pairs} pairs of chunks of {chunk} steps")
    rows = []
    for method, frac in SETS:
        h = frac * h_cd
        c = CScene(args.c_scene, nx, ny, method, h, chunk)
        py = PyScene(ceode, model, plate, method, h, chunk)
        if method == "G3_CD":
            print(f"(the C guard's G3_CD stable step at safety 1: {c.stable_step:.6g})")
        rows.append(report(method, h, plate.n, *measure(py, c, args.pairs)))
        c.close()
    path = os.path.join(args.out, "python_structural.csv")
    H.write_csv(path, rows, FIELDS)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
