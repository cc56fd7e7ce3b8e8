#!/usr/bin/env bash
# Taylor's order above Jorba and Zou's: callgrind instructions per Kepler period (e = 0.9,
# rtol = atol = TOL, default 1e-12) and the closure error, steps and expansions, with the
# order set to Jorba and Zou's p0 = ceil(-ln(TOL)/2 + 1) plus each DELTA given (default
# 0 2 3 4 5 6) and the step lengthened to match (taylor_decay), through
# bench/callgrind_taylor.sh on a copy of the repository whose taylor_order returns
# p0 + DELTA. The library's own rule is p0 + max(3, p0/5).
# Usage (from the repository root, fpm and valgrind on PATH, PYTHON with conmech installed):
#   bash bench/taylor_order_sweep.sh [TOL] [DELTA ...]
set -euo pipefail
cd "$(dirname "$0")/.."
TOL="${1:-1e-12}"
shift || true
DELTAS="${*:-0 2 3 4 5 6}"
PY="${PYTHON:-python3}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
git ls-files -z | tar --null -T - -cf - | (mkdir -p "$work/repo" && tar -C "$work/repo" -xf -)
cd "$work/repo"
core=src/ode/conmech_taylor_core.f90
cp bench/callgrind_taylor.sh "$work/callgrind_taylor.sh"
grep -q 'taylor_order = p0 + max(3, p0/5)' "$core" ||
    { echo "taylor_order's rule not found in $core"; exit 1; }
for d in $DELTAS; do
    sed -i "s|taylor_order = p0 + .*|taylor_order = p0 + $d|" "$core"
    # the fixed-order source for p0 + d (the installed package's taylor_order is the library's)
    jz="max(2, __import__('math').ceil(-0.5*__import__('math').log(float(sys.argv[1])) + 1)) + $d"
    cp "$work/callgrind_taylor.sh" bench/callgrind_taylor.sh
    sed -i "s|taylor_order(float(sys.argv\[1\]))|$jz|" bench/callgrind_taylor.sh
    order="import math; print(max(2, math.ceil(-0.5*math.log(\$TOL) + 1)) + $d)"
    sed -i "s|from conmech.ivp.taylor import taylor_order; print(taylor_order(\$TOL))|$order|" \
        bench/callgrind_taylor.sh
    echo "== order p0 + $d"
    mkdir -p "$work/cg$d"
    CALLGRIND_TMP="$work/cg$d" PYTHON="$PY" bash bench/callgrind_taylor.sh "$TOL" |
        grep -E "^(taylor|fixed) "
done
