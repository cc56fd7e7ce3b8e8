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
from .systems import BuiltinSystem

__all__ = ["Equilibrium", "PeriodicOrbit", "equilibrium", "lagrange_dirichlet", "stm",
           "monodromy", "periodic_orbit", "symmetric_orbit", "floquet", "hill_equation"]

_KINDS = {1: "asymptotically stable", 2: "centre", 3: "unstable", 4: "degenerate"}


def _msg(message):
    if isinstance(message, (bytes, bytearray, np.ndarray)):
        message = bytes(message).decode("ascii", "replace")
    return str(message).strip()


def _raise(info, message):
    msg = _msg(message)
    if info == -4:
        raise ValueError(msg)
    raise RuntimeError(msg)


def _state(y, name="y0"):
    y = np.ascontiguousarray(np.asarray(y, dtype=float).ravel())
    if y.size == 0:
        raise ValueError(f"{name} must not be empty")
    if not np.all(np.isfinite(y)):
        raise ValueError(f"{name} must be finite")
    return y


def _callback(fun, n):
    if not callable(fun):
        raise TypeError("system must be a conmech.systems.BuiltinSystem or a callable "
                        "fun(t, y)")

    def rhs(t, y):
        out = np.asarray(fun(t, y), dtype=float).ravel()
        if out.size != n:
            raise ValueError(f"fun(t, y) returned {out.size} values, expected {n}")
        return out
    return rhs


def _params(system):
    p = np.ascontiguousarray(system.params, dtype=float)
    return p if p.size else np.zeros(1)


def _check_dim(system, y):
    if isinstance(system, BuiltinSystem) and y.size != system.dimension:
        raise ValueError(f"y0 has {y.size} components; the system '{system.name}' has "
                         f"{system.dimension}")


class Equilibrium:
    """Result of :func:`equilibrium`: y, jacobian, eigenvalues (complex), kind
    ('asymptotically stable', 'centre', 'unstable', 'degenerate'), saddle, residual
    (max |f(y)|), analytic (the Jacobian was analytic)."""

    __slots__ = ("y", "jacobian", "eigenvalues", "kind", "saddle", "residual", "analytic")

    def __init__(self, **kw):
        for k in self.__slots__:
            setattr(self, k, kw.get(k))

    @property
    def stable(self):
        """Linearly stable (asymptotically stable or centre)."""
        return self.kind in ("asymptotically stable", "centre")

    def __repr__(self):
        return f"Equilibrium(kind={self.kind!r}, eigenvalues={self.eigenvalues!r})"


def equilibrium(system, y, t=0.0, tol=1e-8):
    """Linearise at y, compute the eigenvalues and classify (see conmech_equilibria).

    ``tol`` is relative to max(1, max|lambda|): Re(lambda) within it counts as zero.
    """
    y = _state(y, "y")
    _check_dim(system, y)
    n = y.size
    if isinstance(system, BuiltinSystem):
        out = _conmech.flat_equilibrium_builtin(*system._flat_args(), y, float(t),
                                                float(tol))
    else:
        out = _conmech.flat_equilibrium_callback(_callback(system, n), y, float(t),
                                                 float(tol))
    jac, wr, wi, kind, saddle, residual, analytic, info, message = out
    if info != 0:
        _raise(info, message)
    return Equilibrium(y=y, jacobian=np.array(jac), eigenvalues=np.asarray(wr) + 1j*np.asarray(wi),
                       kind=_KINDS.get(int(kind), "degenerate"), saddle=bool(saddle),
                       residual=float(residual), analytic=bool(analytic))


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


def stm(system, t_span, y0, rtol=1e-12, atol=1e-12):
    """(y(t1), Phi(t1)) of the state and its state transition matrix from t0 to t1
    (DOP853 with the same step control on the state and the STM)."""
    y0 = _state(y0)
    _check_dim(system, y0)
    t0, t1 = (float(v) for v in t_span)
    if isinstance(system, BuiltinSystem):
        y1, phi, nfev, info, message = _conmech.flat_stm_builtin(
            *system._flat_args(), y0, t0, t1, float(rtol), float(atol))
    else:
        y1, phi, nfev, info, message = _conmech.flat_stm_callback(
            _callback(system, y0.size), y0, t0, t1, float(rtol), float(atol))
    if info < 0:
        _raise(info, message)
    return np.array(y1), np.array(phi)


def monodromy(system, y0, period, rtol=1e-12, atol=1e-12):
    """Monodromy matrix Phi(period) of the orbit through y0."""
    return stm(system, (0.0, period), y0, rtol, atol)[1]


def floquet(m, period):
    """Multipliers (eigenvalues of m), Floquet exponents log(mu)/period and, for a 4 x 4
    monodromy, the trace-based stability index S = (trace - 2)/2. Returns a dict."""
    m = np.asarray(m, dtype=float)
    if m.ndim != 2 or m.shape[0] != m.shape[1]:
        raise ValueError("m must be a square matrix")
    period = float(period)
    if not period > 0:
        raise ValueError("period must be positive")
    mu = np.linalg.eigvals(m)
    out = {"multipliers": mu, "exponents": np.log(mu.astype(complex))/period,
           "trace": float(np.trace(m))}
    if m.shape == (4, 4):
        out["stability_index"] = 0.5*(np.trace(m) - 2.0)
    return out


