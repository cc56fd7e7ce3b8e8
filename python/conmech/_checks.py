"""Argument checks shared by solve_ivp, the steppers and the ensembles: messages name the
argument, as SciPy's do."""
import math
import numbers

import numpy as np

__all__ = ["real_scalar", "tolerance", "event_settings", "initial_state"]


def real_scalar(value, name):
    """``value`` as a float (a real scalar; TypeError/ValueError naming ``name``)."""
    if type(value) is float or type(value) is int:
        return float(value)
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Real, np.ndarray)):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__}")
    arr = np.asarray(value, dtype=float)
    if arr.ndim != 0:
        raise ValueError(f"{name} must be a scalar")
    return float(arr)


def tolerance(value, name, n):
    """A tolerance as a contiguous float array of shape (n,), checked (non-negative,
    finite; a scalar or one value per component)."""
    if type(value) is float or type(value) is int:   # fast path for the common case
        v = float(value)
        if not v >= 0:
            raise ValueError(f"{name} must be non-negative")
        if v == math.inf:
            raise ValueError(f"{name} must be finite")
        return np.full(n, v)
    try:
        arr = np.asarray(value)
        if arr.dtype.kind not in "biuf" or isinstance(value, (bool, np.bool_)):
            raise TypeError
        arr = arr.astype(float)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{name} must be a non-negative number or an array of shape "
                        f"({n},)") from exc
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    elif arr.shape != (n,):
        raise ValueError(f"{name} must be a scalar or have shape ({n},) like y0, got shape "
                         f"{arr.shape}")
    if np.isnan(arr).any() or (arr < 0).any():
        raise ValueError(f"{name} must be non-negative")
    if not np.isfinite(arr).all():
        raise ValueError(f"{name} must be finite")
    return np.ascontiguousarray(arr)


def event_settings(events):
    """(function, terminal count (0: not terminal), direction) per event, SciPy's rules:
    ``terminal`` is a bool or a positive integer (stop at that occurrence)."""
    if events is None:
        return []
    evs = [events] if callable(events) else events
    try:
        evs = list(evs)
    except TypeError:
        raise TypeError("events must be a callable or a list of callables") from None
    for i, e in enumerate(evs):
        if not callable(e):
            raise TypeError(f"events[{i}] is not callable")
    settings = []
    for i, e in enumerate(evs):
        term = getattr(e, "terminal", None)
        if term is None or isinstance(term, (bool, np.bool_)):
            count = int(bool(term))
        elif isinstance(term, numbers.Real):
            tv = float(term)
            if not (math.isfinite(tv) and 0 <= tv <= 2**31 - 1 and tv == int(tv)):
                raise ValueError(f"events[{i}].terminal must be a boolean or a positive "
                                 f"integer (a count of occurrences), got {term!r}")
            count = int(tv)
        else:
            raise ValueError(f"events[{i}].terminal must be a boolean or a positive "
                             f"integer (a count of occurrences), got {term!r}")
        direction = getattr(e, "direction", 0)
        try:
            direction = float(direction)
        except (TypeError, ValueError):
            raise ValueError(f"events[{i}].direction must be a number") from None
        if math.isnan(direction):
            raise ValueError(f"events[{i}].direction must be a number")
        settings.append((e, count, int(np.sign(direction))))
    return settings


def initial_state(y0, fun, builtin):
    """y0 as a 1-dimensional float array, checked: real, not empty, finite, and of the
    system's dimension when ``fun`` is a built-in system."""
    y0_in = np.asarray(y0)
    if y0_in.dtype.kind == "c":
        raise TypeError("y0 must be real: complex states are not supported (split them "
                        "into real and imaginary parts)")
    try:
        y = np.array(y0_in, dtype=float)
    except (TypeError, ValueError):
        raise TypeError("y0 must be an array of real numbers") from None
    if y.ndim != 1:
        raise ValueError(f"y0 must be 1-dimensional, got shape {y.shape}")
    if y.size == 0:
        raise ValueError("y0 must not be empty")
    if not np.isfinite(y).all():
        raise ValueError("y0 contains NaN or Inf")
    if builtin and y.size != fun.dimension:
        raise ValueError(f"y0 must have shape ({fun.dimension},) for the system "
                         f"'{fun.name}', got {y.shape}")
    return y
