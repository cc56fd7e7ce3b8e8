"""Taylor's method in :func:`conmech.solve_ivp` (method "TAYLOR") for systems made by
:mod:`conmech.symbolic`:

- the recurrences written out for the run's order (no loops: the coefficients in
  registers, every multiply-add scheduled at once), compiled on first use of an order and
  cached like the model; they give the loop version's coefficients to the last bit, so a
  run takes the same steps with either. An ode system's (conmech.symbolic.taylor), and a
  generalized system's or a tree's first-order view's while its routine stays small
  (conmech.symbolic.taylor_generalized_fixed; FIXED_MAX_SOURCE_GENERALIZED,
  FIXED_MAX_SOURCE_TREE);
- compiled events (made by :func:`conmech.symbolic.event`): the events of one call are
  compiled together (cached) and located by the Taylor stepper with no Python in the loop.
"""
import math

import numpy as np

from .. import _conmech

__all__ = ["run_compiled_events", "taylor_order", "with_fixed_order"]

#: written-out code is generated up to this many history products per expansion (beyond,
#: the loop version runs: the source and its compile time grow as order**2)
FIXED_MAX_TERMS = 40000
#: a generalized system's written-out routine (a factorisation's solves and the products
#: M_j a_{k-j} at every order besides the operations) is compiled up to this many
#: characters of source: beyond, the loop routine was measured as fast or faster (a
#: solve_ivp run of the double pendulum at order 24, 83 kB of source: 1.06x-1.09x the
#: loop routine's time; of a chain of three links at order 14, 101 kB: 1.15x-1.18x; within
#: it, the double pendulum at order 18, 51 kB, 0.70x-0.75x, the cart pendulum at order 24,
#: 46 kB, 0.74x-0.76x; bench/results/taylor_generalized_fixed.md)
FIXED_MAX_SOURCE_GENERALIZED = 60000
#: the same for a tree's written-out routine (its articulated-body chain's recurrences,
#: written out as an ode system's): two point masses as a tree at orders 14 and 18 (108
#: and 165 kB, compiled in 2 s) run in 0.75x-0.76x and 0.86x the loop routine's time, at
#: order 24 (274 kB) 0.95x-0.96x; three at order 14 (285 kB, 13 s to compile) 1.16x
FIXED_MAX_SOURCE_TREE = 200000


