"""Record what every built-in system computes, for comparing two implementations of them.

    python tools/builtin_reference.py -o python/tests/data/builtin_reference.npz

For each built-in of the Fortran registries (first-order, generalized-coordinate and
constrained), at fixed pseudo-random states: f and the Jacobian (first-order form), M, Q,
the energy, and for constrained systems phi, G, gamma_h, A, b, gamma_n; and short
trajectories from a fixed initial state with their step counts: DOP853 at rtol = atol =
1e-10 (explicit: the Jacobian plays no part), Radau at 1e-8 (first-order and generalized
systems) and conmech.constrained.solve with the default projection (constrained ones).

python/tests/test_builtin_systems.py compares the installed package with the file written
here: the committed file was recorded from the hand-written Fortran systems that the
generated ones replaced (src/systems before tools/generate_builtins.py), so the test shows
that the generated systems compute the same to round-off.
"""
import argparse

import numpy as np

import conmech
from conmech import constrained, systems
from conmech.compiled import evaluate

#: first-order systems (factory, y0, t_end)
FIRST_ORDER = {
    "harmonic": (systems.harmonic(1.3), [1.0, 0.2], 5.0),
    "pendulum": (systems.pendulum(9.81, 0.7), [1.0, 0.3], 3.0),
    "kepler": (systems.kepler(1.1), [1.0, 0.0, 0.1, 1.2], 6.0),
    "arenstorf": (systems.arenstorf(), [0.994, 0.0, 0.0, -2.00158510637908252240537862224],
                  3.0),
    "vanderpol": (systems.vanderpol(2.0), [2.0, 0.0], 5.0),
    "hill": (systems.hill(), [0.5, 0.0, 0.0, 0.4], 2.0),
}
#: generalized-coordinate systems, each with parameters that are not all the defaults
GENERALIZED = {
    "pendulum_angle": [1.2, 9.81, 0.8],
    "cart_pendulum": [1.5, 0.7, 0.9, 9.81],
    "double_pendulum": [1.0, 1.3, 1.1, 0.8, 9.81],
    "atwood": [2.0, 1.5, 9.81],
    "spring_pendulum": [1.1, 35.0, 1.0, 9.81],
    "double_spring_pendulum": [1.0, 1.2, 40.0, 30.0, 1.0, 0.9, 9.81],
    "three_springs": [1.0, 10.0, 1.0],
    "bead_hoop": [1.0, 1.2, 5.0, 9.81],
    "polar_particle": [1.0, 1.3],
    "pendulum_moving": [1.0, 9.81, 1.0, 0.3, 0.1, 3.0],
    "yoyo_angle": [1.0, 0.05, 1.25e-3, 9.81, 0.2, 0.1, 0.0],
}
#: constrained systems (excessive coordinates)
CONSTRAINED = {
    "pendulum_xy": [1.2, 9.81, 0.9],
    "rod_two_masses": [9.81, 1.1],
    "double_pendulum_xy": [1.0, 1.3, 1.1, 0.8, 9.81],
    "atwood_xy": [2.0, 1.5, 9.81, 2.0],
    "pendulum_moving_xy": [1.0, 9.81, 1.0, 0.3, 0.1, 3.0],
    "yoyo": [1.0, 0.05, 1.25e-3, 9.81, 0.2, 0.1, 0.0],
    "skate": [1.0, 1.2, 9.81, 0.3],
    "rolling_disk": [1.0, 1.1, 0.5, 0.25],
    "rolling_ball": [1.0, 1.0, 0.4, 9.81, 0.2],
    "pendulum_chain_xy": [5, 1.0, 1.0, 9.81],
}
T_END_MECH = 2.0
N_STATES = 4


def _states(rng, n, scale=1.0):
    """N_STATES states (q, v) of n coordinates away from singular points."""
    q = 0.3 + rng.random((N_STATES, n))*scale
    v = rng.standard_normal((N_STATES, n))*0.7
    return q, v


