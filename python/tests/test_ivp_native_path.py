"""solve_ivp's short path for a compiled system (no events, no dense output: one Fortran
call, points returned without a call-back when they fit) gives the result of the general
path bit for bit: same points, states, counts, status and message. The general path (the
segments, the callbacks and the store call-back of flat_solve) is what solve_ivp ran for
such a call before the short path, reached here by standing in for the short path."""
import numpy as np
import pytest

import conmech
from conmech.ivp import solve as solve_mod

KEPLER_Y0 = [0.5, 0.0, 0.0, 3.0 ** 0.5]


def _general(fun, t0, tf, y0, t_ev, with_t_eval, code, rtol, atol, h0, hmax, max_steps):
    problem = dict(fun=fun, builtin=True, args=(), t0=t0, tf=tf, y0=y0, t_ev=t_ev,
                   with_t_eval=with_t_eval, dense=False, settings=[], vectorized=False)
    common = dict(method=code, rtol=rtol, atol=atol, max_step=hmax, max_steps=max_steps,
                  dense=0)
    return solve_mod._solve(problem, common, h0, None, None)


def _both(fun, t_span, y0, **kw):
    fast = conmech.solve_ivp(fun, t_span, y0, **kw)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(solve_mod, "_solve_native", _general)
        mp.setattr(solve_mod, "_fast_solve", lambda *a: None)     # the fast entry too
        full = conmech.solve_ivp(fun, t_span, y0, **kw)
    return fast, full


def _same(fast, full):
    assert fast.t_events is None and full.t_events is None
    for key in ("status", "message", "success", "nfev", "njev", "nlu", "naccept",
                "nreject"):
        assert fast[key] == full[key], key
    assert fast.sol is None
    if isinstance(full.t, list):
        assert fast.t == [] and fast.y == []
        return
    assert fast.t.shape == full.t.shape and np.array_equal(fast.t, full.t)
    assert fast.y.shape == full.y.shape and np.array_equal(fast.y, full.y)
    assert fast.y.flags.c_contiguous and fast.y.flags.writeable


@pytest.mark.parametrize("method", ["RK45", "DOPRI5", "DOP853", "VERNER98", "Radau"])
def test_short_run_identical(method):
    fast, full = _both(conmech.systems.kepler(1.0), (0.0, 0.3), KEPLER_Y0, method=method,
                       rtol=1e-8, atol=1e-10)
    assert fast.status == 0 and fast.t.size >= 3
    _same(fast, full)


def test_more_points_than_the_room_identical():
    # more points than the arrays of the single call hold: handed over by the call-back
    k = conmech.systems.kepler(1.0)
    fast, full = _both(k, (0.0, 60.0), KEPLER_Y0, method="DOP853", rtol=1e-11, atol=1e-11)
    assert fast.t.size > solve_mod._OUT_DOUBLES // 5
    _same(fast, full)


def test_t_eval_backwards_and_fixed_step_identical():
    k = conmech.systems.kepler(1.0)
    _same(*_both(k, (0.0, 5.0), KEPLER_Y0, method="DOP853",
                 t_eval=np.linspace(0.0, 5.0, 11), rtol=1e-9))
    _same(*_both(k, (2.0, -1.0), KEPLER_Y0, method="VERNER98", rtol=1e-9, atol=1e-9))
    _same(*_both(k, (0.0, 1.0), KEPLER_Y0, method="GAUSS6", first_step=0.1))
    _same(*_both(k, (0.0, 1.0), KEPLER_Y0, method="RK4", first_step=0.05))


def test_zero_span_failure_and_stiff_identical():
    k = conmech.systems.kepler(1.0)
    fast, full = _both(k, (1.0, 1.0), KEPLER_Y0, method="DOP853")
    assert fast.t.tolist() == [1.0, 1.0]
    _same(fast, full)
    fast, full = _both(k, (0.0, 10.0), KEPLER_Y0, method="DOP853", max_steps=5)
    assert fast.status == -1 and fast.message
    _same(fast, full)
    vdp = conmech.systems.vanderpol(mu=1000.0)
    fast, full = _both(vdp, (0.0, 3000.0), [2.0, 0.0], method="Radau", rtol=1e-6,
                       atol=1e-6)
    assert fast.njev > 0 and fast.nlu > 0
    _same(fast, full)


def test_bad_input_raises_the_same():
    k = conmech.systems.kepler(1.0)
    for kw in (dict(method="RK4"), dict(rtol=-1.0), dict(max_step=0.0),
               dict(method="TAYLOR")):
        with pytest.raises(ValueError) as fast:
            conmech.solve_ivp(k, (0.0, 1.0), KEPLER_Y0, **kw)
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(solve_mod, "_solve_native", _general)
            mp.setattr(solve_mod, "_fast_solve", lambda *a: None)
            with pytest.raises(ValueError) as full:
                conmech.solve_ivp(k, (0.0, 1.0), KEPLER_Y0, **kw)
        assert str(fast.value) == str(full.value)
    with pytest.raises(ValueError, match="finite"):
        conmech.solve_ivp(k, (0.0, 1.0), [0.5, np.nan, 0.0, 1.0])
    with pytest.raises(ValueError, match="finite"):
        conmech.solve_ivp(k, (0.0, 1.0), [0.5, np.inf] + [0.0] * 2)


