#!/usr/bin/env python3
"""The gfortran optimisation level of conmech.symbolic's model libraries: compile time
against the run time of the result.

For each level (--levels, default O1 O2 O3: -O1, -O2, -O3) and system (Arenstorf, Kepler),
in a fresh cache: the compile seconds of the model library (rhs, jac, jac_prod), of its
Taylor core library (conmech_taylor, conmech.symbolic.taylor_library) and of the
recurrences written out for the order of rtol = 1e-12 (wall clock, provisional on a loaded
machine); then the callgrind instruction count of one solve_ivp call (DOP853 and TAYLOR,
rtol = atol = 1e-12, Arenstorf: one period; Kepler e = 0.5: ten periods) with those
libraries, counted inside the flat solver only (--toggle-collect on flat_solve_: the
interpreter, the imports and the set-up not counted). Instruction counts are exactly
repeatable on a shared machine.

Usage:  python bench/bench_model_flags.py [--levels O1 O2 O3] [--systems arenstorf kepler]
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time

SETUP = {
    "arenstorf": ("[0.994, 0.0, 0.0, -2.00158510637908252240537862224]",
                  "17.0652165601579625588917206249"),
    "kepler": ("[0.5, 0.0, 0.0, 3.0**0.5]", "10*3.141592653589793*(1/0.5)**1.5"),
}

CHILD = r'''
import ctypes, json, sys
import numpy as np
import conmech
from conmech.mechanics.compiled import library_taylor, ode_system
info = json.loads(sys.argv[1])
lib = ctypes.CDLL(info["model"])
taylor = None
if info["method"] == "TAYLOR":
    tlib = ctypes.CDLL(info["taylor"])
    flib = ctypes.CDLL(info["fixed"])
    taylor = dict(library_taylor(tlib), jet_fixed=flib.conmech_taylor_fixed,
                  order=info["order"])
s = ode_system(4, lib.conmech_rhs, jac=lib.conmech_jac, jac_prod=lib.conmech_jac_prod,
               params=info["params"], keep=lib, taylor=taylor)
y0 = eval(info["y0"])
tf = eval(info["tf"])
r = conmech.solve_ivp(s, (0.0, tf), y0, method=info["method"], rtol=1e-12, atol=1e-12)
assert r.success
print(json.dumps({"nfev": int(r.nfev), "naccept": int(r.naccept),
                  "y": [float(v) for v in r.y[:, -1]]}))
'''


def build(which, flags, cache):
    """(paths and times) of the model, Taylor and fixed-order libraries for `flags`."""
    os.environ["CONMECH_CACHE"] = cache
    import sympy as sp
    from conmech import symbolic
    from conmech.ivp.taylor import taylor_order
    from conmech.symbolic import build as B
    from conmech.symbolic.taylor import fixed_order_source
    from conmech.symbolic.taylor_library import taylor_library
    x, y, u, w, mu = sp.symbols("x y u w mu")
    full = flags + ["-fPIC", "-shared"]
    if which == "arenstorf":
        mup = 1 - mu
        d1 = ((x + mu)**2 + y**2)**sp.Rational(3, 2)
        d2 = ((x - mup)**2 + y**2)**sp.Rational(3, 2)
        f = [u, w, x + 2*w - mup*(x + mu)/d1 - mu*(x - mup)/d2, y - 2*u - mup*y/d1 - mu*y/d2]
        model = symbolic.ode_system(f, [x, y, u, w], params={mu: 0.012277471}, flags=full,
                                    model_only=True)
    else:
        r3 = (x**2 + y**2)**sp.Rational(3, 2)
        model = symbolic.ode_system([u, w, -x/r3, -y/r3], [x, y, u, w], flags=full,
                                    model_only=True)
    t0 = time.perf_counter()
    taylor_library(model)
    t_taylor = time.perf_counter() - t0
    order = taylor_order(1e-12)
    t0 = time.perf_counter()
    fixed, _ = B.compile_source(fixed_order_source(model.derived, order, variational=False),
                                full)
    t_fixed = time.perf_counter() - t0
    return {"model": model.path, "taylor": model.taylor_path, "fixed": fixed,
            "order": order, "params": list(model.derived.param_values),
            "t_model": model.times["compile_or_load"], "t_taylor": t_taylor,
            "t_fixed": t_fixed}


def instructions(info, method, which):
    y0, tf = SETUP[which]
    arg = json.dumps(dict(info, method=method, y0=y0, tf=tf))
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "cg.out")
        res = subprocess.run(["valgrind", "--tool=callgrind", "--collect-atstart=no",
                              "--toggle-collect=flat_solve_", f"--callgrind-out-file={out}",
                              sys.executable, "-c", CHILD, arg],
                             capture_output=True, text=True, timeout=3600)
        if res.returncode != 0:
            raise RuntimeError(res.stderr[-2000:])
        with open(out) as fh:
            m = re.search(r"^(?:summary|totals):\s+(\d+)", fh.read(), re.M)
        return int(m.group(1)), json.loads(res.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", nargs="+", default=["O1", "O2", "O3"])
    ap.add_argument("--systems", nargs="+", default=["arenstorf", "kepler"])
    a = ap.parse_args()
    with open("/proc/loadavg") as fh:
        print("load before:", " ".join(fh.read().split()[:3]), flush=True)
    rows = []
    for which in a.systems:
        for level in a.levels:
            with tempfile.TemporaryDirectory(prefix="bench_flags_") as cache:
                info = build(which, ["-" + level], cache)
                counts = {}
                for method in ("DOP853", "TAYLOR"):
                    counts[method] = instructions(info, method, which)
            rows.append((which, level, info, counts))
            print(which, level, {k: (v[0], v[1]["naccept"]) for k, v in counts.items()},
                  flush=True)
    with open("/proc/loadavg") as fh:
        print("load after:", " ".join(fh.read().split()[:3]))
    print()
    print("| system | flags | compile s: model / Taylor / fixed order | DOP853 Mi (steps) | "
          "TAYLOR Mi (steps) | end state vs -O3 |")
    print("|---|---|---|---|---|---|")
    ref = {w: c for w, lv, _, c in rows if lv == "O3"}
    for which, level, info, counts in rows:
        dy = max(abs(p - q) for m in counts if which in ref
                 for p, q in zip(counts[m][1]["y"], ref[which][m][1]["y"]))
        print(f"| {which} | {level} | {info['t_model']:.2f} / {info['t_taylor']:.2f} / "
              f"{info['t_fixed']:.2f} | {counts['DOP853'][0]/1e6:.2f} "
              f"({counts['DOP853'][1]['naccept']}) | {counts['TAYLOR'][0]/1e6:.2f} "
              f"({counts['TAYLOR'][1]['naccept']}) | {dy:.1e} |")


if __name__ == "__main__":
    main()
