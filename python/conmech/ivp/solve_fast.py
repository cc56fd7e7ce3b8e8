"""The fast entry of :func:`conmech.solve_ivp` for its most frequent calls: a built-in or
compiled system (with method TAYLOR, a generalized symbolic system's first-order view, as
solve_ivp runs it), a method named by a string, float tolerances, a span and a state of
plain floats, optionally ``t_eval`` (a list, tuple or float array of times), ``first_step``,
``max_step`` and ``max_steps``, and none of the options that call back into Python (events,
dense output, a Jacobian, args). Such a call is checked here with the cheapest tests of the
same rules (type tests on Python scalars and lists, no NumPy conversion to find a type)
and goes to the one-call native path with arguments packed once per system, method and
tolerances (the step options and the output times are written into a copy of them), or,
for a small system, to one run of the system and stepper kept with them (_Kept); any
input outside these kinds, or one that breaks a rule, returns None and the full checks of
solve_ivp run, with their messages. The result is the one the full path gives (the same
run with the same numbers)."""
import math
import weakref

import numpy as np

from .. import _conmech
from .._core.checks import NO_STEP_LIMIT, RTOL_FLOOR, _warn_rtol
from .._core.status import BAD_INPUT
from .methods import BY_NAME, RK45_SCIPY
from .native_path import _PAD, prepare, run as run_native, run_kept, scipy_points, \
    with_options
from .taylor_generalized import first_order_view, name_the_mass_matrix

__all__ = ["fast_solve", "fast_method_code"]

_HUGE = float(np.finfo(float).max)
_INF = math.inf
_isfinite = math.isfinite      # a global lookup per call instead of an attribute's
# method string (as given) -> code, for the methods the fast path takes: an adaptive step
# (the fixed-step ones need first_step) on a first-order system. Bounded: only names the
# table knows get in, in the spellings users typed.
_CODES = {}
# (value, n) -> read-only tolerance array of that value (the flat call reads it only)
_TOLERANCES = {}


def fast_method_code(method):
    """The method code of the string ``method`` when the fast path takes it, else 0."""
    code = _CODES.get(method)
    if code is not None:
        return code
    upper = method.upper()
    m = BY_NAME.get(upper)
    if m is None or m.fixed_step or m.constrained_only:
        return 0
    code = RK45_SCIPY if upper == "RK45" else m.code
    if len(_CODES) < 256:
        _CODES[method] = code
    return code


def _tolerance(v, n):
    arr = _TOLERANCES.get((v, n))
    if arr is None:
        arr = np.empty(n)
        arr.fill(v)
        arr.flags.writeable = False
        if len(_TOLERANCES) >= 64:
            _TOLERANCES.clear()
        _TOLERANCES[(v, n)] = arr
    return arr


def _state(y0, n):
    """y0 itself when it is a list or tuple of n finite floats (or ints), or a 1-D
    float64 array of n finite entries (the flat call reads it as a float64 array); else
    None."""
    if type(y0) is list or type(y0) is tuple:
        if len(y0) != n:
            return None
        for v in y0:
            if not ((isinstance(v, float) or type(v) is int) and _isfinite(v)):
                return None
        return y0
    if type(y0) is np.ndarray and y0.dtype == np.float64 and y0.shape == (n,):
        if n <= 32:
            if not all(map(math.isfinite, y0.tolist())):
                return None
        elif not np.isfinite(y0).all():
            return None
        return y0
    return None


