/*
 * gac_events.c -- event location on the dense output of the step just taken: wall crossings (a gap falling
 * through 0 at one of event_samples interpolant samples, located by bracketing), dips through a wall between two
 * samples (found at the gap's minimum), releases of resting contacts (their force falling to 0), and the
 * tolerances that say when two contacts are simultaneous or a point is at its wall.
 */
#include "gac_internal.h"

#include <math.h>

#define GAC_TUNNEL_DEPTH 96      /* halvings of a sample interval at most (down to event_tol well before) */
#define GAC_TUNNEL_EVALS 512     /* gap evaluations per contact and sample interval at most */

/* The normal speed below which an approach is round-off, given every contact's normal velocity vn:
 * GAC_V_FLOOR + 1e-10 max|vn| (the law's round-off floor on the chain's own speeds). */
double gac_v_round(const gac_model *md, const double *vn)
{
    double scale = 0.0;
    int c;
    for (c = 0; c < md->ncontact; ++c) {
        if (fabs(vn[c]) > scale) scale = fabs(vn[c]);
    }
    return GAC_V_FLOOR + 1e-10 * scale;
}

static double gac_redundant_tie(const gac_sim *s)
{
    return 1e-6 * s->opt.contact_tol + 1e-15;
}

int gac_redundant(const gac_sim *s, int c, const double *gaps, const double *geometry)
{
    return gac_redundant_depth(s->model, s->partner, c, gaps, geometry) < gac_redundant_tie(s);
}

double gac_redundant_lift(const gac_sim *s, int c, const double *gaps, const double *geometry)
{
    const double depth = gac_redundant_depth(s->model, s->partner, c, gaps, geometry), tie = gac_redundant_tie(s);
    if (!(depth < tie)) return 0.0;
    return 2.0 * (s->opt.contact_tol + tie) * (depth > 0.0 ? 1.0 - depth / tie : 1.0);
}

void gac_event_gaps(const gac_sim *s, const double *x, double *gaps)
{
    const gac_model *md = s->model;
    const int nk = gac_kernel_contacts(md);
    double geometry[GAC_LINK_NGEOMETRY * GAC_AT_LEAST_1(md->ncontact)], lift[GAC_AT_LEAST_1(md->ncontact)];
    int c;
    gac_contact_gaps_geometry(md, x, s->p, gaps, geometry);   /* a link's or a pair's contact that an end's
                                                                   measures: lifted */
    for (c = nk; c < md->ncontact; ++c) lift[c] = gac_redundant_lift(s, c, gaps, geometry);
    for (c = nk; c < md->ncontact; ++c) gaps[c] += lift[c];
}

/* Event value (what = 0), normal velocity (what = 1) or normal velocity + gac_v_round (what = 2) of contact c
 * at time t inside the step. */
static double gac_value_at(gac_sim *s, int what, int c, double t)
{
    const gac_model *md = s->model;
    gac_dense(s, t, s->xs);
    if (what == 0) {                           /* (a contact not resting: its gap alone, no resting forces) */
        if (s->is_resting[c]) gac_events(s, t, s->xs, s->es);
        else gac_event_gaps(s, s->xs, s->es);
        return s->es[c];
    }
    gac_normal_velocities(md, s->xs, s->p, s->es);
    return s->es[c] + (what == 2 ? gac_v_round(md, s->es) : 0.0);
}

/* Root in (a, b] of contact c's value_at(what) on the interpolant, value(a) > 0 >= value(b): Illinois,
 * then bisection. */
static double gac_locate(gac_sim *s, int what, int c, double a, double ga, double b, double gb)
{
    int side = 0, iter;
    for (iter = 0; iter < 200; ++iter) {
        double m, gm, tol = s->opt.event_tol + 4.0 * GAC_EPS * fabs(b);
        if (b - a <= tol) break;
        m = iter < 60 ? (a * gb - b * ga) / (gb - ga) : 0.5 * (a + b);
        if (!(m > a && m < b)) m = 0.5 * (a + b);
        gm = gac_value_at(s, what, c, m);
        if (gm > 0.0) {
            a = m; ga = gm;
            if (side == 1) gb *= 0.5;
            side = 1;
        } else {
            b = m; gb = gm;
            if (side == -1) ga *= 0.5;
            side = -1;
        }
    }
    return b;
}

