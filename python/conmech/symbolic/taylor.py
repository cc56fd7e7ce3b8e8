"""Taylor coefficients of the solution, generated from the model (automatic differentiation).

For y' = f(t, y, p) the normalized Taylor coefficients y^[k] = y^(k)(t0)/k! follow from
y^[k+1] = f^[k]/(k + 1), where f^[k] is the k-th coefficient of f along the solution. f is
decomposed into elementary operations u_m = op(u_a, u_b) on the state, t and earlier
operations (after sympy's common-subexpression elimination, identical subtrees shared);
each operation has a recurrence for its k-th coefficient from lower ones (Jorba and Zou
2005, heyoka's decomposition; Moore's rules):

=========================  ==========================================================
product c = a b            c[k] = sum_{j=0..k} a[j] b[k-j]
square c = a^2             c[k] = sum_{j=0..k} a[j] a[k-j]
quotient c = a / b         c[k] = (a[k] - sum_{j=1..k} b[j] c[k-j]) / b[0]
square root c = a^(1/2)    c[k] = (a[k] - sum_{j=1..k-1} c[j] c[k-j]) / (2 c[0])
power c = a^r              c[k] = sum_{j=1..k} ((r + 1) j - k) a[j] c[k-j] / (k a[0])
exp, sin/cos, sinh/cosh    k c[k] = sum_{j=1..k} j a[j] g[k-j]   (g = c, cos, -sin, ...)
tan, tanh                  the same with g = 1 + c^2, 1 - c^2 (built after c)
log, atan, asin, ...       k u[0] c[k] = k a[k] - sum_{j=1..k-1} j c[j] u[k-j]
                           (u c' = a': u = a, 1 + a^2, sqrt(1 - a^2), ...)
=========================  ==========================================================

Linear combinations with constant coefficients (sums, differences, scaling by parameters)
cost one multiply-add per order. Subexpressions of the parameters alone are computed once.

Every recurrence splits into a *history* sum over the coefficients of orders 1..k-1 (all
known when order k starts) and a few *current* terms in the order-k coefficients of the
operands. The generated code computes the history sums of all operations in ONE loop over
j (independent accumulators: the multiply-adds pipeline instead of waiting on one chain),
the two terms holding an order k - 1 coefficient last (taylor_lanes.history_terms: the
rest of the sum is ready before order k - 1 ends), then the current terms in dependency
order, then y^[k+1]. Two sums are cheaper than their
textbook form: a square's (and a square root's) sum is symmetric, sum_{j=1..k-1} a[j]
a[k-j] = 2 sum_{j<k/2} a[j] a[k-j] + a[k/2]^2 (k even), half the products in a second
loop over j < k/2; a power's two sums (of a[j] c[k-j] and of j a[j] c[k-j]) are one sum
weighted by ((r + 1) j - k), with no column of j a[j]:

    subroutine conmech_taylor(t, order, w, p) bind(C)     ! w(0:order, nw)
        w(0, 1:n) = y on entry; on exit w(0:order, 1:n) = y^[0..order]
        (the columns n+1..nw hold the operations' coefficients up to order - 1)

The batch form ``conmech_taylor_batch(t, order, w, p)`` does the same for ``width``
independent members at once, w(width, 0:order, nw), t(width) (members in the fastest
dimension: every statement is a short vector operation the compiler turns into SIMD).

:func:`decompose` builds the decomposition, :class:`conmech.symbolic.taylor_recipe.Recipe`
each operation's statements; :func:`taylor_procedures` prints the Fortran
(double, quadruple precision, batch); :func:`TaylorUnsupported` names what cannot be
expanded (non-smooth functions: Abs, sign, Heaviside, Min, Max, ...).
"""
import sympy as sp

from .printer import FortranPrinter, _names, quiet_nan
from .printer import _wrap as _wrap_line
from .taylor_decompose import (_JWEIGHT, Decomposition,  # noqa: F401 (public names)
                               TaylorUnsupported, decompose, variational_exprs)
