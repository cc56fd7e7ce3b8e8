"""conmech: mechanical systems with constraints and the stability of their motions.

The Python package wraps the same Fortran sources as the fpm package (built by
numpy.f2py + meson-python). The integrators follow SciPy's names::

    import conmech
    sol = conmech.solve_ivp(conmech.systems.kepler(), (0, 10), [1, 0, 0, 1], rtol=1e-10)
"""
from . import constrained, systems
from . import hill, stability
from . import compiled
from ._ivp import DenseOutput, OdeResult, OdeSolution, solve_ivp
from ._dense import ConstantDenseOutput
from . import ensemble  # noqa: E402  (after _ivp: it builds on it)
from ._stepper import (DOP853, DOPRI5, RK4, RK45, VERNER98, Gauss4, Gauss6,  # noqa: F401
                       Radau, Stepper)

__all__ = ["solve_ivp", "OdeResult", "DenseOutput", "OdeSolution", "ConstantDenseOutput", "systems", "hill", "stability",
           "constrained", "compiled"]
__all__ += ["ensemble", "DOP853", "DOPRI5", "RK4", "RK45", "VERNER98"]
__all__ += ["Radau", "Gauss4", "Gauss6", "Stepper"]
__version__ = "0.1.0"
