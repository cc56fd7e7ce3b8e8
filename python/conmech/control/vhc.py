"""Virtual holonomic constraints q = Phi(theta) of underactuated mechanical systems with one
passive degree of freedom: the reduced dynamics alpha theta'' + beta theta'^2 + gamma = 0,
its integral, its periodic orbits, and the feedback that keeps the constraint
(Fortran: conmech_vhc)."""
from __future__ import annotations

from typing import Any, Callable, Sequence  # noqa: F401 (annotations)

from numpy.typing import ArrayLike  # noqa: F401 (annotations)
import math

import numpy as np
from scipy.fft import dct

from .. import _conmech
from .plant import ControlledSystem, FeedbackLaw
from .._core.result import Record
from .._core.status import raise_status

__all__ = ["VirtualConstraint", "ReducedDynamics", "ReducedOrbit", "VHCFeedback"]

_POLY, _CHEB, _FOURIER = 1, 2, 3
_PAD = np.zeros(1)


def _sympy():
    try:   # sympy is optional: imported only for a constraint given as an expression
        import sympy as sp
    except ImportError:   # pragma: no cover (sympy is a dependency of the symbolic extra)
        raise ImportError("a sympy expression needs sympy (pip install sympy)") from None
    return sp


class VirtualConstraint:
    """A virtual holonomic constraint of an underactuated plant with one passive degree
    of freedom (ndof coordinates, ndof - 1 inputs): the phase coordinate theta = q[phase]
    and the others as functions q_i = Phi_i(theta).

    Parameters
    ----------
    plant : :class:`ControlledSystem` with ndof - 1 inputs.
    phase : index of the phase coordinate (often the passive one).
    shape : the other coordinates, in coordinate order (phase left out), as
        - sympy expressions in ``theta`` (default the symbol ``theta``): polynomials are
          kept exactly; any other smooth expression is replaced by its Chebyshev series on
          ``interval`` (required then), checked to 1e-13 relative together with its first
          two derivatives (ValueError if the series does not reach that);
        - an array of polynomial coefficients (ndof - 1, d + 1), ascending powers
          (``kind="poly"``, the default for arrays), or of Chebyshev coefficients on
          ``interval`` (``kind="chebyshev"``), or trigonometric ones
          [a0, a1, b1, a2, b2, ...] of a0 + sum_j a_j cos j theta + b_j sin j theta
          (``kind="fourier"``): a parametrised family, the coefficients being the
          parameters.
    """

    def __init__(self, plant, phase, shape, *, theta=None, interval=None, kind=None):
        if not isinstance(plant, ControlledSystem):
            raise TypeError("plant must be a conmech.control.ControlledSystem")
        nd = plant.ndof
        if plant.n_inputs != nd - 1:
            raise ValueError(f"a virtual holonomic constraint here needs one passive degree "
                             f"of freedom: {nd - 1} inputs for {nd} coordinates, the plant "
                             f"has {plant.n_inputs}")
        if isinstance(phase, bool) or not isinstance(phase, (int, np.integer)) or \
                not 0 <= phase < nd:
            raise ValueError(f"phase must be a coordinate index in 0..{nd - 1}")
        self.plant = plant
        self.phase = int(phase)
        self.interval = None
        self.expressions = None
        if interval is not None:
            a, b = (float(v) for v in interval)
            if not (math.isfinite(a) and math.isfinite(b) and a < b):
                raise ValueError("interval must be (a, b) with a < b")
            self.interval = (a, b)
        if isinstance(shape, np.ndarray) or (isinstance(shape, (list, tuple)) and shape and
                                             all(isinstance(r, (list, tuple, np.ndarray))
                                                 for r in shape)):
            c = np.asarray(shape, dtype=float)
            if c.ndim == 1:
                c = c[None, :]
            kind = (kind or "poly").lower()
            codes = {"poly": _POLY, "chebyshev": _CHEB, "fourier": _FOURIER}
            if kind not in codes:
                raise ValueError("kind must be 'poly', 'chebyshev' or 'fourier'")
            if c.shape[0] != nd - 1 or c.shape[1] < 1 or not np.all(np.isfinite(c)):
                raise ValueError(f"the coefficients must be a finite ({nd - 1}, ncoef) array")
            if kind == "fourier" and c.shape[1] % 2 == 0:
                raise ValueError("fourier coefficients come as [a0, a1, b1, a2, b2, ...] "
                                 "(an odd number per row)")
            if kind == "chebyshev" and self.interval is None:
                raise ValueError("a Chebyshev series needs its interval")
            self.kind = codes[kind]
            self.coefficients_ = c
        else:
            self._from_sympy(shape, theta)
        a, b = self.interval if self.interval is not None else (-1.0, 1.0)
        self._a, self._b = a, b
        self.sgn = self._annihilator_sign()

    def _from_sympy(self, shape, theta):
        sp = _sympy()
        nd = self.plant.ndof
        exprs = list(shape) if isinstance(shape, (list, tuple)) else [shape]
        exprs = [sp.sympify(e) for e in exprs]
        if len(exprs) != nd - 1:
            raise ValueError(f"shape needs {nd - 1} expressions (one per coordinate other "
                             f"than the phase), got {len(exprs)}")
        th = theta if theta is not None else sp.Symbol("theta")
        for e in exprs:
            extra = e.free_symbols - {th}
            if extra:
                raise ValueError(f"the constraint may depend on {th} only; {e} has "
                                 f"{sorted(map(str, extra))}")
        self.expressions = exprs
        polys = []
        for e in exprs:
            try:
                p = sp.Poly(e, th)
                polys.append([float(v) for v in reversed(p.all_coeffs())])
            except (sp.PolynomialError, sp.GeneratorsNeeded, TypeError):
                polys = None
                break
        if polys is not None:
            d = max(len(p) for p in polys)
            c = np.zeros((nd - 1, d))
            for i, p in enumerate(polys):
                c[i, :len(p)] = p
            self.kind = _POLY
            self.coefficients_ = c
            return
        if self.interval is None:
            raise ValueError("a constraint that is not a polynomial in theta is represented "
                             "by its Chebyshev series: give interval=(theta_min, theta_max)")
        a, b = self.interval
        fs = [sp.lambdify(th, e, "numpy") for e in exprs]
        d1 = [sp.lambdify(th, sp.diff(e, th), "numpy") for e in exprs]
        d2 = [sp.lambdify(th, sp.diff(e, th, 2), "numpy") for e in exprs]
        cheb = np.polynomial.chebyshev
        rows = []
        npts = 128
        xk = np.cos(np.pi*(np.arange(npts) + 0.5)/npts)
        for f in fs:
            # interpolation at the Chebyshev points by the DCT (stable), then the tail
            # below round-off dropped (it would only add noise to the derivatives)
            vals = np.broadcast_to(np.asarray(f(0.5*(a + b) + 0.5*(b - a)*xk), dtype=float),
                                   xk.shape)
            c = dct(vals, type=2)/npts
            c[0] *= 0.5
            keep = np.nonzero(np.abs(c) > 1e-15*max(np.max(np.abs(c)), 1e-300))[0]
            rows.append(c[:keep[-1] + 1] if keep.size else c[:1])
        d = max(r.size for r in rows)
        c = np.zeros((nd - 1, d))
        for i, r in enumerate(rows):
            c[i, :r.size] = r
        tt = np.linspace(a, b, 997)
        s = (2*tt - a - b)/(b - a)
        for i in range(nd - 1):
            for order, fun in ((0, fs[i]), (1, d1[i]), (2, d2[i])):
                ref = np.broadcast_to(np.asarray(fun(tt), dtype=float), tt.shape)
                ser = cheb.chebval(s, cheb.chebder(c[i], order))*(2/(b - a))**order
                tol = (1e-13 if order == 0 else 1e-11 if order == 1 else 1e-9)
                if np.max(np.abs(ser - ref)) > tol*max(1.0, np.max(np.abs(ref))):
                    raise ValueError(f"the Chebyshev series of {self.expressions[i]} on "
                                     f"{self.interval} misses derivative {order} by "
                                     f"{np.max(np.abs(ser - ref)):.2e}: the expression is not "
                                     "smooth enough there")
        self.kind = _CHEB
        self.coefficients_ = c

    def _annihilator_sign(self):
        """B_perp's sign: its largest entry positive (for actuated-coordinate inputs it is
        then e_passive); for a q-dependent compiled B the sign is +1."""
        b = self.plant.B
        nd = self.plant.ndof
        if self.plant._baddr:
            return 1.0
        cof = np.array([(-1)**i*np.linalg.det(np.delete(b, i, axis=0)) if nd > 1 else 1.0
                        for i in range(nd)])
        return 1.0 if cof[np.argmax(np.abs(cof))] > 0 else -1.0

    def _desc(self):
        """(ilaw, rlaw) of the constraint as a kind-3 law with zero gains."""
        nd = self.plant.ndof
        c = self.coefficients_
        ilaw = np.array([3, nd - 1, self.phase + 1, self.kind, c.shape[1]], dtype=np.int64)
        rlaw = np.concatenate([[self._a, self._b, self.sgn], c.ravel(order="F"),
                               np.zeros(2*(nd - 1))])
        return ilaw, rlaw

    def _flat(self):
        ilaw, rlaw = self._desc()
        return dict(nil=ilaw.size, ilaw=ilaw, nrl=rlaw.size, rlaw=rlaw)

    def evaluate(self, theta):
        """(Phibar, Phibar', Phibar'') at theta (scalar or array): arrays (..., ndof)."""
        al, be, ga, ph, d1, d2 = self._eval(theta)
        return ph, d1, d2

    def _eval(self, theta):
        th = np.ascontiguousarray(np.atleast_1d(np.asarray(theta, dtype=float)).ravel())
        if not np.all(np.isfinite(th)):
            raise ValueError("theta must be finite")
        out = _conmech.flat_control_vhc(**self.plant._flat(), **self._flat(), thetas=th)
        al, be, ga, ph, d1, d2, info, message = out
        if info != 0:
            raise_status(info, message)
        scal = np.ndim(theta) == 0
        res = (np.array(al), np.array(be), np.array(ga), np.array(ph).T, np.array(d1).T,
               np.array(d2).T)
        return tuple(r[0] for r in res) if scal else res

    def coefficients(self, theta):
        """(alpha, beta, gamma) of the reduced dynamics at theta (scalar or array)."""
        al, be, ga, *_ = self._eval(theta)
        return al, be, ga

    def state(self, theta, dtheta):
        """The full state [Phibar(theta), Phibar'(theta) theta'] on the constraint."""
        ph, d1, _ = self.evaluate(theta)
        return np.concatenate([ph, d1*np.asarray(dtheta)[..., None]], axis=-1) \
            if np.ndim(theta) else np.concatenate([ph, d1*dtheta])

    def reduced(self) -> "ReducedDynamics":
        """The reduced dynamics alpha theta'' + beta theta'^2 + gamma = 0."""
        return ReducedDynamics(self)

    def feedback(self, kp: ArrayLike = 0.0, kd: ArrayLike = 0.0) -> "VHCFeedback":
        """The feedback that keeps the constraint: computed torque making the outputs
        y = q_o - Phi(theta) obey y'' = -kp y - kd y' (partial feedback linearisation)."""
        return VHCFeedback(self, kp, kd)

    def __repr__(self):
        kinds = {_POLY: "polynomial", _CHEB: "Chebyshev", _FOURIER: "trigonometric"}
        return (f"VirtualConstraint(phase={self.phase}, {kinds[self.kind]}, "
                f"{self.coefficients_.shape[1]} coefficients per coordinate)")


