"""RATTLE against projected DOP853 at the same cost (force evaluations): energy error of
the Cartesian pendulum and double pendulum over long runs, constraint residuals.

    python bench/rattle_energy.py run pendulum [--periods N] [--steps S] -o P.npz
    python bench/rattle_energy.py run double [--periods N] [--steps S] -o D.npz
    python bench/rattle_energy.py plot P.npz D.npz [-o out.png]

`run` integrates one system with RATTLE (h = T/S) and (without --rattle-only) with
DOP853 + position/velocity
projection at the rtol whose force evaluations per period are closest to RATTLE's
(calibrated on 50 periods), keeps the energy error at 20001 output points, and saves them
(the two systems can run in parallel processes). pendulum: pendulum_xy, theta0 = 1, T the
exact period (default 1e6 periods, S = 100); double: double_pendulum_xy from its default
state, T = 2 pi sqrt(l/g) (default 1e6 periods, S = 100). `plot` writes the PNG (default
bench/results/rattle_energy.png) and prints the Markdown table with a least-squares fit
dE_max ~ t^p of the maximum error over the ten tenths of the run (p ~ 0: bounded, p ~ 1:
linear growth).
"""
import argparse
import time
from pathlib import Path

import numpy as np

from conmech import constrained

G = 9.81
N_OUT = 20001


def run(system, q0, v0, tf, method, n_out=N_OUT, **kw):
    t0 = time.perf_counter()
    r = constrained.solve(system, (0, tf), q0, v0, method=method,
                          t_eval=np.linspace(0, tf, n_out), max_steps=2**31 - 1, **kw)
    r.seconds = time.perf_counter() - t0
    if not r.success:
        raise RuntimeError(f"{method}: {r.message}")
    return r


def matched_rtol(system, q0, v0, period, nfev_per_period):
    """rtol of projected DOP853 whose nfev per period is closest to the target."""
    best = None
    for rtol in 10.0 ** -np.arange(3.0, 12.0, 0.25):
        # (3 outputs: the steps of DOP853 hit every t_eval point)
        r = run(system, q0, v0, 50 * period, "DOP853", n_out=3, rtol=rtol, atol=rtol)
        cost = r.nfev / 50
        if best is None or abs(np.log(cost / nfev_per_period)) < abs(np.log(best[1] /
                                                                          nfev_per_period)):
            best = (rtol, cost)
    return best[0]


def setup(which):
    if which == "pendulum":
        from scipy.special import ellipk
        th0 = 1.0
        period = 4 * np.sqrt(1.0 / G) * ellipk(np.sin(th0 / 2) ** 2)
        sysm = constrained.builtin("pendulum_xy")
        return ("pendulum_xy (theta0 = 1, T exact)", sysm,
                np.array([np.sin(th0), -np.cos(th0)]), np.zeros(2), period)
    sysm = constrained.builtin("double_pendulum_xy")
    q0, v0 = sysm.initial_state()
    return ("double_pendulum_xy (default state, T = 2 pi sqrt(l/g))", sysm, q0, v0,
            2 * np.pi * np.sqrt(1.0 / G))


def cmd_run(a):
    name, sysm, q0, v0, period = setup(a.system)
    tf = a.periods * period
    rr = run(sysm, q0, v0, tf, "RATTLE", first_step=period / a.steps)
    print(f"RATTLE done: {rr.seconds:.1f} s, nfev {rr.nfev}", flush=True)
    runs = [("rattle", rr)]
    rtol = 0.0
    if not a.rattle_only:
        rtol = matched_rtol(sysm, q0, v0, period, rr.nfev / a.periods)
        print(f"DOP853 rtol {rtol:.1e}", flush=True)
        rd = run(sysm, q0, v0, tf, "DOP853", rtol=rtol, atol=rtol)
        print(f"DOP853 done: {rd.seconds:.1f} s, nfev {rd.nfev}", flush=True)
        runs.append(("dop853", rd))
    out = dict(name=name, periods=a.periods, tf=tf, steps=a.steps, rtol=rtol)
    for key, r in runs:
        out[key + "_t"] = r.t
        out[key + "_de"] = np.abs(r.energy - r.energy[0])
        out[key + "_res_pos"] = r.res_pos
        out[key + "_res_vel"] = r.res_vel
        out[key + "_nfev"] = r.nfev
        out[key + "_seconds"] = r.seconds
    np.savez(a.o, **out)
    print("wrote", a.o)


def growth(t, de):
    """Maximum of de over each tenth of the run and the exponent p of max ~ t^p."""
    k = de.size // 10
    tm = np.array([t[i * k:(i + 1) * k].mean() for i in range(10)])
    mx = np.array([de[i * k:(i + 1) * k].max() for i in range(10)])
    p = np.polyfit(np.log(tm), np.log(np.maximum(mx, 1e-300)), 1)[0]
    return mx, p


def cmd_plot(a):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    data = [np.load(f, allow_pickle=False) for f in a.files]
    fig, axes = plt.subplots(1, len(data), figsize=(6.5 * len(data), 4.5), squeeze=False)
    print("| system | method | periods | force evals | time (s) | max dE first 10 % | "
          "max dE last 10 % | fit dE ~ t^p | max res_pos | max res_vel |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for ax, d in zip(axes[0], data):
        name = str(d["name"])
        for key, label in (("rattle", "RATTLE h = T/%d" % int(d["steps"])),
                           ("dop853", "DOP853 + projection, rtol %.0e" % float(d["rtol"]))):
            if key + "_t" not in d:
                continue
            t, de = d[key + "_t"], d[key + "_de"]
            mx, p = growth(t[1:], de[1:])
            ax.loglog(t[1:], np.maximum(de[1:], 1e-17), lw=0.5, label=label)
            print(f"| {name} | {label} | {float(d['periods']):.0e} | {int(d[key + '_nfev'])} "
                  f"| {float(d[key + '_seconds']):.0f} | {mx[0]:.2e} | {mx[-1]:.2e} | "
                  f"p = {p:.2f} | {d[key + '_res_pos'].max():.1e} | "
                  f"{d[key + '_res_vel'].max():.1e} |")
        ax.set_title(f"{name}, {float(d['periods']):.0e} periods", fontsize=9)
        ax.set_xlabel("t")
        ax.set_ylabel("|E(t) - E(0)|")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(a.o, dpi=110)
    print()
    print("max dE over decades of t (the trend at log scale):")
    print()
    for d in data:
        for key in ("rattle", "dop853"):
            if key + "_t" not in d:
                continue
            t, de = d[key + "_t"], d[key + "_de"]
            edges = 10.0 ** np.arange(np.floor(np.log10(t[1])), np.log10(t[-1]) + 1)
            cells = []
            for lo, hi in zip(edges[:-1], edges[1:]):
                sel = (t >= lo) & (t < hi)
                if sel.any():
                    cells.append(f"[{lo:.0e}, {hi:.0e}): {de[sel].max():.1e}")
            print(f"- {str(d['name']).split(' ')[0]} {key}: " + "; ".join(cells))
    print("wrote", a.o)


def main():
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("system", choices=("pendulum", "double"))
    r.add_argument("--periods", type=float, default=1e6)
    r.add_argument("--steps", type=int, default=100)
    r.add_argument("--rattle-only", action="store_true")
    r.add_argument("-o", required=True)
    p = sub.add_parser("plot")
    p.add_argument("files", nargs="+")
    p.add_argument("-o", default=str(Path(__file__).parent / "results" / "rattle_energy.png"))
    a = ap.parse_args()
    cmd_run(a) if a.cmd == "run" else cmd_plot(a)


if __name__ == "__main__":
    main()
