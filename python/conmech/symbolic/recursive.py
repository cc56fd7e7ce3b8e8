"""Recursive rigid-body dynamics of kinematic trees, generated as straight-line Fortran.

The mass matrix, the forces, the exact Jacobian of the accelerations and (with closed
loops, see :mod:`conmech.symbolic.loops`) the loop constraints of a tree made by
:func:`conmech.symbolic.planar_tree` or :func:`conmech.symbolic.spatial_tree` come from the
recursive algorithms of rigid-body dynamics evaluated on the bodies' data, not from an
expanded Lagrangian: the construction cost grows like the number of bodies, not like the
size of the expanded kinetic energy.

Everything is in the ground ("world") frame, with Featherstone's 6-D spatial vectors
(motion [omega; v_O], force [n_O; f], v_O the velocity of the body point at the origin):
joint k of body k has the world motion subspace S_k (revolute: [k_w; p_k x k_w], prismatic:
[0; k_w]), depending on the coordinates of the ancestors only.

- Position pass (straight-line, ``tree_pos``): poses, S_k, the spatial inertia of each body
  about the origin (compact: m, h = m c, I_O), the composite inertias Ic_k (subtree sums),
  alpha_k = Ic_k S_k. The composite-rigid-body algorithm gives M_jk = S_j . alpha_k for j an
  ancestor of k (or k itself), zero otherwise (a loop over the ancestor pairs).
- Velocity pass (straight-line, ``tree_vel``): v_k = v_parent + S_k qd_k, psi_k = v_parent x
  S_k (= dS_k/dt), a_k = a_parent + S_k qdd_k + psi_k qd_k (a_0 = -gravity), momenta
  h_k = I_k v_k, forces f_k = I_k a_k + v_k x* h_k, subtree sums F_k and the joint forces of
  inverse dynamics tau_k = S_k . F_k (the recursive Newton-Euler algorithm); Q = tau_user -
  tau(q, v, 0).
- Derivatives of inverse dynamics (the idea of Carpentier and Mansard, RSS 2018: world-frame
  quantities and subtree sums; the formulas below are derived for this code): with
  D_k = sum over the subtree of dI/dt = v x* I - I v x (symmetric, compact), H_k (subtree
  momentum), c_j = -(S_j x a_j + psi_j x v_j), eta_k = D_k S_k - S_k x* H_k,
  Phi_j = S_j x* F_j + Ic_j c_j + D_j psi_j + psi_j x* H_j and
  Omega_j = 2 Ic_j psi_j + D_j S_j + S_j x* H_j::

      d tau_k / d q_j  = alpha_k . c_j + eta_k . psi_j      (j an ancestor of k, or k)
                       = S_k . Phi_j                        (k a strict ancestor of j)
      d tau_k / d qd_j = 2 alpha_k . psi_j + eta_k . S_j    (j an ancestor of k, or k)
                       = S_k . Omega_j                      (k a strict ancestor of j)

  O(n) vectors, then one pair of dot products per ancestor pair.
- The Jacobian of the accelerations d a / d[q, v] = M^-1 R (R = [dQ/dq - d(M a)/dq, dQ/dv])
  solves with the tree-sparse factorisation M = L^T D L (Featherstone's LTDL, branch-induced
  sparsity), no LAPACK; a non-positive pivot gives non-finite output.
- The accelerations themselves are the articulated-body algorithm of tree.py / spatial.py.

Planar trees are spatial trees in the plane z = 0 (revolute joints about z); the structural
zeros fold out of the straight-line code (constants are folded at generation), and the loops
run over the spatial components that are not zero for every body (3 in the plane). Absolute
angles (``coordinates="absolute"``) are relative ones through q_rel = T q (T = 1 - P, P
picking each revolute joint's nearest revolute ancestor): M = T^T M_rel T, Q = tau_user -
T^T tau_rel, R = dtau_user - T^T dID diag(T, T), d a/d[q, v] = T^-1 M_rel^-1 T^-T R.

The generated module holds the straight-line passes as module procedures filling a work
record, the loops as small fixed procedures, and thin bind(C) entry points (``mass``,
``forces``, ``mass_forces``, ``forces_jac``, ``accel``, ``accel_jac``, ``energy``; with loops
the constrained entries). Generated identifiers come from indices only (body names stay
data).
"""
import sympy as sp

from .derive import Derived
from .._core.result import Record

