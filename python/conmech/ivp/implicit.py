"""The Jacobian of the methods that use one (Radau IIA): a user's ``jac`` (callable or
constant, dense or a scipy.sparse matrix) and ``jac_sparsity`` for the flat routines of
solve_ivp and of the steppers.

Sparse matrices are recognised by their interface (``toarray``, ``tocsc``), so conmech
needs no SciPy. ``jac_sparsity`` (or the pattern of a constant sparse ``jac``) gives the
structure for finite differences by groups of columns (Curtis-Powell-Reid, done in
Fortran: conmech_jacobian_structure) and, for n >= 100 at most 10% dense, Radau's sparse
LU path (conmech_radau_sparse).

A callable ``jac`` is evaluated once at (t0, y0) before the integration, as SciPy's Radau
does (that value serves the solver's first Jacobian: the user's function is called njev
times in all). When it returns a sparse matrix, its structure (CSC, duplicates summed,
explicit zeros kept) becomes the Jacobian's pattern and every later value travels as
the nnz numbers on it (:class:`SparseJacobian`, flat_sparse_jac.f90): Radau's sparse LUs
read them directly and no n x n array is formed on either side. A later value with
another structure is mapped onto the first one; a nonzero entry outside it is refused
with a message naming the entry (the solver stops, the exception reaches the caller).
"""
import math

import numpy as np

__all__ = ["jacobian_callback", "start_jacobian", "SparseJacobian", "sparsity_pattern",
           "is_sparse", "NO_PATTERN"]

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


def jacobian_callback(jac, n, args, failure, first=None):
    """The f2py Jacobian callback for ``jac`` (a callable ``jac(t, y, *args) -> (n, n)``
    or a constant; dense or sparse); (callback, has_jac, constant). Shapes and finiteness
    are checked: a bad return is kept in ``failure`` (raised by the caller) and NaN is
    returned so that the Fortran solver stops. A constant matrix is read once by the
    solver and never counted as an evaluation (SciPy's njev 0). ``first``: (t0, y0,
    value) of a callable's evaluation made before the run, returned for the solver's
    first request when that is at (t0, y0)."""
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

    held = [first] if first is not None else []

    def jac_cb(t, y):
        if failure:
            return np.full((n, n), math.nan)
        try:
            m = _held_value(held, t, y)
            if m is None:
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


def _held_value(held, t, y):
    """The value evaluated before the run, on the solver's first request if that is at
    the same (t, y) (then forgotten); None otherwise."""
    if not held:
        return None
    t1, y1, m1 = held.pop()
    return m1 if t == t1 and np.array_equal(y, y1) else None


def start_jacobian(jac, n, args, failure, t0, y0):
    """A method's Jacobian at the start of a run: (callback, has_jac, constant, sparse).
    A callable ``jac`` is evaluated at (t0, y0) first (SciPy's Radau does the same); if
    that value is an (n, n) sparse matrix, ``sparse`` is the :class:`SparseJacobian` that
    serves the run (its ``pattern`` for the flat routines, its ``callback`` the values),
    else None and the dense callback of :func:`jacobian_callback` (which returns a good
    first value for the first request). A first value that raises or has a bad shape is
    not kept: the solver's own request evaluates it again and reports it, as without the
    first evaluation (the same exception, or the shape error, from the run)."""
    if not callable(jac):
        return (*jacobian_callback(jac, n, args, failure), None)
    y = np.array(y0, dtype=float)
    try:
        m = jac(t0, y.copy(), *args)
        shape = tuple(m.shape) if is_sparse(m) else np.shape(m)
    except Exception:       # noqa: BLE001 (raised again by the run's own evaluation)
        return (*jacobian_callback(jac, n, args, failure), None)
    if shape != (n, n):
        return (*jacobian_callback(jac, n, args, failure), None)
    if is_sparse(m):
        sparse = SparseJacobian(jac, n, args, failure, m, (t0, y))
        return _no_jacobian, 0, 0, sparse
    return (*jacobian_callback(jac, n, args, failure, first=(t0, y, m)), None)


