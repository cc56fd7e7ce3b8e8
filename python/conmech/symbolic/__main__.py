"""Command line of conmech.symbolic.

    python -m conmech.symbolic emit MODEL.py -o my_model.f90 [--name NAME] [--module MOD]
    python -m conmech.symbolic emit MODEL.py -o my_model.f90 --check   # exit 1 if stale

`emit` writes a standalone Fortran module (see conmech.symbolic.emit_fortran) for the model
defined in MODEL.py: a function ``model()`` returning it, or a module-level ``model`` or
``system`` (a conmech.symbolic.derive.Derived record, a system made by
conmech.symbolic.lagrangian_system / constrained_system / ode_system, or an object with a
``derived`` attribute); an optional module-level ``name`` sets the Fortran type name. Exit codes:
0 success, 1 --check found a difference, 2 bad input (message on stderr).
"""
import argparse
import importlib.util
import os
import sys
import tempfile
from pathlib import Path
from .emit_fortran import emit
from .pipeline import model_of
from .record import Derived


def load_model(path):
    """(Derived record, name or None) from a model file."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"model file '{path}' does not exist")
    spec = importlib.util.spec_from_file_location(f"_conmech_model_{abs(hash(path))}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    obj = None
    for attr in ("model", "system"):
        if hasattr(mod, attr):
            obj = getattr(mod, attr)
            break
    if obj is None:
        raise ValueError(f"{path}: defines neither model() nor model/system")
    if callable(obj) and not isinstance(obj, Derived) and not hasattr(obj, "derived"):
        obj = obj()
    if not isinstance(obj, Derived) and not hasattr(obj, "derived"):
        try:   # a compiled system made by conmech.symbolic (lagrangian_system, ...)
            obj = model_of(obj)
        except (ImportError, TypeError):
            pass
    if hasattr(obj, "derived") and not isinstance(obj, Derived):
        obj = obj.derived
    if not isinstance(obj, Derived):
        raise ValueError(f"{path}: the model is a {type(obj).__name__}, not a "
                         "conmech.symbolic Derived record (use conmech.symbolic.derive."
                         "derive_ode / derive_lagrangian / derive_constrained)")
    return obj, getattr(mod, "name", None)


def _default_name(out):
    stem = Path(out).stem
    return stem[:-len("_model")] if stem.endswith("_model") and len(stem) > 6 else stem + "_sys"


def emit_file(model_path, out, name=None, module=None):
    """Generate the Fortran source for a model file; returns (source, name, module)."""
    d, mname = load_model(model_path)
    name = name or mname or _default_name(out)
    module = module or Path(out).stem
    src = emit(d, name, module=module, source=Path(model_path).name)
    return src, name, module


def _write_atomic(path, text):
    """Write through a temporary file and a rename; the file gets the mode of any new file
    (0666 less the umask: 0644 usually), not mkstemp's private 0600."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent or ".", prefix=".emit_", suffix=".f90")
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(text)
        mask = os.umask(0o022)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m conmech.symbolic",
                                 description="conmech.symbolic command line")
    sub = ap.add_subparsers(dest="cmd", required=True)
    em = sub.add_parser("emit", help="write a standalone Fortran module for a model file")
    em.add_argument("model", help="Python file defining model() / model / system")
    em.add_argument("-o", "--output", required=True, help="output .f90 file")
    em.add_argument("--name", help="Fortran type name (default: model's `name`, else the "
                                   "output stem without _model)")
    em.add_argument("--module", help="Fortran module name (default: the output stem)")
    em.add_argument("--check", action="store_true",
                    help="do not write; exit 1 if the output file differs from the model")
    args = ap.parse_args(argv)
    try:
        src, name, module = emit_file(args.model, args.output, args.name, args.module)
    except (ValueError, TypeError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.check:
        old = Path(args.output).read_text() if Path(args.output).is_file() else None
        if old != src:
            print(f"{args.output} is out of date with {args.model}", file=sys.stderr)
            return 1
        print(f"{args.output} is up to date")
        return 0
    _write_atomic(args.output, src)
    print(f"wrote {args.output}: module {module}, type {name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