__all__ = ["TreeDerived", "derive_recursive", "Code"]

_VERSION = []


def recursive_version():
    """A digest of the modules that generate the recursive code (part of the
    derivation-cache key: a change of the generator invalidates cached derivations)."""
    if not _VERSION:
        import hashlib
        import os
        h = hashlib.sha256()
        here = os.path.dirname(os.path.abspath(__file__))
        for name in ("recursive.py", "tree_fortran.py", "tree_pairs.py", "tree_print.py",
                     "tree_user.py", "loops.py", "tree.py", "spatial.py"):
            try:
                with open(os.path.join(here, name), "rb") as fh:
                    h.update(fh.read())
            except OSError:
                h.update(name.encode())
        _VERSION.append(h.hexdigest()[:16])
    return _VERSION[0]


# ------------------------------------------------------------------ straight-line code

class Code:
    """Straight-line code: a list of (Dummy, expression) definitions. Numbers, symbols and
    negated symbols are propagated instead of defined; an expression defined before is
    reused (a cheap common-subexpression elimination)."""

    def __init__(self):
        self.defs = []
        self.memo = {}

    def let(self, e):
        e = sp.sympify(e)
        if e.is_Number or e.is_Symbol or (e.is_Mul and len(e.args) == 2 and e.args[0] == -1
                                          and e.args[1].is_Symbol):
            return e
        s = self.memo.get(e)
        if s is None:
            s = sp.Dummy("w")          # (no assumptions: creating them is costly)
            self.defs.append((s, e))
            self.memo[e] = s
        return s

    def lv(self, xs):
        return [self.let(x) for x in xs]

    def positive(self, s):
        """Mark the defined symbol s as a pivot that must be positive."""
        self.defs.append((s, "positive"))

    def live(self, outputs):
        """The definitions the expressions `outputs` need (dead code removed), in order."""
        need = set()
        for e in outputs:
            need |= sp.sympify(e).free_symbols
        keep = []
        for s, e in reversed(self.defs):
            if s in need:
                keep.append((s, e))
                if not isinstance(e, str):
                    need |= e.free_symbols
        keep.reverse()
        pos = [(s, e) for s, e in self.defs if isinstance(e, str) and s in need]
        out = []
        for s, e in keep:
            if isinstance(e, str):
                continue
            out.append((s, e))
            for s2, e2 in pos:
                if s2 == s:
                    out.append((s2, e2))
        return out


# ------------------------------------------------------------------ spatial algebra

def _cross(a, b):
    return [a[1]*b[2] - a[2]*b[1], a[2]*b[0] - a[0]*b[2], a[0]*b[1] - a[1]*b[0]]


def _add(a, b):
    return [x + y for x, y in zip(a, b)]


def _dot(a, b):
    return sp.Add(*[x*y for x, y in zip(a, b)])


def crm(m, x):
    """Motion cross product m x x ([w; v] x [xw; xv] = [w x xw; w x xv + v x xw])."""
    w, v = m[:3], m[3:]
    return _cross(w, x[:3]) + _add(_cross(w, x[3:]), _cross(v, x[:3]))


def crf(m, f):
    """Force cross product m x* f ([w; v] x* [n; f] = [w x n + v x f; w x f])."""
    w, v = m[:3], m[3:]
    return _add(_cross(w, f[:3]), _cross(v, f[3:])) + _cross(w, f[3:])


def imul(I, x):
    """A compact spatial inertia (m, h = m c, I_O) times a motion vector x:
    [I_O xw + h x xv; m xv - h x xw]."""
    m, h, J = I
    xw, xv = x[:3], x[3:]
    hv, hw = _cross(h, xv), _cross(h, xw)
    return ([sp.Add(*[J[i][j]*xw[j] for j in range(3)]) + hv[i] for i in range(3)]
            + [m*xv[i] - hw[i] for i in range(3)])


def _sym3(f):
    """A symmetric 3x3 (list of rows) from f(i, j), i <= j."""
    M = [[None]*3 for _ in range(3)]
    for i in range(3):
        for j in range(i, 3):
            M[i][j] = M[j][i] = f(i, j)
    return M


def _rodrigues(k, c, s):
    K = [[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]]
    return [[c*(1 if i == j else 0) + s*K[i][j] + (1 - c)*k[i]*k[j] for j in range(3)]
            for i in range(3)]


