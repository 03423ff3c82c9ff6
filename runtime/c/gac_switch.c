/*
 * gac_switch.c -- the loop's use of the base charts (gac.h, "Base charts"): when to leave the chart it is on, the
 * switch itself, and everything reported in chart A's coordinates whichever chart is integrated.  A model of several
 * chains may turn several bases in 3D (gac_model.nbase): each is switched on its own, and sim.chart holds which are
 * on their chart B (bit j for base j).  The geometry (rotations, angle extraction, the conversion of a state) is
 * gac_chart.c's.
 */
#include "gac_internal.h"

#include <math.h>

/* near_a holds three angles per base a model may switch */
typedef char gac_near_a_fits[sizeof(((gac_sim *)0)->near_a) == 3 * GAC_CHART_BASES_MAX * sizeof(double) ? 1 : -1];

/* 1 if the run may switch charts: opt.chart_switch > 0 and the model has a second chart. */
int gac_can_switch(const gac_sim *s)
{
    return s->opt.chart_switch > 0.0 && s->model_a->chart_b != 0;
}

/* Base j's chart A measure chi_A at the state x of the chart integrated now. */
static double gac_measure_a(const gac_sim *s, int j, const double *x)
{
    const gac_base *base = gac_model_base(s->model, j);
    double angles[3], R[9];
    int i;
    if (!(s->chart >> j & 1)) return gac_chart_measure_of(gac_model_chart(s->model, j), x);
    for (i = 0; i < 3; ++i) angles[i] = x[base->index[i]];
    gac_base_rotation(base, angles, R);
    return gac_base_measure(gac_model_base(s->model_a, j), R);
}

/* The bases that should leave the chart they are on at the current state (bit j for base j; 0: none): chi_A below
 * opt.chart_switch on A, above twice that on B (the hysteresis keeps a motion near the threshold from switching at
 * every step).  Each base's rule looks at that base alone: one chain near chart A's lock goes on B while another
 * near chart B's lock stays on A. */
int gac_wants_switch(const gac_sim *s)
{
    int j, flip = 0;
    if (!gac_can_switch(s)) return 0;
    for (j = 0; j < gac_nbase(s->model_a); ++j) {
        const double mu_a = gac_measure_a(s, j, s->x);
        if ((s->chart >> j & 1) ? mu_a > 2.0 * s->opt.chart_switch : mu_a < s->opt.chart_switch) flip |= 1 << j;
    }
    return flip;
}

/* A chart's signed measure a . (e_z x Rz(theta_0) b) (gac_chart_measure_of without the absolute value): its sign
 * changes where theta_0 passes the lock. */
static double gac_signed_measure(const gac_chart *c, const double *q)
{
    const double *a = c->a, *b = c->b;
    const double theta0 = c->theta0_index >= 0 ? q[c->theta0_index] : c->theta0_value;
    const double cs = cos(theta0), sn = sin(theta0);
    return -a[0] * (sn * b[0] + cs * b[1]) + a[1] * (cs * b[0] - sn * b[1]);
}

/* The bases (bit j for base j; 0: none) whose step from s->x to s->x1 ends below the chart's floor or passes its
 * lock on the way. */
int gac_step_near_lock(const gac_sim *s)
{
    const gac_model *md = s->model;
    int j, near = 0;
    if (!gac_finite(s->x1, md->nx)) return 0;
    for (j = 0; j < gac_nbase(md); ++j) {
        const gac_chart *c = gac_model_chart(md, j);
        if (gac_chart_measure_of(c, s->x1) < gac_chart_floor(s)
            || (gac_signed_measure(c, s->x) > 0.0) != (gac_signed_measure(c, s->x1) > 0.0))
            near |= 1 << j;
    }
    return near;
}

/* Continue with the bases of `flip` (bit j for base j) on their other chart from the current state: x converted
 * base by base (gac_chart_convert; chart A's angles continued from near_a, chart B's the principal ones), the
 * integrator restarted (fresh first step, f invalid), the event values evaluated again with the new chart's
 * kernels. */
