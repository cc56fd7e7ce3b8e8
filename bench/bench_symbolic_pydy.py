#!/usr/bin/env python3
"""conmech.symbolic vs PyDy on the double pendulum and planar chains of N links, in one run.

The system: N point masses (m = 1) on massless rods (l = 1), absolute angles th_i from the
downward vertical, pinned at the origin, gravity g = 9.81 (N = 2 is the double pendulum).
Both tools derive it from its kinematics:
  * PyDy     sympy.physics.mechanics.KanesMethod (points, particles, the velocities of the
             chain), code generation by pydy.codegen.ode_function_generators with its
             fastest backend (cython if it builds, else lambdify), integrated by SciPy's
             solve_ivp(method="DOP853");
  * conmech  conmech.symbolic.lagrangian_system(T - U), compiled with gfortran, integrated
             by conmech.solve_ivp(DOP853), with T written two ways:
             "positions": T = sum m_i |r_i'|^2 / 2 of the same positions as PyDy's,
             "textbook":  T = 1/2 sum_ij (sum_{k >= max(i,j)} m_k) l_i l_j cos(th_i - th_j)
                          th_i' th_j' (the chain's kinetic energy as the notes write it);
             or as a multibody description like PyDy's:
             "tree":      conmech.symbolic.planar_tree (bodies on revolute joints, absolute
                          angles, point masses on massless rods, the frames as PyDy's);
                          its right-hand side is the articulated-body algorithm, O(N).
Same tolerance (rtol = atol = --tol) over [0, --tf]; both endpoints are compared with a tight
reference (conmech, rtol = atol = 1e-13) so that they are shown to reach the same accuracy.
Reported: integration wall time (best of --repeat) and the ratio PyDy/conmech, and the
construction costs: derivation, code generation + first compile, and a second construction
(cache hit for conmech; PyDy has no cache and regenerates).

This is a benchmark, not a test: it needs `pip install pydy cython` (not a dependency).

Usage:  python bench/bench_symbolic_pydy.py [--n 2 4 8 16] [--tol 1e-10] [--tf 10]
                                           [--forms positions textbook tree]
                                           [--repeat 3] [--out bench/results/symbolic_pydy.md]
"""
import argparse
import datetime
import os
import platform
import sys
import tempfile
import time
import warnings

import numpy as np


def chain_positions(N, sp, q):
    import sympy
    x = y = sympy.Integer(0)
    pos = []
    for i in range(N):
        x = x + sp["l"][i] * sympy.sin(q[i])
        y = y - sp["l"][i] * sympy.cos(q[i])
        pos.append((x, y))
    return pos


def build_conmech(N, form):
    """(system, times dict): derive + generate + compile in the current CONMECH_CACHE."""
    import sympy
    from sympy.physics.mechanics import dynamicsymbols
    from conmech import symbolic
    from conmech.symbolic.pipeline import _system
    t = dynamicsymbols._t
    q = dynamicsymbols(f"th1:{N + 1}")
    syms = {"m": sympy.symbols(f"m1:{N + 1}"), "l": sympy.symbols(f"l1:{N + 1}")}
    m, l = syms["m"], syms["l"]
    g = sympy.Symbol("g")
    T = U = 0
    if form == "positions":
        for i, (x, y) in enumerate(chain_positions(N, syms, q)):
            T += m[i] * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2
            U += m[i] * g * y
    else:
        qd = [qi.diff(t) for qi in q]
        for i in range(N):
            T += sum(m[i:]) * l[i] ** 2 * qd[i] ** 2 / 2
            U -= sum(m[i:]) * g * l[i] * sympy.cos(q[i])
            for j in range(i + 1, N):
                T += sum(m[j:]) * l[i] * l[j] * sympy.cos(q[i] - q[j]) * qd[i] * qd[j]
    params = {**{s: 1.0 for s in syms["m"]}, **{s: 1.0 for s in syms["l"]}, g: 9.81}
    if form == "tree":
        # body i hangs from the end of link i - 1 (point (0, -l) of its frame), the mass at
        # (0, -l_i) of its own frame, the frame rotated by th_i from the ground: PyDy's chain
        bodies = [symbolic.Body(f"link{i}", None if i == 0 else f"link{i - 1}", "revolute",
                                q[i], at=(0, 0) if i == 0 else (0, -l[i - 1]), mass=m[i],
                                com=(0, -l[i])) for i in range(N)]

        def construct(**kw):
            return symbolic.planar_tree(bodies, params, gravity=(0, -g),
                                        coordinates="absolute", **kw)
    else:
        def construct(**kw):
            return symbolic.lagrangian_system(T - U, q, params, **kw)
    t0 = time.perf_counter()
    model = construct(model_only=True)
    total = time.perf_counter() - t0
    system = _system(model)
    times = dict(model.times)
    times["total"] = total
    return system, times, construct


