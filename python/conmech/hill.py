"""Hill's lunar problem: the variation orbit, its monodromy and the perigee constant.

Hill's equations, as in the lecture notes: in the frame rotating with the Sun, time scaled so
that the synodic month is 2 pi::

    x'' - 2 m y' = dF/dx,   y'' + 2 m x' = dF/dy,   F = kappa/r + (3/2) m^2 x^2

The variation orbit is the direct periodic orbit of period 2 pi, symmetric about both axes.
Its monodromy matrix has the trivial double multiplier 1 (a Jordan block, accurate only to
~sqrt(eps) as eigenvalues) and the non-trivial pair exp(+-2 pi i c), where c is Hill's
perigee constant: S = (trace M - 2)/2 = cos(2 pi c), c = 1 + arccos(S)/(2 pi), both
computed from products of quarter-period map entries (accurate to ~1e-14 also as S -> 1,
where the trace loses digits)::

    >>> import conmech.hill as hill
    >>> orb = hill.variation_orbit(0.080848933808312)
    >>> round(orb.c, 13)
    1.071583277416

Everything runs in Fortran (fixed-step DOP853 on the state and its state transition matrix,
symmetric Newton shooting over a quarter period, monodromy from the symmetry).
"""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import math

import numpy as np

from . import _conmech
from .stability.continuation import SpecialKind
from .stability.variational import stm as _stm
from .mechanics.systems import hill_spatial as _hill_spatial
from ._core.result import StatusRecord
from ._core.status import raise_status
from ._core.checks import real_number as _real_number

__all__ = ["HillOrbit", "HillFamily", "variation_orbit", "family", "transverse",
           "locate_stability_change", "to_henon", "from_henon", "henon_gamma",
           "M_HILL", "C_HILL", "plot_orbit", "plot_multipliers", "plot_family",
           "node_constant"]

M_HILL = 0.080848933808312   #: Hill's (1877) value of m = n'/(n - n')
C_HILL = 1.0715832774160     #: Hill's perigee constant for M_HILL

#: An orbit is accepted only if its true residual max(|x(pi/2)|, |y'(pi/2)|), from an
#: independent adaptive integration (DOP853, tolerance 1e-12), is below this.
RESIDUAL_TOL = 1e-8


def _true_residuals(ms, kappa, y0s):
    """Residuals of the orbits y0s (n, 4) for ms (n,) by an independent integration of a
    quarter period (conmech flat_hill_residuals); huge for a failed one."""
    y0s = np.asfortranarray(np.asarray(y0s, dtype=float).T)
    return np.asarray(_conmech.flat_hill_residuals(np.ascontiguousarray(ms, dtype=float),
                                                   float(kappa), y0s))


def _check_float(value, name, positive=False, nonneg=False):
    if type(value) is float:            # the common case, checked without conversions
        v = value
    else:
        v = _real_number(value, name)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite")
    if positive and not v > 0:
        raise ValueError(f"{name} must be positive, got {v}")
    if nonneg and not v >= 0:
        raise ValueError(f"{name} must be non-negative, got {v}")
    return v


def _is_integer(value):
    """True for an int or a NumPy integer, not a bool (a plain int, the common case, by one
    type test)."""
    return type(value) is int or (isinstance(value, (int, np.integer))
                                  and not isinstance(value, (bool, np.bool_)))


