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
from .taylor import event_exprs, event_source
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