def fast_solve(fun, t_span, y0, method, rtol, atol, taylor_code, taylor_system,
               t_eval=None, first_step=None, max_step=math.inf, max_steps=None):
    """The result of solve_ivp(fun, t_span, y0, method, t_eval, rtol=rtol, atol=atol,
    first_step=first_step, max_step=max_step, max_steps=max_steps) for a NativeSystem
    ``fun``, float ``rtol``/``atol`` and a string ``method``, when every input is of a
    plain kind and valid; None otherwise (the caller runs the full checks).
    ``taylor_system(fun, rtol, atol)`` gives the system method TAYLOR runs (its
    recurrences written out for the tolerances' order), ``taylor_code`` that method's
    code. The packed arguments of the flat call are kept per system, method and
    tolerances (the last _KEEP), so that a repeated call checks only the span, the state
    and the options it gives."""
    if type(t_span) is tuple or type(t_span) is list:
        if len(t_span) != 2:
            return None
        t0, tf = t_span
        if not ((type(t0) is float or type(t0) is int) and (type(tf) is float or
                                                              type(tf) is int)):
            return None
        if type(t0) is not float or type(tf) is not float:
            t0, tf = float(t0), float(tf)
        if not (_isfinite(t0) and _isfinite(tf)):
            return None
    else:
        return None
    key = (id(fun), method, rtol, atol)
    entry = _PREPARED.get(key)
    # entry = (fun, prep, kept): prep the packed arguments, for the system it runs
    # (prep[0]: fun, or fun with its Taylor recurrences written out, sharing fun's
    # parameter array) with the arrays it was packed for (prep[1], prep[2]); kept its
    # _Kept run (or None). fun given a new parameter array is packed again.
    if entry is None or entry[0] is not fun or entry[1][1] is not fun.params or \
            entry[1][2] is not entry[1][0].spec:
        if _state(y0, fun.dimension) is None:
            return None
        prep = _prepare(fun, method, rtol, atol, taylor_code, taylor_system)
        if prep is None:
            return None
        if len(_PREPARED) >= _KEEP:       # systems made and dropped in a loop
            _PREPARED.clear()
        kept = _Kept.open(prep)
        _PREPARED[key] = (fun, prep, kept)
    else:
        prep, kept = entry[1], entry[2]
        if _state(y0, prep[5]) is None:
            return None
    if t_eval is None and first_step is None and max_steps is None and max_step == _INF:
        if rtol < RTOL_FLOOR:
            _warn_rtol(4)       # SciPy's warning, at the user's call (Fortran raises rtol)
        if kept is not None:
            res = run_kept(kept.handle, prep, t0, tf, y0)
        else:
            res = run_native(prep, t0, tf, y0)
        if not res["success"] and prep[0] is not fun:
            res = name_the_mass_matrix(fun, res)    # (a generalized system's view ran)
        return res
    steps = _step_options(t0, tf, first_step, max_step, max_steps)
    if steps is None:
        return None
    if t_eval is not None:
        t_eval = _time_points(t_eval, t0, tf)
        if t_eval is None:
            return None
    if rtol < RTOL_FLOOR:
        _warn_rtol(4)
    cap = max(len(t_eval), 2) if t_eval is not None else 0
    if kept is not None:
        res = run_kept(kept.handle, prep, t0, tf, y0, steps, t_eval, cap)
    else:
        res = run_native(with_options(prep, *steps, t_eval), t0, tf, y0, cap)
    if not res["success"] and prep[0] is not fun:
        res = name_the_mass_matrix(fun, res)
    return scipy_points(res, t_eval is not None, len(t_eval) if t_eval is not None else 0)


def _step_options(t0, tf, first_step, max_step, max_steps):
    """(first step or 0.0, largest step, step limit) when first_step (None or a positive
    finite number at most the span's length), max_step (a positive number, inf allowed)
    and max_steps (None or an int in [1, 2**31 - 1]) are plain and valid; else None."""
    if first_step is None:
        h0 = 0.0
    elif type(first_step) is float or type(first_step) is int:
        h0 = float(first_step)
        if not (0.0 < h0 < math.inf and (h0 <= abs(tf - t0) or tf == t0)):
            return None
    else:
        return None
    if not ((type(max_step) is float or type(max_step) is int) and max_step > 0):
        return None     # NaN fails the comparison
    if max_steps is None:
        limit = NO_STEP_LIMIT
    elif type(max_steps) is int and 1 <= max_steps <= NO_STEP_LIMIT:
        limit = max_steps
    else:
        return None
    return h0, min(float(max_step), _HUGE), limit


