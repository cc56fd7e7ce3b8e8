"""One wrapper for every Python callback handed to the Fortran layer (f2py).

Every user function called from Fortran (right-hand sides, Jacobians, event functions,
mass matrices, forces, constraints, Hill's Phi(t)) goes through a :class:`Guard`:

- the inputs are copies (the Fortran buffers behind them are reused);
- the return value is checked on *every* call: ``None``, a complex value, a value that
  is not a number, or a wrong shape raises ``ValueError``/``TypeError`` naming the
  function and the expected shape (as SciPy does);
- the wrapper always hands f2py a float array of the declared shape, so f2py never fails
  a conversion (which would longjmp over the Fortran frames, leak their memory and print
  ``rv_cb_arr is NULL``);
- an exception (the user's own, a shape error, ``KeyboardInterrupt``) is kept and NaN is
  returned from then on without calling the user again: the Fortran solvers stop on the
  non-finite values and return normally, freeing their memory, and the caller re-raises
  the kept exception, unchanged (same object, same traceback), with :meth:`Guard.check`.

f2py reads the number of arguments a callback takes from its signature, so the wrappers
spell their arguments out (``nin`` = 1: ``(t)``, 2: ``(t, y)``, 3: ``(t, q, v)``).
"""
import numpy as np

__all__ = ["Guard", "as_result", "message_text"]


def message_text(message):
    """A Fortran message (bytes, numpy bytes array or str) as clean text: ASCII, printable,
    stripped (undecodable bytes are replaced, never raised on)."""
    if isinstance(message, np.ndarray):
        message = message.tobytes()
    if isinstance(message, (bytes, bytearray)):
        message = bytes(message).split(b"\0", 1)[0].rstrip().decode("ascii", "replace")
    text = str(message).strip()
    if text.isascii() and text.isprintable():      # the usual case: no copy per character
        return text
    return "".join(c if c.isascii() and c.isprintable() else "?" for c in text).strip()


def as_result(value, shape, name):
    """``value`` as a float array of ``shape``; a clear error if it cannot be one.

    A vector shape (m,) accepts any array with at most one dimension and m elements (a
    scalar when m == 1); a matrix shape accepts exactly that shape, or any shape with the
    same size when one of its dimensions is 1."""
    if value is None:
        raise ValueError(f"{name} returned None; expected an array of shape {shape}")
    arr = np.asarray(value)
    kind = arr.dtype.kind
    if kind == "c":
        raise TypeError(f"{name} returned complex values: complex problems are not "
                        "supported (split them into real and imaginary parts)")
    if kind not in "biuf":
        try:
            arr = arr.astype(float)
        except (TypeError, ValueError):
            raise TypeError(f"{name} must return real numbers, got {arr.dtype} "
                            f"({type(value).__name__})") from None
    elif kind != "f" or arr.dtype.itemsize != 8:
        arr = arr.astype(float)
    if arr.shape == shape:
        return arr
    size = 1
    for s in shape:
        size *= s
    ok = arr.size == size and (arr.ndim <= 1 if len(shape) <= 1 else 1 in shape)
    if not ok:
        raise ValueError(f"{name} must return an array of shape {shape}, got shape "
                         f"{arr.shape}")
    return arr.reshape(shape)


class Guard:
    """Keeps the first exception raised by any callback of one Fortran call.

    Usage::

        g = Guard()
        rhs = g.wrap(fun, 2, (n,), "fun", extra=args)
        out = _conmech.flat_...(rhs, ...)
        g.check()          # re-raises the kept exception, if any
    """

    __slots__ = ("error", "ncalls")

    def __init__(self):
        self.error = None
        self.ncalls = {}

    @property
    def failed(self):
        return self.error is not None

    def fail(self, exc):
        """Keep ``exc`` (the first one wins); the callbacks return NaN from now on."""
        if self.error is None:
            self.error = exc

    def check(self):
        """Re-raise the kept exception (unchanged) if a callback failed."""
        exc = self.error
        if exc is not None:
            self.error = None
            raise exc

    def count(self, name):
        """How many times the user's function ``name`` was called."""
        return self.ncalls.get(name, 0)

    def wrap(self, fun, nin, shapes, name, extra=(), scalar=False):
        """A callback for f2py calling ``fun(*inputs, *extra)``.

        nin: number of Fortran inputs passed on (1: t; 2: t, y; 3: t, q, v).
        shapes: the output shape, or a tuple of shapes when ``fun`` returns a tuple.
        scalar: the output is one float (returned as a Python float)."""
        multi = bool(shapes) and isinstance(shapes[0], tuple)
        shape_list = list(shapes) if multi else [shapes]
        if scalar:
            nan_out = float("nan")
        else:
            nans = []
            for s in shape_list:
                a = np.full(s, np.nan)
                a.flags.writeable = False
                nans.append(a)
            nan_out = tuple(nans) if multi else nans[0]
        guard = self
        calls = self.ncalls
        calls[name] = 0

        def call(inputs):
            if guard.error is not None:
                return nan_out
            try:
                calls[name] += 1
                r = fun(*inputs, *extra)
                if scalar:
                    return float(as_result(r, (), name))
                if not multi:
                    return as_result(r, shape_list[0], name)
                if r is None or not isinstance(r, (tuple, list)) or len(r) != len(shape_list):
                    raise ValueError(f"{name} must return a tuple of {len(shape_list)} "
                                     f"arrays of shapes {tuple(shape_list)}")
                return tuple(as_result(x, s, name) for x, s in zip(r, shape_list))
            except BaseException as exc:   # noqa: B036 (kept, re-raised by check())
                guard.fail(exc)
                return nan_out

        if nin == 2 and not multi and not scalar:
            # the hot path (right-hand sides: several calls per step): one Python frame,
            # and a float64 array of the right shape passes without conversion
            shape = shape_list[0]
            ndarray, asarray, f64 = np.ndarray, np.asarray, np.dtype(float)

            def cb(t, y):
                if guard.error is not None:
                    return nan_out
                try:
                    calls[name] += 1
                    r = fun(t, y.copy(), *extra)
                    arr = r if type(r) is ndarray else asarray(r)
                    if arr.dtype == f64 and arr.shape == shape:
                        return arr
                    return as_result(r, shape, name)   # converts, or raises the error
                except BaseException as exc:   # noqa: B036 (kept, re-raised by check())
                    guard.fail(exc)
                    return nan_out
        elif nin == 1:
            def cb(t):
                return call((t,))
        elif nin == 2:
            def cb(t, y):
                return call((t, y.copy()))
        elif nin == 3:
            def cb(t, q, v):
                return call((t, q.copy(), v.copy()))
        else:
            raise ValueError("nin must be 1, 2 or 3")
        return cb
