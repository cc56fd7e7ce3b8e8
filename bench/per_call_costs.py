#!/usr/bin/env python3
"""Per-call costs of the calls users repeat, for an A/B of two builds of the package (run it
under each, alternately: ``PYTHONPATH=<the other build's site-packages> python
bench/per_call_costs.py``, each build with its own CONMECH_CACHE). Kepler e = 0.9 as a
conmech.symbolic system; printed, in us, the minimum over 7 rounds of:

1. ``Propagator.propagate_until`` by 1e-4 (one Taylor step, tol 1e-10), 20,000 calls a round;
2. ``solve_ivp`` over one period with TAYLOR, rtol = atol = 1e-12 (54 steps);
3. the same with DOP853;
4. ``conmech.DOP853(...).step()`` (one step per call, tol 1e-10), 20,000 calls a round.

    python bench/per_call_costs.py
"""
import time

import numpy as np
import sympy as sp

import conmech
from conmech import symbolic


def best(f, n, rounds=7):
    b = np.inf
    for _ in range(rounds):
        a = time.perf_counter()
        for _ in range(n):
            f()
        b = min(b, (time.perf_counter() - a)/n*1e6)
    return b


def main():
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    kep = symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])
    e = 0.9
    y0 = [1 - e, 0.0, 0.0, float(np.sqrt((1 + e)/(1 - e)))]
    T = 2*np.pi
    p = conmech.Propagator(kep, y0, method="TAYLOR", rtol=1e-10, atol=1e-10)
    state = {"t": 0.0}

    def until():
        state["t"] += 1e-4
        p.propagate_until(state["t"])

    def taylor():
        return conmech.solve_ivp(kep, (0, T), y0, method="TAYLOR", rtol=1e-12, atol=1e-12)

    def dop853():
        return conmech.solve_ivp(kep, (0, T), y0, method="DOP853", rtol=1e-12, atol=1e-12)

    taylor(), dop853()
    stepper = conmech.DOP853(kep, 0.0, y0, 1e9, rtol=1e-10, atol=1e-10)
    figures = [best(until, 20000), best(taylor, 2000), best(dop853, 1000),
               best(stepper.step, 20000)]
    print("propagate_until  solve_ivp TAYLOR  solve_ivp DOP853  Stepper.step  (us)")
    print("  ".join(f"{v:14.3f}" for v in figures))


if __name__ == "__main__":
    main()