from .isa import scalar_isa_flags as _scalar_isa_flags
from .taylor_lanes import (_SYM, _current_statements, _history_sum,  # noqa: F401
                           _history_sum_pair, _pair_derivatives, _pair_history,
                           _pair_outputs, _sum_seq, history_loops)
from .taylor_recipe import Recipe

__all__ = ["TaylorUnsupported", "Decomposition", "decompose", "taylor_procedures",
           "variational_exprs", "TAYLOR_VERSION"]

TAYLOR_VERSION = "5"

#: flags added to the model libraries' for the written-out routine (isa.scalar_isa_flags):
#: -fopenmp-simd for its paired history sums (two-lane loops marked ``!$omp simd``, which
#: gfortran's SLP vectorizer leaves scalar otherwise; no OpenMP run time), the machine's
#: AVX2 encoding without contraction (the same bits, fewer instructions)
FIXED_EXTRA_FLAGS = _scalar_isa_flags()


# ---------------------------------------------------------------------- Fortran printing

class _QuadPrinter(FortranPrinter):
    """Constants with 36 significant digits (quadruple precision literals)."""

    def _real(self, x):
        if isinstance(x, int) or getattr(x, "is_Integer", False):
            return f"{int(x)}.0{self.kind_suffix}"
        v = sp.Float(x, 40)
        if not v.is_finite:
            raise ValueError(f"non-finite constant {x} in an expression")
        s = str(sp.Float(v, 36))
        if "." not in s and "e" not in s:
            s += ".0"
        return s + self.kind_suffix

    def _print_NumberSymbol(self, expr):
        return self._real(expr.evalf(40))

    _print_Pi = _print_NumberSymbol
    _print_Exp1 = _print_NumberSymbol


class _Printer:
    """Statements of one decomposition in scalar (w(k, c)) or batch (w(:, k, c)) form."""

    def __init__(self, dec, names, batch, kind):
        self.d = dec
        self.batch = batch
        self.kind = kind
        cls = _QuadPrinter if kind == "qp" else FortranPrinter
        self.pr = cls(names, kind_suffix="_" + kind)
        self.const_names = {s: f"tc{k + 1}" for k, (s, _) in enumerate(dec.consts)}
        self.pr.names.update(self.const_names)
        self.scalars = None      # written-out code: the coefficients as scalars s<c>_<k>
        self.lanes = {}          # ... or in a lane of a pair array: column -> (group, lane)

    def w(self, k, c):
        if self.scalars is not None and isinstance(k, int):
            if c in self.lanes:
                g, lane = self.lanes[c]
                return f"g{g + 1}({lane + 1}, {k})"
            name = f"s{c}_{k}"
            self.scalars.add(name)
            return name
        return f"w(:, {k}, {c})" if self.batch else f"w({k}, {c})"

    def num(self, x):
        """A constant (sympy number or const symbol) as Fortran."""
        x = sp.sympify(x)
        if x in self.const_names:
            return self.const_names[x]
        return self.pr._print(x)

    def lin_at(self, lin, k, with_const):
        parts = []
        if with_const and lin.c0 != 0:
            parts.append(self.num(lin.c0))
        for c, v in sorted(lin.terms.items()):
            v = sp.sympify(v)
            if v == 1:
                parts.append(self.w(k, c))
            elif v == -1:
                parts.append(f"-{self.w(k, c)}")
            else:
                parts.append(f"{self.num(v)}*{self.w(k, c)}")
        if not parts:
            return "0.0_" + self.kind
        s = parts[0]
        for p in parts[1:]:
            s += (" - " + p[1:]) if p.startswith("-") else (" + " + p)
        return s

    def real(self, x):
        return self.pr._real(x)

    def pow_order0(self, a, r):
        r = sp.sympify(r)
        if r in self.const_names:
            return f"{a}**{self.const_names[r]}"
        if r.is_Rational and r.q == 2:
            m = int(r.p)
            base = f"sqrt({a})"
            if m == 1:
                return base
            if m == -1:
                return f"{self.real(1)}/{base}"
            return f"{base}**{m}" if m > 0 else f"{self.real(1)}/{base}**{-m}"
        return f"{a}**{self.num(r)}"