def taylor_order(eps):
    """The order for the tolerance eps: Jorba and Zou's p0 = ceil(-ln(eps)/2 + 1) (at
    least 2) raised by max(3, p0 // 5) (conmech_taylor_core's taylor_order, the same
    arithmetic)."""
    p0 = max(2, math.ceil(-0.5*math.log(max(eps, 2.2250738585072014e-308)) + 1.0))
    return p0 + max(3, p0//5)


def with_fixed_order(fun, rtol, atol):
    """`fun` with its Taylor recurrences written out for the order the tolerances give
    (rtol, atol: scalars or the per-component arrays handed to Fortran), when `fun` is an
    ode system made by conmech.symbolic or the first-order view of a generalized one
    (conmech.ivp.taylor_generalized.first_order_view) and such a routine is made for it;
    else `fun` itself. The library is compiled once
    per model and order (cached on disk) and kept with the model; the system is kept per
    `fun` object and order (the last 64), so a repeated call is two dictionary look-ups."""
    r = float(rtol) if isinstance(rtol, float) else float(np.min(rtol))
    a = float(atol) if isinstance(atol, float) else float(np.min(atol))
    eps = max(r, 2.220446049250313e-16, a)       # the stepper's: rtol >= the round-off
    order = _ORDERS.get(eps)
    if order is None:
        order = taylor_order(eps)
        if len(_ORDERS) < 256:
            _ORDERS[eps] = order
    hit = _SYSTEMS.get((id(fun), order))
    if hit is not None and hit[0] is fun and hit[1].params is fun.params:
        return hit[1]       # (made with fun's parameter array: not after a new one)
    if fun.taylor.get("order") == order:
        return fun
    # conmech.symbolic (sympy, an optional dependency) is imported on the Taylor paths
    # only, where the system was made by it
    from ..symbolic.pipeline import model_of
    try:
        model = model_of(fun)
    except TypeError:
        return fun
    out = _fixed_system(fun, model, order)
    if len(_SYSTEMS) >= 64:       # systems made and dropped in a loop: keep the last ones
        _SYSTEMS.clear()
    _SYSTEMS[(id(fun), order)] = (fun, out)     # fun kept alive: its id stays its own
    return out


_ORDERS = {}
_SYSTEMS = {}


def _fixed_system(fun, model, order):
    d = model.derived
    if "jet" not in fun.taylor:
        return fun
    if getattr(d, "kind", None) not in ("ode", "generalized"):
        return fun
    libs = model.__dict__.setdefault("_taylor_fixed_libs", {})
    if order not in libs:
        libs[order] = _fixed_library(d, order)
    lib = libs[order]
    if lib is None:
        return fun
    return fun.with_taylor(jet_fixed=lib.conmech_taylor_fixed, order=order)


def _fixed_library(d, order):
    """The loaded library of d's recurrences written out for `order` (an ode system's, or
    a generalized system's through its first-order view: the view's work columns), or
    None when there is none (the loop version then runs)."""
    import ctypes
    from ..symbolic import build    # sympy: see with_fixed_order
    from ..symbolic.taylor import (FIXED_EXTRA_FLAGS, TaylorUnsupported, fixed_order_source,
                                   ode_decompositions)
    from ..symbolic.taylor_tree import is_tree
    if d.kind == "generalized" and is_tree(d):
        from ..symbolic.taylor_tree import tree_decomposition
        from ..symbolic.taylor_generalized_fixed import tree_fixed_source
        dec, pivots, _ = tree_decomposition(d)
        if dec is None:
            return None
        nhist = sum(_history_sums(op.kind) for op in dec.ops)
        limit = FIXED_MAX_SOURCE_TREE

        def source():
            return tree_fixed_source(d, order, (dec, pivots))
    elif d.kind == "generalized":
        from ..symbolic.taylor_generalized import generalized_decomposition
        from ..symbolic.taylor_generalized_fixed import generalized_fixed_source, \
            mass_products
        g, _ = generalized_decomposition(d)
        if g is None:
            return None
        nhist = sum(_history_sums(op.kind) for op in g.dec.ops) + mass_products(g)
        limit = FIXED_MAX_SOURCE_GENERALIZED

        def source():
            return generalized_fixed_source(d, order, g)
    else:
        dec, _, _ = ode_decompositions(d, variational=False)
        if dec is None:
            return None
        nhist = sum(_history_sums(op.kind) for op in dec.ops)
        limit = None

        def source():
            return fixed_order_source(d, order, variational=False)
    if nhist*order*(order - 1)//2 > FIXED_MAX_TERMS:
        return None
    try:
        src = source()
        if limit is not None and len(src) > limit:
            return None
        path, _ = build.compile_source(src, flags=build.FFLAGS + FIXED_EXTRA_FLAGS)
    except (TaylorUnsupported, build.CompileError):
        return None         # the loop version runs (same coefficients, a little slower)
    return ctypes.CDLL(path)


def _history_sums(kind):
    """History sums per operation of the decomposition (conmech.symbolic.taylor's
    recipes): none for linear combinations and time, two for powers and sine/cosine
    pairs, one otherwise."""
    if kind in ("lin", "time"):
        return 0
    return 2 if kind in ("pow", "sincos", "sinhcosh") else 1


def _library(fun, evs):
    from ..symbolic.pipeline import model_of    # sympy: see with_fixed_order
    from ..symbolic.taylor_events import compile_events, expressions
    model = model_of(fun)
    cache = model.__dict__.setdefault("_taylor_event_libs", {})
    exprs = expressions(evs)
    key = tuple(str(e) for e in exprs)
    if key not in cache:
        cache[key] = compile_events(model.derived, exprs)
    return cache[key]


def run_compiled_events(fun, evs, store, kw):
    """solve_ivp with compiled events: the flat call, returning (counts, form, info,
    message) like flat_solve (counts of 5)."""
    from ..symbolic.taylor_events import DEGREE
    lib = _library(fun, evs)
    name, np_, p, nspec, spec = fun._flat_args()
    args = {k: v for k, v in kw.items() if k != "method"}
    counts, form, info, message = _conmech.flat_solve_taylor(
        name, np_, p, nspec, spec, store, evaddr=lib["address"], evnw=lib["nw"],
        evdeg=DEGREE, **args)
    return counts[:5], form, info, message
