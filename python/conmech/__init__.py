"""conmech: mechanical systems with constraints and the stability of their motions.

The Python package wraps the same Fortran sources as the fpm package (built by
numpy.f2py + meson-python). The integrators follow SciPy's names::

    import conmech
    sol = conmech.solve_ivp(conmech.systems.kepler(), (0, 10), [1, 0, 0, 1], rtol=1e-10)

The folders are layers, each importing only those below it: ``_core`` (argument checks,
status codes, result records, the callback guard, the system handle), ``ivp`` (solve_ivp,
the steppers, dense output, ensembles), ``mechanics`` (built-in, constrained and compiled
systems, degrees of freedom), ``stability``, ``control``, ``symbolic``.
"""
import sys

from .ivp import ensemble
from .ivp.dense import ConstantDenseOutput
from .ivp.solve import DenseOutput, OdeResult, OdeSolution, solve_ivp
from .ivp.propagator import Propagation, Propagator
from .ivp.stepper import (DOP853, DOPRI5, RK4, RK45, VERNER98, Gauss4, Gauss6,  # noqa: F401
                          Radau, Stepper)
from .mechanics import compiled, constrained, degrees_of_freedom, systems
from . import hill, stability

# The public module paths conmech.systems, conmech.constrained, ... name the modules of
# the layered folders: one module object under both names, so that `import
# conmech.systems`, `from conmech.compiled import evaluate` and Sphinx's automodule work.
for _name, _module in (("systems", systems), ("constrained", constrained),
                       ("compiled", compiled), ("degrees_of_freedom", degrees_of_freedom),
                       ("ensemble", ensemble)):
    sys.modules.setdefault(f"{__name__}.{_name}", _module)
del _name, _module

__all__ = ["solve_ivp", "OdeResult", "DenseOutput", "OdeSolution", "ConstantDenseOutput", "systems", "hill", "stability",
           "constrained", "compiled"]
__all__ += ["ensemble", "DOP853", "DOPRI5", "RK4", "RK45", "VERNER98"]
__all__ += ["Radau", "Gauss4", "Gauss6", "Stepper", "Propagator", "Propagation"]
__version__ = "0.1.0"
