"""Generalized momenta, generalized forces, cyclic coordinates and first integrals of a
symbolic Lagrangian system.

The lecture notes call dL/dq' the generalized momenta and dL/dq the generalized
forces ("may not have units of force/momenta"), and note: if L does not depend on q_i, the
Euler-Lagrange equation reads d/dt dL/dq_i' = 0 and dL/dq_i' is conserved. For a system
made by :func:`conmech.symbolic.lagrangian_system` (or a planar or spatial tree) this
module gives

- the expressions p_i = dL/dq_i' and dL/dq_i (in the user's dynamicsymbols),
- the cyclic coordinates: L does not depend on q_i (checked symbolically, with a numeric
  screen at random states and parameter values first) and no non-conservative force acts
  on q_i, so that p_i is a first integral; ``ignorable`` lists the coordinates L does not
  depend on whatever the forces,
- the first integrals: the cyclic momenta and, when L does not depend on t and no
  non-conservative force acts, the energy (Jacobi integral); their values, gradients and
  drifts along solutions,
- compiled functions of the state (the same gfortran path as the equations of motion,
  cached): p(t, q, v), dL/dq(t, q, v), L(t, q, v), the integrals and their gradients, each
  also in a batch form that evaluates a whole solution in one call.

A system from :func:`lagrangian_system` carries these as attributes::

    cart.cyclic_coordinates        # (0,): x
    cart.momenta.p                 # [2*x' + cos(theta)*theta', cos(theta)*x' + theta']
    cart.first_integrals.check(sol)   # {'energy': 3e-12, 'p_x': 1e-13}
"""
import ctypes

import numpy as np
import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

from ..mechanics import compiled
from .build import compile_source, load
from .printer import _procedure, entry_heads
from .source_text import check_source, comment_lines, comment_text

__all__ = ["Momenta", "FirstIntegrals", "LagrangianSystem", "momenta", "first_integrals",
           "as_lagrangian_system", "to_user"]

_D = ctypes.c_double
_P = ctypes.POINTER(ctypes.c_double)
_I = ctypes.c_int


# ------------------------------------------------------------------------ symbolic checks

def is_zero(expr, trials=4, seed=2024):
    """True when `expr` vanishes identically. Structural zeros are immediate; otherwise the
    expression is evaluated at `trials` random points (every free symbol, parameters
    included, uniform in [0.3, 1.7]): nonzero at one of them (beyond 1e-10 of the sum of
    its terms' magnitudes) means not zero; zero at every point means zero (an analytic
    expression that vanishes at random points vanishes identically, with probability
    one). Only if no point can be evaluated does sympy.simplify decide."""
    expr = sp.sympify(expr)
    if expr == 0:
        return True
    syms = sorted(expr.free_symbols, key=str)
    if not syms:
        return complex(expr) == 0
    f = sp.lambdify(syms, expr, modules="math")
    fa = sp.lambdify(syms, sp.Add(*[sp.Abs(a) for a in sp.Add.make_args(expr)]),
                     modules="math")
    rng = np.random.default_rng(seed)
    evaluated = 0
    for _ in range(trials):
        vals = [float(rng.uniform(0.3, 1.7)) for _ in syms]
        try:
            val = complex(f(*vals))
            scale = abs(complex(fa(*vals)))
        except (ValueError, ZeroDivisionError, OverflowError, TypeError):
            continue
        if not (np.isfinite(val.real) and np.isfinite(val.imag) and np.isfinite(scale)):
            continue
        evaluated += 1
        if abs(val) > 1e-10*max(1.0, scale):
            return False
    if evaluated:
        return True
    return sp.simplify(expr) == 0


def to_user(expr, derived):
    """An expression in a derived record's plain symbols rewritten in the user's terms:
    coordinates as dynamicsymbols q(t), velocities as their derivatives, parameters and t
    as plain Symbols of their names."""
    t = dynamicsymbols._t
    sub = {derived.t: t}
    for name, qs, vs in zip(derived.coord_names, derived.coords, derived.speeds):
        f = sp.Function(name)(t)
        sub[qs] = f
        sub[vs] = f.diff(t)
    for ps, name in zip(derived.params, derived.param_names):
        sub[ps] = sp.Symbol(name)
    return sp.sympify(expr).xreplace(sub)


