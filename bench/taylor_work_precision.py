"""Work-precision of conmech's Taylor method (solve_ivp, method="TAYLOR", on a system made
by conmech.symbolic) against heyoka's taylor_adaptive (PyPI, in this benchmark only) and
conmech's own DOP853 on the same compiled system, and conmech.Propagator (method TAYLOR, the
final state alone, as heyoka's propagate_until returns it; solve_ivp returns every step's
point): Kepler e = 0.9 and Arenstorf's orbit by default; with --problems also the planar
restricted three-body problem (pcr3bp), an Earth-Moon L1 halo orbit of the spatial one
(halo) and the double pendulum (pendulum) of bench_taylor.problems; one period (pcr3bp and
the pendulum: t = 10) each, rtol = atol = tol over 1e-8 .. 1e-16.

Errors are measured at the end of the period against a quadruple-precision Taylor reference
(conmech.symbolic.taylor_quad, tol 1e-30; it closes Arenstorf's orbit to 1e-25) started
from the exact values of the doubles the runs start from (bench_taylor.reference: the
published decimal initial values are another orbit, 6.8e-13 away on Kepler after one
period). Below tol ~1e-13 on Kepler e = 0.9 every code is at the round-off floor of a
double-precision state (a few 1e-12, scattered by an order of magnitude with the
roundings: python/tests/test_taylor_precision.py), so single errors there compare luck. Times are
the minimum over interleaved rounds in one process (each round times every method at every
tolerance once, so a burst of load hits all of them alike), each round's figure the
fastest of --calls consecutive calls, and a call is timed alone (the result is read
apart). Orders and steps are printed beside the times.

Ratios at equal accuracy: for each Taylor point (error E, time T) the other method's time at
error E is interpolated linearly in log(time) against log(error) between the two of its
tolerances whose errors bracket E (walking from loose to tight tolerances); when its errors
never reach E (or never rise to E), the ratio is not given ("-": out of its range) rather
than extrapolated.

    python bench/taylor_work_precision.py [--rounds 7] [--calls 5]
                                          [--problems kepler arenstorf]
                                          [--out bench/results/taylor_work_precision.md]
"""
import argparse
import math
import os
import sys
import time

import numpy as np

import conmech
from conmech import symbolic
from conmech.ivp.taylor import taylor_order

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_taylor import heyoka_runner, hy, problems, reference  # noqa: E402

RESULTS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results")
TOLS = [10.0**-k for k in range(8, 17)]
DOP853_MIN_TOL = 1e-14      # below, DOP853 is at its round-off floor (and slow): not run


def runners(pr, sys_, tol):
    """{method: (call, read)}: call() the solve alone (what is timed), read(r) -> (final
    state, steps, order or nfev)."""
    out = {}

    def conmech_run(m):
        def call():
            return conmech.solve_ivp(sys_, (0, pr["T"]), pr["y0"], method=m, rtol=tol,
                                     atol=tol)

        def read(r):
            assert r.success, r.message
            return r.y[:, -1], r.naccept, (taylor_order(tol) if m == "TAYLOR" else r.nfev)
        return call, read
    out["TAYLOR"] = conmech_run("TAYLOR")
    # the final state alone, as heyoka's propagate_until gives it: conmech.Propagator
    prop = conmech.Propagator(sys_, pr["y0"], method="TAYLOR", rtol=tol, atol=tol)
    y0 = np.array(pr["y0"], dtype=float)

    def prop_call():
        prop.t, prop.y = 0.0, y0
        return prop.propagate_until(pr["T"])

    def prop_read(o):
        assert o.success, o.message
        return prop.y, o.naccept, taylor_order(tol)
    out["propagate"] = (prop_call, prop_read)
    if tol >= DOP853_MIN_TOL:
        out["DOP853"] = conmech_run("DOP853")
    if hy is not None:
        out["heyoka"] = heyoka_runner(pr, tol, split=True)
    return out


def measure(name, rounds, calls):
    """Errors, steps and times of every method at every tolerance: the time of a solve
    call alone (its result read apart), the minimum over `calls` consecutive calls in each
    of `rounds` interleaved rounds."""
    pr = problems()[name]
    sys_ = symbolic.ode_system(pr["f"], pr["y"], params=pr["p"])
    ref = reference(sys_, pr)
    runs = {tol: runners(pr, sys_, tol) for tol in TOLS}
    rows = {tol: {} for tol in TOLS}
    for tol, rs in runs.items():             # first calls: compilation, set-up
        for m, (call, read) in rs.items():
            y, steps, extra = read(call())
            rows[tol][m] = dict(err=float(np.max(np.abs(y - ref))), steps=steps, extra=extra,
                                time=math.inf)
    clock = time.perf_counter
    for _ in range(rounds):
        for tol, rs in runs.items():
            for m, (call, _) in rs.items():
                best = rows[tol][m]["time"]
                for _ in range(calls):
                    a = clock()
                    call()
                    best = min(best, clock() - a)
                rows[tol][m]["time"] = best
    return rows


