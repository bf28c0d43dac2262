"""ceode.Integrator against the C library, its dense output and its order."""
import math
import os
import subprocess

import numpy as np
import pytest

import ceode
from conftest import pendulum_rhs


def c_pendulum(method, h, tend):
    """The C library's steps (python/tests/pendulum_driver.c), parsed from %.17g."""
    driver = os.environ.get("CEODE_PENDULUM_DRIVER")
    if not driver:
        pytest.fail("CEODE_PENDULUM_DRIVER is not set (ctest sets it to pendulum_driver)")
    out = subprocess.run([driver, method, repr(h), repr(tend)], check=True,
                         capture_output=True, text=True).stdout
    return np.array([[float(w) for w in line.split()] for line in out.splitlines()])


def python_pendulum(method, h, tend):
    s = ceode.Integrator(pendulum_rhs, 0.0, [0.0], [0.0], method=method)
    s.set_fixed_step(h)
    s.set_stability_guard("off")
    s.set_stop_time(tend)
    rows, t = [], 0.0
    while t < tend - 0.5 * h:
        t, x, v = s.evolve(tend, one_step=True)
        rows.append((t, x[0], v[0]))
    return np.array(rows), s


@pytest.mark.parametrize("method", ["G3_CD", "G4_A34", "G5_ONES"])
def test_pendulum_matches_the_c_example_bit_for_bit(method):
    # Same f, same operation order, same calls: every step must be the same double.
    ref = c_pendulum(method, 1e-3, 10.0)
    got, s = python_pendulum(method, 1e-3, 10.0)
    assert ref.shape == got.shape == (10000, 3)
    assert np.array_equal(ref, got)
    stats = s.stats()
    assert stats["steps"] == 10000
    # Every f evaluation is a Python call, plus the start's check of the x' dependence.
    assert stats["rhs_evals"] <= stats["python_calls"] <= stats["rhs_evals"] + 2


def test_pendulum_energy_error_is_the_papers_figure():
    # examples/pendulum_ode.c's check: the paper's max |E - E0| for G4_A34 at h = 1e-3 is
    # 4.3364e-7 (Table 4); the example accepts 5 %.
    got, _ = python_pendulum("G4_A34", 1e-3, 10.0)
    energy = 0.5 * got[:, 2] ** 2 + 9.81 * np.sin(got[:, 1])
    assert abs(np.max(np.abs(energy)) / 4.3364e-7 - 1.0) < 0.05


def test_evolve_many_equals_repeated_evolve():
    times = np.linspace(0.05, 2.0, 40) + 0.00037  # between step points: dense output
    a = ceode.Integrator(pendulum_rhs, 0.0, [0.3], [0.1])
    b = ceode.Integrator(pendulum_rhs, 0.0, [0.3], [0.1])
    for s in (a, b):
        s.set_fixed_step(1e-2)
    X, V = a.evolve_many(times)
    assert X.shape == V.shape == (40, 1)
    for i, t in enumerate(times):
        tb, xb, vb = b.evolve(t)
        assert tb == t
        assert X[i, 0] == xb[0] and V[i, 0] == vb[0]
    assert a.stats()["steps"] == b.stats()["steps"]


def test_evolve_many_interpolates_to_the_sets_order():
    # x'' = -x: the dense output between step points errs at the method's order (h = 1e-2,
    # G4_A34, third order: about 1e-7 over 2 s).
    s = ceode.Integrator(lambda t, x, v, out: out.__setitem__(0, -x[0]), 0.0, [1.0], [0.0])
    s.set_fixed_step(1e-2)
    times = np.linspace(0.013, 2.0, 57)
    X, V = s.evolve_many(times)
    assert np.max(np.abs(X[:, 0] - np.cos(times))) < 1e-6
    assert np.max(np.abs(V[:, 0] + np.sin(times))) < 1e-6