def _matmul(A, B, L):
    return [[L(sp.Add(*[A[i][m]*B[m][j] for m in range(3)])) for j in range(3)]
            for i in range(3)]


def _matvec(A, x):
    return [sp.Add(*[A[i][m]*x[m] for m in range(3)]) for i in range(3)]


def _iadd(I1, I2, L):
    if I1 is None:
        return I2
    if I2 is None:
        return I1
    return (L(I1[0] + I2[0]), [L(I1[1][i] + I2[1][i]) for i in range(3)],
            _sym3(lambda i, j: L(I1[2][i][j] + I2[2][i][j])))


# ------------------------------------------------------------------ the normalised tree

class Joint(Record):
    """One body and its joint, in world-frame terms (topological order): parent index (-1:
    the ground), kind, joint placement (at, rot), axis, mass, com, inertia about the COM
    (3x3 or None), the user's coordinate index `col` and, for absolute planar angles, the
    index `ka` of the nearest revolute ancestor (-1: none)."""

    __slots__ = ("name", "parent", "kind", "at", "rot", "axis", "mass", "com", "inertia",
                 "col", "ka")


_I3 = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]


def joints_planar(order, index, data, absolute, conv):
    """Joints of a planar tree (tree.py's validated order and data) embedded in space:
    revolute joints about z, prismatic slides in the plane, inertia Izz only (the other
    moments never enter a planar motion). `conv` maps each expression to the canonical
    symbols."""
    topo = {b.name: k for k, b in enumerate(order)}
    out = []
    for k, b in enumerate(order):
        at, axis, m, com, inertia = data[b.name]
        rev = b.joint == "revolute"
        ka = -1
        if absolute and rev:
            p = b.parent
            while p is not None and order[topo[p]].joint != "revolute":
                p = order[topo[p]].parent
            ka = topo[p] if p is not None else -1
        Iz = conv(inertia)
        out.append(Joint(name=b.name, parent=topo[b.parent] if b.parent is not None else -1,
                         kind=b.joint, at=[conv(at[0]), conv(at[1]), 0], rot=_I3,
                         axis=[0, 0, 1] if rev else [conv(axis[0]), conv(axis[1]), 0],
                         mass=conv(m), com=[conv(com[0]), conv(com[1]), 0],
                         inertia=None if Iz == 0 else [[0, 0, 0], [0, 0, 0], [0, 0, Iz]],
                         col=index[b.name], ka=ka))
    return out


def joints_spatial(order, index, data, conv):
    """Joints of a spatial tree (spatial.py's validated order and data)."""
    topo = {b.name: k for k, b in enumerate(order)}
    out = []
    for b in order:
        at, rot, axis, m, com, Ic = data[b.name]
        Icl = [[conv(Ic[i, j]) for j in range(3)] for i in range(3)]
        if all(e == 0 for row in Icl for e in row):
            Icl = None
        out.append(Joint(name=b.name, parent=topo[b.parent] if b.parent is not None else -1,
                         kind=b.joint, at=[conv(x) for x in at],
                         rot=[[conv(rot[i, j]) for j in range(3)] for i in range(3)],
                         axis=[conv(x) for x in axis], mass=conv(m),
                         com=[conv(x) for x in com], inertia=Icl, col=index[b.name], ka=-1))
    return out


def relative(joints, xs):
    """The relative coordinates (rates) in topological order from the user's: x_k -
    x_ka(k) for absolute planar angles."""
    return [xs[J.col] - (xs[joints[J.ka].col] if J.ka >= 0 else 0) for J in joints]


# ------------------------------------------------------------------ the passes

