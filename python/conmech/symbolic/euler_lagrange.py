"""The Euler-Lagrange equations of a Lagrangian L(t, q, v): the mass matrix M (the
Hessian of L in v), the forces Q without the accelerations, and the energy (the Jacobi
integral h = v . dL/dv - L)."""
import sympy as sp


def _euler_lagrange(L, q, v, t):
    """M (Hessian of L in v) and the velocity/potential part of Q (without q'')."""
    p = [sp.diff(L, vi) for vi in v]
    n = len(q)
    M = sp.Matrix(n, n, lambda i, j: sp.diff(p[i], v[j]))
    Q = []
    for i in range(n):
        dpdt = sum((sp.diff(p[i], q[j]) * v[j] for j in range(n)), sp.Integer(0)) \
            + sp.diff(p[i], t)
        Q.append(sp.diff(L, q[i]) - dpdt)
    return M, sp.Matrix(Q)


def _d(e, x):
    """de/dx, skipping expressions free of x."""
    return sp.diff(e, x) if x in e.free_symbols else sp.Integer(0)


def _energy(L, M, v):
    """Jacobi integral h = v . dL/dv - L = v^T M v / 2 - L(v = 0) for L quadratic in v
    (T + U for a natural scleronomic system)."""
    vv = sp.Matrix(v)
    return sp.expand((vv.T * M * vv)[0, 0] / 2) - L.xreplace({vi: 0 for vi in v})


def _mass(L, v):
    """The Hessian of L in v (as _euler_lagrange computes it), symmetric by construction."""
    n = len(v)
    p = [sp.diff(L, vi) for vi in v]
    M = sp.zeros(n, n)
    for i in range(n):
        for j in range(n):
            M[i, j] = sp.diff(p[i], v[j])
    return M
