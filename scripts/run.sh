#!/usr/bin/env bash
# Set up what is missing (scripts/setup.sh), then run the main job: the tour of conmech
# (app/tour.f90), built and run by fpm from the virtual environment.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$ROOT/scripts/setup.sh"
export PATH="$ROOT/.venv/bin:$PATH"
cd "$ROOT"
exec fpm run tour -- "$@"
