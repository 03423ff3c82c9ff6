/*
 * gac_stick.c -- sticking at resting contacts on walls with Coulomb friction (gac.h, "Sticking"): a stuck point's
 * tangential rows held with the normal rows as bilateral constraints and their forces solved in one system, the
 * velocity projection that holds them, the slip of a stuck point (stuck -> sliding) and the test that lets a slow
 * sliding point stick (sliding -> stuck).
 */
#include "gac_internal.h"

#include <math.h>

/* A held row whose pivot in the LDL^T of R I_f^-1 R^T is below this fraction of the largest diagonal entry depends on
 * the rows before it (a link lying flat holds the same tangential row at both ends): it drops out and the forces are
 * shared among the rest.  A nearly dependent row is kept (a shallow arch between two stuck points pushes them apart
 * with a large force, and they slip). */
#define GAC_HELD_DEPENDENT 1e-12

/* phi of a sliding point with tangential velocity vt (2): v_t / max(|v_t|, v_s), and, below v_s with a slip
 * direction d (2, unit, or NULL / zero: none), (1 - |v_t| / v_s) d added, so that a slip begins against the full
 * Coulomb force; phi is continuous in v_t (|phi| <= 1), the loop forgetting d at a step's end where v_t opposes it
 * (within that step phi . v_t >= -|v_t| (1 - |v_t| / v_s) >= -v_s / 4).  Returns phi . v_t. */
double gac_slide_phi(const double *vt, double vs, const double *d, double *phi)
{
    const double speed = sqrt(vt[0] * vt[0] + vt[1] * vt[1]);
    const double scale = speed > vs ? speed : vs;
    int j;
    for (j = 0; j < 2; ++j) phi[j] = vt[j] / scale;
    if (d != 0 && speed < vs) {
        for (j = 0; j < 2; ++j) phi[j] += (1.0 - speed / vs) * d[j];
    }
    return phi[0] * vt[0] + phi[1] * vt[1];
}

/* Contact c's Coulomb coefficient at rest: a rough wall's, a rough link pair's or obstacle's (0 for a frictionless
 * contact and a stop). */
double gac_rest_friction(const gac_model *m, const double *p, int c)
{
    return gac_rowless(m, c) ? gac_contact_friction(m, p, c) : gac_friction_coefficient(m, p, c);
}

/* Contact c's tangential directions at q (gac_tangents): a wall's axes ascending, other than its normal's, with their
 * velocity components (a stop has none); a link pair's or an obstacle's frame.  GAC_OK or gac_rowless_frame's
 * error. */
int gac_tangents_at(const gac_model *m, const double *q, const double *p, int c, gac_tangents *tg)
{
    const gac_contact *k = &m->contacts[c];
    int j, axis = 0;
    tg->c = c;
    tg->rowless = gac_rowless(m, c);
    for (j = 0; j < 2; ++j) tg->has[j] = 0, tg->comp[j] = -1;
    if (tg->rowless) {
        const int code = gac_rowless_frame(m, q, p, c, &tg->frame);
        if (code != GAC_OK) return code;
        tg->has[0] = tg->has[1] = 1;
        return GAC_OK;
    }
    if (k->kind != GAC_CONTACT_WALL) return GAC_OK;
    for (j = 0; j < 2; ++j, ++axis) {
        if (axis == k->axis) ++axis;
        tg->has[j] = k->trow[j] >= 0;
        tg->comp[j] = 3 * (k->point - 1) + axis;
    }
    return GAC_OK;
}

/* The rate along tangential direction j of the velocities whose joint points move with vel (contact_velocities):
 * a wall's point velocity component, a frame's t_j . (v_P - v_Q) at the closest points (0 where it has none). */
double gac_tangent_value(const gac_tangents *tg, int j, const double *vel)
{
    double size;
    if (!tg->has[j]) return 0.0;
    return tg->rowless ? gac_frame_rate(&tg->frame, vel, 1 + j, &size) : vel[tg->comp[j]];
}

/* g (nq) = the generalised force of the tangential force phi (2: along the two directions): a wall's J^T f with
 * f[trow_j] = phi_j (f, njrow: scratch), a frame's phi_1 J^T t1 + phi_2 J^T t2. */
