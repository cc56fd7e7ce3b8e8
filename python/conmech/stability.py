"""Stability of equilibria and periodic motions, for built-in systems
(:mod:`conmech.systems`, run entirely in Fortran) or Python callables ``fun(t, y)``
(finite-difference Jacobian in Fortran).

- :func:`equilibrium`: linearisation, eigenvalues (LAPACK) and classification;
- :func:`lagrange_dirichlet`: is the Hessian of the potential positive definite?
- :func:`stm`: state and state transition matrix (variational equations);
- :func:`periodic_orbit`, :func:`symmetric_orbit`: Newton shooting, with the monodromy
  matrix and Floquet multipliers;
- :func:`floquet`: multipliers, exponents and the planar stability index of a monodromy;
- :func:`hill_equation`: N'' + Phi(t) N = 0 with Phi a callable or periodic samples;
- :func:`continuation`: pseudo-arclength continuation of periodic orbits in a parameter,
  with folds, branch points, period doublings and Neimark-Sacker points located
  (:class:`Branch`, :class:`SpecialPoint`; :func:`plot_branch`, :func:`plot_multipliers`);
- :func:`transverse`: transverse linearisation (Hill's equation of the normal deviation)
  of a periodic orbit of any planar natural (+ gyroscopic) system;
- :func:`find_equilibrium`, :func:`equilibria` (from a :func:`grid` of guesses,
  deduplicated), :func:`lagrange_dirichlet_potential` (Hessian exact or by differences).
"""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from . import _conmech
from ._callback import Guard, as_result, message_text
from .systems import BuiltinSystem

__all__ = ["Equilibrium", "PeriodicOrbit", "Branch", "SpecialPoint", "continuation",
           "transverse", "find_equilibrium", "equilibria", "grid", "potential_hessian",
           "lagrange_dirichlet_potential", "plot_branch", "plot_multipliers",
           "switch_period_doubling", "switch_branch_point", "constrained_equilibrium",
           "constrained_equilibria", "ConstrainedEquilibrium",
           "equilibrium", "lagrange_dirichlet", "stm",
           "monodromy", "periodic_orbit", "symmetric_orbit", "floquet", "hill_equation"]

_KINDS = {1: "asymptotically stable", 2: "centre", 3: "unstable", 4: "degenerate"}
#: equilibrium() classifies y only if max|f(t, y)| <= EQUILIBRIUM_RTOL max(1, |J| max(1, |y|))
EQUILIBRIUM_RTOL = 1e-8


def _msg(message):
    return message_text(message)


def _raise(info, message):
    msg = _msg(message)
    if info == -4:
        raise ValueError(msg)
    raise RuntimeError(msg)


def _state(y, name="y0"):
    y = np.asarray(y)
    if y.dtype.kind == "c":
        raise TypeError(f"{name} must be real: complex states are not supported")
    try:
        y = np.ascontiguousarray(np.asarray(y, dtype=float).ravel())
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be an array of real numbers") from None
    if y.size == 0:
        raise ValueError(f"{name} must not be empty")
    if not np.all(np.isfinite(y)):
        raise ValueError(f"{name} must be finite")
    return y


def _real(value, name, low=None, high=None, low_open=False, allow_zero=True):
    """A finite real number in [low, high] (low excluded with low_open); a ValueError
    naming it otherwise."""
    if isinstance(value, (bool, np.bool_)) or isinstance(value, (str, bytes)):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__}") from None
    if not np.isfinite(v):
        raise ValueError(f"{name} must be finite, got {v}")
    if low is not None and (v < low or (low_open and v == low)):
        raise ValueError(f"{name} must be {'>' if low_open else '>='} {low}, got {v}")
    if high is not None and v > high:
        raise ValueError(f"{name} must be <= {high}, got {v}")
    return v


def _tols(rtol, atol):
    """Integration tolerances: finite, rtol in [0, 1], atol >= 0, not both zero."""
    r = _real(rtol, "rtol", 0.0, 1.0)
    a = _real(atol, "atol", 0.0)
    if r == 0.0 and a == 0.0:
        raise ValueError("rtol and atol must not both be zero")
    return r, a


def _count(value, name, low=1, high=10**6):
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer, got {type(value).__name__}")
    if not low <= int(value) <= high:
        raise ValueError(f"{name} must be in [{low}, {high}], got {value}")
    return int(value)


def _callback(fun, n, y0, t0, jac=None):
    """The guarded callbacks of a user system (rhs, and jac when given). The functions
    are probed once at (t0, y0) in Python first: a wrong shape or an exception is raised
    before the Fortran side allocates anything (the STM of a large system is big)."""
    if not callable(fun):
        raise TypeError("system must be a conmech.systems.BuiltinSystem or a callable "
                        "fun(t, y)")
    if jac is not None and not callable(jac):
        raise TypeError("jac must be a callable jac(t, y) -> (n, n) array, or None")
    as_result(fun(t0, y0.copy()), (n,), "fun")
    if jac is not None:
        as_result(jac(t0, y0.copy()), (n, n), "jac")
    g = Guard()
    rhs = g.wrap(fun, 2, (n,), "fun")
    dfdy = g.wrap(jac, 2, (n, n), "jac") if jac is not None else None
    return g, rhs, dfdy


def _check_dim(system, y):
    if isinstance(system, BuiltinSystem) and y.size != system.dimension:
        raise ValueError(f"y0 has {y.size} components; the system '{system.name}' has "
                         f"{system.dimension}")


