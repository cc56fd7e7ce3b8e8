"""Planar multibody trees: bodies, joints and a coordinate convention in, a compiled system
with O(n) accelerations out.

:func:`planar_tree` takes a kinematic tree of rigid bodies in the plane (each body hangs
from its parent, or from the ground, by a revolute or a prismatic joint), builds the
kinetic and potential energies from the bodies' positions and orientations, and derives
the system with the same machinery as :func:`conmech.symbolic.lagrangian_system` (mass
matrix, forces, energy, the exact Jacobian of the accelerations). In addition it generates
``conmech_accel(t, q, v, a, p)``: the accelerations a = M^-1 Q by Featherstone's
articulated-body algorithm (ABA) as straight-line code, O(n) operations for n bodies (one
sine and cosine per revolute joint, one division per joint), which the right-hand side of
the compiled system uses instead of factorising M.

Frames: every body has a frame; a body's centre of mass ``com`` is given in its own frame.
The frame of a body with a revolute joint is the frame of its parent (the ground frame for
the root bodies), moved to the joint location ``at`` (in the parent's frame) and rotated by
the joint angle; with a prismatic joint it is the parent's frame moved to ``at + s * axis``
(``at`` and ``axis`` in the parent's frame, ``s`` the coordinate; the orientation is the
parent's). The coordinate of a revolute joint is the angle relative to the parent
(``coordinates="relative"``, the robotics convention) or the body's angle measured from the
ground frame (``coordinates="absolute"``, the convention of the lecture notes and of PyDy's
chains).

Algorithm (Featherstone, Rigid Body Dynamics Algorithms, ch. 7, with planar spatial vectors
[omega, v_x, v_y]): a forward pass for the velocities and bias accelerations, a backward
pass for the articulated inertias IA_i and bias forces pA_i (D_i = S_i^T IA_i S_i, the
articulated inertia of joint i, is checked positive: otherwise the output is not finite
and the integration stops with success=False), a forward pass for the accelerations;
gravity enters as the acceleration of the ground. For absolute coordinates the relative
rates are q'_i - q'_k (k the nearest revolute ancestor), the generalized forces are mapped
by tau_rel = L^-T Q (subtree sums) and the accelerations accumulated in the last pass.
"""
import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.physics.mechanics import dynamicsymbols

from .lagrangian import derive_lagrangian
from .tree_aba import _aba
from .tree_print import aba_lines, accel_procedure  # noqa: F401

__all__ = ["Body", "build_tree", "derive_tree"]

_JOINTS = ("revolute", "prismatic")


class Body:
    """One rigid body of a planar tree.

    Parameters
    ----------
    name : str
        The body's name (unique in the tree).
    parent : str or None
        The parent body's name; None: the body is jointed to the ground.
    joint : {"revolute", "prismatic"}
        The joint to the parent.
    q : sympy dynamicsymbol
        The joint's coordinate (a function of t), e.g. ``dynamicsymbols("th1")``.
    at : pair of expressions
        The joint's location in the parent's frame (parameters and numbers).
    axis : pair of expressions
        Prismatic joints: the direction of the slide in the parent's frame (the
        displacement is ``q * axis``).
    mass : expression
        The body's mass (>= 0).
    com : pair of expressions
        The centre of mass in the body's own frame.
    inertia : expression
        The moment of inertia about the centre of mass (0 for a point mass).
    """

    __slots__ = ("name", "parent", "joint", "q", "at", "axis", "mass", "com", "inertia")

    def __init__(self, name, parent=None, joint="revolute", q=None, at=(0, 0), axis=(1, 0),
                 mass=0, com=(0, 0), inertia=0):
        self.name, self.parent, self.joint, self.q = name, parent, joint, q
        self.at, self.axis, self.mass, self.com, self.inertia = at, axis, mass, com, inertia

    def __repr__(self):
        return (f"Body({self.name!r}, parent={self.parent!r}, joint={self.joint!r}, "
                f"q={self.q}, mass={self.mass})")


def _components(x, k, what, kind):
    """The k components of the vector x as expressions; `kind` says what x must be."""
    try:
        seq = list(x)
    except TypeError:
        raise TypeError(f"{what} must be {kind}") from None
    if len(seq) != k:
        raise ValueError(f"{what} must have {k} components, got {len(seq)}")
    return [_expr(e, what) for e in seq]


def _pair(x, what):
    return _components(x, 2, what, "a pair of expressions (x, y)")


