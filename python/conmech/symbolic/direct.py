"""Systems given by their mass matrix and generalized forces directly (no kinetic
energy): M(t, q) q'' = Q(t, q, q') [+ C^T lambda with constraints].

:func:`derive_direct` builds the :class:`~conmech.symbolic.derive.Derived` record that
:func:`conmech.symbolic.lagrangian_system` (``mass=``) and
:func:`conmech.symbolic.constrained_system` (``mass=``) compile: M is checked (square,
symmetric, free of the velocities, not singular everywhere), the exact Jacobian R =
[dQ/dq - d(M a)/dq, dQ/dv] is derived for generalized coordinates, the constraints as in
:func:`conmech.symbolic.derive.derive_constrained` (phi, G, phi_t, gamma_h, A, b,
gamma_n), and the energy is the one given (or, with a potential U in excessive
coordinates, v^T M v / 2 + U).
"""
import sympy as sp

from .inputs import _ae, _check_mass, _Coords, _mechanical_inputs, _sympify_list, _unify_time
from .record import Derived

__all__ = ["derive_direct"]


def _matrix(M, n):
    try:
        M = sp.Matrix(M)
    except (TypeError, ValueError, sp.SympifyError):
        raise TypeError("mass must be a square matrix of expressions") from None
    if M.shape != (n, n):
        raise ValueError(f"mass must be {n} x {n} for {n} coordinates, got the shape "
                         f"{M.shape}")
    return M


def derive_direct(M, Q, q, params=None, velocities=None, energy=None, jacobian=True,
                  holonomic=None, nonholonomic=(), U=None):
    """The Derived record of M(t, q) q'' = Q(t, q, q') (``holonomic=None``: generalized
    coordinates, with the exact Jacobian when ``jacobian``) or of the constrained system
    in excessive coordinates (``holonomic`` a list, possibly empty, ``nonholonomic``
    Pfaffian constraints, ``U`` an optional potential whose -dU/dq joins Q)."""
    constrained = holonomic is not None
    t = sp.Symbol("t")
    c = _Coords(q, velocities, t, need_speeds=True)
    n = len(c.plain)
    M = _matrix(M, n)
    Ql = _sympify_list(Q if Q is not None else [0]*n, "forces")
    if len(Ql) != n:
        raise ValueError(f"forces has {len(Ql)} components for {n} coordinates")
    hol = _sympify_list(list(holonomic or ()), "holonomic") if constrained else []
    nh = _sympify_list(list(nonholonomic or ()), "nonholonomic") if constrained else []
    extra = [sp.sympify(energy)] if energy is not None else []
    Ul = [sp.sympify(U)] if U is not None else []
    exprs = _unify_time(list(M) + Ql + hol + nh + extra + Ul, t)
    exprs, t, psyms, names, values = _mechanical_inputs(exprs, c, params, t, "the expressions")
    k = 0
    M = sp.Matrix(n, n, exprs[:n*n])
    k = n*n
    Qv = sp.Matrix(exprs[k:k + n])
    k += n
    hol = exprs[k:k + len(hol)]
    k += len(hol)
    nh = exprs[k:k + len(nh)]
    k += len(nh)
    E = exprs[k] if extra else None
    k += len(extra)
    Up = exprs[k] if Ul else None
    vset = set(c.speeds)
    for i in range(n):
        for j in range(i + 1, n):
            if sp.expand(M[i, j] - M[j, i]) != 0:
                raise ValueError(f"the mass matrix is not symmetric (entries ({i}, {j}) and "
                                 f"({j}, {i}) differ)")
    _check_mass(M, c.plain, c.speeds, psyms, values, t)
    if Up is not None:
        if Up.free_symbols & vset:
            raise ValueError("U must not depend on the velocities")
        Qv = Qv - sp.Matrix([sp.diff(Up, x) for x in c.plain])
        if E is None:
            vv = sp.Matrix(c.speeds)
            E = (vv.T*M*vv)[0, 0]/2 + Up
    common = dict(t=t, coords=c.plain, coord_names=c.names, speeds=c.speeds,
                  accels=c.accels, params=psyms, param_names=names, param_values=values,
                  M=M, Q=Qv, energy=E)
    if not constrained:
        d = Derived("generalized", with_jacobian=bool(jacobian), **common)
        if jacobian:
            Ma = M*sp.Matrix(c.accels)
            d.R = _ae((Qv - Ma).jacobian(c.plain).row_join(Qv.jacobian(c.speeds)))
        return d
    d = Derived("constrained", n_hol=len(hol), n_nh=len(nh), **common)
    q_, v_ = c.plain, c.speeds
    vv = sp.Matrix(v_)
    if hol:
        for i, h in enumerate(hol):
            if h.free_symbols & vset:
                raise ValueError(f"holonomic constraint {i} depends on the velocities "
                                 "(give it as nonholonomic)")
        phi = sp.Matrix(hol)
        G = phi.jacobian(q_)
        phi_t = sp.diff(phi, t)
        w = G*vv + phi_t
        d.phi, d.G, d.phi_t = phi, G, phi_t
        d.gamma_h = -(w.jacobian(q_)*vv + sp.diff(w, t))
        d.rheonomic = any(e != 0 for e in phi_t)
    if nh:
        A = sp.Matrix(nh).jacobian(v_)
        if A.free_symbols & vset:
            raise ValueError("a non-holonomic constraint is not linear in the velocities "
                             "(Pfaffian form A(t, q) q' + b(t, q) = 0 required)")
        b = sp.Matrix(nh).xreplace({vi: 0 for vi in v_})
        w = A*vv + b
        d.A, d.b = A, b
        d.gamma_n = -(w.jacobian(q_)*vv + sp.diff(w, t))
    return d
