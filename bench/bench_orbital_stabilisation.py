"""Orbital stabilisation by transverse LQR (conmech.control): for each example, the
reduced orbit (period by integration and by quadrature), the Riccati solution
(periodicity, smallest eigenvalue of P), the closed-loop multipliers (transverse and of the
nonlinear N x N monodromy), then the nonlinear closed loop from 20 perturbed starts over 30
periods: the orbital distance at the start and at the end, and the number of periods after
which every run has shrunk by 1e3.

    python bench/bench_orbital_stabilisation.py [--examples cart pendubot dpcart]
                                                [--starts 20] [--periods 30] [--size 0.02]
                                                [--out bench/results/orbital_stabilisation.md]

Wall-clock times are printed too (provisional on a shared machine).
"""
import argparse
import time

import numpy as np

from conmech import control
from conmech.control import examples
from conmech.control.plots import perturbed_runs

SETUPS = {
    # name: (factory, kwargs, theta0, Q, R, kp, kd, perturbation size, label)
    "cart": (examples.cart_pendulum, {}, 0.3, np.eye(3), 0.1, 25.0, 10.0, 0.02,
             "cart pendulum (force on the cart), x = -1.6 theta, amplitude 0.3 rad"),
    "pendubot": (examples.pendubot, {}, 0.15, np.eye(3), 1.0, 100.0, 20.0, 0.01,
                 "Pendubot (shoulder torque), q1 = -0.8 q2, amplitude 0.15 rad"),
    "dpcart": (examples.double_pendulum_cart, {}, 0.2, np.eye(5), np.eye(2), 25.0, 10.0,
               0.02, "double pendulum on a cart (cart force, elbow torque), "
               "x = -1.5 theta1, theta2 = 0, amplitude 0.2 rad"),
}


def run(name, starts, periods, size):
    fac, kw, th0, Q, R, kp, kd, size0, label = SETUPS[name]
    size = size0 if size is None else size
    t0 = time.perf_counter()
    plant, vhc = fac(**kw)
    t_build = time.perf_counter() - t0
    red = vhc.reduced()
    orb = red.periodic_orbit(th0)
    t0 = time.perf_counter()
    ctrl = control.orbital_stabilisation(plant, orb, Q=Q, R=R, kp=kp, kd=kd)
    t_design = time.perf_counter() - t0
    t0 = time.perf_counter()
    t, dist, xi, runs = perturbed_runs(ctrl, n_starts=starts, size=size, periods=periods,
                                       keep_failures=True)
    t_sim = time.perf_counter() - t0
    failed = int(np.sum(np.isnan(dist[:, 0])))
    dist = dist[~np.isnan(dist[:, 0])]
    ratio = dist[:, 0]/dist[:, -1]
    spp = (t.size - 1)//periods
    below = dist <= 1e-3*dist[:, :1]
    first = []
    for row in below:
        idx = np.nonzero(row[::spp])[0]
        first.append(int(idx[0]) if idx.size else None)
    nl = ctrl.nonlinear_multipliers
    nl_nontrivial = nl[np.argsort(np.abs(nl - 1))][1:]
    mu = ctrl.multipliers
    match = np.max(np.abs(np.sort_complex(nl_nontrivial) - np.sort_complex(mu)))
    return dict(name=name, label=label, period=orb.period,
                period_quad=orb.period_quadrature, alpha=orb.alpha_range,
                multipliers=mu, open=ctrl.open_loop_multipliers, nl_match=match,
                periodicity=ctrl.periodicity, min_eig=ctrl.min_eigenvalue,
                passes=ctrl.passes, d0=dist[:, 0], d1=dist[:, -1], ratio=ratio,
                first=first, failed=failed, t_build=t_build, t_design=t_design, t_sim=t_sim,
                nfev=int(np.mean([r.nfev for r in runs])), starts=starts, periods=periods,
                size=size)


def report(r):
    lines = [f"### {r['label']}", ""]
    lines.append(f"- period by integration {r['period']:.12f}, by quadrature "
                 f"{r['period_quad']:.12f} (difference "
                 f"{abs(r['period'] - r['period_quad']):.1e}); alpha in "
                 f"[{r['alpha'][0]:.4g}, {r['alpha'][1]:.4g}]")
    lines.append(f"- Riccati: periodic to {r['periodicity']:.1e}, smallest eigenvalue of P "
                 f"{r['min_eig']:.3g}, {r['passes']} backward passes")
    lines.append("- open-loop transverse multipliers (nominal law only): "
                 + ", ".join(f"{abs(m):.4g}" for m in r["open"]))
    lines.append("- closed-loop transverse multipliers |mu|: "
                 + ", ".join(f"{abs(m):.4g}" for m in r["multipliers"])
                 + f" (nonlinear N x N monodromy agrees to {r['nl_match']:.1e})")
    worst = max((f for f in r["first"] if f is not None), default=None)
    never = sum(f is None for f in r["first"])
    lines.append(f"- {r['starts']} perturbed starts (N(0, {r['size']}) per component): "
                 f"distance {r['d0'].min():.3g}..{r['d0'].max():.3g} at t = 0, "
                 f"{r['d1'].min():.2e}..{r['d1'].max():.2e} after {r['periods']} periods; "
                 f"shrink factors {r['ratio'].min():.2e}..{r['ratio'].max():.2e}; "
                 + (f"every run below 1e-3 of its start after {worst} periods"
                    if never == 0 else f"{never} runs never below 1e-3 of the start")
                 + (f"; {r['failed']} runs left the region of attraction (integration "
                    "failed)" if r["failed"] else ""))
    lines.append(f"- wall clock (provisional): build {r['t_build']:.2f} s, design "
                 f"{r['t_design']:.2f} s, {r['starts']} runs {r['t_sim']:.2f} s "
                 f"(mean nfev {r['nfev']})")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--examples", nargs="+", default=["cart", "pendubot", "dpcart"],
                    choices=list(SETUPS))
    ap.add_argument("--starts", type=int, default=20)
    ap.add_argument("--periods", type=int, default=30)
    ap.add_argument("--size", type=float, default=None,
                    help="perturbation size (default per example: 0.02, Pendubot 0.01)")
    ap.add_argument("--out", default=None)
    a = ap.parse_args(argv)
    text = ["# Orbital stabilisation by transverse LQR", "",
            "`python bench/bench_orbital_stabilisation.py` (conmech.control). Closed loop: "
            "u = u_vhc(x) + K(tau) xi, DOP853 at rtol = atol = 1e-10.", ""]
    ok = True
    for name in a.examples:
        r = run(name, a.starts, a.periods, a.size)
        s = report(r)
        print(s)
        text.append(s)
        ok &= bool(np.all(r["ratio"] >= 1e3)) and bool(np.all(np.abs(r["multipliers"]) < 1))
        ok &= r["failed"] == 0
    if a.out:
        with open(a.out, "w") as fh:
            fh.write("\n".join(text))
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
