/*
 * gac_sim.c -- the hybrid loop: a simulation's storage and start (gac_sim_init), the flight right-hand side and
 * event functions, and the loop (gac_sim_advance, gac_sim_run): flight steps (gac_integrate.c) up to the next
 * event located on the dense output (gac_events.c), an impact resolved there (gac_resolve.c, with the law of
 * gac_impact.c) or a resting contact released (gac_rest.c), samples and the work of inputs, dampers and
 * friction accounted on the way.  Sizes come from the model; arrays live in the caller's dwork / iwork.
 */
#include "gac_internal.h"

#include <math.h>
#include <string.h>
#include <time.h>

void gac_default_options(gac_options *opt)
{
    if (opt == 0) return;
    opt->method = GAC_METHOD_DOPRI5;
    opt->dt = 0.0;
    opt->rtol = 1e-8;
    opt->atol = 1e-10;
    opt->h_max = 0.0;
    opt->event_samples = 4;
    opt->event_tol = 1e-13;
    opt->contact_tol = 1e-6;
    opt->max_steps = 10000000L;
    opt->rest_height = -1.0;
    opt->zeno_impacts = 20;
    opt->max_wall_time = 0.0;
    opt->max_impacts = 10000;
    opt->energy_tol = -1.0;
    opt->chart_switch = 0.3;
}

int gac_check_options(const gac_options *opt, const char **field)
{
    const char *bad = 0;
    if (opt == 0) return GAC_ERR_NULL_ARGUMENT;
    if (opt->method != GAC_METHOD_RK4 && opt->method != GAC_METHOD_DOPRI5 && opt->method != GAC_METHOD_DOP853)
        bad = "method: must be GAC_METHOD_RK4, GAC_METHOD_DOPRI5 or GAC_METHOD_DOP853";
    else if (opt->method == GAC_METHOD_RK4 && !(opt->dt > 0.0 && opt->dt < 1e300))
        bad = "dt: RK4 needs a step within (0, 1e300) s";
    else if (opt->method != GAC_METHOD_RK4 && !(opt->rtol >= GAC_RTOL_MIN && opt->rtol < 1.0))
        bad = "rtol: must be within [1e-14, 1) (GAC_RTOL_MIN: below it round-off stops the steps)";
    else if (opt->method != GAC_METHOD_RK4 && !(opt->atol > 0.0 && opt->atol < 1e300))
        bad = "atol: must be within (0, 1e300) (absolute error per coordinate)";
    else if (opt->method != GAC_METHOD_RK4 && !(opt->dt >= 0.0 && opt->dt < 1e300))
        bad = "dt: the first step of an adaptive method must be within [0, 1e300) s (0: automatic)";
    else if (!(opt->h_max >= 0.0 && opt->h_max < 1e300))
        bad = "h_max: must be within [0, 1e300) s (0: unbounded)";
    else if (opt->event_samples < 1)
        bad = "event_samples: must be >= 1 (interpolant samples searched per step)";
    else if (!(opt->event_tol > 0.0 && opt->event_tol < 1e300))
        bad = "event_tol: must be within (0, 1e300) s";
    else if (!(opt->contact_tol >= 0.0 && opt->contact_tol < 1e300))
        bad = "contact_tol: must be within [0, 1e300) m";
    else if (opt->max_steps < 0)
        bad = "max_steps: must be >= 0 (0: unbounded)";
    else if (!(opt->rest_height < 1e300))
        bad = "rest_height: must be < 1e300 m and not NaN (< 0: 10 contact_tol; 0: never by this rule)";
    else if (opt->zeno_impacts < 0)
        bad = "zeno_impacts: must be >= 0 (0: never by this rule)";
    else if (!(opt->max_wall_time >= 0.0 && opt->max_wall_time < 1e300))
        bad = "max_wall_time: must be within [0, 1e300) s (0: unbounded)";
    else if (opt->max_impacts < 0)
        bad = "max_impacts: must be >= 0 (0: unbounded)";
    else if (!(opt->energy_tol < 1.0))
        bad = "energy_tol: must be < 1 and not NaN (the energy balance's allowed residual per energy scale; < 0: "
              "automatic, 0: off)";
    else if (!(opt->chart_switch == 0.0
               || (opt->chart_switch >= GAC_CHART_SWITCH_MIN && opt->chart_switch <= GAC_CHART_SWITCH_MAX)))
        bad = "chart_switch: must be 0 (never) or within [0.1, 0.35] (GAC_CHART_SWITCH_MIN, _MAX: chart A's measure "
              "below which the loop integrates on the second base chart)";
    if (field != 0) *field = bad;
    return bad == 0 ? GAC_OK : GAC_ERR_BAD_OPTION;
}

/* The run's clock in seconds: the embedder's, or C's processor time. */
static double gac_clock_now(const gac_sim *s)
{
    if (s->clock != 0) return s->clock(s->clock_data);
    return (double)clock() / (double)CLOCKS_PER_SEC;
}