class VHCFeedback(FeedbackLaw):
    """The constraint-keeping feedback of a :class:`VirtualConstraint` (see
    :meth:`VirtualConstraint.feedback`), evaluated in Fortran."""

    def __init__(self, constraint, kp=0.0, kd=0.0):
        nd = constraint.plant.ndof
        kp = np.broadcast_to(np.asarray(kp, dtype=float), (nd - 1,)).copy()
        kd = np.broadcast_to(np.asarray(kd, dtype=float), (nd - 1,)).copy()
        if not (np.all(np.isfinite(kp)) and np.all(np.isfinite(kd))):
            raise ValueError("kp and kd must be finite")
        self.constraint = constraint
        self.kp, self.kd = kp, kd
        self.n_inputs = nd - 1

    def _flat(self):
        ilaw, rlaw = self.constraint._desc()
        nd = self.constraint.plant.ndof
        rlaw = rlaw.copy()
        rlaw[-2*(nd - 1):] = np.concatenate([self.kp, self.kd])
        return ilaw, rlaw, None


class ReducedOrbit(Record):
    """A periodic solution of the reduced dynamics (an oscillation between the turning
    points theta_min and theta_max, theta' = 0 there).

    Attributes: theta0 (the start, a turning point), theta_min, theta_max, period (by
    integrating the reduced dynamics to its second return to theta' = 0),
    period_quadrature (2 int dtheta / sqrt(E(theta)) by Gauss-Legendre quadrature in
    theta = mid - half cos(phi)) and its error estimate quadrature_error (the change from
    n to 2n nodes), alpha_range (min, max of alpha along the orbit), x0 (the full state at
    theta0), t and states (the reduced solution (nt, 2) over one period).
    """

    __slots__ = ("theta0", "theta_min", "theta_max", "period", "period_quadrature",
                 "quadrature_error", "alpha_range", "x0", "t", "states", "constraint")

    @property
    def y0(self):
        return self.x0

    def __repr__(self):
        return (f"ReducedOrbit(theta in [{self.theta_min:.6g}, {self.theta_max:.6g}], "
                f"period={self.period:.12g})")


