"""A nonlinear spring chain of 1000 masses: the FPU-beta chain with fixed ends.

x_i'' = (d_i - d_{i-1}) + beta (d_i^3 - d_{i-1}^3), d_i = x_{i+1} - x_i, x_0 = x_{N+1} = 0,
N = 1000, beta = 1, unit masses and springs; started at rest on A sin(pi m i / (N + 1)) with
m = 50, A = 2 (largest strain 0.31: the cubic force is up to 10 % of the linear one; the
higher harmonics it feeds make accuracy, not only the stability limit, decide the step),
t in [0, 100], outputs every 10. f is written once, numpy-vectorised. Error: max over the outputs of
||x - x_ref||_2 / ||x0||_2; drift: max |E - E0| / E0 there.
"""
import numpy as np

from harness import first_order

N, BETA, MODE, AMP = 1000, 1.0, 50, 2.0


class Problem:
    scene = "python_fpu_chain"
    n = N
    t0 = 0.0
    uses_v = False
    atol_scale = 1e-2  # atol = 1e-2 rtol: the displacements are of order 10
    # Fixed steps as fractions of G4_A34's stable step (harness.fixed_steps rounds them).
    fractions = {"G4_A34": [0.95, 0.7, 0.5, 0.35, 0.25, 0.18, 0.12],
                 "G5_O4": [0.95, 0.7, 0.5, 0.35, 0.25, 0.18],
                 "G8_O8": [0.95, 0.7, 0.5, 0.35]}
    adaptive = {"G8_O8": [1e-5, 1e-7, 1e-9, 1e-11]}
    rtols = [1e-4, 1e-6, 1e-8, 1e-10]
    levels = [1e-4, 1e-6, 1e-8]

    def __init__(self):
        self.t_out = np.arange(10.0, 101.0, 10.0)
        i = np.arange(1, N + 1)
        self.x0 = AMP * np.sin(np.pi * MODE * i / (N + 1))
        self.v0 = np.zeros(N)
        self._pad = np.zeros(N + 2)
        self.f1 = first_order(self.f2, N)
        self.e0 = float(self.energy(self.x0[None, :], self.v0[None, :])[0])
        self.ref = None

    def f2(self, t, x, v, out):
        pad = self._pad
        pad[1:-1] = x
        d = np.diff(pad)
        s = d + BETA * d ** 3
        np.subtract(s[1:], s[:-1], out=out)

    @staticmethod
    def energy(X, V):
        Z = np.zeros((X.shape[0], 1))
        d = np.diff(np.hstack((Z, X, Z)), axis=1)
        return 0.5 * np.sum(V ** 2, axis=1) + np.sum(0.5 * d ** 2 + 0.25 * BETA * d ** 4, axis=1)

    def error(self, X, V):
        err = np.max(np.linalg.norm(X - self.ref[0], axis=1)) / np.linalg.norm(self.x0)
        drift = np.max(np.abs(self.energy(X, V) - self.e0)) / self.e0
        return float(err), float(drift)