def build_pydy(N):
    """(rhs(t, x), times dict, backend) from KanesMethod + PyDy's code generator."""
    import sympy
    from sympy.physics import mechanics as me
    from pydy.codegen.ode_function_generators import generate_ode_function
    t0 = time.perf_counter()
    q = me.dynamicsymbols(f"q1:{N + 1}")
    u = me.dynamicsymbols(f"u1:{N + 1}")
    m = sympy.symbols(f"m1:{N + 1}")
    l = sympy.symbols(f"l1:{N + 1}")
    g = sympy.Symbol("g")
    A = me.ReferenceFrame("A")
    O = me.Point("O")
    O.set_vel(A, 0)
    points, particles, forces, kdes = [O], [], [], []
    for i in range(N):
        Bi = A.orientnew(f"B{i}", "Axis", [q[i], A.z])
        Bi.set_ang_vel(A, u[i] * A.z)
        Pi = points[-1].locatenew(f"P{i}", -l[i] * Bi.y)
        Pi.v2pt_theory(points[-1], A, Bi)
        points.append(Pi)
        particles.append(me.Particle(f"pa{i}", Pi, m[i]))
        forces.append((Pi, -m[i] * g * A.y))
        kdes.append(q[i].diff() - u[i])
    kane = me.KanesMethod(A, q_ind=q, u_ind=u, kd_eqs=kdes)
    kane.kanes_equations(particles, forces)
    mm, ff = kane.mass_matrix_full, kane.forcing_full
    t1 = time.perf_counter()
    consts = list(m) + list(l) + [g]
    backend = None
    rhs = None
    for gen in ("cython", "lambdify"):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                rhs = generate_ode_function(ff, q, u, consts, mass_matrix=mm, generator=gen)
            backend = gen
            break
        except Exception as exc:  # cython may not build here: fall back, and say so
            print(f"pydy backend {gen} failed: {type(exc).__name__}: {exc}", file=sys.stderr)
    t2 = time.perf_counter()
    p = np.array([1.0] * N + [1.0] * N + [9.81])

    def f(t, x):
        return rhs(x, t, p)

    return f, {"derive": t1 - t0, "generate_compile": t2 - t1, "total": t2 - t0}, backend


def best_of(fn, repeat):
    """(best wall time, best CPU time of this process, result) over `repeat` runs. The CPU
    time does not count the time the process waits for a core (other jobs on a shared
    machine), so its ratio is the steadier one there."""
    best, best_cpu, out = np.inf, np.inf, None
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        best = min(best, time.perf_counter() - t0)
        best_cpu = min(best_cpu, time.process_time() - c0)
    return best, best_cpu, out


def run(N, form, args, pydy_cache):
    import conmech
    from scipy.integrate import solve_ivp as scipy_ivp
    y0 = np.concatenate([np.linspace(0.9, 0.3, N), np.zeros(N)])
    res = {"N": N, "form": form}
    with tempfile.TemporaryDirectory() as cache:
        os.environ["CONMECH_CACHE"] = cache
        sysc, tc, construct = build_conmech(N, form)
        # a second construction of the same system: cache hit (same process)
        t0 = time.perf_counter()
        construct()
        res["conmech_hit"] = time.perf_counter() - t0
    res["conmech_times"] = tc
    if N not in pydy_cache:
        pydy_cache[N] = build_pydy(N)
    fpy, tp, backend = pydy_cache[N]
    res["pydy_times"], res["backend"] = tp, backend
    ref = conmech.solve_ivp(sysc, (0, args.tf), y0, method="DOP853", rtol=1e-13, atol=1e-13)
    assert ref.success, ref.message
    yref = ref.y[:, -1]
    kw = dict(method="DOP853", rtol=args.tol, atol=args.tol)
    tcm, ccm, rc = best_of(lambda: conmech.solve_ivp(sysc, (0, args.tf), y0, **kw),
                           args.repeat)
    tpy, cpy, rp = best_of(lambda: scipy_ivp(fpy, (0, args.tf), y0, **kw), args.repeat)
    res["cpu_conmech"], res["cpu_pydy"] = ccm, cpy
    assert rc.success and rp.success
    res["t_conmech"], res["t_pydy"] = tcm, tpy
    res["err_conmech"] = float(np.max(np.abs(rc.y[:, -1] - yref)))
    res["err_pydy"] = float(np.max(np.abs(rp.y[:, -1] - yref)))
    res["nfev_conmech"], res["nfev_pydy"] = int(rc.nfev), int(rp.nfev)
    return res