def _wrap(line, ind):
    w = _wrap_line
    return w(line, ind)


def _decls(names, typ, ind, per_line=10):
    out = []
    for i in range(0, len(names), per_line):
        out.append(f"{ind}{typ} :: " + ", ".join(names[i:i + per_line]))
    return out



def square_sums(sym, W, pp, ind):
    """The loop lines of the history sums of squares (recipes marked _SYM): the pairs
    j < k - j once, doubled, and the middle term when k is even; W(j, column) spells a
    coefficient of the jet."""
    if not sym:
        return []
    lines = [f"{ind}    do j = 1, (k - 1)/2"]
    for h, lft, _, _ in sym:
        lines += _wrap(f"{h} = {h} + {W('j', lft)}*{W('k - j', lft)}", ind + "        ")
    lines.append(f"{ind}    end do")
    lines += [f"{ind}    {h} = {pp.real(2)}*{h}" for h, _, _, _ in sym]
    lines.append(f"{ind}    if (mod(k, 2) == 0) then")
    for h, lft, _, _ in sym:
        lines += _wrap(f"{h} = {h} + {W('k/2', lft)}*{W('k/2', lft)}", ind + "        ")
    lines.append(f"{ind}    end if")
    return lines

def body_lines(dec, names, kind="dp", batch=0, given=False, ind="        ", fixed=None,
               paired=True):
    """(declarations, statements) computing the coefficients in w (see the module
    docstring), for a procedure that declares t, order, w and the names the printer maps
    the parameters to. kind "dp" or "qp"; batch > 0: w(batch, 0:order, nw), t(batch);
    given: the state columns are inputs of orders 0..order and the operations are computed
    up to `order` (the outputs as columns ``dec.out_cols``), else the ODE recursion.
    fixed: an order p to write out (no loops, literal indices and constants, the values in
    scalars, the history sums in the loop's order); the procedure must then be called with
    order = p. paired (with fixed, for an ODE): history sums of the same form computed
    two at a time as 2-wide vectors (see _pair_history; the same bits)."""
    pp = _Printer(dec, names, batch > 0, kind)
    if fixed is not None:
        pp.scalars = set()
    rc = Recipe(pp, given, "order" if fixed is None else fixed)
    pairs, vcur, opairs = [], [], []
    if fixed is not None and paired and not batch and not given:
        pairs, pp.lanes = _pair_history(rc.hist, dec)
        if pairs:             # the statements again, with the paired columns in lanes
            vcur = _pair_outputs(rc, pairs, pp.lanes)
            opairs = _pair_derivatives(dec, pp.lanes)
            pp.scalars = set()
            rc = Recipe(pp, given, fixed)
    W = pp.w
    vec = f"({batch})" if batch else ""
    one = pp.real(1)
    zero = f"0.0_{kind}"
    decl = _decls([c for c, _ in rc.consts], f"real({kind})", ind)
    decl += _decls([f"{x}{vec}" for x in rc.accs + rc.invs], f"real({kind})", ind)
    body = [f"{ind}if (order < {0 if given else 1}) return"]
    if fixed is not None:
        body = [f"{ind}if (order /= {fixed}) return"]
    for c, e in rc.consts:
        body += _wrap(f"{c} = {e}", ind)
    jstate = [i + 1 for i in range(dec.n) if i + 1 in dec.jcol]
    if given and jstate:      # the given state's j-weighted coefficients, all orders
        decl += [f"{ind}integer :: kk"]
        body.append(f"{ind}do kk = 1, order")
        body += [f"{ind}    {W('kk', dec.jcol[c])} = real(kk, {kind})*{W('kk', c)}"
                 for c in jstate]
        body.append(f"{ind}end do")
    for x in rc.s0:
        body += _wrap(x, ind)
    if not given:
        for i, o in enumerate(dec.outputs):
            body += _wrap(f"{W(1, i + 1)} = {pp.lin_at(o, 0, True)}", ind)
        body += [f"{ind}{W(1, dec.jcol[c])} = {W(1, c)}" for c in jstate]
        if fixed is not None:
            body += [f"{ind}w(1, {c}) = {W(1, c)}" for c in range(1, dec.n + 1)]
    if fixed is None:
        decl += [f"{ind}real({kind}) :: fk, rk, rk1", f"{ind}integer :: k, j"]
        E = {"k": "k", "fk": "fk", "rk": "rk"}
        loop = [f"{ind}do k = 1, {'order' if given else 'order - 1'}",
                f"{ind}    fk = real(k, {kind})",
                f"{ind}    rk = {one}/fk",
                f"{ind}    rk1 = {one}/(fk + {one})"]
        loop += [f"{ind}    {h} = {zero}" for h in rc.accs]
        plain = [x for x in rc.hist if x[3] is not _SYM]
        sym = [x for x in rc.hist if x[3] is _SYM]
        loop += history_loops(plain, sym, W, kind, pp.real(2), ind,
                              lambda st, i: [x for s in st for x in _wrap(s, i)])
        for f in rc.cur:
            loop += _wrap(f(E), ind + "    ")
        if not given:
            for i, o in enumerate(dec.outputs):
                loop += _wrap(f"{W('k + 1', i + 1)} = rk1*({pp.lin_at(o, 'k', False)})",
                              ind + "    ")
            loop += [f"{ind}    {W('k + 1', dec.jcol[c])} = (fk + {one})*{W('k + 1', c)}"
                     for c in jstate]
        loop.append(f"{ind}end do")
        if given:      # the outputs into their columns n + 1 .. n + m
            for c, o in zip(dec.out_cols, dec.outputs):
                loop += _wrap(f"{W(0, c)} = {pp.lin_at(o, 0, True)}", ind)
                loop += _wrap(f"if (order >= 1) {W('1:order', c)} = "
                              f"{pp.lin_at(o, '1:order', False)}", ind)
        return decl, body + loop
    last = fixed if given else fixed - 1
    state_in = [f"{ind}{W(k, c)} = w({k}, {c})" for c in range(1, dec.n + 1)
                for k in (range(0, fixed + 1) if given else [0])]
    body = body[:1] + state_in + body[1:]
    for k in range(1, last + 1):
        E = {"k": k, "fk": pp.real(k), "rk": f"({one}/{pp.real(k)})"}
        if pairs:      # one loop over the two lanes (gfortran vectorizes it as told)
            body += [f"{ind}!$omp simd", f"{ind}do ln = 1, 2"]
            for m, (i, j) in enumerate(pairs):
                body += _wrap(f"hv{m + 1}(ln) = "
                              f"{_history_sum_pair(pp, k, rc.hist[i], rc.hist[j])}",
                              ind + "    ")
            body.append(f"{ind}end do")
        for m, (i, j) in enumerate(pairs):
            body += [f"{ind}{rc.hist[i][0]} = hv{m + 1}(1)",
                     f"{ind}{rc.hist[j][0]} = hv{m + 1}(2)"]
        in_pair = {i for pr in pairs for i in pr}
        for i, (h, lft, rgt, wt) in enumerate(rc.hist):
            if i not in in_pair:
                body += _wrap(f"{h} = {_history_sum(pp, k, lft, rgt, wt)}", ind)
        for x in _current_statements(pp, rc, k, [f(E) for f in rc.cur], vcur):
            if isinstance(x, tuple):
                body += [f"{ind}!$omp simd", f"{ind}do ln = 1, 2"]
                body += _wrap(x[0], ind + "    ")
                body.append(f"{ind}end do")
            else:
                body += _wrap(x, ind)
        if not given:
            second = {i2 for _, i2 in opairs}
            first = dict(opairs)
            for i, o in enumerate(dec.outputs):
                if i in second:
                    continue
                if i in first:         # two outputs of one form: one 2-lane statement
                    i2 = first[i]
                    (a, v), = o.terms.items()
                    (b, _), = dec.outputs[i2].terms.items()
                    col = W(k, a) if a == b else f"g{pp.lanes[a][0] + 1}(ln, {k})"
                    v = sp.sympify(v)
                    term = col if v == 1 else f"-{col}" if v == -1 else f"{pp.num(v)}*{col}"
                    body += [f"{ind}!$omp simd", f"{ind}do ln = 1, 2"]
                    body += _wrap(f"g{pp.lanes[i + 1][0] + 1}(ln, {k + 1}) = "
                                  f"({one}/{pp.real(k + 1)})*({term})", ind + "    ")
                    body.append(f"{ind}end do")
                    continue
                body += _wrap(f"{W(k + 1, i + 1)} = ({one}/{pp.real(k + 1)})*("
                              f"{pp.lin_at(o, k, False)})", ind)
            body += [f"{ind}{W(k + 1, dec.jcol[c])} = {pp.real(k + 1)}*{W(k + 1, c)}"
                     for c in jstate]
            # the state's coefficients of order k + 1 out at once, from the registers
            # they were computed in (a copy at the end reloads each one first)
            body += [f"{ind}w({k + 1}, {c}) = {W(k + 1, c)}" for c in range(1, dec.n + 1)]
    if given:
        body += [f"{ind}w({k}, {c}) = {W(k, c)}" for c in dec.out_cols
                 for k in range(0, fixed + 1)]
    names_s = sorted(pp.scalars, key=lambda x: tuple(int(v) for v in x[1:].split("_")))
    decl += _decls(names_s, f"real({kind})", ind)
    decl += _decls([f"g{g + 1}(2, 0:{fixed})" for g in
                    range(max((v[0] for v in pp.lanes.values()), default=-1) + 1)],
                   f"real({kind})", ind, 5)
    decl += _decls([f"hv{m + 1}(2)" for m in range(len(pairs))], f"real({kind})", ind)
    if pairs:
        decl.append(f"{ind}integer :: ln")
    return decl, body


