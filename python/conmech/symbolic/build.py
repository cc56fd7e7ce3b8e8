"""Compile generated Fortran into a shared library in an on-disk cache, and load it.

Cache directory: ``$CONMECH_CACHE`` if set, else ``$XDG_CACHE_HOME/conmech``, else
``~/.cache/conmech``. The library's file name is the SHA-256 of the generated source, the
compiler command and flags, ``gfortran --version`` and ``conmech.__version__``, so a change
of any of them builds a new library and a cache hit needs no compiler run at all.

A build compiles in a private temporary directory inside the cache directory, then moves the
library into place with ``os.replace`` (atomic on POSIX): two processes building the same
system at once both succeed, and neither ever loads a half-written file. A failed compile
raises :class:`CompileError` with the compiler's message and leaves nothing in the cache.
"""
import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile

__all__ = ["CompileError", "cache_dir", "compile_source", "load", "library_path",
           "FFLAGS", "compiler"]

#: the flags of the package's release build (meson buildtype=release), for a shared library
FFLAGS = ["-O3", "-fPIC", "-shared"]

_VERSION_CACHE = {}


class CompileError(RuntimeError):
    """The Fortran compiler is missing or rejected the generated source."""


def compiler():
    """The Fortran compiler command ($CONMECH_FC, else gfortran)."""
    return os.environ.get("CONMECH_FC", "gfortran")


def cache_dir():
    """The cache directory (created on demand)."""
    d = os.environ.get("CONMECH_CACHE")
    if not d:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"),
                                                                 ".cache")
        d = os.path.join(base, "conmech")
    return d


def _compiler_version(fc):
    path = shutil.which(fc)
    if path is None:
        raise CompileError(
            f"the Fortran compiler '{fc}' (gfortran) was not found: conmech.symbolic compiles "
            "the derived equations with gfortran. Install it, e.g. `apt-get install gfortran` "
            "(Debian/Ubuntu), or set CONMECH_FC to a gfortran-compatible compiler.")
    key = (fc, path)
    if key not in _VERSION_CACHE:
        try:
            out = subprocess.run([fc, "--version"], capture_output=True, text=True,
                                 timeout=60)
        except (OSError, subprocess.SubprocessError) as exc:
            raise CompileError(f"cannot run '{fc} --version': {exc}") from exc
        if out.returncode != 0:
            raise CompileError(f"'{fc} --version' failed: {out.stderr.strip()}")
        _VERSION_CACHE[key] = out.stdout.strip()
    return _VERSION_CACHE[key]


def _conmech_version():
    try:
        from .. import __version__
        return __version__
    except ImportError:      # pragma: no cover - running from a source tree
        return "unknown"


def library_path(source, flags=None):
    """(path, key) of the cached library for this source and flags."""
    fc = compiler()
    flags = list(FFLAGS if flags is None else flags)
    h = hashlib.sha256()
    for part in (source, fc, " ".join(flags), _compiler_version(fc), _conmech_version()):
        h.update(part.encode())
        h.update(b"\0")
    key = h.hexdigest()
    return os.path.join(cache_dir(), f"conmech_{key}.so"), key


def _remove_stale_builds(d, age=86400.0):
    """Remove build directories left by killed processes (older than a day)."""
    import time
    now = time.time()
    try:
        names = os.listdir(d)
    except OSError:
        return
    for name in names:
        if name.startswith(".build-"):
            p = os.path.join(d, name)
            try:
                if now - os.path.getmtime(p) > age:
                    shutil.rmtree(p, ignore_errors=True)
            except OSError:
                pass


def compile_source(source, flags=None):
    """Path of the shared library built from `source` (from the cache when present).
    Returns (path, hit) with hit True when no compilation was needed."""
    path, key = library_path(source, flags)
    if os.path.isfile(path):
        return path, True
    fc = compiler()
    flags = list(FFLAGS if flags is None else flags)
    d = os.path.dirname(path)
    try:
        os.makedirs(d, exist_ok=True)
    except OSError as exc:
        raise CompileError(f"cannot create the cache directory {d}: {exc}") from exc
    _remove_stale_builds(d)
    work = tempfile.mkdtemp(prefix=f".build-{key[:12]}-", dir=d)
    try:
        src = os.path.join(work, "model.f90")
        with open(src, "w") as fh:
            fh.write(source)
        out = os.path.join(work, "model.so")
        cmd = [fc] + flags + ["-o", out, src]
        try:
            res = subprocess.run(cmd, cwd=work, capture_output=True, text=True, timeout=600)
        except (OSError, subprocess.SubprocessError) as exc:
            raise CompileError(f"cannot run {' '.join(cmd)}: {exc}") from exc
        if res.returncode != 0 or not os.path.isfile(out):
            msg = (res.stderr or res.stdout).strip()
            raise CompileError(f"{fc} failed to compile the generated module "
                               f"(exit {res.returncode}):\n{msg}")
        # also keep the source beside the library, for reading (same atomic rename)
        os.replace(src, path[:-3] + ".f90")
        os.replace(out, path)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return path, False


def load(path, entries):
    """Load the library; returns (CDLL, {entry: address}) for the bind(C) names cm_<entry>."""
    lib = ctypes.CDLL(path)
    addr = {}
    for e in entries:
        fn = getattr(lib, f"cm_{e}")
        addr[e] = ctypes.cast(fn, ctypes.c_void_p).value
    return lib, addr
