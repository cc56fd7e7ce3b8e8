/* A Jacobian product with conmech's C signature (compiled.ode_system(jac_prod=...)) for
   the Kepler system of c_systems.c, with a call counter (tests check that it is used). */
#include <math.h>

static long kepler_jp_calls = 0;

/* jx = J(y) x for an n x k block x (column-major), n = 4, p = [mu] */
void kepler_jac_prod(double t, const double *y, int k, const double *x, double *jx,
                     const double *p) {
    double a = y[0], b = y[1], r2 = a*a + b*b, r = sqrt(r2), r3 = r2*r, r5 = r3*r2;
    double j00 = p[0]*(3*a*a/r5 - 1/r3), j01 = p[0]*3*a*b/r5, j11 = p[0]*(3*b*b/r5 - 1/r3);
    int c;
    kepler_jp_calls++;
    for (c = 0; c < k; c++) {
        const double *xc = x + 4*c;
        double *o = jx + 4*c;
        o[0] = xc[2]; o[1] = xc[3];
        o[2] = j00*xc[0] + j01*xc[1];
        o[3] = j01*xc[0] + j11*xc[1];
    }
}
long kepler_jac_prod_calls(void) { return kepler_jp_calls; }

/* the model-library name of the product (c_model_kepler.c + this file = a Kepler model
   library with conmech_jac_prod) */
void conmech_jac_prod(double t, const double *y, int k, const double *x, double *jx,
                      const double *p) {
    kepler_jac_prod(t, y, k, x, jx, p);
}
