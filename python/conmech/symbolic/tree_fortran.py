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

from .library_info import _model_info
from .loops import loop_code
from .printer import FortranPrinter, _decl_temps, _names, _wrap
from .kinematics import Code, _sym3, point_force_code, pos_pass, relative, vel_pass
from .tree_pairs import FIXED, straight_pairs
from .spatial_aba import _spatial_aba
from .tree_aba import _aba
from .tree_print import IND as _IND, SC_DECL, fast_print, pos_call, proc as _proc
from .tree_user import has_user_jac, user_forces, user_jac

__all__ = ["generate_tree"]


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
        s = sp.Dummy("ld")
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


def _loaded_pos(st, pos, keep_pose):
    """pos_pass's output as the values a later pass sees."""
    out = []
    for k, d in enumerate(pos):
        e = {"S": st.vector("sv", k, d["S"]), "alpha": st.vector("al", k, d["alpha"])}
        if d["I"] is not None:
            m, h, Io = d["I"]
            e["I"] = (st.scalar(m), [st.scalar(x) for x in h],
                      _sym3(lambda i, j: st.scalar(Io[i][j])))
            e["Jw"] = _sym3(lambda i, j: st.scalar(d["Jw"][i][j]))
            e["cw"] = [st.scalar(x) for x in d["cw"]]
        else:
            e["I"] = e["Jw"] = e["cw"] = None
        if d["Ic"] is not None:
            m, h, Io = d["Ic"]
            e["Ic"] = (st.scalar(m), [st.scalar(x) for x in h],
                       _sym3(lambda i, j: st.scalar(Io[i][j])))
        else:
            e["Ic"] = None
        if k in keep_pose:
            e["R"] = [[st.scalar(x) for x in row] for row in d["R"]]
            e["p"] = [st.scalar(x) for x in d["p"]]
        out.append(e)
    return out


class Emit:
    """Prints straight-line definitions and stores with conmech's Fortran printer: the
    coordinates, velocities, accelerations and parameters as q(i), v(i), a(i), p(i), the
    loads of earlier passes as their work-record targets."""

    def __init__(self, d, loads, cidx):
        names = _names(d)
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


#: a straight-line pass longer than CHUNK statements (CHUNK_LARGE for trees of more than
#: STRAIGHT_MAX bodies) is split into procedures of about that size: the compiler's time
#: grows faster than linearly with the size of one procedure (measured, gfortran -O3:
#: the seven-joint arm compiles in 0.83 of the time of whole passes at the same speed of
#: its accelerations, and a 30-joint chain in half the time with pieces of 150); the
#: values that cross from one piece to a later one go through an array
CHUNK = 300
CHUNK_LARGE = 150


