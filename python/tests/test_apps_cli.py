"""The programs' command lines and their batch files (issues 12 and 13).

Every program answers --help (0), a bad option (2), a bad value (2) and its namelist file
in jobs/ (0) without ERROR STOP or a backtrace; sweep and hill_family resume after kill -9
(serial, OpenMP, MPI), drop a torn last row, refuse junk and other arguments, and end
bit-identical to an uninterrupted serial run. Runs `fpm` from the repository root
(scripts/test.sh puts the venv's fpm on PATH); counts are small to keep CI fast.
"""
import math
import os
import re
import shutil
import signal
import subprocess
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PROGRAMS = ["family", "hill", "hill_family", "seed", "sweep", "tour"]
MPI_ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
# one job = a long integration of the harmonic oscillator at tight tolerances (tens of ms)
SWEEP = ["--system", "harmonic", "--params", "1", "--y0", "1,0", "--vary", "param:1",
         "--from", "0.5", "--to", "2", "--count", "40", "--t-end", "400",
         "--rtol", "1e-12", "--atol", "1e-12", "--section", "2", "--quiet"]
FAMILY = ["--m0", "0.01", "--m1", "0.15", "--n", "1500", "--batch", "32", "--quiet"]
BAD = re.compile(r"error stop|backtrace|error termination", re.I)


def fpm(*args, env=None):
    if shutil.which("fpm") is None:
        pytest.fail("fpm is not on PATH: run the tests through scripts/test.sh")
    return subprocess.run(["fpm", *args], cwd=ROOT, capture_output=True, text=True,
                          env=env, check=True)


def exe(name, *build):
    out = fpm("run", name, *build, "--runner", "echo").stdout.strip().splitlines()
    return str(ROOT / out[-1].strip())


def run(cmd, cwd, env=None):
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, env=env,
                          timeout=300)


def rows(path):
    """{key: row text} of a results CSV (header checked to be one line of names)."""
    lines = Path(path).read_text().splitlines()
    assert lines and not lines[0][0].isdigit()
    out = {}
    for line in lines[1:]:
        key = int(line.split(",")[0])
        assert key not in out, f"duplicate row {key}"
        out[key] = line
    return out


def nrows(path):
    try:
        return max(0, len(Path(path).read_text().splitlines()) - 1)
    except FileNotFoundError:
        return 0


