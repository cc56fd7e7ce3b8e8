"""Compiled user systems (conmech.compiled): C functions with conmech's signatures, loaded
with ctypes, run wherever built-in systems run and agree with the hand-written built-ins."""
import ctypes
import os
import shutil
import subprocess

import numpy as np
import pytest
import scipy

import conmech
from conmech import compiled, constrained, stability

HERE = os.path.dirname(__file__)


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    cc = shutil.which("gcc") or shutil.which("cc")
    assert cc is not None, "a C compiler is needed (gfortran's gcc)"
    out = tmp_path_factory.mktemp("clib") / "libcsys.so"
    subprocess.run([cc, "-O2", "-fPIC", "-shared", os.path.join(HERE, "data", "c_systems.c"),
                    "-o", str(out), "-lm"], check=True)
    return ctypes.CDLL(str(out))


def kepler(lib, jac=True, mu=1.0):
    return compiled.ode_system(4, lib.kepler_rhs, lib.kepler_jac if jac else None,
                               params={"mu": mu}, keep=lib, name="kepler_c")


def test_kepler_agrees_with_builtin(lib):
    y0 = [0.4, 0.0, 0.0, 2.0]
    kw = dict(method="DOP853", rtol=1e-11, atol=1e-11, t_eval=np.linspace(0, 10, 11))
    a = conmech.solve_ivp(kepler(lib), (0, 10), y0, **kw)
    b = conmech.solve_ivp(conmech.systems.kepler(mu=1.0), (0, 10), y0, **kw)
    assert a.success and b.success
    # same arithmetic up to the order of operations: same steps, round-off differences
    assert a.nfev == b.nfev
    assert np.abs(a.y - b.y).max() < 1e-12*np.abs(b.y).max()*1e3


def test_evaluate_and_exact_jacobian(lib):
    s = kepler(lib)
    y = np.array([0.3, -0.7, 0.2, 1.1])
    e = compiled.evaluate(s, 0.0, y)
    b = compiled.evaluate(conmech.systems.kepler(), 0.0, y)
    assert e["analytic"]
    np.testing.assert_allclose(e["f"], b["f"], rtol=1e-15, atol=1e-15)
    # the C Jacobian against central differences of the C right-hand side
    h = 1e-6
    fd = np.column_stack([(compiled.evaluate(s, 0, y + h*ej)["f"]
                           - compiled.evaluate(s, 0, y - h*ej)["f"])/(2*h) for ej in np.eye(4)])
    np.testing.assert_allclose(e["jac"], fd, rtol=1e-8, atol=1e-8)
    assert not compiled.evaluate(kepler(lib, jac=False), 0.0, y)["analytic"]


def test_with_params_no_rebuild(lib):
    s = kepler(lib, mu=1.0)
    s4 = s.with_params(mu=4.0)
    assert s4.spec is s.spec and s4.parameters == {"mu": 4.0}
    y = np.array([1.0, 0.0, 0.0, 1.0])
    assert compiled.evaluate(s4, 0, y)["f"][2] == pytest.approx(-4.0)
    with pytest.raises(ValueError, match="unknown parameter 'nu'"):
        s.with_params(nu=1.0)
    with pytest.raises(ValueError, match="mu must be finite"):
        s.with_params(mu=np.nan)


def test_monodromy_exact_jacobian_vs_fd(lib):
    # circular Kepler orbit, period 2 pi: the exact-Jacobian STM is far more accurate
    y0 = [1.0, 0.0, 0.0, 1.0]
    m_ex = stability.monodromy(kepler(lib), y0, 2*np.pi, rtol=1e-12, atol=1e-12)
    m_fd = stability.monodromy(kepler(lib, jac=False), y0, 2*np.pi, rtol=1e-12, atol=1e-12)
    # closed form of the circular orbit's monodromy (rotating nothing: period 2 pi, the
    # secular term d(phase)/dr): compare the two, and the exact one against its trace = 4
    assert abs(np.trace(m_ex) - 4.0) < 1e-9
    assert abs(np.linalg.det(m_ex) - 1.0) < 1e-9
    assert np.abs(m_ex - m_fd).max() < 1e-5


def test_generalized_cart_pendulum(lib):
    P = dict(M=1.3, m=0.7, l=0.9, g=9.81)
    s = compiled.generalized_system(2, lib.cart_mass, lib.cart_forces, lib.cart_forces_jac,
                                    lib.cart_energy, params=P, keep=lib, name="cart")
    b = conmech.systems.cart_pendulum(**P)
    assert s.dimension == 4 and s.ndof == 2
    q, v = np.array([0.1, 2.5]), np.array([0.3, -0.4])
    es, eb = compiled.evaluate(s, 0.0, q, v), compiled.evaluate(b, 0.0, q, v)
    np.testing.assert_allclose(es["M"], eb["M"], rtol=1e-15)
    np.testing.assert_allclose(es["Q"], eb["Q"], rtol=1e-15)
    assert es["energy"] == pytest.approx(eb["energy"], rel=1e-15)
    y = np.concatenate([q, v])
    js, jb = compiled.evaluate(s, 0.0, y), compiled.evaluate(b, 0.0, y)
    # both exact: the compiled Jacobian and the built-in's (generated from its Lagrangian)
    assert js["analytic"] and jb["analytic"]
    np.testing.assert_allclose(js["jac"], jb["jac"], rtol=1e-13, atol=1e-13)
    y0 = [0.1, np.pi - 0.6, 0.2, 0.0]
    kw = dict(method="DOP853", rtol=1e-12, atol=1e-12, t_eval=np.linspace(0, 5, 51))
    ra, rb = conmech.solve_ivp(s, (0, 5), y0, **kw), conmech.solve_ivp(b, (0, 5), y0, **kw)
    assert ra.success and rb.success
    assert np.abs(ra.y - rb.y).max() < 1e-10*np.abs(rb.y).max()
    # the upright equilibrium: a saddle (z'' = +... z); analytic Jacobian used
    eq = stability.equilibrium(s, [0, 0, 0, 0])
    assert eq.analytic and eq.kind == "unstable"