int gac_switch_chart(gac_sim *s, int flip)
{
    const gac_model *from = s->model, *to = gac_chart_model(s->model_a, s->chart ^ flip);
    double x_from[from->nx];
    int i, j, code;
    if (to == 0) return GAC_ERR_BAD_MODEL;
    gac_copy(x_from, s->x, from->nx);
    for (j = 0; j < gac_nbase(from); ++j) {
        const gac_base *b_from = gac_model_base(from, j), *b_to = gac_model_base(to, j);
        const int leaving_a = !(s->chart >> j & 1);
        double *near_a = s->near_a + 3 * j;
        if (!(flip >> j & 1)) continue;
        if (leaving_a) {
            for (i = 0; i < 3; ++i) near_a[i] = s->x[b_from->index[i]];
        }
        code = gac_chart_convert(b_from, b_to, from->nq, s->x, leaving_a ? 0 : near_a, s->x);
        if (code != GAC_OK) return code;
        if (!leaving_a) {
            for (i = 0; i < 3; ++i) near_a[i] = s->x[b_to->index[i]];
        }
        s->n_chart_switches++;
    }
    gac_sens_switch(s, from, to, flip, x_from, s->x);   /* S carried through the conversion */
    s->chart ^= flip;
    s->model = to;
    s->f_valid = s->vn_valid = 0;
    s->h = s->opt.method == GAC_METHOD_RK4 ? s->opt.dt : 0.0;
    s->n_unstable = 0;
    gac_events(s, s->t, s->x, s->ev);
    return s->fail < 0 ? s->fail : GAC_OK;
}

/* A state x (nx) of the chart integrated now in chart A's coordinates, into out (may be x): each base on its chart
 * B converted, its chart A angles continued from near_a.  GAC_OK or the conversion's error. */
int gac_state_chart_a(const gac_sim *s, const double *x, double *out)
{
    const gac_model *md = s->model;
    int j, code;
    if (out != x) gac_copy(out, x, md->nx);
    for (j = 0; j < gac_nbase(md); ++j) {
        if (!(s->chart >> j & 1)) continue;
        code = gac_chart_convert(gac_model_base(md, j), gac_model_base(s->model_a, j), md->nq, out, s->near_a + 3 * j,
                                 out);
        if (code != GAC_OK) return code;
    }
    return GAC_OK;
}

/* S (k x nx) at x on the chart model `from` carried to y (x converted) on `to`, the bases of `mask` (bit j for base
 * j) converted: the conversion is base by base, each on its own coordinates, so its derivative is too
 * (gac_chart_convert_tangent).  GAC_OK or the first conversion's error. */
int gac_tangent_between(const gac_model *from, const gac_model *to, int mask, const double *x, const double *y, int k,
                        double *S)
{
    int j, code;
    for (j = 0; j < gac_nbase(from); ++j) {
        if (!(mask >> j & 1)) continue;
        code = gac_chart_convert_tangent(gac_model_base(from, j), gac_model_base(to, j), from->nq, x, y, k, S);
        if (code != GAC_OK) return code;
    }
    return GAC_OK;
}

/* A state x (nx) of the chart integrated now, in chart A's coordinates, in place (near_a follows it). */
void gac_to_chart_a(gac_sim *s, double *x)
{
    const gac_model *md = s->model;
    int i, j;
    const int code = s->chart == 0 ? GAC_OK : gac_state_chart_a(s, x, x);
    if (code != GAC_OK) {                     /* never a silent state of the other chart: the run stops with it */
        if (s->fail == 0) s->fail = code;
        return;
    }
    for (j = 0; j < gac_nbase(md); ++j) {
        if (!(s->chart >> j & 1)) continue;
        for (i = 0; i < 3; ++i) s->near_a[3 * j + i] = x[gac_model_base(md, j)->index[i]];
    }
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
