"""The seed app (`fpm run seed`): a named seed system to CSV, summary, exit codes.

Runs `fpm` from the repository root (scripts/test.sh puts the venv's fpm on PATH)."""
import csv
import math
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def fpm(*args, check=True):
    if shutil.which("fpm") is None:
        pytest.fail("fpm is not on PATH: run the tests through scripts/test.sh")
    return subprocess.run(["fpm", *args], cwd=ROOT, capture_output=True, text=True,
                          check=check)


def rows(path):
    with open(path, newline="") as f:
        r = list(csv.reader(f))
    return r[0], [[float(x) for x in row] for row in r[1:]]


def test_seed_pendulum_xy_csv_and_multiplier(tmp_path):
    out = tmp_path / "p.csv"
    r = fpm("run", "seed", "--", "--system", "pendulum_xy", "--t-end", "5", "--n-out", "51",
            "--out", str(out))
    assert "status      : success" in r.stdout
    head, data = rows(out)
    assert head == ["t", "q1", "q2", "v1", "v2", "lambda1", "reaction1", "reaction2",
                    "res_pos", "res_vel", "energy", "power"]
    assert len(data) == 51 and data[-1][0] == pytest.approx(5.0)
    for t, x, y, vx, vy, lam, *_ in data:
        assert abs(x * x + y * y - 1.0) < 1e-12
        assert lam == pytest.approx(y * 9.81 - vx * vx - vy * vy, abs=1e-9)


def test_seed_generalized_and_projection_choice(tmp_path):
    out = tmp_path / "c.csv"
    r = fpm("run", "seed", "--", "--system", "cart_pendulum", "--t-end", "2", "--out", str(out))
    assert "generalized coordinates" in r.stdout
    head, data = rows(out)
    assert head == ["t", "q1", "q2", "v1", "v2", "energy"]
    assert max(abs(row[-1] - data[0][-1]) for row in data) < 1e-8
    r = fpm("run", "seed", "--", "--system", "double_pendulum_xy", "--projection", "none",
            "--t-end", "50", "--rtol", "1e-6", "--atol", "1e-6")
    drift = float(r.stdout.split("|phi|")[1].split(",")[0])
    assert drift > 1e-8


def test_seed_bad_input_exit_codes():
    r = fpm("run", "seed", "--", "--system", "nosuch", check=False)
    assert r.returncode == 2 and "unknown system 'nosuch'; valid: pendulum_xy" in r.stderr
    r = fpm("run", "seed", "--", "--system", "pendulum_xy", "--projection", "sideways",
            check=False)
    assert r.returncode == 2 and "unknown projection" in r.stderr
    r = fpm("run", "seed", "--", "--system", "pendulum_xy", "--params", "0,9.81,1",
            check=False)
    assert r.returncode == 1 and "singular mass matrix" in r.stdout
