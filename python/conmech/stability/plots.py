"""Bifurcation diagrams, multipliers and families of orbits (matplotlib).

- :func:`plot_branch`: a branch of periodic orbits (or of equilibria) against its
  parameter, its energy or its period; the stability index on an ``asinh`` axis when its
  values span decades (linear within +-1, logarithmic beyond), stable parts solid and
  unstable dashed, with stability decided by :func:`stable_orbits` within a round-off-aware
  tolerance shown in the legend; special points numbered on the curve and listed in the
  legend (short labels never overlap the curve's text);
- :func:`plot_multipliers`: the Floquet multipliers along a branch, by default on a
  log-radius view: mu = r e^(i theta) drawn at radius 2^asinh(log10 r), so the unit circle
  stays the unit circle (round, equal aspect), 1e-8 and 1e8 stay in view, and guide circles
  mark the decades;
- :func:`plot_orbits`: the orbits of a family in configuration space (two or three
  coordinates, or any map of the state), coloured by the parameter, energy or period.
"""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from ..ivp.solve import solve_ivp
from .._core.native import BuiltinSystem, NativeSystem
from .continuation import Branch
from .equilibrium_continuation import EquilibriumBranch

__all__ = ["plot_branch", "plot_multipliers", "plot_orbits", "stable_orbits"]

_EPS = np.finfo(float).eps
_MARKS = {"fold": "s", "branch point": "o", "period doubling": "D", "Neimark-Sacker": "^",
          "Hopf": "*"}


def _nontrivial(mult, ntriv):
    """The multipliers without the ntriv nearest 1."""
    mult = np.asarray(mult)
    if ntriv <= 0:
        return mult
    order = np.argsort(np.abs(mult - 1.0))
    return mult[np.sort(order[ntriv:])]


def stable_orbits(branch: Branch, tol: float | None = None) -> tuple:
    """(stable, tau): which orbits of a periodic branch are linearly stable, every
    non-trivial multiplier with |mu| <= 1 + tau. The trivial multipliers (1 for an
    autonomous system, a second 1 for a conservative one) are the ones nearest 1. The
    default tolerance per orbit is the branch's own ``stable_tol`` (from the multipliers'
    error estimates, see :func:`~conmech.stability.continuation`); for a branch without
    one, tau = max(1e-6, 100 sqrt(eps max|mu|)), which covers the round-off of multipliers
    taken from the eigenvalues of a formed monodromy (a pair on the unit circle of a
    symplectic map, or one near 1, moves by ~sqrt(eps |M|)) and the integration error, so
    that small, stable orbits of a conservative family are not called unstable for a 1e-7
    excess; ``tol`` fixes tau."""
    if not isinstance(branch, Branch):
        raise TypeError("stable_orbits needs a Branch of periodic orbits")
    mult = np.asarray(branch.multipliers)
    ntriv = 1 + int(bool(branch.conservative))
    big = np.max(np.abs(mult), axis=1)
    own = getattr(branch, "stable_tol", None)
    if tol is not None:
        tau = np.full(len(mult), float(tol))
    elif own is not None:
        tau = np.asarray(own, dtype=float)
    else:
        tau = np.maximum(1e-6, 100.0*np.sqrt(_EPS*big))
    stable = np.array([np.all(np.abs(_nontrivial(m, ntriv)) <= 1.0 + t)
                       for m, t in zip(mult, tau)], dtype=bool)
    return stable, tau


def _xvalues(branch, x):
    """(values, name) of the horizontal axis."""
    if x is None or x == "p":
        return np.asarray(branch.p, float), branch.param
    if callable(x):
        return np.asarray(x(branch), float), getattr(x, "__name__", "x")
    if x in ("energy", "period"):
        vals = getattr(branch, x, None)
        if vals is None:
            raise ValueError(f"the branch has no {x} (continuation with energy=..., or a "
                             "Lyapunov family)")
        return np.asarray(vals, float), x
    raise ValueError("x must be None (the parameter), 'energy', 'period' or a callable")


