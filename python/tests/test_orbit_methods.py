"""Periodic orbits by single shooting, multiple shooting and orthogonal collocation
(stability.periodic_orbit / symmetric_orbit / continuation, method=...), on built-in,
callback, compiled and symbolic systems; multipliers from the segments by the periodic
eigenvalue method; the bad inputs that must be named."""
import ctypes
import os
import shutil
import subprocess
import warnings

import numpy as np
import pytest

import conmech
from conmech import compiled, hill_families as hf, stability, systems

HERE = os.path.dirname(__file__)
#: Van der Pol's limit cycle at mu = 1 (REFERENCE.md)
T_VDP = 6.663286859323130
METHODS = ("single", "multiple", "collocation")


def _vdp(t, y):
    return [y[1], (1 - y[0]**2)*y[1] - y[0]]


@pytest.mark.parametrize("system", ["builtin", "callback"])
def test_three_methods_agree_on_the_van_der_pol_cycle(system):
    """Where all three converge they give the published period and the same multipliers:
    shooting to 1e-9, collocation (40 intervals of degree 4, adapted) to its discretisation
    error (< 1e-8). The trivial multiplier (the deflated flow direction) is 1 to the same
    accuracy, and the contracting one exp(int div f dt) agrees between the methods."""
    sysm = systems.vanderpol(1.0) if system == "builtin" else _vdp
    orbs = {m: stability.periodic_orbit(sysm, [2.0, 0.0], 6.5, method=m) for m in METHODS}
    for m, o in orbs.items():
        tol = 1e-8 if m == "collocation" else 1e-9
        assert o.method == m
        assert o.period == pytest.approx(T_VDP, abs=tol)
        mu = np.sort(np.abs(o.multipliers))
        assert mu[1] == pytest.approx(1.0, abs=tol)
        assert mu[0] == pytest.approx(np.sort(np.abs(orbs["single"].multipliers))[0],
                                      abs=tol)
        assert o.stable and o.residual < 1e-8
        assert np.all(o.multiplier_error >= 0) and o.accuracy < 1e-6
    assert orbs["multiple"].nodes.shape == (9, 2) and orbs["single"].nodes is None
    assert orbs["collocation"].nodes.shape == (41, 2)
    np.testing.assert_allclose(orbs["multiple"].y0, orbs["single"].y0, atol=1e-9)


def test_three_lap_henon_a_orbit_keeps_its_small_multiplier():
    """Hénon's family a (Hill's problem, Hénon's units): the orbit about L1 of amplitude
    0.1 has S ~ 780; over three laps mu_max ~ 3.8e9. Multiple shooting over 24 segments
    keeps the reciprocal pair and the trivial pair to 1e-8 and gives mu_max = (one lap)^3
    (the acceptance check's numbers); the eigenvalues of the formed product of the same
    segment STMs (r.monodromy) lose mu_min entirely."""
    one = hf.lyapunov_orbit(0.1)
    mu1 = np.max(np.abs(one.multipliers))
    r = stability.periodic_orbit(hf.system(), one.y0, 3*one.period, fixed_period=True,
                                 method="multiple", segments=24, rtol=1e-12, atol=1e-12)
    a = np.sort(np.abs(r.multipliers))
    assert a[-1] > 3e9
    assert abs(a[0]*a[-1] - 1) < 1e-8
    assert max(abs(a[1] - 1), abs(a[2] - 1)) < 1e-8
    assert abs(a[-1]/mu1**3 - 1) < 1e-7
    assert r.accuracy < 1e-6
    # the error estimate of mu_min is below 1e-3 of its value
    imin = int(np.argmin(np.abs(r.multipliers)))
    assert r.multiplier_error[imin] < 1e-3*a[0]
    formed = np.sort(np.abs(np.linalg.eigvals(r.monodromy)))
    assert abs(formed[0]*formed[-1] - 1) > 1e-2
    # floquet() of the formed matrix says so: its estimate for mu_min exceeds mu_min
    fl = stability.floquet(r.monodromy, r.period, rel_error=1e-12)
    jmin = int(np.argmin(np.abs(fl["multipliers"])))
    assert fl["multiplier_error"][jmin] > a[0]