def _no_jac_for_builtin(system, jac):
    if jac is not None and isinstance(system, BuiltinSystem):
        raise TypeError("jac is for Python callables; a built-in system has its own "
                        "Jacobian")


class Equilibrium:
    """Result of :func:`equilibrium`: y, jacobian, eigenvalues (complex), kind
    ('asymptotically stable', 'centre', 'unstable', 'degenerate'), saddle, residual
    (max |f(y)|), analytic (the Jacobian was analytic)."""

    __slots__ = ("y", "jacobian", "eigenvalues", "kind", "saddle", "residual", "analytic",
                 "njev")

    def __init__(self, **kw):
        for k in self.__slots__:
            setattr(self, k, kw.get(k))

    @property
    def stable(self):
        """Linearly stable (asymptotically stable or centre)."""
        return self.kind in ("asymptotically stable", "centre")

    def __repr__(self):
        return f"Equilibrium(kind={self.kind!r}, eigenvalues={self.eigenvalues!r})"


def equilibrium(system: Any, y: ArrayLike, t: float = 0.0, tol: float = 1e-8,
                jac: Callable[..., ArrayLike] | None = None) -> Equilibrium:
    """Linearise at y, compute the eigenvalues and classify (see conmech_equilibria).

    y must be an equilibrium: max|f(t, y)| <= EQUILIBRIUM_RTOL max(1, |J| max(1, |y|)),
    else ValueError (a classification elsewhere would be meaningless).

    ``tol`` (in [0, 1)) is relative to max(1, max|lambda|): Re(lambda) within it counts as
    zero. ``jac``: exact Jacobian jac(t, y) -> (n, n) of a Python system (default:
    central finite differences); the result's ``njev`` counts its calls.
    """
    y = _state(y, "y")
    _check_dim(system, y)
    t = _real(t, "t")
    tol = _real(tol, "tol", 0.0, 1.0)
    if tol == 1.0:
        raise ValueError("tol must be < 1")
    _no_jac_for_builtin(system, jac)
    n = y.size
    njev = 0
    if isinstance(system, BuiltinSystem):
        out = _conmech.flat_equilibrium_builtin(*system._flat_args(), y, t, tol)
    else:
        g, rhs, dfdy = _callback(system, n, y, t, jac)
        if dfdy is None:
            out = _conmech.flat_equilibrium_callback(rhs, y, t, tol)
        else:
            out = _conmech.flat_equilibrium_callback_jac(rhs, dfdy, y, t, tol)
        g.check()
        njev = g.count("jac")
    jmat, wr, wi, kind, saddle, residual, analytic, info, message = out
    if info != 0:
        _raise(info, message)
    # a classification is only meaningful at an equilibrium: check the true residual
    jmax = float(np.max(np.abs(jmat), initial=0.0))
    scale = max(1.0, jmax*max(1.0, float(np.max(np.abs(y)))))
    if not (np.all(np.isfinite(jmat)) and residual <= EQUILIBRIUM_RTOL*scale):
        raise ValueError(f"y is not an equilibrium: max|f(t, y)| = {residual:.3g} > "
                         f"{EQUILIBRIUM_RTOL:g} x {scale:.3g} (or the Jacobian is not "
                         "finite)")
    e = Equilibrium(y=y, jacobian=np.array(jmat),
                    eigenvalues=np.asarray(wr) + 1j*np.asarray(wi),
                    kind=_KINDS.get(int(kind), "degenerate"), saddle=bool(saddle),
                    residual=float(residual), analytic=bool(analytic))
    e.njev = njev
    return e


def lagrange_dirichlet(hessian: ArrayLike, tol: float = 1e-10) -> tuple:
    """Lagrange-Dirichlet test: (positive definite?, eigenvalues ascending) of a symmetric
    Hessian of the potential energy (LAPACK dsyev)."""
    h = np.asfortranarray(np.asarray(hessian, dtype=float))
    if h.ndim != 2 or h.shape[0] != h.shape[1] or h.size == 0:
        raise ValueError("hessian must be a non-empty square matrix")
    if not np.all(np.isfinite(h)):
        raise ValueError("hessian must be finite")
    stable, w, info = _conmech.flat_lagrange_dirichlet(h, float(tol))
    if info == -4:
        raise ValueError("hessian must be symmetric")
    if info != 0:
        raise RuntimeError("dsyev failed")
    return bool(stable), np.array(w)


def stm(system: Any, t_span: Sequence[float], y0: ArrayLike, rtol: float = 1e-12,
        atol: float = 1e-12, jac: Callable[..., ArrayLike] | None = None,
        full_output: bool = False) -> tuple:
    """(y(t1), Phi(t1)) of the state and its state transition matrix from t0 to t1
    (DOP853 with the same step control on the state and the STM).

    ``jac``: exact Jacobian jac(t, y) -> (n, n) of a Python system (SciPy's name; default:
    central finite differences, accurate to ~1e-6 relative). With ``full_output`` a third
    item, a dict {nfev, njev}, is returned."""
    y0 = _state(y0)
    _check_dim(system, y0)
    try:
        t0, t1 = t_span
    except (TypeError, ValueError):
        raise ValueError("t_span must be a pair (t0, t1)") from None
    t0, t1 = _real(t0, "t_span[0]"), _real(t1, "t_span[1]")
    rtol, atol = _tols(rtol, atol)
    _no_jac_for_builtin(system, jac)
    njev = 0
    if isinstance(system, BuiltinSystem):
        y1, phi, nfev, info, message = _conmech.flat_stm_builtin(
            *system._flat_args(), y0, t0, t1, rtol, atol)
    else:
        g, rhs, dfdy = _callback(system, y0.size, y0, t0, jac)
        if dfdy is None:
            y1, phi, nfev, info, message = _conmech.flat_stm_callback(
                rhs, y0, t0, t1, rtol, atol)
        else:
            y1, phi, nfev, info, message = _conmech.flat_stm_callback_jac(
                rhs, dfdy, y0, t0, t1, rtol, atol)
        g.check()
        njev = g.count("jac")
    if info < 0:
        _raise(info, message)
    if full_output:
        return np.array(y1), np.array(phi), {"nfev": int(nfev), "njev": njev}
    return np.array(y1), np.array(phi)


