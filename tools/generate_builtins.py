#!/usr/bin/env python3
"""Generate conmech's built-in systems from their models (tools/builtin_models/).

    python tools/generate_builtins.py            # (re)write the generated files
    python tools/generate_builtins.py --check    # exit 1 if a committed file is stale
    python tools/generate_builtins.py --out DIR  # write the tree below DIR instead

For each model that is not hand-written, conmech.symbolic derives the equations (M, Q,
the Jacobian of the accelerations, the energy, the constraints and their gamma terms, or
f and df/dy) and its Fortran type is written: per kind one module with the types (which
extend ode_system, generalized_system or constrained_system) and the interfaces of their
procedures, and one submodule with the procedures' bodies, every expression after one
common-subexpression elimination per procedure. From every model, hand-written ones
included, the registries are written: the parameter table (conmech_systems_params: counts,
names, defaults), make_system and system_dimension (conmech_systems), make_generalized,
make_constrained and the default initial states (conmech_systems_mech), the modules that
gather the types (conmech_systems_basic, _generalized, _constrained), and the Python side
(python/conmech/_core/builtin_table.py: parameters, validity, state names;
python/conmech/mechanics/systems.py: one factory per system). The output is deterministic;
python/tests/test_builtin_systems.py regenerates it into a temporary folder and compares
byte for byte.
"""
import argparse
import difflib
import json
import sys
import textwrap
from pathlib import Path

import sympy as sp

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))

import builtin_models as bm  # noqa: E402
from conmech.symbolic.codegen import FortranPrinter, assignments, trig_split  # noqa: E402
from conmech.symbolic.derive import (derive_constrained, derive_lagrangian,  # noqa: E402
                                     derive_ode)

GENERATOR = "tools/generate_builtins.py"
IND = "        "
WIDTH = 96


# ------------------------------------------------------------------------------ helpers

def lit(x):
    """A real(dp) literal (shortest repr)."""
    s = repr(float(x))
    if s in ("inf", "-inf", "nan"):
        raise ValueError(f"non-finite value {x}")
    if "." not in s and "e" not in s:
        s += ".0"
    return s + "_dp"


def wrap_comment(text, prefix, width=WIDTH):
    """Paragraphs of `text` as comment lines; lines indented by 4 or more (formulas) and
    blank lines are kept as they are."""
    out = []
    para = []

    def flush():
        if para:
            out.extend(prefix + s for s in textwrap.wrap(" ".join(para), width - len(prefix),
                                                         break_on_hyphens=False,
                                                         break_long_words=False))
            para.clear()
    for line in text.splitlines():
        if not line.strip():
            flush()
            out.append(prefix.rstrip())
        elif line.startswith("    "):
            flush()
            out.append(prefix + line)
        else:
            para.append(line.strip())
    flush()
    return out


