"""The batch programs under hostile input and failing file systems (named regressions).

- A resume over a results file with duplicated rows ends with exactly one row per job
  (identical copies are dropped, a conflicting copy is refused naming both lines); keys out
  of range, and for hill_family out of order, are refused naming the line.
- With OpenMP threads sweep writes its rows in job order by default (the file is byte for
  byte the serial one); `--order completion` writes them as they finish, and a later job-
  order run sorts the file.
- A full disk is reported as "No space left on device" with exit status 3, never as failed
  jobs: on a real small tmpfs in a private mount namespace where the machine allows it, and
  always by a library shim (LD_PRELOAD) that makes the C library's fwrite fail with ENOSPC.
- Every namelist mistake names the key, the value and the line (exit 2).
"""
import errno
import os
import shutil
import subprocess
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PEND = ["--system", "pendulum", "--params", "9.81,1", "--y0", "0.1,0", "--vary", "y0:1",
        "--from", "0.1", "--to", "3", "--count", "120", "--t-end", "5", "--section", "2",
        "--quiet"]


def fpm(*args):
    if shutil.which("fpm") is None:
        pytest.fail("fpm is not on PATH: run the tests through scripts/test.sh")
    return subprocess.run(["fpm", *args], cwd=ROOT, capture_output=True, text=True,
                          check=True)


def exe(name, *build):
    out = fpm("run", name, *build, "--runner", "echo").stdout.strip().splitlines()
    return str(ROOT / out[-1].strip())


def run(cmd, cwd, env=None):
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, env=env,
                          timeout=600)


@pytest.fixture(scope="module")
def exes():
    fpm("build")
    return {n: exe(n) for n in ("sweep", "hill_family", "hill", "seed", "family")}


@pytest.fixture(scope="module")
def clean(exes, tmp_path_factory):
    """Uninterrupted serial runs: sweep (s.csv) and hill_family (h.csv)."""
    d = tmp_path_factory.mktemp("clean")
    r = run([exes["sweep"], *PEND, "--out", "s.csv"], d)
    assert r.returncode == 0, r.stderr
    r = run([exes["hill_family"], "--n", "150", "--quiet", "--out", "h.csv"], d)
    assert r.returncode == 0, r.stderr
    return d


def lines(path):
    return Path(path).read_text().splitlines(keepends=True)


def resume_file(clean, tmp_path, name, body):
    (tmp_path / name).write_text("".join(body))
    shutil.copy(clean / (("s" if name.startswith("s") else "h") + ".csv.args"),
                tmp_path / f"{name}.args")


# ------------------------------------------------------------------ duplicated rows

