"""Fortran of a tree derived by the recursive algorithms (:mod:`conmech.symbolic.recursive`).

One module: the straight-line passes as module procedures that fill a work record
(``tree_pos``: positions, motion subspaces, inertias, composite inertias; ``tree_vel``:
velocities, accelerations, forces, the joint forces of inverse dynamics and, on request,
the vectors of its derivatives; ``tree_aba``: the articulated-body accelerations), a few
fixed procedures with loops over the ancestor pairs (mass matrix, derivatives of inverse
dynamics, the tree-sparse L^T D L factorisation and its solve, the maps of absolute
angles), and thin bind(C) entry points with the C signatures of ``conmech.compiled``.
Values a later pass needs are handed over in the work record; values that are numbers or
parameters are folded into the code instead (so a joint axis along z costs nothing). The
generated identifiers come from indices only.
"""
import sympy as sp

from .codegen import FortranPrinter, _decl_temps, _model_info, _wrap, assignments, prepare
from .recursive import Code, pos_pass, relative, vel_pass

__all__ = ["generate_tree"]

_IND = "        "


class _Store:
    """What one pass hands to the next: scalars in the flat slots w%x(k) and vectors in
    the loop arrays w%NAME(c, k) (compressed spatial components, resolved when printed).
    A number or a symbol of `inline` (parameters, coordinates, t) is folded instead. Each
    stored value is (load symbol, target, expression); only the loads a later pass uses
    are written (:meth:`used`)."""

    def __init__(self, inline):
        self.inline = set(inline)
        self.nx = 0
        self.items = []          # (Dummy, target, expression)
        self.loads = {}          # Dummy -> target

    def _new(self, tgt, e):
        s = sp.Dummy("ld", real=True)
        self.items.append((s, tgt, e))
        self.loads[s] = tgt
        return s

    def scalar(self, e):
        e = sp.sympify(e)
        if e.is_Number or e in self.inline:
            return e
        self.nx += 1
        return self._new(f"w%x({self.nx})", e)

    def vector(self, name, k, vec):
        out = []
        for i, e in enumerate(vec):
            e = sp.sympify(e)
            out.append(sp.Integer(0) if e == 0 else self._new((name, i, k), e))
        return out

    def used(self, exprs, always=()):
        """(target, expression) of the stored values the expressions refer to, and of
        the loop arrays named in `always`."""
        need = set()
        for e in exprs:
            need |= sp.sympify(e).free_symbols
        return [(tgt, e) for s, tgt, e in self.items
                if s in need or (not isinstance(tgt, str) and tgt[0] in always)]


def fast_print(e, names, pr):
    """Fortran text of a straight-line definition: sums, products, integer powers,
    numbers, symbols (through `names`), sin and cos printed directly (much faster than
    the general printer, which orders the terms first); anything else through the
    printer `pr` (conmech's FortranPrinter)."""
    if e.is_Symbol:
        return names[e]
    if e.is_Number:
        return _num(e, pr)
    if e.is_Add:
        out = []
        for a in e.args:
            c, r = a.as_coeff_Mul()
            if c.is_Number and c < 0:
                txt = fast_print(-a, names, pr)
                out.append(f" - {txt}" if out else f"-{txt}")
            else:
                txt = fast_print(a, names, pr)
                out.append(f" + {txt}" if out else txt)
        return "".join(out)
    if e.is_Mul:
        num, den = [], []
        sign = ""
        for f in e.args:
            if f.is_Number:
                if f == -1:
                    sign = "-"
                    continue
                num.append(_num(f, pr))     # a ratio: a folded constant, no division
            elif f.is_Pow and f.exp.is_Integer and f.exp < 0:
                den.append(_factor(f.base**(-f.exp), names, pr))
            else:
                num.append(_factor(f, names, pr))
        txt = "*".join(num) if num else _num(sp.Integer(1), pr)
        if den:
            txt += "/" + (den[0] if len(den) == 1 else "(" + "*".join(den) + ")")
        return sign + txt
    if e.is_Pow and e.exp.is_Integer:
        k = int(e.exp)
        if k > 0:
            return f"{_factor(e.base, names, pr)}**{k}"
        return f"{_num(sp.Integer(1), pr)}/{_factor(e.base**(-k), names, pr)}"
    if isinstance(e, (sp.sin, sp.cos)):
        return f"{type(e).__name__}({fast_print(e.args[0], names, pr)})"
    saved = pr.names
    pr.names = names
    try:
        return pr._print(prepare(e))
    finally:
        pr.names = saved


