#!/usr/bin/env bash
# Wall clock of ONE Kepler expansion written out for order 15 (conmech_taylor_fixed, the
# routine solve_ivp's method TAYLOR calls every step at tol 1e-12), for one or more
# compiled Taylor libraries side by side: rounds of 2000 expansions interleaved across the
# libraries, the fastest round of 400 per library (ns per expansion). Interleaving and the
# minimum make two forms of the routine comparable on a loaded machine, where a whole
# solve's time scatters by 2x. The libraries: conmech_<hash>.so in a CONMECH_CACHE whose
# .f90 is Kepler's routine "written out for order 15" (e.g. one cache per branch). The C
# driver is kept here, not as a .c file in bench/ (fpm would link it into its programs).
# Usage: bash bench/taylor_jet_wallclock.sh A.so [B.so ...]
set -euo pipefail
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cat > "$tmp/jet.c" <<'CEOF'
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

typedef void (*jet_t)(double, int, double *, double *);

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char **argv)
{
    enum { MAXLIB = 8, ORDER = 15, ROUNDS = 400, CALLS = 2000 };
    int nlib = argc - 1;
    jet_t f[MAXLIB];
    double best[MAXLIB];
    double w[(ORDER + 1) * 64] = {0}, p[4] = {0}, sink = 0.0;
    const double e = 0.9, y0[4] = {1 - e, 0.0, 0.0, sqrt((1 + e) / (1 - e))};
    if (nlib < 1 || nlib > MAXLIB) {
        fprintf(stderr, "usage: %s LIB.so [LIB.so ...] (at most %d)\n", argv[0], MAXLIB);
        return 2;
    }
    for (int i = 0; i < nlib; i++) {
        void *h = dlopen(argv[i + 1], RTLD_NOW | RTLD_LOCAL);
        if (!h || !(f[i] = (jet_t)dlsym(h, "conmech_taylor_fixed"))) {
            fprintf(stderr, "%s: no conmech_taylor_fixed (%s)\n", argv[i + 1], dlerror());
            return 1;
        }
        best[i] = INFINITY;
    }
    for (int r = 0; r < ROUNDS; r++) {
        for (int i = 0; i < nlib; i++) {
            double a = now();
            for (int c = 0; c < CALLS; c++) {
                for (int q = 0; q < 4; q++) w[(ORDER + 1) * q] = y0[q] + 1e-17 * c;
                f[i](0.0, ORDER, w, p);
                sink += w[ORDER];
            }
            double dt = (now() - a) / CALLS * 1e9;
            if (dt < best[i]) best[i] = dt;
        }
    }
    for (int i = 0; i < nlib; i++) printf("%.1f ns per expansion  %s\n", best[i], argv[i + 1]);
    return sink == 0.125;   /* keeps the results alive */
}
CEOF
cc -O2 -o "$tmp/jet" "$tmp/jet.c" -ldl -lm
"$tmp/jet" "$@"
