"""Periodic orbits by Newton's method on single shooting, multiple shooting or orthogonal
collocation (general and symmetric), each checked by independent integrations; multipliers
from the segment transfer matrices by the periodic eigenvalue method, with error
estimates."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from .. import _conmech
from ..ivp.solve import solve_ivp
from .._core.native import NativeSystem
from .._core.validate import (_callback, _check_dim, _count, _no_jac_for_builtin, _real,
                              _state, _system_args, _tols)
from .._core.checks import RTOL_FLOOR
from .._core.result import Record
from .._core.status import raise_status
from .variational import stm_integrator

class PeriodicOrbit(Record):
    """Result of the orbit solvers: y0, period, monodromy (the formed product of the
    segment STMs, for reference), multipliers (complex, from the segments by the periodic
    eigenvalue method, never eig of the formed product), multiplier_error (an estimate of
    each multiplier's absolute error), accuracy (the largest multiplier_error relative to
    max(1, |mu|)), stable (every |mu| <= 1 + stable_tol, stable_tol = max(1e-9, ten times the
    error estimate of the multipliers near the unit circle)), stability_index (4 x 4 only:
    (trace M - 2)/2, trace of the formed monodromy), residual (the true residual of the
    equations at the result, from independent integrations: per segment/mesh interval for
    multiple shooting and collocation), iterations, njev (calls of a Python ``jac``),
    method, nodes and node_times (the segment or mesh nodes over the shooting span; None
    for single shooting)."""

    __slots__ = ("y0", "period", "monodromy", "multipliers", "stability_index", "residual",
                 "iterations", "njev", "method", "multiplier_error", "accuracy", "stable",
                 "stable_tol", "nodes", "node_times")

    @property
    def exponents(self):
        return np.log(self.multipliers.astype(complex))/self.period

    def __repr__(self):
        return f"PeriodicOrbit(period={self.period!r}, y0={self.y0.tolist()!r})"


_METHODS = {"single": 1, "multiple": 2, "collocation": 3}


def _method_options(method, segments, degree, intervals, adapt, integrator_code):
    if not isinstance(method, str) or method not in _METHODS:
        raise ValueError(f"method must be one of {sorted(_METHODS)}, got {method!r}")
    segments = _count(segments, "segments", 1, 100000)
    degree = _count(degree, "degree", 1, 8)
    intervals = _count(intervals, "intervals", 2, 100000)
    adapt = _count(adapt, "adapt", 0, 20)
    iopt = np.array([_METHODS[method], segments, degree, intervals, adapt, integrator_code],
                    dtype=np.int32)
    nk = {1: 1, 2: segments + 1, 3: intervals + 1}[_METHODS[method]]
    return iopt, nk


def stable_tolerance(err, mu):
    """The tolerance of |mu| <= 1 + tol: max(1e-9, ten times the largest error estimate of a
    multiplier near the unit circle, 1/2 <= |mu| <= 2)."""
    a = np.abs(np.asarray(mu))
    near = (a >= 0.5) & (a <= 2.0)
    e = np.asarray(err, dtype=float)[near]
    return float(max(1e-9, 10.0*float(np.max(e)) if e.size else 0.0))


def _orbit(system, y0, period, kind, mode, free, targets, free_time, period_factor, rtol,
           atol, max_iter, jac=None, method="single", segments=8, degree=4, intervals=40,
           adapt=2, integrator="DOP853"):
    y0 = _state(y0)
    _check_dim(system, y0)
    period = _real(period, "period", 0.0, low_open=True)
    period_factor = _real(period_factor, "period_factor", 0.0, low_open=True)
    rtol, atol = _tols(rtol, atol)
    max_iter = _count(max_iter, "max_iter", 1, 10000)
    _no_jac_for_builtin(system, jac)
    shooting_system, code = stm_integrator(system, integrator)
    iopt, nk = _method_options(method, segments, degree, intervals, adapt, code)
    try:
        fr = np.asarray(free).ravel()
        tg = np.asarray(targets).ravel()
    except (TypeError, ValueError):
        raise TypeError("free and targets must be sequences of integers") from None
    for nm, a in (("free", fr), ("targets", tg)):
        if a.size and a.dtype.kind not in "iu":
            raise TypeError(f"{nm} must hold integers (state indices)")
    if np.any(fr < 0) or np.any(fr >= y0.size) or np.any(tg < 0) or np.any(tg >= y0.size):
        raise ValueError("free and targets must be state indices in range(len(y0))")
    fr = np.ascontiguousarray(fr.astype(np.int32) + 1)
    tg = np.ascontiguousarray(tg.astype(np.int32) + 1)
    nfree, ntg = fr.size, tg.size
    if kind == 2 and (nfree == 0 or ntg == 0):
        raise ValueError("free and targets must not be empty")
    if kind == 2 and len(set(fr.tolist())) != nfree:
        raise ValueError("free must not repeat an index")
    nun = nfree + bool(free_time)
    if kind == 2 and (nun < ntg or (nun > ntg and method != "single")):
        raise ValueError(
            f"symmetric_orbit: {nfree + bool(free_time)} unknowns ({nfree} free components"
            f"{' + the time' if free_time else ''}) for {ntg} targets: symmetric shooting "
            f"needs as many unknowns (free components, and the time if free_time) as "
            f"targets")
    fr = fr if nfree else np.ones(1, np.int32)
    tg = tg if ntg else np.ones(1, np.int32)
    args = (y0, period, kind, mode, nfree, fr, ntg, tg, int(bool(free_time)),
            period_factor, rtol, atol, max_iter, iopt, nk)
    njev = 0
    g, sargs = _system_args(shooting_system, y0.size, y0, 0.0, jac)
    out = _conmech.flat_po(*sargs, *args)
    if g is not None:
        g.check()
        njev = g.count("jac")
    (y0o, po, mono, mr, mi, merr, accuracy, deflated, nodes, node_times, nnodes, residual,
     iterations, info, message) = out
    if info != 0:
        raise_status(info, message)
    mono = np.array(mono)
    if not (np.all(np.isfinite(mono)) and np.all(np.isfinite(y0o)) and np.isfinite(po)):
        raise RuntimeError("the orbit or its monodromy is not finite")
    y0o = np.array(y0o)
    nnodes = int(nnodes)
    nodes = np.array(nodes[:, :nnodes]).T.copy() if nnodes else None
    node_times = np.array(node_times[:nnodes]) if nnodes else None
    residual = _true_orbit_residual(system, y0o, float(po), kind, tg[:ntg] - 1,
                                    period_factor, rtol, atol, nodes, node_times)
    mu = np.asarray(mr) + 1j*np.asarray(mi)
    merr = np.array(merr)
    tol = stable_tolerance(merr, mu)
    return PeriodicOrbit(y0=y0o, period=float(po), monodromy=mono, multipliers=mu,
                         multiplier_error=merr, accuracy=float(accuracy),
                         stable=bool(np.all(np.abs(mu) <= 1.0 + tol)), stable_tol=tol,
                         stability_index=0.5*(np.trace(mono) - 2.0) if mono.shape == (4, 4)
                         else None, residual=float(residual), iterations=int(iterations),
                         njev=njev, method=method, nodes=nodes, node_times=node_times)


#: An orbit is accepted only if an independent integration from the returned y0 closes to
#: max(ORBIT_RESIDUAL_TOL, 1e3 max(rtol, atol)) max(1, |y0|).
ORBIT_RESIDUAL_TOL = 1e-8


def _true_orbit_residual(system, y0, period, kind, targets, period_factor, rtol, atol,
                         nodes=None, node_times=None):
    """The residual of the orbit's equations after Newton's last step, from fresh
    integrations (Newton's own test used the residual before that step). Single shooting:
    max|y(T) - y0| (general), or max|y_targets(T/period_factor)| (symmetric). Multiple
    shooting and collocation: each segment (mesh interval) integrated from its node, the
    largest miss of the next node, and the closing conditions (y0 at the end, or the
    targets). RuntimeError if too big."""
    tau = period if kind == 1 else period/period_factor
    if nodes is None:
        starts, spans = [y0], [(0.0, tau)]
    else:
        starts = list(nodes[:-1])
        spans = list(zip(node_times[:-1], node_times[1:]))
    res = 0.0
    for j, (y, span) in enumerate(zip(starts, spans)):
        # rtol at SciPy's floor at least: the value the integrator runs with anyway, and
        # no warning about a solve_ivp call the user did not make
        r = solve_ivp(system, span, y, method="DOP853", rtol=max(rtol, RTOL_FLOOR), atol=atol,
                      max_steps=10**6)
        if not r.success:
            raise RuntimeError(f"the orbit found could not be checked: {r.message}")
        y1 = r.y[:, -1]
        if nodes is not None:
            res = max(res, float(np.max(np.abs(y1 - nodes[j + 1]))))
            y1 = nodes[j + 1]
        if j == len(starts) - 1:
            res = max(res, float(np.max(np.abs(y1 - y0) if kind == 1
                                        else np.abs(y1[targets]))))
    scale = max(1.0, float(np.max(np.abs(y0 if nodes is None else nodes))))
    tol = max(ORBIT_RESIDUAL_TOL, 1e3*max(rtol, atol))*scale
    if not res <= tol:
        raise RuntimeError(f"Newton stopped on a state that is not periodic to the "
                           f"tolerance: true residual {res:.3g} > {tol:.3g}")
    return res


_METHOD_DOC = """
    ``method``: "single" (single shooting, the default), "multiple" (multiple shooting over
    ``segments`` segments: one STM per segment, the block-bordered Newton system solved by a
    structured elimination, never a dense solve; for unstable or long orbits) or
    "collocation" (orthogonal collocation at ``degree`` Gauss points on ``intervals`` mesh
    intervals, the mesh adapted ``adapt`` times by equidistribution as in AUTO; a mesh that
    does not resolve the orbit raises RuntimeError saying so). The multipliers come from
    the segments' (or intervals') transfer matrices by the periodic QR algorithm, the flow
    direction deflated: for a Hamiltonian system mu_min mu_max = 1 and the trivial pair
    hold to the integration error even when |mu_max| is 1e9.

    ``integrator``: "DOP853" (the default) or "TAYLOR", the integrator of the shooting
    segments and their state transition matrices (single and multiple shooting, and the
    monodromy of a collocation orbit): Taylor's method on the variational system's own
    recurrences, for a system compiled by :mod:`conmech.symbolic` (ValueError otherwise).
    The orbit's residual is checked by DOP853 either way."""