def _factor(f, names, pr):
    txt = fast_print(f, names, pr)
    if f.is_Add or (f.is_Number and f < 0) or (f.is_Mul and (txt.startswith("-")
                                                              or "/" in txt)):
        return f"({txt})"
    if f.is_Pow:
        return f"({txt})" if "/" in txt else txt
    return txt


def _num(x, pr):
    if x.is_Integer or x.is_Float:
        txt = pr._real(x)
    else:
        txt = pr._print(x)
    return f"({txt})" if txt.startswith("-") else txt


def _loaded_pos(st, pos, keep_pose):
    """pos_pass's output as the values a later pass sees."""
    out = []
    for k, d in enumerate(pos):
        e = {"S": st.vector("sv", k, d["S"]), "alpha": st.vector("al", k, d["alpha"])}
        if d["I"] is not None:
            m, h, Io = d["I"]
            e["I"] = (st.scalar(m), [st.scalar(x) for x in h],
                      _sym(lambda i, j: st.scalar(Io[i][j])))
            e["Jw"] = _sym(lambda i, j: st.scalar(d["Jw"][i][j]))
            e["cw"] = [st.scalar(x) for x in d["cw"]]
        else:
            e["I"] = e["Jw"] = e["cw"] = None
        if d["Ic"] is not None:
            m, h, Io = d["Ic"]
            e["Ic"] = (st.scalar(m), [st.scalar(x) for x in h],
                       _sym(lambda i, j: st.scalar(Io[i][j])))
        else:
            e["Ic"] = None
        if k in keep_pose:
            e["R"] = [[st.scalar(x) for x in row] for row in d["R"]]
            e["p"] = [st.scalar(x) for x in d["p"]]
        out.append(e)
    return out


def _sym(f):
    M = [[None]*3 for _ in range(3)]
    for i in range(3):
        for j in range(i, 3):
            M[i][j] = M[j][i] = f(i, j)
    return M


class Emit:
    """Prints straight-line definitions and stores with conmech's Fortran printer: the
    coordinates, velocities, accelerations and parameters as q(i), v(i), a(i), p(i), the
    loads of earlier passes as their work-record targets."""

    def __init__(self, d, loads, cidx):
        names = {d.t: "t"}
        for i, s in enumerate(d.coords):
            names[s] = f"q({i + 1})"
        for i, s in enumerate(d.speeds):
            names[s] = f"v({i + 1})"
        for i, s in enumerate(d.accels):
            names[s] = f"a({i + 1})"
        for i, s in enumerate(d.params):
            names[s] = f"p({i + 1})"
        self.cidx = cidx
        for s, tgt in loads.items():
            names[s] = self.target(tgt)
        self.pr = FortranPrinter(names)
        self.local = {}

    def target(self, tgt):
        if isinstance(tgt, str):
            return tgt
        name, i, k = tgt
        return f"w%{name}({self.cidx[i] + 1}, {k + 1})"

    def reset(self):
        self.local = {}

    def defs(self, defs, prefix, ind=_IND):
        """Statements of the definitions (new local names prefix<k>, kept for later
        defs() and assign() calls until reset())."""
        lines = []
        saved = self.pr.names
        self.pr.names = {**saved, **self.local}
        try:
            for s, e in defs:
                if isinstance(e, str):      # "positive": a pivot check
                    nm = self.local[s]
                    lines.append(f"{ind}if (.not. ({nm} > 0.0_dp)) {nm} = 0.0_dp")
                    continue
                nm = f"{prefix}{len(self.local) + 1}"
                lines += _wrap(f"{nm} = {fast_print(e, self.pr.names, self.pr)}", ind)
                self.local[s] = nm
                self.pr.names[s] = nm
        finally:
            self.pr.names = saved
        return lines

    def assign(self, pairs, ind=_IND):
        saved = self.pr.names
        self.pr.names = {**saved, **self.local}
        try:
            out = []
            for tgt, e in pairs:
                out += _wrap(f"{self.target(tgt)} = "
                             f"{fast_print(sp.sympify(e), self.pr.names, self.pr)}", ind)
        finally:
            self.pr.names = saved
        return out

    def temps(self):
        return _decl_temps(list(self.local.values()))


