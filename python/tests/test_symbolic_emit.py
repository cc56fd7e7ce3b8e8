"""`python -m conmech.symbolic emit`: standalone Fortran modules from symbolic models.

The committed example modules (example/*_model.f90) are regenerated from their model files
and must be identical; the fpm examples that use them are built and run, and their results
agree with conmech's built-ins (cart pendulum, Arenstorf, rolling ball) computed from Python.
"""
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

import conmech  # noqa: E402
from conmech import stability, systems  # noqa: E402
from conmech.symbolic.__main__ import emit_file, main  # noqa: E402
from conmech.symbolic.derive import derive_constrained, derive_lagrangian, derive_ode  # noqa: E402,E501
from conmech.symbolic.emit_fortran import emit  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "example"
MODELS = [("cart_pendulum", "cart_pendulum_sym"), ("arenstorf", "arenstorf_sym"),
          ("rolling_ball", "rolling_ball_sym")]


@pytest.mark.parametrize("model, typename", MODELS)
def test_committed_module_is_regenerated_identically(model, typename):
    out = EXAMPLE / f"{model}_model.f90"
    src, name, module = emit_file(EXAMPLE / "models" / f"{model}.py", out)
    assert (name, module) == (typename, f"{model}_model")
    assert src == out.read_text(), f"{out} is stale: re-run the emit command in its header"
    assert all(len(line) <= 100 for line in src.splitlines())
    # deterministic: a second run gives the same text
    assert emit_file(EXAMPLE / "models" / f"{model}.py", out)[0] == src


def test_cli_writes_and_checks(tmp_path, capsys):
    out = tmp_path / "pend_model.f90"
    assert main(["emit", str(EXAMPLE / "models" / "cart_pendulum.py"), "-o", str(out),
                 "--name", "pend"]) == 0
    text = out.read_text()
    assert "module pend_model" in text and "type, extends(ode_system) :: pend" in text
    assert "type, extends(generalized_system) :: pend_mech" in text
    assert main(["emit", str(EXAMPLE / "models" / "cart_pendulum.py"), "-o", str(out),
                 "--name", "pend", "--check"]) == 0
    out.write_text(text.replace("9.81_dp", "9.80_dp"))
    assert main(["emit", str(EXAMPLE / "models" / "cart_pendulum.py"), "-o", str(out),
                 "--name", "pend", "--check"]) == 1
    assert not list(tmp_path.glob(".emit_*"))   # no temporary left behind


