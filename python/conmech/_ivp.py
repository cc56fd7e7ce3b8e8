"""solve_ivp: SciPy's interface on conmech's Fortran Runge-Kutta integrators."""
import math
import numbers

import numpy as np

from . import _conmech
from .systems import BuiltinSystem
from . import _implicit

__all__ = ["solve_ivp", "OdeResult", "DenseOutput"]

_METHODS = ("RK4", "DOPRI5", "RK45", "DOP853", "VERNER98", "VERN9", "Radau", "GAUSS4",
            "GAUSS6")
# codes of conmech_ode_solver (METHOD_RK4 = 1, ...); checked against the Fortran
# method_from_name by the tests (flat_method_code)
_METHOD_CODES = {"RK4": 1, "DOPRI5": 2, "RK45": 2, "DOP853": 3, "VERNER98": 4, "VERN9": 4,
                 **_implicit.IMPLICIT_CODES}
_MESSAGES = {
    0: "The solver successfully reached the end of the integration interval.",
    1: "A termination event occurred.",
}
_CM_BAD_INPUT = -4
_HUGE = np.finfo(float).max
# placeholders for f2py, which cannot pass empty arrays (read only, shared)
_PAD = np.zeros(1)
_PADI = np.zeros(1, dtype=np.intc)
_PAD.flags.writeable = False
_PADI.flags.writeable = False


class OdeResult(dict):
    """Result of :func:`solve_ivp`: a dict whose keys are also attributes (as SciPy's).

    Keys: t, y, sol, t_events, y_events, nfev, njev, nlu, status, message, success,
    and conmech's extras naccept, nreject.
    """

    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError as exc:
            raise AttributeError(name) from exc

    __setattr__ = dict.__setitem__
    __delattr__ = dict.__delitem__

    def __repr__(self):
        keys = ("message", "success", "status", "t", "y", "sol", "t_events", "y_events",
                "nfev", "njev", "nlu")
        width = max(map(len, keys)) + 1
        lines = []
        for k in keys:
            v = self.get(k)
            if isinstance(v, np.ndarray) and v.size > 6:
                v = f"array of shape {v.shape}"
            lines.append(f"{k.rjust(width)}: {v!r}" if not isinstance(v, str) else
                         f"{k.rjust(width)}: {v}")
        return "\n".join(lines)

    def __dir__(self):
        return list(self.keys())


class DenseOutput:
    """Continuous solution of an integration: piecewise polynomials, one per step.

    ``sol(t)`` accepts a scalar (returns shape (n,)) or an array of times (returns shape
    (n, len(t))); outside [t_min, t_max] the end polynomials are extrapolated, as SciPy's
    OdeSolution does. On each step [ts, ts + h], with x = (t - ts) / h, the polynomial is
    in Hairer's form y0 + x (F1 + (1 - x)(F2 + x (F3 + (1 - x)(F4 + ...)))) (form 1:
    RK4, DOPRI5, DOP853) or in the power basis y0 + x F1 + x^2 F2 + ... (form 2:
    VERNER98), as in conmech_ode_solver's dense_solution.
    """

    HAIRER = 1
    POWER = 2

    def __init__(self, ts, hs, coef, t_min, t_max, form=HAIRER):
        if form not in (self.HAIRER, self.POWER):
            raise ValueError(f"unknown dense output form {form}")
        self.form = form
        self.t_start = np.ascontiguousarray(ts, dtype=float)   # step starts
        self.h = np.ascontiguousarray(hs, dtype=float)          # signed step lengths
        self.coef = np.ascontiguousarray(coef, dtype=float)     # (n, nf + 1, nseg)
        self.t_min = float(min(t_min, t_max))
        self.t_max = float(max(t_min, t_max))
        self.n_segments = self.t_start.size
        self.ts = np.append(self.t_start, self.t_start[-1] + self.h[-1]) \
            if self.n_segments else np.array([t_min])
        self._ascending = self.n_segments == 0 or self.h[0] > 0

    def __call__(self, t):
        t = np.asarray(t, dtype=float)
        scalar = t.ndim == 0
        tt = np.atleast_1d(t).ravel()
        if self.n_segments == 0:
            raise ValueError("the dense output is empty (no step was taken)")
        if self._ascending:
            idx = np.searchsorted(self.t_start, tt, side="right") - 1
        else:
            idx = np.searchsorted(-self.t_start, -tt, side="right") - 1
        np.clip(idx, 0, self.n_segments - 1, out=idx)
        x = (tt - self.t_start[idx]) / self.h[idx]
        c = self.coef[:, :, idx]                      # (n, nf + 1, m)
        nf = c.shape[1] - 1
        x1 = 1.0 - x
        y = c[:, nf, :].copy()
        for j in range(nf - 1, 0, -1):
            if self.form == self.POWER:
                y *= x
            else:
                y *= x1 if j % 2 == 1 else x
            y += c[:, j, :]
        y *= x
        y += c[:, 0, :]
        return y[:, 0] if scalar else y


