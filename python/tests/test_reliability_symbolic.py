"""The symbolic front end and the parameter lists check their inputs (named regressions).

Each case used to integrate a different system, drop an entry, reach gfortran with an
unprintable expression, or raise a bare OverflowError / TypeError; each must now raise a
ValueError or TypeError naming the entry or the argument, before anything is compiled."""
import numpy as np
import pytest

sp = pytest.importorskip("sympy")
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402

import symbolic_seeds as seeds  # noqa: E402
import conmech  # noqa: E402
from conmech import compiled, constrained, stability, symbolic, systems  # noqa: E402

x, v, k = sp.symbols("x v k")


@pytest.fixture(scope="module", autouse=True)
def cache(tmp_path_factory):
    return seeds.use_test_cache(tmp_path_factory.getbasetemp())


BAD_F = {
    "complex_term": ([v, -x + sp.I], r"f\[1\] contains the imaginary unit I"),
    "complex_python_number": ([v, -x + 2j], r"f\[1\] contains the imaginary unit I"),
    "complex_exponential": ([v, sp.exp(sp.I * x)], r"f\[1\] contains the imaginary unit"),
    "nested_matrix": ([v, sp.Matrix([x, x])], r"f\[1\] is a matrix or a list"),
    "nested_list": ([v, [x, x]], r"f\[1\] is a matrix or a list"),
    "nan": ([v, -x * sp.nan], r"f\[1\] contains nan"),
    "zoo": ([v, sp.zoo * x], r"f\[1\] contains an infinity"),
    "oo": ([v, -x + sp.oo], r"f\[1\] contains an infinity"),
    "minus_oo": ([v, -sp.oo * x], r"f\[1\] contains an infinity"),
    "division_by_zero": ([sp.Integer(1) / 0, -x], r"f\[0\] contains an infinity"),
    "unevaluated_integral": ([v, -sp.Integral(x, x)], r"f\[1\] contains the unevaluated "
                                                       r"Integral"),
    "unevaluated_sum": ([v, -sp.Sum(x / k, (k, 1, 3))], r"f\[1\] contains the unevaluated Sum"),
    "unevaluated_limit": ([v, sp.Limit(x / k, k, 2)], r"f\[1\] contains the unevaluated "
                                                       r"Limit"),
    "huge_rational": ([v, -sp.Rational(10 ** 400, 3) * x], r"f\[1\] contains the number "
                                                             r".*401-digit numerator"),
    "tiny_rational": ([v, -sp.Rational(1, 10 ** 400) * x], r"f\[1\] contains the number .*"
                                                             r"outside the range of double"),
    "huge_integer": ([v, -sp.Integer(10) ** 400 * x], r"outside the range of double"),
    "huge_float": ([v, -sp.Float("1e400") * x], r"f\[1\] contains an infinity|outside"),
    "unknown_function": ([v, -sp.Function("f")(x)], r"depends on f\(x\)"),
    "unknown_symbol": ([v, -k * x], r"unknown symbol.*'k'"),
    "too_few": ([v], r"f has 1 components for 2"),
    "bool_entry": ([v, True], r"f\[1\].*bool"),
}


@pytest.mark.parametrize("case", sorted(BAD_F))
def test_bad_ode_right_hand_side_is_refused(case):
    f, msg = BAD_F[case]
    with pytest.raises((ValueError, TypeError), match=msg):
        symbolic.ode_system(f, [x, v])


def test_matrix_that_is_not_a_vector_is_refused():
    with pytest.raises(ValueError, match="f is a 2 x 2 matrix"):
        symbolic.ode_system(sp.Matrix([[v, x], [x, v]]), [x, v])
    # a column vector is fine
    s = symbolic.ode_system(sp.Matrix([v, -x]), [x, v], model_only=True)
    assert s.derived.n == 2


def test_rational_with_huge_terms_is_printed_correctly_rounded():
    big = sp.Rational(10 ** 30 + 1, 10 ** 29)       # ~10, numerator and denominator > 2^53
    s = symbolic.ode_system([v, -big * x], [x, v], model_only=True)
    np.testing.assert_array_equal(s.call("rhs", 0.0, [1.0, 0.0]), [0.0, -float(big)])