def pos_pass(code, joints, qrel, gravity, trig=None):
    """Poses, world motion subspaces, spatial inertias about the origin, composite
    inertias, alpha = Ic S and the potential energy -g . sum h (`trig`: {k: (cos, sin)}
    symbols of the revolute joints' angles computed elsewhere). Returns a list of dicts
    (R, p, S, I, Jw, cw, Ic, alpha) and U."""
    L = code.let
    out = []
    for k, J in enumerate(joints):
        if J.parent < 0:
            Rp, pp = _I3, [0, 0, 0]
        else:
            Rp, pp = out[J.parent]["R"], out[J.parent]["p"]
        RJ = _matmul(Rp, J.rot, L)
        pJ = code.lv(_add(pp, _matvec(Rp, J.at)))
        kw = code.lv(_matvec(RJ, J.axis))
        if J.kind == "revolute":
            if trig is not None:
                c, s = trig[k]
            else:
                c, s = L(sp.cos(qrel[k])), L(sp.sin(qrel[k]))
            E = [[L(e) for e in row] for row in _rodrigues(J.axis, c, s)]
            R = _matmul(RJ, E, L)
            p = pJ
            S = kw + code.lv(_cross(p, kw))
        else:
            R = RJ
            p = code.lv([pJ[i] + kw[i]*qrel[k] for i in range(3)])
            S = [0, 0, 0] + kw
        d = dict(R=R, p=p, S=S, I=None, Jw=None, cw=None)
        m, Ic = J.mass, J.inertia
        if m != 0 or Ic is not None:
            cw = code.lv(_add(p, _matvec(R, J.com)))
            h = code.lv([m*x for x in cw])
            if Ic is not None:
                A = _matmul(R, Ic, L)
                Jw = _sym3(lambda i, j: L(sp.Add(*[A[i][n]*R[j][n] for n in range(3)])))
            else:
                Jw = [[0]*3 for _ in range(3)]
            hc = L(_dot(h, cw))
            Io = _sym3(lambda i, j: L(Jw[i][j] + (hc if i == j else 0) - h[i]*cw[j]))
            d.update(I=(m, h, Io), Jw=Jw, cw=cw)
        out.append(d)
    for k in reversed(range(len(joints))):
        d = out[k]
        d["Ic"] = _iadd(d.get("Ic"), d["I"], L)
        J = joints[k]
        if J.parent >= 0:
            out[J.parent]["Ic"] = _iadd(out[J.parent].get("Ic"), d["Ic"], L)
    for d in out:
        d["alpha"] = code.lv(imul(d["Ic"], d["S"])) if d["Ic"] is not None else [0]*6
    U = sp.Add(*[-_dot(gravity, d["I"][1]) for d in out if d["I"] is not None])
    return out, U


def vel_pass(code, joints, pos, vrel, arel, gravity, deriv):
    """The recursive Newton-Euler pass on the positions `pos` (pos_pass's output, possibly
    as loaded values): velocities, psi, accelerations (arel None: zero joint
    accelerations), momenta, forces, subtree forces, tau = S . F and the kinetic energy;
    with `deriv` the vectors of the derivatives (c, eta, Phi, Omega). Returns (list of
    dicts, T)."""
    L = code.let
    a0 = [0, 0, 0] + [-x for x in gravity]
    out = []
    T = []
    for k, J in enumerate(joints):
        P = pos[k]
        S = P["S"]
        if J.parent < 0:
            vl, al = [0]*6, a0
        else:
            vl, al = out[J.parent]["v"], out[J.parent]["a"]
        qd = vrel[k]
        v = code.lv([vl[i] + S[i]*qd for i in range(6)])
        psi = code.lv(crm(vl, S))
        qdd = 0 if arel is None else arel[k]
        a = code.lv([al[i] + S[i]*qdd + psi[i]*qd for i in range(6)])
        d = dict(v=v, psi=psi, a=a, hm=None, f=None, D=None)
        I = P["I"]
        if I is not None:
            hm = code.lv(imul(I, v))
            f = code.lv(_add(imul(I, a), crf(v, hm)))
            T.append(_dot(v, hm)/2)
            d.update(hm=hm, f=f)
            if deriv:
                m, h, _ = I
                w, cw, Jw = v[:3], P["cw"], P["Jw"]
                cd = code.lv(_add(v[3:], _cross(w, cw)))
                hd = code.lv([m*x for x in cd])
                cols = [code.lv(_cross(w, [Jw[0][b], Jw[1][b], Jw[2][b]])) for b in range(3)]
                hcd = L(2*_dot(h, cd))
                Iod = _sym3(lambda i, j: L(cols[j][i] + cols[i][j] + (hcd if i == j else 0)
                                           - hd[i]*cw[j] - h[i]*cd[j]))
                d["D"] = (0, hd, Iod)
        out.append(d)
    for k in reversed(range(len(joints))):
        d, J = out[k], joints[k]
        d["F"] = _vadd(d.get("F"), d["f"], L)
        if deriv:
            d["H"] = _vadd(d.get("H"), d["hm"], L)
            d["Dc"] = _iadd(d.get("Dc"), d["D"], L)
        if J.parent >= 0:
            par = out[J.parent]
            par["F"] = _vadd(par.get("F"), d["F"], L)
            if deriv:
                par["H"] = _vadd(par.get("H"), d["H"], L)
                par["Dc"] = _iadd(par.get("Dc"), d["Dc"], L)
    for k, d in enumerate(out):
        S = pos[k]["S"]
        F = d["F"] if d["F"] is not None else [0]*6
        d["tau"] = L(_dot(S, F))
        if not deriv:
            continue
        Ic, psi, v, a = pos[k]["Ic"], d["psi"], d["v"], d["a"]
        H = d["H"] if d["H"] is not None else [0]*6
        Dc = d["Dc"]
        d["c"] = c = code.lv([-x - y for x, y in zip(crm(S, a), crm(psi, v))])
        zero = [0]*6
        Ic_c = imul(Ic, c) if Ic is not None else zero
        Ic_psi = imul(Ic, psi) if Ic is not None else zero
        D_S = imul(Dc, S) if Dc is not None else zero
        D_psi = imul(Dc, psi) if Dc is not None else zero
        SH = crf(S, H)
        d["eta"] = code.lv([x - y for x, y in zip(D_S, SH)])
        if joints[k].parent < 0:         # Phi, Omega serve the strict ancestors only
            d["Phi"] = d["Omega"] = zero
            continue
        d["Phi"] = code.lv([x1 + x2 + x3 + x4 for x1, x2, x3, x4 in
                            zip(crf(S, F), Ic_c, D_psi, crf(psi, H))])
        d["Omega"] = code.lv([2*x1 + x2 + x3 for x1, x2, x3 in zip(Ic_psi, D_S, SH)])
    return out, sp.Add(*T)


