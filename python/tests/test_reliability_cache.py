"""The compile cache and the model libraries cannot poison a process.

- A damaged cache entry (truncated, flipped, emptied, replaced by a foreign file, without
  its manifest) is detected before dlopen, reported with a CacheWarning and rebuilt; the
  model then gives the same numbers. dlopen of a truncated library would kill the process
  with SIGBUS, so every case runs in a child process.
- A model library given by the user (conmech.compiled.load_model, sweep --model, family
  --model) is checked before dlopen: truncated, empty, text, foreign libraries and
  directories are errors naming the file.
- A cache that another user can write (wrong owner, group- or world-writable, a
  world-writable directory above it) is refused before anything is read from it.
- A read-only or full cache is reported as such (on a small tmpfs in a private mount
  namespace where the machine allows it, and always by simulated failures); save_model
  leaves no partial file; a cache hit needs no compiler.
- No user string reaches the generated Fortran unescaped: hostile names go through every
  generator and the library exports conmech's entry points only (nm -D).
"""
import errno
import glob
import json
import os
import shutil
import stat
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

import symbolic_seeds as seeds  # noqa: E402
from conmech import compiled, symbolic  # noqa: E402
from conmech._core.elf import LibraryError, check_library  # noqa: E402
from conmech.symbolic import build  # noqa: E402
from conmech.symbolic.codegen import (check_source, comment_text, generate,  # noqa: E402
                                      private_procedures)

ROOT = Path(__file__).resolve().parents[2]

MODEL = textwrap.dedent("""
    import sys, warnings, numpy as np, sympy as sp
    from conmech import symbolic, solve_ivp
    x, v, k = sp.symbols("x v k")
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        s = symbolic.ode_system([v, -k*x - 0.1*v**3], [x, v], params={k: 2.0})
    r = solve_ivp(s, (0, 10), [1.0, 0.0], rtol=1e-10, atol=1e-10)
    print(repr(float(r.y[0, -1])), r.success, symbolic.model_of(s).cache_hit,
          "|".join(str(m.message) for m in w if m.category is symbolic.CacheWarning))
""")


def run_model(cache, env_extra=None):
    env = dict(os.environ, CONMECH_CACHE=str(cache), **(env_extra or {}))
    r = subprocess.run([sys.executable, "-c", MODEL], env=env, capture_output=True,
                       text=True, timeout=600)
    return r


def parse(r):
    assert r.returncode == 0, r.stderr[-2000:]
    y, ok, hit, warn = r.stdout.rstrip("\n").split(" ", 3)
    return float(y), ok == "True", hit == "True", warn


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """A private cache with the model built once: (cache dir, y_end)."""
    cache = tmp_path_factory.mktemp("cache_base") / "c"
    y, ok, hit, warn = parse(run_model(cache))
    assert ok and not hit and warn == ""
    return cache, y


def fresh_copy(built, tmp_path):
    cache = tmp_path / "c"
    shutil.copytree(built[0], cache)
    return cache


def library_of(cache):
    libs = [p for p in Path(cache).glob("conmech_*.so")]
    assert len(libs) == 1
    return libs[0]


DAMAGE = {
    "truncated": lambda p: p.write_bytes(p.read_bytes()[:7000]),
    "truncated_to_header": lambda p: p.write_bytes(p.read_bytes()[:64]),
    "empty": lambda p: p.write_bytes(b""),
    "one_byte_flipped": lambda p: p.write_bytes(
        p.read_bytes()[:5000] + bytes([p.read_bytes()[5000] ^ 0xFF]) + p.read_bytes()[5001:]),
    "foreign_text": lambda p: p.write_text("not a library\n" * 100),
    "foreign_library": lambda p: p.write_bytes(Path(ctypes_libm()).read_bytes()),
    "manifest_missing": lambda p: p.with_suffix(".json").unlink(),
    "manifest_garbage": lambda p: p.with_suffix(".json").write_text("{not json"),
    "manifest_wrong_size": lambda p: p.with_suffix(".json").write_text(json.dumps(
        dict(json.loads(p.with_suffix(".json").read_text()), size=12))),
}


