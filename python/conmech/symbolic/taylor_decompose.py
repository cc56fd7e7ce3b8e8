"""The decomposition of a right-hand side into elementary operations with Taylor
recurrences (see :mod:`conmech.symbolic.taylor`, which prints their Fortran): each
operation u_m = op(u_a, u_b) on the state, t and earlier operations, linear combinations
with constant coefficients kept as such, subexpressions of the parameters alone computed
once; :class:`TaylorUnsupported` names what has no recurrence (non-smooth functions)."""
import sympy as sp

__all__ = ["TaylorUnsupported", "Decomposition", "decompose", "variational_exprs"]


class TaylorUnsupported(ValueError):
    """The expression contains an operation without a Taylor recurrence here."""


class _Lin:
    """An affine form c0 + sum_i c_i u_i (constant coefficients, columns u_i)."""

    __slots__ = ("c0", "terms")

    def __init__(self, c0=sp.S.Zero, terms=None):
        self.c0 = sp.sympify(c0)
        self.terms = dict(terms or {})

    @staticmethod
    def col(c):
        return _Lin(0, {c: sp.S.One})

    def scaled(self, s):
        return _Lin(self.c0 * s, {c: v * s for c, v in self.terms.items()})

    def plus(self, other):
        out = dict(self.terms)
        for c, v in other.terms.items():
            out[c] = out.get(c, 0) + v
        return _Lin(self.c0 + other.c0, {c: v for c, v in out.items() if v != 0})

    def single(self):
        """The column if the form is exactly 1*u, else None."""
        if self.c0 == 0 and len(self.terms) == 1:
            (c, v), = self.terms.items()
            if v == 1:
                return c
        return None

    def key(self):
        return (self.c0, tuple(sorted(self.terms.items())))


class _Op:
    """One elementary operation: kind, output columns, argument columns, data."""

    __slots__ = ("kind", "out", "args", "data")

    def __init__(self, kind, out, args, data=None):
        self.kind, self.out, self.args, self.data = kind, out, args, data or {}


# kinds whose history sums weight the argument's coefficients by j (powers weight each
# term by ((r + 1) j - k) in the sum itself: one sum instead of two)
_JWEIGHT = {"exp", "sincos", "sinhcosh", "tan", "tanh"}
_INVERSE = {"log": None, "atan": "1+a2", "asin": "sqrt(1-a2)", "acos": "-sqrt(1-a2)",
            "asinh": "sqrt(1+a2)", "acosh": "sqrt(a2-1)", "atanh": "1-a2"}
_SMOOTH_FUNCS = {sp.exp: "exp", sp.log: "log", sp.sin: "sin", sp.cos: "cos",
                 sp.sinh: "sinh", sp.cosh: "cosh", sp.tan: "tan", sp.tanh: "tanh",
                 sp.atan: "atan", sp.asin: "asin", sp.acos: "acos", sp.asinh: "asinh",
                 sp.acosh: "acosh", sp.atanh: "atanh"}


