"""Spatial (3-D) multibody trees: bodies and joints in, a compiled system with O(n)
accelerations out -- the 3-D counterpart of :func:`conmech.symbolic.planar_tree`.

:func:`spatial_tree` takes a kinematic tree of rigid bodies in space (each body hangs from
its parent, or from the ground, by a revolute or a prismatic joint), builds the kinetic and
potential energies from the bodies' poses and derives the system with the machinery of
:func:`conmech.symbolic.lagrangian_system` (mass matrix, forces, energy, the exact Jacobian
of the accelerations). In addition it generates ``conmech_accel(t, q, v, a, p)``: the
accelerations a = M^-1 Q by Featherstone's articulated-body algorithm (ABA) with 6-D spatial
vectors, as straight-line code: O(n) operations for n bodies (one sine and cosine per
revolute joint, one division per joint, no matrix factorisation), which the right-hand
side of the compiled system uses instead of factorising M.

Frames (the convention of URDF): every body has a frame; its centre of mass ``com`` and its
inertia tensor about the centre of mass ``inertia`` (3x3, symmetric) are given in it. A
joint's frame is the parent's frame (the ground frame for the root bodies) moved to the
joint location ``at`` and turned by the fixed rotation ``rot`` (a 3x3 rotation matrix, both
in the parent's frame; default: no rotation, the joint frame is parallel to the parent's).
The joint's unit ``axis`` is given in the joint frame. The body's frame is the joint frame
rotated by the joint angle q about the axis (revolute; Rodrigues' formula, right-handed),
or moved by q * axis (prismatic). The coordinates are relative to the parent (the robotics
convention).

T = sum_i (m_i |v_c,i|^2 + omega_i . I_i omega_i) / 2 (omega_i in body coordinates), U =
-sum_i m_i g . r_c,i; the accelerations: Featherstone, Rigid Body Dynamics Algorithms,
ch. 7 (motion vectors [omega; v], force vectors [n; f], in body coordinates; articulated
inertias 6x6 symmetric; D_i = S_i^T IA_i S_i is checked positive: otherwise the output is
not finite and the integration stops with success=False); gravity enters as the
acceleration of the ground.
"""
import sympy as sp
from sympy.core.function import AppliedUndef

from .tree import _Code, _check_tree, _derive, _expr, _force_list, _forces_at
from .pipeline import _construct, _tup

__all__ = ["SpatialBody", "spatial_tree", "build_spatial_tree", "derive_spatial_tree"]


class SpatialBody:
    """One rigid body of a spatial tree.

    Parameters
    ----------
    name : str
        The body's name (unique in the tree).
    parent : str or None
        The parent body's name; None: the body is jointed to the ground.
    joint : {"revolute", "prismatic"}
        The joint to the parent.
    q : sympy dynamicsymbol
        The joint's coordinate (a function of t), relative to the parent.
    axis : 3 expressions
        The joint's unit axis in the joint frame: the rotation axis (revolute) or the
        direction of the slide (prismatic).
    at : 3 expressions
        The joint's location in the parent's frame.
    rot : 3x3 rotation matrix, optional
        The fixed rotation of the joint frame in the parent's frame (columns: the joint
        frame's axes in parent coordinates); None: the identity.
    mass : expression
        The body's mass (>= 0).
    com : 3 expressions
        The centre of mass in the body's own frame.
    inertia : 3x3 expressions, optional
        The inertia tensor about the centre of mass in the body's frame (symmetric,
        positive semi-definite; 0 or None: a point mass).
    """

    __slots__ = ("name", "parent", "joint", "q", "axis", "at", "rot", "mass", "com",
                 "inertia")

    def __init__(self, name, parent=None, joint="revolute", q=None, axis=(0, 0, 1),
                 at=(0, 0, 0), rot=None, mass=0, com=(0, 0, 0), inertia=None):
        self.name, self.parent, self.joint, self.q = name, parent, joint, q
        self.axis, self.at, self.rot = axis, at, rot
        self.mass, self.com, self.inertia = mass, com, inertia

    def __repr__(self):
        return (f"SpatialBody({self.name!r}, parent={self.parent!r}, "
                f"joint={self.joint!r}, q={self.q}, axis={self.axis}, mass={self.mass})")