def test_cli_as_module_and_bad_input(tmp_path):
    run = [sys.executable, "-m", "conmech.symbolic", "emit"]
    r = subprocess.run(run + [str(tmp_path / "nosuch.py"), "-o", str(tmp_path / "x.f90")],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "does not exist" in r.stderr
    bad = tmp_path / "bad.py"
    bad.write_text("model = 42\n")
    r = subprocess.run(run + [str(bad), "-o", str(tmp_path / "x.f90")], capture_output=True,
                       text=True)
    assert r.returncode == 2 and "not a conmech.symbolic Derived" in r.stderr
    assert not (tmp_path / "x.f90").exists()


def test_bad_names():
    x = sp.Symbol("x")
    v = sp.Symbol("xd")
    M, m = sp.symbols("M m")
    d = derive_lagrangian((M + m) * v ** 2 / 2 - x ** 2 / 2, [x], velocities=[v],
                          params={M: 1.0, m: 2.0})
    with pytest.raises(ValueError, match="case-insensitive"):
        emit(d, "osc")
    n = sp.Symbol("n")
    d3 = derive_lagrangian(n * v ** 2 / 2, [x], velocities=[v], params={n: 1.0})
    with pytest.raises(ValueError, match="clashes"):
        emit(d3, "osc")
    d4 = derive_lagrangian(m * v ** 2 / 2, [x], velocities=[v], params={m: 1.0})
    with pytest.raises(ValueError, match="not a valid Fortran name"):
        emit(d4, "1osc")
    with pytest.raises(ValueError, match="different names"):
        emit(d4, "osc", module="OSC")
    with pytest.raises(TypeError, match="Derived"):
        emit("not a model", "osc")


def test_constrained_module_has_every_procedure():
    x, y = sp.symbols("x y")
    xd, yd = sp.symbols("xd yd")
    m, l, g = sp.symbols("m l g")
    d = derive_constrained(m * (xd ** 2 + yd ** 2) / 2, m * g * y, [x, y],
                           holonomic=[(x ** 2 + y ** 2 - l ** 2) / 2],
                           params={m: 1.0, l: 1.0, g: 9.81}, velocities=[xd, yd])
    src = emit(d, "pend_xy")
    for p in ("mass", "forces", "energy", "phi", "phi_jac", "phi_t", "phi_gamma"):
        assert f"procedure :: {p} => pend_xy_{p}" in src
    assert "nh_matrix" not in src
    assert "s%n_hol = 1" in src and "s%rheonomic = .false." in src


# ------------------------------------------------------------------ fpm build and run
def fpm_example(name):
    if shutil.which("fpm") is None:
        pytest.fail("fpm is not on PATH: run the tests through scripts/test.sh")
    r = subprocess.run(["fpm", "run", "--example", name], cwd=ROOT, capture_output=True,
                       text=True, timeout=900)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout


def value(out, label, k=1):
    m = re.search(re.escape(label) + r"\s*((?:[-+0-9.E]+\s*){%d})" % k, out)
    assert m, (label, out)
    return [float(s) for s in m.group(1).split()]


def load_model_module(model):
    import importlib.util
    spec = importlib.util.spec_from_file_location(f"_emit_test_{model}",
                                                  EXAMPLE / "models" / f"{model}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_model_file_with_a_compiled_system(tmp_path):
    """MODEL.py may define `system = symbolic.lagrangian_system(...)`: same module text."""
    f = tmp_path / "cart_model_compiled.py"
    base = str(EXAMPLE / "models" / "cart_pendulum.py")
    f.write_text("import importlib.util, sys\n"
                 "from conmech import symbolic\n"
                 f"spec = importlib.util.spec_from_file_location('m', {base!r})\n"
                 "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m)\n"
                 "L, q, params = m.inputs()\n"
                 "system = symbolic.lagrangian_system(L, q, params)\n"
                 "name = 'cart_pendulum_sym'\n")
    out = EXAMPLE / "cart_pendulum_model.f90"
    src, _, _ = emit_file(f, out)
    assert src.split("\n", 1)[1] == out.read_text().split("\n", 1)[1]  # header names the file


def test_fpm_example_user_model_agrees_with_builtins():
    out = fpm_example("user_model")
    y_fortran = np.array(value(out, "y(5):", 4))
    # the same model compiled from Python (conmech.symbolic) and integrated there
    from conmech import symbolic
    L, q, params = load_model_module("cart_pendulum").inputs()
    compiled = symbolic.lagrangian_system(L, q, params)
    rc = conmech.solve_ivp(compiled, (0, 5), [0.3, 2.5, 0.4, 1.0], rtol=1e-12, atol=1e-12)
    assert rc.success
    assert np.max(np.abs(y_fortran - rc.y[:, -1])) < 1e-10
    r = conmech.solve_ivp(systems.cart_pendulum(), (0, 5), [0.3, 2.5, 0.4, 1.0],
                          rtol=1e-12, atol=1e-12)
    assert r.success
    assert np.max(np.abs(y_fortran - r.y[:, -1])) < 1e-9
    assert value(out, "energy drift:")[0] < 1e-10
    assert value(out, "momentum drift:")[0] < 1e-10
    assert value(out, "generalized_solve vs ode_solve:")[0] < 1e-10
    assert value(out, "exact vs finite-difference Jacobian:")[0] < 1e-6
    assert abs(value(out, "Liouville det(STM) det M(q1)/det M(q0) - 1:")[0]) < 1e-10
    # Arenstorf: closed orbit, volume-preserving monodromy whose trace agrees with the
    # built-in's (finite-difference Jacobian, ~1e-6 relative)
    # the emitted product (integrate_stm's path) against the emitted dense Jacobian
    assert max(value(out, "arenstorf J x vs dense J times x, f vs rhs:", 2)) < 1e-14
    assert value(out, "arenstorf closure |y(T) - y(0)|:")[0] < 1e-8
    assert abs(value(out, "arenstorf det(monodromy) - 1:")[0]) < 1e-6
    tr = value(out, "arenstorf monodromy trace:")[0]
    y0 = [0.994, 0.0, 0.0, -2.00158510637908252240537862224]
    mono = stability.monodromy(systems.arenstorf(), y0, 17.0652165601579625588917206249,
                               rtol=1e-13, atol=1e-13)
    mono = getattr(mono, "M", mono)
    assert abs(np.trace(np.asarray(mono)) - tr) < 1e-4 * abs(tr)


def test_fpm_example_user_ball_agrees_with_builtin():
    out = fpm_example("user_ball")
    assert max(value(out, "symbolic vs built-in (q, v, lambda):", 3)) < 1e-10
    assert value(out, "parabola x = u t + a t^2/2:")[0] < 1e-10
    assert max(value(out, "constraint residuals (pos, vel):", 2)) < 1e-12
    assert value(out, "energy drift:")[0] < 1e-10


# ------------------------------------------------------------------ names shared with conmech
def _installed_library(prefix):
    """conmech's library and its module files, installed by scripts/install.sh the way a
    user of another build system gets them (fpm's build tree keeps modules and library in
    directories named by different hashes, so pairing them by date can mix two builds)."""
    if shutil.which("fpm") is None:
        pytest.fail("fpm is not on PATH: run the tests through scripts/test.sh")
    r = subprocess.run(["bash", str(ROOT / "scripts" / "install.sh"), "--prefix", str(prefix),
                        "--library-only"], cwd=ROOT, capture_output=True, text=True,
                       timeout=1800)
    assert r.returncode == 0, r.stdout + r.stderr
    return prefix / "include", prefix / "lib" / "libconmech.a"


@pytest.mark.parametrize("kind", ["ode", "generalized"])
def test_names_shared_with_conmech_compile(tmp_path, kind):
    """A system called ode_solve (a conmech procedure) with parameters called radau_solve
    and ode_options: the module imports only what it uses from conmech, so it compiles,
    and a program that uses both conmech and the model still reaches conmech's
    ode_solve through a rename."""
    x, v = sp.symbols("x xd")
    k, c = sp.symbols("radau_solve ode_options")
    if kind == "ode":
        d = derive_ode([v, -k * x - c * v], [x, v], params={k: 2.0, c: 0.1})
    else:
        d = derive_lagrangian(v ** 2 / 2 - k * x ** 2 / 2, [x], velocities=[v],
                              params={k: 2.0, c: 0.1})
    src = emit(d, "ode_solve", module="clash_model")
    uses = [ln for ln in src.splitlines() if ln.strip().startswith("use conmech")]
    assert uses[0].strip().startswith("use conmech, only:")
    (tmp_path / "clash_model.f90").write_text(src)
    (tmp_path / "main.f90").write_text(
        "program main\n"
        "    use conmech, only: dp, ode_options, ode_result, conmech_ode_solve => ode_solve\n"
        "    use clash_model, only: ode_solve, new_ode_solve\n"
        "    implicit none\n"
        "    type(ode_solve) :: s\n"
        "    type(ode_options) :: opt\n"
        "    type(ode_result) :: r\n"
        "    real(dp) :: y(2)\n"
        "    s = new_ode_solve()\n"
        "    y = [1.0_dp, 0.0_dp]\n"
        "    call conmech_ode_solve(s, [0.0_dp, 1.0_dp], y, opt, r)\n"
        "    if (.not. r%success) error stop 1\n"
        "    print '(2es24.16)', r%y(:, r%nt)\n"
        "end program main\n")
    moddir, lib = _installed_library(tmp_path / "prefix")
    exe = tmp_path / "main"
    r = subprocess.run(["gfortran", f"-I{moddir}", "-J", str(tmp_path), "clash_model.f90",
                        "main.f90", str(lib), "-llapack", "-lblas", "-o", str(exe)],
                       cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    out = subprocess.run([str(exe)], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    y1 = [float(s) for s in out.stdout.split()]
    # exact solution of the damped (ode) or undamped (Lagrangian) oscillator at t = 1
    w = np.sqrt(2.0)
    if kind == "ode":
        wd = np.sqrt(2.0 - 0.05 ** 2)
        exact = np.exp(-0.05) * (np.cos(wd) + 0.05 / wd * np.sin(wd))
    else:
        exact = np.cos(w)
    assert abs(y1[0] - exact) < 1e-4
