#!/usr/bin/env python3
"""Run numpy.f2py to generate the C wrapper of conmech._conmech, then silence the two
diagnostics that f2py's callback code prints to stderr when a Python callback raises.

The exception itself still propagates unchanged to the caller of solve_ivp (f2py returns
to the wrapper with longjmp and the exception set); only the lines "capi_return is NULL"
and "Call-back cb_... failed." are removed, as noise for the user.

    python tools/run_f2py.py OUTDIR MODULE FILE.f90 [FILE.f90 ...]
"""
import re
import subprocess
import sys
from pathlib import Path

_NOISE = [
    re.compile(r'^\s*fprintf\(stderr,\s*"capi_return is NULL\\n"\);\s*$'),
    re.compile(r'^\s*fprintf\(stderr,\s*"Call-back cb_\w+ failed\.\\n"\);\s*$'),
]


def main(argv):
    if len(argv) < 3:
        sys.stderr.write(__doc__)
        return 2
    outdir, module, sources = argv[0], argv[1], argv[2:]
    cmd = [sys.executable, "-m", "numpy.f2py", *sources, "-m", module, "--lower",
           "--build-dir", outdir]
    rc = subprocess.call(cmd, stdout=subprocess.DEVNULL)
    if rc != 0:
        return rc
    cfile = Path(outdir) / f"{module}module.c"
    lines = cfile.read_text().splitlines(keepends=True)
    kept = [ln for ln in lines if not any(p.match(ln) for p in _NOISE)]
    cfile.write_text("".join(kept))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
