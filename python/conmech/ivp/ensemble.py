"""Ensembles: many initial states and/or parameter sets of one system, integrated in
parallel in Fortran (OpenMP threads, no Python in the loop). The system is a built-in one
(``conmech.systems``) or a compiled one (``conmech.compiled.ode_system`` /
``generalized_system``, e.g. from ``conmech.symbolic``): they take the same path.

Each member is the single integration :func:`conmech.solve_ivp` would do with the same
system, initial state, parameters and options, bit for bit, whatever the number of threads.

Example: 10,000 Kepler orbits, their states at common times and the first two upward
crossings of y = 0 of each::

    import numpy as np
    import conmech
    from conmech import ensemble

    e = np.linspace(0.0, 0.9, 10_000)
    y0 = np.column_stack([1 - e, 0 * e, 0 * e, np.sqrt((1 + e) / (1 - e))])
    res = ensemble.solve(conmech.systems.kepler(), (0, 20), y0, t_eval=np.linspace(0, 20, 5),
                         method="DOP853", rtol=1e-10, atol=1e-10,
                         events=ensemble.crossing(1, 0.0, direction=1), max_events=2)
    res.y          # (10000, 4, 5): member i's solve_ivp(...).y
    res.t_events   # (10000, 2): the first two crossings (NaN where fewer)

Parameters vary per member through ``params``: an array of shape (m, n_params) in the
factory's order, or a dict of per-member values by parameter name (the others keep the
system's values)::

    res = ensemble.solve(conmech.systems.pendulum(), (0, 10), [1.0, 0.0],
                         params={"l": np.linspace(0.5, 2.0, 100)})
"""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import inspect
import math
import numbers

import numpy as np

from .. import _conmech
from .solve import OdeResult, _METHOD_CODES, _METHODS, _HUGE
from .._core.checks import positive_finite as _positive_finite, real_scalar as _real_scalar, \
    step_controls as _step_controls, time_points as _time_points, time_span as _time_span
from .solve import solve_ivp as _solve_ivp
from .._core.native import NativeSystem, function_address
from .._core.status import BAD_INPUT
from .._core.model import model_of
from .._core.lanes import LANES

__all__ = ["solve", "crossing", "Crossing", "EnsembleResult"]

_NOT_RUN = -99
_PAD = np.zeros(1)
_PADI = np.zeros(1, dtype=np.intc)
# the defaults of solve_ivp (method, rtol, atol), so that a member equals solve_ivp's run
_IVP_DEFAULTS = {k: v.default for k, v in inspect.signature(_solve_ivp).parameters.items()
                 if k in ("method", "rtol", "atol")}


class Crossing:
    """Event kind of an ensemble: the component ``component`` (0-based) of the state
    crossing ``value``; ``direction`` > 0 rising only, < 0 falling only, 0 both (SciPy's
    convention). Located on the dense output as :func:`conmech.solve_ivp` locates
    ``lambda t, y: y[component] - value``, bit for bit."""

    __slots__ = ("component", "value", "direction")

    def __init__(self, component, value=0.0, direction=0):
        if isinstance(component, (bool, np.bool_)) or \
                not isinstance(component, numbers.Integral):
            raise TypeError("crossing: component must be an integer index into the state")
        self.component = int(component)
        self.value = _real_scalar(value, "crossing: value")
        if not math.isfinite(self.value):
            raise ValueError("crossing: value must be finite")
        d = _real_scalar(direction, "crossing: direction")
        if math.isnan(d):
            raise ValueError("crossing: direction must be a number")
        self.direction = int(np.sign(d))

    def __call__(self, t, y):
        """The event function itself, g = y[component] - value (for solve_ivp)."""
        return y[self.component] - self.value

    def __repr__(self):
        return (f"conmech.ensemble.crossing({self.component}, {self.value!r}, "
                f"direction={self.direction})")


def crossing(component: int, value: float = 0.0, direction: int = 0) -> Crossing:
    """A :class:`Crossing` event: state component ``component`` crosses ``value``."""
    return Crossing(component, value, direction)


