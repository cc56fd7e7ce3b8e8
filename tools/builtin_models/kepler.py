"""The planar two-body (Kepler) problem r'' = -mu r/|r|^3, y = [x, y, vx, vy]; its energy
per unit mass |v|^2/2 - mu/|r| is conserved."""
import sympy as sp

from . import Ode, Param

mu = Param("mu", 1.0, "gravitational parameter", positive=True)
x, y, u, w = sp.symbols("x y u w", real=True)
r3 = (x**2 + y**2)**sp.Rational(3, 2)

SYSTEM = Ode("kepler", "kepler_2d",
             "Planar two-body problem r'' = -mu r/|r|^3; y = [x, y, vx, vy].", [mu],
             y=[x, y, u, w], f=[u, w, -mu.symbol*x/r3, -mu.symbol*y/r3], coords=["x", "y"],
             energy=(u**2 + w**2)/2 - mu.symbol/sp.sqrt(x**2 + y**2))