/* A contact that starts the interval [t_a, t_b] at or beyond its wall (gap <= 0, just after an impact or
 * a release) and is approaching it at t_b (faster than gac_v_round) with gap(t_b) <= 0 has come back: if it
 * was leaving at t_a, the crossing follows the apex (root of the normal velocity), or is the apex itself
 * when the bounce is too small to open a positive gap; if it was not leaving, where its approach exceeds
 * gac_v_round. */
static double gac_locate_return(gac_sim *s, int c, double t_a, double t_b, double g_b)
{
    double v_a = gac_value_at(s, 1, c, t_a), v_b, t_apex, g_apex;
    if (!(v_a > 0.0)) {
        const double w_a = gac_value_at(s, 2, c, t_a);
        if (!(w_a > 0.0)) return t_a;
        return gac_locate(s, 2, c, t_a, w_a, t_b, gac_value_at(s, 2, c, t_b));
    }
    v_b = gac_value_at(s, 1, c, t_b);
    t_apex = gac_locate(s, 1, c, t_a, v_a, t_b, v_b);
    g_apex = gac_value_at(s, 0, c, t_apex);
    return g_apex > 0.0 ? gac_locate(s, 0, c, t_apex, g_apex, t_b, g_b) : t_apex;
}

/* 1 if contact c lies beyond its wall at time t of the step by more than the depth gac_resolve refuses at an impact
 * (contact_tol plus the simultaneity window there; the interpolated state is left in s->xs).  A return located on a
 * finite contact that ends this deep is no return: inside a finite body (two capsule segments that intersect) the
 * gap is flat at minus the radii and its normal velocity has no meaning, so its apex and approach mislead. */
static int gac_inside_at(gac_sim *s, int c, double t)
{
    const gac_model *md = s->model;
    gac_dense(s, t, s->xs);
    gac_contact_gaps(md, s->xs, s->p, s->es);
    return s->es[c] < -(s->opt.contact_tol + gac_simultaneity_window(s, s->xs));
}

/* The largest |coordinate| of the contact points at state x (m). */
double gac_extent(const gac_sim *s, const double *x)
{
    const gac_model *md = s->model;
    double r[3 * md->npoint], l = 0.0;
    int i;
    md->contact_points(x, s->p, r);
    for (i = 0; i < 3 * md->npoint; ++i) {
        if (fabs(r[i]) > l) l = fabs(r[i]);
    }
    return l;
}

/* Depth (m) below which a gap minimum found between samples is a graze: the integrator's tolerance on
 * a position, atol + rtol l with l the largest |coordinate| of the contact points at state x (positions
 * are integrated to this, so a shallower dip cannot be told from a tangential touch); 0 for RK4, which has
 * no tolerance. */
double gac_graze_depth(const gac_sim *s, const double *x)
{
    if (s->opt.method == GAC_METHOD_RK4) return 0.0;
    return s->opt.atol + s->opt.rtol * gac_extent(s, x);
}

/* A dip of contact c through its wall and back between two samples t_a < t_b at which its gap is > 0
 * (g_a, g_b) and its normal velocity (the gap rate, from the interpolated qd) goes from v_a < 0 to
 * v_b > 0: the gap's minimum is the root of the rate, searched like a crossing (Illinois, then bisection,
 * to event_tol).  As soon as the gap at an iterate is below -graze_depth, the wall crossing before it is
 * the event; as soon as it exceeds 2 (|v(a)| + |v(b)|) (b - a) - graze_depth on the rate's bracket [a, b],
 * the minimum cannot reach -graze_depth and there is none (so a minimum far from the wall costs a few
 * evaluations).  A minimum at gap >= -graze_depth (a touch with normal velocity 0, or within the
 * integration error of one) is a graze: no event.
 * Skipped, without evaluating anything, when the sampled rates cannot carry the gap to 0 inside the
 * interval: unless the rate overshoots its end values (it is nearly linear over a sample interval), the
 * minimum is at least max(g_a - |v_a| dt, g_b - v_b dt), and the test keeps a factor 2 on the speeds.
 * Returns 1 with the crossing in *t_cross, or 0. */
