"""Exactness of Pfaffian constraints: holonomic (integrable) or non-holonomic.

A Pfaffian constraint (the lecture notes) is the differential form

    omega = a_1(q, t) dq_1 + ... + a_n(q, t) dq_n + a_0(q, t) dt = 0.

It is *holonomic* when it is equivalent to a finite constraint f(q, t) = const, that is when
an integrating factor mu(q, t) makes mu * omega exact: mu * omega = df. The test is the
Frobenius condition:

* one form: omega ^ d omega = 0 (the components
  a_i (d_j a_k - d_k a_j) + a_j (d_k a_i - d_i a_k) + a_k (d_i a_j - d_j a_i), i < j < k);
  with two variables it holds identically: every 2-variable form has an integrating factor;
* several forms omega_1..omega_k (a system of constraints): d omega_i ^ omega_1 ^ ... ^
  omega_k = 0 for every i.

`pfaffian(coeffs, coords)` checks one form and, where it is integrable, looks for mu and f:
the common factor of the coefficients is divided out first, then mu = 1 (exact form, the
seed's exactness condition d_k(a_j) = d_j(a_k)), then the standard ansatz families (a function
of one variable mu(q_k) from the one-variable condition; 1/(sum q_i a_i) for homogeneous
forms; 1/a_i; 1/prod q_i; 1/q_i^2; 1/(q_i q_j); 1/(q_i^2 + q_j^2); 1/|q|^2), and for two
variables the ODE dq_2/dq_1 = -a_1/a_2 solved by `sympy.dsolve`, whose constant of integration
gives the integral F and mu = (dF/dq_1)/a_1. Every candidate is verified: d(mu omega) = 0
simplifies to zero. The integral f is built by line integration and verified: grad f = mu a.

`pfaffian_system(forms, coords)` checks several constraints together (Frobenius),
`pfaffian_from_velocities(expr, q, qdot)` reads the form from a velocity-level constraint
sum_i a_i q_i' + a_0 = 0 (as written in the seeds: x' + r phi' cos(theta) = 0), and
`pfaffian_of(system)` checks the non-holonomic constraints of a derived constrained system.

Example (the seed's pendulum, and the rolling coin):

    >>> import sympy as sp
    >>> from conmech.symbolic import pfaffian
    >>> x, y = sp.symbols("x y")
    >>> r = pfaffian([x, y], [x, y])
    >>> r.integrable, r.integral
    (True, x**2/2 + y**2/2)
    >>> X, Y, th, ph, R = sp.symbols("x y theta phi R")
    >>> pfaffian([1, 0, 0, R*sp.cos(th)], [X, Y, th, ph]).integrable
    False
"""
from __future__ import annotations

import itertools
import signal
import threading
from dataclasses import dataclass, field
from typing import Dict, Optional, Sequence, Tuple

import sympy as sp
from .pipeline import model_of

__all__ = ["PfaffianResult", "PfaffianSystemResult", "pfaffian", "pfaffian_system",
           "pfaffian_of", "pfaffian_from_velocities", "exterior_derivative", "wedge",
           "frobenius_residual"]

Form = Dict[Tuple[int, ...], sp.Expr]


# ---------------------------------------------------------------- exterior algebra
def _perm_sign(seq):
    """Sign of the permutation that sorts `seq` (distinct entries)."""
    seq = list(seq)
    sign = 1
    for i in range(len(seq)):
        for j in range(i + 1, len(seq)):
            if seq[i] > seq[j]:
                sign = -sign
    return sign


def _clean(form: Form) -> Form:
    return {k: v for k, v in form.items() if v != 0}


def one_form(coeffs) -> Form:
    """The 1-form sum_i coeffs[i] dq_i as a dict {(i,): a_i}."""
    return _clean({(i,): sp.sympify(a) for i, a in enumerate(coeffs)})