class EnsembleResult(OdeResult):
    """Result of :func:`solve`, a dict whose keys are also attributes.

    Keys (m members, state dimension n, nt output times, k events kept):

    - ``t``: the output times (t_eval) or None; ``y``: (m, n, nt) states there, NaN
      where a member did not get (failure, terminal event, cancel), or None;
    - ``t_final`` (m,), ``y_final`` (m, n): where each member ended and its state;
    - ``status`` (m,): 0 reached the end, 1 stopped at its terminal event, -1 failed,
      -2 not run (cancelled); ``member_success`` (m,): status >= 0; ``codes`` (m,):
      conmech's status codes;
    - ``nfev``, ``naccept``, ``nreject`` (m,): counters of each member;
    - ``t_events`` (m, k), ``y_events`` (m, k, n), ``event_index`` (m, k) (which event of
      the list, -1 if none), ``n_events`` (m,): the first k events of each member, in
      time order (NaN-padded); None without events;
    - ``success``: every member ended normally; ``message``: the first failure;
      ``done``: members integrated.
    """

    def __repr__(self):
        keys = ("message", "success", "done", "status", "t", "y", "t_final", "y_final",
                "nfev", "t_events", "y_events", "n_events")
        lines = []
        for k in keys:
            v = self.get(k)
            if isinstance(v, np.ndarray) and v.size > 6:
                v = f"array of shape {v.shape}"
            lines.append(f"{k.rjust(9)}: {v}" if isinstance(v, str) else
                         f"{k.rjust(9)}: {v!r}")
        return "\n".join(lines)


def _check_system(system):
    if isinstance(system, NativeSystem):
        return system
    if type(system).__name__ in ("BuiltinConstrained", "CompiledConstrained"):
        raise TypeError("ensemble.solve integrates first-order systems (conmech.systems "
                        "...); constrained systems are not supported in ensembles")
    if callable(system):
        raise TypeError("ensemble.solve integrates compiled systems (conmech.systems ...) in "
                        "parallel threads; a Python function cannot run there: use "
                        "conmech.solve_ivp in a loop for it")
    raise TypeError("system must be a built-in system from conmech.systems, got "
                    f"{type(system).__name__}")


def _member_rows(value, what, or_else, width, shapes):
    """The members' rows of an array argument (a 1-d one: a single member): real numbers,
    `width` columns (`shapes` says which shapes are accepted)."""
    try:
        table = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{what} must be an array of real numbers{or_else}") from None
    if table.ndim == 1:
        table = table.reshape(1, -1)
    if table.ndim != 2 or table.shape[1] != width:
        raise ValueError(f"{what} must have shape {shapes}, got shape {np.shape(value)}")
    return table


def _member_params(system, params):
    """Parameter table (np, mp) in Fortran order, and mp."""
    base = system.params
    npar = base.size
    if params is None:
        # f2py cannot pass empty arrays: a system without parameters gets one dummy row
        return (base.reshape(npar, 1) if npar else np.zeros((1, 1))), 1
    if isinstance(params, dict):
        names = system.param_names
        if not names:
            raise ValueError(f"params: the system '{system.name}' has no parameter names; "
                             "pass an array of shape (m, n_params)")
        cols = {}
        m = None
        for key, val in params.items():
            if key not in names:
                raise ValueError(f"params: unknown parameter {key!r} of the system "
                                 f"'{system.name}' (its parameters: {', '.join(names)})")
            try:
                arr = np.array(val, dtype=float)
            except (TypeError, ValueError):
                raise TypeError(f"params[{key!r}] must be an array of real numbers") from None
            if arr.ndim > 1:
                raise ValueError(f"params[{key!r}] must be a scalar or 1-dimensional")
            if arr.ndim == 1:
                if m is not None and arr.size != m:
                    raise ValueError("params: the per-member arrays must have the same "
                                     f"length, got {m} and {arr.size}")
                m = arr.size
            cols[names.index(key)] = arr
        m = 1 if m is None else m
        table = np.repeat(base.reshape(1, npar), m, axis=0)
        for j, arr in cols.items():
            table[:, j] = arr
    else:
        table = _member_rows(params, "params", " or a dict", npar,
                             f"(m, {npar}) for the system '{system.name}' "
                             f"({', '.join(system.param_names)})")
    if table.shape[0] == 0:
        raise ValueError("params has no rows (no members)")
    if not np.isfinite(table).all():
        raise ValueError("params must be finite")
    if npar == 0:
        return np.zeros((1, table.shape[0]), order="F"), table.shape[0]
    return np.asfortranarray(table.T), table.shape[0]


