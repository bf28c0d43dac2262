"""ceode.LinearStructure (C++ right-hand side) against the same model as a Python callback."""
import numpy as np
import pytest
import scipy.sparse as sp

import ceode
from conftest import chain_matrices

N = 12
H = 2e-3
T = 1.0


def start():
    x0 = np.sin(np.linspace(0.0, 2.0, N))
    return x0, np.zeros(N)


def run(f, mass=None, velocity=None):
    x0, v0 = start()
    s = ceode.Integrator(f, 0.0, x0, v0, method="G4_A34")
    s.set_fixed_step(H)
    if mass is not None:
        s.set_mass(mass)
    if velocity is not None:
        s.set_velocity_dependence(velocity)
    t, x, v = s.evolve(T)
    return x, v, s.stats()


def load(t, out):
    out[:] = 0.0
    out[-1] = np.sin(10.0 * t)


def test_lumped_structure_matches_the_python_callback_and_calls_no_python():
    m, K, _ = chain_matrices(N)

    def f(t, x, v, out):
        out[:] = -(K @ x) / m

    xs, vs, stats = run(ceode.LinearStructure(m, K))
    xp, vp, pstats = run(f)
    # Same steps, sums of at most three products per row in another order: round-off of the
    # state's size (|x| <= 1, |v| <= 30 here) after 500 steps.
    assert np.max(np.abs(xs - xp)) < 1e-13
    assert np.max(np.abs(vs - vp)) < 1e-11
    assert stats["python_calls"] == 0
    assert stats["rhs_evals"] == pstats["rhs_evals"]


def test_damped_forced_structure_matches_the_python_callback_with_one_call_per_evaluation():
    m, K, C = chain_matrices(N, c=2.0)

    def f(t, x, v, out):
        load(t, out)
        out[:] = (out - K @ x - C @ v) / m

    st = ceode.LinearStructure(m, K, C=C, force=load)
    assert st.damped and st.lumped and st.n == N
    xs, vs, stats = run(st, velocity=True)
    xp, vp, _ = run(f, velocity=True)
    assert np.max(np.abs(xs - xp)) < 1e-12
    assert np.max(np.abs(vs - vp)) < 1e-10
    # force(t, out) is the only Python call: one per evaluation of f (the integration's, the
    # guard's and the implicit-step coupling estimate's)
    evals = stats["rhs_evals"] + stats["guard_rhs_evals"] + stats["coupling_rhs_evals"]
    assert stats["python_calls"] == evals


def test_sparse_mass_structure_matches_the_python_callback_with_the_same_mass():
    m, K, _ = chain_matrices(N)
    M = sp.diags([0.1 * m[1:], m, 0.1 * m[1:]], [-1, 0, 1], format="csr")

    def f(t, x, v, out):
        out[:] = -(K @ x)

    xs, vs, stats = run(ceode.LinearStructure(M, K))
    xp, vp, _ = run(f, mass=M)
    # Both factor the same M with KLU; only f's sums differ in order.
    assert np.max(np.abs(xs - xp)) < 1e-13
    assert np.max(np.abs(vs - vp)) < 1e-11
    assert stats["python_calls"] == 0 and stats["mass_evals"] >= 1


def test_damped_sparse_mass_structure_uses_its_exact_velocity_jacobian():
    # Sparse M with C: Newton with KLU and J = -C from the structure. The Python model with a
    # dense M takes difference-quotient Jacobians; Newton on this linear system converges to
    # its tolerance, so the runs agree to well below the method's error (2e-6 at this h).
    m, K, C = chain_matrices(N, c=2.0)
    M = sp.diags(m, format="csr")

    def f(t, x, v, out):
        out[:] = -(K @ x) - C @ v

    xs, _, stats = run(ceode.LinearStructure(M, K, C=C), velocity=True)
    xp, _, _ = run(f, mass=M.toarray(), velocity=True)
    assert np.max(np.abs(xs - xp)) < 1e-9
    assert stats["python_calls"] == 0


def test_structure_accepts_dense_arrays_for_k_and_c():
    m, K, C = chain_matrices(N, c=1.0)
    a, _, _ = run(ceode.LinearStructure(m, K, C=C), velocity=True)
    b, _, _ = run(ceode.LinearStructure(m, K.toarray(), C=C.toarray()), velocity=True)
    assert np.array_equal(a, b)


def test_stable_step_of_a_lumped_structure_bounds_the_chains_frequency():
    m, K, _ = chain_matrices(N)
    x0, v0 = start()
    s = ceode.Integrator(ceode.LinearStructure(m, K), 0.0, x0, v0, method="G3_CD")
    s.set_fixed_step(H)
    omega = np.sqrt(np.max(np.linalg.eigvals(np.diag(1 / m) @ K.toarray()).real))
    h = s.get_stable_step()
    exact = 0.99 * 2.0 / omega
    # The guard's Lanczos bound in the M inner product: omega_max at most 0.1 % high.
    assert exact * (1 - 1e-3) <= h <= exact * (1 + 1e-9)