void gac_tangent_force(const gac_model *m, const double *q, const double *p, const gac_tangents *tg,
                       const double *phi, double *f, double *g)
{
    const gac_contact *k = &m->contacts[tg->c];
    int i, j;
    if (tg->rowless) {
        double row[GAC_AT_LEAST_1(m->nq)];
        for (i = 0; i < m->nq; ++i) g[i] = 0.0;
        for (j = 0; j < 2; ++j) {
            (void)gac_frame_direction(m, q, p, &tg->frame, 1 + j, row);
            for (i = 0; i < m->nq; ++i) g[i] += phi[j] * row[i];
        }
        return;
    }
    for (i = 0; i < m->njrow; ++i) f[i] = 0.0;
    for (j = 0; j < 2; ++j) {
        if (tg->has[j]) f[k->trow[j]] = phi[j];
    }
    m->contact_generalized_force(q, f, p, g);
}

/* The velocity of contact c's point along its two tangential directions (a wall's axes ascending, a link pair's or an
 * obstacle's t1, t2; 0 for an axis the model does not move along, and for a stop) at q, from the points'
 * velocities vq (3 npoint). */
void gac_tangential_velocity(const gac_model *m, const double *q, const double *p, int c, const double *vq,
                             double *vt)
{
    gac_tangents tg;
    vt[0] = vt[1] = 0.0;
    if (m->contacts[c].kind == GAC_CONTACT_STOP || gac_tangents_at(m, q, p, c, &tg) != GAC_OK) return;
    vt[0] = gac_tangent_value(&tg, 0, vq);
    vt[1] = gac_tangent_value(&tg, 1, vq);
}

/* 1 if one of the contacts set[0..n-1] is stuck (stuck: per contact, or NULL: none). */
int gac_any_stuck(const int *stuck, int n, const int *set)
{
    int a;
    if (stuck == 0) return 0;
    for (a = 0; a < n; ++a) {
        if (stuck[set[a]]) return 1;
    }
    return 0;
}

/* The rows held at the contacts set[0..n-1]: first each one's normal row (its response I_f^-1 n_a, left in Y by
 * gac_impact_system), then the tangential rows of each stuck one (responses I_f^-1 J^T e_trow, or a link pair's or an
 * obstacle's I_f^-1 J^T t_j, into T; a frame's tangent that no motion of the chain takes, |J^T t_j| below 1e-10 of
 * its columns' size, left out as a wall's axis without a row).  tg[a]: contact set[a]'s tangential directions.
 * Row r: owner[r] (its contact's position in set), comp[r] (-1 for a normal row, else the tangential row's
 * direction holder: a wall's point velocity component 3 (point - 1) + axis, -2 a frame's), brow[r] (a wall's row
 * of contact_bias), sgn[r] (the normal's sign, 1 along an axis), tj[r] (the tangential direction 0 or 1, -1 for a
 * normal row), resp[r].  Returns the number of rows or an error (< 0). */
static int gac_held_rows(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                         const int *set, const int *stuck, double *work, gac_tangents *tg, int *owner, int *comp,
                         int *brow, double *sgn, int *tj, const double **resp)
{
    const int nq = m->nq;
    double v[GAC_AT_LEAST_1(nq)], e[GAC_AT_LEAST_1(nq)];
    double *Y = GAC_WORK_Y(m, work), *T = GAC_WORK_T(m, work), *g = GAC_WORK_G(m, work), *f = GAC_WORK_F(m, work);
    int a, i, j, nr = 0, nt = 0;
    const int code = gac_impact_system(m, q, qd, p, n, set, work, v, e);
    if (code != GAC_OK) return code;
    for (a = 0; a < n; ++a) {
        int row;
        double sign;
        const int frame = gac_tangents_at(m, q, p, set[a], &tg[a]);
        if (frame != GAC_OK) return frame;
        gac_contact_row(m, set[a], &row, &sign);
        owner[nr] = a, comp[nr] = -1, brow[nr] = row, sgn[nr] = sign, tj[nr] = -1;
        resp[nr++] = Y + (long)a * nq;
    }
    for (a = 0; a < n; ++a) {
        const gac_contact *k = &m->contacts[set[a]];
        if (stuck == 0 || !stuck[set[a]] || !(gac_rest_friction(m, p, set[a]) > 0.0)) continue;
        for (j = 0; j < 2; ++j) {
            double *out = T + (long)nt * nq;
            if (!tg[a].has[j]) continue;
            if (tg[a].rowless) {                       /* J^T t_j, a motion's direction or none */
                double norm = 0.0;
                const double scale = gac_frame_direction(m, q, p, &tg[a].frame, 1 + j, g);
                for (i = 0; i < nq; ++i) norm += g[i] * g[i];
                if (!(sqrt(norm) > 1e-10 * scale)) {
                    tg[a].has[j] = 0;
                    continue;
                }
                m->inertia_solve(q, g, p, out);
                if (!gac_finite(out, nq)) return GAC_ERR_SINGULAR_MASS;
                owner[nr] = a, comp[nr] = -2, brow[nr] = -1, sgn[nr] = 1.0, tj[nr] = j;
            } else {
                const int response = gac_row_response(m, q, p, k->trow[j], f, g, out);   /* along +X_axis */
                if (response != GAC_OK) return response;
                owner[nr] = a, comp[nr] = tg[a].comp[j], brow[nr] = k->trow[j], sgn[nr] = 1.0, tj[nr] = j;
            }
            resp[nr++] = out;
            nt++;
        }
    }
    return nr;
}

