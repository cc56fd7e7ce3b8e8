"""Taylor coefficients of the variational system of a symbolic tree: the state transition
matrix Phi of its first-order view y = [q; v] by the same recurrences as the state, through
forward-mode differentiation of its articulated-body chain.

Along the solution Phi' = J Phi with J = [[0, I], [da/dq, da/dv]]. The accelerations a are
the last values of the chain s_i = e_i(args) (:func:`conmech.symbolic.taylor_tree.tree_chain`),
so the variation of every definition along a column c of Phi follows the chain rule, one
definition at a time:

    ds_i = sum_{a in args} (de_i/da) da,    dq_k = Phi[k, c],  dv_k = Phi[n + k, c],

t and the parameters fixed; column c of J Phi is [Phi[n:2n, c]; da_1 .. da_n]. The
tangents are further definitions of the chain, decomposed by the same machinery
(:mod:`conmech.symbolic.taylor_decompose`): each partial derivative de_i/da that is not a
constant is one definition shared by the 2n columns (the derivative of an inverse D^-1 of a
pivot through the inverse itself, -(D^-1)^2; of a sine through the chain's cosine, which
the decomposition shares with its sine), and each tangent one linear combination of
products, partial times tangent. The cost per column is a multiple of the chain's, O(n) for
n bodies, with no mass matrix: O(n^2) for the 2n columns against the O(n^3) of
differentiating M a = Q (:mod:`conmech.symbolic.taylor_generalized_var`), which a tree does
not have as expressions.

The routine is ``conmech_taylor_var(t, order, w, p)`` with the work-array convention of an
ode system's variational routine (w(0, 1:m) = [y; vec(Phi)] on entry, m = 2n (2n + 1), Phi
by columns) and the pivots checked at order 0 as the core routine checks them, and
``conmech_taylor_var_info``.
"""
import sympy as sp

from .taylor_decompose import TaylorUnsupported, decompose
from .taylor_tree import kept_tree_decomposition, tree_chain, tree_procedures

__all__ = ["tangent_chain", "tree_variational_decomposition", "tree_variational_lines"]


def _partial(e, a, s):
    """de/da for the definition s = e (an inverse e = b**-1 through s itself; s None: an
    expression with no symbol of its own)."""
    if s is not None and e.is_Pow and e.exp == -1:
        return -s**2*sp.diff(e.base, a)
    return sp.diff(e, a)


def tangent_chain(defs, outputs, coords, speeds, columns):
    """(definitions, tangents) of the forward-mode differentiation of the chain `defs`
    (with its outputs `outputs`, expressions in the chain's symbols) in the directions
    `columns`: [(tangents of coords, tangents of speeds)], Symbols or expressions. The
    definitions are the chain's (its markers kept), then the partial derivatives, then the
    tangents column by column; tangents[c][i] is the tangent of outputs[i] along column c."""
    var = set(coords) | set(speeds)
    pos = {x: i for i, x in enumerate(list(coords) + list(speeds))}
    out = list(defs)
    partials = {}            # definition symbol -> [(argument, coefficient, factor)]
    named = {}               # a partial's variable factor -> its definition symbol

    def factors(e, s):
        """[(argument, constant coefficient, variable factor)] of e's partials."""
        args = sorted(e.free_symbols & var, key=pos.__getitem__)
        terms = []
        for a in args:
            p = _partial(e, a, s)
            if p == 0:
                continue
            c, f = p.as_independent(*var, as_Add=False)
            if not (f == 1 or f.is_Symbol):
                if f not in named:
                    named[f] = sp.Dummy(f"dp{len(named) + 1}", real=True)
                    out.append((named[f], f))
                f = named[f]
            terms.append((a, c, f))
        return terms
    for s, e in defs:
        if isinstance(e, str):
            continue
        e = sp.sympify(e)
        terms = factors(e, s)
        if terms:
            pos[s] = len(pos)
            var.add(s)
            partials[s] = terms
    tails = [(o, factors(sp.sympify(o), None)) for o in outputs]
    tangents = []
    for c, (dq, dv) in enumerate(columns):
        tan = dict(zip(coords, dq))
        tan.update(zip(speeds, dv))

        def combine(terms):
            return sp.Add(*[k*f*tan[a] for a, k, f in terms if tan.get(a, 0) != 0])
        for s, e in defs:
            if isinstance(e, str) or s not in partials:
                continue
            x = combine(partials[s])
            if x == 0 or x.is_Symbol or (x.is_Mul and len(x.args) == 2 and
                                         x.args[0].is_Number and x.args[1].is_Symbol):
                tan[s] = x
            else:
                tan[s] = sp.Dummy(f"dt{c + 1}_{len(out)}", real=True)
                out.append((tan[s], x))
        tangents.append([combine(terms) for _, terms in tails])
    return out, tangents


def tree_variational_decomposition(d):
    """(decomposition of [f; J Phi] in the state [q; v; vec(Phi)], pivot forms, None) of
    the tree record `d`, or (None, None, reason) as
    :func:`conmech.symbolic.taylor_tree.tree_decomposition`."""
    chain, why = tree_chain(d)
    if chain is None:
        return None, None, why
    defs, acc = chain
    n, m = d.n, 2*d.n
    coords, speeds = list(d.coords), list(d.speeds)
    phi = [sp.Dummy(f"phi{r + 1}_{c + 1}", real=True) for c in range(m) for r in range(m)]
    columns = [(phi[c*m:c*m + n], phi[c*m + n:(c + 1)*m]) for c in range(m)]
    try:
        defs, tangents = tangent_chain(defs, acc, coords, speeds, columns)
        outputs = speeds + list(acc)
        for c in range(m):
            outputs += phi[c*m + n:(c + 1)*m] + tangents[c]
        dec = decompose(outputs, coords + speeds + phi, d.t, d.params, defs=defs)
    except TaylorUnsupported as exc:
        return None, None, str(exc)
    pivots = [dec._build(s) for s, e in defs if isinstance(e, str)]
    return dec, pivots, None


def tree_variational_lines(d, names, dec_cache):
    """(Fortran lines, entry names, reason) of the variational part ("var") of a tree
    model's Taylor library (conmech.symbolic.taylor_library)."""
    tree, _, why = kept_tree_decomposition(d, dec_cache)    # the tree's own reason first
    if tree is None:
        return [], [], why
    if "tree_var" not in dec_cache:
        dec_cache["tree_var"] = tree_variational_decomposition(d)
    dec, pivots, why = dec_cache["tree_var"]
    if dec is None:
        return [], [], why
    return tree_procedures(dec, pivots, names, "conmech_taylor_var", rhs=False), \
        ["taylor_var", "taylor_var_info"], None
