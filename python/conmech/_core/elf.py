"""Structural check of a shared library before ``dlopen``.

``dlopen`` maps the library's segments as its program headers describe them; a segment that
reaches past the end of a truncated file is mapped anyway, and the first access to it kills
the process with SIGBUS. A foreign file (a text file, a library for another machine, a
library without conmech's entry points) gives at best an obscure ``OSError``. This module
reads the ELF headers with :mod:`struct` (never maps or runs anything) and raises
:class:`LibraryError` naming the file and the problem unless

- the file is a regular file holding an ELF shared object (``ET_DYN``) of this machine's
  class, byte order and architecture,
- the ELF header, every program header and every section header lie inside the file, and
  so does every segment's and every section's file image (``p_offset + p_filesz``,
  ``sh_offset + sh_size`` for sections with file contents),
- the dynamic symbol table defines every requested symbol.

The same checks are made in Fortran by ``conmech_elf_check`` before the programs load a
model library (``sweep --model``, ``family --model``).
"""
import os
import stat
import struct
import sys

__all__ = ["LibraryError", "check_library", "check_bytes", "dynamic_symbols"]

_ET_DYN = 3
_PT_LOAD = 1
_SHT_NOBITS = 8
_SHT_DYNSYM = 11
_SHN_UNDEF = 0
_SHN_LORESERVE = 0xFF00


class LibraryError(ValueError):
    """A file that is not a loadable shared library (truncated, foreign, or without the
    expected entry points); ``path`` and ``reason`` are attributes."""

    def __init__(self, path, reason):
        self.path, self.reason = str(path), reason
        super().__init__(f"{self.path!r} is not a usable shared library: {reason}")


_HOST = None


def _host():
    """(class, byte order, machine) of this process (from the Python executable's ELF
    header), or None where it is not an ELF file."""
    global _HOST
    if _HOST is None:
        cls = 2 if struct.calcsize("P") == 8 else 1
        data = 1 if sys.byteorder == "little" else 2
        machine = None
        for exe in ("/proc/self/exe", sys.executable):
            try:
                with open(exe, "rb") as fh:
                    head = fh.read(20)
            except OSError:
                continue
            if len(head) == 20 and head[:4] == b"\x7fELF":
                machine = struct.unpack_from("<H" if data == 1 else ">H", head, 18)[0]
                break
        _HOST = (cls, data, machine)
    return _HOST


def _fail(path, msg):
    raise LibraryError(path, msg)


