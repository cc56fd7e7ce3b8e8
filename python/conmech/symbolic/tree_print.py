"""Fast Fortran text of straight-line definitions (sums, products, integer powers, sines
and cosines printed directly) for the generated code of trees."""
import sympy as sp

from .printer import _decl_temps, _wrap, prepare

__all__ = ["fast_print", "IND", "proc", "aba_lines", "accel_procedure", "SC_DECL", "pos_call"]

#: the indentation of statements inside a module procedure
IND = "        "


def proc(head, decls, body, name, kind="subroutine"):
    """The lines of a module procedure."""
    return [f"    {head}"] + decls + body + [f"    end {kind} {name}", ""]

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


def aba_lines(printer, d, target="a", ind="        "):
    """(declarations, statements) of the straight-line articulated-body code ``d.aba``
    assigning the accelerations to ``target(1..n)``, printed with `printer` (whose names
    map the coordinates, velocities and parameters). A pivot that is not positive (or NaN)
    is set to 0, so that its inverse and the accelerations are infinite or NaN (the
    integrators then stop with a non-finite status); no ieee_arithmetic (its procedure
    entry and exit would cost ~90 instructions per call)."""
    defs, acc = d.aba
    names = {s: f"b{k + 1}" for k, (s, e) in enumerate(
        (s, e) for s, e in defs if not isinstance(e, str))}
    saved = printer.names
    printer.names = {**saved, **names}
    body = []
    try:
        for s, e in defs:
            if isinstance(e, str):      # "positive": the pivot check
                nm = names[s]
                body.append(f"{ind}if (.not. ({nm} > 0.0_dp)) {nm} = 0.0_dp")
            else:
                body += _wrap(f"{names[s]} = {printer._print(prepare(e))}", ind)
        for i, e in enumerate(acc):
            body += _wrap(f"{target}({i + 1}) = {printer._print(prepare(sp.sympify(e)))}",
                          ind)
    finally:
        printer.names = saved
    return _decl_temps(list(names.values()), ind), body


def accel_procedure(printer, d, cname="conmech_accel"):
    """Fortran lines of the bind(C) subroutine ``cname(t, q, v, a, p)`` that evaluates the
    articulated-body accelerations (:func:`aba_lines`)."""
    n = d.n
    npar = max(len(d.params), 1)
    ind = "        "
    decl, body = aba_lines(printer, d, "a", ind)
    head = [f'    subroutine {cname}(t, q, v, a, p) bind(C, name="{cname}")',
            f"{ind}real(dp), value, intent(in) :: t",
            f"{ind}real(dp), intent(in) :: q({n}), v({n})",
            f"{ind}real(dp), intent(out) :: a({n})",
            f"{ind}real(dp), intent(in) :: p({npar})"]
    return head + decl + body + [f"    end subroutine {cname}", ""]


SC_DECL = f"{IND}real(dp) :: sc(2, nb)"


def pos_call(em, I=IND):
    """The statements that evaluate the sines and cosines and the position pass."""
    return em.trig_lines + [f"{I}call tree_pos(t, q, sc, p, w)"]
