"""Families of symmetric periodic orbits of Hill's problem in Hénon's units.

Hénon (1969, "Numerical exploration of the restricted problem. V. Hill's case: periodic
orbits and their stability", A&A 1, 223) writes Hill's problem without parameters,

    x'' - 2 y' = 3 x - x/r^3,   y'' + 2 x' = -y/r^3,   Gamma = 3 x^2 + 2/r - x'^2 - y'^2,

(``conmech.systems.hill(m=1, kappa=1)``; :func:`conmech.hill.to_henon` converts from
Hill's units) and classifies its families of orbits symmetric about the x axis. Three of
them are reached here from closed-form starts, then followed by the general
pseudo-arclength continuation of a conservative family (:func:`conmech.stability.
continuation` with ``in_period``: the period is the continued quantity, Gamma a function
of the point):

- :func:`lyapunov_orbit`: the orbits about the Lagrange points L1 (x = 3^(-1/3), Hénon's
  family a) and L2 (x = -3^(-1/3), family c, the mirror image), which start at Gamma =
  3^(4/3) with the period 2 pi/sqrt(2 sqrt 7 - 1) of the linearisation (Lyapunov's centre
  theorem);
- :func:`satellite_orbit`: near-circular retrograde (Hénon's family f) and direct (family
  g, which holds Hill's variation orbits) satellite orbits, from the Kepler limit r -> 0
  (period 2 pi/(n +- 1), n = r^(-3/2));
- :func:`family`: the continuation of either (or of a published initial condition), with
  Gamma as the branch's ``energy``; :func:`orbit_at_gamma`: the member of a continued
  family at a given Gamma, started on the x axis (as the published tables list them).

The published families of Batkhin's data set (github.com/abbat06/Hill2D: x(0), p_y(0) =
y'(0) + x(0), T, C = Gamma and the stability index of Hénon's families a, f, g, ... at
round values of C) are the tests' reference.
"""
from __future__ import annotations

import numpy as np

from . import stability
from .ivp.solve import solve_ivp
from .mechanics import systems

__all__ = ["system", "gamma", "X_L1", "GAMMA_L", "PERIOD_L", "lyapunov_orbit",
           "satellite_orbit", "family", "on_axis", "orbit_at_gamma"]

#: x of the Lagrange point L1 (L2 at -X_L1) in Hénon's units
X_L1 = 3.0**(-1.0/3.0)
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
    """The periodic orbit about L1 (``side`` = +1) or L2 (-1) that crosses the x axis at
    right angles at x = +-(X_L1 + amplitude), from the linear oscillation (x - x_L =
    a cos w t, y = -(9 + w^2) a/(2 w) sin w t, w^2 = 2 sqrt 7 - 1) corrected by symmetric
    shooting. Returns a :class:`conmech.stability.PeriodicOrbit`."""
    a = stability._real(amplitude, "amplitude")
    if not 0 < abs(a) < 0.3:
        raise ValueError("amplitude must be non-zero and below 0.3 (the linear start)")
    if side not in (1, -1):
        raise ValueError("side must be +1 (L1) or -1 (L2)")
    w = 2.0*np.pi/PERIOD_L
    vy = -(9.0 + w*w)*a/2.0
    y0 = side*np.array([X_L1 + a, 0.0, 0.0, vy])
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


def on_axis(y0, period: float, rtol: float = 1e-12, side: int = 1) -> np.ndarray:
    """The state [x0, 0, x', y'] where the periodic orbit through ``y0`` crosses the x axis
    farthest to the right (``side`` = +1) or to the left (-1) (for an orbit symmetric about
    the axis x' = 0 there), from an integration over a period and a quarter (so that a
    crossing at the start or the end of the period is not missed) with an event on y."""
    y0 = stability._state(y0)
    if y0.size != 4:
        raise ValueError("y0 must be [x, y, x', y']")
    if side not in (1, -1):
        raise ValueError("side must be +1 (right) or -1 (left)")
    period = stability._real(period, "period", 0.0, low_open=True)
    r = solve_ivp(system(), (0.0, 1.25*period), y0, method="DOP853", rtol=rtol,
                  atol=rtol, events=lambda t, s: s[1])
    ys = r.y_events[0] if r.y_events else np.zeros((0, 4))
    if not r.success or len(ys) == 0:
        raise RuntimeError("the orbit does not cross the x axis within its period")
    y = np.array(ys[int(np.argmax(side*ys[:, 0]))])
    y[1] = 0.0
    return y


def orbit_at_gamma(branch, target: float, rtol: float = 1e-12, tol: float = 1e-11,
                   max_iter: int = 60, side: int = 1):
    """The member of the continued family ``branch`` (from :func:`family`) with Gamma =
    ``target``: between the two branch points whose Gamma brackets it, started on the x
    axis at its crossing farthest right (``side`` = +1) or left (-1) (:func:`on_axis`; the
    published tables list either), by Illinois' regula falsi on x0 inside that bracket
    (each x0 corrected by symmetric shooting, y'0 and the half period free, from the
    nearer bracket orbit) until |Gamma - target| <= tol. Returns the
    :class:`conmech.stability.PeriodicOrbit` (y0 = [x0, 0, 0, y'0])."""
    target = stability._real(target, "target")
    g = np.asarray(branch.energy, dtype=float)
    k = np.nonzero(np.diff(np.sign(g - target)) != 0)[0]
    if k.size == 0:
        raise ValueError(f"Gamma = {target} is not reached on the branch "
                         f"({g.min():.6g} .. {g.max():.6g})")
    k = int(k[0])
    pts = []
    for j in (k, k + 1):
        y = on_axis(branch.y0[j], branch.p[j], rtol, side)
        o = _symmetric(y, branch.p[j], rtol)
        pts.append((o.y0[0], gamma(o.y0) - target, o))
    (xa, fa, oa), (xb, fb, ob) = pts
    if abs(fa) <= tol:
        return oa
    if abs(fb) <= tol:
        return ob
    if not fa*fb < 0:
        raise RuntimeError("orbit_at_gamma: the bracketing orbits on the axis do not "
                           "bracket the target (the family folds between them?)")
    held = 0
    fc = fb
    for _ in range(max_iter):
        xc = (xa*fb - xb*fa)/(fb - fa)
        if not min(xa, xb) < xc < max(xa, xb):
            xc = 0.5*(xa + xb)
        near = oa if abs(xc - xa) < abs(xc - xb) else ob
        o = _symmetric([xc, 0.0, 0.0, near.y0[3]], near.period, rtol)
        fc = gamma(o.y0) - target
        if abs(fc) <= tol:
            return o
        xc = o.y0[0]
        if fc*fb < 0:
            xa, fa, oa = xb, fb, ob
            held = 0
        else:
            held += 1
            if held > 1:
                fa *= 0.5
        xb, fb, ob = xc, fc, o
    raise RuntimeError(f"orbit_at_gamma: the iteration did not reach Gamma = "
                       f"{target} (last |Gamma - target| = {abs(fc):.3g})")