def chunked(em, name, args, decls, blocks, prefix, size=None):
    """A straight-line pass as the procedure `name` (arguments `args`, declarations
    `decls`), from `blocks`: a list of (condition, definitions, stores), condition None
    (always), "deriv" or "plain" (the branches of ``if (deriv)``). Short passes are one
    procedure; long ones call pieces ``name_<k>`` with the values that cross pieces in a
    carry array. Returns the lines."""
    if size is None:
        size = CHUNK if em.nb <= STRAIGHT_MAX else CHUNK_LARGE
    total = sum(1 for _, defs, _ in blocks for _, e in defs if not isinstance(e, str))
    if em.nb <= WHOLE_MAX:
        size = max(size, total)
    I = _IND
    if total <= size:
        em.reset()
        body = []
        conds = [c for c, _, _ in blocks]
        for cond, defs, stores in blocks:
            ind = I if cond is None else I + "    "
            lines = em.defs(defs, prefix, ind) + em.assign(stores, ind)
            if cond == "deriv":
                lines = [f"{I}if (deriv) then"] + lines
            elif cond == "plain":
                lines = [f"{I}else" if "deriv" in conds else f"{I}if (.not. deriv) then"] \
                    + lines
            body += lines
        if "deriv" in conds or "plain" in conds:
            body.append(f"{I}end if")
        return _proc(f"subroutine {name}({', '.join(args)})", decls + em.temps(), body, name)
    # the pieces: consecutive definitions, each pivot check right after its definition
    chunks = []
    for cond, defs, stores in blocks:
        checks = {s_ for s_, e in defs if isinstance(e, str)}
        flat = []
        for s_, e in defs:
            if isinstance(e, str):
                continue
            flat.append((s_, e))
            if s_ in checks:
                flat.append((s_, "positive"))
        defs = flat
        start = len(chunks)
        cur, count = [], 0
        for item in defs:
            if not isinstance(item[1], str) and count >= size:
                chunks.append(dict(cond=cond, defs=cur, stores=[]))
                cur, count = [], 0
            cur.append(item)
            count += 0 if isinstance(item[1], str) else 1
        chunks.append(dict(cond=cond, defs=cur, stores=[]))
        where = {}
        for c in range(start, len(chunks)):
            for s_, e in chunks[c]["defs"]:
                where[s_] = c
        for tgt, e in stores:
            c = max([where[x] for x in sp.sympify(e).free_symbols if x in where],
                    default=start)
            chunks[c]["stores"].append((tgt, e))
    home = {}
    for c, ch in enumerate(chunks):
        for s_, e in ch["defs"]:
            if not isinstance(e, str):
                home[s_] = c
    carry = {}
    for c, ch in enumerate(chunks):
        used = set()
        for s_, e in ch["defs"]:
            if not isinstance(e, str):
                used |= e.free_symbols
        for tgt, e in ch["stores"]:
            used |= sp.sympify(e).free_symbols
        for x in home:                  # (in definition order: a deterministic source)
            if home[x] < c and x in used and x not in carry:
                carry[x] = len(carry) + 1
    ncx = max(len(carry), 1)
    out, calls = [], []
    cargs = [a for a in args if a != "deriv"] + ["cx"]
    cdecls = [d_ for d_ in decls if "deriv" not in d_] + \
        [f"{I}real(dp), intent(inout) :: cx({ncx})"]
    saved = dict(em.pr.names)
    for c, ch in enumerate(chunks):
        em.reset()
        for x, k in carry.items():
            if home[x] < c:
                em.pr.names[x] = f"cx({k})"
        lines = em.defs(ch["defs"], prefix)
        lines += [f"{I}cx({carry[x]}) = {em.local[x]}" for x, _ in ch["defs"]
                  if x in carry and x in em.local]
        lines += em.assign(ch["stores"])
        out += _proc(f"subroutine {name}_{c + 1}({', '.join(cargs)})",
                     cdecls + em.temps(), lines, f"{name}_{c + 1}")
        em.pr.names = dict(saved)
        calls.append((ch["cond"], f"call {name}_{c + 1}({', '.join(cargs)})"))
    body = []
    conds = [c for c, _ in calls]
    for cond in (None, "deriv", "plain"):
        mine = [call for c, call in calls if c == cond]
        if not mine:
            continue
        if cond is None:
            body += [f"{I}{x}" for x in mine]
        elif cond == "deriv":
            body += [f"{I}if (deriv) then"] + [f"{I}    {x}" for x in mine]
        else:
            body += ([f"{I}else"] if "deriv" in conds else [f"{I}if (.not. deriv) then"]) \
                + [f"{I}    {x}" for x in mine]
    if "deriv" in conds or "plain" in conds:
        body.append(f"{I}end if")
    return out + _proc(f"subroutine {name}({', '.join(args)})",
                       decls + [f"{I}real(dp) :: cx({ncx})"], body, name)


