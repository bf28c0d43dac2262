"""CEODE: conditionally explicit integrators for M x'' = f(t, x, x') and index-3 DAEs.

The classes and functions are those of the extension ceode._ceode (docs/python.md):

    Integrator(f, t0, x0, v0, method="G4_A34")   the integrator over CEODE's C API
    LinearStructure(M, K, C=None, force=None)   M a = force(t) - K x - C v, evaluated in C++
    methods(), method_order(method), method_params(method), stability_limit(method, xi=0.0),
    spectral_radius(method, Omega, xi=0.0), version()
    CEodeError, CEodeWarning
"""
from ._errors import CEodeError, CEodeWarning
from ._ceode import (
    Integrator,
    LinearStructure,
    method_order,
    method_params,
    methods,
    spectral_radius,
    stability_limit,
    version,
)

__version__ = version()

__all__ = [
    "CEodeError",
    "CEodeWarning",
    "Integrator",
    "LinearStructure",
    "method_order",
    "method_params",
    "methods",
    "spectral_radius",
    "stability_limit",
    "version",
]