def _vadd(a, b, L):
    if a is None:
        return b
    if b is None:
        return a
    return [L(x + y) for x, y in zip(a, b)]


class TreeDerived(Derived):
    """The derived record of a tree built by the recursive algorithms: the canonical
    symbols (``coords``, ``speeds``, ``params``, ...), the normalised joints, the user's
    generalized forces, gravity, the loops (:mod:`conmech.symbolic.loops`) and the
    options; :meth:`generate_fortran` writes the module (called by
    :func:`conmech.symbolic.codegen.generate`). It has no expanded M, Q or R: the
    Lagrangian route (``method="lagrangian"``, or ``derive_tree`` /
    ``derive_spatial_tree``) gives those."""

    def generate_fortran(self, module, model_values=None):
        from .tree_fortran import generate_tree
        return generate_tree(self, module, model_values)

    @property
    def lagrangian(self):
        """L = T - U in the canonical symbols, built from the bodies' data when first read
        (for the analysis of momenta and cyclic coordinates; the compiled code never needs
        it); None for a tree with forces at points of bodies (their generalized forces are
        not kept as expressions)."""
        if "_lagrangian" not in self.__dict__:
            self._energies()
        return self.__dict__["_lagrangian"]

    @property
    def energy(self):
        """T + U in the canonical symbols (the Jacobi integral of the tree, which is
        scleronomic), built like :attr:`lagrangian` when first read."""
        if self.__dict__.get("_energy") is None:
            self._energies()
        return self.__dict__["_energy"]

    @energy.setter
    def energy(self, value):
        self.__dict__["_energy"] = value

    def _energies(self):
        T, U = _tree_energies(self)
        self.__dict__["_energy"] = T + U
        self.__dict__["_lagrangian"] = None if self.point_forces else T - U


def _tree_energies(d):
    """(T, U) of the tree of a TreeDerived record: its canonical data rebuilt as bodies
    whose coordinates are functions of time, their energies, then the coordinates and their
    rates replaced by the canonical symbols."""
    from sympy.physics.mechanics import dynamicsymbols
    from .spatial import SpatialBody, build_spatial_tree
    from .tree import Body, build_tree
    tt = dynamicsymbols._t
    qf = [sp.Function(f"cq{i}")(tt) for i in range(d.n)]
    index = {name: J.col for name, J in zip(d.order_names, d.joints)}
    bodies = []
    for b in d.aba_order:
        c, q = d.cdata[b.name], qf[index[b.name]]
        if d.planar:
            bodies.append(Body(b.name, b.parent, b.joint, q, at=c[0], axis=c[1], mass=c[2],
                               com=c[3], inertia=c[4]))
        else:
            bodies.append(SpatialBody(b.name, b.parent, b.joint, q, axis=list(c[2]),
                                      at=list(c[0]), rot=c[1], mass=c[3], com=list(c[4]),
                                      inertia=c[5]))
    if d.planar:
        parts = build_tree(bodies, d.gravity[:2], None,
                           "absolute" if d.absolute else "relative", lazy=True)
    else:
        parts = build_spatial_tree(bodies, d.gravity, None, lazy=True)
    rates = {f.diff(tt): v for f, v in zip(qf, d.speeds)}
    values = dict(zip(qf, d.coords))
    return tuple(sp.sympify(e).xreplace(rates).xreplace(values).xreplace({tt: d.t})
                 for e in parts["energies"]())


