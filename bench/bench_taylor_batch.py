"""Taylor ensembles in SIMD lanes: conmech.ensemble.solve(method="TAYLOR") on a symbolic
Kepler system beside heyoka's batch mode, conmech's own member-by-member Taylor route and
its DOP853 ensemble, on one problem, in one run.

Problem: m planar Kepler orbits of eccentricity e (mu = 1, a = 1, period 2 pi), the
members spread evenly in mean anomaly along the orbit (each its own sequence of steps),
integrated over `periods` periods. The exact solution returns to the initial state: the
error of a member is max|y(T) - y0| against that exact reference, for every code.

Codes (same tolerance rtol = atol = tol for all; best of `--repeat` rounds, the codes
interleaved within a round so that the ratios are of the same moments of a shared machine):

- conmech batch: ensemble.solve(symbolic Kepler, method="TAYLOR") (the generated
  propagator over SIMD lanes, the machine's width), and with lanes=8 and lanes=1;
- conmech Taylor member by member: the same call with the parameter mu given per member
  (the ensemble's member-by-member route with the scalar Taylor stepper);
- conmech DOP853: ensemble.solve(conmech.systems.kepler(), method="DOP853");
- heyoka batch: taylor_adaptive_batch of heyoka.recommended_simd_size() members (compiled
  once, before the timed runs), propagate_until on each batch in turn; with 2 threads,
  two Python threads, each with its own copy of the integrator and half of the batches
  (heyoka releases the GIL while it integrates).

Run (heyoka from PyPI, for this benchmark only):

    pip install heyoka
    python bench/bench_taylor_batch.py [--m 10000] [--e 0.5] [--periods 10] [--tol 1e-12]
"""
import argparse
import os
import threading
import time

import numpy as np
import sympy as sp

import conmech
from conmech import ensemble, symbolic


def initial_states(m, e):
    """States at mean anomalies 2 pi k / m of the orbit a = 1, eccentricity e."""
    mean = 2*np.pi*np.arange(m)/m
    big = mean.copy()
    for _ in range(60):
        big -= (big - e*np.sin(big) - mean)/(1 - e*np.cos(big))
    c, s = np.cos(big), np.sin(big)
    q = np.sqrt(1 - e*e)
    den = 1 - e*c
    return np.column_stack([c - e, q*s, -s/den, q*c/den])


def kepler_symbolic(with_mu=False):
    x, y, u, v = sp.symbols("x y u v")
    mu = sp.Symbol("mu")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    k = mu if with_mu else 1
    return symbolic.ode_system([u, v, -k*x/r3, -k*y/r3], [x, y, u, v],
                               params={mu: 1.0} if with_mu else None)


def errors(y_final, y0):
    err = np.max(np.abs(y_final - y0), axis=1)
    return float(np.max(err)), float(np.median(err))


