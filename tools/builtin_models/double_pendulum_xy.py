"""The double pendulum in Cartesian coordinates q = [x1, y1, x2, y2]: masses m1, m2 on rods
l1 (from the origin) and l2 (from mass 1), gravity along -y, two holonomic constraints
phi_1 = (x1^2 + y1^2 - l1^2)/2, phi_2 = ((x2 - x1)^2 + (y2 - y1)^2 - l2^2)/2."""
import sympy as sp

from . import Constrained, Param

m1 = Param("m1", 1.0, "upper mass", positive=True)
m2 = Param("m2", 1.0, "lower mass", positive=True)
l1 = Param("l1", 1.0, "upper rod", positive=True)
l2 = Param("l2", 1.0, "lower rod", positive=True)
g = Param("g", 9.81, "gravity")
x1, y1, x2, y2 = q = sp.symbols("x1 y1 x2 y2", real=True)
v = sp.symbols("x1d y1d x2d y2d", real=True)
M1, M2, L1, L2, G = (p.symbol for p in (m1, m2, l1, l2, g))
half = sp.Rational(1, 2)

SYSTEM = Constrained("double_pendulum_xy", "double_pendulum_xy",
                     "Double pendulum in Cartesian coordinates q = [x1, y1, x2, y2], two "
                     "constraints.", [m1, m2, l1, l2, g], q=q, v=v,
                     T=M1*(v[0]**2 + v[1]**2)/2 + M2*(v[2]**2 + v[3]**2)/2,
                     U=G*(M1*y1 + M2*y2),
                     holonomic=[(x1**2 + y1**2 - L1**2)/2,
                                ((x2 - x1)**2 + (y2 - y1)**2 - L2**2)/2],
                     q0=[L1*sp.sin(1), -L1*sp.cos(1), L1*sp.sin(1) + L2*sp.sin(half),
                         -L1*sp.cos(1) - L2*sp.cos(half)], v0=[0, 0, 0, 0])