/* The loop's look at the world: the progress callback (it may stop the run) and the wall-time budget.  GAC_OK,
 * GAC_ERR_STOPPED or GAC_ERR_WALL_TIME. */
static int gac_look(gac_sim *s)
{
    s->n_look = 0;
    if (s->progress != 0 && s->progress(s->t, s->n_steps + s->n_rejected, s->n_impacts, s->progress_data) != 0)
        return GAC_ERR_STOPPED;
    if (s->opt.max_wall_time > 0.0) {
        s->wall_time = gac_clock_now(s) - s->wall_start;
        if (!(s->wall_time <= s->opt.max_wall_time)) return GAC_ERR_WALL_TIME;
    }
    return GAC_OK;
}

/* The inputs at time t and state x: the held ones, or the controller's (into s->u_eval, starting from the
 * held ones).  A non-finite controller output is kept in s->fail (GAC_ERR_BAD_INPUT). */
static void gac_to_chart_a(gac_sim *s, double *x);

const double *gac_input(gac_sim *s, double t, const double *x)
{
    const gac_model *md = s->model;
    if (s->controller == 0 || md->nu == 0) return s->u;
    gac_copy(s->u_eval, s->u, md->nu);
    if (s->chart == 1) {                      /* the controller sees chart A's coordinates, as every caller does */
        double xa[md->nx];
        gac_copy(xa, x, md->nx);
        gac_to_chart_a(s, xa);
        s->controller(t, xa, xa + md->nq, s->u_eval, s->controller_data);
    } else {
        s->controller(t, x, x + md->nq, s->u_eval, s->controller_data);
    }
    if (!gac_finite(s->u_eval, md->nu) && s->fail == 0) s->fail = GAC_ERR_BAD_INPUT;
    return s->u_eval;
}

/* The flight right-hand side: free, or with the persistent contacts held (an error is kept in s->fail;
 * in a trial stage of an adaptive step it only rejects the step). */
void gac_f(gac_sim *s, double t, const double *x, double *f)
{
    const gac_model *md = s->model;
    const double *u = gac_input(s, t, x);
    s->n_rhs++;
    if (s->nactive == 0) {
        md->rhs(t, x, u, s->p, f);
    } else {
        double lambda[md->nq];
        int i, code;
        for (i = 0; i < md->nq; ++i) f[i] = x[md->nq + i];
        code = gac_constrained_dynamics(md, x, x + md->nq, u, s->p, s->nactive, s->active, f + md->nq, lambda,
                                        s->work);
        if (code != GAC_OK && s->fail == 0) s->fail = code;
    }
}

/* Event value of every contact at time t and state x: its gap, or for a persistent contact its force lambda.
 * An event is a value falling from > 0 to <= 0: a wall crossing, or a persistent contact that would pull. */
void gac_events(gac_sim *s, double t, const double *x, double *ev)
{
    const gac_model *md = s->model;
    md->contact_gaps(x, s->p, ev);
    if (s->nactive > 0) {
        double qdd[md->nq], lambda[md->nq];
        const double *u = gac_input(s, t, x);
        int a, code;
        for (a = 0; a < md->nq; ++a) lambda[a] = 0.0;
        code = gac_constrained_dynamics(md, x, x + md->nq, u, s->p, s->nactive, s->active, qdd, lambda, s->work);
        if (code != GAC_OK && s->fail == 0) s->fail = code;
        for (a = 0; a < s->nactive; ++a) ev[s->active[a]] = lambda[a];
    }
}

/* ---- the two base charts ----------------------------------------------------------------------- */

/* 1 if the run may switch charts: opt.chart_switch > 0 and the model has a second chart. */
static int gac_can_switch(const gac_sim *s)
{
    return s->opt.chart_switch > 0.0 && s->model_a->chart_b != 0;
}

/* Chart A's measure mu_A of the state x of the chart integrated now. */
static double gac_measure_a(const gac_sim *s, const double *x)
{
    const gac_model *md = s->model;
    double angles[3], R[9];
    int i;
    if (s->chart == 0) return gac_chart_measure(md, x);
    for (i = 0; i < 3; ++i) angles[i] = x[md->base.index[i]];
    gac_base_rotation(&md->base, angles, R);
    return gac_base_measure(&s->model_a->base, R);
}

/* 1 if the run should leave the chart it is on at its current state: mu_A below opt.chart_switch on A, above
 * twice that on B (the hysteresis keeps a motion near the threshold from switching at every step). */
static int gac_wants_switch(const gac_sim *s)
{
    const double mu_a = gac_can_switch(s) ? gac_measure_a(s, s->x) : 1.0;
    return gac_can_switch(s) && (s->chart == 0 ? mu_a < s->opt.chart_switch : mu_a > 2.0 * s->opt.chart_switch);
}

/* The current chart's signed measure a . (e_z x Rz(theta_0) b) (gac_chart_measure without the absolute value): its
 * sign changes where theta_0 passes the lock. */
