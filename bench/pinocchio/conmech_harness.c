/* Calls a conmech model library's conmech_accel or conmech_accel_jac `reps` times (for
   callgrind: instructions per call = (I(2 R) - I(R)) / R; for timing: the wall time of the
   loop). Usage: conmech_harness LIB.so N REPS WHICH(0 accel, 1 accel_jac) NPARAMS [g] */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
typedef void (*acc_t)(double, const double *, const double *, double *, const double *);
typedef void (*accj_t)(double, const double *, const double *, double *, double *,
                       const double *);
int main(int argc, char **argv) {
    if (argc < 6) return 2;
    void *h = dlopen(argv[1], RTLD_NOW);
    if (!h) { fprintf(stderr, "%s\n", dlerror()); return 1; }
    int n = atoi(argv[2]), reps = atoi(argv[3]), which = atoi(argv[4]), np = atoi(argv[5]);
    double q[128], v[128], a[128], p[128], *J = malloc(sizeof(double) * 2 * 128 * 128);
    for (int i = 0; i < n; i++) { q[i] = 0.3 + 0.1 * i; v[i] = -0.2 + 0.05 * i; }
    for (int i = 0; i < np; i++) p[i] = 0.0;
    if (np > 0 && argc > 6) p[0] = atof(argv[6]);
    acc_t f = (acc_t)dlsym(h, "conmech_accel");
    accj_t g = (accj_t)dlsym(h, "conmech_accel_jac");
    struct timespec t0, t1;
    double s = 0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (int r = 0; r < reps; r++) {
        q[0] += 1e-9;
        if (which == 0) f(0.0, q, v, a, p); else g(0.0, q, v, a, J, p);
        s += a[n - 1] + (which ? J[n * n] : 0.0);
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    printf("%.17g %.9f\n", s, (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec));
    return 0;
}
