"""solve_ivp(method="TAYLOR") on generalized systems M(q) q'' = Q: the recurrences written
out for the run's order (conmech.symbolic.taylor_generalized_fixed, what solve_ivp runs
while the routine's source stays within conmech.ivp.taylor.FIXED_MAX_SOURCE_GENERALIZED
characters, FIXED_MAX_SOURCE_TREE for a tree) against the loop routine (the model
library's conmech_taylor), in one process, the two routes interleaved in each round.

Systems: the double pendulum (g = 9.81), the lecture notes' cart pendulum, planar chains of
3 and 4 links from their Lagrangians (M and Q; python/tests/taylor_jets.py), and planar
chains of 2 and 3 point masses as trees (symbolic.planar_tree: the recurrences of the
articulated-body chain); initial angles spread over [-0.3, 0.3] and rates over [0.2, -0.2]
(the cart: [0.3, pi - 0.7, -0.2, 0.5]); t in [0, 10]; rtol = atol = tol. Both routes
take the same steps to the last bit (checked). Printed: the order, the written-out
source's size (the routine is compiled here whatever its size, to show where
the limit lies), steps, the best of --rounds rounds of --calls calls per route (us per
call) and their ratio, and DOP853's time and evaluations at the same tolerance (down to
1e-13: DOP853's rtol floor is 100 eps); the load average (1 min) before and after.

    python bench/taylor_generalized_fixed.py [--tol 1e-8 1e-12 1e-16] [--rounds 5]
        [--calls 10] [--systems double_pendulum cart chain3 chain4 tree2 tree3]
"""
import argparse
import os
import sys
import time
import warnings

import numpy as np

import conmech
import conmech.ivp.taylor as ivp_taylor
from conmech.symbolic.pipeline import model_of
from conmech.symbolic.taylor_generalized_fixed import generalized_fixed_source, \
    tree_fixed_source
from conmech.symbolic.taylor_tree import is_tree

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python",
                                "tests"))
import taylor_jets  # noqa: E402

SYSTEMS = {"double_pendulum": taylor_jets.double_pendulum, "cart": taylor_jets.cart_pendulum,
           "chain3": lambda: taylor_jets.pendulum_chain(3),
           "chain4": lambda: taylor_jets.pendulum_chain(4),
           "tree2": lambda: taylor_jets.tree_chain(2),
           "tree3": lambda: taylor_jets.tree_chain(3)}


def _loop_only(fun, model, order):
    return fun


def call(systems, y0, tol, route):
    """solve_ivp of the generalized system: route 0 with its written-out routine (made
    whatever its size: the limit is lifted in main), route 1 with the loop routine (on a
    copy of the system, systems[1]: solve_ivp keeps the system it runs per system object,
    so the copy keeps the loop routine it was first given), route 2 DOP853 (the peer:
    conmech's M(q) q'' = Q route, the accelerations by LAPACK)."""
    if route == 2:
        return conmech.solve_ivp(systems[0], (0.0, 10.0), y0, method="DOP853", rtol=tol,
                                 atol=tol)
    made = ivp_taylor._fixed_system
    if route == 1:
        ivp_taylor._fixed_system = _loop_only
    try:
        return conmech.solve_ivp(systems[route], (0.0, 10.0), y0, method="TAYLOR",
                                 rtol=tol, atol=tol)
    finally:
        ivp_taylor._fixed_system = made


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--tol", type=float, nargs="+", default=[1e-8, 1e-12, 1e-16])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--calls", type=int, default=10)
    ap.add_argument("--systems", nargs="+", default=list(SYSTEMS), choices=list(SYSTEMS))
    args = ap.parse_args()
    warnings.simplefilter("ignore", UserWarning)       # rtol below 100 eps at 1e-16
    limits = (ivp_taylor.FIXED_MAX_SOURCE_GENERALIZED, ivp_taylor.FIXED_MAX_SOURCE_TREE)
    # every routine made, to compare
    ivp_taylor.FIXED_MAX_SOURCE_GENERALIZED = ivp_taylor.FIXED_MAX_SOURCE_TREE = 10**9
    print(f"load before: {os.getloadavg()[0]:.2f}")
    print("| system | tol | order | source kB | made by solve_ivp | steps | written out us "
          "| loop us | written out / loop | DOP853 us (nfev) | written out / DOP853 |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in args.systems:
        system = SYSTEMS[name]()
        systems = (system, system.with_params())
        d = model_of(system).derived
        n = d.n
        y0 = list(np.linspace(-0.3, 0.3, n)) + list(np.linspace(0.2, -0.2, n))
        if name == "cart":
            y0 = [0.3, np.pi - 0.7, -0.2, 0.5]
        tree = is_tree(d)
        for tol in args.tol:
            order = ivp_taylor.taylor_order(max(tol, 2.220446049250313e-16))
            size = len(tree_fixed_source(d, order) if tree else
                       generalized_fixed_source(d, order))
            made = size <= limits[tree]
            a, b = call(systems, y0, tol, 0), call(systems, y0, tol, 1)
            assert a.success and np.array_equal(a.y, b.y) and a.nfev == b.nfev
            dop = call(systems, y0, tol, 2) if tol >= 1e-13 else None
            best = [np.inf, np.inf, np.inf]
            for _ in range(args.rounds):
                for i in (0, 1, 2) if dop is not None else (0, 1):
                    t0 = time.perf_counter()
                    for _ in range(args.calls):
                        call(systems, y0, tol, i)
                    best[i] = min(best[i], (time.perf_counter() - t0)/args.calls)
            peer = f"{best[2]*1e6:.0f} ({dop.nfev}) | {best[0]/best[2]:.2f}" if dop else "- | -"
            print(f"| {name} | {tol:g} | {order} | {size/1000:.0f} | {'yes' if made else 'no'} "
                  f"| {a.naccept} | {best[0]*1e6:.0f} | {best[1]*1e6:.0f} | "
                  f"{best[0]/best[1]:.2f} | {peer} |")
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
