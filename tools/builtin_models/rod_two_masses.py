"""Two unit masses on a massless rod of length l, q = [x1, y1, x2, y2], gravity along -y;
the velocity of the rod's centre stays along the rod (a knife edge at the centre, from the
lecture notes): (x2 - x1)(y1' + y2') - (y2 - y1)(x1' + x2') = 0, one holonomic and one
non-holonomic constraint."""
import sympy as sp

from . import Constrained, Param

g = Param("g", 9.81, "gravity")
l = Param("l", 1.0, "length of the rod", positive=True)
x1, y1, x2, y2 = q = sp.symbols("x1 y1 x2 y2", real=True)
v = x1d, y1d, x2d, y2d = sp.symbols("x1d y1d x2d y2d", real=True)
G, L = g.symbol, l.symbol
c, s = sp.cos(sp.Rational(1, 2)), sp.sin(sp.Rational(1, 2))

SYSTEM = Constrained("rod_two_masses", "rod_two_masses",
                     "Two unit masses on a rod, centre velocity along the rod (holonomic + "
                     "non-holonomic).", [g, l], q=q, v=v,
                     T=(x1d**2 + y1d**2 + x2d**2 + y2d**2)/2, U=G*(y1 + y2),
                     holonomic=[((x2 - x1)**2 + (y2 - y1)**2 - L**2)/2],
                     nonholonomic=[(x2 - x1)*(y1d + y2d) - (y2 - y1)*(x1d + x2d)],
                     # the centre moving along the rod at unit speed, turning at the rate 0.3
                     q0=[0, 0, L*c, L*s],
                     v0=[c + 0.3*s, s - 0.3*c, c - 0.3*s, s + 0.3*c])
