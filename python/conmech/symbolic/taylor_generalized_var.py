"""Taylor coefficients of the variational system of a generalized system M(t, q) q'' =
Q(t, q, q') (a :func:`conmech.symbolic.lagrangian_system`): the state transition matrix
Phi of the first-order view y = [q; v] by the same recurrences as the state.

Along the solution Phi' = J Phi with J = [[0, I], [da/dq, da/dv]], and differentiating
M a = Q in the direction of a column of Phi, (dq, dv) = (P_q, P_v), gives the
accelerations' variation da = (da/dy) Phi by a linear solve with the same M:

    M da = R,    R = K Phi,    K_il = dQ_i/dy_l - sum_m (dM_im/dy_l) a_m,

so the n x 2n matrix K is an expression in t, q, v and the accelerations a, and every
column of Phi is one more right-hand side of M. In series, with a_k known from the
accelerations' solve of order k (:mod:`conmech.symbolic.taylor_generalized`),

    M_0 da_k = R_k - sum_{j=1..k} M_j da_{k-j},

the factorisation of M_0 shared with the accelerations and one pair of triangular solves
per column and order. Then P_q^[k+1] = P_v^[k]/(k + 1) and P_v^[k+1] = da_k/(k + 1).

The entries of M, Q, K and R are decomposed together (the accelerations a are given
series, the columns of Phi state), each derivative dM_im/dy_l and each entry of K once
(a definition of the decomposition's chain) so that R costs one product per entry of K and
column of Phi. The operations that depend on a come after a_k in each order (they are
independent of the others' current terms); the history sums of all of them share the one
loop over j of an order. The routine is ``conmech_taylor_var(t, order, w, p)`` with the
work-array convention of an ode system's variational routine (w(0, 1:m) = [y; vec(Phi)]
on entry, m = 2n (2n + 1), Phi by columns), and ``conmech_taylor_var_info``.
"""
import copy

import sympy as sp

from .taylor import _SYM, _decls, _Printer, _wrap, square_sums
from .taylor_decompose import TaylorUnsupported, decompose
from .taylor_recipe import Recipe
from .taylor_first_order import first_order_procedures
from .taylor_generalized import (WRITE_OUT_MAX, MassEntries, factorisation,
                                 generalized_decomposition, order_zero)

__all__ = ["variational_decomposition", "variational_procedures", "variational_lines"]


class VariationalDecomposition(MassEntries):
    """The decomposition of M (upper triangle), Q and R = K Phi of a generalized record in
    the state [q; v; vec(Phi); a] (attributes: ``dec``; ``n`` degrees of freedom; ``m`` =
    2n the size of y; ``mass`` {(i, j): output index}, i <= j; ``forces`` and ``rhs``
    [output index] (rhs by columns of Phi, then rows); ``acols`` the state columns of the
    accelerations; ``dcols`` [column of Phi][row]: the work columns of da; ``nsplit``: the
    operations before the first that depends on a; ``ncol``)."""

    def __init__(self, d):
        n, m = d.n, 2*d.n
        M, Q = d.M, d.Q
        y = list(d.coords) + list(d.speeds)
        phi = [sp.Dummy(f"phi{r + 1}_{c + 1}", real=True) for c in range(m) for r in range(m)]
        acc = [sp.Dummy(f"acc{i + 1}", real=True) for i in range(n)]
        var = set(y) | set(acc) | {d.t}
        defs = []

        def named(e, label):
            """e itself when constant, else a definition of the chain (decomposed once)."""
            e = sp.sympify(e)
            if e == 0 or not (e.free_symbols & var):
                return e
            s = sp.Dummy(label, real=True)
            defs.append((s, e))
            return s
        dM = {}
        for j in range(n):
            for i in range(j + 1):
                for lc in range(m):
                    dM[(i, j, lc)] = named(sp.diff(M[i, j], y[lc]), f"dm{i}_{j}_{lc}")
        K = [[named(sp.diff(Q[i], y[lc]) -
                    sum(dM[(min(i, k), max(i, k), lc)]*acc[k] for k in range(n)),
                    f"k{i}_{lc}") for lc in range(m)] for i in range(n)]
        R = [sum(K[i][lc]*phi[c*m + lc] for lc in range(m)) for c in range(m)
             for i in range(n)]
        self.n, self.m = n, m
        entries = self.mass_and_forces(M, Q, n)
        self.rhs = list(range(len(entries), len(entries) + len(R)))
        entries += R
        state = y + phi + acc
        self.dec = dec = decompose(entries, state, d.t, d.params, given=True, defs=defs)
        self.acols = list(range(m + m*m + 1, m + m*m + n + 1))
        # the operations that depend on the accelerations after all others (a valid
        # evaluation order: none of the others uses them)
        dep = set(self.acols)
        first, after = [], []
        for op in dec.ops:
            args = op.args[:1] if op.kind in ("tan", "tanh") else op.args
            if any(a in dep for a in args):
                after.append(op)
                dep.update(op.out)
            else:
                first.append(op)
        dec.ops = first + after
        self.nsplit = len(first)
        base = dec.ncol
        self.dcols = [[base + 1 + c*n + i for i in range(n)] for c in range(m)]
        self.ncol = base + m*n


