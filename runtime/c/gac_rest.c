/*
 * gac_rest.c -- resting contact: points held at their walls as bilateral constraints.  The
 * constrained dynamics (with Coulomb friction on rough walls and the P-matrix test of the Painleve paradox),
 * landing (project a state onto the constraints, settle the set that pushes, hold it at rest without driving
 * another contact into its wall), contacts at rest at the start, and release when a force would pull.
 */
#include "gac_internal.h"

#include <math.h>

/* T + V at state x = [q, qd]. */
double gac_total_energy(const gac_model *md, const double *x, const double *p)
{
    double E[2];
    md->energy(x, x + md->nq, p, E);
    return E[0] + E[1];
}

/* Normal velocities (along the inward normals, m/s) of all contacts at state x. */
void gac_normal_velocities(const gac_model *md, const double *x, const double *p, double *vn)
{
    double v[3 * md->npoint];
    int c, nk;
    if (md->ncontact == 0) return;
    md->contact_velocities(x, x + md->nq, p, v);
    nk = gac_kernel_contacts(md);
    for (c = 0; c < nk; ++c) {
        const gac_contact *k = &md->contacts[c];
        vn[c] = (double)k->normal_sign * (k->kind == GAC_CONTACT_STOP ? x[md->nq + k->coordinate]
                                                                      : v[3 * (k->point - 1) + k->axis]);
    }
    gac_link_contact_rates(md, x, p, v, vn);             /* each link pair's and obstacle's */
}

/* 1 if contact c can be held at its wall at state x: a wall's or a stop's always; a link pair's or an obstacle's
 * where its normal has a derivative along qd (gac_rowless_bias: not crossing axes).  Held, a rough link pair or
 * obstacle sticks or slides by Coulomb's law along its frame's tangents as a rough wall's point does (gac_stick.c);
 * where the tangents have no derivative either, its stuck rows fail with GAC_ERR_LINK_REST. */
int gac_holdable(const gac_sim *s, const double *x, int c)
{
    const gac_model *md = s->model;
    double b;
    if (!gac_rowless(md, c)) return 1;
    return gac_rowless_bias(md, x, x + md->nq, s->p, c, &b) == GAC_OK;
}

/* Normal accelerations (along the inward normals) of all contacts at time t and state x, with the contacts
 * set[0..n-1] held (n = 0: free flight); 0 for a link pair or an obstacle whose normal has no derivative, and for
 * one farther than contact_tol from touching (its bias, about 2 nq kernel calls, is read only where it touches). */
int gac_normal_accelerations(gac_sim *s, double t, const double *x, int n, const int *set, double *an)
{
    const gac_model *md = s->model;
    const int nq = md->nq;
    double qdd[nq], lambda[nq], bias[GAC_AT_LEAST_1(md->njrow)], gaps[GAC_AT_LEAST_1(md->ncontact)];
    double *vel = GAC_WORK_VEL(md, s->work);
    const double *u = gac_input(s, t, x);
    int c, code = gac_constrained_dynamics_friction(md, x, x + nq, u, s->p, n, set, set == s->resting ? s->is_stuck : 0,
                                                    s->slip, qdd, lambda, 0, s->work, 0);
    if (code != GAC_OK) return code;
    md->contact_bias(x, x + nq, s->p, bias);
    md->contact_velocities(x, qdd, s->p, vel);           /* J qdd, read row by row */
    gac_contact_gaps(md, x, s->p, gaps);
    for (c = 0; c < md->ncontact; ++c) {
        double b;
        if (gac_rowless(md, c) && !(gaps[c] <= s->opt.contact_tol)) {
            an[c] = 0.0;
            continue;
        }
        an[c] = gac_normal_bias(md, x, x + nq, s->p, c, bias, &b) == GAC_OK
                ? b + gac_normal_value(md, x, s->p, c, qdd, vel) : 0.0;
    }
    return GAC_OK;
}

/* Add contact c to set[0..*n-1] if its constraint row is independent of theirs (N I_f^-1 N^T stays
 * positive definite): a dependent contact is held by the others already.  Returns GAC_OK or an error. */
