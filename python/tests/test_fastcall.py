"""The per-call C entries of python/conmech/flat/fastcall.c (conmech._fastcall) against f2py's
wrappers of the same Fortran routines: the same numbers, bit for bit, from the same
arguments; the arguments' kinds checked with errors that name them; the module loaded
from the extension's own shared object (one copy of the Fortran library)."""
import numpy as np
import pytest
import sympy as sp

import conmech
from conmech import _conmech, symbolic
from conmech._core import fastcall
from conmech.ivp import native_path, propagator, solve_fast


def symbolic_kepler():
    x, y, u, v = sp.symbols("x y u v")
    r3 = (x**2 + y**2)**sp.Rational(3, 2)
    return symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])


def kepler_propagators(method):
    y0 = np.array([0.1, 0.0, 0.0, np.sqrt(19.0)])
    sys = symbolic_kepler() if method == "TAYLOR" else conmech.systems.kepler()
    return [conmech.Propagator(sys, y0, 0.0, method=method, rtol=1e-10, atol=1e-10)
            for _ in range(2)], y0


def test_loaded_from_the_extension_module():
    assert fastcall._module.__name__ == "conmech._fastcall"
    assert fastcall._module.__file__ == _conmech.__file__
    # the package's per-call paths run the C entries
    assert propagator._until is fastcall.until
    assert native_path._solve_kept is fastcall.solve


@pytest.mark.parametrize("method", ["DOP853", "TAYLOR", "RK45"])
def test_until_gives_f2py_numbers(method):
    (pa, pb), y0 = kepler_propagators(method)
    params = pa._packed[1] if pa._packed[1].size else native_path._PAD
    ya, yb = y0.copy(), y0.copy()
    ia, ib = np.zeros(40, np.int64), np.zeros(40, np.int64)
    t0 = 0.0
    for t1 in (0.3, 1.1, 2.9, 0.7):         # forwards, then back: the kept runs resume
        _conmech.flat_propagation_until(pa._handle, params, t0, t1, ya, ia)
        fastcall.until(pb._handle, params, t0, t1, yb, ib)
        assert ia[6] == 0 and ia[0] == 1
        assert ya.tobytes() == yb.tobytes()
        assert ia.tobytes() == ib.tobytes()
        t0 = t1


def test_solve_gives_f2py_numbers():
    (p, _), y0 = kepler_propagators("TAYLOR")
    params = p._packed[1] if p._packed[1].size else native_path._PAD
    huge = float(np.finfo(float).max)
    n = y0.size
    swapped = ">f8" if np.little_endian else "<f8"
    for y, t_eval in [(y0, None), (y0.tolist(), None), (tuple(y0), [0.5, 1.0, 2.0]),
                      (y0, np.array([0.25, 3.0])), (np.repeat(y0, 2)[::2], (1.5,)),
                      (y0.astype(swapped), np.array([0.5, 2.5], dtype=swapped))]:
        outs = []
        for f in (_conmech.flat_propagation_solve, fastcall.solve):
            out = np.zeros(200*(n + 1))
            iout = np.zeros(40, np.int64)
            if t_eval is None:
                f(p._handle, params, 0.0, 3.0, y, 0.0, huge, 10**6, 0, 0,
                  native_path._PAD, out, iout)
            else:
                f(p._handle, params, 0.0, 3.0, y, 0.0, huge, 10**6, 1, len(t_eval),
                  t_eval, out, iout)
            outs.append((out.tobytes(), iout.tobytes()))
        assert iout[6] == 0
        assert iout[0] == (len(t_eval) if t_eval is not None else 29)    # the points
        assert outs[0] == outs[1]


def test_solve_ivp_fast_entry_same_as_full_checks():
    # the fast entry (C solve) and the route of the full checks (a list t_span is not
    # the fast entry's... a numpy scalar rtol is): the same run
    sys = symbolic_kepler()
    y0 = [0.1, 0.0, 0.0, float(np.sqrt(19.0))]
    a = conmech.solve_ivp(sys, (0.0, 5.0), y0, method="TAYLOR", rtol=1e-11, atol=1e-11)
    assert solve_fast._PREPARED            # the fast entry ran (and kept its arguments)
    b = conmech.solve_ivp(sys, (0.0, 5.0), np.array(y0), method="TAYLOR",
                          rtol=np.array([1e-11]*4), atol=1e-11)
    assert a.success and b.success
    assert a.t.tobytes() == b.t.tobytes() and a.y.tobytes() == b.y.tobytes()
    assert a.nfev == b.nfev


def test_long_state_and_times_read_from_lists():
    # more numbers than the stack buffer holds: read into allocated memory
    sys = conmech.systems.kepler()
    y0 = [0.1, 0.0, 0.0, float(np.sqrt(19.0))]
    t_eval = np.linspace(0.0, 2.0, 101).tolist()
    a = conmech.solve_ivp(sys, (0.0, 2.0), y0, method="DOP853", t_eval=t_eval,
                          rtol=1e-10, atol=1e-10)
    b = conmech.solve_ivp(sys, (0.0, 2.0), y0, method="DOP853", t_eval=np.array(t_eval),
                          rtol=1e-10, atol=1e-10)
    assert a.success and a.t.size == 101
    assert a.y.tobytes() == b.y.tobytes()