def wrap_statement(line, indent, width=WIDTH):
    """A long Fortran statement split with continuation lines."""
    if len(indent) + len(line) <= width:
        return [indent + line]
    out, rest, first = [], line, True
    while rest:
        room = width - len(indent) - (2 if first else 8)
        if len(rest) <= room:
            out.append((indent if first else indent + "    & ") + rest)
            break
        cut = room
        for ch in (", ", " + ", " - ", "*", "("):
            k = rest.rfind(ch, room // 2, room)
            if k > 0:
                cut = k + (1 if ch == ", " else 0)
                break
        out.append((indent if first else indent + "    & ") + rest[:cut].rstrip() + " &")
        rest = rest[cut:].lstrip()
        first = False
    return out


def decl_lines(kind, names, indent=IND):
    """`real(dp) :: a, b, ...` in lines of at most WIDTH characters."""
    out, cur = [], []
    for n in names:
        trial = f"{indent}{kind} :: " + ", ".join(cur + [n])
        if cur and len(trial) > WIDTH:
            out.append(f"{indent}{kind} :: " + ", ".join(cur))
            cur = [n]
        else:
            cur.append(n)
    if cur:
        out.append(f"{indent}{kind} :: " + ", ".join(cur))
    return out


class Block:
    """Statements assigning sympy expressions to Fortran targets with one common-
    subexpression elimination (conmech.symbolic.codegen.assignments); sines and cosines
    of sums by angle addition (trig_split) when that needs fewer evaluations."""

    def __init__(self, printer, prefix="w"):
        self.pr = printer
        self.prefix = prefix
        self.targets, self.exprs, self.zero = [], [], []

    def matrix(self, name, mat):
        rows, cols = mat.shape
        nz = 0
        for j in range(cols):
            for i in range(rows):
                if mat[i, j] != 0:
                    self.targets.append(f"{name}({i + 1}, {j + 1})")
                    self.exprs.append(mat[i, j])
                    nz += 1
        if nz < rows*cols:
            self.zero.append(f"{name} = 0.0_dp")
        return self

    def vector(self, name, vec):
        vals = list(vec)
        if all(e == 0 for e in vals):
            self.zero.append(f"{name} = 0.0_dp")
            return self
        for i, e in enumerate(vals):
            self.targets.append(f"{name}({i + 1})")
            self.exprs.append(e)
        return self

    def scalar(self, name, expr):
        self.targets.append(name)
        self.exprs.append(expr)
        return self

    def lines(self):
        """(declarations, statements)."""
        exprs = [sp.sympify(e) for e in self.exprs]
        exprs, tdefs = trig_split(exprs)
        # angle addition defines sin and cos of every sum: keep those the outputs use
        used = set().union(*(e.free_symbols for e in exprs)) if exprs else set()
        for s_, e in reversed(tdefs):
            if s_ in used:
                used |= e.free_symbols
        tdefs = [(s_, e) for s_, e in tdefs if s_ in used]
        saved = self.pr.names
        tnames = {s: f"tg{k + 1}" for k, (s, _) in enumerate(tdefs)}
        self.pr.names = {**saved, **tnames}
        try:
            tlines = []
            for s, e in tdefs:
                tlines += wrap_statement(f"{tnames[s]} = {self.pr._print(e)}", IND)
            temps, body = assignments(self.targets, exprs, self.pr, IND, prefix=self.prefix)
        finally:
            self.pr.names = saved
        temps = list(tnames.values()) + temps
        decl = decl_lines("real(dp)", temps) if temps else []
        return decl, [IND + z for z in self.zero] + tlines + body


# ------------------------------------------------------------------------------ derivation

def derive(model):
    """The conmech.symbolic Derived record of a generated model."""
    params = {p.symbol: p.default for p in model.params}
    if model.kind == "ode":
        return derive_ode(model.f, model.y, params=params)
    if model.kind == "generalized":
        return derive_lagrangian(model.T - model.U, model.q, params=params,
                                 forces=model.forces, velocities=model.v)
    return derive_constrained(model.T, model.U, model.q, holonomic=model.holonomic,
                              nonholonomic=model.nonholonomic, params=params,
                              velocities=model.v)


def component(p):
    return p.component.lower()


def printer(model, d, state="qv"):
    """Printer names: t, the parameters as components of self, the state as q(i), v(i),
    a(i) (state "qv") or y(i) (state "y": an ode, or the ode form of a mechanical one)."""
    names = {d.t: "t"}
    n = d.n
    for i, s in enumerate(d.coords):
        names[s] = f"y({i + 1})" if state == "y" else f"q({i + 1})"
    for i, s in enumerate(d.speeds):
        names[s] = f"y({n + i + 1})" if state == "y" else f"v({i + 1})"
    for i, s in enumerate(d.accels):
        names[s] = f"a({i + 1})"
    for s, p in zip(d.params, model.params):
        names[s] = f"self%{component(p)}"
    return FortranPrinter(names)


def model_symbols(model, d):
    """{model's symbol: Derived's symbol} (the derivation renames every symbol to a real
    Dummy of the same name; the order is the model's)."""
    sub = {p.symbol: s for p, s in zip(model.params, d.params)}
    if model.kind == "ode":
        sub.update(zip(model.y, d.coords))
    else:
        sub.update(zip(model.q, d.coords))
        sub.update(zip(model.v, d.speeds))
    sub[sp.Symbol("t", real=True)] = d.t
    return sub


# ------------------------------------------------------------------------------ Fortran
#
# Each kind of system is one module (conmech_systems_basic, _generalized, _constrained)
# holding the types and the interfaces of their procedures; each system's procedures are a
# submodule of it (src/systems/builtin/conmech_builtin_NAME.f90): the expressions only, the
# interfaces written once in the module.

KINDS = {"ode": ("conmech_systems_basic", "conmech_ode_system", "ode_system",
                 "The built-in first-order systems y' = f(t, y), with exact Jacobians."),
         "generalized": ("conmech_systems_generalized", "conmech_generalized",
                         "generalized_system",
                         "The built-in systems in generalized coordinates, M(t, q) q'' = "
                         "Q(t, q, q'), with the exact Jacobian of the accelerations."),
         "constrained": ("conmech_systems_constrained", "conmech_constrained_system",
                         "constrained_system",
                         "The built-in systems in excessive coordinates with holonomic "
                         "constraints phi(t, q) = 0 and Pfaffian ones A(t, q) q' + b(t, q) = 0 "
                         "(conmech_constrained_system's conventions), with exact constraint "
                         "Jacobians and gamma terms.")}


def system_comment(model):
    """The comment that opens a system's procedures in its kind's equations submodule: the
    model's docstring and its file."""
    out = [f"    ! {'-' * 68} {model.name}"]
    for para in model.doc.split("\n\n"):
        out += wrap_comment(para, "    ! ") + ["    !"]
    return out + [f"    ! (model: {model.source})", ""]


class Procedure:
    """A type-bound procedure of a generated type: its binding, Fortran name, dummy
    arguments and their declarations (the interface, in the kind's module), the body
    (the submodule) and a one-line documentation."""

    def __init__(self, binding, tname, args, decls, doc, block, result=None, pure=False):
        self.binding = binding
        self.name = f"{tname}_{binding}"
        self.tname = tname
        self.args, self.decls, self.doc = args, decls, doc
        self.block, self.result, self.pure = block, result, pure

    def interface(self):
        head = ", ".join(["self"] + self.args)
        ind = IND + "    "
        if self.result:
            kw = "pure module function" if self.pure else "module function"
            out = [f"        {kw} {self.name}({head}) result({self.result})"]
        else:
            out = [f"        module subroutine {self.name}({head})"]
        out.append(f"{ind}class({self.tname}), intent(in) :: self")
        out += [ind + d for d in self.decls]
        if self.result:
            out.append(f"{ind}real(dp) :: {self.result}")
        out.append(f"        end {'function' if self.result else 'subroutine'} {self.name}")
        return out

    def body(self):
        decl, lines = self.block.lines()
        return ([f"    module procedure {self.name}"] + decl + lines
                + [f"    end procedure {self.name}", ""])


def _sub(obj, sub):
    if isinstance(obj, sp.MatrixBase):
        return obj.xreplace(sub)
    return sp.sympify(obj).xreplace(sub)


class System:
    """A generated model with its derivation: the procedures, the type-bound bindings
    (binding, procedure suffix; "has": the type's own true-valued query) and the
    statements that set the dimensions of a new object `s`."""

    def __init__(self, model):
        self.model = model
        self.d = derive(model)
        emit = {"ode": self._ode, "generalized": self._generalized,
                "constrained": self._constrained}[model.kind]
        self.procs, self.bindings, self.dims = emit(model, self.d)

    @staticmethod
    def _ode(model, d):
        t = model.type_name
        pr = printer(model, d, state="y")
        sub = model_symbols(model, d)
        procs = [Procedure("rhs", t, ["t", "y", "dydt"], ["real(dp), intent(in) :: t, y(:)",
                                                          "real(dp), intent(out) :: dydt(:)"],
                           "dydt = f(t, y).", Block(pr).vector("dydt", d.f)),
                 Procedure("jacobian", t, ["t", "y", "dfdy"],
                           ["real(dp), intent(in) :: t, y(:)",
                            "real(dp), intent(out) :: dfdy(:, :)"],
                           "dfdy = df/dy (exact).", Block(pr).matrix("dfdy", d.jac))]
        bindings = [("rhs", "rhs"), ("jacobian", "jacobian")]
        if model.energy is not None:
            e = _sub(model.energy, sub)
            if d.t in e.free_symbols:
                raise ValueError(f"{model.name}: the energy of a first-order system may not "
                                 "depend on t")
            procs.append(Procedure("energy", t, ["y"], ["real(dp), intent(in) :: y(:)"],
                                   "The conserved energy at y.", Block(pr).scalar("e", e),
                                   result="e", pure=True))
            bindings.append(("energy", "energy"))
        return procs, bindings, []

    @staticmethod
    def _generalized(model, d):
        t = model.type_name
        pr = printer(model, d)
        tqv = "real(dp), intent(in) :: t, q(:), v(:)"
        procs = [Procedure("mass_forces", t, ["t", "q", "v", "mm", "f"],
                           [tqv, "real(dp), intent(out) :: mm(:, :), f(:)"],
                           "mm = M(t, q) and f = Q(t, q, v) (one evaluation).",
                           Block(pr).matrix("mm", d.M).vector("f", d.Q))]
        bindings = [("mass_forces", "mass_forces")]
        procs.append(Procedure("forces_jacobian", t, ["t", "q", "v", "a", "r"],
                               ["real(dp), intent(in) :: t, q(:), v(:), a(:)",
                                "real(dp), intent(out) :: r(:, :)"],
                               "r = [dQ/dq - d(M a)/dq, dQ/dv] at the accelerations a.",
                               Block(pr).matrix("r", d.R)))
        bindings.append(("forces_jacobian", "forces_jacobian"))
        if model.energy:
            procs.append(Procedure("energy", t, ["t", "q", "v"], [tqv],
                                   "The energy (the Jacobi integral).",
                                   Block(pr).scalar("e", d.energy), result="e"))
            bindings.append(("energy", "energy"))
        return procs, bindings, [f"s%ndof = {d.n}"]

    @staticmethod
    def _constrained(model, d):
        t = model.type_name
        pr = printer(model, d)
        tq = "real(dp), intent(in) :: t, q(:)"
        tqv = "real(dp), intent(in) :: t, q(:), v(:)"
        n = d.n
        diagonal = all(d.M[i, j] == 0 for i in range(n) for j in range(n) if i != j)
        constant = not (d.M.free_symbols & (set(d.coords) | {d.t}))
        procs, bindings = [], []
        if diagonal:
            procs.append(Procedure("mass_diagonal", t, ["t", "q", "d"],
                                   [tq, "real(dp), intent(out) :: d(:)"],
                                   "d = the diagonal of M(t, q) (M is diagonal).",
                                   Block(pr).vector("d", [d.M[i, i] for i in range(n)])))
            bindings.append(("mass_diagonal", "mass_diagonal"))
        else:
            procs.append(Procedure("mass", t, ["t", "q", "mm"],
                                   [tq, "real(dp), intent(out) :: mm(:, :)"], "mm = M(t, q).",
                                   Block(pr).matrix("mm", d.M)))
            bindings.append(("mass", "mass"))
        procs.append(Procedure("forces", t, ["t", "q", "v", "f"],
                               [tqv, "real(dp), intent(out) :: f(:)"], "f = Q(t, q, v).",
                               Block(pr).vector("f", d.Q)))
        bindings.append(("forces", "forces"))
        if model.energy:
            procs.append(Procedure("energy", t, ["t", "q", "v"], [tqv], "The energy T + U.",
                                   Block(pr).scalar("e", d.energy), result="e"))
            bindings.append(("energy", "energy"))
            if not diagonal:
                bindings.append(("has_energy", "has"))
        if d.n_hol:
            procs += [Procedure("phi", t, ["t", "q", "c"],
                                [tq, "real(dp), intent(out) :: c(:)"],
                                "The holonomic constraints c = phi(t, q).",
                                Block(pr).vector("c", d.phi)),
                      Procedure("phi_jac", t, ["t", "q", "g"],
                                [tq, "real(dp), intent(out) :: g(:, :)"], "g = G = d phi/d q.",
                                Block(pr).matrix("g", d.G))]
            bindings += [("phi", "phi"), ("phi_jac", "phi_jac")]
            if d.rheonomic:
                procs.append(Procedure("phi_t", t, ["t", "q", "pt"],
                                       [tq, "real(dp), intent(out) :: pt(:)"],
                                       "pt = d phi/d t.", Block(pr).vector("pt", d.phi_t)))
                bindings.append(("phi_t", "phi_t"))
            procs.append(Procedure("phi_gamma", t, ["t", "q", "v", "gam"],
                                   [tqv, "real(dp), intent(out) :: gam(:)"],
                                   "gam = gamma_h = -d/dt [G v + phi_t] at fixed v.",
                                   Block(pr).vector("gam", d.gamma_h)))
            bindings.append(("phi_gamma", "phi_gamma"))
        if d.n_nh:
            procs += [Procedure("nh_matrix", t, ["t", "q", "a", "b"],
                                [tq, "real(dp), intent(out) :: a(:, :), b(:)"],
                                "The Pfaffian constraints A(t, q) v + b(t, q) = 0.",
                                Block(pr).matrix("a", d.A).vector("b", d.b)),
                      Procedure("nh_gamma", t, ["t", "q", "v", "gam"],
                                [tqv, "real(dp), intent(out) :: gam(:)"],
                                "gam = gamma_n = -d/dt [A v + b] at fixed v.",
                                Block(pr).vector("gam", d.gamma_n))]
            bindings += [("nh_matrix", "nh_matrix"), ("nh_gamma", "nh_gamma")]
        dims = [f"s%n = {n}"]
        if d.n_hol:
            dims.append(f"s%n_hol = {d.n_hol}")
        if d.n_nh:
            dims.append(f"s%n_nh = {d.n_nh}")
        if d.rheonomic:
            dims.append("s%rheonomic = .true.")
        if diagonal:
            dims.append("s%diagonal_mass = .true.")
        if constant:
            dims.append("s%constant_mass = .true.")
        return procs, bindings, dims

    @property
    def base(self):
        """The type the system's type extends: its kind's intermediate type that says
        what it has (see SHARED), or conmech's base type with its own queries."""
        m = self.model
        if m.kind == "ode":
            return "ode_exact_jacobian"
        if m.kind == "generalized":
            return "generalized_with_energy" if m.energy else "generalized_by_mass_forces"
        if "s%diagonal_mass = .true." in self.dims:
            return "constrained_with_energy" if m.energy else "constrained_diagonal_mass"
        return "constrained_system"

    def type_lines(self):
        m = self.model
        t = m.type_name
        base = self.base
        doc = wrap_comment(m.summary, "    !! ")
        doc[0] = "    !> " + doc[0][7:]
        out = doc + [f"    type, extends({base}) :: {t}"]
        for p in m.params:
            out.append(f"        real(dp) :: {component(p)} = {lit(p.default)}   !! {p.doc}")
        out.append("    contains")
        out += [f"        procedure :: {b} => {t}_{impl}" for b, impl in self.bindings]
        return out + [f"    end type {t}", ""]

    def bodies(self):
        out = system_comment(self.model)
        for p in self.procs:
            out += p.body()
        return out


def pack(statements, indent=IND, width=WIDTH):
    """Short statements joined by '; ' into lines of at most `width` characters."""
    out, cur = [], ""
    for s in statements:
        trial = f"{cur}; {s}" if cur else s
        if cur and len(indent) + len(trial) > width:
            out.append(indent + cur)
            cur = s
        else:
            cur = trial
    if cur:
        out.append(indent + cur)
    return out


# The intermediate types of the generated ones (emitted as they are): what every generated
# system of a kind shares is written once. Per kind: (type definitions, procedures).
SHARED = {
    "ode": ("""\
    !> A first-order system with its exact Jacobian.
    type, abstract, extends(ode_system) :: ode_exact_jacobian
    contains
        procedure :: has_jacobian => ode_yes
    end type ode_exact_jacobian
""", """\
    logical function ode_yes(self)
        class(ode_exact_jacobian), intent(in) :: self
        ode_yes = .true.
    end function ode_yes
"""),
    "generalized": ("""\
    !> A generalized system whose M and Q come from one evaluation, `mass_forces` (which
    !! every extension overrides: the default `mass_forces` calls `mass` and `forces`),
    !! with the exact Jacobian of its accelerations (`forces_jacobian`).
    type, abstract, extends(generalized_system) :: generalized_by_mass_forces
    contains
        procedure :: mass => by_mass_forces_mass
        procedure :: forces => by_mass_forces_forces
        procedure :: has_forces_jacobian => generalized_yes
    end type generalized_by_mass_forces

    !> A generalized_by_mass_forces with its energy (the Jacobi integral, `energy`).
    type, abstract, extends(generalized_by_mass_forces) :: generalized_with_energy
    contains
        procedure :: has_energy => generalized_energy_yes
    end type generalized_with_energy
""", """\
    logical function generalized_yes(self)
        class(generalized_by_mass_forces), intent(in) :: self
        generalized_yes = .true.
    end function generalized_yes

    logical function generalized_energy_yes(self)
        class(generalized_with_energy), intent(in) :: self
        generalized_energy_yes = .true.
    end function generalized_energy_yes

    !> mm = M(t, q) from `mass_forces` (M does not depend on the velocities).
    subroutine by_mass_forces_mass(self, t, q, mm)
        class(generalized_by_mass_forces), intent(in) :: self
        real(dp), intent(in) :: t, q(:)
        real(dp), intent(out) :: mm(:, :)
        real(dp) :: v(size(q)), f(size(q))
        v = 0.0_dp
        call self%mass_forces(t, q, v, mm, f)
    end subroutine by_mass_forces_mass

    !> f = Q(t, q, v) from `mass_forces`.
    subroutine by_mass_forces_forces(self, t, q, v, f)
        class(generalized_by_mass_forces), intent(in) :: self
        real(dp), intent(in) :: t, q(:), v(:)
        real(dp), intent(out) :: f(:)
        real(dp) :: mm(size(q), size(q))
        call self%mass_forces(t, q, v, mm, f)
    end subroutine by_mass_forces_forces
"""),
    "constrained": ("""\
    !> A constrained system whose mass is diagonal, given by `mass_diagonal` (which every
    !! extension overrides: the default `mass_diagonal` calls `mass`).
    type, abstract, extends(constrained_system) :: constrained_diagonal_mass
    contains
        procedure :: mass => diagonal_mass_matrix
    end type constrained_diagonal_mass

    !> A constrained_diagonal_mass with its energy (`energy`).
    type, abstract, extends(constrained_diagonal_mass) :: constrained_with_energy
    contains
        procedure :: has_energy => constrained_yes
    end type constrained_with_energy
""", """\
    logical function constrained_yes(self)
        class(constrained_with_energy), intent(in) :: self
        constrained_yes = .true.
    end function constrained_yes

    !> mm = M(t, q), the diagonal matrix of `mass_diagonal`.
    subroutine diagonal_mass_matrix(self, t, q, mm)
        class(constrained_diagonal_mass), intent(in) :: self
        real(dp), intent(in) :: t, q(:)
        real(dp), intent(out) :: mm(:, :)
        real(dp) :: d(size(q))
        integer :: i
        call self%mass_diagonal(t, q, d)
        mm = 0.0_dp
        do i = 1, size(q)
            mm(i, i) = d(i)
        end do
    end subroutine diagonal_mass_matrix
"""),
}

# The intermediate types that hand-written systems of the kind extend as well.
SHARED_PUBLIC = {"constrained": ["constrained_diagonal_mass", "constrained_with_energy"]}


def check_lines(name, lines):
    for ln in lines:
        if len(ln) > 100:
            raise RuntimeError(f"{name}: generated line over 100 characters: {ln!r}")
    return "\n".join(lines)


def kind_module(kind, systems, extra=()):
    """The module of one kind of generated system: the types, the interfaces of their
    procedures (the bodies are its submodule, kind_submodule) and their true-valued
    queries. `extra`: hand-written models whose types the module also gives."""
    module, base_mod, base, doc = KINDS[kind]
    out = generated_header(doc + f" The procedures are the submodule {module}_equations, "
                           "generated from the models tools/builtin_models/NAME.py.")
    out += [f"module {module}", "    use conmech_kinds, only: dp", f"    use {base_mod}, only: {base}"]
    out += [f"    use {m.module}, only: {m.type_name}" for m in extra]
    out += ["    implicit none", "    private", ""]
    out += wrap_statement("public :: " + ", ".join(
        SHARED_PUBLIC.get(kind, []) + [s.model.type_name for s in systems]
        + [m.type_name for m in extra]), "    ")
    out.append("")
    shared = SHARED[kind]
    out += shared[0].splitlines() + [""]
    for s in systems:
        out += s.type_lines()
    out.append("    interface")
    for i, s in enumerate(systems):
        if i:
            out.append("")
        out += [f"        ! {s.model.name}"]
        for p in s.procs:
            out += p.interface()
    out += ["    end interface", "", "contains", ""]
    out += shared[1].splitlines() + [""]
    for s in systems:
        if any(impl == "has" for _, impl in s.bindings):
            t = s.model.type_name
            out += [f"    logical function {t}_has(self)",
                    f"{IND}class({t}), intent(in) :: self", f"{IND}{t}_has = .true.",
                    f"    end function {t}_has", ""]
    out += [f"end module {module}", ""]
    return check_lines(module, out)


EQUATIONS_DOC = {
    "ode": "The right-hand sides f(t, y) and Jacobians df/dy of the first-order built-ins "
           "(conmech_systems_basic), derived by conmech.symbolic from their models.",
    "generalized": "M, Q, R = [dQ/dq - d(M a)/dq, dQ/dv] and the Jacobi integral of each "
                   "built-in system in generalized coordinates (conmech_systems_generalized), "
                   "derived by conmech.symbolic from its Lagrangian; one common-subexpression "
                   "elimination per procedure, sines and cosines of sums by angle addition.",
    "constrained": "For each built-in system in excessive coordinates "
                   "(conmech_systems_constrained): its diagonal mass and forces from T and U, "
                   "its constraints with their Jacobians, phi_t and the terms gamma_h = "
                   "-d/dt [G v + phi_t], gamma_n = -d/dt [A v + b], derived by "
                   "conmech.symbolic.",
}


def kind_submodule(kind, systems):
    """The procedures of one kind's generated systems, each system's after its model's
    documentation."""
    module = KINDS[kind][0]
    out = generated_header(EQUATIONS_DOC[kind])
    out += [f"submodule ({module}) {module}_equations", "    implicit none", "", "contains", ""]
    for s in systems:
        out += s.bodies()
    out += [f"end submodule {module}_equations", ""]
    return check_lines(module + "_equations", out)


# ------------------------------------------------------------------------------ registries

def fstring(s):
    return '"' + s.replace('"', '""') + '"'


def grouped_cases(items, indent="        "):
    """`case ("a", "b")` blocks for [(name, [statement lines])], names with the same
    statements grouped (in the order of their first appearance)."""
    groups = {}
    for name, lines in items:
        groups.setdefault(tuple(lines), []).append(name)
    out = []
    for lines, names in groups.items():
        out += wrap_statement("case (" + ", ".join(fstring(n) for n in names) + ")", indent)
        out += [indent + "    " + ln for ln in lines]
    return out


def generated_header(text):
    lines = wrap_comment(text, "!! ")
    lines[0] = "!> " + lines[0][3:]
    return lines + [f"!! (Generated by {GENERATOR} from tools/builtin_models/: do not edit.)"]


def params_module(models):
    allm = [m for k in ("ode", "generalized", "constrained") for m in models[k]]
    out = generated_header(
        "The parameters of the built-in systems by name: how many each takes, their names "
        "in the documented order and their defaults (missing trailing parameters keep their "
        "defaults; more than the system has is an error in every registry: `make_system`, "
        "`make_generalized`, `make_constrained`, and so in the programs and the Python "
        "package). One table (`param_table`) holds the names and defaults of every system; "
        "the count, the names and the completed vector are read from it.")
    out += ["module conmech_systems_params", "    use conmech_kinds, only: dp",
            "    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT", "    implicit none",
            "    private",
            "    public :: builtin_param_count, builtin_param_names, builtin_params, "
            "check_param_count", "",
            "    !> The parameters of one built-in system.",
            "    type :: param_entry",
            "        logical :: known = .false.                  !! the name is a built-in",
            '        character(len=:), allocatable :: names      !! in order ("" if unknown)',
            "        real(dp), allocatable :: defaults(:)        !! one per parameter",
            "    end type param_entry", "", "contains", "",
            "    !> The table entry of the built-in `name` (not `known` if the name is unknown).",
            "    pure function param_table(name) result(e)",
            f"{IND}character(len=*), intent(in) :: name",
            f"{IND}type(param_entry) :: e", f"{IND}e%known = .true.",
            f"{IND}select case (trim(name))"]
    out += grouped_cases([(m.name, ["e%names = " + fstring(", ".join(p.name for p in m.params))]
                          + wrap_statement("e%defaults = [" + ", ".join(
                              lit(p.default) for p in m.params) + "]", ""))
                          for m in allm])
    out += [f"{IND}case default", f"{IND}    e%known = .false.", f'{IND}    e%names = ""',
            f"{IND}    allocate (e%defaults(0))", f"{IND}end select",
            "    end function param_table", "",
            "    !> Number of parameters of a built-in system (-1 if the name is unknown).",
            "    pure integer function builtin_param_count(name) result(np)",
            f"{IND}character(len=*), intent(in) :: name",
            f"{IND}type(param_entry) :: e", f"{IND}e = param_table(name)",
            f"{IND}np = merge(size(e%defaults), -1, e%known)",
            "    end function builtin_param_count", "",
            '    !> The parameters of a built-in system, named in order ("" if unknown).',
            "    pure function builtin_param_names(name) result(s)",
            f"{IND}character(len=*), intent(in) :: name",
            f"{IND}character(len=:), allocatable :: s", f"{IND}type(param_entry) :: e",
            f"{IND}e = param_table(name)", f"{IND}s = e%names",
            "    end function builtin_param_names", "",
            "    !> The whole parameter vector of the built-in `name`: the given leading values "
            "and", "    !! the defaults of the others (`params` itself if the name is unknown).",
            "    pure function builtin_params(name, params) result(p)",
            f"{IND}character(len=*), intent(in) :: name",
            f"{IND}real(dp), intent(in) :: params(:)",
            f"{IND}real(dp), allocatable :: p(:)", f"{IND}type(param_entry) :: e",
            f"{IND}integer :: k", f"{IND}e = param_table(name)",
            f"{IND}if (.not. e%known) then", f"{IND}    p = params", f"{IND}    return",
            f"{IND}end if", f"{IND}p = e%defaults", f"{IND}k = min(size(params), size(p))",
            f"{IND}p(1:k) = params(1:k)", "    end function builtin_params", "",
            "    !> info = CM_BAD_INPUT with a message naming the system and its parameters "
            "when more", "    !! parameters are given than the built-in `name` has (unknown "
            "names pass: the", "    !! registry reports them).",
            "    subroutine check_param_count(name, nparams, info, msg)",
            f"{IND}character(len=*), intent(in) :: name",
            f"{IND}integer, intent(in) :: nparams", f"{IND}integer, intent(out) :: info",
            f"{IND}character(len=:), allocatable, intent(out) :: msg",
            f"{IND}integer :: np", f"{IND}character(len=12) :: a, b",
            f"{IND}np = builtin_param_count(name)", f"{IND}info = CM_SUCCESS",
            f'{IND}msg = "success"', f"{IND}if (np < 0 .or. nparams <= np) return",
            f"{IND}write (a, '(i0)') nparams", f"{IND}write (b, '(i0)') np",
            f"{IND}info = CM_BAD_INPUT",
            f'{IND}msg = "bad input: "//trim(a)//" parameters given for the system \'"'
            '//trim(name)// &',
            f'{IND}      "\', which has "//trim(b)//" ("//builtin_param_names(name)//")"',
            "    end subroutine check_param_count", "", "end module conmech_systems_params", ""]
    return "\n".join(out)


def make_lines(m, arg):
    """Statements of a registry case that allocate the system `m` into `arg` from the whole
    parameter vector p: its type's structure constructor with the dimensions and the
    parameters by keyword, or the hand-written model's own `make` statement."""
    if not m.generated and m.make:
        return [m.make]
    dims = m.system.dims if m.generated else []
    args = [d.removeprefix("s%").replace(" = ", "=") for d in dims]
    args += [f"{component(p)}=p({i + 1})" for i, p in enumerate(m.params)]
    # (the lines stand 12 columns in: in a case of a select)
    return [ln[12:] for ln in wrap_statement(
        f"allocate ({arg}, source={m.type_name}({', '.join(args)}))", " " * 12)]


def called(statement):
    """The procedure a `call NAME(...)` statement calls."""
    return statement.split("(")[0].split()[-1]


def use_lines(models):
    """`use` lines of the modules that give the registry the systems' types (and the
    hand-written make routines and initial states)."""
    uses = {}
    for m in models:
        module = KINDS[m.kind][0] if m.generated else m.module
        names = [called(m.make)] if (not m.generated and m.make) else [m.type_name]
        if not m.generated and m.initial:
            names.append(called(m.initial))
        uses.setdefault(module, []).extend(names)
    out = []
    for module, names in uses.items():
        out += wrap_statement(f"use {module}, only: " + ", ".join(names), "    ")
    return out


def names_doc(models):
    return " | ".join(f"{m.name}: {', '.join(p.name for p in m.params)}" for m in models)


def state_lines(m):
    """mech_initial_state's statements for the model m (q0, v0 from the parameters p)."""
    if not m.generated:
        return [m.initial]
    pr = FortranPrinter({p.symbol: f"p({i + 1})" for i, p in enumerate(m.params)})
    out = []
    for name, vec in (("q0", m.q0), ("v0", m.v0)):
        vals = [pr._print(sp.sympify(e)) for e in vec]
        out += wrap_statement(f"{name} = [" + ", ".join(vals) + "]", "")
    return out


def string_parameter(name, words):
    """`character(len=*), parameter :: name = "..."` of space-separated words, continued
    by concatenation (a word is never split)."""
    head = f"    character(len=*), parameter :: {name} = "
    lines, cur = [], ""
    for w in words.split():
        room = WIDTH - len(head if not lines else "        //") - 4
        if cur and len(cur) + 1 + len(w) > room:
            lines.append(cur + " ")
            cur = w
        else:
            cur = f"{cur} {w}" if cur else w
    lines.append(cur)
    out = [head + fstring(lines[0]) + (" &" if len(lines) > 1 else "")]
    for i, ln in enumerate(lines[1:], 1):
        out.append("        //" + fstring(ln) + (" &" if i < len(lines) - 1 else ""))
    return out


def make_routine(kind, arg, base, models, default):
    """A registry routine make_<kind>: check the parameter count, complete the parameters
    with their defaults, one case per system; `default`: the statements for other names."""
    out = ["", f"    subroutine make_{kind}(name, params, {arg}, info, msg)",
           f"{IND}character(len=*), intent(in) :: name",
           f"{IND}real(dp), intent(in) :: params(:)",
           f"{IND}class({base}), allocatable, intent(out) :: {arg}",
           f"{IND}integer, intent(out) :: info",
           f"{IND}character(len=:), allocatable, intent(out) :: msg",
           f"{IND}real(dp), allocatable :: p(:)",
           f"{IND}call complete(name, params, p, info, msg)",
           f"{IND}if (info /= CM_SUCCESS) return", f"{IND}select case (trim(name))"]
    out += grouped_cases([(m.name, make_lines(m, arg)) for m in models])
    out += [f"{IND}case default"] + [f"{IND}    {ln}" for ln in default]
    return out + [f"{IND}end select", f"    end subroutine make_{kind}"]


def registry_modules(models):
    """conmech_systems (the registry: make_system, system_dimension, make_generalized,
    make_constrained, mech_initial_state, the names) and conmech_systems_mech (its
    mechanical part, under the name it has always had)."""
    ode, gen, con = models["ode"], models["generalized"], models["constrained"]
    out = generated_header(
        "Registry of the built-in systems by name, for the programs and the Python layer. "
        "`make_system` allocates a first-order system (or one in generalized coordinates as "
        "a first-order one, y = [q, q']), `make_generalized` a generalized_system, "
        "`make_constrained` a constrained_system, each from its name and its parameters in "
        "the documented order (missing trailing ones keep their defaults; more are an "
        "error; conmech_systems_params). First-order: " + names_doc(ode)
        + ". Generalized coordinates: " + names_doc(gen) + ". Excessive coordinates: "
        + names_doc(con) + ".")
    out += ["module conmech_systems", "    use conmech_kinds, only: dp",
            "    use conmech_status, only: CM_SUCCESS, CM_BAD_INPUT",
            "    use conmech_ode_system, only: ode_system",
            "    use conmech_generalized, only: generalized_system, generalized_ode",
            "    use conmech_constrained_system, only: constrained_system",
            "    use conmech_systems_params, only: builtin_params, check_param_count"]
    out += use_lines(ode + gen + con)
    out += ["    implicit none", "    private",
            "    public :: make_system, system_dimension, make_generalized, "
            "make_generalized_ode",
            "    public :: make_constrained, mech_initial_state, constrained_names, "
            "generalized_names", "    public :: ode_names", "",
            "    !> Names of the built-in first-order systems of `make_system` (space "
            "separated; the", "    !! generalized ones are first-order systems too)."]
    out += string_parameter("ode_names", " ".join(m.name for m in ode))
    out += ["    !> Names of the built-in constrained systems."]
    out += string_parameter("constrained_names", " ".join(m.name for m in con))
    out += ["    !> Names of the built-in generalized-coordinate systems."]
    out += string_parameter("generalized_names", " ".join(m.name for m in gen))
    out += ["", "contains", "",
            "    !> p: the whole parameter vector of the built-in `name` from `params` (the "
            "defaults", "    !! for missing trailing ones); CM_BAD_INPUT if there are too "
            "many.", "    subroutine complete(name, params, p, info, msg)",
            f"{IND}character(len=*), intent(in) :: name",
            f"{IND}real(dp), intent(in) :: params(:)",
            f"{IND}real(dp), allocatable, intent(out) :: p(:)",
            f"{IND}integer, intent(out) :: info",
            f"{IND}character(len=:), allocatable, intent(out) :: msg",
            f"{IND}call check_param_count(name, size(params), info, msg)",
            f"{IND}p = builtin_params(name, params)", "    end subroutine complete", "",
            "    !> Allocate the built-in first-order system `name` (see the module)."]
    out += make_routine("system", "sys", "ode_system", ode,
                        ["! the systems in generalized coordinates, y = [q, q']",
                         "call make_generalized_ode(name, params, sys, info, msg)",
                         "if (info /= CM_SUCCESS) msg = \"bad input: unknown built-in "
                         "system '\"//trim(name)//\"'\""])[1:]
    for kind, arg, base, lst in (("generalized", "mech", "generalized_system", gen),
                                 ("constrained", "sys", "constrained_system", con)):
        what = "n, n_hol, n_nh" if kind == "constrained" else "ndof"
        body = make_routine(kind, arg, base, lst,
                            ["info = CM_BAD_INPUT",
                             f"msg = \"bad input: unknown {kind} system '\"//trim(name)//\"' "
                             f"(known: \" &", f"      //{kind}_names//\")\""])
        out += ["", f"    !> Allocate the built-in {kind} system `name` ({what} set)."] + body[1:]
    out += ["",
            "    !> A built-in generalized system as a first-order ode_system (y = [q, v]).",
            "    subroutine make_generalized_ode(name, params, sys, info, msg)",
            f"{IND}character(len=*), intent(in) :: name",
            f"{IND}real(dp), intent(in) :: params(:)",
            f"{IND}class(ode_system), allocatable, intent(out) :: sys",
            f"{IND}integer, intent(out) :: info",
            f"{IND}character(len=:), allocatable, intent(out) :: msg",
            f"{IND}type(generalized_ode) :: w",
            f"{IND}call make_generalized(name, params, w%mech, info, msg)",
            f"{IND}if (info /= CM_SUCCESS) return", f"{IND}allocate (sys, source=w)",
            "    end subroutine make_generalized_ode", "",
            "    !> State dimension of a built-in first-order or generalized-coordinate "
            "system (0 if", "    !! the name is unknown).",
            "    pure integer function system_dimension(name) result(n)",
            f"{IND}character(len=*), intent(in) :: name", f"{IND}select case (trim(name))"]
    dims = [(m.name, len(m.y) if m.generated else m.size) for m in ode]
    dims += [(m.name, 2*len(m.q)) for m in gen]
    out += grouped_cases([(nm, [f"n = {k}"]) for nm, k in sorted(dims, key=lambda x: x[1])])
    out += [f"{IND}case default", f"{IND}    n = 0", f"{IND}end select",
            "    end function system_dimension", "",
            "    !> A default initial state (q0, v0) of a built-in system (constrained or "
            "generalized),", "    !! consistent with its constraints for the given parameters.",
            "    subroutine mech_initial_state(name, params, q0, v0, info)",
            f"{IND}character(len=*), intent(in) :: name",
            f"{IND}real(dp), intent(in) :: params(:)",
            f"{IND}real(dp), allocatable, intent(out) :: q0(:), v0(:)",
            f"{IND}integer, intent(out) :: info", f"{IND}real(dp), allocatable :: p(:)",
            f"{IND}info = CM_SUCCESS", f"{IND}p = builtin_params(name, params)",
            f"{IND}select case (trim(name))"]
    out += grouped_cases([(m.name, state_lines(m)) for m in con + gen])
    out += [f"{IND}case default", f"{IND}    info = CM_BAD_INPUT",
            f"{IND}    allocate (q0(0), v0(0))", f"{IND}end select",
            "    end subroutine mech_initial_state", "", "end module conmech_systems", ""]
    mech = generated_header(
        "The mechanical part of the registry of built-in systems (conmech_systems, where "
        "the procedures are): `make_generalized`, `make_generalized_ode`, "
        "`make_constrained`, `mech_initial_state` and the lists of names.")
    mech += ["module conmech_systems_mech",
             "    use conmech_systems, only: make_generalized, make_generalized_ode, "
             "make_constrained, &",
             "        & mech_initial_state, constrained_names, generalized_names",
             "    implicit none", "    private",
             "    public :: make_constrained, make_generalized, make_generalized_ode",
             "    public :: mech_initial_state, constrained_names, generalized_names",
             "end module conmech_systems_mech", ""]
    return check_lines("conmech_systems", out), check_lines("conmech_systems_mech", mech)


# ------------------------------------------------------------------------------ Python

PY_NOTE = (f"Generated by {GENERATOR} from the models in tools/builtin_models/: do not edit; "
           "change a model (or add one) and regenerate.")


def py_dict(name, doc, items):
    """`NAME = {...}` with one entry per line (items: [(key, value source)])."""
    out = [f"#: {ln}" for ln in textwrap.wrap(doc, 92)]
    if not items:
        return out + [f"{name} = {{}}"]
    out.append(f"{name} = {{")
    for k, v in items:
        out += wrap_py(f"{pq(k)}: {v},", "    ")
    return out + ["}"]


def pq(x):
    """Python source of a str (double quotes, the project's style) or a tuple of them."""
    if isinstance(x, tuple):
        return "(" + ", ".join(pq(e) for e in x) + ("," if len(x) == 1 else "") + ")"
    return json.dumps(x)


def py_float(x):
    if x == float("inf"):
        return "math.inf"
    return repr(float(x))


def table_module(models):
    allm = [m for k in ("ode", "generalized", "constrained") for m in models[k]]
    out = ['"""The built-in systems\' parameters, their validity and the names of their state',
           "components: the Python side of the Fortran registries.", ""]
    out += textwrap.wrap(PY_NOTE, 92) + ['"""', "import math", ""]
    out += py_dict("KINDS", "The kind of each built-in system: \"ode\" (first-order), "
                   "\"generalized\" (generalized coordinates, y = [q, q']) or \"constrained\" "
                   "(excessive coordinates, conmech.constrained).",
                   [(m.name, pq(m.kind)) for m in allm])
    out += py_dict("PARAMS", "The parameters of each built-in system in the registry's order, "
                   "with their defaults.",
                   [(m.name, "(" + ", ".join(f"({pq(p.name)}, {py_float(p.default)})"
                                             for p in m.params) + ",)") for m in allm])
    out += py_dict("POSITIVE_PARAMS", "Parameters (by position) that must be positive for "
                   "each built-in system: the system is singular (a division by it) or "
                   "meaningless otherwise.",
                   [(m.name, "{" + ", ".join(f"{i}: {pq(p.name)}" for i, p in enumerate(m.params)
                                             if p.positive) + "}")
                    for m in allm if any(p.positive for p in m.params)])
    out += py_dict("RANGE_PARAMS", "Parameters that must lie in a closed interval (whole "
                   "numbers such as a chain's number of links are checked by their factory "
                   "and the Fortran registry).",
                   [(m.name, "{" + ", ".join(
                       f"{i}: ({pq(p.name)}, {py_float(p.interval[0])}, "
                       f"{py_float(p.interval[1])})"
                       for i, p in enumerate(m.params) if p.interval and not p.whole) + "}")
                    for m in allm if any(p.interval and not p.whole for p in m.params)])
    out += py_dict("STATE_NAMES", "Names of the state components of the built-in first-order "
                   "and generalized systems (for reports such as the direction of a secular "
                   "drift): coordinates, then velocities.",
                   [(m.name, pq(tuple(m.coords) + tuple(c + "'" for c in m.coords)))
                    for m in models["ode"] + models["generalized"]])
    fixed = [m.name for m in models["constrained"] if m.generated or m.size]
    out += ["#: The built-in constrained systems with a fixed number of coordinates."]
    out += wrap_py(f"CONSTRAINED_NAMES = {pq(tuple(fixed))}", "")
    return "\n".join(out) + "\n"


def wrap_py(line, indent, width=96):
    """A long Python expression broken after commas (inside its brackets)."""
    if len(indent) + len(line) <= width:
        return [indent + line]
    k = min(i for i in (line.find("("), line.find("[")) if i >= 0) + 1
    pad = indent + " " * k
    out, cur = [], indent + line[:k]
    for part in [p.strip() for p in line[k:].split(", ")]:
        opening = cur.endswith(("(", "["))
        piece = part if opening else ", " + part
        if len(cur + piece.rstrip(",")) > width - 1 and not opening:
            out.append(cur + ",")
            cur = pad + part
        else:
            cur += piece
    return out + [cur]


def factory(m):
    """Source of the Python factory of the model m."""
    args = ", ".join(f"{p.name}={py_float(p.default) if not p.whole else int(p.default)}"
                     for p in m.params)
    out = [f"def {m.name}({args}):"]
    doc = textwrap.wrap(m.summary, 88, break_on_hyphens=False)
    if len(doc) == 1 and len(doc[0]) <= 86:
        out.append(f'    """{doc[0]}"""')
    else:
        out += [f'    """{doc[0]}'] + [f"    {d}" for d in doc[1:-1]] + [f'    {doc[-1]}"""']
    vals = "[" + ", ".join(p.name for p in m.params) + "]"
    if getattr(m, "python_factory", None):
        out += ["    " + ln if ln else "" for ln in m.python_factory.splitlines()]
    elif m.kind == "constrained":
        out += wrap_py(f"return BuiltinConstrained({pq(m.name)}, {vals})", "    ")
    else:
        names = pq(tuple(p.name for p in m.params))
        out += wrap_py(f"return BuiltinSystem({pq(m.name)}, {vals}, {names})", "    ")
    return out


def systems_py(models):
    allm = [m for k in ("ode", "generalized", "constrained") for m in models[k]]
    out = ['"""Built-in systems of conmech, for :func:`conmech.solve_ivp` (first-order and',
           "generalized-coordinate systems) and :func:`conmech.constrained.solve` (constrained",
           "systems in excessive coordinates).", "",
           "Each factory returns a :class:`BuiltinSystem` (y = [q, q'] for generalized",
           "coordinates) or a :class:`conmech.constrained.BuiltinConstrained`: the name of a "
           "system of", "the Fortran registries and its parameters in the documented order "
           "(missing trailing", "parameters keep their defaults). Integrating a built-in "
           "system runs entirely in Fortran,", "with no Python in the loop.", "",
           "Every built-in system is written once, as a model in tools/builtin_models/ (its "
           "T and U", "or Lagrangian, constraints, parameters and their validity); "
           "tools/generate_builtins.py", "derives its Fortran and writes the registries and "
           "this module (see the guide's page", '"Adding a built-in system").', ""]
    out += textwrap.wrap(PY_NOTE, 92) + ['"""']
    out += ["from .._core.builtin_table import POSITIVE_PARAMS, RANGE_PARAMS, STATE_NAMES  "
            "# noqa: F401", "from .._core.native import _NO_SPEC, BuiltinSystem, NativeSystem, "
            "check_params  # noqa: F401", "from .constrained import BuiltinConstrained", ""]
    names = ["NativeSystem", "BuiltinSystem"] + [m.name for m in allm]
    out += wrap_py("__all__ = [" + ", ".join(pq(n) for n in names) + "]", "")
    for m in allm:
        out += ["", ""] + factory(m)
    return "\n".join(out) + "\n"


# ------------------------------------------------------------------------------ driver

def generate(models=None):
    """{path relative to the repository: text} of every generated file, for the models
    {kind: [models in registry order]} (default: builtin_models.load_all())."""
    models = models or bm.load_all()
    files = {}
    for kind in ("ode", "generalized", "constrained"):
        systems = []
        for m in models[kind]:
            if m.generated:
                m.system = System(m)
                systems.append(m.system)
        # the first-order module also gives the hand-written Arenstorf type, as it always has
        extra = [m for m in models[kind] if not m.generated and m.name == "arenstorf"]
        module = KINDS[kind][0]
        files[f"src/systems/{module}.f90"] = kind_module(kind, systems, extra)
        files[f"src/systems/{module}_equations.f90"] = kind_submodule(kind, systems)
    files["src/systems/conmech_systems_params.f90"] = params_module(models)
    (files["src/systems/conmech_systems.f90"],
     files["src/systems/conmech_systems_mech.f90"]) = registry_modules(models)
    files["python/conmech/_core/builtin_table.py"] = table_module(models)
    files["python/conmech/mechanics/systems.py"] = systems_py(models)
    return files


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true",
                    help="write nothing; exit 1 if a committed file differs from the models")
    ap.add_argument("--out", help="write the generated tree below this folder")
    a = ap.parse_args(argv)
    files = generate()
    root = Path(a.out) if a.out else ROOT
    stale = []
    for rel, text in files.items():
        path = root / rel
        if a.check:
            old = path.read_text() if path.exists() else ""
            if old != text:
                stale.append(rel)
                sys.stdout.writelines(difflib.unified_diff(
                    old.splitlines(True), text.splitlines(True), rel, rel + " (models)"))
            continue
        path.parent.mkdir(parents=True, exist_ok=True)
        if not path.exists() or path.read_text() != text:
            path.write_text(text)
    if a.check and stale:
        print(f"stale: {', '.join(stale)} (run python {GENERATOR})", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
