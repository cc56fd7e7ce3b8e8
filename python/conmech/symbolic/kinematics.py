"""The straight-line kinematics of the recursive tree algorithms (the formulas are in
:mod:`conmech.symbolic.recursive`): :class:`Code` (straight-line definitions with a cheap
common-subexpression elimination), the 3-D and spatial vector algebra on lists of sympy
expressions, the normalised joints of planar and spatial trees, the position and velocity
passes, the generalized forces of forces at points of bodies, and forward-mode derivatives over
a straight-line code."""
import sympy as sp

from .._core.result import Record

_I3 = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]


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


class Joint(Record):
    """One body and its joint, in world-frame terms (topological order): parent index (-1:
    the ground), kind, joint placement (at, rot), axis, mass, com, inertia about the COM
    (3x3 or None), the user's coordinate index `col` and, for absolute planar angles, the
    index `ka` of the nearest revolute ancestor (-1: none)."""

    __slots__ = ("name", "parent", "kind", "at", "rot", "axis", "mass", "com", "inertia",
                 "col", "ka")


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


def _path_to_root(joints, k):
    """The joint k and its ancestors' joints, up to the root."""
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
