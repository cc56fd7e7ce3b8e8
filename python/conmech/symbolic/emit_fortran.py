"""Standalone Fortran modules from symbolic models, for fpm projects and batch codes.

:func:`emit` turns a :class:`~conmech.symbolic.derive.Derived` record into the source of one
self-contained Fortran module that needs only ``use conmech, only: ...`` (the names it
uses; no Python, no C ABI, no shared library): the parameters are components of the type
with their values as defaults.

- ode (``derive_ode``): ``type, extends(ode_system) :: NAME`` with ``rhs``, the exact
  ``jacobian`` (``has_jacobian`` true) and the Jacobian product ``jacobian_product`` /
  ``rhs_jacobian_product`` (``has_jacobian_product`` true: ``integrate_stm`` evaluates
  z' = [f; J Phi] in one call over J's structurally nonzero entries, never forming J).
- generalized (``derive_lagrangian``): ``type, extends(generalized_system) :: NAME_mech``
  (mass, forces, energy: for ``generalized_solve``) and ``type, extends(ode_system) ::
  NAME`` with y = [q, v]: ``rhs`` solves M a = Q by Cholesky (LAPACK dpotrf/dpotrs through
  conmech's ``mass_cholesky``; for a planar tree, :func:`conmech.symbolic.planar_tree`, it
  is the articulated-body algorithm instead, O(n)), ``jacobian`` is exact: d a/d[q, v] = M^-1 R with
  R = [dQ/dq - d(M a)/dq |a fixed, dQ/dv]. A mass matrix that is not positive definite makes
  the right-hand side NaN, so conmech's integrators stop with a non-finite status (as
  conmech's own ``generalized_ode``).
- constrained (``derive_constrained``): ``type, extends(constrained_system) :: NAME`` with
  mass, forces, energy, phi, phi_jac, phi_t, phi_gamma, nh_matrix, nh_gamma as present, for
  ``constrained_solve`` (every projection, multipliers, reactions).

Every type has a constructor function ``new_NAME()`` (and ``new_NAME_mech()``) returning an
object with the dimensions set (n, n_hol, n_nh, rheonomic / ndof) and the default
parameters; change a parameter as a component (``s%m = 2.0_dp``). The module also holds
``NAME_n`` (the number of coordinates, or of state variables for an ode) and, for ode and
generalized systems, ``NAME_ny`` (state dimension).

The expressions share one common-subexpression elimination per procedure (the printer of
:mod:`conmech.symbolic.codegen`). The output is deterministic: the same model gives the
same file byte for byte (tests compare a regenerated file with the committed one).

Command line (see ``python -m conmech.symbolic --help``)::

    python -m conmech.symbolic emit MODEL.py -o cart_pendulum_model.f90

MODEL.py defines the system with conmech.symbolic, as one of (first found wins):
a function ``model()`` returning it, or a module-level ``model`` or ``system``; "it" is a
``Derived`` record (``conmech.symbolic.derive.derive_*``, no compilation) or a system made
by ``conmech.symbolic.lagrangian_system`` / ``constrained_system`` / ``ode_system``. Optionally
``name = "..."`` sets the type name (default: the output file's stem without a trailing
``_model``).
"""
import keyword
import re

import sympy as sp

from .record import Derived
from .taylor import emitted_taylor
from .printer import FortranPrinter, assignments, product_lines, product_terms, quiet_nan
from .source_text import check_source, comment_lines, comment_text
from .tree_print import aba_lines

__all__ = ["emit", "fortran_name_check"]

# components and type-bound procedures of conmech's types: a parameter (a component of the
# generated type, always referenced as self%name) may not take these names
_RESERVED = {"n", "n_hol", "n_nh", "rheonomic", "ndof", "mass", "forces", "energy",
             "has_energy", "phi", "phi_jac", "phi_t", "phi_gamma", "nh_matrix", "nh_gamma",
             "rhs", "jacobian", "has_jacobian", "self", "dp", "jacobian_product",
             "rhs_jacobian_product", "has_jacobian_product", "rhs_jacobian",
             "taylor_size", "taylor_jet"}
