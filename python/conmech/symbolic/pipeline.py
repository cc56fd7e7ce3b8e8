"""The derive-compile-cache pipeline behind conmech.symbolic's constructors.

A construction is keyed by its inputs (expressions, parameter names, options): a key found
in the on-disk cache (``$CONMECH_CACHE``, default ``~/.cache/conmech``) loads the library
built before; otherwise the expressions are derived (``derive.py``), the Fortran emitted
(``codegen.py``), compiled and loaded (``build.py``), the result stored under the key. The
:class:`CompiledModel` holds the derivation, the source, the library and the entry points;
:func:`_system` wraps it as a ``conmech.compiled`` system that the integrators and the
stability routines run with no Python in the loop.
"""
import contextlib
import ctypes
import errno
import hashlib
import math
import os
import pickle
import shutil
import tempfile
import time

import numpy as np
import sympy as sp

from ..mechanics import compiled
from .. import _conmech as _flat
from .._core import slot_table as _table
from .._core.model import SystemModel, model_of
from .build import (CacheError, _conmech_version, _write_atomic, cache_dir, check_private,
                    compile_source, load)
from .codegen import CODEGEN_VERSION, generate
from .derive import _as_value, singular_everywhere
from .description import _NotPlain, _param_names, store_description
from .loop_report import closure_error as _closure_error
from .momenta import as_lagrangian_system

__all__ = ["CompiledModel", "compile_model", "save_model", "model_of"]

_D = ctypes.c_double
_P = ctypes.POINTER(ctypes.c_double)
_V = ctypes.c_void_p


