"""The yo-yo of the lecture notes in its one coordinate: a disk (mass m, radius r, central
moment of inertia I) unwinds from a string whose end moves as y_h(t) = h0 + vh t + ah t^2/2,
q = [y] (the centre's height, up); the unwound angle psi = (y_h - y)/r eliminated:
(m + I/r^2) y'' = -m g + (I/r^2) ah."""
import sympy as sp

from . import Lagrangian, Param

m = Param("m", 1.0, "mass", positive=True)
r = Param("r", 0.05, "radius", positive=True)
inertia = Param("I", 1.25e-3, "central moment of inertia", positive=True)
g = Param("g", 9.81, "gravity")
ah = Param("ah", 0.0, "acceleration of the string's end")
vh = Param("vh", 0.0, "its initial velocity")
h0 = Param("h0", 0.0, "its initial height")
y, yd, t = sp.symbols("y yd t", real=True)
M, Rr, I, G, AH, VH, H0 = (p.symbol for p in (m, r, inertia, g, ah, vh, h0))
psid = (sp.diff(H0 + VH*t + AH*t**2/2, t) - yd)/Rr

SYSTEM = Lagrangian("yoyo_angle", "gen_yoyo",
                    "Yo-yo on a string moving as h0 + vh t + ah t^2/2; y = [y, y'].",
                    [m, r, inertia, g, ah, vh, h0], q=[y], v=[yd],
                    T=M*yd**2/2 + I*psid**2/2, U=M*G*y, q0=[0], v0=[0], energy=False)
