"""Compile generated Fortran into a shared library in an on-disk cache, and load it.

Cache directory: ``$CONMECH_CACHE`` if set, else ``$XDG_CACHE_HOME/conmech``, else
``~/.cache/conmech``. An entry is keyed by the SHA-256 of the generated source, the compiler
command and flags, ``gfortran --version`` and ``conmech.__version__``, so a change of any of
them builds a new library. Each entry is three files:

- ``conmech_KEY.so``, the library, and ``conmech_KEY.f90``, its source (for reading);
- ``conmech_KEY.json``, the manifest: the library's size and SHA-256, written (atomically,
  after the library is in place) only when the build succeeded and the library passed the
  structural check of :mod:`conmech._elf` with every expected entry point;
- ``conmech_src_SKEY.json`` (SKEY: the key without the compiler version), the latest entry
  built from this source, so that a cache hit needs no compiler at all (gfortran need not
  be installed where a prepared cache is used).

A library is loaded only after its size and SHA-256 match its manifest: an entry truncated
by a full disk or a killed copy, or modified since, is reported with a
:class:`CacheWarning` and rebuilt (dlopen of a truncated library would kill the
process with SIGBUS). A build compiles in a private temporary directory inside the cache
directory and moves the library into place with ``os.replace`` (atomic on POSIX): two
processes building the same system at once both succeed, and neither ever loads a
half-written file. A failed build raises :class:`CompileError` (the compiler's message) or
:class:`CacheError` (a read-only or full cache, named as such) and leaves nothing behind.

The cache holds code that every later process loads and runs, so it is trusted only when
nobody else can write it (as ssh treats its key files): the cache directory and its
entries must belong to the user (or root) and must not be writable by the group or others
(a directory may be if it has the sticky bit), and no directory above it may be writable by
others without the sticky bit. Otherwise :class:`CacheError` says which path and why,
before anything is read from it.
"""
import ctypes
import errno
import hashlib
import json
import os
import shutil
import stat
import subprocess
import tempfile
import warnings

from .._core.elf import LibraryError, check_bytes, read_regular

__all__ = ["CompileError", "CacheError", "CacheWarning", "cache_dir", "compile_source",
           "load", "library_path", "FFLAGS", "compiler", "verify_entry"]

#: the flags of the package's release build (meson buildtype=release), for a shared library
FFLAGS = ["-O3", "-fPIC", "-shared"]
_EXPORTS_MAP = "exports.map"     # the linker version script written beside the source

_MANIFEST_FORMAT = 1
_VERSION_CACHE = {}


class CompileError(RuntimeError):
    """The Fortran compiler is missing or rejected the generated source."""


class CacheError(RuntimeError):
    """The compile cache cannot be used: writable by another user, read-only, or full."""


class CacheWarning(UserWarning):
    """A damaged cache entry was found (and is rebuilt)."""


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


# ------------------------------------------------------------------ who may write the cache

def _uid():
    return os.geteuid() if hasattr(os, "geteuid") else None


def _writers(st):
    """'the group', 'others' or 'the group and others' for a mode writable by them."""
    w = [who for bit, who in ((stat.S_IWGRP, "the group"), (stat.S_IWOTH, "others"))
         if st.st_mode & bit]
    return " and ".join(w)


def check_private(path, st=None, what=None):
    """CacheError unless `path` belongs to the user (or root) and only they can write it
    (a directory with the sticky bit may be writable by others)."""
    uid = _uid()
    if uid is None:          # not POSIX: no ownership to check
        return
    if st is None:
        st = os.lstat(path)
    isdir = stat.S_ISDIR(st.st_mode)
    what = what or ("cache directory" if isdir else "cache entry")
    if stat.S_ISLNK(st.st_mode):
        raise CacheError(f"the {what} {path} is a symbolic link: conmech loads code only "
                         "from a cache whose entries are plain files")
    if st.st_uid not in (uid, 0):
        raise CacheError(f"the {what} {path} belongs to another user (uid {st.st_uid}, you "
                         f"are {uid}): conmech refuses to load code from a cache that "
                         "someone else controls; set CONMECH_CACHE to a directory of "
                         "your own")
    if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH) and not (isdir and
                                                            st.st_mode & stat.S_ISVTX):
        raise CacheError(f"the {what} {path} is writable by {_writers(st)} (mode "
                         f"{stat.S_IMODE(st.st_mode):04o}): anyone who can write it can "
                         "plant code that conmech would load; run `chmod go-w "
                         f"{path}` or set CONMECH_CACHE to a private directory")


