"""Work-precision diagrams: error against run time over tolerances 1e-4 .. 1e-14 for the
Arenstorf orbit (one period), Kepler e = 0.9 (one period, error = closure |y(T) - y0|,
exact) and the Cartesian double pendulum (t = 10, error in the positions x1, y1, x2, y2),
conmech's methods beside SciPy's and heyoka's. conmech integrates the double pendulum in
Cartesian coordinates with its two constraints (conmech.constrained.solve, built-in system,
position + velocity projection); SciPy and heyoka integrate the same motion in the angles
(an ODE they can take), mapped to the same positions. The Arenstorf and double-pendulum
references are VERNER98 runs at 1e-15, checked against heyoka at 1e-16 (they agree to
1.6e-10 and 1.2e-13: the Arenstorf orbit amplifies round-off, which sets its error floor).

conmech runs its built-in systems (no Python in the loop) where they exist (Arenstorf,
Kepler) and a Python right-hand side otherwise (double pendulum, like SciPy); heyoka is a
compiled Taylor integrator (its JIT compilation is not timed). Times are the best of
`REPEAT` runs. Needs matplotlib, scipy and heyoka (pip install heyoka: benchmark only).

    python bench/work_precision.py      # writes bench/results/work_precision_*.png and .md
"""
import pathlib
import time

import numpy as np
import scipy.integrate as si

import conmech

REPEAT = 3
TOLS = [10.0 ** (-k) for k in range(4, 15)]
OUT = pathlib.Path(__file__).resolve().parent / "results"

try:
    import heyoka as hy
except ImportError:      # the diagrams are drawn without heyoka's curve
    hy = None


def best_time(run):
    best, res = np.inf, None
    for _ in range(REPEAT):
        t0 = time.perf_counter()
        res = run()
        best = min(best, time.perf_counter() - t0)
    return best, res


# ------------------------------------------------------------------ problems
MU_A = 0.012277471
Y0_A = np.array([0.994, 0.0, 0.0, -2.00158510637908252240537862224])
T_A = 17.0652165601579625588917206249


def f_arenstorf(t, y):
    mp = 1.0 - MU_A
    d1 = ((y[0] + MU_A) ** 2 + y[1] ** 2) ** 1.5
    d2 = ((y[0] - mp) ** 2 + y[1] ** 2) ** 1.5
    return [y[2], y[3], y[0] + 2 * y[3] - mp * (y[0] + MU_A) / d1 - MU_A * (y[0] - mp) / d2,
            y[1] - 2 * y[2] - mp * y[1] / d1 - MU_A * y[1] / d2]


E_K = 0.9
Y0_K = np.array([1.0 - E_K, 0.0, 0.0, np.sqrt((1 + E_K) / (1 - E_K))])
T_K = 2 * np.pi


def f_kepler(t, y):
    r3 = (y[0] ** 2 + y[1] ** 2) ** 1.5
    return [y[2], y[3], -y[0] / r3, -y[1] / r3]


G = 9.81
Y0_D = np.array([2.0, 1.5, 0.0, 0.0])     # theta1, theta2 (from the vertical), rates
T_D = 10.0


def f_double(t, y):
    t1, t2, w1, w2 = y
    d = t1 - t2
    den = 3.0 - np.cos(2 * d)               # m1 = m2 = l1 = l2 = 1
    a1 = (-3 * G * np.sin(t1) - G * np.sin(t1 - 2 * t2)
          - 2 * np.sin(d) * (w2 ** 2 + w1 ** 2 * np.cos(d))) / den
    a2 = (2 * np.sin(d) * (2 * w1 ** 2 + 2 * G * np.cos(t1) + w2 ** 2 * np.cos(d))) / den
    return [w1, w2, a1, a2]


def positions(y):
    """(x1, y1, x2, y2) of the double pendulum from (theta1, theta2, ...), y downwards."""
    x1, y1 = np.sin(y[0]), -np.cos(y[0])
    return np.array([x1, y1, x1 + np.sin(y[1]), y1 - np.cos(y[1])])


def cartesian_state(y):
    q = positions(y)
    vx1, vy1 = y[2] * np.cos(y[0]), y[2] * np.sin(y[0])
    v = np.array([vx1, vy1, vx1 + y[3] * np.cos(y[1]), vy1 + y[3] * np.sin(y[1])])
    return q, v


def heyoka_system(name):
    if name == "arenstorf":
        x, y, vx, vy = hy.make_vars("x", "y", "vx", "vy")
        mp = 1.0 - MU_A
        d1 = ((x + MU_A) ** 2 + y ** 2) ** 1.5
        d2 = ((x - mp) ** 2 + y ** 2) ** 1.5
        return [(x, vx), (y, vy),
                (vx, x + 2 * vy - mp * (x + MU_A) / d1 - MU_A * (x - mp) / d2),
                (vy, y - 2 * vx - mp * y / d1 - MU_A * y / d2)]
    if name == "kepler":
        x, y, vx, vy = hy.make_vars("x", "y", "vx", "vy")
        r3 = (x ** 2 + y ** 2) ** 1.5
        return [(x, vx), (y, vy), (vx, -x / r3), (vy, -y / r3)]
    t1, t2, w1, w2 = hy.make_vars("t1", "t2", "w1", "w2")
    d = t1 - t2
    den = 3.0 - hy.cos(2 * d)
    return [(t1, w1), (t2, w2),
            (w1, (-3 * G * hy.sin(t1) - G * hy.sin(t1 - 2 * t2)
                  - 2 * hy.sin(d) * (w2 ** 2 + w1 ** 2 * hy.cos(d))) / den),
            (w2, (2 * hy.sin(d) * (2 * w1 ** 2 + 2 * G * hy.cos(t1) + w2 ** 2 * hy.cos(d)))
             / den)]


