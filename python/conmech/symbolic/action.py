"""Hamilton's principle along computed motions: the action S = integral of L dt, its first
variation (which vanishes on a motion for variations with fixed ends) and its second
variation.

For a motion q(t) of a system from :func:`conmech.symbolic.lagrangian_system` and a
variation eta(t) with eta(t0) = eta(t1) = 0,

    dS[eta]  = integral of (dL/dq . eta + dL/dq' . eta') dt,
    d2S[eta] = integral of [eta; eta']^T Hess_(q, q') L [eta; eta'] dt,

evaluated with the compiled dL/dq, dL/dq' and Hessian of L along the solution's dense
output (Gauss-Legendre on every step, :mod:`conmech.symbolic.quadrature`). Integrating
dL/dq' . eta' by parts, dS = integral of (dL/dq - d/dt dL/dq') . eta: it vanishes on a
motion (Hamilton's principle), up to the integration error of the motion. With
non-conservative forces Q the principle reads dS + integral of Q . eta dt = 0
(Lagrange-d'Alembert); :func:`first_variation` reports both parts. The second variation
decides whether the motion minimises the action among nearby paths with the same ends:
positive for short arcs, it changes sign past the first conjugate point (the linearised
pendulum: d2S[sin(pi t/T)] = (T/2)((pi/T)^2 - g/l) m l^2 changes sign at T = pi sqrt(l/g)).
"""
import numpy as np
import sympy as sp

from .._core.result import Record
from .momenta import analysis
from .quadrature import dense_segments, integrate_dense

__all__ = ["action", "first_variation", "second_variation", "Variation", "check_stationary"]


class Variation(Record):
    """Result of :func:`first_variation` / :func:`check_stationary`: ``delta_S`` (the first
    variation of the action), ``virtual_work`` (integral of Q . eta, 0 without
    non-conservative forces), ``residual`` (delta_S + virtual_work: zero on a motion),
    ``scale`` (integral of |dL/dq . eta| + |dL/dq' . eta'| + |Q . eta|, the size of the terms
    that cancel), ``relative`` (|residual| / scale), ``second`` (the second variation when
    computed, else None)."""

    __slots__ = ("delta_S", "virtual_work", "residual", "scale", "relative", "second")

    def __repr__(self):
        return (f"Variation(delta_S={self.delta_S:.3e}, residual={self.residual:.3e}, "
                f"relative={self.relative:.3e}, second={self.second!r})")


def _system_parts(system):
    a = analysis(system)
    return a, np.asarray(system.params, dtype=float)


def action(system, solution, t_span=None):
    """S = integral of L(t, q, q') dt along a dense solution of `system` (a system from
    :func:`lagrangian_system`; solution from ``solve_ivp(..., dense_output=True)``), over
    t_span (default: the whole solution), by Gauss-Legendre quadrature on each step of the
    dense output."""
    a, p = _system_parts(system)
    _check_solution(solution, 2*a.n)
    lib = a.library()
    return integrate_dense(lambda t, y: lib("lagrangian", t, y, p), solution, t_span)


def _check_solution(solution, dim):
    y = getattr(solution, "y", None)
    if y is None or getattr(solution, "t", None) is None:
        raise TypeError("solution must be a solve_ivp result (t, y, sol)")
    if np.asarray(y).shape[0] != dim:
        raise ValueError(f"solution: states of {np.asarray(y).shape[0]} components for a "
                         f"system of {dim} ([q, q'])")
    dense_segments(solution)


