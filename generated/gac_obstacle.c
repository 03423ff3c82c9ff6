/*
 * gac_obstacle.c -- fixed obstacles bounded by planes: an oriented box and a half-space (a plane).  The gap of a
 * link (segment a-b, radius r) and such an obstacle is
 *     gap = min over s in [0, 1] of sd(a + s (b - a)) - r,
 * sd the obstacle's signed distance (negative inside), and its normal n is the gradient of sd at the closest point
 * a + s* (b - a): a face's normal inside the box or over a face, (p - closest) / |p - closest| outside it by an
 * edge or a corner.  sd is convex, so the minimum is that of a 1-D convex function; it is found exactly from its
 * piecewise structure (below), the gap then exact to round-off.  Spheres and capsules are in gac_link.c.
 *
 * A shape is GAC_OBSTACLE_NSHAPE doubles (m->obstacle_shapes): kind, then a box's centre c, half extents h and
 * rotation R (row-major, its columns the box's axes in the box frame: x = c + R y, y in the box's own frame), or a
 * plane's point and unit normal (or a bar's or sphere's ends and radius, for gac_link.c).  Every obstacle's geometry
 * may be runtime parameters (m->obstacle_params): gac_obstacle_shape gathers the row at the parameters p, and the
 * parameter check refuses what cannot be a shape (gac_rotation_admissible, gac_unit_admissible).
 */
#include "gac_internal.h"

#include <math.h>

/* two candidates whose sd differ by less than this (relative to the segment's and box's size) tie: a segment lying
   flat on a face (or parallel to a plane) touches along a stretch, whose middle is taken as the closest point */
#define GAC_OBST_TIE 1e-12
#define GAC_OBST_NCANDIDATE 96

int gac_obstacle_kind(const gac_model *m, int o)
{
    if (m->obstacle_shapes == 0) return GAC_OBSTACLE_SEGMENT;
    return (int)m->obstacle_shapes[GAC_OBSTACLE_NSHAPE * o];
}

int gac_obstacle_round(int kind)
{
    return kind == GAC_OBSTACLE_SEGMENT || kind == GAC_OBSTACLE_SPHERE;
}

int gac_obstacle_shape(const gac_model *m, const double *p, int o, double *shape)
{
    const double *row;
    int k, at;
    if (m == 0 || shape == 0) return GAC_ERR_NULL_ARGUMENT;
    if (o < 0 || o >= m->nobstacle || m->obstacle_shapes == 0) return GAC_ERR_BAD_CONTACT;
    row = m->obstacle_shapes + GAC_OBSTACLE_NSHAPE * o;
    for (k = 0; k < GAC_OBSTACLE_NSHAPE; ++k) shape[k] = row[k];
    at = m->obstacle_params != 0 ? m->obstacle_params[o] : -1;
    if (at < 0) return GAC_OK;                           /* the model's constants */
    if (p == 0) return GAC_ERR_NULL_ARGUMENT;
    switch ((int)row[0]) {
    case GAC_OBSTACLE_SPHERE:                            /* centre, radius: the segment's two ends the centre */
        for (k = 0; k < 3; ++k) shape[1 + k] = shape[4 + k] = p[at + k];
        shape[7] = p[at + 3];
        break;
    case GAC_OBSTACLE_SEGMENT: for (k = 0; k < 7; ++k) shape[1 + k] = p[at + k]; break;     /* a, b, radius */
    case GAC_OBSTACLE_BOX: for (k = 0; k < 15; ++k) shape[1 + k] = p[at + k]; break;        /* c, h, R */
    default: for (k = 0; k < 6; ++k) shape[1 + k] = p[at + k]; break;                       /* point, normal */
    }
    return GAC_OK;
}

int gac_obstacle_nparam(int kind)
{
    switch (kind) {
    case GAC_OBSTACLE_SPHERE: return 4;
    case GAC_OBSTACLE_SEGMENT: return 7;
    case GAC_OBSTACLE_BOX: return 15;
    case GAC_OBSTACLE_PLANE: return 6;
    default: return 0;
    }
}

