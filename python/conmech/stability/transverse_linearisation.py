"""Transverse linearisation of a periodic orbit of any system: moving transverse
coordinates, reduced by the energy and by the constraints, and the periodic coefficient
matrix A_perp(t) with its monodromy (Fortran: conmech_transverse_general)."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from .. import _conmech
from .._core.callback import Guard, as_result
from .._core.native import _NO_SPEC, _PAD, NativeSystem, _unused_callback
from ..mechanics.constrained import NativeConstrained
from .._core.validate import _real, _state
from .._core.result import Record
from .._core.status import raise_status

__all__ = ["TransverseLinearisation", "transverse_linearisation", "nontrivial_multipliers"]

_ENERGY = {"none": 0, False: 0, "auto": 1, None: 1, "required": 2, True: 2}


class TransverseLinearisation(Record):
    """Result of :func:`transverse_linearisation`.

    Attributes
    ----------
    y0, period : the orbit.
    dimension : k, the number of transverse coordinates: N - 1 (2n - 1 for a mechanical
        system), minus one when the energy was removed (``reduced``), minus the
        constraint normals (2 per holonomic, 1 per Pfaffian constraint).
    reduced : bool, the energy integral was removed.
    t : (nt,) the sample times; ``states`` (nt, N) the orbit there; ``A`` (nt, k, k) the
        periodic coefficient matrix A_perp(t); ``frame`` (nt, N, k) the periodic frame
        Q(t) (orthonormal columns spanning the transverse space, Q(T) = Q(0)).
    monodromy : (k, k) the transverse monodromy (of xi' = A_perp(t) xi over a period);
        ``multipliers`` its eigenvalues.
    full_monodromy, full_multipliers : the N x N monodromy of the orbit (same run).
    nontrivial : the k full multipliers that are not trivial (the k farthest from 1; the
        other N - k belong to the flow direction, the energy and the constraints), ordered
        to match ``multipliers``; ``agreement`` = max |difference|.
    holonomy : (k, k) the rotation R = Q(0)^T Q(T) of the transported frame.
    closure : max |x(T) - x(0)| of the orbit; ``energy_drift``: max |grad H . f| /
        (|grad H| |f|) along it (how well the energy is conserved; 0 if none).
    hill_phi, hill_psi : (nt,) for two degrees of freedom with the energy removed: the
        coefficients of N'' + psi N' + phi N = 0 for the normal deviation N = n . dq
        (n the unit normal to q' in the configuration plane); psi = 0 and phi = Hill's
        Phi(t) for natural systems with identity mass. NaN where q' = 0. None otherwise.
    nfev : right-hand side evaluations of the augmented run.
    """

    __slots__ = ("y0", "period", "dimension", "reduced", "t", "states", "A", "frame",
                 "monodromy", "multipliers", "full_monodromy", "full_multipliers",
                 "nontrivial", "agreement", "holonomy", "closure", "energy_drift",
                 "frame_defect", "hill_phi", "hill_psi", "nfev", "kind")

    def __repr__(self):
        mu = ", ".join(f"{m:.6g}" for m in self.multipliers)
        return (f"TransverseLinearisation(k={self.dimension}, reduced={self.reduced}, "
                f"multipliers=[{mu}], agreement={self.agreement:.2e})")


def nontrivial_multipliers(full: ArrayLike, k: int, match: ArrayLike | None = None):
    """The k multipliers of a monodromy matrix (or of its eigenvalues ``full``) farthest
    from 1 (the others belong to the flow direction, the energy and the constraints). With
    ``match``: ordered to pair with those values (greedy, nearest first)."""
    mu = np.asarray(full)
    if mu.ndim == 2:
        mu = np.linalg.eigvals(mu)
    mu = mu.astype(complex)
    out = mu[np.argsort(np.abs(mu - 1.0), kind="stable")][mu.size - k:]
    if match is None:
        return out
    match = np.asarray(match, dtype=complex)
    left = list(range(out.size))
    res = np.empty(match.size, dtype=complex)
    pairs = sorted((abs(match[i] - out[j]), i, j) for i in range(match.size)
                   for j in range(out.size))
    used_i, used_j = set(), set()
    for _, i, j in pairs:
        if i in used_i or j in used_j:
            continue
        res[i] = out[j]
        used_i.add(i)
        used_j.add(j)
    del left
    return res


def _orbit_args(orbit, period):
    if period is None:
        y0 = getattr(orbit, "y0", None)
        p = getattr(orbit, "period", None)
        if y0 is None or p is None:
            try:
                y0, p = orbit
            except (TypeError, ValueError):
                raise TypeError("orbit must be a PeriodicOrbit (y0, period attributes) or a "
                                "pair (y0, period)") from None
    else:
        y0, p = orbit, period
    return _state(y0, "orbit y0"), _real(p, "period", 0.0, low_open=True)


def transverse_linearisation(system: Any, orbit: Any, period: float | None = None, *,
                             energy: Any = "auto", t: ArrayLike | None = None,
                             nt: int = 65, rtol: float = 1e-12, atol: float = 1e-12,
                             jac: Callable | None = None,
                             energy_gradient: Callable | None = None,
                             full_monodromy: bool = True) -> TransverseLinearisation:
    """Transverse linearisation of the periodic orbit ``orbit`` of ``system``.

    Moving sections normal to the flow, z(t) = f(x*(t)), give the coordinates
    x = x*(tau) + Q(tau) xi; Q spans the transverse space, from which the invariants are
    removed: the energy (when the system is conservative) and, in excessive coordinates,
    the constraint manifold (phi = 0, G v = 0, Pfaffian rows). The result holds the
    periodic coefficient matrix A_perp(t) of xi' = A_perp(t) xi sampled along the orbit,
    its monodromy (2n - 2 coordinates with the energy removed, 2n - 1 without) and its
    multipliers, which are the non-trivial multipliers of the full monodromy (checked:
    ``agreement``).

    Parameters
    ----------
    system : a built-in or compiled system (:mod:`conmech.systems`, ``conmech.symbolic``,
        ``conmech.compiled``; generalized coordinates use their energy), a constrained
        system in excessive coordinates (``conmech.systems.double_pendulum_xy()``, a
        compiled or symbolic constrained system; scleronomic), or a Python callable
        ``fun(t, y)``.
    orbit : a :class:`PeriodicOrbit` (``y0``, ``period``), a pair (y0, period), or y0
        with ``period`` given. For a constrained system y0 = [q, v] on the constraints.
    energy : "auto" (remove the energy when the system has one and it is conserved along
        the orbit, to 1e-7 relative), "none" (keep it: 2n - 1 coordinates) or
        "required" (remove it or raise ValueError).
    t : sample times in [0, period] (default ``nt`` equally spaced, both ends included).
    rtol, atol : tolerances of every integration (the orbit check and the one run that
        integrates the orbit, the invariant covectors, the frame, the transverse and the
        full monodromy, Verner 9(8)).
    jac : exact Jacobian jac(t, y) of a Python system (default: finite differences).
    energy_gradient : grad H(y) of a Python system (the callable returns an (N,) array;
        needed to remove the energy of a Python system).
    full_monodromy : also integrate the N x N monodromy for the check.

    Raises ValueError for an orbit that does not close (``|x(T) - x(0)|`` above
    max(1e-8, 1e3 max(rtol, atol)) max(1, |y0|)), a vector field that vanishes on it,
    y0 off the constraints, or an energy that is required but not conserved.
    """
    y0, per = _orbit_args(orbit, period)
    mode = _ENERGY.get(energy if not isinstance(energy, str) else energy.lower())
    if mode is None:
        raise ValueError("energy must be 'auto', 'none' or 'required'")
    if isinstance(nt, bool) or not isinstance(nt, (int, np.integer)) or not 2 <= nt <= 10**6:
        raise ValueError("nt must be an integer in [2, 1e6]")
    if t is None:
        tt = np.linspace(0.0, per, int(nt))
    else:
        tt = np.ascontiguousarray(np.asarray(t, dtype=float).ravel())
        if tt.size == 0 or not np.all(np.isfinite(tt)) or np.any(tt < 0) or \
                np.any(tt > per*(1 + 1e-12)):
            raise ValueError("t must hold finite times in [0, period]")
    rtol = _real(rtol, "rtol", 0.0, 1.0, low_open=True)
    atol = _real(atol, "atol", 0.0, low_open=True)
    if not rtol < 1.0:
        raise ValueError("rtol must be < 1")
    n = y0.size
    full = int(bool(full_monodromy))
    if isinstance(system, (NativeSystem, NativeConstrained)):
        if jac is not None or energy_gradient is not None:
            raise TypeError("jac and energy_gradient are for Python callables; a built-in or "
                            "compiled system has its own")
        if isinstance(system, NativeConstrained):
            if n != 2*system.n:
                raise ValueError(f"y0 must be [q, v] with {2*system.n} values for this "
                                 f"constrained system, got {n}")
            kmax = n - 1 - 2*system.n_hol - system.n_nh
        else:
            if n != system.dimension:
                raise ValueError(f"y0 has {n} components; the system has {system.dimension}")
            kmax = n - 1
        if kmax < 1:
            raise ValueError("the system has no transverse coordinate (N - 1 - constraints "
                             "< 1)")
        g = None
        sargs = (*system._flat_args(), _unused_callback, _unused_callback, 0,
                 _unused_callback, 0)
    elif callable(system):
        if jac is not None and not callable(jac):
            raise TypeError("jac must be a callable jac(t, y) -> (n, n), or None")
        if energy_gradient is not None and not callable(energy_gradient):
            raise TypeError("energy_gradient must be a callable grad(y) -> (n,), or None")
        as_result(system(0.0, y0.copy()), (n,), "fun")
        g = Guard()
        rhs = g.wrap(system, 2, (n,), "fun")
        dfdy = g.wrap(jac, 2, (n, n), "jac") if jac is not None else _never(g, (n, n))
        if energy_gradient is not None:
            as_result(energy_gradient(y0.copy()), (n,), "energy_gradient")
            eg = g.wrap(lambda t, y: energy_gradient(y), 2, (n,), "energy_gradient")
        else:
            eg = _never(g, (n,))
        kmax = n - 1
        if kmax < 1:
            raise ValueError("y0 must have at least 2 components")
        sargs = ("", 0, _PAD, 0, _NO_SPEC, rhs, dfdy, 1 if jac is None else 2, eg,
                 int(energy_gradient is not None))
    else:
        raise TypeError("system must be a conmech system (built-in, compiled, symbolic, "
                        "constrained) or a callable fun(t, y)")
    out = _conmech.flat_transverse_general(*sargs, y0, per, rtol, atol, mode, full, tt, kmax)
    if g is not None:
        g.check()
    (k, reduced, closure, drift, defect, mono, mr, mi, fmono, fre, fim, holo, xs, qs, as_,
     phis, psis, nfev, kind, info, message) = out
    if info != 0:
        raise_status(info, message)
    k = int(k)
    mu = np.asarray(mr)[:k] + 1j*np.asarray(mi)[:k]
    res = dict(y0=y0, period=per, dimension=k, reduced=bool(reduced), t=tt,
               states=np.array(xs).T.copy(), A=np.moveaxis(np.array(as_)[:k, :k, :], 2, 0),
               frame=np.moveaxis(np.array(qs)[:, :k, :], 2, 0),
               monodromy=np.array(mono)[:k, :k], multipliers=mu,
               holonomy=np.array(holo)[:k, :k], closure=float(closure),
               energy_drift=float(drift), frame_defect=float(defect), nfev=int(nfev),
               kind={0: "ode", 1: "constrained", 2: "generalized"}.get(int(kind), "ode"))
    if full:
        fm = np.array(fmono)
        fmu = np.asarray(fre) + 1j*np.asarray(fim)
        nt_mu = nontrivial_multipliers(fmu, k, match=mu)
        res.update(full_monodromy=fm, full_multipliers=fmu, nontrivial=nt_mu,
                   agreement=float(np.max(np.abs(nt_mu - mu))) if k else 0.0)
    else:
        res.update(agreement=float("nan"))
    if bool(reduced) and n == 4 and k == 2:
        res.update(hill_phi=np.array(phis), hill_psi=np.array(psis))
    return TransverseLinearisation(**res)


def _never(g, shape):
    """A callback for an optional argument that is not used (the flat routine is told)."""
    return g.wrap(lambda t, y: np.zeros(shape), 2, shape, "unused")