static int gac_dip(gac_sim *s, int c, double t_a, double g_a, double v_a, double t_b, double g_b,
                   double v_b, double *t_cross)
{
    const gac_model *md = s->model;
    double a = t_a, b = t_b, va = v_a, vb = v_b, fa = v_a, fb = v_b, depth = -1.0;
    int side = 0, iter;
    if (!(v_a < 0.0 && v_b > 0.0 && g_a > 0.0 && g_b > 0.0)) return 0;
    if (g_a >= -2.0 * v_a * (t_b - t_a) || g_b >= 2.0 * v_b * (t_b - t_a)) return 0;
    for (iter = 0; iter < 200; ++iter) {
        double m, gm, vm;
        if (b - a <= s->opt.event_tol + 4.0 * GAC_EPS * fabs(b)) break;
        m = iter < 60 ? (a * fb - b * fa) / (fb - fa) : 0.5 * (a + b);
        if (!(m > a && m < b)) m = 0.5 * (a + b);
        gac_dense(s, m, s->xs);
        gac_event_gaps(s, s->xs, s->es);
        gm = s->es[c];
        gac_normal_velocities(md, s->xs, s->p, s->es);
        vm = s->es[c];
        if (depth < 0.0) depth = gac_graze_depth(s, s->xs);
        if (gm < -depth) {
            *t_cross = gac_locate(s, 0, c, t_a, g_a, m, gm);
            return 1;
        }
        if (vm < 0.0) {
            a = m; va = fa = vm;
            if (side == 1) fb *= 0.5;
            side = 1;
        } else {
            b = m; vb = fb = vm;
            if (side == -1) fa *= 0.5;
            side = -1;
        }
        if (gm + depth >= 2.0 * (fabs(va) + fabs(vb)) * (b - a)) break;
    }
    return 0;
}

/* The contacts that may dip through their wall inside the step [s->t, t1] (not resting, gap at the
 * step start below speed x the step, speed = 2 (|v(t0)| + |v(t1)|) from their normal velocities at the
 * step ends): cand[0..return-1], their speeds, and the normal velocities at the step start (v0).
 * Cheap when the chain is far from every wall: nothing is evaluated when every gap at the step start
 * exceeds 2 lever sum|qd| x the step (qd at both ends), because no point moves faster than lever sum|qd|
 * (lever = max(1 m, the chain's length): |dO/dq| is 1 for a translation and at most the chain's length for
 * a rotation).  The normal velocities at the step end are kept for the next step (s->vn). */
static int gac_dip_candidates(gac_sim *s, double t1, int *cand, double *speed, double *v0)
{
    const gac_model *md = s->model;
    int c, i, n = 0, nearby = 0;
    double bound = 0.0;
    for (i = 0; i < md->nq; ++i) bound += fabs(s->x[md->nq + i]) + fabs(s->x1[md->nq + i]);
    bound *= 2.0 * s->lever * (t1 - s->t);
    for (c = 0; c < md->ncontact && !nearby; ++c) nearby = !s->is_resting[c] && s->ev[c] < bound;
    if (!nearby) {
        s->vn_valid = 0;
        return 0;
    }
    if (!s->vn_valid) gac_normal_velocities(md, s->x, s->p, s->vn);
    for (c = 0; c < md->ncontact; ++c) v0[c] = s->vn[c];
    gac_normal_velocities(md, s->x1, s->p, s->vn);
    s->vn_valid = 1;                             /* (gac_sim_advance clears it if x becomes anything else) */
    for (c = 0; c < md->ncontact; ++c) {
        speed[c] = 2.0 * (fabs(v0[c]) + fabs(s->vn[c]));
        if (!s->is_resting[c] && s->ev[c] < speed[c] * (t1 - s->t)) cand[n++] = c;
    }
    return n;
}

/* Record a lost contact for the run's message (GAC_ERR_LOST_CONTACT): contact c at time t, its gap there and the
 * depth allowed, and the step searched (the dense output's). */
void gac_note_lost(gac_sim *s, int c, double t, double gap, double depth)
{
    s->lost_contact = c;
    s->lost_t = t;
    s->lost_gap = gap;
    s->lost_depth = depth;
    s->lost_step[0] = s->t0_step;
    s->lost_step[1] = s->t0_step + s->h_step;
}

/* 1 if at the sample state s->xs a free contact lies beyond its wall by more than contact_tol plus the
 * simultaneity window (the depth gac_resolve refuses at an impact) while no crossing was located before it: a
 * crossing was missed (the motion too fast, or I_f too ill-conditioned, for the tolerance).  g: the event values
 * at the sample time t (gaps of the free contacts). */
