"""Simple branch points of equilibrium families and the switch onto the crossing branch.

Along a branch of equilibria x(s) = (y(s), p(s)) of F(y, p) = 0 (F: R^(n+1) -> R^n) the
Jacobian J = [F_y F_p] has the one-dimensional kernel spanned by the tangent t. At a fold
the tangent turns in p but the bordered matrix

    B(s) = [J; t^T]                      ((n + 1) x (n + 1))

stays regular; at a *simple branch point* two branches cross, J loses rank (its kernel
becomes two-dimensional) and det B changes sign (Keller 1977; Kuznetsov, Elements of
Applied Bifurcation Theory, 3rd ed., sect. 10.2.2; Allgower and Georg, sect. 8.1). The
test function is tau(s) = det B(s) with t oriented along the branch (t . dx/ds > 0),
divided by |J|_F^n (t is a unit vector), so that its size reads as a relative distance
from singularity.

A sign change of tau between two points of a branch is located by the Illinois variant of
regula falsi in the arclength of the chord between them, each trial point corrected onto
the branch by Newton's method on [F = 0, chord . (x - x_trial) = 0]. The point is
``located`` when the bracket is below ``locate_tol`` (relative) or tau vanishes to
``test_tol``, and its residual max|F| is the corrected equilibrium's.

Branch switching: at the located point the kernel of J is spanned by t_1 (the known
branch's tangent) and t_2 (orthogonal to t_1, the right singular vector of the second
smallest singular value). A step ``ds`` along t_2, corrected by Newton with the step
direction's hyperplane as the extra equation, lands on the other branch whenever its
tangent is not t_1 (a transversal crossing: pitchfork or transcritical); the
continuation is started there, away from the branch point. This is the orthogonal
complement predictor (Allgower and Georg, sect. 8.2), not the solution of the algebraic
bifurcation equation; the result is checked (the new point must not lie on the old
branch) and a switch that falls back on the old branch raises RuntimeError.
"""
from __future__ import annotations

from typing import Any, Callable  # noqa: F401 (annotations)

import numpy as np

from .. import _conmech
from .._core.native import NativeSystem
from .._core.validate import _real
from .continuation import _param_index
from .equilibrium_continuation import (EquilibriumBranch, EquilibriumSpecialPoint,
                                       equilibrium_continuation)

__all__ = ["equilibrium_branch_points", "switch_equilibrium_branch"]

_H = np.finfo(float).eps**(1/3)


def _fun_jac(system, branch, param, jac, t):
    """F(y, p) and J(y, p) = [F_y F_p] (n x (n+1)) of the branch's system."""
    if isinstance(system, NativeSystem):
        if jac is not None:
            raise ValueError("jac: a built-in or compiled system has its own Jacobian")
        ip = _param_index(system, branch.param if param is None else param)
        base = np.array(system.params, dtype=float)
        name, np_, _, nspec, spec = system._flat_args()

        def ev(y, p):
            pa = base.copy()
            pa[ip] = p
            f, jy, analytic, info, message = _conmech.flat_evaluate_ode(
                name, np_, pa, nspec, spec, t=t, y=np.ascontiguousarray(y, dtype=float))
            if info != 0:
                raise RuntimeError(f"the system could not be evaluated: "
                                   f"{bytes(message).decode(errors='replace').strip()}")
            return np.array(f), (np.array(jy) if analytic else None)
    else:
        if not callable(system):
            raise TypeError("system must be a conmech.systems.NativeSystem or a callable "
                            "fun(t, y, p)")
        if jac is not None and not callable(jac):
            raise TypeError("jac must be a callable jac(t, y, p) -> (n, n) or None")

        def ev(y, p):
            f = np.asarray(system(t, y.copy(), float(p)), dtype=float).ravel()
            jy = None
            if jac is not None:
                jy = np.asarray(jac(t, y.copy(), float(p)), dtype=float)
                if jy.shape != (y.size, y.size) or not np.all(np.isfinite(jy)):
                    raise ValueError(f"jac must return a finite ({y.size}, {y.size}) array, "
                                     f"got {jy.shape}")
            return f, jy

    def fun(x):
        return ev(x[:-1], x[-1])[0]

    def jacobian(x):
        y, p = x[:-1], x[-1]
        n = y.size
        out = np.empty((n, n + 1))
        _, jy = ev(y, p)
        cols = range(n + 1) if jy is None else [n]
        if jy is not None:
            out[:, :n] = jy
        for j in cols:
            h = _H*max(1.0, abs(x[j]))
            e = np.zeros(n + 1)
            e[j] = h
            out[:, j] = (fun(x + e) - fun(x - e))/(2*h)
        return out
    return fun, jacobian


