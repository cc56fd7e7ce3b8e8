"""The Taylor recurrences of a generalized system M(t, q) q'' = Q(t, q, q') written out for
one order (``conmech_taylor_fixed``), as :func:`conmech.symbolic.taylor.fixed_order_source`
writes out an ode system's: no loop over the orders, literal indices, the coefficients in
scalars, so that the compiler schedules the whole expansion at once.

The statements are those of the loop routine (:func:`conmech.symbolic.taylor_generalized.
generalized_body`) order by order, with every sum in the loop's order: the history sums
and the products M_j a_{k-j} term by term for j = 1 .. k - 1, the squares' halved sums for
j = 1 .. (k - 1)/2, then doubled and the middle term added; the same factorisation of
M_0 and the same triangular solves per order. Compiled without contracted multiply-adds
(the flags of the ode systems' written-out routine), the routine gives the loop routine's
coefficients to the last bit, so a run takes the same steps with either.

A tree (:mod:`conmech.symbolic.taylor_tree`: the recurrences of its articulated-body
chain, an ode system's decomposition) is written out as an ode system is, with its pivots
checked at order 0 as its loop routine checks them (:func:`tree_fixed_source`).
"""
from .taylor import _decls, _Printer, _wrap
from .taylor_generalized import WRITE_OUT_MAX, accelerations, factorisation, \
    generalized_decomposition, order_zero
from .taylor_decompose import TaylorUnsupported
from .taylor_lanes import _history_sum, _sum_seq
from .taylor_recipe import Recipe
from .printer import _names, quiet_nan

__all__ = ["generalized_fixed_source", "tree_fixed_source", "mass_products", "NAN_FILL"]


def mass_products(g):
    """The products M_il a_l of one order's history (the entries of M that vary): with the
    operations' history sums, the measure of the written-out source's size (it grows as
    their number times order**2 / 2)."""
    return len(g.varying_products())


def _ascending(k):
    """The terms j = 1 .. k - 1 of a plain history sum in the loop routine's order."""
    return range(1, k)


