"""The `family` program's branch switching (--switch) on a compiled model (--model).

The model (python/tests/data/c_model_nf_cycles.c, the normal-form cycles of
test/test_continuation.f90) has, by construction, on its cycle of period 2 pi a period
doubling at p = 1 (the doubled orbits: period 4 pi, u^2 + w^2 = p - 1) and a pitchfork
branch point at p = 2 (the new orbits: z^2 = p - 2, period 2 pi). The program continues the
cycle, switches at the chosen bifurcation point and continues the new branch; each switched
row is checked against the closed form and by an independent integration (SciPy's DOP853)
over its period (true closure error). Bad switch options exit 2 naming the option, a
missing K-th bifurcation point exits 1.
"""
import math
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[2]
ALPHA = 0.4472135954999579
START = ["--y0", "1,0,0,0,0,0,0", "--period", "6", "--ds", "0.05", "--ds-max", "0.1",
         "--p-max", "2.6", "--max-points", "100"]


def nf_cycles(t, y, p):
    """The model's right-hand side, written again (independent of the C source)."""
    x1, x2, u, w, z, v1, v2 = y
    r2 = x1*x1 + x2*x2
    r = math.sqrt(r2)
    c, s = x1/r, x2/r
    a, b = p - 1.0, -1.0
    q2 = u*u + w*w
    m2 = v1*v1 + v2*v2
    return [x1*(1 - r2) - x2, x2*(1 - r2) + x1,
            -0.5*w + 0.5*(a + b)*u + 0.5*(a - b)*(c*u + s*w) - q2*u,
            0.5*u + 0.5*(a + b)*w + 0.5*(a - b)*(s*u - c*w) - q2*w,
            (p - 2)*z - z**3,
            (p - 3)*v1 - ALPHA*v2 - m2*v1, (p - 3)*v2 + ALPHA*v1 - m2*v2]


def closure(row):
    """max |y(T) - y0| of the row's orbit, integrated independently."""
    p, period, y0 = row[1], row[2], row[7:]
    r = solve_ivp(nf_cycles, (0, period), y0, args=(p,), method="DOP853", rtol=1e-12,
                  atol=1e-12)
    assert r.success
    return float(np.max(np.abs(r.y[:, -1] - y0)))


@pytest.fixture(scope="module")
def family(tmp_path_factory):
    if shutil.which("fpm") is None:
        pytest.fail("fpm is not on PATH: run the tests through scripts/test.sh")
    out = subprocess.run(["fpm", "run", "family", "--runner", "echo"], cwd=ROOT,
                         capture_output=True, text=True, check=True)
    exe = str(ROOT / out.stdout.strip().splitlines()[-1].strip())
    cc = shutil.which("gcc") or shutil.which("cc")
    assert cc, "a C compiler is needed (gfortran brings gcc)"
    lib = tmp_path_factory.mktemp("model") / "nf.so"
    subprocess.run([cc, "-O2", "-shared", "-fPIC", "-o", str(lib),
                    str(ROOT / "python/tests/data/c_model_nf_cycles.c"), "-lm"], check=True)
    return exe, str(lib)


def run(family, args, cwd):
    exe, lib = family
    return subprocess.run([exe, "--model", lib, *args], cwd=cwd, capture_output=True,
                          text=True, timeout=120)


def table(path):
    lines = Path(path).read_text().splitlines()
    return lines[0].split(","), np.array([[float(x) for x in ln.split(",")]
                                          for ln in lines[1:]])


