#!/usr/bin/env python3
"""Instruction counts (callgrind) of conmech against SciPy through Python, for ratios that
do not depend on the machine's load: the same problems as bench/bench_ivp.py (DOP853) and
bench/bench_radau.py (Radau, same Python right-hand side and Jacobian, and the compiled
system), and the routes to Hill's variation orbit of bench/hill_taylor_vs_kernel.py (the
kernel, the STMs by DOP853 and Taylor, the orbit finders' Newton by either integrator).

    python bench/callgrind_python.py [--cases ...] [--k1 1] [--k2 3]

For each case, the snippet runs K1 and K2 times in two processes under
``valgrind --tool=callgrind``; (I(K2) - I(K1))/(K2 - K1) is the count of one call, with
the interpreter's start-up, the imports and the set-up (compilation of the symbolic
systems, a cache hit) cancelled. An instruction ratio is not a time ratio (the
instructions per cycle differ between NumPy's code and compiled Fortran), but it is
exactly repeatable on a shared machine, where CPU and wall times are not.

    python bench/callgrind_python.py one CASE REPS      (what valgrind runs)
"""
import argparse
import gc
import os
import re
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
KEPLER_Y0 = [0.5, 0.0, 0.0, 3.0 ** 0.5]
SPAN = (0.0, 10 * np.pi)


def kepler_rhs(t, y):
    r3 = (y[0] ** 2 + y[1] ** 2) ** 1.5
    return np.array([y[2], y[3], -y[0] / r3, -y[1] / r3])


def cases():
    """{name: (description, make)}: make() returns the call to count."""
    import scipy.integrate as si
    import conmech
    sys.path.insert(0, HERE)
    import bench_radau as br

    def ivp(kind, tol):
        def make():
            if kind == "scipy":
                return lambda: si.solve_ivp(kepler_rhs, SPAN, KEPLER_Y0, method="DOP853",
                                            rtol=tol, atol=tol)
            fun = kepler_rhs if kind == "callback" else conmech.systems.kepler(1.0)
            return lambda: conmech.solve_ivp(fun, SPAN, KEPLER_Y0, method="DOP853",
                                             rtol=tol, atol=tol)
        return make

    def radau(kind, tol):
        def make():
            if kind == "scipy":
                return lambda: si.solve_ivp(br.vdp, (0, 2), [2.0, -0.66], method="Radau",
                                            rtol=tol, atol=tol, jac=br.vdp_jac)
            if kind == "callback":
                return lambda: conmech.solve_ivp(br.vdp, (0, 2), [2.0, -0.66],
                                                 method="Radau", rtol=tol, atol=tol,
                                                 jac=br.vdp_jac)
            vdp_c, _ = br.compiled_systems()
            return lambda: conmech.solve_ivp(vdp_c, (0, 2), [2.0, -0.66], method="Radau",
                                             rtol=tol, atol=tol)
        return make

    def hill_orbit(route):
        # Hill's variation orbit at Hill's m (bench/hill_taylor_vs_kernel.py's routes)
        def make():
            import math
            import hill_taylor_vs_kernel as hk
            m = conmech.hill.M_HILL
            y0 = conmech.hill.variation_orbit(m).y0
            if route == "kernel":
                return lambda: conmech.hill.variation_orbit(m)
            if route == "kernel_stm":
                sys_ = conmech.systems.hill(m=m)
                return lambda: conmech.stability.monodromy(sys_, y0, 2*math.pi)
            param = hk.hill_parametric(m)
            if route == "taylor_stm":
                return lambda: conmech.stability.monodromy(param, y0, 2*math.pi,
                                                           method="TAYLOR")
            return lambda: hk.quarter_orbit(param, y0, "TAYLOR" if route == "taylor_newton"
                                            else "DOP853", 1e-12)
        return make

    out = {}
    for route, what in (("kernel", "hill.variation_orbit (orbit + monodromy, the kernel)"),
                        ("kernel_stm", "monodromy of systems.hill, DOP853"),
                        ("taylor_stm", "monodromy of the symbolic system, TAYLOR"),
                        ("taylor_newton", "symmetric_orbit, quarter period, TAYLOR"),
                        ("dop853_newton", "symmetric_orbit, quarter period, DOP853")):
        out[f"hill_{route}"] = (f"Hill's variation orbit: {what}", hill_orbit(route))
    for kind in ("scipy", "callback", "builtin"):
        out[f"ivp_{kind}"] = (f"Kepler e = 0.5, 5 periods, DOP853 1e-10, {kind}",
                              ivp(kind, 1e-10))
    for kind in ("scipy", "callback", "compiled"):
        out[f"radau_{kind}"] = (f"Van der Pol eps 1e-6, Radau 1e-6, {kind}", radau(kind, 1e-6))
    return out


def count(case, reps, tmp):
    out = os.path.join(tmp, f"cg.{case}.{reps}")
    # the same hash seed in both processes: dict and set layouts, and so the work of
    # the imports, cancel in the difference; one thread of BLAS and OpenMP (callgrind
    # counts the instructions of every thread, a pool's spinning workers included)
    env = dict(os.environ, PYTHONHASHSEED="0", OPENBLAS_NUM_THREADS="1",
               OMP_NUM_THREADS="1")
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                    sys.executable, os.path.abspath(__file__), "one", case, str(reps)],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    with open(out) as fh:
        for line in fh:
            m = re.match(r"(summary|totals): (\d+)", line)
            if m:
                return int(m.group(2))
    raise RuntimeError(f"no instruction total in {out}")


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "one":
        call = cases()[sys.argv[2]][1]()
        call()                                   # first call: lazy set-up outside the count
        gc.collect()
        gc.disable()            # no collection at a point that depends on the count
        for _ in range(int(sys.argv[3])):
            call()
        return 0
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", default=None)
    ap.add_argument("--k1", type=int, default=1)
    ap.add_argument("--k2", type=int, default=3)
    a = ap.parse_args()
    known = cases()
    names = a.cases or list(known)
    bad = [n for n in names if n not in known]
    if bad:
        ap.error(f"unknown cases {bad}; known: {list(known)}")
    per = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            per[name] = (count(name, a.k2, tmp) - count(name, a.k1, tmp)) / (a.k2 - a.k1)
            print(f"{name:16s} {per[name]:16,.0f} instructions per call   ({known[name][0]})",
                  flush=True)
    for group, ref in (("ivp", "ivp_scipy"), ("radau", "radau_scipy"),
                       ("hill", "hill_kernel")):
        if ref in per:
            for name, v in per.items():
                if name.startswith(group + "_") and name != ref:
                    print(f"{ref} / {name}: {per[ref] / v:.1f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