def wedge(a: Form, b: Form) -> Form:
    """Exterior product of two forms (dicts from sorted index tuples to coefficients)."""
    out: Form = {}
    for ia, ca in a.items():
        for ib, cb in b.items():
            if set(ia) & set(ib):
                continue
            idx = ia + ib
            key = tuple(sorted(idx))
            out[key] = out.get(key, 0) + _perm_sign(idx) * ca * cb
    return _clean({k: sp.expand(v) for k, v in out.items()})


def exterior_derivative(a: Form, coords) -> Form:
    """d a for a form in the coordinates `coords`."""
    out: Form = {}
    for idx, c in a.items():
        for j, x in enumerate(coords):
            if j in idx:
                continue
            dc = sp.diff(c, x)
            if dc == 0:
                continue
            full = (j,) + idx
            key = tuple(sorted(full))
            out[key] = out.get(key, 0) + _perm_sign(full) * dc
    return _clean(out)


def _simplify(e):
    e = sp.simplify(e)
    if e != 0 and e.has(sp.sin, sp.cos, sp.tan):
        e = sp.simplify(sp.trigsimp(e))
    return e


_PROBES = ((0.7316, 1.3127, 0.4519, 1.0873, 0.8261, 1.5173, 0.6137, 1.2291),
           (1.4141, 0.5923, 1.1731, 0.3849, 1.6487, 0.9121, 1.3553, 0.7071))


