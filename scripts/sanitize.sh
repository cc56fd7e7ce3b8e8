#!/usr/bin/env bash
# Build the Fortran tests with AddressSanitizer, UndefinedBehaviorSanitizer and all
# run-time checks, run them with leak detection on, and fail if any test program fails,
# reports a sanitizer error or a leak, or ends without its summary line.
#   bash scripts/sanitize.sh              # every test program
#   bash scripts/sanitize.sh test_ode     # one (or more) of them
# The build goes to fpm's build/ directory under its own flag hash (the normal build is
# untouched). Takes ~10 min on the 2-core development machine (see the README).
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
[ -x .venv/bin/fpm ] && export PATH="$ROOT/.venv/bin:$PATH"
FLAGS="-g -fsanitize=address,undefined -fcheck=all -fno-omit-frame-pointer"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:halt_on_error=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
log="$(mktemp)"
trap 'rm -f "$log"' EXIT

if [ "$#" -gt 0 ]; then
    targets=("$@")
else
    mapfile -t targets < <(grep -l '^ *program ' test/*.f90 | xargs -n1 basename \
        | sed 's/\.f90$//')
fi
status=0
start=$(date +%s)
if ! fpm build --tests --flag "$FLAGS" >"$log" 2>&1; then
    cat "$log"
    echo "[sanitize] build failed" >&2
    exit 1
fi
for t in "${targets[@]}"; do
    fpm test --flag "$FLAGS" --target "$t" >"$log" 2>&1
    rc=$?
    if [ "$rc" -ne 0 ] || grep -qE "ERROR: (Address|Leak)Sanitizer|runtime error:" "$log" \
        || ! grep -qE "^$t: [0-9]+ passed, 0 failed$" "$log"; then
        echo "[sanitize] FAILED: $t (exit $rc)"
        grep -E "ERROR: |SUMMARY: |runtime error:|#[0-9]+ 0x.* in .*(src|test)/" "$log" | head -40
        status=1
    else
        echo "[sanitize] clean: $t"
    fi
done
verdict=$([ "$status" -eq 0 ] && echo clean || echo FAILED)
echo "[sanitize] ${#targets[@]} program(s) in $(( $(date +%s) - start )) s: $verdict"
exit "$status"
