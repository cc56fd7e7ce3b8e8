"""The derivatives of a constrained system behind the exact Jacobian of Radau IIA on its
equations of motion (conmech_constrained_dae, conmech_constrained_index3):

- ``R = [dQ/dq - d(M a)/dq, dQ/dv]`` (n x 2n), the Jacobian of the force balance
  M(t, q) a - Q(t, q, v) at a fixed acceleration a (the symbols ``d.accels``);
- ``HL = d(C^T lam)/dq`` (n x n) and ``HV = d(C v + c0)/dq`` (m x n), the second
  derivatives of the constraints contracted with the multipliers and the velocities,
  C = [G; A], c0 = [phi_t; b], m = n_hol + n_nh.

:func:`constrained_derivatives` derives them from a constrained
:class:`~conmech.symbolic.derive.Derived` record (whatever route made it: T and U, or M and
Q given directly); :mod:`conmech.symbolic.codegen` emits them as ``conmech_forces_jac`` and
``conmech_constraint_hessian``.
"""
import sympy as sp

__all__ = ["constrained_derivatives", "multiplier_symbols"]


def multiplier_symbols(m):
    """The m multiplier symbols lam_1..lam_m of the generated constraint_hessian."""
    return [sp.Dummy(f"lam{i + 1}", real=True) for i in range(m)]


def constrained_derivatives(d):
    """(R, HL, HV, lam) for the constrained record `d` (HL, HV None without constraints;
    lam the multiplier symbols HL is linear in)."""
    q, v, a = list(d.coords), list(d.speeds), list(d.accels)
    M = sp.Matrix(d.M)
    Q = sp.Matrix(d.Q)
    Ma = M*sp.Matrix(a)
    R = (Q - Ma).jacobian(q).row_join(Q.jacobian(v))
    mh = int(getattr(d, "n_hol", 0) or 0)
    mn = int(getattr(d, "n_nh", 0) or 0)
    m = mh + mn
    if m == 0:
        return R, None, None, []
    rows, offs = [], []
    if mh:
        rows.append(sp.Matrix(d.G))
        offs.append(sp.Matrix(d.phi_t))
    if mn:
        rows.append(sp.Matrix(d.A))
        offs.append(sp.Matrix(d.b))
    C = sp.Matrix.vstack(*rows)
    c0 = sp.Matrix.vstack(*offs)
    lam = multiplier_symbols(m)
    HL = (C.T*sp.Matrix(lam)).jacobian(q)
    HV = (C*sp.Matrix(v) + c0).jacobian(q)
    return R, HL, HV, lam
