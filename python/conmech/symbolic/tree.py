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

__all__ = ["Body", "planar_tree", "build_tree", "derive_tree"]

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


def _pair(x, what):
    try:
        seq = list(x)
    except TypeError:
        raise TypeError(f"{what} must be a pair of expressions (x, y)") from None
    if len(seq) != 2:
        raise ValueError(f"{what} must have 2 components, got {len(seq)}")
    return [_expr(e, what) for e in seq]


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


class _Code:
    """Straight-line code: a list of (Dummy, expression) definitions; numbers and single
    symbols are propagated instead of defined."""

    def __init__(self):
        self.defs = []
        self.mine = set()
        self.memo = {}

    def let(self, e, name="b", force=False):
        e = sp.sympify(e)
        if force and not e.is_Number and e not in self.mine:
            pass
        elif e.is_Number or e.is_Symbol or (e.is_Mul and len(e.args) == 2 and e.args[0] == -1
                                          and e.args[1].is_Symbol):
            return e
        if e in self.memo:
            return self.memo[e]
        s = sp.Dummy(f"{name}{len(self.defs) + 1}")
        self.defs.append((s, e))
        self.mine.add(s)
        self.memo[e] = s
        return s

    def positive(self, s):
        """Mark s (a defined symbol) as a pivot that must be positive."""
        self.defs.append((s, "positive"))