def derive_recursive(parts, params, planar, absolute=False, loops=(), jacobian=True,
                     point_forces=()):
    """The :class:`TreeDerived` record of a planar or spatial tree (parts from
    tree.build_tree / spatial.build_spatial_tree), with the loop closures `loops`
    (:class:`conmech.symbolic.loops.Loop`) and the point forces `point_forces`
    (:class:`conmech.symbolic.loops.PointForce`). Resolves every symbol to the canonical
    real symbols (an unknown symbol or a parameter without a value: ValueError naming it)."""
    from .derive import (_Coords, _check_no_accel, _realify, _resolve_params, _subs_all,
                         _unify_time)
    from .loops import prepare_loops, prepare_point_forces
    t = sp.Symbol("t")
    order, data = parts["order"], parts["data"]
    coords = parts["q"]
    c = _Coords(coords, None, t, need_speeds=True)
    # every expression of the description, flattened (then put back by position)
    flat = []

    def put(e):
        flat.append(sp.sympify(e))
        return len(flat) - 1
    if planar:
        slots = {b.name: (put(data[b.name][0][0]), put(data[b.name][0][1]),
                          put(data[b.name][1][0]), put(data[b.name][1][1]),
                          put(data[b.name][2]), put(data[b.name][3][0]),
                          put(data[b.name][3][1]), put(data[b.name][4])) for b in order}
    else:
        slots = {}
        for b in order:
            at, rot, axis, m, com, Ic = data[b.name]
            slots[b.name] = ([put(x) for x in at], [put(x) for x in rot],
                             [put(x) for x in axis], put(m), [put(x) for x in com],
                             [put(x) for x in Ic])
    g_slots = [put(x) for x in parts["gravity"]]
    f_slots = [put(x) for x in parts["forces"]]
    loop_items = prepare_loops(loops, order, planar)
    l_slots = [[put(x) for x in item["exprs"]] for item in loop_items]
    pf_items = prepare_point_forces(point_forces, order, planar)
    pf_slots = [[put(x) for x in item["exprs"]] for item in pf_items]
    exprs = _unify_time(flat, t)
    exprs = c.convert(exprs, "the tree's description")
    _check_no_accel(exprs, c)
    psyms, names, values, sub = _resolve_params(params, exprs, list(c.plain) + list(c.speeds),
                                                t)
    exprs = _subs_all(exprs, sub)
    exprs, t, psyms = _realify(exprs, t, c, psyms)
    geometry = set(range(len(flat))) - set(f_slots) - {i for s in pf_slots for i in s}
    qv = set(c.plain) | set(c.speeds) | {t}
    for i in geometry:
        if exprs[i].free_symbols & qv:
            raise ValueError(f"the geometry, masses, inertias, gravity and loop points must "
                             f"depend on parameters only, got {exprs[i]}")
    ex = exprs.__getitem__
    user_index = {b.name: coords.index(b.q) for b in order}
    if planar:
        cdata = {}
        for b in order:
            s = slots[b.name]
            cdata[b.name] = ((ex(s[0]), ex(s[1])), (ex(s[2]), ex(s[3])), ex(s[4]),
                             (ex(s[5]), ex(s[6])), ex(s[7]))
        joints = joints_planar(order, user_index, cdata, absolute, lambda e: e)
    else:
        cdata = {}
        for b in order:
            s = slots[b.name]
            cdata[b.name] = (sp.Matrix([ex(i) for i in s[0]]),
                             sp.Matrix(3, 3, [ex(i) for i in s[1]]),
                             sp.Matrix([ex(i) for i in s[2]]), ex(s[3]),
                             sp.Matrix([ex(i) for i in s[4]]),
                             sp.Matrix(3, 3, [ex(i) for i in s[5]]))
        joints = joints_spatial(order, user_index, cdata, lambda e: e)
    gravity = [ex(i) for i in g_slots]
    if planar:
        gravity = gravity + [0]
    forces = [ex(i) for i in f_slots]
    for item, sl in zip(loop_items, l_slots):
        item["exprs"] = [ex(i) for i in sl]
    for item, sl in zip(pf_items, pf_slots):
        item["exprs"] = [ex(i) for i in sl]
    d = TreeDerived("constrained" if loop_items else "generalized", t=t, coords=c.plain,
                    coord_names=c.names, speeds=c.speeds, accels=c.accels, params=psyms,
                    param_names=names, param_values=values, with_jacobian=bool(jacobian))
    d.joints = joints
    d.gravity = gravity
    d.user_forces = forces
    d.gen_forces = None if pf_items else list(forces)
    d.loops = loop_items
    d.point_forces = pf_items
    d.planar = bool(planar)
    d.absolute = bool(absolute)
    d.cdata = cdata
    d.order_names = [b.name for b in order]
    d.aba_order = list(order)
    d.energy = None         # T + U, built when first read
    if loop_items:
        from .loops import count_rows
        d.n_hol = count_rows(loop_items)
        d.rheonomic = False
    return d


