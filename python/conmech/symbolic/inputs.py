"""The user's symbolic input made into a derivation's plain symbols: coordinates
(``dynamicsymbols`` or Symbols with their velocities), the time symbol, parameters identified by
name with their float values, finite real entries, and the check that the mass matrix is
regular (at random states and parameter values) and free of the velocities."""
import random

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef


def _as_value(name, v):
    """The float value of parameter `name`: a real number (int, float, a NumPy or sympy
    real number); a bool, a string, a complex number or an expression is refused."""
    if v is None:
        raise ValueError(f"parameter '{name}' has no value")
    if isinstance(v, (bool, np.bool_)):
        raise TypeError(f"parameter '{name}' must be a real number, got {v!r}")
    if isinstance(v, (str, bytes)):
        raise ValueError(f"parameter '{name}' has no numeric value (got the string {v!r}: "
                         "give a number)")
    if isinstance(v, sp.Basic) and not (v.is_number and v.is_real):
        raise ValueError(f"parameter '{name}' has no real numeric value (got {v!r})")
    if isinstance(v, (complex, np.complexfloating)):
        raise TypeError(f"parameter '{name}' must be a real number, got {v!r}")
    try:
        x = float(v)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"parameter '{name}' has no numeric value (got {v!r})") from None
    if not np.isfinite(x):
        raise ValueError(f"parameter '{name}' must be finite (got {v!r})")
    return x


# unevaluated operations that have no value at run time (compiled code evaluates numbers)
_UNEVALUATED = (sp.Integral, sp.Sum, sp.Product, sp.Limit, sp.Subs, sp.Order)


_DOUBLE_MAX = 1.7976931348623157e308


def _check_entry(e, label):
    """ValueError naming the entry `label` (e.g. f[1]) unless `e` can become real double
    precision code: no complex number, no nan or infinity, no unevaluated integral, sum,
    product or limit, every number within double range."""
    if e.has(sp.nan):
        raise ValueError(f"{label} contains nan (not a number): {e}")
    if e.has(sp.zoo, sp.oo, sp.S.NegativeInfinity):
        raise ValueError(f"{label} contains an infinity (oo or zoo, e.g. from a division "
                         f"by zero): {e}")
    if e.has(sp.I):
        raise ValueError(f"{label} contains the imaginary unit I: conmech integrates real "
                         "systems; write the real and imaginary parts as separate states "
                         f"({e})")
    for cls in _UNEVALUATED:
        for a in e.atoms(cls):
            raise ValueError(f"{label} contains the unevaluated {cls.__name__} {a}: "
                             "evaluate it (.doit()) or write out what it stands for")
    for a in e.atoms(sp.Number):
        try:
            x = abs(float(a))
        except (OverflowError, TypeError, ValueError):
            x = float("inf")
        if not x <= _DOUBLE_MAX or (x == 0.0 and a != 0):
            text = str(a)
            if len(text) > 30:
                text = (f"{text[:12]}... ({len(str(abs(a.p)))}-digit numerator, "
                        f"{len(str(a.q))}-digit denominator)" if a.is_Rational
                        else text[:30] + "...")
            raise ValueError(f"{label} contains the number {text}, outside the range of "
                             "double precision (magnitudes 5e-324 to 1.8e308)")
    for a in e.atoms(sp.NumberSymbol):
        if not a.is_real:
            raise ValueError(f"{label} contains {a}, which is not a real number")


def _sympify_list(exprs, what):
    if isinstance(exprs, sp.MatrixBase):
        if min(exprs.shape) > 1:
            raise ValueError(f"{what} is a {exprs.shape[0]} x {exprs.shape[1]} matrix: give "
                             "a list or a column vector of scalar expressions")
        exprs = list(exprs)
        single = False
    elif not isinstance(exprs, (list, tuple)):
        exprs = [exprs]
        single = True
    else:
        single = False
    out = []
    for i, e in enumerate(exprs):
        label = what if single else f"{what}[{i}]"
        if isinstance(e, (sp.MatrixBase, np.ndarray, list, tuple)) or getattr(
                e, "is_Matrix", False):
            raise ValueError(f"{label} is a matrix or a list, not a scalar expression "
                             "(nested entries are not flattened: give one expression per "
                             "entry)")
        if isinstance(e, (bool, np.bool_)):
            raise TypeError(f"{label}: {e!r} is a bool, not an expression")
        try:
            e = sp.sympify(e)
        except (sp.SympifyError, TypeError) as exc:
            raise TypeError(f"{label}: cannot read {e!r} as a sympy expression") from exc
        if isinstance(e, sp.Equality):          # a constraint written as lhs == rhs
            e = e.lhs - e.rhs
        if getattr(e, "is_Matrix", False):
            raise ValueError(f"{label} is a matrix, not a scalar expression")
        if not isinstance(e, sp.Expr):
            raise TypeError(f"{label}: {e!r} is not a scalar expression")
        _check_entry(e, label)
        out.append(e)
    return out


