#!/usr/bin/env bash
# Set up what is missing (scripts/setup.sh), then run every test: no compiler warning in src/
# (scripts/warnings.sh), fpm test, the Fortran tests again under AddressSanitizer/UBSan with
# leak detection (scripts/sanitize.sh), pytest and the documentation build.
# Exits non-zero if anything fails (pytest collecting no tests counts as a failure).
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$ROOT/scripts/setup.sh" || { echo "[test] set-up failed" >&2; exit 1; }
export PATH="$ROOT/.venv/bin:$PATH"
cd "$ROOT"

status=0
log_dir="$(mktemp -d)"
trap 'rm -rf "$log_dir"' EXIT

echo "[test] compiler warnings in src/ (scripts/warnings.sh)"
if ! bash "$ROOT/scripts/warnings.sh"; then
    echo "[test] FAILED: compiler warnings in src/" >&2
    status=1
fi

# A runner that dies without its closing summary (e.g. a library calling STOP, which exits
# with status 0) must not pass: every Fortran test program ends with "NAME: N passed, N
# failed", pytest with "N passed ...".
echo "[test] fpm test"
fpm test 2>&1 | tee "$log_dir/fpm.log"
if [ "${PIPESTATUS[0]}" -ne 0 ]; then
    echo "[test] FAILED: fpm test" >&2
    status=1
fi
n_prog=$(grep -l '^ *program ' test/*.f90 | wc -l)
n_done=$(grep -cE '^[a-z_0-9]+: [0-9]+ passed, 0 failed$' "$log_dir/fpm.log" || true)
if [ "$n_done" -ne "$n_prog" ]; then
    echo "[test] FAILED: $n_done of $n_prog Fortran test programs reported a clean summary" >&2
    status=1
fi

echo "[test] Fortran tests under ASan/UBSan, -fcheck=all, leak detection (scripts/sanitize.sh)"
if ! bash "$ROOT/scripts/sanitize.sh"; then
    echo "[test] FAILED: a Fortran test under the sanitizers" >&2
    status=1
fi

echo "[test] pytest python/tests"
python -m pytest -q python/tests "$@" 2>&1 | tee "$log_dir/pytest.log"
rc=${PIPESTATUS[0]}
if [ "$rc" -ne 0 ]; then
    if [ "$rc" -eq 5 ]; then
        echo "[test] FAILED: pytest collected no tests" >&2
    else
        echo "[test] FAILED: pytest (exit code $rc)" >&2
    fi
    status=1
elif ! tail -n 3 "$log_dir/pytest.log" | grep -qE '[0-9]+ passed'; then
    echo "[test] FAILED: pytest ended without its summary line (the process died)" >&2
    status=1
fi
echo "[test] documentation (FORD + Sphinx, warnings as errors)"
if ! bash "$ROOT/scripts/docs.sh"; then
    echo "[test] FAILED: the documentation build" >&2
    status=1
fi
if [ "$status" -eq 0 ]; then
    echo "[test] all tests passed"
fi
exit "$status"
