"""The articulated-body algorithm of planar trees as straight-line sympy definitions
(:class:`_Code`: definitions with numbers and single symbols propagated, pivots marked
positive): the accelerations a = M^-1 Q in O(n) operations, which the generated conmech_accel
and tree_aba evaluate."""
import sympy as sp



def _check_pivot(code, D, body):
    """The articulated inertia D of the joint of `body`: a number must be positive (else the
    mass matrix is not positive definite: ValueError naming the body), an expression is
    marked as a pivot that the generated code checks."""
    if D.is_Number:
        if not D > 0:
            raise ValueError(f"body '{body}': the articulated inertia of its joint is "
                             f"{D}: the mass matrix is not positive definite")
    else:
        code.positive(D, body)


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
        _check_pivot(code, D, b.name)
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

    def positive(self, s, body=None):
        """Mark s (a defined symbol) as a pivot that must be positive: the marker is the
        text "positive", followed by the body whose joint it belongs to (for messages)."""
        self.defs.append((s, "positive" if body is None else f"positive: body '{body}'"))