class HillOrbit:
    """A variation orbit of Hill's problem.

    Attributes
    ----------
    m, kappa : float
    y0 : ndarray (4,)
        Initial state [x0, 0, 0, v0] (on the x axis, crossing it at right angles).
    period : float
        2 pi.
    jacobi : float
        Jacobi constant x'^2 + y'^2 - 2 F.
    monodromy : ndarray (4, 4)
    multipliers : ndarray (4,) complex
        Eigenvalues of the monodromy (LAPACK dgeev); the two trivial ones (a Jordan block
        at 1) are accurate only to ~sqrt(eps).
    stability_index : float
        S = (trace M - 2)/2 (computed as 1 - 8 s t from the quarter-period map, not from
        the trace); linearly stable iff |S| < 1.
    c : float
        Perigee constant, 1 + arccos(S)/(2 pi) (nan if |S| > 1), to ~2e-14 with the
        default 20 steps, also as m -> 0 (m = 1e-6 included).
    residual : float
        The true closure error |(x, y')(T/4)| of the orbit (estimated by integrating its
        start with twice the steps: not the residual of the discretised problem); at most
        ``closure_tol``.
    quarter_state : ndarray (4,)
        State at T/4, [0, y, x', 0]: x'(T/4) -> 0 at the cusp orbit (maximum lunation).
    nsteps : int
        DOP853 steps per quarter period chosen by the error control.
    iterations, nfev : int
        Newton iterations and right-hand side evaluations.
    """

    __slots__ = ("m", "kappa", "y0", "period", "jacobi", "monodromy", "multipliers",
                 "stability_index", "c", "residual", "quarter_state", "nsteps", "iterations",
                 "nfev")

    def __init__(self, m=None, kappa=None, y0=None, period=None, jacobi=None, monodromy=None,
                 multipliers=None, stability_index=None, c=None, residual=None,
                 quarter_state=None, nsteps=None, iterations=None, nfev=None):
        self.m, self.kappa, self.y0, self.period, self.jacobi = m, kappa, y0, period, jacobi
        self.monodromy, self.multipliers, self.stability_index = monodromy, multipliers, \
            stability_index
        self.c, self.residual, self.quarter_state, self.nsteps = c, residual, quarter_state, \
            nsteps
        self.iterations, self.nfev = iterations, nfev

    @property
    def initial_state(self):
        """Alias of y0."""
        return self.y0

    @property
    def stable(self):
        """True when |stability_index| < 1."""
        return bool(abs(self.stability_index) < 1.0)

    def sample(self, t):
        """States (4, nt) and Phi(t) (nt,) of the transverse Hill equation at times t."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        res = transverse(self, t=t)
        return res["states"], res["phi"]

    def __repr__(self):
        return (f"HillOrbit(m={self.m!r}, c={self.c!r}, stability_index="
                f"{self.stability_index!r}, y0={self.y0.tolist()!r})")


def variation_orbit(m: float, kappa: float = 1.0, guess: ArrayLike | None = None,
                    nsteps: int = 0, full_period: bool = False, closure_tol: float = 1e-12,
                    max_nsteps: int = 2560) -> HillOrbit:
    """The variation orbit of Hill's problem for the parameter m.

    Parameters
    ----------
    m : float
        n'/(n - n') (>= 0); Hill's value is :data:`M_HILL`.
    kappa : float, optional
        Gravitational parameter (> 0).
    guess : (x0, v0), optional
        Newton start (default: the circular Kepler orbit of mean motion 1 + m).
    nsteps : int, optional
        Initial DOP853 steps per quarter period (0: the default, 20); the error control
        raises it (up to ``max_nsteps``) until the true closure error is <= closure_tol.
    full_period : bool, optional
        Compute the monodromy by direct integration over 2 pi instead of the symmetry.
    closure_tol : float, optional
        Bound on the true closure error |(x, y')(T/4)| (default 1e-12).

    Returns
    -------
    HillOrbit

    Raises
    ------
    ValueError
        Bad arguments; RuntimeError when Newton fails (the message says why).
    """
    # plain floats and ints in range (the common call) pass by type tests and comparisons
    # alone (nan fails them); anything else takes the checks and their messages
    if type(m) is not float or not 0.0 <= m < _INF:
        m = _check_float(m, "m", nonneg=True)
    if type(kappa) is not float or not 0.0 < kappa < _INF:
        kappa = _check_float(kappa, "kappa", positive=True)
    if guess is None:
        use, g = 0, _NO_GUESS
    else:
        g = np.asarray(guess, dtype=float).ravel()
        if g.size != 2 or not np.all(np.isfinite(g)):
            raise ValueError("guess must be two finite numbers (x0, v0)")
        use = 1
    if type(nsteps) is not int and not _is_integer(nsteps):
        raise TypeError("nsteps must be an integer")
    if not 0 <= nsteps <= 100000:
        raise ValueError("nsteps must be in [0, 100000]")
    if type(max_nsteps) is not int and not _is_integer(max_nsteps):
        raise TypeError("max_nsteps must be an integer")
    if closure_tol != 1e-12:
        closure_tol = _check_float(closure_tol, "closure_tol", positive=True)
    if max_nsteps < max(nsteps, 20):
        raise ValueError("max_nsteps must be >= nsteps (and >= 20)")
    # the orbit and its independent closure check in one Fortran call, every number in one
    # array (its layout: flat_hill_checked.f90), the orbit's arrays views of it
    out = _conmech.flat_hill_orbit_checked(m, kappa, nsteps, 1 if full_period else 0, use,
                                           g, closure_tol, max_nsteps)
    (period, jacobi, s, c, residual, res, scale, nsu, iterations, nfev, finite,
     info) = out[32:44].tolist()
    if info != 0:
        raise_status(int(info), out[44:76].tobytes())
    if not res <= RESIDUAL_TOL*scale:
        raise RuntimeError(f"hill_variation_orbit: the orbit found for m = {m} is not "
                           f"periodic to the tolerance (true residual {res:.3g} > "
                           f"{RESIDUAL_TOL:g}): Newton did not converge to the variation "
                           "orbit (a better guess or more nsteps is needed)")
    if not finite:
        raise RuntimeError("hill_variation_orbit: the monodromy is not finite")
    # views made by the ndarray constructor (offsets in bytes): cheaper than reshape(order=)
    # and view(complex) on a slice
    return HillOrbit(m, kappa, out[0:4], period, jacobi,
                     _ndarray((4, 4), _F8, out, 32, None, "F"), _ndarray(4, _C16, out, 160),
                     s, c, residual, out[28:32], int(nsu), int(iterations), int(nfev))


_NO_GUESS = np.zeros(2)
_ndarray, _F8, _C16 = np.ndarray, np.dtype(np.float64), np.dtype(np.complex128)
_INF = math.inf


class HillFamily(StatusRecord):
    """The family of variation orbits over m (arrays indexed like ``ms``).

    Attributes: ms, y0 (n, 4), jacobi, monodromy (n, 4, 4), stability_index, c (nan past
    the loss of stability, |S| > 1), residual (true closure error of each orbit),
    quarter_state (n, 4) (x'(T/4) = quarter_state[:, 2]), nsteps, status (0 = success),
    iterations, success (bool array), special (list of dicts: the located crossings of
    S = +1 / -1 between consecutive converged orbits: kind ('branch point' / 'period
    doubling', as the continuation's special points; 'S=+1' / 'S=-1' match too), index
    (the orbit before it), m, y0, stability_index, c, residual).
    """

    __slots__ = ("ms", "kappa", "y0", "jacobi", "monodromy", "stability_index", "c",
                 "residual", "quarter_state", "nsteps", "status", "iterations", "special")

    def __len__(self):
        return len(self.ms)

    def __repr__(self):
        return (f"HillFamily(n={len(self.ms)}, failures={int(np.sum(~self.success))}, "
                f"special={[(p['kind'], p['m']) for p in self.special]})")


def locate_stability_change(m_a: float, m_b: float, kappa: float = 1.0, target: float = 1.0,
                            guess_a=None, guess_b=None, mtol=1e-13) -> dict:
    """The m in [m_a, m_b] where the stability index S of the variation orbit equals
    ``target`` (+1: loss of stability through +1, near m = 0.195; -1: through -1), by
    Illinois' regula falsi on S(m) - target with warm-started orbits. Returns a dict: m,
    y0, stability_index, c, residual (true closure error). Raises ValueError when S - target
    has the same sign at both ends."""
    ga = variation_orbit(m_a, kappa, guess=guess_a)
    gb = variation_orbit(m_b, kappa, guess=guess_b)
    return _locate(ga.m, ga.y0, gb.m, gb.y0, kappa, target, mtol)


def _locate(ma, ya, mb, yb, kappa, target, mtol):
    m_star, u, s, c, res, info, message = _conmech.flat_hill_locate(
        float(ma), np.array([ya[0], ya[3]]), float(mb), np.array([yb[0], yb[3]]), kappa,
        float(target), float(mtol))
    if info != 0:
        raise_status(info, message)
    return {"m": float(m_star), "y0": np.array([u[0], 0.0, 0.0, u[1]]),
            "stability_index": float(s), "c": float(c), "residual": float(res)}


def family(ms: ArrayLike, kappa: float = 1.0, nsteps: int = 0, chunk_size: int = 256,
           locate: bool = True, mtol: float = 1e-13) -> HillFamily:
    """The family of variation orbits over ``ms`` by continuation (sorted, close values work
    best: each orbit starts from the extrapolation of its predecessors in its chunk of
    ``chunk_size`` orbits; the chunks run on OpenMP threads and do not depend on their
    number, so the results do not either). Every orbit meets the single-orbit tolerances
    (Newton step 1e-14, true closure error 1e-12). Failed orbits have status < 0 and nan
    entries; nothing is raised for them. With ``locate``, every crossing of S = +1 or -1
    between consecutive converged orbits is located to ``mtol`` in m (``special``)."""
    ms = np.ascontiguousarray(np.asarray(ms, dtype=float).ravel())
    if ms.size == 0:
        raise ValueError("ms must not be empty")
    if not np.all(np.isfinite(ms)) or np.any(ms < 0):
        raise ValueError("ms must be finite and non-negative")
    kappa = _check_float(kappa, "kappa", positive=True)
    if not _is_integer(nsteps):
        raise TypeError("nsteps must be an integer")
    if not 0 <= int(nsteps) <= 100000:
        raise ValueError("nsteps must be in [0, 100000]")
    if int(chunk_size) < 1:
        raise ValueError("chunk_size must be >= 1")
    (y0s, jac, monos, ss, cs, res, quarters, nsu, infos,
     iters) = _conmech.flat_hill_family(ms, kappa, int(nsteps), int(chunk_size))
    ok = np.asarray(infos) == 0
    y0s = np.array(y0s).T.copy()
    quarters = np.array(quarters).T.copy()
    monos = np.moveaxis(np.array(monos), 2, 0).copy()
    ss = np.array(ss)
    cs = np.array(cs)
    jac = np.array(jac)
    res = np.array(res)
    for a in (y0s, monos, ss, cs, jac, res, quarters):
        a[~ok] = np.nan
    special = []
    if locate:
        # the names of the continuation's special points, the stability-index events
        # as aliases: kind == "branch point" and kind == "S=+1" both hold
        for target, kind in ((1.0, SpecialKind("branch point", "S=+1")),
                             (-1.0, SpecialKind("period doubling", "S=-1"))):
            f = ss - target
            idx = np.nonzero(ok[:-1] & ok[1:] & (f[:-1]*f[1:] <= 0)
                             & ~((f[:-1] == 0) & (f[1:] == 0)))[0]
            for i in idx:
                try:
                    p = _locate(ms[i], y0s[i], ms[i + 1], y0s[i + 1], kappa, target, mtol)
                except (RuntimeError, ValueError) as exc:
                    p = {"m": np.nan, "error": str(exc)}
                p.update(kind=kind, index=int(i))
                special.append(p)
        special.sort(key=lambda p: p["index"])
    return HillFamily(ms=ms, kappa=kappa, y0=y0s, jacobi=jac, monodromy=monos,
                      stability_index=ss, c=cs, residual=res, quarter_state=quarters,
                      nsteps=np.asarray(nsu, dtype=int), status=np.asarray(infos, dtype=int),
                      iterations=np.asarray(iters, dtype=int), special=special)


def transverse(orbit: HillOrbit, t: ArrayLike | None = None, rtol: float = 1e-13) -> dict:
    """Transverse linearisation along a variation orbit (as in the lecture notes): the normal
    deviation N obeys Hill's equation N'' + Phi(t) N = 0,
    Phi = 3 (omega + m)^2 + m^2 - n^T H n, omega = n . grad F/|v| - 2 m.

    Returns a dict: monodromy (2, 2) over 2 pi, half_trace (= the orbit's stability_index),
    c, and if ``t`` is given the orbit ``states`` (4, nt) and ``phi`` (nt,) at t.
    """
    if not isinstance(orbit, HillOrbit):
        raise TypeError("orbit must be a HillOrbit (from variation_orbit)")
    rtol = _check_float(rtol, "rtol", positive=True)
    if rtol > 1e-3:
        raise ValueError(f"rtol must be in (0, 1e-3], got {rtol}")
    tt = np.zeros(1) if t is None else np.ascontiguousarray(np.asarray(t, dtype=float).ravel())
    if t is not None and (tt.size == 0 or not np.all(np.isfinite(tt)) or np.any(tt < 0)):
        raise ValueError("t must be finite, non-negative times")
    states, phi, mono2, ht, c, info, message = _conmech.flat_hill_transverse(
        orbit.m, orbit.kappa, orbit.y0, float(rtol), tt)
    if info != 0:
        raise_status(info, message)
    out = {"monodromy": np.array(mono2), "half_trace": float(ht), "c": float(c)}
    if t is not None:
        out["states"] = np.array(states)
        out["phi"] = np.array(phi)
    return out


def node_constant(m: float, kappa: float = 1.0, rtol: float = 1e-14,
                  full_output: bool = False):
    """The node constant g of the variation orbit (Adams 1877): the motion of the lunar
    node, in the units of :func:`variation_orbit` (the synodic month is 2 pi; the latitude
    argument advances by g per unit of time, so the draconic month is 2 pi/g).

    Hill's problem in space (:func:`conmech.systems.hill_spatial`) adds z'' + m^2 z =
    -kappa z/r^3. Along the planar variation orbit the out-of-plane variation obeys the
    Hill's equation dz'' + (m^2 + kappa/r^3) dz = 0, whose coefficient has period pi and
    is even (the orbit is symmetric about both axes); its characteristic exponent is g.
    With y1, y2 the solutions with (y1, y1') = (1, 0), (y2, y2') = (0, 1) at the
    x-axis crossing, integrated over a quarter month pi/2 together with the orbit
    (the z-block of the spatial problem's state transition matrix, DOP853 at ``rtol``,
    the exact Jacobian), y1 y2' = cos^2(pi g/2) and y1' y2 = -sin^2(pi g/2), so that

        g = (2/pi) atan2(sqrt(-y1' y2), sign(y1) sqrt(y1 y2'))

    (well conditioned for every g in (0, 2); g -> 1 + m + 3 m^2/4 as m -> 0: the
    node regresses as the perigee advances, to first order). ``full_output``: also a dict
    with y1, y1p, y2, y2p at pi/2, the Wronskian y1 y2' - y1' y2 (1 up to the integration
    error) and the orbit."""
    m = _check_float(m, "m", nonneg=True)
    kappa = _check_float(kappa, "kappa", positive=True)
    rtol = _check_float(rtol, "rtol", positive=True)
    if rtol > 1e-6:
        raise ValueError(f"rtol must be in (0, 1e-6], got {rtol}")
    orb = variation_orbit(m, kappa)
    x0, _, vx0, vy0 = orb.y0
    y = np.array([x0, 0.0, 0.0, vx0, vy0, 0.0])
    _, phi = _stm(_hill_spatial(m=m, kappa=kappa), (0.0, 0.5*np.pi), y, rtol=rtol,
                  atol=rtol)
    y1, y1p, y2, y2p = phi[2, 2], phi[5, 2], phi[2, 5], phi[5, 5]
    cc, ss = y1*y2p, -y1p*y2
    if cc < -1e-10 or ss < -1e-10:
        raise RuntimeError(f"node_constant: the vertical solutions are inconsistent "
                           f"(y1 y2' = {cc:.3g}, y1' y2 = {-ss:.3g})")
    g = 2.0/np.pi*np.arctan2(np.sqrt(max(ss, 0.0)), np.sign(y1)*np.sqrt(max(cc, 0.0)))
    if not full_output:
        return float(g)
    return float(g), {"y1": float(y1), "y1p": float(y1p), "y2": float(y2), "y2p": float(y2p),
                      "wronskian": float(y1*y2p - y1p*y2), "orbit": orb}


# ------------------------------------------------------------------- Henon's units

def to_henon(m, state, kappa=1.0):
    """A state [x, y, x', y'] in Hill's units (synodic period 2 pi, the equations of seed
    000) in Henon's units (x'' - 2 y' = 3 x - x/r^3, y'' + 2 x' = -y/r^3): time t_H = m t,
    lengths x_H = m^(2/3) kappa^(-1/3) x, velocities v_H = m^(-1/3) kappa^(-1/3) v. The
    synodic period becomes 2 pi m."""
    return _rescale(m, state, kappa, 1.0)


def from_henon(m, state, kappa=1.0):
    """Inverse of :func:`to_henon`."""
    return _rescale(m, state, kappa, -1.0)


def _rescale(m, state, kappa, sign):
    """Hill's units to Henon's (sign = 1) or back (sign = -1): lengths times
    (m^(2/3) kappa^(-1/3))^sign, velocities times (m^(-1/3) kappa^(-1/3))^sign."""
    m = _check_float(m, "m", positive=True)
    kappa = _check_float(kappa, "kappa", positive=True)
    st = np.asarray(state, dtype=float)
    if st.shape[-1] != 4:
        raise ValueError("state must end with 4 components [x, y, x', y']")
    f = kappa**(-sign/3)
    return np.concatenate([st[..., :2]*m**(sign*2/3)*f, st[..., 2:]*m**(-sign/3)*f],
                          axis=-1)


def henon_gamma(m, jacobi, kappa=1.0):
    """Henon's Jacobi constant Gamma = 3 x^2 + 2/r - v^2 (Henon's units and sign) from
    Hill's I = v^2 - 2 F (kappa = 1: Gamma = -I m^(-2/3))."""
    m = _check_float(m, "m", positive=True)
    kappa = _check_float(kappa, "kappa", positive=True)
    return -np.asarray(jacobi, dtype=float)*m**(-2/3)*kappa**(-2/3)


# --------------------------------------------------------------------------- plots

def plot_orbit(orbit, ax=None, npoints=401):
    """The orbit in the rotating frame (matplotlib)."""
    # matplotlib is optional: imported only when a figure is drawn
    import matplotlib.pyplot as plt
    if ax is None:
        _, ax = plt.subplots()
    t = np.linspace(0.0, orbit.period, npoints)
    states, _ = orbit.sample(t)
    ax.plot(states[0], states[1], label=f"m = {orbit.m:.6g}, c = {orbit.c:.12f}")
    ax.plot([0.0], [0.0], "o", color="k", label="Earth")
    ax.set_title("Hill's variation orbit (rotating frame)")
    return _equal_axes(ax, "x", "y")


def plot_multipliers(orbit, ax=None):
    """Floquet multipliers of the monodromy on the unit circle (matplotlib)."""
    # matplotlib is optional: imported only when a figure is drawn
    import matplotlib.pyplot as plt
    if ax is None:
        _, ax = plt.subplots()
    th = np.linspace(0.0, 2.0*np.pi, 400)
    ax.plot(np.cos(th), np.sin(th), color="0.7", lw=1)
    mu = orbit.multipliers
    ax.plot(mu.real, mu.imag, "x", ms=9, label="multipliers (dgeev)")
    ang = 2.0*np.pi*orbit.c
    ax.plot([np.cos(ang)]*2, [np.sin(ang), -np.sin(ang)], "o", mfc="none", ms=12,
            label="exp(+-2 pi i c)")
    return _equal_axes(ax, "Re", "Im")


def _equal_axes(ax, xlabel, ylabel):
    """Equal scales, the axes' labels and the legend: the plane plots' finish."""
    ax.set_aspect("equal")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.legend(loc="best")
    return ax


def plot_family(fam, ax=None):
    """Stability index S and perigee constant c along a family, the located stability
    changes (S = +-1) marked (matplotlib)."""
    # matplotlib is optional: imported only when a figure is drawn
    import matplotlib.pyplot as plt
    if ax is None:
        _, ax = plt.subplots()
    ax.plot(fam.ms, fam.stability_index, label="S = (tr M - 2)/2")
    ax.plot(fam.ms, fam.c, label="c")
    ax.axhline(1.0, color="0.6", lw=0.8, ls="--")
    ax.axhline(-1.0, color="0.6", lw=0.8, ls="--")
    for sp in getattr(fam, "special", None) or []:
        if np.isfinite(sp.get("m", np.nan)):
            ax.plot([sp["m"]], [sp["stability_index"]], "o", color="C3")
            ax.annotate(f"{sp['kind']}\nm = {sp['m']:.12f}", (sp["m"], sp["stability_index"]),
                        textcoords="offset points", xytext=(6, -24), fontsize=8)
    ax.set_xlabel("m")
    ax.legend(loc="best")
    ax.set_title("Hill's variation orbits: stability along the family")
    return ax
