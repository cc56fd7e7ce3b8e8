"""Radau IIA: conmech.solve_ivp(method="Radau") against SciPy's Radau at the same
tolerances (same Python right-hand side and Jacobian), the same problem as a compiled
system (conmech.symbolic.ode_system: native right-hand side and exact Jacobian, what a
conmech user gets) against SciPy's Radau on the Python function (SciPy's only option),
and a stiff spring chain against DOP853.

    python bench/bench_radau.py [--repeat K] [--tight] [--no-chain]

Reported: error against a reference (Van der Pol: SciPy's Radau at rtol = atol = 1e-12;
Robertson: the published values of the Hairer-Wanner / Bari test set at t = 1e11),
accepted steps, Jacobian evaluations, LU decompositions, best-of-K CPU time (the runs of
the three interleaved) and the time ratio SciPy / conmech. Prints a Markdown table
(bench/results/radau.md keeps a run).
"""
import argparse
import time

import numpy as np
import scipy.integrate as si

import conmech

EPS = 1e-6
VDP_REF = np.array([1.706167437543211, -0.8928100165510839])   # SciPy Radau, tol 1e-12
ROBER_REF = np.array([0.2083340149701255e-07, 0.8333360770334713e-13, 0.9999999791665050])


def vdp(t, y):
    return [y[1], ((1 - y[0] ** 2) * y[1] - y[0]) / EPS]


def vdp_jac(t, y):
    return [[0.0, 1.0], [(-2 * y[0] * y[1] - 1) / EPS, (1 - y[0] ** 2) / EPS]]


def rober(t, y):
    return [-0.04 * y[0] + 1e4 * y[1] * y[2],
            0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] ** 2, 3e7 * y[1] ** 2]


def rober_jac(t, y):
    return [[-0.04, 1e4 * y[2], 1e4 * y[1]],
            [0.04, -1e4 * y[2] - 6e7 * y[1], -1e4 * y[1]], [0.0, 6e7 * y[1], 0.0]]


def chain(n=10, k_soft=1.0, k_stiff=1e8, c_stiff=1e4):
    """n unit masses in a row, fixed wall on the left; springs alternately soft and stiff
    (the stiff ones damped): y = [x, v], y' = A y."""
    k = np.array([k_soft if i % 2 == 0 else k_stiff for i in range(n)])
    c = np.array([0.0 if i % 2 == 0 else c_stiff for i in range(n)])
    K = np.zeros((n, n))
    C = np.zeros((n, n))
    for i in range(n):           # spring i joins mass i-1 (or the wall) and mass i
        for M, s in ((K, k[i]), (C, c[i])):
            M[i, i] += s
            if i > 0:
                M[i - 1, i - 1] += s
                M[i, i - 1] -= s
                M[i - 1, i] -= s
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-K, -C]])
    return A


def timed(fn, k):
    best, r = np.inf, None
    for _ in range(k):
        t0 = time.perf_counter()
        r = fn()
        best = min(best, time.perf_counter() - t0)
    return best, r


def compiled_systems():
    """The two problems as compiled systems (sympy -> Fortran, exact Jacobian)."""
    import sympy as sp
    import conmech.symbolic as cs
    y = sp.symbols("y0:3")
    eps = sp.Symbol("eps")
    vdp_c = cs.ode_system([y[1], ((1 - y[0] ** 2) * y[1] - y[0]) / eps], list(y[:2]),
                          params={eps: EPS})
    rober_c = cs.ode_system([-0.04 * y[0] + 1e4 * y[1] * y[2],
                             0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] ** 2,
                             3e7 * y[1] ** 2], list(y))
    return vdp_c, rober_c


def interleaved(fns, k):
    """Best-of-k CPU time of each function (time.process_time: the time the process ran,
    not the time it waited for a core on the shared machine), the runs interleaved (one
    of each per round) so that a change of the machine's load hits all of them alike."""
    best = [np.inf] * len(fns)
    out = [None] * len(fns)
    for _ in range(k):
        for i, fn in enumerate(fns):
            t0 = time.process_time()
            out[i] = fn()
            best[i] = min(best[i], time.process_time() - t0)
    return best, out


