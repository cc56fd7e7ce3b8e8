"""Gauss-Legendre s = 3 (GAUSS6) on Kepler's problem, e = 0.6, over many periods: energy
error bounded, angular momentum at round-off, phase error growing linearly; DOP853 (rtol
1e-13, about half the evaluations) for comparison: its energy error grows linearly.

    python bench/gauss_kepler.py [--periods N] [--steps-per-period K] [out.png]

Defaults: 1e5 periods, h = T/100 (1e7 steps, the built-in kepler system: no Python in
the loop). Outputs are taken on step points (every 7th step, so every phase of the orbit
is sampled) and at whole periods (phase error). Prints a Markdown table, writes the PNG
(default bench/results/gauss_kepler.png).
"""
import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import conmech  # noqa: E402

E = 0.6
Y0 = np.array([1 - E, 0.0, 0.0, np.sqrt((1 + E) / (1 - E))])
T = 2 * np.pi


def invariants(y):
    x, yy, vx, vy = y
    return 0.5 * (vx ** 2 + vy ** 2) - 1 / np.hypot(x, yy), x * vy - yy * vx


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--periods", type=int, default=100000)
    ap.add_argument("--steps-per-period", type=int, default=100)
    ap.add_argument("out", nargs="?",
                    default=str(Path(__file__).parent / "results" / "gauss_kepler.png"))
    a = ap.parse_args()
    n, k = a.periods, a.steps_per_period
    h = n * T / (n * k)
    sysk = conmech.systems.kepler(mu=1.0)
    # sample ~20000 step points spread over every phase
    stride = max(7, (n * k) // 20000 | 1)
    te = np.arange(0, n * k + 1, stride) * h
    t0 = time.perf_counter()
    r = conmech.solve_ivp(sysk, (0, n * T), Y0, method="GAUSS6", first_step=h, t_eval=te,
                          max_steps=2**31 - 1)
    tg = time.perf_counter() - t0
    assert r.success, r.message
    rp = conmech.solve_ivp(sysk, (0, n * T), Y0, method="GAUSS6", first_step=h,
                           t_eval=np.unique(np.geomspace(1, n, 200).astype(int)) * T,
                           max_steps=2**31 - 1)
    # DOP853 at its tightest useful tolerance (about half the evaluations of GAUSS6)
    t0 = time.perf_counter()
    rd = conmech.solve_ivp(sysk, (0, n * T), Y0, method="DOP853", rtol=1e-13, atol=1e-13,
                           t_eval=te, max_steps=2**31 - 1)
    td = time.perf_counter() - t0
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.5))
    print("| method | nfev | time s | max dE first 10 % | max dE last 10 % | "
          "max dL |")
    print("|---|---|---|---|---|---|")
    for label, rr, tt in (("GAUSS6 h = T/%d" % k, r, tg), ("DOP853 rtol 1e-13", rd, td)):
        en, ang = invariants(rr.y)
        de = np.abs(en - en[0])
        m = de.size // 10
        print(f"| {label} | {rr.nfev} | {tt:.1f} | {de[:m].max():.2e} | {de[-m:].max():.2e} "
              f"| {np.abs(ang - ang[0]).max():.1e} |")
        a1.loglog(rr.t[1:] / T, np.maximum(de[1:], 1e-17), lw=0.6, label=label)
    perr = np.abs(rp.y[:2] - Y0[:2, None]).max(axis=0)
    slope = np.polyfit(np.log(rp.t / T), np.log(perr), 1)[0]
    print(f"\nphase (position) error at whole periods: {perr[0]:.2e} after "
          f"{rp.t[0] / T:.0f}, {perr[-1]:.2e} after {rp.t[-1] / T:.0f} periods; "
          f"log-log slope {slope:.3f}")
    a1.set_xlabel("periods")
    a1.set_ylabel("|E(t) - E(0)|")
    a1.set_title("Kepler e = 0.6: energy error")
    a1.legend()
    a2.loglog(rp.t / T, perr, ".-")
    a2.set_xlabel("periods")
    a2.set_ylabel("position error at whole periods")
    a2.set_title(f"GAUSS6 phase error (slope {slope:.2f})")
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
