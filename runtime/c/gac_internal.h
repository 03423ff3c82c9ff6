/*
 * gac_internal.h -- functions shared between the library's source files (not part of the API).
 */
#ifndef GAC_INTERNAL_H
#define GAC_INTERNAL_H

#include "gac.h"

#define GAC_EPS 2.220446049250313e-16

/* Contacts one complementarity solve takes: min(nq, GAC_LCP_CAP). */
#define GAC_MAX_LCP(m) ((m)->nq < GAC_LCP_CAP ? (m)->nq : GAC_LCP_CAP)

/* max(n, 1): the length of an array with one entry per contact or per Jacobian row, never 0. */
#define GAC_AT_LEAST_1(n) ((n) > 0 ? (n) : 1)

/* The impact work array (gac_impact_nwork doubles): Y (nq*nq; row a = I_f^-1 n_a of active contact a) |
 * A (nq*nq; N I_f^-1 N^T, nactive x nactive, row-major) | g (nq) | vel (3 npoint) | f (max(njrow, 1)). */
#define GAC_WORK_Y(m, w)   (w)
#define GAC_WORK_A(m, w)   ((w) + (long)(m)->nq * (m)->nq)
#define GAC_WORK_G(m, w)   ((w) + 2L * (m)->nq * (m)->nq)
#define GAC_WORK_VEL(m, w) (GAC_WORK_G(m, w) + (m)->nq)
#define GAC_WORK_F(m, w)   (GAC_WORK_VEL(m, w) + 3L * (m)->npoint)
/* and for a model with friction: Z (nq*nq; row a = I_f^-1 J_t^T phi_a, the response to contact a's unit friction
 * force) | B (nq*nq; the normal rows applied to the normal and friction directions, nactive x nactive). */
#define GAC_WORK_Z(m, w)   (GAC_WORK_F(m, w) + GAC_AT_LEAST_1((m)->njrow))
#define GAC_WORK_B(m, w)   (GAC_WORK_Z(m, w) + (long)(m)->nq * (m)->nq)

/* gac_model.c */
int gac_has_friction(const gac_model *m);

/* gac_linalg.c */
int gac_lu_solve(int n, double *A, double *b, double tol);
int gac_ldlt(int n, double *A, double tol);
void gac_ldlt_solve(int n, const double *LD, double *b);
int gac_ldlt_drop(int n, double *A, double tol);

/* gac_impact.c */
void gac_contact_row(const gac_model *m, int c, int *row, double *sign);
double gac_row_value(const gac_model *m, int c, const double *w, const double *vel);
double gac_restitution(const gac_model *m, const double *p, int c);
int gac_impact_system(const gac_model *m, const double *q, const double *qd, const double *p, int nactive,
                      const int *active, double *work, double *v, double *e);
int gac_constrained_dynamics_friction(const gac_model *m, const double *q, const double *qd, const double *u,
                                      const double *p, int nactive, const int *active, double *qdd, double *lambda,
                                      double *work, double *dissipation);
int gac_impact_rounds(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                      const int *list, const double *e, int first, double *qd_plus, double *F, double *work,
                      int *rounds, int *plastic);

#endif /* GAC_INTERNAL_H */
