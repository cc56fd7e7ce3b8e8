"""Pseudo-arclength continuation of periodic orbits with special points located
(conmech_continuation), by single shooting, multiple shooting or collocation, and the switch
onto a period-doubled branch."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from .. import _conmech
from .._core.callback import Guard, as_result
from .._core.native import _NO_SPEC, _PAD, NativeSystem, _unused_callback
from .._core.validate import _check_dim, _count, _msg, _real, _state
from .orbits import _METHODS, stable_tolerance
from .variational import stm_integrator
from .._core.result import Record, StatusRecord
from .._core.status import raise_status

_SPECIAL = {1: "fold", 2: "branch point", 3: "period doubling", 4: "Neimark-Sacker"}
_REASONS = {1: "a trial's corrector failed", 2: "a trial left the branch (another branch "
            "crosses here)", 3: "the iteration limit"}


class SpecialKind(str):
    """The kind of a special point: its name ('fold', 'branch point', 'period doubling',
    'Neimark-Sacker'), which for a conservative planar orbit (4 x 4 monodromy) also reads as
    the stability-index event it is: 'S=+1' for a branch point, 'S=-1' for a period
    doubling (the names conmech.hill uses). ``kind == 'S=+1'`` and ``kind == 'branch
    point'`` are then both true; hashing and str() use the first name."""

    __slots__ = ("alias",)

    def __new__(cls, name, alias=None):
        obj = super().__new__(cls, name)
        obj.alias = alias
        return obj

    def __eq__(self, other):
        return str.__eq__(self, other) or (self.alias is not None and other == self.alias)

    def __ne__(self, other):
        return not self.__eq__(other)

    __hash__ = str.__hash__

    def __repr__(self):
        return (str.__repr__(self) if self.alias is None
                else f"{str.__repr__(self)} ({self.alias})")


class SpecialPoint(Record):
    """A special point of a branch: kind (a :class:`SpecialKind`: 'fold', 'branch point',
    'period doubling', 'Neimark-Sacker'; 'S=+1'/'S=-1' also match for conservative planar
    orbits), index (between branch points index and index + 1), p, period, y0,
    multipliers, stability_index; located (True when the locator converged; False: the
    corrector failed or left the branch, and the point is the computed orbit nearest the
    sign change, never an interpolated state), test (the test function at the point),
    residual (the closure of its orbit by an independent integration: |y(T) - y0| for
    single shooting, the largest miss of a node for multiple shooting and collocation),
    p_bracket (the parameter at the ends of the final bracket around the sign change;
    both on one side of a fold), message."""

    __slots__ = ("kind", "index", "p", "period", "y0", "multipliers", "stability_index",
                 "located", "test", "residual", "p_bracket", "message")

    def __repr__(self):
        loc = "" if self.located else ", not located"
        return f"SpecialPoint({self.kind!r}, p={self.p!r}, index={self.index}{loc})"


class BranchRecord(StatusRecord):
    """What a branch of any kind holds first: the points' parameter values ``p``, the
    ``special`` points and the ``message``; its length is its number of points."""

    __slots__ = ()

    def __len__(self):
        return len(self.p)

    def __repr__(self):
        return (f"{type(self).__name__}(points={len(self.p)}, p=[{self.p[0]:.6g} .. "
                f"{self.p[-1]:.6g}], special={[(s.kind, round(s.p, 12)) for s in self.special]}"
                f", message={self.message!r})")


def branch_points(npts, info, message):
    """The points a flat continuation returned (npts of its arrays' mp) as a slice; none
    (the start itself failed): its status raised."""
    if int(npts) == 0:
        raise_status(info, message)
    return slice(0, int(npts))


