"""Systems that conmech evaluates in native code, with no Python in the loop.

:class:`NativeSystem` is what the integrators and the stability routines accept as a
first-order system that runs in Fortran: the flat layer reaches it by a registry name or a
``spec`` (a table of compiled function addresses). Its two kinds:

- :class:`BuiltinSystem`: one of conmech's own systems, by its name in the Fortran
  registry (the factories of :mod:`conmech.systems` make them);
- :class:`conmech.compiled.CompiledSystem`: a system given by compiled functions
  (:mod:`conmech.compiled`, :mod:`conmech.symbolic`).

The constrained systems have the same split (:class:`conmech.constrained.NativeConstrained`,
``BuiltinConstrained``, ``CompiledConstrained``).
"""
import ctypes

import numpy as np

from .. import _conmech
from .builtin_table import PARAMS, POSITIVE_PARAMS, RANGE_PARAMS

_PAD = np.zeros(1)
_NO_SPEC = np.zeros(1, dtype=np.int64)   # spec kind 0: a built-in system, by name


def _unused_callback(t, y):
    """The placeholder call-back of the flat argument set where a role has no Python
    function (f2py needs a callable for every call-back argument; conmech_flat_system
    never calls it)."""
    raise RuntimeError("a placeholder call-back of the flat layer was called")


__all__ = ["NativeSystem", "BuiltinSystem", "check_params", "function_address"]


def check_params(name, params):
    """ValueError naming a parameter of the built-in ``name`` that is out of its range, or
    more parameters than the system has (missing trailing ones keep their defaults)."""
    known = PARAMS.get(name)
    if known is not None and params.size > len(known):
        raise ValueError(f"params: {params.size} values given for the system '{name}', "
                         f"which has {len(known)} ({', '.join(p for p, _ in known)})")
    for i, pname in POSITIVE_PARAMS.get(name, {}).items():
        if i < params.size and not params[i] > 0:
            raise ValueError(f"{pname} of the system '{name}' must be positive, got "
                             f"{params[i]:g}")
    for i, (pname, lo, hi) in RANGE_PARAMS.get(name, {}).items():
        if i < params.size and not lo <= params[i] <= hi:
            raise ValueError(f"{pname} of the system '{name}' must be in [{lo:g}, {hi:g}], "
                             f"got {params[i]:g}")


class NativeSystem:
    """A first-order system y' = f(t, y) evaluated in native code (a built-in of the
    Fortran registry or compiled functions): attributes name, params, param_names,
    dimension (state size) and spec (the function table handed to Fortran; empty for a
    built-in)."""

    __slots__ = ("name", "params", "param_names", "dimension", "spec", "_keep")

    def _flat_args(self):
        """(name, np, params, nspec, spec): the leading arguments of the flat routines
        that build a system (built-in by name, or compiled from its spec)."""
        p = self.params if self.params.size else _PAD
        nspec = self.spec.size if self.spec is not _NO_SPEC else 0
        return self.name, self.params.size, p, nspec, self.spec

    def _system_args(self):
        """The one system argument set of the flat routines (conmech_flat_system): the
        leading arguments above, no Python call-backs, source 0."""
        return (*self._flat_args(), _unused_callback, _unused_callback, 0)

    @property
    def parameters(self):
        """The parameters as a dict (name -> value)."""
        names = self.param_names or tuple(f"p{i}" for i in range(self.params.size))
        return dict(zip(names, self.params.tolist()))

    @property
    def degrees_of_freedom(self):
        """The number of generalized coordinates of a mechanical system in generalized
        coordinates (its holonomic constraints eliminated); None for a first-order system
        without mechanical structure."""
        kind, n, mh, mn, info, _ = _conmech.flat_mech_info(*self._flat_args())
        return int(n) if info == 0 and kind == 2 else None

    def energy(self, y, t=0.0):
        """The energy (first integral) at the state y (time t): T + U of the mechanical
        systems y = [q, q'] (built-in, compiled and symbolic Lagrangian systems; the Jacobi
        integral when the Lagrangian depends on time or has gyroscopic terms), the Jacobi
        integral of the rotating-frame problems (arenstorf, cr3bp: C = 2 Omega - |v|^2;
        hill, hill_spatial: |v|^2 - 2 F), the energy of harmonic, pendulum and kepler.
        ValueError for a system without one (vanderpol, a compiled first-order system), or
        y of the wrong size. A (k, n) array of states gives k energies."""
        ys = np.asarray(y, dtype=float)
        if ys.ndim == 2:
            return np.array([self.energy(row, t) for row in ys])
        ys = np.ascontiguousarray(ys.ravel())
        if ys.size != self.dimension:
            raise ValueError(f"y has {ys.size} components; the system '{self.name}' has "
                             f"{self.dimension}")
        if not np.all(np.isfinite(ys)):
            raise ValueError("y must be finite")
        name, np_, p, nspec, spec = self._flat_args()
        e, info, message = _conmech.flat_system_energy(name, np_, p, nspec, spec, float(t),
                                                       ys)
        if info != 0:
            msg = bytes(message).decode("ascii", "replace").strip() if not isinstance(
                message, str) else message.strip()
            raise ValueError(f"{msg} (system '{self.name}')")
        return float(e)

    @property
    def has_energy(self):
        """Whether :meth:`energy` is defined for this system."""
        try:
            self.energy(np.full(self.dimension, 0.5))
        except ValueError:
            return False
        return True