def test_packed_arguments_of_inconsistent_sizes_refused():
    # flat_solve_packed checks the packed arrays against the state's size: a refusal with
    # a message, never a read past an array
    from conmech import _conmech
    from conmech.ivp import native_path
    from conmech.ivp.methods import BY_NAME
    from conmech._core.status import BAD_INPUT
    k = conmech.systems.kepler(1.0)
    tol = np.full(4, 1e-8)
    fun, params, spec, ipack, rpar, n, name = native_path.prepare(
        k, BY_NAME["DOP853"].code, tol, tol, 0.0, 1e300, 1000)
    y0 = np.array(KEPLER_Y0)
    long_name = ipack.copy()
    long_name[6] = ipack.size           # a name longer than the pack holds
    for i, r, out in ((ipack, rpar[:-2], np.empty(50)), (ipack, rpar, np.empty(2*n + 1)),
                      (ipack[:6], rpar, np.empty(50)), (ipack[:-1], rpar, np.empty(50)),
                      (long_name, rpar, np.empty(50))):
        iout = np.zeros(40, dtype=np.int64)
        _conmech.flat_solve_packed(i, params, spec, r, 0.0, 1.0, y0, out, iout)
        assert iout[6] == BAD_INPUT and iout[0] == 0
        assert "inconsistent sizes" in native_path.message_text(iout[8:])
    iout = np.zeros(40, dtype=np.int64)
    out = np.empty(2*(n + 1))          # room for two points: the run's are kept for take
    _conmech.flat_solve_packed(ipack, params, spec, rpar, 0.0, 1.0, y0, out, iout)
    nt = -int(iout[0])
    assert iout[6] == 0 and nt > 2 and iout[7] != 0
    # a take that does not match the kept points copies nothing (and frees them)
    assert _conmech.flat_solve_take(int(iout[7]), n, nt + 1, np.empty((nt + 1)*(n + 1))) \
        == BAD_INPUT


def _general_callable(fun, t_span, y0, method, t_eval=None, rtol=1e-3, atol=1e-6,
                      max_steps=2**31 - 1):
    from conmech.ivp.methods import BY_NAME, RK45_SCIPY
    y0 = np.array(y0, dtype=float)
    n = y0.size
    t_ev = np.zeros(0) if t_eval is None else np.asarray(t_eval, dtype=float)
    problem = dict(fun=fun, builtin=False, args=(), t0=float(t_span[0]),
                   tf=float(t_span[1]), y0=y0, t_ev=t_ev, with_t_eval=t_eval is not None,
                   dense=False, settings=[], vectorized=False)
    code = RK45_SCIPY if method == "RK45" else BY_NAME[method.upper()].code
    common = dict(method=code, rtol=np.full(n, rtol), atol=np.full(n, atol),
                  max_step=np.finfo(float).max, max_steps=max_steps, dense=0)
    return solve_mod._solve(problem, common, 0.0, None, None)


def _kepler_rhs(t, y):
    r3 = (y[0]**2 + y[1]**2)**1.5
    return [y[2], y[3], -y[0]/r3, -y[1]/r3]


@pytest.mark.parametrize("method", ["RK45", "DOPRI5", "DOP853", "VERNER98", "Radau"])
def test_python_rhs_one_call_identical(method):
    # a Python right-hand side without events, dense output or Jacobian: one flat call
    # whose only call-back is fun gives the general path's result bit for bit
    for span, kw in (((0.0, 0.0), {}), ((0.0, 3.0), dict(rtol=1e-8, atol=1e-10)),
                     ((2.0, -1.0), dict(rtol=1e-6)),
                     ((0.0, 5.0), dict(t_eval=np.linspace(0.0, 5.0, 7), rtol=1e-9)),
                     ((0.0, 60.0), dict(rtol=1e-11, atol=1e-11)),      # points kept, taken
                     ((0.0, 10.0), dict(max_steps=5))):
        fast = conmech.solve_ivp(_kepler_rhs, span, KEPLER_Y0, method=method, **kw)
        full = _general_callable(_kepler_rhs, span, KEPLER_Y0, method, **kw)
        _same(fast, full)
    assert fast.status == -1 and fast.message


def test_python_rhs_exception_reaches_the_caller():
    class Boom(Exception):
        pass
    calls = []

    def f(t, y):
        calls.append(t)
        if len(calls) > 30:
            raise Boom("from fun")
        return -y
    with pytest.raises(Boom, match="from fun"):
        conmech.solve_ivp(f, (0.0, 60.0), KEPLER_Y0, method="DOP853", rtol=1e-12)