def compare(name, fun, jac, span, y0, rtol, atol, ref, k, compiled):
    (tn, tc, ts), (rn, rc, rs) = interleaved([
        lambda: conmech.solve_ivp(compiled, span, y0, method="Radau", rtol=rtol, atol=atol),
        lambda: conmech.solve_ivp(fun, span, y0, method="Radau", rtol=rtol, atol=atol,
                                  jac=jac),
        lambda: si.solve_ivp(fun, span, y0, method="Radau", rtol=rtol, atol=atol, jac=jac)],
        k)
    assert rc.success and rs.success and rn.success
    ec = np.abs(rc.y[:, -1] - ref).max()
    es = np.abs(rs.y[:, -1] - ref).max()
    en = np.abs(rn.y[:, -1] - ref).max()
    print(f"| {name} | {rtol:.0e} | {ec:.2e} / {es:.2e} | {rc.naccept} / {rs.t.size - 1} | "
          f"{rc.njev} / {rs.njev} | {rc.nlu} / {rs.nlu} | {rc.nfev} / {rs.nfev} | "
          f"{tc * 1e3:.1f} / {ts * 1e3:.0f} | {ts / tc:.1f}x | {en:.2e} | {rn.naccept} | "
          f"{tn * 1e3:.2f} | {ts / tn:.0f}x |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--tight", action="store_true", help="also rtol 1e-8 (slow in SciPy)")
    ap.add_argument("--no-chain", action="store_true", help="skip the stiff chain vs DOP853")
    a = ap.parse_args()
    vdp_c, rober_c = compiled_systems()
    print("| problem | rtol | error conmech / SciPy | steps | njev | nlu | nfev | "
          "CPU ms conmech / SciPy | speed-up (same Python f) | compiled: error | "
          "steps | CPU ms | speed-up vs SciPy |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for tol in ((1e-4, 1e-6, 1e-8) if a.tight else (1e-4, 1e-6)):
        compare("Van der Pol eps 1e-6, t in [0, 2]", vdp, vdp_jac, (0, 2), [2.0, -0.66],
                tol, tol, VDP_REF, a.repeat, vdp_c)
    for tol in (1e-6, 1e-8):
        compare("Robertson to t = 1e11 (atol 1e-4 rtol)", rober, rober_jac, (0, 1e11),
                [1.0, 0.0, 0.0], tol, 1e-4 * tol, ROBER_REF, a.repeat, rober_c)
    if a.no_chain:
        return
    A = chain()
    n2 = A.shape[0]
    y0 = np.zeros(n2)
    y0[0] = 1.0
    f = lambda t, y: A @ y
    tc, rr = timed(lambda: conmech.solve_ivp(f, (0, 20), y0, method="Radau", rtol=1e-5,
                                             atol=1e-8, jac=A), 1)
    td, rd = timed(lambda: conmech.solve_ivp(f, (0, 20), y0, method="DOP853", rtol=1e-5,
                                             atol=1e-8), 1)
    from scipy.linalg import expm
    ex = expm(A * 20) @ y0
    print()
    print("| stiff chain (10 masses, k = 1 / 1e8, c = 1e4), t in [0, 20], rtol 1e-5 | "
          "steps | nfev | error | time s |")
    print("|---|---|---|---|---|")
    print(f"| Radau | {rr.naccept} | {rr.nfev} | {np.abs(rr.y[:, -1] - ex).max():.1e} | "
          f"{tc:.2f} |")
    print(f"| DOP853 | {rd.naccept} | {rd.nfev} | {np.abs(rd.y[:, -1] - ex).max():.1e} | "
          f"{td:.2f} |")
    print(f"\nDOP853 / Radau steps: {rd.naccept / rr.naccept:.0f}x")


if __name__ == "__main__":
    main()