def _yvalues(branch, y):
    if callable(y):
        return np.asarray(y(branch), float), getattr(y, "__name__", "y")
    if isinstance(branch, EquilibriumBranch) and y in (None, "stability_index"):
        return np.asarray(branch.y[:, 0], float), "y[0]"
    if isinstance(y, int) and isinstance(branch, EquilibriumBranch):
        return np.asarray(branch.y[:, y], float), f"y[{y}]"
    vals = getattr(branch, y, None)
    if vals is None:
        raise ValueError(f"y = {y!r}: the branch has no such values")
    return np.asarray(vals, float), y


def _special_xy(branch, s, xv, yv):
    """The plotted position of a special point: its own value where it has one, else
    interpolated along its interval (weight from the parameter, or the period)."""
    i = s.index
    j = min(i + 1, len(xv) - 1)
    w = 0.0
    for key in ("p", "period"):
        a = getattr(branch, key, None)
        v = getattr(s, key, None)
        if a is not None and v is not None and a[j] != a[i]:
            w = (v - a[i])/(a[j] - a[i])
            break
    w = min(max(w, 0.0), 1.0)
    return xv[i] + w*(xv[j] - xv[i]), yv[i] + w*(yv[j] - yv[i])


def plot_branch(branch, ax=None, y="stability_index", label_special=True, x=None,
                scale="auto", tol=None):
    """Bifurcation diagram of a branch of periodic orbits (:func:`continuation`,
    :func:`lyapunov_family`) or of equilibria (:func:`equilibrium_continuation`).

    ``x``: None (the branch's parameter), 'energy', 'period' or a callable branch ->
    array; ``y``: 'stability_index', 'period', 'energy', a callable, or for equilibria a
    state index (default 0). ``scale``: 'auto' (asinh for a stability index or any y whose
    magnitudes span more than three decades, else linear), 'linear', 'asinh', 'symlog' or
    'log'. Stable parts are solid, unstable dashed: for periodic orbits by
    :func:`stable_orbits` (``tol``; the tolerance is shown in the legend), for equilibria
    no eigenvalue with a positive real part. Special points are numbered and listed in
    the legend. Returns the axes."""
    # matplotlib is optional: imported only when a figure is drawn
    import matplotlib.pyplot as plt
    if not isinstance(branch, (Branch, EquilibriumBranch)):
        raise TypeError("branch must be a Branch or an EquilibriumBranch")
    if ax is None:
        _, ax = plt.subplots()
    xv, xname = _xvalues(branch, x)
    yv, yname = _yvalues(branch, y)
    if isinstance(branch, Branch):
        st, tau = stable_orbits(branch, tol)
        stable_label = f"stable (|mu| <= 1 + {np.max(tau):.0e})"
    else:
        st = np.asarray(branch.stable, bool)
        stable_label = "stable (Re lambda <= 0)"
    # solid and dashed pieces share their end points, so the curve has no gaps
    for mask, style, lab in ((st, "-", stable_label), (~st, "--", "unstable")):
        if mask.any():
            ax.plot(xv, np.where(_pieces(mask), yv, np.nan), style, color="C0", lw=1.5,
                    label=lab)
    finite = np.abs(yv[np.isfinite(yv)])
    if scale == "auto":
        span = finite.max()/max(finite[finite > 0].min(), 1e-300) if \
            finite.size and np.any(finite > 0) else 1.0
        scale = "asinh" if (yname == "stability_index" and finite.size and
                            finite.max() > 10) or span > 1e3 else "linear"
    if scale == "asinh":
        ax.set_yscale("asinh", linear_width=1.0)
    elif scale == "symlog":
        ax.set_yscale("symlog", linthresh=1.0)
    elif scale in ("log", "linear"):
        ax.set_yscale(scale)
    else:
        raise ValueError("scale must be 'auto', 'linear', 'asinh', 'symlog' or 'log'")
    if yname == "stability_index" and isinstance(branch, Branch):
        for level in ((-1.0, 1.0) if branch.conservative and branch.y0.shape[1] == 4
                      else (1.0,)):
            ax.axhline(level, color="0.7", lw=0.8, zorder=0)
    pos = []
    for k, s in enumerate(branch.special):
        sx, sy = _special_xy(branch, s, xv, yv)
        own = {"p": getattr(s, "p", None), "period": getattr(s, "period", None),
               "stability_index": getattr(s, "stability_index", None)}
        if isinstance(y, str) and own.get(y) is not None and isinstance(branch, Branch):
            sy = own[y]
        xkey = "p" if x is None else x
        if isinstance(xkey, str) and own.get(xkey) is not None:
            sx = own[xkey]
        located = getattr(s, "located", True)
        ax.plot([sx], [sy], _MARKS.get(s.kind, "x"), color="C3" if located else "0.5",
                ms=7, mfc="C3" if located else "none",
                label=f"{k + 1}: {s.kind}, {xname} = {sx:.8g}"
                + ("" if located else " (not located)") if label_special and k < 12
                else None)
        pos.append((sx, sy))
    if label_special and pos:
        _number_points(ax, pos, xv, yv, scale)
    ax.set_xlabel(xname)
    ax.set_ylabel(yname)
    ax.legend(loc="best", fontsize=7, framealpha=0.8)
    ax.set_title("branch of equilibria" if isinstance(branch, EquilibriumBranch) else
                 "branch of periodic orbits", fontsize=10)
    return ax