def _ascending_half(k):
    """The terms j = 1 .. (k - 1)/2 of a square's halved sum in the loop routine's order."""
    return range(1, (k - 1)//2 + 1)


def generalized_fixed_body(g, names, fixed, ind="        ", write_out=None):
    """(declarations, statements) of the coefficient routine written out for the order
    `fixed` (the routine must be called with order = fixed; any other order returns at
    once, w untouched), for a procedure that declares t, order, w(0:order, g.ncol) and p.
    The state's coefficients are read from w(0, 1:2n) and written to w(1:fixed, 1:2n);
    the operations' and the accelerations' stay in scalars."""
    n = g.n
    dec = g.dec
    out = n <= WRITE_OUT_MAX if write_out is None else write_out
    pp = _Printer(dec, names, False, "dp")
    pp.scalars = set()
    rc = Recipe(pp, True, fixed)
    W = pp.w
    one = pp.real(1)
    decl, body, varying, M0, _ = order_zero(g, pp, rc, rc.s0, ind)
    fail = NAN_FILL
    decl = [x for x in decl if "fk, rk, rk1" not in x and "integer :: k, j" not in x]
    decl.append(f"{ind}real(dp) :: cs")
    state = range(1, 2*n + 1)
    body = [f"{ind}if (order /= {fixed}) return"] + \
        [f"{ind}{W(0, c)} = w(0, {c})" for c in state] + body[1:]
    fdecl, chol, solve, rvec, gacc = factorisation(g, pp, M0, ind, fail, out)
    decl += fdecl
    solve = [x[4:] for x in solve]         # (at the body's indentation: no loop over k)
    body += chol
    for i in range(n):
        body += _wrap(f"{rvec[i]} = {pp.lin_at(dec.outputs[g.forces[i]], 0, True)}", ind)
    body += solve
    jstate = [c for c in state if c in dec.jcol]
    for i in range(n):
        body.append(f"{ind}{W(0, g.acols[i])} = {rvec[i]}")
        body.append(f"{ind}{W(1, i + 1)} = {W(0, n + i + 1)}")
        body.append(f"{ind}{W(1, n + i + 1)} = {rvec[i]}")
    body += [f"{ind}{W(1, dec.jcol[c])} = {W(1, c)}" for c in jstate]
    body += [f"{ind}w(1, {c}) = {W(1, c)}" for c in state]
    prods = g.varying_products()
    for k in range(1, fixed):
        E = {"k": k, "fk": pp.real(k), "rk": f"({one}/{pp.real(k)})"}
        for h, lft, rgt, wt in rc.hist:
            hs = _history_sum(pp, k, lft, rgt, wt, None, _ascending, _ascending_half)
            body += _wrap(f"{h} = {hs}", ind)
        # sum_{j=1..k-1} M_j a_{k-j}, term by term in j as the loop adds them
        for i in range(n):
            terms = [f"{W(j, g.entry_col(i, l))}*{W(k - j, g.acols[l])}"
                     for j in range(1, k) for (ii, l) in prods if ii == i]
            body += _wrap(f"{gacc[i]} = {_sum_seq(terms, '0.0_dp')}", ind)
        for f in rc.cur:
            body += _wrap(f(E), ind)
        for (i, j) in varying:
            body += _wrap(f"{W(k, g.entry_col(i, j))} = {pp.lin_at(g.entry(i, j), k, False)}",
                          ind)
        body += accelerations(g, pp, k, k + 1, f"({one}/{pp.real(k + 1)})",
                              pp.real(k + 1), rvec, gacc, solve, ind)
        body += [f"{ind}w({k + 1}, {c}) = {W(k + 1, c)}" for c in state]
    scalars = sorted(pp.scalars, key=lambda x: tuple(int(v) for v in x[1:].split("_")))
    decl += _decls(scalars, "real(dp)", ind)
    return decl, body


#: the statements that fail an expansion (a mass matrix, or a tree's pivot, not positive):
#: NaN coefficients, as the loop routines' (the quiet NaN by its bits, printer.quiet_nan;
#: the flags of the written-out routines also leave out the standard include path, and with
#: it the intrinsic module ieee_arithmetic)
NAN_FILL = [f"w(1:order, :) = {quiet_nan()}", "return"]


def fixed_module(what, order, nw, npar, decl, body, ind="        "):
    """Fortran source of the module conmech_symbolic_taylor_fixed holding
    ``conmech_taylor_fixed(t, order, w, p)`` (bind(C)) of declarations `decl` and
    statements `body` (w(0:order, nw), p(npar)); `what` names the system in its first
    line."""
    lines = ["!> Generated by conmech.symbolic.taylor_generalized_fixed: Taylor coefficients "
             f"of {what} written out for order {order}. Do not edit.",
             "module conmech_symbolic_taylor_fixed",
             "    use, intrinsic :: iso_c_binding, only: c_double, c_int",
             "    implicit none",
             "    integer, parameter :: dp = c_double",
             "    public",
             "contains", "",
             '    subroutine conmech_taylor_fixed(t, order, w, p) bind(C, '
             'name="conmech_taylor_fixed")',
             f"{ind}real(dp), value, intent(in) :: t",
             f"{ind}integer(c_int), value, intent(in) :: order",
             f"{ind}real(dp), intent(inout) :: w(0:order, {nw})",
             f"{ind}real(dp), intent(in) :: p({npar})"]
    lines += decl + body + ["    end subroutine conmech_taylor_fixed", "",
                            "end module conmech_symbolic_taylor_fixed", ""]
    return "\n".join(lines)


def generalized_fixed_source(d, order, g=None, write_out=None):
    """Fortran source of a module with ``conmech_taylor_fixed(t, order, w, p)`` (bind(C);
    the signature and work columns of the generalized record `d`'s ``conmech_taylor``,
    called with order = `order` only); g: d's decomposition when already made; write_out:
    the factorisation in scalars (True) or loops (False), by default as the loop routine
    has it (up to WRITE_OUT_MAX degrees of freedom in scalars).
    TaylorUnsupported when `d` has no recurrences."""
    if g is None:
        g, why = generalized_decomposition(d)
        if g is None:
            raise TaylorUnsupported(why)
    ind = "        "
    decl, body = generalized_fixed_body(g, _names(d), order, ind, write_out)
    return fixed_module("M(q) q'' = Q", order, g.ncol, max(len(d.params), 1), decl, body,
                        ind)


def tree_fixed_source(d, order, tree=None):
    """The same module for a tree (conmech.symbolic.taylor_tree): the recurrences of its
    articulated-body chain written out for `order` as an ode system's are
    (conmech.symbolic.taylor.body_lines with ``fixed``: the loop routine's bits), the
    pivots D_i checked after the order-0 statements as the loop routine checks them;
    tree: (decomposition, pivot forms) when already made. TaylorUnsupported when the
    tree has no recurrences."""
    from .taylor import body_lines
    from .taylor_tree import tree_decomposition
    if tree is None:
        dec, pivots, why = tree_decomposition(d)
        if dec is None:
            raise TaylorUnsupported(why)
    else:
        dec, pivots = tree
    ind = "        "
    names = _names(d)
    decl, body = body_lines(dec, names, "dp", 0, False, ind, order, paired=False)
    pp = _Printer(dec, names, False, "dp")
    pp.scalars = set()        # the written-out routine's names of the order-0 values
    checks = []
    for lin in pivots:
        if lin.terms:         # (a constant pivot was checked when the tree was built)
            checks += _wrap(f"pivot = {pp.lin_at(lin, 0, True)}", ind)
            checks += [f"{ind}if (.not. (pivot > 0.0_dp)) then"] + \
                [f"{ind}    {x}" for x in NAN_FILL] + [f"{ind}end if"]
    if checks:
        # after the order-0 statements: before the first coefficient of order 1 is stored
        at = body.index(f"{ind}w(1, 1) = {pp.w(1, 1)}")
        body = body[:at] + checks + body[at:]
        decl = decl + [f"{ind}real(dp) :: pivot"]
    return fixed_module("a tree", order, dec.ncol, max(len(dec.params), 1), decl, body, ind)
