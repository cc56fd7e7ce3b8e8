#!/usr/bin/env bash
# The cost gfortran adds to every call of a procedure that sees an intrinsic IEEE module's
# names (bench/results/fp_environment.md): two external procedures doing the same work,
# compiled separately (no inlining), timed over 1e7 calls each; and the symbols they import.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
gfortran -O2 -J "$tmp" -c ieee_user.f90 -o "$tmp/ieee_user.o"
gfortran -O2 -J "$tmp" -c time_calls.f90 -o "$tmp/time_calls.o"
gfortran "$tmp/time_calls.o" "$tmp/ieee_user.o" -o "$tmp/time_calls"
"$tmp/time_calls"
echo "calls in sees_ieee: $(objdump -dr "$tmp/ieee_user.o" | awk '/<sees_ieee_>:/{f=1} /<plain_>:/{f=0} f && /R_X86_64_PLT32/{print $NF}' | tr '\n' ' ')"
