"""Work-precision of conmech's constrained solvers on the two index-3 mechanical problems of
the Test Set for IVP Solvers (University of Bari): Andrews' squeezing mechanism and the car
axis (conmech.benchmarks.bari), as the test set reports its solvers: mixed significant
correct digits (mescd, atol = rtol) of the positions (and of all of y = [q, v, lambda])
against the published reference solution, beside the CPU time, for rtol = 1e-6 .. 1e-12.

    python bench/bench_bari.py [--repeat K] [--tols 6,8,10,12]

Methods: projected DOP853 (the default of conmech.constrained.solve), Radau IIA on the
stabilised index-2 form (method="Radau", the default dae_index=2) and on the test set's
index-3 form (dae_index=3), all on the compiled system of conmech.symbolic (exact Jacobian
for Radau). CPU time = best-of-K time.process_time of one solve (construction excluded).
Prints a Markdown table (bench/results/bari.md keeps a run).
"""
import argparse
import time

import numpy as np

from conmech import constrained
from conmech.benchmarks import bari

METHODS = (("DOP853", {}), ("Radau (index 2)", dict(method="Radau")),
           ("Radau (index 3)", dict(method="Radau", dae_index=3)))


def run(p, tol, kw, repeat):
    best = np.inf
    for _ in range(repeat):
        c0 = time.process_time()
        r = constrained.solve(p.system, p.t_span, p.q0, p.v0, rtol=tol, atol=tol,
                              t_eval=[p.t_span[1]], **kw)
        best = min(best, time.process_time() - c0)
    if not r.success:
        return None, best
    y = np.concatenate([r.q[:, -1], r.v[:, -1], r.lam[:, -1]])
    yref = np.concatenate([p.q_ref, p.v_ref, p.lam_ref])
    return dict(q=bari.mescd(r.q[:, -1], p.q_ref, tol, tol),
                v=bari.mescd(r.v[:, -1], p.v_ref, tol, tol),
                all=bari.mescd(y, yref, tol, tol), steps=r.naccept, nfev=r.nfev,
                res=float(r.res_pos[-1])), best


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--tols", default="6,8,10,12")
    a = ap.parse_args()
    tols = [10.0 ** -int(k) for k in a.tols.split(",")]
    print("| problem | method | rtol = atol | mescd q | mescd v | mescd y | steps | nfev "
          "| max abs phi | CPU ms |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for make in (bari.andrews, bari.car_axis):
        p = make()
        for name, kw in METHODS:
            for tol in tols:
                out, cpu = run(p, tol, kw, a.repeat)
                if out is None:
                    print(f"| {p.name} | {name} | {tol:.0e} | failed | | | | | | "
                          f"{1e3 * cpu:.2f} |")
                    continue
                print(f"| {p.name} | {name} | {tol:.0e} | {out['q']:.2f} | {out['v']:.2f} "
                      f"| {out['all']:.2f} | {out['steps']} | {out['nfev']} "
                      f"| {out['res']:.1e} | {1e3 * cpu:.2f} |", flush=True)


if __name__ == "__main__":
    main()