def _expr(e, what):
    try:
        return sp.sympify(e, strict=True) if not isinstance(e, sp.Basic) else e
    except (sp.SympifyError, TypeError):
        raise TypeError(f"{what}: {e!r} is not a sympy expression or a number") from None


def _check_tree(bodies, t, cls=None):
    """Validated bodies (records of class `cls`, default Body) in topological order (parents
    first) and the coordinate list in the given order."""
    cls = Body if cls is None else cls
    if isinstance(bodies, cls):
        bodies = [bodies]
    bodies = list(bodies)
    if not bodies:
        raise ValueError("a tree needs at least one body")
    names, coords = {}, []
    for b in bodies:
        if not isinstance(b, cls):
            raise TypeError(f"bodies must be conmech.symbolic.{cls.__name__} records, got "
                            f"{type(b).__name__}")
        if not isinstance(b.name, str) or not b.name:
            raise TypeError("a body's name must be a non-empty string")
        if b.name in names:
            raise ValueError(f"body '{b.name}' given twice")
        names[b.name] = b
        if b.joint not in _JOINTS:
            raise ValueError(f"body '{b.name}': unknown joint {b.joint!r} (revolute or "
                             "prismatic)")
        if not (isinstance(b.q, AppliedUndef) and b.q.args == (t,)):
            raise TypeError(f"body '{b.name}': q must be a dynamicsymbol (a function of t), "
                            f"got {b.q!r}")
        if b.q in coords:
            raise ValueError(f"coordinate {b.q} is used by two bodies")
        coords.append(b.q)
    for b in bodies:
        if b.parent is not None and b.parent not in names:
            raise ValueError(f"body '{b.name}': unknown parent {b.parent!r}")
        if b.parent == b.name:
            raise ValueError(f"body '{b.name}' is its own parent")
    order, state = [], {}

    def visit(b, path):
        if state.get(b.name) == 2:
            return
        if state.get(b.name) == 1:
            raise ValueError("the bodies form a cycle: " + " -> ".join(path + [b.name]))
        state[b.name] = 1
        if b.parent is not None:
            visit(names[b.parent], path + [b.name])
        state[b.name] = 2
        order.append(b)
    for b in bodies:
        visit(b, [])
    return order, coords


def _rot(th, x, y):
    c, s = sp.cos(th), sp.sin(th)
    return c*x - s*y, s*x + c*y


