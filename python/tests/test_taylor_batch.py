"""Taylor ensembles in SIMD lanes (conmech.symbolic.taylor_batch, ensemble.solve with
method="TAYLOR"):

- every member is its own solve_ivp(method="TAYLOR") run bit for bit (state, steps,
  expansions), for a number of members that is not a multiple of the lanes, whatever the
  lanes (1, 2, 4, 8) and the threads (1, 2);
- a member that fails (a collision orbit: the step collapses at the singularity; a member
  started at the singularity: non-finite coefficients) fails as its own run does, while
  the members beside it in the lanes finish with their own results;
- accuracy: Kepler e = 0.5 over 10 periods at 1e-12 against the exact (periodic)
  solution;
- the generated module is compiled for the machine's vector instructions and its lane
  loops are vectorised (gfortran's -fopt-info-vec report);
- bad lanes are refused with the argument named.
"""
import os
import shutil
import subprocess

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

import conmech  # noqa: E402
from conmech import ensemble, symbolic  # noqa: E402
from conmech.symbolic import taylor_batch, taylor_library  # noqa: E402


@pytest.fixture(scope="module")
def kepler():
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    return symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])


@pytest.fixture(scope="module")
def pendulum():
    """A damped pendulum with a parameter and a sine (the sin/cos recurrence)."""
    th, om, c = sp.symbols("th om c")
    return symbolic.ode_system([om, -sp.sin(th) - c*om], [th, om], params={c: 0.1})


def kepler_states(e):
    e = np.asarray(e, dtype=float)
    return np.column_stack([1 - e, 0*e, 0*e, np.sqrt((1 + e)/(1 - e))])


def _same_as_solve_ivp(system, span, y0, res, rtol, atol, rows=None):
    for i in range(len(y0)) if rows is None else rows:
        r = conmech.solve_ivp(system, span, y0[i], method="TAYLOR", rtol=rtol, atol=atol)
        assert res.status[i] == r.status, i
        assert np.array_equal(res.y_final[i], r.y[:, -1]), i
        assert res.t_final[i] == r.t[-1], i
        assert (res.naccept[i], res.nreject[i], res.nfev[i]) == \
            (r.naccept, r.nreject, r.nfev), i


def test_members_are_their_own_solve_ivp_runs(kepler, pendulum):
    m = 11                                  # not a multiple of 2, 4 or 8
    y0 = kepler_states(np.linspace(0.0, 0.8, m))
    res = ensemble.solve(kepler, (0, 7.5), y0, method="TAYLOR", rtol=1e-12, atol=1e-12)
    assert res.success and res.done == m and (res.status == 0).all()
    # the batch library of the machine's lanes, written out for order 15, ran
    assert "batch" in symbolic.model_of(kepler).taylor_paths
    _same_as_solve_ivp(kepler, (0, 7.5), y0, res, 1e-12, 1e-12)
    # backwards in time, a parameter and a sine, a loose tolerance (another order)
    yp = np.column_stack([np.linspace(-2.5, 2.5, 6), np.linspace(1.0, -1.0, 6)])
    rp = ensemble.solve(pendulum, (3.0, -4.0), yp, method="TAYLOR", rtol=1e-7, atol=1e-9)
    assert rp.success
    _same_as_solve_ivp(pendulum, (3.0, -4.0), yp, rp, 1e-7, 1e-9)


