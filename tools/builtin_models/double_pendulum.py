"""The double pendulum in absolute angles: point masses m1, m2 on massless rods l1, l2,
q = [theta1, theta2], each angle from the downward vertical (chaotic)."""
import sympy as sp

from . import Lagrangian, Param

m1 = Param("m1", 1.0, "upper mass", positive=True)
m2 = Param("m2", 1.0, "lower mass", positive=True)
l1 = Param("l1", 1.0, "upper rod", positive=True)
l2 = Param("l2", 1.0, "lower rod", positive=True)
g = Param("g", 9.81, "gravity")
t1, t2, w1, w2 = sp.symbols("theta1 theta2 theta1d theta2d", real=True)
M1, M2, L1, L2, G = (p.symbol for p in (m1, m2, l1, l2, g))

SYSTEM = Lagrangian("double_pendulum", "gen_double_pendulum",
                    "Double pendulum in absolute angles; y = [th1, th2, th1', th2'].",
                    [m1, m2, l1, l2, g], q=[t1, t2], v=[w1, w2],
                    T=(M1 + M2)*L1**2*w1**2/2 + M2*L2**2*w2**2/2
                    + M2*L1*L2*sp.cos(t1 - t2)*w1*w2,
                    U=-(M1 + M2)*G*L1*sp.cos(t1) - M2*G*L2*sp.cos(t2),
                    q0=[1, 0.5], v0=[0, 0])
