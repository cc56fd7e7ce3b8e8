"""Taylor's method on symbolic trees (conmech.symbolic.taylor_tree: the recurrences of the
articulated-body chain) against DOP853 on the same compiled planar chains of point masses
(3 and 7 links, absolute angles, pinned at the origin, 10 s from a generic start of
moderate amplitude): steps,
right-hand-side evaluations, time (minimum over interleaved repeats in one process: the
ratios are same-run ratios, the machine may be loaded) and the error at the end against a
reference (DOP853 and Taylor at 3e-14, their difference printed), and what one Taylor
expansion costs: the time of one step of Taylor's method over the time of one
right-hand-side evaluation of DOP853 in the same run (the expansion to the order of the
tolerance, plus the step control), and the generated library's operations and build time.

    python bench/bench_taylor_tree.py [--repeat 5] [--links 3 7] [--tf 10] [--amplitude 0.3]
"""
import argparse
import os
import sys
import time

import numpy as np

import conmech
from conmech import symbolic
from conmech.ivp.taylor import taylor_order
from conmech.ivp.taylor_generalized import first_order_view
from conmech.symbolic.taylor_tree import tree_decomposition

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python",
                                "tests"))
from taylor_jets import tree_chain  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--links", type=int, nargs="+", default=[3, 7])
    ap.add_argument("--tf", type=float, default=10.0)
    ap.add_argument("--amplitude", type=float, default=0.3,
                    help="initial angles uniform in +-amplitude, rates in +-amplitude/2 "
                    "(large amplitudes: chaotic motion, no accurate reference)")
    a = ap.parse_args()
    for N in a.links:
        t0 = time.perf_counter()
        system = tree_chain(N, spread=3)     # masses and rods over those of 3 links
        t1 = time.perf_counter()
        first_order_view(system)          # the Taylor library: generated and compiled
        t2 = time.perf_counter()
        model = symbolic.model_of(system)
        dec = tree_decomposition(model.derived)[0]
        ops = dec.counts()
        print(f"\n{N}-link planar chain: model {t1 - t0:.1f} s, Taylor library "
              f"{t2 - t1:.1f} s, operations {ops}")
        rng = np.random.default_rng(N)
        y0 = np.concatenate([rng.uniform(-a.amplitude, a.amplitude, N),
                             rng.uniform(-a.amplitude/2, a.amplitude/2, N)])
        refs = [conmech.solve_ivp(system, (0, a.tf), y0, method=m, rtol=3e-14,
                                  atol=3e-14).y[:, -1] for m in ("DOP853", "TAYLOR")]
        ref = refs[1]
        print(f"  reference: DOP853 and Taylor at 3e-14 differ by "
              f"{np.max(np.abs(refs[0] - refs[1])):.1e}")
        print("  tol     method  order  steps   nfev   time [ms]   error    time ratio "
              "T/D  step/rhs")
        for tol in (1e-10, 1e-12):
            best = {}
            runs = {}
            for _ in range(a.repeat):
                for m in ("DOP853", "TAYLOR"):
                    s = time.perf_counter()
                    r = conmech.solve_ivp(system, (0, a.tf), y0, method=m, rtol=tol,
                                          atol=tol)
                    dt = time.perf_counter() - s
                    best[m] = min(best.get(m, np.inf), dt)
                    runs[m] = r
            d, t = runs["DOP853"], runs["TAYLOR"]
            rhs = best["DOP853"]/d.nfev
            for m, r in (("DOP853", d), ("TAYLOR", t)):
                err = np.max(np.abs(r.y[:, -1] - ref))
                order = taylor_order(tol) if m == "TAYLOR" else 8
                extra = ""
                if m == "TAYLOR":
                    extra = (f"   {best['TAYLOR']/best['DOP853']:.2f}      "
                             f"{best['TAYLOR']/t.naccept/rhs:.1f}")
                print(f"  {tol:.0e}  {m:7s} {order:5d} {r.naccept + r.nreject:6d} "
                      f"{r.nfev:6d} {1e3*best[m]:10.2f}  {err:8.1e}{extra}")


if __name__ == "__main__":
    main()