def test_lanes_and_threads_do_not_change_the_results(kepler):
    y0 = kepler_states(np.linspace(0.05, 0.75, 37))
    kw = dict(method="TAYLOR", rtol=1e-10, atol=1e-10)
    ref = ensemble.solve(kepler, (0, 12.0), y0, threads=1, **kw)
    assert ref.success
    for lanes in (1, 2, 8):
        for threads in (1, 2):
            r = ensemble.solve(kepler, (0, 12.0), y0, threads=threads, lanes=lanes, **kw)
            for key in ("y_final", "t_final", "naccept", "nreject", "nfev", "status"):
                assert np.array_equal(r[key], ref[key]), (lanes, threads, key)
    # the loop version of the recurrences (what runs when the written-out code would be
    # too long): the same results
    model = symbolic.model_of(kepler)
    for lanes in (2, 4):
        entries = taylor_library.batch_entries(model, lanes) if lanes != \
            taylor_batch.machine_lanes() else kepler.taylor_parts("batch")
        assert entries["width"] == lanes
        tol = np.full(4, 1e-10)
        r = ensemble._solve_taylor_batch(kepler, dict(kepler.taylor, **entries), 0.0, 12.0,
                                         y0, len(y0), tol, tol, 1e300, 100000, 1)
        for key in ("y_final", "t_final", "naccept", "nreject", "nfev", "status"):
            assert np.array_equal(r[key], ref[key]), (lanes, key)


def test_a_failing_member_fails_alone(kepler):
    """A radial orbit falls into the centre at t = pi / (2 sqrt 2) ~ 1.11: its steps
    shrink until the step is too small (or the coefficients overflow), as in its own run;
    a member started at the centre has non-finite coefficients at once. The members in
    the lanes beside them end normally with their own results."""
    y0 = kepler_states(np.linspace(0.1, 0.6, 9))
    y0[3] = [1.0, 0.0, 0.0, 0.0]            # radial infall
    y0[6] = [0.0, 0.0, 0.3, 0.0]            # at the singularity
    res = ensemble.solve(kepler, (0, 4.0), y0, method="TAYLOR", rtol=1e-11, atol=1e-11,
                         max_steps=5000)
    assert not res.success and "2 of 9 members failed" in res.message
    assert list(np.flatnonzero(~res.member_success)) == [3, 6]
    assert res.codes[6] == conmech._core.status.NONFINITE and res.t_final[6] == 0.0
    assert 1.0 < res.t_final[3] < np.pi/(2*np.sqrt(2)) + 1e-6
    for i in (3, 6):
        r = conmech.solve_ivp(kepler, (0, 4.0), y0[i], method="TAYLOR", rtol=1e-11,
                              atol=1e-11, max_steps=5000)
        assert not r.success and res.t_final[i] == r.t[-1]
        assert np.array_equal(res.y_final[i], r.y[:, -1], equal_nan=True)
    ok = [i for i in range(9) if i not in (3, 6)]
    _same_as_solve_ivp(kepler, (0, 4.0), y0, res, 1e-11, 1e-11, rows=ok)


def test_kepler_half_eccentric_ten_periods_accuracy(kepler):
    """10 periods of e = 0.5 orbits at 1e-12 (the benchmark's problem): the orbits close to
    the tolerance's level (the exact solution is periodic; the error grows along the
    orbit as the round-off's random walk and the local errors add up)."""
    m = 13
    y0 = kepler_states(np.full(m, 0.5))
    y0[:, 3] *= np.linspace(0.999, 1.001, m)         # nearby orbits (other periods)
    r0 = y0[:, 0]
    v2 = y0[:, 3]**2
    a = 1/(2/r0 - v2)
    period = 2*np.pi*a**1.5
    res = [ensemble.solve(kepler, (0, 10*period[i]), y0[i:i + 1], method="TAYLOR",
                          rtol=1e-12, atol=1e-12) for i in range(m)]
    err = max(np.max(np.abs(r.y_final[0] - y0[i])) for i, r in enumerate(res))
    assert err < 1e-9
    # and the same members in one call over a common span: a member's state at 10 T of
    # the e = 0.5 orbit equals the one-member call's (the lanes do not interfere)
    one = ensemble.solve(kepler, (0, 10*period[6]), y0, method="TAYLOR", rtol=1e-12,
                         atol=1e-12)
    assert np.array_equal(one.y_final[6], res[6].y_final[0])


