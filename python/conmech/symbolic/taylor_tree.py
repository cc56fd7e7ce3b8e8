"""Taylor coefficients of a symbolic tree (:func:`conmech.symbolic.planar_tree`,
:func:`conmech.symbolic.spatial_tree`, the trees of :mod:`conmech.symbolic.urdf`) through its
articulated-body code.

A tree's accelerations a(t, q, v) are the last values of a straight-line chain of
definitions s_i = expr(q, v, earlier s_j) (Featherstone's articulated-body algorithm,
:mod:`conmech.symbolic.tree_aba` and :mod:`conmech.symbolic.spatial_aba`): the chain is an
expression graph with its common subexpressions already shared, O(n) operations for n
bodies. Its Taylor coefficients along the solution of the first-order system

    q' = v,    v' = a(t, q, v)

follow from the recurrences of each definition in turn (:mod:`conmech.symbolic.taylor`):
every definition is one intermediate of the decomposition (substituting the chain into
the accelerations would multiply the expression by the depth of the tree), a joint
angle's cosine and sine are one sin/cos pair, the inverse of a joint's articulated inertia
D_i a quotient recurrence, and the rest products and linear combinations. The cost per
order is that of the chain times the order (the history sums), against the mass matrix
route's O(n**3) expansion of M and Q and order-by-order Cholesky solve
(:mod:`conmech.symbolic.taylor_generalized`), which a tree does not have as expressions.

The pivots D_i (the articulated inertias of the joints, positive for a positive definite
mass matrix) are checked at order 0, as the tree's own right-hand side checks them: a D_i
that is not positive (or NaN) makes every coefficient of order >= 1 NaN, which the
stepper reports as a non-finite right-hand side
(:func:`conmech.ivp.taylor_generalized.name_the_mass_matrix` then names the joint).

The library has the routines of a generalized system's Taylor library (its first-order
view runs on them): ``conmech_taylor(t, order, w, p)`` and ``_info`` with the work-array
convention of an ode system's (the state [q; v] in the columns 1..2n), and
``conmech_taylor_rhs(t, y, dydt, p)`` (f = [v; a] from the order-1 expansion); its
quadruple-precision part the same recurrences in real128 (``conmech_taylor_qp``, the entry
of :mod:`conmech.symbolic.taylor_quad`), and its variational part the chain differentiated
forward (:mod:`conmech.symbolic.taylor_tree_var`).
"""
import math

import sympy as sp

from .printer import quiet_nan
from .spatial_aba import _spatial_aba
from .taylor import _Printer, _wrap, body_lines, quad_procedure
from .taylor_decompose import TaylorUnsupported, decompose
from .taylor_first_order import core_part_lines, first_order_procedures
from .tree_aba import _aba

__all__ = ["is_tree", "tree_chain", "tree_decomposition", "kept_tree_decomposition",
           "tree_body", "tree_procedures", "tree_quad_routine", "tree_lines", "pivot_values"]


def is_tree(d):
    """Whether the derived record `d` is a tree's (its accelerations from the
    articulated-body code)."""
    return getattr(d, "aba", None) is not None or getattr(d, "aba_order", None) is not None


def tree_chain(d):
    """(definitions, accelerations) of the articulated-body algorithm of the tree record
    `d` in its canonical symbols (coordinates, speeds, t, parameters): ``d.aba`` for a
    tree derived through its Lagrangian (``method="lagrangian"``), else built from the
    joints of the recursive route's record as its generated ``conmech_accel`` builds
    them (the sines and cosines of the joint angles computed in the chain). None, reason
    for a tree with forces at points of bodies (their generalized forces come from a
    code of their own) or closed loops."""
    if getattr(d, "aba", None) is not None:
        return d.aba, None
    if getattr(d, "point_forces", None) or getattr(d, "loops", None):
        return None, ("a tree with forces at points of bodies or closed loops has no "
                      "Taylor recurrences here")
    index = {name: J.col for name, J in zip(d.order_names, d.joints)}
    tau = list(d.user_forces)
    if d.planar:
        return _aba(d.aba_order, index, d.cdata, list(d.coords), list(d.speeds), tau,
                    d.gravity[:2], d.absolute), None
    return _spatial_aba(d.aba_order, index, d.cdata, list(d.coords), list(d.speeds), tau,
                        sp.Matrix(d.gravity)), None


def tree_decomposition(d):
    """(decomposition, pivot forms, None) of the first-order system [v; a] of the tree
    record `d` (:func:`tree_chain`), the state [q; v]; pivot forms are the affine forms
    (_Lin) of the checked pivots D_i, in the chain's order. (None, None, reason) when a
    definition has no recurrence."""
    chain, why = tree_chain(d)
    if chain is None:
        return None, None, why
    defs, acc = chain
    state = list(d.coords) + list(d.speeds)
    try:
        dec = decompose(list(d.speeds) + list(acc), state, d.t, d.params, defs=defs)
    except TaylorUnsupported as exc:
        return None, None, str(exc)
    pivots = [dec._build(s) for s, e in defs if isinstance(e, str)]
    return dec, pivots, None


