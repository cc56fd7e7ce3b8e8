"""History sums computed two at a time (conmech.symbolic.taylor's written-out routine): sums
of the same form share one 2-wide vector, as the two lanes of a pair of columns.

- the pairing finds the grouping an SLP vectorizer would (Kepler: the two squares and the
  two products x P, y P; Arenstorf: the two distances' squares and powers, the products
  (x + mu) P1 and (x - 1 + mu) P2; y^2 and y (c - m1 P1 - mu P2), whose common factor y
  the decomposition takes out, alone), every pair of one kind and weight, no column in
  two lanes;
- the paired written-out routine gives the coefficients of the unpaired one (and of the
  loop routine) to the last bit, for powers, products, squares and sine/cosine pairs
  (each lane runs the scalar sum's operations in the same order).
"""
import ctypes

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

import conmech  # noqa: E402
from conmech import symbolic  # noqa: E402
from conmech.symbolic import build  # noqa: E402
from conmech.symbolic import taylor as T  # noqa: E402
from conmech.symbolic.pipeline import model_of  # noqa: E402
from conmech.symbolic.taylor_recipe import Recipe  # noqa: E402

_P = ctypes.POINTER(ctypes.c_double)
x, y, u, v, mu = sp.symbols("x y u v mu")


def kepler_f():
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    return [u, v, -x/r3, -y/r3]


def arenstorf_f():
    mup = 1 - mu
    d1 = ((x + mu)**2 + y**2)**sp.Rational(3, 2)
    d2 = ((x - mup)**2 + y**2)**sp.Rational(3, 2)
    return [u, v, x + 2*v - mup*(x + mu)/d1 - mu*(x - mup)/d2,
            y - 2*u - mup*y/d1 - mu*y/d2]


def pendulum_f():
    a, b = x, y
    dd = a - b
    den = 3 - sp.cos(2*dd)
    return [u, v, (-3*sp.sin(a) - sp.sin(a - 2*b) - 2*sp.sin(dd)*(v**2 + u**2*sp.cos(dd)))/den,
            2*sp.sin(dd)*(2*u**2 + 2*sp.cos(a) + v**2*sp.cos(dd))/den]


def pairing(f, params=()):
    dec = T.decompose(f, [x, y, u, v], sp.Symbol("t"), list(params))
    pp = T._Printer(dec, {p: f"p({i + 1})" for i, p in enumerate(params)}, False, "dp")
    pp.scalars = set()
    rc = Recipe(pp, False, 15)
    pairs, lanes = T._pair_history(rc.hist, dec)
    kind = {c: op.kind for op in dec.ops for c in op.out}
    return dec, rc.hist, pairs, lanes, kind


def _check_pairs(hist, pairs, lanes):
    seen = set()
    for i, j in pairs:
        assert i != j and not ({i, j} & seen)
        seen |= {i, j}
        wi, wj = hist[i][3], hist[j][3]
        assert wi is wj or wi == wj
        for a, b in zip(hist[i][1:3], hist[j][1:3]):
            assert a == b or (lanes[a][0] == lanes[b][0] and lanes[a][1] == 0 and
                              lanes[b][1] == 1)
    slots = list(lanes.values())
    assert len(slots) == len(set(slots))          # no lane holds two columns


def _kind_of(dec, entry):
    """The kind of the operation a history sum belongs to: the recipe makes its
    accumulators h1, h2, ... in the order of the operations, one per operation with a
    history sum (two for a sine/cosine pair, none for linear combinations and time)."""
    order = []
    for op in dec.ops:
        order += [op.kind]*{"lin": 0, "time": 0, "sincos": 2, "sinhcosh": 2}.get(op.kind, 1)
    return order[int(entry[0][1:]) - 1]


def test_kepler_pairs_the_squares_and_the_products():
    dec, hist, pairs, lanes, kind = pairing(kepler_f())
    _check_pairs(hist, pairs, lanes)
    assert len(hist) == 5
    assert sorted(_kind_of(dec, hist[i]) for i, _ in pairs) == ["mul", "sq"]
    for i, j in pairs:
        assert _kind_of(dec, hist[i]) == _kind_of(dec, hist[j])
    assert lanes[1][0] == lanes[2][0]             # x and y: one group
    unpaired = [k for k in range(len(hist)) if all(k not in pr for pr in pairs)]
    assert [_kind_of(dec, hist[k]) for k in unpaired] == ["pow"]


