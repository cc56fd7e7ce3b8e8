"""Radau with a sparse Jacobian pattern: conmech (sparse LU, RCM order) against SciPy's
Radau (SuperLU) with the same jac_sparsity on the 1-D Brusselator (n = 2 N unknowns,
numbered in two blocks), rtol = atol = 1e-6 on [0, 10]. Wall-clock medians of `repeat`
runs, both measured in the same loop (the ratio is the figure; absolute times depend on
the load); counts and the end-point difference printed beside them.

    python bench/bench_radau_sparse.py [--callable] [N ...]

--callable: both solvers get the exact Jacobian as a callable returning a CSC matrix
(python/tests/test_radau_sparse_jac.py: brusselator_jac) instead of jac_sparsity and
grouped differences; njev is printed as well.
"""
import os
import sys
import time

import numpy as np
import scipy.integrate

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "python", "tests"))
from test_radau_sparse import brusselator  # noqa: E402
from test_radau_sparse_jac import brusselator_jac  # noqa: E402

import conmech  # noqa: E402


def main(sizes, repeat=3, callable_jac=False):
    print(f"load average {os.getloadavg()[0]:.2f}"
          + ("; callable sparse jac" if callable_jac else "; jac_sparsity"))
    print(f"{'n':>7} {'conmech s':>10} {'SciPy s':>9} {'ratio':>6} {'nlu c/s':>10} "
          f"{'nfev c/s':>12} {'njev c/s':>10} {'max rel diff':>12}")
    for nb in sizes:
        f, pattern, y0 = brusselator(nb)
        kw = dict(method="Radau", rtol=1e-6, atol=1e-6)
        if callable_jac:
            kw["jac"] = brusselator_jac(nb)
        else:
            kw["jac_sparsity"] = pattern
        tc, ts = [], []
        for _ in range(repeat):
            t0 = time.perf_counter()
            rc = conmech.solve_ivp(f, [0, 10], y0, **kw)
            tc.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            rs = scipy.integrate.solve_ivp(f, [0, 10], y0, **kw)
            ts.append(time.perf_counter() - t0)
        d = np.max(np.abs(rc.y[:, -1] - rs.y[:, -1]) / (1e-6 + np.abs(rs.y[:, -1])))
        mc, ms = np.median(tc), np.median(ts)
        print(f"{2 * nb:7d} {mc:10.3f} {ms:9.3f} {ms / mc:6.2f} {rc.nlu:4d}/{rs.nlu:<4d} "
              f"{rc.nfev:5d}/{rs.nfev:<5d} {rc.njev:4d}/{rs.njev:<4d} {d:12.2e}  (spread c "
              f"{min(tc):.3f}-{max(tc):.3f},"
              f" s {min(ts):.3f}-{max(ts):.3f})")


if __name__ == "__main__":
    argv = sys.argv[1:]
    use_callable = "--callable" in argv
    main([int(a) for a in argv if a != "--callable"] or [1000, 5000],
         callable_jac=use_callable)
