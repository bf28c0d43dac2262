"""ceode.LinearStructure on the Q4 plate of bench/fe_plate_model.h against the C scene.

The plate's K and lumped M come from the C assembly itself (bench/fe_plate_c_scene export, read
by bench/python/problem_plate.py, which checks scipy's K p against the C product), and the C
program integrates the same plate through the C API with CEODE's f = -M^{-1} K x written in C
(fe::Accel). Both runs take the same set, the same fixed step and the same number of single
steps, so they differ only in how the acceleration's round-off falls (the C scene multiplies by
1/m, the structure's evaluation may divide by m): the states agree to a few ulps a step.

The C program is found through the environment variable CEODE_FE_PLATE_C_SCENE or in the build
tree of the module: <build>/bench/fe_plate_c_scene (benchmarks on) or
<build>/python/tests/fe_plate_c_scene (python/tests/CMakeLists.txt builds it when they are off).
"""
import os
import pathlib
import sys

import numpy as np
import pytest

ceode = pytest.importorskip("ceode")
ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench" / "python"))
import problem_plate  # noqa: E402

NX, NY = 16, 4  # 160 DOF, every node type of the mesh (clamped edge, free edges, corners)
STEPS = 200
# Round-off: a step adds a few ulps of the state's size (an 18-term row sum, the set's update);
# the plate's modes neither grow nor decay at a stable step, so the differences add up at most
# linearly: 200 steps x 20 ulps = 9e-13 of max |x|, and 1e-12 is that bound rounded up.
REL_TOL = 1e-12


def c_scene():
    env = os.environ.get("CEODE_FE_PLATE_C_SCENE")
    if env:
        return env
    build = pathlib.Path(ceode.__file__).resolve().parents[2]
    # bench/ with the benchmarks on, python/tests/ (python/tests/CMakeLists.txt) with them off
    for exe in (build / "bench" / "fe_plate_c_scene", build / "python" / "tests" / "fe_plate_c_scene"):
        if exe.exists():
            return str(exe)
    pytest.skip(f"fe_plate_c_scene not built in {build} (build the target fe_plate_c_scene, or "
                "set CEODE_FE_PLATE_C_SCENE)")


@pytest.fixture(scope="module")
def plate():
    return problem_plate.load(c_scene(), NX, NY)


def python_steps(plate, method, h, steps):
    s = ceode.Integrator(ceode.LinearStructure(plate.mass, plate.K), 0.0, plate.x0,
                         np.zeros(plate.n), method=method)
    s.set_fixed_step(h)
    s.set_stability_guard(mode="off")
    tfar = h * (steps + 10)
    for _ in range(steps):
        t, x, v = s.evolve(tfar, one_step=True)
    return t, x, v


def stable_step(plate, method):
    s = ceode.Integrator(ceode.LinearStructure(plate.mass, plate.K), 0.0, plate.x0,
                         np.zeros(plate.n), method=method)
    return s.get_stable_step()


@pytest.mark.parametrize("method", ["G3_CD", "G4_A34"])
def test_linear_structure_reproduces_the_c_scene_to_round_off(plate, method):
    h = 0.5 * stable_step(plate, method)
    t, x, v = python_steps(plate, method, h, STEPS)
    tc, xc, vc = problem_plate.c_run(c_scene(), NX, NY, method, h, STEPS)
    assert t == pytest.approx(tc, rel=1e-14)
    assert np.max(np.abs(x - xc)) <= REL_TOL * np.max(np.abs(xc))
    assert np.max(np.abs(v - vc)) <= REL_TOL * np.max(np.abs(vc))


def test_one_step_more_is_far_outside_the_round_off_bound(plate):
    # The bound discriminates: one step of difference moves the state by ~h |v|, orders of
    # magnitude above REL_TOL.
    h = 0.5 * stable_step(plate, "G4_A34")
    _, x, _ = python_steps(plate, "G4_A34", h, STEPS + 1)
    _, xc, _ = problem_plate.c_run(c_scene(), NX, NY, "G4_A34", h, STEPS)
    assert np.max(np.abs(x - xc)) > 1e3 * REL_TOL * np.max(np.abs(xc))


@pytest.mark.parametrize("bad", ["short_mass", "zero_mass", "nan_stiffness", "not_square"])
def test_a_malformed_structure_is_refused_with_an_error_not_a_crash(plate, bad):
    mass, K = plate.mass.copy(), plate.K.copy()
    if bad == "short_mass":
        mass = mass[:-1]
    elif bad == "zero_mass":
        mass[3] = 0.0  # a = -(K x)_3 / 0: a non-finite acceleration to be reported
    elif bad == "nan_stiffness":
        K.data[5] = np.nan
    else:
        K = K[:, :-1]
    with pytest.raises((ceode.CEodeError, ValueError, TypeError)):
        s = ceode.Integrator(ceode.LinearStructure(mass, K), 0.0, plate.x0[: K.shape[0]],
                             np.zeros(K.shape[0]), method="G4_A34")
        s.set_fixed_step(1e-3)
        s.evolve(1e-2)


def test_the_example_numpy_assembly_is_the_c_assembly(plate):
    # examples/python/plate_tip.py assembles the plate with numpy and scipy.sparse; it numbers
    # the DOFs as the C model does, so the matrices agree entry by entry. The entries are sums of
    # up to four element terms taken in another order: 4 ulps of the largest entry bound them.
    sys.path.insert(0, str(ROOT / "examples" / "python"))
    import plate_tip
    K, mass = plate_tip.plate(NX, NY)
    assert np.array_equal(K.indptr, plate.K.indptr)
    assert np.array_equal(K.indices, plate.K.indices)
    assert np.max(np.abs(K.data - plate.K.data)) <= 4 * np.finfo(float).eps * np.max(
        np.abs(plate.K.data))
    assert np.max(np.abs(mass - plate.mass)) <= np.finfo(float).eps * np.max(plate.mass)