def _proc(head, decls, body, name, kind="subroutine"):
    return [f"    {head}"] + decls + body + [f"    end {kind} {name}", ""]


def generate_tree(d, module="conmech_symbolic_model", model_values=None):
    """(source, entry points) of the Fortran module of a :class:`TreeDerived` record."""
    from .loops import loop_code
    joints = d.joints
    n = nb = len(joints)
    npar = max(len(d.params), 1)
    absolute = any(J.ka >= 0 for J in joints)
    constrained = d.kind == "constrained"
    jac = bool(d.with_jacobian) and not constrained
    st = _Store(set(d.params) | set(d.coords) | {d.t})
    keep_pose = set()
    for item in d.loops:
        keep_pose |= {k for k in item["bodies"] if k >= 0}
    # ---- position pass
    cp = Code()
    qrel = [cp.let(x) for x in relative(joints, d.coords)]
    pos, U = pos_pass(cp, joints, qrel, d.gravity)
    lpos = _loaded_pos(st, pos, keep_pose)
    # ---- velocity pass (on the loaded positions)
    cv = Code()
    vrel = [cv.let(x) for x in relative(joints, d.speeds)]
    arel = [cv.let(x) for x in relative(joints, d.accels)]
    vel, T = vel_pass(cv, joints, lpos, vrel, arel, d.gravity, deriv=jac)
    vel_out = [(f"w%tau({k + 1})", vel[k]["tau"]) for k in range(nb)] + [("w%ke", T)]
    st_vel = _Store(st.inline)
    st_vel.nx = st.nx
    for k in sorted(keep_pose):
        vel[k]["v_load"] = [st_vel.scalar(x) for x in vel[k]["v"]]
        vel[k]["a_load"] = [st_vel.scalar(x) for x in vel[k]["a"]]
    vel_out += [(tgt, e) for _, tgt, e in st_vel.items]
    deriv_out = []
    if jac:
        for k in range(nb):
            for name, key in (("ps", "psi"), ("cc", "c"), ("et", "eta"), ("ph", "Phi"),
                              ("om", "Omega")):
                for i, e in enumerate(vel[k][key]):
                    if sp.sympify(e) != 0:
                        deriv_out.append(((name, i, k), e))
    # ---- loop constraints (on loaded positions and velocities)
    lc = loop_code(d, joints, lpos, vel) if constrained else None
    base_defs = cv.live([e for _, e in vel_out])
    base_set = {s for s, _ in base_defs}
    extra = [(s, e) for s, e in cv.live([e for _, e in vel_out + deriv_out])
             if s not in base_set]
    # ---- what the position pass must store: the loads used later, the loop arrays
    used_by = [e for _, e in base_defs + extra if not isinstance(e, str)] \
        + [e for _, e in vel_out + deriv_out] + (lc.expressions() if lc else [])
    pos_out = st.used(used_by, always=("sv", "al")) + [("w%pe", U)]
    active = {tgt[1] for tgt, _ in pos_out + deriv_out if not isinstance(tgt, str)}
    act = sorted(active) or [0]
    cidx = {c: i for i, c in enumerate(act)}
    na = len(act)
    # ---- printing
    em = Emit(d, {**st.loads, **st_vel.loads}, cidx)
    out = []
    em.reset()
    lines = em.defs(cp.live([e for _, e in pos_out]), "s")
    lines += [f"{_IND}w%{a} = 0.0_dp" for a in ("sv", "al")] + em.assign(pos_out)
    out += _proc("subroutine tree_pos(t, q, p, w)",
                 [f"{_IND}real(dp), intent(in) :: t, q({n}), p({npar})",
                  f"{_IND}type(tree_work), intent(inout) :: w"] + em.temps(),
                 lines, "tree_pos")
    em.reset()
    body = em.defs(base_defs, "u") + em.assign(vel_out)
    if jac:
        body += [f"{_IND}if (deriv) then"]
        body += [f"{_IND}    w%{a} = 0.0_dp" for a in ("ps", "cc", "et", "ph", "om")]
        body += em.defs(extra, "u", _IND + "    ") + em.assign(deriv_out, _IND + "    ")
        body += [f"{_IND}end if"]
    out += _proc("subroutine tree_vel(t, q, v, a, p, w, deriv)",
                 [f"{_IND}real(dp), intent(in) :: t, q({n}), v({n}), a({n}), p({npar})",
                  f"{_IND}type(tree_work), intent(inout) :: w",
                  f"{_IND}logical, intent(in) :: deriv"] + em.temps(),
                 body, "tree_vel")
    em.reset()
    out += _user_forces(d, em.pr)
    if jac:
        out += _user_jac(d, em.pr)
    if not constrained:
        out += _aba_proc(d, em)
    out += _FIXED.splitlines() + [""]
    # ---- entry points
    ent, procs = _entries(d, n, npar, absolute, jac, constrained, lc, em)
    out += procs
    if model_values is not None:
        if len(model_values) != len(d.params):
            raise ValueError(f"{len(model_values)} parameter values for {len(d.params)} "
                             "parameters")
        out += _model_info(d, model_values)
    par = ", ".join(str(J.parent + 1) for J in joints)
    col = ", ".join(str(J.col + 1) for J in joints)
    ka = ", ".join(str(J.ka + 1) for J in joints)
    head = [
        f"!> Generated by conmech.symbolic (recursive algorithms): a tree of {nb} bodies, "
        f"{'constrained' if constrained else 'generalized'} system.",
        "!! Do not edit.",
        f"module {module}",
        "    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_char, c_null_char",
        "    implicit none",
        "    integer, parameter :: dp = c_double",
        f"    integer, parameter :: nb = {nb}, na = {na}",
        f"    integer, parameter :: par(nb) = [{par}]",
        f"    integer, parameter :: col(nb) = [{col}]",
        f"    integer, parameter :: ka(nb) = [{ka}]",
        "    type :: tree_work",
        f"        real(dp) :: x({max(st_vel.nx, 1)})",
        "        real(dp) :: sv(na, nb), al(na, nb)",
        "        real(dp) :: ps(na, nb), cc(na, nb), et(na, nb), ph(na, nb), om(na, nb)",
        "        real(dp) :: tau(nb), ke, pe",
        "    end type tree_work",
        "    private",
        "    public :: " + ", ".join(f"conmech_{e}" for e in ent) + (
            ", conmech_model_info, conmech_model_params, conmech_model_param_names"
            if model_values is not None else ""),
        "contains",
        "",
    ]
    head = [ln for h in head for ln in (_wrap(h.strip(), h[:len(h) - len(h.lstrip())])
                                        if len(h) > 90 else [h])]
    src = "\n".join(head + out + [f"end module {module}", ""])
    return src, ent


