/*
 * gac_dense.c -- the dense matrices of a model, formed from its O(n) operators: the inertia matrix I_f, the
 * flight right-hand side R and the contact Jacobian J.  The hybrid loop never needs them (it applies I_f^-1,
 * I_f and J^T through the kernels); they are for analysis, and for the NAME_mass_matrix, NAME_bias and
 * NAME_contact_jacobian of a model generated without its dense kernels.  O(n) work per column: O(n^2) each.
 */
#include "gac_internal.h"

void gac_mass_matrix(const gac_model *m, const double *q, const double *p, double *M)
{
    const int nq = m->nq;
    double e[nq];
    int i, j;
    for (j = 0; j < nq; ++j) e[j] = 0.0;
    for (j = 0; j < nq; ++j) {               /* row j = I_f e_j, column j of a symmetric matrix */
        e[j] = 1.0;
        m->generalized_momentum(q, e, p, M + (long)j * nq);
        e[j] = 0.0;
    }
    for (i = 0; i < nq; ++i) {
        for (j = 0; j < i; ++j) {
            const double mean = 0.5 * (M[(long)i * nq + j] + M[(long)j * nq + i]);
            M[(long)i * nq + j] = M[(long)j * nq + i] = mean;
        }
    }
}

void gac_bias(const gac_model *m, const double *q, const double *qd, const double *u, const double *p, double *R)
{
    double qdd[m->nq];
    m->forward_dynamics(q, qd, u, p, qdd);
    m->generalized_momentum(q, qdd, p, R);  /* R = I_f qdd */
}

void gac_contact_jacobian(const gac_model *m, const double *q, const double *p, double *J)
{
    double f[GAC_AT_LEAST_1(m->njrow)];
    int r;
    for (r = 0; r < m->njrow; ++r) f[r] = 0.0;
    for (r = 0; r < m->njrow; ++r) {         /* row r = J^T e_r */
        f[r] = 1.0;
        m->contact_generalized_force(q, f, p, J + (long)r * m->nq);
        f[r] = 0.0;
    }
}
