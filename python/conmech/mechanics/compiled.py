"""Systems given by compiled functions: any code with conmech's C signatures runs with no
Python in the loop (what :mod:`conmech.symbolic` generates, C or Fortran ``bind(C)`` code
loaded with ctypes, numba ``cfunc``, ``scipy.LowLevelCallable``).

The C signatures (matrices column-major, ``p`` the run-time parameter array, so that one
compiled function serves every parameter value)::

    /* <generated: tools/generate_slots.py signatures> from the table conmech._core.slot_table */
    /* first-order systems (kind 'ode', n states) */
    /* dydt = f(t, y; p) */
    void rhs(double t, const double *y, double *dydt, const double *p);
    /* df/dy (column-major); without it finite differences (optional) */
    void jac(double t, const double *y, double *dfdy, const double *p);
    /* jx = J(t, y) x for an n x ncol block x (optional) */
    void jac_prod(double t, const double *y, int k, const double *x, double *jx,
                  const double *p);
    /* mechanical systems (nd coordinates, M(t, q) q'' = Q(t, q, q')) */
    /* the mass matrix M(t, q) */
    void mass(double t, const double *q, double *M, const double *p);
    /* the forces Q(t, q, q') */
    void forces(double t, const double *q, const double *v, double *Q, const double *p);
    /* [dQ/dq - d(M a)/dq, dQ/dv], the Jacobian of the force balance at accelerations a
       (optional) */
    void forces_jac(double t, const double *q, const double *v, const double *a,
                    double *R, const double *p);
    /* the energy (a first integral) (optional) */
    double energy(double t, const double *q, const double *v, const double *p);
    /* M and Q in one call (shared subexpressions) (optional) */
    void mass_forces(double t, const double *q, const double *v, double *M, double *Q,
                     const double *p);
    /* the accelerations a = M^-1 Q directly (e.g. the articulated-body algorithm);
       non-finite where M is not positive definite (optional) */
    void accel(double t, const double *q, const double *v, double *a, const double *p);
    /* a and its Jacobian d a/d[q, v] (ndof x 2 ndof) (optional) */
    void accel_jac(double t, const double *q, const double *v, double *a, double *jac,
                   const double *p);
    /* constrained systems (n coordinates; mass, forces, forces_jac, energy
       as above) */
    /* the holonomic constraints phi(t, q) (n_hol; required when n_hol > 0) (optional) */
    void phi(double t, const double *q, double *c, const double *p);
    /* G = dphi/dq (n_hol x n) (optional) */
    void phi_jac(double t, const double *q, double *G, const double *p);
    /* dphi/dt (rheonomic constraints) (optional) */
    void phi_t(double t, const double *q, double *pt, const double *p);
    /* gamma_h = -d/dt [G v + phi_t] at fixed v (optional) */
    void phi_gamma(double t, const double *q, const double *v, double *g,
                   const double *p);
    /* the Pfaffian constraints A(t, q) q' + b(t, q) = 0 (required when n_nh > 0)
       (optional) */
    void nh_matrix(double t, const double *q, double *A, double *b, const double *p);
    /* gamma_n = -d/dt [A v + b] at fixed v (optional) */
    void nh_gamma(double t, const double *q, const double *v, double *g, const double *p);
    /* hl = d(C^T lam)/dq, hv = d(C v + c0)/dq: with forces_jac the exact Jacobian of
       Radau IIA on the constrained equations (optional) */
    void constraint_hessian(double t, const double *q, const double *v, const double *lam,
                            double *hl, double *hv, const double *p);
    /* </generated> */

with ``gamma_h = -d/dt [G v + phi_t]`` and ``gamma_n = -d/dt [A v + b]`` at fixed v (the
acceleration-level right-hand sides of ``G q'' = gamma_h``, ``A q'' = gamma_n``). A missing
optional function falls back to conmech's finite-difference default.

Every function argument below is an int address, a ctypes function pointer, a numba
``cfunc`` or a ``scipy.LowLevelCallable``. ``keep`` holds whatever must stay alive while
the system is used (the loaded library, the numba functions); the returned objects hold
it. A wrong address cannot be detected: it crashes the process, as in any C code.
"""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import ctypes
import math
import os
import threading

import numpy as np