# names the type may not take: Fortran's intrinsic types (C424 of Fortran 2008), what the
# emitted code takes from conmech, the intrinsic modules, and the intrinsic functions of
# its quiet NaN (printer.quiet_nan): a local name would hide them
_TYPE_TAKEN = {"real", "integer", "logical", "character", "complex", "doubleprecision",
               "doublecomplex", "ode_system", "generalized_system", "constrained_system",
               "cm_success", "mass_cholesky", "dpotrs", "ieee_arithmetic",
               "ieee_exceptions", "ieee_features", "iso_c_binding", "iso_fortran_env",
               "transfer", "int", "selected_int_kind"}
_IND = "        "
# what generated code may take from conmech: the module imports exactly the ones it uses
# (`use conmech, only:`), so that a type, a constant or a parameter of the model may share a
# name with any other entity of conmech (a system called ode_solve, a parameter called
# radau_solve) without a clash
_FROM_CONMECH = ("dp", "CM_SUCCESS", "ode_system", "generalized_system",
                 "constrained_system", "mass_cholesky")


def fortran_name_check(name, what):
    """ValueError unless `name` is a valid Fortran identifier (letter first, letters,
    digits, underscores, at most 63 characters)."""
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]{0,62}", name):
        raise ValueError(f"{what} '{name}' is not a valid Fortran name (a letter, then "
                         "letters, digits or underscores; at most 63 characters)")
    return name


_FNAME = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,62}")


def _component_names(d):
    """The Fortran component name of each parameter: its own name when that is a Fortran
    name (a clash with a name the generated code uses, or two names equal but for case, is
    an error: rename in the model); a name that cannot be one (non-ASCII letters, a leading
    underscore, longer than 40 characters) is mapped to a safe identifier (its letters and
    digits, other characters as uXXXX, prefixed p_), the original kept in the component's
    comment."""
    seen, out = {}, []
    valid = {n.lower() for n in d.param_names if _FNAME.fullmatch(n) and len(n) <= 40}
    for i, name in enumerate(d.param_names):
        low = name.lower()
        if _FNAME.fullmatch(name) and len(name) <= 40:
            if low in _RESERVED:
                raise ValueError(f"parameter '{name}' clashes with a name the generated code "
                                 "uses (rename it in the model)")
            if low in seen:
                raise ValueError(f"parameters '{seen[low]}' and '{name}' are the same name "
                                 "in Fortran (case-insensitive): rename one")
            cand = name
        else:
            body = "".join(c if (c.isascii() and (c.isalnum() or c == "_")) else
                           f"u{ord(c):x}" for c in name)
            cand = f"p_{body}" if len(body) <= 30 else f"p{i + 1}"
            while cand.lower() in seen or cand.lower() in valid or cand.lower() in _RESERVED:
                cand += "_"
        seen[cand.lower()] = name
        out.append(cand)
    return out


def _code(line):
    """A generated line without its comment (no string literal in emitted code holds '!')."""
    k = line.find("!")
    return line if k < 0 else line[:k]


def _lit(x):
    s = repr(float(x))
    if s in ("inf", "-inf", "nan"):
        raise ValueError(f"non-finite parameter value {x}")
    if "." not in s and "e" not in s:
        s += ".0"
    return s + "_dp"