static int gac_lost_contact(gac_sim *s, double t, const double *g)
{
    const gac_model *md = s->model;
    const double shallow = -s->opt.contact_tol;
    double depth = -1.0;
    int c;
    for (c = 0; c < md->ncontact; ++c) {
        if (!(g[c] < shallow) || s->is_resting[c]) continue;      /* most contacts: inside, one comparison */
        if (depth < 0.0) {
            gac_dense(s, t, s->xs);
            depth = s->opt.contact_tol + gac_simultaneity_window(s, s->xs);
        }
        if (g[c] < -depth) {
            gac_note_lost(s, c, t, g[c], depth);
            return 1;
        }
    }
    return 0;
}

/* A pass-through of finite contact c (a link pair, a sphere, a bar, a box: gac_finite_contact) inside the interval
 * [t_a, t_b] of the step, at whose ends its gap is g_a, g_b: a link can cross a finite body and leave it on the far
 * side, the gap positive at both ends and no sign change to see.  The gap is 1-Lipschitz in the points' travel (the
 * distance to a convex body, and between two segments, changes by no more than the points move), so if every point
 * of the link moves at most D relative to the other side over [a, b], the gap inside stays above
 * max(g_a - D_a(t), g_b - D_b(t)) >= (g_a + g_b - D) / 2.  D is bounded by 2 max(w_a, w_b) (b - a), w the contact's
 * largest point speed at the interval's ends (gac_finite_speed; the factor 2 covers a speed that grows inside the
 * interval, which is short and nearly linear once it is split).  So an interval with
 *     D <= g_a + g_b + 2 delta,   delta = max(contact_tol, graze depth),
 * holds no penetration deeper than delta: nothing to find there.  Any other interval is split in half (the gap and
 * w at its middle from the interpolant), the halves taken left to right, down to event_tol: the first sample with
 * gap <= 0 after one > 0 brackets a crossing (located like any other); one below -delta reached from gap <= 0 (the
 * contact left its body at an impact or a release and has come back) is a return if approaching there
 * (gac_locate_return), or, deeper than the lost-contact depth without approaching (a point inside the body on its
 * way through), a crossing that was missed.
 * Bodies far apart cost nothing: the caller checks the interval first with the lever bound on the speed.
 * Returns 1 with the crossing in *t_cross, 2 with the sample inside the body in *t_cross, or 0. */
static int gac_tunnel(gac_sim *s, int c, double t_a, double g_a, double t_b, double g_b, double *t_cross)
{
    const gac_model *md = s->model;
    double right[GAC_TUNNEL_DEPTH][3], tl = t_a, gl = g_a, wl, delta, lost, t_inside = 0.0;
    int top = 0, evals = 0, inside = 0;
    gac_dense(s, t_a, s->xs);
    wl = gac_finite_speed(md, s->xs, s->p, c);
    delta = gac_graze_depth(s, s->xs);
    if (s->opt.contact_tol > delta) delta = s->opt.contact_tol;
    lost = s->opt.contact_tol + gac_simultaneity_window(s, s->xs);
    gac_dense(s, t_b, s->xs);
    right[0][0] = t_b, right[0][1] = g_b, right[0][2] = gac_finite_speed(md, s->xs, s->p, c);
    for (;;) {
        const double tr = right[top][0], gr = right[top][1], wr = right[top][2];
        const double travel = 2.0 * (wl > wr ? wl : wr) * (tr - tl);
        double tm, gm;
        const int far = travel <= gl + gr + 2.0 * delta;
        if (far || tr - tl <= s->opt.event_tol + 4.0 * GAC_EPS * fabs(tr)
            || top + 1 == GAC_TUNNEL_DEPTH || evals == GAC_TUNNEL_EVALS) {   /* no pass-through: on to the next */
            if (!far && gl > 0.0 && gr <= 0.0) {        /* a limit reached on a sign change: the crossing is there */
                *t_cross = gac_locate(s, 0, c, tl, gl, tr, gr);
                return 1;
            }
            tl = tr, gl = gr, wl = wr;
            if (top-- == 0 || (inside && tl >= t_inside)) {   /* (everything before the point inside searched) */
                *t_cross = t_inside;
                return inside ? 2 : 0;
            }
            continue;
        }
        tm = 0.5 * (tl + tr);
        gm = gac_value_at(s, 0, c, tm);                  /* (leaves the state at tm in s->xs) */
        ++evals;
        if (gm <= 0.0 && gl > 0.0) {
            *t_cross = gac_locate(s, 0, c, tl, gl, tm, gm);
            return 1;
        }
        if (gm < -delta) {                               /* from gap <= 0: back beyond the wall by more than delta
                                                            (a shallower return is the samples' to find) */
            int deep = gm < -lost;
            gac_normal_velocities(md, s->xs, s->p, s->es);
            if (s->es[c] < -gac_v_round(md, s->es)) {
                *t_cross = gac_locate_return(s, c, tl, tm, gm);
                if (!gac_inside_at(s, c, *t_cross)) return 1;
                deep = 1;                                /* no return: inside the body */
            }
            if (deep) {                                  /* inside the body (deeper than the lost-contact depth,
                                                            not approaching, or no return): the crossing before it,
                                                            if any, is the event; the halves to its left are taken
                                                            first, so each such point is earlier than the last */
                t_inside = tm;
                inside = 1;
            }
            gac_dense(s, tm, s->xs);
        }
        ++top;
        right[top][0] = tm, right[top][1] = gm, right[top][2] = gac_finite_speed(md, s->xs, s->p, c);
    }
}