int gac_add_independent(gac_sim *s, const double *x, int *n, int *set, int c)
{
    const gac_model *md = s->model;
    double v[md->nq], e[md->nq];
    double *A = GAC_WORK_A(md, s->work);
    int code;
    if (*n == md->nq) return GAC_OK;
    set[*n] = c;
    code = gac_impact_system(md, x, x + md->nq, s->p, *n + 1, set, s->work, v, e);
    if (code != GAC_OK) return code;
    if (gac_ldlt(*n + 1, A, 1e-12) == 0) ++*n;
    return GAC_OK;
}

/* Project the state x onto the contacts set[0..n-1] held at their walls: (positions = 1) the gaps to
 * s->gap_held (the gap each had when it landed) by Newton steps dq = -Y (N Y)^-1 (g - g_held)
 * (Y = I_f^-1 N^T, the smallest correction in the mass metric), a contact outside the set that the
 * correction would push deeper into its wall being held where it is (an active-set method); then the normal
 * velocities to 0, qd -= Y (N Y)^-1 N qd: a plastic impact, so the kinetic energy cannot grow (with the stuck points'
 * tangential velocities, gac_project_stuck).  With positions,
 * the energy change is what the step left off the constraints (gac_energy_projected: summed, and
 * GAC_ERR_PROJECTION beyond its tolerance). */
int gac_project(gac_sim *s, double *x, int n, const int *set, int positions)
{
    const gac_model *md = s->model;
    const int nc1 = GAC_AT_LEAST_1(md->ncontact);
    const int nq = md->nq;
    const double floor = 1e-6 * s->opt.contact_tol + 1e-15;
    double v[nq], e[nq], g[nc1], g0[nc1];
    double corr[nq], target[nq];
    double *Y = GAC_WORK_Y(md, s->work), *A = GAC_WORK_A(md, s->work);
    int held[nq], in_set[nc1], a, c, i, it, code, m = n;
    const double E_before = positions && n > 0 ? gac_total_energy(md, x, s->p) : 0.0;
    if (n == 0) return GAC_OK;
    g[0] = g0[0] = 0.0;
    gac_contact_gaps(md, x, s->p, g0);
    for (c = 0; c < md->ncontact; ++c) in_set[c] = 0;
    for (a = 0; a < n; ++a) {
        held[a] = set[a];
        in_set[set[a]] = 1;
        target[a] = s->gap_held[set[a]];
    }
    for (it = 0; positions && it < 4 + md->ncontact; ++it) {
        double gmax = 0.0;
        int added = 0;
        gac_contact_gaps(md, x, s->p, g);
        for (c = 0; c < md->ncontact && it > 0; ++c) {      /* pushed deeper: hold it */
            const double stay = g0[c] < 0.0 ? g0[c] : 0.0;
            if (!in_set[c] && g[c] < stay - floor && m < nq) {
                in_set[c] = 1;
                target[m] = stay;
                held[m++] = c;
                added = 1;
            }
        }
        for (a = 0; a < m; ++a) {
            g[held[a]] -= target[a];
            if (fabs(g[held[a]]) > gmax) gmax = fabs(g[held[a]]);
        }
        if (gmax <= floor && !added) break;
        if (it >= 4 && !added) break;
        code = gac_impact_system(md, x, x + nq, s->p, m, held, s->work, v, e);
        if (code != GAC_OK) return code;
        if (gac_ldlt_drop(m, A, 1e-12) < 0) return GAC_ERR_SINGULAR_CONTACT;
        for (a = 0; a < m; ++a) corr[a] = -g[held[a]];
        gac_ldlt_solve(m, A, corr);
        for (i = 0; i < nq; ++i) {
            for (a = 0; a < m; ++a) x[i] += Y[a*nq + i] * corr[a];
        }
    }
    if (gac_any_stuck(s->is_stuck, n, set)) {             /* stuck points' tangential velocities to 0 too */
        code = gac_project_stuck(s, x, n, set);
        if (code != GAC_OK) return code;
        return positions ? gac_energy_projected(s, E_before, x) : GAC_OK;
    }
    code = gac_impact_system(md, x, x + nq, s->p, n, set, s->work, v, e);
    if (code != GAC_OK) return code;
    if (gac_ldlt_drop(n, A, 1e-12) < 0) return GAC_ERR_SINGULAR_CONTACT;
    for (a = 0; a < n; ++a) corr[a] = -v[a];
    gac_ldlt_solve(n, A, corr);
    for (i = 0; i < nq; ++i) {
        for (a = 0; a < n; ++a) x[nq + i] += Y[a*nq + i] * corr[a];
    }
    return positions ? gac_energy_projected(s, E_before, x) : GAC_OK;   /* what it changed in the energy */
}

