"""The simple pendulum of examples/pendulum_ode.c and bench/oscillators/wp_pendulum_ode.cpp.

theta'' = -(g/L) cos(theta), theta(0) = theta'(0) = 0 (released from the horizontal), g = 9.81,
L = 1, m = 1, t in [0, 10] s; outputs at t = 1, 2, ..., 10. Error: max |theta - theta_ref| over
the outputs against a tight reference (harness.reference); drift: max |E - E0| there,
E = 1/2 theta'^2 + g sin(theta).
"""
import math

import numpy as np

from harness import first_order

GRAV, LEN = 9.81, 1.0


class Problem:
    scene = "python_pendulum"
    n = 1
    t0 = 0.0
    uses_v = False
    atol_scale = 1.0  # atol = rtol: theta is of order 1
    # CEODE's fixed-step curves (sets that lead the C scene) and tolerance curves; scipy's rtol.
    fixed = {"G4_A34": [1e-1, 5e-2, 2e-2, 1e-2, 5e-3, 2e-3],
             "G5": [1e-1, 5e-2, 2e-2, 1e-2, 5e-3, 2e-3, 1e-3],
             "G8_O8": [1e-1, 5e-2, 2.5e-2, 1e-2, 5e-3]}
    adaptive = {"G8_O8": [1e-6, 1e-8, 1e-10, 1e-12]}
    rtols = [1e-4, 1e-6, 1e-8, 1e-10, 1e-12]
    levels = [1e-6, 1e-9]

    def __init__(self):
        self.t_out = np.arange(1.0, 11.0)
        self.x0 = np.zeros(1)
        self.v0 = np.zeros(1)
        self.f1 = first_order(self.f2, self.n)
        self.ref = None  # (X, V) at t_out, set by harness.reference

    @staticmethod
    def f2(t, x, v, out):
        out[0] = -(GRAV / LEN) * math.cos(x[0])

    @staticmethod
    def energy(X, V):
        return 0.5 * V[:, 0] ** 2 + GRAV * LEN * np.sin(X[:, 0])

    def error(self, X, V):
        return (float(np.max(np.abs(X - self.ref[0]))),
                float(np.max(np.abs(self.energy(X, V)))))