/* Search the accepted step for the first event at event_samples points of the interpolant (the step ends
 * included), so that a dip through a wall and back inside one step is still seen.  Events: a wall
 * crossing (gap from > 0 to <= 0 between samples, or below 0 at a gap minimum between two samples where
 * it is > 0: a dip shorter than the sample spacing, see gac_dip); a contact that left its wall from gap <= 0
 * and is back at gap <= 0, approaching (a small bounce); a resting contact's force from > 0 to <= 0.
 * Dips are looked for only for the step's candidates (gac_dip_candidates) in intervals whose gaps are both
 * below reach = speed x the interval (a contact farther from its wall cannot dip to it unless its normal
 * speed inside the step exceeds twice the sum of those at the step ends); only there are the normal
 * velocities at the samples evaluated.
 * A free contact found beyond its wall deeper than the lost-contact depth at a sample before any event
 * (gac_lost_contact) sets s->fail = GAC_ERR_LOST_CONTACT (returned as an event at that sample).
 * Returns 1 with *t_event and *c_event, or 0; s->eprev ends as the event values at the step end. */
int gac_find_event(gac_sim *s, double t1, double *t_event, int *c_event)
{
    const gac_model *md = s->model;
    const int nc1 = GAC_AT_LEAST_1(md->ncontact);
    int j, k, c, found = 0, have_prev = 1, ncand, cand[nc1];
    const int m = s->opt.event_samples, nk = gac_kernel_contacts(md);
    double t_prev = s->t, vprev[nc1], speed[nc1], qsum_prev = 0.0;
    for (k = 0; k < md->nq; ++k) qsum_prev += fabs(s->x[md->nq + k]);
    gac_copy(s->eprev, s->ev, md->ncontact);
    ncand = gac_dip_candidates(s, t1, cand, speed, vprev);
    for (j = 1; j <= m && !found; ++j) {
        double tj = j == m ? t1 : s->t + (t1 - s->t) * (double)j / (double)m;
        double gj[nc1], vj[nc1], qsum = 0.0, t_lost = 0.0;
        int have_v = 0, deep = 0, lost = 0, c_lost = 0;
        gac_dense(s, tj, s->xs);
        for (k = 0; k < md->nq; ++k) qsum += fabs(s->xs[md->nq + k]);
        gac_events(s, tj, s->xs, gj);
        for (c = 0; c < md->ncontact; ++c) {           /* crossings and returns at the samples */
            double tc;
            if (gj[c] > 0.0) continue;
            if (gj[c] < -s->opt.contact_tol && !s->is_resting[c]) deep = 1;   /* maybe beyond its wall */
            if (s->eprev[c] > 0.0) {
                tc = gac_locate(s, 0, c, t_prev, s->eprev[c], tj, gj[c]);
            } else {
                if (s->is_resting[c]) continue;
                if (!have_v) {
                    gac_dense(s, tj, s->xs);
                    gac_normal_velocities(md, s->xs, s->p, vj);
                    have_v = 1;
                }
                if (!(vj[c] < -gac_v_round(md, vj))) continue;
                tc = gac_locate_return(s, c, t_prev, tj, gj[c]);
                if (c >= nk && gac_finite_contact(md, c) && gac_inside_at(s, c, tc)) continue;   /* no return: inside
                                                                                  the body (gac_tunnel searches) */
            }
            if (!found || tc < *t_event) {
                *t_event = tc;
                *c_event = c;
            }
            found = 1;
        }
        for (k = 0; k < ncand; ++k) {                         /* dips between the samples */
            const double reach = speed[cand[k]] * (tj - t_prev);
            double tc;
            c = cand[k];
            if (!(s->eprev[c] > 0.0 && gj[c] > 0.0 && s->eprev[c] < reach && gj[c] < reach)) continue;
            if (!have_prev) {
                gac_dense(s, t_prev, s->xs);
                gac_normal_velocities(md, s->xs, s->p, vprev);
                have_prev = 1;
            }
            if (!have_v) {
                gac_dense(s, tj, s->xs);
                gac_normal_velocities(md, s->xs, s->p, vj);
                have_v = 1;
            }
            if (!gac_dip(s, c, t_prev, s->eprev[c], vprev[c], tj, gj[c], vj[c], &tc)) continue;
            if (!found || tc < *t_event) {
                *t_event = tc;
                *c_event = c;
            }
            found = 1;
        }
        for (c = nk; c < md->ncontact; ++c) {                /* passes through finite bodies between the samples */
            const double lever = s->lever * (md->contacts[c].kind == GAC_CONTACT_LINK ? 2.0 : 1.0);
            double tc;
            int code;
            if (s->is_resting[c] || (s->eprev[c] > 0.0 && gj[c] <= 0.0) || !gac_finite_contact(md, c)) continue;
            if (2.0 * lever * (qsum > qsum_prev ? qsum : qsum_prev) * (tj - t_prev)    /* far apart: no point */
                <= s->eprev[c] + gj[c] + 2.0 * s->opt.contact_tol) continue;           /* moves fast enough */
            code = gac_tunnel(s, c, t_prev, s->eprev[c], tj, gj[c], &tc);
            if (code == 2 && (!lost || tc < t_lost)) {
                t_lost = tc;
                c_lost = c;
                lost = 1;
            }
            if (code != 1) continue;
            if (!found || tc < *t_event) {
                *t_event = tc;
                *c_event = c;
            }
            found = 1;
        }
        if (lost && (!found || t_lost < *t_event)) {      /* inside a body on its way through: a missed crossing */
            if (s->fail == 0) s->fail = GAC_ERR_LOST_CONTACT;
            gac_dense(s, t_lost, s->xs);
            gac_contact_gaps(md, s->xs, s->p, s->es);
            gac_note_lost(s, c_lost, t_lost, s->es[c_lost], s->opt.contact_tol + gac_simultaneity_window(s, s->xs));
            *t_event = t_lost;
            *c_event = 0;
            return 1;
        }
        if (!found && deep && gac_lost_contact(s, tj, gj)) {     /* beyond its wall with no crossing to locate */
            if (s->fail == 0) s->fail = GAC_ERR_LOST_CONTACT;
            *t_event = tj;
            *c_event = 0;
            return 1;
        }
        gac_copy(s->eprev, gj, md->ncontact);
        if (have_v) gac_copy(vprev, vj, md->ncontact);
        have_prev = have_v;
        t_prev = tj;
        qsum_prev = qsum;
    }
    return found;
}

