/*
 * gac_link.c -- two links of the chain as capsules about their segments: the closest points of the two segments,
 * the gap between the capsules, the direction J^T n of a push between them along the normal, and Newton's law for
 * one such pair.  Everything comes from the joint points' positions and velocities (contact_points,
 * contact_velocities): a point at fraction s along link i moves with (1 - s) v_O_i + s v_O_i+1, the link being
 * rigid.
 */
#include "gac_internal.h"

#include <math.h>

static double gac_dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static double gac_clamp01(double x)
{
    return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
}

void gac_segment_closest(const double *a0, const double *a1, const double *b0, const double *b1, double *s_out,
                         double *t_out)
{
    double d1[3], d2[3], r[3], a, e, f, s = 0.0, t = 0.0;
    int k;
    for (k = 0; k < 3; ++k) {
        d1[k] = a1[k] - a0[k];
        d2[k] = b1[k] - b0[k];
        r[k] = a0[k] - b0[k];
    }
    a = gac_dot3(d1, d1);
    e = gac_dot3(d2, d2);
    f = gac_dot3(d2, r);
    if (a == 0.0 && e == 0.0) {                          /* two points */
        s = t = 0.0;
    } else if (a == 0.0) {                               /* segment a is a point: its projection onto b */
        t = gac_clamp01(f / e);
    } else {
        const double c = gac_dot3(d1, r);
        if (e == 0.0) {                                  /* segment b is a point */
            s = gac_clamp01(-c / a);
        } else {
            const double b = gac_dot3(d1, d2), denom = a * e - b * b;
            if (denom > 1e-14 * a * e) {                 /* not parallel: the lines' closest point, clamped */
                s = gac_clamp01((b * f - c * e) / denom);
            } else {                                     /* parallel: the middle of the overlap of b's shadow on a */
                const double u0 = -c / a, u1 = (b - c) / a;
                const double lo = gac_clamp01(u0 < u1 ? u0 : u1), hi = gac_clamp01(u0 < u1 ? u1 : u0);
                s = 0.5 * (lo + hi);
            }
            t = (b * s + f) / e;                         /* b's closest point to a(s), then a's to b(t) if clamped */
            if (t < 0.0) {
                t = 0.0;
                s = gac_clamp01(-c / a);
            } else if (t > 1.0) {
                t = 1.0;
                s = gac_clamp01((b - c) / a);
            }
        }
    }
    *s_out = s;
    *t_out = t;
}

int gac_link_gap(const gac_model *m, const double *q, const double *p, int i, int j, double radius,
                 double *geometry)
{
    const int npoint = m->npoint;
    double r[3 * GAC_AT_LEAST_1(npoint)], d[3], dist, s, t;
    const double *a0, *a1, *b0, *b1;
    int k;
    if (i < 1 || j < 1 || i + 1 > npoint || j + 1 > npoint || i == j || !(radius >= 0.0)) return GAC_ERR_BAD_CONTACT;
    m->contact_points(q, p, r);
    a0 = r + 3 * (i - 1), a1 = a0 + 3, b0 = r + 3 * (j - 1), b1 = b0 + 3;
    gac_segment_closest(a0, a1, b0, b1, &s, &t);
    for (k = 0; k < 3; ++k) d[k] = (1.0 - s) * a0[k] + s * a1[k] - (1.0 - t) * b0[k] - t * b1[k];
    dist = sqrt(gac_dot3(d, d));
    if (dist > 0.0) {
        for (k = 0; k < 3; ++k) d[k] /= dist;
    } else {                                             /* the axes cross: n across both of them (or any normal) */
        double u[3], w[3], len;
        for (k = 0; k < 3; ++k) u[k] = a1[k] - a0[k], w[k] = b1[k] - b0[k];
        d[0] = u[1] * w[2] - u[2] * w[1];
        d[1] = u[2] * w[0] - u[0] * w[2];
        d[2] = u[0] * w[1] - u[1] * w[0];
        len = sqrt(gac_dot3(d, d));
        if (!(len > 0.0)) {
            d[0] = u[1] - u[2], d[1] = u[2] - u[0], d[2] = u[0] - u[1];
            len = sqrt(gac_dot3(d, d));
            if (!(len > 0.0)) d[0] = 1.0, d[1] = d[2] = 0.0, len = 1.0;
        }
        for (k = 0; k < 3; ++k) d[k] /= len;
    }
    geometry[0] = dist - radius;
    geometry[1] = s;
    geometry[2] = t;
    for (k = 0; k < 3; ++k) geometry[3 + k] = d[k];
    return GAC_OK;
}