def _aba(order, index, data, qs, vs, tau_user, gravity, absolute, trig=None):
    """(defs, accelerations) of the articulated-body algorithm in the plain symbols qs, vs
    (`trig`: {body name: (cos, sin) symbols} of the joint angles computed elsewhere)."""
    code = _Code()
    L = code.let
    n = len(order)
    # nearest revolute ancestor (absolute coordinates)
    byname = {b.name: b for b in order}

    def rev_anc(b):
        p = b.parent
        while p is not None and byname[p].joint != "revolute":
            p = byname[p].parent
        return p
    kin = {}
    # ---- pass 1: transforms, velocities, bias terms
    for b in order:
        i = index[b.name]
        at, axis, m, com, inertia = data[b.name]
        k = rev_anc(b) if absolute and b.joint == "revolute" else None
        qrel = qs[i] - qs[index[k]] if k is not None else qs[i]
        qd = vs[i] - vs[index[k]] if k is not None else vs[i]
        qd = L(qd, "qd")
        if b.joint == "revolute":
            if trig is not None:
                c, s = trig[b.name]
            else:
                s, c = L(sp.sin(qrel), "s"), L(sp.cos(qrel), "c")
            E = [[c, s], [-s, c]]
            rx, ry = at
            S = (1, 0, 0)
        else:
            E = [[1, 0], [0, 1]]
            rx, ry = L(at[0] + qs[i]*axis[0]), L(at[1] + qs[i]*axis[1])
            S = (0, axis[0], axis[1])
        bx = L(-E[0][0]*ry + E[0][1]*rx)
        by = L(-E[1][0]*ry + E[1][1]*rx)
        X = (bx, by, E)
        if b.parent is None:
            vp = (0, 0, 0)
        else:
            vp = kin[b.parent]["v"]
        w, vx, vy = _xm(X, vp)
        v = (L(w + S[0]*qd, "w"), L(vx + S[1]*qd, "vx"), L(vy + S[2]*qd, "vy"))
        sq = [S[0]*qd, S[1]*qd, S[2]*qd]
        cb = (0, L(v[2]*sq[0] - v[0]*sq[2]), L(-v[1]*sq[0] + v[0]*sq[1]))
        cx, cy = com
        Ic = L(inertia + m*(cx**2 + cy**2)) if m != 0 or inertia != 0 else 0
        I3 = sp.Matrix([[Ic, -m*cy, m*cx], [-m*cy, m, 0], [m*cx, 0, m]])
        h = I3*sp.Matrix(v)
        h = [L(x) for x in h]
        pA = [-v[2]*h[1] + v[1]*h[2], -v[0]*h[2], v[0]*h[1]]
        kin[b.name] = dict(X=X, S=S, v=v, c=cb, IA=I3, pA=[sp.sympify(x) for x in pA],
                           k=k, qrel=qrel)
    # ---- generalized forces of the joints
    tau = {b.name: tau_user[index[b.name]] for b in order}
    if absolute:
        for b in reversed(order):
            kb = kin[b.name]["k"]
            if kb is not None:
                tau[kb] = tau[kb] + tau[b.name]
    # ---- pass 2: articulated inertias and bias forces, leaves first
    for b in reversed(order):
        kb = kin[b.name]
        IA = kb["IA"]
        IA = sp.Matrix(3, 3, lambda r, c_: L(IA[min(r, c_), max(r, c_)], "ia"))
        pA = [L(x, "pa") for x in kb["pA"]]
        S = sp.Matrix(kb["S"])
        U = [L(x, "u") for x in IA*S]
        D = L(sum(S[j]*U[j] for j in range(3)), "d", force=True)
        if D.is_Number:
            if not D > 0:
                raise ValueError(f"body '{b.name}': the articulated inertia of its joint is "
                                 f"{D}: the mass matrix is not positive definite")
        else:
            code.positive(D)
        Dinv = L(1/D, "di")
        u = L(tau[b.name] - sum(S[j]*pA[j] for j in range(3)), "uu")
        kb.update(U=U, Dinv=Dinv, u=u)
        if b.parent is None:
            continue
        if b.joint == "revolute":    # Ia S = 0 exactly: the first row and column vanish
            Ia = sp.Matrix(3, 3, lambda r, c_: 0 if r == 0 or c_ == 0 else
                           IA[r, c_] - U[r]*U[c_]*Dinv)
        else:
            Ia = sp.Matrix(3, 3, lambda r, c_: IA[r, c_] - U[r]*U[c_]*Dinv)
        Ia = sp.Matrix(3, 3, lambda r, c_: L(Ia[min(r, c_), max(r, c_)]))
        c = kb["c"]
        uD = L(u*Dinv)
        pa = [pA[r] + sum(Ia[r, j]*c[j] for j in range(3)) + U[r]*uD for r in range(3)]
        if b.joint == "revolute":   # exactly: pA_0 + D u / D = tau
            pa[0] = tau[b.name]
        pa = [L(x) for x in pa]
        bx, by, E = kb["X"]
        Xm = sp.Matrix([[1, 0, 0], [bx, E[0][0], E[0][1]], [by, E[1][0], E[1][1]]])
        Y = (Ia*Xm).applyfunc(lambda e: L(e))
        Z = Xm.T*Y
        par = kin[b.parent]
        par["IA"] = sp.Matrix(3, 3, lambda r, c_: par["IA"][r, c_] + Z[min(r, c_), max(r, c_)])
        f = _xtf(kb["X"], pa)
        par["pA"] = [par["pA"][j] + f[j] for j in range(3)]
    # ---- pass 3: accelerations, root first
    gx, gy = gravity
    acc_out = [None]*n
    for b in order:
        kb = kin[b.name]
        ap = (0, -gx, -gy) if b.parent is None else kin[b.parent]["a"]
        a1 = _xm(kb["X"], ap)
        a1 = [L(a1[j] + kb["c"][j], "ac") for j in range(3)]
        qdd = L((kb["u"] - sum(kb["U"][j]*a1[j] for j in range(3)))*kb["Dinv"], "qdd")
        kb["a"] = [L(a1[j] + kb["S"][j]*qdd, "ac") for j in range(3)]
        if kb["k"] is not None:
            qdd = L(qdd + acc_out[index[kb["k"]]], "qdd")
        acc_out[index[b.name]] = qdd
    return code.defs, acc_out


def _xm(X, m):
    """Motion vector from the parent's into the child's coordinates."""
    bx, by, E = X
    w, vx, vy = m
    return (w, bx*w + E[0][0]*vx + E[0][1]*vy, by*w + E[1][0]*vx + E[1][1]*vy)


