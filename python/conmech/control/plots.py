"""Pictures of orbital stabilisation: the chosen orbit, the convergence of the transverse
coordinates from perturbed starts, the multipliers on the unit disc (matplotlib)."""
from __future__ import annotations

import numpy as np

from .plant import simulate

__all__ = ["plot_orbit", "perturbed_runs", "plot_convergence", "plot_multipliers"]


def _axes(ax, figsize=(6, 4)):
    # matplotlib is optional: imported only when a figure is drawn
    import matplotlib.pyplot as plt
    if ax is None:
        _, ax = plt.subplots(figsize=figsize)
    return ax


def plot_orbit(controller, names=None, ax=None, n=400):
    """The orbit x*(t) over one period: the coordinates and the nominal input u*(t)."""
    ax = _axes(ax)
    plant = controller.plant
    t = np.linspace(0, controller.period, n)
    r = simulate(plant, controller.nominal, (0, controller.period), controller.y0,
                 t_eval=t, rtol=1e-11, atol=1e-11)
    nd = plant.ndof
    names = names or [f"q{i}" for i in range(nd)]
    for i in range(nd):
        ax.plot(t, r.y[i], label=names[i])
    ax2 = ax.twinx()
    for j in range(plant.n_inputs):
        ax2.plot(t, r.u[j], ls="--", color=f"C{nd + j}", label=f"u{j}")
    ax.set_xlabel("t")
    ax.set_ylabel("coordinates")
    ax2.set_ylabel("nominal input (dashed)")
    ax.legend(loc="upper left", fontsize=8)
    ax2.legend(loc="upper right", fontsize=8)
    return ax


def perturbed_runs(controller, n_starts=20, size=0.02, periods=30, seed=2026,
                   samples_per_period=10, rtol=1e-10, atol=1e-10, keep_failures=False):
    """Simulate the nonlinear closed loop from ``n_starts`` states x*(tau) + d with random
    d (normal, standard deviation ``size`` per component, phases tau uniform) over
    ``periods`` periods. Returns (t, distances (n_starts, nt), xi norms, results); a run
    that fails (left the region of attraction) raises RuntimeError, or with
    ``keep_failures`` gets NaN distances."""
    rng = np.random.default_rng(seed)
    T = controller.period
    t = np.linspace(0, periods*T, periods*samples_per_period + 1)
    plant = controller.plant
    phases = np.sort(rng.uniform(0, T, n_starts))
    orb = simulate(plant, controller.nominal, (0, T), controller.y0, t_eval=phases,
                   rtol=1e-12, atol=1e-12)
    dist, xin, runs = [], [], []
    for i in range(n_starts):
        x0 = orb.y[:, i] + size*rng.standard_normal(plant.dimension)
        r = simulate(plant, controller, (0, t[-1]), x0, t_eval=t, rtol=rtol, atol=atol)
        runs.append(r)
        if not r.success:
            if not keep_failures:
                raise RuntimeError(f"the closed-loop run from start {i} failed: {r.message}")
            dist.append(np.full(t.size, np.nan))
            xin.append(np.full(t.size, np.nan))
            continue
        tau, xi, d = controller.project(r.y.T)
        dist.append(d)
        xin.append(np.linalg.norm(xi, axis=1))
    return t, np.array(dist), np.array(xin), runs


def plot_convergence(controller, t, dist, ax=None, xi=None):
    """The orbital distance (and |xi|) against t/T from the perturbed starts (log scale)."""
    ax = _axes(ax, (7, 4.2))
    T = controller.period
    for i, d in enumerate(dist):
        ax.semilogy(t/T, d, color="C0", lw=0.8, label="|x - x*(tau)|" if i == 0 else None)
    if xi is not None:
        for i, x in enumerate(xi):
            ax.semilogy(t/T, x, color="C1", lw=0.5, alpha=0.6,
                        label="|xi|" if i == 0 else None)
    rate = np.max(np.abs(controller.multipliers))
    ax.semilogy(t/T, np.median(dist[:, 0])*rate**(t/T), "k--", lw=1.2,
                label=f"largest multiplier^(t/T), {rate:.3g}")
    ax.set_xlabel("t / T")
    ax.set_ylabel("orbital distance")
    ax.legend(fontsize=8)
    return ax


def plot_multipliers(controller, ax=None):
    """Open-loop (nominal law only) and closed-loop transverse multipliers, and those of
    the nonlinear closed loop's monodromy, on the unit disc."""
    ax = _axes(ax, (4.5, 4.5))
    th = np.linspace(0, 2*np.pi, 400)
    ax.plot(np.cos(th), np.sin(th), color="0.6", lw=1)
    ol = controller.open_loop_multipliers
    cl = controller.multipliers
    nl = controller.nonlinear_multipliers
    ax.plot(ol.real, ol.imag, "s", mfc="none", color="C0", label="open loop (nominal law)")
    ax.plot(nl.real, nl.imag, "o", mfc="none", ms=9, color="C2",
            label="nonlinear closed loop (N x N)")
    ax.plot(cl.real, cl.imag, "x", color="C3", ms=8, label="transverse LQR closed loop")
    ax.set_aspect("equal")
    ax.set_xlim(-1.2, 1.2)
    ax.set_ylim(-1.2, 1.2)
    ax.legend(fontsize=7, loc="lower left")
    ax.set_xlabel("Re")
    ax.set_ylabel("Im")
    return ax