def check_bytes(data, path="<bytes>", symbols=()):
    """Check the bytes of a shared library (see the module docstring); returns the set of
    defined dynamic symbols."""
    size = len(data)
    if size < 16 or data[:4] != b"\x7fELF":
        what = "empty" if size == 0 else "not an ELF file"
        _fail(path, f"{what} ({size} bytes)")
    cls, order = data[4], data[5]
    hcls, horder, hmachine = _host()
    if cls not in (1, 2) or order not in (1, 2):
        _fail(path, "invalid ELF identification")
    if cls != hcls or order != horder:
        _fail(path, f"a {32 * cls}-bit {'little' if order == 1 else 'big'}-endian ELF file; "
                    f"this process is {32 * hcls}-bit {sys.byteorder}-endian")
    e = "<" if order == 1 else ">"
    if cls == 2:
        hsize, fmt = 64, e + "HHIQQQIHHHHHH"
        ph_size, sh_size_, sym_size = 56, 64, 24
    else:
        hsize, fmt = 52, e + "HHIIIIIHHHHHH"
        ph_size, sh_size_, sym_size = 32, 40, 16
    if size < hsize:
        _fail(path, f"truncated ({size} bytes: the ELF header alone takes {hsize})")
    (e_type, e_machine, _ver, _entry, phoff, shoff, _flags, ehsize, phentsize, phnum,
     shentsize, shnum, shstrndx) = struct.unpack_from(fmt, data, 16)
    if e_type != _ET_DYN:
        _fail(path, f"an ELF file of type {e_type}, not a shared object")
    if hmachine is not None and e_machine != hmachine:
        _fail(path, f"built for another architecture (ELF machine {e_machine}, this one "
                    f"is {hmachine})")
    if ehsize != hsize or (phnum and phentsize != ph_size) or (shnum and
                                                                shentsize != sh_size_):
        _fail(path, "inconsistent ELF header sizes")
    if phnum == 0:
        _fail(path, "no program headers")
    if phoff + phnum * ph_size > size:
        _fail(path, f"truncated: the program headers end at byte {phoff + phnum * ph_size}, "
                    f"the file has {size}")
    for k in range(phnum):
        off = phoff + k * ph_size
        if cls == 2:
            p_type, _pf, p_offset, _va, _pa, p_filesz, p_memsz, _al = struct.unpack_from(
                e + "IIQQQQQQ", data, off)
        else:
            p_type, p_offset, _va, _pa, p_filesz, p_memsz, _pf, _al = struct.unpack_from(
                e + "IIIIIIII", data, off)
        if p_offset + p_filesz > size:
            _fail(path, f"truncated: segment {k} (type {p_type}) ends at byte "
                        f"{p_offset + p_filesz}, the file has {size}")
        if p_type == _PT_LOAD and p_filesz > p_memsz:
            _fail(path, f"segment {k} is larger in the file than in memory")
    if shnum == 0 or shoff == 0:
        _fail(path, "no section headers (its symbols cannot be checked)")
    if shoff + shnum * sh_size_ > size:
        _fail(path, f"truncated: the section headers end at byte {shoff + shnum * sh_size_}, "
                    f"the file has {size}")
    if shstrndx >= shnum:
        _fail(path, "invalid section-name table index")
    sections = []
    for k in range(shnum):
        off = shoff + k * sh_size_
        if cls == 2:
            (_n, s_type, _fl, _ad, s_offset, s_size, s_link, _inf, _al,
             s_entsize) = struct.unpack_from(e + "IIQQQQIIQQ", data, off)
        else:
            (_n, s_type, _fl, _ad, s_offset, s_size, s_link, _inf, _al,
             s_entsize) = struct.unpack_from(e + "IIIIIIIIII", data, off)
        if s_type != _SHT_NOBITS and s_offset + s_size > size:
            _fail(path, f"truncated: section {k} ends at byte {s_offset + s_size}, the file "
                        f"has {size}")
        sections.append((s_type, s_offset, s_size, s_link, s_entsize))
    names = set()
    for s_type, s_offset, s_size, s_link, s_entsize in sections:
        if s_type != _SHT_DYNSYM:
            continue
        if s_entsize != sym_size or s_link >= shnum:
            _fail(path, "invalid dynamic symbol table")
        _t, str_off, str_size, _l, _es = sections[s_link]
        strtab = data[str_off:str_off + str_size]
        for j in range(s_size // sym_size):
            off = s_offset + j * sym_size
            if cls == 2:
                st_name, _info, _other, st_shndx = struct.unpack_from(e + "IBBH", data, off)
            else:
                st_name, st_shndx = struct.unpack_from(e + "I", data, off)[0], \
                    struct.unpack_from(e + "H", data, off + 14)[0]
            if st_shndx == _SHN_UNDEF or st_name >= len(strtab):
                continue
            if st_shndx >= _SHN_LORESERVE and st_shndx != 0xFFF1:   # SHN_ABS is defined
                continue
            end = strtab.find(b"\0", st_name)
            names.add(strtab[st_name:end if end >= 0 else len(strtab)].decode("latin-1"))
    missing = [s for s in symbols if s not in names]
    if missing:
        _fail(path, "it does not define " + ", ".join(missing)
              + (" (not a conmech model library?)" if len(missing) == len(symbols) else ""))
    return names


def read_regular(path):
    """The bytes of a regular file (LibraryError for a directory, a device, a missing
    file)."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise LibraryError(path, exc.strerror or str(exc)) from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise LibraryError(path, "not a regular file")
        chunks, left = [], st.st_size
        while left > 0:
            b = os.read(fd, min(left, 1 << 24))
            if not b:
                break
            chunks.append(b)
            left -= len(b)
        return b"".join(chunks)
    except OSError as exc:
        raise LibraryError(path, exc.strerror or str(exc)) from None
    finally:
        os.close(fd)


def check_library(path, symbols=()):
    """Check the shared library at `path` before loading it (see the module docstring);
    returns the set of its defined dynamic symbols."""
    return check_bytes(read_regular(path), str(path), symbols)


def dynamic_symbols(path):
    """The defined dynamic symbols of a shared library (after the structural check)."""
    return check_library(path)
