"""Hill's lunar problem x'' - 2 m y' = F_x, y'' + 2 m x' = F_y with
F = kappa/r + (3/2) m^2 x^2, y = [x, y, x', y'] (analytic Jacobian and Jacobian product).

Written by hand (src/systems/conmech_hill.f90): the orbit and family code of
src/stability runs a written-out DOP853 kernel on it."""
import math

from . import Handwritten, Param

m = Param("m", 0.080848933808312, "ratio of the mean motions", interval=(0.0, math.inf))
kappa = Param("kappa", 1.0, "gravitational parameter", positive=True)

SYSTEM = Handwritten("hill", "hill_problem", "ode",
                     "Hill's lunar problem x'' - 2 m y' = F_x, y'' + 2 m x' = F_y, "
                     "F = kappa/r + (3/2) m^2 x^2; y = [x, y, x', y'] (analytic Jacobian).",
                     [m, kappa], ["x", "y"], "conmech_hill", 4)