static double gac_signed_measure(const gac_model *m, const double *q)
{
    const double *a = m->chart.a, *b = m->chart.b;
    const double theta0 = m->chart.theta0_index >= 0 ? q[m->chart.theta0_index] : m->chart.theta0_value;
    const double c = cos(theta0), s = sin(theta0);
    return -a[0] * (s * b[0] + c * b[1]) + a[1] * (c * b[0] - s * b[1]);
}

/* 1 if the step from s->x to s->x1 ends below the chart's floor or passes its lock on the way. */
static int gac_step_near_lock(const gac_sim *s)
{
    const gac_model *md = s->model;
    if (!gac_finite(s->x1, md->nx)) return 0;
    return gac_chart_measure(md, s->x1) < gac_chart_floor(s)
           || (gac_signed_measure(md, s->x) > 0.0) != (gac_signed_measure(md, s->x1) > 0.0);
}

/* Continue on the other chart from the current state: x converted (gac_chart_convert; chart A's angles continued
 * from near_a, chart B's the principal ones), the integrator restarted (fresh first step, f invalid), the event
 * values evaluated again with the new chart's kernels. */
static int gac_switch_chart(gac_sim *s)
{
    const gac_model *from = s->model, *to = s->chart == 0 ? s->model_a->chart_b : s->model_a;
    int i, code;
    if (s->chart == 0) {
        for (i = 0; i < 3; ++i) s->near_a[i] = s->x[from->base.index[i]];
    }
    code = gac_chart_convert(&from->base, &to->base, from->nq, s->x, s->chart == 0 ? 0 : s->near_a, s->x);
    if (code != GAC_OK) return code;
    if (s->chart == 1) {
        for (i = 0; i < 3; ++i) s->near_a[i] = s->x[to->base.index[i]];
    }
    s->chart = 1 - s->chart;
    s->model = to;
    s->n_chart_switches++;
    s->f_valid = s->vn_valid = 0;
    s->h = s->opt.method == GAC_METHOD_RK4 ? s->opt.dt : 0.0;
    s->n_unstable = 0;
    gac_events(s, s->t, s->x, s->ev);
    return s->fail < 0 ? s->fail : GAC_OK;
}

/* A state x (nx) of the chart integrated now, in chart A's coordinates, in place (near_a follows it). */
static void gac_to_chart_a(gac_sim *s, double *x)
{
    const gac_model *md = s->model;
    int i;
    if (s->chart == 0) return;
    if (gac_chart_convert(&md->base, &s->model_a->base, md->nq, x, s->near_a, x) != GAC_OK) return;
    for (i = 0; i < 3; ++i) s->near_a[i] = x[md->base.index[i]];
}

/* The impact record (q, qd_before, qd_after) in chart A's coordinates; returns code. */
static int gac_report(gac_sim *s, gac_impact_record *record, int code)
{
    const int nq = s->model->nq;
    double x[2 * nq], y[2 * nq];
    if (s->chart == 0) return code;
    gac_copy(x, record->q, nq);
    gac_copy(x + nq, record->qd_before, nq);
    gac_copy(y, record->q, nq);
    gac_copy(y + nq, record->qd_after, nq);
    gac_to_chart_a(s, x);
    gac_to_chart_a(s, y);
    gac_copy(record->q, x, nq);
    gac_copy(record->qd_before, x + nq, nq);
    gac_copy(record->qd_after, y + nq, nq);
    return code;
}

void gac_sim_bind(gac_sim *s, const gac_model *md, double *dwork, int *iwork)
{
    const int nx = md->nx, nc1 = GAC_AT_LEAST_1(md->ncontact);
    double *d = dwork;
    int j;
    s->model_a = md;
    s->model = s->chart == 1 && md->chart_b != 0 ? md->chart_b : md;   /* the chart integrated now */
    s->x = d;             d += nx;             /* dwork: x | p | u | u_eval | f | k[0..15] | x1 | xs | cont[0..7] */
    s->p = d;             d += md->nparam;
    s->u = d;             d += md->nu;
    s->u_eval = d;        d += md->nu;
    s->f = d;             d += nx;
    for (j = 0; j < 16; ++j) {
        s->k[j] = d;
        d += nx;
    }
    s->x1 = d;            d += nx;
    s->xs = d;            d += nx;
    for (j = 0; j < 8; ++j) {
        s->cont[j] = d;
        d += nx;
    }
    s->ev = d;            d += nc1;            /* | ev | es | eprev | vn | t_last | dt_last | gap_held */
    s->es = d;            d += nc1;
    s->eprev = d;         d += nc1;
    s->vn = d;            d += nc1;
    s->t_last = d;        d += nc1;
    s->dt_last = d;       d += nc1;
    s->gap_held = d;      d += nc1;
    s->work = d;          d += gac_impact_nwork(md);   /* | work | sub */
    s->sub = d;
    s->active = iwork;                         /* iwork: active | is_active | n_shrink */
    s->is_active = iwork + md->nq;
    s->n_shrink = iwork + md->nq + nc1;
}

/* gac_sim_init once its pointers and the model are checked: the options, the parameters, the state and the start
 * inside the walls checked before anything is written. */