/* Row r's value of a generalised velocity w (vel = contact_velocities(q, w)): a normal row's by gac_normal_value
 * (a link's or an obstacle's contact from its closest points), a tangential row's the point velocity component, or
 * a frame's t_j . (v_P - v_Q). */
static double gac_held_value(const gac_model *m, const double *q, const double *p, const int *set,
                             const gac_tangents *tg, int owner, int comp, int tj, const double *w, const double *vel)
{
    if (comp == -1) return gac_normal_value(m, q, p, set[owner], w, vel);
    return comp >= 0 ? vel[comp] : gac_tangent_value(&tg[owner], tj, vel);
}

/* The bias of held row r (its rate's part without qdd): a normal row's by gac_normal_bias, a wall's tangential row's
 * contact_bias row (bias), a frame's tangent's from gac_rowless_frame_bias (its three rows' biases kept in
 * frame[3 owner..], have[owner] set, for the contact's other tangent).  GAC_OK or GAC_ERR_LINK_REST (a normal or a
 * frame without derivative). */
static int gac_held_bias(const gac_model *m, const double *q, const double *qd, const double *p, const int *set,
                         int owner, int comp, int brow, double sgn, int tj, const double *bias, double *frame,
                         int *have, double *b)
{
    if (comp >= 0) {
        *b = sgn * bias[brow];
        return GAC_OK;
    }
    if (comp == -1) return gac_normal_bias(m, q, qd, p, set[owner], bias, b) == GAC_OK ? GAC_OK : GAC_ERR_LINK_REST;
    if (!have[owner] && gac_rowless_frame_bias(m, q, qd, p, set[owner], frame + 3 * owner) != GAC_OK)
        return GAC_ERR_LINK_REST;
    have[owner] = 1;
    *b = frame[3 * owner + 1 + tj];
    return GAC_OK;
}

/* G (nr x nr) = R I_f^-1 R^T of the held rows, symmetric (vel: scratch). */
static void gac_held_gram(const gac_model *m, const double *q, const double *p, const int *set,
                          const gac_tangents *tg, int nr, const int *owner, const int *comp, const int *tj,
                          const double **resp, double *G, double *vel)
{
    int r, c;
    for (c = 0; c < nr; ++c) {
        m->contact_velocities(q, resp[c], p, vel);
        for (r = 0; r < nr; ++r)
            G[r*nr + c] = gac_held_value(m, q, p, set, tg, owner[r], comp[r], tj[r], resp[c], vel);
    }
    for (r = 0; r < nr; ++r) {
        for (c = 0; c < r; ++c) G[r*nr + c] = G[c*nr + r] = 0.5 * (G[r*nr + c] + G[c*nr + r]);
    }
}

/* 1 if the held system G (nr x nr, row-major: the n normal rows first, then the stuck points' tangential rows; the
 * sliding points' normal columns bent by their friction) gives the normal forces unique, bounded values: with the
 * stuck rows held (G_TT, untouched by friction, is symmetric positive definite), the normal forces solve
 * S lambda_N = b_N - G_NT G_TT^-1 b_T with the Schur complement S = G_NN - G_NT G_TT^-1 G_TN, which must pass the
 * sliding system's test (gac_friction_consistent): where it fails, the stuck points wedge a sliding one in the
 * Painleve paradox, and its normal force passes through a pole (changing sign there, as a release would) instead
 * of a zero. */