def _numerically_nonzero(e) -> bool:
    """True when e is clearly non-zero at one of two fixed generic points (a cheap test
    before simplify; any doubt, e.g. a domain error, answers False)."""
    syms = sorted(e.free_symbols, key=lambda s: s.name)
    for probe in _PROBES:
        vals = {s: probe[k % len(probe)] + 0.01 * (k // len(probe)) for k, s in
                enumerate(syms)}
        try:
            v = complex(e.evalf(subs=vals))
        except (TypeError, ValueError, ZeroDivisionError):
            continue
        if v == v and abs(v) > 1e-9:  # v == v: not NaN
            return True
    return False


def _is_zero(e) -> bool:
    e = sp.sympify(e)
    if e == 0:
        return True
    if _numerically_nonzero(e):
        return False
    return _simplify(e) == 0


def _simplified_nonzero(form: Form) -> Dict[Tuple[int, ...], sp.Expr]:
    out = {}
    for k, v in form.items():
        s = _simplify(v)
        if s != 0:
            out[k] = s
    return out


def frobenius_residual(forms, coords) -> Dict[Tuple[int, ...], sp.Expr]:
    """Non-zero components of d omega_i ^ omega_1 ^ ... ^ omega_k (summed over i as a
    dict keyed by (i, component)); empty when the system satisfies Frobenius' condition."""
    oms = [one_form(f) for f in forms]
    prod: Form = {(): sp.Integer(1)}
    for om in oms:
        prod = wedge(prod, om)
    res = {}
    for i, om in enumerate(oms):
        comp = _simplified_nonzero(wedge(exterior_derivative(om, coords), prod))
        for k, v in comp.items():
            res[(i,) + k] = v
    return res


# ---------------------------------------------------------------- results
@dataclass
class PfaffianResult:
    """Exactness of one Pfaffian form omega = sum_i a_i dq_i.

    Attributes
    ----------
    integrable : bool
        Frobenius' condition omega ^ d omega = 0 holds (holonomic constraint).
    exact : bool
        The form as given is closed (d omega = 0; the seed's exactness condition, mu = 1).
    integrating_factor : sympy expression or None
        mu with d(mu omega) = 0 (verified), or None if none was found (or the form is not
        integrable).
    integral : sympy expression or None
        f with grad f = mu a (verified): the constraint is f(q) = const; or None.
    residual : dict
        The non-zero components of omega ^ d omega, {(i, j, k): expression}; empty exactly
        when ``integrable``.
    closedness : dict
        The non-zero components of d omega, {(i, j): d_i a_j - d_j a_i}.
    method, message : str
        How mu was found; a human summary.
    """
    coords: Tuple[sp.Symbol, ...]
    coeffs: Tuple[sp.Expr, ...]
    integrable: bool
    exact: bool
    integrating_factor: Optional[sp.Expr]
    integral: Optional[sp.Expr]
    residual: Dict[Tuple[int, ...], sp.Expr] = field(default_factory=dict)
    closedness: Dict[Tuple[int, ...], sp.Expr] = field(default_factory=dict)
    method: str = ""
    message: str = ""

    @property
    def holonomic(self) -> bool:
        """Alias of `integrable`."""
        return self.integrable

    @property
    def residual_expr(self) -> sp.Expr:
        """The residual as one expression: the sum of squares of the components of
        omega ^ d omega (zero iff integrable)."""
        return sp.Add(*[v ** 2 for v in self.residual.values()])


@dataclass
class PfaffianSystemResult:
    """Frobenius test of several Pfaffian constraints together (see `pfaffian_system`)."""
    coords: Tuple[sp.Symbol, ...]
    forms: Tuple[Tuple[sp.Expr, ...], ...]
    integrable: bool
    residual: Dict[Tuple[int, ...], sp.Expr]
    each: Tuple[PfaffianResult, ...]
    message: str = ""


# ---------------------------------------------------------------- input checks
def _as_coords(coords):
    if isinstance(coords, (sp.Symbol,)):
        coords = [coords]
    coords = tuple(coords)
    if not coords:
        raise ValueError("coords: at least one coordinate is needed")
    for c in coords:
        if not isinstance(c, sp.Symbol):
            raise TypeError(f"coords: {c!r} is not a sympy Symbol")
    if len(set(coords)) != len(coords):
        raise ValueError("coords: coordinates must be distinct")
    return coords


def _as_coeffs(coeffs, coords, name="coeffs"):
    try:
        coeffs = tuple(sp.sympify(a) for a in coeffs)
    except (sp.SympifyError, TypeError) as exc:
        raise TypeError(f"{name}: cannot read the coefficients as sympy expressions "
                        f"({exc})") from None
    if len(coeffs) != len(coords):
        raise ValueError(f"{name}: {len(coeffs)} coefficients for {len(coords)} coordinates "
                         "(one coefficient per coordinate; put the dt coefficient last with "
                         "t among the coords)")
    if all(a == 0 for a in coeffs):
        raise ValueError(f"{name}: all coefficients are zero (no constraint)")
    return coeffs


# ---------------------------------------------------------------- integrating factors
def _is_closed(coeffs, coords) -> bool:
    return all(_is_zero(v) for v in exterior_derivative(one_form(coeffs), coords).values())


def _common_factor(coeffs):
    """The greatest common factor of the coefficients (over their generators), or 1."""
    nz = [sp.factor(sp.together(a)) for a in coeffs if a != 0]
    g = nz[0]
    for a in nz[1:]:
        try:
            g = sp.gcd(g, a)
        except (sp.PolificationFailed, sp.GeneratorsNeeded, NotImplementedError):
            return sp.Integer(1)
    if g.is_number:
        return sp.Integer(1)
    return g


def _one_variable_factor(coeffs, coords):
    """mu = mu(q_k) for some k, from mu'/mu = (d_j a_k - d_k a_j)/a_j (same for every j)."""
    n = len(coords)
    for k, xk in enumerate(coords):
        ratio = None
        ok = True
        for j in range(n):
            if j == k:
                continue
            curl = sp.diff(coeffs[k], coords[j]) - sp.diff(coeffs[j], xk)
            if coeffs[j] == 0:
                if not _is_zero(curl):
                    ok = False
                    break
                continue
            r = _simplify(curl / coeffs[j])
            if any(r.has(x) for x in coords if x != xk):
                ok = False
                break
            if ratio is None:
                ratio = r
            elif not _is_zero(r - ratio):
                ok = False
                break
        if not ok or ratio is None:
            continue
        mu = None
        try:
            with _time_limit(10.0):
                mu = sp.exp(sp.integrate(ratio, xk))
        except Exception:  # sympy may fail on an integral: then this family is out
            continue
        if mu is None or mu.has(sp.Integral):
            continue
        yield sp.simplify(mu), f"one-variable factor mu({xk})"


def _ansatz_factors(coeffs, coords):
    n = len(coords)
    yield from _one_variable_factor(coeffs, coords)
    euler = sp.Add(*[x * a for x, a in zip(coords, coeffs)])
    if not _is_zero(euler):
        yield 1 / euler, "1/(sum q_i a_i) (homogeneous form)"
    for a in coeffs:
        if a != 0 and not a.is_number:
            yield 1 / a, "1/a_i"
    yield 1 / sp.Mul(*coords), "1/prod(q_i)"
    for x in coords:
        yield 1 / x ** 2, "1/q_i^2"
    for x, y in itertools.combinations(coords, 2):
        yield 1 / (x * y), "1/(q_i q_j)"
        yield 1 / (x ** 2 + y ** 2), "1/(q_i^2 + q_j^2)"
    if n > 2:
        yield 1 / sp.Add(*[x ** 2 for x in coords]), "1/|q|^2"


def _dsolve_factor(coeffs, coords, time_limit=10.0):
    """Two active variables: F(x, y) = C from dsolve(dy/dx = -a_x/a_y); mu = F_x / a_x."""
    if len(coords) == 2:
        active = [0, 1]
    else:
        active = [i for i, a in enumerate(coeffs) if a != 0]
        others = [x for k, x in enumerate(coords) if k not in active]
        if len(active) != 2 or any(coeffs[k].has(*others) for k in active):
            return
    (i, j) = active
    x, y = coords[i], coords[j]
    ax, ay = coeffs[i], coeffs[j]
    for (u, w, au, aw) in ((x, y, ax, ay), (y, x, ay, ax)):
        if aw == 0:
            continue
        f = sp.Function("f")
        ode = sp.Eq(f(u).diff(u), (-au / aw).subs(w, f(u)))
        sols = _dsolve_fast(ode, f(u), time_limit)
        if sols is None:
            continue
        if not isinstance(sols, (list, tuple)):
            sols = [sols]
        for sol in sols:
            eq = sol.lhs - sol.rhs
            eq = eq.subs(f(u), w)
            cs = [s for s in eq.free_symbols if s.name == "C1"]
            if not cs:
                continue
            try:
                fs = sp.solve(eq, cs[0])
            except Exception:  # solve may refuse: try the next solution
                continue
            for big_f in fs:
                if au == 0:
                    mu = sp.simplify(sp.diff(big_f, w) / aw)
                else:
                    mu = sp.simplify(sp.diff(big_f, u) / au)
                if mu != 0:
                    yield mu, "dsolve of dq_j/dq_i = -a_i/a_j", sp.simplify(big_f)


# dsolve hints tried, in order (the Lie-group heuristics and the unevaluated-integral
# variants are left out: they can run for minutes on an ODE without closed form)
_HINTS = ("separable", "1st_exact", "1st_linear", "Bernoulli", "1st_homogeneous_coeff_best",
          "almost_linear", "1st_rational_riccati", "Riccati_special_minus2")


class _TimeUp(Exception):
    pass


class _time_limit:
    """Raise _TimeUp after `seconds` (SIGALRM; only in the main thread on POSIX, else no
    limit)."""

    def __init__(self, seconds):
        self.seconds = seconds
        self.active = False

    def __enter__(self):
        if (self.seconds and hasattr(signal, "setitimer")
                and threading.current_thread() is threading.main_thread()):
            def _raise(signum, frame):
                raise _TimeUp()
            self.old = signal.signal(signal.SIGALRM, _raise)
            signal.setitimer(signal.ITIMER_REAL, self.seconds)
            self.active = True
        return self

    def __exit__(self, *exc):
        if self.active:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, self.old)
        return exc[0] is _TimeUp


