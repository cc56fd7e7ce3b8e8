"""The built-in systems, generated from their models (tools/builtin_models/) by
tools/generate_builtins.py.

- The committed Fortran and Python are exactly what the models give (regenerated into a
  temporary folder and compared byte for byte).
- The generated systems compute what the hand-written Fortran they replaced computed:
  python/tests/data/builtin_reference.npz was recorded by tools/builtin_reference.py from
  the hand-written systems (src/systems before the generator); f, M, Q, the energy, the
  constraints, G and the gamma terms at fixed states agree to round-off, DOP853 and the
  constrained solver take the same steps with the same evaluations (DOP853's dense-output
  stages aside, which today's driver spends only on steps that hold a point of t_eval) and
  reach the same states, and Radau takes the same steps, Jacobians and LU decompositions (the exact
  Jacobian of the accelerations saves the evaluations its finite differences cost).
- A system added the documented way (a model file, the generator) builds with the library
  and runs: its registry entry, its integration, its small-oscillation period.
"""
import importlib.util
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import conmech
from conmech import constrained, systems
from conmech.compiled import evaluate

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = Path(__file__).parent / "data" / "builtin_reference.npz"


def _load(name, path):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


generator = _load("generate_builtins", ROOT / "tools" / "generate_builtins.py")
recorder = _load("builtin_reference", ROOT / "tools" / "builtin_reference.py")


@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    """The generator's output written below a temporary folder, and the folder."""
    out = tmp_path_factory.mktemp("generated")
    assert generator.main(["--out", str(out)]) == 0
    return out


def test_committed_files_are_regenerated_identically(generated):
    files = sorted(p.relative_to(generated) for p in generated.rglob("*") if p.is_file())
    assert len(files) == 11
    for rel in files:
        assert (ROOT / rel).read_bytes() == (generated / rel).read_bytes(), (
            f"{rel} is stale: run python tools/generate_builtins.py")
    # nothing generated lies around that the models no longer give
    eq = {p.name for p in (ROOT / "src" / "systems").glob("*_equations.f90")}
    assert eq == {p.name for p in (generated / "src" / "systems").glob("*_equations.f90")}
    for rel in files:
        assert all(len(ln) <= 100 for ln in (generated / rel).read_text().splitlines())


def test_check_mode_finds_a_stale_file(generated, tmp_path, capsys):
    shutil.copytree(generated, tmp_path / "tree")
    assert generator.main(["--check", "--out", str(tmp_path / "tree")]) == 0
    target = tmp_path / "tree" / "src" / "systems" / "conmech_systems_params.f90"
    target.write_text(target.read_text().replace("9.81_dp", "9.80_dp", 1))
    assert generator.main(["--check", "--out", str(tmp_path / "tree")]) == 1
    assert "conmech_systems_params.f90" in capsys.readouterr().err


def _scale(x):
    """max(|x|, 1) over the finite entries (an undefined energy is NaN)."""
    finite = np.abs(x[np.isfinite(x)])
    return max(float(finite.max()) if finite.size else 0.0, 1.0)


def test_generated_systems_agree_with_the_handwritten_ones():
    old = np.load(REFERENCE)
    new = recorder.record()
    assert set(old.files) == set(new)
    for key in old.files:
        name, what = key.split("/")
        a, b = old[key], np.asarray(new[key])
        assert a.shape == b.shape, key
        if what == "dop853_counts":
            # same steps and rejections; the same evaluations of the steps themselves: the
            # reference's driver spent DOP853's three dense-output stages on every accepted
            # step, today's on the steps that hold a point of t_eval only
            assert np.array_equal(a[1:], b[1:]), (key, a, b)
            assert a[0] - 3*a[1] == b[0] - 3*recorder.DENSE_STEPS[name], (key, a, b)
        elif what == "solve_counts":
            # same steps, rejections, evaluations and projections
            assert np.array_equal(a, b), (key, a, b)
        elif what == "radau_counts":
            nfev, njev, nlu, nacc, nrej = a
            assert np.array_equal(a[1:], b[1:]), (key, a, b)
            kind = "ode" if name in recorder.FIRST_ORDER else "generalized"
            # the hand-written generalized systems' Jacobian was a finite difference: one
            # evaluation per state variable and Jacobian, which the exact one saves
            n = np.load(REFERENCE)[f"{name}/y0"].size
            assert nfev - b[0] == (0 if kind == "ode" else njev * n), (key, a, b)
        elif what == "jac" and name in recorder.GENERALIZED:
            # then: central differences; now: exact (see test_exact_jacobians)
            assert np.allclose(a, b, rtol=1e-6, atol=1e-6 * _scale(a)), key
        else:
            both = np.isnan(a) & np.isnan(b)
            assert np.array_equal(np.isnan(a), np.isnan(b)), key
            err = np.max(np.abs(np.where(both, 0.0, a - b)), initial=0.0)
            assert err <= 1e-13 * _scale(a), (key, err)


