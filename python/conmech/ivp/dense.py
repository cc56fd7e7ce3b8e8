"""Dense output: the continuous solution of an integration as piecewise polynomials, one
per step, in the forms of conmech_ode_dense (Hairer's and the power basis); SciPy's
OdeSolution (any interpolants, one per segment), the constant interpolant of a step of
length zero, and the complex view of the solution of a complex system integrated as its
real and imaginary parts."""
import itertools

import numpy as np

__all__ = ["DenseOutput", "OdeSolution", "ConstantDenseOutput", "ComplexSolution"]


class DenseOutput:
    """Continuous solution of an integration: piecewise polynomials, one per step.

    ``sol(t)`` accepts a scalar (returns shape (n,)) or an array of times (returns shape
    (n, len(t))); outside [t_min, t_max] the end polynomials are extrapolated, as SciPy's
    OdeSolution does. SciPy's OdeSolution attributes: ``ts`` (segment boundaries, in the
    direction of integration), ``ts_sorted``, ``interpolants`` (one callable per step, with
    t_old and t), ``n_segments``, ``t_min``, ``t_max``, ``ascending``. On each step
    [ts, ts + h], with x = (t - ts) / h, the polynomial is
    in Hairer's form y0 + x (F1 + (1 - x)(F2 + x (F3 + (1 - x)(F4 + ...)))) (form 1:
    RK4, DOPRI5, DOP853) or in the power basis y0 + x F1 + x^2 F2 + ... (form 2:
    VERNER98), as in conmech_ode_solver's dense_solution.
    """

    HAIRER = 1
    POWER = 2

    def __init__(self, ts, hs, coef, t_min, t_max, form=HAIRER):
        if form not in (self.HAIRER, self.POWER):
            raise ValueError(f"unknown dense output form {form}")
        self.form = form
        self.t_start = np.ascontiguousarray(ts, dtype=float)   # step starts
        self.h = np.ascontiguousarray(hs, dtype=float)          # signed step lengths
        self.coef = np.ascontiguousarray(coef, dtype=float)     # (n, nf + 1, nseg)
        self.t_min = float(min(t_min, t_max))
        self.t_max = float(max(t_min, t_max))
        self.n_segments = self.t_start.size
        self.ts = np.append(self.t_start, self.t_start[-1] + self.h[-1]) \
            if self.n_segments else np.array([t_min])
        self._ascending = self.n_segments == 0 or self.h[0] > 0

    # SciPy's OdeSolution attributes
    @property
    def ascending(self):
        """True when the integration went forward in time."""
        return bool(self._ascending)

    @property
    def ts_sorted(self):
        """The segment boundaries in ascending order."""
        return self.ts if self._ascending else self.ts[::-1]

    @property
    def side(self):
        return "right" if self._ascending else "left"

    @property
    def interpolants(self):
        """One callable per step (SciPy's DenseOutput objects): ``interpolants[i](t)``
        evaluates the polynomial of step i, with attributes t_old, t, t_min, t_max."""
        return [_Segment(self, i) for i in range(self.n_segments)]

    def __call__(self, t):
        t = np.asarray(t, dtype=float)
        scalar = t.ndim == 0
        tt = np.atleast_1d(t).ravel()
        if self.n_segments == 0:
            raise ValueError("the dense output is empty (no step was taken)")
        if self._ascending:
            idx = np.searchsorted(self.t_start, tt, side="right") - 1
        else:
            idx = np.searchsorted(-self.t_start, -tt, side="right") - 1
        np.clip(idx, 0, self.n_segments - 1, out=idx)
        x = (tt - self.t_start[idx]) / self.h[idx]
        c = self.coef[:, :, idx]                      # (n, nf + 1, m)
        nf = c.shape[1] - 1
        x1 = 1.0 - x
        y = c[:, nf, :].copy()
        for j in range(nf - 1, 0, -1):
            if self.form == self.POWER:
                y *= x
            else:
                y *= x1 if j % 2 == 1 else x
            y += c[:, j, :]
        y *= x
        y += c[:, 0, :]
        return y[:, 0] if scalar else y


