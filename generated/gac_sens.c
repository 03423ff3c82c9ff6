/*
 * gac_sens.c -- forward sensitivities of a hybrid run (gac.h, "forward sensitivities of a run"): the variational
 * equations in flight, taken by the run's Runge-Kutta formula over the state's own steps and stages
 * (gac_sens_flight), the jump of the sensitivities at an impact by the frictionless law -- of one contact or several,
 * walls or joint stops, the set of pushing contacts held fixed -- the saltation matrix of Hiskens & Pai (2000)
 * (gac_sens_impact), and the verdict: the first event not differentiated ends them (gac_sens_stop).
 */
#include "gac_internal.h"

#include <math.h>

#define GAC_SENS_STAGES 12    /* the most stages of a method's solution (DOP853); gac.h's GAC_SENS_NDOUBLE holds them */

long gac_sens_ndouble(const gac_model *m, int k)
{
    if (m == 0 || k < 1) return 0;
    return GAC_SENS_NDOUBLE(m->nq, m->nparam, k);
}

int gac_sens_attach(gac_sim *s, gac_sens *sens, int k, const double *seed_x, const double *seed_p, double *dwork)
{
    const gac_model *md;
    int i;
    if (s == 0) return GAC_ERR_NULL_ARGUMENT;
    if (sens == 0) {                              /* detach */
        s->sens = 0;
        return GAC_OK;
    }
    if (seed_x == 0 || dwork == 0) return GAC_ERR_NULL_ARGUMENT;
    md = s->model_a;
    if (k < 1) return GAC_ERR_BAD_OPTION;
    if (md->forward_dynamics_tangent == 0 || md->inertia_solve_tangent == 0
        || md->contact_generalized_force_tangent == 0 || md->contact_gaps_tangent == 0)
        return GAC_ERR_BAD_MODEL;
    if (!gac_finite(seed_x, k * md->nx) || (seed_p != 0 && !gac_finite(seed_p, k * md->nparam)))
        return GAC_ERR_BAD_OPTION;
    sens->k = k;
    sens->S = dwork;                              /* dwork: S | dp | dt_impact | work */
    sens->dp = dwork + (long)k * md->nx;
    sens->dt_impact = sens->dp + (long)k * md->nparam;
    sens->work = sens->dt_impact + k;
    gac_copy(sens->S, seed_x, k * md->nx);
    for (i = 0; i < k * md->nparam; ++i) sens->dp[i] = seed_p != 0 ? seed_p[i] : 0.0;
    for (i = 0; i < k; ++i) sens->dt_impact[i] = 0.0;
    sens->status = GAC_SENS_VALID;
    sens->t_status = s->t;
    sens->contact_status = -1;
    sens->n_impacts = 0;
    s->sens = sens;
    if (s->chart != 0) gac_sens_stop(s, GAC_SENS_CHART, s->t, -1);
    return GAC_OK;
}

void gac_sens_stop(gac_sim *s, int status, double t, int contact)
{
    gac_sens *z = s->sens;
    const double nan = NAN;
    int i;
    if (z == 0 || z->status != GAC_SENS_VALID) return;
    z->status = status;
    z->t_status = t;
    z->contact_status = contact;
    for (i = 0; i < z->k * s->model_a->nx; ++i) z->S[i] = nan;
    for (i = 0; i < z->k; ++i) z->dt_impact[i] = nan;
}

/* The inputs' derivative is taken as 0: held inputs and schedules are functions of t alone, a controller may not be. */
static int gac_sens_inputs_fixed(const gac_sim *s)
{
    return s->controller == 0 || s->controller == gac_schedule_input || s->model->nu == 0;
}

/* S over one step [t, t + h] from the state x at s->t: the method's stages Y_i = x + h sum_l a_il K_l and with them
 * dY_i = S + h sum_l a_il dK_l, dK_i = [dY_i qd ; forward_dynamics_tangent(Y_i, dY_i, dp)] per direction;
 * S += h sum_i b_i dK_i.  (The derivative of the Runge-Kutta step itself: the variational equations integrated by
 * the same formula.)  The stages K_i = f(Y_i) are the step's own (s->f, s->k[1..], as the integrator left them) when
 * `taken` (the step of size h just accepted); otherwise (a part of it, up to an event) K_0 = s->f and the others
 * are computed here.  The directions' tangents go GAC_TANGENT_BLOCK at a time through the model's
 * forward_dynamics_tangent_block (their primal part computed once), the rest one by one. */