/* Of the contacts set[0..*n-1] (at their walls, normal velocities 0), keep those that push in the
 * acceleration-level complementarity problem: lambda >= 0, normal acceleration w = A lambda + c >= 0,
 * lambda_i w_i = 0, with A = N I_f^-1 N^T and c = N qdd_free + Ndot qd.  Solved exactly by enumerating the
 * pushing sets, as the impact's complementarity form.  The set is reduced in place. */
int gac_settle(gac_sim *s, double t, const double *x, int *n, int *set)
{
    const gac_model *md = s->model;
    const int nq = md->nq, m = *n;
    double v[nq], e[nq], c[nq], qdd[nq], bias[GAC_AT_LEAST_1(md->njrow)];
    double Asub[GAC_LCP_CAP * GAC_LCP_CAP], rhs[nq], scale = 0.0;   /* m <= GAC_LCP_CAP (below) */
    double *A = GAC_WORK_A(md, s->work), *vel = GAC_WORK_VEL(md, s->work);
    int a, b, code;
    unsigned long mask, full;
    if (m == 0) return GAC_OK;
    if (m > GAC_MAX_LCP(md)) return GAC_ERR_LCP;
    md->forward_dynamics(x, x + nq, gac_input(s, t, x), s->p, qdd);
    code = gac_impact_system(md, x, x + nq, s->p, m, set, s->work, v, e);
    if (code != GAC_OK) return code;
    md->contact_bias(x, x + nq, s->p, bias);
    md->contact_velocities(x, qdd, s->p, vel);           /* J qdd_free, read row by row */
    for (a = 0; a < m; ++a) {
        double held_bias;
        if (gac_normal_bias(md, x, x + nq, s->p, set[a], bias, &held_bias) != GAC_OK) return GAC_ERR_LINK_REST;
        c[a] = held_bias + gac_normal_value(md, x, s->p, set[a], qdd, vel);
        if (fabs(c[a]) > scale) scale = fabs(c[a]);
    }
    full = (1UL << m) - 1UL;
    for (mask = full; ; --mask) {
        int idx[nq], k = 0, ok = 1;
        for (a = 0; a < m; ++a) {
            if (mask & (1UL << a)) idx[k++] = a;
        }
        for (a = 0; a < k; ++a) {
            for (b = 0; b < k; ++b) Asub[a*k + b] = A[idx[a]*m + idx[b]];
            rhs[a] = -c[idx[a]];
        }
        if (k > 0 && gac_ldlt(k, Asub, 1e-12) != 0) ok = 0;
        if (ok && k > 0) gac_ldlt_solve(k, Asub, rhs);
        for (a = 0; ok && a < k; ++a) {
            if (rhs[a] < -1e-12 * (scale + 1e-300)) ok = 0;
        }
        for (a = 0; ok && a < m; ++a) {               /* w = A lambda + c >= 0 for the others */
            double w = c[a];
            if (mask & (1UL << a)) continue;
            for (b = 0; b < k; ++b) w += A[a*m + idx[b]] * rhs[b];
            if (w < -1e-10 * (scale + 1e-300)) ok = 0;
        }
        if (ok) {
            for (a = 0; a < k; ++a) set[a] = set[idx[a]];
            *n = k;
            return GAC_OK;
        }
        if (mask == 0) break;
    }
    return GAC_ERR_LCP;
}

/* Bring the contacts set[0..nset-1] to rest (normal velocity 0: bilateral, impulse of either sign, the
 * resting constraint) while no other contact of list[0..n-1] is driven into its wall (impulse >= 0,
 * complementary to its normal velocity >= 0): the projection of qd onto that convex set in the mass
 * metric, so the kinetic energy cannot grow.  Solved exactly by enumerating the pushing sets of the others
 * (as gac_lcp).  Only the others whose rows are independent of the set's take part (a dependent one moves
 * with them). */