def generate_tree(d, module="conmech_symbolic_model", model_values=None):
    """(source, entry points) of the Fortran module of a :class:`TreeDerived` record."""
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
    qrel_expr = relative(joints, d.coords)
    qrel = [cp.let(x) for x in qrel_expr]
    # the sines and cosines of the joint angles: computed once per entry point (shared by
    # the articulated-body pass and the position pass of the Jacobian)
    trig = {k: (sp.Dummy("tc"), sp.Dummy("ts"))
            for k, J in enumerate(joints) if J.kind == "revolute"}
    pos, U = pos_pass(cp, joints, qrel, d.gravity, trig=trig)
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
    # the definitions both modes need, those of the plain mode only (tau, the kinetic
    # energy, the loops' velocities), those of the derivatives only
    plain_defs = cv.live([e for _, e in vel_out])
    deriv_defs = cv.live([e for _, e in deriv_out]) if jac else []
    dset = {s for s, _ in deriv_defs}
    pset = {s for s, _ in plain_defs}
    base_defs = [(s, e) for s, e in plain_defs if s in dset] if jac else plain_defs
    only_plain = [(s, e) for s, e in plain_defs if s not in dset] if jac else []
    extra = [(s, e) for s, e in deriv_defs if s not in pset]
    bset = {s for s, _ in base_defs}
    base_defs = [(s, e) for s, e in cv.live([e for _, e in vel_out + deriv_out])
                 if s in bset]
    # ---- what the position pass must store: the loads used later, the loop arrays
    used_by = [e for _, e in base_defs + extra + only_plain if not isinstance(e, str)] \
        + [e for _, e in vel_out + deriv_out] + (lc.expressions() if lc else [])
    pos_out = st.used(used_by, always=("sv", "al")) + [("w%pe", U)]
    active = {tgt[1] for tgt, _ in pos_out + deriv_out if not isinstance(tgt, str)}
    act = sorted(active) or [0]
    cidx = {c: i for i, c in enumerate(act)}
    na = len(act)
    # ---- printing
    em = Emit(d, {**st.loads, **st_vel.loads}, cidx)
    em.nb = nb
    for k, (c, sn) in trig.items():
        em.pr.names[c] = f"sc(1, {k + 1})"
        em.pr.names[sn] = f"sc(2, {k + 1})"
    em.trig_lines = []
    for k in sorted(trig):
        arg = fast_print(sp.sympify(qrel_expr[k]), em.pr.names, em.pr)
        em.trig_lines += [f"{_IND}sc(1, {k + 1}) = cos({arg})",
                          f"{_IND}sc(2, {k + 1}) = sin({arg})"]
    out = []
    out += chunked(em, "tree_pos", ["t", "q", "sc", "p", "w"],
                   [f"{_IND}real(dp), intent(in) :: t, q({n}), sc(2, nb), p({npar})",
                    f"{_IND}type(tree_work), intent(inout) :: w"],
                   [(None, cp.live([e for _, e in pos_out]),
                     _with_zeros(pos_out, ("sv", "al"), nb, act))], "s")
    if jac:
        blocks = [(None, base_defs, []),
                  ("deriv", extra, _with_zeros(deriv_out, ("ps", "cc", "et", "ph", "om"),
                                               nb, act)),
                  ("plain", only_plain, vel_out)]
    else:
        blocks = [(None, base_defs, vel_out)]
    out += chunked(em, "tree_vel", ["t", "q", "v", "a", "p", "w", "deriv"],
                   [f"{_IND}real(dp), intent(in) :: t, q({n}), v({n}), a({n}), p({npar})",
                    f"{_IND}type(tree_work), intent(inout) :: w",
                    f"{_IND}logical, intent(in) :: deriv"], blocks, "u")
    pfc = point_force_code(d)
    out += user_forces(d, em, pfc)
    if jac:
        out += user_jac(d, em, pfc)
    if not constrained:
        out += _aba_proc(d, em, trig, point_force_code(d, trig))
    chain = all(J.parent == k - 1 for k, J in enumerate(joints))
    fixed = FIXED.replace("ZEROH", "" if chain else f"{_IND}h = 0.0_dp")
    fixed = fixed.replace("ZEROX", "" if chain else f"{_IND}xt = 0.0_dp")
    if all(J.col == k for k, J in enumerate(joints)):       # the user's order is topological
        fixed = fixed.replace("UNTRANSPOSE", "\n".join([
            f"{_IND}do j = 1, nb", f"{_IND}    do i = 1, nb",
            f"{_IND}        r(i, j) = xt(j, i)", f"{_IND}        r(i, nb + j) = xt(nb + j, i)",
            f"{_IND}    end do", f"{_IND}end do"]))
    else:
        fixed = fixed.replace("UNTRANSPOSE", "\n".join([
            f"{_IND}do j = 1, nb", f"{_IND}    do i = 1, nb",
            f"{_IND}        r(col(i), col(j)) = xt(j, i)",
            f"{_IND}        r(col(i), nb + col(j)) = xt(nb + j, i)",
            f"{_IND}    end do", f"{_IND}end do"]))
    procs = fixed.split("\n    !> ")
    if nb <= STRAIGHT_MAX:
        # the pair loops written out: no loop overhead, structural zeros skipped
        nz = {}
        for tgt, e in pos_out + deriv_out:
            if not isinstance(tgt, str):
                nz.setdefault((tgt[0], tgt[2]), set()).add(cidx[tgt[1]] + 1)
        straight = straight_pairs(joints, nz, jac)
        procs = [next((v for key, v in straight.items() if pr.startswith(key)), pr)
                 for pr in procs]
    if not jac:     # what no entry point calls is not generated
        skip = ("tree_did", "tree_ltdl", "tree_ltdl_solve", "tree_abs_r", "tree_untranspose",
                "tree_solve_r")
        procs = [pr for pr in procs
                 if not any(f"subroutine {nm}(" in pr for nm in skip)]
    out += "\n    !> ".join(procs).splitlines() + [""]
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
        "!> Generated by conmech.symbolic (recursive algorithms of rigid-body dynamics):",
        f"!! a tree of {nb} bodies, {'constrained' if constrained else 'generalized'} "
        "system. Do not edit.",
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
                                        if len(h) > 90 and not h.startswith("!") else [h])]
    src = "\n".join(head + out + [f"end module {module}", ""])
    return src, ent


