"""Derivation of the equations of motion with sympy (pure sympy, no code generation).

Three entry points build a :class:`Derived` object, a plain record of sympy expressions in
*plain symbols* (no functions of t), ready for a code generator:

- :func:`derive_ode`: y' = f(t, y, p) and its Jacobian df/dy;
- :func:`derive_lagrangian`: generalized coordinates, L = T - U, optional generalized forces:
  M(t, q), Q(t, q, v), R = [dQ/dq - d(M a)/dq |a fixed, dQ/dv], the energy (Jacobi integral
  h = v . dL/dv - L, i.e. T + U for a natural scleronomic system);
- :func:`derive_constrained`: excessive coordinates, T and U, holonomic phi(t, q) = 0 and
  Pfaffian A(t, q) v + b(t, q) = 0 constraints: M, Q, energy, phi, G, phi_t, gamma_h, A, b,
  gamma_n (conventions of src/mechanics/conmech_constrained_system.f90:
  gamma_h = -d/dt[G v + phi_t], gamma_n = -d/dt[A v + b], v held fixed).

Coordinates are either sympy ``dynamicsymbols`` (functions of t; their first derivatives are
the velocities, second derivatives the accelerations) or plain Symbols, then with
``velocities=[...]`` plain Symbols standing for their time derivatives. Time is the symbol
``t`` (``dynamicsymbols._t``; any free symbol named "t").

``params`` maps sympy Symbols, or their names as strings, to float values. Every free symbol
of the expressions that is not t, a coordinate or a velocity must be a parameter (else
ValueError naming it); a parameter without a value is a ValueError naming it. Parameters are
identified by name (Symbol("m", positive=True) and Symbol("m") are the same parameter).

All symbols of a :class:`Derived` record (t, coordinates, velocities, accelerations,
parameters) are real-valued sympy Dummies carrying the user's names (``coord_names``,
``param_names``); code generators map them to array elements by position.

The :class:`Derived` record (attributes; absent items are None):

=============  ==============================================================================
kind           "ode", "generalized" or "constrained"
t              the time Symbol
coords         list of Symbols: y (ode) or q (generalized, constrained); coord_names
lagrangian     the (cleaned-up) Lagrangian used (generalized, constrained)
speeds         list of Symbols v (velocities; [] for ode)
accels         list of Symbols a (accelerations, used in R; [] for ode)
params         list of parameter Symbols, in the order of the run-time array p
param_names    list of their names; ``param_values``: list of floats
f, jac         ode: Matrix n x 1, Matrix n x n (df/dy)
M, Q           mass matrix (nd x nd, depends on t, q, p), forces (nd x 1, t, q, v, p)
R              generalized only: nd x 2nd, [dQ/dq - d(M a)/dq, dQ/dv] (t, q, v, a, p)
energy         scalar expression (t, q, v, p) or None
phi, G, phi_t  constrained: n_hol x 1, n_hol x n, n_hol x 1
gamma_h        n_hol x 1 (t, q, v, p)
A, b, gamma_n  n_nh x n, n_nh x 1, n_nh x 1
n_hol, n_nh    numbers of constraints; ``rheonomic``: phi depends explicitly on t
=============  ==============================================================================

``Derived.values(**kw)`` returns the parameter vector with some values replaced by name.
"""
import pickle
import random

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

__all__ = ["Derived", "derive_ode", "derive_lagrangian", "derive_constrained"]