def _taylor_batch(system, method, nt, ne, mp, first_step, progress, lanes, eps,
                  generalized=None):
    """The Taylor entries of the batch route of an ensemble, or None: method TAYLOR, a
    system with a batch routine, shared parameters, final states only (no t_eval, events,
    first_step or progress). A system of conmech.symbolic gets its batch library here, on
    first need: the coefficient routine and the propagator over SIMD lanes
    (conmech.symbolic.taylor_batch) with `lanes` lanes (None: the machine's vector
    width), the recurrences written out for the order of the tolerance eps when they are
    small enough. `generalized`: the generalized system M(q) q'' = Q whose first-order
    view `system` is (its batch library: conmech.symbolic.taylor_generalized_batch, the
    loop version, or for a tree conmech.symbolic.taylor_tree_batch, for any number of
    degrees of freedom)."""
    if not (isinstance(method, str) and method.upper() == "TAYLOR"):
        return None
    batch = nt == 0 and ne == 0 and mp <= 1 and first_step is None and progress is None
    if not batch:
        # the member-by-member route: a system of conmech.symbolic compiles its Taylor
        # recurrences here, on first need (their entries then in its spec)
        getattr(system, "taylor", None)
        return None
    if generalized is not None:
        from .taylor_generalized import batch_entries
        extra = batch_entries(generalized, lanes)
        return dict(system.taylor, **extra) if extra else None
    taylor = None
    if hasattr(system, "taylor_parts"):
        # a system of conmech.symbolic compiles its Taylor recurrences here, on first
        # need (their entries then in its spec, for the member-by-member path too)
        from .taylor import taylor_order
        taylor = system.taylor_parts()
        try:
            model = model_of(system)
        except TypeError:
            model = None
        extra = None
        if taylor and model is not None:
            extra = model.taylor_batch_entries(lanes, taylor_order(eps))
        if extra:
            taylor = dict(taylor, **extra)
        elif taylor:       # the machine's lanes, the loop version: the lazy part
            taylor = system.taylor_parts("batch")
    else:
        taylor = getattr(system, "taylor", None)
    if not taylor or taylor.get("batch") is None:
        return None
    return taylor


def _solve_taylor_batch(system, taylor, t0, tf, y0a, m, rtol_v, atol_v, hmax, max_steps,
                        nthreads, generalized=None, params=None):
    """The members in SIMD lanes (the generated propagator, lanes refilled as members end)
    or in batches of the coefficient routine's width (a system given a batch routine
    only), chunks of members in OpenMP threads; each member's steps are those of its
    solve_ivp run, bit for bit. `generalized`: the system M(q) q'' = Q whose first-order
    view `system` is (the message of a failed member then says what its mass matrix is
    where it stopped). `params`: the members' shared parameters (None: the system's)."""
    n = system.dimension
    y0m = np.broadcast_to(y0a, (m, n)) if y0a.shape[0] == 1 else y0a
    if params is not None and system.params.size:
        p = np.ascontiguousarray(params, dtype=float)
    else:
        p = system.params if system.params.size else _PAD
    if taylor.get("batch_run") is not None:
        (y_final, t_final, codes, nfev, naccept, nreject, info,
         message) = _conmech.flat_taylor_batch_run(
            runaddr=function_address(taylor["batch_run"], "taylor['batch_run']"),
            np=system.params.size, params=p, n=n, m=m, y0=np.asfortranarray(y0m.T),
            t_span=np.array([t0, tf]), rtol=rtol_v, atol=atol_v, max_step=hmax,
            max_steps=max_steps, threads=nthreads)
    else:
        (y_final, t_final, codes, nfev, naccept, nreject, info,
         message) = _conmech.flat_taylor_ensemble(
            fnaddr=function_address(taylor["batch"], "taylor['batch']"),
            width=int(taylor["width"]), nw=int(taylor["nw"]), np=system.params.size,
            params=p, n=n, m=m, y0=np.asfortranarray(y0m.T), t_span=np.array([t0, tf]),
            rtol=rtol_v, atol=atol_v, max_step=hmax, max_steps=max_steps,
            threads=nthreads)
    codes = np.asarray(codes, dtype=int)
    status = np.where(codes >= 0, codes, -1)
    info = int(info)
    if info >= 0:
        message = "Every member reached the end of the integration interval."
    else:
        first = int(np.argmax(codes < 0))
        from .._core.status import status_message
        message = (f"{int((codes < 0).sum())} of {m} members failed; the first, member "
                   f"{first}: {status_message(int(codes[first]))}")
        if generalized is not None:
            from .taylor_generalized import mass_note
            message += mass_note(generalized, t_final[first], y_final[:, first],
                                 p if system.params.size else None)
    return EnsembleResult(
        t=None, y=None, t_final=t_final, y_final=np.ascontiguousarray(y_final.T),
        status=status, member_success=status >= 0, codes=codes, nfev=nfev.astype(int),
        naccept=naccept.astype(int), nreject=nreject.astype(int), t_events=None,
        y_events=None, event_index=None, n_events=None, success=info >= 0, message=message,
        done=m)


