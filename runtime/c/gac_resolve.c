/*
 * gac_resolve.c -- one impact event of the hybrid loop: which contacts take part, which land (rest height,
 * Zeno accumulation), the impact law (gac_impact.c) with each wall's restitution and then with the landings
 * plastic, the law's round-off bound and post-conditions (no pulling impulse, no energy gain, no contact left
 * approaching its wall), and the resting set that follows.
 */
#include "gac_internal.h"

#include <math.h>

/* The round-off bound of the impact law on the kinetic energy, relative to T (the velocities qd -> qd_plus
 * at T = T(qd); work holds the rows Y_a = I_f^-1 n_a as left by gac_impact_system).  The law's solves are
 * backward stable: they are exact for I_f + dI_f with |dI_f| <= 4 (nq + 1) eps |I_f|, and the energy they
 * leave differs from the law's by dI_f's work on the velocities, |qd^T dI_f dqd| + |dqd^T dI_f dqd| / 2
 * (dqd = qd_plus - qd).  So b = max(1e-10, 4 (nq + 1) eps |I_f| (|qd| |dqd| + |dqd|^2 / 2) / T), |I_f|
 * (2-norm) by 16 power iterations with the model's I_f v (generalized_momentum, O(n) each), with |dqd| taken
 * as sum_a |F_a| |I_f^-1 n_a| when the contacts' changes cancel (nearly dependent contacts pushing against
 * each other).  The energies the post-conditions compare are themselves evaluated with an error of about
 * (nq + 1) eps |I_f| |v|^2 / 2 at velocities v, so b also holds (nq + 1) eps |I_f| (|qd|^2 + |qd_plus|^2) / (2 T)
 * (far below 1e-10 unless the velocities lie along a soft direction of I_f).  b grows where a large velocity
 * change meets a soft direction of I_f (a slender link with a tiny axial inertia, a state near the gimbal
 * lock). */
static double gac_impact_roundoff(const gac_model *md, const double *q, const double *p, const double *work, int n,
                                  const double *F, const double *qd, const double *qd_plus, double T)
{
    const int nq = md->nq;
    const double *Y = GAC_WORK_Y(md, work);
    double x[nq], y[nq], norm_M = 0.0, size = 0.0, change = 0.0, parts = 0.0, after = 0.0, b;
    int a, i, it;
    for (i = 0; i < nq; ++i) {
        x[i] = 1.0 + 0.1 * i * (i % 2 ? -1.0 : 1.0);      /* a fixed, generic start */
        size += qd[i] * qd[i];
        after += qd_plus[i] * qd_plus[i];
        change += (qd_plus[i] - qd[i]) * (qd_plus[i] - qd[i]);
    }
    for (a = 0; a < n; ++a) {                            /* sum |F_a| |Y_a|: the changes before they cancel */
        double column = 0.0;
        for (i = 0; i < nq; ++i) column += Y[a*nq + i] * Y[a*nq + i];
        parts += fabs(F[a]) * sqrt(column);
    }
    for (it = 0; it < 16; ++it) {                        /* |I_f| by power iteration */
        double sum = 0.0;
        for (i = 0; i < nq; ++i) sum += x[i] * x[i];
        sum = sqrt(sum);
        if (!(sum > 0.0)) break;
        for (i = 0; i < nq; ++i) y[i] = x[i] / sum;
        md->generalized_momentum(q, y, p, x);            /* x = I_f y */
        norm_M = 0.0;
        for (i = 0; i < nq; ++i) norm_M += x[i] * x[i];
        norm_M = sqrt(norm_M);
    }
    b = (nq + 1) * GAC_EPS * norm_M * 0.5 * (size + after);          /* evaluating T before and after */
    size = sqrt(size);
    change = sqrt(change) > parts ? sqrt(change) : parts;
    b += 4.0 * (nq + 1) * GAC_EPS * norm_M * (size * change + 0.5 * change * change);
    b /= T > 0.0 ? T : 1e-300;
    return b > 1e-10 ? b : 1e-10;
}

/* 1 if an impact with the law's round-off bound b (relative to T) leaves the run without useful accuracy: b above
 * GAC_IMPACT_ROUNDOFF_MAX (the bound reaches 1e4 on a chain whose I_f is ill-conditioned along the impact's
 * directions). */