/* n . (v_P - v_Q): the rate of the gap of links i, j with closest points at fractions s, t and normal n, from the
 * joint points' velocities vel (npoint x 3); *size: |v_P - v_Q|. */
static double gac_link_rate(const double *vel, int i, int j, const double *geometry, double *size)
{
    const double s = geometry[1], t = geometry[2], *n = geometry + 3;
    const double *va = vel + 3 * (i - 1), *vb = vel + 3 * (j - 1);
    double rate = 0.0, dv, sq = 0.0;
    int k;
    for (k = 0; k < 3; ++k) {
        dv = (1.0 - s) * va[k] + s * va[3 + k] - (1.0 - t) * vb[k] - t * vb[3 + k];
        rate += n[k] * dv;
        sq += dv * dv;
    }
    *size = sqrt(sq);
    return rate;
}

double gac_link_direction(const gac_model *m, const double *q, const double *p, int i, int j,
                          const double *geometry, double *g)
{
    const int nq = m->nq;
    double w[GAC_AT_LEAST_1(nq)], vel[3 * GAC_AT_LEAST_1(m->npoint)], size, scale = 0.0;
    int k;
    for (k = 0; k < nq; ++k) w[k] = 0.0;
    for (k = 0; k < nq; ++k) {                           /* column k of the row: the rate at qd = e_k */
        w[k] = 1.0;
        m->contact_velocities(q, w, p, vel);
        g[k] = gac_link_rate(vel, i, j, geometry, &size);
        scale += size * size;
        w[k] = 0.0;
    }
    return sqrt(scale);
}

int gac_link_impact(const gac_model *m, const double *q, const double *qd, const double *p, int i, int j,
                    double radius, double e, double *qd_plus, double *impulse, double *v_normal)
{
    const int nq = m->nq;
    double geometry[GAC_LINK_NGEOMETRY], g[GAC_AT_LEAST_1(nq)], y[GAC_AT_LEAST_1(nq)], a = 0.0, size = 0.0, v = 0.0;
    double F, scale, norm = 0.0;
    int k, code;
    if (!(e >= 0.0 && e <= 1.0)) return GAC_ERR_BAD_OPTION;
    code = gac_link_gap(m, q, p, i, j, radius, geometry);
    if (code != GAC_OK) return code;
    scale = gac_link_direction(m, q, p, i, j, geometry, g);
    for (k = 0; k < nq; ++k) norm += g[k] * g[k];
    /* a push no motion of the chain takes (the row round-off against the relative velocities' own size): the
       closest points are the two ends of the link between i and j, and n runs along that rigid link */
    if (!(sqrt(norm) > 1e-10 * scale)) return GAC_ERR_SINGULAR_IMPACT;
    m->inertia_solve(q, g, p, y);
    for (k = 0; k < nq; ++k) {
        if (!isfinite(y[k])) return GAC_ERR_SINGULAR_MASS;
        a += g[k] * y[k];                                /* n I_f^-1 n^T */
        size += fabs(g[k] * y[k]);
        v += g[k] * qd[k];                               /* the normal velocity before */
    }
    if (!(a > 1e-10 * size)) return GAC_ERR_SINGULAR_IMPACT;   /* n I_f^-1 n^T round-off */
    F = v < 0.0 ? -(1.0 + e) * v / a : 0.0;              /* Newton (Eq. 47) on the relative normal velocity */
    for (k = 0; k < nq; ++k) qd_plus[k] = qd[k] + y[k] * F;
    *impulse = F;
    if (v_normal != 0) *v_normal = v;
    return GAC_OK;
}
