/*
 * gac_sens.c -- forward sensitivities of a hybrid run (gac.h, "forward sensitivities of a run"): the variational
 * equations in flight, free or with resting contacts held (the constrained dynamics' tangent; a point stuck on a
 * rough wall held along every axis, its tangential rows with its normal one; a point sliding there with its Coulomb
 * or viscous friction, gac_sens_slide_tangent), taken by the run's
 * Runge-Kutta formula over the state's own steps and stages (gac_sens_flight), the derivative of the projection onto
 * the resting contacts after each step (gac_sens_project), the jump of the sensitivities at an impact by the
 * frictionless law -- of one contact or several, walls, joint stops, link pairs and links on obstacles, landings
 * among them (an obstacle's position and size among the directions), the set of pushing contacts held fixed, in
 * one round or several (the chain of the rounds' laws,
 * gac_sens_rounds_at) -- the saltation
 * matrix of Hiskens & Pai (2000) (gac_sens_impact), the release of a resting contact (gac_sens_release), a stuck
 * point's slip (gac_sens_slip) and a sliding point's coming to stick (gac_sens_stick), contacts at rest at the start
 * (gac_sens_attach), a switch of base chart (gac_sens_switch; S is in the coordinates of the chart integrated now,
 * gac_sens_state gives chart A's), a controller's state feedback by its Jacobian (gac_sens_du), and the verdict: the
 * first event not differentiated ends them (gac_sens_stop).
 */
#include "gac_internal.h"

#include <math.h>

#define GAC_SENS_STAGES 12    /* the most stages of a method's solution (DOP853); gac.h's GAC_SENS_NDOUBLE holds them */

long gac_sens_ndouble(const gac_model *m, int k)
{
    if (m == 0 || k < 1) return 0;
    return GAC_SENS_NDOUBLE(m->nq, m->nparam, m->ncontact, k);
}

static void gac_sens_start_rest(gac_sim *s);

/* 1 if the model has the tangent kernels the sensitivities call. */
static int gac_sens_has_tangents(const gac_model *md)
{
    return md->forward_dynamics_tangent != 0 && md->inertia_solve_tangent != 0
           && md->contact_generalized_force_tangent != 0 && md->contact_gaps_tangent != 0
           && md->contact_bias_tangent != 0;
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
    if (!gac_sens_has_tangents(md)) return GAC_ERR_BAD_MODEL;
    if (!gac_finite(seed_x, k * md->nx) || (seed_p != 0 && !gac_finite(seed_p, k * md->nparam)))
        return GAC_ERR_BAD_OPTION;
    for (i = 0; seed_p != 0 && i < k * md->nobstacle; ++i) {   /* a box's rotation: not a direction; a plane's
                                                                  normal only turned (n . dn = 0) */
        if (!gac_obstacle_turn_admissible(md, s->p, seed_p + (long)(i / md->nobstacle) * md->nparam,
                                          i % md->nobstacle))
            return GAC_ERR_BAD_OPTION;
    }
    sens->k = k;
    sens->S = dwork;                              /* dwork: S | dp | dt_impact | dgap_held | dslip | slip_known |
                                                     work | S_keep */
    sens->dp = dwork + (long)k * md->nx;
    sens->dt_impact = sens->dp + (long)k * md->nparam;
    sens->dgap_held = sens->dt_impact + k;
    sens->dslip = sens->dgap_held + (long)k * GAC_AT_LEAST_1(md->ncontact);
    sens->slip_known = sens->dslip + 2L * k * GAC_AT_LEAST_1(md->ncontact);
    sens->work = sens->slip_known + 2L * GAC_AT_LEAST_1(md->ncontact);
    sens->S_keep = dwork + gac_sens_ndouble(md, k) - (long)k * md->nx;   /* the last k nx doubles */
    sens->S_eval = 0;
    gac_copy(sens->S, seed_x, k * md->nx);
    for (i = 0; i < k * md->nparam; ++i) sens->dp[i] = seed_p != 0 ? seed_p[i] : 0.0;
    for (i = 0; i < k; ++i) sens->dt_impact[i] = 0.0;
    for (i = 0; i < k * GAC_AT_LEAST_1(md->ncontact); ++i) sens->dgap_held[i] = 0.0;
    for (i = 0; i < 2 * k * GAC_AT_LEAST_1(md->ncontact); ++i) sens->dslip[i] = 0.0;
    for (i = 0; i < 2 * GAC_AT_LEAST_1(md->ncontact); ++i) sens->slip_known[i] = 0.0;
    sens->status = GAC_SENS_VALID;
    sens->t_status = s->t;
    sens->contact_status = -1;
    sens->n_impacts = 0;
    sens->one_sided = 0;
    sens->n_boundaries = 0;
    sens->t_boundary = NAN;
    sens->contact_boundary = -1;
    s->sens = sens;
    if (s->chart != 0) {                          /* started on chart B: the seeds (chart A's) carried onto it at the
                                                     state before the start's projection (gac_sens_switch) */
        const int nq = md->nq;
        const double *x_b = s->pending ? s->x1 : s->x;
        double x_a[2 * nq];
        if (!gac_sens_has_tangents(s->model) || gac_state_chart_a(s, x_b, x_a) != GAC_OK
            || gac_tangent_between(md, s->model, s->chart, x_a, x_b, k, sens->S) != GAC_OK)
            gac_sens_stop(s, GAC_SENS_CHART, s->t, -1);
    }
    if (sens->status == GAC_SENS_VALID && s->nresting > 0) gac_sens_start_rest(s);
    return GAC_OK;
}

/* The switch of base chart (gac_switch_chart): the state x on chart `from` became y on `to`, the same physical
 * state (R and omega kept), so S_to = (d phi / dx) S_from, phi the conversion (gac_chart_convert_tangent).  The
 * switch comes at a step's end where chi_A crossed its threshold, a time that may move with the directions, but
 * its saltation term (f_to(y) - (d phi / dx) f_from(x)) dt* is 0 whatever dt*: the two charts' fields describe the
 * same motion, so f_to(phi(x)) = (d phi / dx) f_from(x).  A chart without tangent kernels (or y at its own lock)
 * ends the sensitivities. */
void gac_sens_switch(gac_sim *s, const gac_model *from, const gac_model *to, int flip, const double *x,
                     const double *y)
{
    gac_sens *z = s->sens;
    if (z == 0 || z->status != GAC_SENS_VALID) return;
    if (!gac_sens_has_tangents(to) || gac_tangent_between(from, to, flip, x, y, z->k, z->S) != GAC_OK) {
        gac_sens_stop(s, GAC_SENS_CHART, s->t, -1);
        return;
    }
    if (!gac_finite(z->S, z->k * from->nx)) gac_sens_stop(s, GAC_SENS_NONFINITE, s->t, -1);
}

/* S (k x nx) of the chart integrated now at the state x, into chart A's coordinates at xa (x converted), in place;
 * NaN where chart A is at its lock (its angles' derivatives unbounded there). */
void gac_sens_to_chart_a(const gac_sim *s, const double *x, const double *xa, double *S)
{
    const gac_sens *z = s->sens;
    int i;
    if (z == 0 || s->chart == 0 || z->status != GAC_SENS_VALID) return;
    if (gac_tangent_between(s->model, s->model_a, s->chart, x, xa, z->k, S) != GAC_OK) {
        for (i = 0; i < z->k * s->model->nx; ++i) S[i] = NAN;
    }
}

