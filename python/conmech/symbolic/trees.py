"""The compiled systems of kinematic trees: :func:`planar_tree` and :func:`spatial_tree` check
the bodies (:mod:`conmech.symbolic.tree`, :mod:`conmech.symbolic.spatial`), look the
description up in the cache, and derive by the recursive algorithms
(:mod:`conmech.symbolic.recursive`, the default) or from the Lagrangian, then compile through
the derive-compile-cache pipeline."""
import sympy as sp

from .description import recursive_version, tree_description_key
from .description_lookup import description_hit
from .loops import Loop, PointForce
from .pipeline import _construct, _tup
from .recursive import derive_recursive
from .spatial import _check_bodies, build_spatial_tree
from .tree import _check_leaves, _derive, build_tree

__all__ = ["planar_tree", "spatial_tree"]


def planar_tree(bodies, params=None, gravity=(0, 0), forces=None, coordinates="relative", *,
                loops=None, point_forces=None, method="recursive", simplify="auto",
                jacobian=True, flags=None, model_only=False):
    """A compiled planar multibody tree (see the module docstring for frames and
    conventions).

    Parameters
    ----------
    bodies : list of Body
        The bodies; the coordinates are their ``q`` in this order.
    params : dict
        {Symbol or name: value}: every symbol of the geometry, masses, gravity and forces.
        Run-time values: ``system.with_params(...)`` does not recompile.
    gravity : pair of expressions
        The gravitational acceleration in the ground frame, e.g. ``(0, -g)``.
    forces : list or dict, optional
        Generalized forces (joint torques, dampers, springs, motors) in t, the coordinates
        and their derivatives: one per coordinate, or {body name or coordinate: force}.
        With absolute coordinates they are the generalized forces of the absolute angles.
    coordinates : {"relative", "absolute"}
        Revolute joints' angles relative to the parent, or the bodies' angles from the
        ground frame (prismatic coordinates are the slide in both).
    loops : list of Loop, optional
        Joints that close kinematic loops (:class:`conmech.symbolic.Loop`: revolute or
        prismatic). The system is then a constrained system in the tree's coordinates for
        :func:`conmech.constrained.solve` (see :mod:`conmech.symbolic.loops`).
    point_forces : list of PointForce, optional
        Forces at points of bodies (:class:`conmech.symbolic.PointForce`), mapped through
        the points' Jacobians.
    method : {"recursive", "lagrangian"}
        "recursive" (default): M, Q and the exact Jacobian from the recursive algorithms
        (:mod:`conmech.symbolic.recursive`; construction linear in the number of bodies);
        "lagrangian": from T and U by the Lagrangian derivation (no loops or point forces).
    simplify, jacobian, flags, model_only
        As in :func:`conmech.symbolic.lagrangian_system` (``simplify``: Lagrangian route
        only).

    Returns
    -------
    conmech.compiled.CompiledSystem
        A system in generalized coordinates, state y = [q, q'], whose right-hand side uses
        the articulated-body algorithm; mass matrix, forces, energy and the exact Jacobian
        come from the recursive algorithms (or the Lagrangian); with ``loops`` a
        ``conmech.compiled.CompiledConstrained`` (``model_only=True``: the
        :class:`CompiledModel`).

    Examples
    --------
    A double pendulum of point masses (absolute angles from the downward vertical)::

        th1, th2 = dynamicsymbols("th1 th2")
        m, l, g = sp.symbols("m l g")
        bodies = [Body("a", None, "revolute", th1, mass=m, com=(0, -l)),
                  Body("b", "a", "revolute", th2, at=(0, -l), mass=m, com=(0, -l))]
        sys = planar_tree(bodies, {m: 1, l: 1, g: 9.81}, gravity=(0, -g),
                          coordinates="absolute")
    """
    # a second construction of the same description loads the model, deriving nothing
    dkey = tree_description_key("tree", bodies, params, gravity, forces, loops,
                                point_forces, (coordinates, method, simplify, jacobian), flags)
    hit = description_hit(dkey, flags, model_only, params or {})
    if hit is not None:
        return hit
    parts = build_tree(bodies, gravity, forces, coordinates, lazy=True)
    _check_leaves(parts["order"], parts["data"], params)
    q = parts["q"]
    method, extra = _method_key(method, loops, point_forces)
    if method == "recursive":

        def derive():
            return derive_recursive(parts, params, planar=True,
                                    absolute=coordinates == "absolute", loops=loops,
                                    jacobian=jacobian, point_forces=point_forces)
    else:
        def derive():
            return _derive(parts, params, simplify, jacobian)

    body_key = sp.Tuple(*[sp.Tuple(*parts["data"][b.name][0], *parts["data"][b.name][1],
                                   parts["data"][b.name][2], *parts["data"][b.name][3],
                                   parts["data"][b.name][4]) for b in parts["order"]])
    topo = tuple((b.name, b.parent, b.joint) for b in parts["order"])
    # the key: the description (T and U follow from it; built only on a cache miss)
    return _construct("tree", [_tup(q), _tup(parts["forces"]), _tup(parts["gravity"]),
                               body_key] + extra, params,
                      (coordinates, simplify, bool(jacobian), topo, method) + _loop_names(
                          loops, point_forces), derive, flags, model_only, dkey)


