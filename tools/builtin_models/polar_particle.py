"""A particle of mass m in the plane in polar coordinates q = [r, theta] in the central
field U = -m mu/r (the Kepler problem; r = 0 is singular)."""
import sympy as sp

from . import Lagrangian, Param

m = Param("m", 1.0, "mass", positive=True)
mu = Param("mu", 1.0, "gravitational parameter")
r, th, rd, thd = sp.symbols("r theta rd thetad", real=True)
M, MU = m.symbol, mu.symbol

SYSTEM = Lagrangian("polar_particle", "polar_particle",
                    "Particle in polar coordinates, U = -m mu / r; y = [r, th, r', th'].",
                    [m, mu], q=[r, th], v=[rd, thd], T=M*(rd**2 + r**2*thd**2)/2, U=-M*MU/r,
                    q0=[1, 0], v0=[0, 1.2])
