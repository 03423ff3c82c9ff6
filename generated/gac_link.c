/*
 * gac_link.c -- two links of the chain as capsules about their segments: the closest points of the two segments,
 * the gap between the capsules, the direction J^T n of a push between them along the normal, and Newton's law for
 * one such pair.  Everything comes from the joint points' positions and velocities (contact_points,
 * contact_velocities): a point at fraction s along link i moves with (1 - s) v_O_i + s v_O_i+1, the link being
 * rigid.  A link and a fixed obstacle (a sphere or a bar, a capsule about a fixed segment) are the same contact with
 * the second segment fixed in the box: its closest point does not move (in time; its geometry among the parameters
 * moves it along a direction dp of the sensitivities, gac_normal_tangent).
 */
#include "gac_internal.h"

#include <math.h>

#define GAC_LINK_REFINE_STEPS 4   /* refinement steps of a link pair law's velocities at most (each O(n) per contact) */

static double gac_dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static double gac_clamp01(double x)
{
    return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
}

/* The fraction along segment p0 + u d (|d|^2 = dd > 0) of its point nearest to x, and that distance's square. */
static double gac_foot(const double *p0, const double *d, double dd, const double *x, double *sq)
{
    double w[3], u;
    int k;
    for (k = 0; k < 3; ++k) w[k] = x[k] - p0[k];
    u = gac_clamp01(gac_dot3(w, d) / dd);
    for (k = 0; k < 3; ++k) w[k] -= u * d[k];
    *sq = gac_dot3(w, w);
    return u;
}

/* |a(s) - b(t)|^2 for a(s) = a0 + s d1, b(t) = b0 + t d2. */
static double gac_pair_sq(const double *a0, const double *d1, const double *b0, const double *d2, double s, double t)
{
    double w[3];
    int k;
    for (k = 0; k < 3; ++k) w[k] = a0[k] + s * d1[k] - b0[k] - t * d2[k];
    return gac_dot3(w, w);
}

/* The least distance of two segments is reached at the lines' stationary point where it lies inside both, or on
 * an edge of the unit square of (s, t): an end of one segment and its foot on the other.  Every candidate is a pair
 * of actual points, so the distance returned is never below the least, and the least is among them to round-off:
 * the stationary point s = n . (d2 x r) / |n|^2, t = n . (d1 x r) / |n|^2 (n = d1 x d2, r = a0 - b0; the Lagrange
 * identity's form of the normal equations, whose cross products keep the accuracy the dot-product form
 * (b f - c e) / (a e - b^2) loses to cancellation as the segments turn parallel) and the four ends' feet.  Where a
 * stretch of the overlap of b's shadow on a is closest (parallel segments: the distance is flat along it to within
 * GAC_PARALLEL_TIE of the lengths), the middle of that overlap is taken instead, its distance within the tie of
 * the least: a lying link's contact held at one point, not at whichever end round-off favours.  A tilt beyond the
 * tie makes the distance linear along the overlap, least at its nearer end, which is then the closest point. */
#define GAC_PARALLEL_TIE 1e-12

/* gac_segment_closest's pick, returning 1 where it took the middle of a flat overlap, else 0. */
static int gac_segment_pick(const double *a0, const double *a1, const double *b0, const double *b1, double *s_out,
                            double *t_out)
{
    double d1[3], d2[3], r[3], n[3], m[3], a, e, nn, sq, best, s = 0.0, t = 0.0, u, v;
    int k, end;
    for (k = 0; k < 3; ++k) {
        d1[k] = a1[k] - a0[k];
        d2[k] = b1[k] - b0[k];
        r[k] = a0[k] - b0[k];
    }
    a = gac_dot3(d1, d1);
    e = gac_dot3(d2, d2);
    if (a == 0.0 && e == 0.0) {                          /* two points */
        *s_out = *t_out = 0.0;
        return 0;
    }
    if (a == 0.0) {                                      /* segment a is a point: its foot on b */
        *s_out = 0.0;
        *t_out = gac_foot(b0, d2, e, a0, &sq);
        return 0;
    }
    if (e == 0.0) {                                      /* segment b is a point */
        *s_out = gac_foot(a0, d1, a, b0, &sq);
        *t_out = 0.0;
        return 0;
    }
    best = INFINITY;
    for (end = 0; end < 4; ++end) {                      /* a0, a1 on b; b0, b1 on a */
        if (end < 2) {
            u = (double)end;
            v = gac_foot(b0, d2, e, end == 0 ? a0 : a1, &sq);
        } else {
            v = (double)(end - 2);
            u = gac_foot(a0, d1, a, end == 2 ? b0 : b1, &sq);
        }
        if (sq < best) best = sq, s = u, t = v;
    }
    n[0] = d1[1] * d2[2] - d1[2] * d2[1];                /* the stationary point inside both, if any */
    n[1] = d1[2] * d2[0] - d1[0] * d2[2];
    n[2] = d1[0] * d2[1] - d1[1] * d2[0];
    nn = gac_dot3(n, n);
    if (nn > 0.0) {
        m[0] = d2[1] * r[2] - d2[2] * r[1], m[1] = d2[2] * r[0] - d2[0] * r[2], m[2] = d2[0] * r[1] - d2[1] * r[0];
        u = gac_dot3(n, m) / nn;
        m[0] = d1[1] * r[2] - d1[2] * r[1], m[1] = d1[2] * r[0] - d1[0] * r[2], m[2] = d1[0] * r[1] - d1[1] * r[0];
        v = gac_dot3(n, m) / nn;
        if (u > 0.0 && u < 1.0 && v > 0.0 && v < 1.0) {
            sq = gac_pair_sq(a0, d1, b0, d2, u, v);
            if (sq < best) best = sq, s = u, t = v;
        }
    }
    {                                                    /* a stretch closest: the middle of the overlap */
        const double c = gac_dot3(d1, r), b = gac_dot3(d1, d2);
        const double u0 = -c / a, u1 = (b - c) / a;
        const double lo = gac_clamp01(u0 < u1 ? u0 : u1), hi = gac_clamp01(u0 < u1 ? u1 : u0);
        const double dist = sqrt(best), tie = GAC_PARALLEL_TIE * (sqrt(a) + sqrt(e));
        double x[3], f[3], tt[3];
        int j, flat = (hi - lo) * sqrt(a) > 1e3 * tie;      /* an overlap of some length, not a crossing's foot */
        for (j = 0; flat && j < 3; ++j) {                /* the overlap's ends and middle within the tie */
            const double w = j == 0 ? lo : (j == 1 ? hi : 0.5 * (lo + hi));
            for (k = 0; k < 3; ++k) x[k] = a0[k] + w * d1[k];
            tt[j] = gac_foot(b0, d2, e, x, &sq);
            f[j] = sqrt(sq);
            flat = f[j] <= dist + tie;
        }
        *s_out = flat ? 0.5 * (lo + hi) : s;
        *t_out = flat ? tt[2] : t;
        return flat;
    }
}

void gac_segment_closest(const double *a0, const double *a1, const double *b0, const double *b1, double *s_out,
                         double *t_out)
{
    (void)gac_segment_pick(a0, a1, b0, b1, s_out, t_out);
}

