"""Ensemble benchmark: conmech.ensemble.solve beside heyoka's ensemble_propagate_until
(scalar Taylor integrators, a thread pool) and its batch mode (SIMD-vectorised Taylor
integrators, serial and as an ensemble of batches), on the same problem, in one run.

Problem: m planar Kepler orbits (mu = 1, semi-major axis 1, eccentricities evenly in
[0, e_max], starting at perihelion), integrated over one period 2 pi. The exact solution
returns to the initial state: the error of a member is |y(2 pi) - y0| (max norm), so both
codes are judged on the same exact reference, not on their own tolerance.

heyoka's JIT compilation is done once before the timed runs (reported apart); each figure
is the best of `--repeat` runs. Run (heyoka from PyPI, for this benchmark only):

    pip install heyoka
    python bench/bench_ensemble.py [--m 10000] [--tol 1e-10 1e-12] [--repeat 3]
"""
import argparse
import os
import time

import numpy as np

import conmech
from conmech import ensemble


def initial_states(m, e_max):
    e = np.linspace(0.0, e_max, m)
    return np.column_stack([1 - e, 0 * e, 0 * e, np.sqrt((1 + e) / (1 - e))])


def best_of(repeat, fun):
    times = []
    out = None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fun()
        times.append(time.perf_counter() - t)
    return min(times), out


def errors(y_final, y0):
    err = np.max(np.abs(y_final - y0), axis=1)
    return float(np.max(err)), float(np.median(err))


def run_conmech(y0, tol, threads, repeat, method):
    T = 2 * np.pi

    def go():
        return ensemble.solve(conmech.systems.kepler(), (0, T), y0, method=method, rtol=tol,
                              atol=tol, threads=threads)
    t, res = best_of(repeat, go)
    assert res.success
    return t, res.y_final, int(res.nfev.sum())


def run_conmech_loop(y0, tol, method):
    """The same members as a Python loop of conmech.solve_ivp calls (one run)."""
    T = 2 * np.pi
    kep = conmech.systems.kepler()
    t = time.perf_counter()
    yf = np.array([conmech.solve_ivp(kep, (0, T), y, method=method, rtol=tol,
                                     atol=tol).y[:, -1] for y in y0])
    return time.perf_counter() - t, yf


def heyoka_kepler(hy, tol, batch=None):
    x, y, vx, vy = hy.make_vars("x", "y", "vx", "vy")
    r3 = (x**2 + y**2) ** 1.5
    sys = [(x, vx), (y, vy), (vx, -x / r3), (vy, -y / r3)]
    if batch is None:
        return hy.taylor_adaptive(sys, [1.0, 0.0, 0.0, 1.0], tol=tol)
    return hy.taylor_adaptive_batch(sys, np.tile([[1.0], [0.0], [0.0], [1.0]], (1, batch)),
                                    tol=tol)


def run_heyoka_ensemble(hy, y0, tol, threads, repeat):
    T = 2 * np.pi
    t_jit = time.perf_counter()
    ta = heyoka_kepler(hy, tol)
    t_jit = time.perf_counter() - t_jit

    def gen(ta_copy, i):
        ta_copy.time = 0.0
        ta_copy.state[:] = y0[i]
        return ta_copy

    def go():
        return hy.ensemble_propagate_until(ta, T, len(y0), gen, max_workers=threads)
    t, out = best_of(repeat, go)
    yf = np.array([o[0].state for o in out])
    nsteps = int(sum(o[4] for o in out))
    return t, yf, t_jit, nsteps


def run_heyoka_loop(hy, y0, tol, repeat):
    """One scalar integrator reused for every member in a Python loop (1 thread)."""
    T = 2 * np.pi
    ta = heyoka_kepler(hy, tol)

    def go():
        yf = np.empty_like(y0)
        for i in range(len(y0)):
            ta.time = 0.0
            ta.state[:] = y0[i]
            ta.propagate_until(T)
            yf[i] = ta.state
        return yf
    t, yf = best_of(repeat, go)
    return t, yf


def run_heyoka_batch(hy, y0, tol, threads, repeat):
    """Batches of the recommended SIMD width; serial loop (threads = 1) or an ensemble of
    batch integrators over a thread pool."""
    T = 2 * np.pi
    bs = hy.recommended_simd_size()
    m = len(y0)
    nb = -(-m // bs)
    pad = np.concatenate([y0, np.repeat(y0[-1:], nb * bs - m, axis=0)])
    t_jit = time.perf_counter()
    ta = heyoka_kepler(hy, tol, batch=bs)
    t_jit = time.perf_counter() - t_jit

    def gen(ta_copy, i):
        ta_copy.set_time(0.0)
        ta_copy.state[:] = pad[i * bs:(i + 1) * bs].T
        return ta_copy

    if threads == 1:
        def go():
            yf = np.empty_like(pad)
            for i in range(nb):
                gen(ta, i)
                ta.propagate_until(T)
                yf[i * bs:(i + 1) * bs] = ta.state.T
            return yf
        t, yf = best_of(repeat, go)
    else:
        def go():
            out = hy.ensemble_propagate_until(ta, T, nb, gen, max_workers=threads)
            return np.concatenate([o[0].state.T for o in out])
        t, yf = best_of(repeat, go)
    return t, yf[:m], t_jit, bs


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--m", type=int, default=10000)
    ap.add_argument("--e-max", type=float, default=0.7)
    ap.add_argument("--tol", type=float, nargs="+", default=[1e-10])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    args = ap.parse_args()
    import heyoka as hy

    y0 = initial_states(args.m, args.e_max)
    print(f"# {args.m} Kepler orbits, e in [0, {args.e_max}], one period; heyoka "
          f"{hy.__version__}, conmech {conmech.__version__}; {os.cpu_count()} cores; "
          f"load {os.getloadavg()[0]:.1f}")
    print("| tol | code | threads | time [s] | members/s | max error | median error | "
          "work |")
    print("|---|---|---|---|---|---|---|---|")
    for tol in args.tol:
        rows = []
        for th in args.threads:
            for method in ("DOP853", "VERNER98"):
                t, yf, nfev = run_conmech(y0, tol, th, args.repeat, method)
                rows.append((f"conmech {method}", th, t, *errors(yf, y0), f"{nfev} f-evals"))
            if th == 1:
                t, yf = run_conmech_loop(y0, tol, "DOP853")
                rows.append(("conmech DOP853, loop of solve_ivp", th, t, *errors(yf, y0), ""))
                t, yf = run_heyoka_loop(hy, y0, tol, args.repeat)
                rows.append(("heyoka scalar, Python loop", th, t, *errors(yf, y0), ""))
            # heyoka's ensemble deep-copies the integrator for every member: slow, run once
            t, yf, t_jit, nsteps = run_heyoka_ensemble(hy, y0, tol, th, 1)
            rows.append(("heyoka ensemble (scalar)", th, t, *errors(yf, y0),
                         f"{nsteps} steps; JIT {t_jit:.2f} s"))
            t, yf, t_jit, bs = run_heyoka_batch(hy, y0, tol, th, args.repeat)
            label = "heyoka batch" if th == 1 else "heyoka ensemble of batches"
            rows.append((f"{label} ({bs} wide)", th, t, *errors(yf, y0),
                         f"JIT {t_jit:.2f} s"))
        for code, th, t, emax, emed, work in rows:
            print(f"| {tol:.0e} | {code} | {th} | {t:.3f} | {args.m / t:,.0f} | {emax:.1e} | "
                  f"{emed:.1e} | {work} |", flush=True)


if __name__ == "__main__":
    main()
