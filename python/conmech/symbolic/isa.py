"""The machine's SIMD instruction set and the compiler flags of the libraries generated for
it: the Taylor lanes (conmech.symbolic.taylor_batch) and the scalar written-out recurrences
(conmech.symbolic.taylor). Every set of flags keeps the rounding of the portable build:
never a contracted multiply-add, never a vector math library."""
import functools
import platform

__all__ = ["machine_lanes", "isa_flags", "scalar_isa_flags"]

# the lanes round exactly as the scalar route does: the multiply-adds are not contracted
# into fused ones (gfortran's default with an FMA instruction set), and sin, cos, exp, ...
# are glibc's scalar functions, not its vector ones (libmvec, a few ulp apart), which
# gfortran calls for the lanes when it pre-includes glibc's math-vector-fortran.h (by
# default; -nostdinc leaves it out, and the generated code includes nothing)
# (-fopenmp-simd: the `!$omp simd` lane loops are vectorised as loops, not unrolled first
# into scalar statements that the straight-line vectoriser then misses)
_NO_CONTRACT = ["-ffp-contract=off", "-nostdinc", "-fopenmp-simd"]


@functools.lru_cache(maxsize=1)
def _cpu_features():
    """The SIMD features of this processor (x86-64 only; an empty set elsewhere)."""
    if platform.machine().lower() not in ("x86_64", "amd64"):
        return frozenset()
    feats = set()
    try:
        import numpy as np
        core = getattr(np, "_core", None) or np.core
        table = core._multiarray_umath.__cpu_features__
        feats = {k for k, v in table.items() if v}
    except (ImportError, AttributeError):
        try:
            with open("/proc/cpuinfo") as fh:
                for line in fh:
                    if line.startswith("flags"):
                        flags = set(line.split(":", 1)[1].split())
                        feats = {k for k, f in (("AVX2", "avx2"), ("AVX512F", "avx512f"))
                                 if f in flags}
                        break
        except OSError:
            pass
    return frozenset(f for f in feats if f in ("AVX2", "AVX512F"))


def machine_lanes():
    """Doubles per SIMD register of this machine: 8 (AVX-512), 4 (AVX2), else 2."""
    feats = _cpu_features()
    if "AVX512F" in feats:
        return 8
    if "AVX2" in feats:
        return 4
    return 2


def isa_flags(lanes):
    """Compiler flags of a batch library with `lanes` lanes: the machine's vector
    instruction set (AVX-512 registers only for 8 or more lanes), no contraction."""
    feats = _cpu_features()
    if "AVX512F" in feats and lanes >= 8:
        isa = ["-mavx512f", "-mavx2", "-mprefer-vector-width=512"]
    elif "AVX2" in feats:
        isa = ["-mavx2"]
    else:
        isa = []
    return isa + _NO_CONTRACT


def scalar_isa_flags():
    """Compiler flags of the scalar written-out recurrences (conmech.symbolic.taylor's
    fixed_order_source, compiled on this machine for solve_ivp): AVX2's three-operand
    encoding when the processor has it (no register copies before each operation, 4-wide
    moves: about a quarter fewer instructions per expansion), no contraction (the
    coefficients keep the bits of the loop version compiled with the package's flags)."""
    return (["-mavx2"] if "AVX2" in _cpu_features() else []) + _NO_CONTRACT
