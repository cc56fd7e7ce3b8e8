"""Constrained mechanical systems: multipliers, reaction forces, projected integrators.

The equations are ``M(t, q) q'' = Q(t, q, q') + C^T lambda`` with holonomic constraints
``phi(t, q) = 0`` (Jacobian ``G``) and non-holonomic ones ``A(t, q) q' + b(t, q) = 0``,
``C = [G; A]``. The accelerations and multipliers come from the acceleration-level KKT
system (LAPACK); after each accepted Runge-Kutta step the state is projected back onto the
constraints (mass-weighted position projection by simplified Newton, then velocity
projection), or Baumgarte stabilisation is used, or nothing (the plain index-1 form,
which drifts)::

    from conmech import constrained
    res = constrained.solve("pendulum_xy", (0, 10), rtol=1e-10, atol=1e-10)
    res.q, res.a, res.lam, res.reaction, res.res_pos

A system is a built-in (:func:`builtin` or its name; see :data:`BUILTIN_NAMES`) or a
:class:`ConstrainedSystem` made of Python callables. Integrations of built-ins run
entirely in Fortran.
"""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from .. import _conmech
from . import degrees_of_freedom as _dof
from .._core.builtin_table import CONSTRAINED_NAMES
from .._core.callback import Guard, as_result, message_text
from .._core.checks import real_number as _real_number
from .._core.driver_events import first_crossing_events
from .._core.model import model_of
from ..ivp.methods import BY_NAME
from .._core.native import _NO_SPEC, _unused_callback, check_params
from .._core.result import DictResult
from .._core.status import BAD_INPUT

__all__ = ["solve", "builtin", "NativeConstrained", "BuiltinConstrained",
           "ConstrainedSystem", "ConstrainedResult", "BUILTIN_NAMES", "PROJECTIONS",
           "plot_trajectory", "plot_drift"]

#: Names of the built-in constrained systems (excessive coordinates) with a fixed number of
#: coordinates (the pendulum chain, whose size is a parameter, is not listed).
BUILTIN_NAMES = CONSTRAINED_NAMES
#: Projection names and their codes in conmech_constrained_solver.
PROJECTIONS = {"none": 0, "velocity": 1, "position+velocity": 2, "baumgarte": 3}
# the methods of the Fortran table that constrained_solve runs (codes from the table)
_METHODS = {name: BY_NAME[name.upper()].code for name in (
    "RK4", "DOPRI5", "RK45", "DOP853", "VERNER98", "VERN9", "RATTLE", "Radau", "RADAU5")}
_PAD = np.zeros(1)
_PAD.flags.writeable = False


class ConstrainedResult(DictResult):
    """Result of :func:`solve` (a dict whose keys are also attributes).

    Keys: ``t`` (nt,), ``q``, ``v`` and the accelerations ``a`` (also ``accelerations``)
    (n, nt), ``lam`` (m, nt) multipliers, ``reactions`` (m, n, nt) the generalized force
    C_i^T lam_i by which constraint i acts on the coordinates (the rows of one joint, e.g.
    the two of a planar revolute joint, summed give that joint's reaction; for a joint
    written as the coincidence of two points in Cartesian coordinates its multipliers are
    the force components), ``reaction`` (n, nt) = C^T lambda, their sum,
    ``res_pos`` (max |phi|) and ``res_vel``
    (max |C v + c0|) (nt,), ``energy`` (nt,) (zeros if the system defines none),
    ``power`` (nt,) of the reactions, ``nfev``, ``naccept``, ``nreject``, ``nproj``,
    ``proj_iter`` (total simplified Newton iterations), ``proj_iter_max``, ``rank`` (of
    the constraints; < m when redundant), ``dq0``, ``dv0`` (how far the initial state was
    moved), ``status`` (0 success, 1 a terminal event, -1 failure),
    ``message``, ``success``; with ``events``: ``t_events``, ``q_events``, ``v_events``
    (one array per event function; states (k, n)).
    """

    def __repr__(self):
        return (f"ConstrainedResult(success={self.success}, message={self.message!r}, "
                f"nt={self.t.size}, nfev={self.nfev}, max res_pos="
                f"{np.max(self.res_pos, initial=0.0):.3g})")


