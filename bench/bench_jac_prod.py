"""STM integration with and without a compiled Jacobian product (issues 8/10).

The Arenstorf orbit written as formulas (``conmech.symbolic.ode_system``): its monodromy
matrix (one period, DOP853 on the 20 variational equations, rtol = atol = 1e-12) through
``conmech.stability.monodromy`` (-> Fortran ``integrate_stm``) with the generated
``conmech_jac_prod`` (z' = [f; J Phi] without forming J), with only the generated dense
Jacobian (J formed, then multiplied), and the built-in arenstorf (hand-written product).
CPU time (time.process_time), best of --repeat rounds, the three run interleaved in the
same process; every variant's monodromy is checked against the others.

    python bench/bench_jac_prod.py [--repeat 7] [--periods 10]
"""
import argparse
import os
import sys
import time

import numpy as np

from conmech import compiled, stability, symbolic, systems

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python",
                                "tests"))
import symbolic_seeds as seeds  # noqa: E402

MU = 0.012277471
Y0 = [0.994, 0.0, 0.0, -2.00158510637908252240537862224]
T = 17.0652165601579625588917206249


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--periods", type=int, default=10, help="monodromy calls per timing")
    a = ap.parse_args()
    f, y, mu = seeds.arenstorf_ode()
    with_p = symbolic.ode_system(f, y, params={mu: MU})
    m = symbolic.model_of(with_p)
    dense = compiled.ode_system(4, m.addresses["rhs"], jac=m.addresses["jac"],
                                params={"mu": MU}, keep=m)
    variants = {"symbolic + jac_prod": with_p, "symbolic, dense J": dense,
                "built-in arenstorf": systems.arenstorf()}
    mono = {k: stability.monodromy(s, Y0, T, rtol=1e-12, atol=1e-12)
            for k, s in variants.items()}
    ref = mono["symbolic, dense J"]
    for k, mm in mono.items():
        print(f"{k:22s} max|M - M_dense|/max|M| = "
              f"{np.abs(mm - ref).max()/np.abs(ref).max():.1e}")
    best = dict.fromkeys(variants, np.inf)
    for _ in range(a.repeat):
        for k, s in variants.items():
            t0 = time.process_time()
            for _ in range(a.periods):
                stability.monodromy(s, Y0, T, rtol=1e-12, atol=1e-12)
            best[k] = min(best[k], (time.process_time() - t0)/a.periods)
    base = best["symbolic + jac_prod"]
    for k, b in best.items():
        print(f"{k:22s} {1e3*b:8.3f} ms per period   ratio to symbolic + jac_prod "
              f"{b/base:.3f}")


if __name__ == "__main__":
    main()
