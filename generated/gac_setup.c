/*
 * gac_setup.c -- what a simulation is set up with: the options (defaults and ranges), its storage and start
 * (gac_sim_bind, gac_sim_init), its state read back (gac_sim_state), and what may change between two
 * gac_sim_advance calls (inputs, controller, schedule, clock, progress callback).  Sizes come from the model;
 * arrays live in the caller's dwork / iwork.
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
    opt->impact_law = GAC_IMPACT_LAW_GDI;
    opt->stick = 1;
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
    else if (opt->impact_law != GAC_IMPACT_LAW_GDI && opt->impact_law != GAC_IMPACT_LAW_NEWTON_COULOMB
             && opt->impact_law != GAC_IMPACT_LAW_FRICTIONLESS)
        bad = "impact_law: must be GAC_IMPACT_LAW_GDI (1), GAC_IMPACT_LAW_NEWTON_COULOMB (2) or "
              "GAC_IMPACT_LAW_FRICTIONLESS (0)";
    else if (opt->stick != 0 && opt->stick != 1)
        bad = "stick: must be 1 (a resting point on a rough wall sticks as a constraint) or 0 (the regularised "
              "friction alone)";
    if (field != 0) *field = bad;
    return bad == 0 ? GAC_OK : GAC_ERR_BAD_OPTION;
}

/* The run's clock in seconds: the embedder's, or C's processor time. */
double gac_clock_now(const gac_sim *s)
{
    if (s->clock != 0) return s->clock(s->clock_data);
    return (double)clock() / (double)CLOCKS_PER_SEC;
}

void gac_sim_bind(gac_sim *s, const gac_model *md, double *dwork, int *iwork)
{
    const int nx = md->nx, nc1 = GAC_AT_LEAST_1(md->ncontact);
    double *d = dwork;
    int j;
    s->model_a = md;
    s->model = gac_chart_model(md, s->chart) != 0 ? gac_chart_model(md, s->chart) : md;   /* the chart integrated now */
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
    s->slip = d;          d += 2 * nc1;        /* | slip (2 per contact) */
    s->work = d;          d += gac_impact_nwork(md);   /* | work | sub */
    s->sub = d;
    s->resting = iwork;                         /* iwork: resting | is_resting | n_shrink | is_stuck | partner */
    s->is_resting = iwork + md->nq;
    s->n_shrink = iwork + md->nq + nc1;
    s->is_stuck = iwork + md->nq + 2 * nc1;
    s->partner = iwork + md->nq + 3 * nc1;
    gac_redundant_partners(md, s->partner);
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
        gac_contact_gaps(md, x, pv, gaps);
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
    s->controller_jacobian = 0;
    s->controller_data = 0;
    s->schedule = 0;
    s->sens = 0;
    s->clock = 0;
    s->clock_data = 0;
    s->progress = 0;
    s->progress_data = 0;
    s->wall_start = opt->max_wall_time > 0.0 ? gac_clock_now(s) : 0.0;
    s->wall_time = 0.0;
    s->n_look = 0;
    s->rk4_h_rho = 0.0;
    s->input_changed = 0;
    s->work_input = s->loss_damping = s->loss_friction = 0.0;
    s->n_slow_sliding = 0;
    s->n_sticks = s->n_slips = s->n_tangential_impacts = s->n_painleve_choices = 0;
    s->t_slow_sliding = 0.0;
    for (i = 0; i < md->nx; ++i) s->x[i] = x[i];
    s->n_chart_switches = 0;
    s->lost_contact = -1;
    s->lost_t = s->lost_gap = s->lost_depth = s->lost_step[0] = s->lost_step[1] = 0.0;
    for (i = 0; i < 3 * GAC_CHART_BASES_MAX; ++i) {
        const gac_base *base = i / 3 < gac_nbase(md) ? gac_model_base(md, i / 3) : 0;
        s->near_a[i] = base != 0 && base->index[i % 3] >= 0 ? x[base->index[i % 3]] : 0.0;
    }
    s->t = t0;
    s->h = opt->dt;                               /* RK4 step, or the first adaptive step (0: automatic) */
    s->f_valid = 0;
    s->n_steps = s->n_rejected = s->n_rhs = s->n_impacts = 0;
    s->nresting = 0;
    s->n_landings = s->n_releases = 0;
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
        s->is_resting[i] = 0;
        s->n_shrink[i] = 0;
        s->t_last[i] = t0;
        s->dt_last[i] = -2.0;                     /* -2: no impact of this contact yet, -1: one */
        s->gap_held[i] = 0.0;
        s->is_stuck[i] = 0;
        s->slip[2 * i] = s->slip[2 * i + 1] = 0.0;
    }
    if (gac_wants_switch(s)) {                    /* chart A already poor at the start: start on B */
        int code = gac_switch_chart(s, gac_wants_switch(s));
        if (code != GAC_OK) return code;
    }
    if (s->rest_height > 0.0) {
        int code = gac_rest_at_start(s);
        if (code < 0) return code;
    }
    gac_energy_start(s);
    gac_events(s, s->t, s->x, s->ev);
    if (s->fail == GAC_ERR_FRICTION && s->nresting > 0) s->fail = 0;   /* sliding in the Painleve paradox: the first
                                                                          advance takes a tangential impact */
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
    r->impulse = dwork;                        /* dwork: impulse | q | qd_before | qd_after | impulse_t */
    r->q = dwork + nq;
    r->qd_before = dwork + 2 * nq;
    r->qd_after = dwork + 3 * nq;
    r->impulse_t = dwork + 4 * nq;
    r->contact = iwork;                        /* iwork: contact | landed | released | stuck | slipped */
    r->landed = iwork + nq;
    r->released = iwork + 2 * nq;
    r->stuck = iwork + 3 * nq;
    r->slipped = iwork + 4 * nq;
}

void gac_sim_state(const gac_sim *s, double *t, double *q, double *qd)
{
    int i;
    if (s == 0) return;
    if (t != 0) *t = s->t;
    {
        const int nq = s->model->nq;
        double x[2 * nq];
        if (s->chart == 0 || gac_state_chart_a(s, s->x, x) != GAC_OK) gac_copy(x, s->x, 2 * nq);
        for (i = 0; i < nq; ++i) {
            if (q != 0) q[i] = x[i];
            if (qd != 0) qd[i] = x[nq + i];
        }
    }
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
    s->controller_jacobian = 0;
    s->controller_data = user;
    s->f_valid = 0;
    s->input_changed = 1;
    return GAC_OK;
}

int gac_sim_set_controller_jacobian(gac_sim *s, gac_controller_jacobian jacobian)
{
    if (s == 0) return GAC_ERR_NULL_ARGUMENT;
    if (jacobian != 0 && (s->controller == 0 || s->schedule != 0)) return GAC_ERR_BAD_OPTION;
    s->controller_jacobian = jacobian;
    return GAC_OK;
}

/* The schedule's interval that holds time t begins: its inputs from there (a held schedule's value over the
 * interval, set as held inputs; a linear one stays the controller, evaluated at every stage). */
void gac_schedule_begin(gac_sim *s)
{
    if (s->schedule->linear) {
        s->controller = gac_schedule_input;
        s->controller_data = (void *)s->schedule;
    } else {
        s->controller = 0;
        s->controller_data = 0;
        gac_schedule_input(s->t, s->x, s->x + s->model->nq, s->u, (void *)s->schedule);
    }
    s->controller_jacobian = 0;
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