def _number_points(ax, pos, xv, yv, scale):
    """Number the special points; points closer than 4 % of the axes (in the plotted
    scale) share one label '2-4' / '2,5', so that labels never pile up."""
    def tr(v):
        return np.arcsinh(v) if scale in ("asinh", "symlog") else \
            (np.log10(np.abs(v) + 1e-300) if scale == "log" else v)
    px = np.array([p[0] for p in pos], float)
    py = tr(np.array([p[1] for p in pos], float))
    fx, fy = xv[np.isfinite(xv)], tr(yv[np.isfinite(yv)])
    wx = max(np.ptp(np.concatenate([fx, px])), 1e-300)
    wy = max(np.ptp(np.concatenate([fy, py])), 1e-300)
    groups = []
    for k in range(len(pos)):
        for gr in groups:
            j = gr[0]
            if abs(px[k] - px[j])/wx < 0.04 and abs(py[k] - py[j])/wy < 0.04:
                gr.append(k)
                break
        else:
            groups.append([k])
    for gr in groups:
        nums = [k + 1 for k in gr]
        text = str(nums[0]) if len(nums) == 1 else (
            f"{nums[0]}-{nums[-1]}" if nums == list(range(nums[0], nums[-1] + 1))
            else ",".join(map(str, nums)))
        ax.annotate(text, pos[gr[0]], textcoords="offset points", xytext=(6, 5), fontsize=8,
                    color="C3")


def _pieces(mask):
    """mask widened by one point towards its neighbours where the neighbour is outside
    (the stable and unstable pieces then meet at the switching points)."""
    m = np.asarray(mask, bool)
    out = m.copy()
    out[:-1] |= m[1:]
    out[1:] |= m[:-1]
    return out


def _log_radius(mu):
    """mu = r e^(i theta) at radius 2^asinh(log10 r) (1 -> 1, 0 -> 0, 1e8 -> 7.6)."""
    r = np.abs(mu)
    with np.errstate(divide="ignore"):
        big_r = np.where(r > 0, 2.0**np.arcsinh(np.log10(np.where(r > 0, r, 1.0))), 0.0)
    th = np.angle(mu)
    return big_r*np.cos(th), big_r*np.sin(th)