class CompiledModel(SystemModel):
    """A derived system compiled and loaded: the library, the entry-point addresses, the
    generated source, and timings (``times``: derive, generate, compile_or_load, load;
    ``cache_hit``), the compiler ``flags`` (None: the defaults). An ode model's Taylor
    recurrences are a library of their own, compiled on first need
    (:mod:`conmech.symbolic.taylor_library`: ``taylor_path`` and ``taylor_cache_hit``
    once built). :meth:`call` evaluates an entry point through ctypes (for tests)."""

    def __init__(self, derived, source, path, lib, addresses, cache_hit, times, flags=None):
        self.flags = list(flags) if flags is not None else None
        self.derived = derived
        self.source = source
        self.path = path
        self.lib = lib
        self.addresses = addresses
        self.cache_hit = cache_hit
        self.times = times

    @property
    def kind(self):
        return self.derived.kind

    def closure_error(self, system, q0, t0=0.0):
        """None when the closed loops of `system` (a tree made from this model) close at
        q0, or it has none; otherwise the ValueError naming the loop with the largest
        residual (:func:`conmech.constrained.solve` asks when its initial projection
        fails)."""
        return _closure_error(self, system, q0, t0)

    def taylor_batch_entries(self, lanes, order=None):
        """The batch library's entries of this ode model's Taylor recurrences in `lanes`
        lanes (conmech.symbolic.taylor_library.batch_entries); None for other kinds."""
        if self.kind != "ode":
            return None
        from .taylor_library import batch_entries
        return batch_entries(self, lanes, order)

    def _shapes(self, entry):
        d = self.derived
        return _table.shapes(entry, d.n, d.n_hol, d.n_nh)

    def _entry(self, entry):
        """(ctypes function, number of input arrays, output shapes, returns a value) of an
        entry point, built once per model and entry (pointers passed as addresses)."""
        cache = self.__dict__.setdefault("_entries", {})
        e = cache.get(entry)
        if e is None:
            if entry not in self.addresses:
                raise ValueError(f"this model has no entry point '{entry}' "
                                 f"(has: {', '.join(self.addresses)})")
            if entry == "jac_prod":
                fn = ctypes.CFUNCTYPE(None, _D, _V, ctypes.c_int, _V, _V, _V)(
                    self.addresses[entry])
                e = (fn, 2, [], False)
            else:
                shapes = self._shapes(entry)
                n_in = _table.BY_NAME[entry].inputs
                ret = _table.returns_value(entry)
                fn = ctypes.CFUNCTYPE(_D if ret else None, _D,
                                      *([_V] * (n_in + len(shapes) + 1)))(
                    self.addresses[entry])
                e = (fn, n_in, shapes, ret)
            cache[entry] = e
        return e

    def _params(self, params):
        """The parameter array (the model's values when None), checked: real numbers, as
        many as the model has."""
        if params is None:
            p = self.__dict__.get("_p0")
            if p is None:
                p = self._p0 = self._params(list(self.derived.param_values))
            return p
        names = self.derived.param_names
        if not (isinstance(params, np.ndarray) and params.dtype == np.float64):
            if isinstance(params, (str, bytes)) or any(
                    isinstance(v, (bool, np.bool_, str, bytes))
                    for v in np.ravel(np.asarray(params, dtype=object))):
                raise TypeError(f"params must be {len(names)} real numbers")
        p = np.ascontiguousarray(params, dtype=float)
        if p.ndim != 1 or p.size != len(names):
            raise ValueError(f"params must have {len(names)} values ({', '.join(names)})")
        return p if p.size else np.zeros(1)

    def call(self, entry, t, *arrays, params=None):
        """Evaluate entry point `entry` ('rhs', 'mass', ...) at t and the input arrays
        (y; q; q, v; q, v, a; for 'jac_prod' y and an n x k block x), with the model's
        parameters or `params`."""
        fast = self.__dict__.get("_fast", _NO_CALLS).get(entry)
        if (fast is not None and params is None and len(arrays) == 1 and type(t) is float
                and type(arrays[0]) is np.ndarray):
            # the common call (one float64 array of the input's shape, the model's
            # parameters, an entry with one input and one output) by identity and type
            # tests only; anything else takes the checks below, with their messages
            address, shape, size, out_shape, p = fast
            y = arrays[0]
            if y.dtype is _F64 and y.shape == shape:
                out, info = _flat.flat_entry_call_1(address, t, y, size, p)
                if info == 0:
                    return out if out_shape is None else out.reshape(out_shape, order="F")
        e = self.__dict__.get("_calls", _NO_CALLS).get(entry)
        if e is None:
            e = self._call_layout(entry)
        address, in_shapes, shapes, sizes, ret = e
        if address is None:
            fn = self._entry(entry)[0]
            return self._call_jac_prod(fn, t, *arrays, params=params)
        p = self._params(params)
        if len(arrays) != len(in_shapes):
            raise ValueError(f"'{entry}' takes t and {len(in_shapes)} array(s), got "
                             f"{len(arrays)}")
        ins = []
        for a, shape in zip(arrays, in_shapes):
            if type(a) is not np.ndarray or a.dtype != np.float64:
                a = np.asarray(a, dtype=float)
            if a.shape != shape:
                raise ValueError(f"input arrays must have shape {shape}, got {a.shape}")
            ins.append(a if a.size else _PLACEHOLDER)
        t = float(t)
        # one f2py call (its argument handling is cheaper than ctypes' pointer objects);
        # the outputs are the fresh arrays f2py allocates, flattened in Fortran order
        if len(ins) == 1 and len(shapes) == 1 and not ret:
            out, info = _flat.flat_entry_call_1(address, t, ins[0], sizes[0], p)
            outs = (out,)
        else:
            ins += [_PLACEHOLDER] * (3 - len(ins))
            m = list(sizes) + [1] * (2 - len(sizes))
            out1, out2, value, info = _flat.flat_entry_call(
                address, int(ret), t, len(in_shapes), *ins, len(shapes), *m, p)
            outs = (out1, out2)
        if info != 0:
            raise RuntimeError(f"the model entry '{entry}' could not be called (its "
                               f"signature is not one of conmech's)")
        if ret:
            return float(value)
        res = [_as_array(o, s) for o, s in zip(outs, shapes)]
        if len(res) == 1 and len(ins) == 1 and params is None and res[0] is not None \
                and math.prod(in_shapes[0]) > 0 and math.prod(shapes[0]) > 0:
            # this entry's calls from now on take the fast path above
            self.__dict__.setdefault("_fast", {})[entry] = (
                address, in_shapes[0], sizes[0],
                None if len(shapes[0]) == 1 else shapes[0], p)
        return res[0] if len(res) == 1 else tuple(res)

    def _call_layout(self, entry):
        """(address, input shapes, output shapes, output sizes (at least 1), returns a
        value) of an entry point, made once per model and entry; address None for
        jac_prod (its own call)."""
        if entry not in self.addresses:
            raise ValueError(f"this model has no entry point '{entry}' "
                             f"(has: {', '.join(self.addresses)})")
        calls = self.__dict__.setdefault("_calls", {})
        if entry == "jac_prod":
            calls[entry] = e = (None, (), (), (), False)
            return e
        d = self.derived
        ret = _table.returns_value(entry)
        shapes = list(self._shapes(entry))
        in_shapes = [(d.n,)] * _table.BY_NAME[entry].inputs
        if entry == "constraint_hessian":                      # the multipliers
            in_shapes[2] = (d.n_hol + d.n_nh,)
        sizes = tuple(max(math.prod(s), 1) for s in shapes)
        calls[entry] = e = (int(self.addresses[entry]), tuple(in_shapes), tuple(shapes),
                            sizes, ret)
        return e

    def _call_jac_prod(self, fn, t, y, x, params=None):
        """jx = J(t, y) x through the compiled conmech_jac_prod (x: n or n x k)."""
        n = self.derived.n
        p = self._params(params)
        y = np.ascontiguousarray(y, dtype=float)
        x = np.asarray(x, dtype=float)
        vec = x.ndim == 1
        x = np.asfortranarray(x.reshape(n, -1) if vec else x)
        if y.shape != (n,) or x.ndim != 2 or x.shape[0] != n or x.shape[1] < 1:
            raise ValueError(f"jac_prod needs y of shape ({n},) and x of shape ({n}, k)")
        jx = np.zeros(x.shape, order="F")
        fn(float(t), y.ctypes.data, x.shape[1], x.ctypes.data, jx.ctypes.data, p.ctypes.data)
        return jx.ravel() if vec else jx


