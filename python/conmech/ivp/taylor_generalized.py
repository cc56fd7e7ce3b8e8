"""Taylor's method for generalized systems M(t, q) q'' = Q(t, q, q') made by
:mod:`conmech.symbolic` (``lagrangian_system`` with a Lagrangian or with ``mass=`` and
``forces=``, ``dalembert_system``, and the trees ``planar_tree``, ``spatial_tree``,
``from_urdf``): the run integrates the system's first-order view y = [q; v], an ode
system whose Taylor coefficients come from the recurrences of M and Q and the linear
solve order by order (:mod:`conmech.symbolic.taylor_generalized`), or for a tree from the
recurrences of its articulated-body code, definition by definition
(:mod:`conmech.symbolic.taylor_tree`); compiled on first need and cached like an ode
model's Taylor library. An ensemble (``ensemble.solve(method="TAYLOR")``) of the view runs
its members in SIMD lanes through the batch routine of
:mod:`conmech.symbolic.taylor_generalized_batch`, or of :mod:`conmech.symbolic.taylor_tree_batch`
for a tree (:func:`batch_entries`; for any number of degrees of freedom: written out in
scalars up to 8, the loop form's arrays per lane beyond).

:func:`first_order_view` gives the view (the same parameters; the model behind it, so that
the Taylor paths of ode systems apply to it); :func:`name_the_mass_matrix` adds to a failed
run's message what the mass matrix is at the last accepted point (a singular or indefinite
M makes the coefficients non-finite, which the stepper reports as a non-finite right-hand
side or a step size too small), and for a tree which joint's articulated inertia (the
pivot of its articulated-body algorithm) is not positive there; :func:`mass_note` is that
text for a given point (an ensemble's failed member)."""
import numpy as np

from .._core.model import model_of

__all__ = ["first_order_view", "name_the_mass_matrix", "batch_entries", "mass_note"]


def _model(fun):
    """The symbolic model of a generalized system, or None for any other system."""
    if getattr(fun, "kind", None) != "generalized":
        return None
    try:
        model = model_of(fun)
    except TypeError:
        return None
    return model if getattr(model.derived, "kind", None) == "generalized" else None


def first_order_view(fun, *parts):
    """The first-order view (an ode system of dimension 2 ndof with Taylor coefficients)
    of a generalized system made by conmech.symbolic, with fun's parameters; any other
    system is returned as it is. `parts`: further parts of the Taylor library the view
    carries ("var": the variational system's recurrences, for stm(method="TAYLOR"); "qp":
    quadruple precision, for conmech.symbolic.taylor_quad.reference).
    ValueError with the reason when the generalized system's accelerations (or a part
    asked for) have no Taylor recurrences (a non-smooth expression, an asymmetric mass
    matrix)."""
    model = _model(fun)
    if model is None:
        return fun
    # the view of fun kept with the model (the last _VIEWS systems), while fun keeps its
    # parameter array: a repeated call is a look-up, and the view's written-out
    # recurrences (conmech.ivp.taylor.with_fixed_order) are found by its identity
    views = model.__dict__.setdefault("_taylor_views", {})
    if not parts:
        hit = views.get(id(fun))
        if hit is not None and hit[0] is fun and hit[1].params is fun.params:
            return hit[1]
    from .. import compiled
    from ..symbolic.taylor_library import lazy_taylor
    tay = lazy_taylor(model).get(*parts)
    if not tay:
        raise ValueError("method TAYLOR: the generalized system M(q) q'' = Q has no Taylor "
                         f"recurrences: {getattr(model, 'taylor_reason', None) or 'unknown'}"
                         ". Use method DOP853 or VERNER98")
    for part, what in (("var", "the variational system"), ("qp", "quadruple precision")):
        if part in parts and part not in tay:
            why = model.__dict__.get("_taylor_parts", {}).get(part, (None, None, None))[2]
            raise ValueError(f"method TAYLOR: {what} of the generalized system M(q) q'' = Q "
                             f"has no Taylor recurrences: {why or 'unknown'}")
    base = model.__dict__.get("_taylor_view")
    if base is None:
        base = compiled.ode_system(
            2*model.derived.n, tay["rhs"], params=tuple(fun.params),
            param_names=tuple(fun.param_names), keep=model, name=fun.name,
            taylor={"jet": tay["jet"], "nw": tay["nw"]})
        model._taylor_view = base
    new = {k: tay[k] for k in ("var", "nw_var", "qp") if k in tay and k not in base.taylor}
    if new:
        # the variational or quadruple-precision routine joins the view's entries (its
        # spec is shared by every view of the model; the library stays loaded with it)
        base.taylor.update(new)
        compiled._taylor_spec(base.spec, base.taylor)
    # fun's parameter array itself: values changed in place are read, as fun's own
    view = compiled.CompiledSystem(base.name, "ode", base.spec, fun.params, base.param_names,
                                   base._keep, base.taylor)
    if not parts:
        if len(views) >= _VIEWS:
            views.clear()
        views[id(fun)] = (fun, view)    # fun kept alive: its id stays its own
    return view


