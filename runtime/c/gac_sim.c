/*
 * gac_sim.c -- the hybrid loop (gac_sim_advance, gac_sim_run): flight steps (gac_integrate.c) up to the next event
 * located on the dense output (gac_events.c), an impact resolved there (gac_resolve.c, with the law of gac_impact.c)
 * or a resting contact released (gac_rest.c), the energy balance checked (gac_energy.c) and the base chart switched
 * (gac_switch.c) at step ends, samples written on the way; the budgets and the progress callback looked at every
 * GAC_LOOK_STEPS steps.  The simulation's storage, start and setters are in gac_setup.c.
 */
#include "gac_internal.h"

#include <math.h>

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
const double *gac_input(gac_sim *s, double t, const double *x)
{
    const gac_model *md = s->model;
    if (s->controller == 0 || md->nu == 0) return s->u;
    gac_copy(s->u_eval, s->u, md->nu);
    if (s->chart != 0) {                      /* the controller sees chart A's coordinates, as every caller does */
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

/* The flight right-hand side: free, or with the resting contacts held (an error is kept in s->fail;
 * in a trial stage of an adaptive step it only rejects the step). */
void gac_f(gac_sim *s, double t, const double *x, double *f)
{
    const gac_model *md = s->model;
    const double *u = gac_input(s, t, x);
    s->n_rhs++;
    if (s->nresting == 0) {
        md->rhs(t, x, u, s->p, f);
    } else {
        double lambda[md->nq];
        int i, code;
        for (i = 0; i < md->nq; ++i) f[i] = x[md->nq + i];
        code = gac_constrained_dynamics_friction(md, x, x + md->nq, u, s->p, s->nresting, s->resting, s->is_stuck,
                                                 s->slip, f + md->nq, lambda, 0, s->work, 0);
        if (code != GAC_OK && s->fail == 0) s->fail = code;
    }
}

/* gac_f at a step's end x1, where the loop also wants T and V (the step's energy error, the balance check): with
 * no resting contacts and a model with its fused kernel, both come from one call (the rotations computed once)
 * and are kept in s->energy_x1 (energy_x1_valid); otherwise gac_f, and energy_x1_valid stays 0. */
void gac_f_end(gac_sim *s, double t, const double *x, double *f)
{
    const gac_model *md = s->model;
    s->energy_x1_valid = 0;
    if (s->nresting == 0 && md->forward_dynamics_energy != 0) {
        const int nq = md->nq;
        const double *u = gac_input(s, t, x);
        double y[md->nq + 2];
        int i;
        s->n_rhs++;
        md->forward_dynamics_energy(x, x + nq, u, s->p, y);
        for (i = 0; i < nq; ++i) {
            f[i] = x[nq + i];
            f[nq + i] = y[i];
        }
        s->energy_x1[0] = y[nq];
        s->energy_x1[1] = y[nq + 1];
        s->energy_x1_valid = 1;
        return;
    }
    gac_f(s, t, x, f);
}

/* Event value of every contact at time t and state x: its gap, or for a resting contact its force lambda, for a
 * stuck one lambda - |lambda_T| / c_f (<= lambda: its slip comes first, where |lambda_T| reaches c_f lambda).
 * An event is a value falling from > 0 to <= 0: a wall crossing, a resting contact that would pull, a stuck point
 * that slips. */
void gac_events(gac_sim *s, double t, const double *x, double *ev)
{
    const gac_model *md = s->model;
    gac_event_gaps(s, x, ev);
    if (s->nresting > 0) {
        double qdd[md->nq], lambda[md->nq], lambda_t[2 * md->nq];
        int a, code;
        for (a = 0; a < md->nq; ++a) lambda[a] = lambda_t[2 * a] = lambda_t[2 * a + 1] = 0.0;
        code = gac_rest_forces(s, t, x, qdd, lambda, lambda_t, 0);
        if (code != GAC_OK && s->fail == 0) s->fail = code;
        for (a = 0; a < s->nresting; ++a) {
            const int c = s->resting[a];
            ev[c] = lambda[a];
            if (s->is_stuck[c])
                ev[c] -= sqrt(lambda_t[2*a] * lambda_t[2*a] + lambda_t[2*a + 1] * lambda_t[2*a + 1])
                         / gac_rest_friction(md, s->p, c);
        }
    }
}

/* Write the samples t_eval[*i_eval ..] that fall in (t_a, t_b] (state from the dense output). */
static void gac_emit(gac_sim *s, double t_b, const double *t_eval, int n_eval, int *i_eval,
                     double *x_eval)
{
    const gac_model *md = s->model;
    while (n_eval > 0 && *i_eval < n_eval && t_eval[*i_eval] <= t_b) {
        double *out = x_eval + (long)(*i_eval) * md->nx, x[md->nx];
        if (t_eval[*i_eval] > s->t0_step) {
            gac_dense(s, t_eval[*i_eval], out);
        } else {
            int i;
            for (i = 0; i < md->nx; ++i) out[i] = s->x[i];
        }
        gac_copy(x, out, md->nx);
        gac_to_chart_a(s, out);
        if (s->sens != 0 && s->sens->S_eval != 0) {       /* S at the sample too, when asked (chart A's) */
            double *S = s->sens->S_eval + (long)(*i_eval) * s->sens->k * md->nx;
            gac_sens_sample(s, t_eval[*i_eval], S);
            gac_sens_to_chart_a(s, x, out, S);
        }
        ++*i_eval;
    }
}

/* The end of the stretch the loop integrates next: the schedule's first breakpoint after t, or t_end. */
static double gac_next_breakpoint(const gac_sim *s, double t_end)
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
    for (;;) {                                    /* stretches between the schedule's breakpoints */
        const double t_break = gac_next_breakpoint(s, t_end);
        const int code = gac_advance_to(s, t_break, t_eval, n_eval, i_eval, x_eval, record);
        if (code != GAC_SIM_END || t_break >= t_end) return code;
        gac_schedule_begin(s);
    }
}

/* The resting contacts re-checked where their forces changed at a fixed state (the inputs changed, or a slow point's
 * slip direction was dropped at the Painleve paradox, gac_jam): stuck points pushed beyond their cones slip, contacts
 * pulled off their walls are released (gac_recheck_rest).  0 (nothing to report) or the code to return. */
static int gac_recheck(gac_sim *s, gac_impact_record *record)
{
    int code;
    record->nstuck = record->nslipped = 0;
    code = gac_recheck_rest(s, record);
    if (code == 1 && s->sens != 0 && (record->nreleased > 0 || record->nslipped > 0))
        gac_sens_fixed_release(s);                               /* at a fixed time */
    if (code != 0) return code < 0 ? code : gac_report(s, record, GAC_SIM_CONTACT);
    return 0;
}

/* 1 if a resting contact's event value at s->x (its normal force; a stuck point's, its force less |lambda_T| / c_f)
 * is <= 0: a contact that pulls, or a stuck point beyond its cone. */
static int gac_pulling(const gac_sim *s)
{
    int a;
    for (a = 0; a < s->nresting; ++a) {
        if (s->ev[s->resting[a]] <= 0.0) return 1;
    }
    return 0;
}

/* The loop from s->t to t_end (no breakpoint inside): flight steps up to the next event. */
static int gac_advance_to(gac_sim *s, double t_end, const double *t_eval, int n_eval, int *i_eval,
                          double *x_eval, gac_impact_record *record)
{
    const gac_model *md;
    long steps = 0;
    double fac_max = 10.0;
    int i, rechecked = 0;
    long painleve = 0;                            /* rejections at the Painleve paradox in this stretch */
    md = s->model;
    if (s->pending) {                                        /* the contacts gac_sim_init puts at rest */
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
        record->nlanded = s->nresting;
        record->nreleased = record->nstuck = record->nslipped = 0;
        for (i = 0; i < s->nresting; ++i) {
            record->landed[i] = s->resting[i];
            if (s->is_stuck[s->resting[i]]) record->stuck[record->nstuck++] = s->resting[i];   /* (gac_rest_at_start) */
        }
        return gac_report(s, record, GAC_SIM_CONTACT);
    }
    if (s->input_changed) {
        const int code = gac_recheck(s, record);
        if (code != 0) return code;
    }
    if (s->t < t_end) {                           /* the budget and the progress callback, once per call ... */
        const int code = gac_look(s);
        if (code != GAC_OK) return code;
    }
    while (s->t < t_end) {
        double h, t1, t_event = 0.0, err = 0.0, vt_start[2 * GAC_AT_LEAST_1(md->ncontact)];
        int c_event = -1, last, sticking, stuck_report = 0, found;
        if (!s->f_valid) {
            gac_f(s, s->t, s->x, s->f);
            s->f_valid = 1;
        }
        if (s->fail == GAC_ERR_FRICTION && s->nresting > 0) {   /* sliding with no consistent forces here (the */
            const int code = gac_jam(s, record);                 /* start, a landing): the tangential impact, or */
            const int again = code == GAC_OK ? gac_recheck(s, record) : 0;   /* at zero speed the slip's */
            if (code != GAC_OK) return code;                     /* direction dropped and the resting contacts */
            if (again != 0) return again;                        /* re-checked */
            painleve = 0;
            continue;
        }
        if (s->fail) return s->fail;
        if (!rechecked && gac_pulling(s)) {       /* a transition (a landing, a stick) left a resting contact */
            const int again = gac_recheck(s, record);    /* pulling: released, or a stuck point slipped, before */
            rechecked = 1;                               /* a step integrates a pulling force (once a call: each */
            if (again != 0) return again;                /* transition returns to the caller) */
            continue;
        }
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
            if (s->nresting > 0) {              /* the steps shrank onto the dynamic jam, beyond which B is no */
                const long before = s->n_tangential_impacts;      /* P-matrix, if the tangential impact has a */
                const int code = gac_jam(s, record);              /* non-trivial solution here (at zero speed: */
                if (code == GAC_OK) {                             /* the slip's direction dropped, and on) */
                    const int again = gac_recheck(s, record);      /* the resting contacts re-checked */
                    s->fail_seen = 0;
                    s->h = s->opt.method == GAC_METHOD_RK4 ? s->opt.dt : 0.0;
                    if (again != 0) return again;
                    painleve = 0;
                    continue;
                }
                if (code != GAC_ERR_FRICTION || s->n_tangential_impacts != before) return code;
            }
            return s->fail_seen ? s->fail_seen : GAC_ERR_STEP_SIZE;
        }
        if (s->opt.method == GAC_METHOD_RK4) {
            /* RK4 has no error control: 3 steps in a row at h rho > 2.5, or one far past it, mean the step is
             * beyond its stability */
            const double h_rho = s->rk4_h_rho = gac_rk4_step(s, h);
            if (s->fail == GAC_ERR_FRICTION && s->nresting > 0) {   /* a stage beyond the jam: halve the step */
                if (++painleve >= GAC_PAINLEVE_STALL) return GAC_ERR_PAINLEVE_STALL;
                s->fail_seen = s->fail;                            /* onto it (restored after the impact) */
                s->fail = 0;
                s->n_rejected++;
                s->h = 0.5 * h;
                steps++;
                continue;
            }
            s->fail_seen = 0;
            s->n_unstable = h_rho > 2.5 ? s->n_unstable + 1 : 0;
            if ((s->n_unstable >= 3 || !(h_rho < 10.0)) && h >= s->opt.dt)   /* (halved steps: onto a jam, where */
                return GAC_ERR_UNSTABLE;                                     /* the normal force grows unbounded) */
        } else {
            double fac;
            const int eighth = s->opt.method == GAC_METHOD_DOP853;
            err = eighth ? gac_dop853_step(s, h) : gac_dopri5_step(s, h);
            if (s->fail == GAC_ERR_BAD_INPUT) return s->fail;
            if (s->fail) {                  /* a trial stage the constraints cannot hold: reject and shrink */
                if (s->fail == GAC_ERR_FRICTION && s->nresting > 0 && ++painleve >= GAC_PAINLEVE_STALL)
                    return GAC_ERR_PAINLEVE_STALL;
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
        if (md->chart.theta0_index >= 0                 /* a fixed theta_0 (a planar base): a constant measure */
            && (gac_can_switch(s) ? gac_step_near_lock(s) /* below the chart's floor at the step's end, or past */
                                  : gac_chart_measure(md, s->x1) < gac_chart_floor(s))) {   /* its lock */
            if (!gac_can_switch(s)) {
                if (gac_chart_measure(md, s->x1) < gac_chart_floor(s)) return GAC_ERR_GIMBAL_LOCK;
            } else if (s->opt.method != GAC_METHOD_RK4) {  /* retry shorter: the switch comes at a step's end */
                s->n_rejected++;
                s->h = 0.25 * h;
                fac_max = 1.0;
                steps++;
                continue;
            } else {                                       /* RK4: continue on the other chart from the step's start */
                const int code = gac_switch_chart(s, gac_step_near_lock(s));
                if (code != GAC_OK) return code;
                md = s->model;
                steps++;
                continue;
            }
        }
        steps++;
        s->n_steps++;
        if (s->nresting > 0 && gac_slow_sliding(s, s->x)) {     /* (only resting points slide) */
            s->n_slow_sliding++;
            s->t_slow_sliding += h;
        }
        if (s->fail) return s->fail;
        if (!gac_finite(s->x1, md->nx)) return GAC_ERR_NONFINITE;
        t1 = last ? t_end : s->t + h;
        gac_prepare_dense(s, h);
        found = gac_find_event(s, t1, &t_event, &c_event);
        if (s->fail == GAC_ERR_FRICTION && s->nresting > 0) {   /* the dense output passes where the resting forces */
            if (++painleve >= GAC_PAINLEVE_STALL) return GAC_ERR_PAINLEVE_STALL;   /* do not exist (the jam */
            s->fail_seen = s->fail;                              /* within the step): as a */
            s->fail = 0;                                         /* stage beyond it, reject and shrink onto it */
            s->n_steps--;
            s->n_rejected++;
            if (gac_slow_sliding(s, s->x)) {
                s->n_slow_sliding--;
                s->t_slow_sliding -= h;
            }
            s->h = 0.5 * h;
            fac_max = 1.0;
            continue;
        }
        if (found) {
            int code, released = s->is_resting[c_event], was_stuck[GAC_AT_LEAST_1(md->ncontact)];
            if (s->fail) return s->fail;
            gac_add_work(s, t_event);
            gac_emit(s, t_event, t_eval, n_eval, i_eval, x_eval);
            gac_dense(s, t_event, s->xs);
            if (s->sens != 0) gac_sens_flight(s, s->x, t_event - s->t, 0);   /* S at the event, before it */
            record->nstuck = record->nslipped = 0;
            if (released && s->is_stuck[c_event]) {   /* |lambda_T| reached c_f lambda: the point slips there */
                code = gac_slip(s, t_event, s->xs, c_event, record);
                if (code < 0) return code;
                if (code == 0 && s->sens != 0) gac_sens_stop(s, GAC_SENS_STICK, t_event, c_event);   /* (it leaves
                                                                                           the wall: not followed) */
            } else {
                code = 0;
            }
            if (code == 1) {                          /* the slip, with the others beyond their cones or pulling */
                gac_copy(s->x, s->xs, md->nx);        /* there, is reported (GAC_SIM_CONTACT) */
                s->t = t_event;
                s->f_valid = s->vn_valid = 0;
                code = gac_recheck_rest(s, record);
                if (code < 0) return code;
                if (s->fail) return s->fail;
                if (s->sens != 0) gac_sens_slip(s, record, c_event);   /* its event time's derivative */
                if (gac_energy_check(s, 0) != GAC_OK) return GAC_ERR_DRIFT;
                if (s->opt.method == GAC_METHOD_RK4) s->h = s->opt.dt;
                return gac_report(s, record, GAC_SIM_CONTACT);
            }
            if (!released && s->opt.stick) {          /* the stuck points before the impact (its transitions) */
                for (i = 0; i < md->ncontact; ++i) was_stuck[i] = s->is_stuck[i];
            }
            code = released ? gac_release(s, t_event, c_event, record)
                            : gac_resolve(s, t_event, c_event, record);
            if (code < 0) return code;
            if (s->sens != 0 && released) gac_sens_release(s, record, c_event);   /* its event time's derivative */
            for (i = 0; i < md->nx; ++i) s->x[i] = code == 1 ? s->x1[i] : s->xs[i];
            s->t = t_event;
            s->f_valid = s->vn_valid = 0;
            if (code == 1 && !released && s->opt.stick) {   /* after an impact every resting point re-decided */
                const int stuck = gac_restick(s, 1, was_stuck, record);
                if (stuck < 0) return stuck;
                if (stuck > 0) s->energy_x1_valid = 0;
            }
            if (s->sens != 0 && !released) {      /* the impact's jump (its stuck points decided), or a touch that
                                                     has no derivative */
                if (code == 1) gac_sens_impact(s, record, c_event, s->opt.stick ? was_stuck : 0);
                else gac_sens_stop(s, GAC_SENS_GRAZING, t_event, c_event);
            }
            gac_events(s, s->t, s->x, s->ev);
            if (s->fail == GAC_ERR_FRICTION && s->nresting > 0) {   /* landed sliding in the paradox: the tangential */
                s->fail = 0;                                        /* impact at the next loop's start */
                s->f_valid = 0;
            }
            if (s->fail) return s->fail;
            {                                     /* T and V after an impact: known from gac_resolve */
                const int known = code == 1 && !released && s->energy_x1_valid;
                const int check = gac_energy_check(s, known ? s->energy_x1 : 0);
                s->energy_x1_valid = 0;
                if (check != GAC_OK) return GAC_ERR_DRIFT;
            }
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
        if (s->nresting > 0 && gac_has_link(md, s->nresting, s->resting)   /* a held pair's other end down too */
            && gac_line_contact(md, s->x, s->x1, s->p, s->nresting, s->resting, 0.0) >= 0)
            return GAC_ERR_LINK_LINE;
        gac_add_work(s, t1);
        if (s->fail) return s->fail;
        gac_emit(s, t1, t_eval, n_eval, i_eval, x_eval);
        if (s->fail) return s->fail;
        sticking = s->opt.stick && s->nresting > 0 && gac_has_friction(md);
        if (sticking) gac_tangential_speeds(s, s->x, vt_start);   /* (a sign change within the step) */
        if (s->sens != 0) gac_sens_flight(s, s->x, h, 1);   /* the sensitivities over the same step, its stages */
        gac_copy(s->x, s->x1, md->nx);
        {
            const double *f_end = s->opt.method == GAC_METHOD_RK4 ? s->k[4]
                                : s->opt.method == GAC_METHOD_DOP853 ? s->k[12] : s->k[6];
            gac_copy(s->f, f_end, md->nx);
        }
        gac_copy(s->ev, s->eprev, md->ncontact);
        s->t = t1;
        if (s->nresting > 0) {                     /* back onto the resting-contact constraints */
            int code = gac_project(s, s->x, s->nresting, s->resting, 1);
            if (code != GAC_OK) return code;
            if (s->sens != 0) gac_sens_project(s, s->x1, s->x);   /* (s->x1: the step's end before it) */
            if (sticking) {                       /* sliding -> stuck: slow points that can stick (reported) */
                double x_before[md->nx], slip_before[2 * GAC_AT_LEAST_1(md->ncontact)];
                int stuck_before[GAC_AT_LEAST_1(md->ncontact)];
                gac_copy(x_before, s->x, md->nx);
                gac_copy(slip_before, s->slip, 2 * md->ncontact);
                for (i = 0; i < md->ncontact; ++i) stuck_before[i] = s->is_stuck[i];
                record->nstuck = record->nslipped = 0;
                code = gac_try_stick(s, vt_start, 1, 0, record);
                if (code < 0) return code;
                if (code > 0 && s->sens != 0) gac_sens_stick(s, x_before, stuck_before, slip_before, record);
                if (s->sens != 0) gac_sens_reslip(s, slip_before, code);   /* the slow points' slip directions */
                if (code > 0) {
                    gac_contact_record(s, s->t, x_before, record);
                    record->nlanded = record->nreleased = 0;
                    record->energy_after = gac_total_energy(md, s->x, s->p);
                    for (i = 0; i < md->nq; ++i) record->qd_after[i] = s->x[md->nq + i];
                    stuck_report = 1;
                }
            }
            s->f_valid = s->vn_valid = 0;
            gac_events(s, s->t, s->x, s->ev);
            if (s->fail == GAC_ERR_FRICTION) s->fail = 0;      /* (the next loop's start: the tangential impact) */
            if (s->fail) return s->fail;
        }
        {                                         /* T and V at x: known from the step's energy error unless projected */
            const int known = s->energy_x1_valid && s->nresting == 0;
            const int code = gac_energy_check(s, known ? s->energy_x1 : 0);
            s->energy_x1_valid = 0;
            if (code != GAC_OK) return code;
        }
        if (s->chart != 0) {                      /* chart A's angles followed step by step (near_a) */
            double x[md->nx];
            gac_copy(x, s->x, md->nx);
            gac_to_chart_a(s, x);
            if (s->fail) return s->fail;
        }
        if (stuck_report) {                       /* (in chart A's coordinates before a switch) */
            const int code = gac_report(s, record, GAC_SIM_CONTACT);
            if (code < 0) return code;
        }
        if (gac_wants_switch(s)) {                /* near chart A's lock, or far enough from it again */
            const int code = gac_switch_chart(s, gac_wants_switch(s));
            if (code != GAC_OK) return code;
            md = s->model;
        }
        if (stuck_report) return GAC_SIM_CONTACT; /* points came to stick at this step's end */
    }
    while (n_eval > 0 && *i_eval < n_eval && t_eval[*i_eval] <= t_end) {   /* samples at t_end itself */
        double *out = x_eval + (long)(*i_eval) * md->nx;
        gac_copy(out, s->x, md->nx);
        gac_to_chart_a(s, out);
        if (s->sens != 0 && s->sens->S_eval != 0) {
            double *S = s->sens->S_eval + (long)(*i_eval) * s->sens->k * md->nx;
            gac_copy(S, s->sens->S, s->sens->k * md->nx);
            gac_sens_to_chart_a(s, s->x, out, S);
        }
        ++*i_eval;
    }
    return s->fail ? s->fail : GAC_SIM_END;
}

int gac_sim_run(gac_sim *s, double t_end, gac_impact_record *record, gac_run_summary *summary)
{
    int code;
    if (s == 0 || record == 0 || summary == 0) return GAC_ERR_NULL_ARGUMENT;
    summary->n_impacts = summary->n_contact_events = 0;
    summary->t_first_impact = -1.0;
    summary->loss_impacts = 0.0;
    for (;;) {
        code = gac_sim_advance(s, t_end, 0, 0, 0, 0, record);
        if (code == GAC_SIM_CONTACT) {
            summary->n_contact_events++;
            continue;
        }
        if (code != GAC_SIM_IMPACT) return code;
        if (summary->n_impacts == 0) summary->t_first_impact = record->t;
        summary->n_impacts++;
        summary->loss_impacts += record->energy_before - record->energy_after;
    }
}
