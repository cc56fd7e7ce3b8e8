"""Families of halo orbits per second: the Earth-Moon L1 planar Lyapunov family (to its
halo bifurcation) and the northern halo family by branch switching (conmech.cr3bp, the
continuation in Fortran with the cr3bp built-in's exact Jacobian product), against a
lower bound for the same work with SciPy: one DOP853 integration of the state and its
6 x 6 state transition matrix per halo orbit (numpy right-hand side), at the same
tolerance, which any SciPy shooting continuation needs at least once per orbit (a
corrector needs 2-4). Same run, so the ratio holds on a loaded machine; wall-clock figures
are provisional.

    python bench/bench_halo.py [--orbits 600] [--repeat 3] [--sample 20]

(SciPy's bound is measured on ``--sample`` orbits spread over the family and reported
per orbit.)
"""
import argparse
import time

import numpy as np
from scipy.integrate import solve_ivp as scipy_solve_ivp

from conmech import cr3bp

MU = cr3bp.MU_EARTH_MOON


def scipy_stm(y0, period, rtol):
    def rhs(t, s):
        x, y, z, u, v, w = s[:6]
        d1 = np.array([x + MU, y, z])
        d2 = np.array([x - 1 + MU, y, z])
        r1, r2 = np.linalg.norm(d1), np.linalg.norm(d2)
        a1, a2 = (1 - MU)/r1**3, MU/r2**3
        acc = -a1*d1 - a2*d2 + np.array([x + 2*v, y - 2*u, 0.0])
        h = (3*(1 - MU)/r1**5)*np.outer(d1, d1) + (3*MU/r2**5)*np.outer(d2, d2) \
            - (a1 + a2)*np.eye(3) + np.diag([1.0, 1.0, 0.0])
        jac = np.zeros((6, 6))
        jac[:3, 3:] = np.eye(3)
        jac[3:, :3] = h
        jac[3, 4], jac[4, 3] = 2.0, -2.0
        phi = s[6:].reshape(6, 6)
        return np.concatenate([[u, v, w], acc, (jac @ phi).ravel()])
    s0 = np.concatenate([y0, np.eye(6).ravel()])
    return scipy_solve_ivp(rhs, (0, period), s0, method="DOP853", rtol=rtol, atol=rtol)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--orbits", type=int, default=600)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--sample", type=int, default=20)
    a = ap.parse_args()
    rtol = 1e-11          # the continuation's default integration tolerance
    best_pl, best_h, best_sp, cpu_h = np.inf, np.inf, np.inf, np.inf
    for _ in range(a.repeat):
        t0 = time.perf_counter()
        pl = cr3bp.lyapunov_family(MU, "L1", "planar", max_points=150, ds=0.02, ds_max=0.1)
        t1 = time.perf_counter()
        c1 = time.process_time()
        halo = cr3bp.halo_family(MU, pl, direction=1, max_points=a.orbits, ds=0.01,
                                 ds_max=0.1)
        t2 = time.perf_counter()
        cpu_h = min(cpu_h, time.process_time() - c1)
        ks = np.linspace(0, len(halo) - 1, a.sample).astype(int)
        for k in ks:
            scipy_stm(halo.y0[k], halo.period[k], rtol)
        t3 = (time.perf_counter() - t2)/len(ks)*len(halo) + t2
        best_pl, best_h, best_sp = min(best_pl, t1 - t0), min(best_h, t2 - t1), \
            min(best_sp, t3 - t2)
    n = len(halo)
    print(f"planar L1 Lyapunov family, {len(pl)} orbits (to C = {pl.energy[-1]:.4f}): "
          f"{best_pl:.3f} s")
    print(f"northern L1 halo family, {n} orbits (C {halo.energy[0]:.5f} .. "
          f"{halo.energy[-1]:.5f}, periods {halo.period.max():.3f} .. "
          f"{halo.period.min():.3f}; special points "
          f"{[s.kind for s in halo.special]}): {best_h:.3f} s = {n/best_h:.0f} orbits/s "
          f"= {1/best_h:.2f} families/s")
    print(f"SciPy, one state + STM integration per halo orbit: {best_sp/n*1e3:.1f} ms per "
          f"orbit, {best_sp:.2f} s for {n} (conmech's whole family, every corrector "
          f"iteration, is {best_sp/best_h:.0f}x faster than this lower bound)")
    print(f"halo family CPU time (process): {cpu_h:.3f} s")
    print(f"(best of {a.repeat}; wall clock, provisional)")


if __name__ == "__main__":
    main()