def test_bad_lagrangian_and_constraints_are_refused():
    q = dynamicsymbols("q")
    t = dynamicsymbols._t
    L = q.diff(t) ** 2 / 2 - q ** 2 / 2
    with pytest.raises(ValueError, match=r"L contains the imaginary unit"):
        symbolic.lagrangian_system(L + sp.I * q, [q])
    with pytest.raises(ValueError, match=r"forces\[0\] contains nan"):
        symbolic.lagrangian_system(L, [q], forces=[sp.nan])
    a, b = dynamicsymbols("a b")
    T = (a.diff(t) ** 2 + b.diff(t) ** 2) / 2
    with pytest.raises(ValueError, match=r"holonomic\[0\] contains the unevaluated Integral"):
        symbolic.constrained_system(T, 0, [a, b], holonomic=[a ** 2 + sp.Integral(b, b) - 1])
    with pytest.raises(ValueError, match=r"U contains an infinity"):
        symbolic.constrained_system(T, sp.zoo * a, [a, b])


@pytest.mark.parametrize("value, exc, msg", [
    (True, TypeError, "must be a real number"), ("2", ValueError, "no numeric value"),
    (1 + 2j, TypeError, "must be a real number"), (None, ValueError, "has no value"),
    (float("nan"), ValueError, "must be finite"), (sp.Symbol("z"), ValueError,
                                                   "no real numeric value"),
    (sp.I, ValueError, "no real numeric value"), (10 ** 400, ValueError, "numeric value")])
def test_parameter_values_are_strict(value, exc, msg):
    with pytest.raises(exc, match=f"parameter 'k' .*{msg}|parameter 'k' {msg}"):
        symbolic.ode_system([v, -k * x], [x, v], params={k: value})


@pytest.fixture(scope="module")
def osc():
    return symbolic.ode_system([v, -k * x], [x, v], params={k: 1.0})


@pytest.mark.parametrize("value, exc", [(True, TypeError), ("2", TypeError),
                                        (np.bool_(True), TypeError), (1j, TypeError),
                                        (None, TypeError), (float("inf"), ValueError),
                                        ([2.0], TypeError)])
def test_with_params_is_strict(osc, value, exc):
    with pytest.raises(exc, match="parameter k"):
        osc.with_params(k=value)
    assert osc.with_params(k=np.float32(2.5)).parameters == {"k": 2.5}
    with pytest.raises(ValueError, match="unknown parameter 'c'"):
        osc.with_params(c=1.0)


def test_compiled_call_parameters_are_strict(osc):
    m = symbolic.model_of(osc)
    np.testing.assert_array_equal(m.call("rhs", 0.0, [1.0, 0.0], params=[4.0]), [0.0, -4.0])
    with pytest.raises(TypeError, match="params must be 1 real numbers"):
        m.call("rhs", 0.0, [1.0, 0.0], params=[True])
    with pytest.raises(TypeError, match="params must be 1 real numbers"):
        m.call("rhs", 0.0, [1.0, 0.0], params="4")
    with pytest.raises(ValueError, match="params must have 1 values"):
        m.call("rhs", 0.0, [1.0, 0.0], params=[1.0, 2.0])
    with pytest.raises(ValueError, match="no entry point 'mass'"):
        m.call("mass", 0.0, [1.0, 0.0])
    # the ctypes function is built once per entry
    assert m._entry("rhs") is m._entry("rhs")
    with pytest.raises(TypeError, match="parameter mu"):
        compiled.ode_system(2, m.addresses["rhs"], params={"mu": "1"})
    with pytest.raises(TypeError, match="parameter p0"):
        compiled.ode_system(2, m.addresses["rhs"], params=[False])


