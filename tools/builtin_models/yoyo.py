"""The yo-yo of the lecture notes: a disk (mass m, radius r, central moment of inertia I)
unwinding from a string whose end moves as y_h(t) = h0 + vh t + ah t^2/2, q = [y, psi] (the
centre's height, up, and the unwound angle): phi = y + r psi - y_h(t) (rheonomic); the
multiplier is the string's tension."""
import sympy as sp

from . import Constrained, Param

m = Param("m", 1.0, "mass", positive=True)
r = Param("r", 0.05, "radius", positive=True)
inertia = Param("I", 1.25e-3, "central moment of inertia", positive=True)
g = Param("g", 9.81, "gravity")
ah = Param("ah", 0.0, "acceleration of the string's end")
vh = Param("vh", 0.0, "its initial velocity")
h0 = Param("h0", 0.0, "its initial height")
y, psi, yd, psid, t = sp.symbols("y psi yd psid t", real=True)
M, Rr, I, G, AH, VH, H0 = (p.symbol for p in (m, r, inertia, g, ah, vh, h0))

SYSTEM = Constrained("yoyo", "yoyo",
                     "Yo-yo q = [y, psi] on a string moving as h0 + vh t + ah t^2/2 "
                     "(rheonomic).", [m, r, inertia, g, ah, vh, h0], q=[y, psi], v=[yd, psid],
                     T=M*yd**2/2 + I*psid**2/2, U=M*G*y,
                     holonomic=[y + Rr*psi - (H0 + VH*t + AH*t**2/2)],
                     q0=[H0, 0], v0=[VH, 0], energy=False)
