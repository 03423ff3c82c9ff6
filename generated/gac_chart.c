/*
 * gac_chart.c -- the two base charts of a free base (gac.h, "the two base charts"): the orientation and the joint
 * axes from the angles, the closed-form angles of an orientation, the rates of an angular velocity, and a state
 * converted from one chart to the other.  Plain 3 x 3 algebra, row-major.
 */
#include "gac_internal.h"

#include <math.h>

#define GAC_PI 3.14159265358979323846
#define GAC_RECOMPOSE_TOL 1e-11   /* max |R(angles) - R| accepted from the closed-form angles */

/* ---- a model's bases: one (gac_model.base), or several turning chains' (gac_model.nbase, bases, charts) ---- */
int gac_nbase(const gac_model *m)
{
    return m->nbase > 0 ? m->nbase : 1;
}

const gac_base *gac_model_base(const gac_model *m, int j)
{
    return m->nbase > 0 ? &m->bases[j] : &m->base;
}

const gac_chart *gac_model_chart(const gac_model *m, int j)
{
    return m->nbase > 0 ? &m->charts[j] : &m->chart;
}

const gac_model *gac_chart_model(const gac_model *a, int chart)
{
    if (chart == 0) return a;
    if (a->chart_models != 0) return chart > 0 && chart < 1 << a->nbase ? a->chart_models[chart] : 0;
    return chart == 1 ? a->chart_b : 0;
}

/* One chart's measure |a . (e_z x Rz(theta_0) b)| at q (gac_chart_measure's, for one base). */
double gac_chart_measure_of(const gac_chart *c, const double *q)
{
    const double *a = c->a, *b = c->b;
    const double theta0 = c->theta0_index >= 0 ? q[c->theta0_index] : c->theta0_value;
    const double cs = cos(theta0), sn = sin(theta0);
    return fabs(-a[0] * (sn * b[0] + cs * b[1]) + a[1] * (cs * b[0] - sn * b[1]));
}

/* C = A B (3 x 3); C may not alias A or B. */
static void mul3(const double *A, const double *B, double *C)
{
    int i, j;
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j) C[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
    }
}

/* M <- M Rz(angle). */
static void mul_rz(double *M, double angle)
{
    const double c = cos(angle), s = sin(angle);
    int i;
    for (i = 0; i < 3; ++i) {
        const double a = M[3 * i], b = M[3 * i + 1];
        M[3 * i] = a * c + b * s;
        M[3 * i + 1] = -a * s + b * c;
    }
}

/* T_-1 Rz(a) T_0 Rz(b) T_1 (the rotation before Rz(theta_1)). */
static void partial_rotation(const gac_base *c, double a, double b, double *P)
{
    double M[9], N[9];
    int i;
    for (i = 0; i < 9; ++i) M[i] = c->T_m1[i];
    mul_rz(M, a);
    mul3(M, c->T_0, N);
    mul_rz(N, b);
    mul3(N, c->T_1, P);
}

void gac_base_rotation(const gac_base *c, const double *angles, double *R)
{
    partial_rotation(c, angles[0], angles[1], R);
    mul_rz(R, angles[2]);
}

void gac_base_axes(const gac_base *c, const double *angles, double *E)
{
    double M[9], N[9];
    int i;
    for (i = 0; i < 9; ++i) M[i] = c->T_m1[i];
    for (i = 0; i < 3; ++i) E[3 * i] = M[3 * i + 2];                 /* u_-1 = T_-1 e_z */
    mul_rz(M, angles[0]);
    mul3(M, c->T_0, N);
    for (i = 0; i < 3; ++i) E[3 * i + 1] = N[3 * i + 2];             /* u_0 = T_-1 Rz(a) T_0 e_z */
    mul_rz(N, angles[1]);
    mul3(N, c->T_1, M);
    for (i = 0; i < 3; ++i) E[3 * i + 2] = M[3 * i + 2];             /* u_1 = ... Rz(b) T_1 e_z */
}