class Derived:
    """Plain record of the derived expressions (see the module docstring).

    A generalized system derived structurally (``struct`` set, see :func:`_structure`)
    computes its expanded ``Q`` and ``R`` only when they are first read (the compiled code
    uses ``struct`` instead)."""

    def __init__(self, kind, **kw):
        self.kind = kind
        self.t = sp.Symbol("t")
        self.coords, self.speeds, self.accels = [], [], []
        self.params, self.param_names, self.param_values = [], [], []
        for name in ("f", "jac", "M", "Q", "R", "energy", "phi", "G", "phi_t", "gamma_h",
                     "A", "b", "gamma_n", "struct", "gen_forces"):
            setattr(self, name, None)
        self.n_hol = 0
        self.n_nh = 0
        self.rheonomic = False
        self.with_jacobian = True
        for k, v in kw.items():
            setattr(self, k, v)

    # the attributes a compiled system needs; the expressions (large for long chains) are
    # pickled as one blob and read back only when first used (fast derivation-cache hits)
    _LIGHT = frozenset(("kind", "t", "coords", "coord_names", "speeds", "accels", "params",
                        "param_names", "param_values", "n_hol", "n_nh", "rheonomic",
                        "with_jacobian"))

    def __getstate__(self):
        state = {k: v for k, v in self.__dict__.items() if k in self._LIGHT}
        if "_heavy" in self.__dict__:          # expressions not read back yet
            state["_heavy"] = self.__dict__["_heavy"]
        else:
            heavy = {k: v for k, v in self.__dict__.items() if k not in self._LIGHT}
            state["_heavy"] = pickle.dumps(heavy, protocol=pickle.HIGHEST_PROTOCOL)
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)

    def __getattr__(self, name):
        heavy = None if name.startswith("__") else self.__dict__.pop("_heavy", None)
        if heavy is not None:
            self.__dict__.update(pickle.loads(heavy))
        try:
            return self.__dict__[name]
        except KeyError:
            raise AttributeError(name) from None

    @property
    def Q(self):
        if self._Q is None and self.struct is not None:
            _, Q = _euler_lagrange(self.lagrangian, self.coords, self.speeds, self.t)
            self._Q = Q + sp.Matrix(self.gen_forces)
        return self._Q

    @Q.setter
    def Q(self, value):
        self._Q = value

    @property
    def R(self):
        if self._R is None and self.struct is not None and self.with_jacobian:
            Ma = self.M * sp.Matrix(self.accels)
            Q = self.Q
            self._R = _ae((Q - Ma).jacobian(self.coords).row_join(Q.jacobian(self.speeds)))
        return self._R

    @R.setter
    def R(self, value):
        self._R = value

    @property
    def n(self):
        """Number of coordinates (state dimension for an ode)."""
        return len(self.coords)

    def values(self, **kw):
        """The parameter values as a list, with the named ones replaced."""
        vals = list(self.param_values)
        for k, v in kw.items():
            if k not in self.param_names:
                raise ValueError(f"unknown parameter '{k}' (parameters: "
                                 f"{', '.join(self.param_names) or 'none'})")
            vals[self.param_names.index(k)] = _as_value(k, v)
        return vals

    def __repr__(self):
        return (f"Derived(kind={self.kind!r}, coords={self.coords}, "
                f"params={dict(zip(self.param_names, self.param_values))})")


# ------------------------------------------------------------------------------ helpers

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


# ------------------------------------------------------------------------------ ode

def derive_ode(f, y, params=None):
    """y' = f(t, y, p): f (list of expressions), y (Symbols or dynamicsymbols)."""
    t = sp.Symbol("t")
    f = _unify_time(_sympify_list(f, "f"), t)
    c = _Coords(y, None, t, need_speeds=False)
    if len(f) != len(c.plain):
        raise ValueError(f"f has {len(f)} components for {len(c.plain)} state variables")
    # for dynamicsymbols: y_i(t) -> plain; derivatives of y in f are an error
    f = c.convert(f, "f")
    psyms, names, values, sub = _resolve_params(params, f, c.plain, t)
    f = _subs_all(f, sub)
    f, t, psyms = _realify(f, t, c, psyms)
    F = sp.Matrix(f)
    J = _ae(F.jacobian(c.plain))
    return Derived("ode", t=t, coords=c.plain, coord_names=c.names, params=psyms,
                   param_names=names, param_values=values, f=F, jac=J)


# ------------------------------------------------------------------------------ Lagrange

