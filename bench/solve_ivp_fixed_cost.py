#!/usr/bin/env python3
"""Wall clock of solve_ivp's fixed cost, in one process: the symbolic Kepler system (zero
span and one period at 1e-12, DOP853 and TAYLOR; one period with t_eval = [T] and with
max_steps, through the fast entry and through the full checks, which 0-d array tolerances
take), the built-in Kepler system over a short span, and a Python right-hand side against SciPy's solve_ivp (zero span and (0, 0.1),
DOP853 and RK45). Each figure is the minimum over 7 batches (us per call); run it on a
quiet machine and give `uptime` beside the figures.

    python bench/solve_ivp_fixed_cost.py
    python bench/solve_ivp_fixed_cost.py --routes     # the fast entry's two routes

--routes times the fast entry's kept route (a small system's system and stepper kept
with its packed arguments, flat_propagation_solve) against its packed call
(flat_solve_packed, which makes them at each call) on two copies of the symbolic Kepler
system in one process, interleaved call by call (the minimum over 300 rounds, twice).
"""
import math
import time

import numpy as np
import scipy.integrate as si
import sympy as sp

import conmech
from conmech import symbolic
from conmech.ivp import solve_fast


def tmin(f, n=500):
    """us per call: the minimum over 7 batches of n calls (after one warm-up call)."""
    f()
    best = math.inf
    for _ in range(7):
        a = time.perf_counter()
        for _ in range(n):
            f()
        best = min(best, (time.perf_counter() - a)/n)
    return best*1e6


def rhs(t, y):
    return [y[2], y[3], -y[0], -y[1]]


def main():
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    kep = symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])
    e = 0.9
    y0 = [1 - e, 0.0, 0.0, math.sqrt((1 + e)/(1 - e))]
    for m in ["DOP853", "TAYLOR"]:
        zero = tmin(lambda: conmech.solve_ivp(kep, (0, 0), y0, method=m, rtol=1e-12,
                                              atol=1e-12))
        period = tmin(lambda: conmech.solve_ivp(kep, (0, 2*math.pi), y0, method=m,
                                                rtol=1e-12, atol=1e-12), 200)
        print(f"{m} symbolic Kepler zero span {zero:.1f} us, one period at 1e-12 "
              f"{period:.1f} us")
        T = 2*math.pi
        for label, opts in [("t_eval=[T]", dict(t_eval=[T])),
                            ("max_steps=10**6", dict(max_steps=10**6))]:
            fast = tmin(lambda: conmech.solve_ivp(kep, (0, T), y0, method=m, rtol=1e-12,
                                                  atol=1e-12, **opts), 200)
            full = tmin(lambda: conmech.solve_ivp(kep, (0, T), y0, method=m,
                                                  rtol=np.array(1e-12),
                                                  atol=np.array(1e-12), **opts), 200)
            print(f"{m} symbolic Kepler one period, {label}: {fast:.1f} us "
                  f"(full checks {full:.1f} us)")
    bk = conmech.systems.kepler()
    short = tmin(lambda: conmech.solve_ivp(bk, (0, 0.01), [0.5, 0, 0, 3**0.5],
                                           method="DOP853"))
    print(f"built-in Kepler, DOP853, span 0.01: {short:.1f} us")
    for m in ["DOP853", "RK45"]:
        for span in [(0, 0), (0, 0.1)]:
            c = tmin(lambda: conmech.solve_ivp(rhs, span, [1.0, 0, 0, 1.0], method=m), 200)
            s = tmin(lambda: si.solve_ivp(rhs, span, [1.0, 0, 0, 1.0], method=m), 200)
            print(f"Python rhs {m} span {span}: conmech {c:.1f} us, SciPy {s:.1f} us")


def routes():
    """Kept route against packed call, interleaved (see the module docstring)."""
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    e = 0.9
    y0 = [1 - e, 0.0, 0.0, math.sqrt((1 + e)/(1 - e))]
    T = 2*math.pi
    kept = symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])
    conmech.solve_ivp(kept, (0, T), y0, method="TAYLOR", rtol=1e-12, atol=1e-12)
    size = solve_fast._KEPT_SIZE
    solve_fast._KEPT_SIZE = 0           # the next system's entries: the packed call
    packed = symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])
    conmech.solve_ivp(packed, (0, T), y0, method="TAYLOR", rtol=1e-12, atol=1e-12)
    solve_fast._KEPT_SIZE = size
    for label, tf, kw in [("zero span", 0.0, {}), ("one period", T, {}),
                          ("one period, t_eval=[T]", T, dict(t_eval=[T]))]:
        for _ in range(2):
            best = {}
            for _ in range(300):
                for route, k in (("kept", kept), ("packed", packed)):
                    for m in ("TAYLOR", "DOP853"):
                        a = time.perf_counter()
                        conmech.solve_ivp(k, (0, tf), y0, method=m, rtol=1e-12, atol=1e-12,
                                          **kw)
                        d = time.perf_counter() - a
                        best[route, m] = min(best.get((route, m), math.inf), d)
            print(f"{label}: " + ", ".join(f"{r} {m} {v*1e6:.2f} us"
                                            for (r, m), v in best.items()), flush=True)


if __name__ == "__main__":
    import sys
    routes() if "--routes" in sys.argv[1:] else main()
