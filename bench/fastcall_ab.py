#!/usr/bin/env python3
"""A/B in one process: the per-call entries of python/conmech/flat/fastcall.c (conmech._fastcall:
``until``, ``solve``) against f2py's wrappers of the same Fortran routines
(``_conmech.flat_propagation_until``, ``flat_propagation_solve``), by swapping the entry the
package calls between rounds (``conmech.ivp.propagator._until``,
``conmech.ivp.native_path._solve_kept``). Kepler e = 0.9 and the spatial restricted three-body
halo orbit (bench_taylor's problems) as conmech.symbolic systems, Taylor's method; printed, in us, the minimum and the
median over the rounds (each round runs both entries, first one then the other, in turn) of:

1. ``Propagator.propagate_until`` by 1e-4 (one step, tol 1e-10), the fixed cost of a call;
2. the halo orbit's period in 20 ``propagate_until`` calls, tol 1e-10;
3. ``solve_ivp`` over a span of 1e-6 (one step), tol 1e-12: solve_ivp's fixed cost;
4. ``solve_ivp`` over Kepler's period, tol 1e-12 (the acceptance check taylor-kepler's call).

The results of both entries are compared bit for bit first.

    python bench/fastcall_ab.py [--rounds 9]
"""
import argparse
import os
import statistics
import sys
import time

import numpy as np

import conmech
from conmech import _conmech, symbolic
from conmech._core import fastcall
from conmech.ivp import native_path, propagator

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_taylor import problems  # noqa: E402

ENTRIES = {"f2py": (_conmech.flat_propagation_until, _conmech.flat_propagation_solve),
           "C": (fastcall.until, fastcall.solve)}


def use(name):
    propagator._until, native_path._solve_kept = ENTRIES[name]


def timed(f, n):
    a = time.perf_counter()
    for _ in range(n):
        f()
    return (time.perf_counter() - a)/n*1e6


def system(pr):
    """(the conmech.symbolic system, y0, period) of a problem of bench_taylor.problems."""
    return (symbolic.ode_system(pr["f"], pr["y"], params=pr["p"] or None),
            [float(v) for v in pr["y0"]], float(pr["T"]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=9)
    args = ap.parse_args()
    prs = problems()
    kep, ky0, kT = system(prs["kepler"])
    hsys, hy0, hT = system(prs["halo"])

    def until_case():
        p = conmech.Propagator(kep, ky0, method="TAYLOR", rtol=1e-10, atol=1e-10)
        s = {"t": 0.0}

        def f():
            s["t"] += 1e-4
            p.propagate_until(s["t"])
        return f

    def halo_case():
        p = conmech.Propagator(hsys, hy0, method="TAYLOR", rtol=1e-10, atol=1e-10)
        ts = np.linspace(0.0, hT, 21)[1:].tolist()

        def f():
            p.t, p.y = 0.0, np.array(hy0)
            for t in ts:
                p.propagate_until(t)
        return f

    def short():
        return conmech.solve_ivp(kep, (0.0, 1e-6), ky0, method="TAYLOR", rtol=1e-12,
                                 atol=1e-12)

    def period():
        return conmech.solve_ivp(kep, (0.0, kT), ky0, method="TAYLOR", rtol=1e-12,
                                 atol=1e-12)

    # the same numbers from both entries
    outs = {}
    for name in ENTRIES:
        use(name)
        r = period()
        p = conmech.Propagator(hsys, hy0, method="TAYLOR", rtol=1e-10, atol=1e-10)
        for t in np.linspace(0.0, hT, 21)[1:]:
            p.propagate_until(t)
        outs[name] = (r.t.tobytes(), r.y.tobytes(), r.nfev, p.y.tobytes())
    same = outs["f2py"] == outs["C"]
    cases = [("propagate_until, one step", None, 20000),
             ("halo period in 20 propagate_until", None, 2000),
             ("solve_ivp, one step", short, 10000),
             ("solve_ivp, Kepler period", period, 2000)]
    times = {(c[0], e): [] for c in cases for e in ENTRIES}
    load = [open("/proc/loadavg").read().split()[0]]
    for r in range(args.rounds):
        for name in (list(ENTRIES) if r % 2 == 0 else list(ENTRIES)[::-1]):
            use(name)
            fs = [until_case(), halo_case(), short, period]
            for (label, _, n), f in zip(cases, fs):
                times[(label, name)].append(timed(f, n))
    load.append(open("/proc/loadavg").read().split()[0])
    use("C")
    print(f"# fastcall A/B: {args.rounds} rounds, load {load[0]}-{load[1]}; results "
          f"bit-identical: {same}")
    print("| call | f2py min / median us | C min / median us | C / f2py (min) |")
    print("|---|---|---|---|")
    for label, _, _ in cases:
        a, b = times[(label, "f2py")], times[(label, "C")]
        print(f"| {label} | {min(a):.2f} / {statistics.median(a):.2f} | "
              f"{min(b):.2f} / {statistics.median(b):.2f} | {min(b)/min(a):.3f} |")


if __name__ == "__main__":
    main()