class _Coords:
    """Coordinates q (dynamicsymbols or Symbols), their plain symbols, speeds, accels."""

    def __init__(self, q, velocities, t, need_speeds):
        if isinstance(q, (sp.Basic,)) and not isinstance(q, sp.MatrixBase):
            q = [q]
        q = list(q)
        if not q:
            raise ValueError("no coordinates given")
        self.t = t
        self.kind = None
        self.plain, self.speeds, self.accels = [], [], []
        self.fmap = {}       # functions of t and their derivatives -> plain symbols
        self.names = []
        for i, qi in enumerate(q):
            if isinstance(qi, AppliedUndef):
                if qi.args != (t,):
                    raise ValueError(f"coordinate {qi} must be a function of t only")
                kind = "function"
                name = str(qi.func)
            elif isinstance(qi, sp.Symbol):
                kind = "symbol"
                name = qi.name
            else:
                raise TypeError(f"coordinate {i} ({qi!r}) is neither a sympy Symbol nor a "
                                "dynamicsymbol (function of t)")
            if self.kind is None:
                self.kind = kind
            elif kind != self.kind:
                raise ValueError("coordinates must be all dynamicsymbols or all Symbols")
            if name in self.names:
                raise ValueError(f"coordinate '{name}' given twice")
            if name == t.name:
                raise ValueError(f"the time symbol '{t.name}' cannot be a coordinate")
            self.names.append(name)
        if self.kind == "function":
            if velocities is not None:
                raise ValueError("velocities= is only for coordinates given as plain Symbols "
                                 "(dynamicsymbols carry their own derivatives)")
            for qi, name in zip(q, self.names):
                qs = sp.Dummy(name)
                vs = sp.Dummy(name + "_d")
                as_ = sp.Dummy(name + "_dd")
                self.plain.append(qs)
                self.speeds.append(vs)
                self.accels.append(as_)
                self.fmap[sp.Derivative(qi, (t, 2))] = as_
                self.fmap[sp.Derivative(qi, t)] = vs
                self.fmap[qi] = qs
        else:
            self.plain = list(q)
            if need_speeds:
                if velocities is None:
                    raise ValueError("coordinates given as plain Symbols need velocities=[...] "
                                     "(the Symbols standing for their time derivatives), or "
                                     "use sympy.physics.mechanics.dynamicsymbols")
                velocities = list(velocities)
                if len(velocities) != len(q):
                    raise ValueError(f"velocities has {len(velocities)} entries for "
                                     f"{len(q)} coordinates")
                for v in velocities:
                    if not isinstance(v, sp.Symbol):
                        raise TypeError(f"velocity {v!r} is not a sympy Symbol")
                    if v in self.plain:
                        raise ValueError(f"'{v}' is both a coordinate and a velocity")
                self.speeds = velocities
                self.accels = [sp.Dummy(n + "_dd") for n in self.names]
            elif velocities is not None:
                raise ValueError("velocities= has no meaning for a first-order system")

    def convert(self, exprs, what):
        """Replace the functions of t by plain symbols; reject foreign functions of t."""
        out = []
        for e in exprs:
            e = e.xreplace(self.fmap) if self.fmap else e
            for d in e.atoms(sp.Derivative):
                raise ValueError(f"{what} contains the derivative {d} of something that is "
                                 "not a coordinate (coordinates: " + ", ".join(self.names) + ")")
            for f in e.atoms(AppliedUndef):
                raise ValueError(f"{what} depends on {f}, which is not one of the "
                                 "coordinates " + ", ".join(self.names))
            out.append(e)
        return out


def _unify_time(exprs, t):
    """Replace every free symbol named 't' (whatever its assumptions) by t."""
    out = []
    for e in exprs:
        subs = {s: t for s in e.free_symbols if s.name == t.name and s != t}
        out.append(e.xreplace(subs) if subs else e)
    return out


def _resolve_params(params, exprs, known, t):
    """Parameter symbols (in order), names and values; checks every free symbol."""
    if params is None:
        params = {}
    if isinstance(params, (list, tuple, set)):
        # symbols without values
        for p in params:
            raise ValueError(f"parameter '{p}' has no value (give params as a dict "
                             "{symbol or name: value})")
    if not isinstance(params, dict):
        raise TypeError("params must be a dict {sympy Symbol or name: value}")
    known_names = {s.name for s in known} | {t.name}
    free = set()
    for e in exprs:
        free |= e.free_symbols
    by_name = {}
    known_set = set(known) | {t}
    for s in free:
        if s.name in known_names:
            if s not in known_set:
                raise ValueError(f"the symbol '{s.name}' has the name of a coordinate or "
                                 "velocity but is not it (write the coordinate as given in q, "
                                 "e.g. the dynamicsymbol x and x.diff(t))")
            continue
        by_name.setdefault(s.name, []).append(s)
    names, values = [], []
    for k, v in params.items():
        if isinstance(k, sp.Symbol):
            name = k.name
        elif isinstance(k, str):
            name = k
        else:
            raise TypeError(f"params key {k!r} must be a sympy Symbol or a string")
        if not name.isidentifier():
            raise ValueError(f"parameter name {name!r} is not an identifier")
        if name in known_names:
            raise ValueError(f"'{name}' is a coordinate, a velocity or the time, not a "
                             "parameter")
        if name in names:
            raise ValueError(f"parameter '{name}' given twice")
        names.append(name)
        values.append(_as_value(name, v))
    unknown = sorted(set(by_name) - set(names))
    if unknown:
        raise ValueError("unknown symbol(s) " + ", ".join(f"'{u}'" for u in unknown)
                         + ": neither a coordinate, a velocity, t nor a parameter with a "
                         "value (add it to params=)")
    psyms = [sp.Symbol(n) for n in names]
    # map every free symbol of the same name onto one canonical parameter symbol
    sub = {}
    for n, ps in zip(names, psyms):
        for s in by_name.get(n, []):
            if s != ps:
                sub[s] = ps
    return psyms, names, values, sub