def monodromy(system: Any, y0: ArrayLike, period: float, rtol: float = 1e-12,
              atol: float = 1e-12, jac: Callable[..., ArrayLike] | None = None) -> np.ndarray:
    """Monodromy matrix Phi(period) of the orbit through y0 (``jac`` as in :func:`stm`)."""
    period = _real(period, "period", 0.0, low_open=True)
    return stm(system, (0.0, period), y0, rtol, atol, jac=jac)[1]


def floquet(m: ArrayLike, period: float) -> dict:
    """Multipliers (eigenvalues of m), Floquet exponents log(mu)/period and, for a 4 x 4
    monodromy, the trace-based stability index S = (trace - 2)/2. Returns a dict."""
    m = np.asarray(m)
    if m.dtype.kind not in "biuf":
        raise TypeError("m must be a real matrix")
    m = m.astype(float)
    if m.ndim != 2 or m.shape[0] != m.shape[1] or m.size == 0:
        raise ValueError("m must be a non-empty square matrix")
    if not np.all(np.isfinite(m)):
        raise ValueError("m must be finite")
    period = _real(period, "period", 0.0, low_open=True)
    mu = np.linalg.eigvals(m)
    with np.errstate(divide="ignore", invalid="ignore"):   # a zero multiplier: -inf
        expo = np.log(mu.astype(complex))/period
    out = {"multipliers": mu, "exponents": expo, "trace": float(np.trace(m))}
    if m.shape == (4, 4):
        out["stability_index"] = 0.5*(np.trace(m) - 2.0)
    return out


class PeriodicOrbit:
    """Result of the shooting functions: y0, period, monodromy, multipliers (complex),
    stability_index (4 x 4 only: (trace M - 2)/2), residual (the true residual of the
    shooting equations at the result, from an independent integration), iterations, njev
    (calls of a Python ``jac``)."""

    __slots__ = ("y0", "period", "monodromy", "multipliers", "stability_index", "residual",
                 "iterations", "njev")

    def __init__(self, **kw):
        for k in self.__slots__:
            setattr(self, k, kw.get(k))

    @property
    def exponents(self):
        return np.log(self.multipliers.astype(complex))/self.period

    def __repr__(self):
        return f"PeriodicOrbit(period={self.period!r}, y0={self.y0.tolist()!r})"


def _orbit(system, y0, period, kind, mode, free, targets, free_time, period_factor, rtol,
           atol, max_iter, jac=None):
    y0 = _state(y0)
    _check_dim(system, y0)
    period = _real(period, "period", 0.0, low_open=True)
    period_factor = _real(period_factor, "period_factor", 0.0, low_open=True)
    rtol, atol = _tols(rtol, atol)
    max_iter = _count(max_iter, "max_iter", 1, 10000)
    _no_jac_for_builtin(system, jac)
    try:
        fr = np.asarray(free).ravel()
        tg = np.asarray(targets).ravel()
    except (TypeError, ValueError):
        raise TypeError("free and targets must be sequences of integers") from None
    for nm, a in (("free", fr), ("targets", tg)):
        if a.size and a.dtype.kind not in "iu":
            raise TypeError(f"{nm} must hold integers (state indices)")
    if np.any(fr < 0) or np.any(fr >= y0.size) or np.any(tg < 0) or np.any(tg >= y0.size):
        raise ValueError("free and targets must be state indices in range(len(y0))")
    fr = np.ascontiguousarray(fr.astype(np.int32) + 1)
    tg = np.ascontiguousarray(tg.astype(np.int32) + 1)
    nfree, ntg = fr.size, tg.size
    if kind == 2 and (nfree == 0 or ntg == 0):
        raise ValueError("free and targets must not be empty")
    if kind == 2 and len(set(fr.tolist())) != nfree:
        raise ValueError("free must not repeat an index")
    fr = fr if nfree else np.ones(1, np.int32)
    tg = tg if ntg else np.ones(1, np.int32)
    args = (y0, period, kind, mode, nfree, fr, ntg, tg, int(bool(free_time)),
            period_factor, rtol, atol, max_iter)
    njev = 0
    if isinstance(system, BuiltinSystem):
        out = _conmech.flat_orbit_builtin(*system._flat_args(), *args)
    else:
        g, rhs, dfdy = _callback(system, y0.size, y0, 0.0, jac)
        if dfdy is None:
            out = _conmech.flat_orbit_callback(rhs, *args)
        else:
            out = _conmech.flat_orbit_callback_jac(rhs, dfdy, *args)
        g.check()
        njev = g.count("jac")
    y0o, po, mono, mr, mi, residual, iterations, info, message = out
    if info != 0:
        _raise(info, message)
    mono = np.array(mono)
    if not (np.all(np.isfinite(mono)) and np.all(np.isfinite(y0o)) and np.isfinite(po)):
        raise RuntimeError("the orbit or its monodromy is not finite")
    y0o = np.array(y0o)
    residual = _true_orbit_residual(system, y0o, float(po), kind, tg[:ntg] - 1,
                                    period_factor, rtol, atol)
    return PeriodicOrbit(y0=y0o, period=float(po), monodromy=mono,
                         multipliers=np.asarray(mr) + 1j*np.asarray(mi),
                         stability_index=0.5*(np.trace(mono) - 2.0) if mono.shape == (4, 4)
                         else None, residual=float(residual), iterations=int(iterations),
                         njev=njev)


