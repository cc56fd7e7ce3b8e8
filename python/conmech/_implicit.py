"""The Jacobian callback of the methods that use one (Radau IIA): a user's ``jac`` for the
flat routines of solve_ivp and of the steppers."""
import math

import numpy as np


def _no_jacobian(t, y):
    """The Jacobian argument of the flat routines when there is none (has_jac = 0: never
    called)."""
    return np.zeros((1, 1))


def jacobian_callback(jac, n, args, failure):
    """The f2py Jacobian callback for ``jac`` (a callable ``jac(t, y, *args) -> (n, n)``
    or a constant array_like); (callback, has_jac). Shapes and finiteness are checked: a
    bad return is kept in ``failure`` (raised by the caller) and NaN is returned so that
    the Fortran solver stops."""
    if jac is None:
        return _no_jacobian, 0
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
            return np.full((n, n), math.nan)
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
            return np.full((n, n), math.nan)
    return jac_cb, 1