def _realify(exprs, t, c, psyms):
    """Replace t, the coordinates, velocities, accelerations and parameters by real
    Dummies of the same names (so that e.g. d|x|/dx = sign(x), not re/im terms); updates
    the coordinate record in place; returns (exprs, t, params)."""
    sub = {}

    def real(s):
        r = sp.Dummy(s.name, real=True)
        sub[s] = r
        return r
    t_r = real(t)
    c.plain = [real(s) for s in c.plain]
    c.speeds = [real(s) for s in c.speeds]
    c.accels = [real(s) for s in c.accels]
    p_r = [real(s) for s in psyms]
    return [e.xreplace(sub) for e in exprs], t_r, p_r


def _ae(mat):
    """Jacobians almost everywhere: the DiracDelta of a differentiated sign / Heaviside
    (e.g. Coulomb friction) is dropped (the derivative away from the jump)."""
    if mat.has(sp.DiracDelta):
        return mat.replace(sp.DiracDelta, lambda *a: sp.S.Zero)
    return mat


def _subs_all(exprs, sub):
    return [e.xreplace(sub) if sub else e for e in exprs]


def singular_everywhere(mass_at, n, rng, trials=3):
    """True if the n x n matrices mass_at(trial) (None: not evaluable) are numerically
    singular (sigma_min <= 1e-12 sigma_max) at every trial."""
    for trial in range(trials):
        A = mass_at(trial)
        if A is None:
            return False
        A = np.asarray(A, dtype=float).reshape(n, n)
        if not np.all(np.isfinite(A)):
            return False
        s = np.linalg.svd(A, compute_uv=False)
        if s[0] > 0 and s[-1] > 1e-12 * s[0]:
            return False
    return True


def _check_mass(M, coords, speeds, params, values, t):
    """ValueError if M depends on the velocities or is singular identically (seen at random
    states and random parameter values)."""
    bad = M.free_symbols & set(speeds)
    if bad:
        raise ValueError("the mass matrix depends on the velocities "
                         f"({', '.join(map(str, bad))}): the Lagrangian must be quadratic "
                         "in the velocities")
    n = M.shape[0]
    if M.shape[0] != M.shape[1]:
        raise ValueError(f"mass matrix is not square ({M.shape[0]} x {M.shape[1]})")
    if n > 4:      # large: checked on the compiled mass matrix instead (conmech.symbolic)
        return
    args = [t] + list(coords) + list(params)
    fM = sp.lambdify(args, M, modules="numpy")
    rng = random.Random(12345)

    def mass_at(trial):
        vals = [rng.uniform(0.3, 1.3)] + [rng.uniform(-1.0, 1.0) for _ in coords]
        if trial == 0:
            vals += list(values)
        else:
            vals += [v * rng.uniform(0.7, 1.3) if v != 0 else rng.uniform(0.5, 1.5)
                     for v in values]
        try:
            with np.errstate(all="ignore"):
                return np.array(fM(*vals), dtype=float)
        except (ZeroDivisionError, ValueError, TypeError):
            return None
    if singular_everywhere(mass_at, n, rng):
        det = sp.simplify(M.det()) if n <= 4 else 0
        if det == 0:
            raise ValueError("the mass matrix is singular identically (det M = 0): a "
                             "coordinate has no kinetic energy, or the coordinates are "
                             "dependent")


def _check_no_accel(exprs, c):
    acc = set(c.accels)
    for e in exprs:
        if e.free_symbols & acc:
            raise ValueError("the expressions must not contain accelerations (second "
                             "derivatives of the coordinates)")


def _mechanical_inputs(exprs, c, params, t, what):
    """The expressions of a mechanical system in the derivation's plain real symbols:
    converted from functions of time (`c`: the coordinates and velocities; `what` names the
    expressions in errors), checked free of accelerations, the parameters resolved by name
    (every other free symbol is an error) and substituted. Returns (exprs, t, parameter
    symbols, their names, their values)."""
    exprs = c.convert(exprs, what)
    _check_no_accel(exprs, c)
    known = list(c.plain) + list(c.speeds)
    psyms, names, values, sub = _resolve_params(params, exprs, known, t)
    exprs = _subs_all(exprs, sub)
    exprs, t, psyms = _realify(exprs, t, c, psyms)
    return exprs, t, psyms, names, values
