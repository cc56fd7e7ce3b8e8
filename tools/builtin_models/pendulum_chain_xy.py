"""A chain of N Cartesian pendulums, q = [x1, y1, ..., xN, yN]: point masses m on massless
rods of length l, the first hinged at the origin, gravity along -y; N holonomic constraints
phi_i = ((x_i - x_{i-1})^2 + (y_i - y_{i-1})^2 - l^2)/2 (x_0 = y_0 = 0).

Written by hand (src/systems/conmech_systems_chain.f90): N is a run-time parameter, and
the type declares its diagonal mass and the row windows of G (`phi_jac_band`), so that the
KKT solve and the projections cost O(N) (the generated types have a fixed size and dense
constraint Jacobians)."""
from . import Handwritten, Param

nl = Param("N", 8, "number of links", interval=(1, 100000), whole=True)
m = Param("m", 1.0, "mass of each point")
l = Param("l", 1.0, "length of each rod")
g = Param("g", 9.81, "gravity")

SYSTEM = Handwritten(
    "pendulum_chain_xy", "pendulum_chain_xy", "constrained",
    "Chain of N Cartesian pendulums q = [x1, y1, ..., xN, yN], N rod constraints (a diagonal "
    "mass and a banded constraint Jacobian: O(N) per step in constrained.solve).",
    [nl, m, l, g], [], "conmech_systems_chain", None,
    make="call make_pendulum_chain(p, sys, info, msg)",
    initial="call pendulum_chain_state(p, q0, v0, info)",
    python_factory='''\
try:
    whole = float(N) == int(N) and 1 <= int(N) <= 100000
except (TypeError, ValueError, OverflowError):
    whole = False
if isinstance(N, bool) or not whole:
    raise ValueError(f"pendulum_chain_xy: N must be a whole number of links in "
                     f"1..100000, got {N!r}")
return BuiltinConstrained("pendulum_chain_xy", [int(N), m, l, g])''')
