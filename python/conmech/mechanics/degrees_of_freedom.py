"""Degrees of freedom of mechanical systems (the lecture notes' n = 3N - R).

- A constrained system in excessive coordinates (:class:`conmech.constrained.
  NativeConstrained`: built-in, compiled or symbolic): n coordinates minus the number of independent
  holonomic constraints, the rank of G = dphi/dq at a point of the constraint manifold
  (Fortran conmech_degrees_of_freedom: Gauss-Newton onto phi = 0, ranks by LAPACK's SVD).
  Pfaffian (non-holonomic) constraints do not reduce the degrees of freedom; they reduce
  the independent velocities: ``velocity_dof`` = n - rank [G; A] (the rubber ball rolling
  without slip and spin: 5 degrees of freedom of its configuration, 2 independent
  velocities, the lecture notes' count).
- A system in generalized coordinates (built-in, compiled or symbolic): its number of
  coordinates (the holonomic constraints are eliminated).
- A first-order system without mechanical structure: None.
"""
from __future__ import annotations

import numpy as np

from .. import _conmech
from .._core.callback import message_text
from .._core.native import NativeSystem
from .._core.status import BAD_INPUT
from .._core.result import Record

__all__ = ["DegreesOfFreedom", "degrees_of_freedom"]


class DegreesOfFreedom(Record):
    """Result of :func:`degrees_of_freedom`: ``n`` (coordinates), ``n_hol``, ``n_nh``
    (constraints given), ``rank_h``, ``rank_nh`` (independent ones), ``redundant``
    (n_hol + n_nh - rank_h - rank_nh), ``dof`` (n - rank_h), ``velocity_dof``
    (n - rank_h - rank_nh), ``q`` (the configuration the ranks were taken at),
    ``residual`` (max |phi(t, q)| there)."""

    __slots__ = ("n", "n_hol", "n_nh", "rank_h", "rank_nh", "redundant", "dof",
                 "velocity_dof", "q", "residual")

    def __repr__(self):
        return (f"DegreesOfFreedom(dof={self.dof}, velocity_dof={self.velocity_dof}, n={self.n}, "
                f"holonomic={self.rank_h}/{self.n_hol}, nonholonomic={self.rank_nh}/"
                f"{self.n_nh})")


def _generalized_dof(system):
    """Number of coordinates of a generalized-coordinate system, or None."""
    ndof = getattr(system, "ndof", None)
    if ndof:
        return int(ndof)
    if isinstance(system, NativeSystem):
        kind, n, mh, mn, info, _ = _conmech.flat_mech_info(*system._flat_args())
        if info == 0 and kind == 2:
            return int(n)
    return None


def degrees_of_freedom(system, q=None, t: float = 0.0, project: bool = True,
                       rank_tol: float = 1e-10):
    """The degrees of freedom of `system` (see the module notes) as a
    :class:`DegreesOfFreedom`, or None for a first-order system without mechanical
    structure. For a constrained system the ranks are taken at q (default: the built-in's
    consistent initial state; for a compiled system without one, points drawn from a fixed
    seed and projected onto the manifold), moved onto phi = 0 first when ``project``."""
    if hasattr(system, "n_hol") and hasattr(system, "_flat_args"):
        # conmech.constrained.NativeConstrained (built-in, compiled, symbolic)
        return _constrained_dof(system, q, float(t), project, float(rank_tol))
    if hasattr(system, "n_hol") and callable(getattr(system, "mass", None)):
        # conmech.constrained.ConstrainedSystem (Python callables)
        return _python_constrained_dof(system, q, float(t), float(rank_tol))
    n = _generalized_dof(system)
    if n is None:
        return None
    return DegreesOfFreedom(n=n, n_hol=0, n_nh=0, rank_h=0, rank_nh=0, redundant=0, dof=n,
                            velocity_dof=n, q=None, residual=0.0)


def _constrained_dof(system, q, t, project, rank_tol):
    if not 0 < rank_tol < 1:
        raise ValueError("rank_tol must be in (0, 1)")
    if q is not None:
        starts = [np.ascontiguousarray(np.asarray(q, dtype=float).ravel())]
        if starts[0].size != system.n or not np.all(np.isfinite(starts[0])):
            raise ValueError(f"q must have {system.n} finite components")
    else:
        try:
            starts = [np.asarray(system.initial_state()[0], dtype=float)]
        except ValueError:           # a compiled system has no default state
            rng = np.random.default_rng(2024)
            starts = [rng.uniform(-1.0, 1.0, system.n) for _ in range(5)]
    last = None
    for q0 in starts:
        out = _conmech.flat_degrees_of_freedom(*system._flat_args(), t, q0,
                                               int(bool(project)), rank_tol)
        qout, residual, rank_h, rank_nh, dof, vdof, info, message = out
        if info == 0:
            return DegreesOfFreedom(n=system.n, n_hol=system.n_hol, n_nh=system.n_nh,
                                    rank_h=int(rank_h), rank_nh=int(rank_nh),
                                    redundant=system.n_hol + system.n_nh - int(rank_h)
                                    - int(rank_nh), dof=int(dof), velocity_dof=int(vdof),
                                    q=np.array(qout), residual=float(residual))
        last = message_text(message)
        if info == BAD_INPUT:
            raise ValueError(last)
    raise RuntimeError(f"degrees_of_freedom: {last} (pass q, a configuration on or near the "
                       "constraint manifold)")


def _python_constrained_dof(system, q, t, rank_tol):
    """The same for a system of Python callables (ranks by numpy's SVD at the given q,
    which must lie on the manifold)."""
    if q is None:
        raise ValueError("q: a configuration on the constraint manifold is needed for a "
                         "system of Python callables")
    q = np.asarray(q, dtype=float).ravel()
    n = system.n
    G = np.zeros((0, n))
    res = 0.0
    if system.n_hol:
        res = float(np.max(np.abs(np.asarray(system.phi(t, q), dtype=float))))
        G = np.asarray(system.jac(t, q), dtype=float).reshape(system.n_hol, n) \
            if system.jac is not None else _fd_jac(system, t, q)
    A = np.zeros((0, n))
    if system.n_nh:
        A = np.asarray(system.nh(t, q)[0], dtype=float).reshape(system.n_nh, n)

    def rank(m):
        if m.size == 0:
            return 0
        s = np.linalg.svd(m, compute_uv=False)
        return int(np.sum(s > rank_tol*max(s[0], 1e-300)))
    rh = rank(G)
    rc = rank(np.vstack([G, A]))
    return DegreesOfFreedom(n=n, n_hol=system.n_hol, n_nh=system.n_nh, rank_h=rh,
                            rank_nh=rc - rh, redundant=system.n_hol + system.n_nh - rc,
                            dof=n - rh, velocity_dof=n - rc, q=q, residual=res)


def _fd_jac(system, t, q):
    n = q.size
    G = np.zeros((system.n_hol, n))
    for j in range(n):
        h = np.finfo(float).eps**(1/3)*max(1.0, abs(q[j]))
        qp, qm = q.copy(), q.copy()
        qp[j] += h
        qm[j] -= h
        G[:, j] = (np.asarray(system.phi(t, qp)) - np.asarray(system.phi(t, qm)))/(2*h)
    return G
