"""The implicit methods of solve_ivp (Radau IIA, Gauss-Legendre) on the flat routines of
flat_implicit.f90; called by :func:`conmech.solve_ivp` for method "Radau", "GAUSS4",
"GAUSS6" after its argument checks."""
import math

import numpy as np

from . import _conmech

IMPLICIT_CODES = {"RADAU": 5, "RADAU5": 5, "GAUSS4": 6, "GAUSS6": 7}


def jacobian_callback(jac, n, args, failure):
    """The f2py Jacobian callback for ``jac`` (a callable ``jac(t, y, *args) -> (n, n)``
    or a constant array_like); (callback, has_jac). Shapes and finiteness are checked: a
    bad return is kept in ``failure`` (raised by the caller) and NaN is returned so that
    the Fortran solver stops."""
    nan_j = np.full((n, n), math.nan)
    if jac is None:
        def none_cb(t, y):  # never called when has_jac = 0
            return nan_j
        return none_cb, 0
    if not callable(jac):
        if hasattr(jac, "toarray") or hasattr(jac, "tocsr"):
            raise TypeError("jac: sparse matrices are not supported, pass a dense array")
        try:
            jconst = np.array(jac, dtype=float)
        except (TypeError, ValueError):
            raise TypeError("jac must be callable or an array_like of shape "
                            f"({n}, {n})") from None
        if jconst.shape != (n, n):
            raise ValueError(f"jac must have shape ({n}, {n}), got {jconst.shape}")
        if not np.isfinite(jconst).all():
            raise ValueError("jac contains NaN or Inf")

        def const_cb(t, y):
            return jconst
        return const_cb, 1

    def jac_cb(t, y):
        if failure:
            return nan_j
        try:
            m = np.asarray(jac(t, y.copy(), *args), dtype=float)
            if m.shape != (n, n):
                if hasattr(m, "toarray"):
                    raise TypeError("jac returned a sparse matrix: return a dense array")
                raise ValueError(f"jac must return an array of shape ({n}, {n}), got "
                                 f"shape {m.shape}")
            return m
        except BaseException as exc:
            failure.append(exc)
            return nan_j
    return jac_cb, 1


def run(builtin, fun, rhs, jac, args, n, events_cb, store, common, failure):
    """Run the flat implicit solver; returns (nfev, njev, nlu, naccept, nreject, form,
    info, message)."""
    if builtin:
        if jac is not None:
            raise TypeError("jac cannot be used with a built-in system (it has its own)")
        counts, form, info, message = _conmech.flat_solve_implicit_builtin(
            *fun._flat_args(), events_cb, store, **common)
    else:
        jac_cb, has_jac = jacobian_callback(jac, n, args, failure)
        counts, form, info, message = _conmech.flat_solve_implicit_callback(
            rhs, jac_cb, events_cb, store, has_jac=has_jac, **common)
    nfev, njev, nlu, naccept, nreject = (int(c) for c in counts)
    return nfev, njev, nlu, naccept, nreject, form, info, message
