"""Taylor coefficients of a generalized system M(t, q) q'' = Q(t, q, q') (a
:func:`conmech.symbolic.lagrangian_system`), through the accelerations.

The first-order state is y = [q; v]. Along the solution the entries of M and Q are
expanded by the recurrences of :mod:`conmech.symbolic.taylor` (the same decomposition into
elementary operations as an ode system's right-hand side, with q and v as the state), and
the accelerations a = q'' follow order by order from the linear solve M(t) a(t) = Q(t):
the k-th coefficient of the product M a is sum_{j=0..k} M_j a_{k-j}, so

    M_0 a_k = Q_k - sum_{j=1..k} M_j a_{k-j},

one factorisation of M_0 per expansion (M symmetric positive definite: Cholesky) and one
pair of triangular solves per order. Then q^[k+1] = v^[k]/(k + 1) and v^[k+1] =
a_k/(k + 1). The history sum over j of each product M_il a_l joins the operations' history
sums in the one loop over j of an order; entries of M that are constant (no q, no t) have
no coefficients beyond order 0 and no history terms.

For up to :data:`WRITE_OUT_MAX` degrees of freedom the factorisation and the triangular
solves are written out in scalars (n**3/6 + n**2 multiply-adds with no loop, no array and
no library call: a LAPACK call per order would cost more than the solve itself for such
n); beyond, they are short loops over a local array. A mass matrix that is not positive
definite at the expansion point (a singular configuration) gives non-finite coefficients,
which the stepper reports as a non-finite right-hand side (see
:func:`conmech.ivp.taylor_generalized`, which names M in the message).

The routine has the signature and the work-array convention of an ode system's
``conmech_taylor(t, order, w, p)`` (w(0:order, nw), the state in the columns 1..2n), so the
Taylor stepper, the dense output and the step control run on it unchanged; the library
also exports ``conmech_taylor_rhs(t, y, dydt, p)`` (f = [v; M^-1 Q] from the order-1
expansion), the first-order right-hand side of the stepper's view of the system. The same
statements with a vector of SIMD lanes for every per-member value are the batch routine of
ensembles (:mod:`conmech.symbolic.taylor_generalized_batch`).
"""
import sympy as sp

from .printer import quiet_nan
from .taylor import _SYM, _decls, _Printer, _wrap, quad_procedure, square_sums
from .taylor_decompose import TaylorUnsupported, decompose
from .taylor_recipe import Recipe
from .taylor_first_order import core_part_lines, first_order_procedures

__all__ = ["generalized_decomposition", "generalized_procedures", "generalized_quad_routine",
           "WRITE_OUT_MAX"]

#: the Cholesky factorisation and triangular solves are written out in scalars up to this
#: many degrees of freedom (loops over a local array beyond)
WRITE_OUT_MAX = 8


class MassEntries:
    """The entries of a symmetric mass matrix held as output columns of a decomposition
    (``dec``; ``mass`` {(i, j): output index} for i <= j): shared by the accelerations'
    and the variational system's decompositions."""

    def entry(self, i, j):
        """The affine form (_Lin) of M_ij (symmetric: the upper triangle's)."""
        return self.dec.outputs[self.mass[(min(i, j), max(i, j))]]

    def entry_col(self, i, j):
        return self.dec.out_cols[self.mass[(min(i, j), max(i, j))]]

    def constant(self, i, j):
        return not self.entry(i, j).terms

    def varying_products(self):
        """The pairs (i, l) of the products M_il a_l whose entry of M varies (has
        coefficients beyond order 0: history terms)."""
        return [(i, l) for i in range(self.n) for l in range(self.n)
                if not self.constant(i, l)]

    def mass_and_forces(self, M, Q, n):
        """The outputs M's upper triangle (by columns), then Q: sets ``mass`` and
        ``forces`` and returns the list of the entries."""
        self.mass = {}
        entries = []
        for j in range(n):
            for i in range(j + 1):
                self.mass[(i, j)] = len(entries)
                entries.append(M[i, j])
        self.forces = list(range(len(entries), len(entries) + n))
        return entries + [Q[i] for i in range(n)]


