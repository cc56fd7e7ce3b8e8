"""Single shooting, multiple shooting and collocation on 1,000-point families (not a test).

Hénon's family a (Hill's problem in Hénon's units, the Lyapunov orbits about L1) continued
in the period from the orbit of amplitude 0.01 (stability.continuation, in_period,
conservative), 1,000 points (ds 0.05, ds_max 0.2, special points located):

- one lap: the orbits' largest multiplier grows from 2e3 to 1e5 and beyond;
- three laps of the same orbits (the period continued is 3 T): mu_max^3 ~ 1e10 and more,
  where single shooting's one STM has no usable digit left.

For each discretisation: wall time (provisional: a shared, loaded machine), points reached,
where the family ended (T per lap, Gamma), the largest multiplier, the worst
|mu_min mu_max - 1| over the branch (for this Hamiltonian system exactly 0: the accuracy of
the multipliers) beside the worst accuracy the multipliers report themselves (their
largest error estimate relative to max(1, |mu|)), the status and message. Writes
bench/results/orbit_methods.md.

    python bench/bench_orbit_methods.py [--points 1000] [--repeat 1]
"""
import argparse
import os
import platform
import time

import numpy as np

from conmech import hill_families as hf, stability


def run(laps, method, points, **extra):
    o = hf.lyapunov_orbit(0.01)
    t0 = time.perf_counter()
    try:
        br = stability.continuation(hf.system(), o.y0, laps*o.period, in_period=True,
                                    conservative=True, max_points=points, ds=0.05,
                                    ds_max=0.2, method=method,
                                    energy=lambda y, p: hf.gamma(y), **extra)
    except Exception as exc:     # the start itself failed: reported as such
        return dict(method=method, laps=laps, time=time.perf_counter() - t0, points=0,
                    message=f"{type(exc).__name__}: {exc}")
    el = time.perf_counter() - t0
    a = np.sort(np.abs(br.multipliers), axis=1)
    recip = np.abs(a[:, 0]*a[:, -1] - 1.0)
    return dict(method=method, laps=laps, time=el, points=len(br), T=br.p[-1]/laps,
                gamma=br.energy[-1], mu_max=float(a[:, -1].max()),
                recip=float(recip.max()), acc=float(np.max(br.accuracy)),
                special=len(br.special),
                located=sum(s.located for s in br.special), message=br.message)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, default=1000)
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "results",
                                                  "orbit_methods.md"))
    args = ap.parse_args()
    cases = [(1, "single", {}), (1, "multiple", dict(segments=8)),
             (1, "collocation", dict(intervals=60)),
             (3, "single", {}), (3, "multiple", dict(segments=24)),
             (3, "collocation", dict(intervals=120)),
             (3, "collocation", dict(intervals=240))]
    rows = []
    for laps, method, extra in cases:
        r = run(laps, method, args.points, **extra)
        r["opts"] = ", ".join(f"{k}={v}" for k, v in extra.items())
        rows.append(r)
        print(r)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lines = ["# Single shooting, multiple shooting and collocation on 1,000-point families",
             "",
             "`python bench/bench_orbit_methods.py` (bench/bench_orbit_methods.py): Hénon's "
             "family a continued in the period from the orbit of amplitude 0.01 about L1, "
             f"{args.points} points, ds 0.05, ds_max 0.2, default tolerances (rtol 1e-11). "
             "One lap, and the same orbits traversed three times (the continued period is "
             "3 T). Wall times are provisional: one run on a 2-core machine shared with "
             f"other work (load average {load:.1f} at the end); machine {platform.machine()}.",
             "",
             "| laps | method | options | time (s) | points | T/lap at the end | Gamma at "
             "the end | max mu_max | worst mu_min mu_max - 1 | worst reported accuracy | "
             "special (located) | message |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r["points"] == 0:
            lines.append(f"| {r['laps']} | {r['method']} | {r['opts']} | {r['time']:.1f} | "
                         f"0 | - | - | - | - | - | - | {r['message']} |")
            continue
        lines.append(f"| {r['laps']} | {r['method']} | {r['opts']} | {r['time']:.1f} | "
                     f"{r['points']} | {r['T']:.6f} | {r['gamma']:.6g} | "
                     f"{r['mu_max']:.3g} | {r['recip']:.1e} | {r['acc']:.1e} | {r['special']} "
                     f"({r['located']}) | {r['message']} |")
    with open(args.out, "w") as fh:
        fh.write("\n".join(lines) + "\n")
    print("wrote", args.out)


if __name__ == "__main__":
    main()
