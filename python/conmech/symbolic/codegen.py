"""Fortran code generation for the C ABI of compiled systems (bind(C) procedures).

:func:`generate` turns a :class:`~conmech.symbolic.derive.Derived` record into the source
of one free-form Fortran module whose procedures have the C signatures of conmech's
compiled systems (``value`` for t, explicit-shape arrays, column-major matrices, the
parameter array ``p`` last)::

    ode:          cm_rhs(t, y, dydt, p), cm_jac(t, y, dfdy, p),
                  cm_jac_prod(t, y, k, x, jx, p)   (jx = J x, x an n x k block),
                  cm_taylor(t, order, w, p) and its variants (conmech.symbolic.taylor)
    generalized:  cm_mass(t, q, M, p), cm_forces(t, q, v, Q, p),
                  cm_forces_jac(t, q, v, a, R, p), real cm_energy(t, q, v, p),
                  cm_mass_forces(t, q, v, M, Q, p), and for planar trees
                  cm_accel(t, q, v, a, p) (see conmech.symbolic.tree)
    constrained:  cm_mass, cm_forces, cm_energy, cm_forces_jac (the force balance's
                  Jacobian), and as present cm_phi(t, q, c, p),
                  cm_phi_jac(t, q, G, p), cm_phi_t(t, q, pt, p),
                  cm_phi_gamma(t, q, v, g, p), cm_nh_matrix(t, q, A, b, p),
                  cm_nh_gamma(t, q, v, g, p), cm_constraint_hessian(t, q, v, lam, hl,
                  hv, p) (see conmech.symbolic.constrained_jac)

Each procedure's outputs share one common-subexpression elimination (sympy.cse). A
generalized system derived in structured form (``Derived.struct``) computes the nonzero
entries dM_ab/dq_k (and for the Jacobian the second derivatives) first, as local values with
their own elimination, and then Q (R) as short sums over them: O(n^2) operations for a chain
where the expanded Euler-Lagrange expressions cost O(n^3). Sines and cosines of sums are
built from those of their terms by angle addition when that needs fewer distinct arguments
(:func:`trig_split`: a chain's cos(q_i - q_j) from the n pairs sin(q_i), cos(q_i)). Powers
with half-integer exponents become integer powers of one square root (so r^3 = (x^2+y^2)^(3/2)
costs one sqrt and two multiplications, and the sqrt is shared by CSE); integer powers are
printed with integer exponents (gfortran expands them into multiplications); every number is
a ``real(dp)`` literal (no integer division, no ``d0``).

:class:`FortranPrinter` and :func:`assignments` are reusable by other emitters (e.g. a
standalone module whose type extends conmech's system types).
"""
import re

import sympy as sp
from sympy.printing.fortran import FCodePrinter

from .._core import slot_table as _table

__all__ = ["CODEGEN_VERSION", "FortranPrinter", "assignments", "generate", "prepare",
           "trig_split", "ENTRY_POINTS", "product_terms", "product_lines", "comment_text",
           "comment_lines", "string_constant", "check_source"]

# C names of the entry points (conmech_<name>) per kind, the names of conmech.compiled's
# arguments: the table of compiled functions
ENTRY_POINTS = _table.ENTRY_POINTS

#: bump when the generated code or the derivation changes (invalidates the derivation cache)
CODEGEN_VERSION = "10"  # 2: conmech_* entry names, model-library description;
#                         3: structured forces / Jacobian, sin and cos by angle addition;
#                         4: conmech_mass_forces (M and Q in one call, shared subexpressions);
#                         5: conmech_jac_prod (ode: J x for a block of columns, no J formed);
#                         6: conmech_accel of planar trees (articulated-body algorithm)
#                         7: conmech_taylor* (Taylor coefficients, conmech.symbolic.taylor)
#                         8: constrained: conmech_forces_jac, conmech_constraint_hessian
#                         9: user strings escaped (comments, parameter names as data)
#                        10: Taylor recurrences in a library of their own, on first need

_SQRT = sp.Function("conmech_sqrt")   # an unevaluated sqrt, so that b**(3/2) = cm_sqrt(b)**3

# ------------------------------------------------------------------ user strings
# Every string a user gives (symbol, coordinate, parameter, body and joint names, file
# names) reaches the generated Fortran only through these helpers: in a comment as printable
# ASCII on one line (comment_text), in data as a character constant built from plain
# characters and achar() codes (string_constant). check_source then refuses any source
# with a character outside printable ASCII, an over-long line, or a procedure or C name
# that is not one of the expected entry points, whatever produced it.

_PLAIN = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789"
                   "_ .,:;+-=()[]")