def record():
    out = {}
    rng = np.random.default_rng(20240522)
    t_eval = lambda t1: np.linspace(0.0, t1, 11)   # noqa: E731
    for name, (sys_, y0, t1) in FIRST_ORDER.items():
        y0 = np.array(y0)
        ys = 0.5 + rng.random((N_STATES, y0.size))
        out[f"{name}/states"] = ys
        out[f"{name}/f"] = np.array([evaluate(sys_, 0.3, y)["f"] for y in ys])
        out[f"{name}/jac"] = np.array([evaluate(sys_, 0.3, y)["jac"] for y in ys])
        _trajectories(out, name, sys_, y0, t1, t_eval(t1))
    for name, params in GENERALIZED.items():
        sys_ = systems.BuiltinSystem(name, params)
        n = sys_.dimension//2
        q, v = _states(rng, n)
        out[f"{name}/q"], out[f"{name}/v"] = q, v
        out[f"{name}/f"] = np.array([evaluate(sys_, 0.3, np.r_[a, b])["f"]
                                     for a, b in zip(q, v)])
        out[f"{name}/jac"] = np.array([evaluate(sys_, 0.3, np.r_[a, b])["jac"]
                                       for a, b in zip(q, v)])
        _mech(out, name, sys_, q, v)
        y0 = np.r_[q[0], 0.1*v[0]] if name not in ("three_springs", "polar_particle") else \
            _default_state(name, params)
        _trajectories(out, name, sys_, y0, T_END_MECH, t_eval(T_END_MECH))
    for name, params in CONSTRAINED.items():
        sys_ = constrained.builtin(name, params)
        q, v = _states(rng, sys_.n)
        out[f"{name}/q"], out[f"{name}/v"] = q, v
        _mech(out, name, sys_, q, v)
        q0, v0 = sys_.initial_state()
        out[f"{name}/q0"], out[f"{name}/v0"] = q0, v0
        te = t_eval(T_END_MECH)
        r = constrained.solve(sys_, (0.0, T_END_MECH), rtol=1e-10, atol=1e-10, t_eval=te)
        assert r.success, (name, r.message)
        for key in ("q", "v", "lam", "energy"):
            out[f"{name}/solve_{key}"] = np.asarray(r[key])
        out[f"{name}/solve_counts"] = np.array([r.nfev, r.naccept, r.nreject, r.nproj])
    return out


def _default_state(name, params):
    sys_ = systems.BuiltinSystem(name, params)
    n = sys_.dimension//2
    from conmech import _conmech
    q0, v0, info = _conmech.flat_mech_initial_state(name, len(params), np.array(params), n)
    assert info == 0
    return np.r_[q0, v0]


def _mech(out, name, sys_, q, v):
    keys = ("M", "Q", "energy", "phi", "G", "gamma_h", "A", "b", "gamma_n")
    vals = {k: [] for k in keys}
    for a, b in zip(q, v):
        e = evaluate(sys_, 0.3, a, b)
        for k in keys:
            x = e.get(k)
            vals[k].append(np.nan if x is None else x)
    for k in keys:
        if any(isinstance(x, np.ndarray) and x.size == 0 for x in vals[k]):
            continue
        if k in e or k == "energy":
            out[f"{name}/{k}"] = np.array(vals[k], dtype=float)


#: name -> the number of DOP853 steps of its trajectory that hold a point of t_eval
#: (filled by record(); not part of the recorded file)
DENSE_STEPS = {}


def _trajectories(out, name, sys_, y0, t1, te):
    out[f"{name}/y0"] = y0
    r = conmech.solve_ivp(sys_, (0.0, t1), y0, method="DOP853", rtol=1e-10, atol=1e-10,
                          t_eval=te)
    assert r.success, (name, r.message)
    out[f"{name}/dop853_y"] = r.y
    out[f"{name}/dop853_counts"] = np.array([r.nfev, r.naccept, r.nreject])
    # the steps whose continuous extension t_eval reads (a point strictly inside): DOP853's
    # three extra stages are spent on those steps alone (the hand-written systems were
    # recorded by a driver that spent them on every step)
    steps = conmech.solve_ivp(sys_, (0.0, t1), y0, method="DOP853", rtol=1e-10,
                              atol=1e-10).t
    DENSE_STEPS[name] = sum(bool(np.any((te > a) & (te < b)))
                            for a, b in zip(steps[:-1], steps[1:]))
    r = conmech.solve_ivp(sys_, (0.0, t1), y0, method="Radau", rtol=1e-8, atol=1e-8,
                          t_eval=te)
    assert r.success, (name, r.message)
    out[f"{name}/radau_y"] = r.y
    out[f"{name}/radau_counts"] = np.array([r.nfev, r.njev, r.nlu, r.naccept, r.nreject])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", required=True)
    a = ap.parse_args()
    np.savez_compressed(a.output, **record())


if __name__ == "__main__":
    main()