def _model(system):
    keep = getattr(system, "_keep", None)
    if isinstance(keep, tuple) and keep and hasattr(keep[0], "derived"):
        return keep[0]
    raise TypeError("not a system made by conmech.symbolic (lagrangian_system, "
                    "planar_tree, spatial_tree)")


# ------------------------------------------------------------------------ the analysis

class _Analysis:
    """Symbolic analysis of a derived generalized system, shared by every parameter copy
    of the system (cached on its CompiledModel); the compiled libraries are built on first
    numeric use."""

    def __init__(self, d):
        if d.kind != "generalized":
            raise TypeError(f"momenta need a system in generalized coordinates (a "
                            f"Lagrangian), not a {d.kind!r} system")
        L = getattr(d, "lagrangian", None)
        if L is None:
            raise TypeError("this system has no Lagrangian (its equations were given "
                            "directly): momenta and cyclic coordinates are undefined")
        self.d = d
        n = d.n
        self.n = n
        self.L = L
        q, v = list(d.coords), list(d.speeds)
        self.p = [sp.diff(L, vi) for vi in v]
        self.dLdq = [sp.diff(L, qi) for qi in q]
        gf = list(getattr(d, "gen_forces", None) or [sp.Integer(0)]*n)
        self.nonconservative = [sp.sympify(f) for f in gf]
        self.ignorable = tuple(i for i in range(n) if is_zero(self.dLdq[i]))
        self.cyclic = tuple(i for i in self.ignorable
                            if is_zero(self.nonconservative[i]))
        forced = any(not is_zero(f) for f in self.nonconservative)
        self.time_dependent = d.t in L.free_symbols and not is_zero(sp.diff(L, d.t))
        self.energy_conserved = not self.time_dependent and not forced and d.energy is not None
        names = list(d.coord_names)
        self.integral_names = (["energy"] if self.energy_conserved else []) + \
            [f"p_{names[i]}" for i in self.cyclic]
        self.integrals = ([d.energy] if self.energy_conserved else []) + \
            [self.p[i] for i in self.cyclic]
        self._lib = None
        self._hess = None
        self._lhess = None

    # compiled functions -------------------------------------------------------------
    def library(self):
        if self._lib is None:
            d = self.d
            n = d.n
            y = list(d.coords) + list(d.speeds)
            ints = sp.Matrix(self.integrals) if self.integrals else sp.zeros(0, 1)
            grads = ints.jacobian(y) if self.integrals else sp.zeros(0, 2*n)
            entries = [("momenta", sp.Matrix(self.p), n), ("dldq", sp.Matrix(self.dLdq), n),
                       ("integrals", ints, len(self.integrals)),
                       ("integrals_grad", grads, (len(self.integrals), 2*n)),
                       ("nonconservative", sp.Matrix(self.nonconservative), n)]
            self._lib = _build(d, entries, scalars=[("lagrangian", self.L)],
                               module="conmech_symbolic_momenta")
        return self._lib

    def _state_hessian(self, slot, expr, entry, module):
        """The library of one entry `entry`: the Hessian of expr in y = [q, v] (2n x 2n),
        built once and kept in the attribute `slot`."""
        if getattr(self, slot) is None:
            d = self.d
            H = sp.hessian(expr, list(d.coords) + list(d.speeds))
            setattr(self, slot, _build(d, [(entry, H, (2*d.n, 2*d.n))], module=module))
        return getattr(self, slot)

    def lagrangian_hessian_library(self):
        """The Hessian of L in y = [q, v] (2n x 2n), for the second variation."""
        return self._state_hessian("_lhess", self.L, "lagrangian_hess",
                                   "conmech_symbolic_lagrangian_hessian")

    def hessian_library(self):
        """The Hessian of the energy in y = [q, v] (2n x 2n)."""
        return self._state_hessian("_hess", self.d.energy, "energy_hess",
                                   "conmech_symbolic_energy_hessian")