def test_arenstorf_pairs_the_two_distances():
    dec, hist, pairs, lanes, kind = pairing(arenstorf_f(), [mu])
    _check_pairs(hist, pairs, lanes)
    kinds = sorted(_kind_of(dec, hist[i]) for i, _ in pairs)
    assert kinds == ["mul", "pow", "sq"]
    for i, j in pairs:
        assert _kind_of(dec, hist[i]) == _kind_of(dec, hist[j])
    unpaired = [k for k in range(len(hist)) if all(k not in pr for pr in pairs)]
    # y^2, and y times the sum of the two powers' terms (one product for y's equation)
    assert [_kind_of(dec, hist[k]) for k in unpaired] == ["sq", "mul"]


def _fixed_jet(source, nw, order, y0, params):
    lib = ctypes.CDLL(build.compile_source(source, flags=build.FFLAGS + T.FIXED_EXTRA_FLAGS)[0])
    fn = lib.conmech_taylor_fixed
    fn.argtypes = [ctypes.c_double, ctypes.c_int, _P, _P]
    w = np.zeros((nw, order + 1))
    w[:4, 0] = y0
    p = np.ascontiguousarray(params if len(params) else np.zeros(1), dtype=float)
    fn(0.3, order, w.ctypes.data_as(_P), p.ctypes.data_as(_P))
    return w[:4]


@pytest.mark.parametrize("name", ["arenstorf", "pendulum"])
def test_paired_routine_is_the_unpaired_one_bit_for_bit(name):
    f, params, y0 = {"arenstorf": (arenstorf_f(), {mu: 0.012277471}, [0.994, 0.01, 0.02, -2.0]),
                     "pendulum": (pendulum_f(), {}, [1.2, -0.4, 0.3, 0.1])}[name]
    system = symbolic.ode_system(f, [x, y, u, v], params=params)
    d = model_of(system).derived
    order = 15
    paired = T.fixed_order_source(d, order, variational=False)
    plain = T.fixed_order_source(d, order, variational=False, paired=False)
    assert "hv1" in paired and "hv1" not in plain
    nw = system.taylor["nw"]
    a = _fixed_jet(paired, nw, order, y0, list(params.values()))
    b = _fixed_jet(plain, nw, order, y0, list(params.values()))
    assert np.all(np.isfinite(a)) and np.array_equal(a, b)


def test_written_out_flags_keep_the_bits():
    """The written-out routine is compiled for the machine's vector encoding (AVX2 where
    the processor has it) but never with contracted multiply-adds: a fused a*b + c rounds
    once, the loop version (compiled with the package's flags) twice, and the coefficients
    would drift apart from it and from the batch lanes."""
    flags = T.FIXED_EXTRA_FLAGS
    assert "-fopenmp-simd" in flags
    assert "-ffp-contract=off" in flags
    assert not any(f.startswith("-march") or f == "-mfma" for f in flags)


@pytest.mark.parametrize("order", [2, 15])
def test_each_state_coefficient_is_stored_once(order):
    """The state's coefficients go into w as they are computed: each w(k, i), k = 1..p,
    i = 1..n, is assigned exactly once (no second copy), and w(0, i) never (the input)."""
    import re
    system = symbolic.ode_system(kepler_f(), [x, y, u, v])
    d = model_of(system).derived
    src = T.fixed_order_source(d, order, variational=False)
    stores = re.findall(r"^\s*w\((\d+), (\d+)\) =", src, flags=re.M)
    assert sorted(stores) == sorted((str(k), str(i)) for k in range(1, order + 1)
                                    for i in range(1, 5))
    # and the routine still gives the unpaired routine's (and so the loop version's) bits
    nw = system.taylor["nw"]
    y0 = [0.994, 0.01, 0.02, -2.0]
    a = _fixed_jet(src, nw, order, y0, [])
    b = _fixed_jet(T.fixed_order_source(d, order, variational=False, paired=False), nw,
                   order, y0, [])
    assert np.all(np.isfinite(a)) and np.array_equal(a, b)