#: trees of at most this many bodies get the pair loops as straight-line code
STRAIGHT_MAX = 12
#: trees of at most this many bodies keep each straight-line pass in one procedure (none
#: by default: pieces of CHUNK statements compile faster at nearly the same speed)
WHOLE_MAX = 0


def _with_zeros(pairs, arrays, nb, act):
    """The stores `pairs` with explicit zeros for the entries of the loop arrays `arrays`
    that no store sets (instead of zeroing the arrays first)."""
    have = {tgt for tgt, _ in pairs if not isinstance(tgt, str)}
    out = list(pairs)
    for name in arrays:
        for k in range(nb):
            for c in act:
                if (name, c, k) not in have:
                    out.append(((name, c, k), sp.Integer(0)))
    return out


def _aba_proc(d, em, trig, pfc=None):
    """tree_aba(t, q, v, sc, a, p): the articulated-body accelerations (tree.py /
    spatial.py) on the sines and cosines sc; conmech_accel computes them and calls it."""
    n, npar = d.n, max(len(d.params), 1)
    order = d.aba_order
    index = {name: J.col for name, J in zip(d.order_names, d.joints)}
    btrig = {d.order_names[k]: cs for k, cs in trig.items()}
    tau = list(d.user_forces)
    pre = []
    if pfc is not None:         # the generalized forces of the point forces first
        code, Q = pfc
        pre = code.live(Q)
        tau = [a + b for a, b in zip(tau, Q)]
    if d.planar:
        defs, acc = _aba(order, index, d.cdata, list(d.coords), list(d.speeds), tau,
                         d.gravity[:2], d.absolute, trig=btrig)
    else:
        defs, acc = _spatial_aba(order, index, d.cdata, list(d.coords), list(d.speeds),
                                 tau, sp.Matrix(d.gravity), trig=btrig)
    defs = pre + list(defs)
    out = chunked(em, "tree_aba", ["t", "q", "v", "sc", "a", "p"],
                  [f"{_IND}real(dp), intent(in) :: t, q({n}), v({n}), sc(2, nb), p({npar})",
                   f"{_IND}real(dp), intent(inout) :: a({n})"],
                  [(None, defs, [(f"a({i + 1})", e) for i, e in enumerate(acc)])], "b")
    out += _proc('subroutine conmech_accel(t, q, v, a, p) bind(C, name="conmech_accel")',
                 [f"{_IND}real(dp), value, intent(in) :: t",
                  f"{_IND}real(dp), intent(in) :: q({n}), v({n})",
                  f"{_IND}real(dp), intent(out) :: a({n})",
                  f"{_IND}real(dp), intent(in) :: p({npar})", SC_DECL],
                 em.trig_lines + [f"{_IND}call tree_aba(t, q, v, sc, a, p)"],
                 "conmech_accel")
    return out