void gac_sens_flight(gac_sim *s, const double *x, double h, int taken)
{
    gac_sens *z = s->sens;
    const gac_model *md = s->model;
    const double *a, *b, *c;
    int lda, stages, i, j, l, n;
    if (z == 0 || z->status != GAC_SENS_VALID || !(h > 0.0)) return;
    if (s->nresting > 0) {
        gac_sens_stop(s, GAC_SENS_RESTING, s->t, s->resting[0]);
        return;
    }
    if (!gac_sens_inputs_fixed(s)) {
        gac_sens_stop(s, GAC_SENS_CONTROLLER, s->t, -1);
        return;
    }
    {
        const int nq = md->nq, nx = md->nx, k = z->k;
        double *work = z->work, *dK = work + (long)GAC_SENS_STAGES * nx, *Y = dK + (long)GAC_SENS_STAGES * k * nx;
        double dQ[GAC_TANGENT_BLOCK * nq], dQD[GAC_TANGENT_BLOCK * nq], out[GAC_TANGENT_BLOCK * nq];
        double dU[GAC_TANGENT_BLOCK * GAC_AT_LEAST_1(md->nu)];   /* the inputs' directions: 0 (held, or a schedule) */
        const double *K[GAC_SENS_STAGES];
        int width;
        for (n = 0; n < GAC_TANGENT_BLOCK * GAC_AT_LEAST_1(md->nu); ++n) dU[n] = 0.0;
        stages = gac_tableau(s->opt.method, &a, &lda, &b, &c);
        for (i = 0; i < stages; ++i) K[i] = i == 0 ? s->f : taken ? s->k[i] : work + (long)i * nx;
        for (i = 0; i < stages; ++i) {
            const double *u;
            for (n = 0; n < nx; ++n) {
                double sum = 0.0;
                for (l = 0; l < i; ++l) sum += a[i * lda + l] * K[l][n];
                Y[n] = x[n] + h * sum;
            }
            u = gac_input(s, s->t + c[i] * h, Y);
            if (i > 0 && !taken) md->rhs(s->t + c[i] * h, Y, u, s->p, work + (long)i * nx);
            for (j = 0; j < k; j += width) {         /* GAC_TANGENT_BLOCK directions a call, then one by one */
                double *dKi;
                int m;
                width = md->forward_dynamics_tangent_block != 0 && j + GAC_TANGENT_BLOCK <= k ? GAC_TANGENT_BLOCK : 1;
                for (m = 0; m < width; ++m) {
                    const double *dKj = dK + (long)(j + m) * GAC_SENS_STAGES * nx;
                    dKi = dK + ((long)(j + m) * GAC_SENS_STAGES + i) * nx;
                    for (n = 0; n < nx; ++n) {
                        double sum = 0.0;
                        for (l = 0; l < i; ++l) sum += a[i * lda + l] * dKj[(long)l * nx + n];
                        sum = z->S[(long)(j + m) * nx + n] + h * sum;      /* dY_i of direction j + m */
                        if (n < nq) dQ[m * nq + n] = sum;
                        else dQD[m * nq + n - nq] = dKi[n - nq] = sum;
                    }
                }
                if (width > 1) {
                    md->forward_dynamics_tangent_block(Y, Y + nq, u, s->p, dQ, dQD, dU, z->dp + (long)j * md->nparam,
                                                       out);
                    for (m = 0; m < width; ++m) {
                        dKi = dK + ((long)(j + m) * GAC_SENS_STAGES + i) * nx;
                        for (n = 0; n < nq; ++n) dKi[nq + n] = out[m * nq + n];
                    }
                } else {
                    dKi = dK + ((long)j * GAC_SENS_STAGES + i) * nx;
                    md->forward_dynamics_tangent(Y, Y + nq, u, s->p, dQ, dQD, dU, z->dp + (long)j * md->nparam,
                                                 dKi + nq);
                }
            }
        }
        for (j = 0; j < k; ++j) {
            for (n = 0; n < nx; ++n) {
                double sum = 0.0;
                for (i = 0; i < stages; ++i) sum += b[i] * dK[((long)j * GAC_SENS_STAGES + i) * nx + n];
                z->S[(long)j * nx + n] += h * sum;
            }
        }
        if (!gac_finite(z->S, k * nx)) gac_sens_stop(s, GAC_SENS_NONFINITE, s->t + h, -1);
    }
}

/* The impact map of the active contacts a = 1..m (those that took an impulse) by Newton's law, Eq. 47, with the
 * set fixed: W (m x nq) their signed normal rows w_a = J^T (sign e_row_a), Y_a = I_f^-1 w_a, A = W Y (m x m),
 * v = W qd, A F = -(1 + E) v, qd+ = qd + Y F.  Its differential along (dq, dqd, dp) with de_a = dp[e_index_a]:
 *     dw_a = d(J^T f_a)[dq, dp],  dY_a = d(I_f^-1 w_a)[dq, dw_a, dp],  dA_ab = dw_a . Y_b + w_a . dY_b,
 *     dv_a = dw_a . qd + w_a . dqd,  A dF = -de v - (1 + E) dv - dA F,  d qd+ = dqd + dY F + Y dF.
 * (One contact: dF = dL of y L, L = -(1 + e) v / (w . y).)  A is kept factored (gac_ldlt) in LD. */
