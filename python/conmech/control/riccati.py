"""The stabilising periodic solution of the periodic Riccati differential equation
(Fortran: conmech_periodic_riccati)."""
from __future__ import annotations

from typing import Any, Callable  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from .. import _conmech
from .._core.callback import Guard, as_result
from .._core.result import Record
from .._core.status import raise_status

__all__ = ["PeriodicRiccati", "periodic_riccati", "check_weights"]


class PeriodicRiccati(Record):
    """Result of :func:`periodic_riccati`.

    Attributes: t (nt,), P (nt, k, k) the stabilising periodic solution, K (nt, m, k) the
    gain of u = K x (K = -R^-1 B^T P), closed_loop_multipliers (of x' = (A + B K) x),
    closed_loop_monodromy, hamiltonian_multipliers (2k: the closed-loop ones and their
    reciprocals), periodicity (|P(0) - P(T)|/|P(0)| of the kept backward pass),
    min_eigenvalue (of P over 64 points of the period), passes (backward periods of
    refinement).
    """

    __slots__ = ("t", "P", "K", "closed_loop_multipliers", "closed_loop_monodromy",
                 "hamiltonian_multipliers", "periodicity", "min_eigenvalue", "passes")


def check_weights(Q, R, k, m):
    """Q (k x k symmetric positive semi-definite) and R (m x m positive definite) as
    float arrays; scalars mean multiples of the identity. ValueError naming them."""
    def mat(w, s, name):
        a = np.asarray(w, dtype=float)
        if a.ndim == 0:
            a = float(a)*np.eye(s)
        elif a.ndim == 1 and a.size == s:
            a = np.diag(a)
        if a.shape != (s, s) or not np.all(np.isfinite(a)):
            raise ValueError(f"{name} must be a finite {s} x {s} matrix (or a scalar, or "
                             f"the {s} diagonal entries)")
        if np.max(np.abs(a - a.T)) > 1e-12*max(1.0, np.max(np.abs(a))):
            raise ValueError(f"{name} must be symmetric")
        return np.asfortranarray(0.5*(a + a.T))
    q = mat(1.0 if Q is None else Q, k, "Q")
    r = mat(1.0 if R is None else R, m, "R")
    if np.min(np.linalg.eigvalsh(q)) < -1e-12*max(1.0, np.max(np.abs(q))):
        raise ValueError("Q must be positive semi-definite")
    if not np.min(np.linalg.eigvalsh(r)) > 0:
        raise ValueError("R must be positive definite")
    return q, r


def periodic_riccati(A: Callable, B: Callable, period: float, Q: ArrayLike | None = None,
                     R: ArrayLike | None = None, *, t: ArrayLike | None = None,
                     nt: int = 65, rtol: float = 1e-12, atol: float = 1e-12) -> PeriodicRiccati:
    """The stabilising periodic solution P(t) = P(t + T) of
    -P' = A^T P + P A - P B R^-1 B^T P + Q for the T-periodic system x' = A(t) x + B(t) u
    (``A(t)`` -> (k, k), ``B(t)`` -> (k, m) Python callables; Q, R constant weights).

    Method: the ordered real Schur form of the Hamiltonian monodromy gives P(0) (its
    stable subspace is the graph of P(0)), refined by backward integration over whole
    periods until P(0) returns to itself (see conmech_periodic_riccati). Raises
    RuntimeError when there is no stabilising periodic solution (multipliers of the
    Hamiltonian on the unit circle: not stabilisable, or not detectable through Q)."""
    if not (callable(A) and callable(B)):
        raise TypeError("A and B must be callables of t")
    period = float(period)
    if not (np.isfinite(period) and period > 0):
        raise ValueError("period must be positive and finite")
    a0 = np.atleast_2d(np.asarray(A(0.0), dtype=float))
    b0 = np.asarray(B(0.0), dtype=float)
    if b0.ndim == 1:
        b0 = b0[:, None]
    k = a0.shape[0]
    if a0.shape != (k, k) or b0.ndim != 2 or b0.shape[0] != k:
        raise ValueError("A(t) must be k x k and B(t) k x m")
    m = b0.shape[1]
    q, r = check_weights(Q, R, k, m)
    tt = np.linspace(0, period, int(nt)) if t is None else np.ascontiguousarray(
        np.asarray(t, dtype=float).ravel())
    g = Guard()
    fa = g.wrap(A, 1, (k, k), "A")
    fb = g.wrap(B, 1, (k, m), "B")
    out = _conmech.flat_control_riccati(afun=fa, bfun=fb, period=period, qw=q, rw=r,
                                        rtol=float(rtol), atol=float(atol), t=tt)
    g.check()
    (ps, ks, hmr, hmi, cmr, cmi, clm, periodicity, min_eig, passes, info, message) = out
    if info != 0:
        raise_status(info, message)
    return PeriodicRiccati(t=tt, P=np.moveaxis(np.array(ps), 2, 0),
                           K=np.moveaxis(np.array(ks), 2, 0),
                           closed_loop_multipliers=np.asarray(cmr) + 1j*np.asarray(cmi),
                           closed_loop_monodromy=np.array(clm),
                           hamiltonian_multipliers=np.asarray(hmr) + 1j*np.asarray(hmi),
                           periodicity=float(periodicity), min_eigenvalue=float(min_eig),
                           passes=int(passes))
