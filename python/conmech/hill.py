"""Hill's lunar problem: the variation orbit, its monodromy and the perigee constant.

Hill's equations (seed 000), in the frame rotating with the Sun, time scaled so that the
synodic month is 2 pi::

    x'' - 2 m y' = dF/dx,   y'' + 2 m x' = dF/dy,   F = kappa/r + (3/2) m^2 x^2

The variation orbit is the direct periodic orbit of period 2 pi, symmetric about both axes.
Its monodromy matrix has the trivial double multiplier 1 (a Jordan block, accurate only to
~sqrt(eps) as eigenvalues) and the non-trivial pair exp(+-2 pi i c), where c is Hill's
perigee constant, read from the trace: S = (trace M - 2)/2 = cos(2 pi c),
c = 1 + arccos(S)/(2 pi)::

    >>> import conmech.hill as hill
    >>> orb = hill.variation_orbit(0.080848933808312)
    >>> round(orb.c, 13)
    1.071583277416

Everything runs in Fortran (fixed-step DOP853 on the state and its state transition matrix,
symmetric Newton shooting over a quarter period, monodromy from the symmetry).
"""
import numpy as np

from . import _conmech
from ._callback import message_text

__all__ = ["HillOrbit", "HillFamily", "variation_orbit", "family", "transverse",
           "M_HILL", "C_HILL", "plot_orbit", "plot_multipliers", "plot_family"]

M_HILL = 0.080848933808312   #: Hill's (1877) value of m = n'/(n - n')
C_HILL = 1.0715832774160     #: Hill's perigee constant for M_HILL

_NOT_PERIODIC = -7     #: family status: Newton stopped on a state that is not periodic
_STATUS = {0: "success", -4: "bad input", -5: "singular Newton matrix",
           -6: "Newton did not converge", _NOT_PERIODIC: "true residual above RESIDUAL_TOL"}


#: An orbit is accepted only if its true residual max(|x(pi/2)|, |y'(pi/2)|), from an
#: independent adaptive integration (DOP853, tolerance 1e-12), is below this.
RESIDUAL_TOL = 1e-8


def _msg(message):
    return message_text(message)


def _true_residuals(ms, kappa, y0s):
    """Residuals of the orbits y0s (n, 4) for ms (n,) by an independent integration of a
    quarter period (conmech flat_hill_residuals); huge for a failed one."""
    y0s = np.asfortranarray(np.asarray(y0s, dtype=float).T)
    return np.asarray(_conmech.flat_hill_residuals(np.ascontiguousarray(ms, dtype=float),
                                                   float(kappa), y0s))


def _check_float(value, name, positive=False, nonneg=False):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__}") from None
    if not np.isfinite(v):
        raise ValueError(f"{name} must be finite")
    if positive and not v > 0:
        raise ValueError(f"{name} must be positive, got {v}")
    if nonneg and not v >= 0:
        raise ValueError(f"{name} must be non-negative, got {v}")
    return v


