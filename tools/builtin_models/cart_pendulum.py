"""The pendulum on a cart of the lecture notes: a cart of mass M on a horizontal line and a
bob of mass m on a massless rod of length l hinged to it, q = [x, theta], theta from the
upward vertical (the bob at (x + l sin theta, l cos theta)). With M = m = l = 1 the
equations are the notes' 2 x'' + cos(th) th'' - sin(th) th'^2 = 0,
cos(th) x'' + th'' - g sin(th) = 0. The cart's coordinate is cyclic: its momentum is
conserved."""
import sympy as sp

from . import Lagrangian, Param

mc = Param("M", 1.0, "mass of the cart", component="mc", positive=True)
m = Param("m", 1.0, "mass of the bob", positive=True)
l = Param("l", 1.0, "length of the rod", positive=True)
g = Param("g", 9.81, "gravity")
x, th, xd, thd = sp.symbols("x theta xd thetad", real=True)
Mc, M, L, G = mc.symbol, m.symbol, l.symbol, g.symbol

SYSTEM = Lagrangian("cart_pendulum", "cart_pendulum",
                    "Pendulum on a cart (the lecture notes' seed system; theta from the "
                    "upright); y = [x, th, x', th'].", [mc, m, l, g], q=[x, th], v=[xd, thd],
                    T=Mc*xd**2/2 + M*((xd + L*sp.cos(th)*thd)**2 + (L*sp.sin(th)*thd)**2)/2,
                    U=M*G*L*sp.cos(th), q0=[0, 3], v0=[0, 0])
