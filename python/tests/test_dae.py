"""The pendulum as an index-3 DAE (examples/pendulum_dae.c) with Python callbacks."""
import math

import numpy as np
import scipy.sparse as sp

import ceode

GRAV, LEN = 9.81, 1.0


def force(t, x, v, out):
    out[0] = 0.0
    out[1] = -GRAV
    out[2] = 0.0


def phi(t, x, out):
    out[0] = x[0] - LEN * math.sin(x[2])
    out[1] = x[1] + LEN * math.cos(x[2])


def phi_jac(t, x, G):  # G: (2, 3), zeroed by CEODE
    G[0, 0] = 1.0
    G[0, 2] = -LEN * math.cos(x[2])
    G[1, 1] = 1.0
    G[1, 2] = -LEN * math.sin(x[2])


def run(mass, h=1e-3, tend=10.0):
    s = ceode.Integrator(force, 0.0, [LEN, 0.0, 2.0 * math.atan(1.0)], [0.0, 0.0, 0.0],
                         method="G5_ONES")
    s.set_zero_start(True)
    s.set_fixed_step(h)
    s.set_stop_time(tend)
    s.set_mass(mass)
    s.set_constraints(phi, phi_jac, 2)
    drift, de, t = 0.0, 0.0, 0.0
    while t < tend - 0.5 * h:
        t, x, v = s.evolve(tend, one_step=True)
        drift = max(drift, abs(x[0] ** 2 + x[1] ** 2 - LEN**2))
        de = max(de, abs(0.5 * (v[0] ** 2 + v[1] ** 2) + GRAV * x[1]))
    return drift, de, s


def test_dae_pendulum_holds_its_constraint_to_round_off_and_the_papers_energy_error():
    # examples/pendulum_dae.c: drift below 1e-14, max |E - E0| within 10 % of the paper's
    # Table 11 figure 9.78e-10 (G5 ones, h = 1e-3).
    drift, de, s = run(np.diag([1.0, 1.0, 0.0]))
    assert drift <= 1e-14
    assert abs(de / 9.78e-10 - 1.0) < 0.10
    stats = s.stats()
    assert stats["steps"] == 10000 and stats["constr_jac_evals"] > 0
    lam = s.get_multipliers()
    assert lam.shape == (2,) and np.all(np.isfinite(lam))


def test_dae_pendulum_with_a_sparse_mass_matrix_gives_the_dense_ones_answer():
    # KLU on the saddle-point system against the dense solver: the same Newton iteration,
    # equal to round-off over 1 s.
    d1, e1, s1 = run(np.diag([1.0, 1.0, 0.0]), tend=1.0)
    d2, e2, s2 = run(sp.diags([1.0, 1.0, 0.0], format="csr"), tend=1.0)
    x1, x2 = s1.evolve(1.0)[1], s2.evolve(1.0)[1]
    assert d2 <= 1e-14
    assert np.max(np.abs(x1 - x2)) < 1e-12
