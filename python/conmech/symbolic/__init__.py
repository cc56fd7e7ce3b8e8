"""conmech.symbolic: your own system from formulas, a Lagrangian or constraints, compiled.

Three constructors derive the equations with sympy (exact Jacobians, common-subexpression
elimination), emit Fortran with the C ABI of conmech's compiled systems, compile it with
gfortran into an on-disk cache (``$CONMECH_CACHE``, default ``~/.cache/conmech``) and load
it; the result runs in :func:`conmech.solve_ivp`, ``conmech.stability.*`` and (constrained)
``conmech.constrained.solve`` with no Python in the loop:

- :func:`ode_system` (y' = f(t, y, p), exact df/dy),
- :func:`lagrangian_system` (generalized coordinates, L = T - U, optional forces),
- :func:`constrained_system` (excessive coordinates, T, U, holonomic and Pfaffian
  constraints, rheonomic detected),
- :func:`planar_tree` (a planar multibody tree of :class:`Body` records: revolute and
  prismatic joints, relative or absolute angles; its right-hand side is the O(n)
  articulated-body algorithm),
- :func:`spatial_tree` (the same in 3-D with :class:`SpatialBody` records: revolute and
  prismatic joints about unit axes, inertia tensors, relative coordinates; the spatial
  articulated-body algorithm).

Parameters are run-time values: ``system.with_params(m=2.0)`` gives a copy without
recompiling. Example (a cart carrying a pendulum)::

    import sympy as sp
    from sympy.physics.mechanics import dynamicsymbols
    from conmech import symbolic
    t = dynamicsymbols._t
    x, th = dynamicsymbols("x theta")
    M, m, l, g = sp.symbols("M m l g")
    T = (M + m)*x.diff(t)**2/2 + m*l*sp.cos(th)*x.diff(t)*th.diff(t) + m*l**2*th.diff(t)**2/2
    U = m*g*l*sp.cos(th)
    cart = symbolic.lagrangian_system(T - U, [x, th], params={M: 1, m: 1, l: 1, g: 9.81})

Layout: ``constructors.py`` (the public constructors), ``pipeline.py`` (derive, compile,
cache, load: :class:`CompiledModel`), ``derive.py`` (pure sympy, the
:class:`~conmech.symbolic.derive.Derived` record), ``codegen.py`` (bind(C) Fortran),
``build.py`` (compile, cache, load a library), ``controlled.py`` (control inputs B u),
``tree.py`` (planar multibody trees: T and U from the bodies, the articulated-body
accelerations), ``spatial.py`` (the same for spatial trees); this file only hands the
public names on.
"""
from .build import CacheError, CacheWarning, CompileError, cache_dir
from .constructors import constrained_system, lagrangian_system, ode_system
from .derive import Derived
from .momenta import FirstIntegrals, LagrangianSystem, Momenta, first_integrals, momenta
from .pipeline import CompiledModel, compile_model, model_of, save_model
# exactness of Pfaffian constraints: holonomic or not, integrating factor, integral
from .pfaffian import (PfaffianResult, PfaffianSystemResult, pfaffian,
                       pfaffian_from_velocities, pfaffian_of, pfaffian_system)
# planar multibody trees (articulated-body algorithm)
from .tree import Body
from .trees import planar_tree, spatial_tree
# spatial (3-D) multibody trees (spatial articulated-body algorithm)
from .spatial import SpatialBody
# closed loops on trees, forces at points of bodies, consistent initial states
from .loops import Loop, PointForce, consistent_state
# the loop joints' reactions, per joint, in the joint's frame
from .reactions import JointReaction, joint_reactions
# robots from URDF files
from .urdf import Robot, from_urdf, read_urdf
# compiled events (Taylor series of g along each step, roots isolated: conmech_taylor_events)
from .taylor_events import Event, event
# Routh reduction (cyclic coordinates eliminated for given momenta)
from .reduction import Reduction, ReducedSystem, reduce
# D'Alembert's route (positions, applied forces, generalized forces)
from .dalembert import DAlembertSystem, dalembert_system
# Hamilton's principle along computed motions
from .action import Variation, action, check_stationary, first_variation, second_variation

__all__ = ["ode_system", "lagrangian_system", "constrained_system", "CompiledModel",
           "CompileError", "CacheError", "CacheWarning", "cache_dir", "Derived",
           "compile_model", "model_of", "save_model", "momenta", "first_integrals", "Momenta",
           "FirstIntegrals", "LagrangianSystem", "Body", "planar_tree", "SpatialBody",
           "spatial_tree", "Loop", "PointForce", "consistent_state", "JointReaction",
           "joint_reactions", "Robot", "from_urdf",
           "read_urdf", "Event", "event", "pfaffian", "pfaffian_system",
           "pfaffian_from_velocities", "pfaffian_of", "PfaffianResult", "PfaffianSystemResult",
           "reduce", "Reduction", "ReducedSystem", "dalembert_system", "DAlembertSystem",
           "action", "first_variation", "second_variation", "check_stationary", "Variation"]