#: An orbit is accepted only if an independent integration from the returned y0 closes to
#: max(ORBIT_RESIDUAL_TOL, 1e3 max(rtol, atol)) max(1, |y0|).
ORBIT_RESIDUAL_TOL = 1e-8


def _true_orbit_residual(system, y0, period, kind, targets, period_factor, rtol, atol):
    """The residual of the shooting equations after Newton's last step, from a fresh
    integration (Newton's own test used the residual before that step): max|y(T) - y0|
    (general), or max|y_targets(T/period_factor)| (symmetric). RuntimeError if too big."""
    from ._ivp import solve_ivp
    tau = period if kind == 1 else period/period_factor
    r = solve_ivp(system, (0.0, tau), y0, method="DOP853", rtol=rtol, atol=atol,
                  max_steps=10**6)
    if not r.success:
        raise RuntimeError(f"the orbit found could not be checked: {r.message}")
    y1 = r.y[:, -1]
    res = float(np.max(np.abs(y1 - y0) if kind == 1 else np.abs(y1[targets])))
    tol = max(ORBIT_RESIDUAL_TOL, 1e3*max(rtol, atol))*max(1.0, float(np.max(np.abs(y0))))
    if not res <= tol:
        raise RuntimeError(f"Newton stopped on a state that is not periodic to the "
                           f"tolerance: true residual {res:.3g} > {tol:.3g}")
    return res


def periodic_orbit(system: Any, y0: ArrayLike, period: float, fixed_period: bool = False,
                   rtol: float = 1e-12, atol: float = 1e-12, max_iter=30,
                   jac=None) -> PeriodicOrbit:
    """Newton shooting for a periodic orbit from the guess (y0, period), with the phase
    condition f(y0_guess) . (y0 - y0_guess) = 0. The period is an unknown unless
    ``fixed_period``. Raises RuntimeError when the Newton matrix is singular (an orbit that
    is not isolated, e.g. a conservative family: use :func:`symmetric_orbit` or fix the
    period) or Newton does not converge. ``jac``: exact Jacobian of a Python system."""
    return _orbit(system, y0, period, 1, 2 if fixed_period else 1, [], [], False, 1.0,
                  rtol, atol, max_iter, jac)


def symmetric_orbit(system: Any, y0: ArrayLike, free: Sequence[int], targets: Sequence[int],
                    period: float, period_factor: float = 2.0, free_time: bool = False,
                    rtol=1e-12, atol=1e-12, max_iter=30, jac=None) -> PeriodicOrbit:
    """Symmetric shooting: y0 on the symmetry line (its fixed components as given), the
    components ``free`` (0-based) unknown, the components ``targets`` of the state at
    tau = period/period_factor must vanish (2: half period, 4: quarter period for two
    perpendicular symmetry lines); tau is unknown too if ``free_time``. ``jac``: exact
    Jacobian of a Python system."""
    return _orbit(system, y0, period, 2, 1, free, targets, free_time, period_factor, rtol,
                  atol, max_iter, jac)


class HillEquationResult(dict):
    """dict with monodromy (2, 2), half_trace, det, multipliers, stable."""
    __getattr__ = dict.__getitem__