def variational_decomposition(d):
    """(:class:`VariationalDecomposition`, None) of the generalized record `d`, or (None,
    reason) as :func:`conmech.symbolic.taylor_generalized.generalized_decomposition`."""
    g, why = generalized_decomposition(d)
    if g is None:
        return None, why
    try:
        return VariationalDecomposition(d), None
    except TaylorUnsupported as exc:
        return None, str(exc)


def _prefix_counts(g, names):
    """(order-0 statements, current statements) of the operations that do not depend on
    the accelerations: a prefix of the recipe of all of them."""
    dec = copy.copy(g.dec)
    dec.ops = g.dec.ops[:g.nsplit]
    rc = Recipe(_Printer(dec, names, False, "dp"), True, "order")
    return len(rc.s0), len(rc.cur)


def variational_body(g, names, ind="        ", write_out=None):
    """(declarations, statements) of ``conmech_taylor_var`` (see the module docstring) for
    a procedure that declares t, order, w(0:order, g.ncol) and p."""
    n, m = g.n, g.m
    dec = g.dec
    out = n <= WRITE_OUT_MAX if write_out is None else write_out
    pp = _Printer(dec, names, False, "dp")
    rc = Recipe(pp, True, "order")
    ns0, ncur = _prefix_counts(g, names)
    W = pp.w
    one = pp.real(1)
    zero = "0.0_dp"
    decl, body, varying, M0, fail = order_zero(g, pp, rc, rc.s0[:ns0], ind)
    fdecl, chol, solve, rvec, gacc = factorisation(g, pp, M0, ind, fail, out)
    decl += fdecl
    # the history sums of M da, one per column of Phi
    if out:
        vacc = [[f"cv{c + 1}_{i + 1}" for i in range(n)] for c in range(m)]
        decl += _decls(sum(vacc, []), "real(dp)", ind)
    else:
        vacc = [[f"cv({i + 1}, {c + 1})" for i in range(n)] for c in range(m)]
        decl.append(f"{ind}real(dp) :: cv({n}, {m})")
    body += chol
    solve0 = [x[4:] if x.startswith(ind + "    ") else x for x in solve]
    # the accelerations a_0, then the operations on them and the columns da_0
    for i in range(n):
        body += _wrap(f"{rvec[i]} = {pp.lin_at(dec.outputs[g.forces[i]], 0, True)}", ind)
    body += solve0
    body += [f"{ind}{W(0, g.acols[i])} = {rvec[i]}" for i in range(n)]
    for x in rc.s0[ns0:]:
        body += _wrap(x, ind)
    for c in range(m):
        for i in range(n):
            body += _wrap(f"{rvec[i]} = {pp.lin_at(dec.outputs[g.rhs[c*n + i]], 0, True)}",
                          ind)
        body += solve0
        body += [f"{ind}{W(0, g.dcols[c][i])} = {rvec[i]}" for i in range(n)]
    nz = m + m*m
    jstate = [c for c in range(1, nz + 1) if c in dec.jcol]
    jacc = [c for c in g.acols if c in dec.jcol]

    def advance(k, scale):
        """The state's coefficients of order k + 1 from those of order k."""
        s = f"{scale}*" if scale else ""
        k1 = k + 1 if isinstance(k, int) else f"{k} + 1"
        lines = []
        for i in range(n):
            lines.append(f"{W(k1, i + 1)} = {s}{W(k, n + i + 1)}")
            lines.append(f"{W(k1, n + i + 1)} = {s}{W(k, g.acols[i])}")
        for c in range(m):
            col = m + c*m
            for i in range(n):
                lines.append(f"{W(k1, col + i + 1)} = {s}{W(k, col + n + i + 1)}")
                lines.append(f"{W(k1, col + n + i + 1)} = {s}{W(k, g.dcols[c][i])}")
        fac = "" if isinstance(k, int) else f"(fk + {one})*"
        lines += [f"{W(k1, dec.jcol[c])} = {fac}{W(k1, c)}" for c in jstate]
        return lines
    body += [f"{ind}{x}" for x in advance(0, None)]
    # orders 1 .. order - 1
    loop = [f"{ind}do k = 1, order - 1",
            f"{ind}    fk = real(k, dp)",
            f"{ind}    rk = {one}/fk",
            f"{ind}    rk1 = {one}/(fk + {one})"]
    loop += [f"{ind}    {h} = {zero}" for h in rc.accs]
    loop += [f"{ind}    {x} = {zero}" for x in gacc + sum(vacc, [])]
    plain = [x for x in rc.hist if x[3] is not _SYM]
    sym = [x for x in rc.hist if x[3] is _SYM]
    prods = g.varying_products()
    if plain or prods:
        loop.append(f"{ind}    do j = 1, k - 1")
        for h, lft, rgt, wt in plain:
            wj = f"({wt}*real(j, dp) - fk)*" if wt else ""
            loop += _wrap(f"{h} = {h} + {wj}{W('j', lft)}*{W('k - j', rgt)}", ind + "        ")
        for acc, cols in [(gacc, g.acols)] + [(vacc[c], g.dcols[c]) for c in range(m)]:
            for i in range(n):
                terms = [f"{W('j', g.entry_col(i, l))}*{W('k - j', cols[l])}"
                         for (ii, l) in prods if ii == i]
                if terms:
                    loop += _wrap(f"{acc[i]} = {acc[i]} + " + " + ".join(terms),
                                  ind + "        ")
        loop.append(f"{ind}    end do")
    loop += square_sums(sym, W, pp, ind)
    E = {"k": "k", "fk": "fk", "rk": "rk"}
    for f in rc.cur[:ncur]:
        loop += _wrap(f(E), ind + "    ")
    for (i, j) in varying:
        loop += _wrap(f"{W('k', g.entry_col(i, j))} = {pp.lin_at(g.entry(i, j), 'k', False)}",
                      ind + "    ")

    def solve_k(rhs_out, acc, cols):
        """r = rhs_k - sum_{j=1..k} M_j x_{k-j}, x_k = M_0^-1 r into the columns cols."""
        lines = []
        for i in range(n):
            terms = [f" - {W('k', g.entry_col(i, l))}*{W(0, cols[l])}"
                     for (ii, l) in prods if ii == i]
            q = pp.lin_at(dec.outputs[rhs_out[i]], "k", False)
            lines += _wrap(f"{rvec[i]} = {q} - {acc[i]}" + "".join(terms), ind + "    ")
        lines += solve
        lines += [f"{ind}    {W('k', cols[i])} = {rvec[i]}" for i in range(n)]
        return lines
    loop += solve_k(g.forces, gacc, g.acols)
    loop += [f"{ind}    {W('k', dec.jcol[c])} = fk*{W('k', c)}" for c in jacc]
    for f in rc.cur[ncur:]:
        loop += _wrap(f(E), ind + "    ")
    for c in range(m):
        loop += solve_k(g.rhs[c*n:(c + 1)*n], vacc[c], g.dcols[c])
    loop += [f"{ind}    {x}" for x in advance("k", "rk1")]
    loop.append(f"{ind}end do")
    return decl, body + loop


def variational_procedures(g, names, prefix="conmech_taylor_var", write_out=None, npar=1):
    """Fortran lines of ``prefix(t, order, w, p)`` (bind(C)) and ``prefix_info(info)``
    ([columns of w, 0, 2n (2n + 1), 0])."""
    ind = "        "
    decl, body = variational_body(g, names, ind, write_out)
    return first_order_procedures(prefix, g.ncol, g.m + g.m*g.m, npar, decl, body, ind,
                                  rhs=False)


def variational_lines(d, names, dec_cache):
    """(Fortran lines, entry names, reason) of the variational part ("var") of a generalized
    model's Taylor library (conmech.symbolic.taylor_library); a tree's is its chain's
    (conmech.symbolic.taylor_tree_var.tree_variational_lines)."""
    if "gvar" not in dec_cache:
        dec_cache["gvar"] = variational_decomposition(d)
    gv, why = dec_cache["gvar"]
    if gv is None:
        return [], [], why
    return variational_procedures(gv, names, npar=max(len(d.params), 1)), \
        ["taylor_var", "taylor_var_info"], None
