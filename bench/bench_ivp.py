#!/usr/bin/env python3
"""conmech.solve_ivp vs scipy.integrate.solve_ivp (DOP853), same problems and tolerances.

Problems (both with an exact reference, so the error is the true global error):
  * kepler:    two-body orbit, mu = 1, a = 1, eccentricity 0.5, over 5 periods; the exact
               state after whole periods is the initial state;
  * arenstorf: Arenstorf's periodic orbit of the restricted three-body problem, one period.
rtol = atol in 1e-6 .. 1e-12. For each: the endpoint error (max norm), nfev and the CPU
time (best of several repeats; --clock wall for wall time) of
  * scipy     scipy.integrate.solve_ivp(method="DOP853") with a Python right-hand side,
  * callback  conmech.solve_ivp(method="DOP853") with the same Python right-hand side,
  * builtin   conmech.solve_ivp(method="DOP853") with the compiled built-in system,
  * vern9     conmech.solve_ivp(method="VERNER98"), built-in system (conmech's pair for
              tight tolerances; only compared at equal accuracy),
and the speed-ups scipy time / conmech time at equal tolerance, and at equal accuracy
(SciPy's time interpolated, log-log in its error, at conmech's error).

Usage:  python bench/bench_ivp.py [--quick] [--clock cpu|wall] [--out bench/results/ivp.md]
"""
import argparse
import datetime
import math
import os
import platform
import sys
import time

import numpy as np
import scipy
from scipy.integrate import solve_ivp as scipy_solve_ivp

import conmech
from conmech import systems

KEPLER_Y0 = np.array([0.5, 0.0, 0.0, math.sqrt(3.0)])
ARENSTORF_MU = 0.012277471
ARENSTORF_Y0 = np.array([0.994, 0.0, 0.0, -2.00158510637908252240537862224])
ARENSTORF_T = 17.0652165601579625588917206249


def kepler_rhs(t, y):
    r3 = (y[0] ** 2 + y[1] ** 2) ** 1.5
    return np.array([y[2], y[3], -y[0] / r3, -y[1] / r3])


def arenstorf_rhs(t, y):
    mu = ARENSTORF_MU
    mp = 1.0 - mu
    d1 = ((y[0] + mu) ** 2 + y[1] ** 2) ** 1.5
    d2 = ((y[0] - mp) ** 2 + y[1] ** 2) ** 1.5
    return np.array([y[2], y[3],
                     y[0] + 2.0 * y[3] - mp * (y[0] + mu) / d1 - mu * (y[0] - mp) / d2,
                     y[1] - 2.0 * y[2] - mp * y[1] / d1 - mu * y[1] / d2])


PROBLEMS = {
    "kepler": dict(rhs=kepler_rhs, builtin=systems.kepler(1.0), y0=KEPLER_Y0,
                   span=(0.0, 5 * 2 * math.pi), ref=KEPLER_Y0,
                   label="Kepler e=0.5, 5 periods"),
    "arenstorf": dict(rhs=arenstorf_rhs, builtin=systems.arenstorf(ARENSTORF_MU),
                      y0=ARENSTORF_Y0, span=(0.0, ARENSTORF_T), ref=ARENSTORF_Y0,
                      label="Arenstorf orbit, 1 period"),
}


def batch_size(run, min_total):
    """Calls per timed batch so that a batch lasts about min_total seconds."""
    t0 = clock()
    run()
    one = clock() - t0
    return max(1, int(min_total / max(one, 1e-7)))


CLOCK = {"cpu": time.process_time, "wall": time.perf_counter}
clock = time.process_time


def measure(problem, tol, repeats, min_total):
    """Error, nfev and best time per call of the three variants. The variants are timed
    in turns (one batch each per round) so that a change of machine load affects them
    alike; the best batch of each counts."""
    p = PROBLEMS[problem]
    runs = {
        "scipy": lambda: scipy_solve_ivp(p["rhs"], p["span"], p["y0"], method="DOP853",
                                         rtol=tol, atol=tol),
        "callback": lambda: conmech.solve_ivp(p["rhs"], p["span"], p["y0"], method="DOP853",
                                              rtol=tol, atol=tol),
        "builtin": lambda: conmech.solve_ivp(p["builtin"], p["span"], p["y0"],
                                             method="DOP853", rtol=tol, atol=tol),
        "vern9": lambda: conmech.solve_ivp(p["builtin"], p["span"], p["y0"],
                                           method="VERNER98", rtol=tol, atol=tol),
    }
    out = {}
    for name, run in runs.items():
        res = run()
        if not res.success:
            raise RuntimeError(f"{name} failed on {problem} at tol {tol}: {res.message}")
        err = float(np.max(np.abs(res.y[:, -1] - p["ref"])))
        out[name] = dict(time=math.inf, err=err, nfev=int(res.nfev),
                         number=batch_size(run, min_total))
    for _ in range(repeats):
        for name, run in runs.items():
            number = out[name]["number"]
            t0 = clock()
            for _ in range(number):
                run()
            out[name]["time"] = min(out[name]["time"], (clock() - t0) / number)
    return out