int gac_impact_inaccurate(const gac_sim *s, double b)
{
    (void)s;
    return b > GAC_IMPACT_ROUNDOFF_MAX;
}

/* Resolve the impact at state s->xs (time t).
 * Who takes part: every contact within contact_tol of its wall (c_event whatever its gap), every
 * approaching contact within the simultaneity window, and every persistent contact, approaching ones
 * first (at most nq).  It is an impact when a contact that is not
 * persistent approaches its wall there faster than gac_v_round (or c_event came back to it at its apex) and
 * either an impulse is applied or the persistent set changes; else a graze (returns 0).
 * The law: gac_impact_rounds (Newton's law, Eq. 47, with complementarity, in rounds until no contact
 * approaches; a contact that rests or separates takes an impulse only when the others drive it into its
 * wall).
 * Resting contact: a contact that approaches a wall with e < 1 and whose bounce would rise less than h
 * ((e v-)^2 <= 2 a h, a = its normal acceleration towards the wall with the persistent contacts held;
 * h = rest_height, but never below the resolution of the positions, graze_depth + 16 eps l, unless both
 * rules are off), or that has had zeno_impacts impacts at shrinking intervals, lands: it is struck with
 * e = 0 (a plastic impact: F >= 0, no pull); r->energy_rest is the kinetic energy the landings take (the
 * law with every contact's own e minus the law with the landings plastic).  On a wall with e = 1 a
 * contact lands only if it arrives at rest: v-^2 <= 2 a h and its landing takes no more than the
 * round-off bound of the energy, so that an elastic chain keeps its energy.  Persistent contacts take part
 * with their own e (at rest it does not matter; one driven into its wall in a later round bounces).
 * Landing and persistent contacts that end at rest (normal velocity below round-off) form the new
 * persistent set (independent rows only, held at their landing gap, only those that push kept), and so
 * does a persistent contact of a wall with e < 1 that the impact lifts by less than h (a bounce the rest
 * rule would end: its lift velocity is removed with the others' round-off, a bilateral resting
 * constraint, not an impact impulse; the energy it takes is in energy_rest); one lifted higher is
 * released.  The set is brought to rest by gac_hold, which drives no other contact into its wall.
 * Refused (GAC_ERR_IMPACT_ACCURACY): a bound b that gac_impact_inaccurate refuses, and a plastic closing round when every
 * contact has e = 1 (the sequence of elastic rounds did not end; a plastic round would take energy silently).
 * Post-conditions, checked here (GAC_ERR_IMPACT_ACCURACY if one fails), to the law's round-off bound b
 * (gac_impact_roundoff, 1e-10 for a well-conditioned I_f): every impulse >= 0; no contact within contact_tol
 * of its wall approaches it faster than 10 b max|v-| + 1e-15 m/s; the kinetic energy does not grow by
 * more than b T and, when every contact that takes an impulse has e = 1, changes by at most b T.  The state
 * after the impact is in s->x1.  Returns 1 (impact applied), 0 (graze) or an error. */