int gac_sens_state(const gac_sim *s, double *S)
{
    const gac_sens *z;
    if (s == 0 || S == 0 || s->sens == 0) return GAC_ERR_NULL_ARGUMENT;
    z = s->sens;
    gac_copy(S, z->S, z->k * s->model->nx);
    if (s->chart != 0 && z->status == GAC_SENS_VALID) {
        const int nq = s->model->nq;
        double xa[2 * nq];
        if (gac_state_chart_a(s, s->x, xa) != GAC_OK) {
            int i;
            for (i = 0; i < z->k * s->model->nx; ++i) S[i] = NAN;
            return GAC_OK;
        }
        gac_sens_to_chart_a(s, s->x, xa, S);
    }
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

/* The first link pair or obstacle of set[0..n-1] held at state x whose rest the sensitivities do not follow, or -1:
 * one whose normal has no derivative there (crossing axes, a link parallel to a face or to another link:
 * gac_contact_normal_tangent), or, rough, whose frame has none.  The others are followed as a wall's point: a smooth
 * one by its row J^T n, its bias and their derivatives from gac_link.c; a rough one stuck along its frame's rows
 * J^T t1, J^T t2 too, or sliding with its friction along them (gac_sens_tangent_rows). */
static int gac_sens_rowless_check(const gac_sim *s, const double *x, int n, const int *set)
{
    const gac_model *md = s->model;
    const int nq = md->nq;
    double zero_p[GAC_AT_LEAST_1(md->nparam)], g[3 * GAC_AT_LEAST_1(nq)], dg[3 * GAC_AT_LEAST_1(nq)], axes[9], dgap;
    int a, i;
    for (i = 0; i < GAC_AT_LEAST_1(md->nparam); ++i) zero_p[i] = 0.0;
    for (a = 0; a < n; ++a) {
        const int c = set[a], rough = gac_contact_friction(md, s->p, c) > 0.0;
        if (!gac_rowless(md, c)) continue;
        if (gac_contact_normal_tangent(md, x, s->p, c, x + nq, zero_p, &dgap, g, dg) != GAC_OK
            || (rough && gac_contact_frame_tangent(md, x, s->p, c, x + nq, zero_p, axes, g, dg) != GAC_OK))
            return c;
    }
    return -1;
}

void gac_sens_rest_set(gac_sim *s, double t)
{
    int c;
    if (s->sens == 0 || s->sens->status != GAC_SENS_VALID) return;
    c = gac_sens_rowless_check(s, s->x, s->nresting, s->resting);
    if (c >= 0) gac_sens_stop(s, GAC_SENS_LINK, t, c);
}

/* The inputs' derivative is taken as 0: held inputs and schedules are functions of t alone, a controller may not be. */
static int gac_sens_inputs_fixed(const gac_sim *s)
{
    return s->controller == 0 || s->controller == gac_schedule_input || s->model->nu == 0;
}

/* 1 if the inputs' derivative is known: 0 (gac_sens_inputs_fixed) or a controller's by its Jacobian. */
static int gac_sens_inputs_known(const gac_sim *s)
{
    return gac_sens_inputs_fixed(s) || s->controller_jacobian != 0;
}

/* The inputs' Jacobian at time t and state x (of the chart integrated now), for gac_sens_du: J (2 nu nq doubles) =
 * du/dq | du/dqd from the controller's Jacobian, in chart A's coordinates (the controller's), with xa = x there.
 * Returns 0 if the inputs' derivative is 0 (J not written), 1 if J holds it (NaN where x has no chart A
 * coordinates: the sensitivities then end as not finite). */
static int gac_sens_jacobian_at(gac_sim *s, double t, const double *x, double *J, double *xa)
{
    const gac_model *md = s->model;
    const int nq = md->nq, nu = md->nu;
    int i;
    if (gac_sens_inputs_fixed(s) || s->controller_jacobian == 0) return 0;
    if (s->chart == 0) {
        gac_copy(xa, x, md->nx);
    } else if (gac_state_chart_a(s, x, xa) != GAC_OK) {
        for (i = 0; i < 2 * nu * nq; ++i) J[i] = NAN;
        return 1;
    }
    s->controller_jacobian(t, xa, xa + nq, J, J + (long)nu * nq, s->controller_data);
    return 1;
}

/* The inputs' direction du (nu) along a direction (dq, dqd) of the chart integrated now at x: 0 (J NULL), or
 *     du = du_dq dq_A + du_dqd dqd_A,
 * J and xa from gac_sens_jacobian_at, (dq_A, dqd_A) the direction in chart A's coordinates at xa. */
static void gac_sens_du(const gac_sim *s, const double *J, const double *x, const double *xa, const double *dq,
                        const double *dqd, double *du)
{
    const gac_model *md = s->model;
    const int nq = md->nq, nu = md->nu;
    double d[2 * nq];
    int i, l;
    if (J == 0) {
        for (i = 0; i < nu; ++i) du[i] = 0.0;
        return;
    }
    gac_copy(d, dq, nq);
    gac_copy(d + nq, dqd, nq);
    if (s->chart != 0 && gac_tangent_between(md, s->model_a, s->chart, x, xa, 1, d) != GAC_OK) {
        for (i = 0; i < nu; ++i) du[i] = NAN;
        return;
    }
    for (i = 0; i < nu; ++i) {
        double sum = 0.0;
        for (l = 0; l < nq; ++l) sum += J[(long)i * nq + l] * d[l] + J[(long)(nu + i) * nq + l] * d[nq + l];
        du[i] = sum;
    }
}

/* The inputs' rate along the flow f = [qd, qdd] at (t, x), for an event's rate (a release, a slip): 0 for held
 * inputs (J NULL), else du = du_dq qd + du_dqd qdd + du/dt, the explicit du/dt the controller's central difference in t
 * at the fixed state x (exactly 0 for a controller of the state alone). */
static void gac_sens_input_rate(gac_sim *s, const double *J, double t, const double *x, const double *xa,
                                const double *f, double *du)
{
    const gac_model *md = s->model;
    const int nq = md->nq, nu = md->nu;
    const double h = 1e-5 * (fabs(t) > 1.0 ? fabs(t) : 1.0), tp = t + h, tm = t - h;
    double up[GAC_AT_LEAST_1(nu)], um[GAC_AT_LEAST_1(nu)];
    int i;
    gac_sens_du(s, J, x, xa, f, f + nq, du);
    if (J == 0) return;
    gac_copy(up, s->u, nu);
    gac_copy(um, s->u, nu);
    s->controller(tp, xa, xa + nq, up, s->controller_data);
    s->controller(tm, xa, xa + nq, um, s->controller_data);
    for (i = 0; i < nu; ++i) du[i] += (up[i] - um[i]) / (tp - tm);
}

/* ---- contacts held at their walls: the constrained dynamics and the projections, and their tangents ---- */

/* Contact c's row at q as an impact's law takes it: a wall's or a stop's unit signed row f (nr) of J and
 * w = J^T f; a link pair's or an obstacle's w = J^T n (gac_link_contact_direction, the gap's gradient), f left 0. */
static void gac_sens_row(const gac_sim *s, int c, const double *q, double *f, double *w)
{
    const gac_model *md = s->model;
    const gac_contact *ct = md->contacts + c;
    int i;
    for (i = 0; i < GAC_AT_LEAST_1(md->njrow); ++i) f[i] = 0.0;
    if (gac_rowless(md, c)) {
        gac_link_contact_direction(md, q, s->p, c, w);
        return;
    }
    f[ct->row] = ct->normal_sign;
    md->contact_generalized_force(q, f, s->p, w);
}

/* The derivative dw of contact c's row (gac_sens_row, f its row of J) along (dq, dp): d(J^T f) by
 * contact_generalized_force_tangent, or for a link pair or an obstacle d(J^T n) with the closest points' motion and
 * the normal's rotation (gac_contact_normal_tangent).  Returns 0, or 1 where the latter has none (crossing axes,
 * a link parallel to a face or to another link). */
static int gac_sens_row_tangent(const gac_sim *s, int c, const double *f, const double *q, const double *dq,
                                const double *dp, double *dw)
{
    const gac_model *md = s->model;
    if (gac_rowless(md, c)) {
        double g[md->nq], dgap;
        return gac_contact_normal_tangent(md, q, s->p, c, dq, dp, &dgap, g, dw) != GAC_OK;
    }
    {
        double df[GAC_AT_LEAST_1(md->njrow)];
        int i;
        for (i = 0; i < GAC_AT_LEAST_1(md->njrow); ++i) df[i] = 0.0;
        md->contact_generalized_force_tangent(q, f, s->p, dq, df, dp, dw);
    }
    return 0;
}

/* The gaps' derivatives dgap (ncontact) along (dq, dp) at q: the walls' and stops' by contact_gaps_tangent, and
 * those of the link pairs and obstacles among set[0..n-1] (gac_contact_normal_tangent: n . dD, the closest points'
 * relative motion along the normal); the other link pairs' and obstacles' entries NaN. */
static void gac_sens_gaps_tangent(const gac_sim *s, const double *q, const double *dq, const double *dp, int n,
                                  const int *set, double *dgap)
{
    const gac_model *md = s->model;
    const int nq = md->nq;
    double g[GAC_AT_LEAST_1(nq)], dw[GAC_AT_LEAST_1(nq)];
    int a, c;
    md->contact_gaps_tangent(q, s->p, dq, dp, dgap);
    for (c = gac_kernel_contacts(md); c < md->ncontact; ++c) dgap[c] = NAN;
    for (a = 0; a < n; ++a) {
        if (gac_rowless(md, set[a])
            && gac_contact_normal_tangent(md, q, s->p, set[a], dq, dp, dgap + set[a], g, dw) != GAC_OK)
            dgap[set[a]] = NAN;
    }
}

/* A set of contacts held at their walls (resting, or brought to rest by an impact) at a configuration q, as rows:
 * first each contact's normal row, then the two tangential rows of each one stuck on a rough wall (gac_held_rows'
 * order; a stuck point is a bilateral constraint along all three axes).  Row a: its unit signed row f_a (nr) of J,
 * brow[a] (its row of J and of contact_bias) and sgn[a] (the normal's sign, 1 along a tangential axis); W_a = J^T f_a
 * (its generalised normal), Y_a = I_f^-1 W_a and A = W Y, factored in LD (gac_ldlt).  A link pair or an obstacle
 * held (no row of J) has brow[a] = -1, f_a = 0 and W_a = J^T a_k at its closest points along its frame's axis
 * k = rk[a] (gac_rowless_frame: 0 the normal n, the gap's gradient; 1, 2 the tangents t1, t2 of one stuck there, as
 * gac_held_rows takes them), its bias and their derivatives from gac_link.c; rk[a] = -1 for a row of J.  rc[a]: row
 * a's contact.  The arrays are the caller's, sized for m <= 3 nq rows. */
typedef struct {
    int m;                       /* rows (the first n the normal rows of set's contacts) */
    int n;
    int ndropped;                /* rows dependent on those before them (gac_ldlt_drop: their force 0) */
    const int *set;
    int *brow, *rc, *rk;
    double *sgn, *f, *W, *Y, *LD;
    /* Sliding friction (gac_sens_set_slide; nslide = 0 without): contact a (a < n) sliding on a rough wall has
       cf[a] > 0 and takes -cf lambda_a phi_a along the wall (phi_a = gac_slide_phi of its tangential velocity vt_a):
       its force's generalised direction is D_a = W_a + cf_a G_a, G_a = J^T g_a, g_a = -phi_a on its tangential rows
       (Wt: their J^T e_trow, 2 per contact, 0 for a missing axis; a link pair's or an obstacle's frame rows
       J^T t1, J^T t2: gac_sens_tangent_rows).  Yd_r = I_f^-1 D_r (Y_r for the other rows) and
       B = W Yd^T (m x m, not symmetric), so B lambda = -(W qdd_free + b) and qdd = qdd_free + Yd lambda. */
    int nslide;
    double *cf, *phi, *vt, *G, *Wt, *Yd, *B;
    const double *slip;          /* the slip directions phi was formed with (2 per contact) */
} gac_sens_set;

#define GAC_SENS_SET_ARRAYS_OF(P, nq, nr) \
    double P##_f[3 * (nq) * (nr)], P##_W[3 * (nq) * (nq)], P##_Y[3 * (nq) * (nq)], P##_LD[9 * (nq) * (nq)], \
        P##_sgn[3 * (nq)], P##_cf[(nq)], P##_phi[2 * (nq)], P##_vt[2 * (nq)], P##_G[(nq) * (nq)], \
        P##_Wt[2 * (nq) * (nq)], P##_Yd[(nq) * (nq)], P##_B[(nq) * (nq)]; \
    int P##_brow[3 * (nq)], P##_rc[3 * (nq)], P##_rk[3 * (nq)]
#define GAC_SENS_SET_BIND_OF(S, P) ((S).f = P##_f, (S).W = P##_W, (S).Y = P##_Y, (S).LD = P##_LD, (S).sgn = P##_sgn, \
                                    (S).brow = P##_brow, (S).rc = P##_rc, (S).rk = P##_rk, (S).cf = P##_cf, \
                                    (S).phi = P##_phi, (S).vt = P##_vt, \
                                    (S).G = P##_G, (S).Wt = P##_Wt, (S).Yd = P##_Yd, (S).B = P##_B, (S).nslide = 0)
#define GAC_SENS_SET_ARRAYS(nq, nr) GAC_SENS_SET_ARRAYS_OF(H, nq, nr)   /* the arrays of a set named H */
#define GAC_SENS_SET_BIND(S) GAC_SENS_SET_BIND_OF(S, H)

/* Contact c's two tangential rows at q into wt (2 x nq): a wall's J^T e_trow along +X_axis (0 for an axis without a
 * row), a link pair's or an obstacle's frame rows J^T t1, J^T t2 (gac_frame_direction; a tangent no motion takes is
 * ~0); with dq (not NULL) their derivatives along (dq, dp) into dwt (2 x nq): contact_generalized_force_tangent, or
 * the frame's turning and the closest points' motion (gac_contact_frame_tangent; NaN where it has none). */
static void gac_sens_tangent_rows(const gac_sim *s, const double *q, int c, const double *dq, const double *dp,
                                  double *wt, double *dwt)
{
    const gac_model *md = s->model;
    const gac_contact *ct = md->contacts + c;
    const int nq = md->nq, nr = GAC_AT_LEAST_1(md->njrow);
    int i, t;
    if (gac_rowless(md, c)) {
        double axes[9], g[3 * nq], dg[3 * nq];
        gac_contact_frame frame;
        if (dq != 0 && gac_contact_frame_tangent(md, q, s->p, c, dq, dp, axes, g, dg) == GAC_OK) {
            gac_copy(wt, g + nq, 2L * nq);           /* the rows and their derivatives at once */
            gac_copy(dwt, dg + nq, 2L * nq);
            return;
        }
        if (gac_rowless_frame(md, q, s->p, c, &frame) != GAC_OK) {
            for (i = 0; i < 2 * nq; ++i) wt[i] = NAN;
        } else {
            for (t = 0; t < 2; ++t) (void)gac_frame_direction(md, q, s->p, &frame, 1 + t, wt + (long)t * nq);
        }
        for (i = 0; dq != 0 && i < 2 * nq; ++i) dwt[i] = NAN;   /* (its frame has no derivative there) */
        return;
    }
    {
        double unit[nr], zero[nr];
        for (i = 0; i < nr; ++i) unit[i] = zero[i] = 0.0;
        for (t = 0; t < 2; ++t) {
            for (i = 0; i < nq; ++i) {
                wt[(long)t * nq + i] = 0.0;
                if (dq != 0) dwt[(long)t * nq + i] = 0.0;
            }
            if (ct->kind != GAC_CONTACT_WALL || ct->trow[t] < 0) continue;
            unit[ct->trow[t]] = 1.0;
            md->contact_generalized_force(q, unit, s->p, wt + (long)t * nq);
            if (dq != 0) md->contact_generalized_force_tangent(q, unit, s->p, dq, zero, dp, dwt + (long)t * nq);
            unit[ct->trow[t]] = 0.0;
        }
    }
}

/* The row of set H held along contact c's tangential direction t (0, 1): a wall's trow, a link pair's or an
 * obstacle's frame tangent 1 + t; -1 where it has none (an axis without a row, a tangent no motion takes, or a row
 * dropped). */
static int gac_sens_tangent_row(const gac_sim *s, const gac_sens_set *H, int c, int t)
{
    const gac_contact *ct = s->model->contacts + c;
    const int rowless = gac_rowless(s->model, c);
    int a;
    for (a = H->n; a < H->m; ++a) {
        if (H->rc[a] == c && (rowless ? H->rk[a] == 1 + t : ct->trow[t] >= 0 && H->brow[a] == ct->trow[t]))
            return a;
    }
    return -1;
}

/* A link pair's or an obstacle's frame row J^T t_k (k = 1, 2; gac_frame_direction) at q into w (nq), NaN where its
 * frame fails; its return: the columns' size (gac_frame_direction's). */
static double gac_sens_frame_row(const gac_sim *s, const double *q, int c, int k, double *w)
{
    const gac_model *md = s->model;
    gac_contact_frame frame;
    int i;
    if (gac_rowless_frame(md, q, s->p, c, &frame) != GAC_OK) {
        for (i = 0; i < md->nq; ++i) w[i] = NAN;
        return 0.0;
    }
    return gac_frame_direction(md, q, s->p, &frame, k, w);
}

/* 1 if some motion of the chain moves contact c's closest points along its frame's tangent k (|J^T t_k| above 1e-10
 * of its columns' size): the rows gac_held_rows holds for a stuck link pair or obstacle (a planar model's t2 no motion
 * takes is left out). */
static int gac_sens_frame_moves(const gac_sim *s, const double *q, int c, int k)
{
    double w[GAC_AT_LEAST_1(s->model->nq)];
    const double scale = gac_sens_frame_row(s, q, c, k, w);
    return sqrt(gac_dot(s->model->nq, w, w)) > 1e-10 * scale;
}

/* 1 if contact c rests on a rough wall, link or obstacle without being stuck (stuck: per contact, or NULL: none is):
 * it slides there. */
static int gac_sens_sliding(const gac_sim *s, const int *stuck, int c)
{
    return (stuck == 0 || !stuck[c]) && gac_rest_friction(s->model, s->p, c) > 0.0;
}

/* 1 if resting contact c slides with a slip direction (s->slip, set where a stuck point slipped or a slow point
 * could not stick) over two tangential axes whose derivative is not known: below friction_velocity that direction
 * enters its friction, and its derivative (sens->dslip) is known for the direction sens->slip_known it was found
 * for (gac_sens_slip, gac_sens_reslip).  Along one axis it is +-1, a constant. */
static int gac_sens_slip_unknown(const gac_sim *s, int c)
{
    const gac_contact *ct = s->model->contacts + c;
    const double *d = s->slip + 2 * c, *known = s->sens->slip_known + 2 * c;
    return gac_sens_sliding(s, s->is_stuck, c) && (d[0] != 0.0 || d[1] != 0.0) && (d[0] != known[0] || d[1] != known[1])
           && (gac_rowless(s->model, c) ? gac_sens_frame_moves(s, s->x, c, 2) : ct->trow[0] >= 0 && ct->trow[1] >= 0);
}

/* A contact of set[0..n-1] sliding at state x slower than friction_velocity (stuck: per contact, or NULL: none is),
 * or -1: at an impact the slip directions (s->slip) of the fields before and after are the loop's after it. */
static int gac_sens_slow_slide(const gac_sim *s, const double *x, int n, const int *set, const int *stuck)
{
    const gac_model *md = s->model;
    double vq[3 * GAC_AT_LEAST_1(md->npoint)], vt[2];
    int a;
    md->contact_velocities(x, x + md->nq, s->p, vq);
    for (a = 0; a < n; ++a) {
        if (md->contacts[set[a]].kind == GAC_CONTACT_STOP || !gac_sens_sliding(s, stuck, set[a])) continue;
        gac_tangential_velocity(md, x, s->p, set[a], vq, vt);
        if (!(hypot(vt[0], vt[1]) > md->friction_velocity)) return set[a];
    }
    return -1;
}

/* Fill H for set[0..n-1] at q, with the tangential rows of those stuck (stuck: per contact, or NULL: normal rows
 * only).  A row dependent on those before it (a rod lying flat stuck at both ends holds the same tangential row
 * twice) drops out as in the loop (gac_ldlt_drop: its force 0, the motion the same; counted in H->ndropped).
 * Returns 0, or 1 for more than 3 nq rows or none independent. */
static int gac_sens_set_at(const gac_sim *s, const double *q, int n, const int *set, const int *stuck,
                           gac_sens_set *H)
{
    const gac_model *md = s->model;
    const int nq = md->nq, nr = GAC_AT_LEAST_1(md->njrow);
    int a, b, i, t, m = 0;
    H->set = set;
    H->n = n;
    H->nslide = 0;
    for (a = 0; a < n; ++a) {                     /* the normal rows (a link pair's or an obstacle's: brow -1) */
        const gac_contact *ct = md->contacts + set[a];
        const int rowless = gac_rowless(md, set[a]);
        H->brow[m] = rowless ? -1 : ct->row;
        H->rc[m] = set[a], H->rk[m] = rowless ? 0 : -1;
        H->sgn[m++] = rowless ? 1.0 : ct->normal_sign;
    }
    for (a = 0; a < n && stuck != 0; ++a) {       /* the stuck points' tangential rows, along +X_axis, or a link
                                                     pair's or an obstacle's along its frame's t1, t2 */
        const gac_contact *ct = md->contacts + set[a];
        const int rowless = gac_rowless(md, set[a]);
        if (!stuck[set[a]] || !(gac_rest_friction(md, s->p, set[a]) > 0.0)) continue;
        for (t = 0; t < 2; ++t) {
            if (!rowless && ct->trow[t] < 0) continue;
            if (m == 3 * nq) return 1;
            if (rowless) {                        /* J^T t_k formed here; one no motion takes is left out */
                double *w = H->W + (long)m * nq;
                const double scale = gac_sens_frame_row(s, q, set[a], 1 + t, w);
                if (!(sqrt(gac_dot(nq, w, w)) > 1e-10 * scale)) continue;
            }
            H->brow[m] = rowless ? -1 : ct->trow[t];
            H->rc[m] = set[a], H->rk[m] = rowless ? 1 + t : -1;
            H->sgn[m++] = 1.0;
        }
    }
    H->m = m;                                     /* (more than nq rows: some depend on the others) */
    for (a = 0; a < m; ++a) {
        double *fa = H->f + (long)a * nr;
        if (a < n) {                              /* a normal row: a wall's, or a link pair's or obstacle's J^T n */
            gac_sens_row(s, set[a], q, fa, H->W + (long)a * nq);
        } else if (H->rk[a] > 0) {                /* a stuck link pair's or obstacle's J^T t_k (W formed above) */
            for (i = 0; i < nr; ++i) fa[i] = 0.0;
        } else {                                  /* a stuck point's tangential row */
            for (i = 0; i < nr; ++i) fa[i] = 0.0;
            fa[H->brow[a]] = H->sgn[a];
            md->contact_generalized_force(q, fa, s->p, H->W + (long)a * nq);
        }
        md->inertia_solve(q, H->W + (long)a * nq, s->p, H->Y + (long)a * nq);
    }
    for (a = 0; a < m; ++a) {
        for (b = 0; b <= a; ++b) {
            double sum = 0.0;
            for (i = 0; i < nq; ++i) sum += H->W[(long)a * nq + i] * H->Y[(long)b * nq + i];
            H->LD[a * m + b] = H->LD[b * m + a] = sum;
        }
    }
    H->ndropped = m > 0 ? gac_ldlt_drop(m, H->LD, 1e-12) : 0;
    return H->ndropped < 0;
}

/* The sliding friction of H's contacts that slide on rough walls at state x (stuck: per contact, or NULL: none is;
 * H filled by gac_sens_set_at at x's q): cf, vt, phi, Wt, G, Yd and B (gac_sens_set).  The loop's forces are
 * gac_constrained_dynamics_friction's with the same phi (gac_slide_phi, with the slip directions slip, 2 per
 * contact, below friction_velocity: s->slip, or the loop's before it changed them).  Returns 0, or 1 where a row of H
 * dropped out (B would be singular). */
static int gac_sens_set_slide(const gac_sim *s, const double *x, const int *stuck, const double *slip,
                              gac_sens_set *H)
{
    const gac_model *md = s->model;
    const int nq = md->nq, m = H->m;
    double vq[3 * GAC_AT_LEAST_1(md->npoint)], D[nq];
    int a, b, i, t;
    H->nslide = 0;
    H->slip = slip;
    for (a = 0; a < H->n; ++a) {
        const int c = H->set[a];
        H->cf[a] = md->contacts[c].kind != GAC_CONTACT_STOP && gac_sens_sliding(s, stuck, c)
                   ? gac_rest_friction(md, s->p, c) : 0.0;
        H->nslide += H->cf[a] > 0.0;
    }
    if (H->nslide == 0) return 0;
    if (H->ndropped > 0) return 1;            /* B with a dependent row: no unique forces to differentiate */
    md->contact_velocities(x, x + nq, s->p, vq);
    gac_copy(H->Yd, H->Y, (long)m * nq);
    for (a = 0; a < H->n; ++a) {
        double *G = H->G + (long)a * nq;
        if (!(H->cf[a] > 0.0)) continue;
        gac_tangential_velocity(md, x, s->p, H->set[a], vq, H->vt + 2 * a);
        gac_slide_phi(H->vt + 2 * a, md->friction_velocity, slip + 2 * H->set[a], H->phi + 2 * a);
        gac_sens_tangent_rows(s, x, H->set[a], 0, 0, H->Wt + (long)(2 * a) * nq, 0);
        for (i = 0; i < nq; ++i) G[i] = 0.0;
        for (t = 0; t < 2; ++t) {                 /* G_a = J^T g_a = -sum_t phi_t Wt_t */
            const double *wt = H->Wt + (long)(2 * a + t) * nq;
            for (i = 0; i < nq; ++i) G[i] -= H->phi[2 * a + t] * wt[i];
        }
        for (i = 0; i < nq; ++i) D[i] = H->W[(long)a * nq + i] + H->cf[a] * G[i];
        md->inertia_solve(x, D, s->p, H->Yd + (long)a * nq);
    }
    for (a = 0; a < m; ++a) {
        for (b = 0; b < m; ++b) H->B[a * m + b] = gac_dot(nq, H->W + (long)a * nq, H->Yd + (long)b * nq);
    }
    return 0;
}

/* Solve H's force system for r (m) in place: A r = r by LD, or with sliding friction B r = r by LU (a copy of B).
 * Returns 0, or 1 where B is singular (r then NaN). */
static int gac_sens_set_solve(const gac_sens_set *H, double *r)
{
    const int m = H->m;
    int a;
    if (m == 0) return 0;
    if (H->nslide == 0) {
        gac_ldlt_solve(m, H->LD, r);
        return 0;
    }
    {
        double B[m * m];
        gac_copy(B, H->B, (long)m * m);
        if (gac_lu_solve(m, B, r, 1e-14) == 0) return 0;
    }
    for (a = 0; a < m; ++a) r[a] = NAN;
    return 1;
}

/* The biases (dq NULL) or their derivatives along (dq, dqd, dp) of H's rows of link pairs and obstacles into out
 * (H->m; the other rows' entries left as they are; NaN where a row has none): per contact once, its normal row's and,
 * stuck, its frame rows' together (gac_rowless_frame_bias, gac_rowless_bias_tangent with 3 rows). */
static void gac_sens_rowless_biases(const gac_sim *s, const double *x, const gac_sens_set *H, const double *dq,
                                    const double *dqd, const double *dp, double *out)
{
    const gac_model *md = s->model;
    const int nq = md->nq;
    int a, b;
    for (a = 0; a < H->n; ++a) {                  /* each contact's normal row, then its frame rows */
        double value[3] = {NAN, NAN, NAN};
        int rows = 1, code;
        if (H->rk[a] != 0) continue;
        for (b = H->n; b < H->m; ++b) rows = H->rc[b] == H->rc[a] && H->rk[b] > 0 ? 3 : rows;
        if (dq == 0)
            code = rows == 1 ? gac_rowless_bias(md, x, x + nq, s->p, H->rc[a], value)
                             : gac_rowless_frame_bias(md, x, x + nq, s->p, H->rc[a], value);
        else
            code = gac_rowless_bias_tangent(md, x, x + nq, s->p, H->rc[a], rows, dq, dqd, dp, value);
        if (code != GAC_OK) value[0] = value[1] = value[2] = NAN;
        out[a] = value[0];
        for (b = H->n; b < H->m; ++b) {
            if (H->rc[b] == H->rc[a] && H->rk[b] > 0) out[b] = value[H->rk[b]];
        }
    }
}

/* The constrained flight at state x with H held (H at x's q): qdd_free = I_f^-1 R, the forces lambda of
 * A lambda = -(W qdd_free + b), b_a = sign_a (Jdot qd)[row_a], and qdd = qdd_free + Y lambda
 * (gac_constrained_dynamics on a frictionless set); with sliding friction (gac_sens_set_slide) B lambda = the same
 * and qdd = qdd_free + Yd lambda (gac_constrained_dynamics_friction).  lambda_ref (if not NULL): the force scale,
 * the largest |W_a qdd_free + b_a| / A_aa. */
static void gac_sens_held_forces(const gac_sim *s, const double *x, const double *u, const gac_sens_set *H,
                                 double *qdd_free, double *lambda, double *qdd, double *lambda_ref)
{
    const gac_model *md = s->model;
    const int nq = md->nq, m = H->m;
    const double *Yd = H->nslide > 0 ? H->Yd : H->Y;
    double bias[GAC_AT_LEAST_1(md->njrow)], rowless[GAC_AT_LEAST_1(m)];
    int a, i;
    md->forward_dynamics(x, x + nq, u, s->p, qdd_free);
    md->contact_bias(x, x + nq, s->p, bias);
    gac_sens_rowless_biases(s, x, H, 0, 0, 0, rowless);
    if (lambda_ref != 0) *lambda_ref = 0.0;
    for (a = 0; a < m; ++a) {
        const double b = H->brow[a] >= 0 ? H->sgn[a] * bias[H->brow[a]] : rowless[a];
        lambda[a] = -(b + gac_dot(nq, H->W + (long)a * nq, qdd_free));
        if (lambda_ref != 0) {
            const double A_aa = gac_dot(nq, H->W + (long)a * nq, H->Y + (long)a * nq);
            if (fabs(lambda[a]) / A_aa > *lambda_ref) *lambda_ref = fabs(lambda[a]) / A_aa;
        }
    }
    gac_sens_set_solve(H, lambda);
    for (i = 0; i < nq; ++i) {
        double value = qdd_free[i];
        for (a = 0; a < m; ++a) value += Yd[(long)a * nq + i] * lambda[a];
        qdd[i] = value;
    }
}

/* The derivative dw (nq) along (dq, dp) of H's row a of a link pair or an obstacle: d(J^T n) (gac_sens_row_tangent)
 * or d(J^T t_k) (gac_contact_frame_tangent), NaN where it has none (gac_sens_rowless_check tells it before). */
static void gac_sens_rowless_tangent(const gac_sim *s, const gac_sens_set *H, int a, const double *q, const double *dq,
                                     const double *dp, double *dw)
{
    const gac_model *md = s->model;
    const int nq = md->nq, k = H->rk[a];
    int i, failed;
    if (k == 0) {
        failed = gac_sens_row_tangent(s, H->rc[a], H->f + (long)a * GAC_AT_LEAST_1(md->njrow), q, dq, dp, dw) != 0;
    } else {
        double axes[9], g[3 * nq], dg[3 * nq];
        failed = gac_contact_frame_tangent(md, q, s->p, H->rc[a], dq, dp, axes, g, dg) != GAC_OK;
        if (!failed) gac_copy(dw, dg + (long)k * nq, nq);
    }
    for (i = 0; failed && i < nq; ++i) dw[i] = NAN;
}

/* dW_a = d(J^T f_a) and dY_a = d(I_f^-1 W_a) along (dq, dp), a = 0..m-1 (m x nq each). */
static void gac_sens_set_tangent(const gac_sim *s, const double *q, const gac_sens_set *H, const double *dq,
                                 const double *dp, double *dW, double *dY)
{
    const gac_model *md = s->model;
    const int nq = md->nq, nr = GAC_AT_LEAST_1(md->njrow);
    double df[GAC_AT_LEAST_1(md->njrow)];
    int a, i;
    for (i = 0; i < nr; ++i) df[i] = 0.0;
    for (a = 0; a < H->m; ++a) {
        if (H->brow[a] >= 0)
            md->contact_generalized_force_tangent(q, H->f + (long)a * nr, s->p, dq, df, dp, dW + (long)a * nq);
        else
            gac_sens_rowless_tangent(s, H, a, q, dq, dp, dW + (long)a * nq);
        if (dY != 0)
            md->inertia_solve_tangent(q, H->W + (long)a * nq, s->p, dq, dW + (long)a * nq, dp, dY + (long)a * nq);
    }
}

/* The sliding contacts' dYd_a = d(I_f^-1 D_a) along (dq, dqd, dp) into dY's rows (dW from gac_sens_set_tangent):
 *     dD_a = dW_a + dc_f G_a + c_f d(J^T g_a)[dq, dg_a, dp],   dg_a = -dphi_a on its tangential rows,
 *     dphi = (I - phi phi^T) dv_t / |v_t|                        (Coulomb, |v_t| > v_s),
 *     dphi = dv_t / v_s - (v_t . dv_t) / (|v_t| v_s) d + (1 - |v_t| / v_s) dd   (viscous, below v_s; d the slip
 *                                                                            direction, dd its derivative dslip),
 * dv_t along each tangential row t = d(J^T e_t)[dq, dp] . qd + Wt_t . dqd.  (One tangential axis: phi = +-1, or
 * d where the point moves along d, so dphi = 0 but for the viscous part's dv_t / v_s.) */
static void gac_sens_slide_tangent(const gac_sim *s, const double *x, const gac_sens_set *H, const double *dq,
                                   const double *dqd, const double *dp, const double *dslip, const double *dW,
                                   double *dY)
{
    const gac_model *md = s->model;
    const int nq = md->nq;
    const double vs = md->friction_velocity;
    double wt[2 * nq], dwt[2 * nq], dJg[nq], D[nq], dD[nq];
    int a, i, t;
    for (a = 0; a < H->n; ++a) {
        const gac_contact *ct = md->contacts + H->set[a];
        const double cf = H->cf[a], *vt = H->vt + 2 * a, *phi = H->phi + 2 * a, *d = H->slip + 2 * H->set[a];
        const double speed = sqrt(vt[0] * vt[0] + vt[1] * vt[1]);
        const double dcf = ct->friction_index >= 0 ? dp[ct->friction_index] : 0.0;
        double dvt[2] = {0.0, 0.0}, dphi[2], along = 0.0;
        if (!(cf > 0.0)) continue;
        gac_sens_tangent_rows(s, x, H->set[a], dq, dp, wt, dwt);
        for (t = 0; t < 2; ++t)
            dvt[t] = gac_dot(nq, dwt + (long)t * nq, x + nq) + gac_dot(nq, H->Wt + (long)(2 * a + t) * nq, dqd);
        if (speed > vs) {
            const double pd = phi[0] * dvt[0] + phi[1] * dvt[1];
            for (t = 0; t < 2; ++t) dphi[t] = (dvt[t] - phi[t] * pd) / speed;
        } else {                                  /* (at rest along d: |v_t|' = d . dv_t) */
            along = speed > 0.0 ? (vt[0] * dvt[0] + vt[1] * dvt[1]) / speed : d[0] * dvt[0] + d[1] * dvt[1];
            for (t = 0; t < 2; ++t) dphi[t] = (dvt[t] - along * d[t]) / vs;
            if (dslip != 0 && (d[0] != 0.0 || d[1] != 0.0)) {   /* the slip direction's own derivative */
                for (t = 0; t < 2; ++t) dphi[t] += (1.0 - speed / vs) * dslip[2 * H->set[a] + t];
            }
        }
        for (i = 0; i < nq; ++i) {                /* d(J^T g)[dq, dg, dp], g = -phi on the tangential rows */
            dJg[i] = 0.0;
            for (t = 0; t < 2; ++t) dJg[i] -= dphi[t] * wt[(long)t * nq + i] + phi[t] * dwt[(long)t * nq + i];
        }
        for (i = 0; i < nq; ++i) {
            D[i] = H->W[(long)a * nq + i] + cf * H->G[(long)a * nq + i];
            dD[i] = dW[(long)a * nq + i] + dcf * H->G[(long)a * nq + i] + cf * dJg[i];
        }
        md->inertia_solve_tangent(x, D, s->p, dq, dD, dp, dY + (long)a * nq);
    }
}

/* The constrained flight's tangent along (dq, dqd, dp), dqdd_free the free dynamics' there (the forces as
 * gac_sens_held_forces left them; qdd = qdd_free + Yd lambda):
 *     B dlambda = -(sign d(Jdot qd)[dq, dqd, dp] + dW qdd + W (dqdd_free + dYd lambda)),
 *     d qdd = dqdd_free + dYd lambda + Yd dlambda,
 * dW, dY along (dq, dp) (gac_sens_set_tangent), d(Jdot qd) by contact_bias_tangent; without sliding friction
 * Yd = Y and B = A (so the first is A dlambda = -(sign d(Jdot qd) + dW qdd_free + W dqdd_free) - dA lambda,
 * dA = dW Y + W dY); with it, the sliding contacts' dYd by gac_sens_slide_tangent (dslip: the slip directions'
 * derivatives, 2 per contact, or NULL: 0).  dqdd may be dqdd_free; dlambda (m) may be NULL. */
static void gac_sens_held_tangent(const gac_sim *s, const double *x, const gac_sens_set *H, const double *qdd_free,
                                  const double *lambda, const double *dq, const double *dqd, const double *dp,
                                  const double *dslip, const double *dqdd_free, double *dlambda, double *dqdd)
{
    const gac_model *md = s->model;
    const int nq = md->nq, m = H->m;
    const double *Yd = H->nslide > 0 ? H->Yd : H->Y;
    double dW[m * nq], dY[m * nq], r[m], dbias[GAC_AT_LEAST_1(md->njrow)], qdd[nq], v[nq];
    int a, i;
    if (m == 0) {
        for (i = 0; i < nq; ++i) dqdd[i] = dqdd_free[i];
        return;
    }
    gac_sens_set_tangent(s, x, H, dq, dp, dW, dY);
    if (H->nslide > 0) gac_sens_slide_tangent(s, x, H, dq, dqd, dp, dslip, dW, dY);
    md->contact_bias_tangent(x, x + nq, s->p, dq, dqd, dp, dbias);
    for (i = 0; i < nq; ++i) {
        double value = qdd_free[i], dvalue = dqdd_free[i];
        for (a = 0; a < m; ++a) {
            value += Yd[(long)a * nq + i] * lambda[a];
            dvalue += dY[(long)a * nq + i] * lambda[a];
        }
        qdd[i] = value;
        v[i] = dvalue;
    }
    gac_sens_rowless_biases(s, x, H, dq, dqd, dp, r);     /* (the rows without a row of J: their biases' change) */
    for (a = 0; a < m; ++a) {
        const double db = H->brow[a] >= 0 ? H->sgn[a] * dbias[H->brow[a]] : r[a];
        r[a] = -(db + gac_dot(nq, dW + (long)a * nq, qdd) + gac_dot(nq, H->W + (long)a * nq, v));
    }
    gac_sens_set_solve(H, r);
    for (i = 0; i < nq; ++i) {
        for (a = 0; a < m; ++a) v[i] += Yd[(long)a * nq + i] * r[a];
    }
    gac_copy(dqdd, v, nq);
    if (dlambda != 0) gac_copy(dlambda, r, m);
}

/* d(Y c) along (dq, dp) for fixed weights c (m): Y c = I_f^-1 J^T (sum_a c_a f_a), one tangent of each operator
 * (a link pair's or an obstacle's row adds c_a d(J^T n)). */
static void gac_sens_Yc_tangent(const gac_sim *s, const double *q, const gac_sens_set *H, const double *c,
                                const double *dq, const double *dp, double *out)
{
    const gac_model *md = s->model;
    const int nq = md->nq, nr = GAC_AT_LEAST_1(md->njrow);
    double fc[GAC_AT_LEAST_1(md->njrow)], df[GAC_AT_LEAST_1(md->njrow)], Wc[nq], dWc[nq], dw[nq];
    int a, i, rowless = 0;
    for (i = 0; i < nr; ++i) fc[i] = df[i] = 0.0;
    for (i = 0; i < nq; ++i) Wc[i] = 0.0;
    for (a = 0; a < H->m; ++a) {
        for (i = 0; i < nr; ++i) fc[i] += c[a] * H->f[(long)a * nr + i];
        for (i = 0; i < nq; ++i) Wc[i] += c[a] * H->W[(long)a * nq + i];
        rowless |= H->brow[a] < 0;
    }
    md->contact_generalized_force_tangent(q, fc, s->p, dq, df, dp, dWc);
    for (a = 0; a < H->m && rowless; ++a) {
        if (H->brow[a] >= 0) continue;
        gac_sens_rowless_tangent(s, H, a, q, dq, dp, dw);
        for (i = 0; i < nq; ++i) dWc[i] += c[a] * dw[i];
    }
    md->inertia_solve_tangent(q, Wc, s->p, dq, dWc, dp, out);
}

/* The derivative of the velocities' projection onto the held set's constraints W qd = 0 at q, in the mass metric
 * (gac_project's, gac_hold's and the start's): qd_post = qd_pre + Y c, c = A^-1 W (qd_post - qd_pre), along
 * (dq, dqd, dp):
 *     d qd_post = dqd + d(Y c) + Y dc,   A dc = -(dW qd_post + W (dqd + d(Y c)))   (W qd_post = 0 kept). */
static void gac_sens_hold_tangent(const gac_sim *s, const double *q, const gac_sens_set *H, const double *qd_pre,
                                  const double *qd_post, const double *dq, const double *dqd, const double *dp,
                                  double *out)
{
    const gac_model *md = s->model;
    const int nq = md->nq, m = H->m;
    double c[GAC_AT_LEAST_1(m)], r[GAC_AT_LEAST_1(m)], dW[m * nq], change[nq], v[nq];
    int a, i, moved = 0;
    if (m == 0) {
        gac_copy(out, dqd, nq);
        return;
    }
    for (i = 0; i < nq; ++i) {
        change[i] = qd_post[i] - qd_pre[i];
        moved |= change[i] != 0.0;
    }
    for (a = 0; a < m; ++a) c[a] = gac_dot(nq, H->W + (long)a * nq, change);
    gac_ldlt_solve(m, H->LD, c);
    if (moved) gac_sens_Yc_tangent(s, q, H, c, dq, dp, v);
    else for (i = 0; i < nq; ++i) v[i] = 0.0;
    for (i = 0; i < nq; ++i) v[i] += dqd[i];                  /* dqd + d(Y c) */
    gac_sens_set_tangent(s, q, H, dq, dp, dW, 0);
    for (a = 0; a < m; ++a) r[a] = -(gac_dot(nq, dW + (long)a * nq, qd_post) + gac_dot(nq, H->W + (long)a * nq, v));
    gac_ldlt_solve(m, H->LD, r);
    for (i = 0; i < nq; ++i) {
        double value = v[i];
        for (a = 0; a < m; ++a) value += H->Y[(long)a * nq + i] * r[a];
        out[i] = value;
    }
}

/* The set H of the contacts at rest after a change of the velocities at state x: set[0..n-1] (the resting ones),
 * then each candidate c (not among them) within contact_tol of its wall whose normal velocity is ~0 (below 1e-9 of
 * the chain's speed scale times its lever) and whose row is independent of those before (they were held too, then
 * dropped by gac_settle: their velocity is projected all the same).  Returns m, the set in out[0..m-1]. */
static int gac_sens_at_rest(const gac_sim *s, const double *x, int n, const int *set, int ncand, const int *cand,
                            int *out)
{
    const gac_model *md = s->model;
    const int nq = md->nq, nc1 = GAC_AT_LEAST_1(md->ncontact);
    double gaps[nc1], vn[nc1], speed = 0.0;
    int a, k, m = 0;
    for (a = 0; a < n; ++a) out[m++] = set[a];
    gac_contact_gaps(md, x, s->p, gaps);
    gac_normal_velocities(md, x, s->p, vn);
    for (a = 0; a < nq; ++a) {
        if (fabs(x[nq + a]) > speed) speed = fabs(x[nq + a]);
    }
    for (k = 0; k < ncand && m < nq; ++k) {
        const int c = cand[k];
        int member = 0;
        for (a = 0; a < m; ++a) member |= out[a] == c;
        if (member || gaps[c] > s->opt.contact_tol || !(fabs(vn[c]) <= 1e-9 * speed * s->lever + 1e-300)) continue;
        {
            const int nr = GAC_AT_LEAST_1(md->njrow);
            GAC_SENS_SET_ARRAYS(nq, nr);
            gac_sens_set H;
            GAC_SENS_SET_BIND(H);
            out[m] = c;
            if (gac_sens_set_at(s, x, m + 1, out, 0, &H) == 0 && H.ndropped == 0) ++m;
        }
    }
    return m;
}

/* Contacts at rest at the start (gac_rest_at_start, before the sensitivities were attached): the gaps they are held
 * at are their starting ones (dgap_held = d gap along the seed), and their velocities were projected onto W qd = 0
 * from those gac_rest_at_start saved in s->x1 (s->pending: not yet reported; otherwise the state is taken as given,
 * on its constraints); on rough walls the points that stuck there (gac_try_stick) then had their velocities
 * projected onto the held rows with their tangential ones, from qd_mid = qd_pre + Y c, A c = -W qd_pre (the first
 * projection, formed again here).  Those that slide are followed in flight, with the slip directions the stick test
 * gave them (gac_sens_reslip). */
static void gac_sens_start_rest(gac_sim *s)
{
    gac_sens *z = s->sens;
    const gac_model *md = s->model;
    const int nq = md->nq, nx = md->nx, nr = GAC_AT_LEAST_1(md->njrow), nc1 = GAC_AT_LEAST_1(md->ncontact);
    const double *qd_pre = s->pending ? s->x1 + nq : s->x + nq;
    const int stuck = gac_any_stuck(s->is_stuck, s->nresting, s->resting);
    double dgap[nc1], zero_p[GAC_AT_LEAST_1(md->nparam)], out[nq], qd_mid[nq], c[nq];
    int all[GAC_AT_LEAST_1(md->ncontact)], set[nq], a, i, j, m;
    GAC_SENS_SET_ARRAYS(nq, nr);
    gac_sens_set H;
    GAC_SENS_SET_ARRAYS_OF(H2, nq, nr);
    gac_sens_set H2;                              /* the held rows with the stuck points' tangential ones */
    GAC_SENS_SET_BIND(H);
    GAC_SENS_SET_BIND_OF(H2, H2);
    a = gac_sens_rowless_check(s, s->x, s->nresting, s->resting);   /* a link or obstacle without derivative */
    if (a >= 0) {
        gac_sens_stop(s, GAC_SENS_LINK, s->t, a);
        return;
    }
    for (a = 0; a < md->ncontact; ++a) all[a] = a;
    for (a = 0; a < GAC_AT_LEAST_1(md->nparam); ++a) zero_p[a] = 0.0;
    m = gac_sens_at_rest(s, s->x, s->nresting, s->resting, s->pending ? md->ncontact : 0, all, set);
    if (gac_sens_set_at(s, s->x, m, set, 0, &H) != 0
        || (stuck && gac_sens_set_at(s, s->x, s->nresting, s->resting, s->is_stuck, &H2) != 0)) {
        gac_sens_stop(s, GAC_SENS_SIMULTANEOUS, s->t, s->resting[0]);
        return;
    }
    gac_copy(qd_mid, s->x + nq, nq);
    if (stuck) {                                  /* the velocities after the first projection */
        for (a = 0; a < m; ++a) c[a] = -gac_dot(nq, H.W + (long)a * nq, qd_pre);
        gac_ldlt_solve(m, H.LD, c);
        for (i = 0; i < nq; ++i) {
            qd_mid[i] = qd_pre[i];
            for (a = 0; a < m; ++a) qd_mid[i] += H.Y[(long)a * nq + i] * c[a];
        }
    }
    for (j = 0; j < z->k; ++j) {
        double *S = z->S + (long)j * nx;
        const double *dp = md->nparam > 0 ? z->dp + (long)j * md->nparam : zero_p;
        gac_sens_gaps_tangent(s, s->x, S, dp, s->nresting, s->resting, dgap);
        for (a = 0; a < md->ncontact; ++a) z->dgap_held[(long)j * nc1 + a] = dgap[a];
        gac_sens_hold_tangent(s, s->x, &H, qd_pre, qd_mid, S, S + nq, dp, out);
        gac_copy(S + nq, out, nq);
        if (stuck) {
            gac_sens_hold_tangent(s, s->x, &H2, qd_mid, s->x + nq, S, S + nq, dp, out);
            gac_copy(S + nq, out, nq);
        }
    }
    {                                             /* slip directions the start's stick test gave (none before) */
        double none[2 * nc1];
        for (i = 0; i < 2 * nc1; ++i) none[i] = 0.0;
        gac_sens_reslip(s, none, stuck);
    }
}

/* After an accepted step in constrained flight: the derivative of gac_project's map x_pre -> x_post (both positions
 * and velocities onto the resting set, in the mass metric) applied to S.  Positions, onto the normal rows N alone
 * (a stuck point's tangential position is not held, only its velocity): q_post = q_pre + Y c,
 * c = A^-1 N (q_post - q_pre), the gaps held at gap_held:
 *     dq_post = dq + d(Y c) + Y dc,   A dc = dgap_held - dgap_H(dq + d(Y c), dp);
 * then the velocities at q_post from qd_pre onto every held row, the stuck points' tangential ones too
 * (gac_sens_hold_tangent).  (A contact outside the set that the correction would push deeper, held where it is by
 * gac_project's active set, is not followed.) */
void gac_sens_project(gac_sim *s, const double *x_pre, const double *x_post)
{
    gac_sens *z = s->sens;
    const gac_model *md = s->model;
    const int nq = md->nq, nx = md->nx, nr = GAC_AT_LEAST_1(md->njrow), nc1 = GAC_AT_LEAST_1(md->ncontact);
    const int m = s->nresting;
    double c[GAC_AT_LEAST_1(m)], dc[GAC_AT_LEAST_1(m)], change[nq], dgap[nc1], dq[nq], out[nq];
    double zero_p[GAC_AT_LEAST_1(md->nparam)];
    int a, i, j, moved = 0;
    GAC_SENS_SET_ARRAYS(nq, nr);
    gac_sens_set H;                                          /* the normal rows: the positions */
    if (z == 0 || z->status != GAC_SENS_VALID || m == 0) return;
    GAC_SENS_SET_BIND(H);
    if (gac_sens_set_at(s, x_post, m, s->resting, 0, &H) != 0) {
        gac_sens_stop(s, GAC_SENS_SIMULTANEOUS, s->t, s->resting[0]);
        return;
    }
    for (i = 0; i < GAC_AT_LEAST_1(md->nparam); ++i) zero_p[i] = 0.0;
    for (i = 0; i < nq; ++i) {
        change[i] = x_post[i] - x_pre[i];
        moved |= change[i] != 0.0;
    }
    for (a = 0; a < m; ++a) c[a] = gac_dot(nq, H.W + (long)a * nq, change);
    gac_ldlt_solve(m, H.LD, c);
    for (j = 0; j < z->k; ++j) {
        double *S = z->S + (long)j * nx;
        const double *dp = md->nparam > 0 ? z->dp + (long)j * md->nparam : zero_p;
        if (moved) gac_sens_Yc_tangent(s, x_post, &H, c, S, dp, dq);
        else for (i = 0; i < nq; ++i) dq[i] = 0.0;
        for (i = 0; i < nq; ++i) dq[i] += S[i];
        gac_sens_gaps_tangent(s, x_post, dq, dp, m, s->resting, dgap);
        for (a = 0; a < m; ++a) dc[a] = z->dgap_held[(long)j * nc1 + s->resting[a]] - dgap[s->resting[a]];
        gac_ldlt_solve(m, H.LD, dc);
        for (i = 0; i < nq; ++i) {
            for (a = 0; a < m; ++a) dq[i] += H.Y[(long)a * nq + i] * dc[a];
            S[i] = dq[i];
        }
    }
    if (gac_any_stuck(s->is_stuck, m, s->resting)   /* the velocities: with the stuck points' tangential rows */
        && gac_sens_set_at(s, x_post, m, s->resting, s->is_stuck, &H) != 0) {
        gac_sens_stop(s, GAC_SENS_SIMULTANEOUS, s->t, s->resting[0]);
        return;
    }
    for (j = 0; j < z->k; ++j) {
        double *S = z->S + (long)j * nx;
        const double *dp = md->nparam > 0 ? z->dp + (long)j * md->nparam : zero_p;
        gac_sens_hold_tangent(s, x_post, &H, x_pre + nq, x_post + nq, S, S + nq, dp, out);
        gac_copy(S + nq, out, nq);
    }
    if (!gac_finite(z->S, z->k * nx)) gac_sens_stop(s, GAC_SENS_NONFINITE, s->t, -1);
}

/* S over one step [t, t + h] from the state x at s->t: the method's stages Y_i = x + h sum_l a_il K_l and with them
 * dY_i = S + h sum_l a_il dK_l, dK_i = [dY_i qd ; forward_dynamics_tangent(Y_i, dY_i, dp)] per direction;
 * S += h sum_i b_i dK_i.  (The derivative of the Runge-Kutta step itself: the variational equations integrated by
 * the same formula.)  The stages K_i = f(Y_i) are the step's own (s->f, s->k[1..], as the integrator left them) when
 * `taken` (the step of size h just accepted); otherwise (a part of it, up to an event) K_0 = s->f and the others
 * are computed here.  The directions' tangents go GAC_TANGENT_BLOCK at a time through the model's
 * forward_dynamics_tangent_block (their primal part computed once), the rest one by one.  With resting contacts the
 * stage's constrained dynamics and its tangent (gac_sens_held_forces, gac_sens_held_tangent), sliding friction
 * among them. */
void gac_sens_flight(gac_sim *s, const double *x, double h, int taken)
{
    gac_sens *z = s->sens;
    const gac_model *md = s->model;
    const double *a, *b, *c;
    int lda, stages, i, j, l, n;
    if (z == 0 || z->status != GAC_SENS_VALID || !(h > 0.0)) return;
    for (i = 0; i < s->nresting; ++i) {          /* a slip direction over two axes not followed */
        if (gac_sens_slip_unknown(s, s->resting[i])) {
            gac_sens_stop(s, GAC_SENS_RESTING, s->t, s->resting[i]);
            return;
        }
    }
    i = gac_sens_rowless_check(s, x, s->nresting, s->resting);   /* a link or obstacle without derivative */
    if (i >= 0) {
        gac_sens_stop(s, GAC_SENS_LINK, s->t, i);
        return;
    }
    if (!gac_sens_inputs_known(s)) {
        gac_sens_stop(s, GAC_SENS_CONTROLLER, s->t, -1);
        return;
    }
    {
        const int nq = md->nq, nx = md->nx, k = z->k, nr = GAC_AT_LEAST_1(md->njrow), held = s->nresting > 0;
        const int nc1 = GAC_AT_LEAST_1(md->ncontact), nu1 = GAC_AT_LEAST_1(md->nu);
        double J[2 * nu1 * nq], Ya[nx];                            /* the controller's Jacobian at a stage */
        double *work = z->work, *dK = work + (long)GAC_SENS_STAGES * nx, *Y = dK + (long)GAC_SENS_STAGES * k * nx;
        double dQ[GAC_TANGENT_BLOCK * nq], dQD[GAC_TANGENT_BLOCK * nq], out[GAC_TANGENT_BLOCK * nq];
        double dU[GAC_TANGENT_BLOCK * GAC_AT_LEAST_1(md->nu)];   /* the inputs' directions: 0 (held, or a schedule),
                                                                     or the controller's du_dq dQ + du_dqd dQD */
        double qdd_free[nq], qdd[nq], lambda[3 * nq];               /* the constrained flight at a stage */
        const double *K[GAC_SENS_STAGES];
        int width, jac;
        GAC_SENS_SET_ARRAYS(nq, nr);
        gac_sens_set H;
        GAC_SENS_SET_BIND(H);
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
            jac = gac_sens_jacobian_at(s, s->t + c[i] * h, Y, J, Ya);
            if (held) {                              /* the resting contacts held (the stuck points along every
                                                        axis): their forces at the stage */
                if (gac_sens_set_at(s, Y, s->nresting, s->resting, s->is_stuck, &H) != 0
                    || gac_sens_set_slide(s, Y, s->is_stuck, s->slip, &H) != 0) {   /* (the sliding points' friction) */
                    gac_sens_stop(s, GAC_SENS_SIMULTANEOUS, s->t, s->resting[0]);
                    return;
                }
                gac_sens_held_forces(s, Y, u, &H, qdd_free, lambda, qdd, 0);
                if (i > 0 && !taken) {
                    gac_copy(work + (long)i * nx, Y + nq, nq);
                    gac_copy(work + (long)i * nx + nq, qdd, nq);
                }
            } else if (i > 0 && !taken) {
                md->rhs(s->t + c[i] * h, Y, u, s->p, work + (long)i * nx);
            }
            for (j = 0; j < k; j += width) {         /* GAC_TANGENT_BLOCK directions a call, then one by one */
                double *dKi;
                int m;
                width = !held && md->forward_dynamics_tangent_block != 0 && j + GAC_TANGENT_BLOCK <= k
                        ? GAC_TANGENT_BLOCK : 1;
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
                    if (jac) gac_sens_du(s, J, Y, Ya, dQ + m * nq, dQD + m * nq, dU + m * md->nu);
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
                    if (held)                        /* the constrained dynamics' tangent */
                        gac_sens_held_tangent(s, Y, &H, qdd_free, lambda, dQ, dQD, z->dp + (long)j * md->nparam,
                                              z->dslip + 2L * j * nc1, dKi + nq, 0, dKi + nq);
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

/* S at sample time t of the step that starts at s->t (s->t <= t <= its end) into out (k x nx): one step of the run's
 * formula from the step's start to t, as at an event, S itself kept; NaN once the sensitivities ended. */
void gac_sens_sample(gac_sim *s, double t, double *out)
{
    gac_sens *z = s->sens;
    const long size = (long)z->k * s->model_a->nx;
    if (z->status == GAC_SENS_VALID && t > s->t) {
        gac_copy(z->S_keep, z->S, size);
        gac_sens_flight(s, s->x, t - s->t, 0);
        gac_copy(out, z->S, size);
        if (z->status == GAC_SENS_VALID) gac_copy(z->S, z->S_keep, size);
        return;
    }
    gac_copy(out, z->S, size);                           /* (NaN where they ended) */
}

/* The impact map of the active contacts a = 1..m (those that took an impulse) by Newton's law, Eq. 47, with the
 * set fixed: W (m x nq) their signed normal rows w_a = J^T (sign e_row_a) (a link pair's or an obstacle's J^T n:
 * gac_sens_row), Y_a = I_f^-1 w_a, A = W Y (m x m), v = W qd, A F = -(1 + E) v, qd+ = qd + Y F.  Its differential
 * along (dq, dqd, dp) with de_a = dp[e_index_a]:
 *     dw_a = d(J^T f_a)[dq, dp] (or d(J^T n): gac_sens_row_tangent),  dY_a = d(I_f^-1 w_a)[dq, dw_a, dp],
 *     dA_ab = dw_a . Y_b + w_a . dY_b,
 *     dv_a = dw_a . qd + w_a . dqd,  A dF = -de v - (1 + E) dv - dA F,  d qd+ = dqd + dY F + Y dF.
 * (One contact: dF = dL of y L, L = -(1 + e) v / (w . y).)  A is kept factored (gac_ldlt) in LD. */
typedef struct {
    int m;                       /* active rows */
    const int *active;           /* their contacts' model indices */
    const int *landing;          /* 1: struck with e = 0 (a landing), its wall's e not read */
    const double *f, *W, *Y, *LD, *F, *v, *e;   /* f: m x nr unit signed rows; the rest as above */
    /* sliding contacts (the frictional law, its impulse on the cone): row a of such a contact's tangent has
       normal[a] >= 0, the row of its normal; u[a] the slide's direction's component along it (L_T = -c_f L_N u),
       xi_T[a] the tangential velocity xi_T (|xi_T| of the contact in xi_T_norm[a]); normal[a] = -1 elsewhere.
       With any, the system is not symmetric and LD holds A itself (m x m) for gac_lu_solve. */
    int nslide;
    const int *normal;
    const double *u, *xi_T_norm, *cf;
    const int *cf_index;
    /* a link pair's or an obstacle's tangential rows (the frictional law along its contact frame): frame[a] = k > 0
       for row a = J^T t_k (gac_contact_frame_tangent's row k, f left 0); 0 elsewhere; NULL: none */
    const int *frame;
} gac_sens_law;

/* Newton's law (no slides) on dependent rows (a link lying flat with both ends stuck holds one tangential row twice):
 * the rows dependent on those before drop out as in the held set (gac_ldlt_drop: their impulses 0, the others the
 * reduced law's), provided every row's condition holds with those impulses, |(A F)_a + (1 + e_a) v_a| <= tol (the
 * same velocities after, the impulse split another way).  The differential is then the reduced law's: the dependency
 * lasts along a perturbation that keeps the impact's contacts at their walls (it comes from their geometry).  LD
 * holds A on entry and the dropped factor on a return of 1 (F the impulses); 0 where the conditions do not hold. */
static int gac_sens_law_reduce(const gac_sens_law *L, double *LD, double *F, double tol)
{
    const int m = L->m;
    double A[m * m];
    int a, b;
    gac_copy(A, LD, (long)m * m);
    if (gac_ldlt_drop(m, LD, 1e-12) <= 0) return 0;
    for (a = 0; a < m; ++a) F[a] = -(1.0 + L->e[a]) * L->v[a];
    gac_ldlt_solve(m, LD, F);
    for (a = 0; a < m; ++a) {
        double condition = (1.0 + L->e[a]) * L->v[a];
        for (b = 0; b < m; ++b) condition += A[a * m + b] * F[b];
        if (!(fabs(condition) <= tol)) return 0;
    }
    return 1;
}

/* The matrix M (m x m) of the law's differential with slides (gac_impact_differential, L->nslide > 0): A (L->LD)
 * with each sliding contact's tangential row a replaced by its cone condition R_a = L_T,a + c_f L_N u_a(xi_T) = 0
 * differentiated,
 *     dL_T,a + c_f u_a dL_N + c_f L_N sum_t Du_at (A dL + c)_t = -dc_f L_N u_a,
 *     Du = (I - u u^T) / |xi_T| over the contact's tangential rows t (0 with one tangential row),
 * whose right-hand side (the dc_f and c terms) depends on the direction.  Where two tangential rows are the same
 * (a rod lying flat, sliding at both ends) A is singular but M need not be: the cone fixes each L_T. */
static void gac_sens_slide_matrix(const gac_sens_law *L, double *M)
{
    const int m = L->m;
    int a, b, t;
    for (a = 0; a < m * m; ++a) M[a] = L->LD[a];
    for (a = 0; a < m; ++a) {
        const int nrm = L->normal[a];
        if (nrm < 0) continue;
        for (b = 0; b < m; ++b) M[a * m + b] = (b == a ? 1.0 : 0.0) + (b == nrm ? L->cf[a] * L->u[a] : 0.0);
        for (t = 0; t < m; ++t) {
            double Du;
            if (L->normal[t] != nrm) continue;
            Du = L->cf[a] * L->F[nrm] * ((t == a ? 1.0 : 0.0) - L->u[a] * L->u[t]) / L->xi_T_norm[a];
            if (Du == 0.0) continue;
            for (b = 0; b < m; ++b) M[a * m + b] += Du * L->LD[t * m + b];
        }
    }
}

/* 1 if the law L has a unique differential: without slides A = W Y positive definite (LD, L's own LD holding A, is
 * then factored in place by gac_ldlt for gac_impact_differential); with them M (gac_sens_slide_matrix) regular, LD
 * keeping A. */
static int gac_sens_law_regular(const gac_sens_law *L, double *LD)
{
    const int m = L->m;
    double work[m * m], rhs[m];
    int a;
    if (L->nslide == 0) {
        gac_copy(work, LD, (long)m * m);
        if (gac_ldlt(m, work, 1e-12) != 0) return 0;
        gac_copy(LD, work, (long)m * m);
        return 1;
    }
    gac_sens_slide_matrix(L, work);
    for (a = 0; a < m; ++a) rhs[a] = 1.0;
    return gac_lu_solve(m, work, rhs, 1e-14) == 0;
}

static void gac_impact_differential(const gac_sim *s, const gac_sens_law *L, const double *q, const double *qd,
                                    const double *dq, const double *dqd, const double *dp, double *dqd_plus,
                                    double *dF_out)
{
    const gac_model *md = s->model;
    const int nq = md->nq, nr = GAC_AT_LEAST_1(md->njrow), m = L->m;
    double dW[m * nq], dY[m * nq], dF[m];
    int a, b, i;
    for (a = 0; a < m; ++a) {
        if (L->frame != 0 && L->frame[a] > 0) {         /* d(J^T t_k): the frame's turning and the points' motion */
            double axes[9], g[3 * nq], dg[3 * nq];
            if (gac_contact_frame_tangent(md, q, s->p, L->active[a], dq, dp, axes, g, dg) != GAC_OK) {
                for (i = 0; i < nq; ++i) dqd_plus[i] = NAN;
                for (b = 0; b < m && dF_out != 0; ++b) dF_out[b] = NAN;
                return;
            }
            gac_copy(dW + (long)a * nq, dg + (long)L->frame[a] * nq, nq);
        } else if (gac_sens_row_tangent(s, L->active[a], L->f + (long)a * nr, q, dq, dp, dW + (long)a * nq) != 0) {
            for (i = 0; i < nq; ++i) dqd_plus[i] = NAN;  /* (a rowless row without a derivative: checked before) */
            for (b = 0; b < m && dF_out != 0; ++b) dF_out[b] = NAN;
            return;
        }
        md->inertia_solve_tangent(q, L->W + (long)a * nq, s->p, dq, dW + (long)a * nq, dp, dY + (long)a * nq);
    }
    for (a = 0; a < m; ++a) {
        const gac_contact *ct = md->contacts + L->active[a];
        const double de = ct->e_index >= 0 && !L->landing[a] ? dp[ct->e_index] : 0.0;
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
    if (L->nslide == 0) {
        gac_ldlt_solve(m, L->LD, dF);
    } else {                                             /* with slides: M dF = rhs, M not symmetric */
        double M[m * m], c[m];
        for (a = 0; a < m; ++a) c[a] = -dF[a];           /* d xi_a = (A dF)_a + c_a; A dF = -c on the other rows */
        gac_sens_slide_matrix(L, M);
        for (a = 0; a < m; ++a) {                        /* the slide rows' right-hand sides (gac_sens_slide_matrix) */
            const int nrm = L->normal[a];
            int t;
            if (nrm < 0) continue;
            dF[a] = -(L->cf_index[a] >= 0 ? dp[L->cf_index[a]] : 0.0) * L->F[nrm] * L->u[a];
            for (t = 0; t < m; ++t) {
                if (L->normal[t] != nrm) continue;
                dF[a] -= L->cf[a] * L->F[nrm] * ((t == a ? 1.0 : 0.0) - L->u[a] * L->u[t]) / L->xi_T_norm[a] * c[t];
            }
        }
        if (gac_lu_solve(m, M, dF, 1e-14) != 0) {
            for (i = 0; i < nq; ++i) dqd_plus[i] = NAN;
            for (a = 0; a < m && dF_out != 0; ++a) dF_out[a] = NAN;
            return;
        }
    }
    for (i = 0; i < nq; ++i) {
        double value = dqd[i];
        for (a = 0; a < m; ++a) value += dY[(long)a * nq + i] * L->F[a] + L->Y[(long)a * nq + i] * dF[a];
        dqd_plus[i] = value;
    }
    if (dF_out != 0) gac_copy(dF_out, dF, m);
}

/* The boundary contacts of an impact (gac_sens_impact): contacts that took an impulse ~0 and leave at the law's bound
 * xi_b = w_b . qd+ + e_b w_b . qd- ~ 0 (approaching before), appended to the law's m active rows as rows m..m+nb-1
 * of its arrays (F = 0 there).  A perturbation along a direction may add b to the pushing set or leave it out; the
 * law's complementarity (xi >= 0, F >= 0, xi F = 0) differentiated at such a b says which:
 *     with b pushing:  dxi_b = 0 and dF_b >= 0;        without:  dF_b = 0 and dxi_b >= 0,
 * dxi_b = dw_b . (qd+ + e_b qd-) + w_b . (dqd+ + e_b dqd-) + de_b v_b.  Without b the others' dF solve the active
 * rows' system; with b, dF_b = -dxi_b(without) / s_b, s_b = A_bb - A_bS A_SS^-1 A_Sb > 0 (A positive definite), so
 * for a direction with dxi_b(without) != 0 exactly one of the two is consistent, and the opposite direction takes
 * the other: the derivative is one-sided.  Of the 2^nb sets the one whose conditions hold is taken -- the largest
 * least margin (dF_b in velocity units, A_bb dF_b), robust to round-off where a direction keeps dxi_b = 0 and both
 * sets give the same derivative.  dqd_plus: the law's velocities' derivative (before any hold) in that set. */
#define GAC_SENS_MAX_BOUNDARY 3
static void gac_sens_boundary_column(const gac_sim *s, const gac_sens_law *base, int nb, const double *qd_law,
                                     const double *q, const double *qdm, const double *dx, const double *dp,
                                     double *dqd_plus)
{
    const gac_model *md = s->model;
    const int nq = md->nq, nr = GAC_AT_LEAST_1(md->njrow), m0 = base->m, mt = m0 + nb;
    double f2[mt * nr], W2[mt * nq], Y2[mt * nq], LD2[mt * mt], F2[mt], v2[mt], e2[mt], dF[mt], out[nq], dw[nq];
    double best = -INFINITY;
    int active2[mt], landing2[mt], normal2[mt], row[mt], mask, a, b, i;
    gac_sens_law L = *base;
    for (mask = 0; mask < (1 << nb); ++mask) {
        double margin = INFINITY;
        int m = 0;
        for (a = 0; a < mt; ++a) {                           /* the set: the active rows, then its boundary rows */
            if (a >= m0 && !(mask & (1 << (a - m0)))) continue;
            row[m++] = a;
        }
        for (a = 0; a < m; ++a) {
            const int r = row[a];
            gac_copy(f2 + (long)a * nr, base->f + (long)r * nr, nr);
            gac_copy(W2 + (long)a * nq, base->W + (long)r * nq, nq);
            gac_copy(Y2 + (long)a * nq, base->Y + (long)r * nq, nq);
            F2[a] = base->F[r], v2[a] = base->v[r], e2[a] = base->e[r];
            active2[a] = base->active[r], landing2[a] = base->landing[r], normal2[a] = -1;
            for (b = 0; b <= a; ++b)
                LD2[a * m + b] = LD2[b * m + a] = gac_dot(nq, W2 + (long)a * nq, Y2 + (long)b * nq);
        }
        if (gac_ldlt(m, LD2, 1e-12) != 0) continue;          /* dependent rows: not this set */
        L.m = m, L.active = active2, L.landing = landing2, L.f = f2, L.W = W2, L.Y = Y2, L.LD = LD2;
        L.F = F2, L.v = v2, L.e = e2, L.normal = normal2;
        gac_impact_differential(s, &L, q, qdm, dx, dx + nq, dp, out, dF);
        for (a = m0; a < mt; ++a) {                          /* the boundary rows' conditions */
            const double *wb = base->W + (long)a * nq, eb = base->e[a];
            const gac_contact *ct = md->contacts + base->active[a];
            double cond;
            if (mask & (1 << (a - m0))) {                    /* pushing: dF_b >= 0 (as a velocity, A_bb dF_b) */
                for (b = 0; row[b] != a; ++b) continue;
                cond = dF[b] * gac_dot(nq, wb, base->Y + (long)a * nq);
            } else {                                         /* out: dxi_b >= 0 */
                if (gac_sens_row_tangent(s, base->active[a], base->f + (long)a * nr, q, dx, dp, dw) != 0)
                    for (i = 0; i < nq; ++i) dw[i] = NAN;
                cond = (ct->e_index >= 0 ? dp[ct->e_index] : 0.0) * base->v[a];
                for (i = 0; i < nq; ++i)
                    cond += dw[i] * (qd_law[i] + eb * qdm[i]) + wb[i] * (out[i] + eb * dx[nq + i]);
            }
            if (cond < margin) margin = cond;
        }
        if (mask == 0 || margin > best) {                   /* (mask 0, the nominal set, always factors) */
            best = margin;
            gac_copy(dqd_plus, out, nq);
        }
    }
}

/* The field f = [qd, qdd] at state x with set[0..m-1] held (free flight for m = 0), those stuck (stuck: per contact,
 * or NULL: none) along every axis, the others on rough walls sliding with the slip directions slip (2 per contact).
 * Returns 0, or 1 where the held rows admit no forces to differentiate.  lambda (H->m rows) and lambda_ref as
 * gac_sens_held_forces, the set's arrays in H. */
static int gac_sens_field_slip(gac_sim *s, double t, const double *x, int m, const int *set, const int *stuck,
                               const double *slip, gac_sens_set *H, double *qdd_free, double *lambda, double *f,
                               double *lambda_ref)
{
    const int nq = s->model->nq;
    if (gac_sens_set_at(s, x, m, set, stuck, H) != 0 || gac_sens_set_slide(s, x, stuck, slip, H) != 0) return 1;
    gac_copy(f, x + nq, nq);
    gac_sens_held_forces(s, x, gac_input(s, t, x), H, qdd_free, lambda, f + nq, lambda_ref);
    return 0;
}

/* gac_sens_field_slip with the loop's slip directions (s->slip). */
static int gac_sens_field(gac_sim *s, double t, const double *x, int m, const int *set, const int *stuck,
                          gac_sens_set *H, double *qdd_free, double *lambda, double *f, double *lambda_ref)
{
    return gac_sens_field_slip(s, t, x, m, set, stuck, s->slip, H, qdd_free, lambda, f, lambda_ref);
}

/* The resting set before the event of record r: the set now without the contacts that landed, with those released. */
static int gac_sens_set_before(const gac_sim *s, const gac_impact_record *r, int *set)
{
    int a, b, n = 0;
    for (a = 0; a < s->nresting; ++a) {
        int landed = 0;
        for (b = 0; b < r->nlanded; ++b) landed |= r->landed[b] == s->resting[a];
        if (!landed) set[n++] = s->resting[a];
    }
    for (b = 0; b < r->nreleased; ++b) set[n++] = r->released[b];
    return n;
}

/* ---- an impact the law solved in several rounds ---- */

#define GAC_SENS_TRACE_ROOM 24576L   /* bytes the rounds' trace may take (on the stack): more ends the sensitivities */

/* The rounds' trace for R rounds of n contacts (gac_rounds_trace): k (R ints), idx and hit (R n ints each), F (R n
 * doubles), and under the frictional law (rough) dim (R n ints) and L (3 R n doubles).  257 rounds of two contacts
 * take 9,252 bytes frictionless, 23,644 rough. */
#define GAC_SENS_TRACE_INTS(R, n, rough) ((long)(R) * (1L + ((rough) ? 3L : 2L) * (n)))
#define GAC_SENS_TRACE_DOUBLES(R, n, rough) ((long)(R) * ((rough) ? 4L : 1L) * (n))
#define GAC_SENS_TRACE_BYTES(R, n, rough) \
    (GAC_SENS_TRACE_INTS(R, n, rough) * (long)sizeof(int) + GAC_SENS_TRACE_DOUBLES(R, n, rough) * (long)sizeof(double))

/* The rounds of an impact as a chain of impact laws (qd+ = R_K(...R_1(qd-)) at fixed q), round j the law on its
 * active set S_j (the contacts that took an impulse in it) with e_a for a contact struck in it (approaching) and 0 for
 * one at rest in it or in the plastic round, at the velocities qd_j before it.  Of the rounds only their trace is kept
 * (each round's problem and impulses); a walk through them (gac_sens_round) rebuilds round j's law (gac_sens_law, up
 * to 3 n rows: n, or the frictional law's tangential rows too) from the trace and qd_j in the caller's arrays for one
 * round's law, and gives qd_j+1.  The stack the rounds take: the trace (at most GAC_SENS_TRACE_ROOM bytes), one
 * round's law and the record's n contacts' rows, whatever the number of rounds. */
typedef struct {
    int n, nround;                                     /* the record's contacts; rounds with an impulse walked */
    gac_rounds_trace trace;
    double *fall, *Wall, *e_list;                      /* each contact's row f (n nr) and w (n nq), its e (n) */
    int *zero_start, *zero, *exempt;                   /* n each: held at 0 before the impact, before round j; exempt
                                                          from the bounds (resting before or held after) */
    double thr, largest;                               /* ~0 of a normal velocity; the largest impulse */
    double *qd, *qd_next;                              /* nq each: the velocities before round j, after it */
    gac_sens_law law;                                  /* round j's, in the arrays below */
    int *active, *landing, *normal, *cf_index, *frame; /* 3 n rows each (frame: gac_sens_law.frame) */
    double *f, *W, *Y, *LD, *F, *v, *e, *u, *xi_norm, *cf;   /* 3 n rows of nr, nq, nq, 3 n, 1... */
} gac_sens_rounds;

/* The walk's start: the velocities before the impact, the contacts held at 0 before it. */
static void gac_sens_rounds_start(const gac_sim *s, gac_sens_rounds *C)
{
    int a;
    gac_copy(C->qd, s->xs + s->model->nq, s->model->nq);
    for (a = 0; a < C->n; ++a) C->zero[a] = C->zero_start[a];
    C->nround = 0;
}

/* The law of record r re-run on the record's contacts with each round recorded (gac_impact_rounds_traced, or
 * gac_impact_rounds_friction_traced for the frictional law), each contact's e e_list; 1 if it gives the record's
 * rounds, plastic round, law and impulses (normal and tangential, to 1e-6 of the largest). */
static int gac_sens_rounds_rerun(gac_sim *s, const gac_impact_record *r, int first, const double *e_list,
                                 double largest, gac_rounds_trace *trace)
{
    const gac_model *md = s->model;
    const int nq = md->nq, n = r->ncontact;
    double F[n], Ft[2 * n], qd_plus[nq], residual, parts;
    int rounds = 0, plastic = 0, law = GAC_IMPACT_LAW_FRICTIONLESS, ok, a;
    trace->nround = 0;
    if (r->law == GAC_IMPACT_LAW_FRICTIONLESS) {
        for (a = 0; a < 2 * n; ++a) Ft[a] = 0.0;
        ok = gac_impact_rounds_traced(md, s->xs, s->xs + nq, s->p, n, r->contact, e_list, first, qd_plus, F, s->work,
                                      &rounds, &plastic, trace) == GAC_OK;
    } else {
        ok = gac_impact_rounds_friction_traced(md, s->xs, s->xs + nq, s->p, n, r->contact, e_list, first,
                                               s->opt.impact_law, qd_plus, F, Ft, s->work, &rounds, &plastic, &law,
                                               &residual, &parts, trace) == GAC_OK;
    }
    ok = ok && law == r->law && rounds == r->rounds && plastic == r->plastic && trace->nround == rounds
         && rounds <= trace->cap;
    for (a = 0; ok && a < n; ++a) {
        ok = fabs(F[a] - r->impulse[a]) <= 1e-6 * largest && fabs(Ft[2 * a] - r->impulse_t[2 * a]) <= 1e-6 * largest
             && fabs(Ft[2 * a + 1] - r->impulse_t[2 * a + 1]) <= 1e-6 * largest;
    }
    return ok;
}

/* Round j of the walk: its law into C->law (m = 0: it took no impulse) at the velocities C->qd before it, the
 * velocities after it into C->qd_next, and its set's strictness.  Its active rows W (gac_sens_row; a rough contact's
 * tangential rows under the frictional law after its normal one, stuck -- xi_T = gamma+_T + e gamma-_T = 0 -- or
 * sliding on the cone, as for one round), Y = I_f^-1 W, A = W Y (factored without slides), its impulses (the trace's)
 * and velocities.  A contact at its bound: GAC_SENS_BOUNDARY, its index in *contact (gac_sens_rounds_at). */
static int gac_sens_round(const gac_sim *s, const gac_impact_record *r, gac_sens_rounds *C, int j, int *contact)
{
    const gac_model *md = s->model;
    const int nq = md->nq, nr = GAC_AT_LEAST_1(md->njrow), n = C->n;
    const double *q = s->xs, *qd = C->qd, *Wall = C->Wall, thr = C->thr, largest = C->largest;
    const gac_rounds_trace *T = &C->trace;
    double *qd_next = C->qd_next, vb[n], va[n];
    gac_sens_law *L = &C->law;
    int m = 0, nslide = 0, zero_next[n], a, b, i, t;
    L->m = 0;
    for (a = 0; a < n; ++a) {
        vb[a] = gac_dot(nq, Wall + (long)a * nq, qd);
        zero_next[a] = 0;
        if (!C->zero[a] && !(fabs(vb[a]) > thr)) {           /* meets the round at rest, not held there */
            *contact = r->contact[a];
            return GAC_SENS_BOUNDARY;
        }
    }
    for (b = 0; b < T->k[j]; ++b) {                          /* the active rows: those that took an impulse */
        const int pos = T->idx[j * n + b], hit = T->hit[j * n + b], c = r->contact[pos];
        const double LN = T->F[j * n + b];
        const gac_contact *ct = md->contacts + c;
        const int row_n = m;
        if (!(LN > 1e-9 * largest)) continue;
        C->active[row_n] = c;
        C->e[row_n] = hit ? C->e_list[pos] : 0.0;
        C->landing[row_n] = !hit || C->e_list[pos] != gac_restitution(md, s->p, c);
        C->normal[row_n] = -1;
        C->frame[row_n] = 0;
        C->F[row_n] = LN;
        C->v[row_n] = vb[pos];
        gac_copy(C->f + (long)row_n * nr, C->fall + (long)pos * nr, nr);
        gac_copy(C->W + (long)row_n * nq, Wall + (long)pos * nq, nq);
        zero_next[pos] = C->e[row_n] == 0.0;
        ++m;
        if (r->law != GAC_IMPACT_LAW_FRICTIONLESS && T->dim[j * n + b] > 1) {   /* its tangential rows: a wall's
                                                                                   axes, a link pair's or an
                                                                                   obstacle's frame tangents that
                                                                                   some motion takes (the law's) */
            const double *Lb = T->L + 3L * (j * n + b);
            const double cf = gac_contact_friction(md, s->p, c);
            const double tangential = hypot(Lb[1], T->dim[j * n + b] > 2 ? Lb[2] : 0.0);
            const int slides = !(tangential < (1.0 - 1e-6) * cf * LN), rowless = gac_rowless(md, c);
            int row = 1;
            nslide += slides;
            for (t = 0; t < 2; ++t) {
                const int rt = m;
                double *ft = C->f + (long)rt * nr;
                if (rowless ? !gac_sens_frame_moves(s, q, c, 1 + t) : ct->trow[t] < 0) continue;
                if (row >= T->dim[j * n + b]) break;
                for (i = 0; i < nr; ++i) ft[i] = 0.0;
                if (rowless) {
                    (void)gac_sens_frame_row(s, q, c, 1 + t, C->W + (long)rt * nq);
                    C->frame[rt] = 1 + t;
                } else {
                    ft[ct->trow[t]] = 1.0;
                    md->contact_generalized_force(q, ft, s->p, C->W + (long)rt * nq);
                    C->frame[rt] = 0;
                }
                C->active[rt] = c, C->e[rt] = C->e[row_n], C->landing[rt] = C->landing[row_n];
                C->F[rt] = Lb[row++];
                C->v[rt] = gac_dot(nq, C->W + (long)rt * nq, qd);
                C->normal[rt] = slides ? row_n : -1;
                C->u[rt] = slides ? -C->F[rt] / (cf * LN) : 0.0;
                C->cf[rt] = cf, C->cf_index[rt] = ct->friction_index;
                ++m;
            }
        }
    }
    for (a = 0; a < m; ++a) md->inertia_solve(q, C->W + (long)a * nq, s->p, C->Y + (long)a * nq);
    for (i = 0; i < nq; ++i) {                               /* the velocities after the round */
        double value = qd[i];
        for (a = 0; a < m; ++a) value += C->Y[(long)a * nq + i] * C->F[a];
        qd_next[i] = value;
    }
    for (a = 0; a < m; ++a) {                                /* a slide's xi_T = gamma+_T + e gamma-_T, off 0 */
        double xi2 = 0.0;
        int last;
        if (C->normal[a] < 0) continue;
        for (last = a; last < m && C->normal[last] == C->normal[a]; ++last) {
            const double xi = gac_dot(nq, C->W + (long)last * nq, qd_next) + C->e[last] * C->v[last];
            xi2 += xi * xi;
        }
        if (!(sqrt(xi2) > thr)) {                            /* on the cone with xi_T ~ 0: stick or slide */
            *contact = C->active[a];
            return GAC_SENS_BOUNDARY;
        }
        for (b = a; b < last; ++b) C->xi_norm[b] = sqrt(xi2);
        a = last - 1;
    }
    for (a = 0; a < n; ++a) va[a] = gac_dot(nq, Wall + (long)a * nq, qd_next);
    for (b = 0; b < T->k[j]; ++b) {                          /* the others of its problem: clear of their bound */
        const int pos = T->idx[j * n + b];
        const double bound = va[pos] + (T->hit[j * n + b] ? C->e_list[pos] * vb[pos] : 0.0);
        if (T->F[j * n + b] > 1e-9 * largest || bound > thr) continue;
        if (!C->exempt[pos]) {
            *contact = r->contact[pos];
            return GAC_SENS_BOUNDARY;
        }
        zero_next[pos] = C->zero[pos];
    }
    for (a = 0; a < n; ++a) C->zero[a] = zero_next[a];
    if (m == 0) return GAC_SENS_VALID;                      /* (no impulse: the round leaves qd as it is) */
    for (a = 0; a < m; ++a) {
        for (b = 0; b <= a; ++b)
            C->LD[a * m + b] = C->LD[b * m + a] = gac_dot(nq, C->W + (long)a * nq, C->Y + (long)b * nq);
    }
    L->m = m, L->active = C->active, L->landing = C->landing, L->f = C->f, L->W = C->W, L->Y = C->Y, L->LD = C->LD;
    L->F = C->F, L->v = C->v, L->e = C->e, L->nslide = nslide, L->normal = C->normal, L->u = C->u;
    L->xi_T_norm = C->xi_norm, L->cf = C->cf, L->cf_index = C->cf_index, L->frame = C->frame;
    if (!gac_sens_law_regular(L, C->LD)) {                  /* dependent rows (with slides LD keeps A) */
        L->m = 0;
        return GAC_SENS_SIMULTANEOUS;
    }
    C->nround++;
    return GAC_SENS_VALID;
}

/* The rounds of the impact of record r (located by c_event; before_set[0..nbefore-1] resting before it) walked once
 * (gac_sens_round), C->qd then the law's velocities: the law re-run on the record's contacts (those that took an
 * impulse or approached; the others took none in any round, so each round's solution is the same without them;
 * gac_sens_rounds_rerun) into C's trace, each contact's e its wall's, or, failing that, 0 for those that landed
 * (struck with e = 0); a re-run that does not give the record's rounds and impulses: GAC_SENS_SIMULTANEOUS.  A round
 * is differentiable where its set is strict; a contact at its bound ends the sensitivities (GAC_SENS_BOUNDARY, its
 * index in *contact): one that meets a round with normal velocity ~0 (below 1e-9 of the chain's speed scale times its
 * lever) not held at 0 by the rounds before (resting before the impact, or struck with e = 0 in the round before),
 * one in a round's problem that took impulse ~0 (1e-9 of the largest) and leaves at the round's bound (v+ + e v- ~
 * 0), one sliding on the cone with xi_T ~ 0, or one left at ~0 by the last round, unless resting before or held after
 * the impact (the hold's derivative follows those, as for one round).  A link pair or an obstacle whose closest
 * points have no derivative: GAC_SENS_LINK.  Returns GAC_SENS_VALID or the verdict. */
static int gac_sens_rounds_at(gac_sim *s, const gac_impact_record *r, int c_event, int nbefore,
                              const int *before_set, gac_sens_rounds *C, int *contact)
{
    const gac_model *md = s->model;
    const int nq = md->nq, nr = GAC_AT_LEAST_1(md->njrow), n = r->ncontact;
    const double *q = s->xs, *qdm = s->xs + nq;
    double speed = 0.0, largest = 0.0;
    int first = -1, found = 0, attempt, a, b, i, j;
    *contact = c_event;
    for (i = 0; i < nq; ++i) {
        if (fabs(qdm[i]) > speed) speed = fabs(qdm[i]);
    }
    C->thr = 1e-9 * speed * s->lever;
    for (a = 0; a < n; ++a) {
        const int c = r->contact[a];
        int held_after = 0;
        if (r->impulse[a] > largest) largest = r->impulse[a];
        if (c == c_event) first = a;
        C->zero_start[a] = 0;
        for (b = 0; b < nbefore; ++b) C->zero_start[a] |= before_set[b] == c;
        for (b = 0; b < s->nresting; ++b) held_after |= s->resting[b] == c;
        C->exempt[a] = C->zero_start[a] || held_after;
        gac_sens_row(s, c, q, C->fall + (long)a * nr, C->Wall + (long)a * nq);
        if (gac_rowless(md, c)) {                            /* its row's derivative exists here (or none) */
            double zero_q[nq], zero_p[GAC_AT_LEAST_1(md->nparam)], dw[nq];
            for (i = 0; i < nq; ++i) zero_q[i] = 0.0;
            for (i = 0; i < GAC_AT_LEAST_1(md->nparam); ++i) zero_p[i] = 0.0;
            double axes[9], g[3 * nq], dg[3 * nq];
            if (gac_sens_row_tangent(s, c, C->fall + (long)a * nr, q, zero_q, zero_p, dw) != 0
                || (r->law != GAC_IMPACT_LAW_FRICTIONLESS && gac_contact_friction(md, s->p, c) > 0.0
                    && gac_contact_frame_tangent(md, q, s->p, c, zero_q, zero_p, axes, g, dg) != GAC_OK)) {
                *contact = c;
                return GAC_SENS_LINK;
            }
        }
    }
    C->largest = largest;
    for (attempt = 0; attempt < 2 && !found; ++attempt) {   /* each contact's e: its wall's, or 0 where it landed */
        int changed = 0;
        for (a = 0; a < n; ++a) {
            int landed = 0;
            C->e_list[a] = gac_restitution(md, s->p, r->contact[a]);
            for (b = 0; b < r->nlanded && attempt == 1 && !C->zero_start[a]; ++b)
                landed |= r->landed[b] == r->contact[a];
            if (landed && C->e_list[a] != 0.0) {
                C->e_list[a] = 0.0;
                changed = 1;
            }
        }
        if (attempt == 0 || changed) found = gac_sens_rounds_rerun(s, r, first, C->e_list, largest, &C->trace);
    }
    if (!found) return GAC_SENS_SIMULTANEOUS;             /* not the record's rounds */
    gac_sens_rounds_start(s, C);
    for (j = 0; j < r->rounds; ++j) {                        /* round j: its law, its set's strictness */
        const int verdict = gac_sens_round(s, r, C, j, contact);
        if (verdict != GAC_SENS_VALID) return verdict;
        gac_copy(C->qd, C->qd_next, nq);
    }
    for (a = 0; a < n; ++a) {                                /* after the last round: none left at ~0 unheld */
        if (!C->zero[a] && !C->exempt[a] && !(gac_dot(nq, C->Wall + (long)a * nq, C->qd) > C->thr)) {
            *contact = r->contact[a];
            return GAC_SENS_BOUNDARY;
        }
    }
    return C->nround > 0 ? GAC_SENS_VALID : GAC_SENS_SIMULTANEOUS;
}

/* The rounds' differentials chained, walking the rounds again (each rebuilt as gac_sens_rounds_at found it): round
 * j's (gac_impact_differential on its law at qd_j) applied to every column's d qd in turn before round j + 1 is
 * built.  Each column S_j holds (dq, d qd) at the event (S-_j + f- dt*_j), its d qd replaced by d qd after the
 * rounds; dq passes through unchanged.  Returns GAC_SENS_VALID (or the first walk's verdict, not met again). */
static int gac_sens_rounds_differential(gac_sim *s, const gac_impact_record *r, gac_sens_rounds *C, int *contact)
{
    const gac_sens *z = s->sens;
    const gac_model *md = s->model;
    const int nq = md->nq, nx = md->nx;
    double zero_p[GAC_AT_LEAST_1(md->nparam)], out[nq];
    int i, j, col;
    for (i = 0; i < GAC_AT_LEAST_1(md->nparam); ++i) zero_p[i] = 0.0;
    gac_sens_rounds_start(s, C);
    for (j = 0; j < r->rounds; ++j) {
        const int verdict = gac_sens_round(s, r, C, j, contact);
        if (verdict != GAC_SENS_VALID) return verdict;
        for (col = 0; col < z->k && C->law.m > 0; ++col) {
            double *S = z->S + (long)col * nx;
            const double *dp = md->nparam > 0 ? z->dp + (long)col * md->nparam : zero_p;
            gac_impact_differential(s, &C->law, s->xs, C->qd, S, S + nq, dp, out, 0);
            gac_copy(S + nq, out, nq);
        }
        gac_copy(C->qd, C->qd_next, nq);
    }
    return GAC_SENS_VALID;
}

/* The jump at the impact record r just resolved (state before it s->xs, after it s->x), located by contact
 * c_event's gap: for each direction j, dt*_j = -dg_j / (w_c . qd-) and S+_j = D Delta (S-_j + f- dt*_j, dp_j)
 * - f+ dt*_j, Delta the map of the contacts that took an impulse (a wall's or a joint stop's alike: a stop's row is
 * a row of the identity), f- and f+ the fields with the resting sets before and after held.  A landing contact is
 * struck with e = 0 (its wall's e not read); a resting contact that takes an impulse is at rest before (v ~ 0).
 * When contacts rest after, the loop then held their velocities at 0 (gac_hold): D Delta is followed by the
 * derivative of that projection (gac_sens_hold_tangent, on the resting set and the impact's other contacts left at
 * rest), and a landing contact is held at the gap it had at the event (dgap_held from S-_j + f- dt*_j).  A contact
 * of the record that took no impulse stays out of Delta if it leaves the impact separating or is held; one with
 * impulse ~0 and leaving at the law's bound is a mode boundary inside the impact (the verdict).  An impact the
 * law solved in several rounds (or closed with a plastic round) takes for Delta the chain of its rounds'
 * laws, each on its own active set (gac_sens_rounds_at, gac_sens_rounds_differential; the GDI law's rounds with
 * their rough contacts' tangential rows, stuck or sliding, as for one round), a contact at its bound in one of them
 * ending the sensitivities (GAC_SENS_BOUNDARY, one-sided or not).  On rough walls the
 * stuck points are held along every axis: those before (was_stuck, per contact, or NULL: none) in f-, those after
 * (s->is_stuck, as gac_restick re-decided them: called after it, the state after in s->x) in f+ and in the hold,
 * which brings the law's velocities onto their tangential rows too (a landing that sticks); the others on rough
 * walls slide in f- and f+ with their friction (a landing that slides on).  A point sliding at rest slower than
 * friction_velocity before or after (the slip directions of f- are the loop's after the impact), a stuck point that
 * slipped, or one that came to stick without taking the impact's impulse ends them (GAC_SENS_RESTING,
 * GAC_SENS_STICK), as do impacts of another kind.  A link pair or a link on an obstacle (no Jacobian row) takes part
 * with its row J^T n (gac_sens_row; t* from its gap where it locates the impact, the gap's gradient being that row),
 * its restitution e_<name> (an obstacle's) or the model's constant (a pair's); one resting before or after the
 * impact, left at rest by it, rough under the frictional law, or whose closest points have no derivative ends them
 * (GAC_SENS_LINK). */
void gac_sens_impact(gac_sim *s, const gac_impact_record *r, int c_event, const int *was_stuck)
{
    gac_sens *z = s->sens;
    const gac_model *md = s->model;
    if (z == 0 || z->status != GAC_SENS_VALID) return;
    {
        int a;
        {                                                    /* one at rest without derivative before, or after */
            int before_set[md->nq + GAC_AT_LEAST_1(md->ncontact)], nbefore = gac_sens_set_before(s, r, before_set);
            a = gac_sens_rowless_check(s, s->xs, nbefore, before_set);
            if (a < 0) a = gac_sens_rowless_check(s, s->x, s->nresting, s->resting);
            if (a >= 0) {
                gac_sens_stop(s, GAC_SENS_LINK, r->t, a);
                return;
            }
        }
    }
    if (r->law != GAC_IMPACT_LAW_FRICTIONLESS && r->law != GAC_IMPACT_LAW_GDI) {
        gac_sens_stop(s, r->law == GAC_IMPACT_LAW_GDI_TANGENTIAL ? GAC_SENS_TANGENTIAL : GAC_SENS_FRICTION, r->t,
                      r->ncontact > 0 ? r->contact[0] : -1);
        return;
    }
    if (r->ncontact < 1 || r->rounds < 1) {
        gac_sens_stop(s, GAC_SENS_SIMULTANEOUS, r->t, r->ncontact > 0 ? r->contact[0] : c_event);
        return;
    }
    {                                                        /* on rough walls: stuck points before and after */
        int before_set[md->nq + GAC_AT_LEAST_1(md->ncontact)], nbefore = gac_sens_set_before(s, r, before_set), a, b;
        int slow = gac_sens_slow_slide(s, s->xs, nbefore, before_set, was_stuck);   /* sliding slowly, before */
        if (slow < 0) slow = gac_sens_slow_slide(s, s->x, s->nresting, s->resting, s->is_stuck);   /* or after */
        if (slow >= 0) {
            gac_sens_stop(s, GAC_SENS_RESTING, r->t, slow);
            return;
        }
        if (r->nslipped > 0) {                               /* a stuck point slipped at the impact */
            gac_sens_stop(s, GAC_SENS_STICK, r->t, r->slipped[0]);
            return;
        }
        for (a = 0; a < r->nstuck; ++a) {                    /* came to stick: only the impact's own contacts */
            int struck = 0;
            for (b = 0; b < r->ncontact; ++b) struck |= r->contact[b] == r->stuck[a];
            if (!struck) {
                gac_sens_stop(s, GAC_SENS_STICK, r->t, r->stuck[a]);
                return;
            }
        }
    }
    {
        const int nq = md->nq, nx = md->nx, nr = GAC_AT_LEAST_1(md->njrow), n = r->ncontact, n3 = 3 * n;
        const int nc1 = GAC_AT_LEAST_1(md->ncontact);
        const double *xm = s->xs, *xp = s->x, *q = xm;
        double f[n3 * nr], W[n3 * nq], Y[n3 * nq], LD[n3 * n3], F[n3], v[n3], e[n3], fm[nx], fp[nx];
        double u[n3], xi_t[n3], xi_norm[n3], cf_row[n3];
        int normal[n3], cf_index[n3], nslide = 0;
        double dgap[nc1], dx[nx], dqd_plus[nq], zero_p[GAC_AT_LEAST_1(md->nparam)];
        double qd_law[nq], qdd_free[nq], lambda[3 * nq];
        double speed = 0.0, largest = 0.0, v_event = 0.0;
        double fb[n * nr], Wb[n * nq], vb[n], eb[n];         /* the boundary contacts' rows (one_sided) */
        int active[n3], landing[n3], before_set[nq + nc1], at_rest[nq], m = 0, nbefore, nheld = 0, a, b, i, j;
        int frame[n3], nframe = 0;                           /* rows along a rowless contact's frame (law.frame) */
        int boundary[n], nb = 0;
        const int several = r->rounds > 1 || r->plastic;   /* the rounds' chain (gac_sens_rounds_at) */
        const int R = several ? r->rounds : 1, nR = several ? n : 1, rough = r->law != GAC_IMPACT_LAW_FRICTIONLESS;
        const int fits = GAC_SENS_TRACE_BYTES(R, nR, rough) <= GAC_SENS_TRACE_ROOM;   /* the rounds' trace */
        int Tint[fits ? GAC_SENS_TRACE_INTS(R, nR, rough) : 1], zero_start[nR], zero_round[nR], exempt[nR];
        double Tdouble[fits ? GAC_SENS_TRACE_DOUBLES(R, nR, rough) : 1], fall[nR * nr], Wall[nR * nq], e_list[nR];
        double qd_round[nq], qd_next[nq];
        gac_sens_rounds C;                                   /* (a round's law in f, W, Y, ... above) */
        gac_sens_law law;
        GAC_SENS_SET_ARRAYS(nq, nr);
        gac_sens_set H;
        GAC_SENS_SET_BIND(H);
        nbefore = gac_sens_set_before(s, r, before_set);
        if (several && !fits) {                              /* too many rounds to trace */
            gac_sens_stop(s, GAC_SENS_SIMULTANEOUS, r->t, c_event);
            return;
        }
        C.n = nR, C.trace.cap = R, C.trace.n = nR, C.trace.k = Tint, C.trace.idx = Tint + R;
        C.trace.hit = C.trace.idx + (long)R * nR, C.trace.F = Tdouble;
        C.trace.dim = rough ? C.trace.hit + (long)R * nR : 0, C.trace.L = rough ? Tdouble + (long)R * nR : 0;
        C.fall = fall, C.Wall = Wall, C.e_list = e_list, C.zero_start = zero_start, C.zero = zero_round;
        C.exempt = exempt, C.qd = qd_round, C.qd_next = qd_next;
        C.active = active, C.landing = landing, C.normal = normal, C.cf_index = cf_index, C.frame = frame;
        C.f = f, C.W = W, C.Y = Y;
        C.LD = LD, C.F = F, C.v = v, C.e = e, C.u = u, C.xi_norm = xi_norm, C.cf = cf_row;
        for (i = 0; i < nq; ++i) {
            if (fabs(xm[nq + i]) > speed) speed = fabs(xm[nq + i]);
        }
        for (a = 0; a < n; ++a) {
            if (r->impulse[a] > largest) largest = r->impulse[a];
        }
        {                                                    /* the event's contact: t* from its gap */
            double fe[nr], we[nq];
            gac_sens_row(s, c_event, q, fe, we);
            for (i = 0; i < nq; ++i) v_event += we[i] * xm[nq + i];
            if (!(fabs(v_event) > 1e-9 * speed * s->lever)) {   /* grazing: t* has no derivative */
                gac_sens_stop(s, GAC_SENS_GRAZING, r->t, c_event);
                return;
            }
        }
        for (a = 0; a < n && !several; ++a) {               /* the active set, and the mode boundaries */
            const int c = r->contact[a];
            const gac_contact *ct = md->contacts + c;
            double *fa = f + (long)m * nr, *wa = W + (long)m * nq, before = 0.0, after = 0.0;
            int was_resting = 0, held_after = 0;
            for (b = 0; b < nbefore; ++b) was_resting |= before_set[b] == c;
            for (b = 0; b < s->nresting; ++b) held_after |= s->resting[b] == c;
            gac_sens_row(s, c, q, fa, wa);
            if (gac_rowless(md, c)) {                        /* its row's derivative exists here (or none) */
                double zero_q[nq], zero_p[GAC_AT_LEAST_1(md->nparam)], dw[nq];
                for (i = 0; i < nq; ++i) zero_q[i] = 0.0;
                for (i = 0; i < GAC_AT_LEAST_1(md->nparam); ++i) zero_p[i] = 0.0;
                if (gac_sens_row_tangent(s, c, fa, q, zero_q, zero_p, dw) != 0) {
                    gac_sens_stop(s, GAC_SENS_LINK, r->t, c);
                    return;
                }
            }
            for (i = 0; i < nq; ++i) {
                before += wa[i] * xm[nq + i];
                after += wa[i] * xp[nq + i];
            }
            e[m] = ct->e_index >= 0 ? s->p[ct->e_index] : ct->e_value;
            landing[m] = 0;
            if (r->impulse[a] > 1e-9 * largest) {
                if (!was_resting && !(fabs(before) > 1e-9 * speed * s->lever)) {   /* pushed at rest: a graze */
                    gac_sens_stop(s, GAC_SENS_GRAZING, r->t, c);
                    return;
                }
                if (!was_resting && fabs(after) <= 1e-6 * fabs(before)) {   /* struck with e = 0: it landed */
                    landing[m] = 1;
                    e[m] = 0.0;
                }
                v[m] = before;
                frame[m] = 0;
                active[m++] = c;
                normal[m - 1] = -1;
                F[m - 1] = r->impulse[a];
                if (r->law == GAC_IMPACT_LAW_GDI && gac_contact_friction(md, s->p, c) > 0.0) {   /* a rough contact
                                                                                                  (a wall, a link
                                                                                                  pair, an obstacle):
                                                                                                  stuck or sliding */
                    const double cf = gac_contact_friction(md, s->p, c);
                    const double tangential = hypot(r->impulse_t[2 * a], r->impulse_t[2 * a + 1]);
                    const int row_n = m - 1, first = m, rowless = gac_rowless(md, c);
                    const int slides = !(tangential < (1.0 - 1e-6) * cf * r->impulse[a]);
                    double xi2 = 0.0;
                    gac_contact_frame frame_c;               /* a link pair's or an obstacle's: rows J^T t1, J^T t2 */
                    int t;
                    if (rowless && gac_rowless_frame(md, q, s->p, c, &frame_c) != GAC_OK) {
                        gac_sens_stop(s, GAC_SENS_LINK, r->t, c);
                        return;
                    }
                    for (t = 0; t < 2; ++t) {                /* its tangential rows: stuck, xi_T = gamma+_T + e gamma-_T
                                                                = 0, the normal's law along them; sliding, on the cone */
                        double *ft = f + (long)m * nr, *wt = W + (long)m * nq, vt = 0.0, vt_after = 0.0;
                        if (!rowless && ct->trow[t] < 0) continue;
                        if (rowless) {                       /* a direction no motion takes (a planar model's t2)
                                                                is left out, as the law leaves it */
                            const double scale = gac_frame_direction(md, q, s->p, &frame_c, t + 1, wt);
                            if (!(sqrt(gac_dot(nq, wt, wt)) > 1e-10 * scale)) continue;
                        }
                        for (i = 0; i < nr; ++i) ft[i] = 0.0;
                        if (rowless) {
                            frame[m] = 1 + t;
                            ++nframe;
                        } else {
                            ft[ct->trow[t]] = 1.0;
                            md->contact_generalized_force(q, ft, s->p, wt);
                            frame[m] = 0;
                        }
                        for (i = 0; i < nq; ++i) {
                            vt += wt[i] * xm[nq + i];
                            vt_after += wt[i] * xp[nq + i];
                        }
                        e[m] = e[row_n];
                        landing[m] = landing[row_n];
                        v[m] = vt;
                        F[m] = r->impulse_t[2 * a + t];
                        normal[m] = slides ? row_n : -1;
                        xi_t[m] = vt_after + e[row_n] * vt;
                        xi2 += xi_t[m] * xi_t[m];
                        cf_row[m] = cf;
                        cf_index[m] = ct->friction_index;
                        u[m] = slides ? -r->impulse_t[2 * a + t] / (cf * r->impulse[a]) : 0.0;
                        active[m++] = c;
                    }
                    if (slides) {
                        if (!(sqrt(xi2) > 1e-9 * speed * s->lever)) {   /* on the cone with xi_T ~ 0: a mode
                                                                           boundary between stick and slide */
                            gac_sens_stop(s, GAC_SENS_BOUNDARY, r->t, c);
                            return;
                        }
                        for (t = first; t < m; ++t) xi_norm[t] = sqrt(xi2);
                        ++nslide;
                    }
                }
            } else if (!held_after && !was_resting) {       /* no impulse: out of Delta if it leaves clear of */
                const double bound = after + (before < 0.0 ? e[m] * before : 0.0);   /* the law's bound */
                if (!(bound > 1e-9 * speed * s->lever)) {    /* at it: a mode boundary */
                    const int frictionless = r->law == GAC_IMPACT_LAW_FRICTIONLESS
                                             || !(gac_contact_friction(md, s->p, c) > 0.0);
                    if (!z->one_sided || !frictionless || !(before < 0.0) || nb == GAC_SENS_MAX_BOUNDARY) {
                        gac_sens_stop(s, GAC_SENS_BOUNDARY, r->t, c);
                        return;
                    }
                    gac_copy(fb + (long)nb * nr, fa, nr);    /* each column takes its side (below) */
                    gac_copy(Wb + (long)nb * nq, wa, nq);
                    vb[nb] = before;
                    eb[nb] = e[m];
                    boundary[nb++] = c;
                }
            }
        }
        if (!several && (m == 0 || (nb > 0 && (nslide > 0 || nframe > 0)))) {   /* (boundaries beside slides or
                                                                                   a rowless contact's frame rows:
                                                                                   not followed) */
            gac_sens_stop(s, GAC_SENS_BOUNDARY, r->t, nb > 0 ? boundary[0] : c_event);
            return;
        }
        if (several) {                                       /* the rounds' laws, and the law's velocities */
            int c_stop;
            const int verdict = gac_sens_rounds_at(s, r, c_event, nbefore, before_set, &C, &c_stop);
            if (verdict != GAC_SENS_VALID) {
                gac_sens_stop(s, verdict, r->t, c_stop);
                return;
            }
            gac_copy(qd_law, C.qd, nq);
        }
        for (a = 0; a < m; ++a) {
            md->inertia_solve(q, W + (long)a * nq, s->p, Y + (long)a * nq);
            for (b = 0; b <= a; ++b) {
                double sum = 0.0;
                for (i = 0; i < nq; ++i) sum += W[(long)a * nq + i] * Y[(long)b * nq + i];
                LD[a * m + b] = LD[b * m + a] = sum;
            }
        }
        law.m = m, law.active = active, law.landing = landing, law.f = f, law.W = W, law.Y = Y, law.LD = LD;
        law.F = F, law.v = v, law.e = e;
        law.nslide = nslide, law.normal = normal, law.u = u, law.xi_T_norm = xi_norm, law.cf = cf_row;
        law.cf_index = cf_index;
        law.frame = nframe > 0 ? frame : 0;
        if (!several) {
            if (gac_sens_law_regular(&law, LD)) {
                if (nslide == 0) {                           /* Newton's law on every row: A F = -(1 + E) v */
                    for (a = 0; a < m; ++a) F[a] = -(1.0 + e[a]) * v[a];
                    gac_ldlt_solve(m, LD, F);
                }                                            /* with slides: the law's impulses (the record's),
                                                                and LD keeps A for the differential */
            } else if (nslide > 0 || !gac_sens_law_reduce(&law, LD, F, 1e-9 * speed * s->lever)) {
                gac_sens_stop(s, GAC_SENS_SIMULTANEOUS, r->t, c_event);   /* dependent rows, no unique differential */
                return;
            }
        }
        for (i = 0; i < nq && !several; ++i) {              /* the law's velocities, before any hold */
            double value = xm[nq + i];
            for (a = 0; a < m; ++a) value += Y[(long)a * nq + i] * F[a];
            qd_law[i] = value;
        }
        for (b = 0; b < nb; ++b) {                           /* the boundary rows after the active ones, F = 0 */
            gac_copy(f + (long)(m + b) * nr, fb + (long)b * nr, nr);
            gac_copy(W + (long)(m + b) * nq, Wb + (long)b * nq, nq);
            md->inertia_solve(q, W + (long)(m + b) * nq, s->p, Y + (long)(m + b) * nq);
            F[m + b] = 0.0, v[m + b] = vb[b], e[m + b] = eb[b];
            active[m + b] = boundary[b], landing[m + b] = 0, normal[m + b] = -1;
        }
        if (gac_sens_field(s, r->t, xm, nbefore, before_set, was_stuck, &H, qdd_free, lambda, fm, 0) != 0
            || gac_sens_field(s, r->t, xp, s->nresting, s->resting, s->is_stuck, &H, qdd_free, lambda, fp, 0) != 0) {
            gac_sens_stop(s, GAC_SENS_SIMULTANEOUS, r->t, c_event);
            return;
        }
        if (s->nresting > 0) {                               /* the hold after the law: the set at rest */
            nheld = gac_sens_at_rest(s, xp, s->nresting, s->resting, n, r->contact, at_rest);
            a = gac_sens_rowless_check(s, xp, nheld, at_rest);   /* one left at rest without derivative */
            if (a >= 0) {
                gac_sens_stop(s, GAC_SENS_LINK, r->t, a);
                return;
            }
            if (gac_sens_set_at(s, xp, nheld, at_rest, s->is_stuck, &H) != 0) {
                gac_sens_stop(s, GAC_SENS_SIMULTANEOUS, r->t, c_event);
                return;
            }
        }
        for (i = 0; i < GAC_AT_LEAST_1(md->nparam); ++i) zero_p[i] = 0.0;
        for (j = 0; j < z->k; ++j) {                         /* each column's dt*_j, and its state at the event */
            double *S = z->S + (long)j * nx;
            const double *dp = md->nparam > 0 ? z->dp + (long)j * md->nparam : zero_p;
            double tau;
            gac_sens_gaps_tangent(s, q, S, dp, 1, &c_event, dgap);
            tau = -dgap[c_event] / v_event;                  /* dt*_j: the gap stays 0 at the event */
            for (i = 0; i < nx; ++i) S[i] = S[i] + fm[i] * tau;  /* the perturbed state at the perturbed t* */
            z->dt_impact[j] = tau;
        }
        if (several) {                                       /* the rounds' differentials, chained, every column's
                                                                d qd through round j before round j + 1 */
            int c_stop;
            const int verdict = gac_sens_rounds_differential(s, r, &C, &c_stop);
            if (verdict != GAC_SENS_VALID) {
                gac_sens_stop(s, verdict, r->t, c_stop);
                return;
            }
        }
        for (j = 0; j < z->k; ++j) {                         /* D Delta, the hold, back to the nominal t* */
            double *S = z->S + (long)j * nx;
            const double *dp = md->nparam > 0 ? z->dp + (long)j * md->nparam : zero_p;
            const double tau = z->dt_impact[j];
            gac_copy(dx, S, nx);
            if (several)                                     /* (the rounds' chain, above) */
                gac_copy(dqd_plus, dx + nq, nq);
            else if (nb == 0)
                gac_impact_differential(s, &law, q, xm + nq, dx, dx + nq, dp, dqd_plus, 0);
            else                                             /* this column's side of the boundary */
                gac_sens_boundary_column(s, &law, nb, qd_law, q, xm + nq, dx, dp, dqd_plus);
            if (nheld > 0) {
                double held[nq];
                gac_sens_hold_tangent(s, xp, &H, qd_law, xp + nq, dx, dqd_plus, dp, held);
                gac_copy(dqd_plus, held, nq);
                gac_sens_gaps_tangent(s, q, dx, dp, r->nlanded, r->landed, dgap);
                for (b = 0; b < r->nlanded; ++b)             /* held at the gap it had at the event */
                    z->dgap_held[(long)j * nc1 + r->landed[b]] = dgap[r->landed[b]];
            }
            for (i = 0; i < nq; ++i) {
                S[i] = dx[i] - fp[i] * tau;                      /* back to the nominal t*: minus f+ dt*_j */
                S[nq + i] = dqd_plus[i] - fp[nq + i] * tau;
            }
        }
        z->n_impacts++;
        if (nb > 0 && z->n_boundaries++ == 0) {
            z->t_boundary = r->t;
            z->contact_boundary = boundary[0];
        }
        if (!gac_finite(z->S, z->k * nx)) gac_sens_stop(s, GAC_SENS_NONFINITE, r->t, c_event);
    }
}

/* The release of resting contact c_event, whose force lambda_c fell to 0 at t* (state s->xs; gac_release made the
 * set s->resting, record r): lambda_c is the event function, so dt*_j = -d lambda_c / lambda_c', d lambda_c along
 * (S_j, dp_j) and lambda_c' along the flow (dq, dqd) = (qd, qdd), both by the constrained dynamics' tangent with the
 * set before held.  The state is continuous, so S+_j = S-_j + (f- - f+) dt*_j (f- - f+ = Y_c lambda_c: ~0, as the
 * field is continuous where lambda_c = 0).  A controller's inputs enter both by their Jacobian: du_j along (S_j), and
 * u' along the flow (gac_sens_input_rate) in lambda_c'.  Another contact released with it (its force ~0 too), a force
 * that does not cross 0 (|lambda_c'| below 1e-9 of the force scale per s) or inputs that vary within the stretch
 * without a known rate (a linear schedule, a controller without its Jacobian) end the sensitivities. */
void gac_sens_release(gac_sim *s, const gac_impact_record *r, int c_event)
{
    gac_sens *z = s->sens;
    const gac_model *md = s->model;
    const int nq = md->nq, nx = md->nx, nr = GAC_AT_LEAST_1(md->njrow), nc1 = GAC_AT_LEAST_1(md->ncontact);
    const double *x = s->xs;
    double fm[nx], fp[nx], qdd_free[nq], lambda[3 * nq], dqdd_free[nq], dlambda[3 * nq], qdd_m[nq], lambda_ref, rate;
    double zero_p[GAC_AT_LEAST_1(md->nparam)], du[GAC_AT_LEAST_1(md->nu)], J[2 * GAC_AT_LEAST_1(md->nu) * nq], xa[nx];
    int before_set[nq + nc1], nbefore, a, i, j, index = -1;
    const double *u, *Ju;
    GAC_SENS_SET_ARRAYS(nq, nr);
    gac_sens_set H;
    if (z == 0 || z->status != GAC_SENS_VALID) return;
    GAC_SENS_SET_BIND(H);
    if (r->nreleased != 1) {
        gac_sens_stop(s, GAC_SENS_BOUNDARY, r->t, c_event);
        return;
    }
    if (s->controller != 0 && md->nu > 0 && (gac_sens_inputs_fixed(s) || s->controller_jacobian == 0)) {
        gac_sens_stop(s, GAC_SENS_CONTROLLER, r->t, c_event);   /* (a linear schedule: its rate is not followed) */
        return;
    }
    for (i = 0; i < GAC_AT_LEAST_1(md->nparam); ++i) zero_p[i] = 0.0;
    u = gac_input(s, r->t, x);
    Ju = gac_sens_jacobian_at(s, r->t, x, J, xa) ? J : 0;
    nbefore = gac_sens_set_before(s, r, before_set);
    for (a = 0; a < nbefore; ++a) {
        if (before_set[a] == c_event) index = a;
    }
    if (index < 0                             /* (the stuck points are those before: a stuck one released ended them) */
        || gac_sens_field(s, r->t, x, s->nresting, s->resting, s->is_stuck, &H, qdd_free, lambda, fp, 0) != 0
        || gac_sens_field(s, r->t, x, nbefore, before_set, s->is_stuck, &H, qdd_free, lambda, fm, &lambda_ref) != 0) {
        gac_sens_stop(s, GAC_SENS_SIMULTANEOUS, r->t, c_event);
        return;
    }
    gac_copy(qdd_m, fm + nq, nq);
    gac_sens_input_rate(s, Ju, r->t, x, xa, fm, du);          /* u' along the flow */
    md->forward_dynamics_tangent(x, x + nq, u, s->p, x + nq, qdd_m, du, zero_p, dqdd_free);
    gac_sens_held_tangent(s, x, &H, qdd_free, lambda, x + nq, qdd_m, zero_p, 0, dqdd_free, dlambda, dqdd_free);
    rate = dlambda[index];                                   /* lambda_c' along the flow */
    if (!(fabs(rate) > 1e-9 * lambda_ref)) {
        gac_sens_stop(s, GAC_SENS_GRAZING, r->t, c_event);
        return;
    }
    for (j = 0; j < z->k; ++j) {
        double *S = z->S + (long)j * nx;
        const double *dp = md->nparam > 0 ? z->dp + (long)j * md->nparam : zero_p;
        double tau;
        gac_sens_du(s, Ju, x, xa, S, S + nq, du);
        md->forward_dynamics_tangent(x, x + nq, u, s->p, S, S + nq, du, dp, dqdd_free);
        gac_sens_held_tangent(s, x, &H, qdd_free, lambda, S, S + nq, dp, z->dslip + 2L * j * nc1, dqdd_free, dlambda,
                              dqdd_free);
        tau = -dlambda[index] / rate;
        for (i = 0; i < nx; ++i) S[i] += (fm[i] - fp[i]) * tau;
        z->dt_impact[j] = tau;
    }
    if (!gac_finite(z->S, z->k * nx)) gac_sens_stop(s, GAC_SENS_NONFINITE, r->t, c_event);
}

/* The slip of the stuck resting contact c_event at t* (state s->xs; gac_slip and gac_recheck_rest made it slide,
 * record r): its event function e = lambda_N - |lambda_T| / c_f (the cone) gives dt*_j = -de_j / e',
 *     de_j = dlambda_N - lambda_T . dlambda_T / (|lambda_T| c_f) + |lambda_T| dc_f / c_f^2
 * along (S_j, dp_j) and e' along the flow, both from the stuck field's tangent (gac_sens_held_tangent, c_event held
 * along its tangential rows).  The state is continuous, so S+_j = S-_j + (f- - f+) dt*_j, f- stuck and f+ sliding
 * with phi = d, its slip direction d = -lambda_T / |lambda_T| with |v_t| = 0: the friction c_f lambda_N d equals the
 * stuck force on the cone, so f- - f+ ~ 0.  Along one tangential axis d = +-1 is a constant; over two it turns with
 * the directions, dd_j = -(I - d d^T)(dlambda_T_j + lambda_T' dt*_j) / |lambda_T| (the force at the perturbed
 * event), kept in sens->dslip for the viscous band that follows (gac_sens_slide_tangent).  Several points slipping
 * or released at once (GAC_SENS_BOUNDARY), an event e that does not cross 0 (|e'| below 1e-9 of the force scale per
 * s: GAC_SENS_GRAZING) or inputs without a known rate (a linear schedule, a controller without its Jacobian) end the
 * sensitivities; a controller with its Jacobian enters as at a release (gac_sens_release). */
void gac_sens_slip(gac_sim *s, const gac_impact_record *r, int c_event)
{
    gac_sens *z = s->sens;
    const gac_model *md = s->model;
    const int nq = md->nq, nx = md->nx, nr = GAC_AT_LEAST_1(md->njrow), nc1 = GAC_AT_LEAST_1(md->ncontact);
    const gac_contact *ct = md->contacts + c_event;
    const double *x = s->xs, *d = s->slip + 2 * c_event, cf = gac_rest_friction(md, s->p, c_event);
    double fm[nx], fp[nx], qdd_free[nq], lambda[3 * nq], dqdd_free[nq], dlambda[3 * nq], qdd_m[nq], lambda_ref, rate;
    double zero_p[GAC_AT_LEAST_1(md->nparam)], lt[2] = {0.0, 0.0}, lt_rate[2] = {0.0, 0.0};
    double norm, du[GAC_AT_LEAST_1(md->nu)], J[2 * GAC_AT_LEAST_1(md->nu) * nq], xa[nx];
    int stuck_before[nc1], a, i, j, t, index = -1, row_t[2] = {-1, -1};
    const double *u, *Ju;
    GAC_SENS_SET_ARRAYS(nq, nr);
    gac_sens_set H;
    if (z == 0 || z->status != GAC_SENS_VALID) return;
    GAC_SENS_SET_BIND(H);
    if (r->nslipped != 1 || r->nreleased != 0 || r->slipped[0] != c_event) {
        gac_sens_stop(s, GAC_SENS_BOUNDARY, r->t, c_event);
        return;
    }
    if (s->controller != 0 && md->nu > 0 && (gac_sens_inputs_fixed(s) || s->controller_jacobian == 0)) {
        gac_sens_stop(s, GAC_SENS_CONTROLLER, r->t, c_event);   /* (a linear schedule: its rate is not followed) */
        return;
    }
    for (i = 0; i < GAC_AT_LEAST_1(md->nparam); ++i) zero_p[i] = 0.0;
    for (i = 0; i < md->ncontact; ++i) stuck_before[i] = s->is_stuck[i] || i == c_event;
    u = gac_input(s, r->t, x);
    Ju = gac_sens_jacobian_at(s, r->t, x, J, xa) ? J : 0;
    if (gac_sens_field(s, r->t, x, s->nresting, s->resting, s->is_stuck, &H, qdd_free, lambda, fp, 0) != 0
        || gac_sens_field(s, r->t, x, s->nresting, s->resting, stuck_before, &H, qdd_free, lambda, fm, &lambda_ref)
               != 0) {
        gac_sens_stop(s, GAC_SENS_SIMULTANEOUS, r->t, c_event);
        return;
    }
    for (a = 0; a < H.n; ++a) {
        if (H.set[a] == c_event) index = a;
    }
    for (t = 0; t < 2; ++t) {                               /* its tangential rows, by axis */
        row_t[t] = gac_sens_tangent_row(s, &H, c_event, t);
        if (row_t[t] >= 0) lt[t] = lambda[row_t[t]];
    }
    norm = hypot(lt[0], lt[1]);
    if (index < 0 || H.ndropped > 0 || !(norm > 0.0)) {
        gac_sens_stop(s, GAC_SENS_SIMULTANEOUS, r->t, c_event);
        return;
    }
    gac_copy(qdd_m, fm + nq, nq);
    gac_sens_input_rate(s, Ju, r->t, x, xa, fm, du);          /* u' along the flow */
    md->forward_dynamics_tangent(x, x + nq, u, s->p, x + nq, qdd_m, du, zero_p, dqdd_free);
    gac_sens_held_tangent(s, x, &H, qdd_free, lambda, x + nq, qdd_m, zero_p, 0, dqdd_free, dlambda, dqdd_free);
    rate = dlambda[index];                                  /* e' along the flow */
    for (t = 0; t < 2; ++t) {
        if (row_t[t] < 0) continue;
        lt_rate[t] = dlambda[row_t[t]];
        rate -= lt[t] * lt_rate[t] / (norm * cf);
    }
    if (!(fabs(rate) > 1e-9 * lambda_ref)) {
        gac_sens_stop(s, GAC_SENS_GRAZING, r->t, c_event);
        return;
    }
    for (j = 0; j < z->k; ++j) {
        double *S = z->S + (long)j * nx, *dd = z->dslip + 2L * j * nc1 + 2 * c_event, dlt[2] = {0.0, 0.0}, de, tau;
        const double *dp = md->nparam > 0 ? z->dp + (long)j * md->nparam : zero_p;
        const double dcf = ct->friction_index >= 0 ? dp[ct->friction_index] : 0.0;
        gac_sens_du(s, Ju, x, xa, S, S + nq, du);
        md->forward_dynamics_tangent(x, x + nq, u, s->p, S, S + nq, du, dp, dqdd_free);
        gac_sens_held_tangent(s, x, &H, qdd_free, lambda, S, S + nq, dp, z->dslip + 2L * j * nc1, dqdd_free, dlambda,
                              dqdd_free);
        de = dlambda[index] + norm * dcf / (cf * cf);
        for (t = 0; t < 2; ++t) {
            if (row_t[t] < 0) continue;
            dlt[t] = dlambda[row_t[t]];
            de -= lt[t] * dlt[t] / (norm * cf);
        }
        tau = -de / rate;
        for (i = 0; i < nx; ++i) S[i] += (fm[i] - fp[i]) * tau;
        z->dt_impact[j] = tau;
        {                                                   /* dd = -(I - d d^T)(dlambda_T + lambda_T' tau) / |lambda_T| */
            const double w0 = dlt[0] + lt_rate[0] * tau, w1 = dlt[1] + lt_rate[1] * tau, dw = d[0] * w0 + d[1] * w1;
            dd[0] = -(w0 - d[0] * dw) / norm;
            dd[1] = -(w1 - d[1] * dw) / norm;
        }
    }
    z->slip_known[2 * c_event] = d[0];
    z->slip_known[2 * c_event + 1] = d[1];
    if (!gac_finite(z->S, z->k * nx)) gac_sens_stop(s, GAC_SENS_NONFINITE, r->t, c_event);
}

/* Sliding -> stuck at a step's end (gac_try_stick, record r: the points r->stuck[], slower than friction_velocity
 * there, or turned along their one tangential axis, stuck where the forces allow; the state x_before before, s->x
 * after, stuck_before and slip_before the loop's stuck points and slip directions before).  The step ends where the
 * slowing point has just crossed |v_t| = v_s (there the viscous force steps are short), so the transition is taken as
 * the state event e = |v_t| - v_s of the first one, c: dt*_j = -de_j / e', de_j = v_t . dv_t_j / |v_t| along S_j and
 * e' along the flow f- (sliding), and, the impact map being the velocities' projection onto the held rows with the
 * new stuck points' tangential ones (gac_sens_hold_tangent),
 *     S+_j = D P (S-_j + f- dt*_j) - f+ dt*_j,
 * f+ the stuck field.  (Taking the step's end as a fixed time would miss v_s / (c_f g) in d X / d v0 of a block
 * brought to rest.)  Points that stick together at different speeds (not one body's: a mode boundary) end the
 * sensitivities, as does an e' ~ 0. */
void gac_sens_stick(gac_sim *s, const double *x_before, const int *stuck_before, const double *slip_before,
                    const gac_impact_record *r)
{
    gac_sens *z = s->sens;
    const gac_model *md = s->model;
    const int nq = md->nq, nx = md->nx, nr = GAC_AT_LEAST_1(md->njrow);
    double zero_p[GAC_AT_LEAST_1(md->nparam)], out[nq], fm[nx], fp[nx], qdd_free[nq], lambda[3 * nq], dx[nx];
    double vq[3 * GAC_AT_LEAST_1(md->npoint)], vt[2], wt[2 * nq], dwt[2 * nq], speed, rate = 0.0, amax = 0.0;
    int a, i, j, t, c;
    GAC_SENS_SET_ARRAYS(nq, nr);
    gac_sens_set H;
    if (z == 0 || z->status != GAC_SENS_VALID) return;
    GAC_SENS_SET_BIND(H);
    if (r->nstuck < 1) return;
    c = r->stuck[0];
    md->contact_velocities(x_before, x_before + nq, s->p, vq);
    gac_tangential_velocity(md, x_before, s->p, c, vq, vt);
    speed = hypot(vt[0], vt[1]);
    for (a = 1; a < r->nstuck; ++a) {                        /* one body's points, or a mode boundary */
        double w[2];
        gac_tangential_velocity(md, x_before, s->p, r->stuck[a], vq, w);
        if (!(hypot(w[0] - vt[0], w[1] - vt[1]) <= 1e-6 * speed)) {
            gac_sens_stop(s, GAC_SENS_BOUNDARY, s->t, r->stuck[a]);
            return;
        }
    }
    if (!gac_sens_inputs_known(s)) {                         /* (the map and e' need no du: the fields hold u) */
        gac_sens_stop(s, GAC_SENS_CONTROLLER, s->t, c);
        return;
    }
    if (gac_sens_field_slip(s, s->t, x_before, s->nresting, s->resting, stuck_before, slip_before, &H, qdd_free,
                            lambda, fm, 0) != 0
        || gac_sens_field(s, s->t, s->x, s->nresting, s->resting, s->is_stuck, &H, qdd_free, lambda, fp, 0) != 0) {
        gac_sens_stop(s, GAC_SENS_SIMULTANEOUS, s->t, c);
        return;
    }
    for (i = 0; i < GAC_AT_LEAST_1(md->nparam); ++i) zero_p[i] = 0.0;
    gac_sens_tangent_rows(s, x_before, c, fm, zero_p, wt, dwt);   /* e' = v_t . (d v_t / dt) / |v_t| along f- */
    for (t = 0; t < 2; ++t)
        rate += vt[t] * (gac_dot(nq, dwt + (long)t * nq, x_before + nq) + gac_dot(nq, wt + (long)t * nq, fm + nq));
    rate /= speed;
    for (i = 0; i < nq; ++i) {
        if (fabs(fm[nq + i]) > amax) amax = fabs(fm[nq + i]);
    }
    if (!(speed > 0.0) || !(fabs(rate) > 1e-9 * amax * s->lever)) {   /* not crossing v_s */
        gac_sens_stop(s, GAC_SENS_GRAZING, s->t, c);
        return;
    }
    for (j = 0; j < z->k; ++j) {
        double *S = z->S + (long)j * nx, de = 0.0, tau;
        const double *dp = md->nparam > 0 ? z->dp + (long)j * md->nparam : zero_p;
        gac_sens_tangent_rows(s, x_before, c, S, dp, wt, dwt);
        for (t = 0; t < 2; ++t)
            de += vt[t] * (gac_dot(nq, dwt + (long)t * nq, x_before + nq) + gac_dot(nq, wt + (long)t * nq, S + nq));
        tau = -de / speed / rate;
        for (i = 0; i < nx; ++i) dx[i] = S[i] + fm[i] * tau;  /* the perturbed state at the perturbed t* */
        gac_sens_hold_tangent(s, s->x, &H, x_before + nq, s->x + nq, dx, dx + nq, dp, out);
        for (i = 0; i < nq; ++i) {
            S[i] = dx[i] - fp[i] * tau;
            S[nq + i] = out[i] - fp[nq + i] * tau;
        }
        z->dt_impact[j] = tau;
    }
    if (!gac_finite(z->S, z->k * nx)) gac_sens_stop(s, GAC_SENS_NONFINITE, s->t, c);
}

/* The slip directions gac_try_stick gave slow points that could not stick, at the state s->x (a step's end, or the
 * start; slip_before: s->slip before that call, nstuck: the points it stuck).  A point c over two tangential axes
 * whose direction d changed was judged stuck, its velocities projected onto the held rows with its tangential ones
 * (P, mass metric), and given d = -lambda_T / |lambda_T| of that stuck solve (the others sliding with the slip
 * directions they had then: those before c in s->resting order already renewed).  Its derivative, at this fixed time,
 *     dd_j = -(I - d d^T) dlambda_T_j / |lambda_T|,   dlambda_T_j along (S_q, D P (S_j), dp_j) by the stuck field's
 * tangent, goes into sens->dslip (slip_known: d).  A call that also stuck points (the state then changed after the
 * directions were judged) leaves them unknown: the flight ends the sensitivities if one is used. */
void gac_sens_reslip(gac_sim *s, const double *slip_before, int nstuck)
{
    gac_sens *z = s->sens;
    const gac_model *md = s->model;
    const int nq = md->nq, nx = md->nx, nr = GAC_AT_LEAST_1(md->njrow), nc1 = GAC_AT_LEAST_1(md->ncontact);
    double slip_now[2 * nc1], xp[nx], c_v[3 * nq], qdd_free[nq], lambda[3 * nq], f[nx], dqdd_free[nq];
    double dlambda[3 * nq], dx[nx], du[GAC_AT_LEAST_1(md->nu)], zero_p[GAC_AT_LEAST_1(md->nparam)];
    double J[2 * GAC_AT_LEAST_1(md->nu) * nq], xa[nx];
    int stuck_c[nc1], a, b, i, j, t;
    GAC_SENS_SET_ARRAYS(nq, nr);
    gac_sens_set H;                                          /* the held rows with c stuck, at s->x: P */
    GAC_SENS_SET_ARRAYS_OF(H2, nq, nr);
    gac_sens_set H2;                                         /* the stuck field at P(s->x) */
    if (z == 0 || z->status != GAC_SENS_VALID || nstuck > 0 || !gac_sens_inputs_known(s)) return;
    GAC_SENS_SET_BIND(H);
    GAC_SENS_SET_BIND_OF(H2, H2);
    gac_copy(slip_now, slip_before, 2 * md->ncontact);
    for (i = 0; i < GAC_AT_LEAST_1(md->nparam); ++i) zero_p[i] = 0.0;
    for (a = 0; a < s->nresting; ++a) {
        const int c = s->resting[a];
        const gac_contact *ct = md->contacts + c;
        const double *d = s->slip + 2 * c;
        int row_t[2] = {-1, -1}, ok = 1;
        double lt[2] = {0.0, 0.0}, norm;
        const double *u, *Ju;
        if (d[0] == slip_now[2 * c] && d[1] == slip_now[2 * c + 1]) continue;
        if ((gac_rowless(md, c) ? !gac_sens_frame_moves(s, s->x, c, 2) : ct->trow[0] < 0 || ct->trow[1] < 0)
            || (d[0] == 0.0 && d[1] == 0.0) || s->is_stuck[c]) {
            slip_now[2 * c] = d[0];                          /* along one axis, forgotten: nothing to carry */
            slip_now[2 * c + 1] = d[1];
            continue;
        }
        for (b = 0; b < md->ncontact; ++b) stuck_c[b] = s->is_stuck[b] || b == c;
        if (gac_sens_set_at(s, s->x, s->nresting, s->resting, stuck_c, &H) != 0) ok = 0;
        if (ok) {                                            /* xp = P(s->x): W qd -> 0 on the held rows */
            gac_copy(xp, s->x, nx);
            for (b = 0; b < H.m; ++b) c_v[b] = -gac_dot(nq, H.W + (long)b * nq, s->x + nq);
            gac_ldlt_solve(H.m, H.LD, c_v);
            for (i = 0; i < nq; ++i) {
                for (b = 0; b < H.m; ++b) xp[nq + i] += H.Y[(long)b * nq + i] * c_v[b];
            }
            ok = gac_sens_field_slip(s, s->t, xp, s->nresting, s->resting, stuck_c, slip_now, &H2, qdd_free,
                                     lambda, f, 0) == 0 && H2.ndropped == 0;
        }
        for (t = 0; ok && t < 2; ++t) row_t[t] = gac_sens_tangent_row(s, &H2, c, t);   /* c's tangential rows */
        if (ok && row_t[0] >= 0 && row_t[1] >= 0) {
            lt[0] = lambda[row_t[0]];
            lt[1] = lambda[row_t[1]];
        }
        norm = hypot(lt[0], lt[1]);
        if (!ok || !(norm > 0.0) || hypot(d[0] + lt[0] / norm, d[1] + lt[1] / norm) > 1e-6) {
            slip_now[2 * c] = d[0];                          /* not the direction found here: left unknown */
            slip_now[2 * c + 1] = d[1];
            continue;
        }
        u = gac_input(s, s->t, xp);
        Ju = gac_sens_jacobian_at(s, s->t, xp, J, xa) ? J : 0;
        for (j = 0; j < z->k; ++j) {
            double *S = z->S + (long)j * nx, *dd = z->dslip + 2L * j * nc1 + 2 * c, w[2], dw;
            const double *dp = md->nparam > 0 ? z->dp + (long)j * md->nparam : zero_p;
            gac_copy(dx, S, nq);
            gac_sens_hold_tangent(s, s->x, &H, s->x + nq, xp + nq, S, S + nq, dp, dx + nq);
            gac_sens_du(s, Ju, xp, xa, dx, dx + nq, du);
            md->forward_dynamics_tangent(xp, xp + nq, u, s->p, dx, dx + nq, du, dp, dqdd_free);
            gac_sens_held_tangent(s, xp, &H2, qdd_free, lambda, dx, dx + nq, dp, z->dslip + 2L * j * nc1, dqdd_free,
                                  dlambda, dqdd_free);
            w[0] = dlambda[row_t[0]];
            w[1] = dlambda[row_t[1]];
            dw = d[0] * w[0] + d[1] * w[1];
            dd[0] = -(w[0] - d[0] * dw) / norm;
            dd[1] = -(w[1] - d[1] * dw) / norm;
        }
        z->slip_known[2 * c] = slip_now[2 * c] = d[0];
        z->slip_known[2 * c + 1] = slip_now[2 * c + 1] = d[1];
    }
}

/* Resting contacts released, or stuck points slipped, where the inputs change (gac_recheck_rest: their forces pull at
 * once, or leave the cone): the time is fixed (a schedule's breakpoint, or gac_sim_set_input), the state continuous,
 * and the field's jump there moves no derivative: S goes on unchanged, dt = 0. */
void gac_sens_fixed_release(gac_sim *s)
{
    gac_sens *z = s->sens;
    int j;
    if (z == 0 || z->status != GAC_SENS_VALID) return;
    for (j = 0; j < z->k; ++j) z->dt_impact[j] = 0.0;
}
