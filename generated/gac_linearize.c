/*
 * gac_linearize.c -- the flight dynamics linearised at a state: x_dot = f(x, u), x = [q, qd], A = df/dx and
 * B = df/du, column by column from the model's tangent kernel (the forward-mode derivative of its forward dynamics,
 * codegen/tangent.py): exact to round-off, no difference quotients, nx + nu calls of O(n) each.
 */
#include "gac_internal.h"

int gac_linearize(const gac_model *m, const double *q, const double *qd, const double *u, const double *p, double *A,
                  double *B)
{
    int nq, nx, nu, i, j;
    if (m == 0 || q == 0 || qd == 0 || p == 0 || A == 0 || (m->nu > 0 && (B == 0 || u == 0)))
        return GAC_ERR_NULL_ARGUMENT;
    if (m->forward_dynamics_tangent == 0) return GAC_ERR_BAD_MODEL;
    nq = m->nq;
    nx = m->nx;
    nu = m->nu;
    {
        double seed[2 * nq + (nu > 0 ? nu : 1) + (m->nparam > 0 ? m->nparam : 1)];   /* [dq, dqd | du | dp] */
        double dqdd[nq];
        double *dx = seed, *du = seed + nx, *dp = du + (nu > 0 ? nu : 1);
        for (i = 0; i < (int)(sizeof seed / sizeof seed[0]); ++i) seed[i] = 0.0;
        for (j = 0; j < nx + nu; ++j) {                          /* column j: x_j (j < nx), else u_(j - nx) */
            double *column = j < nx ? A + j : B + (j - nx);
            const int stride = j < nx ? nx : nu;
            if (j < nx) dx[j] = 1.0; else du[j - nx] = 1.0;
            m->forward_dynamics_tangent(q, qd, u, p, dx, dx + nq, du, dp, dqdd);
            if (j < nx) dx[j] = 0.0; else du[j - nx] = 0.0;
            for (i = 0; i < nq; ++i) {
                column[i * stride] = j < nx && j == nq + i ? 1.0 : 0.0;   /* d(qd_i)/dx_j: the upper blocks [0 I] */
                column[(nq + i) * stride] = dqdd[i];
            }
        }
    }
    return GAC_OK;
}
