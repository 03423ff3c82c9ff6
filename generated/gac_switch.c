/*
 * gac_switch.c -- the loop's use of the two base charts (gac.h, "Base charts"): when to leave the chart it is on,
 * the switch itself, and everything reported in chart A's coordinates whichever chart is integrated.  The geometry
 * (rotations, angle extraction, the conversion of a state) is gac_chart.c's.
 */
#include "gac_internal.h"

#include <math.h>

/* 1 if the run may switch charts: opt.chart_switch > 0 and the model has a second chart. */
int gac_can_switch(const gac_sim *s)
{
    return s->opt.chart_switch > 0.0 && s->model_a->chart_b != 0;
}

/* Chart A's measure chi_A of the state x of the chart integrated now. */
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

/* 1 if the run should leave the chart it is on at its current state: chi_A below opt.chart_switch on A, above
 * twice that on B (the hysteresis keeps a motion near the threshold from switching at every step). */
int gac_wants_switch(const gac_sim *s)
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
int gac_step_near_lock(const gac_sim *s)
{
    const gac_model *md = s->model;
    if (!gac_finite(s->x1, md->nx)) return 0;
    return gac_chart_measure(md, s->x1) < gac_chart_floor(s)
           || (gac_signed_measure(md, s->x) > 0.0) != (gac_signed_measure(md, s->x1) > 0.0);
}

/* Continue on the other chart from the current state: x converted (gac_chart_convert; chart A's angles continued
 * from near_a, chart B's the principal ones), the integrator restarted (fresh first step, f invalid), the event
 * values evaluated again with the new chart's kernels. */
int gac_switch_chart(gac_sim *s)
{
    const gac_model *from = s->model, *to = s->chart == 0 ? s->model_a->chart_b : s->model_a;
    double x_from[from->nx];
    int i, code;
    gac_copy(x_from, s->x, from->nx);
    if (s->chart == 0) {
        for (i = 0; i < 3; ++i) s->near_a[i] = s->x[from->base.index[i]];
    }
    code = gac_chart_convert(&from->base, &to->base, from->nq, s->x, s->chart == 0 ? 0 : s->near_a, s->x);
    if (code != GAC_OK) return code;
    if (s->chart == 1) {
        for (i = 0; i < 3; ++i) s->near_a[i] = s->x[to->base.index[i]];
    }
    gac_sens_switch(s, from, to, x_from, s->x);         /* S carried through the conversion */
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
void gac_to_chart_a(gac_sim *s, double *x)
{
    const gac_model *md = s->model;
    int i;
    int code;
    if (s->chart == 0) return;
    code = gac_chart_convert(&md->base, &s->model_a->base, md->nq, x, s->near_a, x);
    if (code != GAC_OK) {                     /* never a silent state of the other chart: the run stops with it */
        if (s->fail == 0) s->fail = code;
        return;
    }
    for (i = 0; i < 3; ++i) s->near_a[i] = x[md->base.index[i]];
}

/* The impact record (q, qd_before, qd_after) in chart A's coordinates; returns code. */
int gac_report(gac_sim *s, gac_impact_record *record, int code)
{
    const int nq = s->model->nq;
    double x[2 * nq], y[2 * nq];
    if (s->sens != 0 && code == GAC_SIM_IMPACT && record->law == GAC_IMPACT_LAW_GDI_TANGENTIAL)
        gac_sens_stop(s, GAC_SENS_TANGENTIAL, record->t, record->ncontact > 0 ? record->contact[0] : -1);
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
    return s->fail < 0 ? s->fail : code;
}

