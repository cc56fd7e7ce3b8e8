#!/usr/bin/env bash
# Build the documentation, warnings as errors: FORD (Fortran API from the `!!` comments)
# into build/docs/fortran, Sphinx (guide with figures computed at build time, Python API)
# into build/docs/html. Run after scripts/setup.sh (it installs ford, sphinx, numpydoc).
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="$ROOT/.venv/bin:$PATH"
cd "$ROOT"
status=0
log="$(mktemp)"
trap 'rm -f "$log"' EXIT
echo "[docs] FORD -> build/docs/fortran"
if ! ford -q docs/ford.md >"$log" 2>&1 || grep -qi "warning" "$log"; then
    cat "$log"
    echo "[docs] FAILED: FORD reported warnings or errors" >&2
    status=1
fi
# FORD's pages load Bootstrap, MathJax and lunr from the network: local copies instead
if ! python scripts/ford_offline.py build/docs/fortran; then
    echo "[docs] FAILED: the FORD site still needs the network" >&2
    status=1
fi
echo "[docs] Sphinx -> build/docs/html"
# MPLBACKEND: the figures are drawn without a display
if ! MPLBACKEND=Agg python -m sphinx -W --keep-going -q -b html docs build/docs/html; then
    echo "[docs] FAILED: Sphinx reported warnings or errors" >&2
    status=1
fi
[ "$status" -eq 0 ] && echo "[docs] built: build/docs/html/index.html, build/docs/fortran/index.html"
exit "$status"
