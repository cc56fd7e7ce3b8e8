"""The Taylor recurrences of a compiled ode model as a library of their own, built on first
need.

A model library (:mod:`conmech.symbolic.pipeline`) holds what every call uses: the
right-hand side, its Jacobian and the Jacobian products. The Taylor recurrences of
:mod:`conmech.symbolic.taylor` (the system's, in double, batch and quadruple precision, and
the variational system's) are several times that code, and only ``method="TAYLOR"`` runs
them, so they are compiled apart, and each in its own library, as a call needs it
(:data:`PARTS`): a Taylor solve (``solve_ivp(method="TAYLOR")``) needs the double routine
only (``core``); a Taylor ensemble the batch routine and its propagator over SIMD lanes
(:mod:`conmech.symbolic.taylor_batch`, compiled for the machine's vector instructions);
:mod:`conmech.symbolic.taylor_quad`
the quadruple-precision one; ``stm(method="TAYLOR")`` the variational system's (half of
all the code). :func:`lazy_taylor` gives the system a :class:`conmech.compiled.LazyTaylor`
whose first request of a part generates its module, compiles it into the same on-disk
cache as the model
(:func:`conmech.symbolic.build.compile_source`: keyed by its source, flags and compiler,
built in a private directory and renamed into place, so that concurrent processes are
safe, and checked against its manifest before loading) and loads it. A second process
finds it there (a cache hit, no compiler run). The copies of a system made by
``with_params`` share the model and its Taylor library.
"""
import json
import os
import re
import threading
import time

from . import taylor_batch as _taylor_batch
from .build import (FFLAGS, _read_json, _write_atomic, cache_dir, compile_source,
                    load)
from .codegen import _names, check_source, private_procedures
from .taylor import TAYLOR_VERSION

__all__ = ["taylor_source", "taylor_library", "lazy_taylor", "batch_part", "batch_entries",
           "MODULE", "PARTS"]

#: the Fortran module of the Taylor library
MODULE = "conmech_symbolic_taylor_library"

_FORMAT = 8     # of the kept source (conmech_KEY.taylor.json; 2: generalized models, 3: trees,
                # 4: the variational and quadruple-precision parts of generalized models,
                # 5: those of trees, 6: the batch part of generalized models and trees,
                # 7: that of generalized models beyond WRITE_OUT_MAX degrees of freedom,
                # 8: the wide lanes' loops of the written-out generalized batch split)

# guards the creation of a model's LazyTaylor (one per model); the build itself runs
# under the LazyTaylor's own lock
_LOCK = threading.Lock()


#: the parts, each a library of its own: the routine a Taylor solve runs (``core``:
#: conmech_taylor and its work columns), the batch routine of ensembles, the quadruple
#: precision one of conmech.symbolic.taylor_quad, and the variational system's (the STM)
PARTS = ("core", "batch", "qp", "var")

#: members per call of the batch coefficient routine, and lanes of the batch propagator
#: (conmech.symbolic.taylor_batch): the machine's vector width for doubles
BATCH_WIDTH = _taylor_batch.machine_lanes()


#: the optimisation of a tree's variational routine: its forward-differentiated chain is
#: ~8x the core's operations in one loop body, which gfortran's -O3 takes 3-4x longer to
#: compile than -O1 (double pendulum 25 s against 8 s, triple 132 s against 34 s) for no
#: faster code (an expansion of the triple pendulum's to order 15: 226-442 us at -O3,
#: 234-361 us at -O1, alternated runs; the same coefficients)
TREE_VAR_OPT = "-O1"


def _part_flags(model, part):
    """The compiler flags of one part's library: the model's (None: build's defaults),
    with a tree's variational routine at TREE_VAR_OPT unless the model was given flags."""
    flags = getattr(model, "flags", None)
    if flags is None and part == "var" and getattr(model.derived, "kind", None) == \
            "generalized":
        from .taylor_tree import is_tree
        if is_tree(model.derived):
            return [TREE_VAR_OPT if f == "-O3" else f for f in FFLAGS]
    return flags