def _euler_lagrange(L, q, v, t):
    """M (Hessian of L in v) and the velocity/potential part of Q (without q'')."""
    p = [sp.diff(L, vi) for vi in v]
    n = len(q)
    M = sp.Matrix(n, n, lambda i, j: sp.diff(p[i], v[j]))
    Q = []
    for i in range(n):
        dpdt = sum((sp.diff(p[i], q[j]) * v[j] for j in range(n)), sp.Integer(0)) \
            + sp.diff(p[i], t)
        Q.append(sp.diff(L, q[i]) - dpdt)
    return M, sp.Matrix(Q)


def _structure(L, M, q, v, a, t, fq, jacobian, l1L0=None):
    """The forces and their Jacobian of a Lagrangian quadratic in the velocities,
    L = v^T M v / 2 + l1 . v + L0, in structured form (nothing expanded):

        Q_i = QL_i + sum_k dM_k . (quadratic monomials of v),
        QL_i = fq_i + dL0/dq_i + (dl1/dq_i) . v - (dl1_i/dq) . v - dl1_i/dt - (dM_i./dt) . v,
        dM_k = dM_ab/dq_k over the nonzero entries only (a <= b),

    (Euler-Lagrange: Q_i = 1/2 v^T (dM/dq_i) v - sum_jk dM_ij/dq_k v_j v_k + ...), with the
    coefficients of each dM entry in each Q_i collected exactly (so that for a chain, where
    M_ij depends on q_i and q_j only, Q costs O(n^2) operations, not O(n^3)).
    Returns a dict: ``defs_Q`` [(Symbol, expr)], ``Q`` (list, in the def symbols and v),
    and with ``jacobian`` ``defs_R``, ``R`` (n x 2n Matrix in the def symbols, v and a):
    R = [dQ/dq - d(M a)/dq, dQ/dv] from the second derivatives of M (also sparse).
    None if M depends on the velocities."""
    n = len(q)
    vs = set(v)
    if any(M[i, j].free_symbols & vs for i in range(n) for j in range(n)):
        return None
    zero = {vi: 0 for vi in v}
    if l1L0 is not None:
        l1, L0 = l1L0
    else:
        grad = [sp.diff(L, vi) for vi in v]
        l1 = [g.xreplace(zero) for g in grad]      # exact: grad = M v + l1
        L0 = L.xreplace(zero)
    qidx = {qi: k for k, qi in enumerate(q)}
    dM, dsym = {}, {}                   # (a, b, k) -> expr, Symbol
    for i in range(n):
        for j in range(i, n):
            for k in sorted(qidx[s] for s in M[i, j].free_symbols if s in qidx):
                e = sp.diff(M[i, j], q[k])
                if e != 0:
                    dM[i, j, k] = e
                    dsym[i, j, k] = sp.Dummy(f"dm{i + 1}_{j + 1}_{k + 1}", real=True)
    # coefficients of each dM entry in each Q_i: {i: {key: {(x, y): c}}}
    coef = [dict() for _ in range(n)]

    def add(i, key, x, y, c):
        mono = coef[i].setdefault(key, {})
        xy = (min(x, y), max(x, y))
        mono[xy] = mono.get(xy, 0) + c
    for (i, j, k) in dM:
        if i < j:
            add(k, (i, j, k), i, j, sp.Integer(1))
            add(i, (i, j, k), j, k, sp.Integer(-1))
            add(j, (i, j, k), i, k, sp.Integer(-1))
        else:
            add(k, (i, j, k), i, i, sp.Rational(1, 2))
            add(i, (i, j, k), i, k, sp.Integer(-1))
    quad = []
    for i in range(n):
        terms = []
        for key, mono in coef[i].items():
            poly = sum((c*v[x]*v[y] for (x, y), c in mono.items() if c != 0), sp.Integer(0))
            if poly != 0:
                terms.append((key, poly, mono))
        quad.append(terms)
    QL = []
    for i in range(n):
        e = fq[i] + _d(L0, q[i]) - _d(l1[i], t) \
            - sum((_d(M[i, j], t)*v[j] for j in range(n)), sp.Integer(0))
        e += sum((_d(l1[j], q[i])*v[j] for j in range(n)), sp.Integer(0))
        e -= sum((_d(l1[i], q[k])*v[k] for k in range(n)), sp.Integer(0))
        QL.append(_collect_params(sp.expand(e), set().union(
            *(x.free_symbols for x in [L] + list(fq))) - set(q) - set(v) - {t}))
    qlsym = [sp.Dummy(f"ql{i + 1}", real=True) if QL[i] != 0 else sp.Integer(0)
             for i in range(n)]
    defs_Q = [(dsym[k], e) for k, e in dM.items()] \
        + [(s_, e) for s_, e in zip(qlsym, QL) if e != 0]
    Qs = [qlsym[i] + sum((dsym[key]*poly for key, poly, _ in quad[i]), sp.Integer(0))
          for i in range(n)]
    out = {"defs_Q": defs_Q, "Q": Qs, "dM": dM, "quad": quad, "QL": QL}
    if not jacobian:
        return out
    # R: the second derivatives of M (nonzero ones), the derivatives of QL
    defs_R = [(dsym[k], e) for k, e in dM.items()]
    ddsym = {}
    for key, e in dM.items():
        for m in sorted(qidx[s] for s in e.free_symbols if s in qidx):
            de = _ae(sp.Matrix([sp.diff(e, q[m])]))[0]
            if de != 0:
                ddsym[key, m] = sp.Dummy(f"ddm{key[0] + 1}_{key[1] + 1}_{key[2] + 1}_{m + 1}",
                                         real=True)
                defs_R.append((ddsym[key, m], de))
    R = sp.zeros(n, 2*n)
    for i in range(n):
        for m, x in enumerate(list(q) + list(v)):
            if x not in QL[i].free_symbols:
                continue
            de = _ae(sp.Matrix([sp.diff(QL[i], x)]))[0]
            if de != 0:
                s_ = sp.Dummy(f"dql{i + 1}_{m + 1}", real=True)
                defs_R.append((s_, de))
                R[i, m] = s_
    for i in range(n):
        for key, poly, mono in quad[i]:
            dp = [sp.Integer(0)]*n             # d poly / dv_m from its monomials
            for (x, y), c in mono.items():
                dp[x] += c*v[y]
                dp[y] += c*v[x]
            for m in range(n):
                if (key, m) in ddsym:
                    R[i, m] += ddsym[key, m]*poly
                if dp[m] != 0:
                    R[i, n + m] += dsym[key]*dp[m]
        for m in range(n):
            for j in range(n):
                key = (min(i, j), max(i, j), m)
                if key in dsym:
                    R[i, m] -= dsym[key]*a[j]
    out.update(defs_R=defs_R, R=R)
    return out