def reference(name, f, y0, T):
    r = conmech.solve_ivp(f, (0, T), y0, method="VERNER98", rtol=1e-15, atol=1e-15)
    ref = r.y[:, -1]
    if hy is not None:
        ta = hy.taylor_adaptive(heyoka_system(name), y0.copy(), tol=1e-16)
        ta.propagate_until(T)
        print(f"{name} reference: VERNER98 at 1e-15 and heyoka at 1e-16 differ by "
              f"{np.max(np.abs(ta.state - ref)):.1e}")
    return ref


PROBLEMS = {
    "arenstorf": dict(f=f_arenstorf, builtin=conmech.systems.arenstorf(), y0=Y0_A, T=T_A,
                      title="Arenstorf orbit, one period"),
    "kepler": dict(f=f_kepler, builtin=conmech.systems.kepler(), y0=Y0_K, T=T_K,
                   title="Kepler e = 0.9, one period (closure error)"),
    "double_pendulum": dict(f=f_double, builtin=None, y0=Y0_D, T=T_D,
                            title="Cartesian double pendulum, t = 10 (positions)"),
}


def run_problem(name, p):
    if name == "kepler":
        ref = p["y0"]
    else:
        ref = reference("double" if name == "double_pendulum" else name, p["f"], p["y0"],
                        p["T"])
    curves = {}

    def add(label, tol, seconds, y):
        err = float(np.max(np.abs(np.asarray(y) - ref)))
        curves.setdefault(label, []).append((tol, seconds, err))

    cart = name == "double_pendulum"
    if cart:
        ref = positions(ref)
        q0, v0 = cartesian_state(p["y0"])
        sys_xy = conmech.systems.double_pendulum_xy()
    for tol in TOLS:
        for m in ("DOP853", "DOPRI5", "VERNER98"):
            if m == "DOPRI5" and tol < 1e-11:
                continue
            if cart:
                s, r = best_time(lambda: conmech.constrained.solve(
                    sys_xy, (0, p["T"]), q0, v0, method=m, rtol=tol, atol=tol))
                add(f"conmech {m} (Cartesian, projected)", tol, s, r.q[:, -1])
                continue
            s, r = best_time(lambda: conmech.solve_ivp(p["builtin"], (0, p["T"]), p["y0"],
                                                       method=m, rtol=tol, atol=tol))
            add(f"conmech {m} (built-in)", tol, s, r.y[:, -1])
        for m in ("DOP853", "RK45"):
            if m == "RK45" and tol < 1e-11:
                continue
            s, r = best_time(lambda: si.solve_ivp(p["f"], (0, p["T"]), p["y0"], method=m,
                                                  rtol=tol, atol=tol))
            y = positions(r.y[:, -1]) if cart else r.y[:, -1]
            add(f"SciPy {m} (Python rhs{', angles' if cart else ''})", tol, s, y)
        if hy is not None:
            ta = hy.taylor_adaptive(heyoka_system(name if name != "double_pendulum"
                                                  else "double"), p["y0"].copy(), tol=tol)

            def prop():
                ta.time = 0.0
                ta.state[:] = p["y0"]
                ta.propagate_until(p["T"])
                return ta.state.copy()
            s, y = best_time(prop)
            add(f"heyoka taylor_adaptive (compiled{', angles' if cart else ''})", tol, s,
                positions(y) if cart else y)
    return curves


def main():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    OUT.mkdir(exist_ok=True)
    lines = ["# Work-precision (error against time, best of 3; tolerances 1e-4..1e-14)", ""]
    for name, p in PROBLEMS.items():
        curves = run_problem(name, p)
        fig, ax = plt.subplots(figsize=(6.4, 4.6))
        lines += [f"## {p['title']}", "", "| method | tol | time [s] | error |",
                  "|---|---|---|---|"]
        for label, pts in curves.items():
            pts = np.array(pts)
            ax.loglog(pts[:, 2], pts[:, 1], "o-", ms=3, label=label)
            lines += [f"| {label} | {t:.0e} | {s:.2e} | {e:.1e} |" for t, s, e in pts]
        ax.set_xlabel("error")
        ax.set_ylabel("time [s]")
        ax.set_title(p["title"])
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(OUT / f"work_precision_{name}.png", dpi=120)
        plt.close(fig)
        lines.append("")
        print(f"{name}: done")
    (OUT / "work_precision.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
