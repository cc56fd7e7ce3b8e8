"""Generated code leaves the floating-point environment alone.

gfortran saves and restores the whole floating-point environment (x87 and SSE state,
about 0.2 us) around every call of a procedure whose scope uses an intrinsic IEEE module
(ieee_arithmetic, even for ieee_value alone), through ``_gfortran_ieee_procedure_entry``
and ``_gfortran_ieee_procedure_exit``. The generated routines run once per step or per
right-hand side, so they make their NaN (the coefficients of a failed expansion, a right-
hand side whose mass matrix is not positive definite) from its bits
(:func:`conmech.symbolic.printer.quiet_nan`) and use no IEEE module:

- the libraries of a generalized system's Taylor recurrences (core, variational and
  quadruple precision parts) and of a tree's do not import the entry routine;
- neither does a module emitted for a Fortran program (the rhs and Jacobian of a
  generalized system, the Taylor jet of an ode system), compiled against a stand-in for
  conmech's modules;
- the NaN text gives the bits ieee_value gives, in double and quadruple precision, and a
  singular mass matrix still gives NaN coefficients in both.

The imports are read from the ELF dynamic symbol table in Python (no binutils).
"""
import ctypes
import struct
import subprocess

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

from conmech import compiled, symbolic  # noqa: E402
from conmech._core.elf import check_library  # noqa: E402
from conmech.ivp.taylor_generalized import first_order_view  # noqa: E402
from conmech.symbolic import build  # noqa: E402
from conmech.symbolic.derive import derive_lagrangian, derive_ode  # noqa: E402
from conmech.symbolic.emit_fortran import emit  # noqa: E402
from conmech.symbolic.pipeline import model_of  # noqa: E402
from conmech.symbolic.printer import quiet_nan  # noqa: E402
from sympy.physics.mechanics import dynamicsymbols  # noqa: E402
import taylor_jets  # noqa: E402

ENTRY = "_gfortran_ieee_procedure_entry"
DP_NAN = 0x7FF8000000000000
QP_NAN = 0x7FFF8000000000000000000000000000


