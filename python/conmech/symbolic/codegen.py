"""Fortran code generation for the C ABI of compiled systems (bind(C) procedures).

:func:`generate` turns a :class:`~conmech.symbolic.derive.Derived` record into the source
of one free-form Fortran module whose procedures have the C signatures of conmech's
compiled systems (``value`` for t, explicit-shape arrays, column-major matrices, the
parameter array ``p`` last)::

    ode:          cm_rhs(t, y, dydt, p), cm_jac(t, y, dfdy, p)
    generalized:  cm_mass(t, q, M, p), cm_forces(t, q, v, Q, p),
                  cm_forces_jac(t, q, v, a, R, p), real cm_energy(t, q, v, p)
    constrained:  cm_mass, cm_forces, cm_energy, and as present cm_phi(t, q, c, p),
                  cm_phi_jac(t, q, G, p), cm_phi_t(t, q, pt, p),
                  cm_phi_gamma(t, q, v, g, p), cm_nh_matrix(t, q, A, b, p),
                  cm_nh_gamma(t, q, v, g, p)

Each procedure's outputs share one common-subexpression elimination (sympy.cse). Powers
with half-integer exponents become integer powers of one square root (so r^3 = (x^2+y^2)^(3/2)
costs one sqrt and two multiplications, and the sqrt is shared by CSE); integer powers are
printed with integer exponents (gfortran expands them into multiplications); every number is
a ``real(dp)`` literal (no integer division, no ``d0``).

:class:`FortranPrinter` and :func:`assignments` are reusable by other emitters (e.g. a
standalone module whose type extends conmech's system types).
"""
import keyword

import sympy as sp
from sympy.printing.fortran import FCodePrinter

__all__ = ["CODEGEN_VERSION", "FortranPrinter", "assignments", "generate", "prepare",
           "ENTRY_POINTS"]

# C names of the entry points, per kind, with the name of conmech.compiled's argument
ENTRY_POINTS = {
    "ode": ["rhs", "jac"],
    "generalized": ["mass", "forces", "forces_jac", "energy"],
    "constrained": ["mass", "forces", "energy", "phi", "phi_jac", "phi_t", "phi_gamma",
                    "nh_matrix", "nh_gamma"],
}

#: bump when the generated code or the derivation changes (invalidates the derivation cache)
CODEGEN_VERSION = "1"

_SQRT = sp.Function("cm_sqrt")   # an unevaluated sqrt, so that b**(3/2) = cm_sqrt(b)**3


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
        s = repr(float(x))
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


def _procedure(printer, cname, args, decls, outputs, result=None):
    """One bind(C) subroutine (or a real(dp) function when `result` is an expression)."""
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
    temps, lines = assignments(targets, exprs, printer, ind)
    if result is None:
        head = f"    subroutine {cname}({', '.join(args)}) bind(C, name=\"{cname}\")"
        tail = f"    end subroutine {cname}"
    else:
        head = (f"    function {cname}({', '.join(args)}) bind(C, name=\"{cname}\") "
                f"result({cname}_r)")
        tail = f"    end function {cname}"
        lines = [ln.replace(f"{ind}{cname} = ", f"{ind}{cname}_r = ", 1) for ln in lines]
        decls = decls + [f"{ind}real(dp) :: {cname}_r"]
    return [head] + decls + _decl_temps(temps, ind) + zero + lines + [tail, ""]


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


def generate(d, module="conmech_symbolic_model"):
    """Fortran source of the bind(C) module for the derived system `d`; returns
    (source, list of the entry points present, e.g. ["mass", "forces", ...])."""
    if not module.isidentifier() or keyword.iskeyword(module):
        raise ValueError(f"bad module name {module!r}")
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
        procs.append(_procedure(pr, "cm_rhs", ["t", "y", "dydt", "p"],
                                [T, arr("y", [n]), arr("dydt", [n], "out"), P],
                                [("dydt", d.f, False)]))
        procs.append(_procedure(pr, "cm_jac", ["t", "y", "dfdy", "p"],
                                [T, arr("y", [n]), arr("dfdy", [n, n], "out"), P],
                                [("dfdy", d.jac, True)]))
        entries = ["rhs", "jac"]
    else:
        Q1 = [T, arr("q", [n])]
        QV = Q1 + [arr("v", [n])]
        procs.append(_procedure(pr, "cm_mass", ["t", "q", "mm", "p"],
                                Q1 + [arr("mm", [n, n], "out"), P], [("mm", d.M, True)]))
        procs.append(_procedure(pr, "cm_forces", ["t", "q", "v", "f", "p"],
                                QV + [arr("f", [n], "out"), P], [("f", d.Q, False)]))
        entries += ["mass", "forces"]
        if d.kind == "generalized" and d.R is not None:
            procs.append(_procedure(pr, "cm_forces_jac", ["t", "q", "v", "a", "r", "p"],
                                    QV + [arr("a", [n]), arr("r", [n, 2 * n], "out"), P],
                                    [("r", d.R, True)]))
            entries.append("forces_jac")
        if d.energy is not None:
            procs.append(_procedure(pr, "cm_energy", ["t", "q", "v", "p"], QV + [P], [],
                                    result=d.energy))
            entries.append("energy")
        if d.kind == "constrained" and d.n_hol:
            h = d.n_hol
            procs.append(_procedure(pr, "cm_phi", ["t", "q", "c", "p"],
                                    Q1 + [arr("c", [h], "out"), P], [("c", d.phi, False)]))
            procs.append(_procedure(pr, "cm_phi_jac", ["t", "q", "g", "p"],
                                    Q1 + [arr("g", [h, n], "out"), P],
                                    [("g", d.G, True)]))
            procs.append(_procedure(pr, "cm_phi_t", ["t", "q", "pt", "p"],
                                    Q1 + [arr("pt", [h], "out"), P], [("pt", d.phi_t, False)]))
            procs.append(_procedure(pr, "cm_phi_gamma", ["t", "q", "v", "gam", "p"],
                                    QV + [arr("gam", [h], "out"), P],
                                    [("gam", d.gamma_h, False)]))
            entries += ["phi", "phi_jac", "phi_t", "phi_gamma"]
        if d.kind == "constrained" and d.n_nh:
            k = d.n_nh
            procs.append(_procedure(pr, "cm_nh_matrix", ["t", "q", "am", "b", "p"],
                                    Q1 + [arr("am", [k, n], "out"), arr("b", [k], "out"), P],
                                    [("am", d.A, True), ("b", d.b, False)]))
            procs.append(_procedure(pr, "cm_nh_gamma", ["t", "q", "v", "gam", "p"],
                                    QV + [arr("gam", [k], "out"), P],
                                    [("gam", d.gamma_n, False)]))
            entries += ["nh_matrix", "nh_gamma"]
    names = ", ".join(getattr(d, "coord_names", [str(c) for c in d.coords]))
    head = [
        f"!> Generated by conmech.symbolic: {d.kind} system, coordinates {names};",
        f"!! parameters p = [{', '.join(d.param_names)}]. Do not edit.",
        f"module {module}",
        "    use, intrinsic :: iso_c_binding, only: c_double",
        "    implicit none",
        "    integer, parameter :: dp = c_double",
        "    public",
        "contains",
        "",
    ]
    body = []
    for p in procs:
        body += p
    src = "\n".join(head + body + [f"end module {module}", ""])
    return src, entries