/* The distance from x to segment p0 p1. */
static double gac_point_segment(const double *p0, const double *p1, const double *x)
{
    double d[3], sq;
    int k;
    for (k = 0; k < 3; ++k) d[k] = p1[k] - p0[k];
    if (!(gac_dot3(d, d) > 0.0)) {
        for (k = 0; k < 3; ++k) d[k] = x[k] - p0[k];
        return sqrt(gac_dot3(d, d));
    }
    (void)gac_foot(p0, d, gac_dot3(d, d), x, &sq);
    return sqrt(sq);
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

/* The part `end` of link i (GAC_END_*) as a segment a0-a1 of the joint points r: the link's, or one joint point
 * as a segment of no length. */
static void gac_part_segment(const double *r, int i, int end, const double **a0, const double **a1)
{
    *a0 = r + 3 * (end == GAC_END_FINISH ? i : i - 1);
    *a1 = end == GAC_END_LINK ? r + 3 * i : *a0;
}

/* A part's geometry with s along the whole link (0 or 1 for a joint point). */
static void gac_part_fraction(int end, double *geometry)
{
    if (end != GAC_END_LINK) geometry[1] = end == GAC_END_FINISH ? 1.0 : 0.0;
}

/* The contact of the part `end` of link i (GAC_END_*: its segment, or one joint point as a segment of no length)
 * and link j; s is the fraction along the whole link i (0 or 1 for a joint point). */
static int gac_link_part_gap(const gac_model *m, const double *r, int i, int j, int end, double radius,
                             double *geometry)
{
    const int npoint = m->npoint;
    const double *a0, *a1;
    if (i < 1 || j < 1 || i + 1 > npoint || j + 1 > npoint || i == j || !(radius >= 0.0)) return GAC_ERR_BAD_CONTACT;
    gac_part_segment(r, i, end, &a0, &a1);
    gac_segment_contact(a0, a1, r + 3 * (j - 1), r + 3 * j, radius, geometry);
    gac_part_fraction(end, geometry);
    return GAC_OK;
}

int gac_link_gap(const gac_model *m, const double *q, const double *p, int i, int j, double radius,
                 double *geometry)
{
    double r[3 * GAC_AT_LEAST_1(m->npoint)];
    m->contact_points(q, p, r);
    return gac_link_part_gap(m, r, i, j, GAC_END_LINK, radius, geometry);
}

/* The contact of the part `end` of link i (GAC_END_*: its segment, or one joint point as a segment of no length)
 * and obstacle o; s is the fraction along the whole link (0 or 1 for a joint point). */
static int gac_obstacle_part_gap(const gac_model *m, const double *r, const double *p, int i, int o, int end,
                                 double radius, double *geometry)
{
    const int npoint = m->npoint;
    double shape[GAC_OBSTACLE_NSHAPE];
    const double *a0, *a1;
    if (i < 1 || i + 1 > npoint || !(radius >= 0.0) || gac_obstacle_shape(m, p, o, shape) != GAC_OK)
        return GAC_ERR_BAD_CONTACT;
    gac_part_segment(r, i, end, &a0, &a1);
    if (!gac_obstacle_shape_contact(shape, a0, a1, radius, geometry))                     /* a box, a plane, */
        gac_segment_contact(a0, a1, shape + 1, shape + 4, radius + shape[7], geometry);   /* or a bar, a sphere */
    gac_part_fraction(end, geometry);
    return GAC_OK;
}

int gac_obstacle_gap(const gac_model *m, const double *q, const double *p, int i, int o, double radius,
                     double *geometry)
{
    double r[3 * GAC_AT_LEAST_1(m->npoint)];
    m->contact_points(q, p, r);
    return gac_obstacle_part_gap(m, r, p, i, o, GAC_END_LINK, radius, geometry);
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
    int lo = 0, hi = m->ncontact;                        /* the rowless contacts come last: the first of them */
    while (lo < hi) {
        const int mid = lo + (hi - lo) / 2;
        if (gac_rowless(m, mid)) hi = mid;
        else lo = mid + 1;
    }
    return lo;
}

int gac_has_link(const gac_model *m, int n, const int *list)
{
    int a;
    for (a = 0; a < n; ++a) {
        if (gac_rowless(m, list[a])) return 1;
    }
    return 0;
}

/* 1 if contact c is a link pair or an obstacle of finite extent (a sphere, a bar or a box; a plane is a half-space,
 * which no motion passes through with its gap positive on both sides). */
int gac_finite_contact(const gac_model *m, int c)
{
    const gac_contact *k = &m->contacts[c];
    if (k->kind == GAC_CONTACT_LINK) return 1;
    return k->kind == GAC_CONTACT_OBSTACLE && gac_obstacle_kind(m, k->coordinate) != GAC_OBSTACLE_PLANE;
}

/* The largest speed (m/s) of finite contact c's link points relative to the other side at state x: a point at
 * fraction s of link i moves with (1 - s) v_O_i + s v_O_i+1, no faster than the faster of the link's two joint
 * points, so the bound is max(|v_O_i|, |v_O_i+1|), plus the same for link j of a link pair (0 for an obstacle). */
double gac_finite_speed(const gac_model *m, const double *x, const double *p, int c)
{
    const gac_contact *k = &m->contacts[c];
    double vel[3 * GAC_AT_LEAST_1(m->npoint)], w = 0.0;
    int side, end;
    m->contact_velocities(x, x + m->nq, p, vel);
    for (side = 0; side < (k->kind == GAC_CONTACT_LINK ? 2 : 1); ++side) {
        const int link = side == 0 ? k->point : k->coordinate;
        double fastest = 0.0;
        for (end = 0; end < 2; ++end) {
            const double *v = vel + 3 * (link - 1 + end), speed = sqrt(gac_dot3(v, v));
            if (speed > fastest) fastest = speed;
        }
        w += fastest;
    }
    return w;
}

/* Contact c's geometry (a link pair or an obstacle) from the joint points r (npoint x 3, contact_points), and its
 * second link (0 for an obstacle: it does not move). */
static int gac_rowless_geometry_at(const gac_model *m, const double *r, const double *p, int c, double *geometry,
                                   int *second)
{
    const gac_contact *k = &m->contacts[c];
    const double radius = m->link_radius[c - gac_kernel_contacts(m)];
    if (k->kind == GAC_CONTACT_OBSTACLE) {
        *second = 0;
        return gac_obstacle_part_gap(m, r, p, k->point, k->coordinate, k->end, radius, geometry);
    }
    *second = k->coordinate;
    return gac_link_part_gap(m, r, k->point, k->coordinate, k->end, radius, geometry);
}

static int gac_rowless_geometry(const gac_model *m, const double *q, const double *p, int c, double *geometry,
                                int *second)
{
    double r[3 * GAC_AT_LEAST_1(m->npoint)];
    m->contact_points(q, p, r);
    return gac_rowless_geometry_at(m, r, p, c, geometry, second);
}

void gac_redundant_partners(const gac_model *m, int *partner)
{
    const int nk = gac_kernel_contacts(m);
    int c, e, a;
    for (c = 0; c < GAC_PARTNERS * m->ncontact; ++c) partner[c] = -1;
    for (c = nk; c < m->ncontact; ++c) {
        const gac_contact *k = &m->contacts[c];
        int *mine = partner + GAC_PARTNERS * c, n = 0;
        for (e = nk; e < m->ncontact && n < GAC_PARTNERS; ++e) {
            const gac_contact *f = &m->contacts[e];
            int joint;
            if (f->kind != k->kind || f->end == GAC_END_LINK) continue;
            joint = f->point + (f->end == GAC_END_FINISH);
            if (k->end != GAC_END_LINK) {                /* an end's: the other link's ends against a link ending at
                                                            this joint, [0] for O_j, [1] for O_j+1 */
                const int own = k->point + (k->end == GAC_END_FINISH);
                if (k->kind != GAC_CONTACT_LINK || (f->coordinate != own && f->coordinate + 1 != own)) continue;
                for (a = 0; a < 2; ++a) {
                    if (joint == k->coordinate + a && mine[a] < 0) mine[a] = e;
                }
                continue;
            }
            if (k->kind == GAC_CONTACT_OBSTACLE) {       /* a link's: its joint points on the same obstacle */
                if (f->coordinate != k->coordinate || (joint != k->point && joint != k->point + 1)) continue;
            } else if (!(f->coordinate == k->coordinate && (joint == k->point || joint == k->point + 1))
                       && !(f->coordinate == k->point && (joint == k->coordinate || joint == k->coordinate + 1))) {
                continue;                                /* a pair's: either link's joint points on the other */
            }
            mine[n++] = e;
        }
    }
}

double gac_redundant_depth(const gac_model *m, const int *partner, int c, const double *gaps, const double *geometry)
{
    const int nk = gac_kernel_contacts(m);
    const int *mine = partner + GAC_PARTNERS * c;
    double least = INFINITY;
    int a;
    if (c < nk) return INFINITY;
    if (m->contacts[c].end != GAC_END_LINK) {            /* an end against a link whose own end is nearest: that
                                                            end's contact against this link is no farther */
        const double t = geometry[GAC_LINK_NGEOMETRY * (c - nk) + 2];
        int e;
        if (t != 0.0 && t != 1.0) return INFINITY;
        e = mine[t == 1.0];
        if (e < 0) return INFINITY;
        {   /* nearest inside: that one is the contact; end to end (the same two points): the first of the two */
            const double t_other = geometry[GAC_LINK_NGEOMETRY * (e - nk) + 2];
            return (t_other != 0.0 && t_other != 1.0) || e < c ? -INFINITY : INFINITY;
        }
    }
    for (a = 0; a < GAC_PARTNERS && mine[a] >= 0; ++a) {
        if (gaps[mine[a]] < least) least = gaps[mine[a]];
    }
    return least - gaps[c];
}

int gac_contact_geometry(const gac_model *m, const double *q, const double *p, int c, double *geometry)
{
    int second;
    if (m == 0 || q == 0 || p == 0 || geometry == 0) return GAC_ERR_NULL_ARGUMENT;
    if (c < 0 || c >= m->ncontact || !gac_rowless(m, c)) return GAC_ERR_BAD_CONTACT;
    return gac_rowless_geometry(m, q, p, c, geometry, &second);
}

/* A held link pair, or a link held on a bar, touches at one point: an end of one segment on the other, the lines'
 * stationary point, or the middle of a flat overlap (gac_segment_pick).  Where the segments turn parallel the
 * other end comes down too: a line contact, which one point cannot hold (the single row keeps the held end on, the
 * other end passes through; like a block rocking onto its other corner, it needs a second contact).  Over a step
 * from x0 to x1, with the point held at x0: the held end's distance at x1 against the opposite end's (of the same
 * segment), or a held middle's against the least; returns the first contact of set[0..n-1] whose other end (or
 * least) came closer than the held point by more than tol (plus the parallel tie of the lengths), else -1. */
/* The signed distance of point x from the box `shape` (minus its depth inside). */
static double gac_box_point_distance(const double *shape, const double *x)
{
    double geometry[GAC_LINK_NGEOMETRY];
    (void)gac_obstacle_shape_contact(shape, x, x, 0.0, geometry);
    return geometry[0];
}

/* A link held on a box (the step from x0 to x1, the joint points r0, r1 at either end) that came to lie along it:
 * held on a face (at an end or, lying flat, at the middle of the stretch over it), an end came closer to the box
 * than the held point; held on an edge or a corner, the link's least distance from the box came below its
 * distance from that edge or corner (the nearest part moved to another edge, or down onto a face: the link
 * pivoted about the held one), by more than tol plus the parallel tie. */
static int gac_box_line_contact(const gac_model *m, const double *r0, const double *r1, const double *p,
                                const gac_contact *c, double tol)
{
    const double *A0 = r0 + 3 * (c->point - 1), *A1 = r0 + 3 * c->point;
    const double *B0 = r1 + 3 * (c->point - 1), *B1 = r1 + 3 * c->point;
    double shape[GAC_OBSTACLE_NSHAPE], geometry[GAC_LINK_NGEOMETRY], e0[3], e1[3], x[3], d[3], s, t, held;
    int k;
    if (gac_obstacle_shape(m, p, c->coordinate, shape) != GAC_OK) return 0;
    for (k = 0; k < 3; ++k) d[k] = B1[k] - B0[k];
    tol += GAC_PARALLEL_TIE * (sqrt(gac_dot3(d, d)) + shape[4] + shape[5] + shape[6]);
    if (gac_obstacle_feature(shape, A0, A1, e0, e1) != 0) {                  /* an edge or a corner */
        (void)gac_obstacle_shape_contact(shape, B0, B1, 0.0, geometry);      /* the least over the link, at x1 */
        gac_segment_closest(B0, B1, e0, e1, &s, &t);
        for (k = 0; k < 3; ++k) x[k] = B0[k] + s * d[k] - e0[k] - t * (e1[k] - e0[k]);
        return geometry[0] < sqrt(gac_dot3(x, x)) - tol;
    }
    (void)gac_obstacle_shape_contact(shape, A0, A1, 0.0, geometry);
    s = geometry[1];
    for (k = 0; k < 3; ++k) x[k] = B0[k] + s * d[k];
    held = gac_box_point_distance(shape, x);
    return (s != 0.0 && gac_box_point_distance(shape, B0) < held - tol)
           || (s != 1.0 && gac_box_point_distance(shape, B1) < held - tol);
}

int gac_line_contact(const gac_model *m, const double *x0, const double *x1, const double *p, int n, const int *set,
                     double tol)
{
    const int npoint = m->npoint;
    double r0[3 * GAC_AT_LEAST_1(npoint)], r1[3 * GAC_AT_LEAST_1(npoint)];
    int a, k, loaded = 0;
    for (a = 0; a < n; ++a) {
        const gac_contact *c = &m->contacts[set[a]];
        const double *A0, *A1, *B0, *B1, *seg[4];
        double s0, t0, s1, t1, x[3], d[3], reach, held, other, shape[GAC_OBSTACLE_NSHAPE];
        int flat, end;
        if (!gac_rowless(m, set[a]) || c->end != GAC_END_LINK) continue;   /* (a joint point's: a point, no line) */
        if (!loaded) {
            m->contact_points(x0, p, r0);
            m->contact_points(x1, p, r1);
            loaded = 1;
        }
        if (c->kind == GAC_CONTACT_OBSTACLE && !gac_obstacle_round(gac_obstacle_kind(m, c->coordinate))) {
            if (gac_obstacle_kind(m, c->coordinate) == GAC_OBSTACLE_BOX && gac_box_line_contact(m, r0, r1, p, c, tol))
                return set[a];
            continue;                                    /* (a plane's line: its joint points' contacts) */
        }
        for (end = 0; end < 2; ++end) {                  /* the two segments at x0 (end 0) and x1 (end 1) */
            const double *r = end == 0 ? r0 : r1;
            seg[2 * end] = r + 3 * (c->point - 1);
            seg[2 * end + 1] = r + 3 * c->point;
        }
        if (c->kind == GAC_CONTACT_OBSTACLE) {
            if (gac_obstacle_shape(m, p, c->coordinate, shape) != GAC_OK) continue;
            B0 = shape + 1, B1 = shape + 4;
        } else {
            B0 = r0 + 3 * (c->coordinate - 1), B1 = r0 + 3 * c->coordinate;
        }
        flat = gac_segment_pick(seg[0], seg[1], B0, B1, &s0, &t0);
        if (c->kind == GAC_CONTACT_LINK) B0 = r1 + 3 * (c->coordinate - 1), B1 = r1 + 3 * c->coordinate;
        A0 = seg[2], A1 = seg[3];
        for (k = 0; k < 3; ++k) d[k] = A1[k] - A0[k];
        reach = sqrt(gac_dot3(d, d));
        for (k = 0; k < 3; ++k) d[k] = B1[k] - B0[k];
        reach = tol + GAC_PARALLEL_TIE * (reach + sqrt(gac_dot3(d, d)));
        if (flat) {                                      /* the held middle against the least */
            (void)gac_segment_pick(A0, A1, B0, B1, &s1, &t1);
            for (k = 0; k < 3; ++k) x[k] = A0[k] + s0 * (A1[k] - A0[k]);
            held = gac_point_segment(B0, B1, x);
            for (k = 0; k < 3; ++k) x[k] = A0[k] + s1 * (A1[k] - A0[k]) - B0[k] - t1 * (B1[k] - B0[k]);
            if (sqrt(gac_dot3(x, x)) < held - reach) return set[a];
            continue;
        }
        if (s0 == 0.0 || s0 == 1.0) {                    /* an end of the link on the other segment */
            held = gac_point_segment(B0, B1, s0 == 0.0 ? A0 : A1);
            other = gac_point_segment(B0, B1, s0 == 0.0 ? A1 : A0);
            if (other < held - reach) return set[a];
        }
        if (t0 == 0.0 || t0 == 1.0) {                    /* an end of the other segment on the link */
            held = gac_point_segment(A0, A1, t0 == 0.0 ? B0 : B1);
            other = gac_point_segment(A0, A1, t0 == 0.0 ? B1 : B0);
            if (other < held - reach) return set[a];
        }
    }
    return -1;
}

void gac_contact_gaps_geometry(const gac_model *m, const double *q, const double *p, double *gaps, double *geometry)
{
    const int nk = gac_kernel_contacts(m);
    double r[3 * GAC_AT_LEAST_1(m->npoint)];
    int c, second;
    if (m->ncontact == 0) return;
    m->contact_gaps(q, p, gaps);                         /* walls and stops (the kernel's contacts) */
    if (nk == m->ncontact) return;
    m->contact_points(q, p, r);                          /* then each link pair and obstacle: distance less radius */
    for (c = nk; c < m->ncontact; ++c) {
        double *g = geometry + GAC_LINK_NGEOMETRY * (c - nk);
        gaps[c] = gac_rowless_geometry_at(m, r, p, c, g, &second) == GAC_OK ? g[0] : NAN;
    }
}

void gac_contact_gaps(const gac_model *m, const double *q, const double *p, double *gaps)
{
    double geometry[GAC_LINK_NGEOMETRY * GAC_AT_LEAST_1(m->ncontact)];
    gac_contact_gaps_geometry(m, q, p, gaps, geometry);
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

void gac_link_contact_rates(const gac_model *m, const double *q, const double *p, const double *vel, double *vn)
{
    const int nk = gac_kernel_contacts(m);
    double r[3 * GAC_AT_LEAST_1(m->npoint)], geometry[GAC_LINK_NGEOMETRY], size;
    int c, second;
    if (nk == m->ncontact) return;
    m->contact_points(q, p, r);                          /* the joint points once for every contact */
    for (c = nk; c < m->ncontact; ++c) {
        vn[c] = gac_rowless_geometry_at(m, r, p, c, geometry, &second) == GAC_OK
                ? gac_link_rate(vel, m->contacts[c].point, second, geometry, &size) : NAN;
    }
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

/* The velocities of a frictionless impact law whose contacts include a link pair refined against the momentum
 * balance r = I_f (qd+ - qd-) - sum_a F_a n_a (n_a = J^T n of each contact, gac_contact_direction), holding the
 * contacts' normal velocities as the law set them (a free step qd+ -= I_f^-1 r moves them along I_f's soft
 * directions): over the pushing contacts H (F > 0),
 *   qd+ += -I_f^-1 r + Y_H dF_H,  F_H += dF_H,  A_HH dF_H = N_H I_f^-1 r
 * (Y_H = I_f^-1 n_H and A_HH = N_H Y_H refined, gac_impact_system_refined; a row dependent on the others takes no
 * multiplier), while |qd+ . r| (r in long double with the model's long-double kernels) falls by half; a step that
 * would pull (F < 0) or not improve is not taken.  Only the law's own residual moves: gac_link_law_accuracy then
 * measures what is left. */
void gac_link_refine(const gac_model *m, const double *q, const double *p, int n, const int *list, double *F,
                     const double *qd, double *qd_plus, double *work)
{
    const int nq = m->nq;
    double *Y = GAC_WORK_Y(m, work), *A = GAC_WORK_A(m, work);
    double f[GAC_AT_LEAST_1(m->njrow)], n_a[GAC_AT_LEAST_1(nq)], r[GAC_AT_LEAST_1(nq)], dq[GAC_AT_LEAST_1(nq)];
    double scratch[2 * GAC_AT_LEAST_1(nq)], kept[GAC_AT_LEAST_1(nq)], kept_F[GAC_AT_LEAST_1(nq)];
    double dF[GAC_AT_LEAST_1(nq)], v_unused[GAC_AT_LEAST_1(nq)], e_unused[GAC_AT_LEAST_1(nq)];
    double previous = INFINITY;
    int set[GAC_AT_LEAST_1(nq)], pos[GAC_AT_LEAST_1(nq)], nh = 0, a, i, it;
    for (a = 0; a < n; ++a) {
        if (!(F[a] > 0.0)) continue;
        pos[nh] = a;
        set[nh++] = list[a];
    }
    if (nh == 0 || gac_impact_system_refined(m, q, qd, p, nh, set, work, v_unused, e_unused) != GAC_OK
        || gac_ldlt_drop(nh, A, 1e-13) < 0) return;
    for (it = 0; it <= GAC_LINK_REFINE_STEPS; ++it) {
        double balance;
        long double sum = 0.0L;
        for (i = 0; i < nq; ++i) r[i] = 0.0;
        for (a = 0; a < n; ++a) {                        /* g = sum_a F_a n_a, subtracted below */
            gac_contact_direction(m, q, p, list[a], f, n_a);
            for (i = 0; i < nq; ++i) r[i] += F[a] * n_a[i];
        }
        if (m->generalized_momentum_ld) {                /* r = I_f qd+ - I_f qd- - g in long double */
            long double hp[GAC_AT_LEAST_1(nq)], hm[GAC_AT_LEAST_1(nq)];
            m->generalized_momentum_ld(q, qd_plus, p, hp);
            m->generalized_momentum_ld(q, qd, p, hm);
            for (i = 0; i < nq; ++i) r[i] = (double)((hp[i] - hm[i]) - r[i]);
        } else {
            for (i = 0; i < nq; ++i) dq[i] = qd_plus[i] - qd[i];
            m->generalized_momentum(q, dq, p, scratch);
            for (i = 0; i < nq; ++i) r[i] = scratch[i] - r[i];
        }
        for (i = 0; i < nq; ++i) sum += (long double)qd_plus[i] * r[i];
        balance = fabs((double)sum);
        if (!(balance < previous)) {                     /* the last step did not improve: undo it */
            if (it > 0) {
                gac_copy(qd_plus, kept, nq);
                for (a = 0; a < nh; ++a) F[pos[a]] = kept_F[a];
            }
            return;
        }
        if (it == GAC_LINK_REFINE_STEPS || balance > 0.5 * previous) return;
        previous = balance;
        m->inertia_solve(q, r, p, dq);
        if (!gac_finite(dq, nq)) return;
        gac_refine_response(m, q, p, r, dq, scratch, scratch + nq);   /* dq = I_f^-1 r, refined */
        for (a = 0; a < nh; ++a) {                       /* N_H dq */
            double s = 0.0;
            gac_contact_direction(m, q, p, set[a], f, n_a);
            for (i = 0; i < nq; ++i) s += n_a[i] * dq[i];
            dF[a] = s;
        }
        gac_ldlt_solve(nh, A, dF);
        if (!gac_finite(dF, nh)) return;
        for (a = 0; a < nh; ++a) {
            if (F[pos[a]] + dF[a] < 0.0) return;         /* it would pull: keep the law's */
        }
        gac_copy(kept, qd_plus, nq);
        for (a = 0; a < nh; ++a) {
            kept_F[a] = F[pos[a]];
            F[pos[a]] += dF[a];
        }
        for (i = 0; i < nq; ++i) {
            double step = -dq[i];
            for (a = 0; a < nh; ++a) step += Y[(long)a * nq + i] * dF[a];
            qd_plus[i] += step;
        }
    }
}

/* The accuracy of an impact law whose contacts include a link pair (relative to T, the kinetic energy before):
 * the momentum balance r = I_f (qd+ - qd-) - g, g = sum_a (F_a n_a + Ft_a . t_a) (n_a = J^T n of each contact,
 * gac_contact_direction; t_a its tangential directions where it took a tangential impulse Ft (2 per contact): a
 * wall's J^T e_trow, a link pair's or an obstacle's J^T t1, J^T t2 of its frame), |qd+ . r| the energy a velocity
 * that balanced exactly would differ by, with what evaluating r resolves, and the energy identity's residual
 * |T+ - T- - 1/2 sum_a Lambda_a . (gamma-_a + gamma+_a)| over every direction.  With the model's long-double kernels
 * (as gac_impact_accuracy): r in long double (gac_momentum_balance_ld, g summed in long double) with its measured
 * floor, T+ - T- by energy_ld, plus eps sum_i |qd+_i| |g_i| for the directions n_a, t_a themselves, computed in
 * double from the contact's geometry (the law applied them as computed; the exact ones differ by that round-off);
 * without them in double, with the floor 4 (nq + 1) eps sum_i |qd+_i| (|(I_f (qd+ - qd-))_i| + |g_i|) + eps/2
 * sum_i |qd+_i| |(I_f qd+)_i|.  Nothing is refined here (the refinement of gac_impact_accuracy works in the
 * Jacobian's rows, which a link pair has none of; gac_link_refine refines a frictionless law's velocities before).
 * Ft may be NULL (no tangential impulses). */
double gac_link_law_accuracy(const gac_model *m, const double *q, const double *p, int n, const int *list,
                             const double *F, const double *Ft, const double *qd, const double *qd_plus, double T)
{
    const int nq = m->nq;
    double n_a[GAC_AT_LEAST_1(nq)], change[GAC_AT_LEAST_1(nq)], p_change[GAC_AT_LEAST_1(nq)];
    double p_plus[GAC_AT_LEAST_1(nq)], f[GAC_AT_LEAST_1(m->njrow)], E0[2], E1[2], balance_ld, floor_ld;
    long double g[GAC_AT_LEAST_1(nq)], balance = 0.0L, size = 0.0L, stored = 0.0L, work = 0.0L, given = 0.0L;
    int a, i, j;
    for (i = 0; i < nq; ++i) g[i] = 0.0L;
    for (a = 0; a < n; ++a) {
        const gac_contact *k = &m->contacts[list[a]];
        gac_contact_frame frame;
        int have_frame = 0;
        for (j = -1; j < 2; ++j) {                       /* the normal, then the two tangential directions */
            const double L = j < 0 ? F[a] : (Ft != 0 ? Ft[2 * a + j] : 0.0);
            long double vm = 0.0L, vp = 0.0L;
            if (j >= 0 && L == 0.0) continue;
            if (j < 0) {
                gac_contact_direction(m, q, p, list[a], f, n_a);
            } else if (gac_rowless(m, list[a])) {
                if (!have_frame && gac_rowless_frame(m, q, p, list[a], &frame) != GAC_OK) return INFINITY;
                have_frame = 1;
                (void)gac_frame_direction(m, q, p, &frame, j + 1, n_a);
            } else {
                int r;
                if (k->trow[j] < 0) return INFINITY;     /* an impulse along a direction the wall has no row of */
                for (r = 0; r < m->njrow; ++r) f[r] = 0.0;
                f[k->trow[j]] = 1.0;
                m->contact_generalized_force(q, f, p, n_a);
            }
            for (i = 0; i < nq; ++i) {
                g[i] += (long double)L * n_a[i];
                vm += (long double)n_a[i] * qd[i];
                vp += (long double)n_a[i] * qd_plus[i];
            }
            work += (long double)L * (vm + vp);
        }
    }
    for (i = 0; i < nq; ++i) given += fabsl((long double)qd_plus[i]) * fabsl(g[i]);
    if (m->energy_ld && gac_momentum_balance_ld(m, q, p, g, qd, qd_plus, &balance_ld, &floor_ld)) {
        long double L0[2], L1[2];
        m->energy_ld(q, qd, p, L0);
        m->energy_ld(q, qd_plus, p, L1);
        return (balance_ld + floor_ld + GAC_EPS * (double)given + fabs((double)((L1[0] - L0[0]) - 0.5L * work)))
               / (T > 0.0 ? T : 1e-300);
    }
    for (i = 0; i < nq; ++i) change[i] = qd_plus[i] - qd[i];
    m->generalized_momentum(q, change, p, p_change);
    m->generalized_momentum(q, qd_plus, p, p_plus);
    for (i = 0; i < nq; ++i) {
        balance += qd_plus[i] * ((long double)p_change[i] - g[i]);
        size += fabsl((long double)qd_plus[i]) * (fabs(p_change[i]) + fabsl(g[i]));
        stored += fabsl((long double)qd_plus[i]) * fabs(p_plus[i]);
    }
    m->energy(q, qd, p, E0);
    m->energy(q, qd_plus, p, E1);
    return (fabs((double)balance) + 4.0 * (nq + 1) * GAC_EPS * (double)size + 0.5 * GAC_EPS * (double)stored
            + fabs((double)(((long double)E1[0] - E0[0]) - 0.5L * work))) / (T > 0.0 ? T : 1e-300);
}

/* ---- the derivative of a link pair's or an obstacle's contact geometry (for the sensitivities' impact) ------ */

/* The Jacobians' own change, sum_k a . d(J_k)[dq, dp] at fixed s, t and direction a, for each of the naxis
 * directions axes[0..naxis-1] (a the normal n, or a frame's t1, t2): the row at fixed geometry (J^T a,
 * gac_link_direction) differentiated along (dq, dp), into out (naxis x nq).  Column k of the points' Jacobian is
 * contact_velocities(q, e_k), so its change is contact_velocities_tangent(q, e_k, dq, dqd = 0, dp): exact, one
 * tangent call per column.  A model without that kernel (a descriptor written by hand) gets the fourth-order central
 * difference 8 (g(h) - g(-h)) - (g(2h) - g(-2h)) over 12 h, h = 1e-3 of the direction's largest entry (truncation
 * ~h^4, round-off ~eps / h: ~1e-12 of the row's size). */
static void gac_link_row_change(const gac_model *m, const double *q, const double *p, int i, int j,
                                const double *geometry, int naxis, const double (*axes)[3], const double *dq,
                                const double *dp, double *out)
{
    const int nq = m->nq, np = m->nparam;
    double qh[GAC_AT_LEAST_1(nq)], ph[GAC_AT_LEAST_1(np)], g[GAC_AT_LEAST_1(nq)], size = 0.0, h;
    double along[3][GAC_LINK_NGEOMETRY];                 /* the geometry with each direction in n's place */
    static const double step[4] = {1.0, -1.0, 2.0, -2.0}, weight[4] = {8.0, -8.0, -1.0, 1.0};
    int k, l, a;
    for (a = 0; a < naxis; ++a) {
        for (k = 0; k < 3; ++k) along[a][k] = geometry[k], along[a][3 + k] = axes[a][k];
    }
    if (m->contact_velocities_tangent != 0) {
        double w[GAC_AT_LEAST_1(nq)], none[GAC_AT_LEAST_1(nq)], dvel[3 * GAC_AT_LEAST_1(m->npoint)], speed;
        for (k = 0; k < nq; ++k) w[k] = none[k] = 0.0;
        for (k = 0; k < nq; ++k) {                       /* a . dJ_k: the rate formula on the columns' change */
            w[k] = 1.0;
            m->contact_velocities_tangent(q, w, p, dq, none, dp, dvel);
            for (a = 0; a < naxis; ++a) out[(long)a * nq + k] = gac_link_rate(dvel, i, j, along[a], &speed);
            w[k] = 0.0;
        }
        return;
    }
    for (k = 0; k < nq; ++k) size = fabs(dq[k]) > size ? fabs(dq[k]) : size;
    for (k = 0; k < np; ++k) size = fabs(dp[k]) > size ? fabs(dp[k]) : size;
    for (k = 0; k < naxis * nq; ++k) out[k] = 0.0;
    if (!(size > 0.0)) return;
    h = 1e-3 / size;
    for (l = 0; l < 4; ++l) {
        for (k = 0; k < nq; ++k) qh[k] = q[k] + step[l] * h * dq[k];
        for (k = 0; k < np; ++k) ph[k] = p[k] + step[l] * h * dp[k];
        for (a = 0; a < naxis; ++a) {
            (void)gac_link_direction(m, qh, ph, i, j, along[a], g);
            for (k = 0; k < nq; ++k) out[(long)a * nq + k] += weight[l] * g[k];
        }
    }
    for (k = 0; k < naxis * nq; ++k) out[k] /= 12.0 * h;
}

/* The joint points' motion along (dq, dp): contact_points_tangent (exact).  A model without it: contact_velocities(q,
 * dq) (exact: the points' Jacobian applied to dq) and, where dp is not 0, the points' change with the parameters (a
 * link's length) by the fourth-order central difference of contact_points, as gac_link_row_change. */
static void gac_link_points_change(const gac_model *m, const double *q, const double *p, const double *dq,
                                   const double *dp, double *dr)
{
    const int np = m->nparam, n3 = 3 * m->npoint;
    double ph[GAC_AT_LEAST_1(np)], r[3 * GAC_AT_LEAST_1(m->npoint)], size = 0.0, h;
    static const double step[4] = {1.0, -1.0, 2.0, -2.0}, weight[4] = {8.0, -8.0, -1.0, 1.0};
    int k, l;
    if (m->contact_points_tangent != 0) {
        m->contact_points_tangent(q, p, dq, dp, dr);
        return;
    }
    m->contact_velocities(q, dq, p, dr);
    for (k = 0; k < np; ++k) size = fabs(dp[k]) > size ? fabs(dp[k]) : size;
    if (!(size > 0.0)) return;
    h = 1e-3 / size;
    for (l = 0; l < 4; ++l) {
        for (k = 0; k < np; ++k) ph[k] = p[k] + step[l] * h * dp[k];
        m->contact_points(q, ph, r);
        for (k = 0; k < n3; ++k) dr[k] += weight[l] * r[k] / (12.0 * h);
    }
}

/* With P = a0 + s d1 and Q = b0 + t d2 the closest points (d1 = a1 - a0, d2 = b1 - b0), D = P - Q = dist n:
 *   interior s:  d1 . D = 0,   interior t:  d2 . D = 0   (an end point: s or t fixed, ds or dt = 0),
 * differentiated with dP0 = (1 - s) da0 + s da1 and dQ0 = (1 - t) db0 + t db1 the points' material motion:
 *   a ds - b dt = -(dd1 . D + d1 . dD0),   b ds - e dt = -(dd2 . D + d2 . dD0),   dD0 = dP0 - dQ0,
 * a = d1 . d1, b = d1 . d2, e = d2 . d2 (both rows where both are interior, the one of the interior fraction where
 * one is); then dD = dD0 + ds d1 - dt d2, d gap = n . dD, dn = (I - n n^T) dD / dist, and the row g_k = n . J_k
 * (J_k = (1 - s) V_a0,k + s V_a1,k - (1 - t) V_b0,k - t V_b1,k, V the points' Jacobian columns) changes by
 *   dg_k = dn . J_k + n . (ds (V_a1,k - V_a0,k) - dt (V_b1,k - V_b0,k)) + n . dJ_k[dq, dp]
 * (the last term: gac_link_row_change; the points' motion: gac_link_points_change, both exact with the model's
 * tangents of contact_points and contact_velocities).  The box's edge or corner the gap is measured from
 * (gac_obstacle_feature) is a fixed segment or point as a bar's or a sphere's; across an edge (both fractions
 * interior, outside the box or reaching into it) n is the lines' common normal +-(d1 x d2) / |d1 x d2| and
 * dn = +-(I - n n^T)(dd1 x d2 + d1 x dd2) / |d1 x d2|, the same as above where dist > 0 and defined at dist <= 0;
 * a plane's or a box's face has a constant normal: the closest point is an end of the link (ds = 0; one inside,
 * the link lies parallel to the face and a whole stretch is closest: no derivative), so d gap = n . (dP0 - dQ),
 * dn = 0, dQ the face's plane's motion.
 * An obstacle's geometry among the parameters moves its side along dp (the second segment of the above, fixed in
 * the box otherwise): a bar's ends db0, db1 and a sphere's centre (db0 = db1) as a link's would, its radius R
 * lowering the gap by dR (n unchanged); a box's edge or corner by dc + R dy (each of its coordinates in the box's
 * frame +-h_k, dy_k = +-dh_k), a box's face by dQ = dc + dh_k n, a plane's by its point's motion
 * (gac_obstacle_feature_change).  The obstacle's J stays 0: its motion reaches the row through the closest point's
 * fraction s and the normal alone.  A box's rotation and a plane's normal are not directions (GAC_ERR_BAD_OPTION). */
static int gac_normal_tangent(const gac_model *m, const double *q, const double *p, int c, const double *dq,
                              const double *dp, int held, double *dgap, double *g, double *dg, double *gt,
                              double *dgt)
{
    const int nq = m != 0 ? m->nq : 0;
    double axes[3][3], daxes[3][3];
    int naxis;
    double geometry[GAC_LINK_NGEOMETRY], r[3 * GAC_AT_LEAST_1(m != 0 ? m->npoint : 1)];
    double dr[3 * GAC_AT_LEAST_1(m != 0 ? m->npoint : 1)], change[3 * GAC_AT_LEAST_1(nq)];
    double d1[3], d2[3], D[3], dd1[3], dd2[3], dD[3], dn[3], a, b, e, dist, s, t, ds = 0.0, dt = 0.0, along;
    double end0[3], end1[3], shape[GAC_OBSTACLE_NSHAPE], dshape[GAC_OBSTACLE_NSHAPE], dend0[3], dend1[3];
    double grow = 0.0;                                   /* a bar's or a sphere's radius' change */
    double turn[3] = {0.0, 0.0, 0.0}, offset[3] = {0.0, 0.0, 0.0};   /* a plane's normal turning, x - its point */
    const double *a0, *a1, *b0, *b1, *da0, *da1, *db0, *db1;
    int i, j, k, code, s_inside, t_inside, face = 0, edge = 0;
    if (m == 0 || q == 0 || p == 0 || dq == 0 || dp == 0 || dgap == 0 || g == 0 || dg == 0)
        return GAC_ERR_NULL_ARGUMENT;
    if (c < 0 || c >= m->ncontact || !gac_rowless(m, c)) return GAC_ERR_BAD_CONTACT;
    code = gac_rowless_geometry(m, q, p, c, geometry, &j);
    if (code != GAC_OK) return code;
    i = m->contacts[c].point;
    m->contact_points(q, p, r);
    gac_link_points_change(m, q, p, dq, dp, dr);
    a0 = r + 3 * (i - 1), a1 = r + 3 * i, da0 = dr + 3 * (i - 1), da1 = dr + 3 * i;
    s = geometry[1], t = geometry[2];
    if (j > 0) {
        b0 = r + 3 * (j - 1), b1 = r + 3 * j, db0 = dr + 3 * (j - 1), db1 = dr + 3 * j;
    } else {                                             /* a fixed obstacle: its segment moves with dp alone */
        const int o = m->contacts[c].coordinate;
        if (gac_obstacle_shape(m, p, o, shape) != GAC_OK || gac_obstacle_shape_change(m, dp, o, dshape) != GAC_OK)
            return GAC_ERR_BAD_CONTACT;
        if (!gac_obstacle_turn_admissible(m, p, dp, o)) return GAC_ERR_BAD_OPTION;   /* a box's rotation */
        b0 = shape + 1, b1 = shape + 4, db0 = dshape + 1, db1 = dshape + 4;   /* a bar's ends (a sphere's centre) */
        grow = dshape[7];
        if (!gac_obstacle_round((int)shape[0])) {        /* a box or a plane: the part the gap is measured from */
            double x[3], span = 0.0;
            const double *p0, *p1;                       /* the part measured: a joint point's contact, its point */
            int feature;
            gac_part_segment(r, i, m->contacts[c].end, &p0, &p1);
            feature = gac_obstacle_feature(shape, p0, p1, end0, end1);
            (void)gac_obstacle_feature_change(shape, dshape, p0, p1, geometry + 3, dend0, dend1);
            for (k = 0; k < 3; ++k) x[k] = (1.0 - s) * a0[k] + s * a1[k];
            face = feature == 0, edge = feature == 1, grow = 0.0;
            if ((int)shape[0] == GAC_OBSTACLE_PLANE) {   /* its normal turning about its point: dn, x - point */
                for (k = 0; k < 3; ++k) turn[k] = dshape[4 + k], offset[k] = x[k] - shape[1 + k];
            }
            b0 = face ? x : end0, b1 = face ? x : end1, t = 0.0;
            db0 = dend0, db1 = dend1;                    /* (a face: its plane's motion, at x) */
            for (k = 0; k < 3; ++k) span += (b1[k] - b0[k]) * (b1[k] - b0[k]);
            if (span > 0.0) {                            /* an edge: the foot of x on it */
                for (k = 0; k < 3; ++k) t += (x[k] - b0[k]) * (b1[k] - b0[k]) / span;
            }
        }
    }
    for (k = 0; k < 3; ++k) {
        d1[k] = a1[k] - a0[k], d2[k] = b1[k] - b0[k], dd1[k] = da1[k] - da0[k], dd2[k] = db1[k] - db0[k];
        D[k] = (1.0 - s) * a0[k] + s * a1[k] - (1.0 - t) * b0[k] - t * b1[k];
        dD[k] = (1.0 - s) * da0[k] + s * da1[k] - (1.0 - t) * db0[k] - t * db1[k];   /* dD0 for now */
    }
    dist = sqrt(gac_dot3(D, D));
    a = gac_dot3(d1, d1), b = gac_dot3(d1, d2), e = gac_dot3(d2, d2);
    s_inside = s > 0.0 && s < 1.0;
    t_inside = e > 0.0 && t > 0.0 && t < 1.0;
    if (face) {                                          /* a constant normal: the link's end moves along it */
        if (!(a > 0.0) || (s_inside && !held)) return GAC_ERR_LINK_CONTACT;   /* parallel: a stretch closest */
        along = gac_dot3(geometry + 3, dD) + gac_dot3(turn, offset);   /* d(n . (x - point)) */
        for (k = 0; k < 3; ++k) dn[k] = turn[k];
    } else if (edge && s_inside && t_inside && a * e - b * b > 1e-8 * a * e) {
        /* a box's edge across the link (outside it, or reaching in: D = gap n either way, of any sign or 0): the
           lines' common normal n = +-w / |w|, w = d1 x d2, turns by dn = +-(I - n n^T) dw / |w|, dw = dd1 x d2 +
           d1 x dd2, free of the distance's round-off where it is ~0 (a link held on the edge) */
        const double r1 = -(gac_dot3(dd1, D) + gac_dot3(d1, dD)), r2 = -(gac_dot3(dd2, D) + gac_dot3(d2, dD));
        const double det = b * b - a * e;
        double w[3], dw[3], len, side, ndw;
        ds = (b * r2 - e * r1) / det;
        dt = (a * r2 - b * r1) / det;
        for (k = 0; k < 3; ++k) {
            const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
            w[k] = d1[k1] * d2[k2] - d1[k2] * d2[k1];
            dw[k] = dd1[k1] * d2[k2] - dd1[k2] * d2[k1] + d1[k1] * dd2[k2] - d1[k2] * dd2[k1];
            dD[k] += ds * d1[k] - dt * d2[k];
        }
        len = sqrt(gac_dot3(w, w));
        side = gac_dot3(w, geometry + 3) < 0.0 ? -1.0 : 1.0;
        ndw = gac_dot3(geometry + 3, dw);
        along = gac_dot3(geometry + 3, dD);
        for (k = 0; k < 3; ++k) dn[k] = side * (dw[k] - ndw * geometry[3 + k]) / len;
    } else {
        if (!(dist > 0.0) || !(a > 0.0)) return GAC_ERR_LINK_CONTACT;   /* crossing axes: n has no derivative */
        {
            const double r1 = -(gac_dot3(dd1, D) + gac_dot3(d1, dD)), r2 = -(gac_dot3(dd2, D) + gac_dot3(d2, dD));
            if (s_inside && t_inside) {
                const double det = b * b - a * e;
                if (!(-det > 1e-8 * a * e)) {            /* parallel: a whole overlap is closest */
                    if (!held) return GAC_ERR_LINK_CONTACT;
                } else {
                    ds = (b * r2 - e * r1) / det;
                    dt = (a * r2 - b * r1) / det;
                }
            } else if (s_inside) {
                ds = r1 / a;
            } else if (t_inside) {
                dt = -r2 / e;
            }
        }
        for (k = 0; k < 3; ++k) dD[k] += ds * d1[k] - dt * d2[k];
        along = gac_dot3(geometry + 3, dD);
        for (k = 0; k < 3; ++k) dn[k] = (dD[k] - along * geometry[3 + k]) / dist;
    }
    *dgap = along - grow;
    naxis = 1;
    for (k = 0; k < 3; ++k) axes[0][k] = geometry[3 + k], daxes[0][k] = dn[k];
    if (dgt != 0) {                                      /* the frame's t1, t2 and their turning */
        gac_contact_frame frame;
        double u[3], du[3], len = 0.0, dd1n, d1n = gac_dot3(d1, geometry + 3), t1du;
        code = gac_rowless_frame(m, q, p, c, &frame);
        if (code != GAC_OK) return code;
        dd1n = gac_dot3(dd1, geometry + 3) + gac_dot3(d1, dn);
        for (k = 0; k < 3; ++k) {                        /* u = d1 - (d1 . n) n, as gac_rowless_frame */
            u[k] = d1[k] - d1n * geometry[3 + k];
            du[k] = dd1[k] - dd1n * geometry[3 + k] - d1n * dn[k];
            len += u[k] * u[k];
        }
        len = sqrt(len);
        if (!(len > 1e-6 * sqrt(a))) {                   /* a box axis X_b in link i's place: u = X_b - n_b n */
            int best = 0;
            for (k = 1; k < 3; ++k) best = fabs(geometry[3 + k]) < fabs(geometry[3 + best]) ? k : best;
            len = 0.0;
            for (k = 0; k < 3; ++k) {
                u[k] = (k == best ? 1.0 : 0.0) - geometry[3 + best] * geometry[3 + k];
                du[k] = -dn[best] * geometry[3 + k] - geometry[3 + best] * dn[k];
                len += u[k] * u[k];
            }
            len = sqrt(len);
        }
        t1du = gac_dot3(frame.axis[1], du);
        for (k = 0; k < 3; ++k) {                        /* dt1 = (I - t1 t1^T) du / |u|,  dt2 = dn x t1 + n x dt1 */
            axes[1][k] = frame.axis[1][k], axes[2][k] = frame.axis[2][k];
            daxes[1][k] = (du[k] - t1du * frame.axis[1][k]) / len;
        }
        for (k = 0; k < 3; ++k) {
            const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
            daxes[2][k] = dn[k1] * axes[1][k2] - dn[k2] * axes[1][k1]
                          + geometry[3 + k1] * daxes[1][k2] - geometry[3 + k2] * daxes[1][k1];
        }
        naxis = 3;
    }
    (void)gac_link_direction(m, q, p, i, j, geometry, g);
    for (k = 1; k < naxis; ++k) {
        double along_axis[GAC_LINK_NGEOMETRY];
        int x;
        for (x = 0; x < 3; ++x) along_axis[x] = geometry[x], along_axis[3 + x] = axes[k][x];
        (void)gac_link_direction(m, q, p, i, j, along_axis, gt + (long)(k - 1) * nq);
    }
    /* da . J_k + a . (dJ_k/ds ds + dJ_k/dt dt) for each direction a (n, and t1, t2), from the points' Jacobian
     * columns V_k (contact_velocities at e_k) */
    {
        double w[GAC_AT_LEAST_1(nq)], vel[3 * GAC_AT_LEAST_1(m->npoint)];
        for (k = 0; k < nq; ++k) w[k] = 0.0;
        for (k = 0; k < nq; ++k) {
            const double *va, *vb;
            int x, l;
            w[k] = 1.0;
            m->contact_velocities(q, w, p, vel);
            w[k] = 0.0;
            va = vel + 3 * (i - 1), vb = j > 0 ? vel + 3 * (j - 1) : 0;
            for (l = 0; l < naxis; ++l) {
                double value = 0.0;
                for (x = 0; x < 3; ++x) {
                    const double Jk = (1.0 - s) * va[x] + s * va[3 + x]
                                      - (vb != 0 ? (1.0 - t) * vb[x] + t * vb[3 + x] : 0.0);
                    const double dJk = ds * (va[3 + x] - va[x]) - (vb != 0 ? dt * (vb[3 + x] - vb[x]) : 0.0);
                    value += daxes[l][x] * Jk + axes[l][x] * dJk;
                }
                if (l == 0) dg[k] = value;
                else dgt[(long)(l - 1) * nq + k] = value;
            }
        }
    }
    gac_link_row_change(m, q, p, i, j, geometry, naxis, (const double (*)[3])axes, dq, dp, change);
    for (k = 0; k < nq; ++k) dg[k] += change[k];
    for (k = nq; k < naxis * nq; ++k) dgt[k - nq] += change[k];
    return GAC_OK;
}

int gac_contact_normal_tangent(const gac_model *m, const double *q, const double *p, int c, const double *dq,
                               const double *dp, double *dgap, double *g, double *dg)
{
    return gac_normal_tangent(m, q, p, c, dq, dp, 0, dgap, g, dg, 0, 0);
}

/* A held contact's bias b = dg(dq = qd) . qd: d/dt (g . qd) = g . qdd + b.  Where a whole stretch is closest (a link
 * lying parallel to a face or to another link) the contact's points are taken as fixed on the links (ds = dt = 0):
 * the stretch stays closest while the held rows keep it parallel. */
int gac_rowless_bias(const gac_model *m, const double *q, const double *qd, const double *p, int c, double *b)
{
    const int nq = m->nq;
    double zero_p[GAC_AT_LEAST_1(m->nparam)], g[GAC_AT_LEAST_1(nq)], dg[GAC_AT_LEAST_1(nq)], dgap, sum = 0.0;
    int i, code;
    for (i = 0; i < GAC_AT_LEAST_1(m->nparam); ++i) zero_p[i] = 0.0;
    code = gac_normal_tangent(m, q, p, c, qd, zero_p, 1, &dgap, g, dg, 0, 0);
    if (code != GAC_OK) return code;
    for (i = 0; i < nq; ++i) sum += dg[i] * qd[i];
    if (!isfinite(sum)) return GAC_ERR_LINK_CONTACT;
    *b = sum;
    return GAC_OK;
}

/* Held contact c's biases into b: rows = 1, the normal's (gac_rowless_bias); rows = 3, the normal's and the frame's
 * t1, t2 (gac_rowless_frame_bias). */
static int gac_rowless_row_biases(const gac_model *m, const double *q, const double *qd, const double *p, int c,
                                  int rows, double *b)
{
    return rows == 1 ? gac_rowless_bias(m, q, qd, p, c, b) : gac_rowless_frame_bias(m, q, qd, p, c, b);
}

/* Its rows' derivatives along v (nq) at fixed p, dg_k[v] (rows x nq), as the biases take them (held: a whole stretch
 * closest keeps its points on the links). */
static int gac_rowless_row_changes(const gac_model *m, const double *q, const double *p, int c, int rows,
                                   const double *v, double *dg)
{
    const int nq = m->nq;
    double zero_p[GAC_AT_LEAST_1(m->nparam)], g[3 * GAC_AT_LEAST_1(nq)], dgap;
    int i;
    for (i = 0; i < GAC_AT_LEAST_1(m->nparam); ++i) zero_p[i] = 0.0;
    return gac_normal_tangent(m, q, p, c, v, zero_p, 1, &dgap, g, dg, rows > 1 ? g + nq : 0, rows > 1 ? dg + nq : 0);
}

/* The derivatives of a held contact's row biases b_k(q, qd, p) = dg_k(qd) . qd (rows = 1: the normal's,
 * gac_rowless_bias; rows = 3: the normal's and the frame's tangents', gac_rowless_frame_bias) along (dq, dqd, dp),
 * into db (rows).  b_k is a quadratic form in qd, so along dqd it is dg_k(dqd) . qd + dg_k(qd) . dqd, exact (two row
 * tangents); its change with q and p at fixed qd (the gap's and the frame's third derivatives, which no kernel gives)
 * is the fourth-order central difference 8 (b(h) - b(-h)) - (b(2h) - b(-2h)) over 12 h of b at (q + h dq, qd,
 * p + h dp), h = 1e-3 over the largest entry of (dq, dp) (truncation ~h^4, round-off ~eps / h: ~1e-12 of b's size,
 * as gac_link_row_change's).  GAC_OK, or GAC_ERR_LINK_CONTACT where a row has no derivative at one of those points. */
int gac_rowless_bias_tangent(const gac_model *m, const double *q, const double *qd, const double *p, int c, int rows,
                             const double *dq, const double *dqd, const double *dp, double *db)
{
    const int nq = m->nq, np = m->nparam;
    double dg[3 * GAC_AT_LEAST_1(nq)], qh[GAC_AT_LEAST_1(nq)], ph[GAC_AT_LEAST_1(np)];
    double sum[3] = {0.0, 0.0, 0.0}, b[3], size = 0.0, h;
    static const double step[4] = {1.0, -1.0, 2.0, -2.0}, weight[4] = {8.0, -8.0, -1.0, 1.0};
    int i, k, l, code;
    code = gac_rowless_row_changes(m, q, p, c, rows, qd, dg);      /* dg_k(qd) . dqd */
    if (code != GAC_OK) return code;
    for (k = 0; k < rows; ++k) sum[k] += gac_dot(nq, dg + (long)k * nq, dqd);
    code = gac_rowless_row_changes(m, q, p, c, rows, dqd, dg);     /* dg_k(dqd) . qd */
    if (code != GAC_OK) return code;
    for (k = 0; k < rows; ++k) sum[k] += gac_dot(nq, dg + (long)k * nq, qd);
    for (i = 0; i < nq; ++i) size = fabs(dq[i]) > size ? fabs(dq[i]) : size;
    for (i = 0; i < np; ++i) size = fabs(dp[i]) > size ? fabs(dp[i]) : size;
    if (size > 0.0) {
        h = 1e-3 / size;
        for (l = 0; l < 4; ++l) {
            for (i = 0; i < nq; ++i) qh[i] = q[i] + step[l] * h * dq[i];
            for (i = 0; i < np; ++i) ph[i] = p[i] + step[l] * h * dp[i];
            code = gac_rowless_row_biases(m, qh, qd, ph, c, rows, b);
            if (code != GAC_OK) return code;
            for (k = 0; k < rows; ++k) sum[k] += weight[l] * b[k] / (12.0 * h);
        }
    }
    if (!gac_finite(sum, rows)) return GAC_ERR_LINK_CONTACT;
    for (k = 0; k < rows; ++k) db[k] = sum[k];
    return GAC_OK;
}

/* The biases of a held contact's three frame rows (n, t1, t2 of gac_rowless_frame), b[k] = dg_k(dq = qd) . qd with
 * g_k = J^T a_k: d/dt (g_k . qd) = g_k . qdd + b[k], the points taken as fixed on the links where a whole stretch is
 * closest (as gac_rowless_bias, whose b b[0] is).  GAC_OK, or GAC_ERR_LINK_CONTACT where the frame has no
 * derivative. */
int gac_rowless_frame_bias(const gac_model *m, const double *q, const double *qd, const double *p, int c, double *b)
{
    const int nq = m->nq;
    double zero_p[GAC_AT_LEAST_1(m->nparam)], g[GAC_AT_LEAST_1(nq)], dg[GAC_AT_LEAST_1(nq)], dgap;
    double gt[2 * GAC_AT_LEAST_1(nq)], dgt[2 * GAC_AT_LEAST_1(nq)], sum[3] = {0.0, 0.0, 0.0};
    int i, code;
    for (i = 0; i < GAC_AT_LEAST_1(m->nparam); ++i) zero_p[i] = 0.0;
    code = gac_normal_tangent(m, q, p, c, qd, zero_p, 1, &dgap, g, dg, gt, dgt);
    if (code != GAC_OK) return code;
    for (i = 0; i < nq; ++i) {
        sum[0] += dg[i] * qd[i];
        sum[1] += dgt[i] * qd[i];
        sum[2] += dgt[nq + i] * qd[i];
    }
    if (!gac_finite(sum, 3)) return GAC_ERR_LINK_CONTACT;
    for (i = 0; i < 3; ++i) b[i] = sum[i];
    return GAC_OK;
}

int gac_contact_frame_tangent(const gac_model *m, const double *q, const double *p, int c, const double *dq,
                              const double *dp, double *axes, double *g, double *dg)
{
    gac_contact_frame frame;
    double dgap;
    int code, k;
    if (m == 0 || q == 0 || p == 0 || dq == 0 || dp == 0 || axes == 0 || g == 0 || dg == 0)
        return GAC_ERR_NULL_ARGUMENT;
    if (c < 0 || c >= m->ncontact || !gac_rowless(m, c)) return GAC_ERR_BAD_CONTACT;
    code = gac_normal_tangent(m, q, p, c, dq, dp, 0, &dgap, g, dg, g + m->nq, dg + m->nq);
    if (code != GAC_OK) return code;
    code = gac_rowless_frame(m, q, p, c, &frame);
    if (code != GAC_OK) return code;
    for (k = 0; k < 9; ++k) axes[k] = frame.axis[k / 3][k % 3];
    return GAC_OK;
}

/* ---- a link pair's or an obstacle's contact frame (the frictional impact law's rows) -------------------------- */

/* Contact c's frame at q: the closest points' fractions s, t on its links i, j (j = 0: a fixed obstacle), the unit
 * normal n (from the obstacle's or link j's closest point to link i's) and two unit tangents.  t1 is link i's axis
 * d1 = O_(i+1) - O_i with its part along n removed, t1 = (d1 - (d1 . n) n) / |...|; where link i lies within 1e-6
 * of n (its end on a face, standing on it), the box axis X_k with the smallest |n_k| (the first of equals) in its
 * place; t2 = n x t1.  The frame is a right-handed orthonormal basis (n, t1, t2). */
int gac_rowless_frame(const gac_model *m, const double *q, const double *p, int c, gac_contact_frame *f)
{
    double geometry[GAC_LINK_NGEOMETRY], r[3 * GAC_AT_LEAST_1(m->npoint)], d[3], len = 0.0, along, *n, *t1, *t2;
    int k, code;
    code = gac_rowless_geometry(m, q, p, c, geometry, &f->j);
    if (code != GAC_OK) return code;
    f->i = m->contacts[c].point;
    f->s = geometry[1];
    f->t = geometry[2];
    n = f->axis[0], t1 = f->axis[1], t2 = f->axis[2];
    for (k = 0; k < 3; ++k) n[k] = geometry[3 + k];
    m->contact_points(q, p, r);
    for (k = 0; k < 3; ++k) d[k] = r[3 * f->i + k] - r[3 * (f->i - 1) + k];
    along = gac_dot3(d, n);
    for (k = 0; k < 3; ++k) t1[k] = d[k] - along * n[k], len += t1[k] * t1[k];
    len = sqrt(len);
    if (!(len > 1e-6 * sqrt(gac_dot3(d, d)))) {          /* the link along the normal: a box axis in its place */
        int best = 0;
        for (k = 1; k < 3; ++k) best = fabs(n[k]) < fabs(n[best]) ? k : best;
        for (k = 0; k < 3; ++k) t1[k] = (k == best ? 1.0 : 0.0) - n[best] * n[k];
        len = sqrt(gac_dot3(t1, t1));
    }
    for (k = 0; k < 3; ++k) t1[k] /= len;
    t2[0] = n[1] * t1[2] - n[2] * t1[1];
    t2[1] = n[2] * t1[0] - n[0] * t1[2];
    t2[2] = n[0] * t1[1] - n[1] * t1[0];
    return GAC_OK;
}

/* The rate of the closest points' relative velocity along the frame's axis k (0 the normal, 1 t1, 2 t2), from the
 * joint points' velocities vel (npoint x 3): axis . (v_P - v_Q), as gac_link_rate (k = 0 is gac_link_contact_rate);
 * *size the relative speed |v_P - v_Q|. */
double gac_frame_rate(const gac_contact_frame *f, const double *vel, int k, double *size)
{
    double geometry[GAC_LINK_NGEOMETRY];
    geometry[0] = 0.0, geometry[1] = f->s, geometry[2] = f->t;
    geometry[3] = f->axis[k][0], geometry[4] = f->axis[k][1], geometry[5] = f->axis[k][2];
    return gac_link_rate(vel, f->i, f->j, geometry, size);
}

/* g = J^T a (nq) for the frame's axis k: the generalised force of a unit push along it at the closest points (the
 * rate of the relative velocity along it at qd = e_k, column by column, as gac_link_direction).  Returns the size
 * of those columns, sqrt(sum_k |v_P - v_Q|^2 at e_k), for telling a direction no motion takes (g ~ 0). */
double gac_frame_direction(const gac_model *m, const double *q, const double *p, const gac_contact_frame *f, int k,
                           double *g)
{
    const int nq = m->nq;
    double w[GAC_AT_LEAST_1(nq)], vel[3 * GAC_AT_LEAST_1(m->npoint)], size, scale = 0.0;
    int i;
    for (i = 0; i < nq; ++i) w[i] = 0.0;
    for (i = 0; i < nq; ++i) {
        w[i] = 1.0;
        m->contact_velocities(q, w, p, vel);
        g[i] = gac_frame_rate(f, vel, k, &size);
        scale += size * size;
        w[i] = 0.0;
    }
    return sqrt(scale);
}