double gac_base_measure(const gac_base *c, const double *R)
{
    const double u[3] = {c->T_m1[2], c->T_m1[5], c->T_m1[8]}, z[3] = {R[2], R[5], R[8]};
    const double x = u[1] * z[2] - u[2] * z[1], y = u[2] * z[0] - u[0] * z[2], w = u[0] * z[1] - u[1] * z[0];
    return sqrt(x * x + y * y + w * w);
}

/* theta_1 given theta_-1 = a, theta_0 = b: Rz(theta_1) = P^T R, P = T_-1 Rz(a) T_0 Rz(b) T_1. */
static double third_angle(const gac_base *c, const double *R, double a, double b)
{
    double P[9];
    partial_rotation(c, a, b, P);
    return atan2(P[1] * R[0] + P[4] * R[3] + P[7] * R[6], P[0] * R[0] + P[3] * R[3] + P[6] * R[6]);
}

/* angle + 2 pi k nearest to reference. */
static double shift_near(double angle, double reference)
{
    return angle + 2.0 * GAC_PI * floor((reference - angle) / (2.0 * GAC_PI) + 0.5);
}

int gac_base_angles(const gac_base *c, const double *R, const double *near, double *angles)
{
    /* w = T_0^T e_z, v = T_1 e_z: theta_0 = phi puts z_1 along +u_-1 (the chart's lock, chi = |sin(theta_0 - phi)|) */
    const double w[3] = {c->T_0[6], c->T_0[7], c->T_0[8]}, v[3] = {c->T_1[2], c->T_1[5], c->T_1[8]};
    const double phi = atan2(w[1] * v[0] - w[0] * v[1], w[0] * v[0] + w[1] * v[1]);
    /* t = T_-1^T z_1: z_1 in frame -1 before Rz(theta_-1); |t_xy| = chi, t_z = u_-1 . z_1 */
    const double t[3] = {c->T_m1[0] * R[2] + c->T_m1[3] * R[5] + c->T_m1[6] * R[8],
                         c->T_m1[1] * R[2] + c->T_m1[4] * R[5] + c->T_m1[7] * R[8],
                         c->T_m1[2] * R[2] + c->T_m1[5] * R[5] + c->T_m1[8] * R[8]};
    const double s = hypot(t[0], t[1]);
    const int lock = s <= GAC_CHART_LOCK;
    double best[3] = {0.0, 0.0, 0.0}, check[9], cost_best = HUGE_VAL, error = 0.0;
    int sign, i;
    for (sign = -1; sign <= 1; sign += 2) {                 /* the principal branch first */
        const double b = phi + atan2(sign * s, t[2]);
        const double cb = cos(b), sb = sin(b);
        const double rv[3] = {cb * v[0] - sb * v[1], sb * v[0] + cb * v[1], v[2]};   /* Rz(b) v */
        const double g0 = c->T_0[0] * rv[0] + c->T_0[1] * rv[1] + c->T_0[2] * rv[2];  /* g = T_0 Rz(b) v */
        const double g1 = c->T_0[3] * rv[0] + c->T_0[4] * rv[1] + c->T_0[5] * rv[2];
        double x[3], cost;
        x[0] = lock ? (near != 0 ? near[0] : 0.0) : atan2(t[1], t[0]) - atan2(g1, g0);
        x[1] = b;
        x[2] = third_angle(c, R, x[0], x[1]);
        if (near == 0) {                                   /* the principal branch, wrapped to (-pi, pi] */
            for (i = 0; i < 3; ++i) best[i] = atan2(sin(x[i]), cos(x[i]));
            break;
        }
        cost = 0.0;
        for (i = 0; i < 3; ++i) {
            x[i] = shift_near(x[i], near[i]);
            cost += fabs(x[i] - near[i]);
        }
        if (cost < cost_best) {
            cost_best = cost;
            for (i = 0; i < 3; ++i) best[i] = x[i];
        }
    }
    gac_base_rotation(c, best, check);
    for (i = 0; i < 9; ++i) {
        if (fabs(check[i] - R[i]) > error) error = fabs(check[i] - R[i]);
    }
    if (!(error <= GAC_RECOMPOSE_TOL)) return GAC_ERR_BAD_MODEL;
    for (i = 0; i < 3; ++i) angles[i] = best[i];
    return GAC_OK;
}

