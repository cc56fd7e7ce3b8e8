"""The table of compiled functions: the one definition of every entry a compiled system
can give (its C signature, the kinds of system that use it, its place in the ``spec``
array handed to Fortran, the shapes of its outputs).

Everything else is read or generated from this table:

- :mod:`conmech.compiled` builds the spec from it and loads model libraries by its names;
- :mod:`conmech.symbolic` calls the entries through ctypes by its layouts and shapes, and
  its code generator checks its entry points against it;
- ``tools/generate_slots.py`` writes the Fortran side (``src/mechanics/conmech_c_entries.f90``:
  the slot numbers, the pointer record of mechanical systems, the loader by name) and the
  C signature text in the documentation of ``conmech.compiled``, ``conmech_c_system``,
  ``conmech_c_mechanics`` and ``conmech_flat_spec``; ``--check`` fails on a stale file.

The spec (``int64``, 1-based as Fortran reads it): 1 kind (0 built-in by name, 1 ode, 2
generalized coordinates, 3 constrained), 2 n (ode: state dimension; generalized: ndof;
constrained: coordinates), 3 n_hol, 4 n_nh, 5 rheonomic (0/1), then one slot per entry
below (an address, 0 when absent, or a count). Two kinds may share a slot number (``rhs``
and ``mass`` are both slot 6): the kind decides how it is read.

This module imports nothing from conmech (the generator loads it from its path).
"""

#: kind codes of spec(1)
KIND_BUILTIN, KIND_ODE, KIND_GENERALIZED, KIND_CONSTRAINED = 0, 1, 2, 3
KINDS = {"ode": KIND_ODE, "generalized": KIND_GENERALIZED, "constrained": KIND_CONSTRAINED}

#: the header of the spec (1-based slots)
HEADER = (("kind", 1), ("n", 2), ("n_hol", 3), ("n_nh", 4), ("rheonomic", 5))


class Entry:
    """One compiled function (or one count) of the table.

    name: the argument name in :mod:`conmech.compiled` and, prefixed by ``conmech_``, the
    C name a model library exports; slot: its 1-based place in the spec; kinds: the kinds
    of system that read it; required: whether those kinds need it; signature: the C
    declaration (None for a count); outputs: the output shapes (expressions in n, h = n_hol,
    k = n_nh; "ret" for a returned double); doc: one line for the documentation; taylor:
    the key in the ``taylor`` dict of :func:`conmech.compiled.ode_system` (Taylor entries
    only, which are not loaded by name)."""

    __slots__ = ("name", "slot", "kinds", "required", "signature", "outputs", "doc",
                 "taylor")

    def __init__(self, name, slot, kinds, signature=None, outputs=(), doc="",
                 required=False, taylor=None):
        self.name = name
        self.slot = slot
        self.kinds = tuple(kinds)
        self.required = required
        self.signature = signature
        self.outputs = tuple(outputs)
        self.doc = doc
        self.taylor = taylor

    @property
    def is_function(self):
        return self.signature is not None

    @property
    def inputs(self):
        """The number of input arrays after t (y; q; q, v; q, v, a; ...), from the C
        signature: the `const double *` arguments other than the parameters p."""
        args = self.signature.split("(", 1)[1].rsplit(")", 1)[0].split(",")
        return sum(1 for a in args if a.strip().startswith("const double *")) - 1

    def __repr__(self):
        return f"Entry({self.name!r}, slot {self.slot})"


_O, _G, _C = ("ode",), ("generalized",), ("constrained",)
_GC = ("generalized", "constrained")