def _path_to_root(joints, k):
    out = []
    while k >= 0:
        out.append(k)
        k = joints[k].parent
    return out


def point_force_code(d, trig=None):
    """(code, Q) of the forces at points of bodies (d.point_forces): Q (user order) are
    expressions in the definitions of `code`: Q_rel_j = S_j . [p x F; F] over the joints
    j on the body's path (p the point and F the force in the ground frame), mapped by
    T^T for absolute angles (`trig`: the joint angles' cosines and sines computed
    elsewhere, as pos_pass). None when there are none."""
    if not getattr(d, "point_forces", None):
        return None
    joints = d.joints
    nb = len(joints)
    code = Code()
    qrel = [code.let(x) for x in relative(joints, d.coords)]
    pos, _ = pos_pass(code, joints, qrel, d.gravity, trig=trig)
    Qrel = [sp.Integer(0)]*nb
    for item in d.point_forces:
        k, dim, e = item["body"], item["npt"], item["exprs"]
        pt = list(e[:dim]) + [0]*(3 - dim)
        F = list(e[dim:2*dim]) + [0]*(3 - dim)
        R, p = pos[k]["R"], pos[k]["p"]
        pw = code.lv(_add(p, _matvec(R, pt)))
        Fw = code.lv(F if item["frame"] == "world" else _matvec(R, F))
        f6 = code.lv(_cross(pw, Fw) + Fw)
        for j in _path_to_root(joints, k):
            Qrel[j] = Qrel[j] + _dot(pos[j]["S"], f6)
    Q = [sp.Integer(0)]*nb
    for a, J in enumerate(joints):
        Q[J.col] += Qrel[a]
        if J.ka >= 0:
            Q[joints[J.ka].col] -= Qrel[a]
    return code, [code.let(x) for x in Q]


def forward_diff(code, outputs, xs):
    """Forward-mode derivatives of the expressions `outputs` (over the definitions of
    `code`) with respect to the symbols `xs`: a list (one per output) of {index in xs:
    expression}, the new definitions appended to `code` (each a short product of
    partial derivatives; the order is the definitions' order: a deterministic code)."""
    defs = code.live(outputs)
    rank = {x: -1 - i for i, x in enumerate(xs)}
    rank.update({s: i for i, (s, e) in enumerate(defs) if not isinstance(e, str)})
    deriv = {x: {i: sp.Integer(1)} for i, x in enumerate(xs)}

    def grad(e):
        acc = {}
        for u in sorted((u for u in e.free_symbols if u in deriv), key=rank.get):
            pe = sp.diff(e, u)
            if pe.has(sp.DiracDelta):
                pe = pe.replace(sp.DiracDelta, lambda *a: sp.S.Zero)
            if pe == 0:
                continue
            pe = code.let(pe)
            for j, val in deriv[u].items():
                acc[j] = acc.get(j, 0) + pe*val
        return {j: code.let(v) for j, v in sorted(acc.items()) if v != 0}
    for s, e in defs:
        if isinstance(e, str):
            continue
        g = grad(e)
        if g:
            deriv[s] = g
    return [grad(sp.sympify(o)) for o in outputs]
