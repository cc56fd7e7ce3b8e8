"""The spring pendulum in polar coordinates: a mass m on a spring (stiffness k, rest length
l0) hinged at the origin, q = [r, theta], theta from the downward vertical."""
import sympy as sp

from . import Lagrangian, Param

m = Param("m", 1.0, "mass", positive=True)
k = Param("k", 40.0, "stiffness")
l0 = Param("l0", 1.0, "rest length")
g = Param("g", 9.81, "gravity")
r, th, rd, thd = sp.symbols("r theta rd thetad", real=True)
M, K, L0, G = (p.symbol for p in (m, k, l0, g))

SYSTEM = Lagrangian("spring_pendulum", "spring_pendulum",
                    "Spring pendulum in polar coordinates; y = [r, th, r', th'].",
                    [m, k, l0, g], q=[r, th], v=[rd, thd], T=M*(rd**2 + r**2*thd**2)/2,
                    U=-M*G*r*sp.cos(th) + K*(r - L0)**2/2,
                    q0=[1.2, 0.8], v0=[0, 0])