def imported_symbols(path):
    """The undefined (imported) symbols of the dynamic symbol table of the shared library
    at `path` (ELF, this machine's class and byte order: checked first)."""
    check_library(path)
    with open(path, "rb") as fh:
        data = fh.read()
    e = "<" if data[5] == 1 else ">"
    if data[4] == 2:
        shoff, = struct.unpack_from(e + "Q", data, 0x28)
        shentsize, shnum = struct.unpack_from(e + "HH", data, 0x3A)
        sec, sym, symsize = e + "IIQQQQIIQQ", e + "IBBHQQ", 24
    else:
        shoff, = struct.unpack_from(e + "I", data, 0x20)
        shentsize, shnum = struct.unpack_from(e + "HH", data, 0x2E)
        sec, sym, symsize = e + "IIIIIIIIII", e + "IIIBBH", 16
    sections = [struct.unpack_from(sec, data, shoff + k*shentsize) for k in range(shnum)]
    out = set()
    for _n, s_type, *_f, s_offset, s_size, s_link, _i, _a, _es in sections:
        if s_type != 11:                                      # SHT_DYNSYM
            continue
        str_off, str_size = sections[s_link][4:6]
        strings = data[str_off:str_off + str_size]
        for j in range(s_size//symsize):
            f = struct.unpack_from(sym, data, s_offset + j*symsize)
            name, shndx = f[0], (f[3] if data[4] == 2 else f[5])
            if shndx == 0 and name:                           # SHN_UNDEF: imported
                out.add(strings[name:strings.index(b"\0", name)].decode("latin-1"))
    return out


def _shared(tmp_path, name, src):
    """Compile the Fortran source `src` into the shared library tmp_path/name.so."""
    f = tmp_path / f"{name}.f90"
    f.write_text(src)
    lib = tmp_path / f"{name}.so"
    r = subprocess.run([build.compiler(), "-O2", "-fPIC", "-shared", "-J", str(tmp_path),
                        str(f), "-o", str(lib)], cwd=tmp_path, capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    return lib


def test_the_check_sees_a_procedure_that_uses_ieee_arithmetic(tmp_path):
    """The reading of the symbol table finds the entry routine where a procedure uses
    ieee_arithmetic, and not in the same procedure with the NaN from its bits."""
    body = ("subroutine fill(w, n) bind(C, name='fill')\n{use}"
            "    use, intrinsic :: iso_c_binding, only: c_double, c_int\n"
            "    integer(c_int), value :: n\n    real(c_double) :: w(n)\n"
            "    w = {nan}\nend subroutine fill\n")
    ieee = _shared(tmp_path, "with_ieee", body.format(
        use="    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan\n",
        nan="ieee_value(1.0_c_double, ieee_quiet_nan)"))
    bits = _shared(tmp_path, "with_bits", body.format(
        use="", nan=quiet_nan("dp").replace("1.0_dp", "1.0_c_double")))
    assert ENTRY in imported_symbols(ieee)
    assert ENTRY not in imported_symbols(bits)


def test_the_nan_text_is_ieee_values_quiet_nan(tmp_path):
    """quiet_nan gives the bits of ieee_value(1.0_k, ieee_quiet_nan), double and real128
    (the quadruple one made from its own bits: converting the double NaN in a constant
    expression is an error of gfortran's range check)."""
    src = "\n".join([
        "module nan_bits",
        "    use, intrinsic :: iso_c_binding, only: c_double",
        "    use, intrinsic :: iso_fortran_env, only: real128",
        "    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan",
        "    implicit none",
        "    integer, parameter :: dp = c_double, qp = real128",
        "contains",
        "    subroutine nans(d, q) bind(C, name='nans')",
        "        real(dp), intent(out) :: d(2)",
        "        real(qp), intent(out) :: q(2)",
        f"        d(1) = {quiet_nan('dp')}",
        "        d(2) = ieee_value(1.0_dp, ieee_quiet_nan)",
        f"        q(1) = {quiet_nan('qp')}",
        "        q(2) = ieee_value(1.0_qp, ieee_quiet_nan)",
        "    end subroutine nans",
        "end module nan_bits", ""])
    lib = ctypes.CDLL(str(_shared(tmp_path, "nan_bits", src)))
    d = (ctypes.c_uint64*2)()
    q = (ctypes.c_uint8*32)()
    lib.nans(d, q)
    assert list(d) == [DP_NAN, DP_NAN]
    raw = bytes(q)
    assert [int.from_bytes(raw[k:k + 16], "little") for k in (0, 16)] == [QP_NAN, QP_NAN]


def test_taylor_libraries_do_not_save_the_fp_environment():
    """A generalized system's Taylor libraries (the loop routine, its variational system,
    quadruple precision) and a tree's do not import the entry routine."""
    double = taylor_jets.double_pendulum()
    first_order_view(double, "var")
    first_order_view(double, "qp").taylor_parts("qp")
    tree = taylor_jets.tree_chain(2)
    first_order_view(tree, "var")
    for system, parts in ((double, ("core", "var", "qp")), (tree, ("core", "var"))):
        paths = model_of(system).taylor_paths
        for part in parts:
            imports = imported_symbols(paths[part])
            assert ENTRY not in imports, (part, paths[part])


def _singular():
    """M = q^2: singular at q = 0."""
    t = dynamicsymbols._t
    q = dynamicsymbols("q")
    return symbolic.lagrangian_system(q**2*q.diff(t)**2/2, [q])


def test_a_singular_mass_matrix_gives_nan_coefficients():
    """At q = 0 the expansion fails: every coefficient of order 1.. is the quiet NaN (its
    bits) in double and in quadruple precision; the state's order-0 values stay."""
    system = _singular()
    view = first_order_view(system, "qp")
    tay = view.taylor
    order = 6
    w = taylor_jets.coefficients(compiled.function_address(tay["jet"]), tay["nw"],
                                 view.params, [0.0, 1.0], order)
    assert np.array_equal(w[:, 0], [0.0, 1.0])
    assert np.all(w[:, 1:].view(np.uint64) == DP_NAN)
    qp = view.taylor_parts("qp")["qp"]
    nw = tay["nw"]
    one = (0x3FFF << 112).to_bytes(16, "little")
    wq = ctypes.create_string_buffer(16*(order + 1)*nw)
    ctypes.memmove(ctypes.addressof(wq) + 16*(order + 1), one, 16)    # w(0, 2) = v = 1
    tq = ctypes.create_string_buffer(16)
    pq = ctypes.create_string_buffer(16*max(len(view.params), 1))
    fn = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int, ctypes.c_void_p,
                          ctypes.c_void_p)(compiled.function_address(qp))
    fn(ctypes.addressof(tq), order, ctypes.addressof(wq), ctypes.addressof(pq))
    raw = wq.raw
    for col in range(2):
        vals = [int.from_bytes(raw[16*(col*(order + 1) + k):16*(col*(order + 1) + k + 1)],
                               "little") for k in range(order + 1)]
        assert vals[0] == (0 if col == 0 else 0x3FFF << 112)
        assert vals[1:] == [QP_NAN]*order


_STAND_IN = """module conmech
    use, intrinsic :: iso_c_binding, only: c_double
    implicit none
    integer, parameter :: dp = c_double
    integer, parameter :: CM_SUCCESS = 0
    type :: ode_system
    end type ode_system
    type :: generalized_system
        integer :: ndof = 0
    end type generalized_system
contains
    subroutine mass_cholesky(mm, info)
        real(dp), intent(inout) :: mm(:, :)
        integer, intent(out) :: info
        info = CM_SUCCESS
    end subroutine mass_cholesky
end module conmech

module conmech_lapack
    implicit none
    interface
        subroutine dpotrs(uplo, n, nrhs, a, lda, b, ldb, info)
            character, intent(in) :: uplo
            integer, intent(in) :: n, nrhs, lda, ldb
            double precision, intent(in) :: a(lda, *)
            double precision, intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine dpotrs
    end interface
end module conmech_lapack
"""


def test_emitted_modules_do_not_save_the_fp_environment(tmp_path):
    """A module emitted for a Fortran program: the rhs and Jacobian of a generalized
    system (NaN when M is not positive definite) and the Taylor jet of an ode system
    (NaN for a wrong kind) use no IEEE module; compiled with a stand-in for conmech's
    modules (which only have to provide the names the module imports), the library does
    not import the entry routine."""
    a, b, ad, bd, g = sp.symbols("a b ad bd g")
    T = ad**2 + ad*bd*sp.cos(a - b) + bd**2/2
    U = -g*(2*sp.cos(a) + sp.cos(b))
    gen = emit(derive_lagrangian(T - U, [a, b], velocities=[ad, bd], params={g: 9.81}),
               "dpend", module="dpend_model")
    x, v, k = sp.symbols("x v k")
    ode = emit(derive_ode([v, -k*sp.sin(x)], [x, v], params={k: 2.0}), "pend",
               module="pend_model")
    assert "subroutine dpend_rhs" in gen and "subroutine dpend_jacobian" in gen
    assert "subroutine pend_taylor_jet" in ode
    for src in (gen, ode):
        assert "ieee" not in src.lower()
        assert quiet_nan("dp") in src
    lib = _shared(tmp_path, "emitted", _STAND_IN + gen + ode)
    imports = imported_symbols(lib)
    assert "dpotrs_" in imports               # (the reading sees the module's imports)
    assert ENTRY not in imports


def test_the_extension_module_does_not_save_the_fp_environment():
    """Nor does any entry of the flat layer, nor the library behind it: no scope of either
    uses an IEEE module (conmech_kinds gives the quiet NaN, comparisons find NaN and Inf),
    so an external procedure of the flat layer does not see their names through the modules
    it uses (it did, and each call of solve_ivp, Propagator.propagate_until or
    Stepper.step paid the save and the restore)."""
    from conmech import _conmech
    imports = imported_symbols(_conmech.__file__)
    assert "free" in imports         # (the table was read: the library frees memory)
    assert ENTRY not in imports and "_gfortran_ieee_procedure_exit" not in imports