class _Segment:
    """The polynomial of one step of a :class:`DenseOutput` (SciPy's DenseOutput)."""

    __slots__ = ("_sol", "_i", "t_old", "t", "t_min", "t_max")

    def __init__(self, sol, i):
        self._sol, self._i = sol, i
        self.t_old = float(sol.t_start[i])
        self.t = float(sol.t_start[i] + sol.h[i])
        self.t_min, self.t_max = min(self.t_old, self.t), max(self.t_old, self.t)

    def __call__(self, t):
        sol = DenseOutput(self._sol.t_start[self._i:self._i + 1],
                          self._sol.h[self._i:self._i + 1],
                          self._sol.coef[:, :, self._i:self._i + 1], self.t_old, self.t,
                          form=self._sol.form)
        return sol(t)


class ConstantDenseOutput:
    """The constant ``value`` on [t_old, t] (SciPy's ConstantDenseOutput): a step of length
    zero, or a state of dimension zero. ``sol(t)`` has shape (n,) for a scalar t, (n, m)
    for m times."""

    def __init__(self, t_old, t, value):
        self.t_old, self.t = t_old, t
        self.t_min, self.t_max = min(t, t_old), max(t, t_old)
        self.value = np.array(value)
        if self.value.dtype.kind not in "fc":
            self.value = self.value.astype(float)

    def __call__(self, t):
        t = np.asarray(t)
        if t.ndim == 0:
            return self.value.copy()
        return np.repeat(self.value[:, None], t.size, axis=1)


class OdeSolution:
    """Continuous solution made of local interpolants (SciPy's ``OdeSolution``).

    Parameters
    ----------
    ts : array_like, shape (n_segments + 1,)
        Segment boundaries, strictly increasing or decreasing (or two equal values: a
        segment of length zero).
    interpolants : list of callables
        ``interpolants[i](t)`` is the solution on [ts[i], ts[i + 1]] (any callable of t
        returning shape (n,) or (n, m): conmech's or SciPy's DenseOutput objects).
    alt_segment : bool
        At a boundary, evaluate the segment that ENDS there (False, SciPy's default: the
        lower index) or the one that STARTS there (True).

    ``sol(t)`` evaluates the segment that contains t (the end segments outside [t_min,
    t_max]); attributes ts, interpolants, n_segments, t_min, t_max, ascending,
    ts_sorted.
    """

    def __init__(self, ts, interpolants, alt_segment=False):
        ts = np.asarray(ts, dtype=float)
        if ts.ndim != 1:
            raise ValueError("`ts` must be 1-dimensional.")
        d = np.diff(ts)
        if not ((ts.size == 2 and ts[0] == ts[-1]) or np.all(d > 0) or np.all(d < 0)):
            raise ValueError("`ts` must be strictly increasing or decreasing.")
        self.interpolants = list(interpolants)
        self.n_segments = len(self.interpolants)
        if ts.shape != (self.n_segments + 1,):
            raise ValueError("Numbers of time stamps and interpolants don't match.")
        self.ts = ts
        self.ascending = bool(ts[-1] >= ts[0])
        if self.ascending:
            self.t_min, self.t_max = ts[0], ts[-1]
            self.ts_sorted = ts
            self.side = "right" if alt_segment else "left"
        else:
            self.t_min, self.t_max = ts[-1], ts[0]
            self.ts_sorted = ts[::-1]
            self.side = "left" if alt_segment else "right"

    def _segments(self, t):
        idx = np.searchsorted(self.ts_sorted, t, side=self.side) - 1
        idx = np.clip(idx, 0, self.n_segments - 1)
        return idx if self.ascending else self.n_segments - 1 - idx

    def __call__(self, t):
        t = np.asarray(t, dtype=float)
        if t.ndim == 0:
            return self.interpolants[int(self._segments(t))](t)
        order = np.argsort(t, kind="stable")
        seg = self._segments(t[order])
        parts, start = [], 0
        for k, group in itertools.groupby(seg):
            stop = start + len(list(group))
            parts.append(np.asarray(self.interpolants[int(k)](t[order[start:stop]])))
            start = stop
        if not parts:
            return np.empty((0, 0))
        ys = np.hstack(parts)
        out = np.empty_like(ys)
        out[:, order] = ys
        return out


class ComplexSolution:
    """The complex solution y = u + i v of a system integrated as [u; v] (2n real
    components): ``sol(t)`` of the real solution, recombined; its attributes passed on."""

    def __init__(self, real_solution, n):
        self._sol = real_solution
        self._n = n

    def __call__(self, t):
        y = np.asarray(self._sol(t))
        return y[:self._n] + 1j * y[self._n:]

    def __getattr__(self, name):
        if name == "interpolants":
            return [ComplexSolution(s, self._n) for s in self._sol.interpolants]
        return getattr(self._sol, name)