class _Emitter:
    def __init__(self, d, name, comp):
        self.d = d
        self.name = name
        self.n = d.n
        self.comp = comp

    def printer(self, state_in_y=False):
        d = self.d
        names = {d.t: "t"}
        for i, s in enumerate(d.coords):
            names[s] = f"y({i + 1})" if (state_in_y or d.kind == "ode") else f"q({i + 1})"
        for i, s in enumerate(d.speeds):
            names[s] = f"y({self.n + i + 1})" if state_in_y else f"v({i + 1})"
        for i, s in enumerate(d.accels):
            names[s] = f"a({i + 1})"
        for s, pn in zip(d.params, self.comp):
            names[s] = f"self%{pn}"
        return FortranPrinter(names)

    # -------------------------------------------------------------- procedure bodies
    @staticmethod
    def _targets(name, obj, matrix):
        tg, ex = [], []
        if matrix:
            rows, cols = obj.shape
            for j in range(cols):
                for i in range(rows):
                    if obj[i, j] != 0:
                        tg.append(f"{name}({i + 1}, {j + 1})")
                        ex.append(obj[i, j])
            zero = len(tg) < rows * cols
        else:
            vals = list(obj)
            tg = [f"{name}({i + 1})" for i in range(len(vals))]
            ex = vals
            zero = False
        return tg, ex, zero

    def body(self, pr, outputs, prefix="w"):
        """Declarations of temporaries and the statements assigning `outputs`
        [(target name, sympy Matrix/expression, is_matrix)]."""
        targets, exprs, zero_lines = [], [], []
        for name, obj, matrix in outputs:
            if not matrix and not isinstance(obj, sp.MatrixBase) and not isinstance(obj, list):
                targets.append(name)
                exprs.append(obj)
                continue
            tg, ex, zero = self._targets(name, obj, matrix)
            if zero:
                zero_lines.append(f"{_IND}{name} = 0.0_dp")
            targets += tg
            exprs += ex
        temps, lines = assignments(targets, exprs, pr, _IND, prefix=prefix)
        decl = [f"{_IND}real(dp) :: " + ", ".join(temps[i:i + 10])
                for i in range(0, len(temps), 10)]
        return decl, zero_lines + lines

    def proc(self, kind, tname, pname, args, decls, pr, outputs, doc, result=None):
        """A type-bound subroutine (or function with `result` = (name, expr))."""
        self_decl = f"{_IND}class({tname}), intent(in) :: self"
        outs = list(outputs)
        if result is not None:
            outs.append((result[0], result[1], False))
        tdecl, lines = self.body(pr, outs)
        if result is None:
            head = f"    subroutine {pname}({', '.join(['self'] + args)})"
            tail = f"    end subroutine {pname}"
        else:
            head = (f"    function {pname}({', '.join(['self'] + args)}) "
                    f"result({result[0]})")
            tail = f"    end function {pname}"
            decls = decls + [f"{_IND}real(dp) :: {result[0]}"]
        return ([f"    !> {doc}", head, self_decl] + decls + tdecl + lines + [tail, ""])


def _decl(name, shape=None, intent="in"):
    if shape is None:
        return f"{_IND}real(dp), intent({intent}) :: {name}"
    return f"{_IND}real(dp), intent({intent}) :: {name}({', '.join(shape)})"


def _logical_true(tname, pname, doc):
    return [f"    !> {doc}", f"    logical function {pname}(self)",
            f"{_IND}class({tname}), intent(in) :: self", f"{_IND}{pname} = .true.",
            f"    end function {pname}", ""]


def _components(d, comp):
    out = []
    for pn, orig, pv in zip(comp, d.param_names, d.param_values):
        note = "" if pn == orig else f" {comment_text(orig, 40)}"
        out.append(f"{_IND[:8]}real(dp) :: {pn} = {_lit(pv)}   !! parameter{note}")
    return out


