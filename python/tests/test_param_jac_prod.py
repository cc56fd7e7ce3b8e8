"""Continuation in a parameter of a compiled system with a Jacobian product: the wrapper
that makes the parameter settable (Fortran builtin_param_system) forwards the product, so
the variational equations of the continuation evaluate J Phi through it (a call counter in
the C product shows it) and the branch equals the dense-Jacobian one to round-off."""
import ctypes
import os
import shutil
import subprocess

import numpy as np
import pytest

from conmech import compiled, stability

HERE = os.path.dirname(__file__)


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    cc = shutil.which("gcc") or shutil.which("cc")
    assert cc is not None, "a C compiler is needed (gfortran's gcc)"
    out = tmp_path_factory.mktemp("vdp") / "libvdp.so"
    subprocess.run([cc, "-O2", "-fPIC", "-shared", os.path.join(HERE, "data",
                    "c_vdp_jac_prod.c"), "-o", str(out)], check=True)
    lib = ctypes.CDLL(str(out))
    lib.vdp_jac_prod_calls.restype = ctypes.c_long
    return lib


def test_continuation_in_mu_uses_the_product(lib):
    def vdp(jp):
        return compiled.ode_system(2, lib.vdp_rhs, jac=lib.vdp_jac, params={"mu": 1.0},
                                   keep=lib, jac_prod=jp)
    opts = dict(param="mu", ds=0.1, ds_max=0.3, p_range=(0, 2.0), rtol=1e-11, atol=1e-11)
    before = lib.vdp_jac_prod_calls()
    b1 = stability.continuation(vdp(lib.vdp_jac_prod), [2.0, 0.0], 6.66, **opts)
    mid = lib.vdp_jac_prod_calls()
    b0 = stability.continuation(vdp(None), [2.0, 0.0], 6.66, **opts)
    assert lib.vdp_jac_prod_calls() == mid            # not called without it
    assert mid - before > 100                         # the continuation used the product
    assert b1.success and b0.success and len(b1) == len(b0) >= 8
    assert b1.p[-1] == 2.0                            # the branch ends on p_max
    for a, b in ((b1.p, b0.p), (b1.period, b0.period), (b1.y0, b0.y0)):
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-10)
    # the limit cycle's period at mu = 1 (published: 6.6632868593231)
    assert b1.period[0] == pytest.approx(6.6632868593231, abs=1e-8)
