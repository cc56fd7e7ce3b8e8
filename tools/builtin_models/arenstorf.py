"""The restricted three-body problem in Arenstorf's rotating frame (the Earth-Moon mass
ratio mu), y = [x, y, x', y']:

    x'' = x + 2 y' - (1 - mu)(x + mu)/r1^3 - mu (x - 1 + mu)/r2^3,
    y'' = y - 2 x' - (1 - mu) y/r1^3 - mu y/r2^3.

Written by hand (src/systems/conmech_arenstorf.f90): the integrator core's benchmark and
acceptance figure are measured on it, and its Jacobian product J x is the structure-aware
kernel of planar rotating-frame problems (conmech_rotating_frame), with the 4 x 4 STM
product written out."""
from . import Handwritten, Param

mu = Param("mu", 0.012277471, "mass ratio", interval=(0.0, 1.0))

SYSTEM = Handwritten("arenstorf", "arenstorf", "ode",
                     "Restricted three-body problem in Arenstorf's rotating frame; "
                     "y = [x, y, vx, vy].", [mu], ["x", "y"], "conmech_arenstorf", 4)