_NO_CALLS = {}
_F64 = np.dtype(np.float64)
# the one-element stand-in for an empty or unused array argument (f2py cannot pass empty
# arrays; the entry never reads it)
_PLACEHOLDER = np.zeros(1)
_PLACEHOLDER.flags.writeable = False


def _as_array(out, shape):
    """A flat output (Fortran order) as an array of `shape`, sharing its memory."""
    if len(shape) == 1:
        return out if shape[0] else np.zeros(shape)
    if math.prod(shape) == 0:
        return np.zeros(shape, order="F")
    return out.reshape(shape, order="F")


def compile_model(derived, flags=None):
    """Generate, compile (or take from the cache) and load the Fortran of `derived`."""
    t0 = time.perf_counter()
    src, entries = generate(derived)
    t1 = time.perf_counter()
    path, hit = compile_source(src, flags, entries)
    t2 = time.perf_counter()
    lib, addr = load(path, entries)
    t3 = time.perf_counter()
    times = {"generate": t1 - t0, "compile_or_load": t2 - t1, "load": t3 - t2}
    return CompiledModel(derived, src, path, lib, addr, hit, times, flags)


def save_model(system, path, flags=None):
    """Write the system as a model library to ``path`` (a shared library with the model
    description of ``conmech_model_library``: its kind, dimensions, parameter names and the
    system's current parameter values as defaults), for the Fortran programs
    (``sweep --model PATH``) and :func:`conmech.compiled.load_model`. The library is
    compiled once (cached like the others), copied to a temporary file beside ``path``,
    checked, flushed to disk and renamed to ``path``: a failure (a full disk, a read-only
    directory) raises OSError naming ``path`` and the cause, and leaves no partial file."""
    model = model_of(system)
    values = [float(v) for v in np.asarray(getattr(system, "params", None) if not
                                           isinstance(system, CompiledModel) else
                                           model.derived.param_values, dtype=float).ravel()]
    # a model library for other programs is complete: its Taylor recurrences included
    src, entries = generate(model.derived, model_values=values, taylor=True)
    lib_path, _ = compile_source(src, flags, entries + ["model_info", "model_params",
                                                       "model_param_names"])
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{os.path.basename(path)}.", suffix=".tmp",
                                   dir=folder)
        with os.fdopen(fd, "wb") as out, open(lib_path, "rb") as inp:
            shutil.copyfileobj(inp, out)
            out.flush()
            os.fsync(out.fileno())
        os.chmod(tmp, 0o755 & ~_umask())
        if os.path.getsize(tmp) != os.path.getsize(lib_path):
            raise OSError(errno.EIO, "short copy")
        os.replace(tmp, path)
        tmp = None
    except OSError as exc:
        raise OSError(exc.errno, f"cannot write the model library {path}: "
                                 f"{exc.strerror or exc}") from None
    finally:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
    return path


def _umask():
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _system(model):
    """The conmech.compiled system for a model."""
    d = model.derived
    a = model.addresses
    common = dict(params=tuple(d.param_values), param_names=tuple(d.param_names), keep=model,
                  name="symbolic")
    if d.kind == "ode":
        # the Taylor recurrences are compiled when a call first needs them
        from .taylor_library import lazy_taylor
        return compiled.ode_system(d.n, a["rhs"], jac=a["jac"], jac_prod=a.get("jac_prod"),
                                   taylor=lazy_taylor(model), **common)
    if d.kind == "generalized":
        return as_lagrangian_system(compiled.generalized_system(
            d.n, a["mass"], a["forces"], forces_jac=a.get("forces_jac"),
            energy=a.get("energy"), mass_forces=a.get("mass_forces"), accel=a.get("accel"),
            accel_jac=a.get("accel_jac"), **common))
    return compiled.constrained_system(
        d.n, a["mass"], a["forces"], n_hol=d.n_hol, n_nh=d.n_nh, phi=a.get("phi"),
        phi_jac=a.get("phi_jac"), phi_t=a.get("phi_t"), phi_gamma=a.get("phi_gamma"),
        nh_matrix=a.get("nh_matrix"), nh_gamma=a.get("nh_gamma"), energy=a.get("energy"),
        rheonomic=bool(d.rheonomic), forces_jac=a.get("forces_jac"),
        constraint_hessian=a.get("constraint_hessian"),
        redundant=bool(getattr(d, "loops", None)), **common)