static int gac_sim_start(gac_sim *s, const gac_model *md, double *dwork, int *iwork, double t0,
                         const double *q, const double *qd, const double *p, const gac_options *opt)
{
    const int nc1 = GAC_AT_LEAST_1(md->ncontact);
    double x[md->nx], pv[GAC_AT_LEAST_1(md->nparam)];
    int i;
    if (gac_check_options(opt, 0) != GAC_OK) return GAC_ERR_BAD_OPTION;
    for (i = 0; i < md->nparam; ++i) pv[i] = p == 0 ? md->default_parameters[i] : p[i];   /* NULL: the defaults */
    if (gac_check_parameters(md, pv, 0) != GAC_OK) return GAC_ERR_BAD_PARAMETER;
    for (i = 0; i < md->nq; ++i) {
        x[i] = q[i];
        x[md->nq + i] = qd[i];
    }
    if (!gac_finite(x, md->nx) || !gac_finite(&t0, 1)) return GAC_ERR_BAD_OPTION;
    {
        /* every point on the right side of its wall, to the depth at which the loop itself reports a lost
         * contact (GAC_ERR_LOST_CONTACT): contact_tol plus the simultaneity window (contact_tol, or 100 times
         * an adaptive method's position tolerance atol + rtol l if larger), plus round-off 1e-12 max(1 m, l),
         * l the largest |point coordinate|.  So the states the loop leaves (a resting contact held at its
         * landing gap) restart, and a point really outside is refused. */
        double gaps[nc1], r[3 * md->npoint], size = 1.0, window, depth;
        md->contact_points(x, pv, r);
        for (i = 0; i < 3 * md->npoint; ++i) {
            if (fabs(r[i]) > size) size = fabs(r[i]);
        }
        md->contact_gaps(x, pv, gaps);
        window = opt->method == GAC_METHOD_RK4 ? 0.0 : 100.0 * (opt->atol + opt->rtol * size);
        if (window < opt->contact_tol) window = opt->contact_tol;
        depth = opt->contact_tol + window + 1e-12 * size;
        for (i = 0; i < md->ncontact; ++i) {
            if (gaps[i] < -depth) return GAC_ERR_START_OUTSIDE;
        }
    }
    s->chart = 0;
    gac_sim_bind(s, md, dwork, iwork);
    s->opt = *opt;
    for (i = 0; i < md->nparam; ++i) s->p[i] = pv[i];
    for (i = 0; i < md->nu; ++i) s->u[i] = s->u_eval[i] = 0.0;
    s->controller = 0;
    s->controller_data = 0;
    s->schedule = 0;
    s->clock = 0;
    s->clock_data = 0;
    s->progress = 0;
    s->progress_data = 0;
    s->wall_start = opt->max_wall_time > 0.0 ? gac_clock_now(s) : 0.0;
    s->wall_time = 0.0;
    s->n_look = 0;
    s->rk4_h_rho = 0.0;
    s->input_changed = 0;
    s->work_input = s->work_damping = s->work_friction = 0.0;
    s->n_slow_sliding = 0;
    s->t_slow_sliding = 0.0;
    for (i = 0; i < md->nx; ++i) s->x[i] = x[i];
    s->n_chart_switches = 0;
    for (i = 0; i < 3; ++i) s->near_a[i] = md->base.index[i] >= 0 ? x[md->base.index[i]] : 0.0;
    s->t = t0;
    s->h = opt->dt;                               /* RK4 step, or the first adaptive step (0: automatic) */
    s->f_valid = 0;
    s->n_steps = s->n_rejected = s->n_rhs = s->n_impacts = 0;
    s->nactive = 0;
    s->n_activations = s->n_releases = 0;
    s->pending = s->fail = s->fail_seen = 0;
    s->vn_valid = 0;
    s->err_index = s->n_unstable = 0;
    s->t0_step = t0;
    s->h_step = 0.0;
    s->rest_height = opt->rest_height < 0.0 ? 10.0 * opt->contact_tol : opt->rest_height;
    {
        double r[3 * md->npoint], length = 0.0;   /* the chain's length: sum of |O_k+1 - O_k| */
        md->contact_points(s->x, s->p, r);
        for (i = 3; i < 3 * md->npoint; i += 3) {
            length += sqrt((r[i] - r[i - 3]) * (r[i] - r[i - 3]) + (r[i + 1] - r[i - 2]) * (r[i + 1] - r[i - 2])
                           + (r[i + 2] - r[i - 1]) * (r[i + 2] - r[i - 1]));
        }
        s->lever = length > 1.0 ? length : 1.0;
    }
    for (i = 0; i < nc1; ++i) {
        s->is_active[i] = 0;
        s->n_shrink[i] = 0;
        s->t_last[i] = t0;
        s->dt_last[i] = -2.0;                     /* -2: no impact of this contact yet, -1: one */
        s->gap_held[i] = 0.0;
    }
    if (gac_wants_switch(s)) {                    /* chart A already poor at the start: start on B */
        int code = gac_switch_chart(s);
        if (code != GAC_OK) return code;
    }
    if (s->rest_height > 0.0) {
        int code = gac_rest_at_start(s);
        if (code < 0) return code;
    }
    gac_energy_start(s);
    gac_events(s, s->t, s->x, s->ev);
    return s->fail < 0 ? s->fail : GAC_OK;
}

