/*
 * gac_jam.c -- the tangential impact ("impact without collision"): resting contacts that slide on rough walls where
 * their sliding system B is no P-matrix (the Painleve paradox: no unique, bounded normal forces) take an impact whose
 * normal velocities before are 0 and whose tangential ones are not.  The loop meets such a state at the start (a chain
 * started sliding in the paradox), after a landing, or at the end of a smooth approach to B's boundary while sliding,
 * the dynamic jam (Genot & Brogliato 1999: the normal force grows without bound as B_aa passes through 0, and the steps
 * shrink onto that instant, whose later stages find B no P-matrix).  There the frictional impact law (GDI,
 * gac_impact_friction.c; Glocker, Pfeiffer & Glocker 1996) is applied with e = 0, as to any contact at rest: besides
 * its trivial solution (no impulse, the sliding goes on, which has no consistent forces) it has a non-trivial one,
 * a normal impulse that stops the sliding, within Coulomb's cone exactly where B_aa <= 0 (one contact: the stick
 * impulse -W^-1 gamma- satisfies |L_T| <= c_f L_N iff W_NN - c_f sgn(v) W_NT <= 0).  The contacts then stick or
 * separate, and the loop goes on.
 */
#include "gac_internal.h"

#include <math.h>

/* At (nearly) zero sliding speed the paradox is one of the slip's direction, not of an impact: a resting point
 * sliding slower than friction_velocity with a slip direction d (phi = v_t / v_s + (1 - |v_t| / v_s) d: a slip that
 * began against the full Coulomb force) whose normal force has no consistent value along d has a tangential velocity
 * too small for any impulse to stop (the impact law's solution is trivial to round-off).  There its direction is
 * dropped (phi = v_t / v_s: the friction grows with the speed from 0, dissipative, and B is the frictionless N I_f^-1
 * N^T to O(|v_t| / v_s)), counted in n_painleve_choices.  Returns GAC_OK where that leaves consistent forces at s->x,
 * else GAC_ERR_FRICTION with the directions as they were. */
static int gac_jam_slow(gac_sim *s)
{
    const gac_model *md = s->model;
    const int nc1 = GAC_AT_LEAST_1(md->ncontact);
    double vt[2 * nc1], slip[2 * nc1];
    int a, c, changed = 0;
    gac_tangential_speeds(s, s->x, vt);
    gac_copy(slip, s->slip, 2 * md->ncontact);
    for (a = 0; a < s->nresting; ++a) {
        c = s->resting[a];
        if (s->is_stuck[c] || !(gac_rest_friction(md, s->p, c) > 0.0)) continue;
        if (!(sqrt(vt[2*c] * vt[2*c] + vt[2*c + 1] * vt[2*c + 1]) < md->friction_velocity)) continue;
        if (!(fabs(s->slip[2*c]) + fabs(s->slip[2*c + 1]) > 0.0)) continue;
        s->slip[2 * c] = s->slip[2 * c + 1] = 0.0;
        changed++;
    }
    if (changed == 0) return GAC_ERR_FRICTION;
    s->fail = 0;
    gac_events(s, s->t, s->x, s->ev);
    if (s->fail) {                                   /* still none: the tangential impact decides */
        if (s->fail != GAC_ERR_FRICTION) return s->fail;
        s->fail = 0;
        gac_copy(s->slip, slip, 2 * md->ncontact);
        return GAC_ERR_FRICTION;
    }
    s->n_painleve_choices += changed;
    s->f_valid = s->vn_valid = 0;
    return GAC_OK;
}

/* Indeterminacy: where the resting contacts' forces at s->x have no consistent solution with all of them held (B no
 * P-matrix), some of them may leave their walls instead: a subset S held with consistent forces (its own B accepted,
 * every lambda >= 0) while every contact released has a normal acceleration >= 0 (it leaves, or stays at its wall
 * without a force) solves the contact problem 0 <= lambda _|_ a_N >= 0 as well.  Of those, the one with the least
 * total normal force is taken (the first in the subsets' order on ties; up to GAC_JAM_SUBSETS contacts), the others
 * released: recorded as a release (GAC_SIM_CONTACT), counted in n_painleve_choices.  GAC_ERR_FRICTION where no subset
 * solves it (inconsistency: the tangential impact's case) or the resting contacts' forces exist at s->x (the dynamic
 * jam, reached by the steps). */
