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
import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.physics.mechanics import dynamicsymbols

from .spatial_aba import _rodrigues, _spatial_aba
from .tree import _check_tree, _components, _derive, _expr, _force_list, _forces_at

__all__ = ["SpatialBody", "build_spatial_tree", "derive_spatial_tree"]


class SpatialBody:
    """One rigid body of a spatial tree.

    Parameters
    ----------
    name, parent, joint, mass
        As for the planar tree's body (``conmech.symbolic.Body``).
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
    return sp.Matrix(_components(x, 3, what, "3 expressions (x, y, z)"))


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


def derive_spatial_tree(bodies, params=None, gravity=(0, 0, 0), forces=None,
                        simplify="auto", jacobian=True):
    """The derived record (:class:`~conmech.symbolic.derive.Derived`) of a spatial tree,
    without compiling (what :func:`spatial_tree` compiles). Arguments as
    :func:`spatial_tree`."""
    parts = build_spatial_tree(bodies, gravity, forces)
    _check_bodies(parts["order"], parts["data"], params)
    return _derive(parts, params, simplify, jacobian)