def c_routine(dec, names, cname, batch=0, given=False, fixed=None, paired=True):
    """The bind(C) routine ``cname(t, order, w, p)`` (double precision; batch > 0: t and w
    with a leading member dimension; fixed: written out for that order only, paired: see
    body_lines)."""
    ind = "        "
    nw = dec.ncol
    npar = max(len(dec.params), 1)
    vec = f"({batch})" if batch else ""
    head = [f'    subroutine {cname}(t, order, w, p) bind(C, name="{cname}")',
            f"{ind}real(dp), {'value, ' if not batch else ''}intent(in) :: t{vec}",
            f"{ind}integer(c_int), value, intent(in) :: order",
            f"{ind}real(dp), intent(inout) :: w({f'{batch}, ' if batch else ''}"
            f"0:order, {nw})",
            f"{ind}real(dp), intent(in) :: p({npar})"]
    decl, body = body_lines(dec, names, "dp", batch, given, ind, fixed, paired)
    return head + decl + body + [f"    end subroutine {cname}", ""]


def quad_entry(cname, nw, npar, ind="        "):
    """``cname(t, order, w, p)`` through C pointers to real128 values (C has no standard
    128-bit type), calling ``cname_body`` on t, w(0:order, nw), p."""
    return [f'    subroutine {cname}(tp, order, wp, pp) bind(C, name="{cname}")',
            f"{ind}type(c_ptr), value, intent(in) :: tp, wp, pp",
            f"{ind}integer(c_int), value, intent(in) :: order",
            f"{ind}real(qp), pointer :: tq",
            f"{ind}real(qp), pointer, contiguous :: wq(:, :), pq(:)",
            f"{ind}call c_f_pointer(tp, tq)",
            f"{ind}call c_f_pointer(wp, wq, [order + 1, {nw}])",
            f"{ind}call c_f_pointer(pp, pq, [{npar}])",
            f"{ind}call {cname}_body(tq, order, wq, pq)",
            f"    end subroutine {cname}", ""]