def build_tree(bodies, gravity=(0, 0), forces=None, coordinates="relative", lazy=False):
    """The pieces of a planar tree without compiling: a dict with ``L``, ``T``, ``U`` (in
    the dynamicsymbols; with ``lazy`` None, computed by ``energies()`` when needed), ``q``
    (coordinates in the order of ``bodies``), ``forces`` (one generalized force per
    coordinate), and ``aba(qs, vs)``, a function that returns the articulated-body
    algorithm's straight-line code (defs, accelerations) in plain symbols qs, vs (one per
    coordinate). Used by :func:`planar_tree`; useful to inspect T and U."""
    if coordinates not in ("relative", "absolute"):
        raise ValueError(f"coordinates must be 'relative' or 'absolute', got {coordinates!r}")
    t = dynamicsymbols._t
    bodies = [bodies] if isinstance(bodies, Body) else list(bodies)
    order, coords = _check_tree(bodies, t)
    index = {b.name: i for i, b in enumerate(bodies)}
    g = _pair(gravity, "gravity")
    data = {}
    for b in order:
        data[b.name] = (_pair(b.at, f"body '{b.name}': at"),
                        _pair(b.axis, f"body '{b.name}': axis"),
                        _expr(b.mass, f"body '{b.name}': mass"),
                        _pair(b.com, f"body '{b.name}': com"),
                        _expr(b.inertia, f"body '{b.name}': inertia"))
        for e in [*data[b.name][0], *data[b.name][1], data[b.name][2], *data[b.name][3],
                  data[b.name][4]]:
            if e.has(t) or e.atoms(AppliedUndef):
                raise ValueError(f"body '{b.name}': the geometry, mass and inertia must "
                                 f"depend on parameters only, got {e}")
        if b.joint == "prismatic" and all(x == 0 for x in data[b.name][1]):
            raise ValueError(f"body '{b.name}': the prismatic joint's axis is zero")
    for e in g:
        if e.has(t) or e.atoms(AppliedUndef):
            raise ValueError(f"gravity must depend on parameters only, got {e}")
    fl = _force_list(forces, coords, index)
    absolute = coordinates == "absolute"
    # positions -> T, U in the compact form: a point's position is sum_phi R(phi) W_phi
    # over the distinct frame angles phi on its path (W_phi: the offsets in that frame),
    # so |r'|^2 = sum |U_phi|^2 + 2 sum_{phi<psi} [cos(psi - phi) U_phi.U_psi
    # - sin(psi - phi) U_phi x U_psi] with U_phi = phi' J W_phi + W_phi' (J: +90 deg):
    # the cosines of angle differences directly, as the lecture notes write T
    def energies():
        pose, acc = {}, {}
        T = U = sp.Integer(0)
        for b in order:
            at, axis, m, com, inertia = data[b.name]
            th_p, segs = (sp.Integer(0), {}) if b.parent is None else pose[b.parent]
            segs = dict(segs)
            q = b.q
            off = at if b.joint == "revolute" else [at[0] + q*axis[0], at[1] + q*axis[1]]
            w = segs.get(th_p, (0, 0))
            segs[th_p] = (w[0] + off[0], w[1] + off[1])
            th = (q if absolute else th_p + q) if b.joint == "revolute" else th_p
            pose[b.name] = (th, segs)
            if m != 0:
                pts = dict(segs)
                w = pts.get(th, (0, 0))
                pts[th] = (w[0] + com[0], w[1] + com[1])
                _speed2(pts, t, m, acc)
                for phi, (wx, wy) in pts.items():
                    c, s_ = sp.cos(phi), sp.sin(phi)
                    # g . R(phi) W = cos(phi) g.W - sin(phi) g x W
                    U -= m*(c*(g[0]*wx + g[1]*wy) - s_*(g[0]*wy - g[1]*wx))
            if inertia != 0:
                T += inertia*th.diff(t)**2/2
        T += _kinetic(acc)
        return T, U

    def aba(qs, vs):
        tau = _forces_at(fl, coords, qs, vs)
        return _aba(order, index, data, qs, vs, tau, g, absolute)

    T = U = None
    if not lazy:
        T, U = energies()
    return dict(L=None if lazy else T - U, T=T, U=U, energies=energies, q=coords, forces=fl,
                aba=aba, order=order, data=data, gravity=g)


def _forces_at(fl, coords, qs, vs):
    """The generalized forces `fl` with the coordinates and their rates replaced by the
    symbols `qs`, `vs` of the generated code (a force that still depends on another
    function of t, or on an acceleration, is refused)."""
    t = dynamicsymbols._t
    sub = {qi.diff(t): vs[i] for i, qi in enumerate(coords)}
    sub.update({qi: qs[i] for i, qi in enumerate(coords)})
    tau = [e.subs(sub) for e in fl]
    for e in tau:
        if e.atoms(AppliedUndef) or e.atoms(sp.Derivative):
            raise ValueError(f"forces: {e} depends on a function of t that is not a "
                             "coordinate (or on an acceleration)")
    return tau


def _force_list(forces, coords, index):
    """One generalized force per coordinate from a list or a dict {body name or coordinate:
    force} (None: no forces)."""
    n = len(coords)
    if forces is None:
        fl = [sp.Integer(0)]*n
    elif isinstance(forces, dict):
        fl = [sp.Integer(0)]*n
        for key, val in forces.items():
            if isinstance(key, str) and key in index:
                i = index[key]
            elif key in coords:
                i = coords.index(key)
            else:
                raise ValueError(f"forces: {key!r} is neither a body name nor a coordinate")
            fl[i] = fl[i] + _expr(val, "forces")
    else:
        fl = [_expr(e, "forces") for e in forces]
        if len(fl) != n:
            raise ValueError(f"forces has {len(fl)} components for {n} coordinates")
    return fl


def _speed2(pts, t, m, acc):
    """Add the terms of m |r'|^2 of r = sum_phi R(phi) W_phi (`pts`: {phi: (W_x, W_y)}) to
    `acc` ({(phi, psi): [terms of cos(psi - phi)], [terms of sin(psi - phi)]}, with the
    squares under (phi, phi)); the sums are built once at the end (fast for long chains)."""
    items = sorted(pts.items(), key=lambda kv: sp.default_sort_key(kv[0]))
    us = []
    for phi, (wx, wy) in items:
        wx, wy = sp.sympify(wx), sp.sympify(wy)
        phid = sp.sympify(phi).diff(t)
        us.append((phi, -phid*wy + wx.diff(t), phid*wx + wy.diff(t)))
    for i, (phi, ax, ay) in enumerate(us):
        acc.setdefault((phi, phi), ([], []))[0].append(m*(ax**2 + ay**2))
        for psi, bx, by in us[i + 1:]:
            c, s_ = acc.setdefault((phi, psi), ([], []))
            c.append(2*m*(ax*bx + ay*by))
            s_.append(-2*m*(ax*by - ay*bx))