class _Lib:
    """A compiled library of state functions f(t, q, v, out, p) with batch forms."""

    def __init__(self, lib, shapes, n):
        self.lib = lib
        self.shapes = shapes
        self.n = n

    def __call__(self, name, t, y, params):
        """Evaluate entry `name` at one state y = [q, v] (1-D) or at many (y of shape
        (2n, m), t scalar or of length m): the batch form loops in Fortran."""
        n = self.n
        y = np.asarray(y, dtype=float)
        p = np.ascontiguousarray(params, dtype=float)
        if p.size == 0:
            p = np.zeros(1)
        shape = self.shapes[name]
        if y.ndim == 1:
            if y.size != 2*n:
                raise ValueError(f"y must have {2*n} components [q, q'], got {y.size}")
            q = np.ascontiguousarray(y[:n])
            v = np.ascontiguousarray(y[n:])
            if shape == ():
                fn = ctypes.CFUNCTYPE(_D, _D, _P, _P, _P)(self._addr(name))
                return float(fn(float(t), _ptr(q), _ptr(v), _ptr(p)))
            out = np.zeros(shape, order="F")
            fn = ctypes.CFUNCTYPE(None, _D, _P, _P, _P, _P)(self._addr(name))
            fn(float(t), _ptr(q), _ptr(v), _ptr(out), _ptr(p))
            return out
        if y.ndim != 2 or y.shape[0] != 2*n:
            raise ValueError(f"y must have shape ({2*n},) or ({2*n}, m), got {y.shape}")
        m = y.shape[1]
        ts = np.ascontiguousarray(np.broadcast_to(np.asarray(t, dtype=float), (m,)))
        q = np.asfortranarray(y[:n])
        v = np.asfortranarray(y[n:])
        size = int(np.prod(shape)) if shape != () else 1
        out = np.zeros((size, m), order="F")
        fn = ctypes.CFUNCTYPE(None, _I, _P, _P, _P, _P, _P)(self._addr(name + "_batch"))
        fn(m, _ptr(ts), _ptr(q), _ptr(v), _ptr(out), _ptr(p))
        if shape == ():
            return out[0]
        return out.reshape(tuple(shape) + (m,), order="F")

    def _addr(self, entry):
        return ctypes.cast(getattr(self.lib, f"conmech_{entry}"), ctypes.c_void_p).value


def _ptr(a):
    return a.ctypes.data_as(_P)


def _build(d, vectors, scalars=(), module="conmech_symbolic_extra"):
    """Generate, compile (cached) and load state functions of the derived record d:
    vectors [(name, Matrix, shape)] as subroutines name(t, q, v, out, p), scalars
    [(name, expr)] as real functions name(t, q, v, p), each with a batch form
    name_batch(m, ts, qs, vs, out, p)."""
    pr, npar, ind, T, P = entry_heads(d)
    n = d.n
    QV = [T, f"{ind}real(dp), intent(in) :: q({n})", f"{ind}real(dp), intent(in) :: v({n})"]
    procs, shapes = [], {}
    for name, mat, shape in vectors:
        shape = (shape,) if isinstance(shape, int) else tuple(shape)
        shapes[name] = shape
        dims = ", ".join(str(max(s, 1)) for s in shape)
        out_decl = f"{ind}real(dp), intent(out) :: o({dims})"
        if 0 in shape:
            body = [f"    subroutine conmech_{name}(t, q, v, o, p) bind(C, "
                    f"name=\"conmech_{name}\")"] + QV + [out_decl, P, f"{ind}o = 0.0_dp",
                                                         f"    end subroutine conmech_{name}",
                                                         ""]
            procs.append(body)
        else:
            is_matrix = len(shape) == 2
            procs.append(_procedure(pr, f"conmech_{name}", ["t", "q", "v", "o", "p"],
                                    QV + [out_decl, P], [("o", mat, is_matrix)]))
        size = int(np.prod(shape)) if shape else 1
        procs.append(_batch(name, n, npar, max(size, 1), scalar=False))
    for name, expr in scalars:
        shapes[name] = ()
        procs.append(_procedure(pr, f"conmech_{name}", ["t", "q", "v", "p"], QV + [P], [],
                                result=expr))
        procs.append(_batch(name, n, npar, 1, scalar=True))
    # the coordinates' names are the user's strings: escaped (comment_text), never raw
    head = ["!> Generated by conmech.symbolic (momenta, integrals)."]
    head += comment_lines("Coordinates " + ", ".join(comment_text(c) for c in d.coord_names)
                          + ". Do not edit.")
    head += [f"module {module}",
            "    use, intrinsic :: iso_c_binding, only: c_double, c_int",
            "    implicit none",
            "    integer, parameter :: dp = c_double",
            "    public",
            "contains", ""]
    body = []
    for p_ in procs:
        body += p_
    src = "\n".join(head + body + [f"end module {module}", ""])
    entries = []
    for name in shapes:
        entries += [name, name + "_batch"]
    check_source(src, [f"conmech_{e}" for e in entries])
    path, _ = compile_source(src, symbols=entries)
    lib, _ = load(path, entries)
    return _Lib(lib, shapes, n)


