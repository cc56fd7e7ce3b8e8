#!/usr/bin/env python3
"""conmech against Pinocchio (the reference for rigid-body algorithms, ``pip install pin``:
for this benchmark only, never a dependency) on the same seven-joint arm read from the
same URDF file (conmech/symbolic/data/arm7.urdf), in one run:

1. agreement: accelerations (conmech_accel vs pinocchio.aba), their Jacobian
   (conmech_accel_jac vs computeABADerivatives), M (crba) and the bias forces (rnea);
2. per evaluation: forward dynamics and its derivatives, as callgrind instruction counts
   per call (a C harness dlopens conmech's model library; a C++ harness rebuilds the arm
   from the joint placements and inertias pinocchio's own URDF parser produced and calls
   pinocchio's C++ functions; both built with -O3 -DNDEBUG, the counts are (I(2R) -
   I(R))/R) and as same-run wall-time ratios of the two harnesses (median, min and max
   over --repeat runs);
3. construction, --build-repeat times: the arm from the URDF, a 30-joint chain and a
   30-body branched tree (derivation, generation, compilation into an empty cache; CPU
   time of this process and of the compiler, the load average), and cache hits;
4. a 10 s simulation at rtol = atol = 1e-10 (DOP853 both; the URDF's joint damping on):
   conmech.solve_ivp of the compiled arm against scipy.integrate.solve_ivp driving
   pinocchio.aba from Python; CPU time (best of --sim-repeat), nfev, final states.

Writes bench/results/pinocchio.md (--out). Needs gcc/g++ and valgrind for item 2 (the
C++ harness also needs Eigen's headers: ``pip install cmeel-eigen`` beside ``pin``).

Usage: python bench/bench_pinocchio.py [--repeat 7] [--reps 20000] [--sim-repeat 3]
                                      [--build-repeat 3] [--construction-only]
"""
import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def cpu():
    s = resource.getrusage(resource.RUSAGE_SELF)
    c = resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime, c.ru_utime + c.ru_stime


def timed_build(build):
    """(result, wall, own CPU, compiler CPU)."""
    w0, (p0, c0) = time.perf_counter(), cpu()
    r = build()
    w1, (p1, c1) = time.perf_counter(), cpu()
    return r, w1 - w0, p1 - p0, c1 - c0