def _check_ancestors(d):
    """No directory above the cache may be writable by others without the sticky bit
    (whoever can write it can replace the cache directory)."""
    p = os.path.dirname(os.path.abspath(d))
    while True:
        try:
            st = os.stat(p)
        except OSError:
            return
        if st.st_mode & stat.S_IWOTH and not st.st_mode & stat.S_ISVTX:
            raise CacheError(f"the directory {p} above the compile cache {d} is writable by "
                             f"everyone (mode {stat.S_IMODE(st.st_mode):04o}, no sticky "
                             "bit): another user could replace the cache; set CONMECH_CACHE "
                             "to a directory in a private location")
        parent = os.path.dirname(p)
        if parent == p:
            return
        p = parent


def _os_problem(exc, d, doing):
    """CacheError for an OSError met while `doing` in the cache directory `d`."""
    code = getattr(exc, "errno", None)
    reason = exc.strerror or str(exc)
    if code in (errno.ENOSPC, getattr(errno, "EDQUOT", -1)):
        return CacheError(f"the compile cache {d} is full ({reason}) while {doing}: free "
                          "space or set CONMECH_CACHE to another directory")
    if code in (errno.EROFS, errno.EACCES, errno.EPERM):
        return CacheError(f"the compile cache {d} is not writable ({reason}) while {doing}: "
                          "a new system must be compiled into it; set CONMECH_CACHE to a "
                          "writable directory")
    return CacheError(f"the compile cache {d}: {reason} while {doing}")


def _open_cache(create):
    """The cache directory, checked (and created, mode 0700, when `create`); None if it
    does not exist and `create` is False."""
    d = cache_dir()
    try:
        st = os.stat(d)
    except FileNotFoundError:
        if not create:
            return None
        try:
            os.makedirs(d, mode=0o700, exist_ok=True)
        except OSError as exc:
            raise _os_problem(exc, d, "creating it") from None
        st = os.stat(d)
    if not stat.S_ISDIR(st.st_mode):
        raise CacheError(f"the compile cache {d} is not a directory")
    check_private(d, st)
    _check_ancestors(d)
    return d


# ------------------------------------------------------------------ keys

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


def _source_key(source, flags):
    """Key of everything but the compiler version."""
    h = hashlib.sha256()
    for part in (source, compiler(), " ".join(flags), _conmech_version()):
        h.update(part.encode())
        h.update(b"\0")
    return h.hexdigest()


def _full_key(skey, version):
    return hashlib.sha256(f"{skey}\0{version}\0".encode()).hexdigest()


def _link_flags(flags):
    """The compiler flags (FFLAGS by default); a shared library gets the version script
    that exports conmech's entry points only (gfortran also makes module procedures and the
    tables of derived types, __mod_MOD_..., global)."""
    flags = list(FFLAGS if flags is None else flags)
    if "-shared" in flags:
        flags.append(f"-Wl,--version-script={_EXPORTS_MAP}")
    return flags


def library_path(source, flags=None):
    """(path, key) of the cached library for this source and flags (needs the compiler,
    whose version is part of the key)."""
    flags = _link_flags(flags)
    key = _full_key(_source_key(source, flags), _compiler_version(compiler()))
    return os.path.join(cache_dir(), f"conmech_{key}.so"), key


# ------------------------------------------------------------------ manifests