def periodic_orbit(system: Any, y0: ArrayLike, period: float, fixed_period: bool = False,
                   rtol: float = 1e-12, atol: float = 1e-12, max_iter=30,
                   jac=None, *, method: str = "single", segments: int = 8, degree: int = 4,
                   intervals: int = 40, adapt: int = 2,
                   integrator: str = "DOP853") -> PeriodicOrbit:
    """Newton's method for a periodic orbit from the guess (y0, period), with the phase
    condition f(y0_guess) . (y0 - y0_guess) = 0. The period is an unknown unless
    ``fixed_period``. Raises ValueError for a start at an equilibrium, RuntimeError when the
    Newton matrix is singular (an orbit that is not isolated, e.g. a conservative family:
    use :func:`symmetric_orbit` or fix the period) or Newton does not converge. ``jac``:
    exact Jacobian of a Python system.
    """
    return _orbit(system, y0, period, 1, 2 if fixed_period else 1, [], [], False, 1.0,
                  rtol, atol, max_iter, jac, method, segments, degree, intervals, adapt,
                  integrator)


def symmetric_orbit(system: Any, y0: ArrayLike, free: Sequence[int], targets: Sequence[int],
                    period: float, period_factor: float = 2.0, free_time: bool = False,
                    rtol=1e-12, atol=1e-12, max_iter=30, jac=None, *,
                    method: str = "single", segments: int = 8, degree: int = 4,
                    intervals: int = 40, adapt: int = 2,
                    integrator: str = "DOP853") -> PeriodicOrbit:
    """Symmetric shooting: y0 on the symmetry line (its fixed components as given), the
    components ``free`` (0-based) unknown, the components ``targets`` of the state at
    tau = period/period_factor must vanish (2: half period, 4: quarter period for two
    perpendicular symmetry lines); tau is unknown too if ``free_time``. The unknowns
    (free components, and tau if free) must be at least as many as the targets, and as
    many for multiple shooting and collocation (a ValueError names both counts; more
    unknowns than targets is a family, of which single shooting's minimum-norm Newton
    step picks a member). ``jac``: exact Jacobian of a Python system. The multipliers are those of
    the full period (the rest of it integrated from the end of the shooting span).
    """
    return _orbit(system, y0, period, 2, 1, free, targets, free_time, period_factor, rtol,
                  atol, max_iter, jac, method, segments, degree, intervals, adapt,
                  integrator)


periodic_orbit.__doc__ += _METHOD_DOC
symmetric_orbit.__doc__ += _METHOD_DOC
