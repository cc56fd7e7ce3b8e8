"""The Jacobian of the methods that use one (Radau IIA): a user's ``jac`` (callable or
constant, dense or a scipy.sparse matrix) and ``jac_sparsity`` for the flat routines of
solve_ivp and of the steppers.

Sparse matrices are recognised by their interface (``toarray``, ``tocsc``), so conmech
needs no SciPy; their values reach Fortran as dense arrays. ``jac_sparsity`` (or the
pattern of a constant sparse ``jac``) gives the structure for finite differences by groups
of columns (Curtis-Powell-Reid, done in Fortran: conmech_jacobian_structure) and, for
n >= 100 at most 10% dense, Radau's sparse LU path (conmech_radau_sparse).
"""
import math

import numpy as np

__all__ = ["jacobian_callback", "sparsity_pattern", "is_sparse", "NO_PATTERN"]

# the flat routines' arguments when there is no pattern: nnz = -1 (f2py needs arrays)
NO_PATTERN = (-1, None, np.zeros(1, dtype=np.intc))


def is_sparse(x):
    """A scipy.sparse matrix or array (recognised by its interface)."""
    return hasattr(x, "toarray") and hasattr(x, "tocsc") and hasattr(x, "nnz")


def _no_jacobian(t, y):
    """The Jacobian argument of the flat routines when there is none (has_jac = 0: never
    called)."""
    return np.zeros((1, 1))


def _shape_error(n, shape):
    return ValueError(f"`jac` is expected to have shape {(n, n)}, but actually has "
                      f"{shape}.")


def jacobian_callback(jac, n, args, failure, y0_t0=None):
    """The f2py Jacobian callback for ``jac`` (a callable ``jac(t, y, *args) -> (n, n)``
    or a constant; dense or sparse); (callback, has_jac, constant). Shapes and finiteness
    are checked: a bad return is kept in ``failure`` (raised by the caller) and NaN is
    returned so that the Fortran solver stops. A constant matrix is read once by the
    solver and never counted as an evaluation (SciPy's njev 0)."""
    if jac is None:
        return _no_jacobian, 0, 0
    if not callable(jac):
        if is_sparse(jac):
            jconst = np.asarray(jac.toarray(), dtype=float)
        else:
            try:
                jconst = np.array(jac, dtype=float)
            except (TypeError, ValueError):
                raise TypeError("jac must be callable or an array_like (or sparse matrix) "
                                f"of shape ({n}, {n})") from None
        if jconst.shape != (n, n):
            raise _shape_error(n, jconst.shape)
        if not np.isfinite(jconst).all():
            raise ValueError("jac contains NaN or Inf")
        jconst = np.asfortranarray(jconst)

        def const_cb(t, y):
            return jconst
        return const_cb, 1, 1

    def jac_cb(t, y):
        if failure:
            return np.full((n, n), math.nan)
        try:
            m = jac(t, y.copy(), *args)
            m = np.asarray(m.toarray() if is_sparse(m) else m, dtype=float)
            if m.shape != (n, n):
                raise _shape_error(n, m.shape)
            return m
        except BaseException as exc:
            failure.append(exc)
            return np.full((n, n), math.nan)
    return jac_cb, 1, 0


def sparsity_pattern(jac_sparsity, n):
    """``jac_sparsity`` (None, an (n, n) array_like or a sparse matrix; entry (i, j)
    nonzero: f_i depends on y_j) as the flat routines' (nnz, column pointers (n + 1,),
    rows (max(nnz, 1),)), 1-based, compressed by columns; NO_PATTERN for None."""
    if jac_sparsity is None:
        return NO_PATTERN
    if is_sparse(jac_sparsity):
        coo = jac_sparsity.tocoo()
        shape = coo.shape
        rows, cols = np.asarray(coo.row), np.asarray(coo.col)
        keep = np.asarray(coo.data) != 0
        rows, cols = rows[keep], cols[keep]
    else:
        try:
            a = np.asarray(jac_sparsity)
            if a.dtype.kind not in "biufc":
                raise TypeError
        except (TypeError, ValueError):
            raise TypeError("jac_sparsity must be None, an array_like or a sparse matrix "
                            f"of shape ({n}, {n})") from None
        shape = a.shape
        if a.ndim == 2:
            rows, cols = np.nonzero(a)
    if tuple(shape) != (n, n):
        raise ValueError(f"`jac_sparsity` is expected to have shape {(n, n)}, but "
                         f"actually has {tuple(shape)}.")
    # unique entries, sorted by column then row
    key = np.unique(np.asarray(cols, dtype=np.int64) * n + np.asarray(rows, dtype=np.int64))
    cols, rows = np.divmod(key, n)
    ptr = np.zeros(n + 1, dtype=np.intc)
    np.cumsum(np.bincount(cols, minlength=n), out=ptr[1:])
    idx = (rows + 1).astype(np.intc) if rows.size else np.zeros(1, dtype=np.intc)
    return int(rows.size), ptr + 1, idx
