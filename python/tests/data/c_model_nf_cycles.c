/* A conmech model library (conmech_model_library's convention), p = [p]: the 7-dim
   normal-form cycles of test/test_continuation.f90. The cycle x = cos t, y = sin t
   (period 2 pi for every p) carries, by construction, a Moebius band (u, w) turning by
   half the angle with xi' = diag(p - 1, -1) xi - |xi|^2 xi in the half-angle frame
   (period doubling at p = 1, the doubled orbit has u^2 + w^2 = p - 1), z' = (p - 2) z - z^3
   (pitchfork branch point at p = 2, new orbits z^2 = p - 2) and
   v' = (p - 3 + i alpha) v - |v|^2 v (Neimark-Sacker at p = 3). */
#include <math.h>
#include <string.h>
void conmech_model_info(int info[6]) {
    info[0] = 1; info[1] = 7; info[2] = 0; info[3] = 0; info[4] = 0; info[5] = 1;
}
void conmech_model_params(double *p) { p[0] = 0.0; }
void conmech_model_param_names(char *buf, int len) { strncpy(buf, "p", len); }
void conmech_rhs(double t, const double *y, double *f, const double *p) {
    const double alpha = 0.4472135954999579;
    double r2 = y[0]*y[0] + y[1]*y[1], r = sqrt(r2), c = y[0]/r, s = y[1]/r;
    double a = p[0] - 1.0, b = -1.0, q2 = y[2]*y[2] + y[3]*y[3];
    double v2 = y[5]*y[5] + y[6]*y[6];
    (void)t;
    f[0] = y[0]*(1.0 - r2) - y[1];
    f[1] = y[1]*(1.0 - r2) + y[0];
    f[2] = -0.5*y[3] + 0.5*(a + b)*y[2] + 0.5*(a - b)*(c*y[2] + s*y[3]) - q2*y[2];
    f[3] = 0.5*y[2] + 0.5*(a + b)*y[3] + 0.5*(a - b)*(s*y[2] - c*y[3]) - q2*y[3];
    f[4] = (p[0] - 2.0)*y[4] - y[4]*y[4]*y[4];
    f[5] = (p[0] - 3.0)*y[5] - alpha*y[6] - v2*y[5];
    f[6] = (p[0] - 3.0)*y[6] + alpha*y[5] - v2*y[6];
}
