/* Test systems with conmech's C signatures (python/conmech/mechanics/compiled.py). */
#include <math.h>

/* Kepler, y = [x, y, vx, vy], p = [mu] */
void kepler_rhs(double t, const double *y, double *f, const double *p) {
    double r2 = y[0]*y[0] + y[1]*y[1], r3 = r2*sqrt(r2);
    f[0] = y[2]; f[1] = y[3]; f[2] = -p[0]*y[0]/r3; f[3] = -p[0]*y[1]/r3;
}
void kepler_jac(double t, const double *y, double *J, const double *p) {
    double x = y[0], yy = y[1], r2 = x*x + yy*yy, r = sqrt(r2), r3 = r2*r, r5 = r3*r2;
    int i;
    for (i = 0; i < 16; i++) J[i] = 0.0;
    J[0 + 4*2] = 1.0; J[1 + 4*3] = 1.0;
    J[2 + 4*0] = p[0]*(3*x*x/r5 - 1/r3); J[2 + 4*1] = p[0]*3*x*yy/r5;
    J[3 + 4*0] = p[0]*3*x*yy/r5;         J[3 + 4*1] = p[0]*(3*yy*yy/r5 - 1/r3);
}

/* cart pendulum (the lecture notes, theta from the upright), q = [x, th], p = [M, m, l, g] */
void cart_mass(double t, const double *q, double *M, const double *p) {
    double c = cos(q[1]);
    M[0] = p[0] + p[1]; M[1] = p[1]*p[2]*c; M[2] = p[1]*p[2]*c; M[3] = p[1]*p[2]*p[2];
}
void cart_forces(double t, const double *q, const double *v, double *Q, const double *p) {
    double s = sin(q[1]);
    Q[0] = p[1]*p[2]*s*v[1]*v[1]; Q[1] = p[1]*p[3]*p[2]*s;
}
/* R = [dQ/dq - d(M a)/dq, dQ/dv], 2 x 4 column-major */
void cart_forces_jac(double t, const double *q, const double *v, const double *a, double *R,
                     const double *p) {
    double s = sin(q[1]), c = cos(q[1]), ml = p[1]*p[2];
    R[0] = 0; R[1] = 0;                                  /* d/dx */
    R[2] = ml*c*v[1]*v[1] + ml*s*a[1];                   /* d/dth, row 1 */
    R[3] = p[1]*p[3]*p[2]*c + ml*s*a[0];                 /* d/dth, row 2 */
    R[4] = 0; R[5] = 0;                                  /* d/dx' */
    R[6] = 2*ml*s*v[1]; R[7] = 0;                        /* d/dth' */
}
double cart_energy(double t, const double *q, const double *v, const double *p) {
    double c = cos(q[1]);
    return 0.5*(p[0] + p[1])*v[0]*v[0] + p[1]*p[2]*c*v[0]*v[1]
           + 0.5*p[1]*p[2]*p[2]*v[1]*v[1] + p[1]*p[3]*p[2]*c;
}

/* Cartesian pendulum, q = [x, y], phi = (x^2 + y^2 - l^2)/2, p = [m, g, l] */
void pxy_mass(double t, const double *q, double *M, const double *p) {
    M[0] = p[0]; M[1] = 0; M[2] = 0; M[3] = p[0];
}
void pxy_forces(double t, const double *q, const double *v, double *Q, const double *p) {
    Q[0] = 0; Q[1] = -p[0]*p[1];
}
void pxy_phi(double t, const double *q, double *c, const double *p) {
    c[0] = 0.5*(q[0]*q[0] + q[1]*q[1] - p[2]*p[2]);
}
void pxy_phi_jac(double t, const double *q, double *G, const double *p) {
    G[0] = q[0]; G[1] = q[1];
}
void pxy_phi_gamma(double t, const double *q, const double *v, double *g, const double *p) {
    g[0] = -(v[0]*v[0] + v[1]*v[1]);
}
double pxy_energy(double t, const double *q, const double *v, const double *p) {
    return 0.5*p[0]*(v[0]*v[0] + v[1]*v[1]) + p[0]*p[1]*q[1];
}