typedef struct {
    int m;                       /* active contacts */
    const int *active;           /* their model indices */
    const double *f, *W, *Y, *LD, *F, *v, *e;   /* f: m x nr unit signed rows; the rest as above */
} gac_sens_law;

static void gac_impact_differential(const gac_sim *s, const gac_sens_law *L, const double *q, const double *qd,
                                    const double *dq, const double *dqd, const double *dp, double *dqd_plus)
{
    const gac_model *md = s->model;
    const int nq = md->nq, nr = GAC_AT_LEAST_1(md->njrow), m = L->m;
    double dW[m * nq], dY[m * nq], dF[m], df[nr];
    int a, b, i;
    for (i = 0; i < nr; ++i) df[i] = 0.0;
    for (a = 0; a < m; ++a) {
        md->contact_generalized_force_tangent(q, L->f + (long)a * nr, s->p, dq, df, dp, dW + (long)a * nq);
        md->inertia_solve_tangent(q, L->W + (long)a * nq, s->p, dq, dW + (long)a * nq, dp, dY + (long)a * nq);
    }
    for (a = 0; a < m; ++a) {
        const gac_contact *ct = md->contacts + L->active[a];
        const double de = ct->e_index >= 0 ? dp[ct->e_index] : 0.0;
        const double *wa = L->W + (long)a * nq, *dwa = dW + (long)a * nq;
        double dv = 0.0, rhs;
        for (i = 0; i < nq; ++i) dv += dwa[i] * qd[i] + wa[i] * dqd[i];
        rhs = -de * L->v[a] - (1.0 + L->e[a]) * dv;
        for (b = 0; b < m; ++b) {
            double dA = 0.0;
            for (i = 0; i < nq; ++i) dA += dwa[i] * L->Y[(long)b * nq + i] + wa[i] * dY[(long)b * nq + i];
            rhs -= dA * L->F[b];
        }
        dF[a] = rhs;
    }
    gac_ldlt_solve(m, L->LD, dF);
    for (i = 0; i < nq; ++i) {
        double value = dqd[i];
        for (a = 0; a < m; ++a) value += dY[(long)a * nq + i] * L->F[a] + L->Y[(long)a * nq + i] * dF[a];
        dqd_plus[i] = value;
    }
}

/* The jump at the impact record r just resolved (state before it s->xs, after it s->x1), located by contact
 * c_event's gap: for each direction j, dt*_j = -dg_j / (w_c . qd-) and S+_j = D Delta (S-_j + f- dt*_j, dp_j)
 * - f+ dt*_j, Delta the map of the contacts that took an impulse (a wall's or a joint stop's alike: a stop's row is
 * a row of the identity).  A contact of the record that took no impulse stays out of Delta if it leaves the impact
 * separating; one with impulse ~0 and leaving at the law's bound is a mode boundary inside the impact (the verdict).
 * Impacts of another kind end the sensitivities. */