int gac_obstacle_parameter(const gac_model *m, int index)
{
    int o;
    for (o = 0; m != 0 && m->obstacle_params != 0 && o < m->nobstacle; ++o) {
        const int at = m->obstacle_params[o];
        if (at >= 0 && index >= at && index < at + gac_obstacle_nparam(gac_obstacle_kind(m, o))) return o;
    }
    return -1;
}

int gac_obstacle_turn_admissible(const gac_model *m, const double *p, const double *dp, int o)
{
    const int kind = gac_obstacle_kind(m, o), at = m->obstacle_params != 0 ? m->obstacle_params[o] : -1;
    double n[3], dn[3], size = 0.0, along = 0.0;
    int k;
    if (at < 0 || (kind != GAC_OBSTACLE_BOX && kind != GAC_OBSTACLE_PLANE)) return 1;
    if (kind == GAC_OBSTACLE_BOX) {                      /* its rotation's entries: not a direction */
        for (k = 6; k < 15; ++k) {
            if (dp[at + k] != 0.0) return 0;
        }
        return 1;
    }
    for (k = 0; k < 3; ++k) {                            /* a plane's normal: turned, not stretched */
        n[k] = p[at + 3 + k], dn[k] = dp[at + 3 + k];
        size += dn[k] * dn[k], along += n[k] * dn[k];
    }
    return fabs(along) <= 1e-12 * sqrt(size);
}

int gac_obstacle_shape_change(const gac_model *m, const double *dp, int o, double *dshape)
{
    double row[GAC_OBSTACLE_NSHAPE];
    int k, used, code;
    if (m == 0 || dshape == 0) return GAC_ERR_NULL_ARGUMENT;
    if (o < 0 || o >= m->nobstacle || m->obstacle_shapes == 0) return GAC_ERR_BAD_CONTACT;
    for (k = 0; k < GAC_OBSTACLE_NSHAPE; ++k) dshape[k] = 0.0;
    dshape[0] = m->obstacle_shapes[GAC_OBSTACLE_NSHAPE * o];
    if (m->obstacle_params == 0 || m->obstacle_params[o] < 0) return GAC_OK;   /* constants: it does not move */
    code = gac_obstacle_shape(m, dp, o, row);            /* the same gathering, of dp (linear in it) */
    if (code != GAC_OK) return code;
    used = (int)row[0] == GAC_OBSTACLE_BOX ? 15 : ((int)row[0] == GAC_OBSTACLE_PLANE ? 6 : 7);
    for (k = 1; k <= used; ++k) dshape[k] = row[k];
    return GAC_OK;
}

int gac_rotation_admissible(const double *R)
{
    double det;
    int i, j, k;
    for (i = 0; i < 3; ++i) {                            /* R^T R = I */
        for (j = 0; j < 3; ++j) {
            double dot = 0.0;
            for (k = 0; k < 3; ++k) dot += R[3 * k + i] * R[3 * k + j];
            if (!(fabs(dot - (i == j ? 1.0 : 0.0)) <= 1e-9)) return 0;
        }
    }
    det = R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) + R[2] * (R[3] * R[7] - R[4] * R[6]);
    return fabs(det - 1.0) <= 1e-9;
}

int gac_unit_admissible(const double *n)
{
    return fabs(sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) - 1.0) <= 1e-9;
}

/* sd of the box at y (its own frame), and n_local, the gradient there (when n is not NULL) */
static double gac_obst_box_sd(const double *h, const double *y, double *n)
{
    double d[3], sq = 0.0, dist, best = -INFINITY;
    int k, face = 0;
    for (k = 0; k < 3; ++k) {
        d[k] = y[k] > h[k] ? y[k] - h[k] : (y[k] < -h[k] ? y[k] + h[k] : 0.0);
        sq += d[k] * d[k];
    }
    dist = sqrt(sq);
    if (dist > 0.0) {                                    /* outside: from the box's closest point */
        if (n != 0) for (k = 0; k < 3; ++k) n[k] = d[k] / dist;
        return dist;
    }
    for (k = 0; k < 3; ++k) {                            /* inside or on it: the nearest face */
        if (fabs(y[k]) - h[k] > best) best = fabs(y[k]) - h[k], face = k;
    }
    if (n != 0) {
        for (k = 0; k < 3; ++k) n[k] = 0.0;
        n[face] = y[face] < 0.0 ? -1.0 : 1.0;
    }
    return best;
}

