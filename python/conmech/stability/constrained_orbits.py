"""Periodic orbits of holonomically constrained systems, on their constraint manifold.

A system in excessive coordinates, M(q) q'' = Q(q, q') + G(q)^T lambda, phi(q) = 0 (m
independent constraints on n coordinates; see :mod:`conmech.constrained`), moves on the
manifold phi(q) = 0, G(q) q' = 0 of dimension 2k, k = n - m. Its periodic orbits are
computed in a chart of that manifold by coordinate partitioning (Wehage and Haug 1982):
k *independent* coordinates q_I are chosen where the constraint Jacobian's block G_D of the
other m (*dependent*) coordinates is best conditioned (QR with column pivoting of G at a
reference point), and

    q_D(q_I) solves phi(q_I, q_D) = 0 (Newton),   v_D = -G_D^{-1} G_I v_I,
    (q_I, v_I)' = (v_I, a_I),   [M G^T; G 0] [a; -lambda] = [Q; gamma]  (KKT system).

The reduced state y = (q_I, v_I) obeys an ordinary differential equation of dimension 2k
whose flow *is* the constrained flow: every orbit solver of :mod:`conmech.stability`
(single and multiple shooting, collocation, continuation) works on it unchanged, and its
2k multipliers are those of the motion on the manifold. The 2m multipliers the
excessive-coordinate flow adds (a Jordan block at 1 per constraint: a state off the
manifold drifts as phi(t) = phi_0 + t phi'_0) belong to no motion and are removed by the
chart, not computed and discarded. A chart covers the region where G_D stays invertible;
an orbit that leaves it raises RuntimeError naming the coordinates (choose another
reference point or ``independent``).

Each orbit is checked on the constrained system itself: (q0, v0) lifted from the chart is
integrated by :func:`conmech.constrained.solve` (position and velocity projection) over
the period, and the closure ``constrained_residual`` must be small.
"""
from __future__ import annotations

from typing import Any, Sequence  # noqa: F401 (annotations)

import numpy as np
import scipy.linalg

from .. import _conmech
from ..mechanics.compiled import evaluate
from ..mechanics.constrained import ConstrainedSystem, NativeConstrained, builtin
from ..mechanics.constrained import solve as _constrained_solve
from .continuation import continuation
from .orbits import periodic_orbit, symmetric_orbit
from .._core.validate import _real, _state
from .._core.result import Record
from .manifold_checks import checked_values as _arr, constraint_jacobian, holonomic_sizes

__all__ = ["ManifoldChart", "ConstrainedOrbit", "ConstrainedBranch",
           "constrained_periodic_orbit", "constrained_symmetric_orbit",
           "constrained_continuation"]


def _evaluator(system):
    """(system, n, m, fun(q, v) -> (M, Q, phi, G, gamma)) of a scleronomic holonomic
    constrained system, G q'' = gamma."""
    if isinstance(system, str):
        system = builtin(system)
    if isinstance(system, NativeConstrained):
        n, m = holonomic_sizes(system, "periodic orbits")
        evaluate(system, 0.0, np.zeros(n), np.zeros(n))      # checks the system once
        name, np_, p, nspec, spec = system._flat_args()
        mn = system.n_nh

        def fun(q, v):      # the flat evaluation directly: this runs in every right-hand side
            mm, qf, _, _, ph, g, gh, _, _, _, info, message = _conmech.flat_evaluate_mech(
                name, np_, p, nspec, spec, kind=1, mh=m, mn=mn, t=0.0,
                q=np.ascontiguousarray(q, dtype=float), v=np.ascontiguousarray(v, dtype=float))
            if info != 0:
                raise RuntimeError(f"the system could not be evaluated: "
                                   f"{bytes(message).decode(errors='replace').strip()}")
            return (np.asarray(mm), np.asarray(qf), np.asarray(ph)[:m],
                    np.asarray(g)[:m].reshape(m, n), np.asarray(gh)[:m])
        return system, n, m, fun
    if isinstance(system, ConstrainedSystem):
        n, m = holonomic_sizes(system, "periodic orbits")
        h1 = np.finfo(float).eps**(1/3)

        def jac(q):
            return constraint_jacobian(system, 0.0, q, m, n)

        def fun(q, v):
            mm = _arr(system.mass(0.0, q), (n, n), "mass(t, q)")
            qf = _arr(system.forces(0.0, q, v), (n,), "forces(t, q, v)")
            ph = _arr(system.phi(0.0, q), (m,), "phi(t, q)")
            g = jac(q)
            if system.gamma is not None:
                gam = _arr(system.gamma(0.0, q, v), (m,), "gamma(t, q, v)")
            else:     # gamma = -v^T phi'' v: the derivative of G along v, by differences
                s = h1*max(1.0, float(np.max(np.abs(q))))/max(float(np.max(np.abs(v))),
                                                              1e-300)
                gam = -((jac(q + s*v) - jac(q - s*v)) @ v)/(2*s) if np.any(v) \
                    else np.zeros(m)
            return mm, qf, ph, g, gam
        return system, n, m, fun
    raise TypeError("system must be a holonomically constrained system: a built-in name, "
                    "conmech.constrained.builtin(...), conmech.systems.pendulum_xy() etc., "
                    "a compiled constrained system or a conmech.constrained."
                    "ConstrainedSystem")