def _d(e, x):
    """de/dx, skipping expressions free of x."""
    return sp.diff(e, x) if x in e.free_symbols else sp.Integer(0)


def _energy(L, M, v):
    """Jacobi integral h = v . dL/dv - L = v^T M v / 2 - L(v = 0) for L quadratic in v
    (T + U for a natural scleronomic system)."""
    vv = sp.Matrix(v)
    return sp.expand((vv.T * M * vv)[0, 0] / 2) - L.xreplace({vi: 0 for vi in v})


def _cheap_simplify(expr, fixed=None):
    """Fast trigonometric clean-up of a Lagrangian: expand, sin(x)^2 -> 1 - cos(x)^2 (so
    that cos^2 + sin^2 cancels), then cos a cos b + sin a sin b -> cos(a - b) (fu's TR10i).
    With `fixed` (the parameter symbols), the terms are first grouped by their factors that
    are not parameters, each group's coefficient a placeholder for TR10i (few terms, fast)
    and then put back with its common factors pulled out (:func:`_collect_params`)."""
    from sympy.simplify.fu import TR10i
    e = sp.expand(expr)
    e = e.replace(lambda u: u.is_Pow and u.exp == 2 and isinstance(u.base, sp.sin),
                  lambda u: 1 - sp.cos(u.base.args[0])**2)
    e = sp.expand(e)
    if fixed is None or not isinstance(e, sp.Add):
        return TR10i(e)
    groups = _groups(e, fixed)
    holders, back, out = {}, {}, sp.Integer(0)
    for key, cf in groups.items():
        num, cf = sp.factor_terms(cf).as_coeff_Mul()
        if cf not in holders:
            holders[cf] = sp.Dummy("c")
            back[holders[cf]] = cf
        out += num*holders[cf]*key
    return TR10i(out).xreplace(back)


