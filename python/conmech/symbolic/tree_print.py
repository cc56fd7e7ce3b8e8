"""Fast Fortran text of straight-line definitions (sums, products, integer powers, sines
and cosines printed directly) for the generated code of trees."""
import sympy as sp

from .codegen import prepare

__all__ = ["fast_print", "IND", "proc"]

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