def tree_body(dec, pivots, names, kind="dp", ind="        "):
    """(declarations, statements) of the recurrences of the chain (`kind` "dp" or "qp"),
    with the pivots checked at order 0, for a procedure that declares t, order, w(0:order,
    dec.ncol) and p."""
    decl, body = body_lines(dec, names, kind, 0, False, ind)
    # the pivot checks: after the order-0 statements, before the loop over the orders
    # (order 0 evaluates the chain in full: the accelerations, as the tree's right-hand
    # side does, and then nothing of order >= 1 is kept from a non-positive pivot)
    pp = _Printer(dec, names, False, kind)
    start = f"{ind}do k = 1, order - 1"
    at = body.index(start) if start in body else len(body)
    checks = []
    for lin in pivots:
        if not lin.terms:
            continue          # a constant pivot: checked positive when the tree was built
        checks += _wrap(f"pivot = {pp.lin_at(lin, 0, True)}", ind)
        checks += [f"{ind}if (.not. (pivot > 0.0_{kind})) then",
                   f"{ind}    w(1:order, :) = {quiet_nan(kind)}",
                   f"{ind}    return",
                   f"{ind}end if"]
    body = body[:at] + checks + body[at:]
    if checks:
        decl = decl + [f"{ind}real({kind}) :: pivot"]
    return decl, body


def tree_procedures(dec, pivots, names, prefix="conmech_taylor", rhs=True):
    """Fortran lines of ``prefix(t, order, w, p)`` (bind(C): the recurrences of the
    chain, with the pivots checked at order 0), ``prefix_info(info)`` ([columns of w, 0,
    size of the state, 0]) and, with `rhs`, ``prefix_rhs(t, y, dydt, p)``."""
    ind = "        "
    decl, body = tree_body(dec, pivots, names, "dp", ind)
    return first_order_procedures(prefix, dec.ncol, dec.n, max(len(dec.params), 1), decl,
                                  body, ind, rhs=rhs)


def tree_quad_routine(dec, pivots, names, cname="conmech_taylor_qp"):
    """The same recurrences in quadruple precision: ``cname(t, order, w, p)`` through C
    pointers to real128 values (:func:`conmech.symbolic.taylor.quad_entry`: t, w(0:order,
    dec.ncol), p), the pivots checked in real128."""
    decl, body = tree_body(dec, pivots, names, "qp")
    return quad_procedure(cname, dec.ncol, max(len(dec.params), 1), decl, body)


def kept_tree_decomposition(d, dec_cache):
    """:func:`tree_decomposition` of `d`, kept in `dec_cache` (one library build's) under
    "tree", the key core_part_lines keeps it under."""
    if "tree" not in dec_cache:
        dec_cache["tree"] = tree_decomposition(d)
    return dec_cache["tree"]


def tree_lines(d, names, part, dec_cache):
    """(Fortran lines, entry names, reason) of one part of a tree model's Taylor library
    (:mod:`conmech.symbolic.taylor_library`): the core and the quadruple precision part
    (``qp``); the variational part is :mod:`conmech.symbolic.taylor_tree_var`'s
    (``tree_variational_lines``), the batch part
    :mod:`conmech.symbolic.taylor_tree_batch`'s (``tree_batch_lines``)."""
    if part == "var":
        raise ValueError("the variational part of a tree: "
                         "conmech.symbolic.taylor_tree_var.tree_variational_lines")
    if part == "qp":
        dec, pivots, why = kept_tree_decomposition(d, dec_cache)
        if dec is None:
            return [], [], why
        return tree_quad_routine(dec, pivots, names), ["taylor_qp"], None
    return core_part_lines(d, part, dec_cache, "tree", tree_decomposition,
                           "trees (their first-order view runs the core)",
                           lambda dec, pivots: tree_procedures(dec, pivots, names))


def pivot_values(d, t, q, v, params):
    """The pivots D_i of the tree record `d` (the articulated inertias of its joints, in
    the chain's order) at (t, q, v) with the parameter values `params`, evaluated along
    the chain in floating point: [(the pivot's symbol, value)]. For messages."""
    chain, _ = tree_chain(d)
    defs = chain[0] if chain is not None else []
    env = {d.t: sp.Float(float(t))}
    env.update({s: sp.Float(float(x)) for s, x in zip(d.coords, q)})
    env.update({s: sp.Float(float(x)) for s, x in zip(d.speeds, v)})
    env.update({s: sp.Float(float(x)) for s, x in zip(d.params, params)})
    out = []
    for s, e in defs:
        if isinstance(e, str):
            out.append((e, float(env[s]) if s in env else math.nan))
            continue
        try:
            env[s] = sp.Float(float(sp.sympify(e).xreplace(env)))
        except (TypeError, ValueError, ZeroDivisionError):
            env[s] = sp.nan
    return out