@pytest.mark.parametrize("method", ["multiple", "collocation"])
def test_symmetric_orbits_by_every_method(method):
    """Hénon's family a orbit by symmetric shooting (half period, y'0 and tau free) with
    the segments or mesh over the half orbit: same orbit and stability index as single
    shooting."""
    ref = hf.lyapunov_orbit(0.05)
    o = stability.symmetric_orbit(hf.system(), ref.y0, [3], [1, 2], ref.period,
                                  period_factor=2, free_time=True, method=method,
                                  segments=6, intervals=30)
    assert o.period == pytest.approx(ref.period, abs=1e-9)
    np.testing.assert_allclose(o.y0, ref.y0, atol=1e-9)
    assert o.stability_index == pytest.approx(ref.stability_index, rel=1e-8)
    assert o.node_times[-1] == pytest.approx(o.period/2, abs=1e-12)


def test_tight_tolerance_orbit_warns_about_nothing_the_user_did_not_call():
    """At rtol below SciPy's floor the orbit's independent closure check runs at the floor
    (the integrator's own value), silently: the same orbit as at the floor itself."""
    ref = hf.lyapunov_orbit(0.05)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        o = stability.symmetric_orbit(hf.system(), ref.y0, [3], [1, 2], ref.period,
                                      free_time=True, rtol=1e-15, atol=1e-15)
    assert o.period == pytest.approx(ref.period, abs=1e-9)
    assert o.residual < 1e-10


@pytest.fixture(scope="module")
def clib(tmp_path_factory):
    cc = shutil.which("gcc") or shutil.which("cc")
    assert cc is not None, "a C compiler is needed (gfortran's gcc)"
    out = tmp_path_factory.mktemp("clib") / "libvdp.so"
    subprocess.run([cc, "-O2", "-fPIC", "-shared",
                    os.path.join(HERE, "data", "c_vdp_jac_prod.c"), "-o", str(out), "-lm"],
                   check=True)
    return ctypes.CDLL(str(out))


def test_compiled_system_multiple_shooting_and_collocation(clib):
    """Van der Pol's oscillator as a compiled C system (rhs, Jacobian, J x product):
    multiple shooting and collocation find the published limit cycle, and continue it
    in mu (the compiled parameter set in place) to the same end point as single
    shooting."""
    vdp = compiled.ode_system(2, clib.vdp_rhs, clib.vdp_jac, params={"mu": 1.0},
                              keep=clib, name="vdp_c", jac_prod=clib.vdp_jac_prod)
    for m in ("multiple", "collocation"):
        o = stability.periodic_orbit(vdp, [2.0, 0.0], 6.5, method=m)
        assert o.period == pytest.approx(T_VDP, abs=1e-8)
    ends = [stability.continuation(vdp, [2.0, 0.0], 6.66, param="mu", ds=0.1, ds_max=0.3,
                                   p_range=(0.5, 1.5), max_points=30, method=m)
            for m in METHODS]
    for br, tol in zip(ends, (1e-9, 1e-9, 1e-7)):    # collocation: its mesh's error
        assert br.success and br.p[-1] == 1.5 and np.all(br.stable)
        assert br.period[-1] == pytest.approx(ends[0].period[-1], abs=tol)