def _band_limited(p):
    """Samples with the same trigonometric interpolant as ``p`` but only as many as its
    significant harmonics need (coefficients below 1e-15 of the largest one dropped):
    a constant or a low-order Phi sampled a million times costs nothing."""
    c = np.fft.rfft(p)
    mag = np.abs(c)
    big = mag > 1e-15*max(mag.max(), 1e-300)
    k = int(np.nonzero(big)[0].max()) if big.any() else 0
    ns = p.size
    if 2*k + 1 >= ns or (ns % 2 == 0 and k == ns//2):
        return p
    m = max(2*k + 1, 3)
    return np.ascontiguousarray(np.fft.irfft(c[:k + 1], n=m)*(m/ns))


def hill_equation(phi: Callable[[float], float] | ArrayLike, period: float,
                  rtol: float = 1e-12) -> HillEquationResult:
    """Monodromy over one period of N'' + Phi(t) N = 0.

    ``phi`` is a callable Phi(t) or an array of equally spaced samples over one period
    (Phi(k T/ns), k = 0..ns-1; trigonometric interpolation, truncated to its significant
    harmonics). Stable iff |half trace| < 1.
    """
    period = _real(period, "period", 0.0, low_open=True)
    rtol = _real(rtol, "rtol", 0.0, 1.0, low_open=True)
    if callable(phi):
        p0 = phi(0.0)
        as_result(p0, (), "phi")
        g = Guard()
        cb = g.wrap(phi, 1, (), "phi", scalar=True)
        mono, ht, det, info, message = _conmech.flat_hill_equation_callback(cb, period, rtol)
        g.check()
    else:
        p = np.asarray(phi)
        if p.dtype.kind == "c":
            raise TypeError("phi samples must be real")
        try:
            p = np.ascontiguousarray(np.asarray(p, dtype=float).ravel())
        except (TypeError, ValueError):
            raise TypeError("phi must be a callable or an array of real samples") from None
        if p.size < 3 or not np.all(np.isfinite(p)):
            raise ValueError("phi samples: need at least 3 finite values")
        p = _band_limited(p)
        mono, ht, det, info, message = _conmech.flat_hill_equation_samples(p, period, rtol)
    if info != 0:
        _raise(info, message)
    mono = np.array(mono)
    return HillEquationResult(monodromy=mono, half_trace=float(ht), det=float(det),
                              multipliers=np.linalg.eigvals(mono),
                              stable=bool(abs(ht) < 1.0))


# ------------------------------------------------------------------ continuation (issue 9)

_SPECIAL = {1: "fold", 2: "branch point", 3: "period doubling", 4: "Neimark-Sacker"}


class SpecialPoint:
    """A located special point of a branch: kind ('fold', 'branch point', 'period
    doubling', 'Neimark-Sacker'), index (between branch points index and index + 1), p,
    period, y0, multipliers, stability_index."""

    __slots__ = ("kind", "index", "p", "period", "y0", "multipliers", "stability_index")

    def __init__(self, **kw):
        for k in self.__slots__:
            setattr(self, k, kw.get(k))

    def __repr__(self):
        return f"SpecialPoint({self.kind!r}, p={self.p!r}, index={self.index})"


class Branch:
    """A branch of periodic orbits from :func:`continuation`.

    Arrays over the points: p (parameter), period, y0 (N, n), multipliers (N, n) complex,
    stability_index (S = (trace M - 2)/2 for a conservative planar orbit, else the largest
    |mu| of the non-trivial multipliers), stable (bool), tests (N, 4: fold = parameter
    component of the tangent, branch point, period doubling, Neimark-Sacker), residual,
    iterations, energy (if an energy function was given); special (list of SpecialPoint);
    success, status, message (a branch that stopped early keeps its points: success False
    and the message names the parameter value); kernel_ratio (a branch from
    :func:`switch_branch_point`: the second smallest singular value of the shooting
    Jacobian at the branch point over the third, small for a genuine branch point)."""

    __slots__ = ("p", "period", "y0", "multipliers", "stability_index", "stable", "tests",
                 "residual", "iterations", "energy", "special", "status", "message",
                 "param", "conservative", "kernel_ratio")

    def __init__(self, **kw):
        for k in self.__slots__:
            setattr(self, k, kw.get(k))

    @property
    def success(self):
        return self.status == 0

    def __len__(self):
        return len(self.p)

    def __repr__(self):
        return (f"Branch(points={len(self.p)}, p=[{self.p[0]:.6g} .. {self.p[-1]:.6g}], "
                f"special={[(s.kind, round(s.p, 12)) for s in self.special]}, "
                f"message={self.message!r})")


def _param_index(system, param):
    names = system.param_names or tuple(f"p{i}" for i in range(system.params.size))
    if isinstance(param, str):
        if param not in names:
            raise ValueError(f"param {param!r} is not a parameter of '{system.name}' "
                             f"(parameters: {', '.join(names)})")
        return names.index(param)
    if isinstance(param, (int, np.integer)) and 0 <= int(param) < system.params.size:
        return int(param)
    raise ValueError(f"param must be a parameter name or index of '{system.name}'")


def continuation(system: Any, y0: ArrayLike, period: float, param: str | int | None = None,
                 p0: float | None = None, *, direction=1, ds=0.01, ds_min=1e-8, ds_max=0.1,
                 p_range=(-np.inf, np.inf), max_points=200, autonomous=True, fixed_period=False,
                 conservative=False, free=None, targets=None, free_time=False,
                 period_factor=2.0, rtol=1e-11, atol=1e-11, tol=1e-10, res_tol=1e-8,
                 max_iter=12, locate=True, locate_tol=1e-11, energy=None, in_period=False,
                 _switch=0, _tangent=None) -> Branch:
    """Pseudo-arclength continuation of the periodic orbit through ``y0`` (period guess
    ``period``) in a parameter, with its special points located (see conmech_continuation).

    ``system``: a built-in system (``param`` = the parameter's name or index; it starts
    from the system's value, or ``p0``) or a callable ``fun(t, y, p)`` (``p0`` required).
    General shooting (unknowns y0, period (unless ``fixed_period``), p; phase condition for
    ``autonomous`` systems) or symmetric shooting (``free``, ``targets``: 0-based indices of
    the free initial components and of the components of y(tau) that vanish; tau =
    period/period_factor, free if ``free_time``). ``conservative``: a second trivial
    multiplier (energy); continue at a fixed period, or with ``in_period`` along the family
    of a conservative system without a parameter: the period is the continued quantity
    (``p`` holds it; ``param``/``p0`` are not needed and a callable is ``fun(t, y)``).
    ``energy(y, p)``: optional, evaluated along the branch. Raises ValueError on bad input
    and RuntimeError when the start is not a periodic orbit or not isolated; a branch that
    stops later is returned with success False and a message naming the parameter value.
    """
    y0 = _state(y0)
    _check_dim(system, y0)
    n = y0.size
    period = float(period)
    if not period > 0:
        raise ValueError("period must be positive")
    if int(max_points) < 1:
        raise ValueError("max_points must be >= 1")
    for name, v in (("ds", ds), ("ds_min", ds_min), ("ds_max", ds_max), ("rtol", rtol),
                    ("atol", atol), ("tol", tol), ("res_tol", res_tol)):
        if not (np.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be positive and finite")
    if not rtol < 1:
        raise ValueError("rtol must be < 1")
    lo, hi = (float(v) for v in p_range)
    sym = free is not None or targets is not None
    if sym and (free is None or targets is None):
        raise ValueError("symmetric shooting needs both free and targets")
    fr = np.ascontiguousarray(np.asarray(free if sym else [0], dtype=np.int32).ravel() + 1)
    tg = np.ascontiguousarray(np.asarray(targets if sym else [0], dtype=np.int32).ravel() + 1)
    if sym and (fr.size == 0 or tg.size == 0 or fr.min() < 1 or fr.max() > n
                or tg.min() < 1 or tg.max() > n):
        raise ValueError("free and targets must be non-empty state indices in range(len(y0))")
    ropt = np.array([ds, ds_min, ds_max, max(lo, -1e300), min(hi, 1e300), tol, res_tol,
                     rtol, atol, locate_tol, period_factor], dtype=float)
    iopt = np.array([max_points, 1 if direction >= 0 else -1, max_iter, bool(autonomous),
                     bool(fixed_period), bool(conservative), bool(locate), sym,
                     bool(free_time), int(_switch), bool(in_period)], dtype=np.int32)
    if in_period and (sym or not autonomous):
        raise ValueError("in_period is for general shooting of autonomous systems")
    tang = np.zeros(1) if _tangent is None else np.array(_tangent, dtype=float).ravel()
    args = (ropt, iopt, fr.size if sym else 0, fr, tg.size if sym else 0, tg,
            tang.size if _tangent is not None else 0, tang, int(max_points))
    if isinstance(system, BuiltinSystem):
        if param is None and in_period:
            param = 0
        if param is None:
            raise ValueError("param (name or index of the continuation parameter) is needed")
        ip = _param_index(system, param)
        params = np.array(system.params, dtype=float)
        if p0 is not None:
            params[ip] = float(p0)
        name, _, _, nspec, spec = system._flat_args()
        out = _conmech.flat_continuation_builtin(name, params.size, params, nspec, spec,
                                                 ip + 1, y0, period, *args)
        pname = (system.param_names or tuple(f"p{i}" for i in range(params.size)))[ip]
    else:
        if not callable(system):
            raise TypeError("system must be a conmech.systems.BuiltinSystem or a callable "
                            "fun(t, y, p)")
        if p0 is None and in_period:
            p0 = 0.0
        if p0 is None:
            raise ValueError("p0 (the start value of the parameter) is needed for a callable")

        def rhs(t, y, p):
            o = np.asarray(system(t, y) if in_period else system(t, y, p),
                           dtype=float).ravel()
            if o.size != n:
                raise ValueError(f"fun(t, y, p) returned {o.size} values, expected {n}")
            return o
        out = _conmech.flat_continuation_callback(rhs, y0, period, float(p0), *args)
        pname = param if isinstance(param, str) else "p"
    (npts, pp, per, ys, mr, mi, s, psi, res, iters, nsp, sk, si, sp_p, sp_per, sp_y,
     sp_mr, sp_mi, sp_s, info, message) = out
    npts = int(npts)
    if npts == 0:
        _raise(info, message)
    k = slice(0, npts)
    mult = (np.asarray(mr)[:, k] + 1j*np.asarray(mi)[:, k]).T.copy()
    s = np.array(s[k])
    if conservative and n == 4:
        stable = np.abs(s) < 1
    else:
        stable = s < 1
    special = []
    for j in range(int(nsp)):
        special.append(SpecialPoint(kind=_SPECIAL.get(int(sk[j]), "unknown"),
                                    index=int(si[j]) - 1, p=float(sp_p[j]),
                                    period=float(sp_per[j]), y0=np.array(sp_y[:, j]),
                                    multipliers=np.asarray(sp_mr[:, j])
                                    + 1j*np.asarray(sp_mi[:, j]),
                                    stability_index=float(sp_s[j])))
    ys = np.array(ys[:, k]).T.copy()
    pp = np.array(pp[k])
    en = None
    if energy is not None:
        en = np.array([float(energy(y, p)) for y, p in zip(ys, pp)])
    return Branch(p=pp, period=np.array(per[k]), y0=ys, multipliers=mult,
                  stability_index=s, stable=stable, tests=np.array(psi[:, k]).T.copy(),
                  residual=np.array(res[k]), iterations=np.array(iters[k], dtype=int),
                  energy=en, special=special, status=int(info), message=_msg(message),
                  param="period" if in_period else pname, conservative=bool(conservative),
                  kernel_ratio=float(tang[0]) if _switch == 2 else None)


def transverse(potential: Callable[..., Any], y0: ArrayLike, period: float, omega: float = 0.0,
               t: ArrayLike | None = None, rtol: float = 1e-12) -> dict:
    """Transverse linearisation (seed 000) of a periodic orbit of the planar natural system
    q'' = -grad V(q) + 2 omega J q' (J q' = (-q2', q1'); omega: a rotating frame, e.g.
    Hill's problem is V = -F, omega = -m): the normal deviation obeys Hill's equation
    N'' + Phi(t) N = 0, Phi = n^T V'' n + 3 (phi' - omega)^2 + omega^2 (phi' the turning
    rate of the velocity). ``potential(q)`` returns (V, grad V (2,), Hessian (2, 2)).
    ``t`` (increasing times in [0, period]) samples Phi along the orbit; ``rtol`` is the
    integrators' tolerance (rtol = atol) everywhere.

    Returns a dict: monodromy (2, 2), half_trace, det, multipliers (2,), the 4 x 4
    ``monodromy4`` of the orbit (same tolerance), its stability index
    ``stability_index4`` = (trace - 2)/2 (equal to half_trace: the 2 x 2 multipliers are
    the non-trivial ones), closure (max |y(T) - y0|), and ``phi`` at t."""
    if not callable(potential):
        raise TypeError("potential must be a callable q -> (V, grad, hessian)")
    y0 = _state(y0)
    if y0.size != 4:
        raise ValueError("y0 must be [q1, q2, q1', q2'] (4 values)")
    period = float(period)
    if not period > 0:
        raise ValueError("period must be positive")
    if not (np.isfinite(rtol) and 0 < rtol < 1):
        raise ValueError("rtol must be in (0, 1)")
    tt = np.zeros(0) if t is None else np.ascontiguousarray(np.asarray(t, float).ravel())
    if tt.size and (not np.all(np.isfinite(tt)) or np.any(np.diff(tt) < 0) or tt[0] < 0):
        raise ValueError("t must be finite, non-negative and increasing")

    def pot(q):
        v, g, h = potential(np.array(q))
        g = np.asarray(g, dtype=float).ravel()
        h = np.asarray(h, dtype=float)
        if g.size != 2 or h.shape != (2, 2):
            raise ValueError("potential(q) must return (V, grad (2,), hessian (2, 2))")
        return float(v), g, h
    ttx = tt if tt.size else np.zeros(1)
    phi, m2, ht, det, closure, m4, info, message = _conmech.flat_transverse_callback(
        pot, float(omega), y0, period, float(rtol), ttx)
    if info != 0:
        _raise(info, message)
    m2 = np.array(m2)
    m4 = np.array(m4)
    out = {"monodromy": m2, "half_trace": float(ht), "det": float(det),
           "multipliers": np.linalg.eigvals(m2), "monodromy4": m4,
           "stability_index4": 0.5*(np.trace(m4) - 2.0), "closure": float(closure)}
    if tt.size:
        out["phi"] = np.array(phi)
    return out


# ------------------------------------------------------------------ equilibria (issue 9)

def find_equilibrium(system: Any, guess: ArrayLike, t: float = 0.0, tol: float = 1e-12,
                     max_iter: int = 50, classify_tol: float = 1e-8) -> Equilibrium:
    """Newton's method for f(t, y) = 0 from ``guess`` (analytic Jacobian of built-in
    systems, central differences for callables), then :func:`equilibrium` at the root:
    returns the classified :class:`Equilibrium`. Raises RuntimeError when Newton fails
    (singular Jacobian or no convergence) or the residual at the root exceeds sqrt(tol)."""
    y = _state(guess, "guess")
    _check_dim(system, y)
    if not (np.isfinite(tol) and tol > 0) or int(max_iter) < 1:
        raise ValueError("tol must be positive and max_iter >= 1")
    if isinstance(system, BuiltinSystem):
        yout, info, message = _conmech.flat_find_equilibrium_builtin(
            *system._flat_args(), y, float(t), float(tol), int(max_iter))
    else:
        g, rhs, _ = _callback(system, y.size, y, float(t))
        yout, info, message = _conmech.flat_find_equilibrium_callback(
            rhs, y, float(t), float(tol), int(max_iter))
        g.check()
    if info != 0:
        _raise(info, message)
    e = equilibrium(system, np.array(yout), t=t, tol=classify_tol)
    if not e.residual <= max(np.sqrt(tol), 1e-8)*max(1.0, np.max(np.abs(e.y))):
        raise RuntimeError(f"find_equilibrium: residual {e.residual:.3g} at the root")
    return e


def equilibria(system: Any, guesses: ArrayLike, t: float = 0.0, tol: float = 1e-12,
               dedup_tol: float = 1e-8, classify_tol: float = 1e-8) -> list:
    """All equilibria reached by Newton from an array of guesses (shape (k, n)), e.g. a
    grid; duplicates (max-norm distance <= dedup_tol max(1, |y|)) removed. Guesses whose
    Newton fails are skipped. Returns a list of :class:`Equilibrium`, sorted by y."""
    g = np.asarray(guesses, dtype=float)
    if g.ndim != 2 or g.shape[0] == 0:
        raise ValueError("guesses must be a non-empty (k, n) array")
    found = []
    for y in g:
        try:
            e = find_equilibrium(system, y, t=t, tol=tol, classify_tol=classify_tol)
        except RuntimeError:
            continue
        if not any(np.max(np.abs(e.y - f.y)) <= dedup_tol*max(1.0, np.max(np.abs(f.y)))
                   for f in found):
            found.append(e)
    found.sort(key=lambda e: tuple(e.y))
    return found


def grid(bounds: Sequence[Sequence[float]], num: int | Sequence[int]) -> np.ndarray:
    """Guesses on a regular grid: ``bounds`` = [(lo, hi), ...] per component, ``num``
    points per component (an int or a list). Returns a (k, n) array for
    :func:`equilibria`."""
    bounds = [tuple(map(float, b)) for b in bounds]
    num = [int(num)]*len(bounds) if np.isscalar(num) else [int(k) for k in num]
    if len(num) != len(bounds) or min(num) < 1:
        raise ValueError("num must be a positive int or one per bound")
    axes = [np.linspace(lo, hi, k) for (lo, hi), k in zip(bounds, num)]
    return np.stack([a.ravel() for a in np.meshgrid(*axes, indexing="ij")], axis=1)


def potential_hessian(potential, q, h=None):
    """Central-difference Hessian of a potential V(q) (step eps^(1/4) max(|q_i|, 1), error
    O(h^2) ~ 1e-8 relative)."""
    q = _state(q, "q")
    n = q.size
    hs = np.full(n, np.finfo(float).eps**0.25)*np.maximum(np.abs(q), 1.0) if h is None \
        else np.full(n, float(h))
    H = np.empty((n, n))
    v0 = float(potential(q))
    for i in range(n):
        e_i = np.zeros(n)
        e_i[i] = hs[i]
        H[i, i] = (float(potential(q + e_i)) - 2*v0 + float(potential(q - e_i)))/hs[i]**2
        for j in range(i + 1, n):
            e_j = np.zeros(n)
            e_j[j] = hs[j]
            H[i, j] = H[j, i] = (float(potential(q + e_i + e_j))
                                 - float(potential(q + e_i - e_j))
                                 - float(potential(q - e_i + e_j))
                                 + float(potential(q - e_i - e_j)))/(4*hs[i]*hs[j])
    return H


def lagrange_dirichlet_potential(potential, q, hessian=None, tol=1e-6):
    """Lagrange-Dirichlet test at q from the potential: a strict minimum (positive-definite
    Hessian) is a stable equilibrium of a conservative system. ``hessian(q)`` if given
    (exact, e.g. symbolic), else :func:`potential_hessian`. Returns (stable, eigenvalues,
    hessian); ``tol`` is relative to the largest |eigenvalue| (finite differences carry
    ~1e-8)."""
    q = _state(q, "q")
    H = np.asarray(hessian(q), dtype=float) if hessian is not None else \
        potential_hessian(potential, q)
    H = 0.5*(H + H.T)
    stable, w = lagrange_dirichlet(H, tol=tol)
    return stable, w, H


def switch_period_doubling(system: Any, point: SpecialPoint, param: str | int | None = None,
                           **options) -> Branch:
    """Branch switching at a located period doubling: the branch of orbits of twice the
    period that bifurcates at ``point`` (a :class:`SpecialPoint` of kind 'period doubling'
    from :func:`continuation` on the same ``system``/``param``). The first step follows the
    eigenvector of the multiplier -1 (``direction`` picks its sign); the other options as
    for :func:`continuation` (general shooting of an autonomous system)."""
    if not isinstance(point, SpecialPoint) or point.kind != "period doubling":
        raise ValueError("point must be a 'period doubling' SpecialPoint of a Branch")
    for bad in ("free", "targets", "p0", "_switch", "_tangent"):
        if bad in options:
            raise ValueError(f"{bad} is not an option of switch_period_doubling")
    return continuation(system, point.y0, point.period, param=param, p0=point.p,
                        _switch=1, **options)


# --------------------------------------------------------------------------- plots

def plot_branch(branch, ax=None, y="stability_index", label_special=True):
    """Bifurcation diagram: the parameter against ``y`` ('stability_index', 'period',
    'energy' or a callable branch -> array), stable parts solid, unstable dashed, special
    points marked and labelled (matplotlib)."""
    import matplotlib.pyplot as plt
    if ax is None:
        _, ax = plt.subplots()
    if callable(y):
        vals, name = np.asarray(y(branch), dtype=float), getattr(y, "__name__", "y")
    else:
        vals, name = np.asarray(getattr(branch, y), dtype=float), y
    p = branch.p
    st = np.asarray(branch.stable)
    for mask, style, lab in ((st, "-", "stable"), (~st, "--", "unstable")):
        v = np.where(mask, vals, np.nan)
        ax.plot(p, v, style, color="C0", label=lab)
    marks = {"fold": "s", "branch point": "o", "period doubling": "D",
             "Neimark-Sacker": "^"}
    for s in branch.special:
        i = s.index
        w = 0.0 if p[i + 1] == p[i] else (s.p - p[i])/(p[i + 1] - p[i])
        yv = vals[i] + w*(vals[i + 1] - vals[i]) if name != "period" else s.period
        ax.plot([s.p], [yv], marks.get(s.kind, "x"), color="C3", ms=8)
        if label_special:
            ax.annotate(f"{s.kind}\n{branch.param} = {s.p:.10g}", (s.p, yv),
                        textcoords="offset points", xytext=(6, 6), fontsize=8)
    ax.set_xlabel(branch.param)
    ax.set_ylabel(name)
    ax.legend(loc="best")
    ax.set_title("branch of periodic orbits")
    return ax


def plot_multipliers(branch, ax=None):
    """The Floquet multipliers of every point of a branch in the complex plane, coloured by
    the parameter, with the unit circle (matplotlib)."""
    import matplotlib.pyplot as plt
    if ax is None:
        _, ax = plt.subplots()
    th = np.linspace(0.0, 2.0*np.pi, 400)
    ax.plot(np.cos(th), np.sin(th), color="0.6", lw=1)
    mu = branch.multipliers
    pp = np.repeat(branch.p[:, None], mu.shape[1], axis=1)
    sc = ax.scatter(mu.real.ravel(), mu.imag.ravel(), c=pp.ravel(), s=8, cmap="viridis")
    plt.colorbar(sc, ax=ax, label=branch.param)
    ax.set_aspect("equal")
    ax.set_xlabel("Re mu")
    ax.set_ylabel("Im mu")
    ax.set_title("multipliers along the branch")
    return ax


from ._branch_switch import switch_branch_point  # noqa: E402 (uses continuation above)
from ._constrained_equilibria import (  # noqa: E402
    ConstrainedEquilibrium, constrained_equilibrium, constrained_equilibria)
