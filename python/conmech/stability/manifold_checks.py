"""A constrained system as the stability analyses on its constraint manifold use it:
holonomic and scleronomic only (the equilibria and the periodic orbits of a manifold that
moves or of non-holonomic constraints are other problems); for a Python-callable one
(conmech.constrained.ConstrainedSystem) every callable's value checked and the constraint
Jacobian G = dphi/dq from the user's ``jac`` or by central differences."""
import numpy as np

from ..mechanics.compiled import CompiledConstrained
from ..mechanics.constrained import NativeConstrained

__all__ = ["checked_values", "holonomic_sizes", "constraint_jacobian"]

_RHEONOMIC_BUILTINS = ("pendulum_moving_xy", "yoyo")

_H = np.finfo(float).eps**(1/3)       # central differences: error O(h^2) ~ eps^(2/3)


def holonomic_sizes(system, what):
    """(n, m): coordinates and holonomic constraints of a built-in, compiled or Python
    constrained system that has no non-holonomic and no time-dependent constraints; `what`
    (the analysis) in the refusals."""
    if isinstance(system, NativeConstrained):
        label = f"system '{system.name}'"
        rheonomic = system.name in _RHEONOMIC_BUILTINS or (
            isinstance(system, CompiledConstrained) and int(system.spec[4]) != 0)
    else:                  # spec[4] above: a compiled system's rheonomic flag (_make_spec)
        label, rheonomic = "system", system.rheonomic
    if system.n_nh > 0:
        raise ValueError(f"{label}: non-holonomic constraints; {what} on a constraint "
                         "manifold need holonomic ones")
    if rheonomic:
        raise ValueError(f"{label}: time-dependent (rheonomic) constraints: its manifold "
                         "moves, use the generalized coordinates")
    return system.n, system.n_hol


def checked_values(x, shape, what):
    """x as a float array of `shape`: ValueError naming the callable `what` when its size
    is off or a value is not finite."""
    a = np.asarray(x, dtype=float)
    if a.size != int(np.prod(shape)) or not np.all(np.isfinite(a)):
        raise ValueError(f"{what} must return {shape} finite values, got {a.shape}")
    return a.reshape(shape)


def constraint_jacobian(system, t, q, m, n):
    """G (m, n) at (t, q): the system's ``jac`` or central differences of ``phi``."""
    if system.jac is not None:
        return checked_values(system.jac(t, q), (m, n), "jac(t, q)")
    g = np.empty((m, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = _H*max(1.0, abs(q[j]))
        g[:, j] = (checked_values(system.phi(t, q + e), (m,), "phi(t, q)")
                   - checked_values(system.phi(t, q - e), (m,), "phi(t, q)"))/(2*e[j])
    return g