def _user_forces(d, pr):
    """tree_user_forces(t, q, v, p, fu): the user's generalized forces (user order)."""
    n, npar = d.n, max(len(d.params), 1)
    fl = [sp.sympify(e) for e in d.user_forces]
    tg = [f"fu({i + 1})" for i, e in enumerate(fl) if e != 0]
    ex = [e for e in fl if e != 0]
    temps, lines = assignments(tg, ex, pr, _IND, prefix="f") if ex else ([], [])
    return _proc("subroutine tree_user_forces(t, q, v, p, fu)",
                 [f"{_IND}real(dp), intent(in) :: t, q({n}), v({n}), p({npar})",
                  f"{_IND}real(dp), intent(out) :: fu({n})"] + _decl_temps(temps),
                 [f"{_IND}fu = 0.0_dp"] + lines, "tree_user_forces")


def _user_jac(d, pr):
    """tree_user_jac(t, q, v, p, ru): d(user forces)/d[q, v] (n x 2n)."""
    n, npar = d.n, max(len(d.params), 1)
    xs = list(d.coords) + list(d.speeds)
    tg, ex = [], []
    for i, e in enumerate(d.user_forces):
        e = sp.sympify(e)
        if e == 0:
            continue
        for j, x in enumerate(xs):
            if x in e.free_symbols:
                de = sp.diff(e, x)
                if de.has(sp.DiracDelta):
                    de = de.replace(sp.DiracDelta, lambda *a: sp.S.Zero)
                if de != 0:
                    tg.append(f"ru({i + 1}, {j + 1})")
                    ex.append(de)
    temps, lines = assignments(tg, ex, pr, _IND, prefix="g") if ex else ([], [])
    return _proc("subroutine tree_user_jac(t, q, v, p, ru)",
                 [f"{_IND}real(dp), intent(in) :: t, q({n}), v({n}), p({npar})",
                  f"{_IND}real(dp), intent(out) :: ru({n}, {2*n})"] + _decl_temps(temps),
                 [f"{_IND}ru = 0.0_dp"] + lines, "tree_user_jac")


