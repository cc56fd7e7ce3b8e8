#!/usr/bin/env python3
"""Hill's variation orbit and its monodromy: the Taylor variational route against the
written-out DOP853 kernel of conmech_hill_kernel.

Hill's problem (kappa = 1, m = Hill's 0.080848933808312): x'' - 2 m y' = F_x,
y'' + 2 m x' = F_y, F = 1/r + (3/2) m^2 x^2, the variation orbit of period 2 pi. Routes,
each timed as min over interleaved rounds in one process:

- kernel: ``hill.variation_orbit(m)``, the library's route (Newton on the quarter period
  with the written-out DOP853 kernel, the monodromy from the symmetry, the closure checked
  with twice the steps): the orbit and its perigee constant in one call;
- kernel STM: ``stability.monodromy(systems.hill(m), y0, 2 pi)``, integrate_stm on the
  built-in system (DOP853, the rotating frame's product loop written out);
- Taylor STM: ``stability.monodromy(hill_sym, y0, 2 pi, method="TAYLOR")`` on the same
  equations from ``conmech.symbolic.ode_system`` (the variational recurrences);
- DOP853 STM on the symbolic system, for reference.

Each route's perigee constant c = 1 + arccos(S)/(2 pi), S = (trace M - 2)/2, is compared
with Hill's published 1.0715832774160 (13 digits) and with the kernel's value.

    python bench/hill_taylor_vs_kernel.py [--rounds 7] [--tol 1e-12]
"""
import argparse
import math
import os
import time

import numpy as np
import sympy as sp

from conmech import hill, stability, symbolic, systems


def hill_symbolic(m):
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    fx = -x/r3 + 3*m**2*x
    fy = -y/r3
    return symbolic.ode_system([u, v, 2*m*v + fx, -2*m*u + fy], [x, y, u, v])


def perigee(mono):
    s = (np.trace(mono) - 2.0)/2.0
    return 1.0 + math.acos(s)/(2*math.pi) if abs(s) <= 1 else float("nan")


def best(f, rounds, calls=5):
    times = []
    for _ in range(rounds):
        a = time.perf_counter()
        for _ in range(calls):
            f()
        times.append((time.perf_counter() - a)/calls)
    return min(times)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--tol", type=float, default=1e-12)
    a = ap.parse_args()
    m = hill.M_HILL
    tol = a.tol
    orbit = hill.variation_orbit(m)
    y0, T = orbit.y0, 2*math.pi
    sym = hill_symbolic(sp.Float(m, 17))
    builtin = systems.hill(m=m)
    routes = {
        "kernel: hill.variation_orbit (orbit + monodromy)":
            lambda: hill.variation_orbit(m).monodromy,
        "kernel STM: monodromy(systems.hill, DOP853)":
            lambda: stability.monodromy(builtin, y0, T, rtol=tol, atol=tol),
        "Taylor STM: monodromy(symbolic, TAYLOR)":
            lambda: stability.monodromy(sym, y0, T, rtol=tol, atol=tol, method="TAYLOR"),
        "DOP853 STM: monodromy(symbolic, DOP853)":
            lambda: stability.monodromy(sym, y0, T, rtol=tol, atol=tol),
    }
    values = {k: f() for k, f in routes.items()}       # compiled, cached, warm
    counts = {
        "kernel STM: monodromy(systems.hill, DOP853)":
            stability.stm(builtin, (0, T), y0, tol, tol, full_output=True)[2]["nfev"],
        "Taylor STM: monodromy(symbolic, TAYLOR)":
            stability.stm(sym, (0, T), y0, tol, tol, full_output=True,
                          method="TAYLOR")[2]["nfev"],
        "DOP853 STM: monodromy(symbolic, DOP853)":
            stability.stm(sym, (0, T), y0, tol, tol, full_output=True)[2]["nfev"],
    }
    times = {k: [] for k in routes}
    for _ in range(3):      # interleaved: each round times every route
        for k, f in routes.items():
            times[k].append(best(f, a.rounds))
    c_kernel = orbit.c
    load = os.getloadavg()[0]
    print(f"# Hill's variation orbit, m = {m}, tol {tol:g}; min over {a.rounds} rounds x 3 "
          f"interleaved passes; load {load:.1f}")
    print("| route | time [us] | evaluations / expansions | perigee constant c | "
          "c - Hill's 1.0715832774160 | c - kernel's c |")
    print("|---|---|---|---|---|---|")
    for k in routes:
        c = perigee(values[k])
        t = min(times[k])*1e6
        print(f"| {k} | {t:.1f} | {counts.get(k, '-')} | {c:.16f} | "
              f"{c - hill.C_HILL:.1e} | {c - c_kernel:.1e} |")


if __name__ == "__main__":
    main()
