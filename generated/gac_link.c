/*
 * gac_link.c -- two links of the chain as capsules about their segments: the closest points of the two segments,
 * the gap between the capsules, the direction J^T n of a push between them along the normal, and Newton's law for
 * one such pair.  Everything comes from the joint points' positions and velocities (contact_points,
 * contact_velocities): a point at fraction s along link i moves with (1 - s) v_O_i + s v_O_i+1, the link being
 * rigid.  A link and a fixed obstacle (a sphere or a bar, a capsule about a fixed segment) are the same contact with
 * the second segment fixed in the box: its closest point does not move.
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

/* The contact geometry of segment a0-a1 (a link) and segment b0-b1 (another link or an obstacle), radii adding up to
 * radius: gap, s, t, n (from b's closest point to a's; across both axes when they cross). */
static void gac_segment_contact(const double *a0, const double *a1, const double *b0, const double *b1,
                                double radius, double *geometry)
{
    double d[3], dist, s, t;
    int k;
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
}

int gac_link_gap(const gac_model *m, const double *q, const double *p, int i, int j, double radius,
                 double *geometry)
{
    const int npoint = m->npoint;
    double r[3 * GAC_AT_LEAST_1(npoint)];
    if (i < 1 || j < 1 || i + 1 > npoint || j + 1 > npoint || i == j || !(radius >= 0.0)) return GAC_ERR_BAD_CONTACT;
    m->contact_points(q, p, r);
    gac_segment_contact(r + 3 * (i - 1), r + 3 * i, r + 3 * (j - 1), r + 3 * j, radius, geometry);
    return GAC_OK;
}

int gac_obstacle_gap(const gac_model *m, const double *q, const double *p, int i, int o, double radius,
                     double *geometry)
{
    const int npoint = m->npoint;
    double r[3 * GAC_AT_LEAST_1(npoint)];
    if (i < 1 || i + 1 > npoint || o < 0 || o >= m->nobstacle || m->obstacles == 0 || !(radius >= 0.0))
        return GAC_ERR_BAD_CONTACT;
    m->contact_points(q, p, r);
    if (gac_obstacle_shape_contact(m, o, r + 3 * (i - 1), r + 3 * i, radius, geometry)) return GAC_OK;  /* box, plane */
    gac_segment_contact(r + 3 * (i - 1), r + 3 * i, m->obstacles + 6 * o, m->obstacles + 6 * o + 3, radius,
                        geometry);
    return GAC_OK;
}

/* n . (v_P - v_Q): the rate of the gap of links i, j with closest points at fractions s, t and normal n, from the
 * joint points' velocities vel (npoint x 3); j = 0: a fixed obstacle (v_Q = 0); *size: |v_P - v_Q|. */