def test_generated_module_is_vectorised(kepler, tmp_path):
    """The lane loops of the generated module are vectorised with the machine's vector
    width (gfortran's optimisation report), and the library was compiled for it."""
    if shutil.which("gfortran") is None:
        pytest.skip("gfortran not installed")
    model = symbolic.model_of(kepler)
    lanes = taylor_batch.machine_lanes()
    src, entries, why = taylor_library.taylor_source(model.derived, f"batch{lanes}o15")
    assert why is None
    assert entries == ["taylor_batch", "taylor_batch_fixed", "taylor_batch_run"]
    assert f"integer, parameter :: nl = {lanes}," in src
    f = tmp_path / "batch.f90"
    f.write_text(src)
    flags = ["-O3", "-c"] + taylor_batch.isa_flags(lanes)
    out = subprocess.run(["gfortran"] + flags + ["-fopt-info-vec-optimized", str(f)],
                         cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    report = out.stderr + out.stdout
    vec = [ln for ln in report.splitlines() if "vectorized" in ln or "VECTORIZED" in ln]
    assert len(vec) >= 10, report[-2000:]
    if lanes >= 4:
        assert any("32 byte vectors" in ln or "64 byte vectors" in ln for ln in vec), \
            report[-2000:]
    # the written-out routine: its single loop over the lanes is vectorised (the whole
    # expansion in vector registers)
    lines = src.split("\n")
    start = next(i for i, ln in enumerate(lines) if "subroutine conmech_taylor_batch_fixed"
                 in ln)
    end = next(i for i in range(start, len(lines)) if "end subroutine" in lines[i])
    inside = [ln for ln in vec if "loop vectorized" in ln and
              start < int(ln.split("batch.f90:")[1].split(":")[0]) <= end]
    assert inside, report[-2000:]
    # the stepping routine compiled for that order: Horner's polynomial, the new error
    # scales and the norms of the last two coefficients are vector loops over the lanes
    # (a select on a logical or a maximum beside a select made them scalar, lane by lane)
    start = next(i for i, ln in enumerate(lines) if "subroutine conmech_taylor_batch_steps15"
                 in ln)
    end = next(i for i in range(start, len(lines)) if "end subroutine" in lines[i])
    if lanes >= 4:
        for stmt in ("dy(l, i) = yn(l, i) + hc(l)*dy(l, i)", "ea(l, i) = max(",
                     "z(l) = z(l) + 0.0_dp*w(l, 1, i, cu)"):
            at = next(i for i in range(start, end) if stmt in lines[i]) + 1
            assert any(f"batch.f90:{at}:" in ln and "loop vectorized" in ln and
                       ("32 byte vectors" in ln or "64 byte vectors" in ln)
                       for ln in vec), (stmt, report[-2000:])
    ensemble.solve(kepler, (0, 1.0), kepler_states([0.3]), method="TAYLOR", rtol=1e-12,
                   atol=1e-12)
    path = model.taylor_paths["batch"]
    manifest = os.path.splitext(path)[0] + ".json"
    import json
    with open(manifest) as fh:
        used = json.load(fh)["flags"]
    assert all(fl in used for fl in taylor_batch.isa_flags(lanes))


def test_bad_lanes_are_refused(kepler):
    y0 = kepler_states([0.1, 0.2])
    with pytest.raises(ValueError, match="lanes"):
        ensemble.solve(kepler, (0, 1), y0, method="TAYLOR", lanes=3)
    with pytest.raises(TypeError, match="lanes"):
        ensemble.solve(kepler, (0, 1), y0, method="TAYLOR", lanes="4")
    with pytest.raises(ValueError, match="lanes"):
        ensemble.solve(kepler, (0, 1), y0, method="DOP853", lanes=4)
    with pytest.raises(ValueError, match="part"):
        taylor_library.taylor_source(symbolic.model_of(kepler).derived, "batch3")
