"""Equilibria: linearisation, eigenvalues and classification (conmech_equilibria), the
Lagrange-Dirichlet test, Newton's method for equilibria and a grid of guesses."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from .. import _conmech
from .._core.builtin_table import STATE_NAMES
from .._core.native import BuiltinSystem, NativeSystem
from .._core.validate import (_callback, _check_dim, _no_jac_for_builtin, _real, _state,
                              _system_args)
from .._core.result import Record
from .._core.status import BAD_INPUT, raise_status

_KINDS = {1: "asymptotically stable", 2: "centre", 3: "unstable", 4: "degenerate",
          5: "unstable (secular drift)", 6: "stable (family of equilibria)"}
#: equilibrium() classifies y only if max|f(t, y)| <= EQUILIBRIUM_RTOL max(1, |J| max(1, |y|))
EQUILIBRIUM_RTOL = 1e-8


class Equilibrium(Record):
    """Result of :func:`equilibrium`.

    Attributes: ``y``, ``jacobian``, ``eigenvalues`` (complex), ``kind``, ``saddle``,
    ``residual`` (max |f(y)|), ``analytic`` (the Jacobian was analytic), ``njev``; the
    structure: ``zero_multiplicity`` (algebraic multiplicity of the eigenvalue 0),
    ``largest_block`` (largest Jordan block on the imaginary axis), ``secular_frequency``
    (w > 0 of a Jordan block at +-i w, else 0), ``drift`` (n x k: the directions of secular
    drift, the eigenvectors of the Jordan blocks at 0) and ``drift_names``,
    ``family_dim`` and ``family`` (n x d, orthonormal: the tangent of the family of
    equilibria through y, e.g. a cyclic coordinate's line), ``state_names``; and
    ``relative`` (a :class:`RelativeEquilibrium`: the classification relative to the
    system's first integrals and the family, or None).

    ``kind`` is one of 'asymptotically stable', 'centre' (every eigenvalue on the
    imaginary axis and semisimple: linearly stable), 'unstable' (some Re > 0),
    'unstable (secular drift along ...)' (a Jordan block at 0: the linearisation drifts
    like t along the named directions; 'unstable (secular growth ...)' for a block at
    +-i w), 'stable (on an attracting family of equilibria of dimension d, not
    asymptotically)', 'degenerate' (the linearisation cannot decide).
    """

    __slots__ = ("y", "jacobian", "eigenvalues", "kind", "saddle", "residual", "analytic",
                 "njev", "zero_multiplicity", "largest_block", "secular_frequency", "drift",
                 "drift_names", "family_dim", "family", "state_names", "relative")

    @property
    def stable(self):
        """Linearly stable (asymptotically stable, centre, or stable on an attracting
        family of equilibria)."""
        return self.kind in ("asymptotically stable", "centre") or \
            str(self.kind).startswith("stable")

    def __repr__(self):
        extra = f", family_dim={self.family_dim}" if self.family_dim else ""
        if self.relative is not None:
            extra += f", relative={self.relative.kind!r}"
        return f"Equilibrium(kind={self.kind!r}, eigenvalues={self.eigenvalues!r}{extra})"


class RelativeEquilibrium(Record):
    """Stability of an equilibrium relative to first integrals and its family of
    equilibria (:func:`equilibrium` with ``integrals``): the linearisation induced on the
    integrals' level set modulo the family (``jacobian`` = W^T J W, ``basis`` W, n x m),
    its ``eigenvalues``, ``kind``, ``saddle``; ``integrals`` (names of the integrals
    used), ``lagrange_dirichlet`` (True when the energy's Hessian restricted to W is
    positive definite: a strict minimum of the reduced energy, nonlinear stability
    relative to the integrals by Routh's theorem; None when no energy Hessian is known),
    ``energy_eigenvalues`` (of that restricted Hessian)."""

    __slots__ = ("jacobian", "basis", "eigenvalues", "kind", "saddle", "integrals",
                 "lagrange_dirichlet", "energy_eigenvalues")

    @property
    def stable(self):
        return self.kind in ("asymptotically stable", "centre") or \
            str(self.kind).startswith("stable")

    def __repr__(self):
        return (f"RelativeEquilibrium(kind={self.kind!r}, eigenvalues={self.eigenvalues!r}, "
                f"lagrange_dirichlet={self.lagrange_dirichlet!r})")


def _state_names(system, n):
    """Names of the state components: a symbolic system's coordinates (and velocities,
    primed), a built-in's documented coordinates, else y[i]."""
    if type(system) is BuiltinSystem and len(STATE_NAMES.get(system.name, ())) == n:
        return list(STATE_NAMES[system.name])
    keep = getattr(system, "_keep", None)
    model = keep[0] if isinstance(keep, tuple) and keep else None
    d = getattr(model, "derived", None)
    names = list(getattr(d, "coord_names", None) or []) if d is not None else []
    if names and getattr(d, "kind", None) == "ode" and len(names) == n:
        return names
    if names and 2*len(names) == n:
        return names + [nm + "'" for nm in names]
    return [f"y[{i}]" for i in range(n)]


def _direction_name(v, names):
    """'x' for a unit vector along x; 'x and theta' for a combination."""
    big = [i for i in np.argsort(-np.abs(v)) if abs(v[i]) >= 0.1*np.max(np.abs(v))]
    return " and ".join(names[i] for i in big)


def _kind_text(code, drift_names=(), secular_frequency=0.0, family_dim=0):
    if code == 5:
        if drift_names:
            return "unstable (secular drift along " + "; ".join(drift_names) + ")"
        return (f"unstable (secular growth: a Jordan block at +-{secular_frequency:.6g} i)")
    if code == 6:
        return (f"stable (on an attracting family of equilibria of dimension {family_dim}, "
                "not asymptotically)")
    return _KINDS.get(int(code), "degenerate")


def equilibrium(system: Any, y: ArrayLike, t: float = 0.0, tol: float = 1e-8,
                jac: Callable[..., ArrayLike] | None = None,
                integrals: Any = "auto") -> Equilibrium:
    """Linearise at y, compute the eigenvalues, their Jordan structure on the imaginary
    axis and the family of equilibria through y, and classify (see conmech_equilibria).

    y must be an equilibrium: max|f(t, y)| <= EQUILIBRIUM_RTOL max(1, |J| max(1, |y|)),
    else ValueError (a classification elsewhere would be meaningless).

    ``tol`` (in [0, 1)) is relative to max(1, max|lambda|): Re(lambda) within it counts as
    zero; ranks (Jordan structure, kernels) use it too. ``jac``: exact Jacobian
    jac(t, y) -> (n, n) of a Python system (default: central finite differences); the
    result's ``njev`` counts its calls.

    ``integrals``: first integrals for the classification relative to them (the result's
    ``relative``): "auto" (a system from :func:`conmech.symbolic.lagrangian_system` with
    cyclic coordinates: their momenta and the energy, with the energy's exact Hessian),
    None (none), or a list of callables I(y) (gradients by central differences) or of
    (name, I, grad) triples. Example: the lecture notes' cart at the hanging position is
    'unstable (secular drift along x)' and ``relative.kind`` is 'centre' with
    ``relative.lagrange_dirichlet`` True (the reduced energy has a strict minimum).
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
    g, sargs = _system_args(system, n, y, t, jac)
    out = _conmech.flat_equilibrium_structure(*sargs, y, t, tol)
    if g is not None:
        g.check()
        njev = g.count("jac")
    (jmat, wr, wi, kind, saddle, residual, analytic, zero_mult, block, sfreq, fdim, fam,
     ndrift, drift, info, message) = out
    if info != 0:
        raise_status(info, message)
    # a classification is only meaningful at an equilibrium: check the true residual
    jmax = float(np.max(np.abs(jmat), initial=0.0))
    scale = max(1.0, jmax*max(1.0, float(np.max(np.abs(y)))))
    if not (np.all(np.isfinite(jmat)) and residual <= EQUILIBRIUM_RTOL*scale):
        raise ValueError(f"y is not an equilibrium: max|f(t, y)| = {residual:.3g} > "
                         f"{EQUILIBRIUM_RTOL:g} x {scale:.3g} (or the Jacobian is not "
                         "finite)")
    names = _state_names(system, n)
    drift = np.array(drift)[:, :int(ndrift)]
    dnames = [_direction_name(drift[:, j], names) for j in range(drift.shape[1])]
    family = np.array(fam)[:, :int(fdim)]
    e = Equilibrium(y=y, jacobian=np.array(jmat),
                    eigenvalues=np.asarray(wr) + 1j*np.asarray(wi),
                    kind=_kind_text(int(kind), dnames, float(sfreq), int(fdim)),
                    saddle=bool(saddle), residual=float(residual), analytic=bool(analytic),
                    zero_multiplicity=int(zero_mult), largest_block=int(block),
                    secular_frequency=float(sfreq), drift=drift, drift_names=dnames,
                    family_dim=int(fdim), family=family, state_names=names)
    e.njev = njev
    e.relative = _relative(system, e, t, tol, integrals)
    return e


def _integral_data(system, y, t, integrals):
    """(names, gradients k x n, energy Hessian n x n or None) of the first integrals at y."""
    if integrals is None:
        return None
    if isinstance(integrals, str):
        if integrals != "auto":
            raise ValueError("integrals must be 'auto', None or a list of callables")
        fi = getattr(system, "first_integrals", None)
        if fi is None or not getattr(fi, "cyclic", None):
            return None
        return fi.names, fi.gradients(y, t), fi.energy_hessian(y, t)
    if callable(integrals):
        integrals = [integrals]
    if not isinstance(integrals, (list, tuple)):
        raise TypeError("integrals must be 'auto', None, a callable I(y) or a list of them "
                        f"(or of (name, I, grad) triples), got {type(integrals).__name__}")
    names, grads = [], []
    for k, item in enumerate(integrals):
        if isinstance(item, tuple) and len(item) == 3:
            name, fun, grad = item
            gr = np.asarray(grad(y), dtype=float).ravel()
        elif callable(item):
            name, fun = f"I{k}", item
            gr = _fd_gradient(fun, y)
        else:
            raise TypeError(f"integrals[{k}] must be a callable I(y) or a (name, I, grad) "
                            "triple")
        if gr.shape != y.shape or not np.all(np.isfinite(gr)):
            raise ValueError(f"integrals[{k}]: the gradient must be finite with {y.size} "
                             "components")
        names.append(str(name))
        grads.append(gr)
    return names, np.array(grads).reshape(len(grads), y.size), None


def _fd_gradient(fun, y):
    g = np.empty(y.size)
    for i in range(y.size):
        h = np.finfo(float).eps**(1/3)*max(1.0, abs(y[i]))
        yp, ym = y.copy(), y.copy()
        yp[i] += h
        ym[i] -= h
        g[i] = (float(fun(yp)) - float(fun(ym)))/(2*h)
    return g


def _relative(system, e, t, tol, integrals):
    """The classification relative to the first integrals and the family (or None)."""
    data = _integral_data(system, e.y, t, integrals)
    if data is None:
        return None
    names, grads, hess = data
    n = e.y.size
    k = grads.shape[0]
    d = e.family_dim
    if k == 0 and d == 0:
        return None
    gpad = np.zeros((max(k, 1), n), order="F")
    gpad[:k] = grads
    fpad = np.zeros((n, max(d, 1)), order="F")
    fpad[:, :d] = e.family
    ar, w, m, info, message = _conmech.flat_relative_linearization(
        k, d, np.asfortranarray(e.jacobian), gpad, fpad)
    if info != 0:
        raise_status(info, message)
    m = int(m)
    if m == 0:
        return None
    ar = np.array(ar)[:m, :m]
    w = np.array(w)[:, :m]
    wr, wi, kind, saddle, zm, block, sfreq, ndrift, drift, info, message = \
        _conmech.flat_classify_matrix(np.asfortranarray(ar), tol)
    if info != 0:
        raise_status(info, message)
    ld, ew = None, None
    if hess is not None:
        hr = w.T @ np.asarray(hess, dtype=float) @ w
        ld, ew = lagrange_dirichlet(0.5*(hr + hr.T), tol=1e-8)
    return RelativeEquilibrium(jacobian=ar, basis=w, eigenvalues=np.asarray(wr) + 1j*np.asarray(wi),
                               kind=_kind_text(int(kind), (), float(sfreq)),
                               saddle=bool(saddle), integrals=list(names),
                               lagrange_dirichlet=ld, energy_eigenvalues=ew)


def lagrange_dirichlet(hessian: ArrayLike, tol: float = 1e-10) -> tuple:
    """Lagrange-Dirichlet test: (positive definite?, eigenvalues ascending) of a symmetric
    Hessian of the potential energy (LAPACK dsyev)."""
    h = np.asfortranarray(np.asarray(hessian, dtype=float))
    if h.ndim != 2 or h.shape[0] != h.shape[1] or h.size == 0:
        raise ValueError("hessian must be a non-empty square matrix")
    if not np.all(np.isfinite(h)):
        raise ValueError("hessian must be finite")
    stable, w, info = _conmech.flat_lagrange_dirichlet(h, float(tol))
    if info == BAD_INPUT:
        raise ValueError("hessian must be symmetric")
    if info != 0:
        raise RuntimeError("dsyev failed")
    return bool(stable), np.array(w)

def find_equilibrium(system: Any, guess: ArrayLike, t: float = 0.0, tol: float = 1e-12,
                     max_iter: int = 50, classify_tol: float = 1e-8,
                     integrals: Any = "auto") -> Equilibrium:
    """Newton's method for f(t, y) = 0 from ``guess`` (analytic Jacobian of built-in and
    compiled systems, central differences for callables) with minimum-norm steps
    (LAPACK dgelsd): on a family of equilibria (a cyclic coordinate's line, where the
    Jacobian is singular everywhere) it converges to a member. Then :func:`equilibrium` at
    the root: returns the classified :class:`Equilibrium` (with ``family_dim``). Raises
    RuntimeError when Newton fails (no convergence, or a singular Jacobian where f does not
    vanish) or the residual at the root exceeds sqrt(tol)."""
    y = _state(guess, "guess")
    _check_dim(system, y)
    if not (np.isfinite(tol) and tol > 0) or int(max_iter) < 1:
        raise ValueError("tol must be positive and max_iter >= 1")
    g, sargs = _system_args(system, y.size, y, float(t))
    yout, info, message = _conmech.flat_find_equilibrium(*sargs, y, float(t), float(tol),
                                                         int(max_iter))
    if g is not None:
        g.check()
    if info != 0:
        raise_status(info, message)
    e = equilibrium(system, np.array(yout), t=t, tol=classify_tol, integrals=integrals)
    if not e.residual <= max(np.sqrt(tol), 1e-8)*max(1.0, np.max(np.abs(e.y))):
        raise RuntimeError(f"find_equilibrium: residual {e.residual:.3g} at the root")
    return e


def equilibria(system: Any, guesses: ArrayLike, t: float = 0.0, tol: float = 1e-12,
               dedup_tol: float = 1e-8, classify_tol: float = 1e-8,
               integrals: Any = "auto") -> list:
    """All equilibria reached by Newton from an array of guesses (shape (k, n)), e.g. a
    grid; duplicates (max-norm distance <= dedup_tol max(1, |y|)) removed, and members of
    the same straight family (their difference lies along the family's tangent, e.g. the
    cart at any x) reported once, with ``family_dim``. Guesses whose Newton fails are
    skipped. Returns a list of :class:`Equilibrium`, sorted by y."""
    found = multistart(guesses, lambda y: find_equilibrium(
        system, y, t=t, tol=tol, classify_tol=classify_tol, integrals=integrals),
        lambda e, f: _same(e, f, dedup_tol))
    found.sort(key=lambda e: tuple(e.y))
    return found


def multistart(guesses, solve, same):
    """The distinct results of ``solve(g)`` over the rows g of the (k, n) array `guesses`,
    in the order found: a guess whose Newton iteration fails (RuntimeError) is skipped, a
    result that is ``same(e, f)`` as one found before is dropped."""
    gs = np.asarray(guesses, dtype=float)
    if gs.ndim != 2 or gs.shape[0] == 0:
        raise ValueError("guesses must be a non-empty (k, n) array")
    found = []
    for g in gs:
        try:
            e = solve(g)
        except RuntimeError:
            continue
        if not any(same(e, f) for f in found):
            found.append(e)
    return found


def _same(e, f, dedup_tol):
    """e and f are the same equilibrium, or members of f's (straight) family."""
    d = e.y - f.y
    if f.family_dim:
        d = d - f.family @ (f.family.T @ d)
    return np.max(np.abs(d)) <= dedup_tol*max(1.0, np.max(np.abs(f.y)))


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