class NativeConstrained:
    """A constrained system evaluated in native code (a built-in of the Fortran registry or
    compiled functions), for :func:`solve`: attributes name, params, n, n_hol, n_nh and
    spec (the function table handed to Fortran; empty for a built-in)."""

    __slots__ = ("name", "params", "n", "n_hol", "n_nh", "spec", "_keep")

    def _flat_args(self):
        """(name, np, params, nspec, spec) for the flat routines (built-in or compiled)."""
        p = self.params if self.params.size else _PAD
        nspec = self.spec.size if self.spec is not _NO_SPEC else 0
        return self.name, self.params.size, p, nspec, self.spec

    @property
    def degrees_of_freedom(self):
        """n minus the independent holonomic constraints, at the default consistent state
        (:func:`conmech.degrees_of_freedom.degrees_of_freedom` gives the whole report:
        independent velocities, redundant constraints)."""
        return _dof.degrees_of_freedom(self).dof


class BuiltinConstrained(NativeConstrained):
    """A built-in constrained system of the Fortran registry, by name and parameters."""

    __slots__ = ()

    def __init__(self, name, params=()):
        if not isinstance(name, str):
            raise TypeError("system name must be a string")
        params = np.array(params, dtype=float).ravel()
        if not np.all(np.isfinite(params)):
            raise ValueError("params must be finite")
        check_params(name, params)
        kind, n, mh, mn, info, msg = _conmech.flat_mech_info(
            name, params.size, params if params.size else _PAD, 0, _NO_SPEC)
        if kind != 1:
            raise ValueError(f"system: unknown built-in constrained system '{name}' "
                             f"(known: {', '.join(BUILTIN_NAMES)})")
        self.name = name
        self.params = params
        self.n, self.n_hol, self.n_nh = int(n), int(mh), int(mn)
        self.spec = _NO_SPEC
        self._keep = None

    def initial_state(self):
        """Default consistent initial state (q0, v0)."""
        q0, v0, info = _conmech.flat_mech_initial_state(
            self.name, self.params.size, self.params if self.params.size else _PAD, self.n)
        return np.array(q0), np.array(v0)

    def __repr__(self):
        return f"conmech.constrained.builtin({self.name!r}, {self.params.tolist()})"


def builtin(name: str, params: Sequence[float] = ()) -> BuiltinConstrained:
    """The built-in constrained system ``name`` with ``params`` (documented order:
    pendulum_xy m, g, l | rod_two_masses g, l | double_pendulum_xy m1, m2, l1, l2, g |
    atwood_xy m1, m2, g, L | pendulum_moving_xy m, g, l, a, b, w |
    yoyo m, r, I, g, ah, vh, h0 | skate m, I, g, alpha | rolling_disk m, R, I_roll, I_turn |
    rolling_ball m, R, I, g, alpha)."""
    return BuiltinConstrained(name, params)