int gac_sim_init(gac_sim *s, const gac_model *m, double *dwork, int *iwork, double t0, const double *q,
                 const double *qd, const double *p, const gac_options *opt)
{
    gac_options defaults;
    int code;
    if (s == 0 || m == 0 || dwork == 0 || iwork == 0 || q == 0 || qd == 0) return GAC_ERR_NULL_ARGUMENT;
    code = gac_model_check(m);
    if (code != GAC_OK) return code;
    if (opt == 0) {                                /* NULL: the default options */
        gac_default_options(&defaults);
        opt = &defaults;
    }
    return gac_sim_start(s, m, dwork, iwork, t0, q, qd, p, opt);
}

void gac_record_bind(gac_impact_record *r, const gac_model *m, double *dwork, int *iwork)
{
    const int nq = m->nq;
    r->impulse = dwork;                        /* dwork: impulse | q | qd_before | qd_after */
    r->q = dwork + nq;
    r->qd_before = dwork + 2 * nq;
    r->qd_after = dwork + 3 * nq;
    r->contact = iwork;                        /* iwork: contact | activated | released */
    r->activated = iwork + nq;
    r->released = iwork + 2 * nq;
}

void gac_sim_state(const gac_sim *s, double *t, double *q, double *qd)
{
    int i;
    if (s == 0) return;
    if (t != 0) *t = s->t;
    {
        const int nq = s->model->nq;
        double x[2 * nq];
        gac_copy(x, s->x, 2 * nq);
        if (s->chart == 1) gac_chart_convert(&s->model->base, &s->model_a->base, nq, x, s->near_a, x);
        for (i = 0; i < nq; ++i) {
            if (q != 0) q[i] = x[i];
            if (qd != 0) qd[i] = x[nq + i];
        }
    }
}

/* Add the work of the inputs, the dissipation of the dampers and (with resting contacts on walls with friction)
 * that of sliding friction over [s->t, t_b] of the current step to s->work_input, s->work_damping and
 * s->work_friction: 5-point Gauss-Legendre (exact for polynomials of degree 9) on the step's dense output. */
static void gac_add_work(gac_sim *s, double t_b)
{
    static const double node[5] = {0.04691007703066800, 0.23076534494715845, 0.5, 0.76923465505284155,
                                   0.95308992296933200};
    static const double weight[5] = {0.11846344252809454, 0.23931433524968324, 0.28444444444444444,
                                     0.23931433524968324, 0.11846344252809454};
    const gac_model *md = s->model;
    const double h = t_b - s->t;
    const int friction = s->nactive > 0 && gac_has_friction(md);
    double x[md->nx], P[2], w_in = 0.0, w_damp = 0.0, w_friction = 0.0;
    int j;
    if ((md->power == 0 && !friction) || !(h > 0.0)) return;
    for (j = 0; j < 5; ++j) {
        const double t = s->t + node[j] * h;
        gac_dense(s, t, x);
        if (md->power != 0) {
            md->power(x, x + md->nq, gac_input(s, t, x), s->p, P);
            w_in += weight[j] * P[0];
            w_damp += weight[j] * P[1];
        }
        if (friction) {
            double qdd[md->nq], lambda[md->nq], D = 0.0;
            if (gac_constrained_dynamics_friction(md, x, x + md->nq, gac_input(s, t, x), s->p, s->nactive, s->active,
                                                  qdd, lambda, s->work, &D) == GAC_OK)
                w_friction += weight[j] * D;
        }
    }
    s->work_input += h * w_in;
    s->work_damping += h * w_damp;
    s->work_friction += h * w_friction;
}

int gac_sim_set_input(gac_sim *s, const double *u)
{
    int i;
    if (s == 0 || (u == 0 && s->model->nu > 0)) return GAC_ERR_NULL_ARGUMENT;
    if (!gac_finite(u, s->model->nu)) return GAC_ERR_BAD_INPUT;
    for (i = 0; i < s->model->nu; ++i) s->u[i] = u[i];
    s->f_valid = 0;                    /* the flight derivative and the resting contacts' forces change */
    s->input_changed = 1;
    return GAC_OK;
}

int gac_sim_set_clock(gac_sim *s, gac_clock clock, void *user)
{
    if (s == 0) return GAC_ERR_NULL_ARGUMENT;
    s->clock = clock;
    s->clock_data = user;
    s->wall_start = gac_clock_now(s);
    s->wall_time = 0.0;
    return GAC_OK;
}

int gac_sim_set_progress(gac_sim *s, gac_progress progress, void *user)
{
    if (s == 0) return GAC_ERR_NULL_ARGUMENT;
    s->progress = progress;
    s->progress_data = user;
    return GAC_OK;
}