def _method_key(method, loops, point_forces):
    """The checked method and the loops' and point forces' expressions for the cache key."""
    if method not in ("recursive", "lagrangian"):
        raise ValueError(f"method must be 'recursive' or 'lagrangian', got {method!r}")
    if method == "lagrangian" and (loops or point_forces):
        raise ValueError("loops and point forces need method='recursive'")
    extra = []
    for x in _as_list(loops, Loop):
        if not isinstance(x, Loop):
            raise TypeError(f"loops must be conmech.symbolic.Loop records, got "
                            f"{type(x).__name__}")
    for x in _as_list(point_forces, PointForce):
        if not isinstance(x, PointForce):
            raise TypeError(f"point_forces must be conmech.symbolic.PointForce records, got "
                            f"{type(x).__name__}")
    for lp in _as_list(loops, Loop):
        extra.append(sp.Tuple(*[_tuple_of(x) for x in (lp.point_a, lp.point_b, lp.axis,
                                                        lp.axis_b, lp.angle)]))
    for pf in _as_list(point_forces, PointForce):
        extra.append(sp.Tuple(_tuple_of(pf.point), _tuple_of(pf.force)))
    if method == "recursive":
        method = "recursive"
        extra.append(sp.Symbol("recursive_" + recursive_version()))
    return method, extra


def _as_list(x, cls):
    if x is None:
        return []
    if isinstance(x, cls):
        return [x]
    try:
        return list(x)
    except TypeError:
        raise TypeError(f"expected a list of {cls.__name__} records") from None


def _tuple_of(x):
    """x (None, an expression or a sequence of them) as a sympy object for the key."""
    if x is None:
        return sp.Integer(0)
    try:
        return sp.Tuple(*[sp.sympify(e) for e in x])
    except TypeError:
        return sp.sympify(x)


def _loop_names(loops, point_forces):
    """The string parts of the loops and point forces (bodies, joints) for the key."""
    out = []
    for lp in _as_list(loops, Loop):
        out.append(("loop", repr(lp.body_a), repr(lp.body_b), repr(lp.joint),
                    repr(lp.name)))
    for pf in _as_list(point_forces, PointForce):
        out.append(("pf", repr(pf.body), repr(pf.frame)))
    return tuple(out)


def _body_key(parts):
    out = []
    for b in parts["order"]:
        at, rot, axis, m, com, Ic = parts["data"][b.name]
        out.append(sp.Tuple(*at, *rot, *axis, m, *com, *Ic))
    return sp.Tuple(*out)


