"""The circular restricted three-body problem in space: libration points, the planar and
vertical Lyapunov families about the collinear points, the halo families that branch from
the planar ones, and the halo bifurcation located by the vertical variational equation.

The system is :func:`conmech.systems.cr3bp` (rotating frame, primaries of masses 1 - mu at
(-mu, 0, 0) and mu at (1 - mu, 0, 0), state [x, y, z, x', y', z'], Jacobi constant
C = 2 Omega - |v|^2 as its energy). Example (Earth-Moon)::

    from conmech import cr3bp
    mu = cr3bp.MU_EARTH_MOON
    lp = cr3bp.libration_points(mu)                 # L1..L5 and their Jacobi constants
    planar = cr3bp.lyapunov_family(mu, "L1", "planar", max_points=150, ds_max=0.1)
    hb = cr3bp.halo_bifurcation(mu, "L1", planar)   # C = 3.17435195..., to ~1e-12
    north = cr3bp.halo_family(mu, planar, direction=1, max_points=100)

The halo bifurcation of a planar Lyapunov family is where the vertical multiplier pair
passes through +1 (Howell 1984; Doedel et al. 2007). Along a planar orbit z = 0 the vertical
variation obeys z'' = Omega_zz(t) z, a Hill's equation whose coefficient is even about the
x-axis crossing (the orbits are symmetric): with y1 (y1(0) = 1, y1'(0) = 0) and y2 (y2(0) =
0, y2'(0) = 1) over half a period, the vertical half-trace is 1 + 2 y1'(T/2) y2(T/2), and
the halo orbits (symmetric about the xz-plane: z'(0) = 0) branch where y1'(T/2) = 0.
:func:`halo_bifurcation` finds that zero by regula falsi in the crossing abscissa x0,
each planar orbit by symmetric shooting, so that the pair near +1 is never taken from the
eigenvalues of the 6 x 6 monodromy (whose trivial pair and the large unstable multiplier
leave it ~1e-4 accurate there).
"""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

import numpy as np

from . import _conmech
from .mechanics import systems as _systems
from .ivp.solve import solve_ivp
from .stability import lyapunov_family as _lyapunov_family
from .stability import normal_modes, stm, switch_branch_point, symmetric_orbit
from .stability.continuation import Branch, SpecialPoint
from ._core.validate import _real
from ._core.result import Record

__all__ = ["MU_EARTH_MOON", "LibrationPoints", "libration_points", "jacobi",
           "lyapunov_family", "HaloBifurcation", "halo_bifurcation", "halo_family",
           "stability_indices"]

#: The Earth-Moon mass parameter (JPL; Doedel et al. 2007 use 0.01215).
MU_EARTH_MOON = 0.012150585609624

_NAMES = ("L1", "L2", "L3", "L4", "L5")


class LibrationPoints:
    """The five libration points of the CR3BP (:func:`libration_points`): positions (5, 3)
    (L1 between the primaries, L2 beyond the smaller, L3 beyond the larger, L4/L5 at the
    equilateral apexes), jacobi (5,) their Jacobi constants, mu; ``lp['L1']`` gives the
    position of one."""

    __slots__ = ("positions", "jacobi", "mu")

    def __init__(self, positions, jacobi_, mu):
        self.positions = positions
        self.jacobi = jacobi_
        self.mu = mu

    def __getitem__(self, name):
        return self.positions[_index(name)]

    def state(self, name):
        """The equilibrium state [x, y, z, 0, 0, 0] of the point ``name``."""
        return np.concatenate([self[name], np.zeros(3)])

    def __repr__(self):
        return (f"LibrationPoints(mu={self.mu!r}, x={self.positions[:3, 0].tolist()!r}, "
                f"jacobi={self.jacobi.tolist()!r})")


def _index(name):
    if name not in _NAMES:
        raise ValueError(f"point must be one of {', '.join(_NAMES)}, got {name!r}")
    return _NAMES.index(name)


def _mu(mu):
    mu = _real(mu, "mu", 0.0, 0.5, low_open=True)
    return mu


def libration_points(mu: float = MU_EARTH_MOON) -> LibrationPoints:
    """The libration points for the mass parameter 0 < mu <= 1/2: the collinear ones from
    the classical quintics in the distance to the nearer primary, solved by Newton's method
    to round-off (conmech_cr3bp), and their Jacobi constants."""
    mu = _mu(mu)
    pos, cj, info = _conmech.flat_cr3bp_libration(mu)
    if info != 0:
        raise RuntimeError("the Newton iteration for a collinear libration point did not "
                           "converge")
    return LibrationPoints(np.array(pos).T.copy(), np.array(cj), mu)


def jacobi(y, mu: float = MU_EARTH_MOON):
    """The Jacobi constant C = 2 Omega - |v|^2 of a state y (6,) or states (k, 6)."""
    return _systems.cr3bp(_mu(mu)).energy(y)


