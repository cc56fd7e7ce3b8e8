#!/usr/bin/env python3
"""The cost of a call and the cost of a step, conmech.Propagator (method TAYLOR) against
heyoka's taylor_adaptive.propagate_until (PyPI, in this benchmark only), on the problems of
bench_taylor.problems: each propagates from the problem's initial state over a growing
fraction of the period (a span of one step first), so that the time of a call splits into
a fixed part (the call, the set-up, the first expansion) and a part per step:

    time(span) ~ fixed + steps(span) * per_step

fitted by least squares over the spans. Both codes run at the same tolerance (rtol = atol =
tol, heyoka's tol), in one process, each figure the minimum over interleaved rounds of
``--calls`` consecutive calls (us per call). Printed: per span the steps and times, then the
fitted fixed cost and cost per step of each code and their ratios. Then a chain: one
period in ``--pieces`` consecutive propagations (the state at evenly spaced times, as a
user samples an orbit), from the initial state each round; a Propagator continues its
Taylor run from one propagation to the next (heyoka's integrator carries its state too);
and the same times in one call of each code's propagate_grid.

    python bench/propagate_fixed_cost.py [--problems halo kepler] [--tol 1e-10]
                                         [--rounds 7] [--calls 200] [--pieces 20]
"""
import argparse
import os
import sys
import time

import numpy as np

import conmech
from conmech import symbolic
from conmech.ivp.taylor import taylor_order

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_taylor import hy, problems  # noqa: E402


def heyoka_integrator(pr, tol):
    """heyoka's taylor_adaptive for the problem (its expressions through sympy's lambdify,
    as bench_taylor.heyoka_runner builds them)."""
    import sympy as sp
    syms = {str(s): hy.make_vars(str(s)) for s in pr["y"]}
    pars = {str(k): float(v) for k, v in pr["p"].items()}
    conv = sp.lambdify(list(pr["y"]) + [sp.Symbol(k) for k in pars], pr["f"],
                       modules=[{"sin": hy.sin, "cos": hy.cos, "sqrt": hy.sqrt}])
    rhs = conv(*syms.values(), *pars.values())
    return hy.taylor_adaptive(list(zip(syms.values(), rhs)), list(map(float, pr["y0"])),
                              tol=tol)


def timed(calls, rounds, ncalls):
    """Minimum over interleaved rounds of ncalls consecutive calls of each function (us)."""
    best = [np.inf]*len(calls)
    for _ in range(rounds):
        for i, f in enumerate(calls):
            a = time.perf_counter()
            for _ in range(ncalls):
                f()
            best[i] = min(best[i], (time.perf_counter() - a)/ncalls*1e6)
    return best


def fit(steps, times):
    """(fixed, per step) of times ~ fixed + steps * per_step (least squares)."""
    a = np.column_stack([np.ones(len(steps)), steps])
    (c0, c1), *_ = np.linalg.lstsq(a, np.asarray(times, dtype=float), rcond=None)
    return c0, c1


def measure(name, pr, tol, rounds, ncalls, pieces):
    y0 = np.array(pr["y0"], dtype=float)
    T = float(pr["T"])
    model = symbolic.ode_system(pr["f"], pr["y"], params=pr["p"] or None)
    prop = conmech.Propagator(model, y0, method="TAYLOR", rtol=tol, atol=tol)
    ta = heyoka_integrator(pr, tol)
    rows = []
    for frac in (1e-4, 0.25, 0.5, 0.75, 1.0):
        span = frac*T

        def c_call(span=span):
            prop.t, prop.y = 0.0, y0
            return prop.propagate_until(span)

        def h_call(span=span):
            ta.time = 0.0
            ta.state[:] = y0
            return ta.propagate_until(span)
        c_steps = c_call().naccept
        h_steps = h_call()[3]
        tc, th = timed([c_call, h_call], rounds, ncalls)
        rows.append((frac, c_steps, tc, h_steps, th))
    print(f"\n{name}, tol {tol:g} (orders: conmech {taylor_order(tol)}, "
          f"heyoka {ta.order})")
    print("| span / period | conmech steps | conmech us | heyoka steps | heyoka us |")
    print("|---|---|---|---|---|")
    for frac, cs, tc, hs, th in rows:
        print(f"| {frac:g} | {cs} | {tc:.2f} | {hs} | {th:.2f} |")
    cf, cp = fit([r[1] for r in rows], [r[2] for r in rows])
    hf, hp = fit([r[3] for r in rows], [r[4] for r in rows])
    print(f"fixed cost: conmech {cf:.2f} us, heyoka {hf:.2f} us ({cf/hf:.2f}x); per step: "
          f"conmech {cp:.3f} us, heyoka {hp:.3f} us ({cp/hp:.2f}x); whole period: "
          f"{rows[-1][2]/rows[-1][4]:.2f}x")
    times = [float(T)*k/pieces for k in range(1, pieces + 1)]

    def c_chain():
        prop.t, prop.y = 0.0, y0
        return sum(prop.propagate_until(t).naccept for t in times)

    def h_chain():
        ta.time = 0.0
        ta.state[:] = y0
        return sum(ta.propagate_until(t)[3] for t in times)
    grid = np.array([0.0] + times)     # heyoka's grid begins at the current time

    def c_grid():
        prop.t, prop.y = 0.0, y0
        return prop.propagate_grid(grid)[0].naccept

    def h_grid():
        ta.time = 0.0
        ta.state[:] = y0
        return ta.propagate_grid(grid)[3]
    c_steps, h_steps = c_chain(), h_chain()
    cg_steps, hg_steps = c_grid(), h_grid()
    tc, th, tcg, thg = timed([c_chain, h_chain, c_grid, h_grid], rounds,
                             max(ncalls//pieces, 5))
    print(f"a period in {pieces} propagations: conmech {tc:.2f} us ({c_steps} steps), "
          f"heyoka {th:.2f} us ({h_steps} steps): {tc/th:.2f}x")
    print(f"the same {pieces} times by propagate_grid: conmech {tcg:.2f} us ({cg_steps} "
          f"steps), heyoka {thg:.2f} us ({hg_steps} steps): {tcg/thg:.2f}x")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--problems", nargs="*", default=["halo", "kepler"])
    ap.add_argument("--tol", type=float, default=1e-10)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--calls", type=int, default=200)
    ap.add_argument("--pieces", type=int, default=20)
    args = ap.parse_args()
    if hy is None:
        sys.exit("heyoka is not installed (pip install heyoka): it is the comparison")
    prs = problems()
    print(f"load {os.getloadavg()[0]:.2f}; {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
    for name in args.problems:
        measure(name, prs[name], args.tol, args.rounds, args.calls, args.pieces)
    print(f"\nload {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
