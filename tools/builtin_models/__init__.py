"""The built-in systems of conmech, each written once as a model.

A model file (one per system, named after the system) defines ``SYSTEM``: one of

- :class:`Ode`: y' = f(t, y) (first-order), the exact Jacobian derived from f;
- :class:`Lagrangian`: generalized coordinates q, L = T - U (and generalized forces);
  M, Q, the Jacobian of the accelerations and the energy derived from L;
- :class:`Constrained`: excessive coordinates q, T, U, holonomic constraints phi(t, q) = 0
  and Pfaffian ones A(t, q) q' + b(t, q) = 0; M, Q, G, the gamma terms and the energy
  derived from them;
- :class:`Handwritten`: a system whose Fortran is written by hand because it is faster or
  special; the model file then declares only what the registries need (parameters,
  defaults, validity, coordinates, how the registry makes it).

Every model declares its parameters (:class:`Param`: name, default, validity), the names of
its coordinates, and for mechanical systems a default initial state (q0, v0) as expressions
of the parameters (consistent with the constraints). ``tools/generate_builtins.py`` derives
the equations with :mod:`conmech.symbolic` and writes the Fortran types, the registries and
the Python factories. Nothing here is imported by the library at run time.

The order of the registries (the names the programs list) is the order of the lists below;
a new system is a model file plus its name in one of them.
"""
import importlib
import importlib.util
from pathlib import Path

import sympy as sp

__all__ = ["Param", "Ode", "Lagrangian", "Constrained", "Handwritten", "FIRST_ORDER",
           "GENERALIZED", "CONSTRAINED", "load", "load_file", "load_all"]

#: first-order systems (``make_system``; the generalized ones are first-order too, y = [q, v])
FIRST_ORDER = ["harmonic", "pendulum", "kepler", "arenstorf", "vanderpol", "hill",
               "hill_spatial", "cr3bp"]
#: systems in generalized coordinates (``make_generalized``)
GENERALIZED = ["pendulum_angle", "cart_pendulum", "double_pendulum", "atwood",
               "spring_pendulum", "double_spring_pendulum", "three_springs", "bead_hoop",
               "polar_particle", "pendulum_moving", "yoyo_angle"]
#: constrained systems in excessive coordinates (``make_constrained``)
CONSTRAINED = ["pendulum_xy", "rod_two_masses", "double_pendulum_xy", "atwood_xy",
               "pendulum_moving_xy", "yoyo", "skate", "rolling_disk", "pendulum_chain_xy",
               "rolling_ball"]


class Param:
    """A parameter: ``name`` (the Python keyword and the registry's documented name),
    ``default``, ``component`` (its Fortran component, when ``name`` does not do: Fortran
    is case-insensitive), ``positive`` (the system is singular or meaningless otherwise),
    ``interval`` (lo, hi) (a closed interval it must lie in), ``whole`` (a whole number
    within ``interval``), ``doc``."""

    def __init__(self, name, default, doc="", component=None, positive=False, interval=None,
                 whole=False):
        self.name = name
        self.default = float(default)
        self.doc = doc
        self.component = component or name
        self.positive = positive
        self.interval = interval
        self.whole = whole
        self.symbol = sp.Symbol(name, real=True)


class _Model:
    kind = None
    generated = True

    def __init__(self, name, type_name, summary, params, coords, module=None):
        self.name = name
        self.type_name = type_name
        self.summary = summary
        self.params = list(params)
        self.coords = list(coords)
        self.module = module or f"conmech_builtin_{name}"
        self.doc = ""          # the model file's docstring (set by load)
        self.source = ""       # the model file, relative to the repository

    @property
    def symbols(self):
        return [p.symbol for p in self.params]


class Ode(_Model):
    """y' = f(t, y): ``f`` (expressions in ``y``, the parameter symbols and ``t``), ``y``
    (Symbols), ``energy`` (an expression of y, or None: a pure type-bound
    ``energy(y)``), ``jacobian_product`` (also generate the structure-aware J x)."""
    kind = "ode"

    def __init__(self, name, type_name, summary, params, y, f, coords, energy=None,
                 jacobian_product=False, module=None):
        super().__init__(name, type_name, summary, params, coords, module)
        self.y = list(y)
        self.f = list(f)
        self.energy = energy
        self.jacobian_product = jacobian_product