static int gac_held_consistent(int n, int nr, const double *G)
{
    const int nt = nr - n;
    double T[GAC_AT_LEAST_1(nt * nt)], S[GAC_AT_LEAST_1(n * n)], col[GAC_AT_LEAST_1(nt)];
    int a, b, r, c;
    for (r = 0; r < nt; ++r) {
        for (c = 0; c < nt; ++c) T[r*nt + c] = G[(n + r)*nr + n + c];
    }
    if (nt > 0 && gac_ldlt(nt, T, 1e-12) != 0) return 1;       /* (dependent stuck rows: judged by the solve) */
    for (b = 0; b < n; ++b) {                                   /* column b of S */
        for (r = 0; r < nt; ++r) col[r] = G[(n + r)*nr + b];
        if (nt > 0) gac_ldlt_solve(nt, T, col);
        for (a = 0; a < n; ++a) {
            double sum = G[a*nr + b];
            for (r = 0; r < nt; ++r) sum -= G[a*nr + n + r] * col[r];
            S[a*n + b] = sum;
        }
    }
    return gac_friction_consistent(n, S, 1e-8);
}

/* The constrained dynamics with some of the resting contacts stuck (stuck[c] = 1): the rows R (normal rows of all,
 * tangential rows of the stuck ones) held, R qdd + Rdot qd = 0, with qdd = qdd_free + I_f^-1 sum_r d_r lambda_r,
 * d_r the row itself, or for the normal row of a sliding point on a rough wall n_a + c_f J_t^T(-phi_a).  So
 * B lambda = -(R qdd_free + Rdot qd), B_rs = r . I_f^-1 d_s (symmetric, solved by LDL^T, without sliding friction;
 * LU with it).  Rows dependent on the others (found by the LDL^T of R I_f^-1 R^T: a rod lying flat holds the same
 * tangential row at both ends) share the force: the least-norm solution of the independent rows' equations,
 * lambda = B_K^T (B_K B_K^T)^-1 b_K, which must hold the dropped rows too (to 1e-8 of the right-hand side; else
 * GAC_ERR_SINGULAR_CONTACT: the stuck set cannot be held).  lambda (n): the normal forces; lambda_t (2 n, or NULL): the stuck points'
 * tangential forces along their wall's axes (0 for a sliding point); dissipation: the sliding points' power. */
