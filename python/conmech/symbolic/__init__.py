"""conmech.symbolic (in progress)."""

# exactness of Pfaffian constraints (holonomic or not; integrating factors)
from .pfaffian import (PfaffianResult, PfaffianSystemResult, pfaffian,  # noqa: E402,F401
                       pfaffian_from_velocities, pfaffian_system)