def _real_scalar(value, name):
    if type(value) is float or type(value) is int:
        return float(value)
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Real, np.ndarray)):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__}")
    arr = np.asarray(value, dtype=float)
    if arr.ndim != 0:
        raise ValueError(f"{name} must be a scalar")
    return float(arr)


def _tolerance(value, name, n):
    if type(value) is float or type(value) is int:   # fast path for the common case
        v = float(value)
        if not v >= 0:
            raise ValueError(f"{name} must be non-negative")
        if v == math.inf:
            raise ValueError(f"{name} must be finite")
        return np.full(n, v)
    try:
        arr = np.asarray(value, dtype=float)
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


def _event_settings(events):
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
        term = getattr(e, "terminal", False)
        if isinstance(term, (bool, np.bool_)):
            term = bool(term)
        elif isinstance(term, numbers.Integral) and term in (0, 1):
            term = bool(term)
        elif isinstance(term, numbers.Integral) and term > 1:
            raise ValueError(f"events[{i}].terminal: a count of occurrences before "
                             f"termination ({term}) is not supported; use True or False")
        else:
            raise ValueError(f"events[{i}].terminal must be a bool")
        direction = getattr(e, "direction", 0)
        try:
            direction = float(direction)
        except (TypeError, ValueError):
            raise ValueError(f"events[{i}].direction must be a number") from None
        if math.isnan(direction):
            raise ValueError(f"events[{i}].direction must be a number")
        settings.append((e, term, int(np.sign(direction))))
    return settings


