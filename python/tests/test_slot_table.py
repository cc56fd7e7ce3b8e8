"""The table of compiled functions (python/conmech/_core/slot_table.py) is the one definition:
the Fortran side and the signature text are generated from it by tools/generate_slots.py.

- the committed files are what the table gives (--check), and --check finds a stale file;
- the table is consistent with itself (outputs against the C signatures, distinct slots
  per kind) and with what conmech.compiled and conmech.symbolic read from it;
- a toy entry added the documented way (one table entry, the generator) reaches the
  Fortran module (which compiles), the pointer record, the loader list and every
  signature block.
"""
import importlib.util
import shutil
import subprocess
from pathlib import Path

import numpy as np

from conmech._core import slot_table as table
from conmech import compiled
from conmech.symbolic import codegen

ROOT = Path(__file__).resolve().parents[2]


def _load(name, path):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


generator = _load("generate_slots", ROOT / "tools" / "generate_slots.py")


def _tree(tmp_path):
    """A copy of the files the generator writes or splices into, below tmp_path."""
    rels = [generator.MODULE] + [rel for rel, _, _ in generator.BLOCKS]
    for rel in rels:
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(ROOT / rel, tmp_path / rel)
    return tmp_path


def test_committed_files_are_generated_from_the_table(capsys):
    assert generator.main(["--check"]) == 0, capsys.readouterr().out


def test_check_mode_finds_a_stale_file(tmp_path, capsys):
    tree = _tree(tmp_path)
    assert generator.main(["--check", "--out", str(tree)]) == 0
    target = tree / "src" / "mechanics" / "conmech_c_mechanics.f90"
    target.write_text(target.read_text().replace("void forces(", "void force(", 1))
    assert generator.main(["--check", "--out", str(tree)]) == 1
    assert "conmech_c_mechanics.f90" in capsys.readouterr().err


def test_the_table_is_consistent():
    for e in table.ENTRIES:
        if not e.is_function:
            continue
        args = e.signature.split("(", 1)[1].rsplit(")", 1)[0].split(",")
        outs = [a for a in args if a.strip().startswith("double *")]
        arrays = [s for s in e.outputs if s != "ret"]
        assert len(outs) == len(arrays), e
        assert e.signature.startswith("double ") == ("ret" in e.outputs), e
        assert args[-1].strip() == "const double *p", e
    for kind in table.KINDS:
        slots = [e.slot for e in table.ENTRIES if kind in e.kinds]
        assert len(slots) == len(set(slots)), kind
        assert all(5 < s <= table.SPEC_SIZE for s in slots)
    # what the Python side reads is the table
    assert compiled._SLOTS is table.SLOTS and compiled._SPEC_SIZE == table.SPEC_SIZE
    assert codegen.ENTRY_POINTS is table.ENTRY_POINTS
    assert table.shapes("constraint_hessian", 5, 2, 1) == [(5, 5), (3, 5)]
    assert table.BY_NAME["forces_jac"].inputs == 3
    assert table.returns_value("energy") and not table.returns_value("mass")


def test_spec_of_a_compiled_system_follows_the_table():
    addr = iter(range(1000, 2000, 8))
    funcs = {name: next(addr) for name in table.ENTRY_POINTS["generalized"]}
    sys = compiled.generalized_system(2, **funcs)
    assert sys.spec.size == table.SPEC_SIZE
    assert sys.spec[0] == table.KIND_GENERALIZED and sys.spec[1] == 2
    for name, a in funcs.items():
        assert sys.spec[table.SLOTS[name] - 1] == a, name
    # every other slot stays empty
    used = {table.SLOTS[n] for n in funcs} | {slot for _, slot in table.HEADER}
    assert not np.any(sys.spec[[s - 1 for s in range(1, table.SPEC_SIZE + 1)
                                if s not in used]])


# one more entry, written into the ENTRIES tuple of a copy of the table (the documented way)
TOY = """    Entry("toy", 29, _G,
          "void toy(double t, const double *q, const double *v, double *a, const double *p)",
          ["(n,)"], "a toy entry of generalized systems"),
"""


def test_a_toy_entry_added_to_the_table_reaches_every_generated_place(tmp_path):
    tree = _tree(tmp_path / "tree")
    toy_table = tmp_path / "toy_table.py"
    source = (ROOT / "python" / "conmech" / "_core" / "slot_table.py").read_text()
    end = "\n)\n\n#: the length of a full spec"
    assert source.count(end) == 1
    toy_table.write_text(source.replace(end, "\n" + TOY.rstrip("\n") + end))
    toy = generator.load_table(toy_table)
    assert toy.SLOTS["toy"] == 29 and "toy" in toy.ENTRY_POINTS["generalized"]
    assert toy.shapes("toy", 3) == [(3,)] and toy.BY_NAME["toy"].inputs == 2
    # the committed tree is stale for the new table; the generator brings it up to date
    assert generator.main(["--check", "--out", str(tree), "--table", str(toy_table)]) == 1
    assert generator.main(["--out", str(tree), "--table", str(toy_table)]) == 0
    assert generator.main(["--check", "--out", str(tree), "--table", str(toy_table)]) == 0
    module = (tree / generator.MODULE).read_text()
    assert "integer, parameter, public :: SLOT_TOY = 29" in module
    assert "integer, parameter, public :: SPEC_SIZE = 29" in module
    assert "type(c_funptr) :: toy = c_null_funptr" in module
    assert "fp%toy = f" in module and '"toy"]' in module
    decl = "void toy(double t, const double *q, const double *v, double *a, const double *p);"
    for rel in ("python/conmech/mechanics/compiled.py", "src/mechanics/conmech_c_mechanics.f90"):
        assert decl in (tree / rel).read_text(), rel
    assert "spec(29) toy (generalized, optional)" in (
        tree / "python/conmech/flat/support/conmech_flat_spec.f90").read_text()
    assert decl not in (tree / "src/ode/conmech_c_system.f90").read_text()
    gfortran = shutil.which("gfortran")      # the compiler the package is built with
    assert gfortran is not None
    # the generated module compiles, and the loader's loop (the entry named "toy" set by
    # its number, as conmech_model_library and conmech_flat_spec do) reaches fp%toy
    (tmp_path / "probe.f90").write_text("""module probe_target
    implicit none
contains
    subroutine f() bind(c, name="probe_target_f")
    end subroutine f
end module probe_target

program probe
    use, intrinsic :: iso_c_binding, only: c_funloc, c_associated
    use conmech_c_entries
    use probe_target, only: f
    implicit none
    type(c_mech_pointers) :: fp
    integer :: k
    do k = 1, N_MECH_ENTRIES
        if (trim(MECH_ENTRY_NAMES(k)) == "toy") call set_mech_entry(fp, k, c_funloc(f))
    end do
    print "(l1, 1x, l1, 1x, i0)", c_associated(fp%toy), c_associated(fp%accel_jac), &
        MECH_ENTRY_SLOTS(N_MECH_ENTRIES)
end program probe
""")
    r = subprocess.run([gfortran, "-std=f2018", "-Wall", "-Werror", "-o", "probe",
                        str(tree / generator.MODULE), "probe.f90"], cwd=tmp_path,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    out = subprocess.run([str(tmp_path / "probe")], capture_output=True, text=True)
    assert out.stdout.split() == ["T", "F", "29"]
