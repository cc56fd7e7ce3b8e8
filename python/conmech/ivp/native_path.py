"""The short path of :func:`conmech.solve_ivp`: a built-in or compiled system without events,
dense output or a Python Jacobian is integrated by one call of the flat routine
flat_solve_packed, with no call-back into Python. Its fixed arguments (the method, the
tolerances, the step limits: everything but the span and the state) are packed once per
system, method and tolerances (:func:`prepare`, kept on the system by the fast entry), the
points come back in an array sized here, and a run with more points than that leaves them
in Fortran memory for one more call (flat_solve_take) rather than calling back."""
import numpy as np

from .. import _conmech
from .._core import fastcall
from .._core.callback import message_text
from .._core.checks import NO_STEP_LIMIT
from .._core.native import _NO_SPEC
from .._core.status import BAD_INPUT
from .result import _MESSAGES, OdeResult

_PAD = np.zeros(1)
_PAD.flags.writeable = False
# the room for the points of a run returned by the one call (numbers of t and y: 8 kB);
# a run with more points hands them over by flat_solve_take
_OUT_DOUBLES = 1024
_INT64 = np.int64
# module-level names for the per-call path of run (a global lookup, not an attribute)
_empty = np.empty
_solve_packed = _conmech.flat_solve_packed
_solve_kept = fastcall.solve     # (flat_propagation_solve, without f2py's wrapper)
# the step options a packed call is made with (prepare's by the fast entry): the method's
# first step, no largest step, no step limit
_NO_OPTIONS = (0.0, float(np.finfo(float).max), NO_STEP_LIMIT)
# the result's keys in SciPy's order with conmech's extras last, and the fields of a run
# without events or dense output that are always the same
_TEMPLATE = dict(t=None, y=None, sol=None, t_events=None, y_events=None, nfev=0, njev=0,
                 nlu=0, status=0, message=_MESSAGES[0], success=True, naccept=0, nreject=0)


def prepare(fun, code, rtol, atol, h0, hmax, max_steps, t_ev=None):
    """The packed fixed arguments of flat_solve_packed for the system ``fun`` (checked
    arguments): (fun, params, spec, ipack, rpar, n, name as bytes), where params and spec
    are the arrays they were packed for (a system given new ones is packed again; they
    are passed as they are, so that values changed in place are read),
    ipack = [np, nspec, method, max_steps, neval, with t_eval, len(name), the name's
    bytes], rpar = [first_step, max_step, rtol, atol, t_eval or one unused number]."""
    params, spec = fun.params, fun.spec
    n = fun.dimension
    name = fun.name.encode("ascii", "replace")
    neval = 0 if t_ev is None else t_ev.size
    ipack = np.concatenate([[params.size, spec.size if spec is not _NO_SPEC else 0, code,
                             max_steps, neval, t_ev is not None, len(name)],
                            np.frombuffer(name, dtype=np.uint8)]).astype(_INT64)
    rpar = np.concatenate([[h0, hmax], np.broadcast_to(rtol, (n,)),
                           np.broadcast_to(atol, (n,)), t_ev if neval else _PAD])
    ipack.flags.writeable = rpar.flags.writeable = False
    return fun, params, spec, ipack, rpar, n, name


def with_options(prep, h0, hmax, max_steps, t_ev=None):
    """The packed arguments ``prep`` (:func:`prepare`, packed without step options or
    output times) with the first step h0 (0.0: the method's choice), the largest step
    hmax, the step limit and the output times t_ev (a sequence of floats, or None: every
    step): copies of its two packs, the rest shared."""
    fun, params, spec, ipack, rpar, n, name = prep
    ipack = ipack.copy()
    ipack[3] = max_steps
    ipack[4] = 0 if t_ev is None else len(t_ev)
    ipack[5] = t_ev is not None
    rpar = np.concatenate([[h0, hmax], rpar[2:2 + 2*n], t_ev if ipack[4] else _PAD])
    return fun, params, spec, ipack, rpar, n, name