def plot_multipliers(branch, ax=None, view="log", color="p"):
    """The Floquet multipliers of every point of a periodic branch in the complex plane,
    coloured by ``color`` ('p', 'energy' or 'period'), with the unit circle.

    ``view='log'`` (default): the log-radius view, mu = r e^(i theta) drawn at radius
    2^asinh(log10 r): the unit circle is kept (round: equal aspect), multipliers from 1e-8
    to 1e8 stay in view, dotted circles mark the decades |mu| = 10^(+-k) (the outer ones
    labelled: 10^-k is the mirror of 10^k);
    ``view='linear'``: the plain complex plane. Returns the axes."""
    # matplotlib is optional: imported only when a figure is drawn
    import matplotlib.pyplot as plt
    if not isinstance(branch, Branch):
        raise TypeError("plot_multipliers needs a Branch of periodic orbits")
    if view not in ("log", "linear"):
        raise ValueError("view must be 'log' or 'linear'")
    if ax is None:
        _, ax = plt.subplots()
    cv, cname = _xvalues(branch, None if color == "p" else color)
    mu = np.asarray(branch.multipliers)
    th = np.linspace(0.0, 2.0*np.pi, 400)
    if view == "log":
        xs, ys = _log_radius(mu.ravel())
        rmax = float(np.max(np.abs(mu))) if mu.size else 1.0
        rmin = float(np.min(np.abs(mu[mu != 0]))) if np.any(mu != 0) else 1.0
        for i, k in enumerate((1, 2, 4, 8, 16)):
            for r in (10.0**k, 10.0**-k):
                if (r > 1 and r <= 10*rmax) or (r < 1 and r >= rmin/10):
                    rr = 2.0**np.arcsinh(np.log10(r))
                    ax.plot(rr*np.cos(th), rr*np.sin(th), ":", color="0.75", lw=0.7)
                    if r > 1:     # (the inner circle 1/r is its mirror)
                        ax.annotate(f"1e{int(np.log10(r)):+d}",
                                    (rr*np.cos(0.9), rr*np.sin(0.9)), fontsize=7,
                                    color="0.5")
        ax.set_xlabel("2^asinh(log10|mu|) cos arg mu")
        ax.set_ylabel("2^asinh(log10|mu|) sin arg mu")
    else:
        xs, ys = mu.real.ravel(), mu.imag.ravel()
        ax.set_xlabel("Re mu")
        ax.set_ylabel("Im mu")
    ax.plot(np.cos(th), np.sin(th), color="0.3", lw=1.0)
    cc = np.repeat(cv[:, None], mu.shape[1], axis=1).ravel()
    sc = ax.scatter(xs, ys, c=cc, s=8, cmap="viridis")
    plt.colorbar(sc, ax=ax, label=cname)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title("multipliers along the branch" + (" (log radius)" if view == "log" else ""),
                 fontsize=10)
    return ax


def _orbit_system(system, branch, k):
    """The right-hand side of orbit k of the branch (its parameter value set)."""
    in_period = branch.param == "period"
    p = float(branch.p[k])
    if isinstance(system, NativeSystem):
        if in_period:
            return system
        names = system.param_names or tuple(f"p{i}" for i in range(system.params.size))
        if branch.param not in names:
            raise ValueError(f"the branch's parameter {branch.param!r} is not a parameter "
                             f"of '{system.name}'")
        if hasattr(system, "with_params"):
            return system.with_params(**{branch.param: p})
        params = np.array(system.params, float)
        params[names.index(branch.param)] = p
        return BuiltinSystem(system.name, params, system.param_names)
    if not callable(system):
        raise TypeError("system must be a built-in system or a callable")
    if in_period:
        return system
    return lambda t, y: system(t, y, p)