def ctypes_libm():
    import ctypes.util
    name = ctypes.util.find_library("m")
    for d in ("/lib/x86_64-linux-gnu", "/usr/lib/x86_64-linux-gnu", "/lib64", "/usr/lib64",
              "/lib", "/usr/lib"):
        for cand in glob.glob(os.path.join(d, "libm.so*")):
            if os.path.isfile(cand) and open(cand, "rb").read(4) == b"\x7fELF":
                return cand
    pytest.fail(f"no libm found ({name})")


@pytest.mark.parametrize("damage", sorted(DAMAGE))
def test_damaged_cache_entry_is_detected_and_rebuilt(built, tmp_path, damage):
    cache = fresh_copy(built, tmp_path)
    lib = library_of(cache)
    DAMAGE[damage](lib)
    y, ok, hit, warn = parse(run_model(cache))
    assert ok and not hit and y == built[1]          # rebuilt, the same bits
    assert str(lib) in warn and "rebuilding" in warn
    # the rebuilt entry is intact: the next process takes it silently
    y2, ok2, hit2, warn2 = parse(run_model(cache))
    assert hit2 and warn2 == "" and y2 == built[1]


def test_cache_hit_needs_no_compiler(built, tmp_path):
    cache = fresh_copy(built, tmp_path)
    nothing = tmp_path / "empty_path"          # PATH without gfortran
    nothing.mkdir()
    y, ok, hit, warn = parse(run_model(cache, {"PATH": str(nothing)}))
    assert ok and hit and y == built[1] and warn == ""
    # without a compiler a damaged entry cannot be rebuilt: a clear error, no crash
    DAMAGE["truncated"](library_of(cache))
    r = run_model(cache, {"PATH": str(nothing)})
    assert r.returncode == 1 and "damaged" in r.stderr and "apt-get install gfortran" in \
        r.stderr


def test_cache_miss_without_compiler_is_a_clear_error(tmp_path):
    r = run_model(tmp_path / "empty", {"CONMECH_FC": "gfortran-not-installed"})
    assert r.returncode == 1 and "was not found" in r.stderr
    assert not (tmp_path / "empty").exists()


# ------------------------------------------------------------------ user model libraries

@pytest.fixture(scope="session", autouse=True)
def symbolic_cache(tmp_path_factory):
    return seeds.use_test_cache(tmp_path_factory.getbasetemp())


@pytest.fixture(scope="module")
def model_lib(tmp_path_factory):
    d = tmp_path_factory.mktemp("models")
    x, v, k = sp.symbols("x v k")
    s = symbolic.ode_system([v, -k * x], [x, v], params={k: 4.0})
    return Path(symbolic.save_model(s, d / "osc.so"))


def bad_files(model_lib, tmp_path):
    data = model_lib.read_bytes()
    files = {"truncated": data[:7000], "header_only": data[:64], "empty": b"",
             "text": b"hello\n", "elf_magic_only": data[:16],
             "foreign": Path(ctypes_libm()).read_bytes()}
    out = {}
    for name, b in files.items():
        p = tmp_path / f"{name}.so"
        p.write_bytes(b)
        out[name] = p
    out["directory"] = tmp_path
    out["missing"] = tmp_path / "missing.so"
    return out


LOAD = "import sys\nfrom conmech import compiled\ntry:\n    compiled.load_model(sys.argv[1])\n" \
       "    print('LOADED')\nexcept ValueError as e:\n    print('ValueError:', e)\n"


