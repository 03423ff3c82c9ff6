/*
 * gac_inverse.c -- inverse dynamics from a model's O(n) operators: the generalised forces that give the chain a
 * chosen acceleration.  With I_f qdd = R(q, qd, u) + tau in flight (R holding gravity, the velocity products, the
 * inputs, joint springs and dampers), tau = I_f qdd - R = I_f (qdd - qdd_free), qdd_free the forward dynamics:
 * one forward dynamics and one generalised momentum, O(n) each, exact to round-off (no difference quotients).
 */
#include "gac_internal.h"

void gac_inverse_dynamics(const gac_model *m, const double *q, const double *qd, const double *qdd, const double *u,
                          const double *p, double *tau)
{
    const int nq = m->nq;
    double delta[nq];
    int i;
    m->forward_dynamics(q, qd, u, p, delta);          /* qdd_free */
    for (i = 0; i < nq; ++i) delta[i] = qdd[i] - delta[i];
    m->generalized_momentum(q, delta, p, tau);        /* tau = I_f (qdd - qdd_free) */
}