int gac_resolve(gac_sim *s, double t, int c_event, gac_impact_record *r)
{
    const gac_model *md = s->model;
    const int nc1 = GAC_AT_LEAST_1(md->ncontact);
    const int nq = md->nq;
    double gaps[nc1], vn[nc1], an[nc1];
    double e[nq], e_law[nq], qd_plus[nq], F[nq], E[2];
    double scale = 0.0, v_hold, v_rest, approach_tol, T_before, T_after, T_law, bound, height = 0.0, window;
    int list[nq], landing[nq], shrinking[nc1], set[nq];
    int c, i, k, pass, n = 0, nset = 0, impact = 0, elastic = 1, changed = 0, first = -1, code, rounds, plastic;
    double *x = s->xs;
    md->contact_gaps(x, s->p, gaps);
    gac_normal_velocities(md, x, s->p, vn);
    r->ncontact = 0;
    r->nactivated = r->nreleased = 0;
    r->rounds = r->plastic = r->law_elastic = 0;
    r->energy_rest = 0.0;
    r->roundoff = 1e-10;
    v_rest = gac_v_round(md, vn);
    for (c = 0; c < md->ncontact; ++c) {
        if (fabs(vn[c]) > scale) scale = fabs(vn[c]);
        if (!s->is_active[c] && (((c == c_event || gaps[c] <= s->opt.contact_tol) && vn[c] < -v_rest)
                                 || (c == c_event && gaps[c] <= 0.0 && vn[c] <= 0.0)))   /* back at the apex */
            impact = 1;
    }
    if (!impact) return 0;                               /* grazing touch: nothing to resolve */
    {
        /* every other point must be on the right side of its wall, to the event search's tolerance */
        const double depth = s->opt.contact_tol + gac_simultaneity_window(s, x);
        for (c = 0; c < md->ncontact; ++c) {
            if (gaps[c] < -depth) return GAC_ERR_LOST_CONTACT;
        }
    }
    if (gac_chart_measure(md, x) < gac_chart_floor(s)) return GAC_ERR_GIMBAL_LOCK;
    window = gac_simultaneity_window(s, x);
    for (pass = 0; pass < 3; ++pass) {                   /* approaching, then at rest, then separating */
        for (c = 0; c < md->ncontact; ++c) {
            const int near = s->is_active[c] || c == c_event || gaps[c] <= s->opt.contact_tol
                             || (vn[c] < -v_rest && gaps[c] <= window);
            const int kind = vn[c] < 0.0 ? 0 : vn[c] == 0.0 ? 1 : 2;
            if (!near || kind != pass) continue;
            if (n == nq) {
                if (pass == 0) return GAC_ERR_TOO_MANY_CONTACTS;
                continue;                                /* resting or leaving: the others hold it */
            }
            if (c == c_event) first = n;
            list[n++] = c;
        }
    }
    r->t = t;
    md->energy(x, x + nq, s->p, E);
    T_before = E[0];
    if (!gac_finite(E, 2)) return GAC_ERR_NONFINITE;
    r->energy_before = E[0] + E[1];
    for (i = 0; i < nq; ++i) {
        r->q[i] = x[i];
        r->qd_before[i] = x[nq + i];
    }
    /* who lands */
    for (c = 0; c < md->ncontact; ++c) {
        an[c] = 0.0;
        /* impacts of c at shrinking intervals */
        shrinking[c] = s->dt_last[c] >= 0.0 && t - s->t_last[c] <= s->dt_last[c];
    }
    if (s->rest_height > 0.0 || s->opt.zeno_impacts > 0) {
        const double floor = gac_graze_depth(s, x) + 16.0 * GAC_EPS * gac_extent(s, x);
        height = s->rest_height > floor ? s->rest_height : floor;
        code = gac_normal_accelerations(s, t, x, s->nactive, s->active, an);
        if (code != GAC_OK) return code;
    }
    for (k = 0; k < n; ++k) {
        c = list[k];
        e_law[k] = e[k] = gac_restitution(md, s->p, c);
        landing[k] = s->is_active[c];                 /* a persistent contact stays if it ends at rest */
        if (s->is_active[c]) {
            /* its own e: at rest (v = 0) e does not matter; driven into its wall in a later round, it bounces */
        } else if (vn[c] <= 0.0 && gaps[c] <= s->opt.contact_tol) {
            const double reach = 2.0 * (-an[c]) * height;   /* v^2 of a bounce that rises that high */
            const double bounce = e_law[k] < 1.0 ? e_law[k] * vn[c] : vn[c];   /* e = 1: arrived at rest */
            const int rests = an[c] < 0.0 && bounce * bounce <= reach;
            const int zeno = e_law[k] < 1.0 && s->opt.zeno_impacts > 0 && shrinking[c]
                             && s->n_shrink[c] + 1 >= s->opt.zeno_impacts;
            if (rests || zeno) {
                landing[k] = 1;
                e[k] = 0.0;
            }
        }
    }
    /* the law with every contact's own e, then (if some contact lands) with the landings plastic; a landing
     * on a wall with e = 1 is kept only if it takes no more than round-off energy (it arrived at rest) */
    code = gac_impact_rounds(md, x, x + nq, s->p, n, list, e_law, first, qd_plus, F, s->work, &rounds,
                                   &plastic);
    if (code != GAC_OK) return code;
    bound = r->roundoff = gac_impact_roundoff(md, x, s->p, s->work, n, F, x + nq, qd_plus, T_before);
    if (gac_impact_inaccurate(s, bound)) return GAC_ERR_IMPACT_ACCURACY;   /* no useful accuracy left */
    if (plastic) {                           /* e = 1 walls only: the plastic closing round would take energy */
        int all_elastic = 1;
        for (k = 0; k < n; ++k) all_elastic &= e_law[k] == 1.0;
        if (all_elastic) return GAC_ERR_IMPACT_ACCURACY;
    }
    md->energy(x, qd_plus, s->p, E);
    T_law = E[0];
    r->law_elastic = !plastic;                   /* contacts on walls with e < 1 may take part, without impulse */
    for (k = 0; k < n; ++k) {
        if (F[k] > 0.0 && e_law[k] != 1.0) r->law_elastic = 0;
    }
    if (r->law_elastic && fabs(T_law - T_before) > bound * T_before) return GAC_ERR_IMPACT_ACCURACY;
    for (k = 0; k < n; ++k) changed |= e[k] != e_law[k];
    for (pass = 0; changed && pass < 2; ++pass) {
        int elastic_landing = 0;
        code = gac_impact_rounds(md, x, x + nq, s->p, n, list, e, first, qd_plus, F, s->work, &rounds,
                                       &plastic);
        if (code != GAC_OK) return code;
        md->energy(x, qd_plus, s->p, E);
        for (k = 0; k < n; ++k) {
            if (landing[k] && !s->is_active[list[k]] && e_law[k] == 1.0 && T_law - E[0] > bound * T_before) {
                landing[k] = 0;
                e[k] = 1.0;
                elastic_landing = 1;
            }
        }
        if (!elastic_landing) break;
    }
    r->rounds = rounds;
    r->plastic = plastic;
    for (i = 0; i < nq; ++i) {
        s->x1[i] = x[i];
        s->x1[nq + i] = qd_plus[i];
    }
    md->energy(s->x1, s->x1 + nq, s->p, E);
    T_after = E[0];
    r->energy_rest = T_law - T_after;
    /* the record: the contacts that approached or took an impulse */
    r->complementarity = rounds > 1;
    for (k = 0; k < n; ++k) {
        c = list[k];
        if (F[k] > 0.0 || (!s->is_active[c] && vn[c] < 0.0)) {
            r->contact[r->ncontact] = c;
            r->impulse[r->ncontact++] = F[k];
            if (!(F[k] > 0.0) || !(vn[c] < 0.0)) r->complementarity = 1;
            if (F[k] > 0.0 && e[k] != 1.0) elastic = 0;
        }
        if (F[k] < 0.0) return GAC_ERR_IMPACT_ACCURACY;
    }
    /* post-conditions of the law (kinetic energy at the impact configuration), to its round-off bound */
    if (T_after > T_before * (1.0 + bound) + 1e-300) return GAC_ERR_IMPACT_ACCURACY;
    if (elastic && !plastic && fabs(T_after - T_before) > bound * T_before) return GAC_ERR_IMPACT_ACCURACY;
    /* the persistent set: landing and persistent contacts that end at rest, and any other contact within
     * contact_tol of its wall that the law leaves at rest (after a plastic round, or rounds that end at
     * round-off, whatever its approach speed; holding it takes no energy): held, it rests if it pushes
     * (gac_settle); left free, a contact pressed into its wall would sink from gap <= 0, where no crossing
     * is looked for */
    gac_normal_velocities(md, s->x1, s->p, vn);
    v_hold = 1e-9 * scale;                          /* at rest, to the law's round-off */
    for (k = 0; k < n; ++k) {
        c = list[k];
        const int left_at_rest = height > 0.0 && !s->is_active[c] && gaps[c] <= s->opt.contact_tol
                                 && fabs(vn[c]) <= v_hold;
        /* a persistent contact that the impact lifts by less than h stays (its small lift velocity, what the
         * bounces of the accumulation it stands for would carry, is removed with the others') */
        int held_lift = 0;
        if (s->is_active[c] && vn[c] > v_hold && e_law[k] < 1.0 && height > 0.0) {
            /* its acceleration towards the wall with the other persistent contacts held */
            double a_free[nc1];
            int others[nq], m = 0, a;
            for (a = 0; a < s->nactive; ++a) {
                if (s->active[a] != c) others[m++] = s->active[a];
            }
            code = gac_normal_accelerations(s, t, s->x1, m, others, a_free);
            if (code != GAC_OK) return code;
            held_lift = a_free[c] < 0.0 && vn[c] * vn[c] <= 2.0 * (-a_free[c]) * height;
        }
        if ((landing[k] && vn[c] <= v_hold) || held_lift || left_at_rest) {
            code = gac_add_independent(s, s->x1, &nset, set, list[k]);
            if (code != GAC_OK) return code;
        }
    }
    if (nset > 0) {
        for (k = 0; k < nset; ++k) {  /* a landing contact is held at the gap it landed at: the configuration */
            if (!s->is_active[set[k]]) s->gap_held[set[k]] = gaps[set[k]];   /* stays, so V does too */
        }
        code = gac_hold(s, s->x1, nset, set, n, list);   /* held at rest, the others not pushed in */
        if (code == GAC_OK) code = gac_settle(s, t, s->x1, &nset, set);
        if (code != GAC_OK && code != GAC_ERR_LCP) return code;
        gac_normal_velocities(md, s->x1, s->p, vn);
        for (k = 0; k < n; ++k) {
            /* a contact whose row is (nearly) dependent on the held ones' moves with them: if holding them
             * drives it into its wall, or the contacts are too degenerate to say which push, nothing is
             * held this time (the law's velocities stand) */
            if (code == GAC_ERR_LCP || vn[list[k]] < -(10.0 * bound * scale + 1e-15)) {
                for (i = 0; i < nq; ++i) s->x1[nq + i] = qd_plus[i];
                nset = 0;
                break;
            }
        }
        gac_normal_velocities(md, s->x1, s->p, vn);
        if (nset > 0) {          /* holding them changed the velocities too: the bound covers the whole change */
            const double held = gac_impact_roundoff(md, x, s->p, s->work, 0, F, x + nq, s->x1 + nq, T_before);
            if (held > bound) bound = r->roundoff = held;
            if (gac_impact_inaccurate(s, bound)) return GAC_ERR_IMPACT_ACCURACY;
        }
    }
    if (rounds == 0) {                               /* no impulse: an impact only if a contact lands */
        int same = nset == s->nactive;
        for (k = 0; same && k < nset; ++k) same = s->is_active[set[k]];
        if (same) return 0;
    }
    for (i = 0; i < nq; ++i) r->qd_after[i] = s->x1[nq + i];
    md->energy(x, s->x1 + nq, s->p, E);          /* at the impact configuration, as T_law */
    r->energy_rest = T_law > E[0] ? T_law - E[0] : 0.0; /* (a landing may also leave more than the law) */
    r->energy_after = gac_total_energy(md, s->x1, s->p);
    r->approach_after = 0.0;                  /* fastest approach of a contact at its wall, afterwards */
    for (c = 0; c < md->ncontact; ++c) {
        if (gaps[c] <= s->opt.contact_tol && -vn[c] > r->approach_after) r->approach_after = -vn[c];
    }
    r->approach_before = scale;
    approach_tol = 10.0 * bound * scale + 1e-15;
    if (r->approach_after > approach_tol) return GAC_ERR_IMPACT_ACCURACY;
    for (k = 0; k < r->ncontact; ++k) {                    /* impact history of each new contact */
        c = r->contact[k];
        if (s->is_active[c]) continue;
        s->n_shrink[c] = shrinking[c] ? s->n_shrink[c] + 1 : 0;
        s->dt_last[c] = s->dt_last[c] < -1.5 ? -1.0 : t - s->t_last[c];
        s->t_last[c] = t;
    }
    gac_set_active(s, nset, set, r);
    s->energy_impacts += r->energy_before - r->energy_after;
    return 1;
}