def test_load_model_refuses_damaged_and_foreign_files(model_lib, tmp_path):
    s = compiled.load_model(model_lib)
    assert s.parameters == {"k": 4.0}
    for name, path in bad_files(model_lib, tmp_path).items():
        r = subprocess.run([sys.executable, "-c", LOAD, str(path)], capture_output=True,
                           text=True, timeout=120)
        assert r.returncode == 0, (name, r.returncode, r.stderr[-500:])   # no signal
        out = r.stdout.strip()
        assert out.startswith("ValueError: cannot load the model library"), (name, out)
        assert str(path) in out, (name, out)
    reasons = {name: subprocess.run([sys.executable, "-c", LOAD, str(p)], capture_output=True,
                                    text=True).stdout for name, p in
               bad_files(model_lib, tmp_path).items()}
    assert "truncated" in reasons["truncated"]
    assert "empty" in reasons["empty"]
    assert "not an ELF file" in reasons["text"]
    assert "conmech_model_info" in reasons["foreign"]
    assert "not a regular file" in reasons["directory"]
    assert "No such file" in reasons["missing"]


def test_elf_check_accepts_real_libraries_and_finds_symbols(model_lib):
    names = check_library(model_lib, ["conmech_model_info", "conmech_rhs"])
    assert {"conmech_rhs", "conmech_jac", "conmech_model_params"} <= names
    with pytest.raises(LibraryError, match="does not define conmech_nothing"):
        check_library(model_lib, ["conmech_nothing"])
    check_library(ctypes_libm(), ["cos", "sin"])


@pytest.fixture(scope="module")
def programs():
    if shutil.which("fpm") is None:
        pytest.fail("fpm is not on PATH: run the tests through scripts/test.sh")
    subprocess.run(["fpm", "build"], cwd=ROOT, capture_output=True, check=True)
    exe = {}
    for prog in ("sweep", "family"):
        out = subprocess.run(["fpm", "run", prog, "--runner", "echo"], cwd=ROOT,
                             capture_output=True, text=True, check=True).stdout
        exe[prog] = str(ROOT / out.strip().splitlines()[-1].strip())
    return exe