class HillOrbit:
    """A variation orbit of Hill's problem.

    Attributes
    ----------
    m, kappa : float
    y0 : ndarray (4,)
        Initial state [x0, 0, 0, v0] (on the x axis, crossing it at right angles).
    period : float
        2 pi.
    jacobi : float
        Jacobi constant x'^2 + y'^2 - 2 F.
    monodromy : ndarray (4, 4)
    multipliers : ndarray (4,) complex
        Eigenvalues of the monodromy (LAPACK dgeev); the two trivial ones (a Jordan block
        at 1) are accurate only to ~sqrt(eps).
    stability_index : float
        S = (trace M - 2)/2; linearly stable iff |S| < 1.
    c : float
        Perigee constant, 1 + arccos(S)/(2 pi) (nan if |S| > 1). Ill-conditioned as
        m -> 0 (S -> 1): about 1e-13 at Hill's m, 3e-9 at m = 1e-6.
    iterations, nfev : int
        Newton iterations and right-hand side evaluations.
    """

    __slots__ = ("m", "kappa", "y0", "period", "jacobi", "monodromy", "multipliers",
                 "stability_index", "c", "residual", "iterations", "nfev")

    def __init__(self, **kw):
        for k in self.__slots__:
            setattr(self, k, kw.get(k))

    @property
    def initial_state(self):
        """Alias of y0."""
        return self.y0

    @property
    def stable(self):
        """True when |stability_index| < 1."""
        return bool(abs(self.stability_index) < 1.0)

    def sample(self, t):
        """States (4, nt) and Phi(t) (nt,) of the transverse Hill equation at times t."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        res = transverse(self, t=t)
        return res["states"], res["phi"]

    def __repr__(self):
        return (f"HillOrbit(m={self.m!r}, c={self.c!r}, stability_index="
                f"{self.stability_index!r}, y0={self.y0.tolist()!r})")


def variation_orbit(m, kappa=1.0, guess=None, nsteps=0, full_period=False):
    """The variation orbit of Hill's problem for the parameter m.

    Parameters
    ----------
    m : float
        n'/(n - n') (>= 0); Hill's value is :data:`M_HILL`.
    kappa : float, optional
        Gravitational parameter (> 0).
    guess : (x0, v0), optional
        Newton start (default: the circular Kepler orbit of mean motion 1 + m).
    nsteps : int, optional
        DOP853 steps per quarter period (0: the default, 20).
    full_period : bool, optional
        Compute the monodromy by direct integration over 2 pi instead of the symmetry.

    Returns
    -------
    HillOrbit

    Raises
    ------
    ValueError
        Bad arguments; RuntimeError when Newton fails (the message says why).
    """
    m = _check_float(m, "m", nonneg=True)
    kappa = _check_float(kappa, "kappa", positive=True)
    if guess is None:
        use, g = 0, np.zeros(2)
    else:
        g = np.asarray(guess, dtype=float).ravel()
        if g.size != 2 or not np.all(np.isfinite(g)):
            raise ValueError("guess must be two finite numbers (x0, v0)")
        use = 1
    if isinstance(nsteps, (bool, np.bool_)) or not isinstance(nsteps, (int, np.integer)):
        raise TypeError("nsteps must be an integer")
    if not 0 <= int(nsteps) <= 100000:
        raise ValueError("nsteps must be in [0, 100000]")
    (y0, period, jacobi, mono, mr, mi, s, c, residual, iterations, nfev, info,
     message) = _conmech.flat_hill_orbit(m, kappa, int(nsteps), int(bool(full_period)),
                                         use, g)
    if info != 0:
        msg = _msg(message) or _STATUS.get(int(info), "failure")
        if info == -4:
            raise ValueError(msg)
        raise RuntimeError(msg)
    y0 = np.array(y0)
    res = float(_true_residuals(np.array([m]), kappa, y0[None, :])[0])
    if not (res <= RESIDUAL_TOL*max(1.0, float(np.max(np.abs(y0))))):
        raise RuntimeError(f"hill_variation_orbit: the orbit found for m = {m} is not "
                           f"periodic to the tolerance (true residual {res:.3g} > "
                           f"{RESIDUAL_TOL:g}): Newton did not converge to the variation "
                           "orbit (a better guess or more nsteps is needed)")
    if not (np.all(np.isfinite(mono)) and np.isfinite(s)):
        raise RuntimeError("hill_variation_orbit: the monodromy is not finite")
    return HillOrbit(m=m, kappa=kappa, y0=y0, period=float(period),
                     jacobi=float(jacobi), monodromy=np.array(mono),
                     multipliers=np.asarray(mr) + 1j*np.asarray(mi),
                     stability_index=float(s), c=float(c), residual=float(residual),
                     iterations=int(iterations), nfev=int(nfev))


class HillFamily:
    """The family of variation orbits over m (arrays indexed like ``ms``).

    Attributes: ms, y0 (n, 4), jacobi, monodromy (n, 4, 4), stability_index, c, status
    (0 = success), iterations, success (bool array).
    """

    __slots__ = ("ms", "kappa", "y0", "jacobi", "monodromy", "stability_index", "c",
                 "status", "iterations")

    def __init__(self, **kw):
        for k in self.__slots__:
            setattr(self, k, kw.get(k))

    @property
    def success(self):
        return self.status == 0

    def __len__(self):
        return len(self.ms)

    def __repr__(self):
        return f"HillFamily(n={len(self.ms)}, failures={int(np.sum(~self.success))})"


def family(ms, kappa=1.0, nsteps=0):
    """The family of variation orbits over ``ms`` by continuation (sorted, close values work
    best: each orbit starts from the extrapolation of its predecessors). Failed orbits have
    status < 0 and nan entries; nothing is raised for them. Every orbit Newton accepted is
    checked by an independent integration of a quarter period: a true residual above
    :data:`RESIDUAL_TOL` gives status -7."""
    ms = np.ascontiguousarray(np.asarray(ms, dtype=float).ravel())
    if ms.size == 0:
        raise ValueError("ms must not be empty")
    if not np.all(np.isfinite(ms)) or np.any(ms < 0):
        raise ValueError("ms must be finite and non-negative")
    kappa = _check_float(kappa, "kappa", positive=True)
    if isinstance(nsteps, (bool, np.bool_)) or not isinstance(nsteps, (int, np.integer)):
        raise TypeError("nsteps must be an integer")
    if not 0 <= int(nsteps) <= 100000:
        raise ValueError("nsteps must be in [0, 100000]")
    y0s, jac, monos, ss, cs, infos, iters = _conmech.flat_hill_family(ms, kappa, int(nsteps))
    infos = np.array(infos, dtype=int)
    # the final check: every orbit called a success has a small true residual
    conv = infos == 0
    if conv.any():
        y0a = np.array(y0s).T
        res = _true_residuals(ms[conv], kappa, y0a[conv])
        scale = np.maximum(1.0, np.max(np.abs(y0a[conv]), axis=1))
        bad = ~(res <= RESIDUAL_TOL*scale)
        idx = np.nonzero(conv)[0][bad]
        infos[idx] = _NOT_PERIODIC
    ok = infos == 0
    y0s = np.array(y0s).T.copy()
    monos = np.moveaxis(np.array(monos), 2, 0).copy()
    ss = np.array(ss)
    cs = np.array(cs)
    jac = np.array(jac)
    for a in (y0s, monos, ss, cs, jac):
        a[~ok] = np.nan
    return HillFamily(ms=ms, kappa=kappa, y0=y0s, jacobi=jac, monodromy=monos,
                      stability_index=ss, c=cs, status=np.asarray(infos, dtype=int),
                      iterations=np.asarray(iters, dtype=int))


def transverse(orbit, t=None, rtol=1e-13):
    """Transverse linearisation along a variation orbit (seed 000): the normal deviation N
    obeys Hill's equation N'' + Phi(t) N = 0,
    Phi = 3 (omega + m)^2 + m^2 - n^T H n, omega = n . grad F/|v| - 2 m.

    Returns a dict: monodromy (2, 2) over 2 pi, half_trace (= the orbit's stability_index),
    c, and if ``t`` is given the orbit ``states`` (4, nt) and ``phi`` (nt,) at t.
    """
    if not isinstance(orbit, HillOrbit):
        raise TypeError("orbit must be a HillOrbit (from variation_orbit)")
    rtol = _check_float(rtol, "rtol", positive=True)
    if rtol > 1e-3:
        raise ValueError(f"rtol must be in (0, 1e-3], got {rtol}")
    tt = np.zeros(1) if t is None else np.ascontiguousarray(np.asarray(t, dtype=float).ravel())
    if t is not None and (tt.size == 0 or not np.all(np.isfinite(tt)) or np.any(tt < 0)):
        raise ValueError("t must be finite, non-negative times")
    states, phi, mono2, ht, c, info, message = _conmech.flat_hill_transverse(
        orbit.m, orbit.kappa, orbit.y0, float(rtol), tt)
    if info != 0:
        raise RuntimeError(_msg(message))
    out = {"monodromy": np.array(mono2), "half_trace": float(ht), "c": float(c)}
    if t is not None:
        out["states"] = np.array(states)
        out["phi"] = np.array(phi)
    return out


# --------------------------------------------------------------------------- plots

def plot_orbit(orbit, ax=None, npoints=401):
    """The orbit in the rotating frame (matplotlib)."""
    import matplotlib.pyplot as plt
    if ax is None:
        _, ax = plt.subplots()
    t = np.linspace(0.0, orbit.period, npoints)
    states, _ = orbit.sample(t)
    ax.plot(states[0], states[1], label=f"m = {orbit.m:.6g}, c = {orbit.c:.12f}")
    ax.plot([0.0], [0.0], "o", color="k", label="Earth")
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_title("Hill's variation orbit (rotating frame)")
    ax.legend(loc="best")
    return ax


def plot_multipliers(orbit, ax=None):
    """Floquet multipliers of the monodromy on the unit circle (matplotlib)."""
    import matplotlib.pyplot as plt
    if ax is None:
        _, ax = plt.subplots()
    th = np.linspace(0.0, 2.0*np.pi, 400)
    ax.plot(np.cos(th), np.sin(th), color="0.7", lw=1)
    mu = orbit.multipliers
    ax.plot(mu.real, mu.imag, "x", ms=9, label="multipliers (dgeev)")
    ang = 2.0*np.pi*orbit.c
    ax.plot([np.cos(ang)]*2, [np.sin(ang), -np.sin(ang)], "o", mfc="none", ms=12,
            label="exp(+-2 pi i c)")
    ax.set_aspect("equal")
    ax.set_xlabel("Re")
    ax.set_ylabel("Im")
    ax.legend(loc="best")
    return ax


def plot_family(fam, ax=None):
    """Stability index S and perigee constant c along a family (matplotlib)."""
    import matplotlib.pyplot as plt
    if ax is None:
        _, ax = plt.subplots()
    ax.plot(fam.ms, fam.stability_index, label="S = (tr M - 2)/2")
    ax.plot(fam.ms, fam.c, label="c")
    ax.axhline(1.0, color="0.6", lw=0.8, ls="--")
    ax.axhline(-1.0, color="0.6", lw=0.8, ls="--")
    ax.set_xlabel("m")
    ax.legend(loc="best")
    ax.set_title("Hill's variation orbits: stability along the family")
    return ax
