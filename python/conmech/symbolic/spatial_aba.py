"""The articulated-body algorithm of spatial trees as straight-line sympy
definitions (3-D joints about an axis, Rodrigues' rotation; the planar version is
:mod:`conmech.symbolic.tree_aba`)."""
import sympy as sp

from .tree_aba import _Code, _check_pivot


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
        _check_pivot(code, D, b.name)
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


def _rodrigues(k, c, s):
    """The rotation by the angle with cosine c and sine s about the unit axis k."""
    K = sp.Matrix([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return c*sp.eye(3) + s*K + (1 - c)*(k*k.T)
