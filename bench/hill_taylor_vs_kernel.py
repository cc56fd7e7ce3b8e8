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
- DOP853 STM on the symbolic system, for reference;
- Taylor Newton / DOP853 Newton: ``stability.symmetric_orbit`` on the symbolic system (m a
  parameter), the quarter period with x and v free and x(T/4) = v(T/4) = 0, with
  ``integrator="TAYLOR"`` or DOP853: the orbit found, its multipliers and monodromy over
  the full period, its closure checked by an independent DOP853 integration.

The family (second table): Hill's family from m = 0.01 to 0.2 and its loss of stability
m* (S = +1, 0.19510399668175 by Hill's problem's published value in REFERENCE.md) by the
kernel, ``hill.family`` over 191 values of m with the crossing located to 1e-13, against
``stability.continuation`` of the symmetric orbit in m on the symbolic system
(pseudo-arclength, the branch point located) with each integrator: time, orbits, m*.

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


M_STAR = 0.19510399668175


def hill_symbolic(m):
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    fx = -x/r3 + 3*m**2*x
    fy = -y/r3
    return symbolic.ode_system([u, v, 2*m*v + fx, -2*m*u + fy], [x, y, u, v])


def hill_parametric(m0):
    """Hill's equations with m a parameter (for the orbit finders and continuation)."""
    x, y, u, v, m = sp.symbols("x y u v m")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    return symbolic.ode_system([u, v, 2*m*v - x/r3 + 3*m**2*x, -2*m*u - y/r3],
                               [x, y, u, v], params={m: m0})


def quarter_orbit(system, y0, integrator, tol):
    return stability.symmetric_orbit(system, y0, free=[0, 3], targets=[0, 3],
                                     period=2*math.pi, period_factor=4, rtol=tol, atol=tol,
                                     integrator=integrator)


def continued(system, integrator, tol):
    start = hill.variation_orbit(0.01)
    return stability.continuation(system, start.y0, 2*math.pi, param="m", p0=0.01,
                                  free=[0, 3], targets=[0, 3], period_factor=4,
                                  fixed_period=True, conservative=True, direction=1,
                                  p_range=(0.01, 0.2), max_points=400, rtol=tol, atol=tol,
                                  integrator=integrator)


def family_table(rounds, tol):
    system = hill_parametric(0.01)
    ms = np.linspace(0.01, 0.2, 191)
    routes = {
        "kernel: hill.family (191 values of m)": lambda: hill.family(ms),
        "DOP853: continuation(symbolic)": lambda: continued(system, "DOP853", tol),
        "Taylor: continuation(symbolic, integrator=TAYLOR)":
            lambda: continued(system, "TAYLOR", tol),
    }
    values = {k: f() for k, f in routes.items()}
    times = {k: min(best(f, 1, calls=1) for _ in range(rounds)) for k, f in routes.items()}
    print()
    print(f"# Hill's family, m in [0.01, 0.2], tol {tol:g}; min over {rounds} runs")
    print("| route | time [ms] | orbits | orbits/s | m* located | m* - 0.19510399668175 |")
    print("|---|---|---|---|---|---|")
    for k, v in values.items():
        if isinstance(v, hill.HillFamily):
            n = int(np.sum(np.asarray(v.status) == 0))
            star = [sp_["m"] for sp_ in v.special if sp_["m"] > 0.1]
        else:
            n = len(v.p)
            star = [s_.p for s_ in v.special if s_.located]
        mstar = star[0] if star else float("nan")
        print(f"| {k} | {times[k]*1e3:.2f} | {n} | {n/times[k]:.0f} | {mstar:.14f} | "
              f"{mstar - M_STAR:.1e} |")


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
    param = hill_parametric(m)
    routes = {
        "kernel: hill.variation_orbit (orbit + monodromy)":
            lambda: hill.variation_orbit(m).monodromy,
        "kernel STM: monodromy(systems.hill, DOP853)":
            lambda: stability.monodromy(builtin, y0, T, rtol=tol, atol=tol),
        "Taylor STM: monodromy(symbolic, TAYLOR)":
            lambda: stability.monodromy(sym, y0, T, rtol=tol, atol=tol, method="TAYLOR"),
        "DOP853 STM: monodromy(symbolic, DOP853)":
            lambda: stability.monodromy(sym, y0, T, rtol=tol, atol=tol),
        "Taylor Newton: symmetric_orbit(symbolic, quarter, TAYLOR)":
            lambda: quarter_orbit(param, y0, "TAYLOR", tol).monodromy,
        "DOP853 Newton: symmetric_orbit(symbolic, quarter, DOP853)":
            lambda: quarter_orbit(param, y0, "DOP853", tol).monodromy,
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
    family_table(a.rounds, tol)


if __name__ == "__main__":
    main()
