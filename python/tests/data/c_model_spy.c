/* A generalized-coordinate model library (conmech_model_library's convention) that counts
   the calls of each entry point: the pendulum M = m l^2, Q = -m g l sin q, p = [m, l, g].
   Built with -DFAST it also exports conmech_mass_forces and conmech_accel. At exit the
   counts are written to the file named by $CONMECH_SPY_OUT (if set): "mass forces
   mass_forces accel". */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static long n_mass = 0, n_forces = 0, n_mf = 0, n_accel = 0;

void conmech_model_info(int info[6]) {
    info[0] = 2; info[1] = 1; info[2] = 0; info[3] = 0; info[4] = 0; info[5] = 3;
}
void conmech_model_params(double *p) { p[0] = 1.0; p[1] = 1.0; p[2] = 9.81; }
void conmech_model_param_names(char *buf, int len) { strncpy(buf, "m l g", len); }
void conmech_mass(double t, const double *q, double *M, const double *p) {
    n_mass++;
    M[0] = p[0]*p[1]*p[1];
}
void conmech_forces(double t, const double *q, const double *v, double *Q, const double *p) {
    n_forces++;
    Q[0] = -p[0]*p[2]*p[1]*sin(q[0]);
}
#ifdef FAST
void conmech_mass_forces(double t, const double *q, const double *v, double *M, double *Q,
                         const double *p) {
    n_mf++;
    M[0] = p[0]*p[1]*p[1];
    Q[0] = -p[0]*p[2]*p[1]*sin(q[0]);
}
void conmech_accel(double t, const double *q, const double *v, double *a, const double *p) {
    n_accel++;
    a[0] = -p[2]*sin(q[0])/p[1];
}
#endif
__attribute__((destructor)) static void spy_report(void) {
    const char *out = getenv("CONMECH_SPY_OUT");
    FILE *f;
    if (!out) return;
    f = fopen(out, "w");
    if (!f) return;
    fprintf(f, "%ld %ld %ld %ld\n", n_mass, n_forces, n_mf, n_accel);
    fclose(f);
}
