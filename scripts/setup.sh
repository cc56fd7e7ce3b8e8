#!/usr/bin/env bash
# Set up everything conmech needs on a Debian machine, idempotently (fast when all is there):
#   1. system packages: gfortran, LAPACK/BLAS, OpenMPI (and python3-venv/-dev if the
#      Python in use lacks venv or its headers), via apt-get, only if missing;
#   2. a virtual environment .venv in the repository with numpy, scipy, meson,
#      meson-python, ninja, pytest, hypothesis, matplotlib, fpm, sympy (conmech.symbolic),
#      and ford, sphinx, numpydoc (the docs),
#      only if something is missing;
#   3. the conmech Python package itself (pip install --no-build-isolation .), rebuilt only
#      when the sources changed (hash stamp in .venv/).
# Environment: PYTHON (default python3) creates the venv; CONMECH_FORCE_REINSTALL=1 rebuilds.
# Source it or run it; scripts/run.sh and scripts/test.sh call it first.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
VENV="$ROOT/.venv"
PYTHON="${PYTHON:-python3}"
log() { printf '[setup] %s\n' "$*"; }

# ------------------------------------------------------------------ 1. system packages
missing=()
for pkg in gfortran liblapack-dev libblas-dev libopenmpi-dev openmpi-bin; do
    if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$pkg")
    fi
done
if ! command -v "$PYTHON" >/dev/null 2>&1; then
    missing+=(python3 python3-venv python3-dev)
    PYTHON=python3
else
    if [ ! -x "$VENV/bin/python" ] && ! "$PYTHON" -c "import venv, ensurepip" >/dev/null 2>&1; then
        missing+=(python3-venv)
    fi
    if ! "$PYTHON" -c "import sysconfig, os, sys; \
sys.exit(0 if os.path.exists(os.path.join(sysconfig.get_paths()['include'], 'Python.h')) else 1)" \
        >/dev/null 2>&1; then
        missing+=(python3-dev)
    fi
fi
if [ "${#missing[@]}" -gt 0 ]; then
    log "installing system packages: ${missing[*]}"
    SUDO=""
    if [ "$(id -u)" -ne 0 ]; then
        if command -v sudo >/dev/null 2>&1; then
            SUDO="sudo"
        else
            echo "[setup] need root (or sudo) to install: ${missing[*]}" >&2
            exit 1
        fi
    fi
    $SUDO apt-get update
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
        "${missing[@]}"
fi

# ------------------------------------------------------------------ 2. virtual environment
if [ ! -x "$VENV/bin/python" ]; then
    log "creating the virtual environment $VENV"
    "$PYTHON" -m venv "$VENV"
fi
VPY="$VENV/bin/python"
export PATH="$VENV/bin:$PATH"
if ! "$VPY" - <<'PYEOF' >/dev/null 2>&1
import importlib.util, shutil, sys
mods = ["numpy", "scipy", "mesonpy", "pytest", "hypothesis", "matplotlib", "sympy",
        "sphinx", "numpydoc"]
ok = all(importlib.util.find_spec(m) is not None for m in mods)
ok = ok and all(shutil.which(x) for x in ("meson", "ninja", "fpm", "ford"))
sys.exit(0 if ok else 1)
PYEOF
then
    log "installing Python packages into $VENV"
    "$VPY" -m pip install --upgrade pip
    "$VPY" -m pip install numpy scipy meson meson-python ninja pytest hypothesis matplotlib \
        fpm sympy ford sphinx numpydoc
fi

# ------------------------------------------------------------------ 3. the conmech package
stamp_file="$VENV/.conmech-build-stamp"
stamp="$(
    {
        find src python/conmech tools -type f \( -name '*.f90' -o -name '*.F90' -o -name '*.inc' -o -name '*.py' -o -name '*.c' \) \
            -not -path '*/__pycache__/*' -print0 | sort -z | xargs -0 sha256sum
        sha256sum meson.build pyproject.toml
    } | sha256sum | cut -d' ' -f1
)"
if [ "${CONMECH_FORCE_REINSTALL:-0}" = "1" ] || [ ! -f "$stamp_file" ] \
    || [ "$(cat "$stamp_file")" != "$stamp" ] \
    || ! (cd / && "$VPY" -c "import conmech._conmech") >/dev/null 2>&1; then
    log "building and installing the conmech Python package"
    rm -f "$stamp_file"
    "$VPY" -m pip install --no-build-isolation --no-deps \
        -Cbuild-dir="$ROOT/build/meson-python" "$ROOT"
    echo "$stamp" >"$stamp_file"
fi
log "ready (venv: $VENV)"