def _entries(d, n, npar, absolute, jac, constrained, lc, em):
    """The bind(C) entry points: (names, lines)."""
    I = _IND
    T = f"{I}real(dp), value, intent(in) :: t"
    P = f"{I}real(dp), intent(in) :: p({npar})"
    Q1 = f"{I}real(dp), intent(in) :: q({n})"
    QV = f"{I}real(dp), intent(in) :: q({n}), v({n})"
    W = f"{I}type(tree_work) :: w\n{SC_DECL}"

    def head(name, args):
        return f'subroutine conmech_{name}({", ".join(args)}) bind(C, name="conmech_{name}")'
    out, ent = [], []
    out += _proc(head("mass", ["t", "q", "mm", "p"]),
                 [T, Q1, f"{I}real(dp), intent(out) :: mm({n}, {n})", P, W],
                 pos_call(em) + [f"{I}call tree_mass_user(w, mm)"],
                 "conmech_mass")
    forces_body = [f"{I}z = 0.0_dp"] + pos_call(em) + [
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
            rbody = [f"{I}call tree_vel(t, q, v, a, p, w, .true.)",
                     f"{I}call tree_did(w, xt)"]
            if any(ka >= 0 for ka in (J.ka for J in d.joints)):
                rbody.append(f"{I}call tree_abs_r(xt)")
            if has_user_jac(d):
                rbody.append(f"{I}call tree_user_jac(t, q, v, p, xt)")
            XT = f"{I}real(dp) :: xt({2*n}, {n})"
            out += _proc(head("forces_jac", ["t", "q", "v", "a", "r", "p"]),
                         [T, QV, f"{I}real(dp), intent(in) :: a({n})",
                          f"{I}real(dp), intent(out) :: r({n}, {2*n})", P, W, XT],
                         pos_call(em) + rbody + [f"{I}call tree_untranspose(xt, r)"],
                         "conmech_forces_jac")
            out += _proc(head("accel_jac", ["t", "q", "v", "a", "jac", "p"]),
                         [T, QV, f"{I}real(dp), intent(out) :: a({n}), jac({n}, {2*n})", P, W,
                          XT, f"{I}real(dp) :: h({n}, {n})"],
                         em.trig_lines + [f"{I}call tree_aba(t, q, v, sc, a, p)",
                                          f"{I}call tree_pos(t, q, sc, p, w)"] + rbody
                         + [f"{I}call tree_mass_topo(w, h)", f"{I}call tree_ltdl(h)",
                            f"{I}call tree_solve_r(h, xt)",
                            f"{I}call tree_untranspose(xt, jac)"], "conmech_accel_jac")
            ent += ["forces_jac", "accel_jac"]
    out += ["    function conmech_energy(t, q, v, p) bind(C, name=\"conmech_energy\") "
            "result(e)", T, QV, P, f"{I}real(dp) :: e", W, f"{I}real(dp) :: z({n})",
            f"{I}z = 0.0_dp"] + pos_call(em) + [
            f"{I}call tree_vel(t, q, v, z, p, w, .false.)", f"{I}e = w%ke + w%pe",
            "    end function conmech_energy", ""]
    ent.append("energy")
    if constrained:
        out += lc.procedures(em, n, npar)
        ent += ["phi", "phi_jac", "phi_gamma"]
    return ent, out