class ManifoldChart:
    """A chart of the constraint manifold by coordinate partitioning (module notes).

    ``ManifoldChart(system, q_ref, independent=None)``: the independent coordinates are
    ``independent`` (k indices) or those left after QR with column pivoting of G(q_ref)
    picks the m best-conditioned dependent ones. Attributes: n, m, k, independent,
    dependent, q_ref. Methods: ``fun(t, y)`` (the reduced vector field, a callable for
    every orbit solver), ``lift(y) -> (q, v)``, ``reduce(q, v) -> y`` (after checking
    (q, v) lies on the manifold) and ``constraint_residual(q, v)``."""

    def __init__(self, system, q_ref, independent=None, tol=1e-15):
        self.system, self.n, self.m, self._fun = _evaluator(system)
        n, m = self.n, self.m
        if m < 1:
            raise ValueError("system has no holonomic constraint: use the orbit solvers "
                             "directly")
        if m >= n:
            raise ValueError("system: the constraints leave no degree of freedom")
        q_ref = _state(q_ref, "q_ref")
        if q_ref.size != n:
            raise ValueError(f"q_ref has {q_ref.size} coordinates; the system has {n}")
        self.tol = _real(tol, "tol", 0.0, 1e-3, low_open=True)
        g = self._fun(q_ref, np.zeros(n))[3]
        if independent is None:
            _, r, piv = scipy.linalg.qr(g, pivoting=True, mode="economic")
            if abs(r[m - 1, m - 1]) <= 1e-10*max(abs(r[0, 0]), 1e-300):
                raise ValueError("q_ref: the constraint Jacobian is rank deficient there "
                                 "(redundant constraints or a singular configuration)")
            dep = np.sort(piv[:m])
            ind = np.array([j for j in range(n) if j not in set(dep.tolist())])
        else:
            try:
                ind = np.asarray(independent).ravel()
            except (TypeError, ValueError):
                raise TypeError("independent must be a sequence of coordinate indices") \
                    from None
            if ind.dtype.kind not in "iu" or ind.size != n - m or len(set(ind.tolist())) \
                    != ind.size or np.any(ind < 0) or np.any(ind >= n):
                raise ValueError(f"independent must be {n - m} distinct coordinate indices "
                                 f"in range({n}), got {list(np.asarray(independent).ravel())}")
            ind = np.sort(ind.astype(int))
            dep = np.array([j for j in range(n) if j not in set(ind.tolist())])
            if np.linalg.cond(g[:, dep]) > 1e10:
                raise ValueError(f"independent: the other coordinates {dep.tolist()} cannot "
                                 "be solved from the constraints at q_ref (singular block)")
        self.independent, self.dependent = ind, dep
        self.k = n - m
        self.q_ref = q_ref.copy()
        self._last = q_ref.copy()
        self.left_chart = None

    def _qfull(self, qi):
        """q with q_I = qi and q_D from phi = 0 by Newton, started at the last solution's
        dependent coordinates (Newton converges quadratically: the start changes the
        result by round-off only), and G(q) there. Converged when max|phi| <= tol
        max(1, |q|) at the current q (so that G is evaluated there, in the same call)."""
        try:
            return self._newton(self._last, qi)
        except RuntimeError:        # a start far off: once more from the reference point
            return self._newton(self.q_ref, qi)

    def _newton(self, start, qi):
        q = start.copy()
        q[self.independent] = qi
        ind, dep = self.independent, self.dependent
        scale = max(1.0, float(np.max(np.abs(q))))
        z = np.zeros(self.n)
        last_step = np.inf
        for _ in range(30):
            _, _, ph, g, _ = self._fun(q, z)
            # phi at round-off, or the last Newton correction at round-off in q
            if np.max(np.abs(ph)) <= self.tol*scale or last_step <= 4e-16*scale:
                self._last = q.copy()
                return q, g
            try:
                dq = np.linalg.solve(g[:, dep], -ph)
            except np.linalg.LinAlgError:
                break
            if not np.all(np.isfinite(dq)) or np.max(np.abs(dq)) > scale:
                break
            q[dep] += dq
            last_step = float(np.max(np.abs(dq)))
        raise RuntimeError(f"the motion leaves the chart: the dependent coordinates "
                           f"{dep.tolist()} cannot be solved from the constraints at the "
                           f"independent coordinates {ind.tolist()} = {np.asarray(qi).tolist()}"
                           " (choose another q_ref or independent)")

    def lift(self, y):
        """(q, v) on the manifold from the reduced state y = (q_I, v_I)."""
        y = np.asarray(y, dtype=float).ravel()
        if y.size != 2*self.k:
            raise ValueError(f"y has {y.size} components; the chart has {2*self.k}")
        k = self.k
        q, g = self._qfull(y[:k])
        v = np.zeros(self.n)
        v[self.independent] = y[k:]
        v[self.dependent] = -np.linalg.solve(g[:, self.dependent],
                                             g[:, self.independent] @ y[k:])
        return q, v

    def constraint_residual(self, q, v):
        """max(|phi(q)|, |G(q) v|)."""
        _, _, ph, g, _ = self._fun(np.asarray(q, float), np.asarray(v, float))
        return float(max(np.max(np.abs(ph)), np.max(np.abs(g @ v))))

    def reduce(self, q, v, tol=1e-8):
        """The reduced state (q_I, v_I) of a state (q, v) on the manifold (ValueError if
        |phi| or |G v| exceeds tol max(1, |q|, |v|), or if it is outside the chart)."""
        q = _state(q, "q0")
        v = _state(v, "v0")
        if q.size != self.n or v.size != self.n:
            raise ValueError(f"q0 and v0 must have {self.n} components, got {q.size} and "
                             f"{v.size}")
        r = self.constraint_residual(q, v)
        if not r <= tol*max(1.0, float(np.max(np.abs(q))), float(np.max(np.abs(v)))):
            raise ValueError(f"q0, v0: the state is not on the constraint manifold "
                             f"(max |phi|, |G v| = {r:.3g})")
        y = np.concatenate([q[self.independent], v[self.independent]])
        q2, _ = self._qfull(y[:self.k])
        if np.max(np.abs(q2 - q)) > 1e-6*max(1.0, float(np.max(np.abs(q)))):
            raise ValueError("q0: the chart's solution of the constraints at these "
                             "independent coordinates is another branch of the manifold "
                             "(choose q_ref near q0)")
        return y

    def fun(self, t, y):
        """The reduced vector field (v_I, a_I) at y = (q_I, v_I)."""
        q, v = self.lift(y)
        mm, qf, _, g, gam = self._fun(q, v)
        n, m = self.n, self.m
        kkt = np.zeros((n + m, n + m))
        kkt[:n, :n] = mm
        kkt[:n, n:] = g.T
        kkt[n:, :n] = g
        a = np.linalg.solve(kkt, np.concatenate([qf, gam]))[:n]
        return np.concatenate([v[self.independent], a[self.independent]])

    def fun_or_nan(self, t, y):
        """``fun``, but NaN outside the chart (the solvers then cut their step or stop
        with a message, as at any non-finite value); ``left_chart`` records it."""
        try:
            return self.fun(t, y)
        except RuntimeError as exc:
            if "leaves the chart" not in str(exc):
                raise
            self.left_chart = str(exc)
            return np.full(2*self.k, np.nan)

    def state_index(self, idx, what):
        """Reduced-state indices of excessive-state indices (0..n-1: q, n..2n-1: v),
        which must be independent coordinates or their velocities."""
        try:
            a = np.asarray(idx).ravel()
        except (TypeError, ValueError):
            raise TypeError(f"{what} must be a sequence of state indices") from None
        if a.size and a.dtype.kind not in "iu":
            raise TypeError(f"{what} must hold integers (indices into [q, v])")
        out = []
        for i in a.tolist():
            if not 0 <= i < 2*self.n:
                raise ValueError(f"{what}: index {i} is not in range(2n) = range({2*self.n})"
                                 " (indices into the excessive state [q, v])")
            j = i % self.n
            if j not in set(self.independent.tolist()):
                raise ValueError(f"{what}: index {i} is a dependent coordinate (or its "
                                 f"velocity); the independent coordinates are "
                                 f"{self.independent.tolist()}: give those, or pass "
                                 "independent= to choose the chart")
            pos = int(np.searchsorted(self.independent, j))
            out.append(pos + (self.k if i >= self.n else 0))
        return out