int gac_sim_set_controller(gac_sim *s, gac_controller controller, void *user)
{
    if (s == 0) return GAC_ERR_NULL_ARGUMENT;
    s->schedule = 0;
    s->controller = controller;
    s->controller_data = user;
    s->f_valid = 0;
    s->input_changed = 1;
    return GAC_OK;
}

/* 1 if at x a persistent contact on a wall with friction slides slower than GAC_SLOW_SLIDING friction_velocity
 * (its velocity along the wall, as in gac_constrained_dynamics_friction): the regularised friction force is then
 * (nearly) viscous, -mu lambda v_t / friction_velocity, a stiff term that bounds an explicit method's step. */
static int gac_slow_sliding(const gac_sim *s, const double *x)
{
    const gac_model *md = s->model;
    const double slow = GAC_SLOW_SLIDING * md->friction_velocity;
    double vq[3 * GAC_AT_LEAST_1(md->npoint)];
    int a, j;
    if (s->nactive == 0 || !gac_has_friction(md)) return 0;
    md->contact_velocities(x, x + md->nq, s->p, vq);
    for (a = 0; a < s->nactive; ++a) {
        const gac_contact *k = &md->contacts[s->active[a]];
        const double mu = k->mu_index >= 0 ? s->p[k->mu_index] : k->mu_value;
        double speed2 = 0.0;
        int axis = 0;
        if (k->kind != GAC_CONTACT_WALL || !k->has_friction || !(mu > 0.0)) continue;
        for (j = 0; j < 2; ++j, ++axis) {             /* the two tangential axes, ascending */
            if (axis == k->axis) ++axis;
            if (k->trow[j] >= 0) speed2 += vq[3 * (k->point - 1) + axis] * vq[3 * (k->point - 1) + axis];
        }
        if (speed2 < slow * slow) return 1;
    }
    return 0;
}

/* Write the samples t_eval[*i_eval ..] that fall in (t_a, t_b] (state from the dense output). */
static void gac_emit(gac_sim *s, double t_b, const double *t_eval, int n_eval, int *i_eval,
                     double *x_eval)
{
    const gac_model *md = s->model;
    while (n_eval > 0 && *i_eval < n_eval && t_eval[*i_eval] <= t_b) {
        double *out = x_eval + (long)(*i_eval) * md->nx;
        if (t_eval[*i_eval] > s->t0_step) {
            gac_dense(s, t_eval[*i_eval], out);
        } else {
            int i;
            for (i = 0; i < md->nx; ++i) out[i] = s->x[i];
        }
        gac_to_chart_a(s, out);
        ++*i_eval;
    }
}

/* The schedule's interval that holds time t begins: its inputs from there (a held schedule's value over the
 * interval, set as held inputs; a linear one stays the controller, evaluated at every stage). */
static void gac_schedule_begin(gac_sim *s)
{
    if (s->schedule->linear) {
        s->controller = gac_schedule_input;
        s->controller_data = (void *)s->schedule;
    } else {
        s->controller = 0;
        s->controller_data = 0;
        gac_schedule_input(s->t, s->x, s->x + s->model->nq, s->u, (void *)s->schedule);
    }
    s->f_valid = 0;                    /* the flight derivative and the resting contacts' forces change */
    s->input_changed = 1;
}

int gac_sim_set_schedule(gac_sim *s, const gac_schedule *schedule)
{
    int code;
    if (s == 0) return GAC_ERR_NULL_ARGUMENT;
    if (schedule == 0) {
        if (s->schedule != 0 && s->schedule->linear) s->controller = 0, s->controller_data = 0;
        s->schedule = 0;
        return GAC_OK;
    }
    code = gac_schedule_check(schedule);
    if (code != GAC_OK) return code;
    if (schedule->nu != s->model->nu) return GAC_ERR_BAD_OPTION;
    s->schedule = schedule;
    gac_schedule_begin(s);
    return GAC_OK;
}

/* The end of the stretch the loop integrates next: the schedule's first time after t, or t_end. */
static double gac_next_stop(const gac_sim *s, double t_end)
{
    int k;
    if (s->schedule == 0) return t_end;
    for (k = 0; k < s->schedule->n; ++k) {
        if (s->schedule->t[k] > s->t) return s->schedule->t[k] < t_end ? s->schedule->t[k] : t_end;
    }
    return t_end;
}

static int gac_advance_to(gac_sim *s, double t_end, const double *t_eval, int n_eval, int *i_eval,
                          double *x_eval, gac_impact_record *record);

int gac_sim_advance(gac_sim *s, double t_end, const double *t_eval, int n_eval, int *i_eval,
                    double *x_eval, gac_impact_record *record)
{
    if (s == 0 || record == 0 || (n_eval > 0 && (t_eval == 0 || x_eval == 0 || i_eval == 0)))
        return GAC_ERR_NULL_ARGUMENT;
    if (!(t_end >= s->t) || !(t_end - t_end == 0.0) || n_eval < 0
        || (n_eval > 0 && (*i_eval < 0 || *i_eval > n_eval)))
        return GAC_ERR_BAD_OPTION;                /* t_end NaN, infinite or before t; bad sample index */
    if (s->opt.max_impacts > 0 && s->n_impacts >= s->opt.max_impacts && s->t < t_end && !s->pending)
        return GAC_ERR_MAX_IMPACTS;
    for (;;) {                                    /* stretches between the schedule's times */
        const double t_stop = gac_next_stop(s, t_end);
        const int code = gac_advance_to(s, t_stop, t_eval, n_eval, i_eval, x_eval, record);
        if (code != GAC_SIM_END || t_stop >= t_end) return code;
        gac_schedule_begin(s);
    }
}