void gac_sens_impact(gac_sim *s, const gac_impact_record *r, int c_event)
{
    gac_sens *z = s->sens;
    const gac_model *md = s->model;
    if (z == 0 || z->status != GAC_SENS_VALID) return;
    if (r->law != GAC_IMPACT_LAW_FRICTIONLESS) {
        gac_sens_stop(s, r->law == GAC_IMPACT_LAW_GDI_TANGENTIAL ? GAC_SENS_TANGENTIAL : GAC_SENS_FRICTION, r->t,
                      r->ncontact > 0 ? r->contact[0] : -1);
        return;
    }
    if (r->ncontact < 1 || r->rounds != 1 || r->plastic) {
        gac_sens_stop(s, GAC_SENS_SIMULTANEOUS, r->t, r->ncontact > 0 ? r->contact[0] : c_event);
        return;
    }
    if (r->nlanded > 0 || r->nreleased > 0 || s->nresting > 0) {
        gac_sens_stop(s, GAC_SENS_RESTING, r->t, r->contact[0]);
        return;
    }
    {
        const int nq = md->nq, nx = md->nx, nr = GAC_AT_LEAST_1(md->njrow), n = r->ncontact;
        const double *xm = s->xs, *xp = s->x1, *q = xm;
        double f[n * nr], W[n * nq], Y[n * nq], LD[n * n], F[n], v[n], e[n], fm[nx], fp[nx];
        double dgap[GAC_AT_LEAST_1(md->ncontact)], dx[nx], dqd_plus[nq], zero_p[GAC_AT_LEAST_1(md->nparam)];
        double speed = 0.0, largest = 0.0, v_event = 0.0;
        int active[n], m = 0, a, b, i, j;
        gac_sens_law law;
        for (i = 0; i < nq; ++i) {
            if (fabs(xm[nq + i]) > speed) speed = fabs(xm[nq + i]);
        }
        for (a = 0; a < n; ++a) {
            if (r->impulse[a] > largest) largest = r->impulse[a];
        }
        {                                                    /* the event's contact: t* from its gap */
            double fe[nr], we[nq];
            const gac_contact *ct = md->contacts + c_event;
            for (i = 0; i < nr; ++i) fe[i] = 0.0;
            fe[ct->row] = ct->normal_sign;
            md->contact_generalized_force(q, fe, s->p, we);
            for (i = 0; i < nq; ++i) v_event += we[i] * xm[nq + i];
            if (!(fabs(v_event) > 1e-9 * speed * s->lever)) {   /* grazing: t* has no derivative */
                gac_sens_stop(s, GAC_SENS_GRAZING, r->t, c_event);
                return;
            }
        }
        for (a = 0; a < n; ++a) {                            /* the active set, and the mode boundaries */
            const int c = r->contact[a];
            const gac_contact *ct = md->contacts + c;
            double *fa = f + (long)m * nr, *wa = W + (long)m * nq, before = 0.0, after = 0.0;
            for (i = 0; i < nr; ++i) fa[i] = 0.0;
            fa[ct->row] = ct->normal_sign;
            md->contact_generalized_force(q, fa, s->p, wa);
            for (i = 0; i < nq; ++i) {
                before += wa[i] * xm[nq + i];
                after += wa[i] * xp[nq + i];
            }
            e[m] = ct->e_index >= 0 ? s->p[ct->e_index] : ct->e_value;
            if (r->impulse[a] > 1e-9 * largest) {
                if (!(fabs(before) > 1e-9 * speed * s->lever)) {   /* pushed at rest: a graze inside the impact */
                    gac_sens_stop(s, GAC_SENS_GRAZING, r->t, c);
                    return;
                }
                v[m] = before;
                active[m++] = c;
            } else {                                         /* no impulse: out of Delta if it leaves clear of */
                const double bound = after + (before < 0.0 ? e[m] * before : 0.0);   /* the law's bound */
                if (!(bound > 1e-9 * speed * s->lever)) {
                    gac_sens_stop(s, GAC_SENS_BOUNDARY, r->t, c);
                    return;
                }
            }
        }
        if (m == 0) {
            gac_sens_stop(s, GAC_SENS_BOUNDARY, r->t, c_event);
            return;
        }
        for (a = 0; a < m; ++a) {
            md->inertia_solve(q, W + (long)a * nq, s->p, Y + (long)a * nq);
            for (b = 0; b <= a; ++b) {
                double sum = 0.0;
                for (i = 0; i < nq; ++i) sum += W[(long)a * nq + i] * Y[(long)b * nq + i];
                LD[a * m + b] = LD[b * m + a] = sum;
            }
            F[a] = -(1.0 + e[a]) * v[a];
        }
        if (gac_ldlt(m, LD, 1e-12) != 0) {                   /* dependent rows: no unique differential */
            gac_sens_stop(s, GAC_SENS_SIMULTANEOUS, r->t, c_event);
            return;
        }
        gac_ldlt_solve(m, LD, F);
        law.m = m, law.active = active, law.f = f, law.W = W, law.Y = Y, law.LD = LD, law.F = F, law.v = v;
        law.e = e;
        md->rhs(r->t, xm, gac_input(s, r->t, xm), s->p, fm);
        md->rhs(r->t, xp, gac_input(s, r->t, xp), s->p, fp);
        for (i = 0; i < GAC_AT_LEAST_1(md->nparam); ++i) zero_p[i] = 0.0;
        for (j = 0; j < z->k; ++j) {
            double *S = z->S + (long)j * nx;
            const double *dp = md->nparam > 0 ? z->dp + (long)j * md->nparam : zero_p;
            double tau;
            md->contact_gaps_tangent(q, s->p, S, dp, dgap);
            tau = -dgap[c_event] / v_event;                  /* dt*_j: the gap stays 0 at the event */
            for (i = 0; i < nx; ++i) dx[i] = S[i] + fm[i] * tau; /* the perturbed state at the perturbed t* */
            gac_impact_differential(s, &law, q, xm + nq, dx, dx + nq, dp, dqd_plus);
            for (i = 0; i < nq; ++i) {
                S[i] = dx[i] - fp[i] * tau;                      /* back to the nominal t*: minus f+ dt*_j */
                S[nq + i] = dqd_plus[i] - fp[nq + i] * tau;
            }
            z->dt_impact[j] = tau;
        }
        z->n_impacts++;
        if (!gac_finite(z->S, z->k * nx)) gac_sens_stop(s, GAC_SENS_NONFINITE, r->t, c_event);
    }
}
