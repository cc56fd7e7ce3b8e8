"""The flat layer's per-call entries as C functions: ``until`` (flat_propagation_until, for
:meth:`conmech.Propagator.propagate_until`) and ``solve`` (flat_propagation_solve, for
:func:`conmech.solve_ivp`'s fast entry), from python/conmech/flat/fastcall.c.

They take the arguments of the f2py wrappers of the same routines (positionally, the
hidden sizes from the arrays) and give the same numbers; they check their arguments' kinds
with type tests only, without f2py's keyword parsing, conversions and return value, so a
call costs a fraction of a microsecond less (``python bench/fastcall_ab.py``).

The C functions are compiled into the extension module ``conmech._conmech`` and form a
module of their own, ``conmech._fastcall``, whose init function lives in the same shared
object: it is loaded here from ``_conmech``'s file, so that both modules run one copy of
the Fortran library (a propagation made by f2py's flat_propagation_new is the one these
functions run).
"""
import importlib.machinery
import importlib.util

from .. import _conmech

__all__ = ["until", "solve"]


def _load():
    name = "conmech._fastcall"
    loader = importlib.machinery.ExtensionFileLoader(name, _conmech.__file__)
    spec = importlib.util.spec_from_file_location(name, _conmech.__file__, loader=loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


_module = _load()
until = _module.until
solve = _module.solve