def emit(d, name, module=None, source="a conmech.symbolic model"):
    """Fortran source (str) of a standalone module for the derived system `d` whose main
    type is called `name` (module `module`, default NAME_model). `source` is named in the
    header comment (e.g. the model file)."""
    if not isinstance(d, Derived):
        raise TypeError("emit: expected a conmech.symbolic.derive.Derived record")
    if d.kind not in ("ode", "generalized", "constrained"):
        raise ValueError(f"emit: unknown kind {d.kind!r}")
    if hasattr(type(d), "generate_fortran"):     # a tree built by the recursive algorithms
        raise ValueError("emit: this tree was built by the recursive algorithms (bind(C) "
                         "module only); for a standalone module use the Lagrangian route: "
                         "conmech.symbolic.tree.derive_tree(...) or "
                         "conmech.symbolic.spatial.derive_spatial_tree(...)")
    fortran_name_check(name, "type name")
    if len(name) > 40:
        raise ValueError(f"type name '{name}' is longer than 40 characters")
    if keyword.iskeyword(name) or name.lower() in _RESERVED | _TYPE_TAKEN:
        raise ValueError(f"type name '{name}' is reserved (an intrinsic type or module, or a "
                         "name the generated code uses)")
    module = module or f"{name}_model"
    fortran_name_check(module, "module name")
    if module.lower() == name.lower():
        raise ValueError("the module and the type need different names")
    if keyword.iskeyword(module) or module.lower() in _RESERVED | _TYPE_TAKEN:
        raise ValueError(f"module name '{module}' is reserved (an intrinsic type or module, "
                         "or a name the generated code uses)")
    for what, nm in (("type", name), ("module", module)):
        if nm.lower().startswith("conmech"):
            raise ValueError(f"{what} name '{nm}': names beginning with 'conmech' belong to "
                             "the library's modules")
    if d.kind == "generalized" and d.R is None:
        raise ValueError("emit: the model was derived without its Jacobian (jacobian=False); "
                         "the emitted type's exact Jacobian needs it: derive with "
                         "jacobian=True")
    comp = _component_names(d)
    em = _Emitter(d, name, comp)
    n = d.n
    coord_names = ", ".join(comment_text(c) for c in getattr(d, "coord_names",
                                                              [str(c) for c in d.coords]))
    params = ", ".join(f"{a} = {b!r}" for a, b in zip(comp, d.param_values))
    rest = (f"Coordinates: {coord_names}. Parameters (components with defaults): "
            f"{params or 'none'}. Generated code: do not edit; regenerate with python -m "
            "conmech.symbolic emit.")
    first = f"!> {name}: {d.kind} system generated by conmech.symbolic from"
    src_name = comment_text(source, 80)
    if len(first) + len(src_name) + 2 <= 100:
        header = [f"{first} {src_name}."] + comment_lines(rest)
    else:
        header = [first] + comment_lines(f"{src_name}. {rest}")
    if d.kind == "ode":
        header += [f"!! Use: new_{name}() is an ode_system with the exact Jacobian (ode_solve,",
                   "!! integrate_stm and conmech's stability routines)."]
    elif d.kind == "generalized":
        header += [f"!! Use: new_{name}() is an ode_system (y = [q, v]) with the exact "
                   "Jacobian;", f"!! new_{name}_mech() a generalized_system for "
                   "generalized_solve."]
    else:
        header += [f"!! Use: new_{name}() is a constrained_system for constrained_solve."]
    lines = header + [f"module {module}", "    use conmech, only: @", "    implicit none",
                      "    private", ""]
    body, helpers = [], []
    if d.kind == "ode":
        lines += [f"    public :: {name}, new_{name}",
                  f"    integer, parameter, public :: {name}_n = {n}   !! state dimension",
                  "", "    !> y' = f(t, y) with the exact Jacobian df/dy.",
                  f"    type, extends(ode_system) :: {name}"]
        lines += _components(d, comp)
        lines += ["    contains", f"        procedure :: rhs => {name}_rhs",
                  f"        procedure :: jacobian => {name}_jacobian",
                  f"        procedure :: has_jacobian => {name}_has_jacobian",
                  f"        procedure :: jacobian_product => {name}_jacobian_product",
                  f"        procedure :: rhs_jacobian_product => {name}_rhs_jacobian_product",
                  f"        procedure :: has_jacobian_product => {name}_has_jacobian_product"]
        pr = em.printer()
        tbind, tprocs, _ = emitted_taylor(name, d, pr.names)
        lines += tbind + [f"    end type {name}", ""]
        # the type-bound taylor_jet calls one private helper per kind (system, variational)
        helpers = [f"{name}_taylor{k}" for k in (0, 1)] if tprocs else []
        body += _ctor(name, name, [], d, comp)
        body += em.proc("ode", name, f"{name}_rhs", ["t", "y", "dydt"],
                        [_decl("t"), _decl("y", [":"]), _decl("dydt", [":"], "out")], pr,
                        [("dydt", d.f, False)], "dydt = f(t, y).")
        body += em.proc("ode", name, f"{name}_jacobian", ["t", "y", "dfdy"],
                        [_decl("t"), _decl("y", [":"]), _decl("dfdy", [":", ":"], "out")],
                        pr, [("dfdy", d.jac, True)], "dfdy = df/dy (exact, from sympy).")
        body += _logical_true(name, f"{name}_has_jacobian", "The Jacobian is exact.")
        body += _ode_products(name, pr, d)
        body += tprocs
    elif d.kind == "generalized":
        mech = f"{name}_mech"
        lines += [f"    public :: {name}, {mech}", f"    public :: new_{name}, new_{mech}",
                  f"    integer, parameter, public :: {name}_n = {n}   !! coordinates",
                  f"    integer, parameter, public :: {name}_ny = {2 * n}   !! y = [q, v]",
                  "", "    !> M(t, q) q'' = Q(t, q, q') (for generalized_solve).",
                  f"    type, extends(generalized_system) :: {mech}"]
        lines += _components(d, comp)
        lines += ["    contains", f"        procedure :: mass => {mech}_mass",
                  f"        procedure :: forces => {mech}_forces"]
        if d.energy is not None:
            lines += [f"        procedure :: energy => {mech}_energy",
                      f"        procedure :: has_energy => {mech}_has_energy"]
        lines += [f"    end type {mech}", "",
                  "    !> First-order form y = [q, v], y' = [v, M^-1 Q], exact Jacobian.",
                  f"    type, extends(ode_system) :: {name}"]
        lines += _components(d, comp)
        lines += ["    contains", f"        procedure :: rhs => {name}_rhs",
                  f"        procedure :: jacobian => {name}_jacobian",
                  f"        procedure :: has_jacobian => {name}_has_jacobian"]
        if d.energy is not None:
            lines += [f"        procedure :: energy => {name}_energy"]
        lines += [f"    end type {name}", ""]
        pr = em.printer()
        pry = em.printer(state_in_y=True)
        body += _ctor(mech, mech, [f"s%ndof = {n}"], d, comp)
        body += _ctor(name, name, [], d, comp)
        qdecl = [_decl("t"), _decl("q", [":"])]
        qvdecl = qdecl + [_decl("v", [":"])]
        body += _mass_forces_energy(em, "g", mech, qdecl, pr, d, "The energy (Jacobi integral).")
        body += _gen_rhs(em, name, pry, d)
        body += _gen_jac(em, name, pry, d)
        body += _logical_true(name, f"{name}_has_jacobian", "The Jacobian is exact.")
        if d.energy is not None:
            body += em.proc("g", name, f"{name}_energy", ["t", "y"],
                            [_decl("t"), _decl("y", [":"])], pry, [],
                            "The energy at y = [q, v].", result=("e", d.energy))
    else:
        lines += [f"    public :: {name}, new_{name}",
                  f"    integer, parameter, public :: {name}_n = {n}   !! coordinates",
                  f"    integer, parameter, public :: {name}_n_hol = {d.n_hol}",
                  f"    integer, parameter, public :: {name}_n_nh = {d.n_nh}", "",
                  "    !> M q'' = Q + G^T lambda_h + A^T lambda_n with the constraints.",
                  f"    type, extends(constrained_system) :: {name}"]
        lines += _components(d, comp)
        procs = ["mass", "forces"]
        if d.energy is not None:
            procs += ["energy", "has_energy"]
        if d.n_hol:
            procs += ["phi", "phi_jac", "phi_t", "phi_gamma"]
        if d.n_nh:
            procs += ["nh_matrix", "nh_gamma"]
        lines += ["    contains"] + [f"        procedure :: {p} => {name}_{p}" for p in procs]
        lines += [f"    end type {name}", ""]
        pr = em.printer()
        ctor = [f"s%n = {n}", f"s%n_hol = {d.n_hol}", f"s%n_nh = {d.n_nh}",
                f"s%rheonomic = {'.true.' if d.rheonomic else '.false.'}"]
        body += _ctor(name, name, ctor, d, comp)
        qdecl = [_decl("t"), _decl("q", [":"])]
        qvdecl = qdecl + [_decl("v", [":"])]
        body += _mass_forces_energy(em, "c", name, qdecl, pr, d, "The energy.")
        if d.n_hol:
            body += em.proc("c", name, f"{name}_phi", ["t", "q", "c"],
                            qdecl + [_decl("c", [":"], "out")], pr, [("c", d.phi, False)],
                            "Holonomic constraints phi(t, q).")
            body += em.proc("c", name, f"{name}_phi_jac", ["t", "q", "g"],
                            qdecl + [_decl("g", [":", ":"], "out")], pr, [("g", d.G, True)],
                            "G = d phi/d q.")
            body += em.proc("c", name, f"{name}_phi_t", ["t", "q", "pt"],
                            qdecl + [_decl("pt", [":"], "out")], pr,
                            [("pt", d.phi_t, False)], "d phi/d t.")
            body += em.proc("c", name, f"{name}_phi_gamma", ["t", "q", "v", "gam"],
                            qvdecl + [_decl("gam", [":"], "out")], pr,
                            [("gam", d.gamma_h, False)], "gamma_h = -d/dt [G v + phi_t].")
        if d.n_nh:
            body += em.proc("c", name, f"{name}_nh_matrix", ["t", "q", "a", "b"],
                            qdecl + [_decl("a", [":", ":"], "out"), _decl("b", [":"], "out")],
                            pr, [("a", d.A, True), ("b", d.b, False)],
                            "Pfaffian constraints A(t, q) v + b(t, q) = 0.")
            body += em.proc("c", name, f"{name}_nh_gamma", ["t", "q", "v", "gam"],
                            qvdecl + [_decl("gam", [":"], "out")], pr,
                            [("gam", d.gamma_n, False)], "gamma_n = -d/dt [A v + b].")
    src = lines + ["contains", ""] + body + [f"end module {module}", ""]
    code = "\n".join(_code(ln) for ln in src)
    used = [nm for nm in _FROM_CONMECH
            if re.search(rf"(?<![%\w]){nm}(?!\w)", code, re.IGNORECASE)]
    src = [f"    use conmech, only: {', '.join(used)}" if ln == "    use conmech, only: @"
           else ln for ln in src]
    for ln in src:
        if len(ln) > 100:
            raise RuntimeError(f"emit: generated line longer than 100 characters: {ln!r}")
    text = "\n".join(src)
    # the procedures are the type-bound ones and the constructors; no C binding at all
    procs = [ln.split("=>")[1].strip() for ln in src if "procedure ::" in ln and "=>" in ln]
    procs += [ln.split("function ")[1].split("(")[0] for ln in src
              if ln.startswith("    function new_")]
    procs += helpers
    check_source(text, sorted(set(procs)), c_names=[], max_line=100)
    # the module's name is a global name: no entity inside may take it
    inner = "\n".join(_code(ln) for ln in src[1:-2] if not ln.startswith("module "))
    if re.search(rf"(?<![%\w]){re.escape(module)}(?!\w)", inner, re.IGNORECASE):
        raise ValueError(f"module name '{module}' is also a name inside the module (a "
                         "procedure, constant or component): choose another")
    return text


