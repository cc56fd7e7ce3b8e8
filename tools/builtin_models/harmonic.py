"""The harmonic oscillator x'' = -omega^2 x as a first-order system, y = [x, x']."""
import sympy as sp

from . import Ode, Param

omega = Param("omega", 1.0, "angular frequency")
x, v = sp.symbols("x v", real=True)

SYSTEM = Ode("harmonic", "harmonic_oscillator",
             "Harmonic oscillator x'' = -omega^2 x; y = [x, v].", [omega],
             y=[x, v], f=[v, -omega.symbol**2*x], coords=["x"])