def _aba_proc(d, em):
    """tree_aba(t, q, v, a, p): the articulated-body accelerations (tree.py / spatial.py)."""
    from .tree import _aba
    from .spatial import _spatial_aba
    n, npar = d.n, max(len(d.params), 1)
    order = d.aba_order
    index = {name: J.col for name, J in zip(d.order_names, d.joints)}
    if d.planar:
        defs, acc = _aba(order, index, d.cdata, list(d.coords), list(d.speeds),
                         list(d.user_forces), d.gravity[:2], d.absolute)
    else:
        defs, acc = _spatial_aba(order, index, d.cdata, list(d.coords), list(d.speeds),
                                 list(d.user_forces), sp.Matrix(d.gravity))
    em.reset()
    body = em.defs(defs, "b") + em.assign([(f"a({i + 1})", e) for i, e in enumerate(acc)])
    return _proc('subroutine conmech_accel(t, q, v, a, p) bind(C, name="conmech_accel")',
                 [f"{_IND}real(dp), value, intent(in) :: t",
                  f"{_IND}real(dp), intent(in) :: q({n}), v({n})",
                  f"{_IND}real(dp), intent(out) :: a({n})",
                  f"{_IND}real(dp), intent(in) :: p({npar})"] + em.temps(), body,
                 "conmech_accel")


