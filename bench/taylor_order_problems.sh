#!/usr/bin/env bash
# Taylor's order rule over the five work-precision problems, in wall clock against heyoka
# (bench/taylor_order_sweep.sh counts instructions on Kepler's orbit alone). For each raise
# D over Jorba and Zou's p0 = ceil(-ln(tol)/2 + 1) given ("rule": the library's own
# p0 + max(3, p0/5)), the package is built from a copy of the repository whose
# taylor_order returns p0 + D (the Fortran conmech_taylor_core and the Python
# conmech.ivp.taylor alike; taylor_decay lengthens the step to match) and installed into a
# directory of its own, and bench/taylor_work_precision.py runs on it (fresh model cache,
# heyoka in the same process). Printed per problem and raise: the sums over tol = 1e-9 ..
# 1e-14 of the times of conmech.Propagator (the final state alone, as heyoka's
# propagate_until), of solve_ivp's TAYLOR and of heyoka, the ratio Propagator / heyoka of
# the sums, and the largest error at the end of the period. The tables of each run are
# kept beside the summary (OUT_DIR, default a temporary directory that is removed).
# Usage (from the repository root; PYTHON with numpy, sympy, meson-python and heyoka):
#   PYTHON=.venv/bin/python bash bench/taylor_order_problems.sh [D ...]   (default: rule 0 5 7)
set -euo pipefail
cd "$(dirname "$0")/.."
PY="$(command -v "${PYTHON:-python3}")"
PY="$(cd "$(dirname "$PY")" && pwd)/$(basename "$PY")"
# meson and ninja of the same environment (meson-python runs them)
export PATH="$(dirname "$PY"):$PATH"
RAISES="${*:-rule 0 5 7}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
out_dir="${OUT_DIR:-$work/tables}"
mkdir -p "$out_dir"
"$PY" -c "import heyoka" 2>/dev/null || { echo "heyoka is not installed for $PY"; exit 1; }
git ls-files -z | tar --null -T - -cf - | (mkdir -p "$work/repo" && tar -C "$work/repo" -xf -)
core="$work/repo/src/ode/conmech_taylor_core.f90"
pyorder="$work/repo/python/conmech/ivp/taylor.py"
grep -q 'taylor_order = p0 + max(3, p0/5)' "$core" ||
    { echo "taylor_order's rule not found in $core"; exit 1; }
grep -q 'return p0 + max(3, p0//5)' "$pyorder" ||
    { echo "taylor_order's rule not found in $pyorder"; exit 1; }
cp "$core" "$work/core.f90"
cp "$pyorder" "$work/taylor.py"
echo "load: $(cut -d' ' -f1-3 /proc/loadavg); $(date -u '+%Y-%m-%d %H:%M UTC')"
for d in $RAISES; do
    cp "$work/core.f90" "$core"
    cp "$work/taylor.py" "$pyorder"
    if [ "$d" != rule ]; then
        sed -i "s|taylor_order = p0 + max(3, p0/5)|taylor_order = p0 + $d|" "$core"
        sed -i "s|return p0 + max(3, p0//5)|return p0 + $d|" "$pyorder"
    fi
    site="$work/site-$d"
    "$PY" -m pip install -q --no-build-isolation --no-deps --target "$site" \
        -Cbuild-dir="$work/build-$d" "$work/repo" >"$work/pip-$d.log" 2>&1 ||
        { tail -5 "$work/pip-$d.log"; exit 1; }
    mkdir -p "$work/cache-$d"
    (cd "$work/repo" && PYTHONPATH="$site" CONMECH_CACHE="$work/cache-$d" "$PY" \
        bench/taylor_work_precision.py --rounds 5 --calls 5 \
        --problems kepler arenstorf pcr3bp halo pendulum \
        --out "$out_dir/order-$d.md" >/dev/null)
done
echo "load: $(cut -d' ' -f1-3 /proc/loadavg); $(date -u '+%Y-%m-%d %H:%M UTC')"
"$PY" - "$out_dir" $RAISES <<'PYEOF'
import re, sys
out_dir, raises = sys.argv[1], sys.argv[2:]


def load(path):
    """{problem: [(tol, solve_ivp us, Propagator us, heyoka us, error)]} of a table."""
    rows, prob = {}, None
    for line in open(path):
        if line.startswith("### "):
            prob = line[4:].strip()
        m = re.match(r"\| (1e-\d+) \|", line)
        if m and prob and 1e-14 <= float(m.group(1)) <= 1e-9:
            c = [x.strip() for x in line.split("|")[1:-1]]
            rows.setdefault(prob, []).append(
                (float(c[0]), float(c[1].split("/")[0]), float(c[8]),
                 float(c[2].split("/")[0]), float(c[1].split("/")[1])))
    return rows


tables = {d: load(f"{out_dir}/order-{d}.md") for d in raises}
print("| problem | raise | Propagator us | solve_ivp us | heyoka us | Propagator / heyoka "
      "| largest error |")
print("|---|---|---|---|---|---|---|")
for prob in ("kepler", "arenstorf", "pcr3bp", "halo", "pendulum"):
    for d in raises:
        r = tables[d][prob]
        sp, st, sh = (sum(x[i] for x in r) for i in (2, 1, 3))
        print(f"| {prob} | {d} | {sp:.1f} | {st:.1f} | {sh:.1f} | {sp/sh:.3f} "
              f"| {max(x[4] for x in r):.1e} |")
PYEOF
