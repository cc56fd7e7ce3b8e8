"""Compiled event functions g(t, y) for :func:`conmech.solve_ivp`, given as sympy expressions.

:func:`event` compiles an expression in the symbols of a system made by
:func:`conmech.symbolic.ode_system` (its state variables, ``t`` and its parameters, matched by
name) into an event with SciPy's attributes (``terminal``, ``direction``). It is a callable
``g(t, y)`` and works with every method; with ``method="TAYLOR"`` the events of one call are
compiled together into the Taylor series of g along each step's polynomial, their roots
isolated on it so that none inside a step is missed, with no Python in the loop (see
``conmech_taylor_events``)::

    t = sp.Symbol("t")
    ev = symbolic.event(kep, sp.sin(50*t) + 0.9)
    r = conmech.solve_ivp(kep, (0, 2), y0, method="TAYLOR", events=[ev], rtol=1e-6)
"""
import ctypes

import numpy as np
import sympy as sp

from .build import compile_source, load
from .printer import _names
from .taylor import c_routine, decompose
from .pipeline import model_of

__all__ = ["Event", "event", "compile_events", "DEGREE"]

#: degree of the events' series on which roots are isolated
DEGREE = 24

_D = ctypes.c_double
_P = ctypes.POINTER(ctypes.c_double)


class Event:
    """An event function g(t, y) of a compiled ode system, given by a sympy expression.

    Attributes: ``expr`` (in the system's derived symbols), ``terminal`` (bool or a positive
    count, SciPy's meaning), ``direction`` (>0 rising, <0 falling, 0 both), ``system``.
    Calling it evaluates g(t, y) with the system's parameters (compiled on first call)."""

    def __init__(self, system, expr, terminal=False, direction=0):
        self.model = model_of(system)
        if self.model.derived.kind != "ode":
            raise ValueError("compiled events need a first-order system made by "
                             "conmech.symbolic.ode_system")
        self.system = system
        self.expr = event_exprs(self.model.derived, [expr])[0]
        self.terminal = terminal
        self.direction = direction
        self._lib = None

    def __call__(self, t, y):
        lib = self._lib or compile_events(self.model.derived, [self.expr])
        self._lib = lib
        n = self.model.derived.n
        y = np.ascontiguousarray(y, dtype=float).ravel()
        if y.size != n:
            raise ValueError(f"y must have {n} components, got {y.size}")
        w = np.zeros(lib["nw"])
        w[:n] = y
        p = np.ascontiguousarray(self.system.params, dtype=float)
        if p.size == 0:
            p = np.zeros(1)
        lib["fn"](float(t), 0, w.ctypes.data_as(_P), p.ctypes.data_as(_P))
        return float(w[n])

    def __repr__(self):
        return (f"Event({self.expr}, terminal={self.terminal!r}, "
                f"direction={self.direction!r})")


def event(system, expr, terminal=False, direction=0):
    """A compiled event g(t, y) = `expr` of a system made by
    :func:`conmech.symbolic.ode_system` (see the module docstring). `expr` is a sympy
    expression in the system's state variables, ``t`` and its parameters (by name);
    ``terminal`` and ``direction`` as SciPy's event attributes."""
    return Event(system, expr, terminal, direction)


def compile_events(d, exprs, flags=None):
    """Compile (or take from the cache) the series routine of the events `exprs` of the
    ode record `d`; returns {"fn": ctypes function, "address", "nw", "ne", "lib"}."""
    src = event_source(d, exprs)
    path, _ = compile_source(src, flags, ["taylor_events", "taylor_events_info"])
    lib, addr = load(path, ["taylor_events", "taylor_events_info"])
    info = (ctypes.c_int*4)()
    lib.conmech_taylor_events_info(info)
    fn = ctypes.CFUNCTYPE(None, _D, ctypes.c_int, _P, _P)(addr["taylor_events"])
    return {"fn": fn, "address": addr["taylor_events"], "nw": int(info[0]),
            "ne": int(info[1]), "lib": lib}