def run(prep, t0, tf, y0, cap=0):
    """The OdeResult of one run of flat_solve_packed with the packed arguments ``prep``
    (:func:`prepare`) from ``y0`` (n finite numbers: an array, list or tuple) over
    [t0, tf]; room for ``cap`` points in one call (0: _OUT_DOUBLES numbers; 2 for a
    zero-length span)."""
    fun, params, spec, ipack, rpar, n, name = prep
    if not cap:
        cap = 2 if tf == t0 else max(_OUT_DOUBLES // (n + 1), 2)
    out = _empty(cap*(n + 1))
    iout = _empty(40, _INT64)       # 8 numbers, then the message's 256 bytes
    _solve_packed(ipack, params if params.size else _PAD, spec, rpar, t0, tf, y0, out, iout)
    # the frequent outcome (the points fit, the run was not refused): no tests of the
    # rare cases
    nt, nfev, njev, nlu, naccept, nreject, info, _ = iout[:8].tolist()
    if nt < 0 or info:
        return _result(out, iout, n)
    return _points(out, n, nt, nfev, njev, nlu, naccept, nreject)


def run_kept(handle, prep, t0, tf, y0, steps=None, t_ev=None, cap=0):
    """:func:`run` of the packed arguments ``prep`` (packed without step options or output
    times) by the kept propagation at ``handle`` made from them, with the step options
    ``steps`` = (first step or 0.0, largest step, step limit) and the output times t_ev
    (as :func:`with_options`; None: the packed ones, every step): the same result, without
    making the system and its stepper in the call."""
    params, n = prep[1], prep[5]
    if not cap:
        cap = 2 if tf == t0 else max(_OUT_DOUBLES // (n + 1), 2)
    out = _empty(cap*(n + 1))
    iout = _empty(40, _INT64)
    h0, hmax, max_steps = steps or _NO_OPTIONS
    if t_ev is None:
        _solve_kept(handle, params if params.size else _PAD, t0, tf, y0, h0, hmax, max_steps,
                    0, 0, _PAD, out, iout)
    else:
        _solve_kept(handle, params if params.size else _PAD, t0, tf, y0, h0, hmax, max_steps,
                    1, len(t_ev), t_ev if len(t_ev) else _PAD, out, iout)
    nt, nfev, njev, nlu, naccept, nreject, info, _ = iout[:8].tolist()
    if nt < 0 or info:
        return _result(out, iout, n)
    return _points(out, n, nt, nfev, njev, nlu, naccept, nreject)


def _take(out, iout, n, guard=None):
    """(the points' array, nt, counts..., info) of a packed call's outputs: the kept points
    taken when they did not fit; ``guard``'s error (an exception of a Python function)
    raised once they are freed; a refusal raised as ValueError."""
    nt, nfev, njev, nlu, naccept, nreject, info, handle = iout[:8].tolist()
    if nt < 0:
        nt = -nt
        try:
            out = np.empty(nt*(n + 1))
        except BaseException:
            _conmech.flat_solve_take(handle, n, 0, _PAD)     # free the kept points
            raise
        _conmech.flat_solve_take(handle, n, nt, out)
    if guard is not None:
        guard.check()
    if info == BAD_INPUT:
        raise ValueError(message_text(iout[8:]))
    return out, nt, nfev, njev, nlu, naccept, nreject, info


def _points(out, n, nt, nfev, njev, nlu, naccept, nreject):
    """The OdeResult of a successful run's nt points in out and its counts."""
    m = nt*(n + 1)
    # the points as an (n + 1, nt) array: its first row the times, the others y (views
    # of one array the size of the points: the result does not hold on to the room)
    points = (out if m == out.size else out[:m].copy()).reshape(n + 1, nt)
    res = OdeResult(_TEMPLATE)
    res["t"] = points[0]
    res["y"] = points[1:]
    if nfev:
        res["nfev"] = nfev
    if njev or nlu:
        res["njev"], res["nlu"] = njev, nlu
    if naccept or nreject:
        res["naccept"], res["nreject"] = naccept, nreject
    return res


def _result(out, iout, n, guard=None):
    """The OdeResult of a packed call's outputs (:func:`_take`)."""
    nt, nfev, njev, nlu, naccept, nreject, info, _ = iout[:8].tolist()
    if nt < 0 or guard is not None or info == BAD_INPUT:
        out, nt, nfev, njev, nlu, naccept, nreject, info = _take(out, iout, n, guard)
    res = _points(out, n, nt, nfev, njev, nlu, naccept, nreject)
    if info:
        if info > 0:
            res["status"], res["message"] = info, _MESSAGES.get(info) or message_text(
                iout[8:])
        else:
            res["status"], res["message"] = -1, message_text(iout[8:])
            res["success"] = False
    return res


def solve_callable(rhs, guard, n, t0, tf, y0, t_ev, with_t_eval, code, rtol, atol, h0,
                   hmax, max_steps):
    """solve_ivp of a Python right-hand side without events, dense output or a Jacobian
    (checked arguments; ``rhs`` the guarded call-back fun(t, y, dydt, n), ``guard`` its
    Guard): one call of flat_solve_rhs_packed, whose only call-back is ``rhs``."""
    neval = t_ev.size if with_t_eval else 0
    ipar = np.array([0, 0, code, max_steps, neval, with_t_eval], dtype=np.intc)
    rpar = np.concatenate([[h0, hmax], rtol, atol, t_ev if neval else _PAD])
    cap = max(t_ev.size, 2) if with_t_eval else 2 if tf == t0 else max(
        _OUT_DOUBLES // (n + 1), 2)
    out = np.empty(cap*(n + 1))
    iout = np.zeros(40, dtype=_INT64)
    _conmech.flat_solve_rhs_packed(rhs, ipar, rpar, t0, tf, y0, out, iout)
    return scipy_points(_result(out, iout, n, guard), with_t_eval, neval)


def scipy_points(res, with_t_eval, neval):
    """res with SciPy's empty lists as t and y when a run with t_eval (neval times)
    reached none of them, or t_eval is empty (the flat call's neval = 0 stores every
    step)."""
    if with_t_eval and (res.t.size == 0 or not neval):
        res.t, res.y = [], []
    return res


def solve_native(fun, t0, tf, y0, t_ev, with_t_eval, code, rtol, atol, h0, hmax,
                 max_steps):
    """solve_ivp of a built-in or compiled system without events or dense output (checked
    arguments): the result of :func:`_solve` for such a run, from one call of
    flat_solve_packed (points returned in an array of t_eval's length, else room for
    _OUT_DOUBLES numbers, and handed over by flat_solve_take when a run has more)."""
    prep = prepare(fun, code, rtol, atol, h0, hmax, max_steps,
                   t_ev if with_t_eval else None)
    res = run(prep, t0, tf, y0, max(t_ev.size, 2) if with_t_eval else 0)
    return scipy_points(res, with_t_eval, t_ev.size)