def _batch(name, n, npar, size, scalar):
    ind = "        "
    call = (f"{ind}    o(1, j) = conmech_{name}(ts(j), qs(:, j), vs(:, j), p)" if scalar
            else f"{ind}    call conmech_{name}(ts(j), qs(:, j), vs(:, j), o(:, j), p)")
    return [f"    subroutine conmech_{name}_batch(m, ts, qs, vs, o, p) bind(C, "
            f"name=\"conmech_{name}_batch\")",
            f"{ind}integer(c_int), value, intent(in) :: m",
            f"{ind}real(dp), intent(in) :: ts(m), qs({n}, m), vs({n}, m)",
            f"{ind}real(dp), intent(out) :: o({size}, m)",
            f"{ind}real(dp), intent(in) :: p({npar})",
            f"{ind}integer :: j",
            f"{ind}do j = 1, m",
            call,
            f"{ind}end do",
            f"    end subroutine conmech_{name}_batch", ""]


def analysis(system):
    """The cached symbolic analysis of a symbolic generalized system."""
    model = _model(system)
    a = getattr(model, "_momenta_analysis", None)
    if a is None:
        a = _Analysis(model.derived)
        model._momenta_analysis = a
    return a


# ------------------------------------------------------------------------ public views

class Momenta:
    """Generalized momenta and forces of a symbolic Lagrangian system (see the module
    notes). Attributes: ``coordinates`` (names), ``p`` (dL/dq' as sympy expressions in the
    user's dynamicsymbols), ``forces`` (dL/dq), ``nonconservative`` (the forces given to
    the constructor), ``lagrangian``, ``cyclic`` (indices of the cyclic coordinates:
    momentum conserved), ``cyclic_names``, ``ignorable`` (L independent of them, whatever
    the forces). Compiled evaluations at a state y = [q, q'] (or a batch y of shape
    (2n, m) with t scalar or of length m): :meth:`p_of`, :meth:`forces_of`,
    :meth:`lagrangian_of`."""

    def __init__(self, system):
        self._a = analysis(system)
        self._params = np.asarray(system.params, dtype=float)
        d = self._a.d
        self.coordinates = list(d.coord_names)
        self.cyclic = self._a.cyclic
        self.cyclic_names = tuple(self.coordinates[i] for i in self.cyclic)
        self.ignorable = self._a.ignorable
        self.p = [to_user(e, d) for e in self._a.p]
        self.forces = [to_user(e, d) for e in self._a.dLdq]
        self.nonconservative = [to_user(e, d) for e in self._a.nonconservative]
        self.lagrangian = to_user(self._a.L, d)

    def p_of(self, y, t=0.0):
        """The generalized momenta dL/dq' at y (compiled)."""
        return self._a.library()("momenta", t, y, self._params)

    def forces_of(self, y, t=0.0):
        """The generalized forces dL/dq at y (compiled)."""
        return self._a.library()("dldq", t, y, self._params)

    def lagrangian_of(self, y, t=0.0):
        """L at y (compiled)."""
        return self._a.library()("lagrangian", t, y, self._params)

    def __repr__(self):
        return (f"Momenta(coordinates={self.coordinates}, cyclic={list(self.cyclic_names)}, "
                f"p={self.p})")