def _groups(e, fixed):
    """{non-parameter factor: sum of the parameter factors} over the terms of the sum e."""
    groups = {}
    for term in e.args:
        par, rest = [], []
        for f in sp.Mul.make_args(term):
            (par if f.free_symbols <= fixed else rest).append(f)
        key = sp.Mul(*rest)
        groups[key] = groups.get(key, sp.Integer(0)) + sp.Mul(*par)
    return groups


def _maybe_simplify(expr, simplify, v=(), parts=None, fixed=None):
    """simplify: True, False or "auto". A Lagrangian at most quadratic in the velocities v
    is cleaned up by parts, L = v^T M v / 2 + l1 . v + L0, each entry of M, l1 and L0 on its
    own (small expressions, so the clean-up stays fast for long chains); "auto" skips parts
    too large for it (more than 600 operations)."""
    if simplify not in (True, False, "auto"):
        raise ValueError(f"simplify must be True, False or 'auto', got {simplify!r}")
    if simplify is False:
        return expr

    def part(e):
        if e == 0:
            return e
        if simplify is True or sp.count_ops(e) <= 600:
            return _cheap_simplify(e, fixed)
        return e
    v = list(v)
    if v:
        n = len(v)
        qp = _quadratic_parts(expr, v) if fixed is not None else None
        if qp is not None:
            H, l1, L0 = qp
        else:
            grad = [sp.diff(expr, vi) for vi in v]
            H = [[sp.diff(grad[i], v[j]) for j in range(n)] for i in range(n)]
            zero = {vi: 0 for vi in v}
            l1 = [g.xreplace(zero) for g in grad]
            L0 = expr.xreplace(zero)
        if not any(h.free_symbols & set(v) for row in H for h in row):
            Hs = {}
            for i in range(n):
                for j in range(i, n):
                    Hs[i, j] = part(H[i][j])
            l1 = [part(g) for g in l1]
            L0 = part(L0)
            if parts is not None:        # the cleaned-up M, l1, L0 for the caller
                parts.extend([sp.Matrix(n, n, lambda i, j: Hs[min(i, j), max(i, j)]),
                              l1, L0])
            quad = sum((Hs[i, i]*v[i]**2/2 for i in range(n)), sp.Integer(0)) \
                + sum((Hs[i, j]*v[i]*v[j] for i in range(n) for j in range(i + 1, n)),
                      sp.Integer(0))
            return quad + sum((c*vi for c, vi in zip(l1, v)), sp.Integer(0)) + L0
    return part(expr)


def _quadratic_parts(expr, v):
    """L = v^T H v / 2 + l1 . v + L0 read off the expanded L term by term (no
    differentiation): (H as a list of rows, l1, L0), or None if L is not a polynomial of
    degree <= 2 in the velocities v."""
    n = len(v)
    idx = {vi: i for i, vi in enumerate(v)}
    vset = set(v)
    H = [[sp.Integer(0)]*n for _ in range(n)]
    l1 = [sp.Integer(0)]*n
    L0 = sp.Integer(0)
    for term in sp.Add.make_args(sp.expand(expr)):
        pw, rest = [], []
        for f in sp.Mul.make_args(term):
            b, e = f.as_base_exp()
            if b in vset and e.is_Integer and e > 0:
                pw += [idx[b]]*int(e)
            elif f.free_symbols & vset:
                return None
            else:
                rest.append(f)
        c = sp.Mul(*rest)
        if not pw:
            L0 += c
        elif len(pw) == 1:
            l1[pw[0]] += c
        elif len(pw) == 2:
            i, j = sorted(pw)
            if i == j:
                H[i][i] += 2*c
            else:
                H[i][j] += c
                H[j][i] += c
        else:
            return None
    return H, l1, L0