class GeneralizedDecomposition(MassEntries):
    """The decomposition of the entries of M (upper triangle, by columns) and Q in the
    state [q; v] (attributes: ``dec``, the :class:`Decomposition` with the entries as
    output columns; ``n`` degrees of freedom; ``mass`` {(i, j): output index} for i <= j
    (0-based); ``forces`` [output index]; ``acols`` the work columns of the
    accelerations' coefficients; ``ncol`` the work columns in all)."""

    def __init__(self, d):
        n = d.n
        M, Q = d.M, d.Q
        self.n = n
        entries = self.mass_and_forces(M, Q, n)
        state = list(d.coords) + list(d.speeds)
        self.dec = decompose(entries, state, d.t, d.params, given=True)
        base = self.dec.ncol
        self.acols = list(range(base + 1, base + n + 1))
        self.ncol = base + n


def generalized_decomposition(d):
    """(:class:`GeneralizedDecomposition`, None) of the generalized record `d`, or (None,
    reason) when its accelerations have no Taylor recurrences here (a non-smooth
    expression, no mass matrix as an expression (trees), an asymmetric one)."""
    if getattr(d, "kind", None) != "generalized":
        return None, "not a system in generalized coordinates"
    if getattr(d, "aba", None) is not None or d.M is None or d.Q is None:
        return None, ("the system has no mass matrix and forces as expressions (method "
                      "TAYLOR expands M and Q here; a symbolic tree's recurrences come "
                      "from its articulated-body code: conmech.symbolic.taylor_tree)")
    M = d.M
    for i in range(d.n):
        for j in range(i + 1, d.n):
            if M[i, j] != M[j, i] and sp.expand(M[i, j] - M[j, i]) != 0:
                return None, ("the mass matrix is not symmetric: Taylor's linear solve "
                              "factorises it by Cholesky")
    try:
        return GeneralizedDecomposition(d), None
    except TaylorUnsupported as exc:
        return None, str(exc)


def _cholesky_out(g, pp, M0, ind, fail, kind="dp"):
    """Written-out Cholesky factorisation of M_0 (its entries as Fortran text M0(i, j)):
    the strictly lower factor in scalars cl<i>_<j>, the reciprocal diagonal in cd<i>."""
    n = g.n
    lines, names = [], []
    one = pp.real(1)
    for j in range(n):
        s = M0(j, j)
        terms = [f"cl{j + 1}_{k + 1}**2" for k in range(j)]
        expr = f"{s}" + "".join(f" - {t}" for t in terms)
        lines += _wrap(f"cs = {expr}", ind)
        lines.append(f"{ind}if (.not. cs > 0.0_{kind}) then")
        lines += [f"{ind}    {x}" for x in fail]
        lines.append(f"{ind}end if")
        lines.append(f"{ind}cd{j + 1} = {one}/sqrt(cs)")
        names.append(f"cd{j + 1}")
        for i in range(j + 1, n):
            terms = [f"cl{i + 1}_{k + 1}*cl{j + 1}_{k + 1}" for k in range(j)]
            expr = f"{M0(i, j)}" + "".join(f" - {t}" for t in terms)
            lines += _wrap(f"cl{i + 1}_{j + 1} = ({expr})*cd{j + 1}", ind)
            names.append(f"cl{i + 1}_{j + 1}")
    return lines, names


def _solve_out(n, ind):
    """Written-out triangular solves L L^T a = r in place in the scalars cr<i>."""
    lines = []
    for i in range(n):
        terms = "".join(f" - cl{i + 1}_{k + 1}*cr{k + 1}" for k in range(i))
        lines += _wrap(f"cr{i + 1} = (cr{i + 1}{terms})*cd{i + 1}", ind)
    for i in reversed(range(n)):
        terms = "".join(f" - cl{k + 1}_{i + 1}*cr{k + 1}" for k in range(i + 1, n))
        lines += _wrap(f"cr{i + 1} = (cr{i + 1}{terms})*cd{i + 1}", ind)
    return lines