def _mode_of(system, y_eq, kind):
    """The normal mode index of the planar or the vertical oscillation about a collinear
    point (its eigenvector lies in the plane, or along z)."""
    nm = normal_modes(system, y_eq)
    for k in range(nm.omega.size):
        v = nm.vectors[:, k]
        vert = np.linalg.norm(v[[2, 5]]) > np.linalg.norm(v[[0, 1, 3, 4]])
        if vert == (kind == "vertical"):
            return k
    raise ValueError(f"no {kind} elliptic mode at this point (eigenvalues "
                     f"{nm.eigenvalues.tolist()})")


def lyapunov_family(mu: float = MU_EARTH_MOON, point: str = "L1", kind: str = "planar",
                    **options):
    """The planar or vertical Lyapunov family about the collinear point ``point`` ('L1',
    'L2' or 'L3'): :func:`conmech.stability.lyapunov_family` on the cr3bp system at the
    point with its planar or vertical elliptic mode (continued in the period, with the
    Jacobi constant as the branch's ``energy``; options as for it: max_points, ds, ds_max,
    energy_range, ...)."""
    if kind not in ("planar", "vertical"):
        raise ValueError(f"kind must be 'planar' or 'vertical', got {kind!r}")
    if _index(point) > 2:
        raise ValueError("Lyapunov families are computed about the collinear points L1, L2, "
                         "L3")
    sysm = _systems.cr3bp(_mu(mu))
    y_eq = libration_points(mu).state(point)
    return _lyapunov_family(sysm, y_eq, mode=_mode_of(sysm, y_eq, kind), **options)


class HaloBifurcation(Record):
    """The halo bifurcation orbit of a planar Lyapunov family (:func:`halo_bifurcation`):
    jacobi (its Jacobi constant C), period, y0 (its state at the x-axis crossing, [x0, 0,
    0, 0, vy, 0]), x0, vertical (y1'(T/2), the test: 0 there), half_trace (of the vertical
    monodromy, 1 there), residual (the orbit's true shooting residual), located (the
    bracket met its tolerance with every orbit converged), iterations."""

    __slots__ = ("jacobi", "period", "y0", "x0", "vertical", "half_trace", "residual",
                 "located", "iterations", "mu", "point")

    def __repr__(self):
        return (f"HaloBifurcation({self.point}, jacobi={self.jacobi!r}, period="
                f"{self.period!r}, located={self.located})")


def _planar_orbit(system, x0, vy, period, rtol):
    o = symmetric_orbit(system, [x0, 0.0, 0.0, 0.0, vy, 0.0], free=[4], targets=[1, 3],
                        period=period, period_factor=2, free_time=True, rtol=rtol, atol=rtol)
    return o


def _vertical(system, orbit, rtol):
    """(y1'(T/2), y2(T/2)) of the vertical variational equation along a planar orbit."""
    _, phi = stm(system, (0.0, 0.5*orbit.period), orbit.y0, rtol=rtol, atol=rtol)
    return float(phi[5, 2]), float(phi[2, 5])


def _crossing(system, y0, period, rtol):
    """The state of a planar orbit at its x-axis crossing with x' = 0 nearest the start
    (the orbits of a family share the phase condition, not the phase)."""
    r = solve_ivp(system, (0.0, period), y0, method="DOP853", rtol=rtol, atol=rtol,
                  events=lambda t, y: y[1])
    ys = np.asarray(r.y_events[0])
    if ys.size == 0:
        raise RuntimeError("the planar orbit does not cross the x axis")
    return ys[int(np.argmin(np.abs(ys[:, 3])))]


def halo_bifurcation(mu: float, point: str, family: Branch, rtol: float = 1e-13,
                     xtol: float = 1e-14) -> HaloBifurcation:
    """The halo bifurcation of the planar Lyapunov family ``family`` (from
    :func:`lyapunov_family` with kind 'planar') about ``point``: the planar orbit where the
    vertical multiplier pair passes +1, from the branch point the continuation located
    (a bracket around it in the crossing abscissa x0) refined by regula falsi on
    y1'(T/2) of the vertical variational equation (see the module notes), every orbit by
    symmetric shooting (residual checked), by Illinois' regula falsi to |x0 bracket| <=
    ``xtol``. ValueError if the family has no branch point."""
    mu = _mu(mu)
    sysm = _systems.cr3bp(mu)
    if not isinstance(family, Branch):
        raise TypeError("family must be the planar Lyapunov family (a Branch)")
    bps = [s for s in family.special if s.kind == "branch point"]
    if not bps:
        raise ValueError("the family has no branch point: continue it further (max_points, "
                         "ds_max)")
    bp = bps[0]
    i = bp.index
    # the crossings of the two branch points around it bracket the bifurcation
    ends = []
    for k in (i, i + 1):
        yc = _crossing(sysm, family.y0[k], family.period[k], rtol)
        ends.append((yc, family.period[k]))
    (ya, ta), (yb, tb) = ends
    guess = {"vy": ya[4], "t": ta}
    count = [0]

    def test(x0):
        w = (x0 - ya[0])/(yb[0] - ya[0])
        o = _planar_orbit(sysm, x0, (1 - w)*ya[4] + w*yb[4], (1 - w)*ta + w*tb, rtol)
        count[0] += 1
        guess.update(vy=o.y0[4], t=o.period, orbit=o)
        return _vertical(sysm, o, rtol)[0]
    fa, fb = test(ya[0]), test(yb[0])
    if not fa*fb < 0:
        raise RuntimeError(f"y1'(T/2) does not change sign between the branch points around "
                           f"the located one ({fa:.3g}, {fb:.3g})")
    x0, converged = _illinois(test, ya[0], yb[0], fa, fb, xtol)
    test(x0)
    o = guess["orbit"]
    y1p, y2 = _vertical(sysm, o, rtol)
    return HaloBifurcation(jacobi=float(sysm.energy(o.y0)), period=o.period, y0=o.y0,
                           x0=float(o.y0[0]), vertical=y1p, half_trace=1.0 + 2.0*y1p*y2,
                           residual=o.residual, located=converged,
                           iterations=count[0], mu=mu, point=point)


