#!/usr/bin/env bash
# Callgrind instruction counts per Kepler period (e = 0.9, rtol = atol = TOL, default 1e-12):
# Taylor's method (the generated module test/taylor_kepler_model.f90) against DOP853 on the
# same system, through ode_integrate (no storage) and ode_solve (every step stored, the path
# of conmech.solve_ivp). The library and the generated code are built with -O3 alone, the
# flags of the Python package's release build and of the libraries conmech.symbolic compiles
# (override with FFLAGS; valgrind cannot decode AVX-512, so not -march=native on such a CPU).
# "fixed": the recurrences written out for the order (generated here with the installed
# conmech package: PYTHON, default python3, e.g. .venv/bin/python), compiled with the flags
# solve_ivp adds for it (conmech.symbolic.taylor.FIXED_EXTRA_FLAGS: -fopenmp-simd for its
# paired history sums, AVX2's encoding without contraction where the processor has it;
# FIXED_FLAGS overrides them); PAIRED=0: the history sums unpaired (the same coefficients,
# one at a time), for comparison.
# Usage (from the repository root, with fpm and valgrind on PATH): bash bench/callgrind_taylor.sh [TOL]
set -euo pipefail
cd "$(dirname "$0")/.."
TOL="${1:-1e-12}"
FF="${FFLAGS:--O3}"
tmp="${CALLGRIND_TMP:-$(mktemp -d)}"
[ -n "${CALLGRIND_TMP:-}" ] || trap 'rm -rf "$tmp"' EXIT
fpm install --prefix "$tmp/cm" --profile release --flag "$FF" >"$tmp/build.log" 2>&1 \
    || { tail -5 "$tmp/build.log"; exit 1; }
libdir=$(ls -d "$tmp"/cm/lib* | head -1)
# the recurrences written out for the run's order, as solve_ivp compiles them
PY="${PYTHON:-python3}"
"$PY" - "$TOL" >"$tmp/fixed_source.f90" <<'PYEOF'
import sys, sympy as sp
from conmech import symbolic
from conmech.ivp.taylor import taylor_order
from conmech.symbolic import model_of
from conmech.symbolic.taylor import fixed_order_source
x, y, u, v = sp.symbols("x y u v")
r3 = (x**2 + y**2)**sp.Rational(3, 2)
kep = symbolic.ode_system([u, v, -x/r3, -y/r3], [x, y, u, v])
import os
print(fixed_order_source(model_of(kep).derived, taylor_order(float(sys.argv[1])),
                         variational=False, paired=os.environ.get("PAIRED", "1") == "1"))
PYEOF
order=$("$PY" -c "from conmech.ivp.taylor import taylor_order; print(taylor_order($TOL))")
sed "s/FIXED_ORDER_VALUE/$order/" bench/taylor_callgrind/kepler_fixed_jet.f90 >"$tmp/kepler_fixed_jet.f90"
XF="${FIXED_FLAGS-$("$PY" -c "from conmech.symbolic.taylor import FIXED_EXTRA_FLAGS as F; print(' '.join(F))")}"
gfortran $FF $XF -J "$tmp" -c "$tmp/fixed_source.f90" -o "$tmp/fixed_source.o"
gfortran $FF -fopenmp-simd -I"$tmp/cm/include" -J "$tmp" test/taylor_kepler_model.f90 "$tmp/fixed_source.o" \
    "$tmp/kepler_fixed_jet.f90" bench/taylor_callgrind/bench_taylor.f90 -L"$libdir" -lconmech \
    -llapack -lblas -o "$tmp/bench_taylor"
ir() { valgrind --tool=callgrind --callgrind-out-file="$tmp/o.$1.$2.$3" "$tmp/bench_taylor" \
           "$1" "$2" "$3" "$TOL" >/dev/null 2>&1
       grep -E '^(summary|totals):' "$tmp/o.$1.$2.$3" | head -1 | awk '{print $2}'; }
per() { echo $(( ($(ir "$1" "$2" 11) - $(ir "$1" "$2" 1))/10 )); }
echo "flags: $FF (written-out recurrences: $FF $XF); Kepler e = 0.9, one period, rtol = atol = $TOL"
printf "%-10s %-10s %14s   %s\n" method path "instr/period" "error nfev naccept"
for m in taylor fixed dop853; do
    for p in integrate solve; do
        printf "%-10s %-10s %14s   %s\n" "$m" "$p" "$(per $m $p)" \
            "$("$tmp/bench_taylor" "$m" "$p" 1 "$TOL" | awk '{print $3, $4, $5}')"
    done
done