_VIEWS = 16


def batch_entries(fun, lanes=None):
    """The entries (``batch``, ``width``, ``batch_run``) of the batch library of a
    generalized system made by conmech.symbolic (its first-order view's coefficients in
    `lanes` SIMD lanes, None: the machine's width, and the propagator,
    :mod:`conmech.symbolic.taylor_generalized_batch`, for a tree
    :mod:`conmech.symbolic.taylor_tree_batch`), compiled on first need; None when it has
    none (any other system, or no batch recurrences: the ensemble then runs member by
    member)."""
    model = _model(fun)
    if model is None:
        return None
    from ..symbolic.taylor_library import batch_entries as library_batch
    tay = library_batch(model, lanes)
    return tay if tay and tay.get("batch_run") is not None else None


def mass_note(fun, t, y, params=None):
    """" (method TAYLOR on M(q) q'' = Q: the mass matrix M(q) at the last accepted point,
    t = ..., ...)": the state of fun's mass matrix at (t, y), y = [q; v] (not finite, not
    positive definite, or its extreme eigenvalues), with fun's parameters or `params`,
    and for a tree its first pivot that is not positive; "" for any other system or when
    M cannot be evaluated."""
    model = _model(fun)
    if model is None:
        return ""
    n = model.derived.n
    y = np.array(y, dtype=float)
    p = np.asarray(fun.params if params is None else params, dtype=float)
    try:
        m = model.call("mass", float(t), y[:n], params=p)
    except (KeyError, ValueError, TypeError, AttributeError):
        return ""
    m = np.array(m, dtype=float).reshape(n, n)
    if not np.all(np.isfinite(m)):
        note = "is not finite"
    else:
        ev = np.linalg.eigvalsh(0.5*(m + m.T))
        if ev[0] > 0:
            note = f"has smallest eigenvalue {ev[0]:.3g} and largest {ev[-1]:.3g}"
        else:
            note = "is not positive definite (singular or indefinite)"
    return (f" (method TAYLOR on M(q) q'' = Q: the mass matrix M(q) at the last accepted "
            f"point, t = {float(t):.6g}, {note}{_pivots(model, float(t), y, p)})")


def name_the_mass_matrix(fun, res):
    """`res` (a failed run of fun's first-order view) with its message completed by the
    state of the mass matrix at the last accepted point: not positive definite there, or
    its condition number."""
    model = _model(fun)
    if model is None or res.success or res.status != -1 or not np.size(res.t):
        return res
    note = mass_note(fun, res.t[-1], res.y[:, -1])
    if note:
        res.message = f"{res.message}{note}"
    return res


def _pivots(model, t, y, p):
    """For a tree: "; the articulated inertia of the joint of body 'b' is x, not
    positive ..." for the first pivot of its articulated-body algorithm that is not
    positive at (t, y), the last accepted point (empty if none is)."""
    from ..symbolic.taylor_tree import is_tree, pivot_values
    d = model.derived
    if not is_tree(d):
        return ""
    n = d.n
    try:
        vals = pivot_values(d, t, y[:n], y[n:2*n], p)
    except (ValueError, TypeError, AttributeError):
        return ""
    # the first in the chain's order (leaves first): the pivots of its ancestors are then
    # not finite
    for marker, x in vals:
        if not x > 0:
            body = marker.split(": ", 1)[1] if ": " in marker else "a body"
            return (f"; the articulated inertia of the joint of {body} is {x:.6g}, not "
                    "positive (the pivot of the articulated-body algorithm)")
    return ""