def _ctor(tname, fname, sets, d, comp):
    """Constructor function: dimensions and the default parameter values, assigned
    explicitly (gfortran does not always default-initialise a function result)."""
    lines = [f"    !> A {tname} with its dimensions set and the default parameters.",
             f"    function new_{fname}() result(s)", f"{_IND}type({tname}) :: s"]
    lines += [f"{_IND}{s}" for s in sets]
    lines += [f"{_IND}s%{pn} = {_lit(pv)}" for pn, pv in zip(comp, d.param_values)]
    lines += [f"    end function new_{fname}", ""]
    return lines


def _ode_products(name, pr, d):
    """jacobian_product (jx = J x) and rhs_jacobian_product (f and J x, one common-
    subexpression elimination over f and J's variable entries) of an ode type: only the
    structurally nonzero entries of J enter, constant ones folded into the products."""
    rows, var = product_terms(d.jac, pr)
    ent = [f"jv{k + 1}" for k in range(len(var))]
    out = []
    for proc, with_f in ((f"{name}_jacobian_product", False),
                         (f"{name}_rhs_jacobian_product", True)):
        targets = ([f"dydt({i + 1})" for i in range(d.n)] if with_f else []) + ent
        exprs = (list(d.f) if with_f else []) + var
        temps, lines = assignments(targets, exprs, pr, _IND) if exprs else ([], [])
        temps = temps + ent
        args = ["t", "n", "k", "y", "dydt", "x", "jx"] if with_f else ["t", "n", "k", "y",
                                                                       "x", "jx"]
        doc = ("f(t, y) and jx = J(t, y) x at once (one elimination over both)." if with_f
               else "jx = J(t, y) x for an n x k block x (no J formed).")
        out += [f"    !> {doc}", f"    subroutine {proc}(self, {', '.join(args)})",
                f"{_IND}class({name}), intent(in) :: self", _decl("t"),
                f"{_IND}integer, intent(in) :: n, k", _decl("y", ["n"]), _decl("x", ["n", "k"])]
        if with_f:
            out.append(_decl("dydt", ["n"], "out"))
        out += [_decl("jx", ["n", "k"], "out"), f"{_IND}integer :: c"]
        out += [f"{_IND}real(dp) :: " + ", ".join(temps[i:i + 10])
                for i in range(0, len(temps), 10)]
        out += lines + [f"{_IND}do c = 1, k"]
        out += product_lines(rows, ent, "x", "jx", "c", _IND + "    ")
        out += [f"{_IND}end do", f"    end subroutine {proc}", ""]
    out += _logical_true(name, f"{name}_has_jacobian_product",
                         "The Jacobian product is structure-aware (integrate_stm uses it).")
    return out