def chain(n, branched=False):
    """A 30-joint test tree: revolute joints about z, y, x in turn (a prismatic joint
    every seventh), offsets, COM offsets, diagonal inertias; `branched`: 5 arms of n/5
    bodies on a common root body."""
    import sympy as sp
    from sympy.physics.mechanics import dynamicsymbols
    from conmech.symbolic import SpatialBody
    qs = dynamicsymbols(f"b1:{n + 1}")
    axes = [(0, 0, 1), (0, 1, 0), (1, 0, 0)]
    bodies = []
    per = max(n // 5, 1)
    for i in range(n):
        if branched:
            parent = None if i == 0 else ("l0" if (i - 1) % per == 0 else f"l{i - 1}")
        else:
            parent = None if i == 0 else f"l{i - 1}"
        bodies.append(SpatialBody(
            f"l{i}", parent, "prismatic" if i % 7 == 3 else "revolute", qs[i],
            axis=axes[i % 3], at=(0, 0.02*(i % 2), -0.2) if i else (0, 0, 0),
            mass=1 + 0.1*(i % 4), com=(0.01, 0, -0.1),
            inertia=[[0.004, 0, 0], [0, 0.004, 0], [0, 0, 0.001 + 0.0005*(i % 3)]]))
    g = sp.Symbol("g")
    return bodies, {g: 9.81}, (0, 0, -g)


def build_harnesses(work, pin_model):
    """(conmech harness, pinocchio harness or None, message)."""
    cc = shutil.which("gcc") or shutil.which("cc")
    cxx = shutil.which("g++")
    if cc is None:
        return None, None, "no C compiler"
    ch = os.path.join(work, "conmech_harness")
    subprocess.run([cc, "-O3", "-o", ch, os.path.join(HERE, "pinocchio", "conmech_harness.c"),
                    "-ldl"], check=True)
    import pinocchio
    # the wheel's prefix: .../cmeel.prefix/lib/pythonX.Y/site-packages/pinocchio/
    prefix = os.path.abspath(pinocchio.__file__)
    while prefix != os.path.dirname(prefix) and os.path.basename(prefix) != "cmeel.prefix":
        prefix = os.path.dirname(prefix)
    if not (cxx and os.path.isdir(os.path.join(prefix, "include", "pinocchio"))
            and os.path.isdir(os.path.join(prefix, "include", "eigen3"))):
        return ch, None, ("no C++ harness (needs g++, the pin wheel's headers and Eigen's: "
                          "pip install cmeel-eigen)")
    ph = os.path.join(work, "pinocchio_harness")
    cmd = [cxx, "-O3", "-DNDEBUG", "-std=c++17", "-DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS",
           "-DBOOST_MPL_LIMIT_LIST_SIZE=30", "-DBOOST_MPL_LIMIT_VECTOR_SIZE=30",
           f"-I{prefix}/include", f"-I{prefix}/include/eigen3", "-o", ph,
           os.path.join(HERE, "pinocchio", "pinocchio_harness.cpp"), f"-L{prefix}/lib",
           "-lpinocchio_default", f"-Wl,-rpath,{prefix}/lib"]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        return ch, None, "the C++ harness did not build: " + r.stderr[-400:]
    # the model as pinocchio's URDF parser built it
    txt = os.path.join(work, "arm7_pinocchio.txt")
    kinds = {"JointModelRX": "RX", "JointModelRY": "RY", "JointModelRZ": "RZ",
             "JointModelPX": "PX", "JointModelPY": "PY", "JointModelPZ": "PZ"}
    with open(txt, "w") as fh:
        fh.write(f"{pin_model.njoints - 1}\n")
        for i in range(1, pin_model.njoints):
            kind = kinds[pin_model.joints[i].shortname()]
            P, I = pin_model.jointPlacements[i], pin_model.inertias[i]
            vals = ([pin_model.parents[i]] + list(P.rotation.ravel()) + list(P.translation)
                    + [I.mass] + list(I.lever) + list(I.inertia.ravel()))
            fh.write(kind + " " + " ".join(repr(float(x)) for x in vals) + "\n")
    return ch, (ph, txt), ""


def instructions(cmd):
    out = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null"]
                         + cmd, capture_output=True, text=True)
    for line in out.stderr.splitlines():
        if "Collected" in line:
            return int(line.split()[-1])
    raise RuntimeError("callgrind failed: " + out.stderr[-300:])


def per_call(cmd_of_reps, reps):
    return (instructions(cmd_of_reps(2*reps)) - instructions(cmd_of_reps(reps))) / reps