def table(rows, args):
    head = ["N", "conmech T", "PyDy backend", "conmech [s]", "PyDy [s]", "PyDy/conmech",
            "CPU: PyDy/conmech", "us/eval c/P", "err conmech", "err PyDy", "nfev c/P", "conmech derive",
            "conmech gen+compile",
            "conmech cache hit", "PyDy derive", "PyDy gen+compile"]
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        tc, tp = r["conmech_times"], r["pydy_times"]
        out.append("| " + " | ".join([
            str(r["N"]), r["form"], str(r["backend"]), f"{r['t_conmech']:.4f}", f"{r['t_pydy']:.4f}",
            f"{r['t_pydy'] / r['t_conmech']:.1f}x",
            f"{r['cpu_pydy'] / max(r['cpu_conmech'], 1e-9):.1f}x",
            f"{1e6 * r['t_conmech'] / r['nfev_conmech']:.1f}/"
            f"{1e6 * r['t_pydy'] / r['nfev_pydy']:.0f}", f"{r['err_conmech']:.1e}",
            f"{r['err_pydy']:.1e}", f"{r['nfev_conmech']}/{r['nfev_pydy']}",
            f"{tc.get('derive', float('nan')):.2f} s",
            f"{tc.get('generate', 0) + tc.get('compile_or_load', 0):.2f} s",
            f"{1e3 * r['conmech_hit']:.0f} ms", f"{tp['derive']:.2f} s",
            f"{tp['generate_compile']:.2f} s"]) + " |")
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[2, 4, 8, 16])
    ap.add_argument("--tol", type=float, default=1e-10)
    ap.add_argument("--tf", type=float, default=10.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--forms", nargs="+", default=["positions", "textbook"],
                    choices=["positions", "textbook", "tree"])
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    rows, pydy_cache = [], {}
    for N in args.n:
        for form in args.forms:
            t0 = time.perf_counter()
            r = run(N, form, args, pydy_cache)
            rows.append(r)
            print("\n".join(table([r], args)[2:]), f"  ({time.perf_counter() - t0:.0f} s)",
                  flush=True)
    lines = [f"# conmech.symbolic vs PyDy (planar N-link chain), "
             f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC", "",
             f"`python bench/bench_symbolic_pydy.py --n {' '.join(map(str, args.n))} "
             f"--forms {' '.join(args.forms)} "
             f"--tol {args.tol:g} --tf {args.tf:g} --repeat {args.repeat}` on "
             f"{platform.machine()}, {os.cpu_count()} cores (shared), Python "
             f"{platform.python_version()}.", "",
             "Integration over [0, tf] with DOP853 at rtol = atol = tol (conmech.solve_ivp "
             "on the compiled symbolic system; SciPy solve_ivp on PyDy's generated right-hand "
             "side); time = best of the repeats (wall clock; CPU: process time, which "
             "leaves out waiting for a core on a shared machine); us/eval = wall time per "
             "right-hand-side evaluation; err = max |y(tf) - y_ref(tf)| against conmech "
             "at rtol = atol = 1e-13. Construction: derivation (sympy), code generation and "
             "first compilation (fresh cache), and for conmech a second construction (cache "
             "hit).", ""] + table(rows, args) + [""]
    text = "\n".join(lines)
    print(text)
    if args.out:
        with open(args.out, "w") as fh:
            fh.write(text)


if __name__ == "__main__":
    main()