def solve_ivp(fun, t_span, y0, method="DOP853", t_eval=None, dense_output=False,
              events=None, vectorized=False, args=None, *, rtol=1e-3, atol=1e-6,
              first_step=None, max_step=np.inf, max_steps=100000, jac=None):
    """Solve an initial value problem y' = fun(t, y), y(t0) = y0 (SciPy's interface).

    Parameters
    ----------
    fun : callable or conmech.systems.BuiltinSystem
        ``fun(t, y, *args) -> dydt`` (array of shape (n,)), called from Fortran through
        an f2py callback; or a compiled built-in system such as
        ``conmech.systems.kepler(mu=1.0)``, integrated with no Python in the loop.
    t_span : 2-sequence of float
        (t0, tf); tf < t0 integrates backwards.
    y0 : array_like, shape (n,)
        Initial state.
    method : {"DOP853", "DOPRI5" (alias "RK45"), "VERNER98" (alias "Vern9"), "RK4",
              "Radau" (alias "RADAU5"), "GAUSS4", "GAUSS6"}
        DOP853: Dormand-Prince 8(5,3), dense output of order 7. DOPRI5: Dormand-Prince
        5(4), dense output of order 4. VERNER98: Verner's 9(8) pair, dense output of
        order 8, for tight tolerances. RK4: classical fixed-step RK4, step ``first_step``.
        Radau: Radau IIA of order 5 for stiff problems (Hairer's RADAU5: simplified
        Newton with one real and one complex LU, dense output of order 3, events; counts
        njev and nlu). GAUSS4 / GAUSS6: Gauss-Legendre collocation with 2 / 3 stages
        (orders 4 / 6), symplectic, fixed step ``first_step``, for long runs of
        conservative systems. Case-insensitive.
    t_eval : array_like or None
        Times at which to store the solution (sorted in the direction of integration,
        inside t_span), from the dense output. None: every accepted step.
    dense_output : bool
        Return ``sol``, a callable continuous solution.
    events : callable or list of callables
        ``event(t, y, *args) -> float``; zero crossings are located on the dense output.
        Optional attributes ``terminal`` (bool) and ``direction`` (>0 rising, <0 falling,
        0 both), as in SciPy.
    vectorized : bool
        Accepted for SciPy compatibility and without effect: explicit Runge-Kutta methods
        call ``fun`` with one state of shape (n,) at a time, as SciPy's do.
    args : tuple or None
        Extra arguments passed to ``fun`` and to every event function.
    rtol, atol : float or array_like of shape (n,)
        Relative and absolute tolerances (rtol is raised to 100 eps at least, as SciPy).
    first_step : float or None
        Initial step (None: Hairer's heuristic). Required by RK4 (its fixed step).
    max_step : float
        Largest step size (default no limit).
    max_steps : int
        Attempted steps before giving up (status -1).
    jac : callable, array_like or None
        Used by method="Radau" (the other methods ignore it with a warning, as SciPy's):
        ``jac(t, y, *args) -> (n, n)`` (dense) or a constant matrix; None: forward
        differences (n evaluations of fun per Jacobian).

    Returns
    -------
    OdeResult
        t, y (n, nt), sol (DenseOutput or None), t_events, y_events (lists per event, or
        None), nfev, njev, nlu (Radau; 0 otherwise), status (0 reached the end, 1 terminal
        event, -1 failure), message, success, and the step counts naccept, nreject.

    The positional order of the arguments is SciPy's; rtol, atol, first_step, max_step and
    max_steps (SciPy's ``**options``) are keyword-only.

    Raises
    ------
    TypeError, ValueError
        On bad input; the message names the argument. An exception raised inside ``fun``
        or an event function reaches the caller unchanged.
    """
    # ---------------------------------------------------------------- fun and args
    builtin = isinstance(fun, BuiltinSystem)
    if not builtin and not callable(fun):
        raise TypeError("fun must be callable or a built-in system from conmech.systems, "
                        f"got {type(fun).__name__}")
    if args is not None:
        if isinstance(args, (str, bytes)) or not hasattr(args, "__iter__"):
            raise TypeError("args should be a tuple")
        args = tuple(args)
        if builtin and args:
            raise TypeError("args cannot be used with a built-in system: pass its "
                            "parameters to the factory in conmech.systems")
    else:
        args = ()

    # ---------------------------------------------------------------- method
    if not isinstance(method, str):
        raise TypeError(f"method must be a string, one of {', '.join(_METHODS)}")
    code = _METHOD_CODES.get(method.upper(), 0)
    if code == 0:
        raise ValueError(f"method must be one of {', '.join(_METHODS)}, got {method!r}")

    # ---------------------------------------------------------------- t_span, y0
    try:
        if len(t_span) != 2:
            raise ValueError("t_span must have two elements (t0, tf)")
    except TypeError:
        raise TypeError("t_span must be a sequence (t0, tf)") from None
    t0 = _real_scalar(t_span[0], "t_span[0]")
    tf = _real_scalar(t_span[1], "t_span[1]")
    if not (math.isfinite(t0) and math.isfinite(tf)):
        raise ValueError("t_span must be finite")
    y0_in = np.asarray(y0)
    if y0_in.dtype.kind == "c":
        raise TypeError("y0 must be real: complex states are not supported")
    try:
        y0 = np.array(y0_in, dtype=float)
    except (TypeError, ValueError):
        raise TypeError("y0 must be an array of real numbers") from None
    if y0.ndim != 1:
        raise ValueError(f"y0 must be 1-dimensional, got shape {y0.shape}")
    n = y0.size
    if n == 0:
        raise ValueError("y0 must not be empty")
    if not np.isfinite(y0).all():
        raise ValueError("y0 contains NaN or Inf")
    if builtin and n != fun.dimension:
        raise ValueError(f"y0 must have shape ({fun.dimension},) for the system "
                         f"'{fun.name}', got {y0.shape}")

    # ---------------------------------------------------------------- tolerances, steps
    rtol_v = _tolerance(rtol, "rtol", n)
    atol_v = _tolerance(atol, "atol", n)
    if first_step is None:
        h0 = 0.0
    else:
        h0 = _real_scalar(first_step, "first_step")
        if not (h0 > 0 and math.isfinite(h0)):
            raise ValueError("first_step must be positive")
        if h0 > abs(tf - t0) and tf != t0:
            raise ValueError("first_step exceeds the length of t_span")
    if code in (1, 6, 7) and first_step is None:
        raise ValueError(f"first_step is required by {method} (a fixed-step method): pass "
                         "the step size")
    if jac is not None and code != 5:
        import warnings
        warnings.warn("The following arguments have no effect for a chosen solver: jac.",
                      stacklevel=2)
        jac = None
    hmax = _real_scalar(max_step, "max_step")
    if not hmax > 0:
        raise ValueError("max_step must be positive")
    hmax = min(hmax, _HUGE)
    if isinstance(max_steps, (bool, np.bool_)) or not isinstance(max_steps, numbers.Integral):
        raise TypeError("max_steps must be an integer")
    if not 1 <= max_steps <= 2**31 - 1:
        raise ValueError("max_steps must be positive (and below 2**31)")

    # ---------------------------------------------------------------- t_eval
    if t_eval is None:
        t_ev = _PAD[:0]
    else:
        try:
            t_ev = np.array(t_eval, dtype=float)
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
            raise ValueError("values in t_eval are not properly sorted (strictly "
                             "monotonic in the direction of integration)")

    # ---------------------------------------------------------------- events
    settings = _event_settings(events)
    ne = len(settings)
    ev_funs = [s[0] for s in settings]

    # A Python exception raised in a callback is kept and the callback returns NaN from
    # then on without calling the user's function again: the Fortran solver stops at once
    # on the non-finite values (status "non-finite") and returns normally, freeing its
    # memory, and the exception is raised again here, unchanged. (Letting it go through
    # f2py instead would longjmp over the Fortran frames and leak their arrays.)
    failure = []

    if ne > 0:
        nan_g = [math.nan] * ne

        def events_cb(t, y):
            if failure:
                return nan_g
            yc = y.copy()
            try:
                return [e(t, yc, *args) for e in ev_funs]
            except BaseException as exc:
                failure.append(exc)
                return nan_g
    else:
        def events_cb(t, y):  # never called when ne = 0
            raise RuntimeError("conmech: events callback called without events")

    out = {}

    def store(t, y, ev_t, ev_y, ev_id, ts, hs, coef):
        # the arrays wrap Fortran memory that is freed on return: copy them
        out["t"] = t.copy()
        out["y"] = y.reshape(n, t.size).copy()
        if ne:
            out["ev_t"] = ev_t.copy()
            out["ev_y"] = ev_y.reshape(n, ev_t.size).copy()
            out["ev_id"] = ev_id.copy()
        if dense_output:
            out["ts"] = ts.copy()
            out["hs"] = hs.copy()
            out["coef"] = coef.reshape(n, -1, ts.size).copy()

    # f2py cannot pass empty arrays: t_eval, ev_dir, ev_term get at least one element
    # and their counts neval, ne say how many are used.
    if ne:
        ev_dir = np.array([s[2] for s in settings], dtype=np.intc)
        ev_term = np.array([int(s[1]) for s in settings], dtype=np.intc)
    else:
        ev_dir = ev_term = _PADI
    common = dict(t_span=np.array([t0, tf]), y0=y0, method=code, rtol=rtol_v, atol=atol_v,
                  first_step=h0, max_step=hmax, max_steps=int(max_steps),
                  dense=int(bool(dense_output)), neval=t_ev.size,
                  t_eval=t_ev if t_ev.size else _PAD, ne=ne, ev_dir=ev_dir, ev_term=ev_term)
    probe_calls = 0
    njev = nlu = 0
    if code >= 5:
        rhs = None
        if not builtin:
            f0 = np.asarray(fun(t0, y0.copy(), *args))
            probe_calls = 1
            if f0.size != n or f0.ndim > 1:
                raise ValueError(f"fun must return an array of shape ({n},) like y0, got "
                                 f"shape {f0.shape}")
            nan_y = np.full(n, math.nan)

            def rhs(t, y):
                if failure:
                    return nan_y
                try:
                    return fun(t, y.copy(), *args)
                except BaseException as exc:
                    failure.append(exc)
                    return nan_y
        nfev, njev, nlu, naccept, nreject, form, info, message = _implicit.run(
            builtin, fun, rhs, jac, args, n, events_cb, store, common, failure)
    elif builtin:
        nfev, naccept, nreject, form, info, message = _conmech.flat_solve_builtin(
            *fun._flat_args(), events_cb, store, **common)
    else:
        # One probe call checks the shape of fun's output and gives a clear error.
        f0 = np.asarray(fun(t0, y0.copy(), *args))
        probe_calls = 1
        if f0.size != n or f0.ndim > 1:
            raise ValueError(f"fun must return an array of shape ({n},) like y0, got "
                             f"shape {f0.shape}")
        nan_y = np.full(n, math.nan)
        nan_y.flags.writeable = False

        def rhs(t, y):
            if failure:
                return nan_y
            try:
                return fun(t, y.copy(), *args)
            except BaseException as exc:
                failure.append(exc)
                return nan_y
        nfev, naccept, nreject, form, info, message = _conmech.flat_solve_callback(
            rhs, events_cb, store, **common)
    if failure:
        raise failure[0]

    message = bytes(message).decode("ascii", "replace").strip() \
        if not isinstance(message, str) else message.strip()
    info = int(info)
    if info == _CM_BAD_INPUT:
        raise ValueError(message)
    if info >= 0:
        status = int(info)
        message = _MESSAGES.get(status, message)
    else:
        status = -1
    res = OdeResult(t=out.get("t", np.array([t0])), y=out.get("y", y0[:, None].copy()),
                    sol=None, t_events=None, y_events=None,
                    nfev=int(nfev) + probe_calls, njev=njev, nlu=nlu, status=status,
                    message=message, success=status >= 0, naccept=int(naccept),
                    nreject=int(nreject))
    if ne > 0 and "ev_t" in out:
        ids = out["ev_id"]
        res.t_events = [out["ev_t"][ids == i + 1] for i in range(ne)]
        res.y_events = [out["ev_y"][:, ids == i + 1].T.copy() for i in range(ne)]
    elif ne > 0:
        res.t_events = [np.zeros(0) for _ in range(ne)]
        res.y_events = [np.zeros((0, n)) for _ in range(ne)]
    if dense_output and "ts" in out and out["ts"].size > 0:
        t_last = float(res.t[-1]) if res.t.size else tf
        if t_eval is not None:
            t_last = float(out["ts"][-1] + out["hs"][-1])
            if status == 1 and ne > 0:
                t_last = float(np.max(out["ev_t"]) if tf > t0 else np.min(out["ev_t"]))
        res.sol = DenseOutput(out["ts"], out["hs"], out["coef"], t0, t_last, form=int(form))
    return res
