"""Orbital stabilisation by transverse LQR (Fortran: conmech_orbital_stabilisation,
conmech_transverse_lqr)."""
from __future__ import annotations

from typing import Any, Callable  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from .. import _conmech
from .._core.callback import Guard
from .plant import ControlledSystem, FeedbackLaw, _as_law, _law_args
from .riccati import check_weights
from .vhc import ReducedOrbit
from .._core.status import raise_status

__all__ = ["TransverseLQR", "orbital_stabilisation"]


class TransverseLQR(FeedbackLaw):
    """The orbitally stabilising feedback u = u_nom(x) + K(tau) xi designed by
    :func:`orbital_stabilisation`, evaluated in Fortran (no Python in the loop unless the
    nominal law is a Python callable).

    Attributes
    ----------
    plant, nominal, y0, period, dimension (k = 2 ndof - 1)
    t : (nt,) sample times; A, B (nt, k, k), (nt, k, m): the transverse linearisation
        with the input, A_perp(t) and B_perp(t); P (nt, k, k) the stabilising periodic
        Riccati solution; K (nt, m, k) the gain.
    open_loop_multipliers : of the transverse linearisation with the nominal law only.
    multipliers : the closed-loop transverse multipliers (strictly inside the unit circle).
    hamiltonian_multipliers, periodicity (of P), min_eigenvalue (of P), passes.
    gramian_eigenvalues : of the controllability Gramian over one period.
    nonlinear_multipliers : of the N x N monodromy of the nonlinear closed loop under this
        law (finite-difference Jacobian of the law): one is the trivial 1, the others
        match ``multipliers``.
    closure : max |x(T) - x(0)| of the orbit under the nominal law.
    """

    def __init__(self, plant, nominal, y0, period, k, ng, rtab, samples):
        self.plant = plant
        self.nominal = nominal
        self.y0 = y0
        self.period = period
        self.dimension = k
        self.ng = ng
        self._rtab = rtab
        self.n_inputs = plant.n_inputs
        for key, v in samples.items():
            setattr(self, key, v)

    def _flat(self):
        il, rl, py = self.nominal._flat()
        n = self.plant.dimension
        ilaw = np.concatenate([np.array([4, self.n_inputs, n, self.dimension, self.ng],
                                        dtype=np.int64), il])
        return ilaw, np.concatenate([self._rtab, rl]), py

    def project(self, x):
        """(tau, xi, distance) of one state (N,) or many (nx, N): the phase (the orbit
        point whose section holds x), the transverse coordinates and |x - x*(tau)|."""
        x = np.asarray(x, dtype=float)
        one = x.ndim == 1
        xs = np.atleast_2d(x)
        n = self.plant.dimension
        if xs.shape[1] != n:
            raise ValueError(f"states must have {n} components")
        g = Guard()
        out = _conmech.flat_control_project(**self.plant._flat(), **_law_args(self.plant, self, g),
                                            n=n, k=self.dimension, xs=np.asfortranarray(xs.T))
        g.check()
        taus, xis, dists, nfail, info, message = out
        if info != 0:
            raise_status(info, message)
        taus, xis, dists = np.array(taus), np.array(xis).T, np.array(dists)
        return (taus[0], xis[0], dists[0]) if one else (taus, xis, dists)

    def distance(self, x):
        """The orbital distance |x - x*(tau(x))| of one state or many."""
        return self.project(x)[2]

    def __repr__(self):
        r = np.max(np.abs(self.multipliers))
        return (f"TransverseLQR(k={self.dimension}, period={self.period:.6g}, largest "
                f"closed-loop multiplier {r:.4g})")