def _kernel(j):
    """The orthonormal right singular vectors of J (n x (n+1)), smallest singular value
    last, and the singular values."""
    _, s, vt = np.linalg.svd(j)
    return vt, s


def _tau(j, t):
    """det [J; t^T] / |J|_F^n: t is a unit vector, so |tau| <= 1, and tau is the product
    of the singular values of J relative to its size."""
    b = np.vstack([j, t])
    scale = max(float(np.linalg.norm(j)), 1e-300)**j.shape[0]
    return float(np.linalg.det(b)/scale)


def _tangent(j, orient):
    vt, _ = _kernel(j)
    t = vt[-1]
    return t if t @ orient >= 0 else -t


def _correct(fun, jacobian, x0, direction, tol, max_iter=20):
    """Newton on [F(x) = 0, direction . (x - x0) = 0]; (x, converged)."""
    x = x0.copy()
    d = direction/np.linalg.norm(direction)
    scale = max(1.0, float(np.max(np.abs(x0))))
    fscale = None
    for _ in range(max_iter):
        f = fun(x)
        j = jacobian(x)
        if fscale is None:
            fscale = max(1.0, float(np.max(np.abs(j))))
        r = np.concatenate([f, [d @ (x - x0)]])
        # a point that already solves the equations is accepted as it is: at the branch
        # point itself the bordered matrix is singular and no step is needed
        if np.max(np.abs(f)) <= tol*fscale*scale and abs(r[-1]) <= tol*scale:
            return x, True
        # least squares: the minimum-norm step stays small where the matrix is nearly
        # singular (next to a branch point)
        dx = np.linalg.lstsq(np.vstack([j, d]), -r, rcond=None)[0]
        if not np.all(np.isfinite(dx)):
            return x, False
        x = x + dx
        if np.max(np.abs(dx)) <= tol*scale:
            return x, True
    return x, False


def equilibrium_branch_points(system: Any, branch: EquilibriumBranch, *, param=None,
                              jac: Callable | None = None, t: float = 0.0,
                              locate_tol: float = 1e-13, test_tol: float = 1e-14,
                              tol: float = 1e-14, max_iter: int = 60) -> list:
    """The simple branch points of a branch of equilibria (module notes): every sign
    change of tau = det [J; t^T] between consecutive points, located. Returns
    :class:`EquilibriumSpecialPoint` s of kind 'branch point' (index, p, y, eigenvalues,
    located, reason, test = tau at the point, bracket = the final arclength bracket
    relative to the chord, residual = max|F|). ``system`` and ``param`` as for
    :func:`equilibrium_continuation` (the branch's own parameter by default); ``jac``:
    the exact Jacobian dF/dy of a callable, ``jac(t, y, p)``."""
    if not isinstance(branch, EquilibriumBranch):
        raise TypeError("branch must be an EquilibriumBranch from equilibrium_continuation")
    for nm, v in (("locate_tol", locate_tol), ("test_tol", test_tol), ("tol", tol)):
        _real(v, nm, 0.0, 1e-3, low_open=True)
    t = _real(t, "t")
    fun, jacobian = _fun_jac(system, branch, param, jac, t)
    xs = np.column_stack([branch.y, branch.p])
    if len(xs) < 2:
        return []
    taus = []
    for i, x in enumerate(xs):
        chord = xs[min(i + 1, len(xs) - 1)] - xs[max(i - 1, 0)]
        taus.append(_tau(jacobian(x), _tangent(jacobian(x), chord)))
    found = []
    for i in range(len(xs) - 1):
        if not taus[i]*taus[i + 1] < 0:
            continue
        xa, xb = xs[i], xs[i + 1]
        chord = xb - xa
        ta, tb = taus[i], taus[i + 1]
        sa, sb = 0.0, 1.0
        side = 0
        best = (xa, ta) if abs(ta) < abs(tb) else (xb, tb)
        located, reason = False, "the iterations ran out before the tolerances were met"
        for _ in range(max_iter):
            s = (sa*tb - sb*ta)/(tb - ta)
            xt, ok = _correct(fun, jacobian, xa + s*chord, chord, tol)
            if not ok:
                reason = "the corrector failed inside the bracket"
                break
            ts = _tau(jacobian(xt), _tangent(jacobian(xt), chord))
            if abs(ts) <= abs(best[1]):
                best = (xt, ts)
            if abs(ts) <= test_tol:
                located = True
                break
            if ts*ta < 0:
                sb, tb = s, ts
                if side == -1:
                    ta *= 0.5
                side = -1
            else:
                sa, ta = s, ts
                if side == 1:
                    tb *= 0.5
                side = 1
            if sb - sa <= locate_tol:
                located = True
                break
        x, ts = best
        j = jacobian(x)
        ev = np.linalg.eigvals(j[:, :-1])
        found.append(EquilibriumSpecialPoint(
            kind="branch point", index=i, p=float(x[-1]), y=x[:-1].copy(), eigenvalues=ev,
            located=located, reason="located" if located else reason, test=ts,
            bracket=float(sb - sa), residual=float(np.max(np.abs(fun(x)))),
            param=branch.param))
    return found