@pytest.mark.parametrize("position, value, error, words", [
    (0, "1", TypeError, "handle must be an int"),
    (0, 2**70, OverflowError, "too big"),
    (1, np.zeros(1, dtype=np.int64), TypeError, "params must be an array of float64"),
    (1, np.zeros((1, 1)), ValueError, "params must be a one-dimensional"),
    (1, ["a"], TypeError, "params[0] must be a float or an int, got str"),
    (1, [True], TypeError, "params[0] must be a float or an int, got bool"),
    (1, [2**1100], OverflowError, "too large"),
    (2, "0", TypeError, "t0 must be a real number"),
    (3, None, TypeError, "t1 must be a real number"),
    (4, [0.1, 0.0, 0.0, 4.0], TypeError, "y must be a numpy array"),
    (4, np.zeros(8)[::2], ValueError, "y must be a one-dimensional contiguous array"),
    (4, np.zeros(4, dtype=np.float32), TypeError, "y must be an array of float64"),
    (4, np.zeros(4, dtype=">f8" if np.little_endian else "<f8"), ValueError,
     "y must be in the machine's byte order"),
    (5, np.zeros(8, dtype=np.int64), ValueError, "iout must have 40 entries"),
    (5, np.zeros(40), TypeError, "iout must be an array of int64"),
])
def test_until_refuses_arguments_of_other_kinds(position, value, error, words):
    (p, _), y0 = kepler_propagators("DOP853")
    args = [p._handle, native_path._PAD, 0.0, 1.0, y0.copy(), np.zeros(40, np.int64)]
    args[position] = value
    with pytest.raises(error, match=words.replace("[", r"\[").replace("]", r"\]")):
        fastcall.until(*args)
    # nothing was run: the propagation still works
    y = y0.copy()
    iout = np.zeros(40, np.int64)
    fastcall.until(p._handle, native_path._PAD, 0.0, 1.0, y, iout)
    assert iout[6] == 0 and iout[0] == 1


def test_read_only_outputs_and_argument_counts_refused():
    (p, _), y0 = kepler_propagators("DOP853")
    y = y0.copy()
    y.flags.writeable = False
    with pytest.raises(ValueError, match="y must be writeable"):
        fastcall.until(p._handle, native_path._PAD, 0.0, 1.0, y, np.zeros(40, np.int64))
    with pytest.raises(TypeError, match="takes 6 positional arguments"):
        fastcall.until(p._handle, native_path._PAD, 0.0, 1.0, y0.copy())
    with pytest.raises(TypeError, match="takes 13 positional arguments"):
        fastcall.solve(p._handle)
    with pytest.raises(ValueError, match="max_steps = .* is out of range"):
        fastcall.solve(p._handle, native_path._PAD, 0.0, 1.0, y0, 0.0, 1.0, 2**40, 0, 0,
                       native_path._PAD, np.zeros(100), np.zeros(40, np.int64))


def test_wrong_state_size_is_the_routines_refusal():
    # sizes are the Fortran routine's to check, as through f2py: a refusal in iout
    (p, _), y0 = kepler_propagators("DOP853")
    y = np.zeros(3)
    iout = np.zeros(40, np.int64)
    fastcall.until(p._handle, native_path._PAD, 0.0, 1.0, y, iout)
    assert iout[6] == conmech._core.status.BAD_INPUT
    assert (y == 0).all()


def test_no_memory_kept_by_list_reads_and_refusals():
    # the buffers of long lists (beyond the stack's) and the copies of strided arrays are
    # freed on every path, the refusals' included (tracemalloc sees PyMem_Malloc)
    import tracemalloc
    (p, _), y0 = kepler_propagators("TAYLOR")
    huge = float(np.finfo(float).max)
    t_eval = np.linspace(0.0, 2.0, 300).tolist()
    strided = np.repeat(np.array(t_eval), 2)[::2]
    bad = t_eval[:-1] + ["x"]
    y0l = y0.tolist()
    out = np.zeros(400*5)
    right = [0]     # refusals with the expected message (a count: no list that grows)

    def calls():
        for te in (t_eval, strided):
            iout = np.zeros(40, np.int64)
            fastcall.solve(p._handle, native_path._PAD, 0.0, 2.0, y0l, 0.0, huge, 10**6, 1,
                           len(te), te, out, iout)
            assert iout[6] == 0 and iout[0] == 300
            try:
                fastcall.solve(p._handle, native_path._PAD, 0.0, 2.0, y0l, 0.0, huge, 10**6,
                               1, len(te), te, out, iout[:8])
            except ValueError as e:
                right[0] += str(e) == "iout must have 40 entries, got 8"
        try:
            fastcall.solve(p._handle, native_path._PAD, 0.0, 2.0, y0, 0.0, huge, 10**6, 1,
                           300, bad, out, np.zeros(40, np.int64))
        except TypeError as e:
            right[0] += str(e) == "t_eval[299] must be a float or an int, got str"

    calls()
    tracemalloc.start()
    try:
        calls()
        before = tracemalloc.get_traced_memory()[0]
        for _ in range(200):
            calls()
        growth = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    assert right[0] == 3*202
    assert growth < 1000        # 200 rounds of 2.4 kB buffers and copies: none kept