int gac_stuck_dynamics(const gac_model *m, const double *q, const double *qd, const double *u, const double *p,
                       int n, const int *set, const int *stuck, const double *slip, double *qdd, double *lambda,
                       double *lambda_t, double *work, double *dissipation)
{
    const int nq = m->nq, cap = 3 * GAC_AT_LEAST_1(nq), n1 = GAC_AT_LEAST_1(n);
    double *G = GAC_WORK_W(m, work), *L = GAC_WORK_L(m, work), *Z = GAC_WORK_Z(m, work);
    double *vel = GAC_WORK_VEL(m, work), *g = GAC_WORK_G(m, work), *f = GAC_WORK_F(m, work);
    double bias[GAC_AT_LEAST_1(m->njrow)], vq[3 * GAC_AT_LEAST_1(m->npoint)], b[cap], lam[cap], sgn[cap];
    double cf[n1], slide[n1], frame_bias[3 * n1];
    int owner[cap], comp[cap], brow[cap], tj[cap], idx[cap], sliding[n1], have_bias[n1];
    const double *resp[cap];
    gac_tangents tg[n1];
    int nr, r, c, a, i, j, dropped, nk = 0, any_sliding = 0;
    if (dissipation) *dissipation = 0.0;
    m->forward_dynamics(q, qd, u, p, qdd);
    if (n == 0) return GAC_OK;
    nr = gac_held_rows(m, q, qd, p, n, set, stuck, work, tg, owner, comp, brow, sgn, tj, resp);
    if (nr < 0) return nr;
    m->contact_bias(q, qd, p, bias);
    m->contact_velocities(q, qd, p, vq);
    for (a = 0; a < n; ++a) {                     /* sliding points: Z_a = I_f^-1 J_t^T (-phi_a) */
        double vt[2], phi[2];
        cf[a] = gac_rest_friction(m, p, set[a]);
        sliding[a] = cf[a] > 0.0 && !stuck[set[a]];
        slide[a] = 0.0;
        have_bias[a] = 0;
        if (!sliding[a]) continue;
        any_sliding = 1;
        for (j = 0; j < 2; ++j) vt[j] = gac_tangent_value(&tg[a], j, vq);
        slide[a] = gac_slide_phi(vt, m->friction_velocity, slip ? slip + 2 * set[a] : 0, phi);
        for (j = 0; j < 2; ++j) phi[j] = -phi[j];
        gac_tangent_force(m, q, p, &tg[a], phi, f, g);
        m->inertia_solve(q, g, p, Z + (long)a * nq);
    }
    gac_held_gram(m, q, p, set, tg, nr, owner, comp, tj, resp, G, vel);
    m->contact_velocities(q, qdd, p, vel);        /* R qdd_free, row by row */
    for (r = 0; r < nr; ++r) {
        double held_bias = 0.0;
        const int code = gac_held_bias(m, q, qd, p, set, owner[r], comp[r], brow[r], sgn[r], tj[r], bias, frame_bias,
                                       have_bias, &held_bias);
        if (code != GAC_OK) return code;
        b[r] = -(held_bias + gac_held_value(m, q, p, set, tg, owner[r], comp[r], tj[r], qdd, vel));
    }
    for (i = 0; i < nr * nr; ++i) L[i] = G[i];
    dropped = gac_ldlt_drop(nr, L, GAC_HELD_DEPENDENT);
    if (dropped < 0) return GAC_ERR_SINGULAR_CONTACT;
    for (a = 0; a < n; ++a) {                     /* B: sliding friction bends the normal columns (column a) */
        if (!sliding[a]) continue;
        m->contact_velocities(q, Z + (long)a * nq, p, vel);
        for (r = 0; r < nr; ++r)
            G[r*nr + a] += cf[a] * gac_held_value(m, q, p, set, tg, owner[r], comp[r], tj[r], Z + (long)a * nq, vel);
    }
    for (r = 0; r < nr; ++r) lam[r] = b[r];
    if (dropped == 0 && !any_sliding) {
        gac_ldlt_solve(nr, L, lam);
    } else if (dropped == 0) {
        if (!gac_held_consistent(n, nr, G)) return GAC_ERR_FRICTION;
        if (gac_lu_solve(nr, G, lam, 1e-12) != 0) return GAC_ERR_FRICTION;
    } else {                                      /* least-norm forces of the independent rows' equations */
        double y[cap];
        for (r = 0; r < nr; ++r) {
            if (L[r*nr + r] != 1e300) idx[nk++] = r;
        }
        for (i = 0; i < nk; ++i) {
            y[i] = b[idx[i]];
            for (j = 0; j < nk; ++j) {
                double sum = 0.0;
                for (c = 0; c < nr; ++c) sum += G[idx[i]*nr + c] * G[idx[j]*nr + c];
                L[i*nk + j] = sum;
            }
        }
        if (gac_ldlt_drop(nk, L, 1e-24) < 0) return GAC_ERR_FRICTION;
        gac_ldlt_solve(nk, L, y);
        for (c = 0; c < nr; ++c) {
            lam[c] = 0.0;
            for (i = 0; i < nk; ++i) lam[c] += G[idx[i]*nr + c] * y[i];
        }
        {                                         /* the dropped rows must be held by the others' forces */
            double worst = 0.0, size = 0.0;
            for (r = 0; r < nr; ++r) {
                double sum = -b[r];
                for (c = 0; c < nr; ++c) sum += G[r*nr + c] * lam[c];
                if (fabs(sum) > worst) worst = fabs(sum);
                if (fabs(b[r]) > size) size = fabs(b[r]);
            }
            if (worst > 1e-8 * size + 1e-300) return GAC_ERR_SINGULAR_CONTACT;
        }
    }
    if (!gac_finite(lam, nr)) return GAC_ERR_FRICTION;
    for (i = 0; i < nq; ++i) {
        for (r = 0; r < nr; ++r) qdd[i] += resp[r][i] * lam[r];
    }
    for (a = 0; a < n; ++a) {
        lambda[a] = lam[a];
        if (!sliding[a]) continue;
        for (i = 0; i < nq; ++i) qdd[i] += cf[a] * Z[(long)a * nq + i] * lam[a];
        if (dissipation) *dissipation += cf[a] * lam[a] * slide[a];
    }
    if (lambda_t != 0) {
        for (a = 0; a < 2 * n; ++a) lambda_t[a] = 0.0;
        for (r = n; r < nr; ++r) lambda_t[2 * owner[r] + tj[r]] = lam[r];
    }
    return GAC_OK;
}

/* The velocities of x brought onto the held rows of the contacts set[0..n-1] (normal rows, and the tangential rows
 * of the stuck ones): qd -= Y (R Y)^-1 R qd, Y = I_f^-1 R^T, the nearest velocities in the mass metric (so the
 * kinetic energy cannot grow; rows dependent on the others drop out). */