def batch_part(lanes=None):
    """The part name of a batch library with `lanes` lanes (None: the machine's width,
    the part "batch"); a ValueError for a lane count not in taylor_batch.LANES."""
    if lanes is None or lanes == BATCH_WIDTH:
        return "batch"
    if isinstance(lanes, bool) or not isinstance(lanes, int) or \
            lanes not in _taylor_batch.LANES:
        raise ValueError("lanes must be one of "
                         f"{', '.join(map(str, _taylor_batch.LANES))}, got {lanes!r}")
    return f"batch{lanes}"


_BATCH_PART = re.compile(r"batch(\d+)(?:o(\d+))?$")


def _lanes(part):
    """The lanes of a batch part ("batch": the machine's width, "batchK": K, "batchKoP":
    K, with the recurrences written out for order P), or None."""
    if part == "batch":
        return BATCH_WIDTH
    m = _BATCH_PART.match(part)
    if m and int(m.group(1)) in _taylor_batch.LANES:
        return int(m.group(1))
    return None


def _fixed_order(part):
    """The written-out order of a batch part "batchKoP", or None."""
    m = _BATCH_PART.match(part)
    return int(m.group(2)) if m and m.group(2) else None


def _decompositions(model):
    """(decomposition of f, of [f; J Phi] or None when not asked yet, reason), computed
    once per model (the sympy work of the recurrences)."""
    return model.__dict__.setdefault("_taylor_dec", {})


def _lines(d, part, dec_cache):
    """(Fortran lines, entry names, reason) of one part."""
    from . import taylor as T
    names = _names(d)
    if d.kind == "generalized":          # through the accelerations' linear solve
        from .taylor_tree import is_tree, tree_lines
        if is_tree(d):                   # through the articulated-body chain
            if part == "var":
                from .taylor_tree_var import tree_variational_lines
                return tree_variational_lines(d, names, dec_cache)
            if _lanes(part) is not None:     # the ode systems' lanes, the pivots per lane
                from .._core import status as S
                from .taylor_tree_batch import tree_batch_lines
                return tree_batch_lines(d, names, _lanes(part), _fixed_order(part),
                                        dec_cache, (S.SUCCESS, S.TOO_MANY_STEPS,
                                                    S.STEP_TOO_SMALL, S.NONFINITE))
            return tree_lines(d, names, part, dec_cache)
        if part == "var":
            from .taylor_generalized_var import variational_lines
            return variational_lines(d, names, dec_cache)
        if _lanes(part) is not None:     # the lanes through the factorisation per lane
            from .._core import status as S
            from .taylor_generalized_batch import batch_lines
            return batch_lines(d, names, _lanes(part), _fixed_order(part), dec_cache,
                               (S.SUCCESS, S.TOO_MANY_STEPS, S.STEP_TOO_SMALL,
                                S.NONFINITE))
        from .taylor_generalized import generalized_lines
        return generalized_lines(d, names, part, dec_cache)
    if "f" not in dec_cache:
        dec, _, why = T.ode_decompositions(d, variational=False)
        dec_cache["f"] = (dec, why)
    dec, why = dec_cache["f"]
    if dec is None:
        return [], [], why
    if part == "core":
        return T.taylor_procedures(dec, names, "conmech_taylor", 0, False), \
            ["taylor", "taylor_info"], None
    lanes = _lanes(part)
    if lanes is not None:
        from .._core import status as S
        run = _taylor_batch.run_routine(
            d.n, dec.ncol, max(len(dec.params), 1), lanes,
            (S.SUCCESS, S.TOO_MANY_STEPS, S.STEP_TOO_SMALL, S.NONFINITE))
        fixed = _fixed_order(part)
        if fixed is None:
            return _taylor_batch.coefficient_routine(dec, names, lanes) + run, \
                ["taylor_batch", "taylor_batch_run"], None
        run = _taylor_batch.run_routine(
            d.n, dec.ncol, max(len(dec.params), 1), lanes,
            (S.SUCCESS, S.TOO_MANY_STEPS, S.STEP_TOO_SMALL, S.NONFINITE), fixed)
        return _taylor_batch.coefficient_routine(dec, names, lanes) + \
            _taylor_batch.fixed_routine(dec, names, lanes, fixed) + run, \
            ["taylor_batch", "taylor_batch_fixed", "taylor_batch_run"], None
    if part == "qp":
        return T.quad_routine(dec, names, "conmech_taylor_qp"), ["taylor_qp"], None
    if "var" not in dec_cache:
        vx, phi = T.variational_exprs(list(d.f), d.jac, d.n)
        dec_cache["var"] = T.decompose(vx, list(d.coords) + phi, d.t, d.params)
    return T.taylor_procedures(dec_cache["var"], names, "conmech_taylor_var", 0, False), \
        ["taylor_var", "taylor_var_info"], None