def spatial_tree(bodies, params=None, gravity=(0, 0, 0), forces=None, *, loops=None,
                 point_forces=None, method="recursive", simplify="auto", jacobian=True,
                 flags=None, model_only=False, _description=None):
    """A compiled spatial multibody tree (see the module docstring of
    ``conmech.symbolic.spatial`` for frames and conventions).

    Parameters
    ----------
    bodies : list of SpatialBody
        The bodies; the coordinates are their ``q`` in this order.
    params : dict
        {Symbol or name: value}: every symbol of the geometry, masses, inertias, gravity
        and forces. Run-time values: ``system.with_params(...)`` does not recompile.
    gravity : 3 expressions
        The gravitational acceleration in the ground frame, e.g. ``(0, 0, -g)``.
    forces : list or dict, optional
        Generalized forces (joint torques or forces, dampers, springs, motors) in t, the
        coordinates and their derivatives: one per coordinate, or {body name or
        coordinate: force}.
    loops : list of Loop, optional
        Joints that close kinematic loops (:class:`conmech.symbolic.Loop`: spherical or
        revolute); the system is then a constrained system in the tree's coordinates.
    point_forces : list of PointForce, optional
        Forces at points of bodies, mapped through the points' Jacobians.
    method : {"recursive", "lagrangian"}
        "recursive" (default): M, Q and the exact Jacobian of the accelerations from the
        recursive algorithms (construction linear in the number of bodies); "lagrangian":
        from T and U by the Lagrangian derivation.
    simplify, jacobian, flags, model_only
        As in :func:`conmech.symbolic.lagrangian_system`.

    Returns
    -------
    conmech.compiled.CompiledSystem
        A system in generalized coordinates, state y = [q, q'], whose right-hand side uses
        the spatial articulated-body algorithm; mass matrix, forces, energy and the exact
        Jacobian (``accel_jac``: d a/d[q, v] without a LAPACK factorisation) come from the
        recursive algorithms; with ``loops`` a constrained system (``model_only=True``:
        the CompiledModel).

    Examples
    --------
    A spherical double pendulum of two links (the second joint's axis tilted)::

        q1, q2 = dynamicsymbols("q1 q2")
        m, l, g = sp.symbols("m l g")
        bodies = [SpatialBody("a", None, "revolute", q1, axis=(1, 0, 0), mass=m,
                              com=(0, 0, -l)),
                  SpatialBody("b", "a", "revolute", q2, axis=(0, 1, 0), at=(0, 0, -l),
                              mass=m, com=(0, 0, -l))]
        sys = spatial_tree(bodies, {m: 1, l: 1, g: 9.81}, gravity=(0, 0, -g))
    """
    # a second construction of the same description loads the model, deriving nothing
    if _description is None:
        _description = tree_description_key(
            "spatial_tree", bodies, params, gravity, forces, loops, point_forces,
            (method, simplify, jacobian), flags)
        hit = description_hit(_description, flags, model_only, params or {})
        if hit is not None:
            return hit
    parts = build_spatial_tree(bodies, gravity, forces, lazy=True)
    _check_bodies(parts["order"], parts["data"], params)
    method, extra = _method_key(method, loops, point_forces)
    if method == "recursive":

        def derive():
            return derive_recursive(parts, params, planar=False, loops=loops,
                                    jacobian=jacobian, point_forces=point_forces)
    else:
        def derive():
            return _derive(parts, params, simplify, jacobian)

    topo = tuple((b.name, b.parent, b.joint) for b in parts["order"])
    return _construct("spatial_tree", [_tup(parts["q"]), _tup(parts["forces"]),
                                       _tup(list(parts["gravity"])), _body_key(parts)]
                      + extra, params,
                      (simplify, bool(jacobian), topo, method)
                      + _loop_names(loops, point_forces), derive, flags, model_only,
                      _description)