def quad_procedure(cname, nw, npar, decl, body, ind="        "):
    """Fortran lines of ``cname`` (:func:`quad_entry`) and of the real128 routine
    ``cname_body(t, order, w(0:order, nw), p(npar))`` it calls, of declarations `decl` and
    statements `body`."""
    inner = [f"    subroutine {cname}_body(t, order, w, p)",
             f"{ind}real(qp), intent(in) :: t",
              f"{ind}integer(c_int), intent(in) :: order",
              f"{ind}real(qp), intent(inout) :: w(0:order, {nw})",
              f"{ind}real(qp), intent(in) :: p({npar})"]
    return quad_entry(cname, nw, npar, ind) + inner + decl + body + \
        [f"    end subroutine {cname}_body", ""]


def quad_routine(dec, names, cname):
    """The recurrences in quadruple precision, entry :func:`quad_entry`."""
    decl, body = body_lines(dec, names, "qp", 0, False)
    return quad_procedure(cname, dec.ncol, max(len(dec.params), 1), decl, body)


def taylor_procedures(dec, names, prefix="conmech_taylor", batch_width=4, quad=True):
    """Fortran lines of the coefficient routines of a decomposition: ``prefix`` (double),
    ``prefix_batch`` (batch_width members, if > 0), ``prefix_qp`` (quadruple precision,
    if quad), and ``prefix_info(info)``: [columns of w, batch width, n, quad]."""
    lines = c_routine(dec, names, prefix)
    if batch_width:
        lines += c_routine(dec, names, prefix + "_batch", batch=batch_width)
    if quad:
        lines += quad_routine(dec, names, prefix + "_qp")
    ind = "        "
    lines += [f'    subroutine {prefix}_info(info) bind(C, name="{prefix}_info")',
              f"{ind}integer(c_int), intent(out) :: info(4)",
              f"{ind}info = [{dec.ncol}, {batch_width}, {dec.n}, {int(quad)}]",
              f"    end subroutine {prefix}_info", ""]
    return lines