def comment_text(text, limit=60):
    """`text` as it may follow '!' in generated Fortran: one line of printable ASCII, every
    other character (newlines, quotes and '&' included, for the reader's sake) written as a
    \\x, \\u or \\U escape, cut to `limit` characters with '...'."""
    out = []
    for ch in str(text):
        o = ord(ch)
        if ch in _PLAIN or (32 < o < 127 and ch not in "\\\"'&!"):
            out.append(ch)
        elif o < 256:
            out.append(f"\\x{o:02x}")
        elif o < 65536:
            out.append(f"\\u{o:04x}")
        else:
            out.append(f"\\U{o:08x}")
    s = "".join(out)
    return s if len(s) <= limit else s[:limit - 3] + "..."


def comment_lines(text, prefix="!! ", width=96):
    """Comment lines (each starting with `prefix`, at most `width` characters) holding
    `text`, which must already be made safe by :func:`comment_text`."""
    if any(not (32 <= ord(c) < 127) for c in text):
        raise ValueError("comment_lines: text must be printable ASCII (use comment_text)")
    words, lines, cur = text.split(" "), [], ""
    room = width - len(prefix)
    for w in words:
        while len(w) > room:                  # an escaped name longer than a line
            if cur:
                lines.append(prefix + cur)
                cur = ""
            lines.append(prefix + w[:room])
            w = w[room:]
        if cur and len(cur) + 1 + len(w) > room:
            lines.append(prefix + cur)
            cur = w
        else:
            cur = (cur + " " + w) if cur else w
    if cur:
        lines.append(prefix + cur)
    return lines


def string_constant(text, indent="            "):
    """Lines of a Fortran character constant expression equal to the UTF-8 bytes of
    `text`: letters, digits, blanks and a few punctuation marks in quoted chunks, every
    other byte as achar(code), joined by // with free-form continuations."""
    parts, chunk = [], ""
    for b in str(text).encode("utf-8"):
        ch = chr(b)
        if b < 128 and ch in _PLAIN:
            chunk += ch
            if len(chunk) >= 48:
                parts.append(f'"{chunk}"')
                chunk = ""
        else:
            if chunk:
                parts.append(f'"{chunk}"')
                chunk = ""
            parts.append(f"achar({b})")
    if chunk or not parts:
        parts.append(f'"{chunk}"')
    lines, cur = [], ""
    for k, p in enumerate(parts):
        piece = p + ("//" if k < len(parts) - 1 else "")
        if cur and len(cur) + len(piece) > 72:
            lines.append(indent + cur + " &")
            cur = piece
        else:
            cur += piece
    lines.append(indent + cur)
    return lines


_PROC = re.compile(r"^\s*(?:(?:pure|elemental|recursive|impure|module|real\s*\([^)]*\)|"
                   r"integer(?:\s*\([^)]*\))?|logical|double\s+precision)\s+)*"
                   r"(subroutine|function|entry)\s+(\w+)", re.IGNORECASE)
_BIND = re.compile(r"bind\s*\(\s*c\s*(?:,\s*name\s*=\s*([\"'])([^\"']*)\1\s*)?\)",
                   re.IGNORECASE)
_END_PROC = re.compile(r"^\s*end\s+(subroutine|function)\b", re.IGNORECASE)


def _code_part(line):
    """The line without its comment (strings of generated code hold no '!': see
    string_constant)."""
    k = line.find("!")
    return line if k < 0 else line[:k]


_TREE_PROC = re.compile(r"^\s*(?:pure\s+)?subroutine\s+(tree_[a-z0-9_]+)\s*\(",
                        re.I | re.M)


def _c_names(entries, model_values):
    """The C names a generated module binds: its entry points, and the model-library
    description when it has default parameter values."""
    names = [f"conmech_{e}" for e in entries]
    if model_values is not None:
        names += ["conmech_model_info", "conmech_model_params", "conmech_model_param_names"]
    return names


def private_procedures(entries, source=None):
    """The internal (private, not C-bound) procedures the generated module defines beside
    the entry points `entries`: the body that the quadruple-precision Taylor entry wraps,
    and, given the `source` of a recursive tree, its passes (``tree_pos``, ``tree_vel``,
    ... and their pieces: names the generator makes, never from user strings)."""
    out = [f"conmech_{e}_body" for e in entries if e.endswith("taylor_qp")]
    if source is not None:
        out += sorted({m.lower() for m in _TREE_PROC.findall(source)})
    return out