static void gac_obst_add(double *list, int *count, double s)
{
    if (s > 0.0 && s < 1.0 && *count < GAC_OBST_NCANDIDATE) list[(*count)++] = s;
}

static void gac_obst_sort(double *list, int count)
{
    int i, j;
    for (i = 1; i < count; ++i) {
        const double x = list[i];
        for (j = i; j > 0 && list[j - 1] > x; --j) list[j] = list[j - 1];
        list[j] = x;
    }
}

/* The depth of a segment y(s) = y0 + s e (the box's frame) touching or reaching into the box (sd <= 0 somewhere
 * along it).  The set of the segment's translations t that make it meet the box is the box's Minkowski sum with the
 * reversed segment, a zonotope whose faces' normals are the 3 face normals E_k and the 3 directions u_k = e x E_k
 * across the segment and an edge (every pair of the generators E_1, E_2, E_3, e); the segment and the box are thus
 * separated along one of these axes, and along each they overlap by the distance of the segment's projection into
 * the box's [-sum_j h_j |u_j|, +same] (the separation, negative when they overlap).  The gap is the greatest
 * separation (minus the depth: the least translation that parts them), the signed distance of t = 0 from the
 * zonotope, 0 where they touch as the distance outside is, and its axis the normal n (from the box to the link):
 *   a face's, +-E_k: separation min_s (+-y_k(s)) - h_k, reached at the segment's end lowest along n (its gradient
 *     that end's motion along n); where the segment lies parallel to the face (|e_k| within tie) every point is, and
 *     *s is left as sd gives it (the middle of the stretch over the face);
 *   an edge's, +-u_k (by more than tie over every face: the segment across that edge): u . y(s) is the same for every
 *     s (u is normal to e), the separation u . y0 - sum_j h_j |u_j|, and its gradient is u . v at the segment's
 *     point nearest to the edge's line (where the two lines' common normal is u, so u's turning with e moves the
 *     separation by nothing), *s.
 * Returns the separation, its axis in n, 1 with the edge's axis in *axis (-1: a face's). */