static double gac_link_rate(const double *vel, int i, int j, const double *geometry, double *size)
{
    const double s = geometry[1], t = geometry[2], *n = geometry + 3;
    const double *va = vel + 3 * (i - 1), *vb = j > 0 ? vel + 3 * (j - 1) : 0;
    double rate = 0.0, dv, sq = 0.0;
    int k;
    for (k = 0; k < 3; ++k) {
        dv = (1.0 - s) * va[k] + s * va[3 + k] - (vb != 0 ? (1.0 - t) * vb[k] + t * vb[3 + k] : 0.0);
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

/* ---- link pairs and obstacles as contacts of the loop (kinds GAC_CONTACT_LINK and GAC_CONTACT_OBSTACLE, after
 * the kernel's contacts) ---------------------------------------------------------------------------------------- */

int gac_rowless(const gac_model *m, int c)
{
    return m->contacts[c].kind == GAC_CONTACT_LINK || m->contacts[c].kind == GAC_CONTACT_OBSTACLE;
}

int gac_kernel_contacts(const gac_model *m)
{
    int n = m->ncontact;
    while (n > 0 && gac_rowless(m, n - 1)) --n;
    return n;
}

int gac_has_link(const gac_model *m, int n, const int *list)
{
    int a;
    for (a = 0; a < n; ++a) {
        if (gac_rowless(m, list[a])) return 1;
    }
    return 0;
}

/* Contact c's geometry (a link pair or an obstacle) and its second link (0 for an obstacle: it does not move). */
static int gac_rowless_geometry(const gac_model *m, const double *q, const double *p, int c, double *geometry,
                                int *second)
{
    const gac_contact *k = &m->contacts[c];
    const double radius = m->link_radius[c - gac_kernel_contacts(m)];
    if (k->kind == GAC_CONTACT_OBSTACLE) {
        *second = 0;
        return gac_obstacle_gap(m, q, p, k->point, k->coordinate, radius, geometry);
    }
    *second = k->coordinate;
    return gac_link_gap(m, q, p, k->point, k->coordinate, radius, geometry);
}

void gac_contact_gaps(const gac_model *m, const double *q, const double *p, double *gaps)
{
    const int nk = gac_kernel_contacts(m);
    double geometry[GAC_LINK_NGEOMETRY];
    int c, second;
    if (m->ncontact == 0) return;
    m->contact_gaps(q, p, gaps);                         /* walls and stops (the kernel's contacts) */
    for (c = nk; c < m->ncontact; ++c)                   /* then each link pair and obstacle: distance less radius */
        gaps[c] = gac_rowless_geometry(m, q, p, c, geometry, &second) == GAC_OK ? geometry[0] : NAN;
}

void gac_link_contact_direction(const gac_model *m, const double *q, const double *p, int c, double *g)
{
    double geometry[GAC_LINK_NGEOMETRY];
    int i, second;
    if (gac_rowless_geometry(m, q, p, c, geometry, &second) != GAC_OK) {
        for (i = 0; i < m->nq; ++i) g[i] = NAN;
        return;
    }
    (void)gac_link_direction(m, q, p, m->contacts[c].point, second, geometry, g);
}

double gac_link_contact_rate(const gac_model *m, const double *q, const double *p, int c, const double *vel)
{
    double geometry[GAC_LINK_NGEOMETRY], size;
    int second;
    if (gac_rowless_geometry(m, q, p, c, geometry, &second) != GAC_OK) return NAN;
    return gac_link_rate(vel, m->contacts[c].point, second, geometry, &size);
}

int gac_contact_normal(const gac_model *m, const double *q, const double *p, int c, double *g)
{
    double f[GAC_AT_LEAST_1(m->njrow)];
    int i;
    if (m == 0 || q == 0 || p == 0 || g == 0) return GAC_ERR_NULL_ARGUMENT;
    if (c < 0 || c >= m->ncontact) return GAC_ERR_BAD_CONTACT;
    gac_contact_direction(m, q, p, c, f, g);
    for (i = 0; i < m->nq; ++i) {
        if (!isfinite(g[i])) return GAC_ERR_BAD_CONTACT;
    }
    return GAC_OK;
}

/* The accuracy of an impact law whose contacts include a link pair (relative to T, the kinetic energy before):
 * the momentum balance r = I_f (qd+ - qd-) - sum_a F_a n_a (n_a = J^T n of each contact, gac_contact_direction),
 * |qd+ . r| the energy a velocity that balanced exactly would differ by, with what evaluating r resolves,
 *   4 (nq + 1) eps sum_i |qd+_i| (|(I_f (qd+ - qd-))_i| + |g_i|) + eps/2 sum_i |qd+_i| |(I_f qd+)_i|,
 * and the energy identity's residual |T+ - T- - 1/2 sum_a F_a (v-_a + v+_a)|.  Nothing is refined (the refinement
 * of gac_impact_accuracy works in the Jacobian's rows, which a link pair has none of). */
double gac_link_law_accuracy(const gac_model *m, const double *q, const double *p, int n, const int *list,
                             const double *F, const double *qd, const double *qd_plus, double T)
{
    const int nq = m->nq;
    double g[GAC_AT_LEAST_1(nq)], n_a[GAC_AT_LEAST_1(nq)], change[GAC_AT_LEAST_1(nq)], p_change[GAC_AT_LEAST_1(nq)];
    double p_plus[GAC_AT_LEAST_1(nq)], f[GAC_AT_LEAST_1(m->njrow)], E0[2], E1[2];
    long double balance = 0.0L, size = 0.0L, stored = 0.0L, work = 0.0L;
    int a, i;
    for (i = 0; i < nq; ++i) g[i] = 0.0;
    for (a = 0; a < n; ++a) {
        long double vm = 0.0L, vp = 0.0L;
        gac_contact_direction(m, q, p, list[a], f, n_a);
        for (i = 0; i < nq; ++i) {
            g[i] += F[a] * n_a[i];
            vm += (long double)n_a[i] * qd[i];
            vp += (long double)n_a[i] * qd_plus[i];
        }
        work += (long double)F[a] * (vm + vp);
    }
    for (i = 0; i < nq; ++i) change[i] = qd_plus[i] - qd[i];
    m->generalized_momentum(q, change, p, p_change);
    m->generalized_momentum(q, qd_plus, p, p_plus);
    for (i = 0; i < nq; ++i) {
        balance += qd_plus[i] * ((long double)p_change[i] - g[i]);
        size += fabsl((long double)qd_plus[i]) * (fabs(p_change[i]) + fabs(g[i]));
        stored += fabsl((long double)qd_plus[i]) * fabs(p_plus[i]);
    }
    m->energy(q, qd, p, E0);
    m->energy(q, qd_plus, p, E1);
    return (fabs((double)balance) + 4.0 * (nq + 1) * GAC_EPS * (double)size + 0.5 * GAC_EPS * (double)stored
            + fabs((double)(((long double)E1[0] - E0[0]) - 0.5L * work))) / (T > 0.0 ? T : 1e-300);
}