class Heyoka:
    """heyoka's batch integrator of Kepler's problem, width = recommended SIMD size."""

    def __init__(self, hy, tol):
        self.hy = hy
        x, y, vx, vy = hy.make_vars("x", "y", "vx", "vy")
        r3 = (x**2 + y**2)**1.5
        self.sys = [(x, vx), (y, vy), (vx, -x/r3), (vy, -y/r3)]
        self.bs = hy.recommended_simd_size()
        t = time.perf_counter()
        self.ta = hy.taylor_adaptive_batch(
            self.sys, np.tile([[1.0], [0.0], [0.0], [1.0]], (1, self.bs)), tol=tol)
        self.jit = time.perf_counter() - t
        self.order = self.ta.order

    def run(self, y0, tf, threads):
        bs = self.bs
        m = len(y0)
        nb = -(-m//bs)
        pad = np.concatenate([y0, np.repeat(y0[-1:], nb*bs - m, axis=0)])
        yf = np.empty_like(pad)
        steps = np.zeros(nb*bs)
        tas = [self.ta] + [self.ta.__copy__() for _ in range(threads - 1)]

        def work(ta, batches):
            for b in batches:
                ta.set_time(0.0)
                ta.state[:] = pad[b*bs:(b + 1)*bs].T
                ta.propagate_until(tf)
                yf[b*bs:(b + 1)*bs] = ta.state.T
                # per member: (outcome, min h, max h, steps)
                steps[b*bs:(b + 1)*bs] = [r[3] for r in ta.propagate_res]
        if threads == 1:
            work(tas[0], range(nb))
        else:
            th = [threading.Thread(target=work, args=(tas[k], range(k, nb, threads)))
                  for k in range(threads)]
            for t in th:
                t.start()
            for t in th:
                t.join()
        return yf[:m], steps[:m]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--m", type=int, default=10000)
    ap.add_argument("--e", type=float, default=0.5)
    ap.add_argument("--periods", type=float, default=10.0)
    ap.add_argument("--tol", type=float, default=1e-12)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--no-heyoka", action="store_true")
    ap.add_argument("--no-member", action="store_true",
                    help="skip the member-by-member Taylor route")
    args = ap.parse_args()
    m, tol = args.m, args.tol
    y0 = initial_states(m, args.e)
    tf = 2*np.pi*args.periods
    kep = kepler_symbolic()
    kep_mu = kepler_symbolic(True)
    builtin = conmech.systems.kepler()
    from conmech.symbolic.taylor_batch import machine_lanes
    from conmech.ivp.taylor import taylor_order
    lanes = machine_lanes()
    # compile (or load) every library before the timed runs
    t = time.perf_counter()
    ensemble.solve(kep, (0, 1.0), y0[:2], method="TAYLOR", rtol=tol, atol=tol)
    t_build = time.perf_counter() - t
    for la in (1, 8):
        if la != lanes:
            ensemble.solve(kep, (0, 1.0), y0[:2], method="TAYLOR", rtol=tol, atol=tol,
                           lanes=la)
    ensemble.solve(kep_mu, (0, 1.0), y0[:2], method="TAYLOR", rtol=tol, atol=tol,
                   params={"mu": [1.0, 1.0]})
    hy = None
    if not args.no_heyoka:
        import heyoka
        hy = Heyoka(heyoka, tol)

    codes = {}
    for th in args.threads:
        codes[("conmech batch", lanes, th)] = lambda th=th: ensemble.solve(
            kep, (0, tf), y0, method="TAYLOR", rtol=tol, atol=tol, threads=th)
        for la in (8, 1):
            if la != lanes:
                codes[("conmech batch", la, th)] = lambda th=th, la=la: ensemble.solve(
                    kep, (0, tf), y0, method="TAYLOR", rtol=tol, atol=tol, threads=th,
                    lanes=la)
        if not args.no_member:
            codes[("conmech Taylor member by member", 1, th)] = lambda th=th: ensemble.solve(
                kep_mu, (0, tf), y0, method="TAYLOR", rtol=tol, atol=tol, threads=th,
                params={"mu": np.ones(m)})
        codes[("conmech DOP853", 1, th)] = lambda th=th: ensemble.solve(
            builtin, (0, tf), y0, method="DOP853", rtol=tol, atol=tol, threads=th)
        if hy is not None:
            codes[("heyoka batch", hy.bs, th)] = lambda th=th: hy.run(y0, tf, th)
    best = {k: np.inf for k in codes}
    out = {}
    loads = []
    for _ in range(args.repeat):
        for key, fun in codes.items():
            loads.append(os.getloadavg()[0])
            t = time.perf_counter()
            r = fun()
            best[key] = min(best[key], time.perf_counter() - t)
            out[key] = r
    print(f"# {m} Kepler orbits e = {args.e} (spread in mean anomaly), {args.periods:g} "
          f"periods, tol {tol:g} (Taylor order {taylor_order(tol)}); conmech "
          f"{conmech.__version__} (lanes {lanes}; batch library built or loaded in "
          f"{t_build:.2f} s)" + (f", heyoka {hy.hy.__version__} (order {hy.order}, JIT "
                                f"{hy.jit:.2f} s)" if hy else "") +
          f"; {os.cpu_count()} cores; load {min(loads):.1f}-{max(loads):.1f}; best of "
          f"{args.repeat} interleaved rounds")
    print("| code | lanes | threads | time [s] | members/s | max error | median error | "
          "steps/member |")
    print("|---|---|---|---|---|---|---|---|")
    for key in codes:
        name, la, th = key
        r = out[key]
        if name.startswith("heyoka"):
            yf, steps = r
            st = f"{np.mean(steps):.0f}" if np.any(steps) else ""
        else:
            assert r.success, (key, r.message)
            yf = r.y_final
            st = f"{np.mean(r.naccept):.0f}" + (f" (+{np.mean(r.nreject):.2f} rej.)"
                                                if r.nreject.any() else "")
        emax, emed = errors(yf, y0)
        print(f"| {name} | {la} | {th} | {best[key]:.3f} | {m/best[key]:,.0f} | "
              f"{emax:.1e} | {emed:.1e} | {st} |", flush=True)
    if hy is not None:
        for th in args.threads:
            ratio = best[("heyoka batch", hy.bs, th)]/best[("conmech batch", lanes, th)]
            print(f"\nthreads {th}: conmech batch members/s / heyoka batch members/s = "
                  f"{ratio:.2f}")


if __name__ == "__main__":
    main()