def test_symbolic_double_pendulum_normal_mode_orbit(tmp_path_factory):
    """The double pendulum from T and U (conmech.symbolic): a brake orbit of the in-phase
    normal mode (theta1 = 0.05 fixed, theta2 and the half period free, velocities zero at
    both ends) by all three methods: the same orbit, its period near 2 pi/omega_1,
    omega_1^2 = (g/l)(2 - sqrt 2) for equal masses and lengths."""
    sp = pytest.importorskip("sympy")
    from conmech import symbolic
    import symbolic_seeds as seeds
    seeds.use_test_cache(tmp_path_factory.getbasetemp())
    L, q = seeds.double_pendulum()
    P = dict(m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=9.81)
    sysm = symbolic.lagrangian_system(L, q, params={sp.Symbol(k): v for k, v in P.items()})
    w1 = np.sqrt(9.81*(2 - np.sqrt(2)))
    y0 = [0.05, 0.05*np.sqrt(2), 0.0, 0.0]
    orbs = [stability.symmetric_orbit(sysm, y0, [1], [2, 3], 2*np.pi/w1, free_time=True,
                                      method=m) for m in METHODS]
    for o in orbs:
        np.testing.assert_allclose(o.y0, orbs[0].y0, atol=1e-9)
        assert o.period == pytest.approx(orbs[0].period, abs=1e-9)
    assert orbs[0].period == pytest.approx(2*np.pi/w1, rel=1e-3)


def test_bad_inputs_are_named():
    with pytest.raises(ValueError, match="3 unknowns .* 4 targets"):
        stability.symmetric_orbit(hf.system(), [0.8, 0, 0, 0.1], [0, 2, 3], [0, 1, 2, 3],
                                  3.0)
    with pytest.raises(ValueError, match="equilibrium"):
        stability.periodic_orbit(systems.vanderpol(1.0), [0.0, 0.0], 6.5)
    with pytest.raises(ValueError, match="equilibrium"):
        stability.periodic_orbit(systems.vanderpol(1.0), [0.0, 0.0], 6.5,
                                 method="multiple")
    with pytest.raises(RuntimeError, match="does not resolve|collocation"):
        stability.periodic_orbit(systems.vanderpol(1.0), [2.0, 0.0], 6.5,
                                 method="collocation", intervals=6, degree=1, adapt=0)
    with pytest.raises(ValueError, match="method"):
        stability.periodic_orbit(systems.vanderpol(1.0), [2.0, 0.0], 6.5, method="hermite")
    with pytest.raises(ValueError, match="segments"):
        stability.periodic_orbit(systems.vanderpol(1.0), [2.0, 0.0], 6.5,
                                 method="multiple", segments=0)
    with pytest.raises(ValueError, match="degree"):
        stability.periodic_orbit(systems.vanderpol(1.0), [2.0, 0.0], 6.5,
                                 method="collocation", degree=9)
    with pytest.raises(ValueError, match="3 unknowns besides the parameter .* 2 targets"):
        stability.continuation(systems.hill(m=0.15), [0.8, 0, 0, 1.0], 2*np.pi, param="m",
                               free=[0, 2, 3], targets=[0, 3], period_factor=4)
    with pytest.raises(ValueError, match="equilibrium"):
        stability.continuation(lambda t, y, p: [y[1], -p*y[0]], [0.0, 0.0], 6.0, p0=1.0)


def test_continuation_by_every_method_in_hills_problem():
    """Hill's variation family continued in m by the three discretisations: the loss of
    stability at m* = 0.19510399668175 located to 1e-10 by each, located, with its true
    closure, and the branch ending exactly at p_max."""
    m_star = 0.19510399668175
    o = conmech.hill.variation_orbit(0.15)
    for method in METHODS:
        br = stability.continuation(systems.hill(m=0.15), o.y0, 2*np.pi, param="m",
                                    free=[0, 3], targets=[0, 3], period_factor=4,
                                    conservative=True, p_range=(0, 0.25), method=method,
                                    segments=4, intervals=20)
        assert br.success and br.method == method
        assert br.p[-1] == 0.25 and np.all(br.p <= 0.25)
        (s,) = br.special
        assert s.kind == "S=+1" and s.kind == "branch point"
        assert s.located and s.residual < 1e-10
        assert abs(s.p - m_star) < 1e-10