def wall(cmd):
    return float(subprocess.run(cmd, capture_output=True, text=True,
                                check=True).stdout.split()[1])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7, help="wall-time repeats")
    ap.add_argument("--reps", type=int, default=20000, help="calls per timed run")
    ap.add_argument("--sim-repeat", type=int, default=3)
    ap.add_argument("--skip-callgrind", action="store_true")
    ap.add_argument("--build-repeat", type=int, default=3, help="builds of each system")
    ap.add_argument("--construction-only", action="store_true",
                    help="only the construction table (printed, not written)")
    ap.add_argument("--out", default=os.path.join(HERE, "results", "pinocchio.md"))
    a = ap.parse_args()
    try:
        import pinocchio as pin
    except ImportError:
        sys.exit("bench_pinocchio.py needs pinocchio: pip install pin")
    work = tempfile.mkdtemp(prefix="bench_pin_")
    os.environ["CONMECH_CACHE"] = os.path.join(work, "cache")
    import conmech
    from conmech import symbolic
    from conmech.symbolic.urdf import data_path
    from scipy.integrate import solve_ivp as scipy_ivp
    urdf = data_path("arm7.urdf")
    lines = ["# conmech vs Pinocchio: the same 7-joint arm from the same URDF", "",
             f"`python bench/bench_pinocchio.py` ({time.strftime('%Y-%m-%d')}; pinocchio "
             f"{pin.__version__}; load average at the start "
             f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs). Arm: "
             "`conmech/symbolic/data/arm7.urdf` (7 revolute joints, a fixed hand).", ""]
    # ---- construction: --build-repeat builds of each system, each into an empty cache
    def fresh_cache(k):
        os.environ["CONMECH_CACHE"] = os.path.join(work, f"cache{k}")

    def arm():
        return symbolic.from_urdf(urdf, torques=None, damping=False, model_only=True)
    trees = {label: chain(30, branched) for label, branched in
             (("30-joint chain", False), ("30-body branched tree", True))}
    runs = {"arm7": [], "30-joint chain": [], "30-body branched tree": []}
    hits = []
    for k in range(a.build_repeat):
        fresh_cache(k)
        load = os.getloadavg()[0]
        model, w, pc, cc = timed_build(arm)
        runs["arm7"].append((w, pc, cc, model.times, len(model.source.splitlines()), load))
        hits.append(timed_build(arm)[1])
        for label, (b, p, g) in trees.items():
            load = os.getloadavg()[0]
            m30, w, pc, cc = timed_build(lambda: symbolic.spatial_tree(b, p, gravity=g,
                                                                       model_only=True))
            runs[label].append((w, pc, cc, m30.times, len(m30.source.splitlines()), load))
    # `model`: the arm of the last build, used below
    # ---- construction table
    ctable = ["## Construction", "",
              f"{a.build_repeat} builds of each system, each into an empty cache; per build: "
              "wall time, CPU time of this process (derivation, generation) and of the "
              "compiler (gfortran -O3), and the load average when it started. The load of "
              "the shared machine inflates the wall time most; the CPU times less.", "",
              "| system | build | load | wall | CPU Python | CPU gfortran | CPU total "
              "| lines of Fortran |", "|---|---|---|---|---|---|---|---|"]
    for label, rs in runs.items():
        name = "arm7 from the URDF" if label == "arm7" else label
        for k, (w, pc, cc, tm, nl, load) in enumerate(rs):
            ctable.append(f"| {name} | {k + 1} | {load:.1f} | {w:.2f} s | {pc:.2f} s | "
                          f"{cc:.2f} s | {pc + cc:.2f} s | {nl} |")
    ctable += ["", "Cache hits (the arm again from the URDF, same process; parsing the "
               "document, building the tree and its cache key, loading the library): "
               + ", ".join(f"{h*1e3:.0f} ms" for h in hits) + ".", ""]
    if a.construction_only:
        print("\n".join(lines[:4] + ctable))
        return
    # ---- agreement
    pm = pin.buildModelFromUrdf(urdf)
    pd = pm.createData()
    rng = np.random.default_rng(1)
    err = dict(a=0.0, J=0.0, M=0.0, Q=0.0)
    for _ in range(20):
        q, v = rng.uniform(-2, 2, 7), rng.uniform(-2, 2, 7)
        tau = np.zeros(7)
        ap_ = pin.aba(pm, pd, q, v, tau)
        ac, J = model.call("accel_jac", 0.0, q, v)
        pin.computeABADerivatives(pm, pd, q, v, tau)
        Jp = np.hstack([pd.ddq_dq, pd.ddq_dv])
        M = pin.crba(pm, pd, q)
        M = np.triu(M) + np.triu(M, 1).T
        err["a"] = max(err["a"], np.max(np.abs(model.call("accel", 0.0, q, v) - ap_))
                       / np.max(np.abs(ap_)))
        err["J"] = max(err["J"], np.max(np.abs(J - Jp))/np.max(np.abs(Jp)))
        err["M"] = max(err["M"], np.max(np.abs(model.call("mass", 0.0, q) - M))
                       / np.max(np.abs(M)))
        bias = pin.rnea(pm, pd, q, v, np.zeros(7))
        err["Q"] = max(err["Q"], np.max(np.abs(model.call("forces", 0.0, q, v) + bias))
                       / np.max(np.abs(bias)))
    lines += ["## Agreement (20 random states, max relative difference)", "",
              "| accelerations (aba) | d a/d[q, v] (computeABADerivatives) | M (crba) | "
              "bias forces (rnea) |", "|---|---|---|---|",
              f"| {err['a']:.1e} | {err['J']:.1e} | {err['M']:.1e} | {err['Q']:.1e} |", ""]
    # ---- per evaluation
    ch, ph, msg = build_harnesses(work, pm)
    lib, npar = model.path, len(model.derived.param_values)
    g0 = str(model.derived.param_values[0]) if npar else "0"

    def ccmd(which):
        return lambda r: [ch, lib, "7", str(r), str(which), str(npar), g0]

    def pcmd(which):
        return lambda r: [ph[0], ph[1], str(r), str(which)]
    lines += ["## Per evaluation", ""]
    if msg:
        lines += [f"({msg})", ""]
    if ch and ph:
        if not a.skip_callgrind and shutil.which("valgrind"):
            ic = {w_: per_call(ccmd(w_), 2000) for w_ in (0, 1)}
            ip = {w_: per_call(pcmd(w_), 2000) for w_ in (0, 1)}
            lines += ["Callgrind instructions per call (C harness on conmech's generated "
                      "library, flags -O3 -fPIC; C++ harness on pinocchio's library from "
                      "the wheel, -O3 -DNDEBUG):", "",
                      "| | conmech | Pinocchio | ratio |", "|---|---|---|---|",
                      f"| forward dynamics (accel / aba) | {ic[0]:,.0f} | {ip[0]:,.0f} | "
                      f"{ic[0]/ip[0]:.3f} |",
                      f"| derivatives (accel_jac / computeABADerivatives) | {ic[1]:,.0f} | "
                      f"{ip[1]:,.0f} | {ic[1]/ip[1]:.3f} |", ""]
        ratios = {0: [], 1: []}
        for _ in range(a.repeat):
            for w_ in (0, 1):
                tc = wall(ccmd(w_)(a.reps))
                tp = wall(pcmd(w_)(a.reps))
                ratios[w_].append((tc/tp, tc/a.reps, tp/a.reps))
        lines += [f"Wall time, same run, {a.repeat} repeats of {a.reps} calls each "
                  "(ratio conmech / Pinocchio: median [min, max]; per call: medians):", "",
                  "| | ratio | conmech | Pinocchio |", "|---|---|---|---|"]
        for w_, name in ((0, "forward dynamics"), (1, "derivatives")):
            r = [x[0] for x in ratios[w_]]
            lines.append(f"| {name} | {statistics.median(r):.3f} [{min(r):.3f}, "
                         f"{max(r):.3f}] | {statistics.median(x[1] for x in ratios[w_])*1e6:.2f}"
                         f" us | {statistics.median(x[2] for x in ratios[w_])*1e6:.2f} us |")
        lines.append("")
    lines += ctable
    # ---- simulation
    sysm = symbolic.from_urdf(urdf, torques=None, damping=True)
    damp = symbolic.read_urdf(urdf).damping
    y0 = np.concatenate([[0.3, -0.5, 0.2, -1.8, 0.1, 1.2, 0.4], np.zeros(7)])
    tol = 1e-10

    def rhs(t, y):
        q, v = y[:7], y[7:]
        return np.concatenate([v, pin.aba(pm, pd, q, v, -damp*v)])
    best_c = best_s = np.inf
    for _ in range(a.sim_repeat):
        c0 = time.process_time()
        rc = conmech.solve_ivp(sysm, (0, 10), y0, method="DOP853", rtol=tol, atol=tol)
        best_c = min(best_c, time.process_time() - c0)
        c0 = time.process_time()
        rs = scipy_ivp(rhs, (0, 10), y0, method="DOP853", rtol=tol, atol=tol)
        best_s = min(best_s, time.process_time() - c0)
    assert rc.success and rs.success
    lines += ["## 10 s simulation, DOP853, rtol = atol = 1e-10", "",
              "From q = (0.3, -0.5, 0.2, -1.8, 0.1, 1.2, 0.4) at rest, no torques, the "
              "URDF's joint damping (-c q').", "",
              "| | CPU time (best of {}) | nfev |".format(a.sim_repeat), "|---|---|---|",
              f"| conmech.solve_ivp (compiled arm) | {best_c*1e3:.1f} ms | {rc.nfev} |",
              f"| SciPy solve_ivp + pinocchio.aba | {best_s*1e3:.1f} ms | {rs.nfev} |", "",
              f"Ratio {best_c/best_s:.3f}; final states differ by "
              f"{np.max(np.abs(rc.y[:, -1] - rs.y[:, -1])):.1e} (max abs).", ""]
    text = "\n".join(lines)
    print(text)
    if a.out:
        with open(a.out, "w") as fh:
            fh.write(text)
    shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