class Decomposition:
    """The elementary operations of a set of output expressions.

    state : list of Symbols (columns 1..n), t : the time Symbol, params : parameter
    Symbols (run-time values p(1..)), outputs : expressions in t, state, params.
    ``given=False`` (an ODE): output i is y_i'; ``given=True``: the state series is given
    (e.g. events along a polynomial) and the outputs are materialized as columns.
    ``defs``: a chain of definitions [(Symbol, expression in t, state, params and earlier
    Symbols of the chain)] the outputs may use (straight-line code such as a tree's
    articulated-body algorithm): each is decomposed once, as an intermediate, instead of
    being substituted into the outputs; entries whose expression is a string (markers of
    the chain, such as pivot checks) are skipped.

    Attributes: n, ncol (columns of w), ops (in evaluation order), consts [(name, expr)],
    outputs (list of _Lin), out_cols (given=True: the output columns), t_col (or None).
    """

    def __init__(self, outputs, state, t, params, given=False, defs=()):
        self.state = list(state)
        self.n = len(self.state)
        self.t = t
        self.params = list(params)
        self.given = given
        self.ops = []
        self.consts = []               # (name, sympy expr in params / earlier consts)
        self._const_memo = {}
        self._memo = {}                # sympy expr -> _Lin
        self._lin_memo = {}            # lin key -> column
        self._op_memo = {}             # (kind, args, data) -> out columns
        self.ncol = self.n + (len(outputs) if given else 0)   # given: the outputs' columns
        self.t_col = None
        self._var = set(self.state) | {t}
        self._cse = {}
        exprs = [sp.sympify(e) for e in outputs]
        chain = [(s, sp.sympify(e)) for s, e in defs if not isinstance(e, str)]
        for e in exprs + [e for _, e in chain]:
            for f in e.atoms(sp.Function):
                if not (type(f) in _SMOOTH_FUNCS or isinstance(f, sp.Function) and
                        f.func in _SMOOTH_FUNCS):
                    raise TaylorUnsupported(
                        f"{type(f).__name__} ({f}) has no Taylor recurrence: the Taylor "
                        "integrator needs smooth functions (exp, log, sin, cos, tan, sinh, "
                        "cosh, tanh, their inverses, powers and roots)")
            for a in e.atoms(sp.Abs, sp.Min, sp.Max, sp.Piecewise):
                raise TaylorUnsupported(f"{a} is not smooth: no Taylor recurrence")
        for s, e in chain:            # the given chain first: the outputs refer to it
            if self._is_const(e):
                self._cse[s] = ("c", self._const(e))
            else:
                self._var.add(s)
                self._cse[s] = ("v", self._build(e))
        repl, red = sp.cse(exprs, symbols=sp.numbered_symbols("tcse", cls=sp.Dummy),
                           order="none")
        for s, e in repl:
            if self._is_const(e):
                self._cse[s] = ("c", self._const(e))
            else:
                self._var.add(s)
                self._cse[s] = ("v", self._build(e))
        self.outputs = [self._build(e) for e in red]
        self.out_cols = list(range(self.n + 1, self.n + len(red) + 1)) if given else []
        # columns whose coefficients enter history sums weighted by j (j u_j): kept as
        # their own columns, so that each history term is one multiply-add
        self.jcol = {}
        for op in self.ops:
            need = op.args[0] if op.kind in _JWEIGHT else op.out[0] if \
                op.kind.startswith("inv_") else None
            if need is not None and need not in self.jcol:
                self.jcol[need] = self._new_cols(1)[0]

    # ------------------------------------------------------------------ helpers
    def _is_const(self, e):
        return not (e.free_symbols & self._var)

    def _const(self, e):
        """A constant (no state, no t): a number, or a named value computed once."""
        e = sp.sympify(e)
        e = e.xreplace({s: v[1] for s, v in self._cse.items() if v[0] == "c"})
        if e.is_Number:
            return e
        if e in self._const_memo:
            return self._const_memo[e]
        name = sp.Dummy(f"tc{len(self.consts) + 1}", real=True)
        self.consts.append((name, e))
        self._const_memo[e] = name
        return name

    def _new_cols(self, k):
        cols = list(range(self.ncol + 1, self.ncol + k + 1))
        self.ncol += k
        return cols

    def _op(self, kind, args, data=None, nout=1):
        key = (kind, tuple(args), tuple(sorted((data or {}).items(), key=str)))
        if key in self._op_memo:
            return self._op_memo[key]
        out = self._new_cols(nout)
        self.ops.append(_Op(kind, out, list(args), data))
        self._op_memo[key] = out
        return out

    def _mat(self, lin):
        """The column of an affine form (a linear-combination operation if needed)."""
        c = lin.single()
        if c is not None:
            return c
        k = lin.key()
        if k not in self._lin_memo:
            out = self._new_cols(1)
            self.ops.append(_Op("lin", out, sorted(lin.terms), {"lin": lin}))
            self._lin_memo[k] = out[0]
        return self._lin_memo[k]

    def _col(self, e):
        return self._mat(self._build(e))

    def _tcol(self):
        if self.t_col is None:
            self.t_col = self._new_cols(1)[0]
            self.ops.append(_Op("time", [self.t_col], []))
        return self.t_col

    # ------------------------------------------------------------------ build
    def _build(self, e):
        """The affine form of expression e (which depends on the state or t)."""
        if e in self._memo:
            return self._memo[e]
        r = self._build_new(e)
        if any(v.is_Add for v in r.terms.values()):
            # coefficients that became sums (a column reached by two terms with symbolic
            # factors, e.g. through definitions that share it): one named constant each,
            # so that every coefficient prints as a factor
            r = _Lin(r.c0, {c: self._const(v) if v.is_Add else v
                            for c, v in r.terms.items()})
        self._memo[e] = r
        return r

    def _build_new(self, e):
        if self._is_const(e):
            return _Lin(self._const(e))
        if e.is_Symbol:
            if e in self._cse:
                kind, v = self._cse[e]
                return _Lin(v) if kind == "c" else v
            if e == self.t:
                return _Lin.col(self._tcol())
            return _Lin.col(self.state.index(e) + 1)
        if e.is_Add:
            const, var = e.as_independent(*self._var, as_Add=True)
            out = _Lin(self._const(const) if const != 0 else 0)
            terms = [term.as_independent(*self._var, as_Add=False)
                     for term in sp.Add.make_args(var)]
            groups, terms = self._common_factors(terms)
            for f, part in groups:
                # f (sum c rest): one product for the group
                s = _Lin()
                for c, rest in part:
                    s = s.plus(self._build(rest).scaled(self._const(c) if c != 1 else 1))
                out = out.plus(_Lin.col(self._op("mul", sorted([self._col(f),
                                                                self._mat(s)]))[0]))
            for c, v in terms:
                out = out.plus(self._build(v).scaled(self._const(c) if c != 1 else 1))
            return out
        if e.is_Mul:
            c, v = e.as_independent(*self._var, as_Add=False)
            if c != 1:
                return self._build(v).scaled(self._const(c))
            return _Lin.col(self._product(e))
        if e.is_Pow:
            return _Lin.col(self._power(e.base, e.exp))
        if isinstance(e, sp.Function) and e.func in _SMOOTH_FUNCS:
            return _Lin.col(self._function(_SMOOTH_FUNCS[e.func], e.args[0]))
        raise TaylorUnsupported(f"cannot expand {type(e).__name__} ({e}) in Taylor series")

    def _common_factors(self, terms):
        """The terms (c, v) of a sum (c constant, v variable) grouped by a variable factor f
        that two or more of them share beside other variable factors: sum c_i f r_i
        = f sum c_i r_i takes one product where the terms take one each (a term f alone
        joins its group for free, its r = 1). Greedy, the factor with the most such terms
        first. Terms with a variable denominator are left as they are (their quotient
        would become a reciprocal and a product). Returns ([(f, [(c, r), ...])], the
        other terms)."""
        def plain(v):
            return all(not (x.is_Integer and x < 0) for _, x in
                       (a.as_base_exp() for a in sp.Mul.make_args(v)))
        groups = []
        while True:
            count = {}
            for c, v in terms:
                if v.is_Mul and plain(v):
                    for a in sp.Mul.make_args(v):
                        count[a] = count.get(a, 0) + 1
            best = [a for a, k in count.items() if k >= 2]
            if not best:
                return groups, terms
            f = max(best, key=lambda a: (count[a], sp.default_sort_key(a)))
            part, others = [], []
            for c, v in terms:
                args = sp.Mul.make_args(v)
                if v == f:
                    part.append((c, sp.S.One))
                elif v.is_Mul and plain(v) and f in args:
                    part.append((c, sp.Mul(*[a for a in args if a != f])))
                else:
                    others.append((c, v))
            groups.append((f, part))
            terms = others

    def _product(self, e):
        """Column of a product of variable factors: numerator chain / denominator chain."""
        num, den = [], []
        for f in sp.Mul.make_args(e):
            b, x = f.as_base_exp()
            if x.is_Integer and x < 0 and not self._is_const(b):
                den.append(b ** (-x))
            else:
                num.append(f)
        nc = self._chain(num) if num else None
        if not den:
            return nc
        dc = self._chain(den)
        if nc is None:
            return self._op("recip", [dc], {"c": sp.S.One})[0]
        return self._op("div", [nc, dc])[0]

    def _chain(self, factors):
        cols = sorted(self._col(f) for f in factors)
        acc = cols[0]
        for c in cols[1:]:
            acc = (self._op("sq", [acc]) if c == acc else
                   self._op("mul", [min(acc, c), max(acc, c)]))[0]
        return acc

    def _power(self, b, x):
        if self._is_const(x):
            if self._is_const(b):       # cannot happen (caught as constant)
                raise TaylorUnsupported(f"constant power {b}**{x}")
            a = self._col(b)
            if x.is_Number:
                if x == 1:
                    return a
                if x == 2:
                    return self._op("sq", [a])[0]
                if x == 3:
                    return self._op("mul", sorted([a, self._op("sq", [a])[0]]))[0]
                if x == 4:
                    return self._op("sq", [self._op("sq", [a])[0]])[0]
                if x == sp.S.Half:
                    return self._op("sqrt", [a])[0]
                if x.is_Integer and x < 0:
                    return self._op("recip", [self._power(b, -x)], {"c": sp.S.One})[0]
                if x == 0:
                    raise TaylorUnsupported("x**0")
                return self._op("pow", [a], {"r": sp.nsimplify(x) if x.is_Float else x})[0]
            return self._op("pow", [a], {"r": self._const(x)})[0]
        # variable exponent: b**x = exp(x log b)
        if self._is_const(b):
            lb = self._const(sp.log(b))
            return self._op("exp", [self._mat(self._build(x).scaled(lb))])[0]
        return self._function("exp", x * sp.log(b))

    def _function(self, name, arg):
        a = self._col(arg)
        if name in ("sin", "cos"):
            s, c = self._op("sincos", [a], nout=2)
            return s if name == "sin" else c
        if name in ("sinh", "cosh"):
            s, c = self._op("sinhcosh", [a], nout=2)
            return s if name == "sinh" else c
        if name == "exp":
            return self._op("exp", [a])[0]
        if name in ("tan", "tanh"):
            key = (name, (a,), ())
            if key in self._op_memo:
                return self._op_memo[key][0]
            out = self._new_cols(1)
            op = _Op(name, out, [a, None])
            self.ops.append(op)
            self._op_memo[key] = out
            sq = self._op("sq", [out[0]])[0]
            g = self._mat(_Lin(1, {sq: 1 if name == "tan" else -1}))
            op.args[1] = g
            return out[0]
        if name in _INVERSE:
            if name == "log":
                u = a
            else:
                a2 = self._op("sq", [a])[0]
                form = _INVERSE[name]
                if form == "1+a2":
                    u = self._mat(_Lin(1, {a2: 1}))
                elif form == "1-a2":
                    u = self._mat(_Lin(1, {a2: -1}))
                elif form == "sqrt(1-a2)":
                    u = self._op("sqrt", [self._mat(_Lin(1, {a2: -1}))])[0]
                elif form == "-sqrt(1-a2)":
                    u = self._mat(_Lin(0, {self._op("sqrt", [self._mat(
                        _Lin(1, {a2: -1}))])[0]: -1}))
                elif form == "sqrt(1+a2)":
                    u = self._op("sqrt", [self._mat(_Lin(1, {a2: 1}))])[0]
                else:
                    u = self._op("sqrt", [self._mat(_Lin(-1, {a2: 1}))])[0]
            return self._op("inv_" + name, [a, u])[0]
        raise TaylorUnsupported(f"no Taylor recurrence for {name}")

    # ------------------------------------------------------------------ summary
    def counts(self):
        """{kind: number of operations}."""
        out = {}
        for op in self.ops:
            out[op.kind] = out.get(op.kind, 0) + 1
        return out


def decompose(exprs, state, t, params, given=False, defs=()):
    """The :class:`Decomposition` of the expressions (see the class)."""
    return Decomposition(exprs, state, t, params, given, defs)


def variational_exprs(f, jac, n):
    """The first-order variational system z' = [f; J Phi] (Phi n x n, column-major in z)
    as expressions in the state symbols and n*n new Dummies; returns (exprs, phi symbols)."""
    phi = [sp.Dummy(f"phi{i + 1}_{j + 1}", real=True) for j in range(n) for i in range(n)]
    P = sp.Matrix(n, n, lambda i, j: phi[j * n + i])
    JP = jac * P
    return list(f) + [JP[i, j] for j in range(n) for i in range(n)], phi