static double gac_obst_box_depth(const double *h, const double *y0, const double *e, double tie, double *s,
                                 double *n, int *axis)
{
    double face = -INFINITY, edge = -INFINITY, best[3] = {0.0, 0.0, 0.0}, size = 0.0, end = -1.0;
    int k, j, which = 0;
    *axis = -1;
    for (k = 0; k < 3; ++k) size += e[k] * e[k];
    for (k = 0; k < 3; ++k) {                            /* the faces +E_k (lowest end) and -E_k (highest end) */
        const double lo = e[k] < 0.0 ? y0[k] + e[k] : y0[k], hi = e[k] < 0.0 ? y0[k] : y0[k] + e[k];
        if (lo - h[k] > face) face = lo - h[k], which = k + 1, end = e[k] < 0.0 ? 1.0 : 0.0;
        if (-h[k] - hi > face) face = -h[k] - hi, which = -(k + 1), end = e[k] < 0.0 ? 0.0 : 1.0;
    }
    for (k = 0; k < 3; ++k) {                            /* u_k = e x E_k */
        const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
        double u[3], len, r = 0.0, p0 = 0.0, p1 = 0.0, lo, hi;
        u[k] = 0.0, u[k1] = e[k2], u[k2] = -e[k1];
        len = sqrt(u[k1] * u[k1] + u[k2] * u[k2]);
        if (!(len > 1e-9 * sqrt(size))) continue;        /* the link along the edge: a face's axis */
        for (j = 0; j < 3; ++j) {
            u[j] /= len;
            r += h[j] * fabs(u[j]);
            p0 += u[j] * y0[j];
            p1 += u[j] * (y0[j] + e[j]);
        }
        lo = p0 < p1 ? p0 : p1, hi = p0 < p1 ? p1 : p0;
        if (lo - r > edge || -r - hi > edge) {
            const double sign = lo - r >= -r - hi ? 1.0 : -1.0;
            edge = sign > 0.0 ? lo - r : -r - hi, *axis = k;
            for (j = 0; j < 3; ++j) best[j] = sign * u[j];
        }
    }
    if (*axis < 0 || !(edge > face + tie)) {             /* a face's */
        k = (which > 0 ? which : -which) - 1;
        for (j = 0; j < 3; ++j) n[j] = 0.0;
        n[k] = which > 0 ? 1.0 : -1.0;
        if (fabs(e[k]) > tie) *s = end;
        *axis = -1;
        return face;
    }
    {                                                    /* the edge: y_j = h_j sign(n_j) off its axis */
        const int k1 = (*axis + 1) % 3, k2 = (*axis + 2) % 3;
        const double w1 = y0[k1] - (best[k1] < 0.0 ? -h[k1] : h[k1]), w2 = y0[k2] - (best[k2] < 0.0 ? -h[k2] : h[k2]);
        const double at = -(w1 * e[k1] + w2 * e[k2]) / (e[k1] * e[k1] + e[k2] * e[k2]);
        *s = at < 0.0 ? 0.0 : (at > 1.0 ? 1.0 : at);
    }
    for (k = 0; k < 3; ++k) n[k] = best[k];
    return edge;
}

/* Outside the box, the segment's closest point y* = y0 + s* e inside it (0 < s* < 1, its piece's vertex) by an
 * edge (two coordinates beyond their faces, k the one between): the closest points of the segment's line and the
 * edge's, whose difference is normal to both, so n = +-(e x E_k) / |e x E_k|, the sign the outward one
 * (sigma_j n_j >= 0 for the two coordinates beyond, on the sides sigma_j).  Equal to (y* - clamp(y*)) / |...| to
 * round-off, and free of its cancellation where the distance is of round-off size (a link held on the edge).
 * Returns 0 (n untouched) elsewhere. */
static int gac_obst_box_edge_normal(const double *h, const double *y, const double *e, double s, double *n)
{
    double u[3], len, out = 0.0;
    int k, j, beyond = 0, along = -1;
    if (!(s > 0.0 && s < 1.0)) return 0;
    for (k = 0; k < 3; ++k) {
        if (y[k] > h[k] || y[k] < -h[k]) ++beyond;
        else along = k;
    }
    if (beyond != 2) return 0;
    {
        const int k1 = (along + 1) % 3, k2 = (along + 2) % 3;
        u[along] = 0.0, u[k1] = e[k2], u[k2] = -e[k1];
        len = sqrt(u[k1] * u[k1] + u[k2] * u[k2]);
        if (!(len > 0.0)) return 0;
        out = (y[k1] > 0.0 ? u[k1] : -u[k1]) + (y[k2] > 0.0 ? u[k2] : -u[k2]);
    }
    for (j = 0; j < 3; ++j) n[j] = (out < 0.0 ? -u[j] : u[j]) / len;
    return 1;
}

/* Along y(s) = y0 + s e (the box's frame), sd is, between two consecutive breakpoints (where a coordinate crosses
 * a face's plane +-h_k or 0, or two faces' distances |y_k| - h_k cross), either outside sqrt of a quadratic in s,
 * least at its vertex or an end, or inside the maximum of linear functions, least at a breakpoint.  So the minimum
 * is at a breakpoint, an end or one of those vertices; every candidate's sd is evaluated at its point.  Where that
 * least is positive (beyond the tie) it is the distance (its gradient n at s*); where it is not, the segment touches
 * or reaches into the box, and the gap is the depth along its separating axis instead (gac_obst_box_depth), 0 with
 * the distance where they touch (within the tie the two differ by less than it, and the axis is a direction the
 * distance's gradient, from a difference of round-off size, cannot resolve).  Writes gap (without a radius), s*, 0
 * and n (the box's frame turned to the world's) into geometry, and returns the part of the box the gap is measured
 * from: 0 a face (a constant normal), 1 an edge, 2 a corner, the part's stretch in the box's frame in [lo, hi] (a
 * corner's lo = hi). */