#define GAC_JAM_SUBSETS 10
static int gac_jam_release(gac_sim *s, gac_impact_record *r)
{
    const gac_model *md = s->model;
    const int nq = md->nq, nc1 = GAC_AT_LEAST_1(md->ncontact), n = s->nresting;
    const double *x = s->x;
    double qdd[GAC_AT_LEAST_1(nq)], lambda[GAC_AT_LEAST_1(nq)], bias[GAC_AT_LEAST_1(md->njrow)], best_sum = 0.0;
    double *vel = GAC_WORK_VEL(md, s->work);
    int set[GAC_AT_LEAST_1(nq)], best[GAC_AT_LEAST_1(nq)], held[nc1], nbest = -1, a, c, code;
    unsigned long mask;
    if (n < 1 || n > GAC_JAM_SUBSETS) return GAC_ERR_FRICTION;
    code = gac_rest_forces(s, s->t, x, qdd, lambda, 0, 0);
    if (s->fail) return s->fail;
    if (code != GAC_ERR_FRICTION) return GAC_ERR_FRICTION;   /* consistent here: the jam, not a choice */
    md->contact_bias(x, x + nq, s->p, bias);
    for (mask = 0; mask + 1 < (1UL << n); ++mask) {   /* every proper subset held (the full set has no forces) */
        const double *u = gac_input(s, s->t, x);
        double sum = 0.0;
        int m = 0, ok = 1;
        for (c = 0; c < md->ncontact; ++c) held[c] = 0;
        for (a = 0; a < n; ++a) {
            if (mask & (1UL << a)) {
                set[m++] = s->resting[a];
                held[s->resting[a]] = 1;
            }
        }
        if (gac_constrained_dynamics_friction(md, x, x + nq, u, s->p, m, set, s->is_stuck, s->slip, qdd, lambda, 0,
                                              s->work, 0) != GAC_OK) continue;
        for (a = 0; a < m; ++a) {
            if (!(lambda[a] >= 0.0)) ok = 0;
            sum += lambda[a];
        }
        if (!ok || (nbest >= 0 && !(sum < best_sum))) continue;
        md->contact_velocities(x, qdd, s->p, vel);    /* the released contacts' normal accelerations */
        for (a = 0; a < n && ok; ++a) {
            double b;
            c = s->resting[a];
            if (held[c]) continue;
            if (gac_normal_bias(md, x, x + nq, s->p, c, bias, &b) != GAC_OK) ok = 0;
            else if (!(b + gac_normal_value(md, x, s->p, c, qdd, vel) >= 0.0)) ok = 0;
        }
        if (!ok) continue;
        nbest = m;
        best_sum = sum;
        for (a = 0; a < m; ++a) best[a] = set[a];
    }
    if (nbest < 0) return GAC_ERR_FRICTION;
    r->nstuck = r->nslipped = 0;
    gac_contact_record(s, s->t, x, r);
    gac_set_resting(s, nbest, best, r);
    s->n_painleve_choices++;
    s->f_valid = s->vn_valid = 0;
    gac_events(s, s->t, s->x, s->ev);
    if (s->fail) return s->fail;
    return gac_report(s, r, GAC_SIM_CONTACT);
}

/* What a tangential impact may change in s, kept to undo an impulse whose state after it still has no consistent
 * forces. */
typedef struct {
    long n_landings, n_releases, n_sticks, n_slips;
    int nresting;
} gac_jam_saved;

static void gac_jam_save(const gac_sim *s, gac_jam_saved *k, double *qd, int *resting, int *flags, double *slip)
{
    const gac_model *md = s->model;
    int c;
    k->n_landings = s->n_landings, k->n_releases = s->n_releases, k->n_sticks = s->n_sticks, k->n_slips = s->n_slips;
    k->nresting = s->nresting;
    gac_copy(qd, s->x + md->nq, md->nq);
    for (c = 0; c < s->nresting; ++c) resting[c] = s->resting[c];
    for (c = 0; c < md->ncontact; ++c) flags[2 * c] = s->is_resting[c], flags[2 * c + 1] = s->is_stuck[c];
    gac_copy(slip, s->slip, 2 * md->ncontact);
}

static void gac_jam_restore(gac_sim *s, const gac_jam_saved *k, const double *qd, const int *resting, const int *flags,
                            const double *slip)
{
    const gac_model *md = s->model;
    int c;
    s->n_landings = k->n_landings, s->n_releases = k->n_releases, s->n_sticks = k->n_sticks, s->n_slips = k->n_slips;
    s->nresting = k->nresting;
    gac_copy(s->x + md->nq, qd, md->nq);
    for (c = 0; c < k->nresting; ++c) s->resting[c] = resting[c];
    for (c = 0; c < md->ncontact; ++c) s->is_resting[c] = flags[2 * c], s->is_stuck[c] = flags[2 * c + 1];
    gac_copy(s->slip, slip, 2 * md->ncontact);
    s->fail = 0;
    s->f_valid = s->vn_valid = 0;
}

