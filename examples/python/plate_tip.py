#!/usr/bin/env python3
"""A cantilever plate under a suddenly applied tip load: ceode.LinearStructure against
scipy.integrate.solve_ivp on the same model.

Model: the Q4 plate of bench/fe_plate_model.h (4 x 1, plane stress, E = 1, nu = 0.3, rho = 1,
24 x 6 bilinear elements, clamped at x = 0, row-sum lumped mass), assembled here with numpy and
scipy.sparse. Load: a transverse force of total 1e-3 on the free edge's nodes from t = 0, the
plate at rest; 3 periods of the lowest mode. CEODE: G4_A34 at 0.9 of the guard's stable step.
solve_ivp: DOP853 at rtol 1e-10 (the reference) and RK45 at rtol 1e-6 on y = (x, v).
Check (exit 1 when it fails): CEODE's tip history within 1e-3 of the peak of DOP853's, and the
peak over the static deflection K^{-1} F within 10 % of 2, the dynamic amplification of a
suddenly applied load (mode 1 carries nearly all of the tip's static deflection).

Usage: PYTHONPATH=<build>/python python3 plate_tip.py [--out plate_tip.png]
"""
import argparse
import sys
import time

import matplotlib
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.integrate import solve_ivp

import ceode

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def q4_stiffness(dx, dy, E=1.0, nu=0.3, thick=1.0):
    """Plane-stress Q4 stiffness, nodes (0,0), (dx,0), (dx,dy), (0,dy), 2 x 2 Gauss points."""
    c = E / (1 - nu * nu)
    D = c * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])
    xi_n, eta_n, g = np.array([-1, 1, 1, -1]), np.array([-1, -1, 1, 1]), 1 / np.sqrt(3)
    k = np.zeros((8, 8))
    for xi in (-g, g):
        for eta in (-g, g):
            B = np.zeros((3, 8))
            dnx = 0.25 * xi_n * (1 + eta * eta_n) * 2 / dx
            dny = 0.25 * eta_n * (1 + xi * xi_n) * 2 / dy
            B[0, 0::2], B[1, 1::2], B[2, 0::2], B[2, 1::2] = dnx, dny, dny, dnx
            k += thick * dx * dy / 4 * B.T @ D @ B
    return k


def plate(nx, ny, lx=4.0, ly=1.0):
    """(K as CSR, lumped masses) on the free DOFs, numbered as bench/fe_plate_model.h numbers
    them: node (i, j), i >= 1, is (i - 1)(ny + 1) + j, its DOFs 2k and 2k + 1."""
    dx, dy = lx / nx, ly / ny
    ei, ej = (a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij"))
    node = lambda i, j: i * (ny + 1) + j  # noqa: E731
    nodes = np.stack([node(ei, ej), node(ei + 1, ej), node(ei + 1, ej + 1), node(ei, ej + 1)], 1)
    dofs = np.repeat(2 * nodes, 2, axis=1) + np.tile([0, 1], 4)
    ndof = 2 * (nx + 1) * (ny + 1)
    K = sp.csr_matrix((np.tile(q4_stiffness(dx, dy).ravel(), len(ei)),
                       (np.repeat(dofs, 8, axis=1).ravel(), np.tile(dofs, 8).ravel())),
                      shape=(ndof, ndof))
    mass = np.bincount(dofs.ravel(), minlength=ndof) * dx * dy / 4
    free = np.arange(2 * (ny + 1), ndof)
    K = K[free][:, free].tocsr()
    K.sort_indices()
    return K, mass[free]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="plate_tip.png")
    args = ap.parse_args()
    nx, ny = 24, 6
    K, m = plate(nx, ny)
    n = K.shape[0]
    edge = 2 * ((nx - 1) * (ny + 1) + np.arange(ny + 1)) + 1  # y-DOFs of the free edge
    tip = edge[ny // 2]
    F = np.zeros(n)
    F[edge] = 1e-3 / (ny + 1)
    w1 = np.sqrt(spla.eigsh(K, k=1, M=sp.diags(m), sigma=0, which="LM")[0][0])
    static = spla.spsolve(K.tocsc(), F)[tip]
    T = 3 * 2 * np.pi / w1
    times = np.linspace(0, T, 301)[1:]

    def force(t, out):
        out[:] = F

    s = ceode.Integrator(ceode.LinearStructure(m, K, force=force), 0.0, np.zeros(n),
                         np.zeros(n), method="G4_A34")
    h = 0.9 * s.get_stable_step()
    s.set_fixed_step(h)
    c0 = time.process_time()
    X, _ = s.evolve_many(times)
    t_ceode = time.process_time() - c0

    def f1(t, y):
        return np.concatenate((y[n:], (F - K @ y[:n]) / m))

    runs = {}
    for method, rtol in (("DOP853", 1e-10), ("RK45", 1e-6)):
        c0 = time.process_time()
        sol = solve_ivp(f1, (0, T), np.zeros(2 * n), method=method, rtol=rtol,
                        atol=1e-6 * rtol * abs(static), t_eval=times)
        runs[method] = (sol.y[tip], time.process_time() - c0, sol.nfev)
    ref = runs["DOP853"][0]
    peak = np.max(np.abs(ref))
    err = np.max(np.abs(X[:, tip] - ref)) / peak
    print(f"plate {nx} x {ny}: {n} DOF, omega_1 = {w1:.5g}, {T:.4g} time units, static tip "
          f"deflection {static:.5g}")
    print(f"CEODE G4_A34, h = {h:.4g} ({s.stats()['steps']} steps): {t_ceode:.3f} s, tip error "
          f"{err:.2e} of the peak against DOP853")
    for method in ("DOP853", "RK45"):
        y, sec, nfev = runs[method]
        print(f"solve_ivp {method}: {sec:.3f} s, {nfev} f evaluations, tip error "
              f"{np.max(np.abs(y - ref)) / peak:.2e}")
    amp = peak / abs(static)
    print(f"peak / static tip deflection {amp:.4f} (suddenly applied load: 2)")

    fig, ax = plt.subplots(figsize=(7, 3.6))
    ax.plot(times, X[:, tip], label="CEODE G4_A34")
    ax.plot(times[::6], ref[::6], "o", ms=3, mfc="none", label="solve_ivp DOP853")
    ax.axhline(static, ls=":", c="k", label="static deflection")
    ax.set_xlabel("t")
    ax.set_ylabel("tip displacement")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")
    ok = err <= 1e-3 and abs(amp - 2) <= 0.2
    print("check:", "passed" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