class ConstrainedOrbit(Record):
    """A periodic orbit on a constraint manifold: q0, v0 (the excessive state at t = 0),
    period, multipliers (the 2k multipliers of the motion on the manifold, from the
    reduced orbit; the 2m constraint directions are removed by the chart, see the module
    notes: ``removed_trivial`` = 2m says how many), multiplier_error, stable, stable_tol,
    residual (the reduced orbit's closure), constrained_residual (the closure of (q0, v0)
    integrated over the period on the constrained system itself), manifold_residual
    (max |phi|, |G v| at (q0, v0)), chart (:class:`ManifoldChart`), reduced (the
    :class:`~conmech.stability.PeriodicOrbit` of the chart's system)."""

    __slots__ = ("q0", "v0", "period", "multipliers", "multiplier_error", "stable",
                 "stable_tol", "residual", "constrained_residual", "manifold_residual",
                 "removed_trivial", "chart", "reduced")

    def __repr__(self):
        return (f"ConstrainedOrbit(period={self.period!r}, q0={self.q0.tolist()!r}, "
                f"v0={self.v0.tolist()!r})")


def _constrained_closure(chart, q0, v0, period, rtol, atol):
    r = _constrained_solve(chart.system, (0.0, period), q0, v0, method="DOP853",
                           rtol=rtol, atol=atol, proj_tol=1e-14)
    if not r.success:
        raise RuntimeError(f"the orbit could not be checked on the constrained system: "
                           f"{r.message}")
    return float(max(np.max(np.abs(r.q[:, -1] - q0)), np.max(np.abs(r.v[:, -1] - v0))))


