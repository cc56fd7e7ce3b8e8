"""The mathematical pendulum theta'' = -(g/l) sin(theta) as a first-order system,
y = [theta, theta'], theta from the downward vertical; its energy per unit mass l^2,
theta'^2/2 - (g/l) cos(theta), is conserved."""
import sympy as sp

from . import Ode, Param

g = Param("g", 9.81, "gravity")
l = Param("l", 1.0, "length", positive=True)
th, w = sp.symbols("theta thetad", real=True)
gl = g.symbol/l.symbol

SYSTEM = Ode("pendulum", "pendulum_theta",
             "Pendulum theta'' = -(g/l) sin(theta); y = [theta, theta'].", [g, l],
             y=[th, w], f=[w, -gl*sp.sin(th)], coords=["theta"],
             energy=w**2/2 - gl*sp.cos(th))