def compiled_events(fun, events):
    """The compiled events of a solve_ivp call when every event is an :class:`Event` of
    `fun`'s model, else None."""
    if events is None:
        return None
    evs = [events] if callable(events) and not isinstance(events, (list, tuple)) else \
        list(events)
    if not evs or not all(isinstance(e, Event) for e in evs):
        return None
    try:
        model = model_of(fun)
    except TypeError:
        return None
    if any(e.model is not model and e.model.source != model.source for e in evs):
        return None
    return evs


def expressions(evs):
    """The expressions of a list of events (for one compiled library)."""
    return [sp.sympify(e.expr) for e in evs]


def event_source(d, exprs):
    """Fortran source of a module with the Taylor series of event functions g(t, y) along a
    given polynomial of the state of the ode record `d` (``conmech_taylor_events(t, order,
    w, p)``: on entry w(0:order, 1:n) = the state's series, on exit w(0:order, n + 1 ..
    n + m) the m events' series; order 0 evaluates g) and ``conmech_taylor_events_info``
    ([work columns, m, n]). The expressions are in the record's symbols (see
    :func:`event_exprs`)."""
    dec = decompose(list(exprs), d.coords, d.t, d.params, given=True)
    lines = c_routine(dec, _names(d), "conmech_taylor_events", given=True)
    ind = "        "
    lines += ['    subroutine conmech_taylor_events_info(info) bind(C, '
              'name="conmech_taylor_events_info")',
              f"{ind}integer(c_int), intent(out) :: info(4)",
              f"{ind}info = [{dec.ncol}, {len(exprs)}, {dec.n}, 0]",
              "    end subroutine conmech_taylor_events_info", ""]
    head = ["!> Generated by conmech.symbolic.taylor: Taylor series of event functions along "
            "the solution. Do not edit.",
            "module conmech_symbolic_taylor_events",
            "    use, intrinsic :: iso_c_binding, only: c_double, c_int",
            "    implicit none",
            "    integer, parameter :: dp = c_double",
            "    public",
            "contains", ""]
    return "\n".join(head + lines + ["end module conmech_symbolic_taylor_events", ""])


def event_exprs(d, exprs):
    """The event expressions in the symbols of the ode record `d`: the user's symbols are
    matched by name (a state variable, t, or a parameter); anything else is a ValueError
    naming it. Non-smooth functions are a TaylorUnsupported error."""
    byname = dict(zip(getattr(d, "coord_names", [str(c) for c in d.coords]), d.coords))
    byname.update(zip(d.param_names, d.params))
    out = []
    for i, e in enumerate(exprs):
        try:
            e = sp.sympify(e)
        except (sp.SympifyError, TypeError) as exc:
            raise TypeError(f"events[{i}]: cannot read {e!r} as a sympy expression") from exc
        if not isinstance(e, sp.Expr) or getattr(e, "is_Matrix", False):
            raise TypeError(f"events[{i}]: {e!r} is not a scalar expression")
        # complex, non-finite, unevaluated or out-of-range entries: a ValueError naming it
        from .derive import _check_entry
        _check_entry(e, f"events[{i}]")
        sub = {}
        for s in e.free_symbols:
            if s.name == d.t.name:
                sub[s] = d.t
            elif s.name in byname:
                sub[s] = byname[s.name]
            else:
                raise ValueError(f"events[{i}]: unknown symbol '{s.name}' (neither t, a state "
                                 f"variable ({', '.join(map(str, byname))}) nor a parameter)")
        from sympy.core.function import AppliedUndef
        for f in e.atoms(AppliedUndef):
            name = str(f.func)
            if name not in byname:
                raise ValueError(f"events[{i}]: unknown function {f}")
            sub[f] = byname[name]
        out.append(e.xreplace(sub))
    return out
