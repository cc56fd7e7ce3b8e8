#!/usr/bin/env python3
"""Instructions per member (callgrind) of Taylor ensembles of the double pendulum from its
Lagrangian (bench_taylor_generalized_batch.py's problem, one thread): the batch route in
SIMD lanes (the machine's width, or --lanes) against the member-by-member route. Exact and
repeatable on a shared machine, unlike times; an instruction count is not a time (a 4-wide
vector instruction counts once).

    python bench/callgrind_taylor_generalized_batch.py [--m1 32] [--m2 288] [--T 10]
                                                       [--tol 1e-12] [--codes batch member]

Each code runs with m1 and m2 members in two processes under valgrind (the same start-up,
imports, initial states made, warm-up call; PYTHONHASHSEED=0, the garbage collector off);
the difference of the two totals over m2 - m1 is the count of one member.

    python bench/callgrind_taylor_generalized_batch.py one CODE M M2 T TOL  (what valgrind runs)
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def one(code, m, m2, T, tol):
    import gc
    import numpy as np
    sys.path.insert(0, HERE)
    from bench_taylor_generalized_batch import double_pendulum
    from conmech import ensemble
    system = double_pendulum()
    rng = np.random.default_rng(7)
    y0 = np.column_stack([rng.uniform(-1.0, 1.0, (m2, 2)),
                          rng.uniform(-0.5, 0.5, (m2, 2))])[:m]
    kw = dict(method="TAYLOR", rtol=tol, atol=tol, threads=1)
    lanes = None
    if code.startswith("batch") and code != "batch":
        lanes = int(code[5:])
    extra = {} if code.startswith("batch") else {"params": {"g": np.full(m, 9.81)}}
    warm = {} if code.startswith("batch") else {"params": {"g": np.full(8, 9.81)}}
    ensemble.solve(system, (0.0, T), y0[:8] if m >= 8 else y0, lanes=lanes, **kw, **warm)
    gc.disable()
    r = ensemble.solve(system, (0.0, T), y0, lanes=lanes, **kw, **extra)
    assert r.success
    print(float(np.mean(r.naccept)))


def count(code, m, m2, T, tol):
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "cg.out")
        env = dict(os.environ, PYTHONHASHSEED="0", OMP_NUM_THREADS="1")
        subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                        sys.executable, os.path.abspath(__file__), "one", code, str(m),
                        str(m2), repr(T), repr(tol)], check=True, env=env,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        with open(out) as f:
            text = f.read()
    return int(re.search(r"^summary:\s+(\d+)", text, re.M).group(1))


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "one":
        code, m, m2, T, tol = sys.argv[2:7]
        one(code, int(m), int(m2), float(T), float(tol))
        return
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--m1", type=int, default=32)
    ap.add_argument("--m2", type=int, default=288)
    ap.add_argument("--T", type=float, default=10.0)
    ap.add_argument("--tol", type=float, default=1e-12)
    ap.add_argument("--codes", nargs="+", default=["batch", "member"],
                    help="batch (the machine's lanes), batch2/batch4/batch8, member")
    args = ap.parse_args()
    # the libraries built (and cached) outside valgrind first
    for code in args.codes:
        one(code, 8, 8, 0.1, args.tol)
    for code in args.codes:
        c1 = count(code, args.m1, args.m2, args.T, args.tol)
        c2 = count(code, args.m2, args.m2, args.T, args.tol)
        print(f"{code:8s} {(c2 - c1)/(args.m2 - args.m1):14,.0f} instructions per member "
              f"(m {args.m1} -> {args.m2}, T {args.T:g}, tol {args.tol:g})", flush=True)


if __name__ == "__main__":
    main()