def _dsolve_fast(ode, func, time_limit):
    """dsolve with the fast first-order hints only, within `time_limit` seconds; None when
    no hint applies or solves."""
    try:
        with _time_limit(time_limit):
            hints = sp.classify_ode(ode, func)
            for h in _HINTS:
                if h in hints:
                    try:
                        return sp.dsolve(ode, func, hint=h)
                    except (NotImplementedError, ValueError, TypeError, AttributeError):
                        continue
    except (NotImplementedError, ValueError, TypeError, AttributeError):
        return None
    return None


def _potential(c, coords):
    """f with grad f = c (c closed), by successive integration; None if sympy cannot."""
    f = sp.Integer(0)
    for i, x in enumerate(coords):
        rest = _simplify(c[i] - sp.diff(f, x))
        if rest == 0:
            continue
        part = None
        try:
            with _time_limit(10.0):
                part = sp.integrate(rest, x)
        except Exception:  # the integral may be beyond sympy
            return None
        if part is None or part.has(sp.Integral):
            return None
        f = f + part
    f = sp.simplify(f)
    if any(not _is_zero(sp.diff(f, x) - ci) for x, ci in zip(coords, c)):
        return None
    return f


def _verified(mu, coeffs, coords):
    c = [mu * a for a in coeffs]
    return c if _is_closed(c, coords) else None


