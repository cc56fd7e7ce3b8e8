"""The Van der Pol oscillator x'' = mu (1 - x^2) x' - x as a first-order system,
y = [x, x'] (stiff for large mu)."""
import sympy as sp

from . import Ode, Param

mu = Param("mu", 1.0, "damping")
x, v = sp.symbols("x v", real=True)

SYSTEM = Ode("vanderpol", "van_der_pol",
             "Van der Pol oscillator x'' = mu (1 - x^2) x' - x; y = [x, x'].", [mu],
             y=[x, v], f=[v, mu.symbol*(1 - x**2)*v - x], coords=["x"])
