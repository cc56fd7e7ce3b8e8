#!/usr/bin/env python3
"""Generate the Fortran side and the C signature text of the compiled-function table
(python/conmech/_core/slot_table.py, the one definition).

    python tools/generate_slots.py            # (re)write the generated files and blocks
    python tools/generate_slots.py --check    # exit 1 if a committed file is stale
    python tools/generate_slots.py --out DIR  # write below DIR (a copy of the tree)
    python tools/generate_slots.py --table FILE   # another table (tests: a toy entry)

Written: src/mechanics/conmech_c_entries.f90 (whole file: the spec kinds and slots, the
pointer record of mechanical systems and its setter by entry number, the C names the
model loader looks up) and, between the markers ``<generated: tools/generate_slots.py
BLOCK>`` and ``</generated>``, the C signatures in the documentation of conmech.compiled,
conmech_c_system and conmech_c_mechanics and the spec layout of conmech_flat_spec. The
output is deterministic; python/tests/test_slot_table.py checks the committed tree.
"""
import argparse
import difflib
import importlib.util
import re
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TABLE = ROOT / "python" / "conmech" / "_core" / "slot_table.py"
GENERATOR = "tools/generate_slots.py"
MODULE = "src/mechanics/conmech_c_entries.f90"
# (file, block, comment prefix of its lines) of the blocks spliced into hand-written files
BLOCKS = [
    ("python/conmech/mechanics/compiled.py", "signatures", "    "),
    ("src/ode/conmech_c_system.f90", "ode signatures", "!!     "),
    ("src/mechanics/conmech_c_mechanics.f90", "mechanics signatures", "!!     "),
    ("python/conmech/flat/support/conmech_flat_spec.f90", "spec layout", "!!     "),
]
WIDTH = 92
BLOCK_WIDTH = 86   # the signature text, after a comment prefix of up to 7 characters


