"""The pendulum on a cart of seed 000, from its T and U, for `python -m conmech.symbolic emit`.

Coordinates (x, theta): the cart's position and the pendulum's angle from the upward
vertical; the bob is at (x + l sin theta, l cos theta). With M = m = l = 1 the Euler-Lagrange
equations are the seed's 2 x'' + cos(th) th'' - sin(th) th'^2 = 0,
cos(th) x'' + th'' - g sin(th) = 0.

    python -m conmech.symbolic emit example/models/cart_pendulum.py \\
        -o example/cart_pendulum_model.f90
"""
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

from conmech.symbolic.derive import derive_lagrangian

name = "cart_pendulum_sym"   # the Fortran type (module: the output file's stem)


def inputs():
    """(L, q, params): also for conmech.symbolic.lagrangian_system(*inputs())."""
    x, th = dynamicsymbols("x theta")
    t = dynamicsymbols._t
    mc, m, l, g = sp.symbols("mc m l g", positive=True)   # mc: the cart's mass M
    xd, thd = x.diff(t), th.diff(t)
    T = mc * xd ** 2 / 2 + m * ((xd + l * sp.cos(th) * thd) ** 2
                                + (l * sp.sin(th) * thd) ** 2) / 2
    U = m * g * l * sp.cos(th)
    return T - U, [x, th], {mc: 1.0, m: 1.0, l: 1.0, g: 9.81}


def model():
    L, q, params = inputs()
    return derive_lagrangian(L, q, params=params)