/* det of a 3 x 3 matrix whose columns are a, b, c. */
static double det3(const double *a, const double *b, const double *c)
{
    return a[0] * (b[1] * c[2] - b[2] * c[1]) - b[0] * (a[1] * c[2] - a[2] * c[1]) + c[0] * (a[1] * b[2] - a[2] * b[1]);
}

/* Solve A x = y by Cramer's rule (A 3 x 3 row-major, det A != 0). */
static void solve3(const double *A, const double *y, double *x)
{
    const double c0[3] = {A[0], A[3], A[6]}, c1[3] = {A[1], A[4], A[7]}, c2[3] = {A[2], A[5], A[8]};
    const double d = det3(c0, c1, c2);
    x[0] = det3(y, c1, c2) / d;
    x[1] = det3(c0, y, c2) / d;
    x[2] = det3(c0, c1, y) / d;
}

void gac_base_rates(const gac_base *c, const double *angles, const double *omega, double *rates)
{
    double E[9], A[9], y[3], n[3] = {0.0, 0.0, 0.0}, size = 0.0;
    int i, j, k;
    gac_base_axes(c, angles, E);
    {
        const double e0[3] = {E[0], E[3], E[6]}, e1[3] = {E[1], E[4], E[7]}, e2[3] = {E[2], E[5], E[8]};
        if (fabs(det3(e0, e1, e2)) > GAC_CHART_LOCK) {
            solve3(E, omega, rates);
            return;
        }
    }
    /* At the lock E has rank 2: n, a unit null vector (E n = 0), is the largest cross product of two rows, and
     * (E^T E + n n^T) x = E^T omega gives the least-squares rates of least norm (n . x = 0). */
    for (i = 0; i < 3; ++i) {
        for (j = i + 1; j < 3; ++j) {
            const double *a = E + 3 * i, *b = E + 3 * j;
            const double x[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
            const double norm = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
            if (norm > size) {
                size = norm;
                for (k = 0; k < 3; ++k) n[k] = x[k] / norm;
            }
        }
    }
    for (i = 0; i < 3; ++i) {
        y[i] = E[i] * omega[0] + E[3 + i] * omega[1] + E[6 + i] * omega[2];
        for (j = 0; j < 3; ++j) A[3 * i + j] = E[i] * E[j] + E[3 + i] * E[3 + j] + E[6 + i] * E[6 + j] + n[i] * n[j];
    }
    solve3(A, y, rates);
}

int gac_chart_convert(const gac_base *from, const gac_base *to, int nq, const double *x, const double *near,
                      double *out)
{
    double angles[3], rates[3], R[9], E[9], omega[3], theta[3], thetadot[3];
    int i, code;
    for (i = 0; i < 3; ++i) {
        if (from->index[i] < 0 || from->index[i] >= nq || to->index[i] != from->index[i]) return GAC_ERR_BAD_MODEL;
        theta[i] = x[from->index[i]];
        thetadot[i] = x[nq + from->index[i]];
    }
    gac_base_rotation(from, theta, R);
    gac_base_axes(from, theta, E);
    for (i = 0; i < 3; ++i) omega[i] = E[3 * i] * thetadot[0] + E[3 * i + 1] * thetadot[1] + E[3 * i + 2] * thetadot[2];
    code = gac_base_angles(to, R, near, angles);
    if (code != GAC_OK) return code;
    gac_base_rates(to, angles, omega, rates);
    if (out != x) gac_copy(out, x, 2 * nq);
    for (i = 0; i < 3; ++i) {
        out[to->index[i]] = angles[i];
        out[nq + to->index[i]] = rates[i];
    }
    return GAC_OK;
}

/* c = a x b. */
static void cross3(const double *a, const double *b, double *c)
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* dE v, the derivative of E(angles) along dangles applied to v: each axis turns about the axes before it,
 * du_-1 = 0, du_0 = (u_-1 da) x u_0, du_1 = (u_-1 da + u_0 db) x u_1 (da, db = dangles[0], [1]), so
 *     dE v = v[1] (u_-1 da) x u_0 + v[2] (u_-1 da + u_0 db) x u_1. */
static void axes_tangent(const double *E, const double *dangles, const double *v, double *out)
{
    const double u_m1[3] = {E[0], E[3], E[6]}, u_0[3] = {E[1], E[4], E[7]}, u_1[3] = {E[2], E[5], E[8]};
    double turn[3], a[3], b[3];
    int i;
    for (i = 0; i < 3; ++i) turn[i] = u_m1[i] * dangles[0];
    cross3(turn, u_0, a);
    for (i = 0; i < 3; ++i) turn[i] += u_0[i] * dangles[1];
    cross3(turn, u_1, b);
    for (i = 0; i < 3; ++i) out[i] = v[1] * a[i] + v[2] * b[i];
}

int gac_chart_convert_tangent(const gac_base *from, const gac_base *to, int nq, const double *x, const double *y,
                              int k, double *S)
{
    double th_a[3], thd_a[3], th_b[3], thd_b[3], E_a[9], E_b[9];
    int i, j;
    for (i = 0; i < 3; ++i) {
        if (from->index[i] < 0 || from->index[i] >= nq || to->index[i] != from->index[i]) return GAC_ERR_BAD_MODEL;
        th_a[i] = x[from->index[i]];
        thd_a[i] = x[nq + from->index[i]];
        th_b[i] = y[to->index[i]];
        thd_b[i] = y[nq + to->index[i]];
    }
    gac_base_axes(from, th_a, E_a);
    gac_base_axes(to, th_b, E_b);
    {
        const double c0[3] = {E_b[0], E_b[3], E_b[6]}, c1[3] = {E_b[1], E_b[4], E_b[7]}, c2[3] = {E_b[2], E_b[5], E_b[8]};
        if (!(fabs(det3(c0, c1, c2)) > GAC_CHART_LOCK)) return GAC_ERR_GIMBAL_LOCK;
    }
    for (j = 0; j < k; ++j) {
        double *dx = S + (long)j * 2 * nq, dth[3], dthd[3], w[3], dE_a[3], dE_b[3], dth_b[3], dthd_b[3];
        for (i = 0; i < 3; ++i) {
            dth[i] = dx[from->index[i]];
            dthd[i] = dx[nq + from->index[i]];
        }
        /* the same angular displacement on both charts: E_b dth_b = E_a dth */
        for (i = 0; i < 3; ++i) w[i] = E_a[3 * i] * dth[0] + E_a[3 * i + 1] * dth[1] + E_a[3 * i + 2] * dth[2];
        solve3(E_b, w, dth_b);
        /* the same omega, E_b thd_b = E_a thd_a, differentiated:
         * E_b dthd_b = dE_a[dth] thd_a + E_a dthd - dE_b[dth_b] thd_b */
        axes_tangent(E_a, dth, thd_a, dE_a);
        axes_tangent(E_b, dth_b, thd_b, dE_b);
        for (i = 0; i < 3; ++i)
            w[i] = dE_a[i] + E_a[3 * i] * dthd[0] + E_a[3 * i + 1] * dthd[1] + E_a[3 * i + 2] * dthd[2] - dE_b[i];
        solve3(E_b, w, dthd_b);
        for (i = 0; i < 3; ++i) {
            dx[to->index[i]] = dth_b[i];
            dx[nq + to->index[i]] = dthd_b[i];
        }
    }
    return GAC_OK;
}
