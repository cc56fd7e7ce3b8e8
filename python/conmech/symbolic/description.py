"""The description cache: a second construction of the same multibody tree or URDF robot,
in a new process, loads its compiled model without deriving anything.

The derivation cache of :func:`conmech.symbolic.pipeline._construct` is keyed by the sympy inputs
of a construction (the tree's validated bodies, forces and loops as sympy objects): for a
tree or a robot, building those inputs (parsing the URDF into sympy records, validating
the bodies, printing them for the key) costs more than loading the cached model itself.
Here the key is taken from the description as the user gives it, before any of that:

- a tree (:func:`~conmech.symbolic.planar_tree`, :func:`~conmech.symbolic.spatial_tree`):
  every field of every body, the gravity, the forces, the loops and point forces, the
  parameters (names and values, in order), the options (coordinates, method, simplify,
  jacobian, flags);
- a URDF robot (:func:`~conmech.symbolic.from_urdf`): the document's text and every
  argument of the call;

together with the versions of the code generators (``CODEGEN_VERSION``, the digest of the
recursive generator's modules) and of conmech. Sympy objects enter through ``srepr``
(their exact structure), numbers through ``repr``; anything else (a callable, an object
of another kind) makes the description uncacheable and the construction takes the
ordinary path. A description entry, ``conmech_desc_DKEY.json``, written after a successful
construction, names the derivation-cache entry and the parameter values it was built with
(for a robot: the values its URDF sets, such as damping). A tree's parameter values are
part of its key (new values take the ordinary path once, which checks them, e.g. for a
negative mass, and finds the derivation in the derivation cache); ``with_params`` changes
them without any construction. Entries are trusted only as the rest of the cache (owned by
the user, writable by nobody else).
"""
import hashlib
import json
import os
import time

__all__ = ["tree_description_key", "urdf_description_key", "description_hit",
           "store_description"]


class _NotPlain(Exception):
    """A value the description cannot represent exactly."""


def _plain(x):
    """A canonical, process-independent representation of x (nested tuples of tagged
    strings); _NotPlain for what has none."""
    import numpy as np
    import sympy as sp
    if x is None or isinstance(x, (bool, str)):
        return (type(x).__name__, x)
    if isinstance(x, (int, np.integer)):
        return ("int", int(x))
    if isinstance(x, (float, np.floating)):
        return ("float", repr(float(x)))
    if isinstance(x, sp.MatrixBase):
        return ("matrix", x.shape, tuple(_plain(e) for e in x))
    if isinstance(x, sp.Basic):
        return ("sympy", sp.srepr(x))
    if isinstance(x, dict):
        return ("dict", tuple((_plain(k), _plain(v)) for k, v in x.items()))
    if isinstance(x, (list, tuple)):
        return ("seq", tuple(_plain(e) for e in x))
    if isinstance(x, np.ndarray) and x.dtype.kind in "biuf":
        return ("array", x.shape, tuple(repr(float(e)) for e in x.ravel()))
    raise _NotPlain(type(x).__name__)


def _versions():
    from .build import _conmech_version
    from .codegen import CODEGEN_VERSION
    from .recursive import recursive_version
    return (CODEGEN_VERSION, recursive_version(), _conmech_version())


def _digest(kind, parts):
    text = repr((kind, parts, _versions()))
    return hashlib.sha256(text.encode()).hexdigest()


def _param_names(params):
    """The parameter names and values in order, or _NotPlain when the values are not
    plain numbers (then the ordinary path reports the problem). The values are part of
    the key although the generated code does not depend on them: the checks of the
    ordinary path that depend on them (a negative mass, a leaf without inertia) then run
    for every new set of values."""
    import numpy as np
    import sympy as sp
    if params is None:
        return ()
    if not isinstance(params, dict):
        raise _NotPlain("params")
    names = []
    for k, v in params.items():
        if isinstance(k, sp.Symbol):
            names.append(k.name)
        elif isinstance(k, str):
            names.append(k)
        else:
            raise _NotPlain("params key")
        if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
            raise _NotPlain("params value")
        names.append(repr(float(v)))
    return tuple(names)


def _records(items, slots):
    out = []
    if items is None:
        return None
    seq = [items] if hasattr(items, "__slots__") else list(items)
    for it in seq:
        if not hasattr(it, "__slots__"):
            raise _NotPlain(type(it).__name__)
        out.append((type(it).__name__,) + tuple(_plain(getattr(it, s)) for s in slots(it)))
    return tuple(out)


def tree_description_key(kind, bodies, params, gravity, forces, loops, point_forces,
                         options, flags):
    """The description key of a tree construction (None: not cacheable this way).
    `options`: a tuple of the remaining keyword arguments that shape the generated code
    (coordinates, method, simplify, jacobian)."""
    try:
        parts = (_records(bodies, lambda b: type(b).__slots__), _param_names(params),
                 _plain(gravity), _plain(forces),
                 _records(loops, lambda b: type(b).__slots__),
                 _records(point_forces, lambda b: type(b).__slots__),
                 _plain(options), _plain(flags))
    except _NotPlain:
        return None
    return _digest(kind, parts)


def urdf_description_key(text, allow_massless, kw):
    """The description key of ``from_urdf(text, allow_massless, **kw)`` (None: not
    cacheable this way)."""
    try:
        parts = (_plain(text), _plain(bool(allow_massless)),
                 tuple((k, _plain(v)) for k, v in sorted(kw.items())))
    except _NotPlain:
        return None
    return _digest("urdf", parts)


def _entry(dkey):
    from .build import cache_dir
    return os.path.join(cache_dir(), f"conmech_desc_{dkey}.json")


def description_hit(dkey, flags, model_only, params=None):
    """The system (``model_only``: the CompiledModel) stored under the description key,
    loaded without any derivation, or None. `params`: the caller's parameter values (a
    tree's); None: the values stored with the entry (a robot's)."""
    if dkey is None:
        return None
    from .pipeline import _from_cache, _system
    from .build import _read_json
    t0 = time.perf_counter()
    path = _entry(dkey)
    if not os.path.isfile(path):
        return None
    info = _read_json(path)
    if not isinstance(info, dict):
        return None
    key, stored = info.get("key"), info.get("params")
    if not (isinstance(key, str) and len(key) == 64 and
            all(c in "0123456789abcdef" for c in key)):
        return None
    if params is None:
        if not (isinstance(stored, list) and all(
                isinstance(p, list) and len(p) == 2 and isinstance(p[0], str) and
                isinstance(p[1], (int, float)) and not isinstance(p[1], bool)
                for p in stored)):
            return None
        params = {name: value for name, value in stored}
    model = _from_cache(key, params, flags)
    if model is None:
        return None
    model.times["description"] = model.times["derived_cache"]   # the marker of this path
    model.times["total"] = time.perf_counter() - t0
    return model if model_only else _system(model)


def store_description(dkey, key, params):
    """Record that the description `dkey` built the derivation-cache entry `key` with the
    parameter values `params` (a dict); best effort (an optimisation only)."""
    if dkey is None or key is None:
        return
    from .build import _write_atomic
    try:
        values = [[k if isinstance(k, str) else k.name, float(v)]
                  for k, v in (params or {}).items()]
        data = json.dumps({"key": key, "params": values}).encode()
        _write_atomic(_entry(dkey), data, 0o644)
    except (OSError, AttributeError, TypeError, ValueError):
        pass
