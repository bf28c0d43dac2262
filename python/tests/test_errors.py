"""Bad input, failing callbacks and non-finite values: clear exceptions, nothing leaked, and
the integrator usable afterwards."""
import gc
import math
import sys
import tracemalloc

import numpy as np
import pytest
import scipy.sparse as sp

import ceode
from conftest import chain_matrices, pendulum_rhs


class ModelError(Exception):
    pass


def oscillator(t, x, v, out):
    out[:] = -x


def fresh_answer(tend=1.0):
    s = ceode.Integrator(oscillator, 0.0, [1.0, 0.5], [0.0, 0.0])
    s.set_fixed_step(1e-2)
    return s.evolve(tend)


@pytest.mark.parametrize("x0,v0,exc", [
    (np.zeros((2, 2)), np.zeros(4), ValueError),    # 2-D
    ([1.0, 2.0], [0.0], ValueError),                # lengths differ
    ([], [], ValueError),                           # empty
    (["a", "b"], [0.0, 0.0], TypeError),            # not numbers
    (np.array([1 + 1j]), np.array([0j]), TypeError),  # complex
])
def test_bad_initial_states_raise_before_reaching_c(x0, v0, exc):
    with pytest.raises(exc):
        ceode.Integrator(oscillator, 0.0, x0, v0)


def test_bad_arguments_raise_value_or_type_errors():
    s = ceode.Integrator(oscillator, 0.0, [1.0, 0.5], [0.0, 0.0])
    with pytest.raises(ValueError, match="atol"):
        s.set_tolerances(1e-6, np.ones(3))
    with pytest.raises(ValueError, match="M is 3 x 3"):
        s.set_mass(np.eye(3))
    with pytest.raises(ValueError, match="non-finite"):
        s.set_mass(np.array([[1.0, 0.0], [0.0, np.nan]]))
    with pytest.raises(ValueError, match="mode"):
        s.set_stability_guard("sometimes")
    s.set_fixed_step(1e-2)
    with pytest.raises(ValueError, match="1-D"):
        s.evolve_many(np.ones((2, 2)))
    with pytest.raises(ValueError, match="decrease"):
        s.evolve_many([0.5, 0.2])
    with pytest.raises(TypeError):
        ceode.Integrator(42, 0.0, [1.0], [0.0])
    with pytest.raises(TypeError):
        ceode.Integrator(oscillator, 0.0, [1.0], [0.0], method=42)


def test_a_bad_method_name_is_a_ceode_error_naming_the_known_sets():
    with pytest.raises(ceode.CEodeError) as info:
        ceode.Integrator(oscillator, 0.0, [1.0], [0.0], method="G4_NOPE")
    assert info.value.flag == -2 and info.value.flag_name == "CE_ILL_INPUT"
    assert "G4_NOPE" in str(info.value) and "G4_A34" in str(info.value)
    with pytest.raises(ceode.CEodeError):
        ceode.stability_limit("G4_NOPE")


def test_a_ceode_error_carries_flag_name_and_ceodes_message():
    s = ceode.Integrator(oscillator, 0.0, [1.0], [0.0])
    with pytest.raises(ceode.CEodeError) as info:
        s.set_fixed_step(-1.0)
    assert info.value.flag_name == "CE_ILL_INPUT"
    assert "h" in str(info.value)
    with pytest.raises(ceode.CEodeError) as info:
        s.evolve(1.0)  # no step size and no tolerances
    assert "CEodeSetFixedStep" in str(info.value)


def test_a_callback_exception_reaches_the_caller_as_itself_and_the_integrator_recovers():
    state = {"fail": True}

    def f(t, x, v, out):
        if state["fail"] and t > 0.5:
            raise ModelError("model broke at t = %g" % t)
        out[:] = -x

    s = ceode.Integrator(f, 0.0, [1.0, 0.5], [0.0, 0.0])
    s.set_fixed_step(1e-2)
    with pytest.raises(ModelError, match="model broke") as info:
        s.evolve(1.0)
    ctx = info.value.__context__
    assert isinstance(ctx, ceode.CEodeError) and ctx.flag_name == "CE_RHSFUNC_FAIL"
    assert s.t <= 0.5 + 1e-12
    state["fail"] = False
    s.reinit(0.0, [1.0, 0.5], [0.0, 0.0])
    t, x, v = s.evolve(1.0)
    t0, x0, v0 = fresh_answer()
    assert t == t0 and np.array_equal(x, x0) and np.array_equal(v, v0)


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_a_non_finite_right_hand_side_ends_as_a_ceode_error(bad):
    def f(t, x, v, out):
        out[:] = -x
        if t >= 0.5:
            out[1] = bad

    s = ceode.Integrator(f, 0.0, [1.0, 0.5], [0.0, 0.0])
    s.set_fixed_step(1e-2)
    with pytest.raises(ceode.CEodeError) as info:
        s.evolve(1.0)
    assert info.value.flag_name == "CE_RHSFUNC_FAIL"
    assert "NaN or Inf" in str(info.value)