static int gac_obst_box_solve(const double *shape, const double *a0, const double *a1, double *geometry, double *lo,
                              double *hi)
{
    const double *c = shape + 1, *h = shape + 4, *R = shape + 7;
    double y0[3], e[3], list[GAC_OBST_NCANDIDATE], f[GAC_OBST_NCANDIDATE], y[3], nl[3], best = INFINITY;
    double first = 1.0, last = 0.0, tie, size = 0.0, s;
    int count = 0, k, j, a, b, base, at = 0, feature = 0, vertex[GAC_OBST_NCANDIDATE] = {0};
    for (k = 0; k < 3; ++k) {                            /* y = R^T (x - c) */
        y0[k] = e[k] = 0.0;
        for (j = 0; j < 3; ++j) {
            y0[k] += R[3 * j + k] * (a0[j] - c[j]);
            e[k] += R[3 * j + k] * (a1[j] - a0[j]);
        }
        size += e[k] * e[k];
    }
    list[count++] = 0.0;
    list[count++] = 1.0;
    for (k = 0; k < 3; ++k) {
        if (e[k] == 0.0) continue;
        gac_obst_add(list, &count, (h[k] - y0[k]) / e[k]);
        gac_obst_add(list, &count, (-h[k] - y0[k]) / e[k]);
        gac_obst_add(list, &count, -y0[k] / e[k]);
    }
    for (k = 0; k < 3; ++k) {                            /* sa y_k - h_k = sb y_j - h_j */
        for (j = k + 1; j < 3; ++j) {
            for (a = -1; a <= 1; a += 2) {
                for (b = -1; b <= 1; b += 2) {
                    const double den = a * e[k] - b * e[j];
                    if (den != 0.0) gac_obst_add(list, &count, (h[k] - h[j] - a * y0[k] + b * y0[j]) / den);
                }
            }
        }
    }
    gac_obst_sort(list, count);
    base = count;
    for (a = 0; a + 1 < base; ++a) {                     /* each stretch outside: its quadratic's vertex */
        const double mid = 0.5 * (list[a] + list[a + 1]);
        double num = 0.0, den = 0.0;
        for (k = 0; k < 3; ++k) {
            const double yk = y0[k] + mid * e[k];
            if (yk > h[k] || yk < -h[k]) {
                num += (y0[k] - (yk > h[k] ? h[k] : -h[k])) * e[k];
                den += e[k] * e[k];
            }
        }
        if (den > 0.0) {
            s = -num / den;
            if (s > list[a] && s < list[a + 1] && count < GAC_OBST_NCANDIDATE) vertex[count] = 1;
            s = s < list[a] ? list[a] : (s > list[a + 1] ? list[a + 1] : s);
            gac_obst_add(list, &count, s);
        }
    }
    for (a = 0; a < count; ++a) {
        for (k = 0; k < 3; ++k) y[k] = y0[k] + list[a] * e[k];
        f[a] = gac_obst_box_sd(h, y, 0);
        if (f[a] < best) best = f[a], at = a;
    }
    tie = GAC_OBST_TIE * (sqrt(size) + fabs(h[0]) + fabs(h[1]) + fabs(h[2]) + fabs(best));
    for (a = 0; a < count; ++a) {                        /* the stretch of (near) minimisers: its middle */
        if (f[a] <= best + tie) {
            if (list[a] < first) first = list[a];
            if (list[a] > last) last = list[a];
        }
    }
    /* the least a vertex inside its stretch: sd strictly convex there, the minimiser unique (a breakpoint next to
       it ties within round-off only by (s - s*)^2, which the middle would turn into an error of sqrt(tie)) */
    s = vertex[at] ? list[at] : 0.5 * (first + last);
    for (k = 0; k < 3; ++k) y[k] = y0[k] + s * e[k];
    if (best > tie) {                                    /* apart: the distance, from the box's nearest part */
        int beyond = 0;
        geometry[0] = gac_obst_box_sd(h, y, nl);
        if (vertex[at]) (void)gac_obst_box_edge_normal(h, y, e, s, nl);     /* strictly convex: lines' closest */
        for (k = 0; k < 3; ++k) {
            if (y[k] > h[k] || y[k] < -h[k]) {           /* beyond a face's plane: the closest point on it */
                lo[k] = hi[k] = y[k] > h[k] ? h[k] : -h[k];
                ++beyond;
            } else {                                     /* between the two: along the whole edge */
                lo[k] = -h[k], hi[k] = h[k];
            }
        }
        feature = beyond < 2 ? 0 : beyond - 1;
    } else {                                             /* touching or overlapping: the depth along its axis */
        int axis;
        geometry[0] = gac_obst_box_depth(h, y0, e, tie, &s, nl, &axis);
        if (axis >= 0) {                                 /* across an edge: y_j = h_j sign(n_j) off its axis */
            for (k = 0; k < 3; ++k) {
                lo[k] = k == axis ? -h[k] : (nl[k] < 0.0 ? -h[k] : h[k]);
                hi[k] = k == axis ? h[k] : lo[k];
            }
            feature = 1;
        }
    }
    geometry[1] = s;
    geometry[2] = 0.0;
    for (k = 0; k < 3; ++k) geometry[3 + k] = R[3 * k] * nl[0] + R[3 * k + 1] * nl[1] + R[3 * k + 2] * nl[2];
    return feature;
}

