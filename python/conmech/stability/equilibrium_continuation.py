"""Continuation of equilibria in a parameter, their folds and Hopf points
(conmech_equilibrium_continuation), the first Lyapunov coefficient at a Hopf point
(conmech_hopf) and the branch of periodic orbits born there."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from .. import _conmech
from .._core.callback import Guard, as_result
from .._core.native import _NO_SPEC, _PAD, NativeSystem, _unused_callback
from .._core.validate import _check_dim, _count, _msg, _real, _state
from .continuation import Branch, BranchRecord, _param_index, branch_points, continuation
from .._core.result import Record
from .._core.status import raise_status

__all__ = ["EquilibriumBranch", "EquilibriumSpecialPoint", "HopfNormalForm",
           "equilibrium_continuation", "first_lyapunov_coefficient", "hopf_orbits"]

_KIND = {1: "fold", 2: "Hopf"}
_CRIT = {1: "supercritical", 2: "subcritical", 3: "degenerate"}
_REASON = {0: "located", 1: "the corrector failed inside the bracket",
           2: "the iterations ran out before the tolerances were met"}


class HopfNormalForm(Record):
    """The normal-form data of a Hopf point (:func:`first_lyapunov_coefficient`): omega
    (the pair +-i omega), re_lambda (the real part of that pair at the point), l1 (first
    Lyapunov coefficient, Kuznetsov's normalisation <q, q> = 1, <p, q> = 1), l1_error (its
    error estimate), scale (the size of the terms of l1), criticality ('supercritical':
    l1 < 0, 'subcritical': l1 > 0, 'degenerate': |l1| not distinguishable from 0),
    q (A q = i omega q), adjoint (A^T p = -i omega p), exact_jacobian (the forms came from
    differences of an analytic Jacobian)."""

    __slots__ = ("omega", "re_lambda", "l1", "scale", "l1_error", "criticality", "q",
                 "adjoint", "exact_jacobian")

    @property
    def period(self):
        """2 pi / omega: the period of the orbits born at the point."""
        return 2.0*np.pi/self.omega

    def __repr__(self):
        return (f"HopfNormalForm(omega={self.omega!r}, l1={self.l1!r}, "
                f"criticality={self.criticality!r})")


class EquilibriumSpecialPoint(Record):
    """A special point of an :class:`EquilibriumBranch`: kind ('fold' or 'Hopf'), index
    (between the branch points index and index + 1), p, y (an equilibrium: its
    ``residual`` max|f| is that of the returned state), eigenvalues, located (the test
    function met its tolerance, or its bracket ``locate_tol``, at a corrected point),
    reason (why not, when not), test (the test function there: the parameter component of
    the tangent at a fold, the real part of the critical pair at a Hopf point), bracket
    (the last bracket in arclength). Hopf points also carry omega, period (2 pi/omega),
    l1, l1_error, l1_scale, criticality ('supercritical', 'subcritical', 'degenerate'), q
    and adjoint (see :class:`HopfNormalForm`)."""

    __slots__ = ("kind", "index", "p", "y", "eigenvalues", "located", "reason", "test",
                 "bracket", "residual", "omega", "l1", "l1_error", "l1_scale", "criticality",
                 "q", "adjoint", "param")

    @property
    def period(self):
        return 2.0*np.pi/self.omega if self.omega else None

    def __repr__(self):
        extra = f", criticality={self.criticality!r}" if self.kind == "Hopf" else ""
        return (f"EquilibriumSpecialPoint({self.kind!r}, p={self.p!r}, "
                f"located={self.located}{extra})")


class EquilibriumBranch(BranchRecord):
    """A branch of equilibria from :func:`equilibrium_continuation`.

    Arrays over the points: p, y (N, n), eigenvalues (N, n) complex, n_unstable
    (eigenvalues with Re > 0), stable (n_unstable == 0), tests (N, 3: fold = parameter
    component of the tangent, Hopf = real part of the complex pair nearest the imaginary
    axis (nan if there is none), sign of prod_{i<j} (lambda_i + lambda_j)), residual
    (max|f| at each point), iterations; special (list of
    :class:`EquilibriumSpecialPoint`); success, status, message (a branch that stopped
    early keeps its points: success False, the message names the parameter); param."""

    __slots__ = ("p", "y", "eigenvalues", "n_unstable", "stable", "tests", "residual",
                 "iterations", "special", "status", "message", "param")


def _param_rhs(system, n, y0, p0):
    """The guarded callback fun(t, y, p) for f2py (probed once at (0, y0, p0))."""
    if not callable(system):
        raise TypeError("system must be a conmech.systems.NativeSystem or a callable "
                        "fun(t, y, p)")
    as_result(system(0.0, y0.copy(), float(p0)), (n,), "fun")
    g = Guard()
    cb = g.wrap(lambda t, y, pa: system(t, y, float(pa[0])), 3, (n,), "fun")

    def rhs(t, y, p):
        return cb(t, y, np.array([p], dtype=float))
    return g, rhs


def _builtin_args(system, param, p0):
    if param is None:
        raise ValueError("param (name or index of the continuation parameter) is needed")
    ip = _param_index(system, param)
    params = np.array(system.params, dtype=float)
    if p0 is not None:
        params[ip] = _real(p0, "p0")
    names = system.param_names or tuple(f"p{i}" for i in range(params.size))
    return ip, params, names[ip]


def equilibrium_continuation(system: Any, y0: ArrayLike, param: str | int | None = None,
                             p0: float | None = None, *, direction: int = 1,
                             ds: float = 0.01, ds_min: float = 1e-8, ds_max: float = 0.1,
                             p_range=(-np.inf, np.inf), max_points: int = 200,
                             tol: float = 1e-12, res_tol: float = 1e-10, max_iter: int = 10,
                             locate: bool = True, locate_tol: float = 1e-12,
                             test_tol: float = 1e-13, l1_tol: float = 1e-6,
                             t: float = 0.0, jac=None) -> EquilibriumBranch:
    """Pseudo-arclength continuation of the equilibrium near ``y0`` in a parameter, with
    its folds and Hopf points located and the first Lyapunov coefficient at each Hopf point
    (see conmech_equilibrium_continuation and conmech_hopf).

    ``system``: a built-in or compiled system (``param`` = the parameter's name or index;
    it starts from the system's value, or ``p0``) or a callable ``fun(t, y, p)`` (``p0``
    required; finite-difference Jacobian). ``direction``: +1/-1, the first step towards
    larger/smaller p. The branch ends after ``max_points`` points or on the bound of
    ``p_range`` (the last point is then the equilibrium at the bound). ``jac``: the exact
    Jacobian df/dy of a callable, ``jac(t, y, p)`` (the p-derivative stays a difference).
    Each point is an equilibrium to ``res_tol`` (max|f|); a special point is ``located``
    when its test function met ``test_tol`` (a Hopf point: relative to max(1, |lambda|)) or its bracket
    ``locate_tol`` at a corrected equilibrium, else it carries the best corrected
    equilibrium of its bracket and the reason. A Hopf point is ``degenerate`` when |l1| <=
    max(l1_tol * scale, l1_error). Raises ValueError on bad input and RuntimeError when
    ``y0`` is not near an equilibrium (Newton at fixed p fails) or the start is a fold; a
    branch that stops later is returned with success False and a message.
    """
    y0 = _state(y0)
    _check_dim(system, y0)
    n = y0.size
    for name, v in (("ds", ds), ("ds_min", ds_min), ("ds_max", ds_max), ("tol", tol),
                    ("res_tol", res_tol), ("locate_tol", locate_tol), ("test_tol", test_tol),
                    ("l1_tol", l1_tol)):
        _real(v, name, 0.0, low_open=True)
    if ds_max < ds_min:
        raise ValueError("ds_max must be >= ds_min")
    max_points = _count(max_points, "max_points", 1)
    max_iter = _count(max_iter, "max_iter", 1, 1000)
    try:
        lo, hi = (float(v) for v in p_range)
    except (TypeError, ValueError):
        raise TypeError("p_range must be a pair (p_min, p_max)") from None
    if not lo < hi:
        raise ValueError("p_range must have p_min < p_max")
    ropt = np.array([ds, ds_min, ds_max, max(lo, -1e300), min(hi, 1e300), tol, res_tol,
                     locate_tol, test_tol, l1_tol, _real(t, "t")], dtype=float)
    iopt = np.array([max_points, 1 if direction >= 0 else -1, max_iter, bool(locate)],
                    dtype=np.int32)
    if jac is not None and not callable(jac):
        raise TypeError("jac must be a callable jac(t, y, p) returning df/dy, or None")
    if isinstance(system, NativeSystem):
        if jac is not None:
            raise ValueError("jac: a built-in or compiled system has its own Jacobian")
        ip, params, pname = _builtin_args(system, param, p0)
        if not lo <= params[ip] <= hi:
            raise ValueError(f"the start value {pname} = {params[ip]:g} is outside p_range")
        name, _, _, nspec, spec = system._flat_args()
        sargs = (name, params.size, params, nspec, spec, ip + 1, _unused_callback,
                 _unused_callback, 0, 0.0)
    else:
        if p0 is None:
            raise ValueError("p0 (the start value of the parameter) is needed for a callable")
        p0 = _real(p0, "p0")
        if not lo <= p0 <= hi:
            raise ValueError(f"the start value p0 = {p0:g} is outside p_range")
        g, rhs = _param_rhs(system, n, y0, p0)
        if jac is None:
            sargs = ("", 0, _PAD, 0, _NO_SPEC, 0, rhs, _unused_callback, 1, p0)
        else:
            as_result(jac(0.0, y0.copy(), float(p0)), (n, n), "jac")
            cbj = g.wrap(lambda tt, y, pa: jac(tt, y, float(pa[0])), 3, (n, n), "jac")

            def jrhs(tt, y, p):
                return cbj(tt, y, np.array([p], dtype=float))
            sargs = ("", 0, _PAD, 0, _NO_SPEC, 0, rhs, jrhs, 2, p0)
    out = _conmech.flat_eq_continuation(*sargs, y0, ropt, iopt, max_points)
    if not isinstance(system, NativeSystem):
        g.check()
        pname = param if isinstance(param, str) else "p"
    (npts, pp, ys, wr, wi, psi, nunst, res, iters, nsp, spi, spr, sp_y, sp_wr, sp_wi, sp_q,
     sp_a, info, message) = out
    k = branch_points(npts, info, message)
    eig = (np.asarray(wr)[:, k] + 1j*np.asarray(wi)[:, k]).T.copy()
    tests = np.array(psi[:, k]).T.copy()
    has_pair = np.any(np.asarray(wi)[:, k] > 0, axis=0)
    tests[~has_pair, 1] = np.nan
    nun = np.array(nunst[k], dtype=int)
    special = []
    for j in range(int(nsp)):
        kind, index, loc, reason, crit = (int(v) for v in spi[:, j])
        p_, test, bracket, resid, omega, l1, l1s, l1e = (float(v) for v in spr[:, j])
        hopf = kind == 2 and crit != 0
        special.append(EquilibriumSpecialPoint(
            kind=_KIND.get(kind, "unknown"), index=index - 1, p=p_, y=np.array(sp_y[:, j]),
            eigenvalues=np.asarray(sp_wr[:, j]) + 1j*np.asarray(sp_wi[:, j]),
            located=bool(loc), reason=_REASON.get(reason, "unknown"), test=test,
            bracket=bracket, residual=resid, omega=omega if kind == 2 else None,
            l1=l1 if hopf else None, l1_error=l1e if hopf else None,
            l1_scale=l1s if hopf else None, criticality=_CRIT.get(crit) if hopf else None,
            q=(np.asarray(sp_q[:n, j]) + 1j*np.asarray(sp_q[n:, j])) if hopf else None,
            adjoint=(np.asarray(sp_a[:n, j]) + 1j*np.asarray(sp_a[n:, j])) if hopf else None,
            param=pname))
    return EquilibriumBranch(p=np.array(pp[k]), y=np.array(ys[:, k]).T.copy(),
                             eigenvalues=eig, n_unstable=nun, stable=nun == 0, tests=tests,
                             residual=np.array(res[k]), iterations=np.array(iters[k], int),
                             special=special, status=int(info), message=_msg(message),
                             param=pname)


def first_lyapunov_coefficient(system: Any, y: ArrayLike, p: float | None = None,
                               param: str | int | None = None, t: float = 0.0,
                               l1_tol: float = 1e-6) -> HopfNormalForm:
    """The first Lyapunov coefficient at the equilibrium ``y`` whose Jacobian has a pair
    +-i omega (Kuznetsov's formula with the multilinear forms by extrapolated differences:
    see conmech_hopf). ``system``: a built-in or compiled system (``param``/``p`` set one
    of its parameters first, optional) or a callable ``fun(t, y, p)`` with ``p``. The real
    part of the pair at ``y`` is returned (``re_lambda``): the formula assumes it is 0
    (a located Hopf point). Raises ValueError when the Jacobian has no complex pair."""
    y = _state(y, "y")
    _check_dim(system, y)
    n = y.size
    t = _real(t, "t")
    l1_tol = _real(l1_tol, "l1_tol", 0.0, low_open=True)
    if isinstance(system, NativeSystem):
        params = np.array(system.params, dtype=float)
        if p is not None:
            if param is None:
                raise ValueError("param is needed with p for a built-in system")
            params[_param_index(system, param)] = _real(p, "p")
        name, _, _, nspec, spec = system._flat_args()
        sargs = (name, params.size, params if params.size else _PAD, nspec, spec, -1,
                 _unused_callback, _unused_callback, 0, 0.0)
    else:
        if p is None:
            raise ValueError("p (the parameter value) is needed for a callable fun(t, y, p)")
        p = _real(p, "p")
        g, rhs = _param_rhs(system, n, y, p)
        sargs = ("", 0, _PAD, 0, _NO_SPEC, 0, rhs, _unused_callback, 1, p)
    out, q, adj, info, message = _conmech.flat_hopf(*sargs, t, y, l1_tol)
    if not isinstance(system, NativeSystem):
        g.check()
    if info != 0:
        raise_status(info, message)
    omega, re_l, l1, scale, err, crit, exact = (float(v) for v in out)
    return HopfNormalForm(omega=omega, re_lambda=re_l, l1=l1, scale=scale, l1_error=err,
                          criticality=_CRIT.get(int(crit)),
                          q=np.asarray(q[:n]) + 1j*np.asarray(q[n:]),
                          adjoint=np.asarray(adj[:n]) + 1j*np.asarray(adj[n:]),
                          exact_jacobian=bool(exact))


def hopf_orbits(system: Any, branch: EquilibriumBranch, point: EquilibriumSpecialPoint,
                param: str | int | None = None, *, amplitude: float = 1e-3,
                **options) -> Branch:
    """The branch of periodic orbits born at a located Hopf point of ``branch`` (from
    :func:`equilibrium_continuation` on the same ``system``/``param``).

    The first orbit comes from the normal form: with mu(p) the real part of the critical
    pair (its slope mu' from the branch points around the Hopf point) and l1 the first
    Lyapunov coefficient, the cycle of amplitude rho (``amplitude`` times max(1, |y_H|); in
    the normal-form coordinate z = <p, y - y_H>, <q, q> = 1) lies at
    p - p_H = -l1 omega rho^2 / mu' and is
    y_H + 2 rho Re(q e^(i omega t)) to first order, with the period 2 pi / omega. From that
    guess :func:`~conmech.stability.continuation` corrects the orbit at that parameter and
    continues it away from the Hopf point (general shooting of an autonomous system;
    ``param`` defaults to the branch's parameter; the other options as for continuation).
    Raises ValueError at a degenerate Hopf point (l1
    not distinguishable from 0: the side on which the cycles exist is not decided by the
    normal form) or a point that is not a located Hopf point."""
    if not isinstance(branch, EquilibriumBranch):
        raise TypeError("branch must be the EquilibriumBranch on which the Hopf point was "
                        "located")
    if not isinstance(point, EquilibriumSpecialPoint) or point.kind != "Hopf":
        raise ValueError("point must be a 'Hopf' special point of the branch")
    if not any(point is s for s in branch.special):
        raise ValueError("point must be one of branch.special")
    if not point.located:
        raise ValueError(f"the Hopf point at {point.param} = {point.p:.12g} was not located "
                         f"({point.reason}): no periodic branch is started from it")
    if point.criticality is None:
        raise ValueError("the first Lyapunov coefficient at this Hopf point is not available")
    if point.criticality == "degenerate":
        raise ValueError(f"degenerate Hopf point at {point.param} = {point.p:.12g}: l1 = "
                         f"{point.l1:.3g} is not distinguishable from 0 (error "
                         f"{point.l1_error:.3g}); the normal form does not decide on which "
                         "side of the point the cycles exist")
    amplitude = _real(amplitude, "amplitude", 0.0, low_open=True)
    amplitude *= max(1.0, float(np.max(np.abs(point.y))))
    if param is None and isinstance(system, NativeSystem):
        param = branch.param
    for bad in ("p0", "free", "targets", "in_period", "conservative", "_switch", "_tangent",
                "fixed_period", "autonomous", "direction"):
        if bad in options:
            raise ValueError(f"{bad} is not an option of hopf_orbits")
    i = point.index
    mu = branch.tests[:, 1]
    if not (0 <= i < len(branch) - 1 and np.isfinite(mu[i]) and np.isfinite(mu[i + 1])
            and branch.p[i + 1] != branch.p[i]):
        raise ValueError("the branch points around the Hopf point do not give the slope of "
                         "the critical pair")
    dmu = (mu[i + 1] - mu[i])/(branch.p[i + 1] - branch.p[i])
    if not dmu != 0.0:
        raise ValueError("the critical pair crosses the imaginary axis with zero speed")
    dp = -point.l1*point.omega*amplitude**2/dmu
    p_start = point.p + dp
    y_start = point.y + 2.0*amplitude*np.real(point.q)
    period = 2.0*np.pi/point.omega
    return continuation(system, y_start, period, param=param, p0=p_start,
                        direction=1 if dp > 0 else -1, **options)
