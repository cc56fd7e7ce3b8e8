#!/usr/bin/env python3
"""Instructions per member (callgrind) of Taylor ensembles: the propagator over SIMD lanes
(lanes 1, the machine's width, 8) against the member-by-member Taylor route, DOP853 and
heyoka's batch mode (its JIT compilation cancels in the difference),
on the benchmark's problem (Kepler e = 0.5, members spread in mean anomaly, 10 periods,
tol 1e-12, one thread). Exact and repeatable on a shared machine, unlike times; an
instruction count is not a time (a 4-wide vector instruction counts once).

    python bench/callgrind_taylor_batch.py [--m1 8] [--m2 40] [--tol 1e-12] [--periods 10]

Each code runs with m1 and m2 members in two processes under valgrind; the difference of
the two totals over m2 - m1 is the count of one member, with the interpreter's start-up,
the imports and the set-up (the compiled libraries are loaded from the cache: run the
benchmark or the code once before) cancelled.

    python bench/callgrind_taylor_batch.py one CODE M TOL PERIODS    (what valgrind runs)
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
CODES = ("lanes1", "lanes", "lanes8", "member", "dop853", "heyoka")


def one(code, m, tol, periods):
    import numpy as np
    sys.path.insert(0, HERE)
    from bench_taylor_batch import initial_states, kepler_symbolic
    import conmech
    from conmech import ensemble
    y0 = initial_states(m, 0.5)
    tf = 2*np.pi*periods
    kw = dict(method="TAYLOR", rtol=tol, atol=tol, threads=1)
    if code == "heyoka":          # its batch mode, JIT-compiled before the count differs
        import heyoka as hy
        from bench_taylor_batch import Heyoka
        h = Heyoka(hy, tol)
        yf, steps = h.run(y0, tf, 1)
        print(float(np.mean(steps)))
        return
    if code == "dop853":
        r = ensemble.solve(conmech.systems.kepler(), (0, tf), y0, method="DOP853",
                           rtol=tol, atol=tol, threads=1)
    elif code == "member":
        r = ensemble.solve(kepler_symbolic(True), (0, tf), y0, params={"mu": np.ones(m)},
                           **kw)
    else:
        lanes = {"lanes1": 1, "lanes8": 8, "lanes": None}[code]
        r = ensemble.solve(kepler_symbolic(), (0, tf), y0, lanes=lanes, **kw)
    assert r.success
    print(float(np.mean(r.naccept)))


def count(code, m, tol, periods, tmp):
    out = os.path.join(tmp, f"cg.{code}.{m}")
    cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", sys.executable,
           os.path.abspath(__file__), "one", code, str(m), str(tol), str(periods)]
    res = subprocess.run(cmd, capture_output=True, text=True, check=True)
    steps = float(res.stdout.strip().splitlines()[-1])
    with open(out) as fh:
        for line in fh:
            mm = re.match(r"^(summary|totals):\s+(\d+)", line)
            if mm:
                return int(mm.group(2)), steps
    raise RuntimeError("no totals in the callgrind output")


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "one":
        one(sys.argv[2], int(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5]))
        return
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--m1", type=int, default=8)
    ap.add_argument("--m2", type=int, default=40)
    ap.add_argument("--tol", type=float, default=1e-12)
    ap.add_argument("--periods", type=float, default=10.0)
    ap.add_argument("--codes", nargs="+", default=list(CODES), choices=CODES)
    args = ap.parse_args()
    from conmech.symbolic.taylor_batch import machine_lanes
    print(f"# callgrind, Kepler e = 0.5, {args.periods:g} periods, tol {args.tol:g}, one "
          f"thread; members {args.m1} and {args.m2}; machine lanes {machine_lanes()}")
    print("| code | instructions/member | instructions/step | steps/member |")
    print("|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for code in args.codes:
            i1, _ = count(code, args.m1, args.tol, args.periods, tmp)
            i2, steps = count(code, args.m2, args.tol, args.periods, tmp)
            per = (i2 - i1)/(args.m2 - args.m1)
            print(f"| {code} | {per:,.0f} | {per/steps:,.0f} | {steps:.1f} |", flush=True)


if __name__ == "__main__":
    main()