int gac_hold(gac_sim *s, double *x, int nset, const int *set, int n, const int *list)
{
    const gac_model *md = s->model;
    const int nq = md->nq;
    double v[nq], e[nq], rhs[nq], F[nq];
    double *Asub = s->sub;                         /* up to nq x nq */
    double *Y = GAC_WORK_Y(md, s->work), *A = GAC_WORK_A(md, s->work);
    double scale = 0.0;
    int all[nq], m = nset, a, b, i, k, code, uni;
    unsigned long mask;
    for (a = 0; a < nset; ++a) all[a] = set[a];
    for (k = 0; k < n; ++k) {                  /* the others, independent ones only */
        int member = 0;
        for (a = 0; a < nset; ++a) member |= set[a] == list[k];
        if (member) continue;
        code = gac_add_independent(s, x, &m, all, list[k]);
        if (code != GAC_OK) return code;
    }
    uni = m - nset;
    if (uni > GAC_MAX_LCP(md)) return GAC_ERR_LCP;
    code = gac_impact_system(md, x, x + nq, s->p, m, all, s->work, v, e);
    if (code != GAC_OK) return code;
    for (a = 0; a < m; ++a) {
        if (fabs(v[a]) > scale) scale = fabs(v[a]);
    }
    for (mask = (1UL << uni) - 1UL; ; --mask) {        /* the others that push, largest sets first */
        int idx[nq], kk = 0, ok = 1;
        for (a = 0; a < nset; ++a) idx[kk++] = a;
        for (a = 0; a < uni; ++a) {
            if (mask & (1UL << a)) idx[kk++] = nset + a;
        }
        for (a = 0; a < kk; ++a) {
            for (b = 0; b < kk; ++b) Asub[a*kk + b] = A[idx[a]*m + idx[b]];
            rhs[a] = -v[idx[a]];
        }
        if (kk > 0 && gac_ldlt(kk, Asub, 1e-12) != 0) ok = 0;
        if (ok && kk > 0) gac_ldlt_solve(kk, Asub, rhs);
        for (a = 0; ok && a < m; ++a) F[a] = 0.0;
        for (a = 0; ok && a < kk; ++a) {
            if (idx[a] >= nset && rhs[a] < 0.0) ok = 0;
            F[idx[a]] = rhs[a];
        }
        for (a = nset; ok && a < m; ++a) {             /* the others' normal velocities afterwards >= 0 */
            double w = v[a];
            for (b = 0; b < m; ++b) w += A[a*m + b] * F[b];
            if (w < -1e-10 * (scale + 1e-300)) ok = 0;
        }
        if (ok) {
            for (i = 0; i < nq; ++i) {
                for (a = 0; a < m; ++a) x[nq + i] += Y[a*nq + i] * F[a];
            }
            return GAC_OK;
        }
        if (mask == 0) break;
    }
    return GAC_ERR_LCP;
}

/* Make set[0..n-1] the resting contacts; record (if not NULL) lists the landings and releases. */
void gac_set_resting(gac_sim *s, int n, const int *set, gac_impact_record *r)
{
    const gac_model *md = s->model;
    int now[GAC_AT_LEAST_1(md->ncontact)], a, c;
    for (c = 0; c < md->ncontact; ++c) now[c] = 0;
    for (a = 0; a < n; ++a) now[set[a]] = 1;
    if (r) {
        r->nlanded = r->nreleased = 0;
        for (a = 0; a < n; ++a) {
            if (!s->is_resting[set[a]]) r->landed[r->nlanded++] = set[a];
        }
        for (a = 0; a < s->nresting; ++a) {
            if (!now[s->resting[a]]) r->released[r->nreleased++] = s->resting[a];
        }
        s->n_landings += r->nlanded;
        s->n_releases += r->nreleased;
    }
    for (c = 0; c < md->ncontact; ++c) {
        s->is_resting[c] = now[c];
        if (!now[c]) {                                /* free again: neither stuck nor slipping */
            s->is_stuck[c] = 0;
            s->slip[2 * c] = s->slip[2 * c + 1] = 0.0;
        }
    }
    for (a = 0; a < n; ++a) s->resting[a] = set[a];
    s->nresting = n;
    gac_sens_rest_set(s, r ? r->t : s->t);           /* a rough link or obstacle held: not differentiated */
}