def _wrap(chart, orb, rtol, atol):
    q0, v0 = chart.lift(orb.y0)
    cres = _constrained_closure(chart, q0, v0, orb.period, max(rtol, 1e-13),
                                max(atol, 1e-13))
    tol = max(1e-7, 1e4*max(rtol, atol))*max(1.0, float(np.max(np.abs(q0))),
                                             float(np.max(np.abs(v0))))
    if not cres <= tol:
        raise RuntimeError(f"the orbit found in the chart does not close on the constrained "
                           f"system: residual {cres:.3g} > {tol:.3g}")
    return ConstrainedOrbit(q0=q0, v0=v0, period=orb.period, multipliers=orb.multipliers,
                            multiplier_error=orb.multiplier_error, stable=orb.stable,
                            stable_tol=orb.stable_tol, residual=orb.residual,
                            constrained_residual=cres,
                            manifold_residual=chart.constraint_residual(q0, v0),
                            removed_trivial=2*chart.m, chart=chart, reduced=orb)


def _chart(system, q0, v0, q_ref, independent):
    q0 = _state(q0, "q0")
    chart = ManifoldChart(system, q0 if q_ref is None else q_ref, independent)
    return chart, chart.reduce(q0, v0)


def constrained_periodic_orbit(system: Any, q0, v0, period: float,
                               fixed_period: bool = False, rtol: float = 1e-12,
                               atol: float = 1e-12, max_iter: int = 30, *,
                               q_ref=None, independent=None, method: str = "single",
                               segments: int = 8, degree: int = 4, intervals: int = 40,
                               adapt: int = 2) -> ConstrainedOrbit:
    """A periodic orbit of a holonomically constrained system through the guess (q0, v0)
    on its manifold (module notes), by :func:`conmech.stability.periodic_orbit` on the
    manifold's chart (``q_ref``, default q0; ``independent`` coordinates, default chosen
    by pivoted QR of G): ``method`` "single", "multiple" or "collocation" as there. A
    conservative system's orbits form families: use :func:`constrained_symmetric_orbit`
    or ``fixed_period``."""
    chart, y0 = _chart(system, q0, v0, q_ref, independent)
    orb = periodic_orbit(chart.fun, y0, period, fixed_period=fixed_period, rtol=rtol,
                         atol=atol, max_iter=max_iter, method=method, segments=segments,
                         degree=degree, intervals=intervals, adapt=adapt)
    return _wrap(chart, orb, rtol, atol)


