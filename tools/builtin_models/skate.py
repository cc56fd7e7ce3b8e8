"""The ice skate (a knife edge) on a plane inclined at alpha (downhill = +x):
q = [x, y, theta], mass m, moment of inertia I about the contact point; the blade cannot
move sideways: -sin(theta) x' + cos(theta) y' = 0 (non-holonomic)."""
import sympy as sp

from . import Constrained, Param

m = Param("m", 1.0, "mass", positive=True)
inertia = Param("I", 1.0, "moment of inertia", positive=True)
g = Param("g", 9.81, "gravity")
alpha = Param("alpha", 0.3, "inclination of the plane")
x, y, th, xd, yd, thd = sp.symbols("x y theta xd yd thetad", real=True)
M, I, G, AL = (p.symbol for p in (m, inertia, g, alpha))

SYSTEM = Constrained("skate", "skate",
                     "Ice-skate blade / knife edge on an incline, q = [x, y, theta] "
                     "(non-holonomic).", [m, inertia, g, alpha], q=[x, y, th],
                     v=[xd, yd, thd], T=M*(xd**2 + yd**2)/2 + I*thd**2/2,
                     U=-M*G*sp.sin(AL)*x, nonholonomic=[-sp.sin(th)*xd + sp.cos(th)*yd],
                     q0=[0, 0, 0], v0=[0, 0, 2])
