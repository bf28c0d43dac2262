"""Shared models of the Python tests (PYTHONPATH=<build>/python, set by ctest)."""
import math

import numpy as np
import pytest
import scipy.sparse as sp

GRAV = 9.81
LEN = 1.0


def pendulum_rhs(t, x, v, out):
    """examples/pendulum_ode.c's f, with its floating-point operations in its order."""
    out[0] = -(GRAV / LEN) * math.cos(x[0])


def chain_matrices(n, k=400.0, c=0.0):
    """A fixed-free spring chain: tridiagonal K (and C = c K / k), lumped masses 1..2."""
    main = 2.0 * np.ones(n)
    main[-1] = 1.0
    K = sp.diags([-np.ones(n - 1), main, -np.ones(n - 1)], [-1, 0, 1], format="csr") * k
    C = K * (c / k) if c else None
    m = np.linspace(1.0, 2.0, n)
    return m, K, C


@pytest.fixture
def chain():
    return chain_matrices(12)