def equal_accuracy_ratio(scipy_rows, err, secs):
    """SciPy's time interpolated (log-log) at error `err`, divided by `secs`;
    None if err lies outside SciPy's measured error range."""
    e = np.log([r["err"] for r in scipy_rows])
    t = np.log([r["time"] for r in scipy_rows])
    order = np.argsort(e)
    e, t = e[order], t[order]
    le = math.log(err)
    if le < e[0] or le > e[-1]:
        return None
    return math.exp(np.interp(le, e, t)) / secs


def fmt_ratio(x):
    return "n/a" if x is None else f"{x:.0f}x" if x >= 10 else f"{x:.1f}x"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer tolerances and repeats")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                  "results", "ivp.md"))
    ap.add_argument("--clock", choices=sorted(CLOCK), default="cpu",
                    help="cpu: process time (the default: on a shared machine it leaves out "
                         "the time spent waiting for a core); wall: perf_counter")
    args = ap.parse_args()
    global clock
    clock = CLOCK[args.clock]
    tols = [1e-6, 1e-9, 1e-12] if args.quick else [1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11,
                                                     1e-12]
    repeats = 3 if args.quick else 15
    min_total = 0.03 if args.quick else 0.05

    load_start = os.getloadavg()[0]
    results = {}
    for problem in PROBLEMS:
        results[problem] = {}
        for tol in tols:
            results[problem][tol] = measure(problem, tol, repeats, min_total)
            r = results[problem][tol]
            print(f"{problem:9s} tol={tol:.0e}  scipy {r['scipy']['time']*1e3:8.2f} ms  "
                  f"callback {r['callback']['time']*1e3:8.2f} ms  "
                  f"builtin {r['builtin']['time']*1e3:8.3f} ms", flush=True)

    lines = []
    lines.append("# conmech.solve_ivp vs scipy.integrate.solve_ivp (DOP853)")
    lines.append("")
    lines.append(f"Generated by `python bench/bench_ivp.py` on "
                 f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC; "
                 f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
                 f"Python {platform.python_version()}, numpy {np.__version__}, "
                 f"SciPy {scipy.__version__}, conmech {conmech.__version__}; load average "
                 f"{load_start:.2f} at the start, {os.getloadavg()[0]:.2f} at the end (other "
                 f"processes on the machine make the times noisy: compare within a row).")
    lines.append("")
    lines.append("rtol = atol = tol. err: max-norm error of the final state against the exact "
                 "one. Times: best of several repeats, whole `solve_ivp` call (all steps "
                 f"stored), {'CPU (process) time' if args.clock == 'cpu' else 'wall time'}; "
                 "the variants interleaved round by round. Speed-up = SciPy time / conmech time, at equal tolerance; "
                 "'equal acc.' interpolates SciPy's time (log-log in its error) at conmech's "
                 "error (n/a outside SciPy's measured range).")
    summary = {}
    for problem, rows in results.items():
        lines.append("")
        lines.append(f"## {PROBLEMS[problem]['label']}")
        lines.append("")
        lines.append("| tol | err SciPy | err conmech | nfev SciPy | nfev conmech | "
                     "t SciPy (ms) | t callback (ms) | t built-in (ms) | "
                     "speed-up callback | speed-up built-in | built-in, equal acc. | "
                     "err Vern9 | t Vern9 (ms) | Vern9, equal acc. |")
        lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        scipy_rows = [rows[t]["scipy"] for t in tols]
        for tol in tols:
            r = rows[tol]
            s, c, b, v = r["scipy"], r["callback"], r["builtin"], r["vern9"]
            eq = equal_accuracy_ratio(scipy_rows, b["err"], b["time"])
            eqv = equal_accuracy_ratio(scipy_rows, v["err"], v["time"])
            sc, sb = s["time"] / c["time"], s["time"] / b["time"]
            summary.setdefault(problem, []).append((tol, sc, sb, eq, eqv))
            lines.append(f"| {tol:.0e} | {s['err']:.1e} | {b['err']:.1e} | {s['nfev']} | "
                         f"{b['nfev']} | {s['time']*1e3:.2f} | {c['time']*1e3:.2f} | "
                         f"{b['time']*1e3:.3f} | {fmt_ratio(sc)} | {fmt_ratio(sb)} | "
                         f"{fmt_ratio(eq)} | {v['err']:.1e} | {v['time']*1e3:.3f} | "
                         f"{fmt_ratio(eqv)} |")
    lines.append("")
    lines.append("Summary (speed-up over SciPy at equal tolerance, min .. max over tol):")
    lines.append("")
    def span(values, digits):
        values = [x for x in values if x is not None]
        if not values:
            return "n/a"
        return f"{min(values):.{digits}f}x .. {max(values):.{digits}f}x"

    for problem, rows in summary.items():
        lines.append(f"- {problem}: Python callback {span([r[1] for r in rows], 1)}, "
                     f"built-in DOP853 {span([r[2] for r in rows], 0)}; at equal accuracy: "
                     f"built-in DOP853 {span([r[3] for r in rows], 0)}, built-in VERNER98 "
                     f"{span([r[4] for r in rows], 0)}")
    text = "\n".join(lines) + "\n"
    print()
    print(text)
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w") as fh:
        fh.write(text)
    print(f"written to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
