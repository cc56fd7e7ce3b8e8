"""Taylor ensembles of a generalized system M(q) q'' = Q in SIMD lanes: conmech.ensemble.solve
(method="TAYLOR") on the double pendulum from its Lagrangian (symbolic.lagrangian_system),
the batch route (conmech.symbolic.taylor_generalized_batch: the coefficients of the
first-order view for several members at once, the written-out Cholesky factorisation of M
per lane, the ode systems' lane propagator) against the member-by-member route (the scalar
Taylor stepper on the first-order view, one member after another: the same call with the
parameter g given per member, which the batch route does not take), in one run.

Problem: m double pendulums (unit masses and rods, g = 9.81), initial angles uniform in
[-1, 1] and angular velocities in [-0.5, 0.5] (seeded), integrated over [0, T] at rtol =
atol = tol. ``--system chain3``: a planar tree of 3 point masses on rods instead
(symbolic.planar_tree, its articulated-body chain: conmech.symbolic.taylor_tree_batch).
``--system chain10``: a planar chain of 10 unit point masses on unit rods from its
Lagrangian (the tests' pendulum_chain: beyond taylor_generalized.WRITE_OUT_MAX degrees of
freedom, M's factorisation in loops over per-lane arrays), initial angles in [-0.3, 0.3]
and rates in [-0.2, 0.2]; ``--system chain8``: the same chain of 8 links (the
written-out factorisation per lane, at its largest size); ``--system metronomes10``: the
tests' nine pendulums on a cart (10 degrees of freedom), the same ranges. The time of the
first build of each library (sympy to loaded library, compile included; nothing when it is
cached) is printed. Both
routes give each member the steps and the final state of its own
solve_ivp(method="TAYLOR") run, bit for bit (checked here). Best of `--repeat` rounds, the
routes interleaved within a round; the machine's load (uptime) before and after.

    python bench/bench_taylor_generalized_batch.py [--m 2000] [--T 10] [--tol 1e-12]
        [--threads 1 2] [--repeat 3]
        [--system double_pendulum|chain3|chain8|chain10|metronomes10]
"""
import argparse
import os
import sys
import time

import numpy as np
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

from conmech import ensemble, symbolic

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python",
                                "tests"))
from taylor_jets import double_pendulum, metronomes_on_a_cart, pendulum_chain  # noqa: E402


def chain3():
    """3 point masses on rods pinned at the origin, absolute angles (a planar tree)."""
    th = dynamicsymbols("th1:4")
    m, ell = sp.symbols("m1:4"), sp.symbols("l1:4")
    g = sp.Symbol("g")
    bodies = [symbolic.Body(f"link{i}", None if i == 0 else f"link{i - 1}", "revolute",
                            th[i], at=(0, 0) if i == 0 else (0, -ell[i - 1]), mass=m[i],
                            com=(0, -ell[i])) for i in range(3)]
    params = {**{s: 0.8 + 0.15*i for i, s in enumerate(m)},
              **{s: 1.1 - 0.05*i for i, s in enumerate(ell)}, g: 9.81}
    return symbolic.planar_tree(bodies, params, gravity=(0, -g), coordinates="absolute")


def load():
    return os.getloadavg()[0]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--m", type=int, default=2000)
    ap.add_argument("--T", type=float, default=10.0)
    ap.add_argument("--tol", type=float, default=1e-12)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--lanes", type=int, nargs="+", default=[None])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--system", choices=["double_pendulum", "chain3", "chain8", "chain10",
                                         "metronomes10"], default="double_pendulum")
    args = ap.parse_args()
    system, nq = {"double_pendulum": (double_pendulum, 2), "chain3": (chain3, 3),
                  "chain8": (lambda: pendulum_chain(8), 8),
                  "chain10": (lambda: pendulum_chain(10), 10),
                  "metronomes10": (lambda: metronomes_on_a_cart(9), 10)}[args.system]
    system = system()
    rng = np.random.default_rng(7)
    m = args.m
    wide = nq > 3
    y0 = np.column_stack([rng.uniform(-0.3 if wide else -1.0, 0.3 if wide else 1.0, (m, nq)),
                          rng.uniform(-0.2 if wide else -0.5, 0.2 if wide else 0.5, (m, nq))])
    span = (0.0, args.T)
    kw = dict(method="TAYLOR", rtol=args.tol, atol=args.tol)
    per_member_g = {"g": np.full(m, 9.81)}      # the same value: the member route
    # build both routes' libraries before the timed runs (the member route's core first)
    t0 = time.perf_counter()
    ensemble.solve(system, span, y0[:8], params={"g": np.full(8, 9.81)}, **kw)
    print(f"first member-by-member call (core library built if not cached): "
          f"{time.perf_counter() - t0:.1f} s")
    for lanes in args.lanes:
        t0 = time.perf_counter()
        ensemble.solve(system, span, y0[:8], lanes=lanes, **kw)
        print(f"first batch call, lanes {lanes or 'machine'} (batch library built if not "
              f"cached): {time.perf_counter() - t0:.1f} s")
    print(f"{args.system}, {m} members over [0, {args.T:g}] at tol {args.tol:g}; "
          f"load before {load():.2f}")
    for threads in args.threads:
        best = {}
        out = {}
        for _ in range(args.repeat):
            for lanes in args.lanes:
                key = f"batch (lanes {lanes or 'machine'})"
                t0 = time.perf_counter()
                out[key] = ensemble.solve(system, span, y0, lanes=lanes, threads=threads,
                                          **kw)
                best[key] = min(best.get(key, np.inf), time.perf_counter() - t0)
            key = "member by member"
            t0 = time.perf_counter()
            out[key] = ensemble.solve(system, span, y0, params=per_member_g,
                                      threads=threads, **kw)
            best[key] = min(best.get(key, np.inf), time.perf_counter() - t0)
        ref = out["member by member"]
        assert ref.success
        for key, r in out.items():
            same = np.array_equal(r.y_final, ref.y_final) and \
                np.array_equal(r.nfev, ref.nfev)
            print(f"  threads {threads}  {key:24s} {m/best[key]:10,.0f} members/s  "
                  f"({best[key]:.3f} s; median steps {int(np.median(r.naccept))}; "
                  f"bits as member by member: {same})")
        base = m/best["member by member"]
        for key in out:
            if key != "member by member":
                print(f"  threads {threads}  {key}: {m/best[key]/base:.2f}x member by member")
    print(f"load after {load():.2f}")


if __name__ == "__main__":
    main()