def check_source(src, procedures, c_names=None, max_line=132):
    """ValueError unless the generated source `src` is printable ASCII (plus newlines) with
    lines of at most `max_line` characters, defines exactly the procedures named in
    `procedures` (no other subroutine, function or entry), and binds to C only the names
    in `c_names` (default: the procedure names); a last line of defence against a user
    string reaching the code unescaped."""
    allowed = {p.lower() for p in procedures}
    c_allowed = set(procedures if c_names is None else c_names)
    seen = []
    for k, line in enumerate(src.split("\n"), 1):
        bad = [c for c in line if not 32 <= ord(c) < 127]
        if bad:
            raise ValueError(f"generated Fortran line {k} holds the character {bad[0]!r}: "
                             "a user string reached the code unescaped")
        if len(line) > max_line:
            raise ValueError(f"generated Fortran line {k} is longer than {max_line} "
                             "characters")
        code = _code_part(line)
        if _END_PROC.match(code):
            continue
        m = _PROC.match(code)
        if m:
            name = m.group(2).lower()
            if name not in allowed:
                raise ValueError(f"generated Fortran line {k} defines an unexpected "
                                 f"procedure '{m.group(2)}'")
            seen.append(name)
        for b in _BIND.finditer(code):
            if not m or b.group(2) is None or b.group(2) not in c_allowed:
                raise ValueError(f"generated Fortran line {k} binds an unexpected C name "
                                 f"{b.group(2)!r}")
    if sorted(seen) != sorted(allowed):
        raise ValueError("generated Fortran defines the procedures "
                         f"{sorted(seen)}, expected {sorted(allowed)}")


class FortranPrinter(FCodePrinter):
    """Free-form Fortran 2008 printer: symbols through a name map, real(dp) literals,
    integer exponents, sqrt for half-integer powers (after :func:`prepare`)."""

    def __init__(self, names, kind_suffix="_dp"):
        super().__init__({"source_format": "free", "standard": 2008, "strict": False})
        self.names = dict(names)
        self.kind_suffix = kind_suffix
        self._not_supported = set()
        self._number_symbols = set()

    def _real(self, x):
        try:
            s = repr(float(x))
        except OverflowError:
            raise ValueError(f"the number {str(x)[:40]} is outside the range of double "
                             "precision") from None
        if s in ("inf", "-inf", "nan"):
            raise ValueError(f"non-finite constant {x} in an expression")
        if "." not in s and "e" not in s:
            s += ".0"
        return s + self.kind_suffix

    def _print_Symbol(self, expr):
        try:
            return self.names[expr]
        except KeyError:
            raise ValueError(f"symbol '{expr}' has no Fortran name (not a coordinate, "
                             "velocity, parameter or t)") from None

    _print_Dummy = _print_Symbol

    def _print_Integer(self, expr):
        return self._real(int(expr))

    def _print_Rational(self, expr):
        # exact ratios of integers as a quotient of real literals (folded by the compiler)
        p, q = int(expr.p), int(expr.q)
        if max(abs(p), q) >= 2**53:         # not exact as doubles: the rounded quotient
            return self._real(float(expr))
        return f"({self._real(p)}/{self._real(q)})"

    def _print_Float(self, expr):
        return self._real(expr)

    def _print_NumberSymbol(self, expr):
        return self._real(expr.evalf(20))

    _print_Pi = _print_NumberSymbol
    _print_Exp1 = _print_NumberSymbol

    def _print_Zero(self, expr):
        return "0.0" + self.kind_suffix

    def _print_One(self, expr):
        return "1.0" + self.kind_suffix

    def _print_NegativeOne(self, expr):
        return "(-1.0" + self.kind_suffix + ")"

    def _print_Half(self, expr):
        return "0.5" + self.kind_suffix

    def _print_Function(self, expr):
        if expr.func == _SQRT:
            return f"sqrt({self._print(expr.args[0])})"
        return super()._print_Function(expr)

    def _print_sign(self, expr):
        a = self._print(expr.args[0])
        one, zero = self._real(1), self._real(0)
        return f"(merge({one}, {zero}, {a} > 0) - merge({one}, {zero}, {a} < 0))"

    def _print_Heaviside(self, expr):
        a = self._print(expr.args[0])
        h0 = expr.args[1] if len(expr.args) > 1 else sp.S.Half
        return (f"merge({self._real(1)}, merge({self._print(h0)}, {self._real(0)}, "
                f"{a} == 0), {a} > 0)")

    def _minmax(self, expr, name):
        args = [self._print(a) for a in expr.args]
        return f"{name}({', '.join(args)})"

    def _print_Max(self, expr):
        return self._minmax(expr, "max")

    def _print_Min(self, expr):
        return self._minmax(expr, "min")

    def _print_not_supported(self, expr):
        raise ValueError(f"cannot generate Fortran for {type(expr).__name__} ({expr}): "
                         "not supported in compiled code")

    def _print_Pow(self, expr):
        b, e = expr.base, expr.exp
        pb = self.parenthesize(b, sp.printing.precedence.PRECEDENCE["Pow"] + 1)
        if e.is_Integer:
            k = int(e)
            if k == 1:
                return self._print(b)
            if k > 0:
                return f"{pb}**{k}"
            if k == -1:
                return f"{self._real(1)}/{pb}"
            return f"{self._real(1)}/{pb}**{-k}"
        if e == sp.S.Half:
            return f"sqrt({self._print(b)})"
        if e == -sp.S.Half:
            return f"{self._real(1)}/sqrt({self._print(b)})"
        pe = self.parenthesize(e, sp.printing.precedence.PRECEDENCE["Pow"] + 1)
        return f"{pb}**{pe}"