@pytest.mark.parametrize("make", [
    lambda: constrained.solve("pendulum_xy", (0, 1), [1.0, 0.0], [0.0, 0.0],
                              params=[1, 2, 3, 4, 5]),
    lambda: constrained.builtin("double_pendulum_xy", [1, 1, 1, 1, 9.81, 0]),
    lambda: systems.BuiltinSystem("pendulum", [9.81, 1.0, 3.0]),
    lambda: conmech.solve_ivp(systems.BuiltinSystem("kepler", [1.0, 2.0]), (0, 1),
                              [1, 0, 0, 1]),
])
def test_extra_parameters_are_refused_as_the_programs_do(make):
    with pytest.raises(ValueError, match=r"params: \d+ values given for the system '\w+', "
                                         r"which has \d+ \("):
        make()


def test_parameter_counts_match_the_programs_table():
    """Every built-in takes exactly the parameters its documented list names."""
    from conmech import _conmech
    for name in list(constrained.BUILTIN_NAMES) + ["harmonic", "pendulum", "kepler",
                                                   "arenstorf", "vanderpol", "hill",
                                                   "cart_pendulum", "double_pendulum"]:
        count, names = _conmech.flat_builtin_params(name)
        names = (names.decode() if isinstance(names, bytes) else str(names)).strip()
        assert count >= 1 and len(names.split(", ")) == count, (name, count, names)
    assert _conmech.flat_builtin_params("no_such_system")[0] == -1


def fun(t, s, p):
    return [s[1], -s[0] + p * 0, 0.0]


@pytest.mark.parametrize("kw, exc, msg", [
    (dict(period=None), TypeError, "period must be a real number"),
    (dict(period="6.3"), TypeError, "period must be a real number"),
    (dict(ds="1.0"), TypeError, "ds must be a real number"),
    (dict(ds=True), TypeError, "ds must be a real number"),
    (dict(ds=-0.1), ValueError, "ds must be > 0"),
    (dict(p0="1.5"), TypeError, "p0 must be a real number"),
    (dict(max_points=2.5), TypeError, "max_points must be an integer"),
    (dict(p_range=(0, None)), TypeError, r"p_range\[1\] must be a real number"),
    (dict(p_range=5), TypeError, "p_range must be a pair"),
])
def test_continuation_arguments_give_clear_messages(kw, exc, msg):
    args = dict(period=6.3, p0=1.5, ds=0.1, max_points=3)
    args.update(kw)
    period = args.pop("period")
    with pytest.raises(exc, match=msg):
        stability.continuation(fun, [1, 0, 0], period, **args)


@pytest.mark.parametrize("m", [True, "0.1", None, float("nan")])
def test_hill_arguments_are_strict(m):
    with pytest.raises((TypeError, ValueError), match="m must be"):
        conmech.hill.variation_orbit(m)


@pytest.mark.parametrize("expr, exc, msg", [
    (x + sp.I, ValueError, r"events\[0\] contains the imaginary unit I"),
    (x + 2j, ValueError, r"events\[0\] contains the imaginary unit I"),
    (x * sp.nan, ValueError, r"events\[0\] contains nan"),
    (x + sp.zoo, ValueError, r"events\[0\] contains an infinity"),
    (x - sp.oo, ValueError, r"events\[0\] contains an infinity"),
    (sp.Sum(x / k, (k, 1, 3)), ValueError, r"events\[0\] contains the unevaluated Sum"),
    (x + sp.Rational(10 ** 400, 3), ValueError, r"events\[0\] contains the number"),
    (sp.Matrix([x, x]), TypeError, r"(?s)events\[0\]: .* is not a scalar expression"),
    (sp.Function("f")(x), ValueError, r"events\[0\]: unknown function"),
])
def test_compiled_event_expressions_are_checked(expr, exc, msg):
    """An event of a compiled system given as a sympy expression is checked like the
    system's own entries: x + I used to drop the imaginary part (g = x), nan and zoo to
    reach gfortran, oo to become the largest double."""
    s = symbolic.ode_system([v, -k * x], [x, v], params={k: 1.0})
    with pytest.raises(exc, match=msg):
        symbolic.event(s, expr)(0.0, [0.5, 0.1])
