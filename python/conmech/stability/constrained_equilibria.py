"""Equilibria of holonomically constrained systems on their constraint manifold .

The system M(q) q'' = Q(t, q, q') + G(q)^T lambda, phi(q) = 0 (excessive coordinates; see
:mod:`conmech.constrained`) is at rest at q* when

    Q(t, q*, 0) + G(q*)^T lambda* = 0,   phi(q*) = 0,

solved by Newton's method in (q, lambda) (the q-derivative of Q + G^T lambda by central
differences, G from the system). Linearised about it with Z an orthonormal basis of the
tangent space ker G(q*) (SVD), q = q* + Z eta:

    Z^T M Z eta'' = Z^T K Z eta + Z^T D Z eta',  K = d(Q + G^T lambda*)/dq, D = dQ/dv,

(second-order terms of the constraint drop out because the total force vanishes at q*);
its eigenvalues classify the equilibrium as :func:`conmech.stability.equilibrium` does.
Lagrange-Dirichlet: with a potential V (given, or the system's energy at v = 0), the
Hessian of V restricted to the manifold is Z^T (V'' - sum_i lambda_i phi_i'') Z (the
Hessian of the Lagrangian V - lambda . phi; V'' and phi_i'' by differences): positive
definite means a strict minimum on the manifold, a stable equilibrium.
Exported by :mod:`conmech.stability`.
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np

from ..mechanics.compiled import evaluate
from ..mechanics.constrained import ConstrainedSystem, NativeConstrained, builtin
from .equilibria import equilibrium, lagrange_dirichlet, multistart, potential_hessian
from .._core.validate import _real, _state
from .._core.result import Record
from .manifold_checks import checked_values, constraint_jacobian, holonomic_sizes

__all__ = ["ConstrainedEquilibrium", "constrained_equilibrium", "constrained_equilibria"]


class ConstrainedEquilibrium(Record):
    """Result of :func:`constrained_equilibrium`: q, lam (multipliers), residual (max of
    |Q + G^T lam| and |phi| at the point, evaluated afresh), iterations, tangent (n, k)
    orthonormal basis of the tangent space, mass_reduced, stiffness_reduced (-Z^T K Z),
    damping_reduced (Z^T D Z), eigenvalues (2k, complex) of the reduced linearisation,
    kind ('asymptotically stable', 'centre', 'unstable', 'degenerate'), saddle,
    frequencies (the positive imaginary parts of the eigenvalues on the imaginary axis),
    and, when a potential is known, hessian_reduced (of V on the manifold), its eigenvalues
    and lagrange_dirichlet (strict minimum: stable); else those three are None."""

    __slots__ = ("q", "lam", "residual", "iterations", "tangent", "mass_reduced",
                 "stiffness_reduced", "damping_reduced", "eigenvalues", "kind", "saddle",
                 "frequencies", "hessian_reduced", "hessian_eigenvalues",
                 "lagrange_dirichlet")

    @property
    def stable(self):
        """Linearly stable (asymptotically stable or centre)."""
        return self.kind in ("asymptotically stable", "centre")

    def __repr__(self):
        return (f"ConstrainedEquilibrium(q={self.q.tolist()!r}, kind={self.kind!r}, "
                f"frequencies={self.frequencies.tolist()!r})")


def _evaluator(system, t):
    """(n, m, fun(q, v) -> (M, Q, phi, G), energy(q) or None) of a constrained system."""
    if isinstance(system, str):
        system = builtin(system)
    if isinstance(system, NativeConstrained):
        n, m = holonomic_sizes(system, "equilibria")

        def fun(q, v):
            d = evaluate(system, t, q, v)
            return d["M"], d["Q"], d["phi"], d["G"].reshape(m, n)

        def energy(q):
            return evaluate(system, t, q, np.zeros(n))["energy"]
        has_energy = evaluate(system, t, np.ones(n), np.zeros(n))["energy"] is not None
        return n, m, fun, (energy if has_energy else None)
    if isinstance(system, ConstrainedSystem):
        n, m = holonomic_sizes(system, "equilibria")

        def fun(q, v):
            mm = checked_values(system.mass(t, q), (n, n), "mass(t, q)")
            qf = checked_values(system.forces(t, q, v), (n,), "forces(t, q, v)")
            if m == 0:
                return mm, qf, np.zeros(0), np.zeros((0, n))
            ph = checked_values(system.phi(t, q), (m,), "phi(t, q)")
            return mm, qf, ph, constraint_jacobian(system, t, q, m, n)
        energy = None
        if system.energy is not None:
            def energy(q):
                return float(system.energy(t, q, np.zeros(n)))
        return n, m, fun, energy
    raise TypeError("system must be a constrained system: a name, conmech.constrained."
                    "builtin(...), conmech.systems.pendulum_xy() etc., a compiled constrained "
                    "system or a conmech.constrained.ConstrainedSystem")


def _force(fun, q, lam, v=None):
    n = q.size
    mm, qf, ph, g = fun(q, np.zeros(n) if v is None else v)
    return qf + g.T @ lam, ph, g, mm


def _dforce_dq(fun, q, lam):
    n = q.size
    k = np.empty((n, n))
    for j in range(n):
        h = np.finfo(float).eps**(1/3)*max(1.0, abs(q[j]))
        e = np.zeros(n)
        e[j] = h
        k[:, j] = (_force(fun, q + e, lam)[0] - _force(fun, q - e, lam)[0])/(2*h)
    return k


def _dforce_dv(fun, q):
    n = q.size
    d = np.empty((n, n))
    for j in range(n):
        h = np.finfo(float).eps**(1/3)
        e = np.zeros(n)
        e[j] = h
        d[:, j] = (fun(q, e)[1] - fun(q, -e)[1])/(2*h)
    return d


def constrained_equilibrium(system: Any, guess, t: float = 0.0,
                            potential: Callable[[np.ndarray], float] | None = None,
                            tol: float = 1e-12, max_iter: int = 50,
                            classify_tol: float = 1e-8) -> ConstrainedEquilibrium:
    """Newton's method for an equilibrium of a holonomically constrained system on its
    constraint manifold from the coordinates ``guess`` (n,), then its classification by
    the reduced linearisation on the tangent space and, when a potential is known
    (``potential(q)``, else the system's energy at v = 0), the Lagrange-Dirichlet test on
    the manifold (see the module notes). Raises ValueError on bad input (non-holonomic or
    rheonomic systems, wrong shapes) and RuntimeError when Newton fails or the point found
    does not satisfy the equations to the tolerance."""
    t = _real(t, "t")
    tol = _real(tol, "tol", 0.0, 1.0, low_open=True)
    if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) \
            or max_iter < 1:
        raise ValueError("max_iter must be a positive integer")
    if potential is not None and not callable(potential):
        raise TypeError("potential must be a callable V(q) or None")
    n, m, fun, energy = _evaluator(system, t)
    q = _state(guess, "guess").copy()
    if q.size != n:
        raise ValueError(f"guess has {q.size} coordinates; the system has {n}")
    if m >= n:
        raise ValueError("the constraints leave no degree of freedom")
    f0, ph, g, _ = _force(fun, q, np.zeros(m))
    lam = np.linalg.lstsq(g.T, -f0, rcond=None)[0] if m else np.zeros(0)
    ok = False
    for it in range(1, max_iter + 1):
        f, ph, g, _ = _force(fun, q, lam)
        k = _dforce_dq(fun, q, lam)
        jac = np.block([[k, g.T], [g, np.zeros((m, m))]])
        rhs = -np.concatenate([f, ph])
        try:
            dz = np.linalg.solve(jac, rhs)
        except np.linalg.LinAlgError:
            raise RuntimeError(f"constrained_equilibrium: singular Newton matrix at q = "
                               f"{q.tolist()} (a degenerate equilibrium or redundant "
                               "constraints)") from None
        if not np.all(np.isfinite(dz)):
            raise RuntimeError("constrained_equilibrium: non-finite Newton step")
        q += dz[:n]
        lam += dz[n:]
        if np.max(np.abs(dz)) <= tol*max(1.0, np.max(np.abs(np.concatenate([q, lam])))):
            ok = True
            break
    f, ph, g, mm = _force(fun, q, lam)
    scale = max(1.0, float(np.max(np.abs(fun(q, np.zeros(n))[1]), initial=0.0)))
    residual = float(max(np.max(np.abs(f), initial=0.0)/scale,
                         np.max(np.abs(ph), initial=0.0)/max(1.0, np.max(np.abs(q)))))
    if not ok or not residual <= max(1e3*tol, 1e-10):
        raise RuntimeError(f"constrained_equilibrium: Newton did not converge from {guess!r}"
                           f" (after {it} iterations, relative residual {residual:.3g})")
    # tangent space: the right singular vectors of G beyond its rank
    if m:
        _, sv, vt = np.linalg.svd(g)
        rank = int(np.sum(sv > 1e-10*max(sv[0], 1e-300)))
        z = vt[rank:].T
    else:
        z = np.eye(n)
    kdim = z.shape[1]
    k = _dforce_dq(fun, q, lam)
    d = _dforce_dv(fun, q)
    mr = z.T @ mm @ z
    kr = z.T @ k @ z
    dr = z.T @ d @ z
    a = np.block([[np.zeros((kdim, kdim)), np.eye(kdim)],
                  [np.linalg.solve(mr, kr), np.linalg.solve(mr, dr)]])
    e = equilibrium(lambda tt, y: a @ y, np.zeros(2*kdim), tol=classify_tol,
                    jac=lambda tt, y: a)
    ev = e.eigenvalues
    onaxis = np.abs(ev.real) <= classify_tol*max(1.0, float(np.max(np.abs(ev))))
    freqs = np.sort(ev.imag[onaxis & (ev.imag > 0)])
    out = ConstrainedEquilibrium(q=q, lam=lam, residual=residual, iterations=it, tangent=z,
                                 mass_reduced=mr, stiffness_reduced=-kr, damping_reduced=dr,
                                 eigenvalues=ev, kind=e.kind, saddle=e.saddle,
                                 frequencies=freqs)
    pot = potential if potential is not None else energy
    if pot is not None:
        hv = potential_hessian(lambda x: float(pot(np.asarray(x))), q)
        for i in range(m):       # - lam_i phi_i'' from differences of the rows of G
            hp = np.empty((n, n))
            for j in range(n):
                h = np.finfo(float).eps**(1/3)*max(1.0, abs(q[j]))
                ej = np.zeros(n)
                ej[j] = h
                hp[:, j] = (fun(q + ej, np.zeros(n))[3][i] - fun(q - ej, np.zeros(n))[3][i]) \
                    / (2*h)
            hv -= lam[i]*0.5*(hp + hp.T)
        hr = z.T @ hv @ z
        hr = 0.5*(hr + hr.T)
        stable, w = lagrange_dirichlet(hr, tol=1e-6)
        out.hessian_reduced, out.hessian_eigenvalues = hr, w
        out.lagrange_dirichlet = bool(stable)
    return out


def constrained_equilibria(system: Any, guesses, t: float = 0.0,
                           potential: Callable[[np.ndarray], float] | None = None,
                           tol: float = 1e-12, dedup_tol: float = 1e-8,
                           classify_tol: float = 1e-8) -> list:
    """All equilibria reached by :func:`constrained_equilibrium` from an array of guesses
    (k, n) (e.g. :func:`conmech.stability.grid` points near the manifold); failures are
    skipped, duplicates (max-norm distance <= dedup_tol max(1, |q|)) removed. Sorted by
    q."""
    found = multistart(guesses, lambda g: constrained_equilibrium(
        system, g, t=t, potential=potential, tol=tol, classify_tol=classify_tol),
        lambda e, f: np.max(np.abs(e.q - f.q)) <= dedup_tol*max(1.0, np.max(np.abs(f.q))))
    found.sort(key=lambda e: tuple(e.q))
    return found