/* gac_sim_init: contacts that start at their wall (|gap| <= contact_tol) with a normal velocity whose bounce
 * would rise less than rest_height (under the largest free-flight normal acceleration of any contact, so
 * that a contact pressed only through the others, like the top of a ladder, counts; of a link pair or an obstacle
 * only where it touches) come to rest:
 * positions and velocities projected, then only those with a pushing force kept.  On a wall with e = 1 a
 * contact must start at rest to round-off (gac_v_round), as it must arrive at rest to land there: the bounce
 * rule alone would let the projection take kinetic energy from an elastic chain (a chain spinning fast has a
 * large normal acceleration, so a large normal velocity passes it). */
int gac_rest_at_start(gac_sim *s)
{
    const gac_model *md = s->model;
    const int nc1 = GAC_AT_LEAST_1(md->ncontact);
    double gaps[nc1], vn[nc1], an[nc1], a = 0.0, geometry[GAC_LINK_NGEOMETRY * nc1];
    int set[md->nq], n = 0, c, code;
    gac_contact_gaps_geometry(md, s->x, s->p, gaps, geometry);
    gac_normal_velocities(md, s->x, s->p, vn);
    code = gac_normal_accelerations(s, s->t, s->x, 0, 0, an);
    if (code != GAC_OK) return code;
    for (c = 0; c < md->ncontact; ++c) {      /* (a link pair or an obstacle only where it touches) */
        if (fabs(an[c]) > a && (!gac_rowless(md, c) || fabs(gaps[c]) <= s->opt.contact_tol)) a = fabs(an[c]);
    }
    for (c = 0; c < md->ncontact; ++c) {
        const int at_rest = gac_restitution(md, s->p, c) < 1.0 ? vn[c] * vn[c] <= 2.0 * a * s->rest_height
                                                                : fabs(vn[c]) <= gac_v_round(md, vn);
        if (fabs(gaps[c]) <= s->opt.contact_tol && at_rest && gac_holdable(s, s->x, c) && !gac_redundant(s, c, gaps, geometry)) {
            code = gac_add_independent(s, s->x, &n, set, c);
            if (code != GAC_OK) return code;
        }
    }
    if (n == 0) return GAC_OK;
    for (c = 0; c < n; ++c) s->gap_held[set[c]] = gaps[set[c]];         /* held where they start */
    gac_copy(s->x1, s->x, md->nx);                 /* the state before (the sensitivities' attach reads it) */
    code = gac_project(s, s->x, n, set, 0);
    if (code == GAC_OK) code = gac_settle(s, s->t, s->x, &n, set);
    if (code != GAC_OK) return code;
    s->n_landings += n;
    gac_set_resting(s, n, set, 0);
    s->pending = n > 0;
    code = gac_try_stick(s, 0, 0, 0, 0);             /* at rest on a rough wall: stuck where it can be (listed by
                                                        the first advance's report of the contacts at rest) */
    return code < 0 ? code : GAC_OK;
}

/* Release the resting contact c_event, whose force fell to 0 at state s->xs (time t); any other
 * resting contact that would then pull goes too.  Fills the record (no impact: ncontact = 0). */
int gac_release(gac_sim *s, double t, int c_event, gac_impact_record *r)
{
    const gac_model *md = s->model;
    int set[md->nq], n = 0, a, code;
    for (a = 0; a < s->nresting; ++a) {
        if (s->resting[a] != c_event) set[n++] = s->resting[a];
    }
    code = gac_settle(s, t, s->xs, &n, set);
    if (code != GAC_OK) return code;
    gac_contact_record(s, t, s->xs, r);
    gac_set_resting(s, n, set, r);
    return GAC_OK;
}

/* The record of an event without impact at time t and state x (ncontact = 0, the state the same before and after);
 * its lists of contacts (landed, released, stuck, slipped) are left as they are. */