def _xtf(X, f):
    """Force vector from the child's into the parent's coordinates (X^T f)."""
    bx, by, E = X
    n_, fx, fy = f
    return (n_ + bx*fx + by*fy, E[0][0]*fx + E[1][0]*fy, E[0][1]*fx + E[1][1]*fy)


def build_tree(bodies, gravity=(0, 0), forces=None, coordinates="relative", lazy=False):
    """The pieces of a planar tree without compiling: a dict with ``L``, ``T``, ``U`` (in
    the dynamicsymbols; with ``lazy`` None, computed by ``energies()`` when needed), ``q``
    (coordinates in the order of ``bodies``), ``forces`` (one generalized force per
    coordinate), and ``aba(qs, vs)``, a function that returns the articulated-body
    algorithm's straight-line code (defs, accelerations) in plain symbols qs, vs (one per
    coordinate). Used by :func:`planar_tree`; useful to inspect T and U."""
    if coordinates not in ("relative", "absolute"):
        raise ValueError(f"coordinates must be 'relative' or 'absolute', got {coordinates!r}")
    from sympy.physics.mechanics import dynamicsymbols
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
    from sympy.physics.mechanics import dynamicsymbols
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
    from .derive import derive_lagrangian
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
    from .pipeline import _construct, _tup
    from .description import description_hit, tree_description_key
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
        from .recursive import derive_recursive

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
    from .loops import Loop, PointForce
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
        from .recursive import recursive_version
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
    from .loops import Loop, PointForce
    out = []
    for lp in _as_list(loops, Loop):
        out.append(("loop", repr(lp.body_a), repr(lp.body_b), repr(lp.joint),
                    repr(lp.name)))
    for pf in _as_list(point_forces, PointForce):
        out.append(("pf", repr(pf.body), repr(pf.frame)))
    return tuple(out)


def aba_lines(printer, d, target="a", ind="        "):
    """(declarations, statements) of the straight-line articulated-body code ``d.aba``
    assigning the accelerations to ``target(1..n)``, printed with `printer` (whose names
    map the coordinates, velocities and parameters). A pivot that is not positive (or NaN)
    is set to 0, so that its inverse and the accelerations are infinite or NaN (the
    integrators then stop with a non-finite status); no ieee_arithmetic (its procedure
    entry and exit would cost ~90 instructions per call)."""
    from .codegen import _decl_temps, _wrap, prepare
    defs, acc = d.aba
    names = {s: f"b{k + 1}" for k, (s, e) in enumerate(
        (s, e) for s, e in defs if not isinstance(e, str))}
    saved = printer.names
    printer.names = {**saved, **names}
    body = []
    try:
        for s, e in defs:
            if isinstance(e, str):      # "positive": the pivot check
                nm = names[s]
                body.append(f"{ind}if (.not. ({nm} > 0.0_dp)) {nm} = 0.0_dp")
            else:
                body += _wrap(f"{names[s]} = {printer._print(prepare(e))}", ind)
        for i, e in enumerate(acc):
            body += _wrap(f"{target}({i + 1}) = {printer._print(prepare(sp.sympify(e)))}",
                          ind)
    finally:
        printer.names = saved
    return _decl_temps(list(names.values()), ind), body


def accel_procedure(printer, d, cname="conmech_accel"):
    """Fortran lines of the bind(C) subroutine ``cname(t, q, v, a, p)`` that evaluates the
    articulated-body accelerations (:func:`aba_lines`)."""
    n = d.n
    npar = max(len(d.params), 1)
    ind = "        "
    decl, body = aba_lines(printer, d, "a", ind)
    head = [f'    subroutine {cname}(t, q, v, a, p) bind(C, name="{cname}")',
            f"{ind}real(dp), value, intent(in) :: t",
            f"{ind}real(dp), intent(in) :: q({n}), v({n})",
            f"{ind}real(dp), intent(out) :: a({n})",
            f"{ind}real(dp), intent(in) :: p({npar})"]
    return head + decl + body + [f"    end subroutine {cname}", ""]
