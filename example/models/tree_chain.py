"""A triple pendulum described as a planar multibody tree, for `python -m conmech.symbolic
emit`: three point masses on massless rods, absolute angles from the downward vertical
(PyDy's chain). The emitted type's right-hand side is the articulated-body algorithm
(O(n), no matrix); its Jacobian is the exact one of the Lagrangian.

    python -m conmech.symbolic emit example/models/tree_chain.py \\
        -o example/tree_chain_model.f90
"""
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

from conmech.symbolic.tree import Body, derive_tree

name = "tree_chain_sym"   # the Fortran type (module: the output file's stem)


def inputs():
    """(bodies, params, gravity, coordinates): also for conmech.symbolic.planar_tree."""
    th = dynamicsymbols("th1:4")
    m1, m2, m3, l1, l2, l3, g = sp.symbols("m1 m2 m3 l1 l2 l3 g")
    m, l = (m1, m2, m3), (l1, l2, l3)
    bodies = [Body(f"link{i + 1}", None if i == 0 else f"link{i}", "revolute", th[i],
                   at=(0, 0) if i == 0 else (0, -l[i - 1]), mass=m[i], com=(0, -l[i]))
              for i in range(3)]
    params = {m1: 1.0, m2: 0.8, m3: 0.6, l1: 1.0, l2: 0.9, l3: 0.7, g: 9.81}
    return bodies, params, (0, -g), "absolute"


def model():
    bodies, params, gravity, coordinates = inputs()
    return derive_tree(bodies, params, gravity, coordinates=coordinates)