void gac_contact_record(const gac_sim *s, double t, const double *x, gac_impact_record *r)
{
    const gac_model *md = s->model;
    int i;
    r->t = t;
    r->ncontact = 0;
    r->complementarity = 0;
    r->energy_before = r->energy_after = gac_total_energy(md, x, s->p);
    for (i = 0; i < md->nq; ++i) {
        r->q[i] = x[i];
        r->qd_before[i] = r->qd_after[i] = x[md->nq + i];
    }
    r->approach_before = r->approach_after = 0.0;
}

/* After the inputs changed (or a point slipped): the stuck points the forces now push beyond their cones slip
 * (gac_slip, appended to record->slipped), and the resting contacts they pull off their walls (their force
 * lambda <= 0 at the current state) are released.  Returns 1 (record filled: GAC_SIM_CONTACT; a release, or a slip
 * listed in record->slipped, this call's or the caller's), 0 or an error. */
int gac_recheck_rest(gac_sim *s, gac_impact_record *record)
{
    const gac_model *md = s->model;
    int a, code;
    s->input_changed = 0;
    for (;;) {
        a = s->nresting;
        if (s->nresting > 0) gac_events(s, s->t, s->x, s->ev);
        if (s->nresting > 0 && s->fail == GAC_ERR_FRICTION) {   /* sliding in the Painleve paradox: the loop's */
            s->fail = 0;                                         /* tangential impact */
            s->f_valid = 0;
        } else if (s->nresting > 0) {
            if (s->fail) return s->fail;
            for (a = 0; a < s->nresting; ++a) {
                if (s->ev[s->resting[a]] <= 0.0) break;
            }
        }
        if (a == s->nresting) {                       /* nothing released: a record only of the slips */
            if (record->nslipped == 0) return 0;
            gac_contact_record(s, s->t, s->x, record);
            record->nlanded = record->nreleased = 0;
            return 1;
        }
        if (!s->is_stuck[s->resting[a]]) break;
        code = gac_slip(s, s->t, s->x, s->resting[a], record);
        if (code < 0) return code;
        if (code == 0) break;                         /* no normal force left: released */
        s->f_valid = s->vn_valid = 0;
    }
    gac_copy(s->xs, s->x, md->nx);
    code = gac_release(s, s->t, s->resting[a], record);
    if (code < 0) return code;
    s->f_valid = s->vn_valid = 0;
    gac_events(s, s->t, s->x, s->ev);
    return s->fail ? s->fail : 1;
}

/* 1 if the n x n row-major B (n <= GAC_PMATRIX_MAX) is a P-matrix with margin: every principal minor above
 * tol times the product of its diagonal's magnitudes (the minors by Gaussian elimination of each subset). */
#define GAC_PMATRIX_MAX 10
static int gac_is_p_matrix(int n, const double *B, double tol)
{
    double M[GAC_PMATRIX_MAX * GAC_PMATRIX_MAX];
    int idx[GAC_PMATRIX_MAX];
    unsigned long mask;
    if (n > GAC_PMATRIX_MAX) return 0;
    for (mask = 1; mask < (1UL << n); ++mask) {
        double det = 1.0, scale = 1.0;
        int k = 0, i, j, c;
        for (i = 0; i < n; ++i) {
            if (mask & (1UL << i)) idx[k++] = i;
        }
        for (i = 0; i < k; ++i) {
            for (j = 0; j < k; ++j) M[i*k + j] = B[idx[i]*n + idx[j]];
            scale *= fabs(M[i*k + i]) > 0.0 ? fabs(M[i*k + i]) : 1.0;
        }
        for (c = 0; c < k; ++c) {                 /* elimination with partial pivoting: det = +-prod of pivots */
            int p = c;
            for (i = c + 1; i < k; ++i) {
                if (fabs(M[i*k + c]) > fabs(M[p*k + c])) p = i;
            }
            if (M[p*k + c] == 0.0) return 0;
            if (p != c) {
                for (j = 0; j < k; ++j) {
                    const double t = M[c*k + j];
                    M[c*k + j] = M[p*k + j];
                    M[p*k + j] = t;
                }
                det = -det;
            }
            det *= M[c*k + c];
            for (i = c + 1; i < k; ++i) {
                const double f = M[i*k + c] / M[c*k + c];
                for (j = c; j < k; ++j) M[i*k + j] -= f * M[c*k + j];
            }
        }
        if (!(det > tol * scale)) return 0;
    }
    return 1;
}