/* The loop from s->t to t_end (no schedule time inside): flight steps up to the next event. */
static int gac_advance_to(gac_sim *s, double t_end, const double *t_eval, int n_eval, int *i_eval,
                          double *x_eval, gac_impact_record *record)
{
    const gac_model *md;
    long steps = 0;
    double fac_max = 10.0;
    int i;
    md = s->model;
    if (s->pending) {                                        /* the activations of gac_sim_init */
        s->pending = 0;
        record->t = s->t;
        record->ncontact = 0;
        record->complementarity = 0;
        record->energy_before = record->energy_after = gac_total_energy(md, s->x, s->p);
        for (i = 0; i < md->nq; ++i) {
            record->q[i] = s->x[i];
            record->qd_before[i] = record->qd_after[i] = s->x[md->nq + i];
        }
        record->approach_before = record->approach_after = 0.0;
        record->nactivated = s->nactive;
        record->nreleased = 0;
        for (i = 0; i < s->nactive; ++i) record->activated[i] = s->active[i];
        return gac_report(s, record, GAC_SIM_CONTACT);
    }
    if (s->input_changed) {
        const int code = gac_recheck_rest(s, record);
        if (code != 0) return code < 0 ? code : gac_report(s, record, GAC_SIM_CONTACT);
    }
    if (s->t < t_end) {                           /* the budget and the progress callback, once per call ... */
        const int code = gac_look(s);
        if (code != GAC_OK) return code;
    }
    while (s->t < t_end) {
        double h, t1, t_event = 0.0, err = 0.0;
        int c_event = -1, last;
        if (!s->f_valid) {
            gac_f(s, s->t, s->x, s->f);
            s->f_valid = 1;
        }
        if (s->fail) return s->fail;
        if (s->opt.max_steps > 0 && steps >= s->opt.max_steps) return GAC_ERR_MAX_STEPS;
        if (++s->n_look >= GAC_LOOK_STEPS) {      /* ... and every GAC_LOOK_STEPS steps, at a step end */
            const int code = gac_look(s);
            if (code != GAC_OK) return code;
        }
        if (s->opt.method != GAC_METHOD_RK4 && !(s->h > 0.0)) s->h = gac_initial_step(s, t_end);
        h = s->h;
        if (s->opt.h_max > 0.0 && h > s->opt.h_max) h = s->opt.h_max;
        last = s->t + h >= t_end * (1.0 - 4.0 * GAC_EPS) - 4.0 * GAC_EPS * fabs(t_end);
        if (last) h = t_end - s->t;
        if (!(h > 8.0 * GAC_EPS * fabs(s->t))) {
            if (last) { s->t = t_end; break; }
            return s->fail_seen ? s->fail_seen : GAC_ERR_STEP_SIZE;
        }
        if (s->opt.method == GAC_METHOD_RK4) {
            /* RK4 has no error control: 3 steps in a row at h rho > 2.5, or one far past it, mean the step is
             * beyond its stability */
            const double h_rho = s->rk4_h_rho = gac_rk4_step(s, h);
            s->n_unstable = h_rho > 2.5 ? s->n_unstable + 1 : 0;
            if (s->n_unstable >= 3 || !(h_rho < 10.0)) return GAC_ERR_UNSTABLE;
        } else {
            double fac;
            const int eighth = s->opt.method == GAC_METHOD_DOP853;
            err = eighth ? gac_dop853_step(s, h) : gac_dopri5_step(s, h);
            if (s->fail == GAC_ERR_BAD_INPUT) return s->fail;
            if (s->fail) {                  /* a trial stage the constraints cannot hold: reject and shrink */
                s->fail_seen = s->fail;
                s->fail = 0;
                err = 1e10;
            }
            if (!(err == err)) err = 1e10;                   /* NaN: reject and shrink */
            fac = err > 0.0 ? 0.9 * pow(err, eighth ? -0.125 : -0.2) : fac_max;
            if (fac > fac_max) fac = fac_max;
            if (fac < 0.2) fac = 0.2;
            if (err > 1.0) {                                 /* reject */
                s->n_rejected++;
                s->h = h * fac;
                fac_max = 1.0;
                steps++;
                continue;
            }
            s->h = h * fac;
            fac_max = 10.0;
            s->fail_seen = 0;
        }
        if (gac_step_near_lock(s)) {          /* below the chart's floor at the step's end, or past its lock */
            if (!gac_can_switch(s)) {
                if (gac_chart_measure(md, s->x1) < gac_chart_floor(s)) return GAC_ERR_GIMBAL_LOCK;
            } else if (s->opt.method != GAC_METHOD_RK4) {  /* retry shorter: the switch comes at a step's end */
                s->n_rejected++;
                s->h = 0.25 * h;
                fac_max = 1.0;
                steps++;
                continue;
            } else {                                       /* RK4: continue on the other chart from the step's start */
                const int code = gac_switch_chart(s);
                if (code != GAC_OK) return code;
                md = s->model;
                steps++;
                continue;
            }
        }
        steps++;
        s->n_steps++;
        if (gac_slow_sliding(s, s->x)) {
            s->n_slow_sliding++;
            s->t_slow_sliding += h;
        }
        if (s->fail) return s->fail;
        if (!gac_finite(s->x1, md->nx)) return GAC_ERR_NONFINITE;
        t1 = last ? t_end : s->t + h;
        gac_prepare_dense(s, h);
        if (gac_find_event(s, t1, &t_event, &c_event)) {
            int code, released = s->is_active[c_event];
            if (s->fail) return s->fail;
            gac_add_work(s, t_event);
            gac_emit(s, t_event, t_eval, n_eval, i_eval, x_eval);
            gac_dense(s, t_event, s->xs);
            code = released ? gac_release(s, t_event, c_event, record)
                            : gac_resolve(s, t_event, c_event, record);
            if (code < 0) return code;
            for (i = 0; i < md->nx; ++i) s->x[i] = code == 1 ? s->x1[i] : s->xs[i];
            s->t = t_event;
            s->f_valid = s->vn_valid = 0;
            gac_events(s, s->t, s->x, s->ev);
            if (s->fail) return s->fail;
            if (gac_energy_check(s) != GAC_OK) return GAC_ERR_DRIFT;
            if (released) {                       /* a wall crossing counts once the gap has opened again */
                for (i = 0; i < record->nreleased; ++i) {
                    if (s->ev[record->released[i]] > 0.0) s->ev[record->released[i]] = 0.0;
                }
            }
            if (s->opt.method == GAC_METHOD_RK4) s->h = s->opt.dt;
            if (released) return gac_report(s, record, GAC_SIM_CONTACT);
            if (code == 1) {
                s->n_impacts++;
                return gac_report(s, record, GAC_SIM_IMPACT);
            }
            continue;                                         /* grazing: carry on from the touch */
        }
        gac_add_work(s, t1);
        if (s->fail) return s->fail;
        gac_emit(s, t1, t_eval, n_eval, i_eval, x_eval);
        gac_copy(s->x, s->x1, md->nx);
        {
            const double *f_end = s->opt.method == GAC_METHOD_RK4 ? s->k[4]
                                : s->opt.method == GAC_METHOD_DOP853 ? s->k[12] : s->k[6];
            gac_copy(s->f, f_end, md->nx);
        }
        gac_copy(s->ev, s->eprev, md->ncontact);
        s->t = t1;
        if (s->nactive > 0) {                     /* back onto the persistent constraints */
            int code = gac_project(s, s->x, s->nactive, s->active, 1);
            if (code != GAC_OK) return code;
            s->f_valid = s->vn_valid = 0;
            gac_events(s, s->t, s->x, s->ev);
            if (s->fail) return s->fail;
        }
        {
            const int code = gac_energy_check(s);
            if (code != GAC_OK) return code;
        }
        if (s->chart == 1) {                      /* chart A's angles followed step by step (near_a) */
            double x[md->nx];
            gac_copy(x, s->x, md->nx);
            gac_to_chart_a(s, x);
        }
        if (gac_wants_switch(s)) {                /* near chart A's lock, or far enough from it again */
            const int code = gac_switch_chart(s);
            if (code != GAC_OK) return code;
            md = s->model;
        }
    }
    while (n_eval > 0 && *i_eval < n_eval && t_eval[*i_eval] <= t_end) {   /* samples at t_end itself */
        for (i = 0; i < md->nx; ++i) x_eval[(long)(*i_eval) * md->nx + i] = s->x[i];
        gac_to_chart_a(s, x_eval + (long)(*i_eval) * md->nx);
        ++*i_eval;
    }
    return GAC_SIM_END;
}

int gac_sim_run(gac_sim *s, double t_end, gac_impact_record *record, gac_run_summary *summary)
{
    int code;
    if (s == 0 || record == 0 || summary == 0) return GAC_ERR_NULL_ARGUMENT;
    summary->n_impacts = summary->n_contact_events = 0;
    summary->t_first_impact = -1.0;
    summary->energy_impact_loss = 0.0;
    for (;;) {
        code = gac_sim_advance(s, t_end, 0, 0, 0, 0, record);
        if (code == GAC_SIM_CONTACT) {
            summary->n_contact_events++;
            continue;
        }
        if (code != GAC_SIM_IMPACT) return code;
        if (summary->n_impacts == 0) summary->t_first_impact = record->t;
        summary->n_impacts++;
        summary->energy_impact_loss += record->energy_before - record->energy_after;
    }
}