def test_constrained_pendulum_xy(lib):
    s = compiled.constrained_system(2, lib.pxy_mass, lib.pxy_forces, n_hol=1, phi=lib.pxy_phi,
                                    phi_jac=lib.pxy_phi_jac, phi_gamma=lib.pxy_phi_gamma,
                                    energy=lib.pxy_energy, params=dict(m=1.0, g=9.81, l=1.0),
                                    keep=lib, name="pxy")
    q0, v0 = [np.sin(1.0), -np.cos(1.0)], [0.0, 0.0]
    kw = dict(rtol=1e-11, atol=1e-11, t_eval=np.linspace(0, 5, 26))
    a = constrained.solve(s, (0, 5), q0, v0, **kw)
    b = constrained.solve("pendulum_xy", (0, 5), q0, v0, **kw)
    assert a.success and b.success
    assert np.abs(a.q - b.q).max() < 1e-10
    assert np.abs(a.lam - b.lam).max() < 1e-9*np.abs(b.lam).max()
    assert np.abs(a.energy - a.energy[0]).max() < 1e-9
    e = compiled.evaluate(s, 0.0, q0, [0.3, 0.1])
    eb = compiled.evaluate(constrained.builtin("pendulum_xy"), 0.0, q0, [0.3, 0.1])
    for k in ("M", "Q", "phi", "G", "gamma_h"):
        np.testing.assert_allclose(e[k], eb[k], rtol=1e-14, atol=1e-14)
    with pytest.raises(ValueError, match="pass q0 and v0"):
        constrained.solve(s, (0, 1))
    # the finite-difference defaults when only phi is given
    s_fd = compiled.constrained_system(2, lib.pxy_mass, lib.pxy_forces, n_hol=1,
                                       phi=lib.pxy_phi, params=[1.0, 9.81, 1.0], keep=lib)
    c = constrained.solve(s_fd, (0, 5), q0, v0, **kw)
    assert c.success and np.abs(c.q - b.q).max() < 1e-6


def test_address_kinds(lib):
    rhs = lib.kepler_rhs
    addr = ctypes.cast(rhs, ctypes.c_void_p).value
    assert compiled.function_address(addr) == addr
    assert compiled.function_address(rhs) == addr
    assert compiled.function_address(ctypes.c_void_p(addr)) == addr
    llc = scipy.LowLevelCallable(ctypes.cast(rhs, ctypes.CFUNCTYPE(None)))
    assert compiled.function_address(llc) == addr
    s = compiled.ode_system(4, addr, params=[1.0], keep=lib)
    r = conmech.solve_ivp(s, (0, 1), [1.0, 0, 0, 1.0], rtol=1e-10, atol=1e-10)
    assert r.success and abs(r.y[0, -1] - np.cos(1.0)) < 1e-8


@pytest.mark.parametrize("kw, err, match", [
    (dict(n=0), ValueError, "n must be >= 1"),
    (dict(n=2.5), TypeError, "n must be an integer"),
    (dict(rhs=None), ValueError, "rhs is required"),
    (dict(rhs=0), ValueError, "null function pointer"),
    (dict(rhs="f"), TypeError, "rhs must be an address"),
    (dict(params=[np.inf]), ValueError, "p0 must be finite"),
    (dict(params=[1.0], param_names=["a", "b"]), ValueError, "2 names for 1 params"),
])
def test_bad_input(lib, kw, err, match):
    args = dict(n=4, rhs=lib.kepler_rhs, params=[1.0], keep=lib)
    args.update(kw)
    with pytest.raises(err, match=match):
        compiled.ode_system(**args)


def test_bad_constrained_input(lib):
    with pytest.raises(ValueError, match="phi is required"):
        compiled.constrained_system(2, lib.pxy_mass, lib.pxy_forces, n_hol=1)
    with pytest.raises(ValueError, match="leave no motion"):
        compiled.constrained_system(2, lib.pxy_mass, lib.pxy_forces, n_hol=2,
                                    phi=lib.pxy_phi)
    s = kepler(lib)
    with pytest.raises(ValueError, match="y0 has 2 components"):
        stability.stm(s, (0, 1), [1.0, 0.0])
    with pytest.raises(ValueError, match="y0 must have shape"):
        conmech.solve_ivp(s, (0, 1), [1.0, 0.0], rtol=1e-8)


def test_model_library(tmp_path):
    cc = shutil.which("gcc") or shutil.which("cc")
    so = tmp_path / "libkep.so"
    subprocess.run([cc, "-O2", "-fPIC", "-shared", os.path.join(HERE, "data",
                    "c_model_kepler.c"), "-o", str(so), "-lm"], check=True)
    s = compiled.load_model(so)
    assert s.kind == "ode" and s.dimension == 4 and s.parameters == {"mu": 1.0}
    r = conmech.solve_ivp(s.with_params(mu=4.0), (0, np.pi), [1.0, 0, 0, 2.0], rtol=1e-10,
                          atol=1e-10)
    assert r.success and np.abs(r.y[:, -1] - [1.0, 0, 0, 2.0]).max() < 1e-8  # period pi
    with pytest.raises(ValueError, match="cannot load the model library"):
        compiled.load_model(tmp_path / "missing.so")
