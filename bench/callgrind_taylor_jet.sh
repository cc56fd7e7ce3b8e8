#!/usr/bin/env bash
# Callgrind instructions of ONE Taylor expansion written out for one order (the routine
# solve_ivp's method TAYLOR runs every step), history sums paired into 2-wide vectors
# (conmech.symbolic.taylor's default) against unpaired, Kepler and Arenstorf, compiled
# with the flags of the written-out library (-O3 -fPIC and conmech.symbolic.taylor's
# FIXED_EXTRA_FLAGS, the machine's; override with FFLAGS). The checksums of the two forms
# must agree to the last digit (the same coefficients, bit for bit).
# Usage (repository root, installed conmech package, valgrind on PATH):
#   bash bench/callgrind_taylor_jet.sh [ORDER]      (default 15: tol 1e-12)
set -euo pipefail
cd "$(dirname "$0")/.."
ORDER="${1:-15}"
PY="${PYTHON:-python3}"
FF="${FFLAGS:--O3 -fPIC $("$PY" -c "from conmech.symbolic.taylor import FIXED_EXTRA_FLAGS as F; print(' '.join(F))")}"
tmp=$(mktemp -d)
[ -n "${KEEP:-}" ] || trap 'rm -rf "$tmp"' EXIT; echo "$tmp" >&2
"$PY" - "$ORDER" "$tmp" <<'PYEOF'
import sys, sympy as sp
from conmech import symbolic
from conmech.symbolic import model_of
from conmech.symbolic.taylor import fixed_order_source
order, tmp = int(sys.argv[1]), sys.argv[2]
x, y, u, v, mu = sp.symbols("x y u v mu")
r3 = (x**2 + y**2)**sp.Rational(3, 2)
mup = 1 - mu
d1 = ((x + mu)**2 + y**2)**sp.Rational(3, 2)
d2 = ((x - mup)**2 + y**2)**sp.Rational(3, 2)
systems = {"kepler": ([u, v, -x/r3, -y/r3], {}),
           "arenstorf": ([u, v, x + 2*v - mup*(x + mu)/d1 - mu*(x - mup)/d2,
                          y - 2*u - mup*y/d1 - mu*y/d2], {mu: 0.012277471})}
for name, (f, p) in systems.items():
    s = symbolic.ode_system(f, [x, y, u, v], params=p)
    d = model_of(s).derived
    for paired in (True, False):
        with open(f"{tmp}/{name}_{int(paired)}.f90", "w") as fh:
            fh.write(fixed_order_source(d, order, variational=False, paired=paired))
    with open(f"{tmp}/{name}.nw", "w") as fh:
        fh.write(str(s.taylor["nw"]))
PYEOF
echo "flags: $FF; order $ORDER; instructions per expansion (callgrind)"
printf "%-10s %-8s %14s   %s\n" system form instr checksum
for name in kepler arenstorf; do
    nw=$(cat "$tmp/$name.nw")
    for paired in 1 0; do
        d="$tmp/$name$paired"
        mkdir -p "$d"
        gfortran $FF -J "$d" "$tmp/${name}_$paired.f90" bench/taylor_callgrind/jet_count.f90 \
            -o "$d/jet"
        ir() { valgrind --tool=callgrind --callgrind-out-file="$d/o.$1" "$d/jet" "$ORDER" \
                   "$nw" "$1" 0.012277471 >/dev/null 2>&1
               grep -E '^(summary|totals):' "$d/o.$1" | head -1 | awk '{print $2}'; }
        per=$(( ($(ir 11) - $(ir 1))/10 ))
        form=$([ "$paired" = 1 ] && echo paired || echo unpaired)
        printf "%-10s %-8s %14s   %s\n" "$name" "$form" "$per" \
            "$("$d/jet" "$ORDER" "$nw" 11 0.012277471)"
    done
done
