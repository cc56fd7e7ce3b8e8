""":func:`derive_lagrangian`: M q'' = Q from a Lagrangian in generalized
coordinates, with Q and its Jacobian R in the structured form that the compiled code uses
(nothing expanded; see :func:`_structure`)."""
import sympy as sp

from .euler_lagrange import _d, _energy, _euler_lagrange, _mass
from .inputs import _ae, _check_mass, _Coords, _mechanical_inputs, _sympify_list, _unify_time
from .record import Derived
from .simplify import _collect_params, _maybe_simplify


def _structure(L, M, q, v, a, t, fq, jacobian, l1L0=None):
    """The forces and their Jacobian of a Lagrangian quadratic in the velocities,
    L = v^T M v / 2 + l1 . v + L0, in structured form (nothing expanded):

        Q_i = QL_i + sum_k dM_k . (quadratic monomials of v),
        QL_i = fq_i + dL0/dq_i + (dl1/dq_i) . v - (dl1_i/dq) . v - dl1_i/dt - (dM_i./dt) . v,
        dM_k = dM_ab/dq_k over the nonzero entries only (a <= b),

    (Euler-Lagrange: Q_i = 1/2 v^T (dM/dq_i) v - sum_jk dM_ij/dq_k v_j v_k + ...), with the
    coefficients of each dM entry in each Q_i collected exactly (so that for a chain, where
    M_ij depends on q_i and q_j only, Q costs O(n^2) operations, not O(n^3)).
    Returns a dict: ``defs_Q`` [(Symbol, expr)], ``Q`` (list, in the def symbols and v),
    and with ``jacobian`` ``defs_R``, ``R`` (n x 2n Matrix in the def symbols, v and a):
    R = [dQ/dq - d(M a)/dq, dQ/dv] from the second derivatives of M (also sparse).
    None if M depends on the velocities."""
    n = len(q)
    vs = set(v)
    if any(M[i, j].free_symbols & vs for i in range(n) for j in range(n)):
        return None
    zero = {vi: 0 for vi in v}
    if l1L0 is not None:
        l1, L0 = l1L0
    else:
        grad = [sp.diff(L, vi) for vi in v]
        l1 = [g.xreplace(zero) for g in grad]      # exact: grad = M v + l1
        L0 = L.xreplace(zero)
    qidx = {qi: k for k, qi in enumerate(q)}
    dM, dsym = {}, {}                   # (a, b, k) -> expr, Symbol
    for i in range(n):
        for j in range(i, n):
            for k in sorted(qidx[s] for s in M[i, j].free_symbols if s in qidx):
                e = sp.diff(M[i, j], q[k])
                if e != 0:
                    dM[i, j, k] = e
                    dsym[i, j, k] = sp.Dummy(f"dm{i + 1}_{j + 1}_{k + 1}", real=True)
    # coefficients of each dM entry in each Q_i: {i: {key: {(x, y): c}}}
    coef = [dict() for _ in range(n)]

    def add(i, key, x, y, c):
        mono = coef[i].setdefault(key, {})
        xy = (min(x, y), max(x, y))
        mono[xy] = mono.get(xy, 0) + c
    for (i, j, k) in dM:
        if i < j:
            add(k, (i, j, k), i, j, sp.Integer(1))
            add(i, (i, j, k), j, k, sp.Integer(-1))
            add(j, (i, j, k), i, k, sp.Integer(-1))
        else:
            add(k, (i, j, k), i, i, sp.Rational(1, 2))
            add(i, (i, j, k), i, k, sp.Integer(-1))
    quad = []
    for i in range(n):
        terms = []
        for key, mono in coef[i].items():
            poly = sum((c*v[x]*v[y] for (x, y), c in mono.items() if c != 0), sp.Integer(0))
            if poly != 0:
                terms.append((key, poly, mono))
        quad.append(terms)
    QL = []
    for i in range(n):
        e = fq[i] + _d(L0, q[i]) - _d(l1[i], t) \
            - sum((_d(M[i, j], t)*v[j] for j in range(n)), sp.Integer(0))
        e += sum((_d(l1[j], q[i])*v[j] for j in range(n)), sp.Integer(0))
        e -= sum((_d(l1[i], q[k])*v[k] for k in range(n)), sp.Integer(0))
        QL.append(_collect_params(sp.expand(e), set().union(
            *(x.free_symbols for x in [L] + list(fq))) - set(q) - set(v) - {t}))
    qlsym = [sp.Dummy(f"ql{i + 1}", real=True) if QL[i] != 0 else sp.Integer(0)
             for i in range(n)]
    defs_Q = [(dsym[k], e) for k, e in dM.items()] \
        + [(s_, e) for s_, e in zip(qlsym, QL) if e != 0]
    Qs = [qlsym[i] + sum((dsym[key]*poly for key, poly, _ in quad[i]), sp.Integer(0))
          for i in range(n)]
    out = {"defs_Q": defs_Q, "Q": Qs, "dM": dM, "quad": quad, "QL": QL}
    if not jacobian:
        return out
    # R: the second derivatives of M (nonzero ones), the derivatives of QL
    defs_R = [(dsym[k], e) for k, e in dM.items()]
    ddsym = {}
    for key, e in dM.items():
        for m in sorted(qidx[s] for s in e.free_symbols if s in qidx):
            de = _ae(sp.Matrix([sp.diff(e, q[m])]))[0]
            if de != 0:
                ddsym[key, m] = sp.Dummy(f"ddm{key[0] + 1}_{key[1] + 1}_{key[2] + 1}_{m + 1}",
                                         real=True)
                defs_R.append((ddsym[key, m], de))
    R = sp.zeros(n, 2*n)
    for i in range(n):
        for m, x in enumerate(list(q) + list(v)):
            if x not in QL[i].free_symbols:
                continue
            de = _ae(sp.Matrix([sp.diff(QL[i], x)]))[0]
            if de != 0:
                s_ = sp.Dummy(f"dql{i + 1}_{m + 1}", real=True)
                defs_R.append((s_, de))
                R[i, m] = s_
    for i in range(n):
        for key, poly, mono in quad[i]:
            dp = [sp.Integer(0)]*n             # d poly / dv_m from its monomials
            for (x, y), c in mono.items():
                dp[x] += c*v[y]
                dp[y] += c*v[x]
            for m in range(n):
                if (key, m) in ddsym:
                    R[i, m] += ddsym[key, m]*poly
                if dp[m] != 0:
                    R[i, n + m] += dsym[key]*dp[m]
        for m in range(n):
            for j in range(n):
                key = (min(i, j), max(i, j), m)
                if key in dsym:
                    R[i, m] -= dsym[key]*a[j]
    out.update(defs_R=defs_R, R=R)
    return out