def _kinetic(acc):
    """sum over `acc` (see _speed2) of cos(psi - phi) (sum) + sin(psi - phi) (sum), / 2."""
    out = []
    for (phi, psi), (c, s_) in acc.items():
        if phi == psi:
            out.append(sp.Add(*c)/2)
        else:
            d = psi - phi
            out.append(sp.cos(d)*sp.Add(*c)/2 + sp.sin(d)*sp.Add(*s_)/2)
    return sp.Add(*out)


def _check_leaves(order, data, params):
    """Clear errors for bodies that make M singular or indefinite, where the parameter values
    decide it (a leaf without mass, or without inertia about its revolute joint)."""
    vals = {}
    for k, v in (params or {}).items() if isinstance(params, dict) else ():
        name = k.name if isinstance(k, sp.Symbol) else str(k)
        vals[name] = v

    def num(e):
        e = e.subs({s: vals[s.name] for s in e.free_symbols if s.name in vals})
        return float(e) if e.is_number else None
    has_child = {b.parent for b in order}
    for b in order:
        at, axis, m, com, inertia = data[b.name]
        mv, iv = num(m), num(inertia)
        if mv is not None and mv < 0:
            raise ValueError(f"body '{b.name}': negative mass {mv}")
        if iv is not None and iv < 0:
            raise ValueError(f"body '{b.name}': negative inertia {iv}")
        if b.name in has_child:
            continue
        if b.joint == "prismatic" and mv == 0:
            raise ValueError(f"body '{b.name}' is a leaf of zero mass on a prismatic joint: "
                             "the mass matrix would be singular")
        if b.joint == "revolute":
            r2 = num(com[0]**2 + com[1]**2)
            if mv is not None and iv is not None and r2 is not None and iv + mv*r2 == 0:
                raise ValueError(f"body '{b.name}' is a leaf without inertia about its "
                                 "revolute joint (zero mass, or a point mass on the joint, "
                                 "and zero inertia): the mass matrix would be singular")


def _derive(parts, params, simplify, jacobian):
    """The Derived record of the tree's Lagrangian with the ABA code attached (d.aba)."""
    L = parts["L"]
    if L is None:
        T, U = parts["energies"]()
        L = T - U
    d = derive_lagrangian(L, parts["q"], params, parts["forces"], None, simplify,
                          bool(jacobian))
    n = d.n
    qs = [sp.Dummy(f"q{i}", real=True) for i in range(n)]
    vs = [sp.Dummy(f"v{i}", real=True) for i in range(n)]
    defs, acc = parts["aba"](qs, vs)
    sub = {**dict(zip(qs, d.coords)), **dict(zip(vs, d.speeds))}
    byname = dict(zip(d.param_names, d.params))
    known = set(d.coords) | set(d.speeds) | {d.t} | {s for s, _ in defs}
    exprs = [e for _, e in defs if not isinstance(e, str)] + acc
    for s in set().union(*[sp.sympify(e).free_symbols for e in exprs]):
        if s in sub or s in known:
            continue
        if s.name in byname:
            sub[s] = byname[s.name]
        elif s.name == d.t.name:
            sub[s] = d.t
        else:
            raise ValueError(f"unknown symbol '{s}': neither t, a coordinate nor a "
                             "parameter with a value")
    d.aba = ([(s, e if isinstance(e, str) else sp.sympify(e).xreplace(sub))
              for s, e in defs], [sp.sympify(e).xreplace(sub) for e in acc])
    return d


def derive_tree(bodies, params=None, gravity=(0, 0), forces=None, coordinates="relative",
                simplify="auto", jacobian=True):
    """The derived record (:class:`~conmech.symbolic.derive.Derived`) of a planar tree,
    without compiling: what :func:`planar_tree` compiles, and what
    ``python -m conmech.symbolic emit`` writes as a standalone Fortran module (whose
    right-hand side is then the articulated-body algorithm). Arguments as
    :func:`planar_tree`."""
    parts = build_tree(bodies, gravity, forces, coordinates)
    _check_leaves(parts["order"], parts["data"], params)
    return _derive(parts, params, simplify, jacobian)