def _illinois(f, a, b, fa, fb, xtol, max_iter=100):
    """A zero of f in [a, b] (f(a) f(b) < 0) by Illinois' regula falsi, to |b - a| <= xtol
    (or f = 0); (x, converged)."""
    side = 0
    for _ in range(max_iter):
        c = (a*fb - b*fa)/(fb - fa)
        if not min(a, b) < c < max(a, b):
            c = 0.5*(a + b)
        fc = f(c)
        if fc == 0.0 or abs(b - a) <= xtol:
            return c, True
        if fc*fb < 0:
            a, fa = b, fb
            side = 0
        else:
            if side == 1:
                fa *= 0.5
            side = 1
        b, fb = c, fc
    return b, False


def halo_family(mu: float, family: Branch, direction: int = 1, **options) -> Branch:
    """The halo family branching from the planar Lyapunov family ``family`` at its branch
    point (the vertical pair through +1), by :func:`conmech.stability.switch_branch_point`
    (continued in the period like the planar family; ``direction`` +1/-1: the northern
    (z > 0 first) or southern family). The branch's ``energy`` is the Jacobi constant.
    Options as for switch_branch_point (max_points, ds, ds_max, ...)."""
    sysm = _systems.cr3bp(_mu(mu))
    if not isinstance(family, Branch):
        raise TypeError("family must be the planar Lyapunov family (a Branch)")
    bps = [s for s in family.special if s.kind == "branch point"]
    if not bps:
        raise ValueError("the family has no branch point: continue it further")
    bp = bps[0]
    if direction not in (1, -1):
        raise ValueError("direction must be +1 (north) or -1 (south)")
    halo = switch_branch_point(sysm, family, bp, direction=1, **options)
    # the kernel direction's sign is arbitrary: the first step's z decides north/south
    if len(halo) > 1 and np.sign(halo.y0[1, 2] + halo.y0[1, 5]) != direction:
        halo = switch_branch_point(sysm, family, bp, direction=-1, **options)
    halo.energy = sysm.energy(halo.y0)
    return halo


def stability_indices(branch: Branch) -> np.ndarray:
    """The stability indices nu = (mu + 1/mu)/2 of the two non-trivial multiplier pairs of
    each orbit of a family of the spatial problem (Howell 1984; |nu| <= 1 with nu real:
    the pair on the unit circle), shape (N, 2), sorted by |nu|, from the branch's
    multipliers with the trivial pair (the two nearest 1) removed. Near +1 they carry the
    accuracy of the multipliers (~1e-4 where the large multiplier is ~1e3)."""
    mult = np.asarray(branch.multipliers)
    if mult.ndim != 2 or mult.shape[1] != 6:
        raise ValueError("stability_indices: a branch of the six-dimensional problem is needed")
    out = np.empty((mult.shape[0], 2))
    for k, m in enumerate(mult):
        order = np.argsort(np.abs(m - 1.0))
        rest = m[order[2:]]
        # pair each with its reciprocal: sort by |log|mu||, take the two largest |mu| >= 1
        # members of their pairs (or the unit-circle ones)
        mags = np.abs(rest)
        big = rest[np.argsort(-np.abs(np.log(np.maximum(mags, 1e-300))))]
        nus = []
        used = np.zeros(4, bool)
        for a in range(4):
            if used[a]:
                continue
            used[a] = True
            j = int(np.argmin([abs(big[a]*big[b] - 1) if not used[b] else np.inf
                               for b in range(4)]))
            used[j] = True
            nus.append(0.5*(big[a] + 1.0/big[a]).real)
        out[k] = sorted(nus, key=abs)
    return out
