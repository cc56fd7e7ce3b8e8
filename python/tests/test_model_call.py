"""CompiledModel.call through the flat routine flat_entry_call(_1): its values agree with
the same entry called through ctypes (an independent path to the same function), its
outputs are fresh arrays, and bad inputs are refused with the argument named."""
import ctypes

import numpy as np
import pytest

sp = pytest.importorskip("sympy")
from conmech import symbolic  # noqa: E402

_D, _V = ctypes.c_double, ctypes.c_void_p


def _ctypes_call(model, entry, t, ins, shapes, p, ret=False):
    fn = ctypes.CFUNCTYPE(_D if ret else None, _D, *([_V] * (len(ins) + len(shapes) + 1)))(
        model.addresses[entry])
    ins = [np.ascontiguousarray(a, dtype=float) for a in ins]
    outs = [np.zeros(s, order="F") for s in shapes]
    r = fn(t, *[a.ctypes.data for a in ins], *[o.ctypes.data for o in outs], p.ctypes.data)
    return r if ret else outs


@pytest.fixture(scope="module")
def cart():
    x, th, M, m, l, g = sp.symbols("x theta M m l g")
    xd, thd = sp.symbols("xd thd")
    # the cart pendulum's Lagrangian in coordinates q = (x, theta), velocities (xd, thd)
    T = (M + m)*xd**2/2 + m*l*xd*thd*sp.cos(th) + m*l**2*thd**2/2
    U = m*g*l*sp.cos(th)
    from sympy.physics.mechanics import dynamicsymbols
    xt, tht = dynamicsymbols("x theta")
    L = (T - U).subs({x: xt, th: tht, xd: xt.diff(), thd: tht.diff()})
    return symbolic.lagrangian_system(L, [xt, tht], params={M: 1.0, m: 0.3, l: 0.7, g: 9.81},
                                      model_only=True)


def test_entries_agree_with_ctypes(cart):
    rng = np.random.default_rng(3)
    p = np.array(list(cart.derived.param_values), dtype=float)
    for _ in range(5):
        q, v, a = rng.normal(size=2), rng.normal(size=2), rng.normal(size=2)
        t = float(rng.normal())
        for entry, ins in (("mass", [q]), ("forces", [q, v]), ("forces_jac", [q, v, a])):
            shapes = cart._shapes(entry)
            want = _ctypes_call(cart, entry, t, ins, shapes, p)[0]
            got = cart.call(entry, t, *ins)
            assert got.shape == want.shape and np.array_equal(got, want), entry
        e = _ctypes_call(cart, "energy", t, [q, v], [], p, ret=True)
        got = cart.call("energy", t, q, v)
        assert type(got) is float and got == e


def test_two_outputs_and_params(cart):
    q, v = np.array([0.1, 0.4]), np.array([-0.2, 0.3])
    if "mass_forces" in cart.addresses:
        M, Q = cart.call("mass_forces", 0.0, q, v)
        assert np.array_equal(M, cart.call("mass", 0.0, q))
        assert np.array_equal(Q, cart.call("forces", 0.0, q, v))
    # other parameters: g = 0 removes gravity from the forces (theta's row: m g l sin)
    p = np.array(list(cart.derived.param_values), dtype=float)
    names = [str(n) for n in cart.derived.param_names]
    p0 = p.copy()
    p0[names.index("g")] = 0.0
    q0 = np.array([0.0, 0.5])
    f_g = cart.call("forces", 0.0, q0, np.zeros(2))
    f_0 = cart.call("forces", 0.0, q0, np.zeros(2), params=p0)
    assert np.allclose(f_0, 0.0)
    assert abs(f_g[1] - 0.3*9.81*0.7*np.sin(0.5)) < 1e-14


def test_outputs_fresh_and_inputs_untouched():
    x, v, k = sp.symbols("x v k")
    model = symbolic.ode_system([v, -k*sp.sin(x)], [x, v], params={k: 2.0}, model_only=True)
    y = np.array([0.3, 0.1])
    y.flags.writeable = False                  # a read-only input is accepted
    a = model.call("rhs", 0.0, y)
    b = model.call("rhs", 0.0, [0.3, 0.1])
    assert a is not b and np.array_equal(a, b)
    assert np.array_equal(a, [0.1, -2.0*np.sin(0.3)])
    a[0] = 99.0
    assert model.call("rhs", 0.0, y)[0] == 0.1
    J = model.call("jac", 1.0, y)
    assert J.shape == (2, 2) and np.array_equal(J, [[0.0, 1.0], [-2.0*np.cos(0.3), 0.0]])
    with pytest.raises(ValueError, match="shape"):
        model.call("rhs", 0.0, [0.3])
    with pytest.raises(ValueError, match="takes t and 1"):
        model.call("rhs", 0.0, y, y)
    with pytest.raises(ValueError, match="no entry point"):
        model.call("nope", 0.0, y)
    with pytest.raises(ValueError, match="params must have 1"):
        model.call("rhs", 0.0, y, params=[1.0, 2.0])


def test_fast_path_agrees_with_the_checked_call():
    """After its first call, an entry with one input and one output is called by identity
    and type tests only: every input the checks would convert (a list, float32, an int t,
    a strided view, explicit parameters) must give bit for bit what the plain call gives,
    and every bad input must still be refused with its message."""
    x, v, k = sp.symbols("x v k")
    model = symbolic.ode_system([v, -k*sp.sin(x)], [x, v], params={k: 2.0}, model_only=True)
    y = np.array([0.3, 0.1])
    first = model.call("rhs", 0.5, y)                 # the checked call
    fast = model.call("rhs", 0.5, y)                  # the fast path
    assert first is not fast and np.array_equal(first, fast)
    assert np.array_equal(fast, [0.1, -2.0*np.sin(0.3)])
    strided = np.array([0.3, -1.0, 0.1])[::2]
    for t, arr, kw in ((0.5, [0.3, 0.1], {}), (np.float64(0.5), y, {}), (0.5, strided, {}),
                       (0.5, y, {"params": [2.0]}), (0.5, y, {"params": np.array([2.0])})):
        assert np.array_equal(model.call("rhs", t, arr, **kw), fast)
    # an int t and a float32 input are converted, as by the checked call
    assert np.array_equal(model.call("rhs", 0, y), model.call("rhs", 0.0, y))
    y32 = np.array([0.25, 0.5], dtype=np.float32)
    assert np.array_equal(model.call("rhs", 0.5, y32),
                          model.call("rhs", 0.5, y32.astype(np.float64)))
    # 2-D outputs keep their shape and Fortran order on the fast path
    J1, J2 = model.call("jac", 0.0, y), model.call("jac", 0.0, y)
    assert J2.shape == (2, 2) and J2.flags.f_contiguous and np.array_equal(J1, J2)
    # the checks still run for what the fast path does not take
    with pytest.raises(ValueError, match="shape"):
        model.call("rhs", 0.0, np.zeros(3))
    with pytest.raises(ValueError, match="takes t and 1"):
        model.call("rhs", 0.0, y, y)
    with pytest.raises(TypeError, match="params must be 1 real numbers"):
        model.call("rhs", 0.0, y, params=[True])