class ConstrainedSystem:
    """A constrained system from Python callables.

    Parameters
    ----------
    n : int
        Number of (excessive) coordinates.
    mass : callable ``mass(t, q) -> (n, n)``
        Symmetric positive definite mass matrix.
    forces : callable ``forces(t, q, v) -> (n,)``
        Applied forces, velocity terms included.
    phi : callable ``phi(t, q) -> (n_hol,)``, optional
        Holonomic constraints (then ``n_hol`` > 0).
    jac : callable ``jac(t, q) -> (n_hol, n)``, optional
        d phi / d q; default: central differences.
    gamma : callable ``gamma(t, q, v) -> (n_hol,)``, optional
        Acceleration term, G q'' = gamma; default: five-point differences of phi.
    n_hol : int
    nh : callable ``nh(t, q) -> (A (n_nh, n), b (n_nh,))``, optional
        Non-holonomic constraints A q' + b = 0.
    nh_gamma : callable ``nh_gamma(t, q, v) -> (n_nh,)``, optional
        A q'' = nh_gamma; default: five-point differences of A v + b.
    n_nh : int
    rheonomic : bool
        phi depends explicitly on t.
    energy : callable ``energy(t, q, v) -> float``, optional
        Evaluated at the output points into ``result.energy``.
    """

    def __init__(self, n, mass, forces, phi=None, jac=None, gamma=None, n_hol=0, nh=None,
                 nh_gamma=None, n_nh=0, rheonomic=False, energy=None):
        self.n, self.n_hol, self.n_nh = int(n), int(n_hol), int(n_nh)
        if self.n < 1:
            raise ValueError("n must be at least 1")
        if self.n_hol < 0 or self.n_nh < 0:
            raise ValueError("n_hol and n_nh must be non-negative")
        for label, f in (("mass", mass), ("forces", forces)):
            if not callable(f):
                raise TypeError(f"{label} must be callable")
        if self.n_hol > 0 and not callable(phi):
            raise TypeError("phi must be callable when n_hol > 0")
        if self.n_nh > 0 and not callable(nh):
            raise TypeError("nh must be callable when n_nh > 0")
        for label, f in (("jac", jac), ("gamma", gamma), ("nh_gamma", nh_gamma),
                         ("energy", energy)):
            if f is not None and not callable(f):
                raise TypeError(f"{label} must be callable or None")
        self.mass, self.forces, self.phi, self.jac, self.gamma = mass, forces, phi, jac, gamma
        self.nh, self.nh_gamma, self.rheonomic = nh, nh_gamma, bool(rheonomic)
        self.energy = energy

    def _callbacks(self, guard):
        """The f2py callbacks, through one :class:`conmech._callback.Guard`: every return
        is checked (shape, real numbers); an exception raised by a user function is kept
        and the callbacks return NaN from then on (the Fortran solver stops on the
        non-finite values and returns normally); :func:`solve` re-raises it."""
        n, mh, mn = self.n, max(self.n_hol, 1), max(self.n_nh, 1)
        w = guard.wrap

        def missing(*args):    # a callback Fortran never calls (count 0 or FD default)
            raise RuntimeError("conmech: callback called although not defined")

        return (w(self.mass, 2, (n, n), "mass"),
                w(self.forces, 3, (n,), "forces"),
                w(self.phi if self.phi is not None else missing, 2, (mh,), "phi"),
                w(self.jac if self.jac is not None else missing, 2, (mh, n), "jac"),
                w(self.gamma if self.gamma is not None else missing, 3, (mh,), "gamma"),
                w(self.nh if self.nh is not None else missing, 2, ((mn, n), (mn,)), "nh"),
                w(self.nh_gamma if self.nh_gamma is not None else missing, 3, (mn,),
                  "nh_gamma"))


def _finite(value, name, low=0.0, low_open=False, allow_inf=False):
    v = _real_number(value, name)
    if np.isnan(v) or (np.isinf(v) and not (allow_inf and v > 0)):
        raise ValueError(f"{name} must be finite, got {v}")
    if v < low or (low_open and v == low):
        raise ValueError(f"{name} must be {'>' if low_open else '>='} {low}, got {v}")
    return v


def _int(value, name, low=1, high=2**31 - 1):
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer, got {type(value).__name__}")
    if not low <= int(value) <= high:
        raise ValueError(f"{name} must be in [{low}, {high}], got {value}")
    return int(value)


