"""Derivation of the equations of motion with sympy (pure sympy, no code generation).

Three entry points build a :class:`Derived` object, a plain record of sympy expressions in
*plain symbols* (no functions of t), ready for a code generator:

- :func:`derive_ode`: y' = f(t, y, p) and its Jacobian df/dy;
- :func:`derive_lagrangian`: generalized coordinates, L = T - U, optional generalized forces:
  M(t, q), Q(t, q, v), R = [dQ/dq - d(M a)/dq |a fixed, dQ/dv], the energy (Jacobi integral
  h = v . dL/dv - L, i.e. T + U for a natural scleronomic system);
- :func:`derive_constrained`: excessive coordinates, T and U, holonomic phi(t, q) = 0 and
  Pfaffian A(t, q) v + b(t, q) = 0 constraints: M, Q, energy, phi, G, phi_t, gamma_h, A, b,
  gamma_n (conventions of src/mechanics/conmech_constrained_system.f90:
  gamma_h = -d/dt[G v + phi_t], gamma_n = -d/dt[A v + b], v held fixed).

Coordinates are either sympy ``dynamicsymbols`` (functions of t; their first derivatives are
the velocities, second derivatives the accelerations) or plain Symbols, then with
``velocities=[...]`` plain Symbols standing for their time derivatives. Time is the symbol
``t`` (``dynamicsymbols._t``; any free symbol named "t").

``params`` maps sympy Symbols, or their names as strings, to float values. Every free symbol
of the expressions that is not t, a coordinate or a velocity must be a parameter (else
ValueError naming it); a parameter without a value is a ValueError naming it. Parameters are
identified by name (Symbol("m", positive=True) and Symbol("m") are the same parameter).

All symbols of a :class:`Derived` record (t, coordinates, velocities, accelerations,
parameters) are real-valued sympy Dummies carrying the user's names (``coord_names``,
``param_names``); code generators map them to array elements by position.

The :class:`Derived` record (attributes; absent items are None):

=============  ==============================================================================
kind           "ode", "generalized" or "constrained"
t              the time Symbol
coords         list of Symbols: y (ode) or q (generalized, constrained); coord_names
lagrangian     the (cleaned-up) Lagrangian used (generalized, constrained)
speeds         list of Symbols v (velocities; [] for ode)
accels         list of Symbols a (accelerations, used in R; [] for ode)
params         list of parameter Symbols, in the order of the run-time array p
param_names    list of their names; ``param_values``: list of floats
f, jac         ode: Matrix n x 1, Matrix n x n (df/dy)
M, Q           mass matrix (nd x nd, depends on t, q, p), forces (nd x 1, t, q, v, p)
R              generalized only: nd x 2nd, [dQ/dq - d(M a)/dq, dQ/dv] (t, q, v, a, p)
energy         scalar expression (t, q, v, p) or None
phi, G, phi_t  constrained: n_hol x 1, n_hol x n, n_hol x 1
gamma_h        n_hol x 1 (t, q, v, p)
A, b, gamma_n  n_nh x n, n_nh x 1, n_nh x 1
n_hol, n_nh    numbers of constraints; ``rheonomic``: phi depends explicitly on t
=============  ==============================================================================

``Derived.values(**kw)`` returns the parameter vector with some values replaced by name.

The pieces live by concept: the record in ``record.py``, the checking of the user's input
(coordinates, time, parameters, the mass matrix) in ``inputs.py``, the Euler-Lagrange equations
in ``euler_lagrange.py``, the clean-up of L in ``simplify.py``, :func:`derive_lagrangian` in
``lagrangian.py``; this module holds the ODE and constrained derivations and names them all.
"""
import sympy as sp

from .euler_lagrange import _energy, _euler_lagrange
from .inputs import (_ae, _as_value, _check_entry, _check_mass, _check_no_accel,  # noqa: F401
                     _Coords, _mechanical_inputs, _realify, _resolve_params, _subs_all,
                     _sympify_list, _unify_time, singular_everywhere)
from .lagrangian import _forces_list, derive_lagrangian
from .record import Derived
from .simplify import _maybe_simplify, _quadratic_parts  # noqa: F401

__all__ = ["Derived", "derive_ode", "derive_lagrangian", "derive_constrained"]


# ------------------------------------------------------------------------------ ode