def orbital_stabilisation(plant: ControlledSystem, orbit: Any, nominal: Any = None,
                          Q: ArrayLike | None = None, R: ArrayLike | None = None, *,
                          kp: ArrayLike = 0.0, kd: ArrayLike = 0.0, ng: int = 400,
                          nt: int = 65, rtol: float = 1e-11,
                          atol: float = 1e-11) -> TransverseLQR:
    """Design the transverse LQR that makes a periodic orbit orbitally asymptotically
    stable.

    Parameters
    ----------
    plant : :class:`ControlledSystem`.
    orbit : a :class:`ReducedOrbit` of a virtual constraint (the nominal law is then the
        constraint's feedback with gains ``kp``, ``kd`` unless ``nominal`` is given), or
        a periodic orbit (``y0``, ``period``, a PeriodicOrbit or a pair) of the closed
        loop under ``nominal``.
    nominal : the nominal law u_nom (a conmech law, a compiled law, a Python callable).
    Q, R : weights of the transverse LQR (k x k and m x m, k = 2 ndof - 1; scalars or
        diagonals allowed; default identities).
    ng : phases in the controller's table; nt : sample times of the returned data.

    The transverse linearisation of the closed loop under u_nom with the additive input
    (2 ndof - 1 coordinates), a stabilisability check (the controllability Gramian over a
    period; an uncontrollable multiplier on or outside the unit circle is a ValueError),
    the stabilising periodic Riccati solution (RuntimeError if there is none), the gain
    table; then the N x N monodromy of the nonlinear closed loop as a check.
    """
    if not isinstance(plant, ControlledSystem):
        raise TypeError("plant must be a conmech.control.ControlledSystem")
    if isinstance(orbit, ReducedOrbit):
        if orbit.constraint.plant is not plant:
            raise ValueError("the reduced orbit belongs to another plant")
        y0, period = orbit.x0, orbit.period
        if nominal is None:
            nominal = orbit.constraint.feedback(kp, kd)
    else:
        y0 = getattr(orbit, "y0", None)
        period = getattr(orbit, "period", None)
        if y0 is None:
            try:
                y0, period = orbit
            except (TypeError, ValueError):
                raise TypeError("orbit must be a ReducedOrbit, a PeriodicOrbit or a pair "
                                "(y0, period)") from None
        if nominal is None:
            raise ValueError("a nominal law is needed for an orbit that is not a "
                             "ReducedOrbit")
    nominal = _as_law(plant, nominal)
    y0 = np.ascontiguousarray(np.asarray(y0, dtype=float).ravel())
    period = float(period)
    n = plant.dimension
    if y0.size != n or not np.all(np.isfinite(y0)):
        raise ValueError(f"the orbit's y0 must hold {n} finite values")
    if not (np.isfinite(period) and period > 0):
        raise ValueError("the period must be positive and finite")
    k, m = n - 1, plant.n_inputs
    q, r = check_weights(Q, R, k, m)
    ng = int(ng)
    if ng < 8:
        raise ValueError("ng must be >= 8")
    tt = np.linspace(0, period, int(nt))
    ntab = 1 + 3*n*(ng + 1) + 2*n*k*(ng + 1) + 2*m*k*(ng + 1)
    g = Guard()
    out = _conmech.flat_control_design(**plant._flat(), **_law_args(plant, nominal, g), n=n,
                                       y0=y0, period=period, k=k, qw=q, rw=r, ng=ng,
                                       rtol=float(rtol), atol=float(atol), t=tt, ntab=ntab)
    g.check()
    (as_, bs, ps, ks, omr, omi, gev, hmr, hmi, cmr, cmi, periodicity, min_eig, passes, rtab,
     fmr, fmi, closure, info, message) = out
    if info != 0:
        raise_status(info, message)
    samples = dict(t=tt, A=np.moveaxis(np.array(as_), 2, 0), B=np.moveaxis(np.array(bs), 2, 0),
                   P=np.moveaxis(np.array(ps), 2, 0), K=np.moveaxis(np.array(ks), 2, 0),
                   open_loop_multipliers=np.asarray(omr) + 1j*np.asarray(omi),
                   gramian_eigenvalues=np.array(gev),
                   hamiltonian_multipliers=np.asarray(hmr) + 1j*np.asarray(hmi),
                   multipliers=np.asarray(cmr) + 1j*np.asarray(cmi),
                   periodicity=float(periodicity), min_eigenvalue=float(min_eig),
                   passes=int(passes),
                   nonlinear_multipliers=np.asarray(fmr) + 1j*np.asarray(fmi),
                   closure=float(closure), message=str(message))
    return TransverseLQR(plant, nominal, y0, period, k, ng, np.array(rtab), samples)