def solve(system: str | NativeConstrained | ConstrainedSystem, t_span: Sequence[float],
          q0: ArrayLike | None = None, v0: ArrayLike | None = None, method: str = "DOP853",
          projection: str | None = None, t_eval: ArrayLike | None = None,
          rtol: float = 1e-8, atol: float = 1e-10, params: Sequence[float] = (),
          first_step: float | None = None, max_step: float = np.inf, max_steps: int = 1000000,
          every: int = 1, alpha: float = 5.0, beta: float = 5.0, proj_tol: float = 1e-14,
          proj_max_iter: int = 10,
          events: Callable[..., float] | Sequence[Callable[..., float]] | None = None,
          dae_index: int | None = None) -> ConstrainedResult:
    """Integrate a constrained mechanical system.

    Parameters
    ----------
    system : str, NativeConstrained (built-in or compiled) or ConstrainedSystem
        A built-in (name, with ``params``) or a system of Python callables.
    t_span : (t0, tf)
    q0, v0 : array_like, optional
        Initial coordinates and velocities (built-ins: their default state if omitted).
        They are projected onto the constraints first; ``dq0``/``dv0`` say how far.
    method : "RK4" (fixed step ``first_step``), "DOPRI5", "DOP853" (default), "VERNER98",
        "RATTLE" or "Radau"
        RATTLE: the symplectic constrained integrator for holonomic constraints (fixed
        step ``first_step``, deliberately: a variable step destroys the symplecticity and
        the bounded energy error, see the integrators guide; constraints solved to
        round-off every step; rtol and atol are not used; a t_eval point between grid
        points is reached by a side step, so every output is on the manifold). Radau: Radau IIA (order 5,
        adaptive, rtol/atol) on a differential-algebraic form of the equations (see
        ``dae_index``): no drift and no projection; stiff forces and any mass matrix
        M(t, q) welcome; the Jacobian is exact for systems of :mod:`conmech.symbolic`
        (central differences of M, Q and the constraints otherwise). Redundant
        constraints (rows dependent all along the motion, e.g. Bricard's mechanism):
        RATTLE solves its constraint equations in the minimum-norm least-squares sense;
        Radau integrates an independent subset of the rows chosen at t0 (the results,
        residuals and minimum-norm multipliers are those of the full set). A singular
        configuration at t0 (rows dependent there only, e.g. a parallelogram linkage
        flat): Radau raises ValueError before the first step (the projected methods pass
        it).
    projection : "position+velocity" (the default of the explicit methods), "velocity",
        "baumgarte", "none"
        For the explicit methods only (RATTLE and Radau keep the constraints themselves:
        giving a projection with them raises ValueError).
    t_eval : array_like, optional
        Output times (sorted, inside t_span; the steps hit them exactly). Default: every
        accepted step.
    rtol, atol : float
    every : int
        Project every ``every`` accepted steps.
    alpha, beta : float
        Baumgarte parameters.
    proj_tol, proj_max_iter :
        Position projection: target max |phi| and simplified Newton iterations.
    dae_index : 2 or 3, optional (Radau only)
        2 (default): the stabilised index-2 form of Gear, Gupta and Leimkuhler, y = [q, v,
        lambda, mu] (q and v to order 5, both constraint levels at every step); 3: the
        index-3 form of the Bari test set, y = [q, v, a, lambda], with RADAU5's index-aware
        error scaling (q to order 5, v to order 3; the velocity constraints hold to the
        tolerance only). bench/results/bari.md compares them.
    events : callable ``event(t, q, v) -> float`` or a list of them, optional
        Zero crossings are located (SciPy's conventions: attributes ``terminal`` (bool)
        and ``direction``); the result gets ``t_events``, ``q_events``, ``v_events``
        (lists per event) and, after a terminal event, ``status`` 1 with the run ending
        at the event (t_eval points after it are dropped). The explicit methods locate a
        crossing by Brent's method on the dense output of the step, then project the
        event state like the steps (with "position+velocity" or "velocity"; not with
        "none" or "baumgarte"): event states on the constraints to ``proj_tol``, the event
        function zero there to the integration tolerance. RATTLE locates a crossing by
        Brent's method on its side step from the grid point before it (event states on
        the constraints to round-off, event times of the method's order 2); Radau on its
        dense output (to the tolerance).

    Returns
    -------
    ConstrainedResult

    Raises
    ------
    ValueError, TypeError
        On bad input (the message names the argument); ValueError also when the loops
        of a mechanism (a symbolic tree with ``loops=``) cannot close at q0: the message
        names the loop (its joint, bodies and points) and the residual.
    """
    if isinstance(system, str):
        system = BuiltinConstrained(system, params)
    elif not isinstance(system, (NativeConstrained, ConstrainedSystem)):
        raise TypeError("system must be a built-in name, conmech.constrained.builtin(...) or "
                        "a ConstrainedSystem")
    n = system.n
    if not isinstance(method, str) or method not in _METHODS:
        raise ValueError(f"method must be one of {sorted(_METHODS)}, got {method!r}")
    implicit = method in ("RATTLE", "Radau", "RADAU5")
    if projection is None:
        projection = "position+velocity"
    elif implicit:
        raise ValueError(f"projection: method={method!r} keeps the constraints itself (no "
                         f"projection applies); got projection={projection!r}")
    if projection not in PROJECTIONS:
        raise ValueError(f"projection must be one of {sorted(PROJECTIONS)}, got "
                         f"{projection!r}")
    if dae_index is None:
        dae_index = 2
    elif method not in ("Radau", "RADAU5"):
        raise ValueError(f"dae_index applies to method='Radau' only (got method={method!r})")
    elif isinstance(dae_index, (bool, np.bool_)) or dae_index not in (2, 3):
        raise ValueError(f"dae_index must be 2 (the stabilised index-2 form) or 3 (the "
                         f"index-3 form), got {dae_index!r}")
    try:
        t0, tf = (float(x) for x in t_span)
    except (TypeError, ValueError) as exc:
        raise ValueError("t_span must be a pair of numbers (t0, tf)") from exc
    if not (np.isfinite(t0) and np.isfinite(tf)):
        raise ValueError("t_span must be finite")
    if q0 is None or v0 is None:
        if not isinstance(system, NativeConstrained):
            raise ValueError("q0 and v0 are required for a user-defined system")
        dq, dv = system.initial_state()
        q0 = dq if q0 is None else q0
        v0 = dv if v0 is None else v0
    for name, a in (("q0", q0), ("v0", v0)):
        if np.asarray(a).dtype.kind not in "biuf":
            raise TypeError(f"{name} must be an array of real numbers")
    q0 = np.array(q0, dtype=float).ravel()
    v0 = np.array(v0, dtype=float).ravel()
    if q0.size != n:
        raise ValueError(f"q0 must have {n} elements, got {q0.size}")
    if v0.size != n:
        raise ValueError(f"v0 must have {n} elements, got {v0.size}")
    if not (np.all(np.isfinite(q0)) and np.all(np.isfinite(v0))):
        raise ValueError("q0 and v0 must be finite")
    rtol = _finite(rtol, "rtol")
    atol = _finite(atol, "atol")
    if rtol > 1.0:
        raise ValueError(f"rtol must be <= 1, got {rtol}")
    if rtol == 0.0 and atol == 0.0:
        raise ValueError("rtol and atol must not both be zero")
    if first_step is not None:
        first_step = _finite(first_step, "first_step", low_open=True)
    if method in ("RK4", "RATTLE") and first_step is None:
        raise ValueError(f"first_step (the fixed step) is required for {method}")
    if method == "RATTLE" and system.n_nh:
        raise ValueError("RATTLE handles holonomic constraints only (the system has "
                         f"n_nh = {system.n_nh} non-holonomic ones)")
    max_step = _finite(max_step, "max_step", low_open=True, allow_inf=True)
    max_steps = _int(max_steps, "max_steps")
    every = _int(every, "every")
    proj_max_iter = _int(proj_max_iter, "proj_max_iter", 1, 10000)
    proj_tol = _finite(proj_tol, "proj_tol", low_open=True)
    if proj_tol >= 1.0:
        raise ValueError(f"proj_tol must be < 1, got {proj_tol}")
    alpha = _finite(alpha, "alpha")
    beta = _finite(beta, "beta")
    if t_eval is None:
        t_ev = np.zeros(0)
    else:
        try:
            t_ev = np.array(t_eval, dtype=float).ravel()
        except (TypeError, ValueError):
            raise TypeError("t_eval must be an array of real numbers") from None
        if not np.all(np.isfinite(t_ev)):
            raise ValueError("t_eval must be finite")
        lo, hi = min(t0, tf), max(t0, tf)
        if np.any(t_ev < lo) or np.any(t_ev > hi):
            raise ValueError("t_eval values must lie in t_span")
        d = np.diff(t_ev) * np.sign(tf - t0)
        if np.any(d <= 0):
            raise ValueError("t_eval must be strictly monotonic in the direction of "
                             "integration (sorted, no repeated values)")
    settings = first_crossing_events(events, "constrained.solve")
    ne = len(settings)
    ev_dir = np.array([d for _, _, d in settings] or [0], dtype=np.intc)
    ev_term = np.array([int(c > 0) for _, c, _ in settings] or [0], dtype=np.intc)
    ev_guard = Guard()
    ev_out = {}

    def events_cb(t, y):
        g = np.zeros(max(ne, 1))
        if ev_guard.failed:
            return g * np.nan
        try:
            for i, (fun, _, _) in enumerate(settings):
                r = fun(t, y[:n].copy(), y[n:].copy())
                if r is None:
                    raise ValueError(f"events[{i}] returned None; expected a number")
                g[i] = float(as_result(r, (), f"events[{i}]"))
                if not np.isfinite(g[i]):
                    raise ValueError(f"events[{i}] returned {g[i]} at t = {t}; expected a "
                                     "finite number")
        except Exception as exc:  # kept and re-raised after the Fortran run
            ev_guard.fail(exc)
            return g * np.nan
        return g

    def evstore(ev_t, ev_q, ev_v, ev_id, n_, nev):
        ev_out.update(t=np.array(ev_t), q=np.array(ev_q), v=np.array(ev_v),
                      id=np.array(ev_id))

    iopt = np.array([PROJECTIONS[projection], int(every), int(proj_max_iter), int(max_steps),
                     int(dae_index)], dtype=np.intc)
    mstep = float(max_step) if np.isfinite(max_step) else np.finfo(float).max
    ropt = np.array([float(first_step or 0.0), mstep, float(alpha), float(beta),
                     float(proj_tol)])
    out = {}

    def store(t, q, v, acc, lam, reac, cm, rp, rv, en, pw, n_, mm, nt):
        lam = np.array(lam)
        out.update(t=np.array(t), q=np.array(q), v=np.array(v), a=np.array(acc), lam=lam,
                   reaction=np.array(reac), reactions=np.array(cm) * lam[:, None, :],
                   res_pos=np.array(rp), res_vel=np.array(rv), energy=np.array(en),
                   power=np.array(pw))

    common = dict(n=n, t_span=np.array([t0, tf]), q0=q0, v0=v0, method=_METHODS[method],
                  rtol=float(rtol), atol=float(atol), iopt=iopt, ropt=ropt,
                  neval=t_ev.size, t_eval=t_ev if t_ev.size else _PAD, ne=ne,
                  ev_dir=ev_dir, ev_term=ev_term)
    if isinstance(system, NativeConstrained):
        guard = None
        sargs = (*system._flat_args(), 0) + (_unused_callback,) * 7 + (0, 0, 0, 0, 0, 0)
    else:
        guard = Guard()
        sargs = ("", 0, _PAD, 0, _NO_SPEC, 1, *system._callbacks(guard),
                 int(system.jac is not None), int(system.gamma is not None),
                 int(system.nh_gamma is not None), int(system.rheonomic), system.n_hol,
                 system.n_nh)
    stats, moved, info, message = _conmech.flat_constrained(*sargs, store, events_cb,
                                                            evstore, **common)
    if guard is not None:
        guard.check()
    ev_guard.check()
    message = message_text(message)
    info = int(info)
    if info == BAD_INPUT:
        raise ValueError(message)
    if info < 0 and message.startswith("inconsistent initial position"):
        # a mechanism whose loops cannot close at q0: its model says which loop (a bad
        # input, not a failed integration)
        try:
            model = model_of(system)
        except TypeError:           # not a generated system: no loops to name
            model = None
        err = model.closure_error(system, q0, t0) if model is not None else None
        if err is not None:
            raise err
    m = system.n_hol + system.n_nh
    if not out:
        out = dict(t=np.zeros(0), q=np.zeros((n, 0)), v=np.zeros((n, 0)),
                   a=np.zeros((n, 0)), lam=np.zeros((max(m, 1), 0)), reaction=np.zeros((n, 0)),
                   reactions=np.zeros((max(m, 1), n, 0)),
                   res_pos=np.zeros(0), res_vel=np.zeros(0), energy=np.zeros(0),
                   power=np.zeros(0))
    out["lam"] = out["lam"][:m]
    out["reactions"] = out["reactions"][:m]
    out["accelerations"] = out["a"]
    if isinstance(system, ConstrainedSystem) and system.energy is not None:
        out["energy"] = np.array([float(system.energy(t, q.copy(), v.copy()))
                                  for t, q, v in zip(out["t"], out["q"].T, out["v"].T)])
    res = ConstrainedResult(out)
    res.update(nfev=int(stats[0]), naccept=int(stats[1]), nreject=int(stats[2]),
               nproj=int(stats[3]), proj_iter=int(stats[4]), rank=int(stats[5]),
               proj_iter_max=int(stats[6]),
               dq0=float(moved[0]), dv0=float(moved[1]), status=0 if info >= 0 else -1,
               message=message, success=info >= 0, info=info)
    if ne:
        ids = ev_out.get("id", np.zeros(0, dtype=int))
        sel = [ids == k + 1 for k in range(ne)]
        res.update(t_events=[ev_out["t"][s_] if ev_out else np.zeros(0) for s_ in sel],
                   q_events=[ev_out["q"][:, s_].T if ev_out else np.zeros((0, n))
                             for s_ in sel],
                   v_events=[ev_out["v"][:, s_].T if ev_out else np.zeros((0, n))
                             for s_ in sel])
        if info == 1:
            res["status"] = 1
    return res


def plot_trajectory(res, coords=(0, 1), ax=None, **kwargs):
    """Plot q[coords[1]] against q[coords[0]] of a result (matplotlib); returns the axes."""
    import matplotlib.pyplot as plt
    if ax is None:
        _, ax = plt.subplots()
    i, j = coords
    ax.plot(res.q[i], res.q[j], **kwargs)
    ax.set_xlabel(f"q{i + 1}")
    ax.set_ylabel(f"q{j + 1}")
    ax.set_aspect("equal", adjustable="datalim")
    return ax


def plot_drift(results, ax=None, velocity=False):
    """Constraint drift max|phi| (or max|C v + c0| with ``velocity``) against t, on a log
    scale, for a dict {label: result} (e.g. with and without projection)."""
    import matplotlib.pyplot as plt
    if ax is None:
        _, ax = plt.subplots()
    key = "res_vel" if velocity else "res_pos"
    for label, r in results.items():
        ax.semilogy(r.t, np.maximum(r[key], 1e-17), label=label)
    ax.set_xlabel("t")
    ax.set_ylabel("max |C v + c0|" if velocity else "max |phi|")
    ax.legend()
    return ax
