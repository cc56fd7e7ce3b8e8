"""The public constructors of conmech.symbolic: a compiled system from formulas
(:func:`ode_system`), a Lagrangian (:func:`lagrangian_system`, with control inputs a
:class:`conmech.control.ControlledSystem`) or kinetic and potential energy with
constraints (:func:`constrained_system`). Each hands its derivation to the pipeline
(``pipeline.py``: cache, compile, load)."""
import sympy as sp

from .controlled import controlled_system, input_matrix
from .derive import derive_constrained, derive_lagrangian, derive_ode
from .direct import derive_direct
from .pipeline import _construct, _tup

__all__ = ["ode_system", "lagrangian_system", "constrained_system"]


def ode_system(f, y, params=None, *, flags=None, model_only=False):
    """A compiled first-order system y' = f(t, y, p) with its exact Jacobian df/dy.

    f : list of sympy expressions (one per state variable), in t, y and the parameters.
    y : list of sympy Symbols (or dynamicsymbols), the state variables.
    params : dict {Symbol or name: value}; every other free symbol is an error.
    Returns a ``conmech.compiled`` system (``model_only=True``: the :class:`CompiledModel`).
    """
    return _construct("ode", [_tup(f), _tup(y)], params, (), lambda: derive_ode(f, y, params),
                      flags, model_only)


def lagrangian_system(L, q, params=None, forces=None, *, velocities=None, simplify="auto",
                      jacobian=True, mass=None, energy=None, flags=None, model_only=False,
                      inputs=None):
    """A compiled system in generalized coordinates, M(t, q) q'' = Q(t, q, q'), derived from
    the Lagrangian L = T - U by Euler-Lagrange, with the exact Jacobian of the accelerations
    (forces_jac) and the energy (the Jacobi integral v . dL/dv - L).

    For L quadratic in the velocities, Q and its Jacobian are generated in structured form:
    the nonzero entries dM_ab/dq_k first, then Q_i as short sums over them (no expanded
    Christoffel sums), sines and cosines of sums by angle addition; for a chain of n links
    the code costs O(n^2) operations and 2n trigonometric evaluations.

    Parameters
    ----------
    L : sympy expression
        The Lagrangian T - U.
    q : list
        dynamicsymbols (functions of t), or plain Symbols with ``velocities=[...]``.
    params : dict
        {Symbol or name: value}.
    forces : list, optional
        Generalized non-conservative forces, one expression per coordinate (in t, q, q'
        and the parameters).
    simplify : True, False or "auto"
        "auto": a fast trigonometric clean-up of L first, part by part (sin^2 + cos^2 = 1,
        cos a cos b + sin a sin b = cos(a - b)).
    jacobian : bool
        Generate the exact Jacobian of the accelerations (forces_jac); False saves
        derivation and compile time for large systems that are only integrated.
    mass : square matrix, optional
        The mass matrix M(t, q) given directly (symmetric, positive definite, free of the
        velocities; ``L`` must then be None): the system is M q'' = Q with Q = ``forces``,
        the complete generalized forces (velocity terms included), with the exact
        Jacobian; ``energy`` (an expression in t, q, q') is optional.
    inputs : list, optional
        Control inputs: coordinates of q (one input each), input symbols appearing
        linearly in ``forces``, or a matrix B (ndof x m); then the result is a
        :class:`conmech.control.ControlledSystem` with M q'' = Q + B(q) u.
    """
    if inputs is not None:
        if mass is not None:
            raise ValueError("inputs= needs the Lagrangian L (not mass=)")
        bmat, forces_u0 = input_matrix(q, forces, inputs)
        plant = lagrangian_system(L, q, params, forces_u0, velocities=velocities,
                                  simplify=simplify, jacobian=jacobian, flags=flags)
        return controlled_system(plant, bmat, q, params)
    if mass is not None:
        if L is not None:
            raise ValueError("give either the Lagrangian L or mass= (then L=None)")
        return _construct("direct", [sp.Matrix(mass), _tup(forces), _tup(q),
                                     _tup(velocities), energy], params, (bool(jacobian),),
                          lambda: derive_direct(mass, forces, q, params, velocities, energy,
                                                bool(jacobian)),
                          flags, model_only)
    if energy is not None:
        raise ValueError("energy= goes with mass= (a Lagrangian defines its own energy)")
    return _construct("generalized", [L, _tup(q), _tup(forces), _tup(velocities)], params,
                      (simplify, bool(jacobian)),
                      lambda: derive_lagrangian(L, q, params, forces, velocities, simplify,
                                                bool(jacobian)),
                      flags, model_only)


def constrained_system(T, U, q, holonomic=(), nonholonomic=(), params=None, forces=None, *,
                       velocities=None, simplify="auto", mass=None, energy=None, flags=None,
                       model_only=False):
    """A compiled system in excessive coordinates for ``conmech.constrained.solve``:
    kinetic energy T, potential U, holonomic constraints phi(t, q) = 0 and non-holonomic
    constraints given as expressions linear in the velocities (A(t, q) q' + b(t, q) = 0).
    Derives M, Q, G = d phi/dq, phi_t, gamma_h, A, b, gamma_n and the energy T + U (Jacobi
    integral); rheonomic constraints (explicit t) are detected.

    ``mass=`` gives the mass matrix M(t, q) directly instead of T (``T`` must then be
    None): the forces are ``forces`` (complete, velocity terms included) minus dU/dq when
    U is given (U may be None), and the energy is ``energy`` or v^T M v / 2 + U.
    """
    if mass is not None:
        if T is not None:
            raise ValueError("give either the kinetic energy T or mass= (then T=None)")
        return _construct("direct_constrained",
                          [sp.Matrix(mass), _tup(forces), _tup(q), _tup(velocities), energy,
                           U, _tup(holonomic), _tup(nonholonomic)], params, (),
                          lambda: derive_direct(mass, forces, q, params, velocities, energy,
                                                True, list(holonomic), nonholonomic, U),
                          flags, model_only)
    if energy is not None:
        raise ValueError("energy= goes with mass= (T and U define the energy)")
    return _construct("constrained", [T, U, _tup(q), _tup(holonomic), _tup(nonholonomic),
                                      _tup(forces), _tup(velocities)], params, (simplify,),
                      lambda: derive_constrained(T, U, q, holonomic, nonholonomic, params,
                                                 forces, velocities, simplify),
                      flags, model_only)
