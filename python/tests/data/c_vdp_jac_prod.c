/* Van der Pol's oscillator x'' - mu (1 - x^2) x' + x = 0 with conmech's C signatures
   (compiled.ode_system): rhs, the dense Jacobian and the Jacobian product, the product
   with a call counter (tests check that continuation in mu uses it). p = [mu]. */
static long vdp_jp_calls = 0;

void vdp_rhs(double t, const double *y, double *f, const double *p) {
    (void)t;
    f[0] = y[1];
    f[1] = p[0]*(1.0 - y[0]*y[0])*y[1] - y[0];
}

/* column-major 2 x 2 */
void vdp_jac(double t, const double *y, double *J, const double *p) {
    (void)t;
    J[0] = 0.0; J[1] = -2.0*p[0]*y[0]*y[1] - 1.0;
    J[2] = 1.0; J[3] = p[0]*(1.0 - y[0]*y[0]);
}

/* jx = J(y) x for a 2 x k block x */
void vdp_jac_prod(double t, const double *y, int k, const double *x, double *jx,
                  const double *p) {
    double j10 = -2.0*p[0]*y[0]*y[1] - 1.0, j11 = p[0]*(1.0 - y[0]*y[0]);
    int c;
    (void)t;
    vdp_jp_calls++;
    for (c = 0; c < k; c++) {
        jx[2*c] = x[2*c + 1];
        jx[2*c + 1] = j10*x[2*c] + j11*x[2*c + 1];
    }
}

long vdp_jac_prod_calls(void) { return vdp_jp_calls; }