def descendants(pid):
    """Process ids below pid (from /proc), deepest last."""
    kids = {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                ppid = int((d / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            kids.setdefault(ppid, []).append(int(d.name))
    out, todo = [], [pid]
    while todo:
        for c in kids.get(todo.pop(), []):
            out.append(c)
            todo.append(c)
    return out


def kill_part_way(cmd, cwd, watch, at_least, env=None):
    """Start cmd, SIGKILL its whole process group once `watch` files hold >= at_least rows
    in total; return how many rows there were (the run must not have finished)."""
    p = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL, start_new_session=True)
    t0 = time.time()
    while time.time() - t0 < 120:
        n = sum(nrows(Path(cwd) / w) for w in watch)
        if n >= at_least or p.poll() is not None:
            break
        time.sleep(0.005)
    for pid in [*descendants(p.pid), p.pid]:  # MPI ranks live in their own groups
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    p.wait()
    assert p.returncode == -signal.SIGKILL, "the run ended before the kill: make it longer"
    return n


@pytest.fixture(scope="module")
def exes():
    fpm("build")
    return {name: exe(name) for name in PROGRAMS}


@pytest.fixture(scope="module")
def serial(exes, tmp_path_factory):
    """Uninterrupted serial runs of sweep and hill_family: the reference rows."""
    d = tmp_path_factory.mktemp("serial")
    r = run([exes["sweep"], *SWEEP, "--out", "s.csv"], d)
    assert r.returncode == 0, r.stderr
    r = run([exes["hill_family"], *FAMILY, "--out", "f.csv"], d)
    assert r.returncode == 0, r.stderr
    return rows(d / "s.csv"), rows(d / "f.csv"), d


# ------------------------------------------------------------------ the command lines

BAD_VALUES = {"family": ["--switch", "1,2"], "hill": ["--m", "abc"], "hill_family": ["--n", "1,2"],
              "seed": ["--system", "pendulum_xy", "--params", "1,,1"],
              "sweep": ["--t-end", "/"], "tour": ["--m", "abc"]}


@pytest.mark.parametrize("name", PROGRAMS)
def test_help_bad_option_bad_value_namelist(exes, name, tmp_path):
    cases = [(["--help"], 0), (["--bogus", "1"], 2), (BAD_VALUES[name], 2), (["--version"], 0)]
    nml = ROOT / "jobs" / f"{name}.nml"
    if name != "tour":  # the tour takes no options (and says so to --input)
        cases.append((["--input", str(nml)], 0))
    else:
        cases.append((["--input", "x.nml"], 2))
    for args, want in cases:
        r = run([exes[name], *args], tmp_path)
        text = r.stdout + r.stderr
        assert r.returncode == want, (name, args, text)
        assert not BAD.search(text), (name, args, text)
        if want == 2:
            assert f"{name}: error:" in r.stderr, (name, args, r.stderr)
    assert "Example:" in run([exes[name], "--help"], tmp_path).stdout


def test_errors_name_the_problem(exes, tmp_path):
    cases = [
        ("sweep", ["--bogus", "1"], "unknown option --bogus"),
        ("sweep", ["--system", "nosuch"], "valid: harmonic pendulum"),
        ("sweep", ["--system", "pendulum", "--params", "9.81,1,3", "--y0", "1,0",
                   "--vary", "y0:1"], "pendulum has 2 parameter(s) (g, l), got 3"),
        ("sweep", ["--system", "pendulum", "--y0", "1,0,0", "--vary", "y0:1"],
         "has dimension 2, got 3"),
        ("sweep", ["--system", "pendulum", "--y0", "1,0", "--vary", "y0:1",
                   "--count", "100000000"], "--count must be in 1..10000000"),
        ("sweep", ["--system", "pendulum", "--y0", "1,0", "--vary", "y0:1",
                   "--method", "RK5"], "valid: DOP853"),
        ("sweep", ["--count", "1.5"], "'1.5' is not an integer"),
        ("sweep", ["--from", "1e400"], "not a finite number"),
        ("sweep", ["--system", "pendulum", "--y0", "1,0", "--vary", "y0:1",
                   "--out", "/nonexistent/dir/s.csv"], "cannot write"),
        ("hill", ["--m", "-1"], "--m must be positive"),
        ("hill", ["--npoints", "1e12"], "not an integer"),
        ("hill", ["--npoints", "100000000"], "--npoints must be in 2..10000000"),
        ("hill_family", ["--n", "100000000"], "--n must be in 1..10000000"),
        ("seed", ["--system", "pendulum_xy", "--q0", "1"], "has 2 coordinates, got 1"),
        ("seed", ["--system", "nosuch"], "valid: pendulum_xy"),
        ("seed", ["--system", "pendulum_xy", "--projection", "sideways"],
         "unknown projection 'sideways'"),
        ("seed", ["--system"], "missing value after --system"),
        ("tour", ["extra"], "unexpected argument 'extra'"),
    ]
    for name, args, text in cases:
        r = run([exes[name], *args], tmp_path)
        assert r.returncode == 2 and text in r.stderr, (name, args, r.stderr)
    assert not list(tmp_path.iterdir())  # nothing written by a refused command


def test_sweep_list(exes, tmp_path):
    r = run([exes["sweep"], "--list"], tmp_path)
    assert r.returncode == 0 and "harmonic pendulum" in r.stdout and "cart_pendulum" in r.stdout


def test_namelist_errors_and_command_line_override(exes, tmp_path):
    (tmp_path / "gap.nml").write_text("&sweep system='pendulum', params=9.81,,1 /\n")
    r = run([exes["sweep"], "--input", "gap.nml"], tmp_path)
    assert r.returncode == 2 and "'params' has an empty entry" in r.stderr
    (tmp_path / "typo.nml").write_text("&hill mm = 0.1 /\n")
    r = run([exes["hill"], "--input", "typo.nml"], tmp_path)
    assert r.returncode == 2 and "line 1: unknown key 'mm' in &hill" in r.stderr
    r = run([exes["hill"], "--input", "missing.nml"], tmp_path)
    assert r.returncode == 2 and "cannot open --input missing.nml" in r.stderr
    # the command line overrides the file: n from the file, m range from the file
    (tmp_path / "f.nml").write_text("&hill_family m0=0.02, m1=0.03, n=50, out='a.csv' /\n")
    r = run([exes["hill_family"], "--input", "f.nml", "--n", "5", "--out", "b.csv"],
            tmp_path)
    assert r.returncode == 0, r.stderr
    assert len(rows(tmp_path / "b.csv")) == 5 and not (tmp_path / "a.csv").exists()


def test_outputs_never_silently_overwritten(exes, tmp_path):
    (tmp_path / "orbit.csv").write_text("precious\n")
    r = run([exes["hill"], "--csv", "orbit.csv"], tmp_path)
    assert r.returncode == 2 and "--force" in r.stderr
    assert (tmp_path / "orbit.csv").read_text() == "precious\n"
    r = run([exes["hill"], "--csv", "orbit.csv", "--force", "--npoints", "5"], tmp_path)
    assert r.returncode == 0 and len((tmp_path / "orbit.csv").read_text().splitlines()) == 6
    (tmp_path / "family.csv").write_text("i,m\n1,2\n")  # not made by hill_family
    r = run([exes["hill_family"], "--n", "3"], tmp_path)
    assert r.returncode == 2 and "exists without family.csv.args" in r.stderr


def test_progress_line_on_stderr_and_quiet(exes, tmp_path):
    env = dict(os.environ, CONMECH_PROGRESS_SECONDS="0")  # a line at every step
    args = ["--m0", "0.02", "--m1", "0.03", "--n", "64", "--batch", "32"]
    r = run([exes["hill_family"], *args, "--out", "a.csv"], tmp_path, env=env)
    assert r.returncode == 0
    assert re.search(r"hill_family: 64/64 \(100\.0%\), [0-9.]+ per s, ETA 0 s", r.stderr)
    r = run([exes["hill_family"], *args, "--out", "b.csv", "--quiet"], tmp_path, env=env)
    assert r.returncode == 0 and r.stderr == ""
    r = run([exes["sweep"], *SWEEP[:-1], "--count", "3", "--t-end", "1"], tmp_path, env=env)
    assert r.returncode == 0 and "sweep: 3/3 (100.0%)" in r.stderr, r.stderr


def test_programs_valgrind_clean(exes, tmp_path):
    """No invalid access, no uninitialised value, no leak (a list with an empty field used
    to read an uninitialised value; a failed job used to read res%y(:, 0))."""
    if shutil.which("valgrind") is None:
        pytest.fail("valgrind is not installed (apt-get install valgrind)")
    vg = ["valgrind", "-q", "--error-exitcode=9", "--leak-check=full"]
    for args, want in [
            (["sweep", "--system", "harmonic", "--params", "1", "--y0", "1e-150,0", "--vary",
              "y0:1", "--from", "1e-150", "--to", "1e150", "--count", "2", "--t-end", "1"],
             (0, 1)),
            (["seed", "--system", "pendulum_xy", "--params", "1,,1"], (2,)),
            (["family", "--system", "vanderpol", "--params", "1", "--y0", "2,0", "--period",
              "6.6", "--p-max", "1.2"], (0,))]:
        r = run([*vg, exes[args[0]], *args[1:]], tmp_path)
        assert r.returncode in want and "==" not in r.stderr, (args, r.stderr)


def test_sweep_model_library_matches_builtin_and_kepler(exes, tmp_path):
    """--model LIB.so: a compiled user model (conmech_model_library's C convention) sweeps
    like the built-in system: the same rows as --system kepler, periods by Kepler's law."""
    cc = shutil.which("gcc") or shutil.which("cc")
    assert cc, "a C compiler is needed (gfortran brings gcc)"
    lib = tmp_path / "kepler.so"
    subprocess.run([cc, "-O2", "-shared", "-fPIC", "-o", str(lib),
                    str(ROOT / "python/tests/data/c_model_kepler.c"), "-lm"], check=True)
    grid = ["--y0", "1,0,0,1", "--vary", "y0:4", "--from", "0.9", "--to", "1.1", "--count",
            "5", "--t-end", "10", "--section", "2", "--rtol", "1e-12", "--atol", "1e-12"]
    r = run([exes["sweep"], "--model", str(lib), *grid, "--out", "m.csv"], tmp_path)
    assert r.returncode == 0, r.stderr
    r = run([exes["sweep"], "--system", "kepler", *grid, "--out", "b.csv"], tmp_path)
    assert r.returncode == 0, r.stderr
    m, b = rows(tmp_path / "m.csv"), rows(tmp_path / "b.csv")
    assert m.keys() == b.keys() == set(range(5))
    for k in m:
        xm = [float(x) for x in m[k].split(",")]
        xb = [float(x) for x in b[k].split(",")]
        assert all(abs(p - q) <= 1e-12 * max(1, abs(q)) for p, q in zip(xm, xb))
        v = xm[1]
        a = 1 / (2 - v * v)  # vis-viva at r = 1, mu = 1
        assert abs(xm[6] - 2 * math.pi * a ** 1.5) < 1e-9, (v, xm[6])
    r = run([exes["sweep"], "--model", str(lib), "--params", "1,2", *grid], tmp_path)
    assert r.returncode == 2 and "the model has 1 parameter(s) (mu), got 2" in r.stderr
    r = run([exes["sweep"], "--model", "nope.so", *grid], tmp_path)
    assert r.returncode == 2 and "cannot load the model library" in r.stderr


# ------------------------------------------------------------------ sweep resume

def test_sweep_failed_jobs_exit_1_with_a_count(exes, tmp_path):
    # a huge step count limit is not needed: 1e150 overflows at once, so every job fails
    r = run([exes["sweep"], "--system", "harmonic", "--params", "1", "--y0", "1e-150,0",
             "--vary", "y0:1", "--from", "1e-150", "--to", "1e150", "--count", "3",
             "--t-end", "1"], tmp_path)
    data = rows(tmp_path / "sweep.csv")
    nfail = sum(1 for line in data.values() if line.split(",")[-1] != "0")
    assert len(data) == 3
    for line in data.values():
        [float(x) for x in line.split(",")]  # every field parses (3-digit exponents)
    if nfail:
        assert r.returncode == 1 and f"{nfail} of 3 jobs failed" in r.stderr
    else:
        assert r.returncode == 0


def test_sweep_serial_kill_torn_junk_resume(exes, serial, tmp_path):
    ref = serial[0]
    cmd = [exes["sweep"], *SWEEP, "--out", "k.csv"]
    kill_part_way(cmd, tmp_path, ["k.csv"], 5)
    out = tmp_path / "k.csv"
    have = rows(out)
    assert 0 < len(have) < len(ref)
    assert all(ref[k] == v for k, v in have.items())
    # a junk line in the middle: refused, naming the line, file untouched
    text = out.read_text()
    lines = text.splitlines(keepends=True)
    out.write_text("".join(lines[:2] + ["3,oops\n"] + lines[2:]))
    r = run(cmd, tmp_path)
    assert r.returncode == 2 and "k.csv line 3: not a valid row" in r.stderr
    # a torn last row (a kill mid-write): dropped and recomputed
    missing = min(set(ref) - set(have))
    out.write_text(text + ref[missing][:17])
    r = run(cmd, tmp_path)
    assert r.returncode == 0, r.stderr
    assert "incomplete last row dropped" in r.stderr
    assert rows(out) == ref
    # resumed with other arguments: refused
    r = run([*cmd[:-2], "--t-end", "399", "--out", "k.csv"], tmp_path)
    assert r.returncode == 2 and "made by different arguments" in r.stderr
    assert rows(out) == ref


def test_sweep_openmp_kill_resume(serial, tmp_path):
    ref = serial[0]
    env = dict(os.environ, OMP_NUM_THREADS="2")
    cmd = [exe("sweep", "--flag", "-fopenmp"), *SWEEP, "--out", "o.csv"]
    kill_part_way(cmd, tmp_path, ["o.csv"], 5, env=env)
    assert 0 < len(rows(tmp_path / "o.csv")) < len(ref)
    r = run(cmd, tmp_path, env=env)
    assert r.returncode == 0 and "2 thread(s)" in r.stdout, r.stderr
    assert rows(tmp_path / "o.csv") == ref


@pytest.fixture(scope="module")
def mpi_sweep():
    if shutil.which("mpirun") is None:
        pytest.fail("mpirun not found: scripts/setup.sh installs OpenMPI")
    return exe("sweep", "--compiler", "mpifort", "--flag", "-DCONMECH_MPI")


def mpirun(n, *args):
    return ["mpirun", "--allow-run-as-root", "--oversubscribe", "-n", str(n), *args]


def test_sweep_mpi_kill_resume(mpi_sweep, serial, tmp_path):
    ref = serial[0]
    cmd = mpirun(2, mpi_sweep, *SWEEP, "--out", "m.csv")
    kill_part_way(cmd, tmp_path, ["m.csv.rank0", "m.csv.rank1"], 6, env=MPI_ENV)
    parts = sorted(p.name for p in tmp_path.glob("m.csv.rank*"))
    assert parts == ["m.csv.rank0", "m.csv.rank1"]
    done = {**rows(tmp_path / "m.csv.rank0"), **rows(tmp_path / "m.csv.rank1")}
    assert 0 < len(done) < len(ref) and all(ref[k] == v for k, v in done.items())
    # both ranks took jobs (a finished rank takes the next one)
    assert rows(tmp_path / "m.csv.rank0") and rows(tmp_path / "m.csv.rank1")
    with open(tmp_path / "m.csv.rank1", "a") as f:  # and a torn row in a part
        f.write(ref[max(ref)][:20])
    r = run(cmd, tmp_path, env=MPI_ENV)
    assert r.returncode == 0, r.stdout + r.stderr
    assert f"{len(done)} already done" in r.stdout
    assert rows(tmp_path / "m.csv") == ref
    assert not list(tmp_path.glob("m.csv.rank*")) and not (tmp_path / "m.csv.tmp").exists()


def rank_pids(pid):
    """{MPI rank: process id} of the ranks below pid."""
    out = {}
    for c in descendants(pid):
        try:
            env = Path(f"/proc/{c}/environ").read_bytes().split(b"\0")
        except OSError:
            continue
        for e in env:
            if e.startswith(b"OMPI_COMM_WORLD_RANK="):
                out[int(e.split(b"=")[1])] = c
    return out


def wait_for(cond, what, timeout=120):
    t0 = time.time()
    while not cond():
        assert time.time() - t0 < timeout, f"timed out waiting for {what}"
        time.sleep(0.005)


def test_sweep_mpi_a_free_rank_takes_the_next_job(mpi_sweep, tmp_path):
    """Rank 1 runs under valgrind's no-op tool (several times slower, still computing):
    rank 0 takes most jobs (the static split it replaced gave each rank half), and the
    merge is complete."""
    if shutil.which("valgrind") is None:
        pytest.fail("valgrind is not installed (apt-get install valgrind)")
    args = [*SWEEP, "--t-end", "100", "--out", "d.csv"]  # (the last --t-end wins)
    cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-n", "1", mpi_sweep, *args,
           ":", "-n", "1", "valgrind", "-q", "--tool=none", mpi_sweep, *args]
    r = run(cmd, tmp_path, env=MPI_ENV)
    assert r.returncode == 0, r.stdout + r.stderr
    ran = {int(a): int(b) for a, b in re.findall(r"rank (\d) ran (\d+) job", r.stdout)}
    assert ran.keys() == {0, 1} and sum(ran.values()) == 40, r.stdout
    assert ran[0] >= 28, ran
    done = rows(tmp_path / "d.csv")
    assert sorted(done) == list(range(40))
    assert all(line.endswith(",0") for line in done.values())


@pytest.mark.parametrize("stage", ["before_rename", "after_rename", "serial_resume"])
def test_sweep_mpi_kill_during_merge(exes, mpi_sweep, serial, tmp_path, stage):
    """The states a kill during the final merge leaves, resumed with 2 ranks (or by the
    serial build, which merges the parts first)."""
    ref = serial[0]
    keys = sorted(ref)
    header = "job,value,y1,y2,return_time,nfev,status\n"
    shutil.copy(serial[2] / "s.csv.args", tmp_path / "m.csv.args")  # same arguments
    # rebuild the interrupted state from the reference rows
    rank0 = [ref[k] for k in keys if k % 2 == 0]
    rank1 = [ref[k] for k in keys if k % 2 == 1]
    if stage in ("before_rename", "serial_resume"):
        (tmp_path / "m.csv").write_text(header + "".join(ref[k] + "\n" for k in keys[:4]))
        (tmp_path / "m.csv.tmp").write_text(header + ref[keys[0]] + "\n" + ref[keys[1]][:9])
    else:  # merged file in place, the parts not yet deleted
        (tmp_path / "m.csv").write_text(header + "".join(ref[k] + "\n" for k in keys))
    (tmp_path / "m.csv.rank0").write_text(header + "".join(x + "\n" for x in rank0[:-2]))
    (tmp_path / "m.csv.rank1").write_text(header + "".join(x + "\n" for x in rank1))
    if stage == "serial_resume":
        r = run([exes["sweep"], *SWEEP, "--out", "m.csv"], tmp_path)
    else:
        r = run(mpirun(2, mpi_sweep, *SWEEP, "--out", "m.csv"), tmp_path, env=MPI_ENV)
    assert r.returncode == 0, r.stdout + r.stderr
    assert rows(tmp_path / "m.csv") == ref
    assert not list(tmp_path.glob("m.csv.rank*"))


# ------------------------------------------------------------------ hill_family resume

def test_hill_family_kill_torn_junk_resume(exes, serial, tmp_path):
    ref = serial[1]
    cmd = [exes["hill_family"], *FAMILY, "--out", "f.csv"]
    kill_part_way(cmd, tmp_path, ["f.csv"], 100)
    out = tmp_path / "f.csv"
    have = rows(out)
    assert 0 < len(have) < len(ref) and all(ref[k] == v for k, v in have.items())
    text = out.read_text()
    out.write_text(text + ref[len(have) + 1][:30])  # torn row
    lines = (text + "junk\n").splitlines(keepends=True)
    (tmp_path / "j.csv").write_text("".join(lines))
    shutil.copy(tmp_path / "f.csv.args", tmp_path / "j.csv.args")
    r = run([*cmd[:-1], "j.csv"], tmp_path)
    assert r.returncode == 2 and f"j.csv line {len(lines)}: not a valid row" in r.stderr
    # a smaller --n must not shrink the file
    r = run([*cmd, "--n", "100"], tmp_path)
    assert r.returncode == 2 and "made by different arguments" in r.stderr
    r = run(cmd, tmp_path)
    assert r.returncode == 0, r.stderr
    assert rows(out) == ref  # bit-identical to the uninterrupted run
    # empty file (a kill before the header): starts over
    out.write_text("")
    r = run(cmd, tmp_path)
    assert r.returncode == 0 and rows(out) == ref


def test_hill_family_openmp_kill_resume_bit_identical(serial, tmp_path):
    ref = serial[1]
    env = dict(os.environ, OMP_NUM_THREADS="2")
    cmd = [exe("hill_family", "--flag", "-fopenmp"), *FAMILY, "--out", "o.csv"]
    kill_part_way(cmd, tmp_path, ["o.csv"], 200, env=env)
    r = run([*cmd, "--batch", "200"], tmp_path, env=env)  # a different batch: same rows
    assert r.returncode == 0, r.stderr
    assert rows(tmp_path / "o.csv") == ref