int gac_project_stuck(gac_sim *s, double *x, int n, const int *set)
{
    const gac_model *md = s->model;
    const int nq = md->nq, cap = 3 * GAC_AT_LEAST_1(nq);
    double *G = GAC_WORK_W(md, s->work), *vel = GAC_WORK_VEL(md, s->work);
    double sgn[cap], corr[cap];
    int owner[cap], comp[cap], brow[cap], tj[cap];
    const double *resp[cap];
    gac_tangents tg[GAC_AT_LEAST_1(n)];
    int nr, r, i;
    nr = gac_held_rows(md, x, x + nq, s->p, n, set, s->is_stuck, s->work, tg, owner, comp, brow, sgn, tj, resp);
    if (nr < 0) return nr;
    gac_held_gram(md, x, s->p, set, tg, nr, owner, comp, tj, resp, G, vel);
    md->contact_velocities(x, x + nq, s->p, vel);
    for (r = 0; r < nr; ++r) corr[r] = -gac_held_value(md, x, s->p, set, tg, owner[r], comp[r], tj[r], x + nq, vel);
    if (gac_ldlt_drop(nr, G, GAC_HELD_DEPENDENT) < 0) return GAC_ERR_SINGULAR_CONTACT;
    gac_ldlt_solve(nr, G, corr);
    for (i = 0; i < nq; ++i) {
        for (r = 0; r < nr; ++r) x[nq + i] += resp[r][i] * corr[r];
    }
    return GAC_OK;
}

/* The forces of the resting contacts at time t and state x, their stuck points held: qdd (nq), lambda (nresting),
 * lambda_t (2 nresting, or NULL), the sliding friction's power (dissipation, or NULL). */
int gac_rest_forces(gac_sim *s, double t, const double *x, double *qdd, double *lambda, double *lambda_t,
                    double *dissipation)
{
    const gac_model *md = s->model;
    return gac_constrained_dynamics_friction(md, x, x + md->nq, gac_input(s, t, x), s->p, s->nresting, s->resting,
                                             s->is_stuck, s->slip, qdd, lambda, lambda_t, s->work, dissipation);
}

/* The stuck resting contact c at state x (time t) whose |lambda_T| reached c_f lambda_N: it slips, along
 * -lambda_T (s->slip, the friction's direction until it is faster than friction_velocity), counted in n_slips and
 * listed in r->slipped (r NULL: not listed).  Returns 1 (it slips), 0 (its normal force is not positive: it is to be
 * released instead) or an error. */
int gac_slip(gac_sim *s, double t, const double *x, int c, gac_impact_record *r)
{
    const gac_model *md = s->model;
    const int nq1 = GAC_AT_LEAST_1(md->nq);
    double qdd[nq1], lambda[nq1], lambda_t[2 * nq1], norm;
    int a, code;
    for (a = 0; a < s->nresting && s->resting[a] != c; ++a) {}
    if (a == s->nresting) return 0;
    code = gac_rest_forces(s, t, x, qdd, lambda, lambda_t, 0);
    if (code != GAC_OK) return code;
    if (!(lambda[a] > 0.0)) return 0;
    norm = sqrt(lambda_t[2 * a] * lambda_t[2 * a] + lambda_t[2 * a + 1] * lambda_t[2 * a + 1]);
    s->is_stuck[c] = 0;
    s->slip[2 * c] = norm > 0.0 ? -lambda_t[2 * a] / norm : 0.0;
    s->slip[2 * c + 1] = norm > 0.0 ? -lambda_t[2 * a + 1] / norm : 0.0;
    s->n_slips++;
    if (r != 0) r->slipped[r->nslipped++] = c;
    return 1;
}

/* The tangential velocities vt (2 per contact) of every contact's point at state x (of a link pair or an obstacle,
 * whose frame costs its closest points, only where it rests: 0 elsewhere). */
void gac_tangential_speeds(const gac_sim *s, const double *x, double *vt)
{
    const gac_model *md = s->model;
    double vq[3 * GAC_AT_LEAST_1(md->npoint)];
    int c;
    md->contact_velocities(x, x + md->nq, s->p, vq);
    for (c = 0; c < md->ncontact; ++c) {
        if (gac_rowless(md, c) && !s->is_resting[c]) vt[2 * c] = vt[2 * c + 1] = 0.0;
        else gac_tangential_velocity(md, x, s->p, c, vq, vt + 2 * c);
    }
}