def constrained_symmetric_orbit(system: Any, q0, v0, free: Sequence[int],
                                targets: Sequence[int], period: float,
                                period_factor: float = 2.0, free_time: bool = False,
                                rtol: float = 1e-12, atol: float = 1e-12,
                                max_iter: int = 30, *, q_ref=None, independent=None,
                                method: str = "single", segments: int = 8, degree: int = 4,
                                intervals: int = 40, adapt: int = 2) -> ConstrainedOrbit:
    """Symmetric shooting (:func:`conmech.stability.symmetric_orbit`) on the constraint
    manifold. ``free`` and ``targets`` index the excessive state [q, v] (0..n-1 the
    coordinates, n..2n-1 their velocities) and must name independent coordinates of the
    chart (ValueError otherwise, listing them)."""
    chart, y0 = _chart(system, q0, v0, q_ref, independent)
    fr = chart.state_index(free, "free")
    tg = chart.state_index(targets, "targets")
    orb = symmetric_orbit(chart.fun, y0, fr, tg, period, period_factor=period_factor,
                          free_time=free_time, rtol=rtol, atol=atol, max_iter=max_iter,
                          method=method, segments=segments, degree=degree,
                          intervals=intervals, adapt=adapt)
    return _wrap(chart, orb, rtol, atol)


class ConstrainedBranch(Record):
    """A family of periodic orbits on a constraint manifold: branch (the
    :class:`~conmech.stability.Branch` of the chart's system: p, period, multipliers,
    special points, ...), q0 and v0 ((N, n): the excessive states of its points), chart."""

    __slots__ = ("branch", "q0", "v0", "chart")

    def __len__(self):
        return len(self.branch)

    def __repr__(self):
        return f"ConstrainedBranch({self.branch!r})"


def constrained_continuation(system: Any, q0, v0, period: float, *, free=None,
                             targets=None, q_ref=None, independent=None,
                             **kwargs) -> ConstrainedBranch:
    """The family of periodic orbits through (q0, v0) on the constraint manifold,
    continued in its period (a conservative system without a parameter:
    :func:`conmech.stability.continuation` with ``in_period=True`` on the chart's system;
    ``free``/``targets`` index [q, v] as in :func:`constrained_symmetric_orbit`; other
    keywords as there: ``ds``, ``max_points``, ``period_range``, ``method``, ...). Where
    the family leaves the chart the branch ends with a message saying so (success
    False), keeping its points."""
    for bad in ("param", "p0", "in_period", "autonomous"):
        if bad in kwargs:
            raise ValueError(f"{bad}: constrained_continuation continues in the period "
                             "(in_period) of an autonomous system")
    chart, y0 = _chart(system, q0, v0, q_ref, independent)
    if free is not None:
        kwargs["free"] = chart.state_index(free, "free")
    if targets is not None:
        kwargs["targets"] = chart.state_index(targets, "targets")
    kwargs.setdefault("conservative", True)
    # outside the chart the field is NaN: the continuation cuts its step there and, if it
    # cannot go on, ends the branch with a message (completed below)
    br = continuation(chart.fun_or_nan, y0, period, in_period=True, **kwargs)
    if br.status != 0 and chart.left_chart is not None:
        br.message = f"{br.message} (a trial left the chart: {chart.left_chart})"
    lifted = [chart.lift(y) for y in br.y0]
    return ConstrainedBranch(branch=br, q0=np.array([a for a, _ in lifted]),
                             v0=np.array([b for _, b in lifted]), chart=chart)
