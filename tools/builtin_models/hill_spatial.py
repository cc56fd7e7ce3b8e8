"""Hill's lunar problem in space, y = [x, y, z, x', y', z']:

    x'' - 2 m y' = F_x,   y'' + 2 m x' = F_y,   z'' = F_z,
    F = kappa/r + (3/2) m^2 x^2 - (1/2) m^2 z^2,

in the units of the planar problem (synodic month 2 pi).

Written by hand (src/systems/conmech_hill_spatial.f90): its exact Jacobian product
applies the symmetric Hessian of F and the Coriolis entries without forming J, for the
variational equations of the spatial families."""
import math

from . import Handwritten, Param

m = Param("m", 0.080848933808312, "ratio of the mean motions", interval=(0.0, math.inf))
kappa = Param("kappa", 1.0, "gravitational parameter", positive=True)

SYSTEM = Handwritten("hill_spatial", "hill_spatial", "ode",
                     "Hill's lunar problem in space: x'' - 2 m y' = F_x, y'' + 2 m x' = F_y, "
                     "z'' = F_z, F = kappa/r + (3/2) m^2 x^2 - (1/2) m^2 z^2 (so z'' + m^2 z "
                     "= -kappa z/r^3), in the units of :func:`hill` (synodic month 2 pi); y "
                     "= [x, y, z, x', y', z'] (analytic Jacobian); energy: the Jacobi "
                     "integral |v|^2 - 2 F.", [m, kappa], ["x", "y", "z"],
                     "conmech_hill_spatial", 6)