def plot_orbits(system, branch, ax=None, coords=(0, 1), n_orbits=15, indices=None,
                color="p", cmap="viridis", npoints=400, rtol=1e-10, colorbar=True,
                label=None):
    """The orbits of a family in configuration space, coloured by ``color`` ('p',
    'energy' or 'period').

    ``system``: the system the branch was continued on (a built-in or compiled system, or
    the callable ``fun(t, y, p)``, or ``fun(t, y)`` for a family continued in the period).
    ``coords``: two or three state indices (three draw a 3-D plot), or a callable mapping
    the states (n, npoints) to an array (2 or 3, npoints) (e.g. generalized coordinates to
    Cartesian positions). ``n_orbits`` orbits evenly spaced along the branch, or the
    branch points ``indices``; each is integrated over its period (DOP853, ``rtol``).
    ``colorbar``: draw one (several families on one axes: draw it once, or none and a
    legend from ``label``). Returns the axes."""
    # matplotlib is optional: imported only when a figure is drawn
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    if not isinstance(branch, Branch):
        raise TypeError("plot_orbits needs a Branch of periodic orbits")
    if indices is None:
        indices = np.unique(np.linspace(0, len(branch) - 1, max(1, int(n_orbits))).astype(int))
    indices = np.asarray(indices, int)
    if indices.size == 0 or indices.min() < 0 or indices.max() >= len(branch):
        raise ValueError("indices must be branch point indices")
    if callable(coords):
        fmap = coords
        dim = None
    else:
        idx = tuple(int(c) for c in coords)
        if len(idx) not in (2, 3):
            raise ValueError("coords must be two or three state indices, or a callable")
        fmap = (lambda ys, idx=idx: ys[list(idx), :])
        dim = len(idx)
    cv, cname = _xvalues(branch, None if color == "p" else color)
    curves = []
    for k in indices:
        fun = _orbit_system(system, branch, k)
        tt = np.linspace(0.0, float(branch.period[k]), int(npoints))
        r = solve_ivp(fun, (0.0, tt[-1]), branch.y0[k], method="DOP853", t_eval=tt,
                      rtol=rtol, atol=rtol)
        xy = np.asarray(fmap(r.y), float)
        curves.append(xy)
    dim = dim or curves[0].shape[0]
    if dim not in (2, 3):
        raise ValueError("coords must give two or three coordinates")
    norm = plt.Normalize(float(np.min(cv[indices])), float(np.max(cv[indices])))
    cm = plt.get_cmap(cmap)
    if ax is None:
        fig = plt.figure()
        ax = fig.add_subplot(111, projection="3d" if dim == 3 else None)
    if dim == 2:
        lc = LineCollection([c.T for c in curves], cmap=cm, norm=norm, lw=1.0, label=label)
        lc.set_array(cv[indices])
        ax.add_collection(lc)
        ax.autoscale()
        ax.set_aspect("equal", adjustable="datalim")
        mappable = lc
    else:
        # the legend entry goes with the strongest colour of the map
        strong = int(np.argmax(np.abs(np.asarray([norm(cv[k]) for k in indices]) - 0.5)))
        for i, (c, k) in enumerate(zip(curves, indices)):
            ax.plot(c[0], c[1], c[2], color=cm(norm(cv[k])), lw=0.9,
                    label=label if i == strong else None)
        mappable = plt.cm.ScalarMappable(norm=norm, cmap=cm)
        mappable.set_array(cv[indices])
        # equal scales on the three axes (the orbits' true shape)
        lo = np.array([ax.get_xlim3d()[0], ax.get_ylim3d()[0], ax.get_zlim3d()[0]])
        hi = np.array([ax.get_xlim3d()[1], ax.get_ylim3d()[1], ax.get_zlim3d()[1]])
        ax.set_box_aspect(np.maximum(hi - lo, 1e-3*np.max(hi - lo)))
    if colorbar:
        plt.colorbar(mappable, ax=ax, label=cname, shrink=0.7)
    if not callable(coords):
        names = [f"y[{c}]" for c in coords]
        ax.set_xlabel(names[0])
        ax.set_ylabel(names[1])
        if dim == 3:
            ax.set_zlabel(names[2])
    ax.set_title("orbits of the family", fontsize=10)
    return ax
