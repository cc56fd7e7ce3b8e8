"""The Atwood machine of the lecture notes in excessive coordinates: masses m1, m2 at the
depths q = [y1, y2] (measured downward) on a string of length L over a massless pulley,
phi = L - y1 - y2: the multiplier is the string's tension."""
import sympy as sp

from . import Constrained, Param

m1 = Param("m1", 2.0, "first mass", positive=True)
m2 = Param("m2", 1.0, "second mass", positive=True)
g = Param("g", 9.81, "gravity")
L = Param("L", 2.0, "length of the string", component="len")
y1, y2, y1d, y2d = sp.symbols("y1 y2 y1d y2d", real=True)
M1, M2, G, LL = (p.symbol for p in (m1, m2, g, L))

SYSTEM = Constrained("atwood_xy", "atwood_xy",
                     "Atwood machine q = [y1, y2] (downward), y1 + y2 = L; the multiplier is "
                     "the tension.", [m1, m2, g, L], q=[y1, y2], v=[y1d, y2d],
                     T=(M1*y1d**2 + M2*y2d**2)/2, U=-G*(M1*y1 + M2*y2),
                     holonomic=[LL - y1 - y2], q0=[LL/2, LL/2], v0=[0, 0])