/* The tangential impact's impulses (F, Ft per contact of list[0..n-1]) and velocities after (qd_plus) applied at s->x,
 * and the resting set after them: contacts left at rest (normal velocity within round-off of 0, v_hold) stay and
 * stick where they can (gac_restick), the others are released.  E: T and V before.  Returns GAC_SIM_IMPACT (the
 * record reported), GAC_ERR_FRICTION where the state after still has no consistent forces (s then to be restored by
 * the caller), or another error. */
static int gac_jam_apply(gac_sim *s, gac_impact_record *r, int n, const int *list, const double *qd_plus,
                         const double *F, const double *Ft, const double *E, double v_hold)
{
    const gac_model *md = s->model;
    const int nq = md->nq, nc1 = GAC_AT_LEAST_1(md->ncontact);
    double *x = s->x, vn[nc1];
    int set[GAC_AT_LEAST_1(nq)], was_stuck[nc1], nset = 0, a, c, i, code;
    r->ncontact = 0;
    for (a = 0; a < n; ++a) {                        /* the contacts that took an impulse */
        if (F[a] < 0.0) {
            r->refusal = GAC_REFUSED_PULL;
            return GAC_ERR_IMPACT_ACCURACY;
        }
        if (!(F[a] > 0.0)) continue;
        r->contact[r->ncontact] = list[a];
        r->impulse[r->ncontact] = F[a];
        r->impulse_t[2 * r->ncontact] = Ft[2 * a];
        r->impulse_t[2 * r->ncontact + 1] = Ft[2 * a + 1];
        r->ncontact++;
    }
    {
        double E_plus[2];
        md->energy(x, qd_plus, s->p, E_plus);
        if (!(E_plus[0] <= E[0] * (1.0 + r->roundoff))) {                               /* T+ <= T- */
            r->refusal = GAC_REFUSED_GAIN;
            return GAC_ERR_IMPACT_ACCURACY;
        }
    }
    for (i = 0; i < nq; ++i) x[nq + i] = qd_plus[i];
    gac_normal_velocities(md, x, s->p, vn);          /* who stays at rest: lifted by round-off at most */
    for (a = 0; a < n; ++a) {
        if (vn[list[a]] <= v_hold) {
            code = gac_add_independent(s, x, &nset, set, list[a]);
            if (code != GAC_OK) return code;
        }
    }
    for (c = 0; c < md->ncontact; ++c) {            /* the stuck points before (the record's transitions) */
        was_stuck[c] = s->is_stuck[c];
        s->is_stuck[c] = 0;
    }
    if (nset > 0) {                                  /* their normal velocities to 0: round-off, never a gain */
        code = gac_project(s, x, nset, set, 0);
        if (code != GAC_OK) return code;
    }
    gac_set_resting(s, nset, set, r);
    code = gac_restick(s, 0, was_stuck, r);          /* stopped: stuck where the cone holds it */
    if (code < 0) return code;
    s->f_valid = s->vn_valid = 0;
    gac_events(s, s->t, x, s->ev);
    if (s->fail) return s->fail;                     /* still no consistent forces: GAC_ERR_FRICTION */
    md->energy(x, x + nq, s->p, s->energy_x1);
    r->energy_after = s->energy_x1[0] + s->energy_x1[1];
    if (!(s->energy_x1[0] <= E[0] * (1.0 + r->roundoff))) {
        r->refusal = GAC_REFUSED_GAIN;
        return GAC_ERR_IMPACT_ACCURACY;
    }
    for (i = 0; i < nq; ++i) r->qd_after[i] = x[nq + i];
    gac_normal_velocities(md, x, s->p, vn);
    {
        double gaps[nc1];
        gac_contact_gaps(md, x, s->p, gaps);
        r->approach_after = 0.0;
        for (c = 0; c < md->ncontact; ++c) {
            if (gaps[c] <= s->opt.contact_tol && -vn[c] > r->approach_after) r->approach_after = -vn[c];
        }
    }
    s->loss_impacts += r->energy_before - r->energy_after;
    s->energy_roundoff += r->roundoff * E[0];
    s->n_impacts++;
    s->n_tangential_impacts++;
    s->input_changed = 1;                            /* the next advance re-checks the resting contacts */
    code = gac_energy_check(s, s->energy_x1);
    if (code != GAC_OK) return GAC_ERR_DRIFT;
    s->h = s->opt.method == GAC_METHOD_RK4 ? s->opt.dt : 0.0;   /* the steps shrank onto the jam: start afresh */
    return gac_report(s, r, GAC_SIM_IMPACT);
}