def _forces_list(forces, n, what="forces"):
    if forces is None:
        return [sp.Integer(0)] * n
    fl = _sympify_list(forces, what)
    if len(fl) != n:
        raise ValueError(f"{what} has {len(fl)} components for {n} coordinates")
    return fl


def derive_lagrangian(L, q, params=None, forces=None, velocities=None, simplify="auto",
                      jacobian=True, structured=True):
    """M q'' = Q from the Lagrangian L(t, q, q'); optional generalized forces.
    ``simplify`` (True, False, "auto") cleans L up first (sin^2 + cos^2 = 1, products of
    sines and cosines into cosines of differences) so that M and Q come out compact.
    ``jacobian=False`` skips R (the integrators then difference the accelerations).
    ``structured`` (default): Q and R are derived in the structured form of
    :func:`_structure` (``Derived.struct``, used by the compiled code; the expanded ``Q`` and
    ``R`` are then computed only when read); False: expanded Q and R (the form
    ``python -m conmech.symbolic emit`` writes)."""
    t = sp.Symbol("t")
    c = _Coords(q, velocities, t, need_speeds=True)
    n = len(c.plain)
    exprs = _unify_time(_sympify_list(L, "L") + _forces_list(forces, n), t)
    if len(exprs) != n + 1:
        raise ValueError("L must be a single expression")
    exprs = c.convert(exprs, "L")
    _check_no_accel(exprs, c)
    known = list(c.plain) + list(c.speeds)
    psyms, names, values, sub = _resolve_params(params, exprs, known, t)
    exprs = _subs_all(exprs, sub)
    exprs, t, psyms = _realify(exprs, t, c, psyms)
    parts = []
    Lp, fq = _maybe_simplify(exprs[0], simplify, c.speeds, parts,
                             set(psyms) if structured else None), exprs[1:]
    struct = None
    if structured:
        M = parts[0] if parts else _mass(Lp, c.speeds)
        fixed = set(psyms)
        M = M.applyfunc(lambda e: _collect_params(e, fixed))
        struct = _structure(Lp, M, c.plain, c.speeds, c.accels, t, fq, jacobian,
                            parts[1:] if parts else None)
    if struct is None:
        M, Q = _euler_lagrange(Lp, c.plain, c.speeds, t)
    _check_mass(M, c.plain, c.speeds, psyms, values, t)
    energy = _energy(Lp, M, c.speeds)
    d = Derived("generalized", t=t, coords=c.plain, coord_names=c.names,
                speeds=c.speeds, accels=c.accels, params=psyms, param_names=names,
                param_values=values, M=M, energy=energy, lagrangian=Lp, struct=struct,
                gen_forces=list(fq), with_jacobian=bool(jacobian))
    if struct is None:
        d.Q = Q + sp.Matrix(fq)
        if jacobian:
            Ma = M * sp.Matrix(c.accels)
            d.R = _ae((d.Q - Ma).jacobian(c.plain).row_join(d.Q.jacobian(c.speeds)))
    return d


def _collect_params(e, params):
    """A sum regrouped by its factors that are not parameters, each group's coefficient (a
    polynomial in the parameters) with its common factors pulled out: sum_k m_k l_i l_j
    cos(..) -> l_i l_j (sum_k m_k) cos(..), so that the code does not repeat the
    state-dependent factor per parameter."""
    if not isinstance(e, sp.Add):
        return e
    groups = _groups(e, params)
    if len(groups) == len(e.args):
        return e
    return sp.Add(*[sp.factor_terms(cf)*key for key, cf in groups.items()])


def _mass(L, v):
    """The Hessian of L in v (as _euler_lagrange computes it), symmetric by construction."""
    n = len(v)
    p = [sp.diff(L, vi) for vi in v]
    M = sp.zeros(n, n)
    for i in range(n):
        for j in range(n):
            M[i, j] = sp.diff(p[i], v[j])
    return M