# ---------------------------------------------------------------- public API
def pfaffian(coeffs: Sequence, coords: Sequence[sp.Symbol]) -> PfaffianResult:
    """Exactness of the Pfaffian constraint sum_i coeffs[i] d coords[i] = 0.

    A dt term is a coordinate like the others: pass t among `coords` and its coefficient
    (b in the seed's notation) at the same place in `coeffs`.
    Returns a `PfaffianResult` (integrable, exact, integrating_factor, integral, residual).
    """
    coords = _as_coords(coords)
    coeffs = _as_coeffs(coeffs, coords)
    om = one_form(coeffs)
    closedness = _simplified_nonzero(exterior_derivative(om, coords))
    residual = _simplified_nonzero(wedge(om, exterior_derivative(om, coords)))
    integrable = not residual
    res = PfaffianResult(coords=coords, coeffs=coeffs, integrable=integrable,
                         exact=not closedness, integrating_factor=None, integral=None,
                         residual=residual, closedness=closedness)
    if not integrable:
        res.message = ("non-holonomic: omega ^ d omega != 0, no integrating factor exists "
                       f"({len(residual)} non-zero component(s))")
        return res
    g = _common_factor(coeffs)
    red = [sp.simplify(a / g) for a in coeffs]
    found = None
    if not closedness:
        found = (sp.Integer(1), "exact as given (mu = 1)", None)
    elif _is_closed(red, coords):
        found = (1 / g, "common factor divided out", None)
    else:
        cands = itertools.chain(((m, how, None) for m, how in _ansatz_factors(red, coords)),
                                _dsolve_factor(red, coords))
        for mu, how, big_f in cands:
            if _verified(mu, red, coords) is not None:
                found = (sp.simplify(mu / g), how + ("" if g == 1 else
                                                     ", after dividing the common factor"),
                         big_f)
                break
    if found is None:
        res.method = "none"
        res.message = ("holonomic (Frobenius condition holds), but no integrating factor was "
                       "found among the ansatz families and dsolve")
        return res
    mu, how, big_f = found
    c = _verified(mu, coeffs, coords)
    c = None if c is None else [sp.simplify(ci) for ci in c]
    if c is None:  # cannot happen for a verified reduced factor; keep the check honest
        res.message = "integrating factor failed verification"
        return res
    res.integrating_factor = mu
    res.method = how
    res.integral = _potential(c, coords)
    if res.integral is None and big_f is not None:
        grad_ok = all(_is_zero(sp.diff(big_f, x) - ci) for x, ci in zip(coords, c))
        res.integral = big_f if grad_ok else None
    res.message = (f"holonomic: mu = {mu} ({how}); integral "
                   + (f"{res.integral} = const" if res.integral is not None
                      else "not found in closed form"))
    return res


