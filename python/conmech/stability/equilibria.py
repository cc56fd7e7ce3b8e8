"""Equilibria: linearisation, eigenvalues and classification (conmech_equilibria), the
Lagrange-Dirichlet test, Newton's method for equilibria and a grid of guesses."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from .. import _conmech
from ..systems import BuiltinSystem
from ._validate import _callback, _check_dim, _no_jac_for_builtin, _raise, _real, _state

_KINDS = {1: "asymptotically stable", 2: "centre", 3: "unstable", 4: "degenerate"}
#: equilibrium() classifies y only if max|f(t, y)| <= EQUILIBRIUM_RTOL max(1, |J| max(1, |y|))
EQUILIBRIUM_RTOL = 1e-8


class Equilibrium:
    """Result of :func:`equilibrium`: y, jacobian, eigenvalues (complex), kind
    ('asymptotically stable', 'centre', 'unstable', 'degenerate'), saddle, residual
    (max |f(y)|), analytic (the Jacobian was analytic)."""

    __slots__ = ("y", "jacobian", "eigenvalues", "kind", "saddle", "residual", "analytic",
                 "njev")

    def __init__(self, **kw):
        for k in self.__slots__:
            setattr(self, k, kw.get(k))

    @property
    def stable(self):
        """Linearly stable (asymptotically stable or centre)."""
        return self.kind in ("asymptotically stable", "centre")

    def __repr__(self):
        return f"Equilibrium(kind={self.kind!r}, eigenvalues={self.eigenvalues!r})"


def equilibrium(system: Any, y: ArrayLike, t: float = 0.0, tol: float = 1e-8,
                jac: Callable[..., ArrayLike] | None = None) -> Equilibrium:
    """Linearise at y, compute the eigenvalues and classify (see conmech_equilibria).

    y must be an equilibrium: max|f(t, y)| <= EQUILIBRIUM_RTOL max(1, |J| max(1, |y|)),
    else ValueError (a classification elsewhere would be meaningless).

    ``tol`` (in [0, 1)) is relative to max(1, max|lambda|): Re(lambda) within it counts as
    zero. ``jac``: exact Jacobian jac(t, y) -> (n, n) of a Python system (default:
    central finite differences); the result's ``njev`` counts its calls.
    """
    y = _state(y, "y")
    _check_dim(system, y)
    t = _real(t, "t")
    tol = _real(tol, "tol", 0.0, 1.0)
    if tol == 1.0:
        raise ValueError("tol must be < 1")
    _no_jac_for_builtin(system, jac)
    n = y.size
    njev = 0
    if isinstance(system, BuiltinSystem):
        out = _conmech.flat_equilibrium_builtin(*system._flat_args(), y, t, tol)
    else:
        g, rhs, dfdy = _callback(system, n, y, t, jac)
        if dfdy is None:
            out = _conmech.flat_equilibrium_callback(rhs, y, t, tol)
        else:
            out = _conmech.flat_equilibrium_callback_jac(rhs, dfdy, y, t, tol)
        g.check()
        njev = g.count("jac")
    jmat, wr, wi, kind, saddle, residual, analytic, info, message = out
    if info != 0:
        _raise(info, message)
    # a classification is only meaningful at an equilibrium: check the true residual
    jmax = float(np.max(np.abs(jmat), initial=0.0))
    scale = max(1.0, jmax*max(1.0, float(np.max(np.abs(y)))))
    if not (np.all(np.isfinite(jmat)) and residual <= EQUILIBRIUM_RTOL*scale):
        raise ValueError(f"y is not an equilibrium: max|f(t, y)| = {residual:.3g} > "
                         f"{EQUILIBRIUM_RTOL:g} x {scale:.3g} (or the Jacobian is not "
                         "finite)")
    e = Equilibrium(y=y, jacobian=np.array(jmat),
                    eigenvalues=np.asarray(wr) + 1j*np.asarray(wi),
                    kind=_KINDS.get(int(kind), "degenerate"), saddle=bool(saddle),
                    residual=float(residual), analytic=bool(analytic))
    e.njev = njev
    return e


def lagrange_dirichlet(hessian: ArrayLike, tol: float = 1e-10) -> tuple:
    """Lagrange-Dirichlet test: (positive definite?, eigenvalues ascending) of a symmetric
    Hessian of the potential energy (LAPACK dsyev)."""
    h = np.asfortranarray(np.asarray(hessian, dtype=float))
    if h.ndim != 2 or h.shape[0] != h.shape[1] or h.size == 0:
        raise ValueError("hessian must be a non-empty square matrix")
    if not np.all(np.isfinite(h)):
        raise ValueError("hessian must be finite")
    stable, w, info = _conmech.flat_lagrange_dirichlet(h, float(tol))
    if info == -4:
        raise ValueError("hessian must be symmetric")
    if info != 0:
        raise RuntimeError("dsyev failed")
    return bool(stable), np.array(w)

def find_equilibrium(system: Any, guess: ArrayLike, t: float = 0.0, tol: float = 1e-12,
                     max_iter: int = 50, classify_tol: float = 1e-8) -> Equilibrium:
    """Newton's method for f(t, y) = 0 from ``guess`` (analytic Jacobian of built-in
    systems, central differences for callables), then :func:`equilibrium` at the root:
    returns the classified :class:`Equilibrium`. Raises RuntimeError when Newton fails
    (singular Jacobian or no convergence) or the residual at the root exceeds sqrt(tol)."""
    y = _state(guess, "guess")
    _check_dim(system, y)
    if not (np.isfinite(tol) and tol > 0) or int(max_iter) < 1:
        raise ValueError("tol must be positive and max_iter >= 1")
    if isinstance(system, BuiltinSystem):
        yout, info, message = _conmech.flat_find_equilibrium_builtin(
            *system._flat_args(), y, float(t), float(tol), int(max_iter))
    else:
        g, rhs, _ = _callback(system, y.size, y, float(t))
        yout, info, message = _conmech.flat_find_equilibrium_callback(
            rhs, y, float(t), float(tol), int(max_iter))
        g.check()
    if info != 0:
        _raise(info, message)
    e = equilibrium(system, np.array(yout), t=t, tol=classify_tol)
    if not e.residual <= max(np.sqrt(tol), 1e-8)*max(1.0, np.max(np.abs(e.y))):
        raise RuntimeError(f"find_equilibrium: residual {e.residual:.3g} at the root")
    return e


def equilibria(system: Any, guesses: ArrayLike, t: float = 0.0, tol: float = 1e-12,
               dedup_tol: float = 1e-8, classify_tol: float = 1e-8) -> list:
    """All equilibria reached by Newton from an array of guesses (shape (k, n)), e.g. a
    grid; duplicates (max-norm distance <= dedup_tol max(1, |y|)) removed. Guesses whose
    Newton fails are skipped. Returns a list of :class:`Equilibrium`, sorted by y."""
    g = np.asarray(guesses, dtype=float)
    if g.ndim != 2 or g.shape[0] == 0:
        raise ValueError("guesses must be a non-empty (k, n) array")
    found = []
    for y in g:
        try:
            e = find_equilibrium(system, y, t=t, tol=tol, classify_tol=classify_tol)
        except RuntimeError:
            continue
        if not any(np.max(np.abs(e.y - f.y)) <= dedup_tol*max(1.0, np.max(np.abs(f.y)))
                   for f in found):
            found.append(e)
    found.sort(key=lambda e: tuple(e.y))
    return found


def grid(bounds: Sequence[Sequence[float]], num: int | Sequence[int]) -> np.ndarray:
    """Guesses on a regular grid: ``bounds`` = [(lo, hi), ...] per component, ``num``
    points per component (an int or a list). Returns a (k, n) array for
    :func:`equilibria`."""
    bounds = [tuple(map(float, b)) for b in bounds]
    num = [int(num)]*len(bounds) if np.isscalar(num) else [int(k) for k in num]
    if len(num) != len(bounds) or min(num) < 1:
        raise ValueError("num must be a positive int or one per bound")
    axes = [np.linspace(lo, hi, k) for (lo, hi), k in zip(bounds, num)]
    return np.stack([a.ravel() for a in np.meshgrid(*axes, indexing="ij")], axis=1)


def potential_hessian(potential, q, h=None):
    """Central-difference Hessian of a potential V(q) (step eps^(1/4) max(|q_i|, 1), error
    O(h^2) ~ 1e-8 relative)."""
    q = _state(q, "q")
    n = q.size
    hs = np.full(n, np.finfo(float).eps**0.25)*np.maximum(np.abs(q), 1.0) if h is None \
        else np.full(n, float(h))
    H = np.empty((n, n))
    v0 = float(potential(q))
    for i in range(n):
        e_i = np.zeros(n)
        e_i[i] = hs[i]
        H[i, i] = (float(potential(q + e_i)) - 2*v0 + float(potential(q - e_i)))/hs[i]**2
        for j in range(i + 1, n):
            e_j = np.zeros(n)
            e_j[j] = hs[j]
            H[i, j] = H[j, i] = (float(potential(q + e_i + e_j))
                                 - float(potential(q + e_i - e_j))
                                 - float(potential(q - e_i + e_j))
                                 + float(potential(q - e_i - e_j)))/(4*hs[i]*hs[j])
    return H


def lagrange_dirichlet_potential(potential, q, hessian=None, tol=1e-6):
    """Lagrange-Dirichlet test at q from the potential: a strict minimum (positive-definite
    Hessian) is a stable equilibrium of a conservative system. ``hessian(q)`` if given
    (exact, e.g. symbolic), else :func:`potential_hessian`. Returns (stable, eigenvalues,
    hessian); ``tol`` is relative to the largest |eigenvalue| (finite differences carry
    ~1e-8)."""
    q = _state(q, "q")
    H = np.asarray(hessian(q), dtype=float) if hessian is not None else \
        potential_hessian(potential, q)
    H = 0.5*(H + H.T)
    stable, w = lagrange_dirichlet(H, tol=tol)
    return stable, w, H