from .. import _conmech
from .._core import slot_table as _table
from .._core.elf import LibraryError, check_library
from .._core.native import NativeSystem, function_address
from .._core.status import raise_status
from .constrained import NativeConstrained

__all__ = ["ode_system", "generalized_system", "constrained_system", "CompiledSystem",
           "CompiledConstrained", "evaluate", "function_address", "load_model",
           "library_taylor", "LazyTaylor"]

_KIND_ODE, _KIND_GEN, _KIND_CON = (_table.KIND_ODE, _table.KIND_GENERALIZED,
                                   _table.KIND_CONSTRAINED)
_SPEC_SIZE = _table.SPEC_SIZE
_SLOTS = _table.SLOTS                   # function entries by name (conmech_<name>)
_TAYLOR_SLOTS = _table.TAYLOR_SLOTS     # the Taylor entries of the ``taylor`` dict
_TAYLOR_FUNCS = _table.TAYLOR_FUNCS


def _real(name, v):
    """float(v) for a real number v (a bool, a string, a complex or None is a TypeError
    naming the parameter)."""
    if isinstance(v, (bool, np.bool_, str, bytes)) or v is None or np.iscomplexobj(v):
        raise TypeError(f"parameter {name} must be a real number, got {v!r}")
    try:
        x = float(v)
    except (TypeError, ValueError, OverflowError):
        raise TypeError(f"parameter {name} must be a real number, got {v!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"parameter {name} must be finite, got {v!r}")
    return x


def _params(params, param_names):
    """(values, names) from a sequence or a dict of parameters."""
    if isinstance(params, dict):
        names = tuple(str(k) for k in params)
        values = [_real(k, v) for k, v in params.items()]
    else:
        if isinstance(params, (str, bytes)):
            raise TypeError("params must be a sequence of real numbers or a dict")
        flat = list(np.ravel(np.asarray(params, dtype=object))) if np.size(params) else []
        names = tuple(param_names) if param_names else tuple(f"p{i}" for i in
                                                             range(len(flat)))
        values = [_real(names[i] if i < len(names) else f"p{i}", v)
                  for i, v in enumerate(flat)]
    values = np.array(values, dtype=float).ravel()
    if len(names) != values.size:
        raise ValueError(f"param_names has {len(names)} names for {values.size} params")
    if len(set(names)) != len(names):
        raise ValueError("param_names must be distinct")
    for k, v in zip(names, values):
        if not math.isfinite(v):
            raise ValueError(f"parameter {k} must be finite, got {v}")
    return values, names


def _count(value, what, low):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{what} must be an integer")
    if value < low:
        raise ValueError(f"{what} must be >= {low}, got {value}")
    return int(value)


def _make_spec(kind, n, n_hol, n_nh, rheonomic, funcs):
    spec = np.zeros(_SPEC_SIZE, dtype=np.int64)
    for (_, slot), v in zip(_table.HEADER, (kind, n, n_hol, n_nh, int(bool(rheonomic)))):
        spec[slot - 1] = v
    for key, f in funcs.items():
        spec[_SLOTS[key] - 1] = function_address(f, key)
    return spec


def _with_params(obj, kw):
    values = dict(zip(obj.param_names, obj.params.tolist()))
    for k, v in kw.items():
        if k not in values:
            raise ValueError(f"unknown parameter {k!r} (known: {', '.join(obj.param_names)})")
        values[k] = _real(k, v)
    return np.array([values[k] for k in obj.param_names], dtype=float)


def _taylor_spec(spec, taylor):
    """Write the Taylor entries of `taylor` (a dict, see :func:`ode_system`) into spec."""
    if not taylor:
        return spec
    if not isinstance(taylor, dict):
        raise TypeError("taylor must be a dict (jet, nw, and optionally var, nw_var)")
    unknown = set(taylor) - set(_TAYLOR_SLOTS) - {"batch", "width", "batch_run", "qp", "model"}
    if unknown:
        raise ValueError(f"unknown taylor entries {sorted(unknown)}")
    for key, slot in _TAYLOR_SLOTS.items():
        v = taylor.get(key)
        if v is None:
            continue
        if key in _TAYLOR_FUNCS:
            spec[slot - 1] = function_address(v, f"taylor['{key}']")
        else:
            spec[slot - 1] = _count(v, f"taylor['{key}']", 0)
    if spec[_TAYLOR_SLOTS["jet"] - 1] and spec[_TAYLOR_SLOTS["nw"] - 1] < spec[1]:
        raise ValueError("taylor['nw'] (the work columns) must be at least n")
    return spec


class LazyTaylor:
    """The Taylor entries of a system (the ``taylor`` dict of :func:`ode_system`, or None),
    made when first asked for, part by part: ``build(part)`` returns the entries of a part
    ("core": ``jet`` and ``nw``; others, e.g. "var", "batch", "qp", their own entries), or
    None when the system has no Taylor recurrences. :mod:`conmech.symbolic` compiles a
    model's Taylor code only when a call runs Taylor's method, and only the part it needs.
    Each part is built once (under a lock, so that threads asking together build once); a
    failed build raises and is tried again at the next request."""

    __slots__ = ("_build", "_value", "_parts", "_lock")

    def __init__(self, build):
        if not callable(build):
            raise TypeError("LazyTaylor needs a callable that returns the taylor entries")
        self._build = build
        self._value = None
        self._parts = set()
        self._lock = threading.Lock()

    @property
    def built(self):
        """Whether the core entries have been made."""
        return "core" in self._parts

    def has(self, part):
        """Whether `part` has been made."""
        return part in self._parts

    def get(self, *parts):
        """The taylor dict with the core and `parts` (and those made before), or None when
        the system has no Taylor recurrences."""
        for part in ("core",) + parts:
            if part in self._parts:
                continue
            if part != "core" and self._value is None:
                break
            with self._lock:
                if part in self._parts:
                    continue
                value = self._build(part)
                if value is not None and not isinstance(value, dict):
                    raise TypeError("the Taylor build must return a dict or None")
                if value:
                    self._value = dict(self._value or {}, **value)
                self._parts.add(part)
        return self._value


class CompiledSystem(NativeSystem):
    """A first-order system (``kind`` 'ode') or a system in generalized coordinates
    (``kind`` 'generalized', state y = [q, q']) given by compiled functions. It works
    wherever a built-in system does: :func:`conmech.solve_ivp`, :mod:`conmech.stability`.
    Attributes: name, kind, dimension (state size), ndof (generalized only), params,
    param_names, spec (the function table handed to Fortran), taylor (the Taylor
    coefficient routines, a dict, or None; made on first access when the system was
    given a :class:`LazyTaylor`, whose entries then go into ``spec``)."""

    __slots__ = ("kind", "ndof", "_taylor")

    def __init__(self, name, kind, spec, params, param_names, keep, taylor=None):
        self.name = name
        self.kind = kind
        self.spec = spec
        self.params = params
        self.param_names = param_names
        self.ndof = int(spec[1]) if kind == "generalized" else None
        self.dimension = 2*self.ndof if kind == "generalized" else int(spec[1])
        self._keep = keep
        self._taylor = taylor

    @property
    def taylor(self):
        """The Taylor entries (a dict) or None. A lazy set (:class:`LazyTaylor`) makes its
        core here, at the first access, and its entries go into ``spec`` (shared with the
        copies of :meth:`with_params`, which share the lazy set too): the Taylor paths
        (``solve_ivp(method="TAYLOR")``, ``stm(method="TAYLOR")``, ensembles) read this
        attribute, or call :meth:`taylor_parts`, before they hand ``spec`` to Fortran."""
        return self.taylor_parts()

    def taylor_parts(self, *parts):
        """The Taylor entries with the lazy `parts` made ("var": the variational system,
        for stm; "batch": ensembles; "qp": quadruple precision), their entries in
        ``spec``; the entries as they are for a system given them at construction."""
        t = self._taylor
        if not isinstance(t, LazyTaylor):
            return t
        value = t.get(*parts)
        if value and (parts or not self.spec[_TAYLOR_SLOTS["jet"] - 1]):
            _taylor_spec(self.spec, value)
        return value

    @property
    def taylor_pending(self):
        """True while the Taylor entries are lazy and not built yet (no compilation has
        been asked for)."""
        return isinstance(self._taylor, LazyTaylor) and not self._taylor.built

    def with_params(self, **kw):
        """A copy with new values of some parameters (same compiled code: no rebuild)."""
        return CompiledSystem(self.name, self.kind, self.spec, _with_params(self, kw),
                              self.param_names, self._keep, self._taylor)

    def with_taylor(self, **entries):
        """A copy whose Taylor entries (see :func:`ode_system`) are updated (e.g. the
        routines written out for one order, ``jet_fixed`` and ``order``)."""
        taylor = dict(self.taylor or {})
        taylor.update(entries)
        spec = _taylor_spec(self.spec.copy(), taylor)
        extra = tuple(v for k, v in entries.items() if k in _TAYLOR_FUNCS)
        keep = (tuple(self._keep) if isinstance(self._keep, tuple) else (self._keep,)) + extra
        return CompiledSystem(self.name, self.kind, spec, self.params, self.param_names,
                              keep, taylor)

    def __repr__(self):
        args = ", ".join(f"{k}={v!r}" for k, v in self.parameters.items())
        return f"<compiled {self.kind} system {self.name!r} n={self.dimension} ({args})>"


class CompiledConstrained(NativeConstrained):
    """A constrained system in excessive coordinates given by compiled functions; it
    works with :func:`conmech.constrained.solve` like a built-in (every projection,
    multipliers, reactions, energy). q0 and v0 must be given to solve."""

    __slots__ = ("param_names",)

    def __init__(self, name, spec, params, param_names, keep):
        self.name = name
        self.spec = spec
        self.params = params
        self.param_names = param_names
        self.n, self.n_hol, self.n_nh = int(spec[1]), int(spec[2]), int(spec[3])
        self._keep = keep

    @property
    def parameters(self):
        """The parameters as a dict (name -> value)."""
        return dict(zip(self.param_names, self.params.tolist()))

    def with_params(self, **kw):
        """A copy with new values of some parameters (same compiled code: no rebuild)."""
        return CompiledConstrained(self.name, self.spec, _with_params(self, kw),
                                   self.param_names, self._keep)

    def initial_state(self):
        raise ValueError(f"the compiled system {self.name!r} has no default initial state: "
                         "pass q0 and v0")

    def __repr__(self):
        return (f"<compiled constrained system {self.name!r} n={self.n} n_hol={self.n_hol} "
                f"n_nh={self.n_nh}>")


def ode_system(n: int, rhs, jac=None, params: Sequence[float] | dict = (),
               param_names: Sequence[str] = (), keep=None,
               name: str = "compiled", *, jac_prod=None, taylor=None) -> CompiledSystem:
    """A first-order system y' = rhs(t, y; p) of dimension ``n`` from compiled functions
    (``jac``: the exact Jacobian df/dy, column-major; None: finite differences).
    ``params``: a sequence (names from ``param_names``) or a dict name -> value.
    ``jac_prod`` (optional), ``void jac_prod(double t, const double *y, int k, const double
    *x, double *jx, const double *p)``, gives jx = J(t, y) x for an n x k block x
    (column-major): the variational equations (:func:`conmech.stability.stm`,
    ``monodromy``, shooting) then evaluate J Phi through it without forming J. It must
    agree with ``jac``.

    ``taylor`` (optional) gives the normalized Taylor coefficients of the solution for
    ``method="TAYLOR"``, a dict: ``jet``, ``void taylor(double t, int order, double *w,
    const double *p)`` (w an (order + 1) x nw column-major array; on entry w[0, i] = y_i,
    on exit column i holds y_i^[0..order]), ``nw`` (its work columns, >= n), and
    optionally ``var``/``nw_var`` (the same for the variational system [f; J Phi], state
    n + n**2), ``jet_fixed``/``order`` (a routine written out for one order),
    ``batch``/``width`` (members in the fastest dimension) and ``qp`` (quadruple
    precision); :mod:`conmech.symbolic` generates them. A :class:`LazyTaylor` instead of
    the dict defers them to the first access of the system's ``taylor``."""
    n = _count(n, "n", 1)
    values, names = _params(params, param_names)
    spec = _make_spec(_KIND_ODE, n, 0, 0, False, {"rhs": rhs, "jac": jac,
                                                  "jac_prod": jac_prod})
    if spec[_SLOTS["rhs"] - 1] == 0:
        raise ValueError("rhs is required")
    if isinstance(taylor, LazyTaylor):
        # built at the first access of CompiledSystem.taylor (a Taylor call)
        return CompiledSystem(str(name), "ode", spec, values, names,
                              (keep, rhs, jac, jac_prod, taylor), taylor)
    spec = _taylor_spec(spec, taylor)
    return CompiledSystem(str(name), "ode", spec, values, names,
                          (keep, rhs, jac, jac_prod, taylor), dict(taylor) if taylor else None)


def generalized_system(ndof: int, mass, forces, forces_jac=None, energy=None,
                       params: Sequence[float] | dict = (), param_names: Sequence[str] = (),
                       keep=None, name: str = "compiled", *,
                       mass_forces=None, accel=None, accel_jac=None) -> CompiledSystem:
    """M(t, q) q'' = Q(t, q, q') with ``ndof`` coordinates from compiled functions; the
    state is y = [q, q']. ``forces_jac`` gives the exact Jacobian of the accelerations
    (see the module's signatures); without it the Jacobian is a finite difference.
    ``mass_forces`` (optional), ``void mass_forces(double t, const double *q, const double
    *v, double *M, double *Q, const double *p)``, computes M and Q in one call (the
    right-hand side then uses it instead of ``mass`` + ``forces``); it must give the same
    values as the two. ``accel`` (optional), ``void accel(double t, const double *q, const
    double *v, double *a, const double *p)``, computes the accelerations a = M^-1 Q directly
    (e.g. by the articulated-body algorithm of :func:`conmech.symbolic.planar_tree`); the
    right-hand side then uses it instead of factorising M (non-finite output, e.g. where
    M is not positive definite, stops the integration with success=False). ``accel_jac``
    (optional), ``void accel_jac(double t, const double *q, const double *v, double *a,
    double *jac, const double *p)``, computes the accelerations and their Jacobian
    jac = d a/d[q, v] (ndof x 2 ndof, column-major) directly (e.g. from the derivatives of
    the recursive algorithms of :func:`conmech.symbolic.spatial_tree`); the Jacobian of the
    system then uses it instead of ``forces_jac`` and a factorisation of M."""
    ndof = _count(ndof, "ndof", 1)
    values, names = _params(params, param_names)
    if mass is None or forces is None:
        raise ValueError("mass and forces are required")
    spec = _make_spec(_KIND_GEN, ndof, 0, 0, False, {"mass": mass, "forces": forces,
                                                     "forces_jac": forces_jac,
                                                     "energy": energy,
                                                     "mass_forces": mass_forces,
                                                     "accel": accel, "accel_jac": accel_jac})
    return CompiledSystem(str(name), "generalized", spec, values, names,
                          (keep, mass, forces, forces_jac, energy, mass_forces, accel,
                           accel_jac))


def constrained_system(n: int, mass, forces, n_hol: int = 0, n_nh: int = 0, phi=None,
                       phi_jac=None, phi_t=None, phi_gamma=None, nh_matrix=None, nh_gamma=None,
                       energy=None, rheonomic: bool = False,
                       params: Sequence[float] | dict = (), param_names: Sequence[str] = (),
                       keep=None, name: str = "compiled", *, forces_jac=None,
                       constraint_hessian=None, redundant: bool = False
                       ) -> CompiledConstrained:
    """A constrained system in excessive coordinates from compiled functions: ``n``
    coordinates, ``n_hol`` holonomic constraints phi(t, q) = 0 and ``n_nh`` Pfaffian
    constraints A(t, q) q' + b(t, q) = 0. Missing phi_jac, phi_t, phi_gamma, nh_gamma
    fall back to finite differences (phi_t only when ``rheonomic``); so do the optional
    ``forces_jac`` and ``constraint_hessian`` (the derivatives behind the Jacobian of
    ``method="Radau"``; see the module's signatures). ``redundant=True`` admits n_hol +
    n_nh >= n: constraints known to be dependent, as the loop equations of an
    over-constrained mechanism (Bricard's: as many as its joint coordinates, one degree
    of freedom), whose motion the rank-revealing KKT solve finds."""
    n = _count(n, "n", 1)
    n_hol = _count(n_hol, "n_hol", 0)
    n_nh = _count(n_nh, "n_nh", 0)
    if n_hol + n_nh >= n and not redundant:
        raise ValueError(f"n_hol + n_nh = {n_hol + n_nh} constraints leave no motion for "
                         f"n = {n} coordinates")
    if mass is None or forces is None:
        raise ValueError("mass and forces are required")
    if n_hol > 0 and phi is None:
        raise ValueError("phi is required when n_hol > 0")
    if n_nh > 0 and nh_matrix is None:
        raise ValueError("nh_matrix is required when n_nh > 0")
    values, names = _params(params, param_names)
    funcs = dict(mass=mass, forces=forces, energy=energy, phi=phi, phi_jac=phi_jac,
                 phi_t=phi_t, phi_gamma=phi_gamma, nh_matrix=nh_matrix, nh_gamma=nh_gamma,
                 forces_jac=forces_jac, constraint_hessian=constraint_hessian)
    spec = _make_spec(_KIND_CON, n, n_hol, n_nh, rheonomic, funcs)
    return CompiledConstrained(str(name), spec, values, names, (keep, tuple(funcs.values())))


def _check(info, message):
    if info != 0:
        raise_status(info, message)


def evaluate(system: Any, t: float, y: ArrayLike, v: ArrayLike | None = None) -> dict:
    """The quantities of a built-in or compiled system at one state, as a dict.

    - first-order systems (:class:`conmech.systems.NativeSystem`: built-in, or compiled
      'ode' or 'generalized'), ``evaluate(system, t, y)``: ``f`` and ``jac`` (``analytic`` tells
      whether the Jacobian is exact);
    - mechanical systems, ``evaluate(system, t, q, v)``: ``M``, ``Q``, ``energy`` (None if
      undefined), and for constrained systems ``phi``, ``G``, ``gamma_h``, ``A``, ``b``,
      ``gamma_n``. Generalized-coordinate systems (built-in by name, e.g.
      ``conmech.systems.cart_pendulum()``, or compiled) give M and Q this way too.
    """
    t = float(t)
    y = np.ascontiguousarray(np.asarray(y, dtype=float).ravel())
    if not isinstance(system, (NativeSystem, NativeConstrained)):
        raise TypeError("system must be a built-in or compiled conmech system")
    name, np_, p, nspec, spec = system._flat_args()
    if v is None:
        if not isinstance(system, NativeSystem):
            raise ValueError("a constrained system needs q and v: evaluate(system, t, q, v)")
        f, jac, analytic, info, message = _conmech.flat_evaluate_ode(
            name, np_, p, nspec, spec, t=t, y=y)
        _check(info, message)
        return dict(f=np.array(f), jac=np.array(jac), analytic=bool(analytic))
    v = np.ascontiguousarray(np.asarray(v, dtype=float).ravel())
    if v.size != y.size:
        raise ValueError(f"q and v must have the same size, got {y.size} and {v.size}")
    kind, n, mh, mn, info, message = _conmech.flat_mech_info(name, np_, p, nspec, spec)
    _check(info, message)
    if kind not in (1, 2):
        raise ValueError(f"{name!r} is not a mechanical system")
    if n != y.size:
        raise ValueError(f"q has {y.size} components; the system has {n}")
    out = _conmech.flat_evaluate_mech(name, np_, p, nspec, spec, kind=kind, mh=mh, mn=mn, t=t,
                                      q=y, v=v)
    mm, qf, energy, has_e, phi, g, gh, a, b, gn, info, message = out
    _check(info, message)
    res = dict(M=np.array(mm), Q=np.array(qf), energy=float(energy) if has_e else None)
    if kind == 1:
        res.update(phi=np.array(phi)[:mh], G=np.array(g)[:mh], gamma_h=np.array(gh)[:mh],
                   A=np.array(a)[:mn], b=np.array(b)[:mn], gamma_n=np.array(gn)[:mn])
    return res


def library_taylor(lib):
    """The Taylor entries of a loaded library (``conmech_taylor``, ``conmech_taylor_info``
    and their variants, as :mod:`conmech.symbolic` generates them), as the ``taylor`` dict
    of :func:`ode_system`; None if the library has none."""
    if getattr(lib, "conmech_taylor", None) is None or \
            getattr(lib, "conmech_taylor_info", None) is None:
        return None
    info = (ctypes.c_int*4)()
    lib.conmech_taylor_info(info)
    out = {"jet": lib.conmech_taylor, "nw": int(info[0])}
    if info[1] > 0 and getattr(lib, "conmech_taylor_batch", None) is not None:
        out.update(batch=lib.conmech_taylor_batch, width=int(info[1]))
    if info[3] and getattr(lib, "conmech_taylor_qp", None) is not None:
        out["qp"] = lib.conmech_taylor_qp
    if getattr(lib, "conmech_taylor_var", None) is not None and \
            getattr(lib, "conmech_taylor_var_info", None) is not None:
        lib.conmech_taylor_var_info(info)
        out.update(var=lib.conmech_taylor_var, nw_var=int(info[0]))
    return out


def load_model(path, name: str | None = None) -> CompiledSystem | CompiledConstrained:
    """A system from a model library: a shared library that exports, with C linkage,
    ``conmech_model_info(int info[6])`` (kind 1 ode / 2 generalized / 3 constrained, n,
    n_hol, n_nh, rheonomic, number of parameters), ``conmech_model_params(double *p)``
    (defaults), ``conmech_model_param_names(char *buf, int len)`` (blank-separated) and the
    functions of its kind named ``conmech_rhs``, ``conmech_jac``, ``conmech_mass``,
    ``conmech_forces``, ``conmech_forces_jac``, ``conmech_energy``, ``conmech_phi``,
    ``conmech_phi_jac``, ``conmech_phi_t``, ``conmech_phi_gamma``, ``conmech_nh_matrix``,
    ``conmech_nh_gamma`` (and optionally ``conmech_mass_forces``, ``conmech_accel``,
    ``conmech_accel_jac``, ``conmech_jac_prod``, ``conmech_constraint_hessian``, and the
    Taylor routines ``conmech_taylor``, ``conmech_taylor_info``, ... of
    :func:`library_taylor`). The Fortran programs load the same libraries (``sweep
    --model``, conmech_model_library)."""
    path = os.fspath(path)
    try:
        # before dlopen: a truncated library would be mapped past its end (SIGBUS at the
        # first access), a foreign file gives an obscure error
        check_library(path, ["conmech_model_info"])
        lib = ctypes.CDLL(os.path.abspath(path) if os.sep not in path else path)
    except LibraryError as e:
        raise ValueError(f"cannot load the model library {path!r}: {e.reason}") from None
    except OSError as e:
        raise ValueError(f"cannot load the model library {path!r}: {e}") from None
    info = (ctypes.c_int*6)()
    lib.conmech_model_info(info)
    kind, n, n_hol, n_nh, rheo, npar = list(info)
    if kind not in (1, 2, 3) or not 1 <= n <= 1000000 or not 0 <= npar <= 4096 \
            or not 0 <= n_hol <= n or not 0 <= n_nh <= n:
        raise ValueError(f"{path!r}: invalid description from conmech_model_info "
                         f"(kind {kind}, n {n}, n_hol {n_hol}, n_nh {n_nh}, {npar} "
                         "parameters)")
    p = (ctypes.c_double*max(npar, 1))()
    if npar:
        if not hasattr(lib, "conmech_model_params"):
            raise ValueError(f"{path!r} has {npar} parameters but no conmech_model_params")
        lib.conmech_model_params(p)
    names = ()
    if hasattr(lib, "conmech_model_param_names"):
        buf = ctypes.create_string_buffer(4096)
        lib.conmech_model_param_names(buf, ctypes.c_int(4096))
        names = tuple(buf.value.decode("utf-8", "replace").split())
    if len(names) != npar:
        names = tuple(f"p{i}" for i in range(npar))
    params = dict(zip(names, list(p)[:npar]))
    kind_name = {v: k for k, v in _table.KINDS.items()}[kind]
    fn = {k: getattr(lib, "conmech_" + k, None) for k in _table.ENTRY_POINTS[kind_name]}
    name = name or str(path)
    if kind == _KIND_ODE:
        return ode_system(n, params=params, keep=lib, name=name, taylor=library_taylor(lib),
                          **fn)
    if kind == _KIND_GEN:
        return generalized_system(n, params=params, keep=lib, name=name, **fn)
    return constrained_system(n, n_hol=n_hol, n_nh=n_nh, rheonomic=bool(rheo), params=params,
                              keep=lib, name=name, **fn)