def _variation_functions(variation, n):
    """(eta(t) -> (n, m), eta'(t) -> (n, m)) from a variation given as a list of sympy
    expressions in the symbol t (exact derivative), a pair of callables, or one callable
    (derivative by the fourth-order central difference, step 1e-3 max(1, |t|))."""
    if isinstance(variation, (list, tuple, sp.MatrixBase)) and len(variation) == n and \
            all(isinstance(e, (sp.Basic, int, float)) for e in variation):
        exprs = [sp.sympify(e) for e in variation]
        syms = set().union(*(e.free_symbols for e in exprs))
        if len(syms) > 1 or any(s.name != "t" for s in syms):
            raise ValueError("variation: sympy expressions must depend on t only")
        ts = next(iter(syms)) if syms else sp.Symbol("t")
        f = sp.lambdify(ts, sp.Matrix(exprs), modules="numpy")
        fd = sp.lambdify(ts, sp.Matrix([sp.diff(e, ts) for e in exprs]), modules="numpy")

        def eta(t):
            t = np.atleast_1d(t)
            return np.array(np.broadcast_to(np.asarray(f(t), dtype=float).reshape(n, -1),
                                            (n, t.size)))

        def deta(t):
            t = np.atleast_1d(t)
            return np.array(np.broadcast_to(np.asarray(fd(t), dtype=float).reshape(n, -1),
                                            (n, t.size)))
        return eta, deta
    if isinstance(variation, tuple) and len(variation) == 2 and all(map(callable, variation)):
        e0, e1 = variation
        return (lambda t: np.asarray(e0(np.atleast_1d(t)), dtype=float).reshape(n, -1),
                lambda t: np.asarray(e1(np.atleast_1d(t)), dtype=float).reshape(n, -1))
    if callable(variation):
        def eta(t):
            return np.asarray(variation(np.atleast_1d(t)), dtype=float).reshape(n, -1)

        def deta(t):
            t = np.atleast_1d(np.asarray(t, dtype=float))
            h = 1e-3*np.maximum(1.0, np.abs(t))
            return (8*(eta(t + h) - eta(t - h)) - (eta(t + 2*h) - eta(t - 2*h)))/(12*h)
        return eta, deta
    raise TypeError("variation must be n sympy expressions in t, a callable eta(t) -> (n, m), "
                    "or a pair (eta, eta_dot) of callables")


def _ends(solution, t_span):
    ts = dense_segments(solution, t_span)
    return ts[0], ts[-1]


def first_variation(system, solution, variation, t_span=None, second=False):
    """The first variation of the action along `solution` in the direction `variation`
    (eta with fixed ends: eta(t0) = eta(t1) = 0, else ValueError), and the virtual work of
    the non-conservative forces; with ``second`` also the second variation. Returns a
    :class:`Variation`."""
    a, p = _system_parts(system)
    n = a.n
    _check_solution(solution, 2*n)
    eta, deta = _variation_functions(variation, n)
    t0, t1 = _ends(solution, t_span)
    e_ends = eta(np.array([t0, t1]))
    probe = eta(np.linspace(t0, t1, 33))
    emax = max(float(np.max(np.abs(probe))), 1e-300)
    if np.max(np.abs(e_ends)) > 1e-10*emax:
        raise ValueError(f"variation: must vanish at both ends (|eta(t0)|, |eta(t1)| = "
                         f"{np.max(np.abs(e_ends[:, 0])):.3g}, "
                         f"{np.max(np.abs(e_ends[:, 1])):.3g}; Hamilton's principle varies "
                         "paths with fixed ends)")
    lib = a.library()

    def g(t, y):
        e, de = eta(t), deta(t)
        fq = np.asarray(lib("dldq", t, y, p)).reshape(n, -1)
        pv = np.asarray(lib("momenta", t, y, p)).reshape(n, -1)
        qn = np.asarray(lib("nonconservative", t, y, p)).reshape(n, -1)
        a1 = np.sum(fq*e + pv*de, axis=0)
        w = np.sum(qn*e, axis=0)
        sc = np.sum(np.abs(fq*e) + np.abs(pv*de) + np.abs(qn*e), axis=0)
        return np.vstack([a1, w, sc])
    dS, W, scale = integrate_dense(g, solution, (t0, t1))
    res = dS + W
    d2 = second_variation(system, solution, variation, (t0, t1)) if second else None
    return Variation(delta_S=float(dS), virtual_work=float(W), residual=float(res),
                     scale=float(scale), relative=abs(float(res))/max(float(scale), 1e-300),
                     second=d2)


def second_variation(system, solution, variation, t_span=None):
    """The second variation of the action, integral of [eta; eta']^T H [eta; eta'] dt with H
    the Hessian of L in (q, q') (exact, compiled), along the dense solution."""
    a, p = _system_parts(system)
    n = a.n
    _check_solution(solution, 2*n)
    eta, deta = _variation_functions(variation, n)
    lib = a.lagrangian_hessian_library()

    def g(t, y):
        z = np.vstack([eta(t), deta(t)])
        H = np.asarray(lib("lagrangian_hess", t, y, p)).reshape(2*n, 2*n, -1)
        return np.einsum("im,ijm,jm->m", z, H, z)
    return float(integrate_dense(g, solution, t_span))


def check_stationary(system, solution, variations, t_span=None, tol=None):
    """Hamilton's principle along a solution: the first variation in each of `variations`
    (each as in :func:`first_variation`) relative to the size of its terms. Returns
    (ok, [Variation, ...]); ok when every ``relative`` is <= tol (default 1e-6: choose it
    from the tolerance the solution was integrated with)."""
    if tol is None:
        tol = 1e-6
    out = [first_variation(system, solution, v, t_span) for v in variations]
    return all(v.relative <= tol for v in out), out
