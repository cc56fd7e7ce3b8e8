/* A conmech model library (conmech_model_library's convention): Kepler, p = [mu]. */
#include <math.h>
#include <string.h>
void conmech_model_info(int info[6]) {
    info[0] = 1; info[1] = 4; info[2] = 0; info[3] = 0; info[4] = 0; info[5] = 1;
}
void conmech_model_params(double *p) { p[0] = 1.0; }
void conmech_model_param_names(char *buf, int len) { strncpy(buf, "mu", len); }
void conmech_rhs(double t, const double *y, double *f, const double *p) {
    double r2 = y[0]*y[0] + y[1]*y[1], r3 = r2*sqrt(r2);
    f[0] = y[2]; f[1] = y[3]; f[2] = -p[0]*y[0]/r3; f[3] = -p[0]*y[1]/r3;
}