def test_x_and_v_are_read_only_in_the_callback():
    def f(t, x, v, out):
        x[0] = 0.0

    s = ceode.Integrator(f, 0.0, [1.0], [0.0])
    s.set_fixed_step(1e-2)
    with pytest.raises(ValueError, match="read-only"):
        s.evolve(1.0)


def test_a_failing_mass_or_constraint_callable_raises_its_exception():
    def mass(t, x):
        raise ModelError("no mass")

    s = ceode.Integrator(oscillator, 0.0, [1.0, 0.5], [0.0, 0.0])
    with pytest.raises(ModelError):
        s.set_mass(mass)  # probed once at set time
    calls = {"n": 0}

    def mass_later(t, x):
        calls["n"] += 1
        if calls["n"] > 3:
            raise ModelError("mass failed later")
        return np.eye(2)

    s.set_mass(mass_later, constant=False)
    s.set_fixed_step(1e-2)
    with pytest.raises(ModelError, match="later") as info:
        s.evolve(1.0)
    assert isinstance(info.value.__context__, ceode.CEodeError)


def test_linear_structure_checks_sizes_and_formats():
    m, K, _ = chain_matrices(5)
    with pytest.raises(ValueError, match="expected 5"):
        ceode.LinearStructure(np.ones(4), K)
    with pytest.raises(ValueError, match="positive"):
        ceode.LinearStructure(-m, K)
    with pytest.raises(ValueError, match="K is 5 x 4"):
        ceode.LinearStructure(m, sp.random(5, 4, density=0.5, format="csr"))
    with pytest.raises(ValueError, match="C is 4 x 4"):
        ceode.LinearStructure(m, K, C=sp.eye(4))
    with pytest.raises(TypeError, match="force"):
        ceode.LinearStructure(m, K, force=3.0)
    with pytest.raises(TypeError):
        ceode.LinearStructure(m, K.astype(complex))
    st = ceode.LinearStructure(m, K)
    with pytest.raises(ValueError, match="expected 5"):
        ceode.Integrator(st, 0.0, np.zeros(6), np.zeros(6))


def _failing_runs(n):
    def f(t, x, v, out):
        if t > 0.2:
            raise ModelError("fail")
        out[:] = -x

    for _ in range(n):
        s = ceode.Integrator(f, 0.0, np.ones(50), np.zeros(50))
        s.set_fixed_step(1e-2)
        try:
            s.evolve(1.0)
        except ModelError:
            pass
        s.reinit(0.0, np.ones(50), np.zeros(50))
        try:
            ceode.Integrator(f, 0.0, np.ones(3), np.ones(2))
        except ValueError:
            pass
    return f


def _rss_kb():
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * 4


def test_errors_leak_neither_python_objects_nor_native_memory():
    f = _failing_runs(50)  # warm-up: caches, interned strings, first allocations
    gc.collect()
    refs = sys.getrefcount(f)
    tracemalloc.start()
    before = tracemalloc.take_snapshot()
    rss0 = _rss_kb()
    _failing_runs(500)
    gc.collect()
    after = tracemalloc.take_snapshot()
    rss1 = _rss_kb()
    tracemalloc.stop()
    growth = sum(s.size_diff for s in after.compare_to(before, "filename"))
    # 500 runs that each create, fail and free an integrator of 50 DOF (~10 kB of vectors):
    # any per-run leak of Python objects would exceed 50 kB, of native memory 2 MB.
    assert growth < 50_000
    assert rss1 - rss0 < 2048
    assert sys.getrefcount(f) == refs


def test_a_cycle_through_the_right_hand_side_is_collected():
    import weakref

    class Model:
        def rhs(self, t, x, v, out):
            out[:] = -x

    model = Model()
    model.integ = ceode.Integrator(model.rhs, 0.0, [1.0], [0.0])
    ref = weakref.ref(model)
    del model
    gc.collect()
    assert ref() is None


def test_callbacks_cannot_reenter_or_close_their_integrator():
    def f(t, x, v, out):
        s.close()

    s = ceode.Integrator(f, 0.0, [1.0], [0.0])
    s.set_fixed_step(1e-2)
    with pytest.raises(RuntimeError, match="callbacks"):
        s.evolve(1.0)

    def g(t, x, v, out):
        s2.evolve(2.0)

    s2 = ceode.Integrator(g, 0.0, [1.0], [0.0])
    s2.set_fixed_step(1e-2)
    with pytest.raises(RuntimeError, match="running"):
        s2.evolve(1.0)
    s.reinit(0.0, [1.0], [0.0])  # both are still usable
    s2.close()