class SparseJacobian:
    """A callable ``jac`` whose first value is a sparse matrix, as the values callback of
    flat_sparse_jac.f90 (``callback``, a plain function of (t, y)): ``self(t, y)`` returns
    df/dy's nnz values on the pattern fixed by that first value (CSC order). ``pattern``: (nnz, column pointers, rows), 1-based, for
    the flat routines. A later value (sparse or dense) with another structure is mapped
    onto the pattern; a nonzero entry outside it, a bad shape or an exception is kept in
    ``failure`` and NaN returned, so that the solver stops."""

    def __init__(self, jac, n, args, failure, first, at):
        c = first.tocsc(copy=True)
        c.sum_duplicates()                      # canonical: sorted rows, no duplicates
        self.jac, self.n, self.args, self.failure = jac, n, args, failure
        self._ptr = np.asarray(c.indptr)
        self._rows = np.asarray(c.indices)
        nnz = self._rows.size
        self._cols = np.repeat(np.arange(n), np.diff(self._ptr))
        self._keys = self._cols.astype(np.int64) * n + self._rows     # sorted
        self._nan = np.full(max(nnz, 1), math.nan)
        self._held = [(at[0], at[1], np.array(c.data, dtype=float))]
        self.nnz = nnz
        # f2py hands a plain function only the arguments it names (t, y)

        def callback(t, y):
            return self(t, y)
        self.callback = callback
        self.pattern = (nnz, (self._ptr + 1).astype(np.intc),
                        (self._rows + 1).astype(np.intc) if nnz else
                        np.zeros(1, dtype=np.intc))

    def __call__(self, t, y):
        if self.failure:
            return self._nan
        try:
            v = _held_value(self._held, t, y)
            if v is not None:
                return v
            return self.values(self.jac(t, y.copy(), *self.args), t)
        except BaseException as exc:        # noqa: B036 (kept, re-raised by the caller)
            self.failure.append(exc)
            return self._nan

    def values(self, m, t):
        """The values of m (sparse or dense (n, n)) on the pattern, in its order."""
        n = self.n
        if is_sparse(m):
            if tuple(m.shape) != (n, n):
                raise _shape_error(n, tuple(m.shape))
            c = m.tocsc()
            if not c.has_canonical_format:
                c = c.copy()
                c.sum_duplicates()
            if c.indices.size == self.nnz and np.array_equal(c.indptr, self._ptr) and \
                    np.array_equal(c.indices, self._rows):
                return np.asarray(c.data, dtype=float)
            rows, vals = np.asarray(c.indices), np.asarray(c.data, dtype=float)
            cols = np.repeat(np.arange(n), np.diff(c.indptr))
            return self._onto_pattern(rows, cols, vals, t)
        a = np.asarray(m, dtype=float)
        if a.shape != (n, n):
            raise _shape_error(n, a.shape)
        rows, cols = np.nonzero(a)
        return self._onto_pattern(rows, cols, a[rows, cols], t)

    def _onto_pattern(self, rows, cols, vals, t):
        keys = cols.astype(np.int64) * self.n + rows
        pos = np.searchsorted(self._keys, keys)
        inside = pos < self._keys.size
        inside[inside] = self._keys[pos[inside]] == keys[inside]
        outside = ~inside & (vals != 0)
        if outside.any():
            k = int(np.argmax(outside))
            raise ValueError(
                f"jac returned at t = {t!r} a nonzero entry ({int(rows[k])}, "
                f"{int(cols[k])}) outside the sparsity pattern of its first value (at "
                "t0): a sparse jac fixes its pattern by its first call; include there "
                "every entry that can become nonzero (explicit zeros count)")
        out = np.zeros(max(self.nnz, 1))
        np.add.at(out, pos[inside], vals[inside])
        return out