/* 1 if every stuck resting contact at x lies strictly inside its cone, |lambda_T| < c_f lambda_N (its slip
 * event's value lambda_N - |lambda_T| / c_f > 0), with the set of stuck points as it is now.  d (2): the direction
 * contact c would slip in, -lambda_T / |lambda_T| (0 when its normal force is not positive). */
static int gac_stuck_feasible(gac_sim *s, const double *x, int c_try, double *d)
{
    const gac_model *md = s->model;
    const int nq1 = GAC_AT_LEAST_1(md->nq);
    double qdd[nq1], lambda[nq1], lambda_t[2 * nq1];
    int a, ok = 1;
    d[0] = d[1] = 0.0;
    if (gac_rest_forces(s, s->t, x, qdd, lambda, lambda_t, 0) != GAC_OK || s->fail) {
        if (s->fail != GAC_ERR_BAD_INPUT) s->fail = 0;
        return 0;
    }
    for (a = 0; a < s->nresting; ++a) {
        const double norm = sqrt(lambda_t[2*a] * lambda_t[2*a] + lambda_t[2*a + 1] * lambda_t[2*a + 1]);
        if (s->resting[a] == c_try && lambda[a] > 0.0 && norm > 0.0) {
            d[0] = -lambda_t[2*a] / norm;
            d[1] = -lambda_t[2*a + 1] / norm;
        }
    }
    for (a = 0; a < s->nresting; ++a) {
        const int c = s->resting[a];
        const double cf = gac_rest_friction(md, s->p, c);
        if (!s->is_stuck[c]) continue;
        if (!(lambda[a] - sqrt(lambda_t[2*a] * lambda_t[2*a] + lambda_t[2*a + 1] * lambda_t[2*a + 1]) / cf > 0.0))
            ok = 0;
    }
    return ok;
}

/* The number of tangential directions contact c's point moves along at q: a wall's axes with a row, a frame's
 * tangents with |J^T t_j| above 1e-10 of its columns' size (a planar chain's t2 is none), 0 for a stop. */
static int gac_tangent_axes(const gac_model *m, const double *q, const double *p, int c)
{
    const gac_contact *k = &m->contacts[c];
    double g[GAC_AT_LEAST_1(m->nq)];
    gac_contact_frame frame;
    int j, i, count = 0;
    if (!gac_rowless(m, c)) return k->kind == GAC_CONTACT_WALL ? (k->trow[0] >= 0) + (k->trow[1] >= 0) : 0;
    if (gac_rowless_frame(m, q, p, c, &frame) != GAC_OK) return 0;
    for (j = 0; j < 2; ++j) {
        double norm = 0.0;
        const double scale = gac_frame_direction(m, q, p, &frame, 1 + j, g);
        for (i = 0; i < m->nq; ++i) norm += g[i] * g[i];
        count += sqrt(norm) > 1e-10 * scale;
    }
    return count;
}

/* The slip direction of the slow resting contact c that cannot stick (s->slip): d, the direction its stuck solve
 * would slip in, where the resting contacts' sliding forces exist with it; else -d (3D: then the two directions
 * across d) where they exist with that; else none (phi = v_t / v_s: the friction grows with the speed from 0, and
 * the loop meets the paradox, if at all, at a speed the tangential impact can stop).  At zero speed the slip's
 * direction is free: a direction with no consistent normal force (Painleve) is not the one the point takes. */
static void gac_slide_direction(gac_sim *s, int c, const double *d)
{
    const gac_model *md = s->model;
    const int nq1 = GAC_AT_LEAST_1(md->nq);
    const double tries[4][2] = {{d[0], d[1]}, {-d[0], -d[1]}, {-d[1], d[0]}, {d[1], -d[0]}};
    double qdd[nq1], lambda[nq1];
    int k;
    for (k = 0; k < 4; ++k) {
        if (k == 2 && gac_tangent_axes(md, s->x, s->p, c) < 2) break;
        s->slip[2 * c] = tries[k][0];
        s->slip[2 * c + 1] = tries[k][1];
        if (!(fabs(d[0]) + fabs(d[1]) > 0.0)) return;
        if (gac_rest_forces(s, s->t, s->x, qdd, lambda, 0, 0) != GAC_ERR_FRICTION) return;
        s->n_painleve_choices++;
    }
    s->slip[2 * c] = s->slip[2 * c + 1] = 0.0;
}

