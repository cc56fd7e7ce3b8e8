#!/usr/bin/env bash
# Instructions per accepted step of conmech.DOP853 driven step by step from Python (the
# built-in Kepler system, no Python right-hand side: what is left is the Python and f2py
# glue plus the Fortran step), by callgrind on the installed package of a virtualenv:
# (I(K2 steps) - I(K1 steps))/(K2 - K1), which cancels start-up and imports. The Fortran
# step alone is read from the same profile (flat_stepper_step_builtin_, inclusive).
# Usage (repository root): bash bench/stepper_glue_callgrind.sh [PYTHON] [K1] [K2]
set -euo pipefail
cd "$(dirname "$0")/.."
py="${1:-.venv/bin/python}"
k1="${2:-100}"
k2="${3:-1100}"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cat >"$tmp/steps.py" <<'PYEOF'
import sys
import conmech
s = conmech.DOP853(conmech.systems.kepler(), 0.0, [0.4, 0.0, 0.0, 2.0], 1e9, rtol=1e-10,
                   atol=1e-10)
for _ in range(int(sys.argv[1])):
    s.step()
PYEOF
run() {  # run K -> "total fortran"
    valgrind --tool=callgrind --callgrind-out-file="$tmp/cg.$1" "$py" "$tmp/steps.py" "$1" \
        >/dev/null 2>&1
    local tot fort
    tot=$(grep -E '^(summary|totals):' "$tmp/cg.$1" | head -1 | awk '{print $2}')
    # the step routine: flat_stepper_step_builtin (or flat_stepper_builtin, older builds)
    fort=$(callgrind_annotate --inclusive=yes --threshold=100 "$tmp/cg.$1" 2>/dev/null \
        | grep -m1 -E 'flat_stepper_(step_)?builtin_ ' | awk '{gsub(",", "", $1); print $1}' \
        || true)
    echo "$tot ${fort:-0}"
}
read -r t1 f1 < <(run "$k1")
read -r t2 f2 < <(run "$k2")
awk -v t1="$t1" -v t2="$t2" -v f1="$f1" -v f2="$f2" -v k=$((k2 - k1)) 'BEGIN {
    printf "instructions per step: total %.0f, Fortran (flat_stepper_builtin) %.0f, " \
           "Python + f2py glue %.0f\n", (t2 - t1)/k, (f2 - f1)/k, ((t2 - t1) - (f2 - f1))/k }'