def taylor_source(d, part="core", _dec=None):
    """(source, entry names, reason) of one part of the Taylor library of the ode record
    `d` (see :data:`PARTS`): ``core`` holds ``conmech_taylor`` and ``_info``, ``batch``
    ``conmech_taylor_batch``, ``qp`` ``conmech_taylor_qp``, ``var``
    ``conmech_taylor_var`` and ``_var_info``, the routines a model library with Taylor
    code holds. A generalized record M(q) q'' = Q has the core, with
    ``conmech_taylor_rhs`` (:mod:`conmech.symbolic.taylor_generalized`), the batch part
    for its first-order view (:mod:`conmech.symbolic.taylor_generalized_batch`, the loop
    version, for any number of degrees of freedom), the quadruple
    precision part and the variational part (:mod:`conmech.symbolic.taylor_generalized_var`);
    a tree the same four through its articulated-body chain
    (:mod:`conmech.symbolic.taylor_tree`, :mod:`conmech.symbolic.taylor_tree_batch`,
    :mod:`conmech.symbolic.taylor_tree_var`). (None, [],
    reason) when f has no Taylor recurrences (a non-smooth expression)."""
    if part not in PARTS and _lanes(part) is None:
        raise ValueError(f"part must be one of {', '.join(PARTS)} or batchK (K lanes), "
                         f"got {part!r}")
    lines, entries, why = _lines(d, part, {} if _dec is None else _dec)
    if not lines:
        return None, [], why
    internal = private_procedures(entries)
    if "taylor_batch_run" in entries:        # the propagator's private stepping routines
        internal += _taylor_batch.step_routines(_fixed_order(part))
    what = "a generalized system" if d.kind == "generalized" else "an ode system"
    head = [f"!> Generated by conmech.symbolic: Taylor recurrences of {what} "
            f"({part}). Do not edit.",
            f"module {MODULE}_{part}",
            "    use, intrinsic :: iso_c_binding, only: c_double, c_int, c_ptr, c_f_pointer",
            "    use, intrinsic :: iso_fortran_env, only: real128",
            "    implicit none",
            "    integer, parameter :: dp = c_double, qp = real128",
            "    public"]
    head += [f"    private :: {p}" for p in internal] + ["contains", ""]
    src = "\n".join(head + lines + [f"end module {MODULE}_{part}", ""])
    c_names = [f"conmech_{e}" for e in entries]
    check_source(src, c_names + internal, c_names)
    return src, entries, None


