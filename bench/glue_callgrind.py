#!/usr/bin/env python3
"""Instructions per call of conmech's Python entry points that do one Fortran call, split
into the Fortran call (the flat routine, inclusive) and the Python + f2py glue around it,
by callgrind (exact counts, independent of the machine's load).

    python bench/glue_callgrind.py [CASE ...] [--k1 10] [--k2 1010]

Each case runs K1 and K2 times in two processes under ``valgrind --tool=callgrind``
(OPENBLAS_NUM_THREADS=1); (I(K2) - I(K1))/(K2 - K1) is one call, with the interpreter's
start-up, the imports and the set-up cancelled. The Fortran share is the inclusive count
of the flat routine the call ends in (callgrind_annotate), the glue the rest.

Cases:
  step    conmech.DOP853(kepler).step(), one accepted step (flat_stepper_step_builtin)
  solve   conmech.solve_ivp(kepler, (0, 0.01), DOP853): the fixed cost of a short solve
          of a built-in system (flat_propagation_solve: the system and stepper kept
          with the packed arguments; flat_solve_packed in a build before it)
  hill    conmech.hill.variation_orbit(M_HILL) (flat_hill_orbit_checked)
  call    CompiledModel.call("rhs", t, y) of a symbolic ode model (the model's rhs, in
          its own library; the flat routine flat_entry_call_1 calls it)
  sym     solve_ivp(kepler from conmech.symbolic, (0, 0), DOP853): the fixed cost on a
          compiled symbolic system (flat_propagation_solve)
  symp    the same with a parameter (params={mu: 1.0})
  taylor  the same system, method TAYLOR, rtol = atol = 1e-12 (flat_propagation_solve)
  py      solve_ivp(Python callable, (0, 0), DOP853) (flat_solve)
  radau   conmech.Radau(kepler).step(), rtol = atol = 1e-10 (flat_stepper_step_builtin)
  gauss6  conmech.Gauss6(kepler, first_step=1e-3).step() (flat_stepper_step_builtin)
  tstep   conmech.Stepper(symbolic kepler, method="TAYLOR").step(), rtol = atol = 1e-12
          (flat_stepper_step_builtin)
  family  conmech.hill.family(64 values of m in [0.05, 0.1], locate=False): per call of
          64 orbits (flat_hill_family)

    python bench/glue_callgrind.py one CASE REPS        (what valgrind runs)
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

# (the flat routine or model symbol whose inclusive count is the Fortran share; the
# solve cases name the routines of older builds after it, so that a build from before
# flat_propagation_solve or flat_solve_packed is split the same way)
_SOLVE = "flat_propagation_solve_|flat_solve_packed_|flat_solve_native_"
SYMBOLS = {"step": "flat_stepper_step_builtin_", "solve": _SOLVE,
           "hill": "flat_hill_orbit_checked_", "call": "conmech_rhs",
           "sym": _SOLVE, "symp": _SOLVE, "taylor": _SOLVE, "py": "flat_solve_"}


def make(case):
    """The call to count, after its set-up."""
    import numpy as np
    import conmech
    if case in MORE_CASES:
        return MORE_CASES[case]()
    if case == "step":
        s = conmech.DOP853(conmech.systems.kepler(), 0.0, [0.4, 0.0, 0.0, 2.0], 1e9,
                           rtol=1e-10, atol=1e-10)
        return s.step
    if case == "solve":
        kep = conmech.systems.kepler()
        y0 = [0.5, 0.0, 0.0, 3.0 ** 0.5]
        return lambda: conmech.solve_ivp(kep, (0.0, 0.01), y0, method="DOP853")
    if case == "hill":
        from conmech import hill
        return lambda: hill.variation_orbit(hill.M_HILL)
    if case == "call":
        import sympy as sp
        from conmech import symbolic
        from conmech.symbolic import model_of
        x, v, k = sp.symbols("x v k")
        sys_ = symbolic.ode_system([v, -k * sp.sin(x)], [x, v], params={k: 2.0})
        model = model_of(sys_)
        y = np.array([0.3, 0.1])
        model.call("rhs", 0.0, y)
        return lambda: model.call("rhs", 0.0, y)
    if case in ("sym", "symp", "taylor"):
        import sympy as sp
        from conmech import symbolic
        x, y, u, v, mu = sp.symbols("x y u v mu")
        r3 = (x**2 + y**2)**sp.Rational(3, 2)
        if case == "symp":
            s = symbolic.ode_system([u, v, -mu*x/r3, -mu*y/r3], [x, y, u, v],
                                    params={mu: 1.0})
        else:
            s = symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])
        y0 = [0.5, 0.0, 0.0, 3.0 ** 0.5]
        m = "TAYLOR" if case == "taylor" else "DOP853"
        return lambda: conmech.solve_ivp(s, (0.0, 0.0), y0, method=m, rtol=1e-12,
                                         atol=1e-12)
    if case == "py":
        y0 = [0.5, 0.0, 0.0, 3.0 ** 0.5]

        def f(t, y):
            return -y
        return lambda: conmech.solve_ivp(f, (0.0, 0.0), y0, method="DOP853")
    raise SystemExit(f"unknown case {case}")


def _stepper_case(method, fun, **kw):
    """A step of `method` on `fun` from the Kepler state of the `step` case."""
    import conmech
    s = conmech.Stepper(fun, 0.0, [0.4, 0.0, 0.0, 2.0], 1e3, method=method, **kw)
    return s.step


def _symbolic_kepler():
    import sympy as sp
    from conmech import symbolic
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    return symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])


def _family_case():
    import numpy as np
    from conmech import hill
    ms = np.linspace(0.05, 0.1, 64)
    return lambda: hill.family(ms, locate=False)


def _kepler():
    import conmech
    return conmech.systems.kepler()


# the cases of the steppers other than DOP853 and of hill.family (their flat routines)
MORE_CASES = {
    "radau": lambda: _stepper_case("Radau", _kepler(), rtol=1e-10, atol=1e-10),
    "gauss6": lambda: _stepper_case("Gauss6", _kepler(), first_step=1e-3),
    "tstep": lambda: _stepper_case("TAYLOR", _symbolic_kepler(), rtol=1e-12, atol=1e-12),
    "family": _family_case,
}
SYMBOLS.update(radau="flat_stepper_step_builtin_", gauss6="flat_stepper_step_builtin_",
               tstep="flat_stepper_step_builtin_", family="flat_hill_family_")


def one(case, reps):
    f = make(case)
    f()
    for _ in range(reps):
        f()


def count(case, reps, tmp):
    out = os.path.join(tmp, f"cg.{case}.{reps}")
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1",
               PYTHONHASHSEED="0")     # the imports' counts repeatable between the runs
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                    sys.executable, os.path.abspath(__file__), "one", case, str(reps)],
                   check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    total = None
    with open(out) as fh:
        for line in fh:
            if line.startswith(("summary:", "totals:")):
                total = int(line.split()[1])
                break
    ann = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", out],
                         capture_output=True, text=True).stdout
    fort = 0
    for sym in SYMBOLS[case].split("|"):
        for line in ann.splitlines():
            m = re.match(r"\s*([\d,]+)\s.*[\s:]" + re.escape(sym) + r"(\s|$|\[)", line)
            if m:
                fort = int(m.group(1).replace(",", ""))
                break
        if fort:
            break
    return total, fort


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "one":
        one(sys.argv[2], int(sys.argv[3]))
        return
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="*", default=list(SYMBOLS))
    ap.add_argument("--k1", type=int, default=10)
    ap.add_argument("--k2", type=int, default=1010)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for case in a.cases:
            t1, f1 = count(case, a.k1, tmp)
            t2, f2 = count(case, a.k2, tmp)
            k = a.k2 - a.k1
            tot, fort = (t2 - t1) / k, (f2 - f1) / k
            print(f"{case:6s} instructions per call: total {tot:,.0f}, Fortran ({SYMBOLS[case]}) "
                  f"{fort:,.0f}, Python + f2py glue {tot - fort:,.0f}", flush=True)


if __name__ == "__main__":
    main()