/* 1 if the n x n row-major B of the normal forces of sliding resting contacts (bent by their friction) gives them
 * unique, bounded forces: B + B^T positive definite (LDL^T to tol), else (up to GAC_PMATRIX_MAX contacts) B a
 * P-matrix, every principal minor above tol of its diagonal's scale.  0 where friction is strong enough for the
 * Painleve paradox.  B is left as it was. */
int gac_friction_consistent(int n, const double *B, double tol)
{
    double S[GAC_AT_LEAST_1(n * n)];
    int a, b;
    for (a = 0; a < n; ++a) {
        for (b = 0; b < n; ++b) S[a*n + b] = 0.5 * (B[a*n + b] + B[b*n + a]);
    }
    return gac_ldlt(n, S, tol) == 0 || gac_is_p_matrix(n, B, tol);
}

/* The constrained dynamics of the contacts held at their walls (resting), with Coulomb friction on the walls
 * that have it: a held point with velocity v_t along its wall takes the force -c_f lambda phi, phi = v_t /
 * max(|v_t|, v_s) (v_s = m->friction_velocity), lambda >= 0 its normal force.  With d_a = n_a + mu_a J^T(-phi_a)
 * the generalised direction of contact a's force, qdd = qdd_free + sum_a I_f^-1 d_a lambda_a and the normal
 * rows n_b . qdd + ndot_b qd = 0 give B lambda = -(N qdd_free + Ndot qd), B_ba = n_b I_f^-1 d_a (not symmetric
 * with friction: solved by LU).  GAC_ERR_FRICTION where B is not a P-matrix (B + B^T positive definite, else
 * every principal minor positive, to 1e-8 of its diagonal's scale; more than 10 contacts: the first test only):
 * friction strong enough for the Painleve paradox, where the forces are not unique or unbounded.  Constraints dependent on
 * the earlier ones (found by the LDL^T of the frictionless N I_f^-1 N^T) take no force.  dissipation (if not
 * NULL): the power friction takes, sum_a mu_a lambda_a phi_a . v_t,a (W). */