def _entries(lib, part):
    """The taylor-dict entries of one loaded part."""
    import ctypes
    info = (ctypes.c_int*4)()
    if part == "core":
        lib.conmech_taylor_info(info)
        out = {"jet": lib.conmech_taylor, "nw": int(info[0])}
        rhs = getattr(lib, "conmech_taylor_rhs", None)
        if rhs is not None:          # a generalized model: f = [v; M^-1 Q] for its view
            out["rhs"] = rhs
        return out
    lanes = _lanes(part)
    if lanes is not None:
        return {"batch": lib.conmech_taylor_batch, "width": lanes,
                "batch_run": lib.conmech_taylor_batch_run}
    if part == "qp":
        return {"qp": lib.conmech_taylor_qp}
    lib.conmech_taylor_var_info(info)
    return {"var": lib.conmech_taylor_var, "nw_var": int(info[0])}


def taylor_library(model, part="core"):
    """The entries of the ``taylor`` dict (see :func:`conmech.compiled.ode_system`) of one
    part of a compiled ode model's Taylor code, from its library (generated, then compiled
    or found in the cache, and loaded); None when f has no Taylor recurrences. Records on
    the model, per part: ``taylor_paths[part]`` (the library), ``taylor_hits[part]`` (no
    compilation was needed) and the times ``taylor_<part>_generate`` and
    ``taylor_<part>_compile_or_load`` in ``model.times``; ``taylor_path`` and
    ``taylor_cache_hit`` are those of the core. Called through the model's
    :func:`lazy_taylor`, which builds each part once under its lock."""
    parts = model.__dict__.setdefault("_taylor_parts", {})
    state = parts.get(part)
    if state is None:
        t0 = time.perf_counter()
        key = getattr(model, "cache_key", None)
        found = _load_source(key, part) if key else None
        if found is None:
            src, entries, why = taylor_source(model.derived, part, _decompositions(model))
            if key:
                _store_source(key, part, src, entries, why)
        else:
            src, entries, why = found
        t1 = time.perf_counter()
        model.times[f"taylor_{part}_generate"] = t1 - t0
        if src is None:
            state = (None, None, why)
        else:
            flags = _part_flags(model, part)
            lanes = _lanes(part)
            if lanes is not None:   # the batch code for the machine's vector instructions
                flags = list(FFLAGS if flags is None else flags) + \
                    _taylor_batch.isa_flags(lanes)
            path, hit = compile_source(src, flags, entries)
            lib, _ = load(path, entries)
            model.times[f"taylor_{part}_compile_or_load"] = time.perf_counter() - t1
            # a batch library written out for an order is the model's batch library
            name = "batch" if _fixed_order(part) is not None else part
            model.__dict__.setdefault("taylor_paths", {})[name] = path
            model.__dict__.setdefault("taylor_hits", {})[name] = hit
            if part == "core":
                model.taylor_path, model.taylor_cache_hit = path, hit
            state = (lib, _entries(lib, part), None)
        parts[part] = state
    if part == "core":
        model.taylor_reason = state[2]
    return state[1]


def _source_path(key, part):
    lanes = _lanes(part)
    if lanes is not None:       # the batch source depends on the lanes (the machine's)
        fixed = _fixed_order(part)
        part = f"batch{lanes}{'' if fixed is None else f'o{fixed}'}-v{_taylor_batch.VERSION}"
    else:                       # the scalar source depends on the emitter's version
        part = f"{part}-v{TAYLOR_VERSION}"
    return os.path.join(cache_dir(), f"conmech_{key}.taylor-{part}.json")


def _load_source(key, part):
    """(source, entries, reason) kept beside the derivation of `key` (a process that finds
    the model in the cache finds its Taylor source too, with no sympy work), or None. The
    file is trusted as the cache's other files are (check_private), and the source is
    checked as a generated one is."""
    info = _read_json(_source_path(key, part), limit=None)
    try:
        if info.get("format") != _FORMAT:
            return None
        src, entries, why = info["source"], info["entries"], info["reason"]
        if src is None:
            return (None, [], str(why)) if isinstance(why, str) else None
        if not (isinstance(src, str) and isinstance(entries, list)
                and all(isinstance(e, str) for e in entries)):
            return None
        internal = private_procedures(entries)
        if "taylor_batch_run" in entries:
            internal += _taylor_batch.step_routines(_fixed_order(part))
        c_names = [f"conmech_{e}" for e in entries]
        check_source(src, c_names + internal, c_names)
        return src, entries, None
    except (ValueError, KeyError, TypeError, AttributeError):
        return None         # absent, stale or damaged: generated again


