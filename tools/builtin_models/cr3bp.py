"""The spatial circular restricted three-body problem in the rotating frame: primaries of
masses 1 - mu at (-mu, 0, 0) and mu at (1 - mu, 0, 0), y = [x, y, z, x', y', z']:

    x'' - 2 y' = Omega_x,   y'' + 2 x' = Omega_y,   z'' = Omega_z,
    Omega = (x^2 + y^2)/2 + (1 - mu)/r1 + mu/r2.

Written by hand (src/systems/conmech_cr3bp.f90): its Jacobian product applies the
symmetric Hessian of Omega and the Coriolis entries without forming J (the variational
equations of the halo and Lyapunov families run through it), and the module holds the
libration points and the Jacobi constant the family code uses."""
from . import Handwritten, Param

mu = Param("mu", 0.012150585609624, "mass ratio of the smaller primary (Earth-Moon)",
           positive=True, interval=(0.0, 0.5))

SYSTEM = Handwritten("cr3bp", "cr3bp", "ode",
                     "The spatial circular restricted three-body problem in the rotating "
                     "frame: primaries of masses 1 - mu at (-mu, 0, 0) and mu at (1 - mu, 0, "
                     "0) (0 < mu <= 1/2; default the Earth-Moon value), x'' - 2 y' = "
                     "Omega_x, y'' + 2 x' = Omega_y, z'' = Omega_z, Omega = (x^2 + y^2)/2 + "
                     "(1 - mu)/r1 + mu/r2; y = [x, y, z, x', y', z'] (analytic Jacobian and "
                     "Jacobian product); energy: the Jacobi constant C = 2 Omega - |v|^2. "
                     ":mod:`conmech.cr3bp` has its libration points and families.",
                     [mu], ["x", "y", "z"], "conmech_cr3bp", 6)