def _cholesky_loop(n, ind, fail, kind="dp"):
    """The same factorisation in loops over the local array lm (lower triangle, holding
    M_0's on entry), reciprocal diagonal in ld."""
    return [f"{ind}do jj = 1, {n}",
            f"{ind}    cs = lm(jj, jj) - sum(lm(jj, 1:jj - 1)**2)",
            f"{ind}    if (.not. cs > 0.0_{kind}) then"] + \
        [f"{ind}        {x}" for x in fail] + \
        [f"{ind}    end if",
         f"{ind}    ld(jj) = 1.0_{kind}/sqrt(cs)",
         f"{ind}    do ii = jj + 1, {n}",
         f"{ind}        lm(ii, jj) = (lm(ii, jj) - sum(lm(ii, 1:jj - 1)*lm(jj, 1:jj - 1)))"
         "*ld(jj)",
         f"{ind}    end do",
         f"{ind}end do"]


def _solve_loop(n, ind):
    return [f"{ind}do ii = 1, {n}",
            f"{ind}    cr(ii) = (cr(ii) - sum(lm(ii, 1:ii - 1)*cr(1:ii - 1)))*ld(ii)",
            f"{ind}end do",
            f"{ind}do ii = {n}, 1, -1",
            f"{ind}    cr(ii) = (cr(ii) - sum(lm(ii + 1:{n}, ii)*cr(ii + 1:{n})))*ld(ii)",
            f"{ind}end do"]


def factorisation(g, pp, M0, ind, fail, out, kind="dp"):
    """The factorisation of M_0 and the triangular solves, written out in scalars (`out`)
    or in loops over local arrays: (declarations, the factorisation's lines, the solves'
    lines at the indentation ind + 4, the right-hand sides' names rvec, the history sums'
    names gacc); M0(i, j) the Fortran value of M_ij at order 0, `fail` the statements
    that fail the expansion."""
    n = g.n
    real = f"real({kind})"
    if out:
        chol, names_c = _cholesky_out(g, pp, M0, ind, fail, kind)
        rvec = [f"cr{i + 1}" for i in range(n)]
        gacc = [f"cg{i + 1}" for i in range(n)]
        return (_decls(names_c + rvec + gacc, real, ind), chol, _solve_out(n, ind + "    "),
                rvec, gacc)
    decl = [f"{ind}{real} :: lm({n}, {n}), ld({n}), cr({n}), cg({n})",
            f"{ind}integer :: ii, jj"]
    chol = [f"{ind}lm = 0.0_{kind}"]
    for j in range(n):
        for i in range(j, n):
            chol += _wrap(f"lm({i + 1}, {j + 1}) = {M0(i, j)}", ind)
    chol += _cholesky_loop(n, ind, fail, kind)
    return (decl, chol, _solve_loop(n, ind + "    "), [f"cr({i + 1})" for i in range(n)],
            [f"cg({i + 1})" for i in range(n)])


def order_zero(g, pp, rc, s0, ind, kind="dp"):
    """The parts every coefficient routine through M's factorisation starts with:
    (declarations, the order-0 statements `s0` of the operations and of the entries of M
    that vary, those entries' index pairs, M0(i, j) the Fortran value of M_ij at order 0,
    the statements that fail the expansion when M_0 is not positive definite)."""
    W = pp.w
    real = f"real({kind})"
    decl = _decls([c for c, _ in rc.consts], real, ind)
    decl += _decls(rc.accs + rc.invs, real, ind)
    decl += [f"{ind}{real} :: fk, rk, rk1, cs", f"{ind}integer :: k, j"]
    body = [f"{ind}if (order < 1) return"]
    for c, e in rc.consts:
        body += _wrap(f"{c} = {e}", ind)
    for x in s0:
        body += _wrap(x, ind)
    varying = [(i, j) for (i, j) in g.mass if not g.constant(i, j)]
    for (i, j) in varying:
        body += _wrap(f"{W(0, g.entry_col(i, j))} = {pp.lin_at(g.entry(i, j), 0, True)}", ind)

    def M0(i, j):
        if g.constant(i, j):
            return pp.lin_at(g.entry(i, j), 0, True)
        return W(0, g.entry_col(i, j))
    fail = [f"w(1:order, :) = {quiet_nan(kind)}", "return"]
    return decl, body, varying, M0, fail


