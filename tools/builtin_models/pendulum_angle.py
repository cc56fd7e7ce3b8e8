"""The pendulum in its angle: a point mass m on a massless rod of length l, theta from the
downward vertical, q = [theta]: m l^2 theta'' = -m g l sin(theta)."""
import sympy as sp

from . import Lagrangian, Param

m = Param("m", 1.0, "mass", positive=True)
g = Param("g", 9.81, "gravity")
l = Param("l", 1.0, "length", positive=True)
th, thd = sp.symbols("theta thetad", real=True)
M, G, L = m.symbol, g.symbol, l.symbol

SYSTEM = Lagrangian("pendulum_angle", "gen_pendulum",
                    "Pendulum m l^2 th'' = -m g l sin th (angle from the downward vertical); "
                    "y = [th, th'].", [m, g, l], q=[th], v=[thd],
                    T=M*L**2*thd**2/2, U=-M*G*L*sp.cos(th), q0=[1], v0=[0])
