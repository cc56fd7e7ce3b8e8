"""The Atwood machine of the lecture notes in its one coordinate: masses m1 and m2 on a
string over a massless pulley, y1 measured downward (y1 + y2 = L eliminated):
(m1 + m2) y1'' = (m1 - m2) g."""
import sympy as sp

from . import Lagrangian, Param

m1 = Param("m1", 2.0, "first mass", positive=True)
m2 = Param("m2", 1.0, "second mass", positive=True)
g = Param("g", 9.81, "gravity")
y1, y1d = sp.symbols("y1 y1d", real=True)
M1, M2, G = m1.symbol, m2.symbol, g.symbol

SYSTEM = Lagrangian("atwood", "gen_atwood",
                    "Atwood machine, y1 downward: (m1 + m2) y1'' = (m1 - m2) g; y = [y1, y1'].",
                    [m1, m2, g], q=[y1], v=[y1d], T=(M1 + M2)*y1d**2/2,
                    U=-(M1 - M2)*G*y1, q0=[0], v0=[0], energy=False)
