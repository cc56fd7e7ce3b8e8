#!/usr/bin/env bash
# A Taylor step written out for one model against the library's generic step operations:
# Kepler e = 0.9, one period, rtol = atol = 1e-12 (order 15), in the loop of
# taylor_propagate (bench/taylor_callgrind/step_kernel_drive.f90). G: the library's
# taylor_eval_jet, the recurrences written out for the order (through a procedure pointer),
# taylor_check_jet, taylor_next_rho; K: the same operations in one routine with n = 4 and
# p = 15 as constants (bench/taylor_callgrind/step_kernel_kepler.f90, compiled with the
# flags of the written-out recurrences, conmech.symbolic.taylor.FIXED_EXTRA_FLAGS); J: the
# recurrences alone, as many expansions as a period has steps (D: each expansion waiting for
# the last coefficients of the previous one, a serial chain). Prints the steps and the
# final state's bits of G and K (they must agree), callgrind instructions per period, and
# the time per period: ROUNDS interleaved rounds of 20000 periods each, min and median.
# Usage (repository root; fpm, valgrind, PYTHON with conmech installed):
#   bash bench/taylor_step_kernel.sh [ROUNDS]
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS="${1:-8}"
FF="${FFLAGS:--O3}"
PY="${PYTHON:-python3}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fpm install --prefix "$tmp/cm" --profile release --flag "$FF" >"$tmp/build.log" 2>&1 \
    || { tail -5 "$tmp/build.log"; exit 1; }
libdir=$(ls -d "$tmp"/cm/lib* | head -1)
"$PY" - >"$tmp/fixed_source.f90" <<'PYEOF'
import sympy as sp
from conmech import symbolic
from conmech.symbolic import model_of
from conmech.symbolic.taylor import fixed_order_source
x, y, u, v = sp.symbols("x y u v")
r3 = (x**2 + y**2)**sp.Rational(3, 2)
kep = symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])
print(fixed_order_source(model_of(kep).derived, 15, variational=False))
PYEOF
XF=$("$PY" -c "from conmech.symbolic.taylor import FIXED_EXTRA_FLAGS as F; print(' '.join(F))")
gfortran $FF $XF -J "$tmp" -c "$tmp/fixed_source.f90" -o "$tmp/fixed_source.o"
gfortran $FF $XF -J "$tmp" -I"$tmp" -c bench/taylor_callgrind/step_kernel_kepler.f90 \
    -o "$tmp/kernel.o"
gfortran $FF -I"$tmp/cm/include" -I"$tmp" -J "$tmp" bench/taylor_callgrind/step_kernel_drive.f90 \
    "$tmp/kernel.o" "$tmp/fixed_source.o" -L"$libdir" -lconmech -llapack -lblas -o "$tmp/drive"
echo "flags: library $FF, kernel and recurrences $FF $XF; uptime:$(uptime | sed 's/.*average//')"
for m in G K; do
    echo "$m: $("$tmp/drive" $m 1 | awk '{print "steps", $2, "rejected", $3, "y", $4, $5, $6, $7}')"
done
ir() { valgrind --tool=callgrind --callgrind-out-file="$tmp/o.$1.$2" "$tmp/drive" "$1" "$2" \
           >/dev/null 2>&1
       grep -E '^(summary|totals):' "$tmp/o.$1.$2" | head -1 | awk '{print $2}'; }
for m in G K J; do echo "$m instructions/period: $(( ($(ir $m 11) - $(ir $m 1))/10 ))"; done
for r in $(seq 1 "$ROUNDS"); do
    for m in G K J D; do "$tmp/drive" $m 20000 | awk -v m=$m '{print m, $(NF-1)}'; done
done | sort -k1,1 -k2,2n | awk '{v[$1] = v[$1] " " $2; c[$1]++; a[$1, c[$1]] = $2}
    END {for (m in c) printf "%s us/period: min %s median %s (all:%s)\n", m, a[m, 1],
         a[m, int((c[m] + 1)/2)], v[m]}'
echo "uptime after:$(uptime | sed 's/.*average//')"