class BuiltinSystem(NativeSystem):
    """One of conmech's built-in first-order systems (or a system in generalized
    coordinates as a first-order one, y = [q, q']), identified by name and parameters.

    Parameters
    ----------
    name : str
        Name in the Fortran registry (``make_system``).
    params : sequence of float
        Parameters in the registry's order (missing trailing ones keep their defaults).
    param_names : sequence of str, optional
        Names of the parameters, for ``repr`` and ``parameters``.
    """

    __slots__ = ()

    def __init__(self, name, params=(), param_names=()):
        if not isinstance(name, str) or not name:
            raise TypeError("name must be a non-empty string")
        params = np.array(params, dtype=float).ravel()
        if not np.all(np.isfinite(params)):
            raise ValueError(f"params of the system '{name}' must be finite")
        check_params(name, params)
        param_names = tuple(param_names)
        if param_names and len(param_names) != params.size:
            raise ValueError("param_names must match params in length")
        dim = int(_conmech.flat_system_dimension(name))
        if dim <= 0:
            raise ValueError(f"unknown built-in system '{name}'")
        self.name = name
        self.params = params
        self.param_names = param_names
        self.dimension = dim
        self.spec = _NO_SPEC
        self._keep = None

    def __repr__(self):
        args = ", ".join(f"{k}={v!r}" for k, v in self.parameters.items())
        return f"conmech.systems.{self.name}({args})"


def function_address(f, what: str = "function") -> int:
    """The address of a compiled function: an int, a ctypes function pointer or
    ``c_void_p``, a numba ``cfunc`` (its ``address``) or a ``scipy.LowLevelCallable``.
    None gives 0 (absent)."""
    if f is None:
        return 0
    if isinstance(f, bool):
        raise TypeError(f"{what} must be a compiled function or an address, got a bool")
    if isinstance(f, (int, np.integer)):
        addr = int(f)
    elif isinstance(f, ctypes._CFuncPtr):
        addr = ctypes.cast(f, ctypes.c_void_p).value or 0
    elif isinstance(f, ctypes.c_void_p):
        addr = f.value or 0
    elif type(f).__name__ == "LowLevelCallable":
        cap = tuple.__getitem__(f, 0)   # the PyCapsule (a LowLevelCallable is a tuple)
        get_name = ctypes.pythonapi.PyCapsule_GetName
        get_name.restype, get_name.argtypes = ctypes.c_char_p, [ctypes.py_object]
        get_ptr = ctypes.pythonapi.PyCapsule_GetPointer
        get_ptr.restype, get_ptr.argtypes = ctypes.c_void_p, [ctypes.py_object,
                                                              ctypes.c_char_p]
        addr = get_ptr(cap, get_name(cap)) or 0
    elif isinstance(getattr(f, "address", None), int):      # numba cfunc
        addr = f.address
    else:
        raise TypeError(f"{what} must be an address (int), a ctypes function, a numba "
                        f"cfunc or a scipy.LowLevelCallable, got {type(f).__name__}")
    if addr <= 0:
        raise ValueError(f"{what} is a null function pointer")
    return addr
