"""Periodic orbits and their families by the two integrators of the state and its STM:
DOP853 (the default) and Taylor's method on the variational system's own recurrences
(``integrator="TAYLOR"`` of conmech.stability.periodic_orbit / symmetric_orbit /
continuation), on systems of conmech.symbolic, in one process:

- Arenstorf's orbit (planar restricted three-body problem, mu = 0.012277471), symmetric
  shooting from the published start (free: the y-velocity and the half period; targets:
  y and the x-velocity at the half period), single and multiple shooting;
- an Earth-Moon L1 halo orbit (spatial problem; free: x, the y-velocity and the half
  period; targets: y and the x- and z-velocities at the half period);
- Van der Pol's limit cycle continued in mu over [1, 2] (general shooting, free period).

Each line: the time (the minimum over --repeat interleaved rounds, each integrator once per
round), Newton's iterations (a family: its points), the period, the largest multiplier,
how far the two integrators' orbits are apart (period, start and multipliers: two
independent integrations of the same equations), and each integrator's error in what the
multipliers must satisfy: the trivial multipliers at 1 (the pair of a conservative orbit,
the restricted three-body orbits: a Jordan block, whose eigenvalues split by the square
root of the error; the one of Van der Pol's cycle) and mu_min mu_max = 1 (Hamiltonian
reciprocity). The orbits' residuals are checked by DOP853 in both cases
(the orbit solvers' own check).

    python bench/orbit_integrators.py [--repeat 7] [--rtol 1e-12]
"""
import argparse
import os
import time

import numpy as np
import sympy as sp

from conmech import stability, symbolic


def systems():
    x, y, z, u, v, w, mu = sp.symbols("x y z u v w mu")
    m1 = 1 - mu
    d1 = ((x + mu)**2 + y**2)**sp.Rational(3, 2)
    d2 = ((x - m1)**2 + y**2)**sp.Rational(3, 2)
    planar = symbolic.ode_system(
        [u, v, x + 2*v - m1*(x + mu)/d1 - mu*(x - m1)/d2, y - 2*u - m1*y/d1 - mu*y/d2],
        [x, y, u, v], params={mu: 0.012277471})
    r1 = ((x + mu)**2 + y**2 + z**2)**sp.Rational(3, 2)
    r2 = ((x - m1)**2 + y**2 + z**2)**sp.Rational(3, 2)
    spatial = symbolic.ode_system(
        [u, v, w, x + 2*v - m1*(x + mu)/r1 - mu*(x - m1)/r2, y - 2*u - m1*y/r1 - mu*y/r2,
         -m1*z/r1 - mu*z/r2], [x, y, z, u, v, w], params={mu: 0.012150585609624})
    a, b, m = sp.symbols("a b m")
    vdp = symbolic.ode_system([b, m*(1 - a**2)*b - a], [a, b], params={m: 1.0})
    return planar, spatial, vdp


def cases(rtol):
    planar, spatial, vdp = systems()
    arenstorf = ([0.994, 0.0, 0.0, -2.00158510637908252240537862224],
                 17.0652165601579625588917206249)
    halo = ([0.8242000712223545, 0.0, 0.058201226424566974, 0.0, 0.16882862193947631, 0.0],
            2.763288917273153)
    tol = dict(rtol=rtol, atol=rtol)
    return {
        "arenstorf single": lambda i: stability.symmetric_orbit(
            planar, arenstorf[0], free=[3], targets=[1, 2], period=arenstorf[1],
            free_time=True, integrator=i, **tol),
        "arenstorf multiple": lambda i: stability.symmetric_orbit(
            planar, arenstorf[0], free=[3], targets=[1, 2], period=arenstorf[1],
            free_time=True, method="multiple", integrator=i, **tol),
        "halo single": lambda i: stability.symmetric_orbit(
            spatial, halo[0], free=[0, 4], targets=[1, 3, 5], period=halo[1],
            free_time=True, integrator=i, **tol),
        "halo multiple": lambda i: stability.symmetric_orbit(
            spatial, halo[0], free=[0, 4], targets=[1, 3, 5], period=halo[1],
            free_time=True, method="multiple", integrator=i, **tol),
        "vdp family": lambda i: stability.continuation(
            vdp, [2.0, 0.0], 6.66, param="m", p_range=(1.0, 2.0), max_points=60,
            integrator=i, **tol),
    }


def summary(r):
    """(period(s), start(s), multipliers) of an orbit or a branch's last point."""
    if hasattr(r, "multipliers") and np.ndim(r.multipliers) == 1:
        return r.period, r.y0, r.multipliers, r.iterations
    return r.period[-1], r.y0[-1], r.multipliers[-1], len(r.p)


def trivial(mu):
    """max |mu - 1| over the trivial multipliers: the two nearest 1 (a conservative orbit
    of four states or more), the one nearest 1 (two states)."""
    d = np.sort(np.abs(np.asarray(mu) - 1.0))
    return d[1] if d.size >= 4 else d[0]


def reciprocity(mu):
    """|mu_min mu_max - 1| (moduli), or nan for a planar system of two states."""
    a = np.sort(np.abs(mu))
    return abs(a[0]*a[-1] - 1.0) if a.size >= 4 else float("nan")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--rtol", type=float, default=1e-12)
    args = ap.parse_args()
    print(f"load {os.getloadavg()[0]:.2f}; rtol = atol = {args.rtol:g}; times: min over "
          f"{args.repeat} rounds")
    print(f"{'case':20s} {'DOP853 ms':>10s} {'TAYLOR ms':>10s} {'T/D':>6s} {'it/pts':>7s} "
          f"{'period':>20s} {'max|mu|':>12s} {'dT':>8s} {'dy0':>8s} {'dmu rel':>8s} "
          f"{'triv D':>8s} {'triv T':>8s} {'recip D':>8s} {'recip T':>8s}")
    for name, run in cases(args.rtol).items():
        res = {i: run(i) for i in ("DOP853", "TAYLOR")}      # warm: libraries built/loaded
        best = {"DOP853": np.inf, "TAYLOR": np.inf}
        for _ in range(args.repeat):
            for i in best:
                t = time.perf_counter()
                run(i)
                best[i] = min(best[i], time.perf_counter() - t)
        (pd, yd, md, kd), (pt, yt, mt, kt) = summary(res["DOP853"]), summary(res["TAYLOR"])
        md, mt = np.sort_complex(md), np.sort_complex(mt)
        dmu = np.max(np.abs(md - mt)/np.maximum(1.0, np.abs(md)))
        print(f"{name:20s} {best['DOP853']*1e3:10.2f} {best['TAYLOR']*1e3:10.2f} "
              f"{best['TAYLOR']/best['DOP853']:6.2f} {f'{kd}/{kt}':>7s} {pd:20.15f} "
              f"{np.max(np.abs(md)):12.6g} {abs(pd - pt):8.1e} "
              f"{np.max(np.abs(yd - yt)):8.1e} {dmu:8.1e} {trivial(md):8.1e} "
              f"{trivial(mt):8.1e} {reciprocity(md):8.1e} {reciprocity(mt):8.1e}")


if __name__ == "__main__":
    main()