def _time_points(t_eval, t0, tf):
    """t_eval itself when it is a list or tuple of floats (or ints), or a 1-D float64
    array, of times inside [t0, tf] strictly monotonic in the direction of integration;
    else None."""
    if type(t_eval) is list or type(t_eval) is tuple:
        for v in t_eval:
            if not (type(v) is float or type(v) is int):
                return None
        values = t_eval
    elif type(t_eval) is np.ndarray and t_eval.dtype == np.float64 and t_eval.ndim == 1:
        if t_eval.size > 32:
            lo, hi = min(t0, tf), max(t0, tf)
            d = np.diff(t_eval)
            ok = bool(t_eval.min() >= lo and t_eval.max() <= hi and
                      ((d > 0).all() if tf >= t0 else (d < 0).all()))
            return t_eval if ok else None       # NaN fails min/max's comparisons
        values = t_eval.tolist()
    else:
        return None
    lo, hi = min(t0, tf), max(t0, tf)
    last = None
    for v in values:
        if not lo <= v <= hi:                   # NaN and Inf fail it too
            return None
        if last is not None and not (v > last if tf >= t0 else v < last):
            return None
        last = v
    return t_eval


def _prepare(fun, method, rtol, atol, taylor_code, taylor_system):
    """The packed arguments of native_path.prepare for the fast path's call, or
    None when the method or the tolerances are not of its kinds (the full checks run)."""
    code = fast_method_code(method)
    if not code:
        return None
    if not (0.0 <= atol < math.inf and 0.0 <= rtol < math.inf):
        return None
    n = fun.dimension
    run_fun = fun
    if code == taylor_code:
        if getattr(fun, "taylor", None):        # as solve_ivp: the written-out recurrences
            run_fun = taylor_system(fun, rtol, atol)    # (cached per system and order)
        elif getattr(fun, "kind", None) == "generalized":
            try:                                # as solve_ivp: its first-order view
                view = first_order_view(fun)
            except ValueError:
                return None                     # no recurrences: the full path says so
            if view is fun:
                return None
            run_fun = taylor_system(view, rtol, atol)
    return prepare(run_fun, code, _tolerance(rtol, n), _tolerance(atol, n), 0.0, _HUGE,
                   NO_STEP_LIMIT)


class _Kept:
    """The system and its stepper made once in Fortran memory (a kept propagation, as
    conmech.Propagator's) for the calls of solve_ivp with the same system, method and
    tolerances: each call is then one run of the kept stepper with the call's step
    options and output times (flat_propagation_solve: the points, counts and bits of
    flat_solve_packed) without making the system and the stepper again and freeing them,
    nor packing the options into copies of the packed arrays. Kept for systems of at most
    _KEPT_SIZE equations (the stepper's arrays, a Jacobian's n x n among them, live as
    long as the entry); the memory is freed with the entry."""

    __slots__ = ("handle", "__weakref__")

    @classmethod
    def open(cls, prep):
        """The kept run of the packed arguments prep, or None (a large system, or one the
        flat layer refuses: the packed route then runs and reports it)."""
        fun, params, spec, ipack, rpar, n, _ = prep
        if n > _KEPT_SIZE:
            return None
        iout = np.zeros(40, np.int64)
        _conmech.flat_propagation_new(ipack, params if params.size else _PAD, spec, rpar, n,
                                      iout)
        if iout[6] == BAD_INPUT or not iout[7]:
            return None
        kept = cls()
        kept.handle = int(iout[7])
        weakref.finalize(kept, _conmech.flat_propagation_free, kept.handle)
        return kept


# (id(system), method, rtol, atol) -> (system, the packed arguments, their _Kept run or
# None); the system is kept with them, so its id stays its own while the entry lives
_PREPARED = {}
_KEEP = 256
_KEPT_SIZE = 64
