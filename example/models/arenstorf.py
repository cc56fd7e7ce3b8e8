"""The Arenstorf orbit's equations (restricted three-body problem, rotating frame) as a
first-order system y' = f(t, y), y = [x, y, x', y'], for `python -m conmech.symbolic emit`.

    python -m conmech.symbolic emit example/models/arenstorf.py -o example/arenstorf_model.f90
"""
import sympy as sp

from conmech.symbolic.derive import derive_ode

name = "arenstorf_sym"


def model():
    x, y, u, w = sp.symbols("x y u w")
    mu = sp.Symbol("mu")
    mup = 1 - mu
    d1 = ((x + mu) ** 2 + y ** 2) ** sp.Rational(3, 2)
    d2 = ((x - mup) ** 2 + y ** 2) ** sp.Rational(3, 2)
    f = [u, w, x + 2 * w - mup * (x + mu) / d1 - mu * (x - mup) / d2,
         y - 2 * u - mup * y / d1 - mu * y / d2]
    return derive_ode(f, [x, y, u, w], params={mu: 0.012277471})