/* The smallest chart measure at which the run's results keep its tolerance: impacts and accelerations
 * computed with I_f carry a relative error of about 16 eps / chi^2 from the chart alone, so
 * mu_min = sqrt(16 eps / tol), tol = rtol (adaptive) or 1e-10 (RK4).  Below it the loop stops with
 * GAC_ERR_GIMBAL_LOCK (continue on another chart). */
double gac_chart_floor(const gac_sim *s)
{
    const double tol = s->opt.method == GAC_METHOD_RK4 || s->opt.rtol > 1e-6 ? 1e-10 : s->opt.rtol;
    return sqrt(16.0 * GAC_EPS / (tol < 1e-12 ? 1e-12 : tol));
}

/* Gap (m) within which an approaching contact joins an impact located on another contact: contact_tol, or
 * for the adaptive methods 100 times their position tolerance (atol + rtol l, l the largest |coordinate|
 * of the contact points) if larger.  Impacts that the exact motion makes simultaneous (a symmetric pair)
 * arrive split by the integration error, which accumulates over the steps to about this much. */
double gac_simultaneity_window(const gac_sim *s, const double *x)
{
    const double w = 100.0 * gac_graze_depth(s, x);
    return w > s->opt.contact_tol ? w : s->opt.contact_tol;
}