/* The tangential impact at s->x (time s->t) on the resting contacts, and the resting set after it (gac_jam_apply).
 * The impulses: the frictional law's (GDI with e = 0, gac_impact_tangential), or where it has no non-trivial solution
 * or its state after still has no consistent forces (it is then undone), the cones' most dissipative ones
 * (gac_impact_cones; for one contact the two agree wherever the law has a solution: the stick impulse inside the cone).
 * The record says so (law GAC_IMPACT_LAW_GDI_TANGENTIAL, impulses, released contacts); the loop re-checks the
 * resting contacts at the next advance (those the new state pulls off their walls are released, as after a change
 * of the inputs).  Post-conditions: every impulse >= 0, no kinetic energy gained beyond the law's round-off (1e-10
 * of T).  Returns GAC_SIM_IMPACT (the record reported) or an error: GAC_ERR_FRICTION when no resting contact slides
 * on a rough wall, neither has a non-trivial solution, or the state after still has no consistent forces (the first
 * two leave the state as it was). */
int gac_jam(gac_sim *s, gac_impact_record *r)
{
    const gac_model *md = s->model;
    const int nq = md->nq, nc1 = GAC_AT_LEAST_1(md->ncontact), n = s->nresting;
    double *x = s->x, qd_plus[nq], F[nq], Ft[2 * nq], E[2], vn[nc1], vt[2 * nc1];
    double residual, parts, scale = 0.0, qd_saved[nq], slip_saved[2 * nc1];
    int list[nq], resting_saved[nq], flags_saved[2 * nc1], a, c, i, code;
    gac_jam_saved saved;
    s->fail = 0;
    for (a = 0; a < n; ++a) list[a] = s->resting[a];
    md->energy(x, x + nq, s->p, E);
    if (!gac_finite(E, 2)) return GAC_ERR_NONFINITE;
    r->t = s->t;
    r->ncontact = r->nlanded = r->nreleased = r->nstuck = r->nslipped = 0;
    r->rounds = 1;
    r->plastic = r->law_elastic = 0;
    r->complementarity = 1;                          /* no contact approached: not Eq. 47 */
    r->energy_rest = 0.0;
    r->roundoff = 1e-10;
    r->roundoff_cause = GAC_ROUNDOFF_FLOOR;
    r->refusal = GAC_REFUSED_NONE;
    r->law = GAC_IMPACT_LAW_GDI_TANGENTIAL;
    r->energy_before = E[0] + E[1];
    for (i = 0; i < nq; ++i) {
        r->q[i] = x[i];
        r->qd_before[i] = x[nq + i];
    }
    gac_normal_velocities(md, x, s->p, vn);
    gac_tangential_speeds(s, x, vt);
    r->approach_before = 0.0;
    for (a = 0; a < n; ++a) {
        c = list[a];
        if (-vn[c] > r->approach_before) r->approach_before = -vn[c];
        if (!s->is_stuck[c] && gac_rest_friction(md, s->p, c) > 0.0) {       /* sliding, rough */
            const double speed = sqrt(vt[2*c] * vt[2*c] + vt[2*c + 1] * vt[2*c + 1]);
            if (speed > scale) scale = speed;
        }
    }
    if (!(scale > 0.0)) return GAC_ERR_FRICTION;    /* nothing slides: no paradox of sliding friction here */
    code = gac_jam_slow(s);                          /* at (nearly) zero speed: the slip's direction dropped */
    if (code != GAC_ERR_FRICTION) return code;
    code = gac_jam_release(s, r);                    /* some contacts may leave instead: the least force */
    if (code != GAC_ERR_FRICTION) return code;
    code = gac_impact_tangential(md, x, x + nq, s->p, n, list, qd_plus, F, Ft, s->work, &residual, &parts);
    if (code == GAC_OK) {                            /* the law's impulses, undone if they leave the paradox */
        r->residual = residual;
        gac_jam_save(s, &saved, qd_saved, resting_saved, flags_saved, slip_saved);
        code = gac_jam_apply(s, r, n, list, qd_plus, F, Ft, E, 1e-9 * scale + 1e-15);
        if (code != GAC_ERR_FRICTION) return code;
        gac_jam_restore(s, &saved, qd_saved, resting_saved, flags_saved, slip_saved);
    }
    if (code != GAC_ERR_FRICTION) return code;
    code = gac_impact_cones(md, x, x + nq, s->p, n, list, qd_plus, F, Ft, s->work);   /* the cones' most
                                                                                         dissipative impulses */
    if (code != GAC_OK) return code;
    r->residual = 0.0;
    return gac_jam_apply(s, r, n, list, qd_plus, F, Ft, E, 1e-9 * scale + 1e-15);
}
