"""A closed kinematic loop: the four-bar linkage as a tree (two cranks and a coupler) plus
the revolute joint that closes it (conmech.symbolic.Loop). Consistent initial state from
the crank angle, a motion, the joint force from the multipliers.

    python example/fourbar.py
"""
import numpy as np
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

from conmech import constrained, symbolic

phi1, psi, phi2 = dynamicsymbols("phi1 psi phi2")          # absolute angles of the bars
m, l1, l2, l3, d, g = sp.symbols("m l1 l2 l3 d g")


def rod(length):
    return dict(mass=m, com=(length/2, 0), inertia=m*length**2/12)


bodies = [symbolic.Body("crank1", None, "revolute", phi1, at=(0, 0), **rod(l1)),
          symbolic.Body("coupler", "crank1", "revolute", psi, at=(l1, 0), **rod(l2)),
          symbolic.Body("crank2", None, "revolute", phi2, at=(d, 0), **rod(l3))]
mech = symbolic.planar_tree(bodies, {m: 1.0, l1: 0.5, l2: 1.3, l3: 1.1, d: 1.5, g: 9.81},
                            gravity=(0, -g), coordinates="absolute",
                            loops=[symbolic.Loop("coupler", (l2, 0), "crank2", (l3, 0))])

# a crank-rocker (Grashof: the crank turns all the way round): the crank at 1.2 rad
# turning at 6 rad/s; the coupler and the rocker follow
q0, v0 = symbolic.consistent_state(mech, [1.2, 0.4, 1.6], [6.0, 0, 0], independent=[phi1])
print("consistent initial state:", np.round(q0, 6), np.round(v0, 6))
r = constrained.solve(mech, (0, 3), q0, v0, t_eval=np.linspace(0, 3, 7), rtol=1e-10,
                      atol=1e-10)
print(f"{r.message}; max |phi| = {np.max(r.res_pos):.1e}; energy drift "
      f"{np.max(np.abs(r.energy - r.energy[0])):.1e}")
for t, q, lam in zip(r.t, r.q.T, r.lam.T):
    print(f"t = {t:4.2f}  angles {np.round(q, 4)}  force of the joint on the coupler "
          f"{np.round(lam, 3)} N")
