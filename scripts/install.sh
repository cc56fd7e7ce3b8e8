#!/usr/bin/env bash
# Install the Fortran library for other build systems: libconmech.a, the library's module
# files and (unless --library-only) the programs.
#
#   bash scripts/install.sh --prefix DIR [--library-only] [other fpm install options]
#
# fpm 0.12 installs the module file of every module its targets provide: besides the
# library's, the programs' helpers (app_cli.mod, ...) and the examples' (arenstorf_model.mod,
# cart_pendulum_model.mod, ...), which could clash with a user's own modules. This wrapper
# runs `fpm install` and then removes every installed module file that is not one of the
# library's (the modules of src/), so DIR/include holds conmech's API only.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="$ROOT/.venv/bin:$PATH"
cd "$ROOT"
prefix="" includedir="" bindir="" library_only=0 args=()
while [ $# -gt 0 ]; do
    case "$1" in
        --library-only) library_only=1 ;;
        --prefix) prefix="$2"; args+=("$1" "$2"); shift ;;
        --prefix=*) prefix="${1#*=}"; args+=("$1") ;;
        --includedir) includedir="$2"; args+=("$1" "$2"); shift ;;
        --includedir=*) includedir="${1#*=}"; args+=("$1") ;;
        --bindir) bindir="$2"; args+=("$1" "$2"); shift ;;
        --bindir=*) bindir="${1#*=}"; args+=("$1") ;;
        *) args+=("$1") ;;
    esac
    shift
done
[ -n "$prefix" ] || { echo "usage: bash scripts/install.sh --prefix DIR [--library-only] [fpm install options]" >&2; exit 2; }
# --no-prune: every module of the library, also those no program or test uses (fpm drops
# them otherwise, from libconmech.a and from the installed modules alike)
fpm install --no-prune "${args[@]}"
inc="${includedir:-$prefix/include}"
# the library's modules: `module NAME` statements in src/ (not `module procedure` etc.)
keep="$(grep -rhoiE '^[[:space:]]*module[[:space:]]+[a-z][a-z0-9_]*[[:space:]]*(!.*)?$' src \
        | awk '{print tolower($2)}' | sort -u)"
removed=0
for f in "$inc"/*.mod "$inc"/*.smod; do
    [ -e "$f" ] || continue
    name="$(basename "$f")"; name="${name%.mod}"; name="${name%.smod}"; name="${name%%@*}"
    if ! grep -qx "$name" <<<"$keep"; then
        rm -f "$f"
        removed=$((removed + 1))
    fi
done
echo "[install] removed $removed module file(s) of the programs and examples from $inc"
if [ "$library_only" -eq 1 ]; then
    for p in $(ls app | sed -n 's/\.[fF]90$//p'); do
        rm -f "${bindir:-$prefix/bin}/$p"
    done
    rmdir "${bindir:-$prefix/bin}" 2>/dev/null || true
    echo "[install] --library-only: the programs are not installed"
fi
echo "[install] $(ls "$inc" | wc -l) module files in $inc; library: $(ls "$prefix"/lib*/libconmech.a 2>/dev/null || echo '?')"