def test_sweep_resume_with_rows_50_to_60_duplicated_is_repaired(exes, clean, tmp_path):
    full = lines(clean / "s.csv")
    body = full[:101] + full[51:62] + full[101:110]      # rows of jobs 50..60 twice
    resume_file(clean, tmp_path, "s.csv", body)
    r = run([exes["sweep"], *PEND, "--out", "s.csv"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert "11 duplicated row(s) removed" in r.stderr
    assert (tmp_path / "s.csv").read_text() == (clean / "s.csv").read_text()


def test_sweep_resume_with_a_conflicting_duplicate_is_refused(exes, clean, tmp_path):
    full = lines(clean / "s.csv")
    other = full[51].rsplit(",", 1)[0] + ",7\n"           # job 50 again, another status
    resume_file(clean, tmp_path, "s.csv", full[:80] + [other])
    r = run([exes["sweep"], *PEND, "--out", "s.csv"], tmp_path)
    assert r.returncode == 2
    assert "line 81: job = 50 appears again (first at line 52) with different values" in \
        r.stderr
    assert len(lines(tmp_path / "s.csv")) == 81            # left as it was


def test_sweep_resume_with_a_job_out_of_range_is_refused(exes, clean, tmp_path):
    full = lines(clean / "s.csv")
    resume_file(clean, tmp_path, "s.csv", full[:30] + ["120" + full[29][full[29].index(","):]])
    r = run([exes["sweep"], *PEND, "--out", "s.csv"], tmp_path)
    assert r.returncode == 2 and "line 31: job = 120 is out of range 0..119" in r.stderr


def test_hill_family_resume_duplicates_repaired_out_of_order_refused(exes, clean, tmp_path):
    full = lines(clean / "h.csv")
    resume_file(clean, tmp_path, "h.csv", full[:61] + full[21:31] + full[61:90])
    r = run([exes["hill_family"], "--n", "150", "--quiet", "--out", "h.csv"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert "10 duplicated row(s) removed" in r.stderr
    assert (tmp_path / "h.csv").read_text() == (clean / "h.csv").read_text()
    resume_file(clean, tmp_path, "h2.csv", full[:40] + full[41:60])
    r = run([exes["hill_family"], "--n", "150", "--quiet", "--out", "h2.csv"], tmp_path)
    assert r.returncode == 2
    assert "line 41: i = 41 out of order (expected 40" in r.stderr


# ------------------------------------------------------------------ row order

@pytest.fixture(scope="module")
def sweep_omp():
    return exe("sweep", "--flag", "-fopenmp")


def test_threads_write_rows_in_job_order(sweep_omp, clean, tmp_path):
    env = dict(os.environ, OMP_NUM_THREADS="3")
    r = run([sweep_omp, *PEND, "--out", "t.csv"], tmp_path, env=env)
    assert r.returncode == 0, r.stderr and "3 thread(s)" in r.stdout
    assert (tmp_path / "t.csv").read_text() == (clean / "s.csv").read_text()
    # completion order: the same rows; a job-order rerun (nothing left to do) sorts them
    r = run([sweep_omp, *PEND, "--out", "c.csv", "--order", "completion"], tmp_path,
            env=env)
    assert r.returncode == 0, r.stderr
    got = lines(tmp_path / "c.csv")
    assert sorted(got[1:]) == sorted(lines(clean / "s.csv")[1:])
    r = run([sweep_omp, *PEND, "--out", "c.csv"], tmp_path, env=env)
    assert r.returncode == 0 and "120 already done" in r.stdout
    assert (tmp_path / "c.csv").read_text() == (clean / "s.csv").read_text()
    r = run([sweep_omp, *PEND, "--out", "x.csv", "--order", "random"], tmp_path, env=env)
    assert r.returncode == 2 and "unknown --order 'random'; valid: job completion" in r.stderr


# ------------------------------------------------------------------ full disks

SHIM = textwrap.dedent(r"""
    /* fwrite fails after CONMECH_TEST_FWRITES successful calls with the errno
       CONMECH_TEST_ERRNO (default ENOSPC: a full disk), as the C library reports a failed
       write: through the count and the stream's error flag */
    #define _GNU_SOURCE
    #include <dlfcn.h>
    #include <errno.h>
    #include <stdio.h>
    #include <stdlib.h>
    static long calls = 0;
    static int failed = 0;
    size_t fwrite(const void *p, size_t s, size_t n, FILE *f) {
        static size_t (*real)(const void *, size_t, size_t, FILE *) = 0;
        if (!real) real = (size_t (*)(const void *, size_t, size_t, FILE *))
                          dlsym(RTLD_NEXT, "fwrite");
        const char *lim = getenv("CONMECH_TEST_FWRITES");
        if (f != stderr && f != stdout && lim && calls++ >= atol(lim)) {
            const char *e = getenv("CONMECH_TEST_ERRNO");
            failed = e ? atoi(e) : ENOSPC; errno = failed; return 0;
        }
        return real(p, s, n, f);
    }
    int ferror(FILE *f) {
        static int (*real)(FILE *) = 0;
        if (!real) real = (int (*)(FILE *))dlsym(RTLD_NEXT, "ferror");
        if (failed && f != stderr && f != stdout) { errno = failed; return 1; }
        return real(f);
    }
""")


@pytest.fixture(scope="module")
def shim(tmp_path_factory):
    d = tmp_path_factory.mktemp("shim")
    (d / "shim.c").write_text(SHIM)
    subprocess.run(["gcc", "-O2", "-shared", "-fPIC", "-o", str(d / "shim.so"),
                    str(d / "shim.c"), "-ldl"], check=True)
    return str(d / "shim.so")


@pytest.mark.parametrize("prog, code", [("sweep", errno.ENOSPC), ("hill_family", errno.ENOSPC),
                                        ("sweep", errno.EIO), ("sweep", errno.EACCES),
                                        ("hill_family", errno.EDQUOT)])
def test_full_disk_is_named_not_counted_as_failed_jobs_simulated(exes, shim, tmp_path, prog,
                                                                code):
    args = PEND if prog == "sweep" else ["--n", "150", "--batch", "32", "--quiet"]
    env = dict(os.environ, LD_PRELOAD=shim, CONMECH_TEST_FWRITES="40",
               CONMECH_TEST_ERRNO=str(code))
    r = run([exes[prog], *args, "--out", "o.csv"], tmp_path, env=env)
    assert r.returncode == 3, (r.returncode, r.stderr)
    assert f"cannot write o.csv: {os.strerror(code)}" in r.stderr
    assert "failed" not in r.stderr.replace("not a failed computation", "")
    # space again: the same command resumes and completes
    r = run([exes[prog], *args, "--out", "o.csv"], tmp_path)
    assert r.returncode == 0, r.stderr


def _unshare():
    if shutil.which("unshare") is None:
        return None
    for pre in (["unshare", "-m"], ["unshare", "-rm"]):
        r = subprocess.run(pre + ["sh", "-c", "d=$(mktemp -d) && mount -t tmpfs -o size=64k "
                                              "tmpfs $d && umount $d && rmdir $d"],
                           capture_output=True)
        if r.returncode == 0:
            return pre
    return None


UNSHARE = _unshare()


@pytest.mark.skipif(UNSHARE is None, reason="no private mount namespace here (unshare -m / "
                    "-rm refused): the LD_PRELOAD test above covers the same path")
@pytest.mark.parametrize("prog", ["sweep", "hill_family"])
def test_full_disk_on_a_real_tmpfs(exes, clean, tmp_path, prog):
    mnt = tmp_path / "mnt"
    mnt.mkdir()
    args = " ".join(PEND if prog == "sweep" else ["--n", "1000", "--quiet"])
    script = (f"mount -t tmpfs -o size=16k tmpfs {mnt} && cd {mnt} && "
              f"{exes[prog]} {args} --out o.csv; echo rc=$?; "
              f"rm -f o.csv.args; {exes[prog]} {args} --out o.csv --force; echo rc=$?")
    r = run(UNSHARE + ["sh", "-c", script], tmp_path)
    assert r.stdout.count("rc=3") == 2, (r.stdout, r.stderr)
    assert r.stderr.count("No space left on device") == 2, r.stderr
    assert "jobs failed" not in r.stderr and "incomplete" not in r.stderr


# ------------------------------------------------------------------ namelists

BASE = ("&sweep\n system = 'pendulum', params = 9.81, 1.0, y0 = 0.1, 0.0, vary = 'y0:1',\n"
        " from = 0.1, to = 1, count = 3, t_end = 1\n")
NAMELISTS = [
    (BASE + " count = 'ten'\n/\n", "line 4: count = 'ten': not an integer"),
    (BASE + " count = 2.5\n/\n", "line 4: count = 2.5: not an integer"),
    (BASE + " count = 1e3\n/\n", "line 4: count = 1e3: not an integer"),
    (BASE + " y0(100000) = 1\n/\n", "line 4: y0(100000): index out of range 1..64"),
    (BASE + " params(2:3) = 1, 2, 3\n/\n", "line 4: params = 3: too many values"),
    (BASE + " colour = 3\n/\n", "line 4: unknown key 'colour' in &sweep (valid: system,"),
    (BASE, "the group &sweep that starts at line 1 has no terminator '/'"),
    ("&sweeps count = 3 /\n", "line 1: wrong group name '&sweeps' (this program reads "
                              "&sweep)"),
    ("! nothing\n\n", "no namelist group &sweep in the file"),
    ("count = 3 /\n", "line 1: expected &sweep to start the namelist, found 'count = 3 /'"),
    (BASE + " system = pendulum\n/\n", "line 4: system = pendulum: a string must be in "
                                       "quotes"),
    (BASE + " force = yes\n/\n", "line 4: force = yes: not a logical"),
    (BASE + " rtol = nan\n/\n", "line 4: rtol = nan: not a finite number"),
    (BASE + " count = 3 5\n/\n", "line 4: count = 5: 'count' takes one value"),
    (BASE + " method = 'DOP853\n/\n", "a string starting with ' is not closed"),
    (BASE + " count(2) = 1\n/\n", "line 4: count(2): 'count' is not an array"),
    (BASE + " system = '" + "x" * 70 + "'\n/\n", "too long (at most 64 characters)"),
    (b"\x7fELF\x02\x01\x01\x00\x00\x00", "line 1: not a text file (byte 2 at offset 4)"),
]


@pytest.mark.parametrize("text, message", NAMELISTS, ids=range(len(NAMELISTS)))
def test_namelist_mistakes_are_named(exes, tmp_path, text, message):
    f = tmp_path / "in.nml"
    f.write_bytes(text if isinstance(text, bytes) else text.encode())
    r = run([exes["sweep"], "--input", "in.nml", "--out", "o.csv"], tmp_path)
    assert r.returncode == 2, r.stderr
    assert f"sweep: error: --input in.nml" in r.stderr and message in r.stderr, r.stderr
    assert "End of file" not in r.stderr and not (tmp_path / "o.csv").exists()


def test_namelist_forms_the_read_accepts(exes, tmp_path):
    """Comments, CRLF, repeat counts, subscripts, null values, &end, no final newline."""
    good = [BASE + " ! a comment / with a slash\n y0(2) = 0.0\n/\n",
            BASE.replace("\n", "\r\n") + "/\r\n",
            BASE + " y0 = 2*0.1 /",
            BASE.replace("&sweep", "$SWEEP") + " $end\n",
            BASE + " params = 9.81, , \n &end\n"]
    for k, text in enumerate(good):
        (tmp_path / "in.nml").write_text(text)
        r = run([exes["sweep"], "--input", "in.nml", "--out", f"o{k}.csv"], tmp_path)
        assert r.returncode == 0, (k, r.stderr)
    for prog in ("hill", "hill_family", "seed", "family"):
        (tmp_path / "bad.nml").write_text(f"&{prog}\n nope = 1\n/\n")
        r = run([exes[prog], "--input", "bad.nml"], tmp_path)
        assert r.returncode == 2 and f"line 2: unknown key 'nope' in &{prog}" in r.stderr


# ------------------------------------------------------------------ install footprint

def test_install_puts_the_library_modules_only(tmp_path):
    """scripts/install.sh: libconmech.a and exactly the modules of src/ (fpm 0.12 alone also
    installs the programs' and the examples' modules); --library-only: no programs."""
    import re
    r = subprocess.run(["bash", str(ROOT / "scripts" / "install.sh"), "--prefix",
                        str(tmp_path / "p"), "--library-only"], cwd=ROOT, capture_output=True,
                       text=True, timeout=1800)
    assert r.returncode == 0, r.stderr[-2000:]
    src = set()
    for f in (ROOT / "src").rglob("*.f90"):
        src |= {m.lower() for m in re.findall(r"(?im)^\s*module\s+([a-z]\w*)\s*(?:!.*)?$",
                                               f.read_text())}
    mods = {p.stem for p in (tmp_path / "p" / "include").glob("*.mod")}
    assert mods == src and "conmech" in mods and "arenstorf_model" not in mods
    assert (tmp_path / "p" / "lib" / "libconmech.a").is_file()
    assert not (tmp_path / "p" / "bin").exists()
