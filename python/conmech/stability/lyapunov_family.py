"""Normal modes of an equilibrium of a conservative system and the Lyapunov families of
periodic orbits born at its elliptic ones (Lyapunov's centre theorem), continued along
the family (in the period, with the energy of every orbit)."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from ..mechanics.compiled import CompiledSystem, evaluate
from .._core.native import NativeSystem
from .._core.validate import _count, _real, _state
from .continuation import Branch, continuation
from .equilibria import equilibrium, find_equilibrium
from .variational import stm
from .._core.result import Record

__all__ = ["NormalModes", "normal_modes", "LyapunovFamily", "lyapunov_family"]

#: An eigenvalue pair counts as elliptic (+-i omega) when |Re lambda| <= ELLIPTIC_RTOL |lambda|.
ELLIPTIC_RTOL = 1e-7
#: Another eigenvalue lambda_j is resonant with the mode omega_k when
#: |lambda_j/(i omega_k) - n| <= RESONANCE_TOL for an integer n (n = 0: a zero eigenvalue).
RESONANCE_TOL = 1e-6


class NormalModes(Record):
    """The linearisation of a conservative system at an equilibrium
    (:func:`normal_modes`): y_eq (the equilibrium state), eigenvalues (all), omega (the
    frequencies of the elliptic pairs +-i omega, ascending: mode 0 is the slowest), vectors
    (complex eigenvectors of J for +i omega, columns, each normalised to unit length with
    the largest possible real part), left (the matching left eigenvectors, u^H v = 1),
    periods (2 pi/omega), resonant (for each mode, the resonances with the other
    eigenvalues as text, empty when none: Lyapunov's theorem needs none), hyperbolic (the
    number of eigenvalues off the imaginary axis)."""

    __slots__ = ("y_eq", "eigenvalues", "omega", "vectors", "left", "resonant", "hyperbolic",
                 "jacobian")

    @property
    def periods(self):
        return 2.0*np.pi/self.omega

    def __repr__(self):
        return f"NormalModes(omega={self.omega!r}, hyperbolic={self.hyperbolic})"


class LyapunovFamily(Branch):
    """A :class:`~conmech.stability.Branch` of the Lyapunov family of one normal mode
    (continued in the period: ``p`` holds the period, ``param`` is 'period'), with
    ``energy`` filled, plus: mode, omega (its frequency), equilibrium (y_eq),
    energy_equilibrium, start (the two orbits of amplitudes a and 2 a that started it:
    (y0, period, energy) each)."""

    __slots__ = ("mode", "omega", "equilibrium", "energy_equilibrium", "start")


def _equilibrium_state(system, q_eq, jac):
    """The equilibrium state y_eq from a configuration (y = [q, 0]) or a full state,
    polished by Newton; ValueError if it is not (near) an equilibrium."""
    q = _state(q_eq, "q_eq")
    if isinstance(system, NativeSystem):
        n = system.dimension
        if q.size == n:
            y = q
        elif 2*q.size == n:
            y = np.concatenate([q, np.zeros_like(q)])
        else:
            raise ValueError(f"q_eq has {q.size} components: the configuration ({n//2}) or "
                             f"the state ({n}) of the system '{system.name}' is expected")
    else:
        if not callable(system):
            raise TypeError("system must be a conmech.systems.NativeSystem or a callable "
                            "fun(t, y)")
        y = q
    try:
        e = find_equilibrium(system, y)
    except RuntimeError as exc:
        raise ValueError(f"q_eq is not an equilibrium: Newton's method from it fails "
                         f"({exc})") from None
    scale = max(1.0, float(np.max(np.abs(y))))
    if not np.max(np.abs(e.y - y)) <= 1e-6*scale:
        raise ValueError(f"q_eq is not an equilibrium: the nearest one Newton finds is "
                         f"{e.y.tolist()} (distance {np.max(np.abs(e.y - y)):.3g})")
    if jac is not None:
        e = equilibrium(system, e.y, jac=jac)
    return e


def normal_modes(system: Any, q_eq: ArrayLike, jac=None) -> NormalModes:
    """The normal modes of the equilibrium ``q_eq`` of a conservative system: the elliptic
    eigenvalue pairs +-i omega of the linearisation, slowest first (see
    :class:`NormalModes`). ``q_eq``: the equilibrium configuration q (the state is then
    [q, 0], as for systems in generalized coordinates) or the full equilibrium state (a
    callable ``fun(t, y)`` needs the full state); it is polished by Newton's method.
    ``jac``: the exact Jacobian of a callable. ValueError if ``q_eq`` is not an
    equilibrium."""
    e = _equilibrium_state(system, q_eq, jac)
    lam = np.asarray(e.eigenvalues, dtype=complex)
    jm = np.asarray(e.jacobian, dtype=float)
    w, vr = np.linalg.eig(jm)
    scale = np.maximum(np.abs(w), 1e-300)
    ell = (np.abs(w.real) <= ELLIPTIC_RTOL*scale) & (w.imag > 0)
    idx = np.flatnonzero(ell)
    idx = idx[np.argsort(w.imag[idx])]
    omega = w.imag[idx]
    wl, vl = np.linalg.eig(jm.T)          # J^T u' = lambda u': left vectors conj(u')
    vectors = np.empty((jm.shape[0], idx.size), dtype=complex)
    left = np.empty_like(vectors)
    resonant = []
    for c, i in enumerate(idx):
        v = vr[:, i]
        v = v*np.exp(-0.5j*np.angle(np.sum(v*v)))    # the largest real part
        v = v/np.linalg.norm(v)
        # the sign of an eigenvector is arbitrary (LAPACK's choice): fix it, so that a
        # family always starts on the same side of the equilibrium
        v = v if v.real[int(np.argmax(np.abs(v.real)))] >= 0 else -v
        j = int(np.argmin(np.abs(wl - w[i])))
        u = np.conj(vl[:, j])
        with np.errstate(divide="ignore", invalid="ignore"):    # (a 1:1 resonance)
            u = u/np.conj(np.vdot(u, v))              # u^H v = 1
        vectors[:, c] = v
        left[:, c] = u
        notes = []
        others = np.delete(lam, [int(np.argmin(np.abs(lam - w[i]))),
                                 int(np.argmin(np.abs(lam - np.conj(w[i]))))])
        for lj in others:
            ratio = lj/(1j*w[i].imag)
            nr = np.round(ratio.real)
            if abs(ratio - nr) <= RESONANCE_TOL:
                notes.append("a zero eigenvalue" if nr == 0 else
                             f"eigenvalue {lj:.6g} = {int(nr)} i omega")
        resonant.append("; ".join(notes))
    hyper = int(np.count_nonzero(np.abs(lam.real) > ELLIPTIC_RTOL*np.maximum(np.abs(lam),
                                                                             1e-300)))
    return NormalModes(y_eq=np.array(e.y), eigenvalues=lam, omega=omega, vectors=vectors,
                       left=left, resonant=resonant, hyperbolic=hyper, jacobian=jm)


def _small_orbit(system, y_eq, v, u, period, eps, rtol, jac, max_iter=30):
    """The periodic orbit with mode coordinate z = u^H (y0 - y_eq) = eps (real): Gauss-
    Newton on [y(T) - y0, Im z, Re z - eps] = 0 in (y0, T) (n + 2 equations of rank n + 1:
    the energy makes one redundant), from the linear mode y_eq + 2 eps Re v."""
    n = y_eq.size
    y0 = y_eq + 2.0*eps*np.real(v)
    t = float(period)
    scale = max(1.0, float(np.max(np.abs(y_eq))))
    for _ in range(max_iter):
        y1, phi = stm(system, (0.0, t), y0, rtol=rtol, atol=rtol, jac=jac)
        f1 = np.asarray(system(t, y1) if not isinstance(system, NativeSystem) else
                        _rhs(system, y1), dtype=float)
        z = np.vdot(u, y0 - y_eq)
        r = np.concatenate([y1 - y0, [z.imag, z.real - eps]])
        a = np.zeros((n + 2, n + 1))
        a[:n, :n] = phi - np.eye(n)
        a[:n, n] = f1
        a[n, :n] = np.imag(np.conj(u))
        a[n + 1, :n] = np.real(np.conj(u))
        dx = np.linalg.lstsq(a, -r, rcond=None)[0]
        y0 = y0 + dx[:n]
        t = t + dx[n]
        if np.max(np.abs(dx)) <= 1e-13*max(scale, t) and np.max(np.abs(r[:n])) <= 1e-9*scale:
            return y0, t
    raise RuntimeError(f"the small orbit of the mode (amplitude {eps:.3g}) was not found: "
                       f"Gauss-Newton did not converge (residual {np.max(np.abs(r)):.3g})")


def _rhs(system, y):
    return evaluate(system, 0.0, y)["f"]


def lyapunov_family(system: Any, q_eq: ArrayLike, mode: int = 0, *, amplitude: float = 1e-3,
                    energy: Callable | None = None, jac: Callable | None = None,
                    energy_range=None, rtol: float = 1e-12, **options) -> LyapunovFamily:
    """The Lyapunov family of periodic orbits born at normal mode ``mode`` (0: the slowest
    elliptic pair +-i omega, see :func:`normal_modes`) of the equilibrium ``q_eq`` of a
    conservative system, continued along the family (in the period, by
    :func:`~conmech.stability.continuation` with ``in_period=True, conservative=True``),
    with the energy of every orbit.

    The family starts on its own: the orbits with mode amplitude ``amplitude`` and twice
    that (relative to max(1, |y_eq|); the mode coordinate z = u^H (y0 - y_eq) real,
    Gauss-Newton on the shooting equations) give the first point and the direction away
    from the equilibrium. ``energy(y)``: the first integral (default: ``system.energy``
    of a built-in or compiled system; required for a callable ``fun(t, y)``).
    ``energy_range``: (E_min, E_max): the branch is cut at its last point inside.
    ``jac``: the exact Jacobian of a callable, for the normal modes and the first orbits
    (the continuation of a callable uses finite differences).
    Other options as for continuation (max_points, ds, ds_max, p_range = a period range,
    rtol, tol, locate, ...).

    Raises ValueError when ``q_eq`` is not an equilibrium, ``mode`` is not an elliptic mode
    (the message lists the eigenvalues), or the mode is resonant (another eigenvalue equals
    n i omega, n integer, including a zero eigenvalue: Lyapunov's theorem does not apply),
    and when the period does not change along the family near the equilibrium (it cannot
    be continued in the period). The small orbits' period tends to 2 pi/omega."""
    for bad in ("in_period", "conservative", "param", "p0", "free", "targets", "energy",
                "_switch", "_tangent", "direction", "autonomous", "fixed_period"):
        if bad in options:
            raise ValueError(f"{bad} is not an option of lyapunov_family")
    if isinstance(mode, (bool, np.bool_)) or not isinstance(mode, (int, np.integer)):
        raise TypeError(f"mode must be an integer, got {type(mode).__name__}")
    amplitude = _real(amplitude, "amplitude", 0.0, low_open=True)
    rtol = _real(rtol, "rtol", 0.0, low_open=True)
    if jac is not None and isinstance(system, NativeSystem):
        raise TypeError("jac is for Python callables; a built-in system has its own Jacobian")
    nm = normal_modes(system, q_eq, jac=jac)
    if not 0 <= int(mode) < nm.omega.size:
        raise ValueError(f"mode {mode} is not an elliptic mode of the equilibrium: it has "
                         f"{nm.omega.size} (frequencies {nm.omega.tolist()}); eigenvalues "
                         f"{np.round(nm.eigenvalues, 10).tolist()}")
    k = int(mode)
    if nm.resonant[k]:
        raise ValueError(f"mode {k} (omega = {nm.omega[k]:.12g}) is resonant: "
                         f"{nm.resonant[k]}; Lyapunov's theorem does not give its family")
    if energy is None:
        if not isinstance(system, NativeSystem):
            raise ValueError("energy(y) is needed for a callable system")
        efun = system.energy
        efun(nm.y_eq)          # a ValueError naming the system if it has none
    else:
        if not callable(energy):
            raise TypeError("energy must be a callable energy(y) -> float")
        efun = energy
    y_eq, v, u = nm.y_eq, nm.vectors[:, k], nm.left[:, k]
    eps = amplitude*max(1.0, float(np.max(np.abs(y_eq))))
    t0 = 2.0*np.pi/nm.omega[k]
    ya, ta = _small_orbit(system, y_eq, v, u, t0, eps, rtol, jac)
    yb, tb = _small_orbit(system, y_eq, v, u, ta, 2.0*eps, rtol, jac)
    if not abs(tb - ta) > 1e-9*ta:
        raise ValueError(f"the period of mode {k} does not change near the equilibrium "
                         f"(T = {ta:.15g} at amplitudes {eps:.3g} and {2*eps:.3g}): the "
                         "family cannot be continued in the period (a linear or isochronous "
                         "mode)")
    if isinstance(system, NativeSystem):
        csys = system
        if system.params.size == 0 and isinstance(system, CompiledSystem):
            # continuation() needs a parameter slot even when it continues in the period
            # (it never sets it): a compiled system without parameters gets an unused one,
            # its Taylor entries shared (integrator="TAYLOR")
            csys = CompiledSystem(system.name, system.kind, system.spec, np.zeros(1),
                                  ("unused",), system._keep, system._taylor)
        br = continuation(csys, ya, ta, in_period=True, conservative=True,
                          direction=1 if tb > ta else -1, rtol=rtol, atol=rtol,
                          energy=lambda y, p: efun(y), **options)
    else:
        br = continuation(lambda t, y: system(t, y), ya, ta, in_period=True,
                          conservative=True, direction=1 if tb > ta else -1, rtol=rtol,
                          atol=rtol, energy=lambda y, p: efun(y), **options)
    fam = LyapunovFamily()
    for name in Branch.__slots__:
        setattr(fam, name, getattr(br, name))
    fam.mode = k
    fam.omega = float(nm.omega[k])
    fam.equilibrium = y_eq
    fam.energy_equilibrium = float(efun(y_eq))
    fam.start = ((ya, ta, float(efun(ya))), (yb, tb, float(efun(yb))))
    if energy_range is not None:
        _cut_energy(fam, energy_range)
    return fam


def _cut_energy(fam, energy_range):
    try:
        lo, hi = (float(v) for v in energy_range)
    except (TypeError, ValueError):
        raise TypeError("energy_range must be a pair (E_min, E_max)") from None
    inside = (fam.energy >= lo) & (fam.energy <= hi)
    if inside.all():
        return
    if not inside[0]:
        raise ValueError(f"the first orbit's energy {fam.energy[0]:.12g} is outside "
                         f"energy_range")
    m = int(np.argmin(inside))          # the first point outside
    for name in ("p", "period", "y0", "multipliers", "stability_index", "stable", "tests",
                 "residual", "iterations", "energy"):
        setattr(fam, name, getattr(fam, name)[:m])
    fam.special = [s for s in fam.special if s.index < m - 1]
    fam.message = (f"success: the family left energy_range after {m} points (energy "
                   f"{fam.energy[-1]:.12g})")