def _check_no_accel(exprs, c):
    acc = set(c.accels)
    for e in exprs:
        if e.free_symbols & acc:
            raise ValueError("the expressions must not contain accelerations (second "
                             "derivatives of the coordinates)")


# ------------------------------------------------------------------------------ constrained

def derive_constrained(T, U, q, holonomic=(), nonholonomic=(), params=None, forces=None,
                       velocities=None, simplify="auto"):
    """Excessive coordinates q with L = T - U, holonomic phi(t, q) = 0 and Pfaffian
    constraints given as expressions linear in the velocities (A q' + b = 0)."""
    t = sp.Symbol("t")
    c = _Coords(q, velocities, t, need_speeds=True)
    n = len(c.plain)
    hol = _sympify_list(list(holonomic) if not isinstance(holonomic, sp.Basic)
                        else [holonomic], "holonomic")
    nh = _sympify_list(list(nonholonomic) if not isinstance(nonholonomic, sp.Basic)
                       else [nonholonomic], "nonholonomic")
    base = _sympify_list(T, "T") + _sympify_list(U, "U") + _forces_list(forces, n)
    if len(base) != n + 2:
        raise ValueError("T and U must be single expressions")
    exprs = _unify_time(base + hol + nh, t)
    exprs = c.convert(exprs, "the expressions")
    _check_no_accel(exprs, c)
    known = list(c.plain) + list(c.speeds)
    psyms, names, values, sub = _resolve_params(params, exprs, known, t)
    exprs = _subs_all(exprs, sub)
    exprs, t, psyms = _realify(exprs, t, c, psyms)
    Tp, Up, fq = exprs[0], exprs[1], exprs[2:2 + n]
    hol = exprs[2 + n:2 + n + len(hol)]
    nh = exprs[2 + n + len(hol):]
    if Up.free_symbols & set(c.speeds):
        raise ValueError("U must not depend on the velocities")
    L = _maybe_simplify(Tp - Up, simplify, c.speeds)
    M, Q = _euler_lagrange(L, c.plain, c.speeds, t)
    _check_mass(M, c.plain, c.speeds, psyms, values, t)
    Q = Q + sp.Matrix(fq)
    energy = _energy(L, M, c.speeds)
    q_, v_ = c.plain, c.speeds
    vv = sp.Matrix(v_)
    d = Derived("constrained", t=t, coords=q_, coord_names=c.names, speeds=v_,
                accels=c.accels, params=psyms, param_names=names, param_values=values,
                M=M, Q=Q, energy=energy, lagrangian=L, n_hol=len(hol), n_nh=len(nh))
    if hol:
        for i, h in enumerate(hol):
            if h.free_symbols & set(v_):
                raise ValueError(f"holonomic constraint {i} depends on the velocities "
                                 "(give it as nonholonomic)")
        phi = sp.Matrix(hol)
        G = phi.jacobian(q_)
        phi_t = sp.diff(phi, t)
        w = G * vv + phi_t                       # d phi/dt
        gamma_h = -(w.jacobian(q_) * vv + sp.diff(w, t))
        d.phi, d.G, d.phi_t, d.gamma_h = phi, G, phi_t, gamma_h
        d.rheonomic = any(sp.simplify(e) != 0 for e in phi_t) if len(hol) < 8 \
            else any(e != 0 for e in phi_t)
    if nh:
        E = sp.Matrix(nh)
        A = E.jacobian(v_)
        if A.free_symbols & set(v_):
            raise ValueError("a non-holonomic constraint is not linear in the velocities "
                             "(Pfaffian form A(t, q) q' + b(t, q) = 0 required)")
        b = E.xreplace({vi: 0 for vi in v_})
        w = A * vv + b
        gamma_n = -(w.jacobian(q_) * vv + sp.diff(w, t))
        d.A, d.b, d.gamma_n = A, b, gamma_n
    return d