# fixed procedures: mass matrix (composite rigid bodies), derivatives of inverse dynamics
# over the ancestor pairs, L^T D L factorisation of M and its solve (Featherstone,
# Rigid Body Dynamics Algorithms, 6.5: the sparsity of the tree), maps of absolute angles
_FIXED = """
    !> M (relative coordinates, topological order): M_jk = S_j . alpha_k, j an ancestor
    !! of k or k.
    pure subroutine tree_mass_topo(w, h)
        type(tree_work), intent(in) :: w
        real(dp), intent(out) :: h(nb, nb)
        integer :: j, k
        real(dp) :: s
        h = 0.0_dp
        do k = 1, nb
            j = k
            do while (j > 0)
                s = dot_product(w%sv(:, j), w%al(:, k))
                h(j, k) = s
                h(k, j) = s
                j = par(j)
            end do
        end do
    end subroutine tree_mass_topo

    !> d tau / d q and d tau / d qd of inverse dynamics (relative, topological).
    pure subroutine tree_did(w, dq, dv)
        type(tree_work), intent(in) :: w
        real(dp), intent(out) :: dq(nb, nb), dv(nb, nb)
        integer :: j, k
        dq = 0.0_dp
        dv = 0.0_dp
        do k = 1, nb
            j = k
            do while (j > 0)
                dq(k, j) = dot_product(w%al(:, k), w%cc(:, j)) &
                    + dot_product(w%et(:, k), w%ps(:, j))
                dv(k, j) = 2.0_dp*dot_product(w%al(:, k), w%ps(:, j)) &
                    + dot_product(w%et(:, k), w%sv(:, j))
                if (j /= k) then
                    dq(j, k) = dot_product(w%sv(:, j), w%ph(:, k))
                    dv(j, k) = dot_product(w%sv(:, j), w%om(:, k))
                end if
                j = par(j)
            end do
        end do
    end subroutine tree_did

    !> M = L^T D L in place (L unit lower triangular with the tree's sparsity, D on the
    !! diagonal); a pivot that is not positive makes the factor NaN.
    pure subroutine tree_ltdl(h)
        real(dp), intent(inout) :: h(nb, nb)
        integer :: i, j, k
        real(dp) :: a
        do k = nb, 1, -1
            if (.not. (h(k, k) > 0.0_dp)) h(k, k) = 0.0_dp
            i = par(k)
            do while (i > 0)
                a = h(k, i)/h(k, k)
                j = i
                do while (j > 0)
                    h(i, j) = h(i, j) - a*h(k, j)
                    j = par(j)
                end do
                h(k, i) = a
                i = par(i)
            end do
        end do
    end subroutine tree_ltdl

    !> x := M^-1 x for the columns of x, M = L^T D L from tree_ltdl.
    pure subroutine tree_ltdl_solve(h, m, x)
        real(dp), intent(in) :: h(nb, nb)
        integer, intent(in) :: m
        real(dp), intent(inout) :: x(nb, m)
        integer :: i, j
        do i = nb, 1, -1
            j = par(i)
            do while (j > 0)
                x(j, :) = x(j, :) - h(i, j)*x(i, :)
                j = par(j)
            end do
        end do
        do i = 1, nb
            x(i, :) = x(i, :)/h(i, i)
        end do
        do i = 1, nb
            j = par(i)
            do while (j > 0)
                x(i, :) = x(i, :) - h(i, j)*x(j, :)
                j = par(j)
            end do
        end do
    end subroutine tree_ltdl_solve

    !> x := T^T x (rows; T maps absolute to relative angles).
    pure subroutine tree_tt_left(m, x)
        integer, intent(in) :: m
        real(dp), intent(inout) :: x(nb, m)
        real(dp) :: y(nb, m)
        integer :: k
        y = x
        do k = 1, nb
            if (ka(k) > 0) x(ka(k), :) = x(ka(k), :) - y(k, :)
        end do
    end subroutine tree_tt_left

    !> x := x T (columns).
    pure subroutine tree_t_right(m, x)
        integer, intent(in) :: m
        real(dp), intent(inout) :: x(m, nb)
        real(dp) :: y(m, nb)
        integer :: k
        y = x
        do k = 1, nb
            if (ka(k) > 0) x(:, ka(k)) = x(:, ka(k)) - y(:, k)
        end do
    end subroutine tree_t_right

    !> x := T^-T x (rows: subtree sums along the revolute ancestors).
    pure subroutine tree_tinvt_left(m, x)
        integer, intent(in) :: m
        real(dp), intent(inout) :: x(nb, m)
        integer :: k
        do k = nb, 1, -1
            if (ka(k) > 0) x(ka(k), :) = x(ka(k), :) + x(k, :)
        end do
    end subroutine tree_tinvt_left

    !> x := T^-1 x (rows: accumulated along the revolute ancestors).
    pure subroutine tree_tinv_left(m, x)
        integer, intent(in) :: m
        real(dp), intent(inout) :: x(nb, m)
        integer :: k
        do k = 1, nb
            if (ka(k) > 0) x(k, :) = x(k, :) + x(ka(k), :)
        end do
    end subroutine tree_tinv_left

    !> M in the user's coordinates and order.
    pure subroutine tree_mass_user(w, mm)
        type(tree_work), intent(in) :: w
        real(dp), intent(out) :: mm(nb, nb)
        real(dp) :: h(nb, nb)
        integer :: i, j
        call tree_mass_topo(w, h)
        if (any(ka > 0)) then
            call tree_tt_left(nb, h)
            call tree_t_right(nb, h)
        end if
        do j = 1, nb
            do i = 1, nb
                mm(col(i), col(j)) = h(i, j)
            end do
        end do
    end subroutine tree_mass_user

    !> Q = fu - T^T tau in the user's order.
    pure subroutine tree_q_user(w, fu, f)
        type(tree_work), intent(in) :: w
        real(dp), intent(in) :: fu(nb)
        real(dp), intent(out) :: f(nb)
        real(dp) :: y(nb, 1)
        integer :: i
        y(:, 1) = w%tau
        if (any(ka > 0)) call tree_tt_left(1, y)
        do i = 1, nb
            f(col(i)) = fu(col(i)) - y(i, 1)
        end do
    end subroutine tree_q_user

    !> R = d(fu)/d[q, v] - T^T dID/d[q, v] diag(T, T), user order (ru: the user part).
    pure subroutine tree_r_user(w, ru, r)
        type(tree_work), intent(in) :: w
        real(dp), intent(in) :: ru(nb, 2*nb)
        real(dp), intent(out) :: r(nb, 2*nb)
        real(dp) :: dq(nb, nb), dv(nb, nb)
        integer :: i, j
        call tree_did(w, dq, dv)
        if (any(ka > 0)) then
            call tree_tt_left(nb, dq)
            call tree_t_right(nb, dq)
            call tree_tt_left(nb, dv)
            call tree_t_right(nb, dv)
        end if
        r = ru
        do j = 1, nb
            do i = 1, nb
                r(col(i), col(j)) = r(col(i), col(j)) - dq(i, j)
                r(col(i), nb + col(j)) = r(col(i), nb + col(j)) - dv(i, j)
            end do
        end do
    end subroutine tree_r_user

    !> d a / d[q, v] = T^-1 M_rel^-1 T^-T R (user order).
    pure subroutine tree_accel_jac_user(w, r, jac)
        type(tree_work), intent(in) :: w
        real(dp), intent(in) :: r(nb, 2*nb)
        real(dp), intent(out) :: jac(nb, 2*nb)
        real(dp) :: h(nb, nb), x(nb, 2*nb)
        integer :: i, j
        do j = 1, nb
            do i = 1, nb
                x(i, j) = r(col(i), col(j))
                x(i, nb + j) = r(col(i), nb + col(j))
            end do
        end do
        call tree_mass_topo(w, h)
        call tree_ltdl(h)
        if (any(ka > 0)) call tree_tinvt_left(2*nb, x)
        call tree_ltdl_solve(h, 2*nb, x)
        if (any(ka > 0)) call tree_tinv_left(2*nb, x)
        do j = 1, nb
            do i = 1, nb
                jac(col(i), col(j)) = x(i, j)
                jac(col(i), nb + col(j)) = x(i, nb + j)
            end do
        end do
    end subroutine tree_accel_jac_user
"""


