"""Pseudo-arclength continuation of periodic orbits with special points located
(conmech_continuation), and the switch onto a period-doubled branch."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from .. import _conmech
from ..systems import BuiltinSystem
from ._validate import _check_dim, _count, _msg, _raise, _real, _state

_SPECIAL = {1: "fold", 2: "branch point", 3: "period doubling", 4: "Neimark-Sacker"}


class SpecialPoint:
    """A located special point of a branch: kind ('fold', 'branch point', 'period
    doubling', 'Neimark-Sacker'), index (between branch points index and index + 1), p,
    period, y0, multipliers, stability_index."""

    __slots__ = ("kind", "index", "p", "period", "y0", "multipliers", "stability_index")

    def __init__(self, **kw):
        for k in self.__slots__:
            setattr(self, k, kw.get(k))

    def __repr__(self):
        return f"SpecialPoint({self.kind!r}, p={self.p!r}, index={self.index})"


class Branch:
    """A branch of periodic orbits from :func:`continuation`.

    Arrays over the points: p (parameter), period, y0 (N, n), multipliers (N, n) complex,
    stability_index (S = (trace M - 2)/2 for a conservative planar orbit, else the largest
    |mu| of the non-trivial multipliers), stable (bool), tests (N, 4: fold = parameter
    component of the tangent, branch point, period doubling, Neimark-Sacker), residual,
    iterations, energy (if an energy function was given); special (list of SpecialPoint);
    success, status, message (a branch that stopped early keeps its points: success False
    and the message names the parameter value); kernel_ratio (a branch from
    :func:`switch_branch_point`: the second smallest singular value of the shooting
    Jacobian at the branch point over the third, small for a genuine branch point)."""

    __slots__ = ("p", "period", "y0", "multipliers", "stability_index", "stable", "tests",
                 "residual", "iterations", "energy", "special", "status", "message",
                 "param", "conservative", "kernel_ratio")

    def __init__(self, **kw):
        for k in self.__slots__:
            setattr(self, k, kw.get(k))

    @property
    def success(self):
        return self.status == 0

    def __len__(self):
        return len(self.p)

    def __repr__(self):
        return (f"Branch(points={len(self.p)}, p=[{self.p[0]:.6g} .. {self.p[-1]:.6g}], "
                f"special={[(s.kind, round(s.p, 12)) for s in self.special]}, "
                f"message={self.message!r})")


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


def continuation(system: Any, y0: ArrayLike, period: float, param: str | int | None = None,
                 p0: float | None = None, *, direction=1, ds=0.01, ds_min=1e-8, ds_max=0.1,
                 p_range=(-np.inf, np.inf), max_points=200, autonomous=True, fixed_period=False,
                 conservative=False, free=None, targets=None, free_time=False,
                 period_factor=2.0, rtol=1e-11, atol=1e-11, tol=1e-10, res_tol=1e-8,
                 max_iter=12, locate=True, locate_tol=1e-11, energy=None, in_period=False,
                 _switch=0, _tangent=None) -> Branch:
    """Pseudo-arclength continuation of the periodic orbit through ``y0`` (period guess
    ``period``) in a parameter, with its special points located (see conmech_continuation).

    ``system``: a built-in system (``param`` = the parameter's name or index; it starts
    from the system's value, or ``p0``) or a callable ``fun(t, y, p)`` (``p0`` required).
    General shooting (unknowns y0, period (unless ``fixed_period``), p; phase condition for
    ``autonomous`` systems) or symmetric shooting (``free``, ``targets``: 0-based indices of
    the free initial components and of the components of y(tau) that vanish; tau =
    period/period_factor, free if ``free_time``). ``conservative``: a second trivial
    multiplier (energy); continue at a fixed period, or with ``in_period`` along the family
    of a conservative system without a parameter: the period is the continued quantity
    (``p`` holds it; ``param``/``p0`` are not needed and a callable is ``fun(t, y)``).
    ``energy(y, p)``: optional, evaluated along the branch. Raises ValueError on bad input
    and RuntimeError when the start is not a periodic orbit or not isolated; a branch that
    stops later is returned with success False and a message naming the parameter value.
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
    if p0 is not None:
        p0 = _real(p0, "p0")
    direction = _real(direction, "direction")
    if not (isinstance(p_range, (tuple, list, np.ndarray)) and len(p_range) == 2):
        raise TypeError("p_range must be a pair (p_min, p_max)")
    lo, hi = (_real(v, name) if not (isinstance(v, (float, np.floating)) and np.isinf(v))
              else float(v) for v, name in zip(p_range, ("p_range[0]", "p_range[1]")))
    sym = free is not None or targets is not None
    if sym and (free is None or targets is None):
        raise ValueError("symmetric shooting needs both free and targets")
    fr = np.ascontiguousarray(np.asarray(free if sym else [0], dtype=np.int32).ravel() + 1)
    tg = np.ascontiguousarray(np.asarray(targets if sym else [0], dtype=np.int32).ravel() + 1)
    if sym and (fr.size == 0 or tg.size == 0 or fr.min() < 1 or fr.max() > n
                or tg.min() < 1 or tg.max() > n):
        raise ValueError("free and targets must be non-empty state indices in range(len(y0))")
    ropt = np.array([ds, ds_min, ds_max, max(lo, -1e300), min(hi, 1e300), tol, res_tol,
                     rtol, atol, locate_tol, period_factor], dtype=float)
    iopt = np.array([max_points, 1 if direction >= 0 else -1, max_iter, bool(autonomous),
                     bool(fixed_period), bool(conservative), bool(locate), sym,
                     bool(free_time), int(_switch), bool(in_period)], dtype=np.int32)
    if in_period and (sym or not autonomous):
        raise ValueError("in_period is for general shooting of autonomous systems")
    tang = np.zeros(1) if _tangent is None else np.array(_tangent, dtype=float).ravel()
    args = (ropt, iopt, fr.size if sym else 0, fr, tg.size if sym else 0, tg,
            tang.size if _tangent is not None else 0, tang, int(max_points))
    if isinstance(system, BuiltinSystem):
        if param is None and in_period:
            param = 0
        if param is None:
            raise ValueError("param (name or index of the continuation parameter) is needed")
        ip = _param_index(system, param)
        params = np.array(system.params, dtype=float)
        if p0 is not None:
            params[ip] = float(p0)
        name, _, _, nspec, spec = system._flat_args()
        out = _conmech.flat_continuation_builtin(name, params.size, params, nspec, spec,
                                                 ip + 1, y0, period, *args)
        pname = (system.param_names or tuple(f"p{i}" for i in range(params.size)))[ip]
    else:
        if not callable(system):
            raise TypeError("system must be a conmech.systems.BuiltinSystem or a callable "
                            "fun(t, y, p)")
        if p0 is None and in_period:
            p0 = 0.0
        if p0 is None:
            raise ValueError("p0 (the start value of the parameter) is needed for a callable")

        def rhs(t, y, p):
            o = np.asarray(system(t, y) if in_period else system(t, y, p),
                           dtype=float).ravel()
            if o.size != n:
                raise ValueError(f"fun(t, y, p) returned {o.size} values, expected {n}")
            return o
        out = _conmech.flat_continuation_callback(rhs, y0, period, float(p0), *args)
        pname = param if isinstance(param, str) else "p"
    (npts, pp, per, ys, mr, mi, s, psi, res, iters, nsp, sk, si, sp_p, sp_per, sp_y,
     sp_mr, sp_mi, sp_s, info, message) = out
    npts = int(npts)
    if npts == 0:
        _raise(info, message)
    k = slice(0, npts)
    mult = (np.asarray(mr)[:, k] + 1j*np.asarray(mi)[:, k]).T.copy()
    s = np.array(s[k])
    if conservative and n == 4:
        stable = np.abs(s) < 1
    else:
        stable = s < 1
    special = []
    for j in range(int(nsp)):
        special.append(SpecialPoint(kind=_SPECIAL.get(int(sk[j]), "unknown"),
                                    index=int(si[j]) - 1, p=float(sp_p[j]),
                                    period=float(sp_per[j]), y0=np.array(sp_y[:, j]),
                                    multipliers=np.asarray(sp_mr[:, j])
                                    + 1j*np.asarray(sp_mi[:, j]),
                                    stability_index=float(sp_s[j])))
    ys = np.array(ys[:, k]).T.copy()
    pp = np.array(pp[k])
    en = None
    if energy is not None:
        en = np.array([float(energy(y, p)) for y, p in zip(ys, pp)])
    return Branch(p=pp, period=np.array(per[k]), y0=ys, multipliers=mult,
                  stability_index=s, stable=stable, tests=np.array(psi[:, k]).T.copy(),
                  residual=np.array(res[k]), iterations=np.array(iters[k], dtype=int),
                  energy=en, special=special, status=int(info), message=_msg(message),
                  param="period" if in_period else pname, conservative=bool(conservative),
                  kernel_ratio=float(tang[0]) if _switch == 2 else None)

def switch_period_doubling(system: Any, point: SpecialPoint, param: str | int | None = None,
                           **options) -> Branch:
    """Branch switching at a located period doubling: the branch of orbits of twice the
    period that bifurcates at ``point`` (a :class:`SpecialPoint` of kind 'period doubling'
    from :func:`continuation` on the same ``system``/``param``). The first step follows the
    eigenvector of the multiplier -1 (``direction`` picks its sign); the other options as
    for :func:`continuation` (general shooting of an autonomous system)."""
    if not isinstance(point, SpecialPoint) or point.kind != "period doubling":
        raise ValueError("point must be a 'period doubling' SpecialPoint of a Branch")
    for bad in ("free", "targets", "p0", "_switch", "_tangent"):
        if bad in options:
            raise ValueError(f"{bad} is not an option of switch_period_doubling")
    return continuation(system, point.y0, point.period, param=param, p0=point.p,
                        _switch=1, **options)