class PeriodicOrbit:
    """Result of the shooting functions: y0, period, monodromy, multipliers (complex),
    stability_index (4 x 4 only: (trace M - 2)/2), residual, iterations."""

    __slots__ = ("y0", "period", "monodromy", "multipliers", "stability_index", "residual",
                 "iterations")

    def __init__(self, **kw):
        for k in self.__slots__:
            setattr(self, k, kw.get(k))

    @property
    def exponents(self):
        return np.log(self.multipliers.astype(complex))/self.period

    def __repr__(self):
        return f"PeriodicOrbit(period={self.period!r}, y0={self.y0.tolist()!r})"


def _orbit(system, y0, period, kind, mode, free, targets, free_time, period_factor, rtol,
           atol, max_iter):
    y0 = _state(y0)
    _check_dim(system, y0)
    period = float(period)
    if not period > 0:
        raise ValueError("period must be positive")
    fr = np.ascontiguousarray(np.asarray(free, dtype=np.int32).ravel() + 1)
    tg = np.ascontiguousarray(np.asarray(targets, dtype=np.int32).ravel() + 1)
    nfree, ntg = fr.size, tg.size
    if kind == 2 and (nfree == 0 or ntg == 0):
        raise ValueError("free and targets must not be empty")
    if np.any(fr < 1) or np.any(fr > y0.size) or np.any(tg < 1) or np.any(tg > y0.size):
        raise ValueError("free and targets must be state indices in range(len(y0))")
    fr = fr if nfree else np.ones(1, np.int32)
    tg = tg if ntg else np.ones(1, np.int32)
    args = (y0, period, kind, mode, nfree, fr, ntg, tg, int(bool(free_time)),
            float(period_factor), float(rtol), float(atol), int(max_iter))
    if isinstance(system, BuiltinSystem):
        out = _conmech.flat_orbit_builtin(*system._flat_args(), *args)
    else:
        out = _conmech.flat_orbit_callback(_callback(system, y0.size), *args)
    y0o, po, mono, mr, mi, residual, iterations, info, message = out
    if info != 0:
        _raise(info, message)
    mono = np.array(mono)
    return PeriodicOrbit(y0=np.array(y0o), period=float(po), monodromy=mono,
                         multipliers=np.asarray(mr) + 1j*np.asarray(mi),
                         stability_index=0.5*(np.trace(mono) - 2.0) if mono.shape == (4, 4)
                         else None, residual=float(residual), iterations=int(iterations))


def periodic_orbit(system, y0, period, fixed_period=False, rtol=1e-12, atol=1e-12,
                   max_iter=30):
    """Newton shooting for a periodic orbit from the guess (y0, period), with the phase
    condition f(y0_guess) . (y0 - y0_guess) = 0. The period is an unknown unless
    ``fixed_period``. Raises RuntimeError when the Newton matrix is singular (an orbit that
    is not isolated, e.g. a conservative family: use :func:`symmetric_orbit` or fix the
    period) or Newton does not converge."""
    return _orbit(system, y0, period, 1, 2 if fixed_period else 1, [], [], False, 1.0,
                  rtol, atol, max_iter)


def symmetric_orbit(system, y0, free, targets, period, period_factor=2.0, free_time=False,
                    rtol=1e-12, atol=1e-12, max_iter=30):
    """Symmetric shooting: y0 on the symmetry line (its fixed components as given), the
    components ``free`` (0-based) unknown, the components ``targets`` of the state at
    tau = period/period_factor must vanish (2: half period, 4: quarter period for two
    perpendicular symmetry lines); tau is unknown too if ``free_time``."""
    return _orbit(system, y0, period, 2, 1, free, targets, free_time, period_factor, rtol,
                  atol, max_iter)


class HillEquationResult(dict):
    """dict with monodromy (2, 2), half_trace, det, multipliers, stable."""
    __getattr__ = dict.__getitem__


def hill_equation(phi, period, rtol=1e-12):
    """Monodromy over one period of N'' + Phi(t) N = 0.

    ``phi`` is a callable Phi(t) or an array of equally spaced samples over one period
    (Phi(k T/ns), k = 0..ns-1; trigonometric interpolation). Stable iff |half trace| < 1.
    """
    period = float(period)
    if not period > 0:
        raise ValueError("period must be positive")
    if callable(phi):
        def cb(t):
            return float(phi(t))
        mono, ht, det, info, message = _conmech.flat_hill_equation_callback(cb, period,
                                                                             float(rtol))
    else:
        p = np.ascontiguousarray(np.asarray(phi, dtype=float).ravel())
        if p.size < 3 or not np.all(np.isfinite(p)):
            raise ValueError("phi samples: need at least 3 finite values")
        mono, ht, det, info, message = _conmech.flat_hill_equation_samples(p, period,
                                                                            float(rtol))
    if info != 0:
        _raise(info, message)
    mono = np.array(mono)
    return HillEquationResult(monodromy=mono, half_trace=float(ht), det=float(det),
                              multipliers=np.linalg.eigvals(mono),
                              stable=bool(abs(ht) < 1.0))
