"""Families of symmetric periodic orbits of Hill's problem in Hénon's units (issue 9).

Hénon (1969, "Numerical exploration of the restricted problem. V. Hill's case: periodic
orbits and their stability", A&A 1, 223) writes Hill's problem without parameters,

    x'' - 2 y' = 3 x - x/r^3,   y'' + 2 x' = -y/r^3,   Gamma = 3 x^2 + 2/r - x'^2 - y'^2,

(``conmech.systems.hill(m=1, kappa=1)``; :func:`conmech.hill.to_henon` converts from
Hill's units) and classifies its families of orbits symmetric about the x axis. Three of
them are reached here from closed-form starts, then followed by the general
pseudo-arclength continuation of a conservative family (:func:`conmech.stability.
continuation` with ``in_period``: the period is the continued quantity, Gamma a function
of the point):

- :func:`lyapunov_orbit`: the orbits about the Lagrange points L2 (x = 3^(-1/3)) and L1
  (their mirror image), which start at Gamma = 3^(4/3) with the period 2 pi/sqrt(2 sqrt 7 -
  1) of the linearisation (Lyapunov's centre theorem);
- :func:`satellite_orbit`: near-circular retrograde (Hénon's family f) and direct (family
  g, which holds Hill's variation orbits) satellite orbits, from the Kepler limit r -> 0
  (period 2 pi/(n +- 1), n = r^(-3/2));
- :func:`family`: the continuation of either, with Gamma as the branch's ``energy``.

No initial condition was taken from Hénon's tables (they were not available to us); the
starts are the closed-form limits above.
"""
from __future__ import annotations

import numpy as np

from . import stability, systems

__all__ = ["system", "gamma", "X_L2", "GAMMA_L", "PERIOD_L", "lyapunov_orbit",
           "satellite_orbit", "family"]

#: x of the Lagrange point L2 (L1 at -X_L2) in Hénon's units
X_L2 = 3.0**(-1.0/3.0)
#: Gamma at L1, L2: 3 x^2 + 2/x = 3^(4/3)
GAMMA_L = 3.0**(4.0/3.0)
#: the period of the linear oscillation about L1, L2: 2 pi/sqrt(2 sqrt 7 - 1)
PERIOD_L = 2.0*np.pi/np.sqrt(2.0*np.sqrt(7.0) - 1.0)


def system():
    """Hill's problem in Hénon's units: ``conmech.systems.hill(m=1, kappa=1)``."""
    return systems.hill(m=1.0, kappa=1.0)


def gamma(y) -> np.ndarray | float:
    """Hénon's Jacobi constant Gamma = 3 x^2 + 2/r - x'^2 - y'^2 of states [x, y, x', y']
    (one state (4,) -> float, several (k, 4) -> array)."""
    a = np.asarray(y, dtype=float)
    if a.shape[-1:] != (4,):
        raise ValueError("states must be [x, y, x', y'] (last dimension 4)")
    r = np.hypot(a[..., 0], a[..., 1])
    g = 3.0*a[..., 0]**2 + 2.0/r - a[..., 2]**2 - a[..., 3]**2
    return float(g) if g.ndim == 0 else g


def _symmetric(y0, period, rtol):
    """The orbit through y0 = [x0, 0, 0, y'0] crossing the x axis at right angles again
    at half its period: y'0 and the half period free, x0 fixed."""
    return stability.symmetric_orbit(system(), y0, [3], [1, 2], period, period_factor=2,
                                     free_time=True, rtol=rtol, atol=rtol)


def lyapunov_orbit(amplitude: float, side: int = 1, rtol: float = 1e-12):
    """The periodic orbit about L2 (``side`` = +1) or L1 (-1) that crosses the x axis at
    right angles at x = +-(X_L2 + amplitude), from the linear oscillation (x - x_L =
    a cos w t, y = -(9 + w^2) a/(2 w) sin w t, w^2 = 2 sqrt 7 - 1) corrected by symmetric
    shooting. Returns a :class:`conmech.stability.PeriodicOrbit`."""
    a = stability._real(amplitude, "amplitude")
    if not 0 < abs(a) < 0.3:
        raise ValueError("amplitude must be non-zero and below 0.3 (the linear start)")
    if side not in (1, -1):
        raise ValueError("side must be +1 (L2) or -1 (L1)")
    w = 2.0*np.pi/PERIOD_L
    vy = -(9.0 + w*w)*a/2.0
    y0 = side*np.array([X_L2 + a, 0.0, 0.0, vy])
    return _symmetric(y0, PERIOD_L, rtol)


def satellite_orbit(r0: float, kind: str = "f", rtol: float = 1e-12):
    """A near-circular satellite orbit through (r0, 0) perpendicular to the x axis:
    ``kind`` 'f' retrograde, 'g' direct (Hénon's families), from the Kepler limit
    (velocity -+(n +- 1) r0, period 2 pi/(n +- 1), n = r0^(-3/2)) corrected by symmetric
    shooting. Returns a :class:`conmech.stability.PeriodicOrbit`."""
    r0 = stability._real(r0, "r0", 0.0, low_open=True)
    if not r0 < 0.5:
        raise ValueError("r0 must be below 0.5 (the Kepler start)")
    if kind not in ("f", "g"):
        raise ValueError("kind must be 'f' (retrograde) or 'g' (direct)")
    n = r0**-1.5
    s = -1.0 if kind == "f" else 1.0
    return _symmetric([r0, 0.0, 0.0, s*(n - s)*r0], 2.0*np.pi/(n - s), rtol)


def family(orbit, direction: int = 1, max_points: int = 50, ds: float = 0.05,
           ds_max: float = 0.3, rtol: float = 1e-11, **options):
    """Continue the family of ``orbit`` (from :func:`lyapunov_orbit`,
    :func:`satellite_orbit` or any periodic orbit of :func:`system`) by pseudo-arclength
    in the period (general shooting of a conservative family; ``direction`` +1 towards
    longer periods first). Returns a :class:`conmech.stability.Branch`: ``p`` the period
    (Hénon's time), ``energy`` Gamma, ``stability_index`` (trace M - 2)/2 and the located
    special points (S through +1: 'branch point', through -1: 'period doubling'); other
    options as for :func:`conmech.stability.continuation`."""
    for bad in ("in_period", "conservative", "energy", "param", "p0"):
        if bad in options:
            raise ValueError(f"{bad} is set by hill_families.family")
    return stability.continuation(system(), orbit.y0, orbit.period, in_period=True,
                                  conservative=True, direction=direction,
                                  max_points=max_points, ds=ds, ds_max=ds_max, rtol=rtol,
                                  atol=rtol, energy=lambda y, p: gamma(y), **options)
