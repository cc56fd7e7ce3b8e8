"""Three equal masses m in the plane joined pairwise by springs (stiffness k, rest length
l0), no gravity, q = [x1, y1, x2, y2, x3, y3]."""
import itertools

import sympy as sp

from . import Lagrangian, Param

m = Param("m", 1.0, "mass of each point", positive=True)
k = Param("k", 10.0, "stiffness")
l0 = Param("l0", 1.0, "rest length")
q = sp.symbols("x1 y1 x2 y2 x3 y3", real=True)
v = sp.symbols("x1d y1d x2d y2d x3d y3d", real=True)
M, K, L0 = m.symbol, k.symbol, l0.symbol
U = sum(K*(sp.sqrt((q[2*j] - q[2*i])**2 + (q[2*j + 1] - q[2*i + 1])**2) - L0)**2/2
        for i, j in itertools.combinations(range(3), 2))

SYSTEM = Lagrangian("three_springs", "three_springs",
                    "Three equal masses joined pairwise by springs; "
                    "y = [x1, y1, x2, y2, x3, y3, vel.].", [m, k, l0], q=q, v=v,
                    T=M*sum(vi**2 for vi in v)/2, U=U,
                    q0=[0, 0, 1.2, 0, 0.5, 0.9], v0=[0, 0.1, 0, -0.2, 0.3, 0.1])
