"""Constraint drift of the Cartesian double pendulum with and without projection.

    python bench/plot_drift.py [out.png]      (default bench/results/projection_drift.png)
"""
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from conmech import constrained  # noqa: E402


def main(out):
    t = np.linspace(0, 200, 401)
    runs = {p: constrained.solve("double_pendulum_xy", (0, 200), projection=p, t_eval=t,
                                 rtol=1e-8, atol=1e-8)
            for p in ("none", "baumgarte", "velocity", "position+velocity")}
    fig, (a1, a2, a3) = plt.subplots(1, 3, figsize=(14, 4.2))
    constrained.plot_trajectory(runs["position+velocity"], coords=(2, 3), ax=a1, lw=0.5)
    a1.set_title("double pendulum, second mass (x2, y2)")
    constrained.plot_drift(runs, ax=a2)
    a2.set_title("position residual, DOP853 rtol 1e-8")
    constrained.plot_drift(runs, ax=a3, velocity=True)
    a3.set_title("velocity residual")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    for p, r in runs.items():
        print(f"{p:18s} nfev {r.nfev:7d}  final |phi| {r.res_pos[-1]:.2e}  "
              f"|G v| {r.res_vel[-1]:.2e}")
    print("wrote", out)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else
         str(Path(__file__).parent / "results" / "projection_drift.png"))
