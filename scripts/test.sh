#!/usr/bin/env bash
# Set up what is missing (scripts/setup.sh), then run every test: fpm test and pytest.
# Exits non-zero if anything fails (pytest collecting no tests counts as a failure).
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$ROOT/scripts/setup.sh" || { echo "[test] set-up failed" >&2; exit 1; }
export PATH="$ROOT/.venv/bin:$PATH"
cd "$ROOT"

status=0
echo "[test] fpm test"
if ! fpm test; then
    echo "[test] FAILED: fpm test" >&2
    status=1
fi
echo "[test] pytest python/tests"
python -m pytest -q python/tests "$@"
rc=$?
if [ "$rc" -ne 0 ]; then
    if [ "$rc" -eq 5 ]; then
        echo "[test] FAILED: pytest collected no tests" >&2
    else
        echo "[test] FAILED: pytest (exit code $rc)" >&2
    fi
    status=1
fi
if [ "$status" -eq 0 ]; then
    echo "[test] all tests passed"
fi
exit "$status"