def _read_json(path, limit=1 << 16):
    """A JSON file of the cache (its ownership checked; at most `limit` bytes read, None:
    the whole file), or None if absent or unreadable."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
    except OSError:
        return None
    try:
        check_private(path, os.fstat(fd))
        with os.fdopen(fd, "rb", closefd=False) as fh:
            text = fh.read() if limit is None else fh.read(limit)
        return json.loads(text.decode())
    except (ValueError, UnicodeDecodeError, OSError):
        return None
    finally:
        os.close(fd)


def _write_atomic(path, data, mode):
    """Write bytes to `path` through a temporary file in the same directory (fsync,
    chmod, rename); nothing is left behind on failure."""
    d = os.path.dirname(path)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", dir=d)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, mode)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def verify_entry(path, symbols=()):
    """Check the cache entry of the library `path` against its manifest: (True, "") when
    its size and SHA-256 match and it passes the structural check with `symbols`; (False,
    reason) when it is damaged; (None, "") when there is no such entry."""
    manifest = path[:-3] + ".json"
    if not os.path.lexists(path):
        return None, ""
    check_private(path)
    info = _read_json(manifest)
    if info is None or info.get("format") != _MANIFEST_FORMAT:
        return False, ("it has no valid manifest (made by an older conmech, or by a build "
                       "killed before it finished)")
    try:
        data = read_regular(path)
    except LibraryError as exc:
        return False, str(exc)
    if len(data) != info.get("size"):
        return False, (f"its size is {len(data)} bytes, the manifest says "
                       f"{info.get('size')} (truncated by a full disk or a killed copy?)")
    if hashlib.sha256(data).hexdigest() != info.get("sha256"):
        return False, "its SHA-256 differs from the manifest's (modified after the build)"
    try:
        check_bytes(data, path, [f"conmech_{e}" for e in symbols])
    except LibraryError as exc:
        return False, str(exc)
    return True, ""


def _discard(path, reason):
    """Report a damaged entry. It is not deleted: the rebuild replaces the library and then
    its manifest by atomic renames, so a process that loaded the old file keeps its mapping
    and one that checks the entry meanwhile never loads a file its manifest does not
    certify."""
    warnings.warn(f"conmech cache: {path}: {reason}; rebuilding it", CacheWarning,
                  stacklevel=4)


def _remove_stale_builds(d, age=86400.0):
    """Remove build directories and temporary files left by killed processes (older than
    a day)."""
    import time
    now = time.time()
    try:
        names = os.listdir(d)
    except OSError:
        return
    for name in names:
        if name.startswith((".build-", ".tmp-")):
            p = os.path.join(d, name)
            try:
                if now - os.lstat(p).st_mtime > age:
                    if os.path.isdir(p) and not os.path.islink(p):
                        shutil.rmtree(p, ignore_errors=True)
                    else:
                        os.unlink(p)
            except OSError:
                pass


# ------------------------------------------------------------------ build

def compile_source(source, flags=None, symbols=()):
    """Path of the shared library built from `source` (from the cache when present and
    intact). Returns (path, hit) with hit True when no compilation was needed. `symbols`:
    entry names (``rhs``, ``mass``, ...) whose ``conmech_<name>`` the library must
    define."""
    flags = _link_flags(flags)
    fc = compiler()
    skey = _source_key(source, flags)
    try:
        version = _compiler_version(fc)
        no_compiler = None
    except CompileError as exc:
        version, no_compiler = None, exc
    d = _open_cache(create=no_compiler is None)
    alias = os.path.join(d, f"conmech_src_{skey}.json") if d else None
    if version is None:
        # no compiler: the latest intact entry built from this source, if any
        info = _read_json(alias) if alias else None
        key = info.get("key") if isinstance(info, dict) else None
        if isinstance(key, str) and len(key) == 64 and all(c in "0123456789abcdef"
                                                            for c in key):
            path = os.path.join(d, f"conmech_{key}.so")
            ok, reason = verify_entry(path, symbols)
            if ok:
                return path, True
            if ok is False:
                raise CompileError(f"the cached library {path} is damaged ({reason}) and "
                                   f"cannot be rebuilt: {no_compiler}")
        raise no_compiler
    key = _full_key(skey, version)
    path = os.path.join(d, f"conmech_{key}.so")
    ok, reason = verify_entry(path, symbols)
    if ok:
        return path, True
    if ok is False:
        _discard(path, reason)
    _remove_stale_builds(d)
    try:
        work = tempfile.mkdtemp(prefix=f".build-{key[:12]}-", dir=d)
    except OSError as exc:
        raise _os_problem(exc, d, "creating a build directory") from None
    try:
        src = os.path.join(work, "model.f90")
        out = os.path.join(work, "model.so")
        try:
            with open(src, "w") as fh:
                fh.write(source)
        except OSError as exc:
            raise _os_problem(exc, d, "writing the generated source") from None
        if any(f.startswith("-Wl,--version-script=") for f in flags):
            try:
                with open(os.path.join(work, _EXPORTS_MAP), "w") as fh:
                    fh.write("{ global: conmech_*; local: *; };\n")
            except OSError as exc:
                raise _os_problem(exc, d, "writing the export list") from None
        cmd = [fc] + flags + ["-o", out, src]
        try:
            res = subprocess.run(cmd, cwd=work, capture_output=True, text=True, timeout=600)
        except (OSError, subprocess.SubprocessError) as exc:
            raise CompileError(f"cannot run {' '.join(cmd)}: {exc}") from exc
        msg = (res.stderr or res.stdout).strip()
        if res.returncode != 0 or not os.path.isfile(out):
            if "No space left on device" in msg or "Disk quota exceeded" in msg:
                raise _os_problem(OSError(errno.ENOSPC, "No space left on device"), d,
                                  f"compiling ({fc}: {msg[-300:]})")
            raise CompileError(f"{fc} failed to compile the generated module "
                               f"(exit {res.returncode}):\n{msg}")
        expected = [f"conmech_{e}" for e in symbols]
        try:
            data = read_regular(out)
            exported = check_bytes(data, out, expected)
        except LibraryError as exc:
            raise CompileError(f"{fc} reported success but wrote a damaged library: {exc}"
                               ) from None
        # a generated library exports conmech's entry points and nothing else (names with
        # a leading underscore belong to the toolchain)
        extra = sorted(s for s in exported if s not in expected and not s.startswith("_"))
        if symbols and extra:
            raise CompileError("the compiled library exports symbols that are not conmech "
                               f"entry points ({', '.join(extra[:5])}): refused")
        try:
            os.chmod(out, 0o755)
            os.chmod(src, 0o644)
            with open(out, "rb") as fh:       # on disk before the manifest says it is
                os.fsync(fh.fileno())
            # the source beside the library, for reading; then the library; then the
            # manifest that certifies it; then the alias for compiler-less hits
            os.replace(src, path[:-3] + ".f90")
            os.replace(out, path)
            manifest = {"format": _MANIFEST_FORMAT, "library": os.path.basename(path),
                        "size": len(data), "sha256": hashlib.sha256(data).hexdigest(),
                        "source_key": skey, "compiler": version, "flags": flags}
            _write_atomic(path[:-3] + ".json", json.dumps(manifest, indent=1).encode(),
                          0o644)
            _write_atomic(alias, json.dumps({"key": key}).encode(), 0o644)
        except OSError as exc:
            for p in (path[:-3] + ".json", path):
                try:
                    os.unlink(p)
                except OSError:
                    pass
            raise _os_problem(exc, d, "storing the library") from None
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return path, False


def load(path, entries):
    """Load the library (after the structural check: ELF headers and segments within the
    file, every ``conmech_<entry>`` defined); returns (CDLL, {entry: address})."""
    names = [f"conmech_{e}" for e in entries]
    check_bytes(read_regular(path), str(path), names)
    try:
        lib = ctypes.CDLL(path)
    except OSError as exc:
        raise LibraryError(path, f"dlopen failed: {exc}") from None
    addr = {}
    for e, nm in zip(entries, names):
        fn = getattr(lib, nm)
        addr[e] = ctypes.cast(fn, ctypes.c_void_p).value
    return lib, addr
