"""Cheap simplification of a Lagrangian before the equations are derived: the
trigonometric clean-up (sin^2 + cos^2 = 1, products of sines and cosines into cosines of
differences), the split of L into its parts quadratic, linear and free in the velocities, and
the regrouping of sums by their state-dependent factors (parameters collected in front)."""
import sympy as sp
from sympy.simplify.fu import TR10i


def _cheap_simplify(expr, fixed=None):
    """Fast trigonometric clean-up of a Lagrangian: expand, sin(x)^2 -> 1 - cos(x)^2 (so
    that cos^2 + sin^2 cancels), then cos a cos b + sin a sin b -> cos(a - b) (fu's TR10i).
    With `fixed` (the parameter symbols), the terms are first grouped by their factors that
    are not parameters, each group's coefficient a placeholder for TR10i (few terms, fast)
    and then put back with its common factors pulled out (:func:`_collect_params`)."""
    e = sp.expand(expr)
    e = e.replace(lambda u: u.is_Pow and u.exp == 2 and isinstance(u.base, sp.sin),
                  lambda u: 1 - sp.cos(u.base.args[0])**2)
    e = sp.expand(e)
    if fixed is None or not isinstance(e, sp.Add):
        return TR10i(e)
    groups = _groups(e, fixed)
    holders, back, out = {}, {}, sp.Integer(0)
    for key, cf in groups.items():
        num, cf = sp.factor_terms(cf).as_coeff_Mul()
        if cf not in holders:
            holders[cf] = sp.Dummy("c")
            back[holders[cf]] = cf
        out += num*holders[cf]*key
    return TR10i(out).xreplace(back)


def _groups(e, fixed):
    """{non-parameter factor: sum of the parameter factors} over the terms of the sum e."""
    groups = {}
    for term in e.args:
        par, rest = [], []
        for f in sp.Mul.make_args(term):
            (par if f.free_symbols <= fixed else rest).append(f)
        key = sp.Mul(*rest)
        groups[key] = groups.get(key, sp.Integer(0)) + sp.Mul(*par)
    return groups


def _maybe_simplify(expr, simplify, v=(), parts=None, fixed=None):
    """simplify: True, False or "auto". A Lagrangian at most quadratic in the velocities v
    is cleaned up by parts, L = v^T M v / 2 + l1 . v + L0, each entry of M, l1 and L0 on its
    own (small expressions, so the clean-up stays fast for long chains); "auto" skips parts
    too large for it (more than 600 operations)."""
    if simplify not in (True, False, "auto"):
        raise ValueError(f"simplify must be True, False or 'auto', got {simplify!r}")
    if simplify is False:
        return expr

    def part(e):
        if e == 0:
            return e
        if simplify is True or sp.count_ops(e) <= 600:
            return _cheap_simplify(e, fixed)
        return e
    v = list(v)
    if v:
        n = len(v)
        qp = _quadratic_parts(expr, v) if fixed is not None else None
        if qp is not None:
            H, l1, L0 = qp
        else:
            grad = [sp.diff(expr, vi) for vi in v]
            H = [[sp.diff(grad[i], v[j]) for j in range(n)] for i in range(n)]
            zero = {vi: 0 for vi in v}
            l1 = [g.xreplace(zero) for g in grad]
            L0 = expr.xreplace(zero)
        if not any(h.free_symbols & set(v) for row in H for h in row):
            Hs = {}
            for i in range(n):
                for j in range(i, n):
                    Hs[i, j] = part(H[i][j])
            l1 = [part(g) for g in l1]
            L0 = part(L0)
            if parts is not None:        # the cleaned-up M, l1, L0 for the caller
                parts.extend([sp.Matrix(n, n, lambda i, j: Hs[min(i, j), max(i, j)]),
                              l1, L0])
            quad = sum((Hs[i, i]*v[i]**2/2 for i in range(n)), sp.Integer(0)) \
                + sum((Hs[i, j]*v[i]*v[j] for i in range(n) for j in range(i + 1, n)),
                      sp.Integer(0))
            return quad + sum((c*vi for c, vi in zip(l1, v)), sp.Integer(0)) + L0
    return part(expr)


def _quadratic_parts(expr, v):
    """L = v^T H v / 2 + l1 . v + L0 read off the expanded L term by term (no
    differentiation): (H as a list of rows, l1, L0), or None if L is not a polynomial of
    degree <= 2 in the velocities v."""
    n = len(v)
    idx = {vi: i for i, vi in enumerate(v)}
    vset = set(v)
    H = [[sp.Integer(0)]*n for _ in range(n)]
    l1 = [sp.Integer(0)]*n
    L0 = sp.Integer(0)
    for term in sp.Add.make_args(sp.expand(expr)):
        pw, rest = [], []
        for f in sp.Mul.make_args(term):
            b, e = f.as_base_exp()
            if b in vset and e.is_Integer and e > 0:
                pw += [idx[b]]*int(e)
            elif f.free_symbols & vset:
                return None
            else:
                rest.append(f)
        c = sp.Mul(*rest)
        if not pw:
            L0 += c
        elif len(pw) == 1:
            l1[pw[0]] += c
        elif len(pw) == 2:
            i, j = sorted(pw)
            if i == j:
                H[i][i] += 2*c
            else:
                H[i][j] += c
                H[j][i] += c
        else:
            return None
    return H, l1, L0


def _collect_params(e, params):
    """A sum regrouped by its factors that are not parameters, each group's coefficient (a
    polynomial in the parameters) with its common factors pulled out: sum_k m_k l_i l_j
    cos(..) -> l_i l_j (sum_k m_k) cos(..), so that the code does not repeat the
    state-dependent factor per parameter."""
    if not isinstance(e, sp.Add):
        return e
    groups = _groups(e, params)
    if len(groups) == len(e.args):
        return e
    return sp.Add(*[sp.factor_terms(cf)*key for key, cf in groups.items()])
