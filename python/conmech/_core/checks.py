"""Argument checks shared by solve_ivp, the steppers and the ensembles: messages name the
argument, as SciPy's do."""
import cmath
import math
import numbers
import warnings

import numpy as np

__all__ = ["real_scalar", "real_number", "step_limit", "NO_STEP_LIMIT", "tolerance", "time_span", "time_points", "event_settings", "initial_state",
           "RTOL_FLOOR", "step_controls", "positive_finite"]

#: The smallest relative tolerance (SciPy's 100 eps): smaller values are raised to it,
#: with SciPy's warning.
RTOL_FLOOR = 100 * np.finfo(float).eps


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


def real_number(value, name):
    """``value`` as a float: anything ``float()`` takes but a bool or a string (TypeError
    naming ``name``); the range is the caller's to check."""
    if isinstance(value, (bool, np.bool_, str, bytes)):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__}")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__}") from None


#: No step limit (SciPy has none): the largest count the Fortran counters hold.
NO_STEP_LIMIT = 2**31 - 1


def step_limit(max_steps):
    """``max_steps`` as an int (None: :data:`NO_STEP_LIMIT`); a positive integer below
    2**31, else TypeError/ValueError naming ``max_steps``."""
    if max_steps is None:
        return NO_STEP_LIMIT
    if isinstance(max_steps, (bool, np.bool_)) or not isinstance(max_steps, numbers.Integral):
        raise TypeError("max_steps must be None or an integer")
    if not 1 <= max_steps <= NO_STEP_LIMIT:
        raise ValueError("max_steps must be positive (and below 2**31)")
    return int(max_steps)


def tolerance(value, name, n, stacklevel=3, warn=True):
    """A tolerance as a contiguous float array of shape (n,), checked (non-negative,
    finite; a scalar or one value per component). ``rtol`` below 100 eps is raised to it
    with SciPy's UserWarning (``stacklevel``: the user's call; ``warn=False``: a caller
    that gave the warning already, without touching the global warning filters)."""
    if type(value) is float or type(value) is int or type(value) is np.float64:
        # the common cases: a Python number, or a NumPy double (np.logspace's values)
        v = float(value)
        if not v >= 0:
            raise ValueError(f"{name} must be non-negative")
        if v == math.inf:
            raise ValueError(f"{name} must be finite")
        if warn and name == "rtol" and v < RTOL_FLOOR:
            _warn_rtol(stacklevel + 1)
        arr = np.empty(n)
        arr.fill(v)           # (np.full costs three times as much on small arrays)
        return arr
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
    if warn and name == "rtol" and (arr < RTOL_FLOOR).any():
        _warn_rtol(stacklevel + 1)
    return np.ascontiguousarray(arr)


def time_span(t_span):
    """(t0, tf) of ``t_span`` as floats (a sequence of two real numbers; messages name
    ``t_span``)."""
    try:
        if len(t_span) != 2:
            raise ValueError("t_span must have two elements (t0, tf)")
    except TypeError:
        raise TypeError("t_span must be a sequence (t0, tf)") from None
    return real_scalar(t_span[0], "t_span[0]"), real_scalar(t_span[1], "t_span[1]")


def time_points(t_eval, t0, tf):
    """``t_eval`` as a float array, checked: real, one-dimensional, finite, inside
    [t0, tf] and strictly monotonic in the direction of integration (SciPy's rules;
    messages name ``t_eval``)."""
    try:
        t_ev = np.asarray(t_eval)
        if t_ev.dtype.kind not in "biuf":
            raise TypeError
        t_ev = np.array(t_ev, dtype=float)
    except (TypeError, ValueError):
        raise TypeError("t_eval must be an array of real numbers") from None
    if t_ev.ndim != 1:
        raise ValueError("t_eval must be 1-dimensional")
    if not np.all(np.isfinite(t_ev)):
        raise ValueError("t_eval contains NaN or Inf")
    lo, hi = min(t0, tf), max(t0, tf)
    if np.any(t_ev < lo) or np.any(t_ev > hi):
        raise ValueError("values in t_eval are not within t_span")
    d = np.diff(t_ev)
    if (tf >= t0 and np.any(d <= 0)) or (tf < t0 and np.any(d >= 0)):
        raise ValueError("values in t_eval are not properly sorted (strictly monotonic in "
                         "the direction of integration, no repeated values)")
    return t_ev


