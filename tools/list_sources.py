#!/usr/bin/env python3
"""Print the source files under a directory, one per line, sorted (used by meson.build).

Meson cannot glob, so meson.build runs this script at configure time; a file added under
src/ (or python/conmech/flat/) is picked up at the next configure without editing meson.build.

    python3 tools/list_sources.py src                      # src/**/*.f90 and *.F90 (fpm's)
    python3 tools/list_sources.py python/conmech/flat --flat           # flat/*.f90 only
    python3 tools/list_sources.py python/conmech --flat --ext py       # conmech/*.py only
    python3 tools/list_sources.py python/conmech --packages    # stability, symbolic, ...

Paths are relative to the current directory, with forward slashes.
"""
import argparse
import sys
from pathlib import Path


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("directory")
    parser.add_argument("--flat", action="store_true", help="do not descend into subfolders")
    parser.add_argument("--packages", action="store_true",
                        help="list the Python subpackage folders below DIRECTORY (those "
                             "with an __init__.py, flat/ excluded), relative to it")
    parser.add_argument("--ext", action="append",
                        help="file extension without the dot (repeatable; default: f90 and "
                             "F90, the free-form Fortran sources fpm compiles)")
    args = parser.parse_args(argv)
    root = Path(args.directory)
    if not root.is_dir():
        sys.stderr.write(f"list_sources.py: no directory {root}\n")
        return 1
    if args.packages:
        pkgs = sorted(p.parent.relative_to(root).as_posix()
                      for p in root.glob("**/__init__.py")
                      if p.parent != root and "flat" not in p.parent.relative_to(root).parts
                      and "__pycache__" not in p.parts)
        sys.stdout.write("".join(f + "\n" for f in pkgs))
        return 0
    exts = args.ext or ["f90", "F90"]
    prefix = "" if args.flat else "**/"
    files = sorted({p.as_posix() for ext in exts for p in root.glob(prefix + "*." + ext)
                    if p.is_file()})
    sys.stdout.write("".join(f + "\n" for f in files))
    return 0


if __name__ == "__main__":
    sys.exit(main())