def ode_decompositions(d, variational=True):
    """(decomposition of f, decomposition of [f; J Phi] or None, reason): reason is the
    TaylorUnsupported message when f has no Taylor recurrences (then both are None)."""
    try:
        dec = decompose(list(d.f), d.coords, d.t, d.params)
    except TaylorUnsupported as exc:
        return None, None, str(exc)
    vdec = None
    if variational:
        vx, phi = variational_exprs(list(d.f), d.jac, d.n)
        vdec = decompose(vx, list(d.coords) + phi, d.t, d.params)
    return dec, vdec, None


def ode_taylor_lines(d, names, batch_width=4, quad=True, variational=True):
    """The Taylor routines of an ode record `d` (:mod:`conmech.symbolic.derive`):
    (Fortran lines, entry names, reason). ``conmech_taylor`` / ``_batch`` / ``_qp`` /
    ``_info`` for y' = f, and with `variational` ``conmech_taylor_var`` / ``_var_info`` for
    z' = [f; J Phi] (the state transition matrix by the same recurrences). An expression
    without recurrences (non-smooth) gives no lines, no entries and the reason."""
    dec, vdec, why = ode_decompositions(d, variational)
    if dec is None:
        return [], [], why
    lines = taylor_procedures(dec, names, "conmech_taylor", batch_width, quad)
    entries = ["taylor", "taylor_info"] + (["taylor_batch"] if batch_width else []) + \
        (["taylor_qp"] if quad else [])
    if vdec is not None:
        lines += taylor_procedures(vdec, names, "conmech_taylor_var", 0, False)
        entries += ["taylor_var", "taylor_var_info"]
    return lines, entries, None


