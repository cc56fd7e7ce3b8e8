"""The pendulum with a moving suspension in Cartesian coordinates q = [x, y]: the support
moves as (s(t), 0), s = a t^2/2 + b sin(w t), and phi = ((x - s)^2 + y^2 - l^2)/2
(rheonomic). No energy is conserved."""
import sympy as sp

from . import Constrained, Param

m = Param("m", 1.0, "mass", positive=True)
g = Param("g", 9.81, "gravity")
l = Param("l", 1.0, "length", positive=True)
a = Param("a", 0.0, "acceleration of the support")
b = Param("b", 0.1, "amplitude of its oscillation")
w = Param("w", 3.0, "angular frequency of its oscillation")
x, y, xd, yd, t = sp.symbols("x y xd yd t", real=True)
M, G, L, A, B, W = (p.symbol for p in (m, g, l, a, b, w))
s = A*t**2/2 + B*sp.sin(W*t)
half = sp.Rational(1, 2)

SYSTEM = Constrained("pendulum_moving_xy", "pendulum_moving_xy",
                     "Pendulum with a moving suspension (s(t) = a t^2/2 + b sin w t), "
                     "rheonomic.", [m, g, l, a, b, w], q=[x, y], v=[xd, yd],
                     T=M*(xd**2 + yd**2)/2, U=M*G*y,
                     holonomic=[((x - s)**2 + y**2 - L**2)/2],
                     # at rest relative to the support, which starts at s = 0, s' = b w
                     q0=[L*sp.sin(half), -L*sp.cos(half)], v0=[B*W, 0], energy=False)
