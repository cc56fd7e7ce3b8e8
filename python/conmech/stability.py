"""Stability of equilibria and periodic motions, for built-in systems
(:mod:`conmech.systems`, run entirely in Fortran) or Python callables ``fun(t, y)``
(finite-difference Jacobian in Fortran).

- :func:`equilibrium`: linearisation, eigenvalues (LAPACK) and classification;
- :func:`lagrange_dirichlet`: is the Hessian of the potential positive definite?
- :func:`stm`: state and state transition matrix (variational equations);
- :func:`periodic_orbit`, :func:`symmetric_orbit`: Newton shooting, with the monodromy
  matrix and Floquet multipliers;
- :func:`floquet`: multipliers, exponents and the planar stability index of a monodromy;
- :func:`hill_equation`: N'' + Phi(t) N = 0 with Phi a callable or periodic samples.
"""
import numpy as np

from . import _conmech
from ._callback import Guard, as_result, message_text
from .systems import BuiltinSystem

__all__ = ["Equilibrium", "PeriodicOrbit", "equilibrium", "lagrange_dirichlet", "stm",
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


def equilibrium(system, y, t=0.0, tol=1e-8, jac=None):
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


def lagrange_dirichlet(hessian, tol=1e-10):
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


def stm(system, t_span, y0, rtol=1e-12, atol=1e-12, jac=None, full_output=False):
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


def monodromy(system, y0, period, rtol=1e-12, atol=1e-12, jac=None):
    """Monodromy matrix Phi(period) of the orbit through y0 (``jac`` as in :func:`stm`)."""
    period = _real(period, "period", 0.0, low_open=True)
    return stm(system, (0.0, period), y0, rtol, atol, jac=jac)[1]


def floquet(m, period):
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


def periodic_orbit(system, y0, period, fixed_period=False, rtol=1e-12, atol=1e-12,
                   max_iter=30, jac=None):
    """Newton shooting for a periodic orbit from the guess (y0, period), with the phase
    condition f(y0_guess) . (y0 - y0_guess) = 0. The period is an unknown unless
    ``fixed_period``. Raises RuntimeError when the Newton matrix is singular (an orbit that
    is not isolated, e.g. a conservative family: use :func:`symmetric_orbit` or fix the
    period) or Newton does not converge. ``jac``: exact Jacobian of a Python system."""
    return _orbit(system, y0, period, 1, 2 if fixed_period else 1, [], [], False, 1.0,
                  rtol, atol, max_iter, jac)


def symmetric_orbit(system, y0, free, targets, period, period_factor=2.0, free_time=False,
                    rtol=1e-12, atol=1e-12, max_iter=30, jac=None):
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


def hill_equation(phi, period, rtol=1e-12):
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
