"""Hill's variation orbit + monodromy through the Python API against SciPy, same run.

    python bench/hill_python_bench.py          (after pip install .)

conmech: conmech.hill.variation_orbit (Fortran: fixed-step DOP853 on state + STM, symmetric
Newton over a quarter period, monodromy by symmetry). SciPy: solve_ivp(DOP853, rtol = atol =
1e-13) on the same 20 variational equations, fsolve with the STM Jacobian on the same
quarter-period conditions, the monodromy by integrating the full period (the same algorithm,
in SciPy). Both start from the same circular-orbit guess. CPU times (time.process_time), the
three timed in turns over 5 rounds, best of each; the family's rate is wall time (threads).
"""
import os
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

from conmech import hill

M, C_REF = hill.M_HILL, hill.C_HILL
ROUNDS = 5


def scipy_orbit(m, kappa=1.0, rtol=1e-13, atol=1e-13, symmetry=False):
    nfev = [0]

    def rhs(t, z):
        nfev[0] += 1
        x, y, vx, vy = z[:4]
        r2 = x*x + y*y
        r3 = r2*np.sqrt(r2)
        r5 = r3*r2
        fxx = kappa*(3*x*x/r5 - 1/r3) + 3*m*m
        fxy = 3*kappa*x*y/r5
        fyy = kappa*(3*y*y/r5 - 1/r3)
        a = np.array([[0, 0, 1, 0], [0, 0, 0, 1], [fxx, fxy, 0, 2*m], [fxy, fyy, -2*m, 0]])
        p = z[4:].reshape(4, 4)
        return np.concatenate([[vx, vy, 2*m*vy - kappa*x/r3 + 3*m*m*x,
                                -2*m*vx - kappa*y/r3], (a @ p).ravel()])

    def flow(u, t1):
        z0 = np.concatenate([[u[0], 0, 0, u[1]], np.eye(4).ravel()])
        return solve_ivp(rhs, (0, t1), z0, method="DOP853", rtol=rtol, atol=atol).y[:, -1]

    def resid(u):
        z = flow(u, np.pi/2)
        return [z[0], z[3]]

    def jac(u):
        p = flow(u, np.pi/2)[4:].reshape(4, 4)
        return [[p[0, 0], p[0, 3]], [p[3, 0], p[3, 3]]]

    a0 = kappa**(1/3)*(1 + m)**(-2/3)
    u = fsolve(resid, [a0, a0], fprime=jac, xtol=1e-14)
    if symmetry:
        a = flow(u, np.pi/2)[4:].reshape(4, 4)
        g1 = np.diag([-1.0, 1, 1, -1])
        b = g1 @ np.linalg.solve(a, g1 @ a)
        mono = b @ b
    else:
        mono = flow(u, 2*np.pi)[4:].reshape(4, 4)
    s = 0.5*(np.trace(mono) - 2)
    return 1 + np.arccos(s)/(2*np.pi), nfev[0]


def timeit(f, min_time=1.0, clock=time.process_time):
    """Mean time per call over at least min_time seconds of `clock` (CPU time by default:
    on a shared machine it leaves out the time spent waiting for a core)."""
    n, t = 0, 0.0
    t0 = clock()
    while t < min_time:
        f()
        n += 1
        t = clock() - t0
    return t/n


def main():
    load0 = os.getloadavg()[0]
    orb = hill.variation_orbit(M)
    c_sp, nfev_sp = scipy_orbit(M)
    c_sps, _ = scipy_orbit(M, symmetry=True)
    rounds = []               # the three timed in turns, so that a load change hits all
    for _ in range(ROUNDS):
        rounds.append((timeit(lambda: hill.variation_orbit(M), 0.3),
                       timeit(lambda: scipy_orbit(M), 1.0),
                       timeit(lambda: scipy_orbit(M, symmetry=True), 1.0)))
    t_cm, t_sp, t_sps = (min(r[i] for r in rounds) for i in range(3))
    ratios = [r[1]/r[0] for r in rounds]
    ms = np.linspace(0.01, 0.15, 10000)
    t_fam = timeit(lambda: hill.family(ms), 1.0, clock=time.perf_counter)
    print("# Hill variation orbit + monodromy at m = %.15g (c_ref = %.13f)" % (M, C_REF))
    print("%-44s %12s %10s %10s" % ("method", "time/orbit", "|c err|", "nfev"))
    print("%-44s %9.1f us %10.1e %10d" % ("conmech.hill.variation_orbit (cold start)",
                                          1e6*t_cm, abs(orb.c - C_REF), orb.nfev))
    print("%-44s %9.1f ms %10.1e %10d" % ("SciPy solve_ivp DOP853 + fsolve (full period)",
                                          1e3*t_sp, abs(c_sp - C_REF), nfev_sp))
    print("%-44s %9.1f ms %10.1e %10s" % ("SciPy, monodromy by symmetry", 1e3*t_sps,
                                          abs(c_sps - C_REF), ""))
    print("speed-up over SciPy (best CPU times of %d interleaved rounds): %.0fx (full "
          "period), %.0fx (SciPy with symmetry); per round %.0fx-%.0fx (full period)"
          % (ROUNDS, t_sp/t_cm, t_sps/t_cm, min(ratios), max(ratios)))
    print("family of 10,000 orbits through conmech.hill.family: %.0f orbits/s (%.1f us/orbit, "
          "wall time, OpenMP threads)" % (len(ms)/t_fam, 1e6*t_fam/len(ms)))
    print("load average %.2f at the start, %.2f at the end" % (load0, os.getloadavg()[0]))


if __name__ == "__main__":
    main()
