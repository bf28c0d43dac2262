"""The stability functions against the C library's documented figures."""
import numpy as np
import pytest

import ceode


def test_methods_lists_every_named_set():
    names = ceode.methods()
    assert names[0] == "G3_CD" and "G4_A34" in names and "G8_O8" in names
    assert len(names) == len(set(names))


def test_central_differences_have_order_two_and_limit_two():
    # x'' = -w^2 x with central differences is stable for h w <= 2, exactly.
    assert ceode.method_order("G3_CD") == 2
    assert abs(ceode.stability_limit("G3_CD") - 2.0) < 1e-3  # the scan's 1e-3 grid


def test_method_order_of_every_set_is_its_documented_order():
    orders = {"G3_CD": 2, "G4_A34": 3, "G5_ONES": 4, "G6_O6": 6, "G7_O7": 7, "G8_O8": 8}
    for name, p in orders.items():
        assert ceode.method_order(name) == p
    degree, params = ceode.method_params("G4_A34")
    assert ceode.method_order(params) == 3


def test_spectral_radius_takes_floats_and_arrays():
    om = np.array([0.1, 1.0, 1.9, 2.5])
    rho = ceode.spectral_radius("G3_CD", om)
    assert rho.shape == om.shape
    for o, r in zip(om, rho):
        assert ceode.spectral_radius("G3_CD", float(o)) == r
    # Inside the limit |lambda| = 1 (to the eigenvalue tolerance), beyond it > 1.
    assert np.all(np.abs(rho[:3] - 1.0) < 1e-12) and rho[3] > 1.0


def test_stability_functions_refuse_bad_input():
    with pytest.raises(ceode.CEodeError):
        ceode.spectral_radius("G3_CD", -1.0)
    with pytest.raises(ceode.CEodeError):
        ceode.stability_limit("G3_CD", xi=-1.0)
    with pytest.raises(ValueError):
        ceode.method_order([1.0])