@pytest.mark.parametrize("method,hmax", [("G3_CD", 0.04), ("G4_A34", 0.04), ("G5_ONES", 0.08)])
def test_the_order_of_a_set_from_a_log_log_fit_is_method_order(method, hmax):
    # Damped oscillator x'' + 2 z x' + x = 0 on the implicit path; five halvings of h from
    # hmax over 10 s (test/test_convergence.cpp's steps, which keep the smallest error above
    # round-off); a least-squares slope is good to a few hundredths, and 0.1 hides no lost
    # order (a lost order moves it by 1).
    z = 0.1
    wd = math.sqrt(1 - z * z)

    def exact(t):
        return math.exp(-z * t) * (math.cos(wd * t) + z / wd * math.sin(wd * t))

    def f(t, x, v, out):
        out[0] = -x[0] - 2 * z * v[0]

    hs = [hmax / 2**k for k in range(5)]
    errs = []
    for h in hs:
        s = ceode.Integrator(f, 0.0, [1.0], [0.0], method=method)
        s.set_fixed_step(h)
        s.set_velocity_dependence(True)
        s.set_stability_guard("off")
        t, x, _ = s.evolve(round(10 / h) * h)
        errs.append(abs(x[0] - exact(t)))
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert errs[-1] > 1e-11  # far above round-off: the fit measures the method
    assert abs(slope - ceode.method_order(method)) < 0.1


def test_method_given_by_parameters_is_the_named_set():
    # G4_A34's parameters as a sequence give the named set's steps exactly.
    degree, params = ceode.method_params("G4_A34")
    assert degree == 4 and len(params) == 3
    a = ceode.Integrator(pendulum_rhs, 0.0, [0.0], [0.0], method="G4_A34")
    b = ceode.Integrator(pendulum_rhs, 0.0, [0.0], [0.0], method=np.array(params))
    for s in (a, b):
        s.set_fixed_step(1e-3)
        s.set_stability_guard("off")
    ra, rb = a.evolve(1.0), b.evolve(1.0)
    assert ra[0] == rb[0] and np.array_equal(ra[1], rb[1]) and np.array_equal(ra[2], rb[2])


def test_tolerances_choose_the_steps_and_meet_the_accuracy():
    s = ceode.Integrator(lambda t, x, v, out: out.__setitem__(0, -x[0]), 0.0, [1.0], [0.0])
    s.set_tolerances(1e-8, 1e-10)
    t, x, v = s.evolve(5.0)
    assert t == 5.0
    # Local error control, 5 s: the global error stays within a few hundred tolerances.
    assert abs(x[0] - math.cos(5.0)) < 1e-5
    s.reinit(0.0, [1.0], [0.0])
    s.set_tolerances(1e-8, np.array([1e-10]))
    t2, x2, _ = s.evolve(5.0)
    assert x2[0] == x[0]


def test_stable_step_is_the_stability_limit_over_omega():
    # x'' = -w^2 x: omega_max = w; the guard's Lanczos bound is within 0.1 % above it.
    w = 30.0
    s = ceode.Integrator(lambda t, x, v, out: out.__setitem__(0, -w * w * x[0]),
                         0.0, [1.0], [0.0], method="G3_CD")
    s.set_fixed_step(1e-3)
    h = s.get_stable_step()
    expected = 0.99 * ceode.stability_limit("G3_CD") / w
    assert expected * (1 - 1e-3) <= h <= expected * (1 + 1e-12)


def test_the_guard_refuses_an_unstable_step_with_ce_unstable():
    s = ceode.Integrator(lambda t, x, v, out: out.__setitem__(0, -100.0 * x[0]),
                         0.0, [1.0], [0.0], method="G3_CD")
    s.set_fixed_step(0.5)  # h omega = 5 > 2
    s.set_stability_guard("refuse")
    with pytest.raises(ceode.CEodeError) as info:
        s.evolve(1.0)
    assert info.value.flag_name == "CE_UNSTABLE"
    assert info.value.flag == -16


def test_the_guard_warns_as_a_ceode_warning():
    s = ceode.Integrator(lambda t, x, v, out: out.__setitem__(0, -100.0 * x[0]),
                         0.0, [1.0], [0.0], method="G3_CD")
    s.set_fixed_step(0.3)  # h omega = 3 > 2: the guard warns once and the run goes on
    with pytest.warns(ceode.CEodeWarning, match="is stable"):
        t, _, _ = s.evolve(0.9)
    assert t == pytest.approx(0.9, rel=1e-15)


