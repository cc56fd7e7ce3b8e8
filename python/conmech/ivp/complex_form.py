"""A complex initial value problem as a real one (as SciPy's explicit methods integrate
it): y = u + i v, [u; v]' = [Re f; Im f], the events and the result mapped both ways."""
import numpy as np

from .dense import ComplexSolution

__all__ = ["real_form", "real_form_event", "complex_result"]


def real_form(fun, n):
    """fun of a complex y as a function of [Re y; Im y] returning [Re f; Im f] (also for
    a vectorized fun: columns)."""
    def real_fun(t, u, *a):
        y = u[:n] + 1j * u[n:]
        r = fun(t, y, *a)
        if r is None:
            return None
        f = np.asarray(r)
        if f.dtype.kind not in "biufc":
            return f          # the callback wrapper names the bad type
        if f.size != y.size:
            raise ValueError(f"fun must return an array of shape {y.shape} (complex), got "
                             f"shape {f.shape}")
        f = f.reshape(y.shape)
        return np.concatenate([f.real, f.imag], axis=0)
    return real_fun


def real_form_event(event, n):
    """An event function of a complex y as a function of [Re y; Im y]."""
    def real_event(t, u, *a):
        return event(t, u[:n] + 1j * u[n:], *a)
    return real_event


def complex_result(res, n):
    """The result of the real form back in complex numbers."""
    if isinstance(res.y, np.ndarray):
        res.y = res.y[:n] + 1j * res.y[n:]
    if res.y_events is not None:
        res.y_events = [ye[:, :n] + 1j * ye[:, n:] if ye.size else ye for ye in res.y_events]
    if res.sol is not None:
        res.sol = ComplexSolution(res.sol, n)
    return res
