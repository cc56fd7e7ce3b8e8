"""Jacobian products of compiled systems: ``compiled.ode_system(jac_prod=...)`` (a C
function, spec slot 18) and the ``conmech_jac_prod`` that ``conmech.symbolic.ode_system``
generates. The variational equations (stm, monodromy) then evaluate J Phi through the
product without forming J; results agree with the dense-Jacobian path."""
import ctypes
import os
import shutil
import subprocess

import numpy as np
import pytest

import conmech
from conmech import compiled, stability

sp = pytest.importorskip("sympy")
from conmech import symbolic  # noqa: E402
import symbolic_seeds as seeds  # noqa: E402

HERE = os.path.dirname(__file__)
MU = 0.012277471
Y0 = [0.994, 0.0, 0.0, -2.00158510637908252240537862224]
T = 17.0652165601579625588917206249


@pytest.fixture(scope="session", autouse=True)
def symbolic_cache_jac_prod(tmp_path_factory):
    return seeds.use_test_cache(tmp_path_factory.getbasetemp())


def _inputs():
    f, y, mu = seeds.arenstorf_ode()
    return f, y, {mu: MU}


@pytest.fixture(scope="module")
def aren():
    return symbolic.ode_system(*_inputs(), model_only=True)


def without_product(model):
    a = model.addresses
    return compiled.ode_system(4, a["rhs"], jac=a["jac"], params={"mu": MU}, keep=model)


@pytest.fixture(scope="module")
def clib(tmp_path_factory):
    cc = shutil.which("gcc") or shutil.which("cc")
    assert cc is not None, "a C compiler is needed (gfortran's gcc)"
    out = tmp_path_factory.mktemp("cjp") / "libcjp.so"
    subprocess.run([cc, "-O2", "-fPIC", "-shared", os.path.join(HERE, "data", "c_systems.c"),
                    os.path.join(HERE, "data", "c_jac_prod.c"), "-o", str(out), "-lm"],
                   check=True)
    lib = ctypes.CDLL(str(out))
    lib.kepler_jac_prod_calls.restype = ctypes.c_long
    return lib


@pytest.mark.parametrize("k", [1, 4])
def test_symbolic_product_is_jacobian_times_x(aren, k):
    rng = np.random.default_rng(7)
    assert "jac_prod" in aren.addresses
    for _ in range(5):
        y = rng.uniform(-1.5, 1.5, 4)
        t = rng.uniform(0, 10)
        x = np.asfortranarray(rng.normal(size=(4, k)))
        jx = aren.call("jac_prod", t, y, x)
        ref = aren.call("jac", t, y) @ x
        assert jx.shape == (4, k)
        assert np.abs(jx - ref).max() <= 1e-14*np.abs(ref).max()
    # a vector x gives a vector
    assert aren.call("jac_prod", 0.0, y, x[:, 0]).shape == (4,)
    # new parameter values reach the product (run-time p)
    p2 = [0.2]
    np.testing.assert_allclose(aren.call("jac_prod", 0.0, y, x, params=p2),
                               aren.call("jac", 0.0, y, params=p2) @ x, rtol=1e-13,
                               atol=1e-13)


def test_product_of_a_sparse_jacobian_with_constants_and_zero_rows():
    # J has a zero row, entries 1, -1, -3, 1/2, and entries in t, y and a parameter
    a, b, c, d, k = sp.symbols("a b c d k")
    f = [sp.Integer(7), b - a + d/2, -3*a + k*sp.sin(c)*b, sp.exp(-d)*sp.Symbol("t")]
    m = symbolic.ode_system(f, [a, b, c, d], params={k: 1.7}, model_only=True)
    assert "jac_prod" in m.addresses
    rng = np.random.default_rng(3)
    y = rng.normal(size=4)
    x = np.asfortranarray(rng.normal(size=(4, 3)))
    J = m.call("jac", 0.8, y)
    assert np.all(J[0] == 0) and J[1, 0] == -1 and J[2, 0] == -3 and J[1, 3] == 0.5
    np.testing.assert_allclose(m.call("jac_prod", 0.8, y, x), J @ x, rtol=1e-14,
                               atol=1e-15)
    assert "jx(1, c) = 0.0_dp" in m.source and "-3.0_dp*x(1, c)" in m.source


