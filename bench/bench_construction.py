#!/usr/bin/env python3
"""Construction time of conmech.symbolic systems: derive + generate + compile + load in a
fresh compile cache, then the same construction in a second process (a cache hit).

Systems: Arenstorf's restricted three-body problem and the Kepler problem
(symbolic.ode_system), the 7-joint arm of the shipped URDF (symbolic.from_urdf, data/
arm7.urdf) and a spatial chain of 30 revolute links (symbolic.spatial_tree, the chain of
bench_spatial_tree.py). Each construction runs in its own process with its own fresh
CONMECH_CACHE, so that nothing is shared between runs; --python compares interpreters
(``LABEL=PYTHON[:PYTHONPATH]``: e.g. this branch's interpreter with and without a copy of
the package as it was before, on PYTHONPATH) in the same run, interleaved. Reported per
system and interpreter: the wall-clock seconds of the whole construction (median and min
of --repeat), its compile-only part (model.times compile_or_load) and the cache hit in a
second process; with --taylor, for the ode systems, the first TAYLOR solve after a cold
construction (what it compiles then); the load average before and after.

Usage:  python bench/bench_construction.py [--python LABEL=PYTHON[:PYTHONPATH] ...]
                                           [--repeat 3] [--taylor]
                                           [--systems arenstorf kepler arm7 chain30]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

CHILD = r'''
import json, sys, time
t0 = time.perf_counter()
import sympy as sp
from conmech import symbolic
t_import = time.perf_counter() - t0
which = sys.argv[1]
t0 = time.perf_counter()
if which in ("arenstorf", "kepler"):
    x, y, u, w, mu = sp.symbols("x y u w mu")
    if which == "arenstorf":
        mup = 1 - mu
        d1 = ((x + mu)**2 + y**2)**sp.Rational(3, 2)
        d2 = ((x - mup)**2 + y**2)**sp.Rational(3, 2)
        f = [u, w, x + 2*w - mup*(x + mu)/d1 - mu*(x - mup)/d2, y - 2*u - mup*y/d1 - mu*y/d2]
        model = symbolic.ode_system(f, [x, y, u, w], params={mu: 0.012277471},
                                    model_only=True)
    else:
        r3 = (x**2 + y**2)**sp.Rational(3, 2)
        model = symbolic.ode_system([u, w, -x/r3, -y/r3], [x, y, u, w], model_only=True)
elif which == "arm7":
    from conmech.symbolic.urdf import data_path
    model = symbolic.from_urdf(data_path("arm7.urdf"), model_only=True)
else:
    from sympy.physics.mechanics import dynamicsymbols
    from conmech.symbolic import SpatialBody
    N = int(which[len("chain"):])
    qs = dynamicsymbols(f"q1:{N + 1}")
    axes = [(0, 0, 1), (0, 1, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 0)]
    half = sp.Rational(3, 20)
    Ir = sp.Rational(9, 1200)
    bodies = [SpatialBody(f"l{i}", None if i == 0 else f"l{i - 1}", "revolute", qs[i],
                          axis=axes[i % 6], at=(0, 0, 0) if i == 0 else (0, 0, -2*half),
                          mass=1, com=(0, 0, -half),
                          inertia=[[Ir, 0, 0], [0, Ir, 0], [0, 0, Ir/100]])
              for i in range(N)]
    g = sp.Symbol("g")
    model = symbolic.spatial_tree(bodies, {g: 9.81}, gravity=(0, 0, -g), model_only=True)
total = time.perf_counter() - t0
first_taylor = None
if which in ("arenstorf", "kepler") and "--taylor" in sys.argv:
    # the first Taylor solve after the construction: what it compiles then (the
    # recurrences written out for its order; and with lazy Taylor code, its library)
    import conmech
    system = symbolic.pipeline._system(model)
    y0 = [0.994, 0.0, 0.0, -2.00158510637908252240537862224] if which == "arenstorf" \
        else [0.5, 0.0, 0.0, 3.0**0.5]
    t1 = time.perf_counter()
    r = conmech.solve_ivp(system, (0.0, 1.0), y0, method="TAYLOR", rtol=1e-12, atol=1e-12)
    assert r.success
    first_taylor = time.perf_counter() - t1
print(json.dumps({"total": total, "compile": model.times.get("compile_or_load", 0.0),
                  "hit": bool(model.cache_hit), "import": t_import,
                  "source_kb": len(model.source) / 1024, "first_taylor": first_taylor}))
'''


def uptime():
    try:
        with open("/proc/loadavg") as fh:
            return " ".join(fh.read().split()[:3])
    except OSError:
        return "?"


def run(python, which, cache, taylor=False):
    python, _, path = python.partition(":")
    env = dict(os.environ, CONMECH_CACHE=cache)
    if path:
        env["PYTHONPATH"] = path
    out = subprocess.run([python, "-c", CHILD, which] + (["--taylor"] if taylor else []),
                         capture_output=True, text=True,
                         env=env, timeout=3600)
    if out.returncode != 0:
        raise RuntimeError(f"{python} {which}: {out.stderr[-2000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--python", nargs="+", default=[f"this={sys.executable}"])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--taylor", action="store_true",
                    help="also time the first TAYLOR solve after a cold construction "
                         "(ode systems; a third process, its own fresh cache)")
    ap.add_argument("--systems", nargs="+", default=["arenstorf", "kepler", "arm7",
                                                       "chain30"])
    a = ap.parse_args()
    pythons = [p.split("=", 1) for p in a.python]
    print(f"load before: {uptime()}", flush=True)
    rows = []
    for which in a.systems:
        res = {label: [] for label, _ in pythons}
        hits = {label: [] for label, _ in pythons}
        for _ in range(a.repeat):
            for label, py in pythons:           # interleaved: the same load for each
                with tempfile.TemporaryDirectory(prefix="bench_construction_") as cache:
                    cold = run(py, which, cache)
                    warm = run(py, which, cache)
                with tempfile.TemporaryDirectory(prefix="bench_construction_") as cache:
                    tay = run(py, which, cache, taylor=True)["first_taylor"] \
                        if a.taylor else None
                cold["first_taylor"] = tay
                assert not cold["hit"] and warm["hit"], (cold, warm)
                res[label].append(cold)
                hits[label].append(warm)
                print(f"  {which} {label}: {cold['total']:.2f} s (compile "
                      f"{cold['compile']:.2f} s), hit {warm['total']*1e3:.0f} ms, first "
                      f"Taylor solve {tay if tay is None else round(tay, 2)} s", flush=True)
        for label, _ in pythons:
            tot = [r["total"] for r in res[label]]
            comp = [r["compile"] for r in res[label]]
            hit = [r["total"] for r in hits[label]]
            tay = [r["first_taylor"] for r in res[label] if r["first_taylor"] is not None]
            rows.append((which, label, statistics.median(tot), min(tot),
                         statistics.median(comp), min(comp), statistics.median(hit) * 1e3,
                         res[label][0]["source_kb"],
                         f"{statistics.median(tay):.2f} / {min(tay):.2f}" if tay else "-"))
    print(f"load after: {uptime()}")
    print()
    print("| system | build | construction s (median / min) | compile s (median / min) | "
          "cache hit ms (median) | model source KiB | first TAYLOR solve s (median / min) |")
    print("|---|---|---|---|---|---|---|")
    for which, label, tm, tmin, cm, cmin, hm, kb, tay in rows:
        print(f"| {which} | {label} | {tm:.2f} / {tmin:.2f} | {cm:.2f} / {cmin:.2f} | "
              f"{hm:.0f} | {kb:.0f} | {tay} |")


if __name__ == "__main__":
    main()