static void gac_obst_box_contact(const double *shape, const double *a0, const double *a1, double radius,
                                 double *geometry)
{
    double lo[3], hi[3];
    (void)gac_obst_box_solve(shape, a0, a1, geometry, lo, hi);
    geometry[0] -= radius;
}

/* sd = n . (x - point), linear along the segment: least at an end, or (parallel) the middle */
static void gac_obst_plane_contact(const double *shape, const double *a0, const double *a1, double radius,
                                   double *geometry)
{
    const double *point = shape + 1, *n = shape + 4;
    double f0 = 0.0, f1 = 0.0, size = 0.0, s;
    int k;
    for (k = 0; k < 3; ++k) {
        f0 += n[k] * (a0[k] - point[k]);
        f1 += n[k] * (a1[k] - point[k]);
        size += (a1[k] - a0[k]) * (a1[k] - a0[k]);
    }
    if (fabs(f1 - f0) <= GAC_OBST_TIE * sqrt(size)) s = 0.5;
    else s = f1 < f0 ? 1.0 : 0.0;
    geometry[0] = (s == 0.5 ? 0.5 * (f0 + f1) : (s == 1.0 ? f1 : f0)) - radius;
    geometry[1] = s;
    geometry[2] = 0.0;
    for (k = 0; k < 3; ++k) geometry[3 + k] = n[k];
}

int gac_obstacle_shape_contact(const double *shape, const double *a0, const double *a1, double radius,
                               double *geometry)
{
    switch ((int)shape[0]) {
    case GAC_OBSTACLE_BOX: gac_obst_box_contact(shape, a0, a1, radius, geometry); return 1;
    case GAC_OBSTACLE_PLANE: gac_obst_plane_contact(shape, a0, a1, radius, geometry); return 1;
    default: return 0;
    }
}

