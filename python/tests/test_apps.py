"""The fpm programs: the tour (main job) and the batch sweep (resume, OpenMP, MPI).

These run `fpm` from the repository root (scripts/test.sh puts the venv's fpm on PATH).
"""
import csv
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from scipy.special import ellipk

ROOT = Path(__file__).resolve().parents[2]
SWEEP_ARGS = ["--system", "pendulum", "--params", "9.81,1", "--y0", "0.1,0",
              "--vary", "y0:1", "--from", "0.1", "--to", "2.5", "--count", "12",
              "--t-end", "12", "--section", "2", "--rtol", "1e-11", "--atol", "1e-11"]


def fpm(*args, env=None, check=True):
    if shutil.which("fpm") is None:
        pytest.fail("fpm is not on PATH: run the tests through scripts/test.sh")
    return subprocess.run(["fpm", *args], cwd=ROOT, capture_output=True, text=True,
                          env=env, check=check)


def read_rows(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    return header, {int(r[0]): [float(x) for x in r[1:]] for r in body}


def exe_path(*build_args):
    out = fpm("run", "sweep", *build_args, "--runner", "echo").stdout.strip().splitlines()
    return out[-1].strip()


@pytest.fixture(scope="module")
def serial_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep") / "serial.csv"
    fpm("run", "sweep", "--", *SWEEP_ARGS, "--out", str(out))
    return out


def test_tour_runs_and_shows_the_pendulum_period():
    r = fpm("run", "tour")
    lines = r.stdout.splitlines()
    num = float(next(l for l in lines if "period from events" in l).split()[-1])
    exact = float(next(l for l in lines if "K(sin 1)" in l).split()[-1])
    assert abs(num - exact) < 1e-9
    c = float(next(l for l in lines if "perigee constant c" in l).split()[-1])
    assert abs(c - 1.0715832774160) < 1e-12


def test_sweep_return_times_are_pendulum_periods(serial_sweep):
    header, rows = read_rows(serial_sweep)
    assert header[:2] == ["job", "value"] and len(rows) == 12
    col = header.index("return_time") - 1
    for job, r in rows.items():
        theta0 = r[0]
        exact = 4 * np.sqrt(1 / 9.81) * ellipk(np.sin(theta0 / 2) ** 2)
        assert abs(r[col] - exact) < 1e-8, (job, r[col], exact)
        assert r[-1] == 0  # status


def test_sweep_resumes_without_recomputing(serial_sweep, tmp_path):
    part = tmp_path / "resumed.csv"
    lines = serial_sweep.read_text().splitlines()
    part.write_text("\n".join(lines[:6]) + "\n")  # header + 5 finished jobs
    shutil.copy(str(serial_sweep) + ".args", str(part) + ".args")  # made by the same args
    r = fpm("run", "sweep", "--", *SWEEP_ARGS, "--out", str(part))
    assert "5 already done" in r.stdout
    _, a = read_rows(serial_sweep)
    _, b = read_rows(part)
    assert sorted(a) == sorted(b)
    for job in a:
        assert a[job] == b[job]


def test_sweep_openmp_two_threads_matches_serial(serial_sweep, tmp_path):
    out = tmp_path / "omp.csv"
    env = dict(os.environ, OMP_NUM_THREADS="2")
    r = fpm("run", "sweep", "--flag", "-fopenmp", "--", *SWEEP_ARGS, "--out", str(out),
            env=env)
    assert "2 thread(s)" in r.stdout
    _, a = read_rows(serial_sweep)
    _, b = read_rows(out)
    assert a == b


def test_sweep_mpi_two_ranks_matches_serial(serial_sweep, tmp_path):
    out = tmp_path / "mpi.csv"
    exe = exe_path("--compiler", "mpifort", "--flag", "-DCONMECH_MPI")
    # as root, OpenMPI needs --allow-run-as-root (the README explains why)
    r = subprocess.run(["mpirun", "--allow-run-as-root", "--oversubscribe", "-n", "2", exe,
                        *SWEEP_ARGS,
                        "--out", str(out)], cwd=ROOT, capture_output=True, text=True,
                       check=True)
    assert "2 rank(s)" in r.stdout
    assert not list(tmp_path.glob("mpi.csv.rank*"))  # parts merged and removed
    _, a = read_rows(serial_sweep)
    _, b = read_rows(out)
    assert a == b


def test_sweep_bad_input_is_a_clear_error():
    r = fpm("run", "sweep", "--", "--system", "nosuch", check=False)
    assert r.returncode != 0
    assert "unknown system 'nosuch'; valid: harmonic pendulum" in r.stderr
