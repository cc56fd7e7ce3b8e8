"""A pendulum whose suspension point moves horizontally as s(t) = a t^2/2 + b sin(w t)
(rheonomic), q = [theta] from the downward vertical: the bob at (s + l sin(theta),
-l cos(theta)) gives l theta'' + g sin(theta) + s''(t) cos(theta) = 0. No energy is
conserved (the support does work)."""
import sympy as sp

from . import Lagrangian, Param

m = Param("m", 1.0, "mass", positive=True)
g = Param("g", 9.81, "gravity")
l = Param("l", 1.0, "length", positive=True)
a = Param("a", 0.0, "acceleration of the support")
b = Param("b", 0.1, "amplitude of its oscillation")
w = Param("w", 3.0, "angular frequency of its oscillation")
th, thd, t = sp.symbols("theta thetad t", real=True)
M, G, L, A, B, W = (p.symbol for p in (m, g, l, a, b, w))
s = A*t**2/2 + B*sp.sin(W*t)
xd = sp.diff(s, t) + L*sp.cos(th)*thd
yd = L*sp.sin(th)*thd

SYSTEM = Lagrangian("pendulum_moving", "gen_pendulum_moving",
                    "Pendulum with suspension s(t) = a t^2/2 + b sin(w t) (rheonomic); "
                    "y = [th, th'].", [m, g, l, a, b, w], q=[th], v=[thd],
                    T=M*(xd**2 + yd**2)/2, U=-M*G*L*sp.cos(th), q0=[1], v0=[0], energy=False)
