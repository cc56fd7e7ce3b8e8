"""The Fortran printer of the code generators: sympy expressions to ``real(dp)``
assignments and whole bind(C) procedures.

Each procedure's outputs share one common-subexpression elimination (sympy.cse). Sines and
cosines of sums are built from those of their terms by angle addition when that needs fewer
distinct arguments (:func:`trig_split`: a chain's cos(q_i - q_j) from the n pairs sin(q_i),
cos(q_i)). Powers with half-integer exponents become integer powers of one square root (so
r^3 = (x^2+y^2)^(3/2) costs one sqrt and two multiplications, and the sqrt is shared by CSE);
integer powers are printed with integer exponents (gfortran expands them into
multiplications); every number is a ``real(dp)`` literal (no integer division, no ``d0``).
:class:`FortranPrinter`, :func:`assignments` and :func:`_procedure` serve every emitter (the
compiled model library, trees, loops, Taylor recurrences, standalone modules).
"""
import sympy as sp
from sympy.printing.fortran import FCodePrinter


_SQRT = sp.Function("conmech_sqrt")   # an unevaluated sqrt, so that b**(3/2) = cm_sqrt(b)**3


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


#: the bits of the quiet NaN of each real kind of the generated code, as ieee_value(1.0_k,
#: ieee_quiet_nan) gives it: (hexadecimal digits, decimal range of an integer that holds them)
_QUIET_NAN_BITS = {"dp": ("7FF8000000000000", 18),
                   "qp": ("7FFF8000000000000000000000000000", 38)}


def quiet_nan(kind="dp"):
    """Fortran text of the quiet NaN of the real kind `kind` ("dp", or "qp" for quadruple
    precision: real128) made from its bits, with nothing to import: the generated code fills
    the coefficients of a failed expansion with it. Not ieee_value: gfortran saves and
    restores the whole floating-point environment (about 0.2 us) on every call of a
    procedure whose scope uses an intrinsic IEEE module, which would tax every expansion
    and every right-hand side. The quadruple NaN is not the double one converted: a NaN in
    a constant conversion is an error of gfortran's range check."""
    digits, rng = _QUIET_NAN_BITS[kind]
    return f"transfer(int(z'{digits}', selected_int_kind({rng})), 1.0_{kind})"


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


def entry_heads(d, ind="        "):
    """What every generated entry point of the derived record d starts from: the printer of
    its expressions, the parameter vector's length (at least 1: Fortran has no empty
    explicit-shape dummy), the indent and the declarations of t (by value) and p(npar)."""
    npar = max(len(d.params), 1)
    return (FortranPrinter(_names(d)), npar, ind, f"{ind}real(dp), value, intent(in) :: t",
            f"{ind}real(dp), intent(in) :: p({npar})")