def prepare(expr):
    """Half-integer powers b**(k/2) -> cm_sqrt(b)**k (one sqrt, integer power)."""
    if not isinstance(expr, sp.Basic):
        return sp.sympify(expr)

    def is_half(e):
        return e.is_Pow and e.exp.is_Rational and not e.exp.is_Integer and e.exp.q == 2

    return expr.replace(is_half, lambda e: _SQRT(e.base) ** int(e.exp.p))


def _wrap(line, indent, width=96):
    """Split a long statement with free-form continuations (& ... &)."""
    if len(indent) + len(line) <= width:
        return [indent + line]
    out, rest, first = [], line, True
    room = width - len(indent) - 2
    while rest:
        pad = indent if first else indent + "    &"
        take = room if first else room - 5
        if len(rest) <= take:
            out.append(pad + rest)
            break
        cut = take
        for ch in (" ", "+", "*", ",", "("):    # prefer a break at an operator
            k = rest.rfind(ch, take // 2, take)
            if k > 0:
                cut = k
                break
        out.append(pad + rest[:cut] + "&")
        rest = rest[cut:]
        first = False
    return out


def assignments(targets, exprs, printer, indent="        ", prefix="w"):
    """CSE over exprs; returns (declared temporaries, statement lines) assigning each
    expression to the Fortran target string in `targets` (zero entries included)."""
    exprs = [prepare(sp.sympify(e)) for e in exprs]
    tmp = sp.numbered_symbols(prefix + "_cse")
    repl, red = sp.cse(exprs, symbols=tmp, order="none")
    names = dict(printer.names)
    temps = []
    for k, (s, _) in enumerate(repl):
        names[s] = f"{prefix}{k + 1}"
        temps.append(names[s])
    saved = printer.names
    printer.names = names
    lines = []
    try:
        for s, e in repl:
            lines += _wrap(f"{names[s]} = {printer._print(e)}", indent)
        for tgt, e in zip(targets, red):
            lines += _wrap(f"{tgt} = {printer._print(e)}", indent)
    finally:
        printer.names = saved
    return temps, lines


def _decl_temps(temps, indent="        "):
    out = []
    for i in range(0, len(temps), 10):
        out.append(f"{indent}real(dp) :: " + ", ".join(temps[i:i + 10]))
    return out


def _matrix_targets(name, mat):
    """Targets and expressions of the nonzero entries of a matrix (column-major array)."""
    tg, ex = [], []
    rows, cols = mat.shape
    for j in range(cols):
        for i in range(rows):
            e = mat[i, j]
            if e != 0:
                tg.append(f"{name}({i + 1}, {j + 1})")
                ex.append(e)
    return tg, ex


def _vector_targets(name, vec):
    return [f"{name}({i + 1})" for i in range(len(vec))], list(vec)


def _split(term):
    """A term of a trigonometric argument as (base, sign): -x -> (x, -1)."""
    c, r = term.as_coeff_Mul()
    return (r, -1) if c == -1 else (term, 1)


def trig_split(exprs):
    """Sines and cosines of sums from those of their terms (angle addition), when that
    needs fewer distinct trigonometric arguments: e.g. the n(n-1)/2 cos(q_i - q_j) of a
    chain's mass matrix from the n pairs sin(q_i), cos(q_i) (gfortran evaluates sin and cos
    of one argument as one sincos). Returns (exprs with sin/cos replaced by symbols,
    [(symbol, definition)] in evaluation order: sin/cos of the single terms first, then the
    sums, each from an already defined shorter sum and one term). Unchanged when nothing is
    gained."""
    atoms = set()
    for e in exprs:
        atoms |= e.atoms(sp.sin, sp.cos)
    args = {a.args[0] for a in atoms}
    sums = [x for x in args if x.is_Add]
    if not sums:
        return exprs, []
    bases = {_split(tm)[0] for x in sums for tm in x.args}
    singles = {_split(x)[0] for x in args if not x.is_Add}
    if len(bases | singles) >= len(args):
        return exprs, []
    defs, S, C = [], {}, {}
    for k, r in enumerate(sorted(bases | singles, key=sp.default_sort_key)):
        S[r], C[r] = sp.Dummy(f"ts{k}", real=True), sp.Dummy(f"tc{k}", real=True)
        defs += [(S[r], sp.sin(r)), (C[r], sp.cos(r))]

    def sc(x):
        if not x.is_Add:
            r, g = _split(x)
            return g*S[r], C[r]
        if x not in S:
            terms = list(x.args)
            pick = terms[-1]
            for tm in terms:
                rest = sp.Add(*[u for u in terms if u != tm])
                if not rest.is_Add or rest in S:
                    pick = tm
                    break
            sb, cb = sc(sp.Add(*[u for u in terms if u != pick]))
            st, ct = sc(pick)
            k = len(S)
            S[x], C[x] = sp.Dummy(f"ts{k}", real=True), sp.Dummy(f"tc{k}", real=True)
            defs.extend([(S[x], sb*ct + cb*st), (C[x], cb*ct - sb*st)])
        return S[x], C[x]
    for x in sorted(sums, key=lambda u: (len(u.args), sp.default_sort_key(u))):
        sc(x)
    rep = {a: sc(a.args[0])[0 if isinstance(a, sp.sin) else 1] for a in atoms}
    return [e.xreplace(rep) for e in exprs], defs


def _trig_defs(printer, exprs, local, ind):
    """:func:`trig_split` over exprs: (exprs with the sines and cosines replaced, {symbol:
    Fortran name tg<k>}, the statements defining them). `local`: further {symbol: name}
    the definitions may refer to."""
    exprs, tdefs = trig_split(exprs)
    extra = {s_: f"tg{k + 1}" for k, (s_, _) in enumerate(tdefs)}
    saved = printer.names
    printer.names = {**saved, **extra, **local}
    try:
        lines = []
        for s_, e in tdefs:
            lines += _wrap(f"{extra[s_]} = {printer._print(prepare(e))}", ind)
    finally:
        printer.names = saved
    return exprs, extra, lines


def _procedure(printer, cname, args, decls, outputs, result=None, defs=(), trig=True):
    """One bind(C) subroutine (or a real(dp) function when `result` is an expression).
    `defs` [(Symbol, expr)]: local values computed first (their own common-subexpression
    elimination), that the outputs refer to; `trig`: :func:`trig_split` over everything."""
    ind = "        "
    targets, exprs, zero = [], [], []
    for name, obj, is_matrix in outputs:
        if is_matrix:
            tg, ex = _matrix_targets(name, obj)
            if len(tg) < obj.shape[0] * obj.shape[1]:
                zero.append(f"{ind}{name} = 0.0_dp")
        else:
            tg, ex = _vector_targets(name, list(obj))
        targets += tg
        exprs += ex
    if result is not None:
        targets.append(cname)
        exprs.append(result)
    defs = list(defs)
    nd = len(defs)
    allx = [sp.sympify(e) for _, e in defs] + [sp.sympify(e) for e in exprs]
    local = {s: f"dd{k + 1}" for k, (s, _) in enumerate(defs)}
    allx, extra, lines0 = _trig_defs(printer, allx, local, ind) if trig else (allx, {}, [])
    extra.update(local)
    saved = printer.names
    printer.names = {**saved, **extra}
    try:
        temps1, lines1 = ([], [])
        if nd:
            temps1, lines1 = assignments([extra[s_] for s_, _ in defs], allx[:nd], printer,
                                         ind, prefix="x")
        temps, lines = assignments(targets, allx[nd:], printer, ind)
    finally:
        printer.names = saved
    if result is None:
        head = f"    subroutine {cname}({', '.join(args)}) bind(C, name=\"{cname}\")"
        tail = f"    end subroutine {cname}"
    else:
        head = (f"    function {cname}({', '.join(args)}) bind(C, name=\"{cname}\") "
                f"result({cname}_r)")
        tail = f"    end function {cname}"
        lines = [ln.replace(f"{ind}{cname} = ", f"{ind}{cname}_r = ", 1) for ln in lines]
        decls = decls + [f"{ind}real(dp) :: {cname}_r"]
    return ([head] + decls + _decl_temps(list(extra.values()) + temps1 + temps, ind) + zero
            + lines0 + lines1 + lines + [tail, ""])


def product_terms(jac, printer):
    """Row-wise terms of the product J x for a Jacobian `jac` (sympy Matrix): for each row
    i, a list of (column j, sign "+" or "-", coefficient) over the structurally nonzero
    entries, where the coefficient is None for +-1, the printed literal of the magnitude of
    a constant entry, or the index into the returned list of variable entries (expressions
    of t, y, p). Returns (rows, variable entries)."""
    rows, var = [], []
    for i in range(jac.shape[0]):
        terms = []
        for j in range(jac.shape[1]):
            e = sp.sympify(jac[i, j])
            if e == 0:
                continue
            if e.is_number and e.is_real:
                sign = "-" if e < 0 else "+"
                mag = abs(e)
                terms.append((j, sign, None if mag == 1 else printer._print(mag)))
            else:
                terms.append((j, "+", len(var)))
                var.append(e)
        rows.append(terms)
    return rows, var


def product_lines(rows, entry_names, x, jx, col, indent):
    """Statements jx(i, col) = sum_j J_ij x(j, col) for :func:`product_terms`' rows
    (`entry_names`: the Fortran names of the variable entries)."""
    out = []
    for i, terms in enumerate(rows):
        parts = []
        for j, sign, c in terms:
            xv = f"{x}({j + 1}, {col})"
            if c is None:
                parts.append((sign, xv))
            elif isinstance(c, int):
                parts.append((sign, f"{entry_names[c]}*{xv}"))
            else:
                parts.append((sign, f"{c}*{xv}"))
        if not parts:
            rhs = "0.0_dp"
        else:
            rhs = ("-" if parts[0][0] == "-" else "") + parts[0][1]
            rhs += "".join(f" {sg} {t}" for sg, t in parts[1:])
        out += _wrap(f"{jx}({i + 1}, {col}) = {rhs}", indent)
    return out


def _jac_prod_procedure(printer, d):
    """cm_jac_prod(t, y, k, x, jx, p): jx = J x for an n x k block x. The variable entries
    of J are evaluated once (one common-subexpression elimination), then each column of x
    is multiplied over the structurally nonzero entries only (constant entries folded)."""
    n, npar = d.n, max(len(d.params), 1)
    ind = "        "
    rows, var = product_terms(d.jac, printer)
    allx, extra, lines0 = _trig_defs(printer, [sp.sympify(e) for e in var], {}, ind)
    ent = [f"jv{k + 1}" for k in range(len(var))]
    saved = printer.names
    printer.names = {**saved, **extra}
    try:
        temps, lines = assignments(ent, allx, printer, ind) if var else ([], [])
    finally:
        printer.names = saved
    name = "conmech_jac_prod"
    head = [f"    subroutine {name}(t, y, k, x, jx, p) bind(C, name=\"{name}\")",
            f"{ind}real(dp), value, intent(in) :: t",
            f"{ind}real(dp), intent(in) :: y({n})",
            f"{ind}integer(c_int), value, intent(in) :: k",
            f"{ind}real(dp), intent(in) :: x({n}, k)",
            f"{ind}real(dp), intent(out) :: jx({n}, k)",
            f"{ind}real(dp), intent(in) :: p({npar})",
            f"{ind}integer :: c"]
    loop = ([f"{ind}do c = 1, k"] + product_lines(rows, ent, "x", "jx", "c", ind + "    ")
            + [f"{ind}end do"])
    return (head + _decl_temps(list(extra.values()) + temps + ent, ind) + lines0 + lines
            + loop + [f"    end subroutine {name}", ""])


def _names(d):
    names = {d.t: "t"}
    for i, s in enumerate(d.coords):
        names[s] = f"{'y' if d.kind == 'ode' else 'q'}({i + 1})"
    for i, s in enumerate(d.speeds):
        names[s] = f"v({i + 1})"
    for i, s in enumerate(d.accels):
        names[s] = f"a({i + 1})"
    for i, s in enumerate(d.params):
        names[s] = f"p({i + 1})"
    return names


def _model_info(d, values):
    """The description procedures of a model library (conmech_model_library's convention):
    kind, dimensions, default parameter values `values` and parameter names."""
    kind = {"ode": 1, "generalized": 2, "constrained": 3}[d.kind]
    n_hol = getattr(d, "n_hol", 0) or 0
    n_nh = getattr(d, "n_nh", 0) or 0
    rheo = int(bool(getattr(d, "rheonomic", False)))
    npar = len(d.params)
    names = string_constant(" ".join(d.param_names), "            ")
    vals = ", ".join(FortranPrinter({})._real(float(v)) for v in values) or "0.0_dp"
    ind = "        "
    return [
        '    subroutine conmech_model_info(info) bind(C, name="conmech_model_info")',
        f"{ind}integer(c_int), intent(out) :: info(6)",
        f"{ind}info = [{kind}, {d.n}, {n_hol}, {n_nh}, {rheo}, {npar}]",
        "    end subroutine conmech_model_info",
        "",
        '    subroutine conmech_model_params(p) bind(C, name="conmech_model_params")',
        f"{ind}real(dp), intent(out) :: p({max(npar, 1)})",
        f"{ind}p = [{vals}]" if npar else f"{ind}p = 0.0_dp",
        "    end subroutine conmech_model_params",
        "",
        '    subroutine conmech_model_param_names(buf, n) bind(C, '
        'name="conmech_model_param_names")',
        f"{ind}integer(c_int), value, intent(in) :: n",
        f"{ind}character(kind=c_char), intent(out) :: buf(n)",
        f"{ind}character(len=*), parameter :: names = &",
        *names,
        f"{ind}integer :: i",
        f"{ind}buf = c_null_char",
        f"{ind}do i = 1, min(n - 1, len(names))",
        f"{ind}    buf(i) = names(i:i)",
        f"{ind}end do",
        "    end subroutine conmech_model_param_names",
        "",
    ]


def _constrained_derivative_procedures(printer, d, T, P, arr):
    """The procedures conmech_forces_jac and (with constraints)
    conmech_constraint_hessian of a constrained record: the exact Jacobian of Radau IIA on
    its equations of motion."""
    from .constrained_jac import constrained_derivatives
    n = d.n
    R, HL, HV, lam = constrained_derivatives(d)
    QV = [T, arr("q", [n]), arr("v", [n])]
    out = [_procedure(printer, "conmech_forces_jac", ["t", "q", "v", "a", "r", "p"],
                      QV + [arr("a", [n]), arr("r", [n, 2 * n], "out"), P],
                      [("r", R, True)])]
    if HL is None:
        return out
    m = len(lam)
    saved = printer.names
    printer.names = {**saved, **{s: f"lam({i + 1})" for i, s in enumerate(lam)}}
    try:
        out.append(_procedure(printer, "conmech_constraint_hessian",
                              ["t", "q", "v", "lam", "hl", "hv", "p"],
                              QV + [arr("lam", [m]), arr("hl", [n, n], "out"),
                                    arr("hv", [m, n], "out"), P],
                              [("hl", HL, True), ("hv", HV, True)]))
    finally:
        printer.names = saved
    return out


def generate(d, module="conmech_symbolic_model", model_values=None, taylor=False):
    """Fortran source of the bind(C) module for the derived system `d`; returns
    (source, list of the entry points present, e.g. ["mass", "forces", ...]).
    With `model_values` (the default parameter values), the module also describes itself
    as a model library (conmech_model_info, conmech_model_params,
    conmech_model_param_names) for `sweep --model` and `conmech.compiled.load_model`.
    With `taylor` an ode module also holds its Taylor recurrences (conmech_taylor* of
    :mod:`conmech.symbolic.taylor`), as a model library written for other programs needs;
    without, they are a library of their own compiled on first need
    (:mod:`conmech.symbolic.taylor_library`): most calls never run Taylor's method, and
    its recurrences (the system's and the variational system's, in double, batch and
    quadruple precision) are most of the code to compile."""
    if not isinstance(module, str) or not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]{0,62}", module):
        raise ValueError(f"bad module name {module!r} (a Fortran name: a letter, then "
                         "letters, digits or underscores; at most 63 characters)")
    if hasattr(type(d), "generate_fortran"):     # a record that writes its own module
        src, entries = d.generate_fortran(module, model_values)
        c_names = _c_names(entries, model_values)
        check_source(src, c_names + private_procedures(entries, src), c_names)
        return src, entries
    pr = FortranPrinter(_names(d))
    n = d.n
    npar = max(len(d.params), 1)
    ind = "        "
    T = f"{ind}real(dp), value, intent(in) :: t"
    P = f"{ind}real(dp), intent(in) :: p({npar})"

    def arr(name, shape, intent="in"):
        return f"{ind}real(dp), intent({intent}) :: {name}({', '.join(map(str, shape))})"

    procs, entries = [], []
    if d.kind == "ode":
        procs.append(_procedure(pr, "conmech_rhs", ["t", "y", "dydt", "p"],
                                [T, arr("y", [n]), arr("dydt", [n], "out"), P],
                                [("dydt", d.f, False)]))
        procs.append(_procedure(pr, "conmech_jac", ["t", "y", "dfdy", "p"],
                                [T, arr("y", [n]), arr("dfdy", [n, n], "out"), P],
                                [("dfdy", d.jac, True)]))
        procs.append(_jac_prod_procedure(pr, d))
        entries = ["rhs", "jac", "jac_prod"]
        if taylor:
            # Taylor coefficients of the solution (conmech.symbolic.taylor), when f is smooth
            from .taylor import ode_taylor_lines
            tl, te, _ = ode_taylor_lines(d, pr.names)
            if tl:
                procs.append(tl)
                entries += te
    else:
        Q1 = [T, arr("q", [n])]
        QV = Q1 + [arr("v", [n])]
        procs.append(_procedure(pr, "conmech_mass", ["t", "q", "mm", "p"],
                                Q1 + [arr("mm", [n, n], "out"), P], [("mm", d.M, True)]))
        st = d.struct if d.kind == "generalized" else None
        procs.append(_procedure(pr, "conmech_forces", ["t", "q", "v", "f", "p"],
                                QV + [arr("f", [n], "out"), P],
                                [("f", sp.Matrix(st["Q"]) if st else d.Q, False)],
                                defs=st["defs_Q"] if st else ()))
        entries += ["mass", "forces"]
        if d.kind == "generalized":
            # M and Q in one function: one common-subexpression elimination over both (the
            # sines and cosines of the coordinates once); the right-hand side calls this
            procs.append(_procedure(pr, "conmech_mass_forces", ["t", "q", "v", "mm", "f", "p"],
                                    QV + [arr("mm", [n, n], "out"), arr("f", [n], "out"), P],
                                    [("mm", d.M, True),
                                     ("f", sp.Matrix(st["Q"]) if st else d.Q, False)],
                                    defs=st["defs_Q"] if st else ()))
            entries.append("mass_forces")
        if st is not None and "R" in st:
            procs.append(_procedure(pr, "conmech_forces_jac", ["t", "q", "v", "a", "r", "p"],
                                    QV + [arr("a", [n]), arr("r", [n, 2 * n], "out"), P],
                                    [("r", st["R"], True)], defs=st["defs_R"]))
            entries.append("forces_jac")
        elif d.kind == "generalized" and st is None and d.R is not None:
            procs.append(_procedure(pr, "conmech_forces_jac", ["t", "q", "v", "a", "r", "p"],
                                    QV + [arr("a", [n]), arr("r", [n, 2 * n], "out"), P],
                                    [("r", d.R, True)]))
            entries.append("forces_jac")
        if d.kind == "generalized" and getattr(d, "aba", None) is not None:
            # a planar tree (conmech.symbolic.tree): a = M^-1 Q by the articulated-body
            # algorithm, straight-line O(n) code
            from .tree import accel_procedure
            procs.append(accel_procedure(pr, d))
            entries.append("accel")
        if d.energy is not None:
            procs.append(_procedure(pr, "conmech_energy", ["t", "q", "v", "p"], QV + [P], [],
                                    result=d.energy))
            entries.append("energy")
        if d.kind == "constrained" and d.n_hol:
            h = d.n_hol
            procs.append(_procedure(pr, "conmech_phi", ["t", "q", "c", "p"],
                                    Q1 + [arr("c", [h], "out"), P], [("c", d.phi, False)]))
            procs.append(_procedure(pr, "conmech_phi_jac", ["t", "q", "g", "p"],
                                    Q1 + [arr("g", [h, n], "out"), P],
                                    [("g", d.G, True)]))
            procs.append(_procedure(pr, "conmech_phi_t", ["t", "q", "pt", "p"],
                                    Q1 + [arr("pt", [h], "out"), P], [("pt", d.phi_t, False)]))
            procs.append(_procedure(pr, "conmech_phi_gamma", ["t", "q", "v", "gam", "p"],
                                    QV + [arr("gam", [h], "out"), P],
                                    [("gam", d.gamma_h, False)]))
            entries += ["phi", "phi_jac", "phi_t", "phi_gamma"]
        if d.kind == "constrained" and d.n_nh:
            k = d.n_nh
            procs.append(_procedure(pr, "conmech_nh_matrix", ["t", "q", "am", "b", "p"],
                                    Q1 + [arr("am", [k, n], "out"), arr("b", [k], "out"), P],
                                    [("am", d.A, True), ("b", d.b, False)]))
            procs.append(_procedure(pr, "conmech_nh_gamma", ["t", "q", "v", "gam", "p"],
                                    QV + [arr("gam", [k], "out"), P],
                                    [("gam", d.gamma_n, False)]))
            entries += ["nh_matrix", "nh_gamma"]
        if d.kind == "constrained":
            procs += _constrained_derivative_procedures(pr, d, T, P, arr)
            entries.append("forces_jac")
            if d.n_hol or d.n_nh:
                entries.append("constraint_hessian")
    names = ", ".join(comment_text(c) for c in getattr(d, "coord_names",
                                                         [str(c) for c in d.coords]))
    pnames = ", ".join(comment_text(p) for p in d.param_names)
    head = [f"!> Generated by conmech.symbolic: {d.kind} system."]
    head += comment_lines(f"Coordinates {names}; parameters p = [{pnames}]. Do not edit.")
    head += [
        f"module {module}",
        "    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_char, c_null_char, "
        "c_ptr, c_f_pointer",
        "    use, intrinsic :: iso_fortran_env, only: real128",
        "    implicit none",
        "    integer, parameter :: dp = c_double, qp = real128",
        "    public",
    ]
    # the quadruple-precision Taylor entry wraps an internal body: private, so that the
    # library exports conmech's C entry points only
    internal = private_procedures(entries)
    head += [f"    private :: {p}" for p in internal] + ["contains", ""]
    if model_values is not None:
        if len(model_values) != len(d.params):
            raise ValueError(f"{len(model_values)} parameter values for {len(d.params)} "
                             "parameters")
        procs.append(_model_info(d, model_values))
    body = []
    for p in procs:
        body += p
    src = "\n".join(head + body + [f"end module {module}", ""])
    c_names = _c_names(entries, model_values)
    check_source(src, c_names + internal, c_names)
    return src, entries