def test_close_frees_the_memory_and_later_calls_raise():
    with ceode.Integrator(pendulum_rhs, 0.0, [0.0], [0.0]) as s:
        s.set_fixed_step(1e-2)
        s.evolve(0.1)
    with pytest.raises(ceode.CEodeError) as info:
        s.evolve(0.2)
    assert info.value.flag_name == "CE_MEM_NULL"
    s.close()  # a second close is harmless


def test_roots_stop_evolve_at_the_event_time():
    # A ball dropped from 1 m hits x = 0 at sqrt(2 / g); the root is located on the dense
    # output of a third-order set, exact here (the solution is a parabola) to round-off.
    s = ceode.Integrator(lambda t, x, v, out: out.__setitem__(0, -9.81), 0.0, [1.0], [0.0])
    s.set_fixed_step(1e-2)
    s.set_roots(lambda t, x, v, gout: gout.__setitem__(0, x[0]), 1, direction=[-1])
    t, x, v = s.evolve(5.0)
    assert s.last_flag == 2  # CE_ROOT_RETURN
    assert list(s.root_info()) == [-1]
    assert abs(t - math.sqrt(2 / 9.81)) < 1e-12 and abs(x[0]) < 1e-12


def test_newton_with_a_dense_linear_solver_takes_jacobians_and_the_same_solution():
    # x'' = -x - 0.2 x' on the implicit path: Newton with SUNLinSol_Dense (difference-quotient
    # Jacobians) and fixed point without a solver converge to the same step to their
    # tolerances; both lie within the method's error (G4_A34, h = 1e-2: 1e-6) of the exact one.
    z = 0.1
    wd = math.sqrt(1 - z * z)

    def f(t, x, v, out):
        out[0] = -x[0] - 2 * z * v[0]

    runs = []
    for solver in (True, False):
        s = ceode.Integrator(f, 0.0, [1.0], [0.0])
        s.set_fixed_step(1e-2)
        s.set_velocity_dependence(True)
        s.set_implicit_mode("newton")
        if solver:
            s.set_linear_solver("dense")
        t, x, _ = s.evolve(10.0)
        runs.append((x[0], s.stats()))
    exact = math.exp(-z * 10.0) * (math.cos(wd * 10.0) + z / wd * math.sin(wd * 10.0))
    (xn, newton), (xf, fixed) = runs
    assert newton["jac_evals"] > 0 and newton["lin_setups"] > 0 and fixed["jac_evals"] == 0
    assert newton["nls_steps"] == fixed["nls_steps"] == 1000
    assert abs(xn - exact) < 1e-6 and abs(xf - exact) < 1e-6
    with pytest.raises(ValueError):
        s.set_implicit_mode("sometimes")


def test_the_diagonal_solve_takes_one_evaluation_a_step_and_newtons_solution():
    # x'' = -x - 2 z x': f is affine in x' with df/dx' = -2 z, so the step's equation is solved
    # exactly with one f a step; Newton at tight tolerances solves the same equation.
    z = 0.1

    def f(t, x, v, out):
        out[0] = -x[0] - 2 * z * v[0]

    runs = []
    for diagonal in (True, False):
        s = ceode.Integrator(f, 0.0, [1.0], [0.0], method="G4_A34")
        s.set_fixed_step(1e-2)
        s.set_velocity_dependence(True)
        if diagonal:
            s.set_vel_jac_diagonal([-2 * z])
        else:
            s.set_implicit_mode("newton")
            s.set_linear_solver("dense")
        t, x, _ = s.evolve(10.0)
        runs.append((x[0], s.stats()))
    (xd, diag), (xn, _) = runs
    assert diag["rhs_evals"] - diag["start_rhs_evals"] == diag["steps"] == 1000
    assert diag["nls_steps"] == 0 and diag["pc_steps"] == 0
    assert abs(xd - xn) < 1e-9
    with pytest.raises(ValueError):
        s.set_vel_jac_diagonal([1.0, 2.0])  # one unknown
    with pytest.raises(ceode.CEodeError):
        s.set_vel_jac_diagonal([float("nan")])
    s.set_vel_jac_diagonal(None)