def at_equal_error(curve, err):
    """The time of a method at error `err`, interpolated in log-log along its curve
    [(error, time)] in tolerance order; None when no two consecutive points bracket err."""
    for (e1, t1), (e2, t2) in zip(curve, curve[1:]):
        lo, hi = min(e1, e2), max(e1, e2)
        if lo <= err <= hi and e1 != e2:
            s = (math.log(err) - math.log(e1))/(math.log(e2) - math.log(e1))
            return math.exp(math.log(t1) + s*(math.log(t2) - math.log(t1)))
        if err == e1 == e2:
            return min(t1, t2)
    return None


def table(name, rows):
    curves = {m: [(rows[t][m]["err"], rows[t][m]["time"]) for t in TOLS if m in rows[t]]
              for m in ("heyoka", "DOP853")}
    lines = [f"### {name}", "",
             "| tol | TAYLOR us / error / order, steps | heyoka us / error / order, steps | "
             "DOP853 us / error / nfev | TAYLOR / heyoka (equal error) | TAYLOR / heyoka "
             "(same tol) | TAYLOR / DOP853 (equal error) | TAYLOR / DOP853 (same tol) | "
             "Propagator us | Propagator / heyoka (equal error) | Propagator / heyoka "
             "(same tol) |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for tol in TOLS:
        r = rows[tol]
        t = r["TAYLOR"]
        cells = [f"{tol:.0e}",
                 f"{t['time']*1e6:.1f} / {t['err']:.1e} / {t['extra']}, {t['steps']}"]
        h = r.get("heyoka")
        cells.append(f"{h['time']*1e6:.1f} / {h['err']:.1e} / {h['extra']}, {h['steps']}"
                     if h else "-")
        d = r.get("DOP853")
        cells.append(f"{d['time']*1e6:.1f} / {d['err']:.1e} / {d['extra']}" if d else "-")
        for m, other in (("heyoka", h), ("DOP853", d)):
            te = at_equal_error(curves[m], t["err"]) if curves[m] else None
            cells.append(f"{t['time']/te:.2f}" if te else "-")
            cells.append(f"{t['time']/other['time']:.2f}" if other else "-")
        p = r["propagate"]
        cells.append(f"{p['time']*1e6:.1f}")
        te = at_equal_error(curves["heyoka"], p["err"]) if curves["heyoka"] else None
        cells.append(f"{p['time']/te:.2f}" if te else "-")
        cells.append(f"{p['time']/h['time']:.2f}" if h else "-")
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--calls", type=int, default=5, help="consecutive calls timed per round")
    ap.add_argument("--problems", nargs="*", default=["kepler", "arenstorf"])
    ap.add_argument("--out", default=os.path.join(RESULTS, "taylor_work_precision.md"))
    args = ap.parse_args()
    if hy is None:
        print("heyoka is not installed: only conmech's methods are timed")
    load0 = os.getloadavg()
    allrows = {name: measure(name, args.rounds, args.calls) for name in args.problems}
    load1 = os.getloadavg()
    lines = ["# Work-precision: conmech TAYLOR vs heyoka vs conmech DOP853", "",
             f"`python bench/taylor_work_precision.py --rounds {args.rounds} --calls "
             f"{args.calls} --problems {' '.join(args.problems)}`; heyoka "
             f"{getattr(hy, '__version__', 'not installed')}; one period, rtol = atol = tol; "
             "error = max-norm at the end against a quadruple-precision Taylor reference from the "
             "exact values of the doubles the runs start from; "
             f"time = min over {args.rounds} interleaved rounds of {args.calls} consecutive "
             "calls each (us, through Python: the solve_ivp / propagate_until call alone, "
             "its result read apart). "
             f"Load average (1 min) {load0[0]:.1f} at the start, {load1[0]:.1f} at the end "
             "(2 cores shared): wall-clock figures are provisional.", ""]
    for name, rows in allrows.items():
        lines += table(name, rows) + [""]
    text = "\n".join(lines)
    print(text)
    if args.out:
        with open(args.out, "w") as fh:
            fh.write(text)


if __name__ == "__main__":
    main()