class FirstIntegrals:
    """The first integrals of a symbolic Lagrangian system that its structure guarantees:
    the energy (Jacobi integral v . dL/dv - L, when L does not depend on t and no
    non-conservative force acts) and the momenta of the cyclic coordinates. Attributes:
    ``names`` (e.g. ['energy', 'p_x']), ``expressions`` (sympy, user's symbols),
    ``cyclic``; compiled: :meth:`values`, :meth:`gradients`, :meth:`energy_hessian`,
    :meth:`along` (values along a solution), :meth:`check` (their largest drift)."""

    def __init__(self, system):
        self._a = analysis(system)
        self._params = np.asarray(system.params, dtype=float)
        self.names = list(self._a.integral_names)
        self.cyclic = self._a.cyclic
        self.expressions = [to_user(e, self._a.d) for e in self._a.integrals]

    def values(self, y, t=0.0):
        """The integrals at y (k values; batch: (k, m))."""
        return self._a.library()("integrals", t, y, self._params)

    def gradients(self, y, t=0.0):
        """Their gradients with respect to y = [q, q'] (k x 2n)."""
        return self._a.library()("integrals_grad", t, y, self._params)

    def energy_hessian(self, y, t=0.0):
        """The energy's Hessian with respect to y (2n x 2n), exact (compiled on first use);
        None when the energy is not a first integral."""
        if not self._a.energy_conserved:
            return None
        return self._a.hessian_library()("energy_hess", t, y, self._params)

    def along(self, sol):
        """The integrals along a solution (an OdeResult: its t and y): array (k, nt)."""
        y = np.asarray(sol.y, dtype=float)
        return np.asarray(self.values(y, np.asarray(sol.t, dtype=float))).reshape(
            len(self.names), y.shape[1])

    def check(self, sol, relative=False):
        """{name: max |I(t) - I(t0)|} along the solution (relative to max(1, |I(t0)|) with
        ``relative``)."""
        vals = self.along(sol)
        out = {}
        for name, row in zip(self.names, vals):
            dev = float(np.max(np.abs(row - row[0]))) if row.size else 0.0
            out[name] = dev/max(1.0, abs(float(row[0]))) if relative else dev
        return out

    def __repr__(self):
        return f"FirstIntegrals({dict(zip(self.names, self.expressions))})"


def momenta(system):
    """:class:`Momenta` of a system made by :func:`conmech.symbolic.lagrangian_system` (or
    a planar or spatial tree)."""
    return Momenta(system)


def first_integrals(system):
    """:class:`FirstIntegrals` of a system made by :func:`lagrangian_system`."""
    return FirstIntegrals(system)


class LagrangianSystem(compiled.CompiledSystem):
    """A compiled system in generalized coordinates derived from a Lagrangian (what
    :func:`conmech.symbolic.lagrangian_system`, :func:`planar_tree` and
    :func:`spatial_tree` return): a :class:`conmech.compiled.CompiledSystem` that also
    knows its ``cyclic_coordinates`` (indices), ``momenta`` (:class:`Momenta`),
    ``first_integrals`` (:class:`FirstIntegrals`) and ``degrees_of_freedom`` (its number
    of coordinates: the holonomic constraints are already eliminated)."""

    __slots__ = ()

    def with_params(self, **kw):
        """A copy with new values of some parameters (same compiled code: no rebuild)."""
        base = compiled.CompiledSystem.with_params(self, **kw)
        return type(self)(base.name, base.kind, base.spec, base.params, base.param_names,
                          base._keep)

    @property
    def cyclic_coordinates(self):
        """Indices of the cyclic coordinates (L independent of them, no non-conservative
        force on them): their momenta are conserved."""
        try:
            return analysis(self).cyclic
        except TypeError:
            return ()

    @property
    def momenta(self):
        return Momenta(self)

    @property
    def first_integrals(self):
        return FirstIntegrals(self)

    @property
    def degrees_of_freedom(self):
        """Number of degrees of freedom: the number of generalized coordinates."""
        return self.ndof


def as_lagrangian_system(system):
    """The :class:`LagrangianSystem` view of a compiled generalized system (same spec,
    parameters and compiled code)."""
    if isinstance(system, LagrangianSystem):
        return system
    if not (isinstance(system, compiled.CompiledSystem) and system.kind == "generalized"):
        return system
    return LagrangianSystem(system.name, system.kind, system.spec, system.params,
                            system.param_names, system._keep)
