"""The planar two-body problem (Kepler), y = [x, y, u, v], as a first-order system for
`python -m conmech.symbolic emit`: the emitted type has Taylor coefficients (taylor_jet)
besides rhs and the exact Jacobian, so METHOD_TAYLOR integrates it.

    python -m conmech.symbolic emit example/models/kepler.py -o test/taylor_kepler_model.f90
"""
import sympy as sp

from conmech.symbolic.derive import derive_ode

name = "kepler_sym"


def model():
    x, y, u, v = sp.symbols("x y u v")
    mu = sp.Symbol("mu")
    r3 = (x ** 2 + y ** 2) ** sp.Rational(3, 2)
    return derive_ode([u, v, -mu * x / r3, -mu * y / r3], [x, y, u, v], params={mu: 1.0})