def test_symbolic_system_passes_the_product(aren):
    s = symbolic.ode_system(*_inputs())
    assert s.spec[17] != 0 and s.spec.size >= 18
    assert without_product(aren).spec[17] == 0


def test_arenstorf_stm_and_monodromy_with_and_without_product(aren):
    with_p = symbolic.ode_system(*_inputs())
    no_p = without_product(aren)
    m1 = np.asarray(stability.monodromy(with_p, Y0, T, rtol=1e-12, atol=1e-12))
    m0 = np.asarray(stability.monodromy(no_p, Y0, T, rtol=1e-12, atol=1e-12))
    assert np.abs(m1 - m0).max() <= 1e-12*np.abs(m0).max()
    # a volume-preserving flow: det = 1 (to the integration accuracy of |Phi| ~ 1e4)
    assert abs(np.linalg.det(m1) - 1) < 1e-5
    y1, p1 = stability.stm(with_p, (0, T/3), Y0, rtol=1e-12, atol=1e-12)
    y0_, p0 = stability.stm(no_p, (0, T/3), Y0, rtol=1e-12, atol=1e-12)
    assert np.abs(p1 - p0).max() <= 1e-12*np.abs(p0).max()
    np.testing.assert_allclose(y1, y0_, rtol=1e-12, atol=1e-12)
    # and the built-in arenstorf (its own hand-written product) to the tolerance
    mb = np.asarray(stability.monodromy(conmech.systems.arenstorf(), Y0, T, rtol=1e-12,
                                        atol=1e-12))
    assert np.abs(m1 - mb).max() <= 1e-6*np.abs(mb).max()


def test_c_product_is_called_and_agrees(clib):
    def kep(jp):
        return compiled.ode_system(4, clib.kepler_rhs, clib.kepler_jac, params={"mu": 1.0},
                                   keep=clib, jac_prod=jp)
    y0 = [1.0, 0.0, 0.0, 1.2]
    before = clib.kepler_jac_prod_calls()
    m1 = np.asarray(stability.monodromy(kep(clib.kepler_jac_prod), y0, 5.0, rtol=1e-12,
                                        atol=1e-12))
    assert clib.kepler_jac_prod_calls() > before     # integrate_stm used the product
    mid = clib.kepler_jac_prod_calls()
    m0 = np.asarray(stability.monodromy(kep(None), y0, 5.0, rtol=1e-12, atol=1e-12))
    assert clib.kepler_jac_prod_calls() == mid       # not without it
    assert np.abs(m1 - m0).max() <= 1e-12*np.abs(m0).max()
    # the same through with_params (the spec, slot 18 included, is shared)
    s = kep(clib.kepler_jac_prod).with_params(mu=2.0)
    assert s.spec[17] != 0


def test_bad_jac_prod():
    with pytest.raises(TypeError, match="jac_prod must be"):
        compiled.ode_system(2, 12345, jac_prod="f")
    with pytest.raises(ValueError, match="jac_prod is a null function pointer"):
        compiled.ode_system(2, 12345, jac_prod=ctypes.c_void_p(None))


def test_model_library_exports_the_product(tmp_path):
    s = symbolic.ode_system(*_inputs())
    path = symbolic.save_model(s, tmp_path / "aren.so")
    m = compiled.load_model(path)
    assert m.kind == "ode" and m.spec[17] != 0
    a = np.asarray(stability.monodromy(m, Y0, T/2, rtol=1e-12, atol=1e-12))
    b = np.asarray(stability.monodromy(s, Y0, T/2, rtol=1e-12, atol=1e-12))
    assert np.abs(a - b).max() <= 1e-12*np.abs(b).max()
