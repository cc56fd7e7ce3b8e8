#!/usr/bin/env bash
# Compile every library source (src/) with the project's flags plus -Wall -Wextra and fail
# if the compiler prints any warning. Called by scripts/test.sh (a few seconds).
#
#   bash scripts/warnings.sh           # -fsyntax-only: all front-end warnings (seconds)
#   bash scripts/warnings.sh --full    # -O2 -c as well: the middle-end warnings such as
#                                      # -Wmaybe-uninitialized (about a minute)
#
# The project's flags are fpm's (fpm.toml [fortran] and its debug profile):
# -fimplicit-none -Werror=implicit-interface -ffree-form -fcoarray=single; -fopenmp as in
# the meson build (checks the OpenMP directives too). Two warning classes are off, for the
# reasons given where meson.build sets them (keep the three lists the same: here,
# meson.build's fortran_args and docs/guide/warnings.rst):
#   -Wno-unused-dummy-argument  deferred interfaces fix every override's argument list
#   -Wno-compare-reals          every remaining exact real comparison is intended
# Files are compiled in module dependency order (parsed from module/submodule/use lines),
# into a scratch module directory; the build trees are not touched.
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
FC="${FC:-gfortran}"
full=0
[ "${1:-}" = "--full" ] && full=1

flags=(-fimplicit-none -Werror=implicit-interface -ffree-form -fcoarray=single -fopenmp
       -Wall -Wextra -Wno-unused-dummy-argument -Wno-compare-reals)

scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT

# Dependency order: a file after the files defining the modules it uses (and, for a
# submodule, after its parent module). Modules from outside src/ (intrinsic ones) are ignored.
order="$(python3 - <<'PYEOF'
import re, subprocess, sys
files = subprocess.run([sys.executable, "tools/list_sources.py", "src"], check=True,
                       capture_output=True, text=True).stdout.split()
defines, needs = {}, {}
for f in files:
    needs[f] = set()
    for line in open(f, encoding="utf-8"):
        s = line.split("!", 1)[0].strip().lower()
        m = re.match(r"module\s+(\w+)\s*$", s)
        if m and m.group(1) != "procedure":
            defines[m.group(1)] = f
        m = re.match(r"submodule\s*\(\s*(\w+)", s)
        if m:
            needs[f].add(m.group(1))
        m = re.match(r"use\b(?:\s*,\s*(?:non_)?intrinsic)?\s*(?:::)?\s*(\w+)", s)
        if m and "intrinsic" not in s.split("::")[0]:
            needs[f].add(m.group(1))
done, out = set(), []
def visit(f, stack=()):
    if f in done:
        return
    if f in stack:
        sys.exit(f"warnings.sh: module dependency cycle through {f}")
    for mod in sorted(needs[f]):
        g = defines.get(mod)
        if g and g != f:
            visit(g, stack + (f,))
    done.add(f)
    out.append(f)
for f in files:
    visit(f)
print("\n".join(out))
PYEOF
)" || { echo "[warnings] FAILED: could not order the sources" >&2; exit 1; }

run_pass() {  # $1: label; rest: mode flags
    local label="$1" n_files=0 n_warn=0 f log
    shift
    rm -rf "$scratch/mod" && mkdir -p "$scratch/mod"
    log="$scratch/log"
    : >"$log"
    for f in $order; do
        n_files=$((n_files + 1))
        if ! "$FC" "${flags[@]}" "$@" -J "$scratch/mod" -I "$scratch/mod" "$f" \
            -o "$scratch/out.o" >>"$log" 2>&1; then
            cat "$log" >&2
            echo "[warnings] FAILED: $f does not compile ($label)" >&2
            return 1
        fi
    done
    n_warn=$(grep -c 'Warning:' "$log" || true)
    if [ "$n_warn" -ne 0 ]; then
        cat "$log" >&2
        echo "[warnings] FAILED: $n_warn compiler warnings in src/ ($label):" >&2
        grep -o '\[-W[a-z0-9-]*\]' "$log" | sort | uniq -c | sort -rn >&2
        return 1
    fi
    echo "[warnings] $n_files files in src/, 0 warnings ($label: $FC ${flags[*]} $*)"
}

run_pass "syntax" -fsyntax-only || exit 1
if [ "$full" -eq 1 ]; then
    run_pass "optimised" -O2 -c || exit 1
fi
exit 0