def switch_equilibrium_branch(system: Any, branch: EquilibriumBranch,
                              point: EquilibriumSpecialPoint, *, ds: float = 0.01,
                              side: int = 1, param=None, jac: Callable | None = None,
                              t: float = 0.0, tol: float = 1e-13,
                              **kwargs) -> EquilibriumBranch:
    """The branch of equilibria crossing ``branch`` at its located branch point ``point``
    (from :func:`equilibrium_branch_points`), continued by
    :func:`equilibrium_continuation` (``kwargs``: its options; ``p0``/``direction`` are
    set here) from the point a step ``ds`` along the second kernel direction (``side``
    +1/-1: which half of the crossing branch). RuntimeError when the corrected point falls
    back on the known branch."""
    if not isinstance(branch, EquilibriumBranch):
        raise TypeError("branch must be an EquilibriumBranch from equilibrium_continuation")
    if not isinstance(point, EquilibriumSpecialPoint) or point.kind != "branch point":
        raise ValueError("point must be a 'branch point' from equilibrium_branch_points")
    if not point.located:
        raise ValueError(f"point: the branch point was not located ({point.reason}); no "
                         "branch is switched onto from it")
    ds = _real(ds, "ds", 0.0, low_open=True)
    if side not in (1, -1):
        raise ValueError("side must be +1 or -1")
    for bad in ("p0", "direction"):
        if bad in kwargs:
            raise ValueError(f"{bad} is set by switch_equilibrium_branch")
    fun, jacobian = _fun_jac(system, branch, param, jac, _real(t, "t"))
    x0 = np.concatenate([point.y, [point.p]])
    i = min(point.index, len(branch) - 2)
    chord = np.concatenate([branch.y[i + 1] - branch.y[i], [branch.p[i + 1] - branch.p[i]]])
    vt, _ = _kernel(jacobian(x0))
    # the kernel: the two smallest singular directions; t1 the known branch's tangent
    k2 = vt[-2:]
    t1 = k2.T @ (k2 @ chord)
    t1 /= np.linalg.norm(t1)
    rest = [v - (v @ t1)*t1 for v in k2]
    t2 = max(rest, key=np.linalg.norm)
    t2 = side*t2/np.linalg.norm(t2)
    xn, ok = _correct(fun, jacobian, x0 + ds*t2, t2, tol)
    if not ok:
        raise RuntimeError(f"switch_equilibrium_branch: Newton did not converge from the "
                           f"branch point at p = {point.p:.15g} (step ds = {ds:g}: try a "
                           "smaller ds)")
    # not back on the known branch: the new point is off the known branch's line
    off = xn - x0
    if np.linalg.norm(off - (off @ t1)*t1) <= 0.1*ds:
        raise RuntimeError("switch_equilibrium_branch: the corrected point lies on the "
                           "known branch (no transversal branch found at this point)")
    dp = xn[-1] - x0[-1]
    direction = 1 if dp >= 0 else -1
    pname = branch.param if param is None else param
    return equilibrium_continuation(system, xn[:-1], pname, p0=float(xn[-1]),
                                    direction=direction, **kwargs)