def positive_finite(value, name, allow_inf=False):
    """A real scalar that is positive and finite (or +inf with ``allow_inf``); ValueError
    naming `name` otherwise."""
    v = real_scalar(value, name)
    if math.isnan(v) or not v > 0 or (v == math.inf and not allow_inf):
        raise ValueError(f"{name} must be a positive{'' if allow_inf else ' finite'} "
                         f"number, got {v}")
    return v


def step_controls(rtol, atol, n, first_step, t0, tf):
    """The tolerances as arrays of shape (n,) (:func:`tolerance`, warnings pointing at the
    caller's caller) and the first step (0.0 for None, else a positive finite number at
    most the length of [t0, tf] when that is not zero)."""
    rtol_v = tolerance(rtol, "rtol", n, stacklevel=4)
    atol_v = tolerance(atol, "atol", n, stacklevel=4)
    if first_step is None:
        return rtol_v, atol_v, 0.0
    h0 = positive_finite(first_step, "first_step")
    if h0 > abs(tf - t0) and tf != t0:
        raise ValueError("first_step exceeds the length of t_span")
    return rtol_v, atol_v, h0


def _warn_rtol(stacklevel):
    # SciPy's warning (validate_tol); the solvers raise rtol to the floor themselves
    warnings.warn("At least one element of `rtol` is too small. Setting `rtol = "
                  f"np.maximum(rtol, {RTOL_FLOOR})`.", UserWarning, stacklevel=stacklevel)


_TERMINAL = ("The `terminal` attribute of each event must be a boolean or positive "
             "integer")


def event_settings(events):
    """(function, terminal count (0: not terminal), direction, resolution) per event,
    SciPy's rules: ``terminal`` is a bool or a positive integer (stop at that occurrence);
    ``resolution`` (conmech's: None or 0, SciPy's rule; else a positive time) the largest
    spacing of the event's samples inside each step."""
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
                raise ValueError(f"{_TERMINAL} (a count of occurrences): events[{i}]."
                                 f"terminal is {term!r}")
            count = int(tv)
        else:
            raise ValueError(f"{_TERMINAL} (a count of occurrences): events[{i}].terminal "
                             f"is {term!r}")
        direction = getattr(e, "direction", 0)
        try:
            direction = float(direction)
        except (TypeError, ValueError):
            raise ValueError(f"events[{i}].direction must be a number") from None
        if math.isnan(direction):
            raise ValueError(f"events[{i}].direction must be a number")
        settings.append((e, count, int(np.sign(direction)),
                         _resolution(getattr(e, "resolution", None), i)))
    return settings


def _resolution(value, i):
    """An event's ``resolution``: None or 0 (the step's ends only, SciPy's rule), else a
    positive finite time."""
    if value is None:
        return 0.0
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise TypeError(f"events[{i}].resolution must be None or a positive number (a "
                        f"time), got {type(value).__name__}")
    r = float(value)
    if not (r >= 0 and math.isfinite(r)):
        raise ValueError(f"events[{i}].resolution must be None or a positive finite number "
                         f"(a time), got {value!r}")
    return r


def _all_finite(y):
    """Whether every entry of the float or complex array y is finite: on a short array by
    the Python scalars (a tenth of the cost of NumPy's isfinite and all on a few
    entries), else by NumPy."""
    if y.size <= 32:
        return all(map(cmath.isfinite, y.tolist()))
    return bool(np.isfinite(y).all())


def initial_state(y0, fun, builtin, allow_complex=False, allow_empty=False):
    """y0 as a 1-dimensional float array (complex128 if allow_complex and y0 is
    complex), checked: real unless allowed, not empty unless allowed, finite (SciPy's
    message), and of the system's dimension when ``fun`` is a built-in system."""
    y0_in = np.asarray(y0)
    if y0_in.dtype.kind == "c" and not allow_complex:
        raise TypeError("y0 must be real: complex states are not supported here (split "
                        "them into real and imaginary parts)")
    try:
        y = np.array(y0_in, dtype=complex if y0_in.dtype.kind == "c" else float)
    except (TypeError, ValueError):
        raise TypeError("y0 must be an array of real (or complex) numbers") from None
    if y.ndim != 1:
        raise ValueError(f"y0 must be 1-dimensional, got shape {y.shape}")
    if y.size == 0 and not allow_empty:
        raise ValueError("y0 must not be empty")
    if not _all_finite(y):
        raise ValueError("All components of the initial state `y0` must be finite.")
    if builtin and y.size != fun.dimension:
        raise ValueError(f"y0 must have shape ({fun.dimension},) for the system "
                         f"'{fun.name}', got {y.shape}")
    return y