int gac_obstacle_feature(const double *shape, const double *a0, const double *a1, double *b0, double *b1)
{
    const double *c = shape + 1, *R = shape + 7;
    double geometry[GAC_LINK_NGEOMETRY], lo[3], hi[3];
    int k, feature;
    if ((int)shape[0] != GAC_OBSTACLE_BOX) return 0;                     /* a plane: its one face */
    feature = gac_obst_box_solve(shape, a0, a1, geometry, lo, hi);
    if (feature == 0) return 0;
    for (k = 0; k < 3; ++k) {                            /* x = c + R y */
        b0[k] = c[k] + R[3 * k] * lo[0] + R[3 * k + 1] * lo[1] + R[3 * k + 2] * lo[2];
        b1[k] = c[k] + R[3 * k] * hi[0] + R[3 * k + 1] * hi[1] + R[3 * k + 2] * hi[2];
    }
    return feature;
}

int gac_obstacle_feature_change(const double *shape, const double *dshape, const double *a0, const double *a1,
                                const double *n, double *db0, double *db1)
{
    const double *R = shape + 7, *dc = dshape + 1, *dh = dshape + 4;
    double geometry[GAC_LINK_NGEOMETRY], lo[3], hi[3], dlo[3], dhi[3];
    int k, feature, face = 0;
    if ((int)shape[0] != GAC_OBSTACLE_BOX) {             /* a plane: its point's motion */
        for (k = 0; k < 3; ++k) db0[k] = db1[k] = dshape[1 + k];
        return 0;
    }
    feature = gac_obst_box_solve(shape, a0, a1, geometry, lo, hi);
    if (feature == 0) {                                  /* a face: the axis n lies along, R^T n = +-E_face */
        double best = -1.0;
        for (k = 0; k < 3; ++k) {
            const double along = fabs(R[k] * n[0] + R[3 + k] * n[1] + R[6 + k] * n[2]);
            if (along > best) best = along, face = k;
        }
        for (k = 0; k < 3; ++k) db0[k] = db1[k] = dc[k] + dh[face] * n[k];
        return 0;
    }
    for (k = 0; k < 3; ++k) {                            /* each coordinate of the part +-h_k */
        dlo[k] = lo[k] < 0.0 ? -dh[k] : dh[k];
        dhi[k] = hi[k] < 0.0 ? -dh[k] : dh[k];
    }
    for (k = 0; k < 3; ++k) {
        db0[k] = dc[k] + R[3 * k] * dlo[0] + R[3 * k + 1] * dlo[1] + R[3 * k + 2] * dlo[2];
        db1[k] = dc[k] + R[3 * k] * dhi[0] + R[3 * k + 1] * dhi[1] + R[3 * k + 2] * dhi[2];
    }
    return feature;
}

int gac_obstacle_shape_check(const gac_model *m, int o)
{
    const double *shape;
    int k, kind;
    if (m->obstacle_shapes == 0) return GAC_OK;
    shape = m->obstacle_shapes + GAC_OBSTACLE_NSHAPE * o;
    kind = gac_obstacle_kind(m, o);
    if (gac_obstacle_nparam(kind) == 0) return GAC_ERR_BAD_MODEL;
    for (k = 0; k < GAC_OBSTACLE_NSHAPE; ++k) {
        if (!isfinite(shape[k])) return GAC_ERR_BAD_MODEL;
    }
    if (kind == GAC_OBSTACLE_BOX) {
        for (k = 4; k < 7; ++k) {
            if (!(shape[k] > 0.0)) return GAC_ERR_BAD_MODEL;
        }
        if (!gac_rotation_admissible(shape + 7)) return GAC_ERR_BAD_MODEL;
    } else if (kind == GAC_OBSTACLE_PLANE) {
        if (!gac_unit_admissible(shape + 4)) return GAC_ERR_BAD_MODEL;
    } else if (!(shape[7] > 0.0)) {                      /* a bar's or sphere's radius */
        return GAC_ERR_BAD_MODEL;
    }
    if (m->obstacle_params != 0 && m->obstacle_params[o] >= 0
        && (m->obstacle_params[o] + gac_obstacle_nparam(kind) > m->nparam)) return GAC_ERR_BAD_MODEL;
    return GAC_OK;
}