def _vec3(x, what):
    try:
        seq = list(x)
    except TypeError:
        raise TypeError(f"{what} must be 3 expressions (x, y, z)") from None
    if len(seq) != 3:
        raise ValueError(f"{what} must have 3 components, got {len(seq)}")
    return sp.Matrix([_expr(e, what) for e in seq])


def _mat3(x, what, default, zero_ok=False):
    """A 3x3 matrix of expressions; None (or 0 where `zero_ok`): `default`."""
    if x is None or (zero_ok and not hasattr(x, "__len__")
                     and not isinstance(x, sp.MatrixBase) and _expr(x, what) == 0):
        return default
    try:
        M = sp.Matrix(x)
    except (TypeError, ValueError, sp.SympifyError):
        raise TypeError(f"{what} must be a 3x3 matrix of expressions") from None
    if M.shape != (3, 3):
        raise ValueError(f"{what} must be 3x3, got the shape {M.shape}")
    return M.applyfunc(lambda e: _expr(e, what))


def _numeric(e, vals):
    e = sp.sympify(e)
    e = e.subs({s: vals[s.name] for s in e.free_symbols if s.name in vals})
    return float(e) if e.is_number else None


def _param_values(params):
    vals = {}
    if isinstance(params, dict):
        for k, v in params.items():
            vals[k.name if isinstance(k, sp.Symbol) else str(k)] = v
    return vals


def _check_bodies(order, data, params):
    """Clear errors for an axis that is not a unit vector, a rotation that is not a
    rotation, an inertia that is not symmetric or not positive semi-definite, negative
    masses, and leaves that would make M singular -- wherever the parameter values decide
    it."""
    import numpy as np
    vals = _param_values(params)
    has_child = {b.parent for b in order}
    for b in order:
        at, rot, axis, m, com, Ic = data[b.name]
        nm = f"body '{b.name}'"
        a2 = _numeric(axis.dot(axis), vals)
        if all(e == 0 for e in axis):
            raise ValueError(f"{nm}: the joint axis is zero")
        if a2 is not None and abs(a2 - 1) > 1e-12:
            raise ValueError(f"{nm}: the joint axis {list(axis)} is not a unit vector "
                             f"(|axis|^2 = {a2})")
        R = [_numeric(e, vals) for e in rot]
        if None not in R:
            R = np.array(R, float).reshape(3, 3)
            if (np.max(np.abs(R.T @ R - np.eye(3))) > 1e-12
                    or abs(np.linalg.det(R) - 1) > 1e-12):
                raise ValueError(f"{nm}: rot is not a rotation matrix (orthonormal with "
                                 "determinant 1)")
        for r in range(3):
            for c in range(r + 1, 3):
                if sp.expand(Ic[r, c] - Ic[c, r]) != 0:
                    raise ValueError(f"{nm}: the inertia tensor is not symmetric "
                                     f"(entries ({r}, {c}) and ({c}, {r}) differ)")
        mv = _numeric(m, vals)
        if mv is not None and mv < 0:
            raise ValueError(f"{nm}: negative mass {mv}")
        Iv = [_numeric(e, vals) for e in Ic]
        if None not in Iv:
            ev = np.linalg.eigvalsh(np.array(Iv, float).reshape(3, 3))
            tol = 1e-12*max(1.0, np.max(np.abs(ev)))
            if ev[0] < -tol:
                raise ValueError(f"{nm}: the inertia tensor is not positive semi-definite "
                                 f"(principal moments {ev.tolist()})")
            if ev[0] + ev[1] < ev[2] - tol:
                raise ValueError(f"{nm}: the principal moments {ev.tolist()} violate the "
                                 "triangle inequality (no rigid body has this inertia)")
        if b.name in has_child:
            continue
        if mv == 0 and None not in Iv and not any(Iv):
            raise ValueError(f"{nm} is a leaf without mass and inertia: the mass matrix "
                             "would be singular")