def _mass_solve(n, nrhs, rhs_name):
    """Statements: Cholesky of mm (conmech's mass_cholesky), then dpotrs on rhs_name;
    NaN on failure (from its bits: no IEEE module, whose use would save and restore the
    floating-point environment on every call)."""
    return [f"{_IND}call mass_cholesky(mm, info)",
            f"{_IND}if (info /= CM_SUCCESS) then",
            f"{_IND}    {rhs_name} = {quiet_nan()}",
            f"{_IND}else",
            f"{_IND}    call dpotrs('U', {n}, {nrhs}, mm, {n}, {rhs_name}, {n}, info)",
            f"{_IND}end if"]


def _mass_forces_energy(em, kind, owner, qdecl, pr, d, energy_doc):
    """The type-bound mass matrix, forces and (when defined) energy procedures of the
    mechanical type `owner` (kind "g": generalized, "c": constrained)."""
    qvdecl = qdecl + [_decl("v", [":"])]
    out = em.proc(kind, owner, f"{owner}_mass", ["t", "q", "mm"],
                  qdecl + [_decl("mm", [":", ":"], "out")], pr, [("mm", d.M, True)],
                  "mm = M(t, q).")
    out += em.proc(kind, owner, f"{owner}_forces", ["t", "q", "v", "f"],
                   qvdecl + [_decl("f", [":"], "out")], pr, [("f", d.Q, False)],
                   "f = Q(t, q, v).")
    if d.energy is not None:
        out += em.proc(kind, owner, f"{owner}_energy", ["t", "q", "v"], qvdecl, pr, [],
                       energy_doc, result=("e", d.energy))
        out += _logical_true(owner, f"{owner}_has_energy", "The energy is defined.")
    return out