class Branch(BranchRecord):
    """A branch of periodic orbits from :func:`continuation`.

    Arrays over the points: p (parameter), period, y0 (N, n), multipliers (N, n) complex
    (periodic eigenvalues of the segment factors), multiplier_error (N, n: their error
    estimates), accuracy (N), stability_index (S = (trace M - 2)/2 for a conservative
    planar orbit, else the largest |mu| of the non-trivial multipliers), stable (bool:
    |S| <= 1 + tol, or every non-trivial |mu| <= 1 + tol), stable_tol (N: that tol, max(1e-9,
    ten times the error estimate of the multipliers near the unit circle)), tests (N, 4:
    fold = parameter component of the tangent, branch point, period doubling,
    Neimark-Sacker), residual, iterations, energy (if an energy function was given);
    special (list of SpecialPoint); success, status, message (a branch that stopped early
    keeps its points: success False and the message names the parameter value); direction
    (+1/-1: the side continued to first); method; kernel_ratio (a branch from
    :func:`switch_branch_point`: the second smallest singular value of the shooting
    Jacobian at the branch point over the third, small for a genuine branch point)."""

    __slots__ = ("p", "period", "y0", "multipliers", "stability_index", "stable", "tests",
                 "residual", "iterations", "energy", "special", "status", "message",
                 "param", "conservative", "kernel_ratio", "multiplier_error", "accuracy",
                 "stable_tol", "direction", "method")


def _param_index(system, param):
    names = system.param_names or tuple(f"p{i}" for i in range(system.params.size))
    if isinstance(param, str):
        if param not in names:
            raise ValueError(f"param {param!r} is not a parameter of '{system.name}' "
                             f"(parameters: {', '.join(names)})")
        return names.index(param)
    if isinstance(param, (int, np.integer)) and 0 <= int(param) < system.params.size:
        return int(param)
    raise ValueError(f"param must be a parameter name or index of '{system.name}'")


def _range(value, name):
    """A pair (low, high) of reals, either end possibly infinite; TypeError/ValueError
    naming the entry otherwise."""
    if not (isinstance(value, (tuple, list, np.ndarray)) and len(value) == 2):
        raise TypeError(f"{name} must be a pair (low, high)")
    lo, hi = (float(v) if isinstance(v, (float, np.floating)) and np.isinf(v)
              else _real(v, f"{name}[{i}]") for i, v in enumerate(value))
    if not lo <= hi:
        raise ValueError(f"{name} must be a pair (low, high) with low <= high")
    return max(lo, -1e300), min(hi, 1e300)


def _stable(s, mu, merr, conservative, n, tol):
    if conservative and n == 4:
        return np.abs(s) <= 1 + tol
    return s <= 1 + tol


