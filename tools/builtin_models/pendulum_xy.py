"""The pendulum in Cartesian coordinates: a point mass m on a circle of radius l about the
origin, q = [x, y], gravity along -y. The constraint phi = (x^2 + y^2 - l^2)/2 makes the
multiplier lambda = m/l^2 (y g - x'^2 - y'^2) (the lecture notes' convention: the reaction
is G^T lambda)."""
import sympy as sp

from . import Constrained, Param

m = Param("m", 1.0, "mass", positive=True)
g = Param("g", 9.81, "gravity")
l = Param("l", 1.0, "length", positive=True)
x, y, xd, yd = sp.symbols("x y xd yd", real=True)
M, G, L = m.symbol, g.symbol, l.symbol

SYSTEM = Constrained("pendulum_xy", "pendulum_xy",
                     "Point mass on a circle, q = [x, y], phi = (x^2 + y^2 - l^2)/2 "
                     "(constrained.solve).", [m, g, l], q=[x, y], v=[xd, yd],
                     T=M*(xd**2 + yd**2)/2, U=M*G*y, holonomic=[(x**2 + y**2 - L**2)/2],
                     q0=[L*sp.sin(1), -L*sp.cos(1)], v0=[0, 0])