def solve(system: Any, t_span: Sequence[float], y0: ArrayLike,
          params: ArrayLike | dict | None = None, *, t_eval: ArrayLike | None = None,
          method: str | None = None, rtol: float | None = None, atol: float | None = None,
          first_step: float | None = None, max_step: float = np.inf, max_steps: int = 100000,
          events=None, max_events: int = 1, terminal: bool = False, threads: int | None = None,
          chunk: int | None = None,
          progress: Callable[[int, int], Any] | None = None,
          lanes: int | None = None) -> EnsembleResult:
    """Integrate an ensemble of members of one compiled system in parallel.

    Parameters
    ----------
    system : conmech.systems.NativeSystem (a built-in or a compiled system)
        The system (its parameters are the default of every member): built-in
        (``conmech.systems``) or compiled (``conmech.compiled.ode_system``,
        ``generalized_system``); constrained systems are not supported.
    t_span : 2-sequence of float
        (t0, tf), common to every member; tf < t0 integrates backwards.
    y0 : array_like, shape (m, n) or (n,)
        Initial states, one row per member, or one state shared by every member.
    params : array_like of shape (m, n_params) or (n_params,), or dict, optional
        Parameters per member in the factory's order, or ``{name: values}`` (values of
        length m, or scalars) overriding the system's parameters.
    t_eval : array_like, optional
        Common output times (sorted in the direction of integration, inside t_span).
    method, rtol, atol, first_step, max_step, max_steps
        As in :func:`conmech.solve_ivp`, shared by every member; None (method, rtol,
        atol): solve_ivp's defaults.
    events : Crossing or list of Crossing, optional
        Built-in event kinds (:func:`crossing`); Python callables cannot run in threads.
    max_events : int
        Events kept per member (the first ones, in time order).
    terminal : bool
        Stop each member at its ``max_events``-th event (then its final state).
    threads : int, optional
        OpenMP threads (default: OMP_NUM_THREADS or every core). The results do not
        depend on it.
    chunk : int, optional
        Members between two calls of ``progress`` (default: about 1 % of them).
    progress : callable, optional
        ``progress(done, total)``, called between chunks from the calling thread. An
        exception raised in it cancels the members not yet started and is raised again
        after the call.
    lanes : int, optional
        method="TAYLOR" on a system of :mod:`conmech.symbolic` with final states only (no
        t_eval, events, first_step, progress or per-member params): members integrated
        together in this many SIMD lanes (1, 2, 4, 8 or 16; None: the machine's vector
        width for doubles, 4 with AVX2, 8 with AVX-512), each a library compiled once per
        model. The results do not depend on it. Only with method="TAYLOR". An ode system,
        a generalized system M(q) q'' = Q of any number of degrees of freedom
        (conmech.symbolic.taylor_generalized_batch: M's factorisation written out in
        scalars up to 8, in loops over per-lane arrays beyond) and a tree
        (conmech.symbolic.taylor_tree_batch) take this route.

    Returns
    -------
    EnsembleResult

    Raises
    ------
    TypeError, ValueError
        On bad input, naming the argument.
    """
    system = _check_system(system)
    n = system.dimension
    method = _IVP_DEFAULTS["method"] if method is None else method
    rtol = _IVP_DEFAULTS["rtol"] if rtol is None else rtol
    atol = _IVP_DEFAULTS["atol"] if atol is None else atol
    if not isinstance(method, str):
        raise TypeError(f"method must be a string, one of {', '.join(_METHODS)}")
    code = _METHOD_CODES.get(method.upper(), 0)
    if code == 0:
        raise ValueError(f"method must be one of {', '.join(_METHODS)}, got {method!r}")
    generalized = None
    if method.upper() == "TAYLOR" and getattr(system, "kind", None) == "generalized":
        # M(q) q'' = Q made by conmech.symbolic: its first-order view, with the batch
        # routine of its lanes when it has one
        from .taylor_generalized import first_order_view
        generalized = system
        system = first_order_view(system)

    # ---------------------------------------------------------------- t_span, y0, params
    t0, tf = _time_span(t_span)
    if not (math.isfinite(t0) and math.isfinite(tf)):
        raise ValueError("t_span must be finite")
    y0_in = np.asarray(y0)
    if y0_in.dtype.kind == "c":
        raise TypeError("y0 must be real: complex states are not supported")
    y0a = _member_rows(y0_in, "y0", "", n, f"(m, {n}) or ({n},) for the system '{system.name}'")
    if y0a.shape[0] == 0:
        raise ValueError("y0 has no rows (no members)")
    if not np.isfinite(y0a).all():
        raise ValueError("y0 contains NaN or Inf")
    ptab, mp = _member_params(system, params)
    my0 = y0a.shape[0]
    if mp > 1 and my0 > 1 and mp != my0:
        raise ValueError(f"y0 has {my0} rows and params {mp}: they must agree (or one of "
                         "them be shared)")
    m = max(mp, my0)

    # ---------------------------------------------------------------- options
    rtol_v, atol_v, h0 = _step_controls(rtol, atol, n, first_step, t0, tf)
    if code == 1 and first_step is None:
        raise ValueError("first_step is required by RK4 (a fixed-step method): pass the "
                         "step size")
    hmax = min(_positive_finite(max_step, "max_step", allow_inf=True), _HUGE)
    for value, name in ((max_steps, "max_steps"), (max_events, "max_events")):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
            raise TypeError(f"{name} must be an integer")
        if not 1 <= value <= 2**31 - 1:
            raise ValueError(f"{name} must be positive (and below 2**31)")
    if threads is None:
        nthreads = 0
    else:
        if isinstance(threads, (bool, np.bool_)) or not isinstance(threads, numbers.Integral):
            raise TypeError("threads must be an integer or None")
        if not 1 <= threads <= 1024:
            raise ValueError("threads must be between 1 and 1024")
        nthreads = int(threads)
    if chunk is None:
        nchunk = 0
    else:
        if isinstance(chunk, (bool, np.bool_)) or not isinstance(chunk, numbers.Integral):
            raise TypeError("chunk must be an integer or None")
        if not 1 <= chunk <= 2**31 - 1:
            raise ValueError("chunk must be positive")
        nchunk = int(chunk)
    if lanes is not None:
        if isinstance(lanes, (bool, np.bool_)) or not isinstance(lanes, numbers.Integral):
            raise TypeError("lanes must be an integer or None")
        if int(lanes) not in LANES:
            raise ValueError(f"lanes must be one of {', '.join(map(str, LANES))}, got "
                             f"{lanes!r}")
        if method.upper() != "TAYLOR":
            raise ValueError("lanes applies to method='TAYLOR' only")
        lanes = int(lanes)
    if progress is not None and not callable(progress):
        raise TypeError("progress must be callable or None")
    if not isinstance(terminal, (bool, np.bool_)):
        raise TypeError("terminal must be a bool")

    # ---------------------------------------------------------------- t_eval, events
    t_ev = _PAD[:0] if t_eval is None else _time_points(t_eval, t0, tf)
    if events is None:
        evs = []
    elif isinstance(events, Crossing) or callable(events):
        evs = [events]
    else:
        try:
            evs = list(events)
        except TypeError:
            raise TypeError("events must be a Crossing (conmech.ensemble.crossing) or a "
                            "list of them") from None
    for i, e in enumerate(evs):
        if not isinstance(e, Crossing):
            what = "a Python function" if callable(e) else type(e).__name__
            raise TypeError(f"events[{i}] is {what}: an ensemble takes built-in event kinds "
                            "(conmech.ensemble.crossing), which run in the threads")
        if not -n <= e.component < n:
            raise ValueError(f"events[{i}]: component {e.component} is out of range for a "
                             f"state of size {n}")
    if terminal and not evs:
        raise ValueError("terminal=True needs events")
    ne = len(evs)
    k = int(max_events) if ne else 0

    # ---------------------------------------------------------------- run
    failure = []

    def relay(done, total):
        if failure:
            return 1
        try:
            progress(int(done), int(total))
        except BaseException as exc:
            failure.append(exc)
            return 1
        return 0

    def no_progress(done, total):
        return 0

    nt = t_ev.size
    eps = max(float(np.min(rtol_v)), 2.220446049250313e-16, float(np.min(atol_v)))
    taylor = _taylor_batch(system, method, nt, ne, mp, first_step, progress, lanes, eps,
                           generalized)
    if taylor is not None:
        return _solve_taylor_batch(system, taylor, t0, tf, y0a, m, rtol_v, atol_v, hmax,
                                   int(max_steps), nthreads, generalized, ptab[:, 0])
    name, _, _, nspec, spec = system._flat_args()
    (y_eval, t_final, y_final, codes, nfev, naccept, nreject, nev, ev_t, ev_y, ev_id, done,
     info, message) = _conmech.flat_ensemble_builtin(
        name=name, np=system.params.size, mp=mp, params=ptab, nspec=nspec, spec=spec, n=n,
        m=m, my0=my0,
        y0=np.asfortranarray(y0a.T), t_span=np.array([t0, tf]), method=code, rtol=rtol_v,
        atol=atol_v, first_step=h0, max_step=hmax, max_steps=int(max_steps), neval=nt,
        t_eval=t_ev if nt else _PAD, ne=ne,
        ev_comp=np.array([e.component % n + 1 for e in evs], dtype=np.intc) if ne else _PADI,
        ev_value=np.array([e.value for e in evs]) if ne else _PAD,
        ev_dir=np.array([e.direction for e in evs], dtype=np.intc) if ne else _PADI,
        k=k, terminal=int(bool(terminal)), threads=nthreads, chunk=nchunk,
        use_progress=int(progress is not None),
        progress=relay if progress is not None else no_progress,
        meval=m if nt else 1, mev=m if k else 1)
    if failure:
        raise failure[0]
    message = bytes(message).decode("ascii", "replace").strip() \
        if not isinstance(message, str) else message.strip()
    info = int(info)
    codes = np.asarray(codes, dtype=int)
    if info == BAD_INPUT and (codes == BAD_INPUT).all():
        raise ValueError(message)
    status = np.where(codes >= 0, codes, -1)
    status[codes == _NOT_RUN] = -2
    if info >= 0:
        message = "Every member reached the end of the integration interval." \
            if (codes == 0).all() else "Every member ended normally (some on their " \
            "terminal event)."
    res = EnsembleResult(
        t=t_ev.copy() if nt else None,
        y=np.ascontiguousarray(y_eval.transpose(2, 0, 1)) if nt else None,
        t_final=t_final, y_final=np.ascontiguousarray(y_final.T), status=status,
        member_success=status >= 0, codes=codes, nfev=nfev.astype(int),
        naccept=naccept.astype(int), nreject=nreject.astype(int), t_events=None,
        y_events=None, event_index=None, n_events=None, success=info >= 0, message=message,
        done=int(done))
    if k:
        res.t_events = np.ascontiguousarray(ev_t.T)
        res.y_events = np.ascontiguousarray(ev_y.transpose(2, 1, 0))
        res.event_index = np.ascontiguousarray(ev_id.T).astype(int) - 1
        res.n_events = nev.astype(int)
    return res