class Lagrangian(_Model):
    """M(t, q) q'' = Q(t, q, q') from L = T - U: ``q`` and ``v`` (Symbols of the
    coordinates and their velocities), ``T``, ``U``, ``forces`` (generalized forces not from
    U, or None), ``q0``, ``v0`` (default initial state, expressions of the parameters),
    ``energy`` (generate the Jacobi integral: where it is conserved, L free of t). The
    exact Jacobian of the accelerations is always generated."""
    kind = "generalized"

    def __init__(self, name, type_name, summary, params, q, v, T, U, q0, v0, coords=None,
                 forces=None, energy=True, module=None):
        super().__init__(name, type_name, summary, params,
                         coords or [str(s) for s in q], module)
        self.q, self.v = list(q), list(v)
        self.T, self.U = T, U
        self.forces = forces
        self.q0, self.v0 = list(q0), list(v0)
        self.energy = energy


class Constrained(_Model):
    """Excessive coordinates with constraints: ``q``, ``v``, ``T``, ``U``, ``holonomic``
    (expressions phi(t, q), scaled so that the multipliers are the physical ones),
    ``nonholonomic`` (expressions A(t, q) v + b(t, q), linear in v), ``q0``, ``v0``,
    ``energy`` (generate T + U; only where it is meaningful)."""
    kind = "constrained"

    def __init__(self, name, type_name, summary, params, q, v, T, U, q0, v0, holonomic=(),
                 nonholonomic=(), coords=None, energy=True, module=None):
        super().__init__(name, type_name, summary, params,
                         coords or [str(s) for s in q], module)
        self.q, self.v = list(q), list(v)
        self.T, self.U = T, U
        self.holonomic = list(holonomic)
        self.nonholonomic = list(nonholonomic)
        self.q0, self.v0 = list(q0), list(v0)
        self.energy = energy


class Handwritten(_Model):
    """A system whose Fortran type is written by hand (``module``, ``type_name``), of kind
    "ode", "generalized" or "constrained". The registries make it with ``make`` (Fortran
    statements with ``params`` the parameter array, ``info``/``msg`` the status, and the
    result allocated into ``sys`` (ode, constrained) or ``mech`` (generalized)); None: a
    local of the type with the parameters assigned to their components. ``initial``
    (Fortran statements setting q0, v0 from ``params``, ``info`` on bad input) gives the
    default initial state of a mechanical system. ``size`` is the number of coordinates
    (first-order systems: of state variables), None when it depends on the parameters.
    ``python_factory``: the body of the Python factory when the generic one does not do."""
    generated = False

    def __init__(self, name, type_name, kind, summary, params, coords, module, size,
                 make=None, initial=None, python_factory=None):
        super().__init__(name, type_name, summary, params, coords, module)
        self.kind = kind
        self.size = size
        self.make = make
        self.initial = initial
        self.python_factory = python_factory


def load(name):
    """The model of the built-in system ``name`` (its file builtin_models/NAME.py)."""
    mod = importlib.import_module(f"{__name__}.{name}")
    sysm = mod.SYSTEM
    if sysm.name != name:
        raise ValueError(f"builtin_models/{name}.py declares the system '{sysm.name}'")
    sysm.doc = (mod.__doc__ or "").strip()
    sysm.source = f"tools/builtin_models/{name}.py"
    return sysm


def load_file(path):
    """The model defined in the file `path` (anywhere: e.g. a system tried out before it is
    added to this folder); it imports its declarations from ``builtin_models``."""
    path = Path(path)
    spec = importlib.util.spec_from_file_location(f"{__name__}._file_{path.stem}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    sysm = mod.SYSTEM
    sysm.doc = (mod.__doc__ or "").strip()
    sysm.source = path.name
    return sysm


def load_all():
    """{kind: [models in registry order]} for the kinds "ode", "generalized",
    "constrained"."""
    return {"ode": [load(n) for n in FIRST_ORDER],
            "generalized": [load(n) for n in GENERALIZED],
            "constrained": [load(n) for n in CONSTRAINED]}
