"""Stability of equilibria and periodic motions, for built-in systems
(:mod:`conmech.systems`, run entirely in Fortran), compiled and symbolic systems, or Python
callables ``fun(t, y)`` (finite-difference Jacobian in Fortran).

- :func:`equilibrium`: linearisation, eigenvalues (LAPACK) and classification;
  :func:`find_equilibrium`, :func:`equilibria` (from a :func:`grid` of guesses,
  deduplicated); :func:`lagrange_dirichlet`, :func:`lagrange_dirichlet_potential`
  (Hessian exact or by differences); :func:`constrained_equilibrium` on a constraint
  manifold (``equilibria.py``, ``constrained_equilibria.py``);
- :func:`stm`: state and state transition matrix (variational equations);
  :func:`monodromy`, :func:`floquet` (``variational.py``);
- :func:`periodic_orbit`, :func:`symmetric_orbit`: periodic orbits by single shooting,
  multiple shooting or orthogonal collocation (``method``), multipliers from the segments
  by the periodic QR algorithm with error estimates (``orbits.py``);
- :func:`hill_equation`: N'' + Phi(t) N = 0 with Phi a callable or periodic samples;
- :func:`continuation`: pseudo-arclength continuation of periodic orbits in a parameter
  (single shooting, multiple shooting or collocation), with folds, branch points, period
  doublings and Neimark-Sacker points located and reported honestly (:class:`Branch`,
  :class:`SpecialPoint`, :class:`SpecialKind`); :func:`switch_period_doubling`,
  :func:`switch_branch_point` (``continuation.py``, ``branch_switch.py``);
- :func:`equilibrium_continuation`: continuation of equilibria in a parameter, folds and
  Hopf points located, the first Lyapunov coefficient (:func:`first_lyapunov_coefficient`)
  at each Hopf point, and :func:`hopf_orbits`, the periodic branch born there
  (``equilibrium_continuation.py``);
- :func:`normal_modes` of an equilibrium of a conservative system and
  :func:`lyapunov_family`, the family of periodic orbits born at one of them, continued
  with its energy (``lyapunov_family.py``);
- :func:`plot_branch`, :func:`plot_multipliers`, :func:`plot_orbits`,
  :func:`stable_orbits` (``plots.py``);
- :func:`transverse`: transverse linearisation (Hill's equation of the normal deviation)
  of a periodic orbit of any planar natural (+ gyroscopic) system (``transverse.py``);
- :func:`transverse_linearisation`: the transverse linearisation of a periodic orbit of
  any system (built-in, compiled, symbolic, Python; generalized or excessive coordinates):
  the periodic A_perp(t), its monodromy (energy and constraints removed) and the check
  against the full monodromy (``transverse_linearisation.py``).
"""
from .equilibria import (EQUILIBRIUM_RTOL, Equilibrium, RelativeEquilibrium, equilibria,
                         equilibrium, find_equilibrium, grid, lagrange_dirichlet,
                         lagrange_dirichlet_potential, potential_hessian)
from .variational import floquet, monodromy, stm
from .orbits import ORBIT_RESIDUAL_TOL, PeriodicOrbit, periodic_orbit, symmetric_orbit
from .hill_equation import HillEquationResult, hill_equation
from .continuation import (Branch, SpecialKind, SpecialPoint, continuation,
                           switch_period_doubling)
from .branch_switch import switch_branch_point
from .constrained_equilibria import (ConstrainedEquilibrium, constrained_equilibria,
                                     constrained_equilibrium)
from .transverse import transverse
from .equilibrium_continuation import (EquilibriumBranch, EquilibriumSpecialPoint,
                                       HopfNormalForm, equilibrium_continuation,
                                       first_lyapunov_coefficient, hopf_orbits)
from .equilibrium_branch_points import equilibrium_branch_points, switch_equilibrium_branch
from .lyapunov_family import LyapunovFamily, NormalModes, lyapunov_family, normal_modes
from .transverse_linearisation import (TransverseLinearisation, nontrivial_multipliers,
                                       transverse_linearisation)
from .plots import plot_branch, plot_multipliers, plot_orbits, stable_orbits
from .constrained_orbits import (ConstrainedBranch, ConstrainedOrbit, ManifoldChart,
                                 constrained_continuation, constrained_periodic_orbit,
                                 constrained_symmetric_orbit)
# validators used by sibling modules (hill_families)
from .._core.validate import _real, _state  # noqa: F401

__all__ = ["Equilibrium", "RelativeEquilibrium", "PeriodicOrbit", "Branch", "SpecialPoint",
           "SpecialKind", "continuation", "transverse", "transverse_linearisation",
           "TransverseLinearisation", "nontrivial_multipliers", "find_equilibrium",
           "equilibria", "grid", "potential_hessian",
           "lagrange_dirichlet_potential", "plot_branch", "plot_multipliers",
           "switch_period_doubling", "switch_branch_point", "constrained_equilibrium",
           "constrained_equilibria", "ConstrainedEquilibrium",
           "equilibrium", "lagrange_dirichlet", "stm",
           "monodromy", "periodic_orbit", "symmetric_orbit", "floquet", "hill_equation",
           "EquilibriumBranch", "EquilibriumSpecialPoint", "HopfNormalForm",
           "equilibrium_continuation", "first_lyapunov_coefficient", "hopf_orbits",
           "LyapunovFamily", "NormalModes", "lyapunov_family", "normal_modes",
           "plot_orbits", "stable_orbits", "ManifoldChart", "ConstrainedOrbit",
           "ConstrainedBranch", "constrained_periodic_orbit", "constrained_symmetric_orbit",
           "constrained_continuation", "equilibrium_branch_points",
           "switch_equilibrium_branch"]