def continuation(system: Any, y0: ArrayLike, period: float, param: str | int | None = None,
                 p0: float | None = None, *, direction=None, ds=0.01, ds_min=1e-8,
                 ds_max=0.1, p_range=(-np.inf, np.inf), max_points=200, autonomous=True,
                 fixed_period=False, conservative=False, free=None, targets=None,
                 free_time=False, period_factor=2.0, rtol=1e-11, atol=1e-11, tol=1e-10,
                 res_tol=1e-8, max_iter=12, locate=True, locate_tol=1e-11, energy=None,
                 in_period=False, period_range=(-np.inf, np.inf),
                 energy_range=(-np.inf, np.inf), method="single", segments=8, degree=4,
                 intervals=40, jac=None, integrator="DOP853", _switch=0,
                 _tangent=None) -> Branch:
    """Pseudo-arclength continuation of the periodic orbit through ``y0`` (period guess
    ``period``) in a parameter, with its special points located (see conmech_continuation).

    ``system``: a built-in system (``param`` = the parameter's name or index; it starts
    from the system's value, or ``p0``) or a callable ``fun(t, y, p)`` (``p0`` required).
    General shooting (unknowns y0, period (unless ``fixed_period``), p; phase condition for
    ``autonomous`` systems) or symmetric shooting (``free``, ``targets``: 0-based indices of
    the free initial components and of the components of y(tau) that vanish; tau =
    period/period_factor, free if ``free_time``; as many unknowns besides p as targets).
    ``conservative``: a second trivial multiplier (energy); continue at a fixed period, or
    with ``in_period`` along the family of a conservative system without a parameter: the
    period is the continued quantity (``p`` holds it; ``param``/``p0`` are not needed and a
    callable is ``fun(t, y)``; general or symmetric shooting).

    ``method``: "single" (default), "multiple" (``segments`` segments) or "collocation"
    (``intervals`` intervals of ``degree`` Gauss points): the same equations discretised
    as a boundary-value problem and solved by a structured Newton; the step ``ds``
    measures the same unknowns (first node, period, parameter) for all three.

    ``integrator``: "DOP853" (the default) or "TAYLOR", the integrator of the orbits and
    their state transition matrices: Taylor's method on the variational system's own
    recurrences, for a system compiled by :mod:`conmech.symbolic` (ValueError otherwise).

    ``jac``: the exact Jacobian df/dy of a callable, ``jac(t, y, p)`` (``jac(t, y)`` with
    ``in_period``), for the state transition matrices instead of differences.

    ``direction``: +1 (towards larger p) or -1; None (default): +1 unless the orbit's
    amplitude shrinks that way to an equilibrium within the branch's reach, then -1 (a
    family born at an equilibrium is followed away from it). ``p_range``,
    ``period_range``, ``energy_range`` (with ``energy``): the branch ends exactly on the
    bound it reaches (the orbit there is computed), or, if that orbit cannot be computed,
    at the last point inside, with a message. ``energy(y, p)``: optional, evaluated along
    the branch. Raises ValueError on bad input (a message naming it: inconsistent
    free/targets counts, a start at an equilibrium) and RuntimeError when the start is not
    a periodic orbit or not isolated; a branch that stops later is returned with success
    False and a message naming the parameter value.
    """
    y0 = _state(y0)
    _check_dim(system, y0)
    n = y0.size
    period = _real(period, "period", 0.0, low_open=True)
    max_points = _count(max_points, "max_points")
    max_iter = _count(max_iter, "max_iter")
    for name, v in (("ds", ds), ("ds_min", ds_min), ("ds_max", ds_max), ("rtol", rtol),
                    ("atol", atol), ("tol", tol), ("res_tol", res_tol),
                    ("locate_tol", locate_tol), ("period_factor", period_factor)):
        _real(v, name, 0.0, low_open=True)
    if not rtol < 1:
        raise ValueError("rtol must be < 1")
    if not isinstance(method, str) or method not in _METHODS:
        raise ValueError(f"method must be one of {sorted(_METHODS)}, got {method!r}")
    shooting_system, code = stm_integrator(system, integrator)
    segments = _count(segments, "segments", 1, 100000)
    degree = _count(degree, "degree", 1, 8)
    intervals = _count(intervals, "intervals", 2, 100000)
    if p0 is not None:
        p0 = _real(p0, "p0")
    if direction is None:
        dirn = 0
    elif _real(direction, "direction") != 0:
        dirn = 1 if direction > 0 else -1
    else:
        raise ValueError("direction must be +1, -1 or None (automatic)")
    lo, hi = _range(p_range, "p_range")
    tlo, thi = _range(period_range, "period_range")
    elo, ehi = _range(energy_range, "energy_range")
    has_range_e = elo > -1e300 or ehi < 1e300
    if has_range_e and energy is None:
        raise ValueError("energy_range needs energy(y, p)")
    if energy is not None and not callable(energy):
        raise TypeError("energy must be a callable energy(y, p)")
    sym = free is not None or targets is not None
    if sym and (free is None or targets is None):
        raise ValueError("symmetric shooting needs both free and targets")
    fr = np.ascontiguousarray(np.asarray(free if sym else [0], dtype=np.int32).ravel() + 1)
    tg = np.ascontiguousarray(np.asarray(targets if sym else [0], dtype=np.int32).ravel() + 1)
    if sym and (fr.size == 0 or tg.size == 0 or fr.min() < 1 or fr.max() > n
                or tg.min() < 1 or tg.max() > n):
        raise ValueError("free and targets must be non-empty state indices in range(len(y0))")
    if sym:
        nun = fr.size + (1 if free_time else 0)
        if nun != tg.size:
            raise ValueError(
                f"continuation: {nun} unknowns besides the parameter ({fr.size} free "
                f"components{' + the time' if free_time else ''}) for {tg.size} targets: "
                "symmetric shooting needs as many unknowns (free components, and the time if "
                "free_time) as targets")
    if in_period and not autonomous:
        raise ValueError("in_period is for autonomous systems")
    if in_period and sym and free_time:
        raise ValueError("in_period continues in the time itself: free_time must be False")
    if _tangent is not None and not _switch:
        # start at a known solution with a given first tangent ([y0, T, p], T if free)
        _switch = 3
    ropt = np.array([ds, ds_min, ds_max, lo, hi, tol, res_tol, rtol, atol, locate_tol,
                     period_factor, tlo, thi, elo, ehi], dtype=float)
    iopt = np.array([max_points, dirn, max_iter, bool(autonomous),
                     bool(fixed_period), bool(conservative), bool(locate), sym,
                     bool(free_time), int(_switch), bool(in_period), _METHODS[method],
                     segments, degree, intervals, bool(has_range_e), code], dtype=np.int32)
    tang = np.zeros(1) if _tangent is None else np.array(_tangent, dtype=float).ravel()
    g = Guard()
    nan = float("nan")

    def en(y, p):
        if g.failed:
            return nan
        try:
            return float(as_result(energy(y.copy(), float(p)), (), "energy"))
        except BaseException as exc:   # noqa: B036 (kept, re-raised by check())
            g.fail(exc)
            return nan
    args = (ropt, iopt, fr.size if sym else 0, fr, tg.size if sym else 0, tg,
            tang.size if _tangent is not None else 0, tang, int(max_points), en)
    if jac is not None and not callable(jac):
        raise TypeError("jac must be a callable jac(t, y, p) (jac(t, y) with in_period) "
                        "returning df/dy, or None")
    if isinstance(system, NativeSystem):
        if jac is not None:
            raise ValueError("jac: a built-in or compiled system has its own Jacobian")
        if param is None and in_period:
            param = 0 if system.params.size else None
        params = np.array(system.params, dtype=float)
        if param is None and in_period:       # no parameter at all: none is continued
            ip, npar = -1, 0
            params = np.zeros(1)
            pname = "period"
        else:
            if param is None:
                raise ValueError("param (name or index of the continuation parameter) is "
                                 "needed")
            ip, npar = _param_index(system, param), params.size
            if p0 is not None:
                params[ip] = float(p0)
            pname = (system.param_names or tuple(f"p{i}" for i in range(params.size)))[ip]
        name, _, _, nspec, spec = shooting_system._flat_args()
        sargs = (name, npar, params, nspec, spec, ip + 1, _unused_callback,
                 _unused_callback, 0, 0.0)
    else:
        if not callable(system):
            raise TypeError("system must be a conmech.systems.NativeSystem or a callable "
                            "fun(t, y, p)")
        if p0 is None and in_period:
            p0 = 0.0
        if p0 is None:
            raise ValueError("p0 (the start value of the parameter) is needed for a callable")
        nans = np.full(n, np.nan)

        def rhs(t, y, p):
            if g.failed:
                return nans
            try:
                o = system(t, y.copy()) if in_period else system(t, y.copy(), float(p))
                return as_result(o, (n,), "fun")
            except BaseException as exc:   # noqa: B036 (kept, re-raised by check())
                g.fail(exc)
                return nans
        if jac is None:
            sargs = ("", 0, _PAD, 0, _NO_SPEC, 0, rhs, _unused_callback, 1, float(p0))
        else:
            nanj = np.full((n, n), np.nan)

            def jrhs(t, y, p):
                if g.failed:
                    return nanj
                try:
                    o = jac(t, y.copy()) if in_period else jac(t, y.copy(), float(p))
                    return as_result(o, (n, n), "jac")
                except BaseException as exc:   # noqa: B036 (kept, re-raised by check())
                    g.fail(exc)
                    return nanj
            sargs = ("", 0, _PAD, 0, _NO_SPEC, 0, rhs, jrhs, 2, float(p0))
        pname = param if isinstance(param, str) else "p"
    out = _conmech.flat_branch(*sargs, y0, period, *args)
    g.check()
    (npts, pp, per, ys, mr, mi, merr, acc, s, psi, res, iters, nsp, sk, si, sp_p, sp_per,
     sp_y, sp_mr, sp_mi, sp_s, sp_loc, sp_test, sp_clo, sp_br, dirout, info, message) = out
    k = branch_points(npts, info, message)
    mult = (np.asarray(mr)[:, k] + 1j*np.asarray(mi)[:, k]).T.copy()
    merr = np.array(merr[:, k]).T.copy()
    s = np.array(s[k])
    tol_pts = np.array([stable_tolerance(e, m) for e, m in zip(merr, mult)])
    stable = _stable(s, mult, merr, conservative, n, tol_pts)
    planar = bool(conservative) and n == 4
    special = []
    for j in range(int(nsp)):
        kind = _SPECIAL.get(int(sk[j]), "unknown")
        alias = {"branch point": "S=+1", "period doubling": "S=-1"}.get(kind) if planar \
            else None
        located = bool(int(sp_loc[j]) % 10)
        reason = _REASONS.get(int(sp_loc[j]) // 10, "")
        special.append(SpecialPoint(
            kind=SpecialKind(kind, alias), index=int(si[j]) - 1, p=float(sp_p[j]),
            period=float(sp_per[j]), y0=np.array(sp_y[:, j]),
            multipliers=np.asarray(sp_mr[:, j]) + 1j*np.asarray(sp_mi[:, j]),
            stability_index=float(sp_s[j]), located=located, test=float(sp_test[j]),
            residual=float(sp_clo[j]), p_bracket=(float(sp_br[0, j]), float(sp_br[1, j])),
            message=("located" if located and not reason else
                     f"located to the bracket p in [{sp_br[0, j]:.12g}, {sp_br[1, j]:.12g}] "
                     f"({reason})" if located else
                     f"not located: {reason} (p in [{sp_br[0, j]:.12g}, "
                     f"{sp_br[1, j]:.12g}]); the point is the computed orbit nearest the sign "
                     f"change, test = {sp_test[j]:.3g}")))
    ys = np.array(ys[:, k]).T.copy()
    pp = np.array(pp[k])
    en_vals = None
    if energy is not None:
        en_vals = np.array([float(energy(y, p)) for y, p in zip(ys, pp)])
    return Branch(p=pp, period=np.array(per[k]), y0=ys, multipliers=mult,
                  multiplier_error=merr, accuracy=np.array(acc[k]), stability_index=s,
                  stable=stable, stable_tol=tol_pts, tests=np.array(psi[:, k]).T.copy(),
                  residual=np.array(res[k]), iterations=np.array(iters[k], dtype=int),
                  energy=en_vals, special=special, status=int(info), message=_msg(message),
                  param="period" if in_period else pname, conservative=bool(conservative),
                  kernel_ratio=float(tang[0]) if _switch == 2 else None,
                  direction=int(dirout), method=method)


def switch_period_doubling(system: Any, point: SpecialPoint, param: str | int | None = None,
                           **options) -> Branch:
    """Branch switching at a located period doubling: the branch of orbits of twice the
    period that bifurcates at ``point`` (a :class:`SpecialPoint` of kind 'period doubling'
    from :func:`continuation` on the same ``system``/``param``). The first step follows the
    eigenvector of the multiplier -1 (``direction`` picks its sign); the other options as
    for :func:`continuation` (general shooting of an autonomous system; ``method`` too)."""
    if not isinstance(point, SpecialPoint) or point.kind != "period doubling":
        raise ValueError("point must be a 'period doubling' SpecialPoint of a Branch")
    for bad in ("free", "targets", "p0", "_switch", "_tangent"):
        if bad in options:
            raise ValueError(f"{bad} is not an option of switch_period_doubling")
    if options.get("direction") is None:
        options["direction"] = 1
    return continuation(system, point.y0, point.period, param=param, p0=point.p,
                        _switch=1, **options)
