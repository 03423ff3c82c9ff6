/*
 * gac_input.c -- input schedules: inputs given as values at breakpoints, held or interpolated, as a controller.
 */
#include "gac_internal.h"

/* The interval k of the schedule with t[k] <= t < t[k+1] (0 before t[0], n - 1 from t[n-1] on). */
static int gac_schedule_interval(const gac_schedule *s, double t)
{
    int lo = 0, hi = s->n - 1;
    if (t < s->t[0]) return 0;
    while (lo < hi) {                       /* the last k with t[k] <= t */
        const int mid = (lo + hi + 1) / 2;
        if (s->t[mid] <= t) lo = mid;
        else hi = mid - 1;
    }
    return lo;
}

void gac_schedule_input(double t, const double *q, const double *qd, double *u, void *schedule)
{
    const gac_schedule *s = (const gac_schedule *)schedule;
    const int k = gac_schedule_interval(s, t);
    const double *a = s->u + (long)k * s->nu;
    int i;
    (void)q;
    (void)qd;
    if (!s->linear || k == s->n - 1 || t <= s->t[0]) {
        for (i = 0; i < s->nu; ++i) u[i] = a[i];
        return;
    }
    {
        const double *b = a + s->nu;
        const double w = (t - s->t[k]) / (s->t[k + 1] - s->t[k]);
        for (i = 0; i < s->nu; ++i) u[i] = a[i] + w * (b[i] - a[i]);
    }
}

int gac_schedule_check(const gac_schedule *s)
{
    int k;
    if (s == 0 || s->t == 0 || s->u == 0) return GAC_ERR_NULL_ARGUMENT;
    if (s->n < 1 || s->nu < 0) return GAC_ERR_BAD_OPTION;
    for (k = 0; k < s->n; ++k) {
        int i;
        if (!(s->t[k] - s->t[k] == 0.0) || (k > 0 && !(s->t[k] > s->t[k - 1]))) return GAC_ERR_BAD_OPTION;
        for (i = 0; i < s->nu; ++i) {
            if (!(s->u[(long)k * s->nu + i] - s->u[(long)k * s->nu + i] == 0.0)) return GAC_ERR_BAD_INPUT;
        }
    }
    return GAC_OK;
}