def emitted_taylor(tname, d, names):
    """For a standalone module (conmech.symbolic.emit_fortran): the type-bound procedure
    bindings and the procedures ``taylor_size`` / ``taylor_jet`` of the ode type `tname`
    (the system, kind 0, and its variational system, kind 1), with the parameters printed
    through `names` (self%name). Returns ([], [], reason) when f has no recurrences."""
    dec, vdec, why = ode_decompositions(d, True)
    if dec is None:
        return [], [], why
    ind = "        "
    binds = [f"        procedure :: taylor_size => {tname}_taylor_size",
             f"        procedure :: taylor_jet => {tname}_taylor_jet"]
    procs = [
        "    !> Columns of the Taylor work array (kind 0: the system, 1: its variational "
        "system).",
        f"    integer function {tname}_taylor_size(self, kind)",
        f"{ind}class({tname}), intent(in) :: self",
        f"{ind}integer, intent(in) :: kind",
        f"{ind}{tname}_taylor_size = 0",
        f"{ind}if (kind == 0) {tname}_taylor_size = {dec.ncol}",
        f"{ind}if (kind == 1) {tname}_taylor_size = {vdec.ncol}",
        f"    end function {tname}_taylor_size", "",
        "    !> Normalized Taylor coefficients w(0:order, 1:m) from w(0, 1:m) (generated "
        "recurrences).",
        f"    subroutine {tname}_taylor_jet(self, kind, t, order, nw, w)",
        f"{ind}class({tname}), intent(in) :: self",
        f"{ind}integer, intent(in) :: kind, order, nw",
        f"{ind}real(dp), intent(in) :: t",
        f"{ind}real(dp), intent(inout) :: w(0:order, nw)",
        f"{ind}if (kind == 0 .and. nw >= {dec.ncol}) then",
        f"{ind}    call {tname}_taylor0(self, t, order, w)",
        f"{ind}else if (kind == 1 .and. nw >= {vdec.ncol}) then",
        f"{ind}    call {tname}_taylor1(self, t, order, w)",
        f"{ind}else",
        f"{ind}    w(1:, :) = {quiet_nan()}",
        f"{ind}end if",
        f"    end subroutine {tname}_taylor_jet", ""]
    for k, dd in enumerate((dec, vdec)):
        decl, body = body_lines(dd, names, "dp", 0, False, ind)
        procs += [f"    subroutine {tname}_taylor{k}(self, t, order, w)",
                  f"{ind}type({tname}), intent(in) :: self",
                  f"{ind}real(dp), intent(in) :: t",
                  f"{ind}integer, intent(in) :: order",
                  f"{ind}real(dp), intent(inout) :: w(0:order, {dd.ncol})"]
        procs += decl + body + [f"    end subroutine {tname}_taylor{k}", ""]
    return binds, procs, None


def fixed_order_source(d, order, variational=True, paired=True):
    """Fortran source of a module with the Taylor routines of the ode record `d` written out
    for one order (``conmech_taylor_fixed``, and ``conmech_taylor_var_fixed`` with
    `variational`): no loops, so the compiler schedules every multiply-add of the expansion
    at once; `paired`: history sums of the same form two at a time in 2-wide vectors. Same
    signature and work columns as ``conmech_taylor`` (called with order = `order` only)."""
    dec, vdec, why = ode_decompositions(d, variational)
    if dec is None:
        raise TaylorUnsupported(why)
    names = _names(d)
    lines = c_routine(dec, names, "conmech_taylor_fixed", fixed=order, paired=paired)
    if vdec is not None:
        lines += c_routine(vdec, names, "conmech_taylor_var_fixed", fixed=order,
                           paired=paired)
    head = ["!> Generated by conmech.symbolic.taylor: Taylor coefficients written out for "
            f"order {order}. Do not edit.",
            "module conmech_symbolic_taylor_fixed",
            "    use, intrinsic :: iso_c_binding, only: c_double, c_int",
            "    implicit none",
            "    integer, parameter :: dp = c_double",
            "    public",
            "contains", ""]
    return "\n".join(head + lines + ["end module conmech_symbolic_taylor_fixed", ""])
