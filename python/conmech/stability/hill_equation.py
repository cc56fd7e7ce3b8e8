"""Hill's equation N'' + Phi(t) N = 0: its monodromy over one period."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import numpy as np

from .. import _conmech
from .._core.callback import Guard, as_result
from .._core.result import DictResult
from .._core.validate import _real
from .._core.status import raise_status

class HillEquationResult(DictResult):
    """dict with monodromy (2, 2), half_trace, det, multipliers, stable."""


def _band_limited(p):
    """Samples with the same trigonometric interpolant as ``p`` but only as many as its
    significant harmonics need (coefficients below 1e-15 of the largest one dropped):
    a constant or a low-order Phi sampled a million times costs nothing."""
    c = np.fft.rfft(p)
    mag = np.abs(c)
    big = mag > 1e-15*max(mag.max(), 1e-300)
    k = int(np.nonzero(big)[0].max()) if big.any() else 0
    ns = p.size
    if 2*k + 1 >= ns or (ns % 2 == 0 and k == ns//2):
        return p
    m = max(2*k + 1, 3)
    return np.ascontiguousarray(np.fft.irfft(c[:k + 1], n=m)*(m/ns))


def hill_equation(phi: Callable[[float], float] | ArrayLike, period: float,
                  rtol: float = 1e-12) -> HillEquationResult:
    """Monodromy over one period of N'' + Phi(t) N = 0.

    ``phi`` is a callable Phi(t) or an array of equally spaced samples over one period
    (Phi(k T/ns), k = 0..ns-1; trigonometric interpolation, truncated to its significant
    harmonics). Stable iff |half trace| < 1.
    """
    period = _real(period, "period", 0.0, low_open=True)
    rtol = _real(rtol, "rtol", 0.0, 1.0, low_open=True)
    if callable(phi):
        p0 = phi(0.0)
        as_result(p0, (), "phi")
        g = Guard()
        cb = g.wrap(phi, 1, (), "phi", scalar=True)
        mono, ht, det, info, message = _conmech.flat_hill_equation_callback(cb, period, rtol)
        g.check()
    else:
        p = np.asarray(phi)
        if p.dtype.kind == "c":
            raise TypeError("phi samples must be real")
        try:
            p = np.ascontiguousarray(np.asarray(p, dtype=float).ravel())
        except (TypeError, ValueError):
            raise TypeError("phi must be a callable or an array of real samples") from None
        if p.size < 3 or not np.all(np.isfinite(p)):
            raise ValueError("phi samples: need at least 3 finite values")
        p = _band_limited(p)
        mono, ht, det, info, message = _conmech.flat_hill_equation_samples(p, period, rtol)
    if info != 0:
        raise_status(info, message)
    mono = np.array(mono)
    return HillEquationResult(monodromy=mono, half_trace=float(ht), det=float(det),
                              multipliers=np.linalg.eigvals(mono),
                              stable=bool(abs(ht) < 1.0))