def _rodrigues(k, c, s):
    """The rotation by the angle with cosine c and sine s about the unit axis k."""
    K = sp.Matrix([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return c*sp.eye(3) + s*K + (1 - c)*(k*k.T)


def _cross(a, b):
    return sp.Matrix([a[1]*b[2] - a[2]*b[1], a[2]*b[0] - a[0]*b[2], a[0]*b[1] - a[1]*b[0]])


def _skew(c):
    return sp.Matrix([[0, -c[2], c[1]], [c[2], 0, -c[0]], [-c[1], c[0], 0]])


def build_spatial_tree(bodies, gravity=(0, 0, 0), forces=None, lazy=False):
    """The pieces of a spatial tree without compiling: a dict with ``L``, ``T``, ``U`` (in
    the dynamicsymbols; with ``lazy`` None, computed by ``energies()``), ``q``, ``forces``
    (one generalized force per coordinate) and ``aba(qs, vs)`` (the articulated-body
    algorithm's straight-line code in plain symbols). Used by :func:`spatial_tree`; useful
    to inspect T and U or to derive the same system with
    :func:`conmech.symbolic.lagrangian_system`."""
    from sympy.physics.mechanics import dynamicsymbols
    t = dynamicsymbols._t
    bodies = [bodies] if isinstance(bodies, SpatialBody) else list(bodies)
    order, coords = _check_tree(bodies, t, SpatialBody)
    index = {b.name: i for i, b in enumerate(bodies)}
    g = _vec3(gravity, "gravity")
    data = {}
    for b in order:
        nm = f"body '{b.name}'"
        d = (_vec3(b.at, f"{nm}: at"), _mat3(b.rot, f"{nm}: rot", sp.eye(3)),
             _vec3(b.axis, f"{nm}: axis"), _expr(b.mass, f"{nm}: mass"),
             _vec3(b.com, f"{nm}: com"), _mat3(b.inertia, f"{nm}: inertia", sp.zeros(3, 3), True))
        data[b.name] = d
        for e in [*d[0], *d[1], *d[2], d[3], *d[4], *d[5]]:
            if e.has(t) or e.atoms(AppliedUndef):
                raise ValueError(f"{nm}: the geometry, mass and inertia must depend on "
                                 f"parameters only, got {e}")
        if all(e == 0 for e in d[2]):
            raise ValueError(f"{nm}: the joint axis is zero")
    for e in g:
        if e.has(t) or e.atoms(AppliedUndef):
            raise ValueError(f"gravity must depend on parameters only, got {e}")
    fl = _force_list(forces, coords, index)

    def energies():
        """T and U: T in the compact form of :func:`_kinetic_compact` (no products of a
        rotation with its own transpose), U from the positions in ground coordinates."""
        T, U = _kinetic_compact(order, data, t), sp.Integer(0)
        R, p = {}, {}
        for b in order:
            at, rot, k, m, com, Ic = data[b.name]
            Rp, pp = (sp.eye(3), sp.zeros(3, 1)) if b.parent is None else (R[b.parent],
                                                                          p[b.parent])
            Erel, r = _joint(b, data[b.name], sp.cos(b.q), sp.sin(b.q))
            R[b.name], p[b.name] = Rp*Erel, pp + Rp*r
            if m != 0:
                U -= m*g.dot(p[b.name] + R[b.name]*com)
        return T, U

    def energies_naive():
        """T and U from the poses: omega and the origin's velocity in body coordinates
        (recursively, parent to child), the positions in ground coordinates (the plain
        form: expanded, it is much longer than the compact one; kept to check it)."""
        kin = {}
        T = U = sp.Integer(0)
        for b in order:
            at, rot, k, m, com, Ic = data[b.name]
            q, qd = b.q, b.q.diff(t)
            if b.parent is None:
                Rp, pp, wp, vp = sp.eye(3), sp.zeros(3, 1), sp.zeros(3, 1), sp.zeros(3, 1)
            else:
                Rp, pp, wp, vp = kin[b.parent]
            if b.joint == "revolute":
                Erel = rot*_rodrigues(k, sp.cos(q), sp.sin(q))
                r, rd = at, sp.zeros(3, 1)
            else:
                Erel = rot
                r, rd = at + rot*k*q, rot*k*qd
            w = Erel.T*wp + (k*qd if b.joint == "revolute" else sp.zeros(3, 1))
            v = Erel.T*(vp + _cross(wp, r) + rd)
            R, p = Rp*Erel, pp + Rp*r
            kin[b.name] = (R, p, w, v)
            if m != 0:
                vc = v + _cross(w, com)
                T += m*vc.dot(vc)/2
                U -= m*g.dot(p + R*com)
            if any(e != 0 for e in Ic):
                T += w.dot(Ic*w)/2
        return T, U

    def aba(qs, vs):
        tau = _forces_at(fl, coords, qs, vs)
        return _spatial_aba(order, index, data, qs, vs, tau, g)

    T = U = None
    if not lazy:
        T, U = energies()
    return dict(L=None if lazy else T - U, T=T, U=U, energies=energies,
                energies_naive=energies_naive, q=coords, forces=fl,
                aba=aba, order=order, data=data, gravity=g)


def _joint(b, d, c, s):
    """(E, r): the body's axes in its parent's frame and its origin there."""
    at, rot, k = d[0], d[1], d[2]
    if b.joint == "revolute":
        return rot*_rodrigues(k, c, s), at
    return rot, at + rot*k*b.q


def _dot_cols(u1, u2, rho, n2):
    """(h1 + a1 x rho) . (h2 + a2 x rho) with |rho|^2 = n2 given (not expanded from rho)."""
    h1, a1 = u1
    h2, a2 = u2
    return (h1.dot(h2) + h1.dot(_cross(a2, rho)) + h2.dot(_cross(a1, rho))
            + a1.dot(a2)*n2 - a1.dot(rho)*a2.dot(rho))


def _kinetic_compact(order, data, t):
    """T = sum_i (m_i |v_c,i|^2 + omega_i . I_i omega_i)/2 written so that its expanded
    form stays short: the velocity of a point due to joint j is h + a x rho (a: joint j's
    axis, h: the velocity of the frame-l origin, rho: the point from that origin, all in
    the frame l of the deeper of the two joints of a product), the products of two such
    columns are taken in that frame, with |rho|^2 propagated as a sum (not as rho . rho,
    whose expansion would carry E E^T = 1 unsimplified through every joint)."""
    cols, E, r = {}, {}, {}
    byname = {b.name: b for b in order}
    T = []
    for b in order:
        at, rot, k, m, com, Ic = data[b.name]
        Eb, rb = _joint(b, data[b.name], sp.cos(b.q), sp.sin(b.q))
        E[b.name], r[b.name] = Eb, rb
        mine = {}
        if b.parent is not None:
            for j, (h, a) in cols[b.parent].items():
                mine[j] = (Eb.T*(h + _cross(a, rb)), Eb.T*a)
        z = sp.zeros(3, 1)
        mine[b.name] = (z, k) if b.joint == "revolute" else (k, z)
        cols[b.name] = mine
        qd = {j: byname[j].q.diff(t) for j in mine}
        if any(e != 0 for e in Ic):
            w = sum((a*qd[j] for j, (h, a) in mine.items()), sp.zeros(3, 1))
            T.append(w.dot(Ic*w)/2)
        if m == 0:
            continue
        # up the path: rho (COM from the origin of l, in frame l) and |rho|^2
        rho, n2, lname = com, com.dot(com), b.name
        while True:
            ul = cols[lname][lname]
            T.append(m*qd[lname]**2*_dot_cols(ul, ul, rho, n2)/2)
            for j, uj in cols[lname].items():
                if j != lname:
                    T.append(m*qd[j]*qd[lname]*_dot_cols(uj, ul, rho, n2))
            par = byname[lname].parent
            if par is None:
                break
            El, rl = E[lname], r[lname]
            Er = El*rho
            rho, n2 = rl + Er, rl.dot(rl) + 2*rl.dot(Er) + n2
            lname = par
    return sp.Add(*T)


def _mm(A, B):
    """A B for matrices as lists of rows (sympy entries; no Matrix overhead)."""
    return [[sp.Add(*[A[i][k]*B[k][j] for k in range(len(B))]) for j in range(len(B[0]))]
            for i in range(len(A))]


def _mv(A, x):
    return [sp.Add(*[A[i][k]*x[k] for k in range(len(x))]) for i in range(len(A))]


def _lcross(a, b):
    return [a[1]*b[2] - a[2]*b[1], a[2]*b[0] - a[0]*b[2], a[0]*b[1] - a[1]*b[0]]


def _spatial_aba(order, index, data, qs, vs, tau, g, trig=None):
    """(defs, accelerations) of the spatial articulated-body algorithm (matrices as lists
    of rows: the construction cost is the arithmetic, not sympy's matrix machinery;
    `trig`: {body name: (cos, sin) symbols} of the joint angles computed elsewhere)."""
    code = _Code()
    L = code.let

    def lv(vec, name="b"):
        return [L(e, name) for e in vec]

    def sym6(M, name):
        out = [[None]*6 for _ in range(6)]
        for r in range(6):
            for c in range(r, 6):
                out[r][c] = out[c][r] = L(M[r][c], name)
        return out

    def lst(M):
        return [[M[i, j] for j in range(M.shape[1])] for i in range(M.shape[0])]
    kin = {}
    # ---- pass 1: transforms, velocities, bias terms
    for b in order:
        i = index[b.name]
        at, rot, k, m, com, Ic = data[b.name]
        at, rot, k, com, Ic = list(at), lst(rot), list(k), list(com), lst(Ic)
        qd = vs[i]
        if b.joint == "revolute":
            if trig is not None:
                c, s = trig[b.name]
            else:
                c, s = L(sp.cos(qs[i]), "c"), L(sp.sin(qs[i]), "s")
            Rk = lst(_rodrigues(sp.Matrix(k), c, s))
            Erel = [[L(e, "e") for e in row] for row in _mm(rot, Rk)]
            r = at
            S = k + [0, 0, 0]
        else:
            Erel = rot
            rk = _mv(rot, k)
            r = lv([at[j] + rk[j]*qs[i] for j in range(3)], "r")
            S = [0, 0, 0] + k
        E = [[Erel[j][i_] for j in range(3)] for i_ in range(3)]
        X = (E, r)
        vp = [0]*6 if b.parent is None else kin[b.parent]["v"]
        v = lv([x + y*qd for x, y in zip(_xm(X, vp), S)], "v")
        w, vl = v[:3], v[3:]
        sq = [x*qd for x in S]
        cw, cv1, cv2 = _lcross(w, sq[:3]), _lcross(w, sq[3:]), _lcross(vl, sq[:3])
        cb = lv(cw + [cv1[j] + cv2[j] for j in range(3)], "cb")
        # the spatial inertia about the body's origin, in body coordinates
        cx = [[0, -com[2], com[1]], [com[2], 0, -com[0]], [-com[1], com[0], 0]]
        cc = sp.Add(*[x*x for x in com])
        I6 = [[0]*6 for _ in range(6)]
        for r_ in range(3):
            for c_ in range(3):
                I6[r_][c_] = Ic[r_][c_] + m*((cc if r_ == c_ else 0) - com[r_]*com[c_])
                I6[r_][3 + c_] = m*cx[r_][c_]
                I6[3 + r_][c_] = m*cx[c_][r_]
                I6[3 + r_][3 + c_] = m if r_ == c_ else 0
        I6 = sym6(I6, "ii")
        h = lv(_mv(I6, v), "h")
        p1, p2, p3 = _lcross(w, h[:3]), _lcross(vl, h[3:]), _lcross(w, h[3:])
        pA = [p1[j] + p2[j] for j in range(3)] + p3
        kin[b.name] = dict(X=X, S=S, v=v, c=cb, IA=I6, pA=pA)
    # ---- pass 2: articulated inertias and bias forces, leaves first
    for b in reversed(order):
        kb = kin[b.name]
        IA, pA, S = sym6(kb["IA"], "ia"), lv(kb["pA"], "pa"), kb["S"]
        U = lv(_mv(IA, S), "u")
        D = L(sp.Add(*[x*y for x, y in zip(S, U)]), "d", force=True)
        if D.is_Number:
            if not D > 0:
                raise ValueError(f"body '{b.name}': the articulated inertia of its joint is "
                                 f"{D}: the mass matrix is not positive definite")
        else:
            code.positive(D)
        Dinv = L(1/D, "di")
        u = L(tau[index[b.name]] - sp.Add(*[x*y for x, y in zip(S, pA)]), "uu")
        kb.update(U=U, Dinv=Dinv, u=u)
        if b.parent is None:
            continue
        # Ia S = 0 exactly: for a motion subspace along a coordinate axis (S = e_k, the
        # usual joint axes) row and column k of Ia vanish and pa_k = tau (written so:
        # fewer products below, and exact zeros instead of rounding residues)
        unit = [j for j, x in enumerate(S) if x != 0]
        k = unit[0] if len(unit) == 1 and S[unit[0]] == 1 else None
        Ia = sym6([[0 if k in (r_, c_) else IA[r_][c_] - U[r_]*U[c_]*Dinv
                    for c_ in range(6)] for r_ in range(6)], "ja")
        uD = L(u*Dinv)
        Iac = _mv(Ia, kb["c"])
        pa = lv([tau[index[b.name]] if j == k else pA[j] + Iac[j] + U[j]*uD
                 for j in range(6)], "pb")
        E, r = kb["X"]
        Er = _mm(E, [[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
        Xm = [[0]*6 for _ in range(6)]
        for r_ in range(3):
            for c_ in range(3):
                Xm[r_][c_] = E[r_][c_]
                Xm[3 + r_][3 + c_] = E[r_][c_]
                Xm[3 + r_][c_] = -Er[r_][c_]
        Xm = [[L(e, "x") for e in row] for row in Xm]
        Y = [[L(e, "y") for e in row] for row in _mm(Ia, Xm)]
        XmT = [[Xm[j][i_] for j in range(6)] for i_ in range(6)]
        Z = _mm(XmT, Y)
        par = kin[b.parent]
        par["IA"] = [[par["IA"][r_][c_] + Z[min(r_, c_)][max(r_, c_)] for c_ in range(6)]
                     for r_ in range(6)]
        f = _xtf(kb["X"], pa)
        par["pA"] = [par["pA"][j] + f[j] for j in range(6)]
    # ---- pass 3: accelerations, root first
    acc = [None]*len(order)
    for b in order:
        kb = kin[b.name]
        ap = [0, 0, 0] + [-x for x in g] if b.parent is None else kin[b.parent]["a"]
        a1 = lv([x + y for x, y in zip(_xm(kb["X"], ap), kb["c"])], "ac")
        qdd = L((kb["u"] - sp.Add(*[x*y for x, y in zip(kb["U"], a1)]))*kb["Dinv"], "qdd")
        kb["a"] = lv([x + y*qdd for x, y in zip(a1, kb["S"])], "ac")
        acc[index[b.name]] = qdd
    return code.defs, acc


def _xm(X, m):
    """Motion vector [omega; v] from the parent's into the child's coordinates."""
    E, r = X
    w, v = list(m[:3]), list(m[3:])
    wr = _lcross(w, r)
    return _mv(E, w) + _mv(E, [v[j] + wr[j] for j in range(3)])


def _xtf(X, f):
    """Force vector [n; f] from the child's into the parent's coordinates (X^T f)."""
    E, r = X
    ET = [[E[j][i] for j in range(3)] for i in range(3)]
    fp = _mv(ET, list(f[3:]))
    n = _mv(ET, list(f[:3]))
    rf = _lcross(r, fp)
    return [n[j] + rf[j] for j in range(3)] + fp


def _body_key(parts):
    out = []
    for b in parts["order"]:
        at, rot, axis, m, com, Ic = parts["data"][b.name]
        out.append(sp.Tuple(*at, *rot, *axis, m, *com, *Ic))
    return sp.Tuple(*out)


def derive_spatial_tree(bodies, params=None, gravity=(0, 0, 0), forces=None,
                        simplify="auto", jacobian=True):
    """The derived record (:class:`~conmech.symbolic.derive.Derived`) of a spatial tree,
    without compiling (what :func:`spatial_tree` compiles). Arguments as
    :func:`spatial_tree`."""
    parts = build_spatial_tree(bodies, gravity, forces)
    _check_bodies(parts["order"], parts["data"], params)
    return _derive(parts, params, simplify, jacobian)


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
    from .pipeline import _construct, _tup
    from .description import description_hit, tree_description_key
    from .tree import _loop_names, _method_key
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
        from .recursive import derive_recursive

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
