"""The double spring pendulum in Cartesian coordinates: mass m1 on a spring (k1, rest
length l1) from the origin, mass m2 on a spring (k2, rest l2) from mass 1,
q = [x1, y1, x2, y2], gravity along -y."""
import sympy as sp

from . import Lagrangian, Param

m1 = Param("m1", 1.0, "first mass", positive=True)
m2 = Param("m2", 1.0, "second mass", positive=True)
k1 = Param("k1", 40.0, "first stiffness")
k2 = Param("k2", 40.0, "second stiffness")
l1 = Param("l1", 1.0, "first rest length")
l2 = Param("l2", 1.0, "second rest length")
g = Param("g", 9.81, "gravity")
x1, y1, x2, y2 = q = sp.symbols("x1 y1 x2 y2", real=True)
v = sp.symbols("x1d y1d x2d y2d", real=True)
M1, M2, K1, K2, L1, L2, G = (p.symbol for p in (m1, m2, k1, k2, l1, l2, g))
r1 = sp.sqrt(x1**2 + y1**2)
r2 = sp.sqrt((x2 - x1)**2 + (y2 - y1)**2)

SYSTEM = Lagrangian("double_spring_pendulum", "double_spring_pendulum",
                    "Double spring pendulum in Cartesian coordinates; "
                    "y = [x1, y1, x2, y2, velocities].", [m1, m2, k1, k2, l1, l2, g], q=q, v=v,
                    T=M1*(v[0]**2 + v[1]**2)/2 + M2*(v[2]**2 + v[3]**2)/2,
                    U=M1*G*y1 + M2*G*y2 + K1*(r1 - L1)**2/2 + K2*(r2 - L2)**2/2,
                    q0=[0.8, -0.8, 1.5, -1.6], v0=[0, 0, 0, 0])