@pytest.mark.parametrize("name", list(recorder.GENERALIZED))
def test_exact_jacobians(name):
    """The generated Jacobian of a generalized system (first-order form) against
    Richardson-extrapolated central differences of f (error O(h^4) ~ 1e-12)."""
    sys_ = systems.BuiltinSystem(name, recorder.GENERALIZED[name])
    rng = np.random.default_rng(7)
    y = np.r_[0.4 + 0.5 * rng.random(sys_.dimension // 2),
              rng.standard_normal(sys_.dimension // 2)]
    out = evaluate(sys_, 0.2, y)
    assert out["analytic"]

    def diff(h):
        cols = []
        for j in range(y.size):
            e = np.zeros(y.size)
            e[j] = h
            cols.append((evaluate(sys_, 0.2, y + e)["f"] - evaluate(sys_, 0.2, y - e)["f"])
                        / (2 * h))
        return np.array(cols).T
    h = 1e-3
    rich = (4 * diff(h / 2) - diff(h)) / 3
    assert np.allclose(out["jac"], rich, rtol=1e-8, atol=1e-8 * _scale(out["jac"]))


def test_capabilities_follow_the_models():
    """Energy where the models define one (the Jacobi integral), none where it is not
    conserved or the model declares none; exact Jacobians everywhere."""
    for name, params in recorder.GENERALIZED.items():
        n = systems.BuiltinSystem(name, params).dimension // 2
        e = evaluate(systems.BuiltinSystem(name, params), 0.0, np.full(n, 0.5),
                     np.full(n, 0.1))["energy"]
        assert (e is None) == (name in ("atwood", "pendulum_moving", "yoyo_angle")), name
    for name in ("pendulum_moving_xy", "yoyo"):
        s = constrained.builtin(name)
        assert evaluate(s, 0.0, *s.initial_state())["energy"] is None
    s = constrained.builtin("skate")
    assert evaluate(s, 0.0, *s.initial_state())["energy"] is not None
    for name in recorder.FIRST_ORDER:
        sys_ = recorder.FIRST_ORDER[name][0]
        assert evaluate(sys_, 0.0, recorder.FIRST_ORDER[name][1])["analytic"]


def test_python_table_and_factories():
    from conmech._core import builtin_table as table
    assert list(table.PARAMS) == list(table.KINDS)
    for name, params in table.PARAMS.items():
        factory = getattr(systems, name)
        obj = factory()
        assert obj.name == name
        assert np.array_equal(obj.params, [v for _, v in params])
        assert (isinstance(obj, systems.BuiltinSystem)
                == (table.KINDS[name] != "constrained")), name
    assert constrained.BUILTIN_NAMES == table.CONSTRAINED_NAMES
    with pytest.raises(ValueError, match="4 values given for the system 'pendulum_xy', "
                                         "which has 3 \\(m, g, l\\)"):
        constrained.builtin("pendulum_xy", [1.0, 9.81, 1.0, 2.0])
    with pytest.raises(ValueError, match="2 values given for the system 'kepler'"):
        systems.BuiltinSystem("kepler", [1.0, 2.0])
    # the class names say what the objects are: a compiled system is native, not built in
    from conmech.compiled import CompiledSystem, CompiledConstrained
    assert issubclass(CompiledSystem, systems.NativeSystem)
    assert not issubclass(CompiledSystem, systems.BuiltinSystem)
    assert issubclass(CompiledConstrained, constrained.NativeConstrained)
    assert not issubclass(CompiledConstrained, constrained.BuiltinConstrained)


TOY = '''"""A bead of mass m on a frictionless wire bent into the vertical parabola
y = c x^2/2, q = [x]: T = m (1 + c^2 x^2) x'^2/2, U = m g c x^2/2; small oscillations have
omega^2 = g c."""
import sympy as sp

from builtin_models import Lagrangian, Param

m = Param("m", 1.0, "mass", positive=True)
g = Param("g", 9.81, "gravity")
c = Param("c", 2.0, "curvature of the wire", positive=True)
x, xd = sp.symbols("x xd", real=True)
M, G, C = m.symbol, g.symbol, c.symbol

SYSTEM = Lagrangian("bead_parabola", "bead_parabola",
                    "Bead on the wire y = c x^2/2; y = [x, x'].", [m, g, c], q=[x], v=[xd],
                    T=M*(1 + C**2*x**2)*xd**2/2, U=M*G*C*x**2/2, q0=[0.5], v0=[0])
'''

DRIVER = '''program toy
    use conmech
    implicit none
    class(ode_system), allocatable :: sys
    class(generalized_system), allocatable :: mech
    type(ode_options) :: opt
    type(ode_result) :: res
    real(dp), allocatable :: q0(:), v0(:)
    real(dp) :: period, e0, drift
    integer :: info, j
    character(len=:), allocatable :: msg
    call make_system("bead_parabola", [1.0_dp, 9.81_dp, 2.0_dp], sys, info, msg)
    if (info /= CM_SUCCESS) error stop "make_system"
    write (*, '(a, i0)') "dimension ", system_dimension("bead_parabola")
    call make_generalized("bead_parabola", [1.0_dp, 9.81_dp, 2.0_dp], mech, info, msg)
    if (info /= CM_SUCCESS) error stop "make_generalized"
    call mech_initial_state("bead_parabola", [real(dp) ::], q0, v0, info)
    write (*, '(a, 2es24.16)') "state ", q0, v0
    opt%rtol = 1.0e-12_dp
    opt%atol = 1.0e-12_dp
    opt%method = METHOD_DOP853
    ! large amplitude: the energy is conserved
    call generalized_solve(mech, [0.0_dp, 10.0_dp], q0, v0, opt, res)
    if (.not. res%success) error stop "solve"
    e0 = mech%energy(0.0_dp, res%y(1:1, 1), res%y(2:2, 1))
    drift = 0.0_dp
    do j = 1, res%nt
        drift = max(drift, abs(mech%energy(0.0_dp, res%y(1:1, j), res%y(2:2, j)) - e0))
    end do
    write (*, '(a, es24.16)') "drift ", drift/abs(e0)
    ! small amplitude 1e-4: back after one linear period 2 pi/sqrt(g c), up to O(1e-8)
    period = 8.0_dp*atan(1.0_dp)/sqrt(9.81_dp*2.0_dp)
    call ode_solve(sys, [0.0_dp, period], [1.0e-4_dp, 0.0_dp], opt, res)
    if (.not. res%success) error stop "ode_solve"
    write (*, '(a, es24.16)') "return ", abs(res%y(1, res%nt) - 1.0e-4_dp)/1.0e-4_dp
end program toy
'''


def test_a_system_added_through_the_generator_builds_and_runs(tmp_path):
    """The documented way to add a built-in (docs/guide/builtin_systems.rst), followed in
    a copy of the library: a model file, the generator, a build; the new system is in every
    registry and integrates correctly."""
    if shutil.which("fpm") is None:
        pytest.fail("fpm is not on PATH: run the tests through scripts/test.sh")
    model = tmp_path / "bead_parabola.py"
    model.write_text(TOY)
    toy = generator.bm.load_file(model)
    models = generator.bm.load_all()
    models["generalized"].append(toy)
    files = generator.generate(models)
    systems_py = files["python/conmech/mechanics/systems.py"]
    assert "def bead_parabola(m=1.0, g=9.81, c=2.0):" in systems_py
    compile(files["python/conmech/mechanics/systems.py"], "systems.py", "exec")
    table_py = files["python/conmech/_core/builtin_table.py"]
    assert '"bead_parabola": {0: "m", 2: "c"}' in table_py
    proj = tmp_path / "proj"
    shutil.copytree(ROOT / "src", proj / "src")
    for rel, text in files.items():
        if rel.startswith("src/"):
            (proj / rel).write_text(text)
    (proj / "app").mkdir()
    (proj / "app" / "toy.f90").write_text(DRIVER)
    (proj / "fpm.toml").write_text(
        'name = "toy"\n[build]\nauto-executables = true\nauto-tests = false\n'
        'auto-examples = false\nlink = ["lapack", "blas"]\n[fortran]\n'
        'implicit-typing = false\nimplicit-external = false\nsource-form = "free"\n')
    r = subprocess.run(["fpm", "run", "toy", "--flag", "-O1"], cwd=proj, capture_output=True,
                       text=True, timeout=1800)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    out = {ln.split()[0]: ln.split()[1:] for ln in r.stdout.splitlines() if ln.strip()}
    assert out["dimension"] == ["2"]
    assert [float(s) for s in out["state"]] == [0.5, 0.0]
    assert float(out["drift"][0]) < 1e-10
    assert float(out["return"][0]) < 1e-6