def load_table(path=TABLE):
    spec = importlib.util.spec_from_file_location("_slot_table_source", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


# ----------------------------------------------------------------------------- text

def c_declaration(sig, indent=""):
    """The C declaration `sig;` wrapped at WIDTH, continuation lines under the '('."""
    head, args = sig.split("(", 1)
    args = [a.strip() for a in args.rsplit(")", 1)[0].split(",")]
    lines, cur = [], indent + head + "("
    pad = " " * len(cur)
    for i, a in enumerate(args):
        piece = a + (");" if i == len(args) - 1 else ",")
        if len(cur) + len(piece) + 1 > BLOCK_WIDTH and not cur.endswith("("):
            lines.append(cur.rstrip())
            cur = pad + piece
        else:
            cur += ("" if cur.endswith("(") else " ") + piece
    lines.append(cur)
    return lines


def c_comment(text, indent=""):
    wrapped = textwrap.wrap(text, BLOCK_WIDTH - len(indent) - 6)
    if len(wrapped) == 1:
        return [f"{indent}/* {wrapped[0]} */"]
    return ([f"{indent}/* {wrapped[0]}"] + [f"{indent}   {w}" for w in wrapped[1:-1]]
            + [f"{indent}   {wrapped[-1]} */"])


def signature_lines(entries):
    out = []
    for e in entries:
        if not e.is_function:
            continue
        note = e.doc + ("" if e.required else " (optional)")
        out += c_comment(note) + c_declaration(e.signature)
    return out


def block_text(t, block):
    """The lines of one generated block (without the comment prefix)."""
    funcs = [e for e in t.ENTRIES if e.taylor is None]
    if block == "signatures":
        out = ["/* first-order systems (kind 'ode', n states) */"]
        out += signature_lines([e for e in funcs if "ode" in e.kinds])
        out += ["/* mechanical systems (nd coordinates, M(t, q) q'' = Q(t, q, q')) */"]
        out += signature_lines([e for e in funcs if "generalized" in e.kinds])
        out += ["/* constrained systems (n coordinates; mass, forces, forces_jac, energy",
                "   as above) */"]
        out += signature_lines([e for e in funcs if e.kinds == ("constrained",)])
        return out
    if block == "ode signatures":
        return signature_lines([e for e in funcs if "ode" in e.kinds])
    if block == "mechanics signatures":
        return signature_lines([e for e in funcs if set(e.kinds) & {"generalized",
                                                                    "constrained"}])
    if block == "spec layout":
        out = ["spec(1) kind: " + ", ".join(
            [f"{t.KIND_BUILTIN} none (the built-in `name`)"]
            + [f"{v} {k}" for k, v in t.KINDS.items()]),
            "spec(2) n (ode: state dimension; generalized: ndof; constrained: coordinates)",
            "spec(3) n_hol    spec(4) n_nh    spec(5) rheonomic (0/1)"]
        for slot in range(6, t.SPEC_SIZE + 1):
            names = []
            for e in t.ENTRIES:
                if e.slot == slot:
                    kinds = "/".join(e.kinds)
                    opt = "" if e.required else ", optional"
                    names.append(f"{e.name} ({kinds}{opt})")
            if names:
                out += textwrap.wrap(f"spec({slot}) " + "; ".join(names), BLOCK_WIDTH,
                                     subsequent_indent="        ")
        return out
    raise ValueError(f"unknown block {block}")


def splice(text, block, lines, prefix, rel):
    """`text` with the lines between the markers of `block` replaced by `lines` (each
    after `prefix`)."""
    begin = f"<generated: {GENERATOR} {block}>"
    src = text.splitlines(True)
    try:
        a = next(i for i, ln in enumerate(src) if begin in ln)
        b = next(i for i in range(a + 1, len(src)) if "</generated>" in src[i])
    except StopIteration:
        raise ValueError(f"{rel}: no block '{begin}' ... '</generated>'") from None
    body = [(prefix + ln).rstrip() + "\n" for ln in lines]
    return "".join(src[:a + 1] + body + src[b:])


# ------------------------------------------------------------------------- Fortran

def fortran_module(t):
    mech = t.MECH_ENTRIES
    width = max(len(e.name) for e in mech)
    out = [
        "!> The table of compiled functions on the Fortran side: the kinds and slots of the",
        "!! spec array (see conmech_flat_spec), the pointer record of compiled mechanical",
        "!! systems and the C names a model library exports (conmech_<name>).",
        "!!",
        f"!! Generated by {GENERATOR} from python/conmech/_core/slot_table.py (the one",
        "!! definition of the table): edit the table and run the generator, not this file.",
        "module conmech_c_entries",
        "    use, intrinsic :: iso_c_binding, only: c_funptr, c_null_funptr",
        "    implicit none",
        "    private",
        "    public :: c_mech_pointers, set_mech_entry",
        "",
        "    !> kinds of system (spec(1))"]
    out += _parameters([f"SPEC_KIND_BUILTIN = {t.KIND_BUILTIN}"]
                       + [f"SPEC_KIND_{k.upper()} = {v}" for k, v in t.KINDS.items()])
    out += ["    !> the header of the spec"]
    out += _parameters([f"SLOT_{name.upper()} = {slot}" for name, slot in t.HEADER])
    out += ["    !> the length of a full spec",
            f"    integer, parameter, public :: SPEC_SIZE = {t.SPEC_SIZE}"]
    for e in t.ENTRIES:
        name = ("TAYLOR_" + e.name if e.taylor is not None else e.name).upper()
        out += _doc(f"{e.doc} ({'/'.join(e.kinds)})", "    ")
        out += [f"    integer, parameter, public :: SLOT_{name} = {e.slot}"]
    names = ", ".join(f'"{e.name}"' for e in mech)
    slots = ", ".join(str(e.slot) for e in mech)
    out += [
        "    !> the number of entries of mechanical systems",
        f"    integer, parameter, public :: N_MECH_ENTRIES = {len(mech)}",
        "    !> their names (C name conmech_<name>) and slots, in the order of set_mech_entry",
        f"    character(len={width}), parameter, public :: MECH_ENTRY_NAMES(N_MECH_ENTRIES) = &",
    ]
    out += ["        " + ln for ln in
            _wrap_list(f"[character(len={width}) :: {names}]", WIDTH - 8)]
    out += ["    integer, parameter, public :: MECH_ENTRY_SLOTS(N_MECH_ENTRIES) = &"]
    out += ["        " + ln for ln in _wrap_list(f"[{slots}]", WIDTH - 8)]
    out += ["", "    !> The C function pointers of a compiled mechanical system (null where "
                "absent).", "    type :: c_mech_pointers"]
    for e in mech:
        opt = "" if e.required else " (optional)"
        out += _doc(e.doc + opt, "        ")
        out += [f"        type(c_funptr) :: {e.name} = c_null_funptr"]
    out += ["    end type c_mech_pointers", "", "contains", "",
            "    !> Set entry k (1 .. N_MECH_ENTRIES, the order of MECH_ENTRY_NAMES) of fp to f.",
            "    subroutine set_mech_entry(fp, k, f)",
            "        type(c_mech_pointers), intent(inout) :: fp",
            "        integer, intent(in) :: k",
            "        type(c_funptr), intent(in) :: f",
            "        select case (k)"]
    for i, e in enumerate(mech, 1):
        out += [f"        case ({i})", f"            fp%{e.name} = f"]
    out += ["        end select", "    end subroutine set_mech_entry", "",
            "end module conmech_c_entries"]
    return "\n".join(out) + "\n"


def _doc(text, indent):
    """A FORD doc comment (!> then !! lines) wrapped at WIDTH."""
    lines = textwrap.wrap(text, WIDTH - len(indent) - 4)
    return [indent + "!> " + lines[0]] + [indent + "!! " + ln for ln in lines[1:]]


def _parameters(decls):
    """Public integer parameters, wrapped with '&' continuations."""
    text = "integer, parameter, public :: " + ", ".join(d.replace(" ", "\0") for d in decls)
    parts = [p.replace("\0", " ") for p in
             textwrap.wrap(text, WIDTH - 10, break_long_words=False)]
    return (["    " + parts[0] + " &"] + ["        " + p + " &" for p in parts[1:-1]]
            + (["        " + parts[-1]] if len(parts) > 1 else []))


def _wrap_list(text, width):
    """A Fortran array constructor broken after commas, '&' continuations."""
    parts = textwrap.wrap(text, width - 2, break_long_words=False, break_on_hyphens=False)
    return [p + " &" for p in parts[:-1]] + parts[-1:]


# -------------------------------------------------------------------------- driver

def generate(table=TABLE, root=ROOT):
    """{path relative to the repository: text} of every generated file, the spliced files
    read from `root`."""
    t = load_table(table)
    files = {MODULE: fortran_module(t)}
    for rel, block, prefix in BLOCKS:
        text = files.get(rel) or (Path(root) / rel).read_text()
        files[rel] = splice(text, block, block_text(t, block), prefix, rel)
    return files


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true",
                    help="write nothing; exit 1 if a committed file differs from the table")
    ap.add_argument("--out", help="the tree to write (and read the spliced files from)")
    ap.add_argument("--table", help="the table module (default: python/conmech/_core/slot_table.py)")
    a = ap.parse_args(argv)
    root = Path(a.out) if a.out else ROOT
    files = generate(Path(a.table) if a.table else TABLE, root)
    stale = []
    for rel, text in files.items():
        path = root / rel
        if a.check:
            old = path.read_text() if path.exists() else ""
            if old != text:
                stale.append(rel)
                sys.stdout.writelines(difflib.unified_diff(
                    old.splitlines(True), text.splitlines(True), rel, rel + " (table)"))
            continue
        path.parent.mkdir(parents=True, exist_ok=True)
        if not path.exists() or path.read_text() != text:
            path.write_text(text)
    if a.check and stale:
        print(f"stale: {', '.join(stale)} (run python {GENERATOR})", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
