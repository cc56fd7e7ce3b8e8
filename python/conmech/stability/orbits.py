"""Periodic orbits by Newton shooting (general and symmetric), each checked by an
independent integration."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from .. import _conmech
from .._ivp import solve_ivp
from .._native import NativeSystem
from ._validate import (_callback, _check_dim, _count, _no_jac_for_builtin, _raise, _real,
                        _state, _tols)

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
    if isinstance(system, NativeSystem):
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
