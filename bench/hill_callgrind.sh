#!/usr/bin/env bash
# Instructions per orbit of the Hill variation-orbit family (10,000 points, m in
# [0.01, 0.15], one thread; bench/hill_family_ir.f90) by callgrind, for this tree and
# optionally a base revision built the same way, with a timing ratio from the same run
# (alternating, best of 5). valgrind cannot decode AVX-512: built without -march=native.
# Usage (repository root, fpm + valgrind on PATH): bash bench/hill_callgrind.sh [BASE_REF] [N]
set -euo pipefail
cd "$(dirname "$0")/.."
FF="${FFLAGS:--O3 -funroll-loops}"
base="${1:-}"
n="${2:-2000}"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
build() {  # build SRC_DIR OUT_EXE
    (cd "$1" && fpm install --prefix "$tmp/p.$(basename "$2")" --profile release \
        --flag "$FF" >"$tmp/build.$(basename "$2").log" 2>&1) \
        || { tail -5 "$tmp/build.$(basename "$2").log"; exit 1; }
    local lib; lib=$(ls -d "$tmp/p.$(basename "$2")"/lib* | head -1)
    mkdir -p "$tmp/mod.$(basename "$2")"
    gfortran $FF -I"$tmp/p.$(basename "$2")/include" -J "$tmp/mod.$(basename "$2")" \
        bench/hill_family_ir.f90 -L"$lib" -lconmech -llapack -lblas -o "$2"
}
ir() {  # ir EXE N
    valgrind --tool=callgrind --callgrind-out-file="$tmp/cg.out" "$1" "$2" >/dev/null 2>&1
    grep -E '^(summary|totals):' "$tmp/cg.out" | head -1 | awk '{print $2}'
}
build . "$tmp/new"
if [ -n "$base" ]; then
    mkdir -p "$tmp/base_src"
    git archive "$base" | tar -x -C "$tmp/base_src"
    build "$tmp/base_src" "$tmp/base"
fi
echo "flags: $FF; family of $n orbits, m in [0.01, 0.15], one thread"
per() { echo $(( ($(ir "$1" "$n") - $(ir "$1" 1)) / (n - 1) )); }
pnew=$(per "$tmp/new")
echo "instructions per orbit, this tree: $pnew   ($("$tmp/new" "$n" 1))"
if [ -n "$base" ]; then
    pbase=$(per "$tmp/base")
    echo "instructions per orbit, $base: $pbase   ($("$tmp/base" "$n" 1))"
    awk -v a="$pbase" -v b="$pnew" 'BEGIN{printf "instruction ratio base/new: %.3f\n", a/b}'
    tb=1e9; tn=1e9
    for k in 1 2 3 4 5; do
        x=$("$tmp/base" 10000 1 | awk '{print $2}'); tb=$(awk -v a="$tb" -v b="$x" 'BEGIN{print (b<a)?b:a}')
        x=$("$tmp/new" 10000 1 | awk '{print $2}'); tn=$(awk -v a="$tn" -v b="$x" 'BEGIN{print (b<a)?b:a}')
    done
    echo "us/orbit (10,000 orbits, best of 5, alternating): base $tb, this tree $tn"
    awk -v a="$tb" -v b="$tn" 'BEGIN{printf "time ratio base/new: %.3f\n", a/b}'
fi