def _store_source(key, part, src, entries, why):
    """Keep the Taylor source beside the derivation of `key` (an optimisation only: a
    failure to write it is ignored)."""
    data = json.dumps({"format": _FORMAT, "source": src, "entries": list(entries),
                       "reason": why}).encode()
    try:
        _write_atomic(_source_path(key, part), data, 0o644)
    except OSError:
        pass


_BATCH_LOCK = threading.Lock()


#: written-out batch recurrences up to this many history products per expansion (beyond,
#: the loop version: the source and its compile time grow as order**2)
FIXED_MAX_TERMS = 40000


def batch_entries(model, lanes, order=None):
    """The entries (``batch``, ``width``, ``batch_run``) of a batch library of a compiled
    ode model: `lanes` lanes (None: the machine's), the recurrences written out for
    `order` when given and small enough (FIXED_MAX_TERMS), else the loop version. Built
    once per model, lanes and order, under a lock; None when f has no Taylor recurrences
    (or, for the machine's lanes in the loop version, which is the lazy part "batch" of
    the model's systems: ask the system). A generalized model M(q) q'' = Q has the loop
    version only, for any lanes (:mod:`conmech.symbolic.taylor_generalized_batch`, a tree's
    :mod:`conmech.symbolic.taylor_tree_batch`): its entries, or None with the reason in
    ``model._taylor_parts[part]`` (no recurrences)."""
    part = batch_part(lanes)
    if getattr(model.derived, "kind", None) == "generalized":
        with _BATCH_LOCK:
            return taylor_library(model, part)
    if order is not None:
        dec = _decomposition(model)
        if dec is not None:
            # history sums: none for linear combinations and time, two for powers and
            # sine/cosine pairs, one otherwise (conmech.symbolic.taylor's recipes)
            nhist = sum(0 if op.kind in ("lin", "time") else
                        2 if op.kind in ("pow", "sincos", "sinhcosh") else 1
                        for op in dec.ops)
            if nhist*order*(order - 1)//2 <= FIXED_MAX_TERMS and _algebraic(dec):
                part = f"batch{lanes or BATCH_WIDTH}o{int(order)}"
    if part == "batch":
        return None
    with _BATCH_LOCK:
        return taylor_library(model, part)


def _algebraic(dec):
    """Whether the expansion calls no elementary function but square roots: glibc's scalar
    sin, cos, exp, log, pow (kept for the scalar route's bits) stop the compiler from
    vectorising the written-out routine's single loop over the lanes, while the loop
    version keeps its history sums vectorised apart from them."""
    import sympy as sp
    for op in dec.ops:
        if op.kind in ("lin", "time", "mul", "sq", "div", "recip", "sqrt"):
            continue
        r = sp.sympify(op.data.get("r")) if op.kind == "pow" else None
        if r is not None and r.is_Rational and r.q == 2:
            continue          # a half-integer power: square roots
        return False
    return True


def _decomposition(model):
    """The decomposition of the model's f (computed once), or None."""
    from . import taylor as T
    cache = _decompositions(model)
    if "f" not in cache:
        dec, _, why = T.ode_decompositions(model.derived, variational=False)
        cache["f"] = (dec, why)
    return cache["f"][0]


def lazy_taylor(model):
    """The :class:`conmech.compiled.LazyTaylor` of an ode model (one per model, shared by
    every system made from it)."""
    from ..mechanics.compiled import LazyTaylor
    with _LOCK:
        lazy = model.__dict__.get("_lazy_taylor")
        if lazy is None:
            lazy = model._lazy_taylor = LazyTaylor(lambda part: taylor_library(model, part))
        return lazy
