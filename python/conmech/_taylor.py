"""Taylor's method with compiled events, for :func:`conmech.solve_ivp` (method "TAYLOR"
with events made by :func:`conmech.symbolic.event`): the events of one call are compiled
together (cached) and located by the Taylor stepper with no Python in the loop."""
import numpy as np

from . import _conmech

__all__ = ["run_compiled_events"]


def _library(fun, evs):
    from .symbolic import model_of
    from .symbolic.taylor_events import compile_events, expressions
    model = model_of(fun)
    cache = model.__dict__.setdefault("_taylor_event_libs", {})
    exprs = expressions(evs)
    key = tuple(str(e) for e in exprs)
    if key not in cache:
        cache[key] = compile_events(model.derived, exprs)
    return cache[key]


def run_compiled_events(fun, evs, store, kw, zero_at_start):
    """One segment of solve_ivp with compiled events: the flat call, returning (counts,
    form, info, message) like flat_solve_builtin (counts of 5)."""
    from .symbolic.taylor_events import DEGREE
    lib = _library(fun, evs)
    ne = len(evs)
    zero = np.array([int(i in zero_at_start) for i in range(ne)], dtype=np.intc)
    name, np_, p, nspec, spec = fun._flat_args()
    args = {k: v for k, v in kw.items() if k != "method"}
    counts, form, info, message = _conmech.flat_solve_taylor(
        name, np_, p, nspec, spec, store, evaddr=lib["address"], evnw=lib["nw"],
        evdeg=DEGREE, ev_zero=zero, **args)
    return counts[:5], form, info, message