def pfaffian_system(forms: Sequence[Sequence], coords: Sequence[sp.Symbol]
                    ) -> PfaffianSystemResult:
    """Frobenius test for several Pfaffian constraints sum_i forms[c][i] dq_i = 0 together:
    integrable (holonomic as a set) iff d omega_c ^ omega_1 ^ ... ^ omega_k = 0 for all c.
    Each constraint is also checked on its own (`each`)."""
    coords = _as_coords(coords)
    if not forms:
        raise ValueError("forms: at least one constraint is needed")
    forms = tuple(_as_coeffs(f, coords, name=f"forms[{i}]") for i, f in enumerate(forms))
    residual = frobenius_residual(forms, coords)
    each = tuple(pfaffian(f, coords) for f in forms)
    integrable = not residual
    msg = ("holonomic: the system satisfies Frobenius' condition" if integrable else
           "non-holonomic: d omega_i ^ omega_1 ^ ... ^ omega_k != 0")
    return PfaffianSystemResult(coords=coords, forms=forms, integrable=integrable,
                                residual=residual, each=each, message=msg)


def pfaffian_from_velocities(expr, coords: Sequence[sp.Symbol], velocities: Sequence,
                             t: Optional[sp.Symbol] = None) -> PfaffianResult:
    """Exactness of a velocity-level constraint expr = sum_i a_i(q, t) v_i + a_0(q, t) = 0
    (v_i the symbols or expressions in `velocities`, e.g. sympy Derivative(q_i(t), t)).
    With `t` given, the dt coefficient a_0 is kept and t is appended to the coordinates."""
    coords = _as_coords(coords)
    velocities = tuple(sp.sympify(v) for v in velocities)
    if len(velocities) != len(coords):
        raise ValueError(f"velocities: {len(velocities)} velocities for {len(coords)} "
                         "coordinates")
    expr = sp.expand(sp.sympify(expr))
    dummies = sp.symbols(f"_v0:{len(coords)}")
    e = expr.subs(dict(zip(velocities, dummies)))
    coeffs = [sp.diff(e, d) for d in dummies]
    if any(c.has(*dummies) for c in coeffs):
        raise ValueError("expr: the constraint is not linear in the velocities (not "
                         "Pfaffian)")
    a0 = sp.simplify(e.subs({d: 0 for d in dummies}))
    if t is None:
        if a0 != 0:
            raise ValueError("expr: the constraint has a term free of velocities (a_0 dt): "
                             "pass t= to keep it")
        return pfaffian(coeffs, coords)
    return pfaffian(coeffs + [a0], coords + (t,))


def pfaffian_of(system) -> PfaffianSystemResult:
    """Exactness of the non-holonomic constraints A(t, q) q' + b(t, q) = 0 of a derived
    constrained system (a conmech.symbolic.derive.Derived record of kind "constrained", or a
    system made by conmech.symbolic.constrained_system). Each row is the form
    sum_j A_ij dq_j + b_i dt (t joins the coordinates when b or A depends on t): a row found
    integrable (`each[i].integrable`, with its `integral`) is in truth holonomic and could be
    given as `holonomic=[integral - const]`; `integrable` tells the set as a whole."""
    d = system
    if not hasattr(d, "kind"):
        try:
            d = model_of(system).derived
        except (ImportError, TypeError):
            raise TypeError("pfaffian_of: expected a Derived record or a conmech.symbolic "
                            "constrained system") from None
    if getattr(d, "kind", None) != "constrained" or not d.n_nh:
        raise ValueError("pfaffian_of: the system has no non-holonomic constraints")
    coords = tuple(d.coords)
    timed = any(d.b[i] != 0 or d.A.row(i).has(d.t) for i in range(d.n_nh))
    forms = []
    for i in range(d.n_nh):
        row = list(d.A.row(i))
        forms.append(row + [d.b[i]] if timed else row)
    return pfaffian_system(forms, coords + ((d.t,) if timed else ()))