/* Sliding -> stuck at s->x (a step's end, after an impact, at the start): each resting point on a rough wall that is
 * not stuck, slower than friction_velocity along its wall or (one tangential axis) whose velocity changed sign since
 * vt_start (2 per contact, the step's start; NULL: no such test), sticks if the stuck solve keeps every stuck point
 * inside its cone.  The velocities are then projected onto the held rows (the stuck tangential velocities to 0, mass
 * metric); with count_loss the kinetic energy that takes is added to loss_friction.  A slow point that cannot stick
 * slides on with the direction its stuck solve would slip in (s->slip); a slip's direction is forgotten once its point
 * is faster than friction_velocity or moves against it.  A point that sticks and was not stuck before (was_stuck, per
 * contact; NULL: none was) came to stick: counted in n_sticks and listed in r->stuck (r NULL: not listed).  Returns
 * the number of points that stuck, or an error. */
int gac_try_stick(gac_sim *s, const double *vt_start, int count_loss, const int *was_stuck, gac_impact_record *r)
{
    const gac_model *md = s->model;
    const double vs = md->friction_velocity;
    double vt[2 * GAC_AT_LEAST_1(md->ncontact)], E_before, d[2], x[md->nx];
    int list[GAC_AT_LEAST_1(md->nq)], a, added = 0, code;
    if (!s->opt.stick || s->nresting == 0 || !gac_has_friction(md)) return 0;
    gac_tangential_speeds(s, s->x, vt);
    for (a = 0; a < s->nresting; ++a) {
        const int c = s->resting[a];
        const double *w = vt + 2 * c, speed = sqrt(w[0] * w[0] + w[1] * w[1]);
        int turned;
        if (s->is_stuck[c] || !(gac_rest_friction(md, s->p, c) > 0.0)) continue;
        turned = vt_start != 0 && gac_tangent_axes(md, s->x, s->p, c) == 1
                 && w[0] * vt_start[2*c] + w[1] * vt_start[2*c + 1] < 0.0;
        if ((!(speed < vs) && !turned) || w[0] * s->slip[2*c] + w[1] * s->slip[2*c + 1] < 0.0)
            s->slip[2 * c] = s->slip[2 * c + 1] = 0.0;     /* past the passage through zero speed, or turned back */
        if (!(speed < vs) && !turned) continue;
        s->is_stuck[c] = 1;
        d[0] = d[1] = 0.0;
        gac_copy(x, s->x, md->nx);                    /* judged with its tangential velocity at 0 */
        code = gac_project_stuck(s, x, s->nresting, s->resting);
        if (code != GAC_OK || !gac_stuck_feasible(s, x, c, d)) {           /* it slides on: along the way its load drives it */
            s->is_stuck[c] = 0;
            gac_slide_direction(s, c, d);
            continue;
        }
        s->slip[2 * c] = s->slip[2 * c + 1] = 0.0;
        list[added++] = c;
    }
    if (added == 0) return 0;
    E_before = gac_total_energy(md, s->x, s->p);
    code = gac_project_stuck(s, s->x, s->nresting, s->resting);
    if (code != GAC_OK) return code;
    if (count_loss) s->loss_friction += E_before - gac_total_energy(md, s->x, s->p);
    for (a = 0; a < added; ++a) {                      /* the transitions: stuck now, not before */
        const int c = list[a];
        if (was_stuck != 0 && was_stuck[c]) continue;
        s->n_sticks++;
        if (r != 0) r->stuck[r->nstuck++] = c;
    }
    s->f_valid = s->vn_valid = 0;
    return added;
}

/* After an impact (or a tangential impact), every resting point re-decided: none stuck, then gac_try_stick (count_loss
 * as there).  Against was_stuck (per contact, the stuck points before the impact) the record r lists the transitions:
 * stuck now and not before (r->stuck), stuck before, still resting and now sliding (r->slipped); n_sticks and n_slips
 * count them.  Returns the number of points stuck now, or an error. */
int gac_restick(gac_sim *s, int count_loss, const int *was_stuck, gac_impact_record *r)
{
    const gac_model *md = s->model;
    int a, c, stuck;
    for (c = 0; c < md->ncontact; ++c) s->is_stuck[c] = 0;
    stuck = gac_try_stick(s, 0, count_loss, was_stuck, r);
    if (stuck < 0) return stuck;
    for (a = 0; a < s->nresting; ++a) {
        c = s->resting[a];
        if (!was_stuck[c] || s->is_stuck[c]) continue;
        s->n_slips++;
        if (r != 0) r->slipped[r->nslipped++] = c;
    }
    return stuck;
}
