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
where the expanded Euler-Lagrange expressions cost O(n^3).

The printer (:class:`FortranPrinter`, :func:`assignments`, angle addition, square roots) is
:mod:`conmech.symbolic.printer`, the escaping of user strings and the check of a generated
source :mod:`conmech.symbolic.source_text`; their names are also importable from here.
"""
import re

import sympy as sp

from .._core import slot_table as _table
from .printer import (_SQRT, FortranPrinter, _decl_temps, _names, _procedure,  # noqa: F401
                      _trig_defs, _wrap, assignments, entry_heads, prepare, product_lines,
                      product_terms, trig_split)
from .constrained_jac import constrained_derivatives
from .library_info import _model_info
from .tree_print import accel_procedure
from .taylor import ode_taylor_lines
from .source_text import (_c_names, check_source, comment_lines, comment_text,  # noqa: F401
                          private_procedures, string_constant)

__all__ = ["CODEGEN_VERSION", "FortranPrinter", "assignments", "generate", "prepare",
           "trig_split", "ENTRY_POINTS", "product_terms", "product_lines", "comment_text",
           "comment_lines", "string_constant", "check_source"]

# C names of the entry points (conmech_<name>) per kind, the names of conmech.compiled's
# arguments: the table of compiled functions
ENTRY_POINTS = _table.ENTRY_POINTS

#: bump when the generated code or the derivation changes (invalidates the derivation cache)
CODEGEN_VERSION = "11"  # 2: conmech_* entry names, model-library description;
#                         3: structured forces / Jacobian, sin and cos by angle addition;
#                         4: conmech_mass_forces (M and Q in one call, shared subexpressions);
#                         5: conmech_jac_prod (ode: J x for a block of columns, no J formed);
#                         6: conmech_accel of planar trees (articulated-body algorithm)
#                         7: conmech_taylor* (Taylor coefficients, conmech.symbolic.taylor)
#                         8: constrained: conmech_forces_jac, conmech_constraint_hessian
#                         9: user strings escaped (comments, parameter names as data)
#                        10: Taylor recurrences in a library of their own, on first need
#                        11: Taylor: symmetric sums of squares, one weighted sum per power


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


def _constrained_derivative_procedures(printer, d, T, P, arr):
    """The procedures conmech_forces_jac and (with constraints)
    conmech_constraint_hessian of a constrained record: the exact Jacobian of Radau IIA on
    its equations of motion."""
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
    pr, npar, ind, T, P = entry_heads(d)
    n = d.n

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
