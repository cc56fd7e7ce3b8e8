"""Bifurcation diagrams and multiplier plots of branches (matplotlib)."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

def plot_branch(branch, ax=None, y="stability_index", label_special=True):
    """Bifurcation diagram: the parameter against ``y`` ('stability_index', 'period',
    'energy' or a callable branch -> array), stable parts solid, unstable dashed, special
    points marked and labelled (matplotlib)."""
    import matplotlib.pyplot as plt
    if ax is None:
        _, ax = plt.subplots()
    if callable(y):
        vals, name = np.asarray(y(branch), dtype=float), getattr(y, "__name__", "y")
    else:
        vals, name = np.asarray(getattr(branch, y), dtype=float), y
    p = branch.p
    st = np.asarray(branch.stable)
    for mask, style, lab in ((st, "-", "stable"), (~st, "--", "unstable")):
        v = np.where(mask, vals, np.nan)
        ax.plot(p, v, style, color="C0", label=lab)
    marks = {"fold": "s", "branch point": "o", "period doubling": "D",
             "Neimark-Sacker": "^"}
    for s in branch.special:
        i = s.index
        w = 0.0 if p[i + 1] == p[i] else (s.p - p[i])/(p[i + 1] - p[i])
        yv = vals[i] + w*(vals[i + 1] - vals[i]) if name != "period" else s.period
        ax.plot([s.p], [yv], marks.get(s.kind, "x"), color="C3", ms=8)
        if label_special:
            ax.annotate(f"{s.kind}\n{branch.param} = {s.p:.10g}", (s.p, yv),
                        textcoords="offset points", xytext=(6, 6), fontsize=8)
    ax.set_xlabel(branch.param)
    ax.set_ylabel(name)
    ax.legend(loc="best")
    ax.set_title("branch of periodic orbits")
    return ax


def plot_multipliers(branch, ax=None):
    """The Floquet multipliers of every point of a branch in the complex plane, coloured by
    the parameter, with the unit circle (matplotlib)."""
    import matplotlib.pyplot as plt
    if ax is None:
        _, ax = plt.subplots()
    th = np.linspace(0.0, 2.0*np.pi, 400)
    ax.plot(np.cos(th), np.sin(th), color="0.6", lw=1)
    mu = branch.multipliers
    pp = np.repeat(branch.p[:, None], mu.shape[1], axis=1)
    sc = ax.scatter(mu.real.ravel(), mu.imag.ravel(), c=pp.ravel(), s=8, cmap="viridis")
    plt.colorbar(sc, ax=ax, label=branch.param)
    ax.set_aspect("equal")
    ax.set_xlabel("Re mu")
    ax.set_ylabel("Im mu")
    ax.set_title("multipliers along the branch")
    return ax