def test_programs_refuse_damaged_model_libraries(programs, model_lib, tmp_path):
    for name, path in bad_files(model_lib, tmp_path).items():
        for prog, args in (("sweep", ["--y0", "1,0", "--vary", "y0:1", "--from", "0.5",
                                      "--to", "1", "--count", "2"]),
                           ("family", ["--y0", "1,0", "--period", "3.1"])):
            r = subprocess.run([programs[prog], "--model", str(path), *args, "--out",
                                str(tmp_path / f"{prog}.csv")], cwd=tmp_path,
                               capture_output=True, text=True, timeout=120)
            assert r.returncode == 2, (prog, name, r.returncode, r.stderr)
            assert str(path) in r.stderr and "error" in r.stderr, (prog, name, r.stderr)
    r = subprocess.run([programs["sweep"], "--model", "osc.so", "--y0", "1,0", "--vary",
                        "y0:1", "--from", "0.5", "--to", "1", "--count", "2", "--out",
                        "s.csv", "--quiet"], cwd=model_lib.parent, capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stderr            # a bare name is the file in the cwd


# ------------------------------------------------------------------ who may write the cache

def test_cache_writable_by_others_is_refused(built, tmp_path, monkeypatch):
    cache = fresh_copy(built, tmp_path)
    monkeypatch.setenv("CONMECH_CACHE", str(cache))
    x, v, k = sp.symbols("x v k")

    def make():
        return symbolic.ode_system([v, -k * x - 0.1 * v ** 3], [x, v], params={k: 2.0})
    os.chmod(cache, 0o777)
    with pytest.raises(symbolic.CacheError, match="writable by the group and others"):
        make()
    os.chmod(cache, 0o1777)                 # sticky: others cannot replace our entries
    make()
    os.chmod(cache, 0o720)
    with pytest.raises(symbolic.CacheError, match=r"writable by the group .*chmod go-w"):
        make()
    os.chmod(cache, 0o700)
    lib = library_of(cache)
    os.chmod(lib, 0o666)
    with pytest.raises(symbolic.CacheError, match="cache entry .* writable by"):
        make()
    os.chmod(lib, 0o755)
    manifest = lib.with_suffix(".json")
    os.chmod(manifest, 0o646)
    with pytest.raises(symbolic.CacheError, match="writable by others"):
        make()
    os.chmod(manifest, 0o644)
    make()
    # a directory above the cache that everyone can write (no sticky bit)
    outer = tmp_path / "open"
    outer.mkdir()
    os.chmod(outer, 0o777)
    monkeypatch.setenv("CONMECH_CACHE", str(outer / "cache"))
    with pytest.raises(symbolic.CacheError, match="above the compile cache"):
        make()


def test_cache_owned_by_another_user_is_refused(built, tmp_path, monkeypatch):
    cache = fresh_copy(built, tmp_path)
    monkeypatch.setenv("CONMECH_CACHE", str(cache))
    x, v, k = sp.symbols("x v k")
    me = os.geteuid()
    other = 4242 if me != 4242 else 4243
    if me == 0:                        # root: really give the files away
        os.chown(library_of(cache), other, other)
    else:                              # otherwise: pretend to be someone else
        monkeypatch.setattr(build, "_uid", lambda: other)
    with pytest.raises(symbolic.CacheError, match="belongs to another user"):
        symbolic.ode_system([v, -k * x - 0.1 * v ** 3], [x, v], params={k: 2.0})


def test_symlinked_entry_is_refused(built, tmp_path, monkeypatch):
    cache = fresh_copy(built, tmp_path)
    lib = library_of(cache)
    target = tmp_path / "elsewhere.so"
    shutil.move(lib, target)
    os.symlink(target, lib)
    monkeypatch.setenv("CONMECH_CACHE", str(cache))
    x, v, k = sp.symbols("x v k")
    with pytest.raises(symbolic.CacheError, match="symbolic link"):
        symbolic.ode_system([v, -k * x - 0.1 * v ** 3], [x, v], params={k: 2.0})


# ------------------------------------------------------------------ read-only and full caches

def _new_model(tag):
    x, v = sp.symbols("x v")
    return lambda: symbolic.ode_system([v, -x - x ** 3 / tag], [x, v])


def test_read_only_and_full_caches_are_named_simulated(tmp_path, monkeypatch):
    """Simulated failures (always runs): the cache's file operations fail with EROFS,
    ENOSPC, EDQUOT; the error says read-only / full, nothing is left behind."""
    cache = tmp_path / "c"
    cache.mkdir(mode=0o700)
    monkeypatch.setenv("CONMECH_CACHE", str(cache))
    real = build.tempfile.mkdtemp
    for code, word in ((errno.EROFS, "not writable"), (errno.EACCES, "not writable"),
                       (errno.ENOSPC, "is full"), (errno.EDQUOT, "is full")):
        def failing(*a, _code=code, **k):
            raise OSError(_code, os.strerror(_code))
        monkeypatch.setattr(build.tempfile, "mkdtemp", failing)
        with pytest.raises(symbolic.CacheError, match=word) as e:
            _new_model(7 + code)()
        assert os.strerror(code) in str(e.value) and str(cache) in str(e.value)
    monkeypatch.setattr(build.tempfile, "mkdtemp", real)

    # the disk fills while the manifest is written: no library without its manifest
    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(build, "_write_atomic", full)
    with pytest.raises(symbolic.CacheError, match="full .No space left on device"):
        _new_model(99)()
    assert sorted(os.listdir(cache)) == [] or all(
        not f.endswith(".so") for f in os.listdir(cache)), os.listdir(cache)


def test_save_model_leaves_no_partial_file(tmp_path, monkeypatch, model_lib):
    s = compiled.load_model(model_lib)
    x, v, k = sp.symbols("x v k")
    sys_ = symbolic.ode_system([v, -k * x], [x, v], params={k: 4.0})
    out = tmp_path / "out"
    out.mkdir()

    def boom(src, dst, *a, **k):
        dst.write(b"partial")
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(symbolic.pipeline.shutil, "copyfileobj", boom)
    with pytest.raises(OSError, match="cannot write the model library .*No space left"):
        symbolic.save_model(sys_, out / "m.so")
    assert os.listdir(out) == []
    monkeypatch.undo()
    assert s.parameters == {"k": 4.0}


def _tmpfs_runner():
    """A command prefix that runs a shell script in a private mount namespace where a
    tmpfs can be mounted (root: unshare -m; otherwise a user namespace: unshare -rm), or
    None where neither works."""
    if shutil.which("unshare") is None:
        return None
    for pre in (["unshare", "-m"], ["unshare", "-rm"]):
        r = subprocess.run(pre + ["sh", "-c", "d=$(mktemp -d) && mount -t tmpfs -o size=64k "
                                              "tmpfs $d && umount $d && rmdir $d"],
                           capture_output=True)
        if r.returncode == 0:
            return pre
    return None


TMPFS = _tmpfs_runner()


@pytest.mark.skipif(TMPFS is None, reason="no private mount namespace here (unshare -m / "
                    "-rm refused): the simulated test above covers the same paths")
@pytest.mark.parametrize("case", ["read_only_empty", "read_only_with_entry", "full",
                                  "save_model_full"])
def test_read_only_and_full_caches_on_a_real_tmpfs(tmp_path, case, built):
    mnt = tmp_path / "mnt"
    mnt.mkdir()
    script = textwrap.dedent(f"""
        import os, sys, sympy as sp, numpy as np
        from conmech import symbolic, solve_ivp
        x, v, k = sp.symbols("x v k")
        case = {case!r}
        try:
            if case == "save_model_full":
                os.environ["CONMECH_CACHE"] = {str(built[0])!r}
                s = symbolic.ode_system([v, -k*x - 0.1*v**3], [x, v], params={{k: 2.0}})
                symbolic.save_model(s, os.path.join({str(mnt)!r}, "m.so"))
            else:
                s = symbolic.ode_system([v, -k*x - 0.1*v**3], [x, v], params={{k: 2.0}})
                r = solve_ivp(s, (0, 10), [1.0, 0.0], rtol=1e-10, atol=1e-10)
                print("OK", repr(float(r.y[0, -1])), symbolic.model_of(s).cache_hit)
        except Exception as e:
            print(type(e).__name__ + ":", e)
        print("FILES", sorted(f for f in os.listdir({str(mnt)!r}) if f != "filler"))
    """)
    (tmp_path / "t.py").write_text(script)
    cache_setup = ""
    if case == "read_only_with_entry":
        cache_setup = f"cp -a {built[0]}/. {mnt}/ && "
    fill = ""
    if case in ("full", "save_model_full"):
        fill = f"dd if=/dev/zero of={mnt}/filler bs=1k count=64 2>/dev/null; "
    remount = "mount -o remount,ro tmpfs " + str(mnt) + " && " if case.startswith(
        "read_only") else ""
    env = dict(os.environ, CONMECH_CACHE=str(mnt))
    cmd = (f"mount -t tmpfs -o size=64k,mode=0700 tmpfs {mnt} && {cache_setup}{fill}"
           f"{remount}{sys.executable} {tmp_path / 't.py'}")
    r = subprocess.run(TMPFS + ["sh", "-c", cmd], env=env, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    out = r.stdout
    if case == "read_only_empty":
        assert "CacheError: the compile cache" in out and "not writable" in out
        assert "Read-only file system" in out
    elif case == "read_only_with_entry":      # a prepared read-only cache serves hits
        assert f"OK {built[1]!r} True" in out, out
    elif case == "full":
        assert "CacheError" in out and "is full" in out and "No space left" in out, out
        assert "FILES []" in out, out
    else:
        assert "OSError: [Errno 28] cannot write the model library" in out, out
        assert "FILES []" in out, out


# ------------------------------------------------------------------ injection

HOSTILE_COORDS = [
    "x\nsubroutine p() bind(C, name=\"pwn\")\nend subroutine\n!",
    "q\"; call execute_command_line(\"id\") ! '",
    "a&\n& b", "r\r\nfunction f()", "θ_ñ", "do", "module", "program", "w" * 200,
    "tab\there", "nul\0byte", "!comment", "&",
]
HOSTILE_PARAMS = ["end", "real", "contains", "θ", "_k", "p" * 200, "subroutine", "α1"]


def _exports(path):
    out = subprocess.run(["nm", "-D", "--defined-only", str(path)], capture_output=True,
                         text=True, check=True).stdout
    return {ln.split()[-1] for ln in out.splitlines() if ln.strip()}


def _hostile_systems():
    t = sp.Symbol("t")
    q = [sp.Function(n)(t) for n in HOSTILE_COORDS[:4]]
    ps = [sp.Symbol(n) for n in HOSTILE_PARAMS]
    pvals = {p: 1.0 + i for i, p in enumerate(ps)}
    xs = [sp.Symbol(n) for n in HOSTILE_COORDS]
    c = sum(ps)                       # every parameter appears
    out = {}
    out["ode"] = lambda: symbolic.ode_system(
        [xs[(i + 1) % len(xs)] - c * xs[i] / 100 for i in range(len(xs))], xs, params=pvals)
    qd = [qi.diff(t) for qi in q]
    T = sum(qd[i] ** 2 for i in range(4)) / 2 * c
    U = c * sum(qi ** 2 for qi in q) / 2
    out["lagrangian"] = lambda: symbolic.lagrangian_system(T - U, q, params=pvals)
    out["constrained"] = lambda: symbolic.constrained_system(
        T, U, q, holonomic=[q[0] ** 2 + q[1] ** 2 - 1], params=pvals)
    th = [sp.Function(n)(t) for n in HOSTILE_COORDS[4:7]]
    names = ["body\nsubroutine x() bind(C)\n!", "b\"'&!", "θ" * 70]
    m, l, g = ps[0], ps[1], ps[3]
    bodies = [symbolic.Body(names[i], None if i == 0 else names[i - 1], "revolute", th[i],
                            at=(0, 0) if i == 0 else (0, -l), mass=m, com=(0, -l))
              for i in range(3)]
    out["planar_tree"] = lambda: symbolic.planar_tree(bodies, pvals, gravity=(0, -g))
    sbodies = [symbolic.SpatialBody(names[i], None if i == 0 else names[i - 1], "revolute",
                                    th[i], axis=(1, 0, 0) if i % 2 == 0 else (0, 1, 0),
                                    at=(0, 0, 0) if i == 0 else (0, 0, -l), mass=m,
                                    com=(0, 0, -l))
               for i in range(2)]
    out["spatial_tree"] = lambda: symbolic.spatial_tree(sbodies, pvals, gravity=(0, 0, -g))
    return out, HOSTILE_PARAMS


@pytest.mark.parametrize("kind", ["ode", "lagrangian", "constrained", "planar_tree",
                                  "spatial_tree"])
def test_hostile_names_cannot_inject_code(kind, tmp_path, built, monkeypatch):
    monkeypatch.setenv("CONMECH_CACHE", str(tmp_path / "cache"))
    systems, pnames = _hostile_systems()
    s = systems[kind]()
    model = symbolic.model_of(s)
    assert _exports(model.path) == {f"conmech_{e}" for e in model.addresses}
    head = model.source.split("\nmodule conmech_symbolic_model")[0]
    assert all(ln.startswith("!") for ln in head.split("\n"))     # names stay in comments
    c_names = [f"conmech_{e}" for e in model.addresses]
    check_source(model.source, c_names + private_procedures(model.addresses, model.source),
                 c_names)
    # the model library: parameter names kept as data, exactly; it holds the Taylor
    # recurrences of an ode system too (compiled apart, on first need, for the model)
    lib = symbolic.save_model(s, tmp_path / "m.so")
    entries = {f"conmech_{e}" for e in generate(model.derived, taylor=True)[1]} | {
        "conmech_model_info", "conmech_model_params", "conmech_model_param_names"}
    assert {f"conmech_{e}" for e in model.addresses} <= entries
    assert _exports(lib) == entries
    loaded = compiled.load_model(lib)
    got = list(loaded.parameters)
    want = list(model.derived.param_names)
    if sum(len(n.encode()) + 1 for n in want) < 4096:
        assert got == want
    np.testing.assert_allclose(list(loaded.parameters.values()), model.derived.param_values)
    if kind != "ode" and kind != "constrained":
        # the analytical-mechanics generators (momenta, first integrals, energy Hessian)
        y = np.full(2 * model.derived.n, 0.1)
        assert np.all(np.isfinite(s.momenta.p_of(y)))
        fi = s.first_integrals
        assert np.all(np.isfinite(fi.values(y))) and np.all(np.isfinite(fi.energy_hessian(y)))
    # every library any generator built into the cache exports conmech's names only
    libs = glob.glob(str(tmp_path / "cache" / "**" / "*.so"), recursive=True)
    assert libs
    for so in libs:
        extra = {e for e in _exports(so) if not e.startswith("conmech_")}
        assert not extra, (so, extra)
    # emit: a standalone module, checked and compiled against conmech's modules (trees by
    # the Lagrangian route: a recursive tree's module is bind(C) only, emit refuses it)
    from conmech.symbolic.emit_fortran import emit
    if kind.endswith("_tree"):
        with pytest.raises(ValueError, match="recursive algorithms"):
            emit(model.derived, "hostile")
        return
    src = emit(model.derived, "hostile", source="evil\nsubroutine q()\n.py")
    head = src.split("\nmodule hostile_model")[0]
    assert all(ln.startswith("!") for ln in head.split("\n"))
    mods = sorted(glob.glob(str(ROOT / "build" / "**" / "conmech.mod"), recursive=True))
    assert mods, "conmech.mod not found under build/ (run scripts/setup.sh)"
    f = tmp_path / "hostile_model.f90"
    f.write_text(src)
    r = subprocess.run(["gfortran", "-fsyntax-only", f"-I{os.path.dirname(mods[0])}",
                        f"-J{tmp_path}", str(f)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-3000:]


HOSTILE_TYPE_NAMES = ["do", "end", "module", "contains", "type", "if", "pure", "program",
                      "real", "integer", "complex", "doubleprecision", "character", "conmech",
                      "conmech_ode", "ode_system", "constrained_system", "dp", "self", "rhs",
                      "cm_success", "mass_cholesky", "x" * 41, "a b", "\u03b8", "1abc", "_a",
                      "n\nsubroutine p()", "k!", "q&", ""]


@pytest.mark.parametrize("kind", ["ode", "constrained"])
def test_hostile_type_and_module_names_in_emit(kind, tmp_path):
    """A type or module name for emit is refused with a ValueError naming it, or the emitted
    module compiles: never Fortran that gfortran rejects (an intrinsic type's name, a name
    the generated code takes from conmech, a module name that is also a name inside)."""
    from conmech.symbolic.derive import derive_constrained, derive_ode
    from conmech.symbolic.emit_fortran import emit
    x, v, k = sp.symbols("x v k")
    if kind == "ode":
        d = derive_ode([v, -k * x], [x, v], {k: 1.0})
    else:
        t = sp.Symbol("t")
        q = [sp.Function("a")(t), sp.Function("b")(t)]
        qd = [qi.diff(t) for qi in q]
        d = derive_constrained((qd[0] ** 2 + qd[1] ** 2) / 2, k * q[1], q,
                               [q[0] ** 2 + q[1] ** 2 - 1], [], {k: 9.81})
    mods = sorted(glob.glob(str(ROOT / "build" / "**" / "conmech.mod"), recursive=True))
    assert mods, "conmech.mod not found under build/ (run scripts/setup.sh)"
    cases = [(n, None) for n in HOSTILE_TYPE_NAMES]
    cases += [("osc", m) for m in HOSTILE_TYPE_NAMES + ["new_osc", "osc_rhs", "osc_n", "k",
                                                         "osc_model", "t", "y"]]
    compiled_ok = refused = 0
    for i, (name, module) in enumerate(cases):
        try:
            src = emit(d, name, module=module)
        except ValueError as exc:
            assert f"'{name if module is None else module}'" in str(exc), (name, module, exc)
            refused += 1
            continue
        f = tmp_path / f"case{i}.f90"
        f.write_text(src)
        r = subprocess.run(["gfortran", "-fsyntax-only", f"-I{os.path.dirname(mods[0])}",
                            f"-J{tmp_path}", str(f)], capture_output=True, text=True)
        assert r.returncode == 0, (name, module, r.stderr[-2000:])
        compiled_ok += 1
    assert compiled_ok >= 8 and refused >= 30, (compiled_ok, refused)


def test_hostile_parameter_names_are_validated_or_kept_as_data():
    x, v = sp.symbols("x v")
    for bad in ["k\nsubroutine", "k k", "k\"", "1k", "", "k!"]:
        with pytest.raises(ValueError, match="not an identifier"):
            symbolic.ode_system([v, -x], [x, v], params={bad: 1.0})
    assert comment_text("a\nb&c!'\"θ") == "a\\x0ab\\x26c\\x21\\x27\\x22\\u03b8"
    assert len(comment_text("z" * 200)) == 60


def test_check_source_refuses_injected_code():
    x, v, k = sp.symbols("x v k")
    from conmech.symbolic.derive import derive_ode
    d = derive_ode([v, -k * x], [x, v], {k: 1.0})
    src, entries = generate(d)
    cn = [f"conmech_{e}" for e in entries]
    procs = cn + private_procedures(entries)
    check_source(src, procs, cn)
    evil = src.replace("contains\n", "contains\n    subroutine pwn() bind(C, name=\"pwn\")\n"
                       "    end subroutine pwn\n", 1)
    with pytest.raises(ValueError, match="unexpected procedure 'pwn'"):
        check_source(evil, procs, cn)
    with pytest.raises(ValueError, match="unexpected C name"):
        check_source(src.replace('name="conmech_rhs"', 'name="system"'), procs, cn)
    with pytest.raises(ValueError, match="character"):
        check_source(src.replace("Generated", "Gener\u00e4ted"), procs, cn)


def test_emitted_files_get_the_umask_mode(tmp_path):
    """emit writes through a temporary file, which mkstemp creates 0600: the result must
    have the mode of any new file (0666 less the umask), like the files it sits beside."""
    from conmech.symbolic.__main__ import main
    model = ROOT / "example" / "models" / "arenstorf.py"
    old = os.umask(0o022)
    try:
        assert main(["emit", str(model), "-o", str(tmp_path / "arenstorf_model.f90")]) == 0
        assert stat.S_IMODE(os.stat(tmp_path / "arenstorf_model.f90").st_mode) == 0o644
        os.umask(0o077)
        assert main(["emit", str(model), "-o", str(tmp_path / "b_model.f90"),
                     "--name", "aren"]) == 0
        assert stat.S_IMODE(os.stat(tmp_path / "b_model.f90").st_mode) == 0o600
    finally:
        os.umask(old)
    assert not [f for f in os.listdir(tmp_path) if f.startswith(".emit_")]
