#!/usr/bin/env python3
"""Instructions per member (callgrind) of Taylor ensembles: the propagator over SIMD lanes
(lanes 1, the machine's width, 8) against the member-by-member Taylor route, DOP853 and
heyoka's batch mode (its JIT compilation cancels in the difference),
on the benchmark's problem (Kepler e = 0.5, members spread in mean anomaly, 10 periods,
tol 1e-12, one thread). Exact and repeatable on a shared machine, unlike times; an
instruction count is not a time (a 4-wide vector instruction counts once).

    python bench/callgrind_taylor_batch.py [--m1 64] [--m2 1024] [--repeat 3] [--tol 1e-12]
                                           [--periods 10] [--codes lanes lanes8 ...]

Each code runs with m1 and m2 members in two processes under valgrind; the difference of
the two totals over m2 - m1 is the count of one member. Everything but the integration is
the same in both processes, so that it cancels: the same interpreter start-up, imports and
hash seed (PYTHONHASHSEED=0), the same initial states made (m2 of them; the first m1 or
m2 integrated), the same warm-up call (the compiled libraries loaded or JIT-compiled), the
garbage collector off. What does not cancel (the interpreter's and a JIT's own
variations) is spread over m2 - m1 members: over the 32 of 8 and 40 members it made the
figure printed for 4 lanes 139,909 where a standalone Fortran driver of the same library
counts 385,670; the default spreads it over 960. Each pair is run `repeat` times: the mean
and the spread (min-max) are printed.

    python bench/callgrind_taylor_batch.py one CODE M M2 TOL PERIODS    (what valgrind runs)
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
CODES = ("lanes1", "lanes", "lanes8", "member", "dop853", "heyoka")


def one(code, m, m2, tol, periods):
    import gc
    import numpy as np
    sys.path.insert(0, HERE)
    from bench_taylor_batch import initial_states, kepler_symbolic
    import conmech
    from conmech import ensemble
    y0 = initial_states(m2, 0.5)[:m]          # the same states made in both processes
    tf = 2*np.pi*periods
    kw = dict(method="TAYLOR", rtol=tol, atol=tol, threads=1)
    if code == "heyoka":          # its batch mode, JIT-compiled before the count differs
        import heyoka as hy
        from bench_taylor_batch import Heyoka
        h = Heyoka(hy, tol)
        h.run(initial_states(8, 0.5), 1.0, 1)
        gc.disable()
        yf, steps = h.run(y0, tf, 1)
        print(float(np.mean(steps)))
        return
    warm = initial_states(8, 0.5)
    if code == "dop853":
        system, kw = conmech.systems.kepler(), dict(method="DOP853", rtol=tol, atol=tol,
                                                   threads=1)
    elif code == "member":
        system = kepler_symbolic(True)
        ensemble.solve(system, (0, 1.0), warm, params={"mu": np.ones(8)}, **kw)
        kw["params"] = {"mu": np.ones(m)}
    else:
        system = kepler_symbolic()
        kw["lanes"] = {"lanes1": 1, "lanes8": 8, "lanes": None}[code]
    if code != "member":
        ensemble.solve(system, (0, 1.0), warm, **kw)
    gc.disable()
    r = ensemble.solve(system, (0, tf), y0, **kw)
    assert r.success
    print(float(np.mean(r.naccept)))


def count(code, m, m2, tol, periods, tmp):
    out = os.path.join(tmp, f"cg.{code}.{m}")
    cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", sys.executable,
           os.path.abspath(__file__), "one", code, str(m), str(m2), str(tol), str(periods)]
    env = dict(os.environ, PYTHONHASHSEED="0")
    res = subprocess.run(cmd, capture_output=True, text=True, check=True, env=env)
    steps = float(res.stdout.strip().splitlines()[-1])
    with open(out) as fh:
        for line in fh:
            mm = re.match(r"^(summary|totals):\s+(\d+)", line)
            if mm:
                return int(mm.group(2)), steps
    raise RuntimeError("no totals in the callgrind output")


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "one":
        one(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), float(sys.argv[5]),
            float(sys.argv[6]))
        return
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--m1", type=int, default=64)
    ap.add_argument("--m2", type=int, default=1024)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--tol", type=float, default=1e-12)
    ap.add_argument("--periods", type=float, default=10.0)
    ap.add_argument("--codes", nargs="+", default=list(CODES), choices=CODES)
    args = ap.parse_args()
    if not 0 < args.m1 < args.m2:
        ap.error("need 0 < m1 < m2")
    from conmech.symbolic.taylor_batch import machine_lanes
    print(f"# callgrind, Kepler e = 0.5, {args.periods:g} periods, tol {args.tol:g}, one "
          f"thread; members {args.m1} and {args.m2}, {args.repeat} pairs each; machine "
          f"lanes {machine_lanes()}")
    print("| code | instructions/member (mean) | spread (min-max) | instructions/step | "
          "steps/member |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for code in args.codes:
            per = []
            for _ in range(args.repeat):
                i1, _ = count(code, args.m1, args.m2, args.tol, args.periods, tmp)
                i2, steps = count(code, args.m2, args.m2, args.tol, args.periods, tmp)
                per.append((i2 - i1)/(args.m2 - args.m1))
            mean = sum(per)/len(per)
            print(f"| {code} | {mean:,.0f} | {min(per):,.0f}-{max(per):,.0f} | "
                  f"{mean/steps:,.0f} | {steps:.1f} |", flush=True)


if __name__ == "__main__":
    main()
