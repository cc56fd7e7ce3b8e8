"""Control of mechanical systems with inputs, and orbital stabilisation of periodic motions
of underactuated systems (the Fortran work in src/control).

- :class:`ControlledSystem`: M(q) q'' = Q(q, q') + B(q) u for built-in, compiled and
  symbolic systems in generalized coordinates (``actuated=[...]``, a constant ``B`` or a
  compiled B(q)); ``symbolic.lagrangian_system(L, q, inputs=[...])`` builds one;
- feedback laws: :class:`PythonLaw`, :class:`CompiledLaw`, :class:`ZeroLaw`, the
  virtual-constraint feedback and the transverse LQR; :func:`simulate` integrates the
  closed loop in Fortran (events, dense output, t_eval) (``plant.py``);
- :class:`VirtualConstraint`: q = Phi(theta) (sympy expressions, polynomials, Chebyshev or
  trigonometric coefficients), the reduced dynamics alpha theta'' + beta theta'^2 + gamma
  = 0 (:class:`ReducedDynamics`: its integral, equilibria, periodic orbits with the period
  by quadrature and by integration, the phase portrait) and the feedback that keeps the
  constraint (``vhc.py``);
- :func:`periodic_riccati`: the stabilising periodic solution of a periodic Riccati
  equation (``riccati.py``);
- :func:`orbital_stabilisation`: the transverse LQR of a periodic orbit
  (:class:`TransverseLQR`: A_perp, B_perp, P, K, the closed-loop multipliers, the phase and
  orbital distance of any state) (``stabilisation.py``);
- :mod:`conmech.control.examples`: the cart pendulum, the Pendubot and a double pendulum on
  a cart, with virtual constraints for oscillations about the upright;
  :mod:`conmech.control.plots`: the pictures of the guide.
"""
from .plant import (CompiledLaw, ControlledSystem, FeedbackLaw, PythonLaw, ZeroLaw,
                    evaluate_law, simulate)
from .vhc import ReducedDynamics, ReducedOrbit, VHCFeedback, VirtualConstraint
from .riccati import PeriodicRiccati, periodic_riccati
from .stabilisation import TransverseLQR, orbital_stabilisation

__all__ = ["ControlledSystem", "FeedbackLaw", "PythonLaw", "CompiledLaw", "ZeroLaw",
           "evaluate_law", "simulate", "VirtualConstraint", "ReducedDynamics",
           "ReducedOrbit", "VHCFeedback", "PeriodicRiccati", "periodic_riccati",
           "TransverseLQR", "orbital_stabilisation"]
