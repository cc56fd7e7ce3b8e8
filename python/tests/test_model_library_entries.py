"""Model libraries (``sweep --model LIB.so``, conmech_model_library) pick up the fast entry
points when the library exports them: ``conmech_mass_forces`` and ``conmech_accel``
(generalized models) and ``conmech_jac_prod`` (ode models); without them the plain entries
are used. Results agree with the Python path through the same library."""
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import conmech
from conmech import compiled

sp = pytest.importorskip("sympy")
from conmech import symbolic  # noqa: E402
from conmech.symbolic.build import compile_source  # noqa: E402
from conmech.symbolic.codegen import generate  # noqa: E402
import symbolic_seeds as seeds  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
GRID = ["--vary", "y0:1", "--from", "0.2", "--to", "1.0", "--count", "3", "--t-end", "3",
        "--rtol", "1e-11", "--atol", "1e-11", "--quiet"]


@pytest.fixture(scope="session", autouse=True)
def symbolic_cache_models(tmp_path_factory):
    return seeds.use_test_cache(tmp_path_factory.getbasetemp())


@pytest.fixture(scope="module")
def sweep():
    if shutil.which("fpm") is None:
        pytest.fail("fpm is not on PATH: run the tests through scripts/test.sh")
    subprocess.run(["fpm", "build"], cwd=ROOT, capture_output=True, check=True)
    out = subprocess.run(["fpm", "run", "sweep", "--runner", "echo"], cwd=ROOT,
                         capture_output=True, text=True, check=True).stdout
    return str(ROOT / out.strip().splitlines()[-1].strip())


def run_sweep(exe, lib, y0, cwd, env=None):
    out = f"{Path(lib).stem}.csv"
    r = subprocess.run([exe, "--model", str(lib), "--y0", y0, *GRID, "--out", out],
                       cwd=cwd, capture_output=True, text=True, timeout=300, env=env)
    assert r.returncode == 0, r.stderr
    lines = (Path(cwd) / out).read_text().splitlines()[1:]
    return np.array([[float(x) for x in ln.split(",")] for ln in lines])


def cc_build(tmp, name, fast):
    cc = shutil.which("gcc") or shutil.which("cc")
    assert cc, "a C compiler is needed (gfortran brings gcc)"
    out = tmp / name
    subprocess.run([cc, "-O2", "-shared", "-fPIC", *(["-DFAST"] if fast else []), "-o",
                    str(out), str(HERE / "data" / "c_model_spy.c"), "-lm"], check=True)
    return out


def test_sweep_uses_the_fast_entries_of_a_generalized_model(sweep, tmp_path):
    fast, plain = cc_build(tmp_path, "fast.so", True), cc_build(tmp_path, "plain.so", False)
    spy = tmp_path / "calls.txt"
    env = dict(os.environ, CONMECH_SPY_OUT=str(spy))
    a = run_sweep(sweep, fast, "0.5,0", tmp_path, env)
    n_mass, n_forces, n_mf, n_accel = map(int, spy.read_text().split())
    # the right-hand side calls one fast entry instead of mass + forces
    assert n_mf + n_accel > 0 and n_mass == 0 and n_forces == 0
    b = run_sweep(sweep, plain, "0.5,0", tmp_path, env)
    n_mass, n_forces, n_mf, n_accel = map(int, spy.read_text().split())
    assert n_mass > 0 and n_forces > 0 and n_mf == n_accel == 0
    assert a.shape == b.shape == (3, 7)   # job, value, y1, y2, t_return, nfev, status
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-13)
    # the Python path through the same library (compiled.load_model)
    m = compiled.load_model(fast)
    for row in a:
        r = conmech.solve_ivp(m, (0, 3), [row[1], 0.0], method="DOP853", rtol=1e-11,
                              atol=1e-11)
        assert r.success
        np.testing.assert_allclose(row[2:4], r.y[:, -1], rtol=1e-12, atol=1e-13)


def test_sweep_of_a_symbolic_model_with_and_without_mass_forces(sweep, tmp_path):
    L, q = seeds.cart_pendulum()
    s = symbolic.lagrangian_system(L, q, params=dict(M=1.0, m=0.5, l=1.0, g=9.81))
    lib = symbolic.save_model(s, tmp_path / "cart.so")
    d = symbolic.model_of(s).derived
    src, entries = generate(d, model_values=list(s.params))
    assert "mass_forces" in entries
    # the same library with conmech_mass_forces hidden: the plain entries are used
    hidden = src.replace('name="conmech_mass_forces"', 'name="hidden_mass_forces"')
    assert hidden != src
    path, _ = compile_source(hidden)
    plain = shutil.copy(path, tmp_path / "cart_plain.so")
    y0 = "0.3,2.5,0.4,1.0"
    a = run_sweep(sweep, lib, y0, tmp_path)
    b = run_sweep(sweep, plain, y0, tmp_path)
    assert a.shape == b.shape == (3, 9)
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-13)
    for row in a:
        r = conmech.solve_ivp(s, (0, 3), [row[1], 2.5, 0.4, 1.0], method="DOP853",
                              rtol=1e-11, atol=1e-11)
        assert r.success
        np.testing.assert_allclose(row[2:6], r.y[:, -1], rtol=1e-12, atol=1e-13)


def test_sweep_of_a_symbolic_ode_model_with_jac_prod(sweep, tmp_path):
    # an ode model exports conmech_jac_prod; sweep (explicit DOP853) runs it as before
    f, y, mu = seeds.arenstorf_ode()
    s = symbolic.ode_system(f, y, params={mu: 0.012277471})
    lib = symbolic.save_model(s, tmp_path / "aren.so")
    a = run_sweep(sweep, lib, "0.994,0,0,-2.00158510637908252240537862224", tmp_path)
    for row in a:
        r = conmech.solve_ivp(s, (0, 3), [row[1], 0, 0, -2.00158510637908252240537862224],
                              method="DOP853", rtol=1e-11, atol=1e-11)
        assert r.success
        np.testing.assert_allclose(row[2:6], r.y[:, -1], rtol=1e-11, atol=1e-12)