def _entries(d, n, npar, absolute, jac, constrained, lc, em):
    """The bind(C) entry points: (names, lines)."""
    I = _IND
    T = f"{I}real(dp), value, intent(in) :: t"
    P = f"{I}real(dp), intent(in) :: p({npar})"
    Q1 = f"{I}real(dp), intent(in) :: q({n})"
    QV = f"{I}real(dp), intent(in) :: q({n}), v({n})"
    W = f"{I}type(tree_work) :: w"

    def head(name, args):
        return f'subroutine conmech_{name}({", ".join(args)}) bind(C, name="conmech_{name}")'
    out, ent = [], []
    out += _proc(head("mass", ["t", "q", "mm", "p"]),
                 [T, Q1, f"{I}real(dp), intent(out) :: mm({n}, {n})", P, W],
                 [f"{I}call tree_pos(t, q, p, w)", f"{I}call tree_mass_user(w, mm)"],
                 "conmech_mass")
    forces_body = [f"{I}z = 0.0_dp", f"{I}call tree_pos(t, q, p, w)",
                   f"{I}call tree_vel(t, q, v, z, p, w, .false.)",
                   f"{I}call tree_user_forces(t, q, v, p, fu)",
                   f"{I}call tree_q_user(w, fu, f)"]
    out += _proc(head("forces", ["t", "q", "v", "f", "p"]),
                 [T, QV, f"{I}real(dp), intent(out) :: f({n})", P, W,
                  f"{I}real(dp) :: z({n}), fu({n})"], forces_body, "conmech_forces")
    ent += ["mass", "forces"]
    if not constrained:
        out += _proc(head("mass_forces", ["t", "q", "v", "mm", "f", "p"]),
                     [T, QV, f"{I}real(dp), intent(out) :: mm({n}, {n}), f({n})", P, W,
                      f"{I}real(dp) :: z({n}), fu({n})"],
                     forces_body + [f"{I}call tree_mass_user(w, mm)"], "conmech_mass_forces")
        ent += ["mass_forces", "accel"]
        if jac:
            rbody = [f"{I}call tree_pos(t, q, p, w)",
                     f"{I}call tree_vel(t, q, v, a, p, w, .true.)",
                     f"{I}call tree_user_jac(t, q, v, p, ru)",
                     f"{I}call tree_r_user(w, ru, r)"]
            out += _proc(head("forces_jac", ["t", "q", "v", "a", "r", "p"]),
                         [T, QV, f"{I}real(dp), intent(in) :: a({n})",
                          f"{I}real(dp), intent(out) :: r({n}, {2*n})", P, W,
                          f"{I}real(dp) :: ru({n}, {2*n})"], rbody, "conmech_forces_jac")
            out += _proc(head("accel_jac", ["t", "q", "v", "a", "jac", "p"]),
                         [T, QV, f"{I}real(dp), intent(out) :: a({n}), jac({n}, {2*n})", P, W,
                          f"{I}real(dp) :: ru({n}, {2*n}), r({n}, {2*n})"],
                         [f"{I}call conmech_accel(t, q, v, a, p)"] + rbody
                         + [f"{I}call tree_accel_jac_user(w, r, jac)"], "conmech_accel_jac")
            ent += ["forces_jac", "accel_jac"]
    out += ["    function conmech_energy(t, q, v, p) bind(C, name=\"conmech_energy\") "
            "result(e)", T, QV, P, f"{I}real(dp) :: e", W, f"{I}real(dp) :: z({n})",
            f"{I}z = 0.0_dp", f"{I}call tree_pos(t, q, p, w)",
            f"{I}call tree_vel(t, q, v, z, p, w, .false.)", f"{I}e = w%ke + w%pe",
            "    end function conmech_energy", ""]
    ent.append("energy")
    if constrained:
        out += lc.procedures(em, n, npar)
        ent += ["phi", "phi_jac", "phi_gamma"]
    return ent, out
