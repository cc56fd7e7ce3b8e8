"""Argument checks shared by the stability routines and their neighbours: each raises a
ValueError/TypeError naming the argument."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from .. import _conmech  # noqa: F401
from .callback import Guard, as_result, message_text
from .native import _NO_SPEC, _PAD, NativeSystem, _unused_callback

def _msg(message):
    return message_text(message)


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
        raise TypeError("system must be a conmech.systems.NativeSystem or a callable "
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


def _system_args(system, n, y0, t0, jac=None):
    """(guard, args): the one system argument set of the flat routines (name, np, params,
    nspec, spec, fun, jfun, source; see conmech_flat_system) for a built-in or compiled
    system (guard None) or a Python right-hand side with its optional Jacobian (guarded,
    probed at (t0, y0) by :func:`_callback`)."""
    if isinstance(system, NativeSystem):
        return None, system._system_args()
    g, rhs, dfdy = _callback(system, n, y0, t0, jac)
    if dfdy is None:
        return g, ("", 0, _PAD, 0, _NO_SPEC, rhs, _unused_callback, 1)
    return g, ("", 0, _PAD, 0, _NO_SPEC, rhs, dfdy, 2)


def _check_dim(system, y):
    if isinstance(system, NativeSystem) and y.size != system.dimension:
        raise ValueError(f"y0 has {y.size} components; the system '{system.name}' has "
                         f"{system.dimension}")


def _no_jac_for_builtin(system, jac):
    if jac is not None and isinstance(system, NativeSystem):
        raise TypeError("jac is for Python callables; a built-in system has its own "
                        "Jacobian")

