"""solve_ivp: SciPy's interface on conmech's Fortran integrators (every method of the
method table, through the one driver loop)."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import math

import warnings

import numpy as np

from .. import _conmech
from .._core.callback import Guard, as_result, message_text
from .._core.checks import event_settings as _event_settings, initial_state as _initial_state, \
    step_limit as _step_limit, time_points as _time_points, \
    time_span as _time_span, step_controls as _step_controls, \
    positive_finite as _positive_finite
from .dense import DenseOutput, OdeSolution
from .implicit import is_sparse, sparsity_pattern, start_jacobian
from .methods import METHODS, RK45_SCIPY, method_info
from .stepper import method_code
from .taylor import run_compiled_events, with_fixed_order
from .taylor_generalized import first_order_view, name_the_mass_matrix
from .._core.native import _NO_SPEC, NativeSystem
from .native_path import _OUT_DOUBLES, solve_native as _solve_native, \
    solve_callable as _solve_callable  # noqa: F401 (tests)
from .complex_form import complex_result as _complex_result, real_form as _real_form, \
    real_form_event as _real_form_event
from .empty import solve_empty as _solve_empty
from .solve_fast import fast_solve as _fast_solve
from .result import OdeResult
from .assemble import assemble as _assemble
from .._core.status import BAD_INPUT

__all__ = ["solve_ivp", "OdeResult", "DenseOutput", "OdeSolution"]

# the names solve_ivp accepts: the Fortran table's methods (conmech_ode_methods) but the
# constrained-only ones, with aliases (the Python spelling first: "RK45", "Radau")
_METHOD_CODES = {n.upper(): m.code for m in METHODS.values() if not m.constrained_only
                 for n in (m.name, *m.aliases)}
_METHODS = ("RK45", "Radau") + tuple(n for n in _METHOD_CODES if n not in ("RK45", "RADAU"))
# RK45 is code 12 here (DOPRI5 with SciPy's control, METHOD_RK45_SCIPY), DOPRI5 elsewhere
_RK45_SCIPY = RK45_SCIPY
_TAYLOR = _METHOD_CODES.get("TAYLOR", -1)
_HUGE = np.finfo(float).max
# placeholders for f2py, which cannot pass empty arrays (read only, shared)
_PAD, _PADI, _EMPTY = np.zeros(1), np.zeros(1, dtype=np.intc), np.zeros(0)
_PAD.flags.writeable = _PADI.flags.writeable = _EMPTY.flags.writeable = False
_COMPLEX_REFUSED = ("`y0` is complex, but the chosen solver does not support integration "
                    "in a complex domain.")


_OPTION_NAMES = ("jac", "jac_sparsity", "lband", "uband", "min_step")


def solve_ivp(fun: Callable[..., ArrayLike] | NativeSystem, t_span: Sequence[float],
              y0: ArrayLike, method: str | type = "RK45", t_eval: ArrayLike | None = None,
              dense_output: bool = False,
              events: Callable[..., float] | Sequence[Callable[..., float]] | None = None,
              vectorized: bool = False, args: tuple | None = None, *,
              rtol: float | ArrayLike = 1e-3, atol: float | ArrayLike = 1e-6,
              first_step: float | None = None, max_step: float = np.inf,
              max_steps: int | None = None,
              jac: Callable[..., ArrayLike] | ArrayLike | None = None,
              **options: Any) -> OdeResult:
    """Solve an initial value problem y' = fun(t, y), y(t0) = y0 (SciPy's interface).

    A drop-in for ``scipy.integrate.solve_ivp``: the same defaults (method RK45, rtol
    1e-3, atol 1e-6, so a default run takes the same steps and about the same nfev, and no
    limit on the number of steps), the same event rules (``terminal`` as a count, an event
    zero at t0 counted as SciPy does), the same result fields and shapes, complex and
    empty states, infinite ``t_span`` with terminal events; SciPy's own test files run on
    it (python/tests/test_scipy_own_suite.py).

    Parameters
    ----------
    fun : callable or conmech.systems.NativeSystem
        ``fun(t, y, *args) -> dydt`` (array of shape (n,)), called from Fortran through
        an f2py callback; or a compiled built-in system such as
        ``conmech.systems.kepler(mu=1.0)``, integrated with no Python in the loop. The
        return value is checked on every call: None, a wrong shape, or complex values for
        a real y0 raise ValueError/TypeError.
    t_span : 2-sequence of float
        (t0, tf); tf < t0 integrates backwards; tf may be infinite with a terminal event
        or ``max_steps`` to end the run (else ValueError: SciPy would integrate for ever;
        not for the fixed-step methods).
    y0 : array_like, shape (n,)
        Initial state, real or complex (a complex system is integrated as its real and
        imaginary parts, as SciPy's explicit methods do; Radau refuses it, as SciPy's),
        possibly empty (n = 0: nothing is integrated).
    method : str or a stepper class
        "RK45" (default), "DOPRI5", "DOP853", "VERNER98" (alias "Vern9"), "RK4", "Radau"
        (alias "RADAU5"), "GAUSS4" or "GAUSS6"; or a stepper class: conmech.DOP853,
        conmech.RK45, ..., and SciPy's scipy.integrate.RK45 / DOP853 / Radau (mapped to
        conmech's counterparts). RK45: Dormand-Prince 5(4) with SciPy's step control and
        initial step (SciPy's default method). DOPRI5: the same pair with Hairer's control
        (Lund stabilisation beta = 0.04). DOP853: Dormand-Prince 8(5,3), dense output of
        order 7. VERNER98: Verner's 9(8) pair, dense output of order 8, for tight
        tolerances. RK4: classical fixed-step RK4, step ``first_step``.
        Radau: Radau IIA of order 5 for stiff problems (Hairer's RADAU5: simplified
        Newton with one real and one complex LU, dense output of order 3, events; counts
        njev and nlu). GAUSS4 / GAUSS6: Gauss-Legendre collocation with 2 / 3 stages
        (orders 4 / 6), symplectic, fixed step ``first_step``, for long runs of
        conservative systems. Case-insensitive.
    t_eval : array_like or None
        Times at which to store the solution (strictly monotonic in the direction of
        integration, inside t_span), from the dense output. None: every accepted step.
    dense_output : bool
        Return ``sol``, a callable continuous solution with SciPy's OdeSolution
        attributes (ts, interpolants, n_segments, t_min, t_max, ascending); always
        present when asked (a zero-length span or a stop at t0: the constant y0).
    events : callable or list of callables
        ``event(t, y, *args) -> float``; zero crossings are located on the dense output.
        Optional attributes ``terminal`` (bool, or a positive integer: stop at that
        occurrence) and ``direction`` (>0 rising, <0 falling, 0 both), as in SciPy >= 1.11.
        An event that is zero at t0 is reported at t0 when the first step moves it in its
        direction (SciPy's rule). SciPy's rule compares an event at the two ends of each
        step only, so two crossings inside one step cancel and are missed; conmech's
        optional attribute ``resolution`` (a time) also samples the event on each step's
        continuous extension at points at most that far apart, and locates every sign
        change between them: crossings more than ``resolution`` apart are all found
        (without changing the steps; cost: event evaluations). An event value that is
        NaN stops the run (status -1, the message names the event and the time).
    vectorized : bool
        As SciPy's explicit methods: ``fun`` is called with y of shape (n, 1) and its
        result flattened.
    args : tuple or None
        Extra arguments passed to ``fun``, ``jac`` and every event function.
    rtol, atol : float or array_like of shape (n,)
        Relative and absolute tolerances (finite, non-negative; rtol is raised to 100 eps
        at least, with SciPy's warning).
    first_step : float or None
        Initial step (None: SciPy's heuristic for RK45 and Radau, Hairer's for the
        others). Required by RK4, GAUSS4 and GAUSS6 (their fixed step).
    max_step : float
        Largest step size (default no limit; positive, NaN rejected).
    max_steps : int or None
        Attempted steps before giving up (status -1). None (default): no limit, as SciPy.
    jac : callable, array_like, sparse matrix or None
        Used by method="Radau": ``jac(t, y, *args) -> (n, n)`` (a dense array or a
        scipy.sparse matrix) or a constant matrix (dense or sparse: read once, njev 0, as
        SciPy); None: forward differences (n evaluations of fun per Jacobian, or one per
        group of columns with ``jac_sparsity``). With a sparsity structure (``jac_sparsity``,
        or a constant sparse ``jac``), n >= 100 and at most 10% of the n^2 entries in it,
        the two LU factorisations per step are sparse (Gilbert-Peierls with a reverse
        Cuthill-McKee column order, J kept on its pattern: work and memory grow with the
        entries, not with n^3 / n^2); otherwise dense (LAPACK). A callable's sparse value
        at (t0, y0) fixes the pattern: its values are passed on it, never densified.
        The other methods validate it and warn that it has no effect, as SciPy's
        explicit ones.
    **options
        ``jac_sparsity`` (Radau, without ``jac``): the sparsity structure of df/dy (an
        (n, n) array_like or sparse matrix, nonzero where f_i depends on y_j): the
        finite-difference Jacobian then takes one evaluation per group of columns that
        share no row (Curtis-Powell-Reid, as SciPy's). SciPy's other solver options
        (lband, uband, min_step) are accepted and warned about as SciPy does; anything
        else is a TypeError.

    Returns
    -------
    OdeResult
        t, y (n, nt), sol (OdeSolution-like or None), t_events, y_events (lists per
        event, None without events; an event that never fired has t_events[k] of shape
        (0,) and y_events[k] of shape (0,), as SciPy), nfev, njev, nlu (Radau's Jacobian
        evaluations and LU decompositions; 0 for the other methods), status (0 reached
        the end, 1 terminal event, -1 failure), message, success, and the step counts
        naccept, nreject. With ``t_eval`` and no point reached (a terminal event first),
        t and y are empty lists, as SciPy's.

    The positional order of the arguments is SciPy's; rtol, atol, first_step, max_step,
    max_steps and jac (SciPy's ``**options``) are keyword-only.

    Raises
    ------
    TypeError, ValueError
        On bad input; the message names the argument. An exception raised inside ``fun``
        or an event function reaches the caller unchanged.
    """
    if ((type(rtol) is float or type(rtol) is np.float64) and
            (type(atol) is float or type(atol) is np.float64) and type(method) is str
            and args is None
            and events is None and dense_output is False and vectorized is False
            and jac is None and not options and isinstance(fun, NativeSystem)):
        # the most frequent calls, with plain inputs: checked with the cheapest tests of
        # the same rules (None: an input of another kind or a bad one, checked below)
        res = _fast_solve(fun, t_span, y0, method, rtol, atol, _TAYLOR, with_fixed_order,
                          t_eval, first_step, max_step, max_steps)
        if res is not None:
            return res
    # ---------------------------------------------------------------- fun and args
    builtin = isinstance(fun, NativeSystem)
    if not builtin and not callable(fun):
        raise TypeError("fun must be callable or a built-in system from conmech.systems, "
                        f"got {type(fun).__name__}")
    if args is not None:
        if isinstance(args, (str, bytes)):
            raise TypeError("args should be a tuple, not a string")
        try:
            args = tuple(args)
        except TypeError:
            raise TypeError("Supplied 'args' cannot be unpacked. Please supply `args` as "
                            f"a tuple (e.g. `args=({args},)`)") from None
        if builtin and args:
            raise TypeError("args cannot be used with a built-in system: pass its "
                            "parameters to the factory in conmech.systems")
    else:
        args = ()
    unknown = [k for k in options if k not in _OPTION_NAMES] if options else ()
    if unknown:
        raise TypeError(f"solve_ivp() got unexpected keyword arguments: {', '.join(unknown)}")

    # ---------------------------------------------------------------- method
    if isinstance(method, type):     # a stepper class: conmech.DOP853, scipy.integrate.RK45
        code = method_code(method)
        if code == 0:
            raise ValueError(f"method {method.__name__} has no counterpart in conmech; use "
                             f"one of {', '.join(_METHODS)} or conmech.DOP853, ...")
    elif not isinstance(method, str):
        raise TypeError(f"method must be a string, one of {', '.join(_METHODS)}")
    else:
        upper = method.upper()
        code = _RK45_SCIPY if upper == "RK45" else _METHOD_CODES.get(upper, 0)
    if code == 0:
        raise ValueError(f"method must be one of {', '.join(_METHODS)}, got {method!r}")
    if isinstance(method, type) and method.__module__.startswith("scipy.integrate") \
            and method.__name__ == "RK45":
        code = _RK45_SCIPY      # SciPy's own RK45: its step control, as the name "RK45"
    info = method_info(code)

    # ---------------------------------------------------------------- t_span, y0
    t0, tf = _time_span(t_span)
    if not math.isfinite(t0):
        raise ValueError("t_span[0] must be finite")
    if math.isnan(tf):
        raise ValueError("t_span[1] must not be NaN")
    if math.isinf(tf) and info.fixed_step:
        raise ValueError(f"t_span must be finite for {method} (a fixed-step method)")
    y0 = _initial_state(y0, fun, builtin, allow_complex=not builtin, allow_empty=not builtin)
    n = y0.size
    is_complex = y0.dtype.kind == "c"
    if is_complex and info.uses_jacobian:
        raise ValueError(_COMPLEX_REFUSED)

    # ---------------------------------------------------------------- tolerances, steps
    rtol_v, atol_v, h0 = _step_controls(rtol, atol, n, first_step, t0, tf)
    if info.fixed_step and first_step is None:
        raise ValueError(f"first_step is required by {method} (a fixed-step method): pass "
                         "the step size")
    hmax = min(_positive_finite(max_step, "max_step", allow_inf=True), _HUGE)
    step_cap = max_steps is not None
    max_steps = _step_limit(max_steps)
    sparsity = options.get("jac_sparsity")
    unused = sorted(k for k in options if not (k == "jac_sparsity" and info.uses_jacobian)) \
        if options else []
    if jac is not None and not info.uses_jacobian:
        unused.append("jac")
        _check_jac_value(jac, n)
        jac = None
    if unused:   # as SciPy's solvers
        warnings.warn("The following arguments have no effect for a chosen solver: "
                      f"{', '.join(f'`{k}`' for k in unused)}.", stacklevel=2)
    if not info.uses_jacobian or jac is not None:
        sparsity = None        # SciPy: jac_sparsity only serves finite differences
        if info.uses_jacobian and is_sparse(jac):
            sparsity = jac     # a constant sparse jac: its pattern for the sparse LUs
    pattern = sparsity_pattern(sparsity, n) if sparsity is not None and n else None
    if vectorized not in (True, False, 0, 1) or isinstance(vectorized, float):
        raise TypeError("vectorized must be a bool")
    if dense_output not in (True, False, 0, 1) or isinstance(dense_output, float):
        raise TypeError("dense_output must be a bool")

    # ---------------------------------------------------------------- t_eval
    t_ev = _EMPTY if t_eval is None else _time_points(t_eval, t0, tf)

    # ---------------------------------------------------------------- events
    settings = _event_settings(events)
    if math.isinf(tf) and n and not step_cap and not any(c > 0 for _, c, _, _ in settings):
        # SciPy would integrate for ever: nothing ends such a run but a failure
        raise ValueError("t_span: an infinite end needs a terminal event (or max_steps) to "
                         "end the integration")
    generalized = None
    if builtin and code == _TAYLOR:
        if getattr(fun, "taylor", None):        # the recurrences written out for the order
            fun = with_fixed_order(fun, rtol, atol)
        elif getattr(fun, "kind", None) == "generalized":
            # M(q) q'' = Q: its first-order view (the same state y = [q; v]), whose
            # recurrences solve with M order by order, runs from here on (other systems
            # without Taylor code: the Fortran stepper's message)
            view = first_order_view(fun)
            if view is not fun:
                generalized, fun = fun, with_fixed_order(view, rtol_v, atol_v)
    if builtin and not settings and not dense_output and jac is None and pattern is None:
        # the common case (a compiled system, nothing called back): one Fortran call
        res = _solve_native(fun, t0, tf, y0, t_ev, t_eval is not None, code, rtol_v,
                            atol_v, h0, hmax, int(max_steps))
        return res if generalized is None else name_the_mass_matrix(generalized, res)
    problem = dict(fun=fun, builtin=builtin, args=args, t0=t0, tf=tf, y0=y0,
                   t_ev=t_ev, with_t_eval=t_eval is not None, dense=bool(dense_output),
                   settings=settings, vectorized=bool(vectorized))
    if n == 0:
        return _solve_empty(**problem)
    if not builtin and not settings and not dense_output and jac is None and pattern is None \
            and not is_complex:
        # a Python right-hand side and nothing else called back: one Fortran call whose
        # only call-back is fun (its exceptions raised by the guard)
        run = _Run(fun, False, args, n, [], problem["vectorized"], t0, None, None, y0)
        return _solve_callable(run.rhs, run.guard, n, t0, tf, y0, t_ev, t_eval is not None,
                               code, rtol_v, atol_v, h0, hmax, int(max_steps))
    common = dict(method=code, rtol=rtol_v, atol=atol_v, max_step=hmax,
                  max_steps=int(max_steps), dense=int(bool(dense_output)))
    if not is_complex:
        res = _solve(problem, common, h0, jac, pattern)
        return res if generalized is None else name_the_mass_matrix(generalized, res)
    # a complex system as its real and imaginary parts: y = u + i v, [u; v]' = [Re f; Im f]
    problem.update(fun=_real_form(fun, n), y0=np.concatenate([y0.real, y0.imag]),
                   settings=[(_real_form_event(e, n), c, d, r) for e, c, d, r in settings])
    common.update(rtol=np.concatenate([rtol_v, rtol_v]),
                  atol=np.concatenate([atol_v, atol_v]))
    res = _solve(problem, common, h0, None, None)
    return _complex_result(res, n)


def _check_jac_value(jac, n):
    """SciPy's explicit methods ignore jac but a constant one must still be (n, n)."""
    if jac is None or callable(jac):
        return
    shape = jac.shape if is_sparse(jac) else np.shape(jac)
    if tuple(shape) != (n, n):
        raise ValueError(f"`jac` is expected to have shape {(n, n)}, but actually has "
                         f"{tuple(shape)}.")


def _solve(problem, common, h0, jac, pattern):
    """solve_ivp on a real, non-empty problem (checked): one Fortran call, which counts the
    occurrences of the terminal events (ev_term: each event's count, 0 not terminal) and
    applies SciPy's rule to an event exactly zero at t0."""
    fun, builtin, args = problem["fun"], problem["builtin"], problem["args"]
    t0, tf, y0, t_ev = problem["t0"], problem["tf"], problem["y0"], problem["t_ev"]
    with_t_eval, settings = problem["with_t_eval"], problem["settings"]
    n = y0.size
    ne = len(settings)
    run = _Run(fun, builtin, args, n, settings, problem["vectorized"], t0, jac, pattern, y0)
    if ne:
        ev_dir = np.array([s[2] for s in settings], dtype=np.intc)
        ev_term = np.array([s[1] for s in settings], dtype=np.intc)
        ev_res = np.array([s[3] for s in settings], dtype=float)
    else:
        ev_dir, ev_term, ev_res = _PADI, _PADI, _PAD
    out = run.call(t0, tf, y0, t_ev, h0, ev_dir, ev_term, ev_res, common)
    if with_t_eval and not t_ev.size:
        # t_eval=[]: no output time (the flat call's neval = 0 stores every step)
        out["t"], out["y"] = out["t"][:0], out["y"][:, :0]
    run.guard.check()
    info, message = out["info"], out["message"]
    if info == BAD_INPUT:
        raise ValueError(message)
    return _assemble(out, run, n, ne, t0, tf, y0, with_t_eval, problem["dense"],
                     out["form"], info if info >= 0 else -1, message, out["nfev"],
                     out["naccept"], out["nreject"])


class _Run:
    """The callbacks of one solve_ivp call (one Guard for fun and the events) and its
    Fortran call."""

    def __init__(self, fun, builtin, args, n, settings, vectorized, t0, jac=None,
                 pattern=None, y0=None):
        self.guard = Guard()
        self.jac = jac
        self.njev = self.nlu = 0
        self.fun, self.builtin, self.args, self.n = fun, builtin, args, n
        self.settings = settings
        self.rhs = None
        self.failure = []
        if builtin and jac is not None:
            raise TypeError("jac cannot be used with a built-in system (it has its own)")
        self.jac_cb, self.has_jac, self.jac_const, self.sparse_jac = start_jacobian(
            jac, n, args, self.failure, t0, y0)
        pattern = self.sparse_jac.pattern if self.sparse_jac is not None else pattern
        nnz, ptr, idx = pattern if pattern is not None else (-1, None, _PADI)
        self.pattern = dict(nnz=nnz, sp_ptr=ptr if ptr is not None else
                            np.zeros(n + 1, dtype=np.intc), sp_idx=idx)
        if not builtin:
            if vectorized:
                def user(t, y, *a):
                    r = fun(t, y[:, None], *a)
                    return None if r is None else np.asarray(r).reshape(-1)
            else:
                user = fun
            self.rhs = self.guard.wrap(user, 2, (n,), "fun", extra=args)

    def events_callback(self):
        """The events callback: g of every event, checked (one scalar each); NaN from the
        first exception on (kept by the guard, which the caller re-raises)."""
        settings, args, guard = self.settings, self.args, self.guard
        ne = len(settings)
        funs = [s[0] for s in settings]
        nan_g = np.full(ne, np.nan)

        def events_cb(t, y):
            if guard.error is not None:
                return nan_g
            try:
                yc = y.copy()
                g = np.empty(ne)
                for i, e in enumerate(funs):
                    r = e(t, yc, *args)
                    if r is None:
                        raise ValueError(f"events[{i}] returned None; expected a number")
                    g[i] = as_result(r, (), f"events[{i}]")
                return g
            except BaseException as exc:   # noqa: B036 (kept, re-raised by check())
                guard.fail(exc)
                return nan_g
        return events_cb

    def call(self, t_a, tf, y_a, t_ev, h0, ev_dir, ev_term, ev_res, common):
        ne = len(self.settings)
        n = self.n
        res = {}

        def store(t, y, ev_t, ev_y, ev_id, ts, hs, coef):
            # the arrays wrap Fortran memory that is freed on return: copy them
            res["t"] = t.copy()
            res["y"] = y.reshape(n, t.size).copy()
            res["ev"] = [(int(i) - 1, float(te), ev_y.reshape(n, -1)[:, k].copy())
                         for k, (te, i) in enumerate(zip(ev_t, ev_id))] if ev_t.size else []
            if ts.size:
                res["dense"] = (ts.copy(), hs.copy(), coef.reshape(n, -1, ts.size).copy())

        if ne:
            events_cb = self.events_callback()
        else:
            def events_cb(t, y):  # never called when ne = 0
                return _PAD
        kw = dict(t_span=np.array([t_a, tf]), y0=y_a, first_step=h0, neval=t_ev.size,
                  t_eval=t_ev if t_ev.size else _PAD, ne=ne, ev_dir=ev_dir,
                  ev_term=ev_term, ev_res=ev_res, **self.pattern, **common)
        if self.builtin and ne and _compiled_events(self.fun, common["method"], self.settings):
            # Taylor's method with events from conmech.symbolic.event: no Python in the loop
            # (no sampling inside the steps: _compiled_events requires resolution 0)
            kw_taylor = {k: v for k, v in kw.items()
                         if k not in ("ev_res", "nnz", "sp_ptr", "sp_idx")}
            counts, form, info, message = run_compiled_events(
                self.fun, [st[0] for st in self.settings], store, kw_taylor)
        elif self.builtin:
            counts, form, info, message = _conmech.flat_solve(
                *self.fun._system_args(), events_cb, store, jac_const=0, **kw)
        elif self.sparse_jac is not None:
            counts, form, info, message = _conmech.flat_solve_sparse_jac(
                self.rhs, self.sparse_jac.callback, events_cb, store, **kw)
        else:
            counts, form, info, message = _conmech.flat_solve(
                "", 0, _PAD, 0, _NO_SPEC, self.rhs, self.jac_cb, 2 if self.has_jac else 1,
                events_cb, store, jac_const=self.jac_const, **kw)
        if self.failure:
            self.guard.fail(self.failure[0])
        nfev, njev, nlu, naccept, nreject = counts.tolist()
        self.njev += njev
        self.nlu += nlu
        res.setdefault("t", np.array([t_a]))
        res.setdefault("y", y_a[:, None].copy())
        res.setdefault("ev", [])
        res.setdefault("dense", None)
        res.update(nfev=nfev, naccept=naccept, nreject=nreject,
                   form=int(form), info=int(info), message=message_text(message))
        return res


def _compiled_events(fun, code, settings):
    """True when method TAYLOR runs with events that are all conmech.symbolic events of
    fun's model (then the Fortran stepper locates them itself) and none asks for samples
    inside the steps (a resolution: the Python-located path samples them)."""
    if METHODS.get(code) is None or METHODS[code].name != "TAYLOR":
        return False
    if any(st[3] > 0 for st in settings):
        return False
    # conmech.symbolic needs sympy, an optional dependency: imported on this path only
    from ..symbolic.taylor_events import compiled_events
    return compiled_events(fun, [st[0] for st in settings]) is not None
