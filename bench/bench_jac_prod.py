"""STM integration with and without a compiled Jacobian product (issues 8/10).

The Arenstorf orbit written as formulas (``conmech.symbolic.ode_system``): its monodromy
matrix (one period, DOP853 on the 20 variational equations, rtol = atol = 1e-12) through
``conmech.stability.monodromy`` (-> Fortran ``integrate_stm``) with the generated
``conmech_jac_prod`` (z' = [f; J Phi] without forming J), with only the generated dense
Jacobian (J formed, then multiplied), and the built-in arenstorf (hand-written product).

    python bench/bench_jac_prod.py [time] [--repeat 9] [--periods 10]
        CPU time (time.process_time), best of --repeat rounds, the three interleaved in
        one process; every variant's monodromy is checked against the others.
    python bench/bench_jac_prod.py save LIB.so
        write the symbolic system as a model library (no sympy needed to run it)
    valgrind --tool=callgrind --toggle-collect='flat_stm_' \\
        python bench/bench_jac_prod.py one prod|dense|builtin --lib LIB.so
        one period of one variant: instructions inside the Fortran STM integration only
"""
import argparse
import ctypes
import os
import sys
import time

import numpy as np

from conmech import compiled, stability, systems

MU = 0.012277471
Y0 = [0.994, 0.0, 0.0, -2.00158510637908252240537862224]
T = 17.0652165601579625588917206249


def symbolic_system():
    from conmech import symbolic
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..",
                                    "python", "tests"))
    import symbolic_seeds as seeds
    f, y, mu = seeds.arenstorf_ode()
    return symbolic.ode_system(f, y, params={mu: MU})


def variants(lib=None):
    """{name: system}: the symbolic system with its product, the same compiled rhs and
    dense Jacobian without it, the built-in."""
    if lib is None:
        from conmech import symbolic
        with_p = symbolic_system()
        m = symbolic.model_of(with_p)
        rhs, jac, keep = m.addresses["rhs"], m.addresses["jac"], m
    else:
        with_p = compiled.load_model(lib)
        keep = ctypes.CDLL(lib)
        rhs, jac = keep.conmech_rhs, keep.conmech_jac
    dense = compiled.ode_system(4, rhs, jac=jac, params={"mu": MU}, keep=keep)
    return {"prod": with_p, "dense": dense, "builtin": systems.arenstorf()}


LABEL = {"prod": "symbolic + jac_prod", "dense": "symbolic, dense J",
         "builtin": "built-in arenstorf"}


def timing(a):
    vs = variants()
    mono = {k: stability.monodromy(s, Y0, T, rtol=1e-12, atol=1e-12) for k, s in vs.items()}
    ref = mono["dense"]
    for k, mm in mono.items():
        print(f"{LABEL[k]:22s} max|M - M_dense|/max|M| = "
              f"{np.abs(mm - ref).max()/np.abs(ref).max():.1e}")
    best = dict.fromkeys(vs, np.inf)
    for _ in range(a.repeat):
        for k, s in vs.items():
            t0 = time.process_time()
            for _ in range(a.periods):
                stability.monodromy(s, Y0, T, rtol=1e-12, atol=1e-12)
            best[k] = min(best[k], (time.process_time() - t0)/a.periods)
    for k, b in best.items():
        print(f"{LABEL[k]:22s} {1e3*b:8.3f} ms per period   ratio to the built-in "
              f"{b/best['builtin']:.3f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", nargs="?", default="time", choices=["time", "save", "one"])
    ap.add_argument("arg", nargs="?", help="save: the library path; one: the variant")
    ap.add_argument("--lib", help="one: the model library written by save")
    ap.add_argument("--repeat", type=int, default=9)
    ap.add_argument("--periods", type=int, default=10, help="monodromy calls per timing")
    a = ap.parse_args()
    if a.what == "time":
        timing(a)
    elif a.what == "save":
        from conmech import symbolic
        print(symbolic.save_model(symbolic_system(), a.arg))
    else:
        if a.arg not in LABEL or not a.lib:
            ap.error("one needs a variant (prod, dense, builtin) and --lib LIB.so")
        stability.monodromy(variants(a.lib)[a.arg], Y0, T, rtol=1e-12, atol=1e-12)


if __name__ == "__main__":
    main()