def test_switch_at_the_branch_point(family, tmp_path):
    """--switch 2 (the second bifurcation point, the pitchfork at p = 2): both sides."""
    r = run(family, START + ["--switch", "2", "--switch-points", "6"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert "switching at the branch point" in r.stdout
    head, old = table(tmp_path / "branch.csv")
    sp = (tmp_path / "special.csv").read_text().splitlines()[1:]
    assert [s.split(",")[0] for s in sp] == ["period doubling", "branch point"]
    bp = [float(x) for x in sp[1].split(",")[2:]]
    assert bp[0] == pytest.approx(2.0, abs=1e-8)
    assert np.max(np.abs(old[:, 11])) < 1e-12            # z = 0 on the old branch
    head2, new = table(tmp_path / "switched.csv")
    assert head2 == head and new.shape[0] == 6
    assert np.array_equal(new[:, 0], np.arange(1, 7))
    assert new[0, 1] == bp[0] and np.array_equal(new[0, 7:], bp[3:])  # row 1 = the point
    p, z = new[1:, 1], new[1:, 11]
    assert np.all(p > 2) and np.all(z > 0)               # the new branch, not the old one
    assert np.allclose(z**2, p - 2, atol=1e-9)           # closed form
    assert np.allclose(new[:, 2], 2*np.pi, atol=1e-9)
    assert max(closure(row) for row in new[1:]) < 1e-8
    # the switched branch's special points go to a file only when asked
    assert not (tmp_path / "switched_special.csv").exists()
    assert sorted(f.name for f in tmp_path.iterdir()) == ["branch.csv", "special.csv",
                                                          "switched.csv"]
    r = run(family, START + ["--switch", "2", "--switch-direction", "-1",
                             "--switch-points", "4", "--force",
                             "--switch-out", "mirror.csv", "--switch-special", "ms.csv"],
            tmp_path)
    assert r.returncode == 0, r.stderr
    _, mirror = table(tmp_path / "mirror.csv")
    assert mirror.shape[0] == 4 and np.all(mirror[1:, 11] < 0)     # z < 0
    assert (tmp_path / "ms.csv").read_text().startswith("kind,index,p,")
    assert np.allclose(mirror[1:, 11]**2, mirror[1:, 1] - 2, atol=1e-9)
    assert closure(mirror[-1]) < 1e-8


def test_switch_at_the_period_doubling(family, tmp_path):
    """--switch 1: the period-doubled orbits (period 4 pi, u^2 + w^2 = p - 1, p > 1)."""
    r = run(family, START + ["--switch", "1", "--switch-points", "6"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert "switching at the period doubling" in r.stdout
    _, new = table(tmp_path / "switched.csv")
    assert new.shape[0] == 6
    p, u, w = new[1:, 1], new[1:, 9], new[1:, 10]
    assert np.all(p > 1)
    assert np.allclose(new[:, 2], 4*np.pi, atol=1e-9)
    assert np.allclose(u**2 + w**2, p - 1, atol=1e-9)
    assert max(closure(row) for row in new[1:]) < 1e-8
    # not closed after one old period: a genuinely doubled orbit
    half = new[-1].copy()
    half[2] /= 2
    assert closure(half) > 1e-2


def test_no_such_bifurcation_exits_1(family, tmp_path):
    r = run(family, START + ["--switch", "3"], tmp_path)
    assert r.returncode == 1
    assert "--switch 3: the branch has 2 bifurcation point(s)" in r.stderr
    assert (tmp_path / "branch.csv").exists() and not (tmp_path / "switched.csv").exists()


@pytest.mark.parametrize("extra, text", [
    (["--switch", "0"], "--switch must be >= 1"),
    (["--switch", "abc"], "bad value for --switch"),
    (["--switch", "1", "--switch-direction", "2"], "--switch-direction must be 1 or -1"),
    (["--switch", "1", "--switch-points", "1"], "--switch-points must be >= 2"),
    (["--switch-direction", "-1"], "--switch-direction needs --switch K"),
    (["--switch-out", "x.csv"], "--switch-out needs --switch K"),
    (["--switch", "1", "--free", "1", "--targets", "2"], "--switch needs general shooting"),
    (["--switch", "1", "--conservative"], "--switch is not available for a conservative"),
    (["--switch", "1", "--fixed-period"], "--switch is not available with --fixed-period"),
    (["--switch", "1", "--switch-out", "branch.csv"], "--switch-out and --switch-special"),
    (["--params", "1,2"], "--params: the model has 1 parameter(s) (p), got 2"),
    (["--param", "2"], "--param must be in 1..1"),
    (["--system", "vanderpol"], "give --system or --model, not both"),
])
def test_bad_switch_options_exit_2(family, tmp_path, extra, text):
    r = run(family, START + extra, tmp_path)
    assert r.returncode == 2 and text in r.stderr, (extra, r.stderr)
    assert "family: error:" in r.stderr and not list(tmp_path.iterdir())  # nothing computed


def test_existing_output_needs_force(family, tmp_path):
    (tmp_path / "branch.csv").write_text("i,p\n")
    r = run(family, START + ["--switch", "1"], tmp_path)
    assert r.returncode == 2 and "branch.csv exists (--force replaces it)" in r.stderr
    (tmp_path / "switched.csv").write_text("i,p\n")
    r = run(family, START + ["--switch", "1", "--out", "b2.csv"], tmp_path)
    assert r.returncode == 2 and "--switch-out switched.csv exists" in r.stderr
    exe, _ = family
    r = subprocess.run([exe, "--model", "nope.so", *START], cwd=tmp_path,
                       capture_output=True, text=True)
    assert r.returncode == 2 and "--model:" in r.stderr


def test_namelist_switching_and_its_errors(family, tmp_path):
    """--input FILE.nml: the same switching from a namelist &family (the pitchfork's
    z < 0 side); a switch option without switch, and a negative switch, exit 2."""
    _, lib = family
    (tmp_path / "s.nml").write_text(
        f"&family model = '{lib}', y0 = 1,0,0,0,0,0,0, period = 6, ds = 0.05,\n"
        "  ds_max = 0.1, p_max = 2.6, max_points = 100, switch = 2,\n"
        "  switch_direction = -1, switch_points = 4, switch_out = 'z.csv' /\n")
    exe, _ = family
    r = subprocess.run([exe, "--input", "s.nml"], cwd=tmp_path, capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    _, new = table(tmp_path / "z.csv")
    assert new.shape[0] == 4 and np.all(new[1:, 11] < 0)
    assert np.allclose(new[1:, 11]**2, new[1:, 1] - 2, atol=1e-9)
    assert closure(new[-1]) < 1e-8
    (tmp_path / "bad.nml").write_text(f"&family model = '{lib}', switch_points = 4 /\n")
    r = subprocess.run([exe, "--input", "bad.nml", *START], cwd=tmp_path,
                       capture_output=True, text=True)
    assert r.returncode == 2 and "switch_* of --input bad.nml needs --switch K" in r.stderr
    (tmp_path / "neg.nml").write_text(f"&family model = '{lib}', switch = -1 /\n")
    r = subprocess.run([exe, "--input", "neg.nml", *START], cwd=tmp_path,
                       capture_output=True, text=True)
    assert r.returncode == 2 and "switch must be >= 1" in r.stderr
