#!/usr/bin/env bash
# Set up what is missing (scripts/setup.sh), then run the main job: the tour of conmech.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$ROOT/scripts/setup.sh"
export PATH="$ROOT/.venv/bin:$PATH"
cd "$ROOT"
if [ -f app/tour.f90 ]; then
    exec fpm run tour -- "$@"
elif compgen -G "app/*.f90" >/dev/null; then
    exec fpm run -- "$@"
else
    # No Fortran app yet: a short tour from Python on the same Fortran core.
    exec python - <<'PYEOF'
import numpy as np
import conmech
from conmech import systems

print("conmech tour (Python front end; the Fortran tour app is not there yet)")
for name, sys_, y0, T in [
    ("pendulum", systems.pendulum(g=9.81, l=1.0), [1.0, 0.0], 10.0),
    ("kepler e=0.5", systems.kepler(mu=1.0), [0.5, 0.0, 0.0, np.sqrt(3.0)], 2 * np.pi),
]:
    r = conmech.solve_ivp(sys_, (0.0, T), y0, rtol=1e-10, atol=1e-10)
    y = r.y
    if name == "pendulum":
        e = 0.5 * y[1] ** 2 - 9.81 * np.cos(y[0])
    else:
        e = 0.5 * (y[2] ** 2 + y[3] ** 2) - 1.0 / np.hypot(y[0], y[1])
    print(f"{name:14s} status={r.status} nfev={r.nfev:5d} steps={r.naccept:4d} "
          f"rejected={r.nreject:3d} max|dE|={np.max(np.abs(e - e[0])):.2e}")
PYEOF
fi
