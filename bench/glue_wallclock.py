#!/usr/bin/env python3
"""Wall-clock cost of conmech's Python glue per call: each entry point beside the flat
f2py routine it ends in, called directly with arguments prepared once (that call is f2py's
argument handling plus the Fortran), interleaved in one process.

    python bench/glue_wallclock.py [CASE ...] [--runs 5] [--rounds 200] [--batch 20]

Every figure is the minimum over ``rounds`` batches of ``batch`` calls (per call), taken
``runs`` times; the table gives the smallest and the largest of the runs' minima, so the
spread between runs is visible. ``uptime`` is printed before and after: on a loaded machine
the minima still move; the instruction counts of bench/glue_callgrind.py are exact.

Cases (entry point | the flat call alone):
  hill      hill.variation_orbit(M_HILL) | _conmech.flat_hill_orbit_checked
  family    hill.family(ms) per orbit (ms: 64 values in [0.05, 0.1], locate=False):
            the glue is its Python timed with the flat call's result given, the entry
            figure that plus the flat call | _conmech.flat_hill_family, per orbit
  step      DOP853(kepler).step() | the step's flat routine with its prepared arguments
  radau     Radau(kepler).step()  (rtol = atol = 1e-10)
  gauss6    Gauss6(kepler, first_step=1e-3).step()
  taylor    Stepper(symbolic kepler, method="TAYLOR").step() (rtol = atol = 1e-12)
  call      CompiledModel.call("rhs", t, y) of a 2-state symbolic ode model
            | _conmech.flat_entry_call_1 with its arguments
"""
import argparse
import os
import subprocess
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

STEPPERS = {"step": ("DOP853", {}), "radau": ("Radau", {}),
            "gauss6": ("Gauss6", {"first_step": 1e-2}),
            "taylor": ("TAYLOR", {"rtol": 1e-12, "atol": 1e-12})}


def _stepper(case):
    import conmech
    name, kw = STEPPERS[case]
    kw = dict({"rtol": 1e-10, "atol": 1e-10}, **kw)
    y0 = [0.4, 0.0, 0.0, 2.0]
    if name == "TAYLOR":
        import sympy as sp
        from conmech import symbolic
        x, y, u, v = sp.symbols("x y u v")
        r3 = (x**2 + y**2)**sp.Rational(3, 2)
        fun = symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])
    else:
        fun = conmech.systems.kepler()
    # t_bound: not reached within the measurement (Gauss6: N = 1e8 fixed steps over it)
    t_bound = 1e6 if name == "Gauss6" else 1e9
    a = conmech.Stepper(fun, 0.0, y0, t_bound, method=name, **kw)
    b = conmech.Stepper(fun, 0.0, y0, t_bound, method=name, **kw)
    a.step()
    b.step()
    routine, args = b._step_call
    return a.step, lambda: routine(*args), 1


def make(case):
    """(entry point, the flat call alone, calls of the flat work per entry call)."""
    import numpy as np
    if case in STEPPERS:
        return _stepper(case)
    from conmech import _conmech
    if case == "hill":
        from conmech import hill
        g = np.zeros(2)
        return (lambda: hill.variation_orbit(hill.M_HILL),
                lambda: _conmech.flat_hill_orbit_checked(hill.M_HILL, 1.0, 0, 0, 0, g,
                                                         1e-12, 2560), 1)
    if case == "family":
        # the family's flat call (~1.5 ms) dwarfs its glue on a loaded machine: the entry
        # point is timed with that call replaced by its result, computed once (so the
        # figure is the Python around the call; the flat column is the call itself)
        from conmech import hill
        ms = np.linspace(0.05, 0.1, 64)
        result = _conmech.flat_hill_family(ms, 1.0, 0, 256)

        class _Cached:
            def __getattr__(self, name):
                if name == "flat_hill_family":
                    return lambda *args: result
                return getattr(_conmech, name)

        def glue_only():
            hill._conmech = _Cached()
            try:
                hill.family(ms, locate=False)
            finally:
                hill._conmech = _conmech

        # the entry point's figure is its Python alone here: the flat call (~1.5 ms) moves
        # by more than the glue between two timings on a loaded machine
        return (glue_only, lambda: _conmech.flat_hill_family(ms, 1.0, 0, 256), -ms.size)
    if case == "call":
        import sympy as sp
        from conmech import symbolic
        from conmech.symbolic import model_of
        x, v, k = sp.symbols("x v k")
        model = model_of(symbolic.ode_system([v, -k*sp.sin(x)], [x, v], params={k: 2.0}))
        y = np.array([0.3, 0.1])
        model.call("rhs", 0.0, y)
        address, _, _, sizes, _ = model._calls["rhs"]
        p = model._params(None)
        return (lambda: model.call("rhs", 0.0, y),
                lambda: _conmech.flat_entry_call_1(address, 0.0, y, sizes[0], p), 1)
    raise SystemExit(f"unknown case {case}")


def per_call(f, batch):
    t = time.perf_counter()
    for _ in range(batch):
        f()
    return (time.perf_counter() - t)/batch


def measure(case, runs, rounds, batch):
    """Per run: (entry point, flat call, glue) in us; per < 0: the entry point is timed
    without its flat call (the glue itself), the entry figure is glue + flat."""
    full, flat, per = make(case)
    mins = []
    for _ in range(runs):
        bf = bl = float("inf")
        for _ in range(rounds):
            bf = min(bf, per_call(full, batch))
            bl = min(bl, per_call(flat, batch))
        f, l = bf/abs(per)*1e6, bl/abs(per)*1e6
        mins.append((f + l, l, f) if per < 0 else (f, l, f - l))
    return mins


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="*", default=["hill", "family", "step", "radau",
                                                 "gauss6", "taylor", "call"])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=200)
    ap.add_argument("--batch", type=int, default=20)
    a = ap.parse_args()
    print("before:", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    print("| case | entry point, us | flat call alone, us | glue (difference), us |")
    print("|---|---|---|---|")
    for case in a.cases:
        batch = max(1, a.batch//8) if case == "family" else a.batch
        mins = measure(case, a.runs, a.rounds if case != "family" else a.rounds//4, batch)
        full = [m[0] for m in mins]
        flat = [m[1] for m in mins]
        glue = [m[2] for m in mins]
        print(f"| {case} | {min(full):.2f}-{max(full):.2f} | {min(flat):.2f}-{max(flat):.2f} "
              f"| {min(glue):.2f}-{max(glue):.2f} |", flush=True)
    print("after:", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())


if __name__ == "__main__":
    sys.exit(main())