def _gen_rhs(em, name, pry, d):
    n = d.n
    if getattr(d, "aba", None) is not None:
        # a planar tree (conmech.symbolic.planar_tree): the articulated-body algorithm
        decl, lines = aba_lines(pry, d, "a", _IND)
        return (["    !> y' = [v, a], a = M^-1 Q by the articulated-body algorithm (O(n), no "
                 "matrix;", "    !! non-finite if M is not positive definite).",
                 f"    subroutine {name}_rhs(self, t, y, dydt)",
                 f"{_IND}class({name}), intent(in) :: self",
                 _decl("t"), _decl("y", [":"]), _decl("dydt", [":"], "out"),
                 f"{_IND}real(dp) :: a({n})"]
                + decl + lines
                + [f"{_IND}dydt(1:{n}) = y({n + 1}:{2 * n})",
                   f"{_IND}dydt({n + 1}:{2 * n}) = a", f"    end subroutine {name}_rhs", ""])
    decl, lines = em.body(pry, [("mm", d.M, True), ("a", d.Q, False)])
    return (["    !> y' = [v, a], M a = Q (Cholesky; NaN if M is not positive definite).",
             f"    subroutine {name}_rhs(self, t, y, dydt)",
             f"{_IND}use conmech_lapack, only: dpotrs",
             f"{_IND}class({name}), intent(in) :: self",
             _decl("t"), _decl("y", [":"]), _decl("dydt", [":"], "out"),
             f"{_IND}real(dp) :: mm({n}, {n}), a({n})", f"{_IND}integer :: info"]
            + decl + lines + _mass_solve(n, 1, "a")
            + [f"{_IND}dydt(1:{n}) = y({n + 1}:{2 * n})", f"{_IND}dydt({n + 1}:{2 * n}) = a",
               f"    end subroutine {name}_rhs", ""])