class ReducedDynamics:
    """alpha(theta) theta'' + beta(theta) theta'^2 + gamma(theta) = 0 of a virtual
    constraint, integrated in Fortran (conmech_vhc)."""

    def __init__(self, constraint):
        self.constraint = constraint
        self._plant = constraint.plant

    def coefficients(self, theta):
        return self.constraint.coefficients(theta)

    def _args(self):
        return dict(**self._plant._flat(), **self.constraint._flat())

    def solve(self, y0, t_span, t_eval=None, rtol=1e-12, atol=1e-12, events=False,
              max_events=64):
        """The reduced solution from y0 = (theta, theta') at t_eval (default 201 points):
        (t, states (nt, 2)), and with ``events`` the crossings of theta' = 0 (times,
        states)."""
        y0 = np.asarray(y0, dtype=float).ravel()
        if y0.size != 2 or not np.all(np.isfinite(y0)):
            raise ValueError("y0 must be (theta, theta')")
        t0, t1 = (float(v) for v in t_span)
        te = np.linspace(t0, t1, 201) if t_eval is None else np.ascontiguousarray(
            np.asarray(t_eval, dtype=float).ravel())
        out = _conmech.flat_control_reduced(**self._args(), y0=y0, t0=t0, t1=t1, neval=te.size,
                                            t_eval=te, with_events=int(bool(events)),
                                            maxev=int(max_events), rtol=float(rtol),
                                            atol=float(atol))
        ys, nev, ev_t, ev_y, info, message = out
        if info < 0:
            raise_status(info, message)
        res = (te, np.array(ys).T)
        if events:
            return res + (np.array(ev_t)[:nev], np.array(ev_y).T[:nev])
        return res

    def energy(self, theta, theta0, dtheta0, rtol=1e-13, atol=1e-13, stop_at_zero=False):
        """E(theta) = theta'^2 of the reduced solution through (theta0, theta0') at the
        thetas (monotone away from theta0), from the linear equation
        dE/dtheta = -2 (beta E + gamma)/alpha; with ``stop_at_zero`` also the first turning
        point (E = 0) or None."""
        th = np.ascontiguousarray(np.atleast_1d(np.asarray(theta, dtype=float)).ravel())
        d = np.diff(np.concatenate([[theta0], th]))
        if not (np.all(d > 0) or np.all(d < 0)):
            raise ValueError("theta must move monotonically away from theta0")
        es, tz, found, info, message = _conmech.flat_control_energy(
            **self._args(), theta0=float(theta0), e0=float(dtheta0)**2, thetas=th,
            stop_at_zero=int(bool(stop_at_zero)), rtol=float(rtol), atol=float(atol))
        if info != 0:
            raise_status(info, message)
        es = np.array(es)
        if stop_at_zero:
            return es, (float(tz) if found else None)
        return es

    def integral(self, theta, dtheta, theta0, dtheta0, rtol=1e-13, atol=1e-13):
        """Shiriaev's integral I = theta'^2 - psi(theta0, theta) (theta0'^2 -
        int_theta0^theta psi(theta0, s) 2 gamma(s)/alpha(s) ds), psi(a, b) =
        exp(-2 int_a^b beta/alpha), i.e. theta'^2 - E(theta) with E the solution of the
        linear equation above through (theta0, theta0'^2): constant along every solution
        of the reduced dynamics, zero along the one through (theta0, theta0'). theta and
        dtheta: arrays (any order)."""
        th = np.atleast_1d(np.asarray(theta, dtype=float)).ravel()
        dth = np.broadcast_to(np.asarray(dtheta, dtype=float), th.shape).ravel()
        out = np.empty(th.size)
        for sign in (1, -1):
            sel = np.nonzero((th - theta0)*sign > 0)[0]
            if sel.size:
                order = sel[np.argsort((th[sel] - theta0)*sign)]
                out[order] = self.energy(th[order], theta0, dtheta0, rtol, atol)
        at0 = th == theta0
        out[at0] = float(dtheta0)**2
        res = dth**2 - out
        return res if np.ndim(theta) else float(res[0])

    def equilibria(self, theta_range, n=2001):
        """The zeros of gamma in theta_range (sampling + bisection) with their kind: a
        'centre' where gamma'/alpha > 0, a 'saddle' where it is < 0."""
        a, b = (float(v) for v in theta_range)
        th = np.linspace(a, b, int(n))
        _, _, ga = self.constraint.coefficients(th)
        out = []
        for i in np.nonzero(np.sign(ga[:-1])*np.sign(ga[1:]) <= 0)[0]:
            lo, hi = th[i], th[i + 1]
            glo = ga[i]
            if glo == 0:
                z = lo
            else:
                for _ in range(200):
                    mid = 0.5*(lo + hi)
                    gm = self.constraint.coefficients(mid)[2]
                    if gm == 0 or hi - lo < 1e-15*max(1, abs(mid)):
                        break
                    if np.sign(gm) == np.sign(glo):
                        lo, glo = mid, gm
                    else:
                        hi = mid
                z = 0.5*(lo + hi)
            if out and abs(z - out[-1][0]) < 1e-9:
                continue
            h = 1e-6*max(1.0, abs(z))
            al = self.constraint.coefficients(z)[0]
            dg = (self.constraint.coefficients(z + h)[2] - self.constraint.coefficients(z - h)[2])/(2*h)
            out.append((z, "centre" if dg/al > 0 else "saddle", float(np.sqrt(abs(dg/al)))))
        return out

    def periodic_orbit(self, theta0: float, *, nodes: int = 32, rtol: float = 1e-13,
                       atol: float = 1e-13, max_swing: float = 2*np.pi) -> ReducedOrbit:
        """The oscillation through the turning point (theta0, theta' = 0): the other
        turning point from E(theta) = 0, the period by quadrature and by integration
        (they must agree), the range of alpha along it (ValueError if alpha vanishes or
        changes sign there: the constraint is not regular along the orbit) and the full
        state x0 = [Phibar(theta0), 0]."""
        theta0 = float(theta0)
        al0, be0, ga0 = self.constraint.coefficients(theta0)
        if not abs(al0) > 0:
            raise ValueError(f"the constraint is not regular at theta0 = {theta0}: alpha = 0")
        acc = -ga0/al0
        if acc == 0:
            raise ValueError(f"theta0 = {theta0} is an equilibrium of the reduced dynamics")
        direction = 1.0 if acc > 0 else -1.0
        # E from theta0 towards the motion, up to where alpha changes sign (there the
        # reduced dynamics is singular); the turning point where E returns to 0
        grid = theta0 + direction*np.linspace(0, max_swing, 4001)[1:]
        al_grid = self.constraint.coefficients(grid)[0]
        bad = np.nonzero((np.sign(al_grid) != np.sign(al0)) |
                         (np.abs(al_grid) <= 1e-10*abs(al0)))[0]
        upto = grid[:bad[0]] if bad.size else grid
        tz = None
        if upto.size:
            try:
                es, tz = self.energy(upto, theta0, 0.0, rtol, atol, stop_at_zero=True)
            except RuntimeError:
                tz = None
        if tz is None:
            if bad.size:
                raise ValueError(f"the constraint is not regular along the orbit: "
                                 f"alpha(theta) crosses zero near theta = {grid[bad[0]]:.6g} "
                                 f"before the motion from theta0 = {theta0:.6g} turns back")
            raise ValueError(f"no oscillation through theta0 = {theta0}: theta' does not "
                             f"return to 0 within {max_swing:.3g} rad (a rotation, or an "
                             "unbounded motion)")
        lo, hi = sorted((theta0, tz))
        ths = np.linspace(lo, hi, 801)
        al = self.constraint.coefficients(ths)[0]
        amin, amax = float(np.min(al)), float(np.max(al))
        if amin*amax <= 0 or min(abs(amin), abs(amax)) <= 1e-10*max(abs(amin), abs(amax)):
            raise ValueError(f"the constraint is not regular along the orbit: alpha(theta) "
                             f"vanishes between {lo:.6g} and {hi:.6g}")
        # period by quadrature, theta = mid - half cos(phi): the integrand is smooth
        tq, err = self._period_quadrature(theta0, tz, nodes, rtol, atol)
        # period by integration: the second return to theta' = 0
        t_end = 1.25*tq
        _, _, evt, evy = self.solve([theta0, 0.0], (0.0, t_end), [0.0, t_end], rtol=rtol,
                                    atol=atol, events=True)
        ret = evt[evt > 1e-6*tq]
        if ret.size < 2:
            raise RuntimeError("the reduced solution did not return to theta' = 0 twice")
        period = float(ret[1])
        t, st = self.solve([theta0, 0.0], (0.0, period), np.linspace(0, period, 257),
                           rtol=rtol, atol=atol)
        x0 = self.constraint.state(theta0, 0.0)
        return ReducedOrbit(theta0=theta0, theta_min=lo, theta_max=hi, period=period,
                            period_quadrature=tq, quadrature_error=err,
                            alpha_range=(amin, amax), x0=x0, t=t, states=st,
                            constraint=self.constraint)

    def _period_quadrature(self, ta, tb, nodes, rtol, atol):
        """2 int_ta^tb dtheta/sqrt(E) with theta = mid - half cos(phi) (the integrand
        half sin(phi)/sqrt(E) is smooth: E vanishes linearly at both turning points).
        E is integrated from each turning point towards the middle (E = 0 there exactly,
        and its small values near the ends keep their relative accuracy: atol 1e-18):
        one branch from ta alone would reach tb as a difference of large numbers, and the
        quadrature nodes next to tb would see that error amplified by 1/sqrt(E)."""
        mid, half = 0.5*(ta + tb), 0.5*(tb - ta)
        tiny = 1e-18

        def quad(nn):
            x, w = np.polynomial.legendre.leggauss(nn)
            phi = 0.5*np.pi*(x + 1)
            wphi = 0.5*np.pi*w
            th = mid - half*np.cos(phi)          # from ta (phi = 0) to tb (phi = pi)
            e = np.empty(nn)
            first = phi < 0.5*np.pi
            for sel, start in ((first, ta), (~first, tb)):
                idx = np.nonzero(sel)[0]
                order = idx[np.argsort(np.abs(th[idx] - start))]
                e[order] = self.energy(th[order], start, 0.0, rtol, tiny)
            if np.any(e <= 0):
                raise RuntimeError("E vanishes inside the orbit: not an oscillation")
            return 2*np.sum(wphi*abs(half)*np.sin(phi)/np.sqrt(e))
        ea = self.energy([mid], ta, 0.0, rtol, tiny)[0]
        eb = self.energy([mid], tb, 0.0, rtol, tiny)[0]
        if abs(ea - eb) > 1e-8*max(abs(ea), abs(eb)):
            raise RuntimeError(f"the turning points do not bound one orbit (E from either "
                               f"end differs by {abs(ea - eb):.2e} in the middle)")
        t1, t2 = quad(nodes), quad(2*nodes)
        return float(t2), float(abs(t2 - t1))

    def phase_portrait(self, theta_range, starts, *, orbit=None, ax=None, t_max=20.0,
                       n=801):
        """Plot reduced solutions (theta, theta') from the start points (theta, theta')
        for t in [0, t_max] (stopping where alpha vanishes), the chosen orbit (thick), the
        equilibria, and the lines where alpha = 0; returns the axes."""
        # matplotlib is optional: imported only when a figure is drawn
        import matplotlib.pyplot as plt
        if ax is None:
            _, ax = plt.subplots(figsize=(6, 4.5))
        a, b = theta_range
        for s in starts:
            try:
                t, st = self.solve(s, (0, t_max), np.linspace(0, t_max, n), rtol=1e-10,
                                   atol=1e-10)
            except (RuntimeError, ValueError):
                continue
            ok = np.all(np.isfinite(st), axis=1) & (st[:, 0] >= a) & (st[:, 0] <= b)
            stop = np.argmin(ok) if not ok.all() else st.shape[0]
            ax.plot(st[:stop, 0], st[:stop, 1], color="0.55", lw=0.8)
        if orbit is not None:
            ax.plot(orbit.states[:, 0], orbit.states[:, 1], color="C3", lw=2.2,
                    label=f"chosen orbit, T = {orbit.period:.4f}")
        for z, kind, w in self.equilibria(theta_range):
            ax.plot(z, 0, "o" if kind == "centre" else "x", color="k", ms=6)
        th = np.linspace(a, b, 2001)
        al = self.constraint.coefficients(th)[0]
        for j, i in enumerate(np.nonzero(np.sign(al[:-1]) != np.sign(al[1:]))[0]):
            ax.axvline(th[i], color="C0", ls="--", lw=1, label="alpha = 0" if j == 0 else None)
        ax.set_xlim(a, b)
        ax.set_xlabel("theta")
        ax.set_ylabel("theta'")
        ax.legend(loc="upper right", fontsize=8)
        return ax