def generalized_body(g, names, ind="        ", write_out=None, kind="dp"):
    """(declarations, statements) of the coefficient routine (see the module docstring)
    for a procedure that declares t, order, w(0:order, g.ncol) and p (of the real kind
    `kind`: "dp", or "qp" for quadruple precision)."""
    n = g.n
    dec = g.dec
    out = n <= WRITE_OUT_MAX if write_out is None else write_out
    pp = _Printer(dec, names, False, kind)
    rc = Recipe(pp, True, "order")
    W = pp.w
    one = pp.real(1)
    zero = f"0.0_{kind}"
    # order 0: the operations, the entries of M and Q, the factorisation, a_0
    decl, body, varying, M0, fail = order_zero(g, pp, rc, rc.s0, ind, kind)
    fdecl, chol, solve, rvec, gacc = factorisation(g, pp, M0, ind, fail, out, kind)
    decl += fdecl
    body += chol
    for i in range(n):
        body += _wrap(f"{rvec[i]} = {pp.lin_at(dec.outputs[g.forces[i]], 0, True)}", ind)
    body += [x[4:] if x.startswith(ind + "    ") else x for x in solve]
    jstate = [c for c in range(1, 2*n + 1) if c in dec.jcol]
    for i in range(n):
        body.append(f"{ind}{W(0, g.acols[i])} = {rvec[i]}")
        body.append(f"{ind}{W(1, i + 1)} = {W(0, n + i + 1)}")
        body.append(f"{ind}{W(1, n + i + 1)} = {rvec[i]}")
    body += [f"{ind}{W(1, dec.jcol[c])} = {W(1, c)}" for c in jstate]
    # orders 1 .. order - 1
    loop = [f"{ind}do k = 1, order - 1",
            f"{ind}    fk = real(k, {kind})",
            f"{ind}    rk = {one}/fk",
            f"{ind}    rk1 = {one}/(fk + {one})"]
    loop += [f"{ind}    {h} = {zero}" for h in rc.accs]
    loop += [f"{ind}    {x} = {zero}" for x in gacc]
    plain = [x for x in rc.hist if x[3] is not _SYM]
    sym = [x for x in rc.hist if x[3] is _SYM]
    # the products M_il a_l: sum_{j=1..k-1} M_j a_{k-j} (the term j = k below)
    prods = g.varying_products()
    if plain or prods:
        loop.append(f"{ind}    do j = 1, k - 1")
        for h, lft, rgt, wt in plain:
            wj = f"({wt}*real(j, {kind}) - fk)*" if wt else ""
            loop += _wrap(f"{h} = {h} + {wj}{W('j', lft)}*{W('k - j', rgt)}", ind + "        ")
        for i in range(n):
            terms = [f"{W('j', g.entry_col(i, l))}*{W('k - j', g.acols[l])}"
                     for (ii, l) in prods if ii == i]
            if terms:
                loop += _wrap(f"{gacc[i]} = {gacc[i]} + " + " + ".join(terms), ind + "        ")
        loop.append(f"{ind}    end do")
    loop += square_sums(sym, W, pp, ind)
    E = {"k": "k", "fk": "fk", "rk": "rk"}
    for f in rc.cur:
        loop += _wrap(f(E), ind + "    ")
    for (i, j) in varying:
        loop += _wrap(f"{W('k', g.entry_col(i, j))} = {pp.lin_at(g.entry(i, j), 'k', False)}",
                      ind + "    ")
    loop += accelerations(g, pp, "k", "k + 1", "rk1", f"(fk + {one})", rvec, gacc, solve,
                          ind + "    ")
    loop.append(f"{ind}end do")
    return decl, body + loop