def derive_ode(f, y, params=None):
    """y' = f(t, y, p): f (list of expressions), y (Symbols or dynamicsymbols)."""
    t = sp.Symbol("t")
    f = _unify_time(_sympify_list(f, "f"), t)
    c = _Coords(y, None, t, need_speeds=False)
    if len(f) != len(c.plain):
        raise ValueError(f"f has {len(f)} components for {len(c.plain)} state variables")
    # for dynamicsymbols: y_i(t) -> plain; derivatives of y in f are an error
    f = c.convert(f, "f")
    psyms, names, values, sub = _resolve_params(params, f, c.plain, t)
    f = _subs_all(f, sub)
    f, t, psyms = _realify(f, t, c, psyms)
    F = sp.Matrix(f)
    J = _ae(F.jacobian(c.plain))
    return Derived("ode", t=t, coords=c.plain, coord_names=c.names, params=psyms,
                   param_names=names, param_values=values, f=F, jac=J)


# ------------------------------------------------------------------------------ constrained

def derive_constrained(T, U, q, holonomic=(), nonholonomic=(), params=None, forces=None,
                       velocities=None, simplify="auto"):
    """Excessive coordinates q with L = T - U, holonomic phi(t, q) = 0 and Pfaffian
    constraints given as expressions linear in the velocities (A q' + b = 0)."""
    t = sp.Symbol("t")
    c = _Coords(q, velocities, t, need_speeds=True)
    n = len(c.plain)
    hol = _sympify_list(list(holonomic) if not isinstance(holonomic, sp.Basic)
                        else [holonomic], "holonomic")
    nh = _sympify_list(list(nonholonomic) if not isinstance(nonholonomic, sp.Basic)
                       else [nonholonomic], "nonholonomic")
    base = _sympify_list(T, "T") + _sympify_list(U, "U") + _forces_list(forces, n)
    if len(base) != n + 2:
        raise ValueError("T and U must be single expressions")
    exprs = _unify_time(base + hol + nh, t)
    exprs, t, psyms, names, values = _mechanical_inputs(exprs, c, params, t, "the expressions")
    Tp, Up, fq = exprs[0], exprs[1], exprs[2:2 + n]
    hol = exprs[2 + n:2 + n + len(hol)]
    nh = exprs[2 + n + len(hol):]
    if Up.free_symbols & set(c.speeds):
        raise ValueError("U must not depend on the velocities")
    L = _maybe_simplify(Tp - Up, simplify, c.speeds)
    M, Q = _euler_lagrange(L, c.plain, c.speeds, t)
    _check_mass(M, c.plain, c.speeds, psyms, values, t)
    Q = Q + sp.Matrix(fq)
    energy = _energy(L, M, c.speeds)
    q_, v_ = c.plain, c.speeds
    vv = sp.Matrix(v_)
    d = Derived("constrained", t=t, coords=q_, coord_names=c.names, speeds=v_,
                accels=c.accels, params=psyms, param_names=names, param_values=values,
                M=M, Q=Q, energy=energy, lagrangian=L, n_hol=len(hol), n_nh=len(nh))
    if hol:
        for i, h in enumerate(hol):
            if h.free_symbols & set(v_):
                raise ValueError(f"holonomic constraint {i} depends on the velocities "
                                 "(give it as nonholonomic)")
        phi = sp.Matrix(hol)
        G = phi.jacobian(q_)
        phi_t = sp.diff(phi, t)
        w = G * vv + phi_t                       # d phi/dt
        gamma_h = -(w.jacobian(q_) * vv + sp.diff(w, t))
        d.phi, d.G, d.phi_t, d.gamma_h = phi, G, phi_t, gamma_h
        d.rheonomic = any(sp.simplify(e) != 0 for e in phi_t) if len(hol) < 8 \
            else any(e != 0 for e in phi_t)
    if nh:
        E = sp.Matrix(nh)
        A = E.jacobian(v_)
        if A.free_symbols & set(v_):
            raise ValueError("a non-holonomic constraint is not linear in the velocities "
                             "(Pfaffian form A(t, q) q' + b(t, q) = 0 required)")
        b = E.xreplace({vi: 0 for vi in v_})
        w = A * vv + b
        gamma_n = -(w.jacobian(q_) * vv + sp.diff(w, t))
        d.A, d.b, d.gamma_n = A, b, gamma_n
    return d