#: every entry, in spec order (the order of the generated documentation)
ENTRIES = (
    Entry("rhs", 6, _O, "void rhs(double t, const double *y, double *dydt, const double *p)",
          ["(n,)"], "dydt = f(t, y; p)", required=True),
    Entry("jac", 7, _O, "void jac(double t, const double *y, double *dfdy, const double *p)",
          ["(n, n)"], "df/dy (column-major); without it finite differences"),
    Entry("mass", 6, _GC, "void mass(double t, const double *q, double *M, const double *p)",
          ["(n, n)"], "the mass matrix M(t, q)", required=True),
    Entry("forces", 7, _GC,
          "void forces(double t, const double *q, const double *v, double *Q, "
          "const double *p)", ["(n,)"], "the forces Q(t, q, q')", required=True),
    Entry("forces_jac", 8, _GC,
          "void forces_jac(double t, const double *q, const double *v, const double *a, "
          "double *R, const double *p)", ["(n, 2*n)"],
          "[dQ/dq - d(M a)/dq, dQ/dv], the Jacobian of the force balance at accelerations a"),
    Entry("energy", 9, _GC,
          "double energy(double t, const double *q, const double *v, const double *p)",
          ["ret"], "the energy (a first integral)"),
    Entry("phi", 10, _C, "void phi(double t, const double *q, double *c, const double *p)",
          ["(h,)"], "the holonomic constraints phi(t, q) (n_hol; required when n_hol > 0)"),
    Entry("phi_jac", 11, _C,
          "void phi_jac(double t, const double *q, double *G, const double *p)",
          ["(h, n)"], "G = dphi/dq (n_hol x n)"),
    Entry("phi_t", 12, _C, "void phi_t(double t, const double *q, double *pt, const double *p)",
          ["(h,)"], "dphi/dt (rheonomic constraints)"),
    Entry("phi_gamma", 13, _C,
          "void phi_gamma(double t, const double *q, const double *v, double *g, "
          "const double *p)", ["(h,)"], "gamma_h = -d/dt [G v + phi_t] at fixed v"),
    Entry("nh_matrix", 14, _C,
          "void nh_matrix(double t, const double *q, double *A, double *b, const double *p)",
          ["(k, n)", "(k,)"],
          "the Pfaffian constraints A(t, q) q' + b(t, q) = 0 (required when n_nh > 0)"),
    Entry("nh_gamma", 15, _C,
          "void nh_gamma(double t, const double *q, const double *v, double *g, "
          "const double *p)", ["(k,)"], "gamma_n = -d/dt [A v + b] at fixed v"),
    Entry("mass_forces", 16, _G,
          "void mass_forces(double t, const double *q, const double *v, double *M, "
          "double *Q, const double *p)", ["(n, n)", "(n,)"],
          "M and Q in one call (shared subexpressions)"),
    Entry("accel", 17, _G,
          "void accel(double t, const double *q, const double *v, double *a, "
          "const double *p)", ["(n,)"],
          "the accelerations a = M^-1 Q directly (e.g. the articulated-body algorithm); "
          "non-finite where M is not positive definite"),
    Entry("jac_prod", 18, _O,
          "void jac_prod(double t, const double *y, int k, const double *x, double *jx, "
          "const double *p)", ["(n, ncol)"], "jx = J(t, y) x for an n x ncol block x"),
    Entry("jet", 19, _O, "void taylor(double t, int order, double *w, const double *p)",
          ["(order + 1, nw)"], "normalized Taylor coefficients of the solution",
          taylor="jet"),
    Entry("nw", 20, _O, doc="the work columns of jet (>= n)", taylor="nw"),
    Entry("var", 21, _O, "void taylor_var(double t, int order, double *w, const double *p)",
          ["(order + 1, nw_var)"], "the same for the variational system [f; J Phi]",
          taylor="var"),
    Entry("nw_var", 22, _O, doc="the work columns of var", taylor="nw_var"),
    Entry("jet_fixed", 23, _O,
          "void taylor_fixed(double t, int order, double *w, const double *p)",
          ["(order + 1, nw)"], "jet written out for one order", taylor="jet_fixed"),
    Entry("order", 24, _O, doc="the order of jet_fixed", taylor="order"),
    Entry("var_fixed", 25, _O,
          "void taylor_var_fixed(double t, int order, double *w, const double *p)",
          ["(order + 1, nw_var)"], "var written out for one order", taylor="var_fixed"),
    Entry("order_var", 26, _O, doc="the order of var_fixed", taylor="order_var"),
    Entry("constraint_hessian", 27, _C,
          "void constraint_hessian(double t, const double *q, const double *v, "
          "const double *lam, double *hl, double *hv, const double *p)",
          ["(n, n)", "(h + k, n)"],
          "hl = d(C^T lam)/dq, hv = d(C v + c0)/dq: with forces_jac the exact Jacobian of "
          "Radau IIA on the constrained equations"),
    Entry("accel_jac", 28, _G,
          "void accel_jac(double t, const double *q, const double *v, double *a, "
          "double *jac, const double *p)", ["(n,)", "(n, 2*n)"],
          "a and its Jacobian d a/d[q, v] (ndof x 2 ndof)"),
)

#: the length of a full spec
SPEC_SIZE = max(e.slot for e in ENTRIES)

#: entries by name
BY_NAME = {e.name: e for e in ENTRIES}

#: the functions loaded by name (conmech_<name>), slot by name (Taylor entries apart)
SLOTS = {e.name: e.slot for e in ENTRIES if e.taylor is None}

#: the Taylor entries: key of the taylor dict -> slot
TAYLOR_SLOTS = {e.taylor: e.slot for e in ENTRIES if e.taylor is not None}

#: the Taylor keys that are functions (the others are counts)
TAYLOR_FUNCS = tuple(e.taylor for e in ENTRIES if e.taylor is not None and e.is_function)

#: the functions of each kind of system (loaded by name), in table order
ENTRY_POINTS = {kind: [e.name for e in ENTRIES if kind in e.kinds and e.taylor is None]
                for kind in KINDS}

#: the mechanical entries (the pointer record c_mech_pointers of conmech_c_entries)
MECH_ENTRIES = tuple(e for e in ENTRIES if set(e.kinds) & set(_GC))


def shapes(name, n, h=0, k=0):
    """The output shapes of entry `name` for n coordinates (or states), h holonomic and k
    Pfaffian constraints: a list of tuples ([] for a returned double)."""
    env = {"n": n, "h": h, "k": k}
    return [eval(s, {"__builtins__": {}}, env) for s in BY_NAME[name].outputs  # noqa: S307
            if s != "ret"]


def returns_value(name):
    """Whether entry `name` returns a double (the energy) instead of writing arrays."""
    return "ret" in BY_NAME[name].outputs