int gac_constrained_dynamics_friction(const gac_model *m, const double *q, const double *qd, const double *u,
                                      const double *p, int nresting, const int *resting, const int *stuck,
                                      const double *slip, double *qdd, double *lambda, double *lambda_t, double *work,
                                      double *dissipation)
{
    const int nq = m->nq;
    double v[GAC_AT_LEAST_1(nq)], e[GAC_AT_LEAST_1(nq)], bias[GAC_AT_LEAST_1(m->njrow)];
    double cf[GAC_AT_LEAST_1(nq)], slide[GAC_AT_LEAST_1(nq)];
    double *Y = GAC_WORK_Y(m, work), *A = GAC_WORK_A(m, work), *vel = GAC_WORK_VEL(m, work);
    int a, b, i, code, friction = 0;
    if (gac_any_stuck(stuck, nresting, resting))          /* stuck points: their tangential rows held too */
        return gac_stuck_dynamics(m, q, qd, u, p, nresting, resting, stuck, slip, qdd, lambda, lambda_t, work,
                                  dissipation);
    if (lambda_t != 0) {
        for (a = 0; a < 2 * nresting; ++a) lambda_t[a] = 0.0;
    }
    if (dissipation) *dissipation = 0.0;
    m->forward_dynamics(q, qd, u, p, qdd);
    if (nresting == 0) return GAC_OK;
    code = gac_impact_system(m, q, qd, p, nresting, resting, work, v, e);
    if (code != GAC_OK) return code;
    m->contact_bias(q, qd, p, bias);
    m->contact_velocities(q, qdd, p, vel);       /* J qdd_free, read row by row */
    for (a = 0; a < nresting; ++a) {              /* lambda = -(N qdd_free + Ndot qd) */
        double held_bias;
        if (gac_normal_bias(m, q, qd, p, resting[a], bias, &held_bias) != GAC_OK) return GAC_ERR_LINK_REST;
        lambda[a] = -(held_bias + gac_normal_value(m, q, p, resting[a], qdd, vel));
        cf[a] = gac_rest_friction(m, p, resting[a]);
        if (cf[a] > 0.0) friction = 1;
    }
    if (!friction) {
        if (gac_ldlt_drop(nresting, A, 1e-12) < 0) return GAC_ERR_SINGULAR_CONTACT;
        gac_ldlt_solve(nresting, A, lambda);
    } else {
        double *Z = GAC_WORK_Z(m, work), *B = GAC_WORK_B(m, work), *g = GAC_WORK_G(m, work), *f = GAC_WORK_F(m, work);
        double vq[3 * m->npoint];
        m->contact_velocities(q, qd, p, vq);
        for (a = 0; a < nresting * nresting; ++a) B[a] = A[a];
        for (a = 0; a < nresting; ++a) {
            gac_tangents tg;
            double vt[2], phi[2];
            int j;
            slide[a] = 0.0;
            if (!(cf[a] > 0.0)) continue;
            code = gac_tangents_at(m, q, p, resting[a], &tg);       /* a wall's two axes ascending, or a frame's */
            if (code != GAC_OK) return code;
            for (j = 0; j < 2; ++j) vt[j] = gac_tangent_value(&tg, j, vq);
            slide[a] = gac_slide_phi(vt, m->friction_velocity, slip ? slip + 2 * resting[a] : 0, phi);  /* >= 0 */
            for (j = 0; j < 2; ++j) phi[j] = -phi[j];                         /* -phi: against the sliding */
            gac_tangent_force(m, q, p, &tg, phi, f, g);
            m->inertia_solve(q, g, p, Z + (long)a * nq);
            m->contact_velocities(q, Z + (long)a * nq, p, vel);
            for (b = 0; b < nresting; ++b)
                B[b*nresting + a] += cf[a] * gac_normal_value(m, q, p, resting[b], Z + (long)a * nq, vel);
        }
        if (gac_ldlt_drop(nresting, A, 1e-12) < 0) return GAC_ERR_SINGULAR_CONTACT;
        for (b = 0; b < nresting; ++b) {
            if (A[b*nresting + b] == 1e300) {         /* dependent on the others: no force */
                for (a = 0; a < nresting; ++a) B[b*nresting + a] = B[a*nresting + b] = 0.0;
                B[b*nresting + b] = 1.0;
                lambda[b] = 0.0;
            }
        }
        /* Unique, bounded forces need B to stay a P-matrix as friction bends it away from N I_f^-1 N^T: B + B^T
         * positive definite (checked by LDL^T in A's place, which is no longer needed) ensures it; where that
         * fails, up to GAC_PMATRIX_MAX contacts are checked exactly, minor by minor.  Where B is no P-matrix the
         * friction is strong enough for the Painleve paradox (one contact: B_aa <= 0), and the model stops. */
        if (!gac_friction_consistent(nresting, B, 1e-8)) return GAC_ERR_FRICTION;
        if (gac_lu_solve(nresting, B, lambda, 1e-12) != 0) return GAC_ERR_FRICTION;
        for (a = 0; a < nresting; ++a) {
            if (!(cf[a] > 0.0)) continue;
            for (i = 0; i < nq; ++i) qdd[i] += cf[a] * Z[(long)a * nq + i] * lambda[a];
            if (dissipation) *dissipation += cf[a] * lambda[a] * slide[a];
        }
    }
    for (i = 0; i < nq; ++i) {
        for (a = 0; a < nresting; ++a) qdd[i] += Y[a*nq + i] * lambda[a];
    }
    return GAC_OK;
}

int gac_constrained_dynamics(const gac_model *m, const double *q, const double *qd, const double *u,
                             const double *p, int nresting, const int *resting, double *qdd, double *lambda,
                             double *work)
{
    return gac_constrained_dynamics_friction(m, q, qd, u, p, nresting, resting, 0, 0, qdd, lambda, 0, work, 0);
}