def accelerations(g, pp, k, k1, rk1, fk1, rvec, gacc, solve, ind):
    """The statements that close order k: r = Q_k - sum_{j=1..k} M_j a_{k-j} (gacc the
    terms j < k), a_k = M_0^-1 r (the solves' lines `solve`), then q^[k+1] = v^[k]/(k + 1),
    v^[k+1] = a_k/(k + 1) and the state's j-weighted columns. k and k1 are the order and
    the next one (Fortran text, or numbers in a written-out routine), rk1 and fk1 the
    text of 1/(k + 1) and k + 1; the lines at the indentation ind."""
    W = pp.w
    n, dec = g.n, g.dec
    prods = g.varying_products()
    lines = []
    for i in range(n):
        terms = [f" - {W(k, g.entry_col(i, l))}*{W(0, g.acols[l])}"
                 for (ii, l) in prods if ii == i]
        q = pp.lin_at(dec.outputs[g.forces[i]], k, False)
        lines += _wrap(f"{rvec[i]} = {q} - {gacc[i]}" + "".join(terms), ind)
    lines += solve
    for i in range(n):
        lines.append(f"{ind}{W(k, g.acols[i])} = {rvec[i]}")
        lines.append(f"{ind}{W(k1, i + 1)} = {rk1}*{W(k, n + i + 1)}")
        lines.append(f"{ind}{W(k1, n + i + 1)} = {rk1}*{rvec[i]}")
    lines += [f"{ind}{W(k1, dec.jcol[c])} = {fk1}*{W(k1, c)}"
              for c in range(1, 2*n + 1) if c in dec.jcol]
    return lines


def generalized_procedures(g, names, prefix="conmech_taylor", write_out=None, npar=1):
    """Fortran lines of ``prefix(t, order, w, p)`` (bind(C)), ``prefix_info(info)``
    ([columns of w, 0, 2n, 0]) and ``prefix_rhs(t, y, dydt, p)`` (f = [v; M^-1 Q])."""
    ind = "        "
    nw = g.ncol
    m = 2*g.n
    decl, body = generalized_body(g, names, ind, write_out)
    return first_order_procedures(prefix, nw, m, npar, decl, body, ind)


def generalized_quad_routine(g, names, cname="conmech_taylor_qp", write_out=None, npar=1):
    """The same recurrences in quadruple precision: ``cname(t, order, w, p)`` through C
    pointers to real128 values (as conmech.symbolic.taylor.quad_routine: t, w(0:order,
    g.ncol), p), the accelerations' factorisation and solves in real128 too."""
    decl, body = generalized_body(g, names, "        ", write_out, "qp")
    return quad_procedure(cname, g.ncol, npar, decl, body)


def generalized_lines(d, names, part, dec_cache):
    """(Fortran lines, entry names, reason) of one part of a generalized model's Taylor
    library (conmech.symbolic.taylor_library): the core and the quadruple precision one
    (``qp``) (the batch part: conmech.symbolic.taylor_generalized_batch.batch_lines; the
    variational part: conmech.symbolic.taylor_generalized_var.variational_lines; a tree's
    parts: conmech.symbolic.taylor_tree).
    """
    npar = max(len(d.params), 1)
    if part == "qp":
        if "g" not in dec_cache:
            dec_cache["g"] = generalized_decomposition(d)
        g, why = dec_cache["g"]
        if g is None:
            return [], [], why
        return generalized_quad_routine(g, names, npar=npar), ["taylor_qp"], None
    return core_part_lines(d, part, dec_cache, "g", generalized_decomposition,
                           "generalized systems M(q) q'' = Q",
                           lambda g: generalized_procedures(g, names, npar=npar))