def _forces_list(forces, n, what="forces"):
    if forces is None:
        return [sp.Integer(0)] * n
    fl = _sympify_list(forces, what)
    if len(fl) != n:
        raise ValueError(f"{what} has {len(fl)} components for {n} coordinates")
    return fl


def derive_lagrangian(L, q, params=None, forces=None, velocities=None, simplify="auto",
                      jacobian=True, structured=True):
    """M q'' = Q from the Lagrangian L(t, q, q'); optional generalized forces.
    ``simplify`` (True, False, "auto") cleans L up first (sin^2 + cos^2 = 1, products of
    sines and cosines into cosines of differences) so that M and Q come out compact.
    ``jacobian=False`` skips R (the integrators then difference the accelerations).
    ``structured`` (default): Q and R are derived in the structured form of
    :func:`_structure` (``Derived.struct``, used by the compiled code; the expanded ``Q`` and
    ``R`` are then computed only when read); False: expanded Q and R (the form
    ``python -m conmech.symbolic emit`` writes)."""
    t = sp.Symbol("t")
    c = _Coords(q, velocities, t, need_speeds=True)
    n = len(c.plain)
    exprs = _unify_time(_sympify_list(L, "L") + _forces_list(forces, n), t)
    if len(exprs) != n + 1:
        raise ValueError("L must be a single expression")
    exprs, t, psyms, names, values = _mechanical_inputs(exprs, c, params, t, "L")
    parts = []
    Lp, fq = _maybe_simplify(exprs[0], simplify, c.speeds, parts,
                             set(psyms) if structured else None), exprs[1:]
    struct = None
    if structured:
        M = parts[0] if parts else _mass(Lp, c.speeds)
        fixed = set(psyms)
        M = M.applyfunc(lambda e: _collect_params(e, fixed))
        struct = _structure(Lp, M, c.plain, c.speeds, c.accels, t, fq, jacobian,
                            parts[1:] if parts else None)
    if struct is None:
        M, Q = _euler_lagrange(Lp, c.plain, c.speeds, t)
    _check_mass(M, c.plain, c.speeds, psyms, values, t)
    energy = _energy(Lp, M, c.speeds)
    d = Derived("generalized", t=t, coords=c.plain, coord_names=c.names,
                speeds=c.speeds, accels=c.accels, params=psyms, param_names=names,
                param_values=values, M=M, energy=energy, lagrangian=Lp, struct=struct,
                gen_forces=list(fq), with_jacobian=bool(jacobian))
    if struct is None:
        d.Q = Q + sp.Matrix(fq)
        if jacobian:
            Ma = M * sp.Matrix(c.accels)
            d.R = _ae((d.Q - Ma).jacobian(c.plain).row_join(d.Q.jacobian(c.speeds)))
    return d