def _gen_jac(em, name, pry, d):
    n = d.n
    decl1, lines1 = em.body(pry, [("mm", d.M, True), ("a", d.Q, False)], prefix="w")
    decl2, lines2 = em.body(pry, [("r", d.R, True)], prefix="u")
    lines = ["    !> Exact Jacobian: d a/d[q, v] = M^-1 R, R = [dQ/dq - d(M a)/dq, dQ/dv].",
             f"    subroutine {name}_jacobian(self, t, y, dfdy)",
             f"{_IND}use conmech_lapack, only: dpotrs",
             f"{_IND}class({name}), intent(in) :: self",
             _decl("t"), _decl("y", [":"]), _decl("dfdy", [":", ":"], "out"),
             f"{_IND}real(dp) :: mm({n}, {n}), a({n}), r({n}, {2 * n})",
             f"{_IND}integer :: info, i"]
    lines += decl1 + decl2 + lines1
    lines += [f"{_IND}call mass_cholesky(mm, info)",
              f"{_IND}if (info /= CM_SUCCESS) then",
              f"{_IND}    dfdy = {quiet_nan()}",
              f"{_IND}    return",
              f"{_IND}end if",
              f"{_IND}call dpotrs('U', {n}, 1, mm, {n}, a, {n}, info)"]
    lines += lines2
    lines += [f"{_IND}call dpotrs('U', {n}, {2 * n}, mm, {n}, r, {n}, info)",
              f"{_IND}dfdy = 0.0_dp",
              f"{_IND}do i = 1, {n}",
              f"{_IND}    dfdy(i, {n} + i) = 1.0_dp",
              f"{_IND}end do",
              f"{_IND}dfdy({n + 1}:{2 * n}, :) = r",
              f"    end subroutine {name}_jacobian", ""]
    return lines
