#!/usr/bin/env python3
"""conmech.symbolic.spatial_tree: the spatial articulated-body right-hand side (conmech_accel,
O(n)) against the Cholesky right-hand side of the same compiled model (mass and forces
from the recursive algorithms, or with --method lagrangian from the Lagrangian
derivation; M factorised per evaluation), in one run.

The system: a spatial chain of N links (revolute joints about z, y, x, y, z, x, ...; each
link 0.3 long along z with its COM at the middle, mass 1, a diagonal inertia tensor of a
rod), gravity (0, 0, -9.81), from a bent initial state. Both right-hand sides integrate
the same interval with DOP853 at the same tolerance; reported: the construction time
(derive / generate / compile), CPU time per right-hand-side evaluation (best of --repeat)
for both over [0, --tf], their ratio, and the endpoints' agreement over [0, 1].

Usage:  python bench/bench_spatial_tree.py [--n 3 6] [--tf 30] [--tol 1e-10] [--repeat 3]
                                          [--method recursive|lagrangian]
"""
import argparse
import os
import sys
import tempfile
import time

import numpy as np


def chain(N):
    import sympy as sp
    from sympy.physics.mechanics import dynamicsymbols
    from conmech.symbolic import SpatialBody
    qs = dynamicsymbols(f"q1:{N + 1}")
    axes = [(0, 0, 1), (0, 1, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 0)]
    half = sp.Rational(3, 20)
    Ir = sp.Rational(9, 1200)          # m l^2 / 12 of a rod of length 0.3
    bodies = [SpatialBody(f"l{i}", None if i == 0 else f"l{i - 1}", "revolute", qs[i],
                          axis=axes[i % 6], at=(0, 0, 0) if i == 0 else (0, 0, -2*half),
                          mass=1, com=(0, 0, -half),
                          inertia=[[Ir, 0, 0], [0, Ir, 0], [0, 0, Ir/100]])
              for i in range(N)]
    g = sp.Symbol("g")
    return bodies, {g: 9.81}, (0, 0, -g)


def cpu_per_eval(sysm, y0, tf, tol, repeat):
    import conmech
    best, r = np.inf, None
    for _ in range(repeat):
        c0 = time.process_time()
        r = conmech.solve_ivp(sysm, (0, tf), y0, method="DOP853", rtol=tol, atol=tol)
        best = min(best, time.process_time() - c0)
    assert r.success, r.message
    return best / r.nfev, r


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, nargs="+", default=[3, 6])
    ap.add_argument("--tf", type=float, default=30.0)
    ap.add_argument("--tol", type=float, default=1e-10)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--method", choices=("recursive", "lagrangian"), default="recursive")
    a = ap.parse_args()
    os.environ.setdefault("CONMECH_CACHE", tempfile.mkdtemp(prefix="bench_spatial_"))
    from conmech import compiled, symbolic
    print("| N | derive s | generate s | compile s | Cholesky us/eval | ABA us/eval | "
          "ratio | nfev | diff at t = 1 |")
    print("|---|---|---|---|---|---|---|---|---|")
    for N in a.n:
        bodies, params, gravity = chain(N)
        sysm = symbolic.spatial_tree(bodies, params, gravity=gravity, jacobian=False,
                                     method=a.method)
        model = symbolic.model_of(sysm)
        tm = model.times
        d = model.addresses
        # the same compiled model without accel: M factorised per evaluation (with the
        # fused mass_forces entry, as symbolic systems without a tree use it)
        plain = compiled.generalized_system(N, d["mass"], d["forces"], d.get("forces_jac"),
                                            mass_forces=d.get("mass_forces"),
                                            params=sysm.parameters, keep=model)
        y0 = np.concatenate([np.linspace(0.8, -0.5, N), np.zeros(N)])
        ta, ra = cpu_per_eval(sysm, y0, a.tf, a.tol, a.repeat)
        tc, rc = cpu_per_eval(plain, y0, a.tf, a.tol, a.repeat)
        # agreement over [0, 1] (the chain is chaotic: over long times the two paths
        # separate from rounding differences)
        _, ra1 = cpu_per_eval(sysm, y0, 1.0, a.tol, 1)
        _, rc1 = cpu_per_eval(plain, y0, 1.0, a.tol, 1)
        diff = np.max(np.abs(ra1.y[:, -1] - rc1.y[:, -1]))
        print(f"| {N} | {tm['derive']:.1f} | {tm['generate']:.1f} | "
              f"{tm['compile_or_load']:.1f} | {tc * 1e6:.2f} | {ta * 1e6:.2f} | "
              f"{tc / ta:.2f} | {ra.nfev}/{rc.nfev} | {diff:.1e} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