def _input_key(kind, inputs, params, options):
    """Key of a construction's inputs (expressions, parameter names, options), or None when
    the inputs are not plainly cacheable (then the derivation runs and reports errors)."""
    if not isinstance(params, dict):
        return None
    # the names without their values; a value that is not a plain number, or an integer
    # beyond a double's range, is left to the derivation to report
    try:
        names = list(_param_names(params)[::2])
    except (_NotPlain, OverflowError):
        return None
    try:
        text = repr((kind, [sp.srepr(sp.sympify(x)) if x is not None else None
                            for x in inputs], names, options, CODEGEN_VERSION,
                     _conmech_version()))
    except (sp.SympifyError, TypeError, AttributeError):
        return None
    return hashlib.sha256(text.encode()).hexdigest()


def _entry_path(key):
    return os.path.join(cache_dir(), f"conmech_{key}.derived.pickle")


def _from_cache(key, params, flags):
    """The model from the derivation cache (derived record + source), or None."""
    path = _entry_path(key)
    if not os.path.isfile(path):
        return None
    t0 = time.perf_counter()
    try:
        with open(path, "rb") as fh:
            # unpickling runs code: only from a file nobody else can write
            check_private(os.path.dirname(path), os.stat(os.path.dirname(path)))
            check_private(path, os.fstat(fh.fileno()))
            d, src, entries, fl = pickle.load(fh)
    except CacheError:
        raise
    except Exception:        # a stale or corrupt entry: derive again
        return None
    if fl != (list(flags) if flags is not None else None):
        return None
    if len(params) != len(d.param_names):
        return None
    # the same checks as the derivation: a value out of range is a ValueError naming it
    d.param_values = [_as_value(n, v) for n, v in zip(d.param_names, params.values())]
    t1 = time.perf_counter()
    lib_path, hit = compile_source(src, flags, entries)
    t2 = time.perf_counter()
    lib, addr = load(lib_path, entries)
    t3 = time.perf_counter()
    times = {"derive": 0.0, "derived_cache": t1 - t0, "generate": 0.0,
             "compile_or_load": t2 - t1, "load": t3 - t2}
    model = CompiledModel(d, src, lib_path, lib, addr, hit, times, flags)
    model.cache_key = key
    return model


def _store(key, model, flags):
    try:
        data = pickle.dumps((model.derived, model.source, list(model.addresses),
                             list(flags) if flags is not None else None))
        _write_atomic(_entry_path(key), data, 0o644)
    except Exception:        # the derivation cache is an optimisation only
        pass


def _check_compiled_mass(model):
    """Large systems: the singularity check of the mass matrix on the compiled code (random
    states, the given and perturbed parameter values)."""
    rng = np.random.default_rng(12345)
    d = model.derived

    def mass_at(trial):
        p = np.asarray(d.param_values, float)
        if trial:
            p = np.where(p != 0, p*rng.uniform(0.7, 1.3, p.size), rng.uniform(0.5, 1.5, p.size))
        with np.errstate(all="ignore"):
            return model.call("mass", rng.uniform(0.3, 1.3), rng.uniform(-1, 1, d.n), params=p)
    if singular_everywhere(mass_at, d.n, rng):
        raise ValueError("the mass matrix is singular at every sampled state (det M = 0): a "
                         "coordinate has no kinetic energy, or the coordinates are dependent")


def _construct(kind, inputs, params, options, derive, flags, model_only, description=None):
    """Derive (or take the derivation from the cache), compile (or load), wrap.
    `description`: the key of the cheap description (symbolic/description.py) to record
    for the next construction of the same system."""
    t0 = time.perf_counter()
    params = {} if params is None else params
    key = _input_key(kind, inputs, params, options)
    model = _from_cache(key, params, flags) if key else None
    if model is None:
        d = derive()
        t1 = time.perf_counter()
        model = compile_model(d, flags)
        model.times["derive"] = t1 - t0
        if d.kind != "ode" and d.n > 4:
            _check_compiled_mass(model)
        if key:
            _store(key, model, flags)
    # the derivation cache's key, under which the Taylor library's source is kept too
    model.cache_key = key
    if description and key:
        store_description(description, key, params)
    model.times["total"] = time.perf_counter() - t0
    return model if model_only else _system(model)


def _tup(x):
    """A sympy Tuple of a list of expressions (for the input key)."""
    if x is None:
        return None
    if isinstance(x, sp.MatrixBase):
        x = list(x)
    if isinstance(x, (list, tuple)):
        return sp.Tuple(*x)
    return x
