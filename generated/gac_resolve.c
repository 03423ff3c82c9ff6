/*
 * gac_resolve.c -- one impact event of the hybrid loop: which contacts take part, which land (rest height,
 * Zeno accumulation), the impact law (gac_impact.c) with each wall's restitution and then with the landings
 * plastic, the law's measured accuracy (gac_impact_accuracy.c) and post-conditions (no pulling impulse, no energy gain, no contact left
 * approaching its wall), and the resting set that follows.
 */
#include "gac_internal.h"

#include <math.h>

/* 1 if an impact whose energy is known to b (relative to T; its measured accuracy, gac_impact_accuracy) leaves the
 * run without useful accuracy: b above GAC_IMPACT_ROUNDOFF_MAX. */
int gac_impact_inaccurate(const gac_sim *s, double b)
{
    (void)s;
    return b > GAC_IMPACT_ROUNDOFF_MAX;
}

/* Resolve the impact at state s->xs (time t).
 * Who takes part: every contact within contact_tol of its wall (c_event whatever its gap), every
 * approaching contact within the simultaneity window, and every resting contact, approaching ones
 * first (at most nq).  It is an impact when a contact that is not
 * resting approaches its wall there faster than gac_v_round (or c_event came back to it at its apex) and
 * either an impulse is applied or the resting set changes; else a graze (returns 0).
 * The law: gac_impact_rounds (Newton's law, Eq. 47, with complementarity, in rounds until no contact
 * approaches; a contact that rests or separates takes an impulse only when the others drive it into its
 * wall).
 * Resting contact: a contact that approaches a wall with e < 1 and whose bounce would rise less than h
 * ((e v-)^2 <= 2 a h, a = its normal acceleration towards the wall with the resting contacts held;
 * h = rest_height, but never below the resolution of the positions, graze_depth + 16 eps l, unless both
 * rules are off), or that has had zeno_impacts impacts at shrinking intervals, lands: it is struck with
 * e = 0 (a plastic impact: F >= 0, no pull); r->energy_rest is the kinetic energy the landings take (the
 * law with every contact's own e minus the law with the landings plastic).  On a wall with e = 1 a
 * contact lands only if it arrives at rest: v-^2 <= 2 a h and its landing takes no more than the
 * round-off bound of the energy, so that an elastic chain keeps its energy.  Resting contacts take part
 * with their own e (at rest it does not matter; one driven into its wall in a later round bounces).
 * Landing and resting contacts that end at rest (normal velocity below round-off) form the new
 * resting set (independent rows only, held at their landing gap, only those that push kept), and so
 * does a resting contact of a wall with e < 1 that the impact lifts by less than h (a bounce the rest
 * rule would end: its lift velocity is removed with the others' round-off, a bilateral resting
 * constraint, not an impact impulse; the energy it takes is in energy_rest); one lifted higher is
 * released.  The set is brought to rest by gac_hold, which drives no other contact into its wall.
 * Refused (GAC_ERR_IMPACT_ACCURACY): a bound b that gac_impact_inaccurate refuses, and a plastic closing round when every
 * contact has e = 1 (the sequence of elastic rounds did not end; a plastic round would take energy silently).
 * Post-conditions, checked here (GAC_ERR_IMPACT_ACCURACY if one fails), to the law's measured accuracy b
 * (gac_law_accuracy, at least 1e-10; its residuals refined to that where the chain allows): every impulse >= 0; no contact within contact_tol
 * of its wall approaches it faster than 10 b max|v-| + 1e-15 m/s; the kinetic energy does not grow by
 * more than b T and, when every contact that takes an impulse has e = 1, changes by at most b T.  The state
 * after the impact is in s->x1.  Returns 1 (impact applied), 0 (graze) or an error. */
/* One impact being resolved: what gac_resolve's steps share (the arrays live on gac_resolve's stack). */
typedef struct {
    double t;              /* the impact time (s) */
    const double *x;       /* the state there, s->xs */
    int c_event;           /* the contact whose crossing was located */
    int n;                 /* contacts taking part: list[0..n-1] (indices of the model's contacts) */
    int first;             /* the position of c_event in list, or -1 */
    int *list, *landing, *shrinking;
    double *gaps, *vn, *an; /* per model contact: gap, normal velocity (before; after, once the law is applied),
                               normal acceleration towards the wall with the resting contacts held */
    double *e, *e_law;     /* per contact taking part: the restitution applied, and its wall's own */
    double *qd_plus, *F;   /* the law's velocities and impulses */
    double *Ft;            /* the law's tangential impulses (2 per contact taking part) */
    int friction;          /* 1 if the frictional law applies: opt.impact_law not frictionless and some contact
                              taking part has c_f > 0 (a rough wall, link pair or obstacle) */
    int law;               /* the law applied (GAC_IMPACT_LAW_*) */
    double residual;       /* the frictional law's residual */
    double parts;          /* the frictional law's sum |L_T| |I_f^-1 t| (reported by it, unused here) */
    double scale;          /* the largest |normal velocity| before (m/s) */
    double height;         /* the rest height in force (m; 0: no landings by it) */
    double T_before, T_law, bound;
    int cause;             /* bound's largest part (GAC_ROUNDOFF_*) */
    double v_acc;          /* how accurately the normal velocities after are known (m/s; gac_impact_accuracy) */
    double E_plus[2];      /* T and V at (x, qd_plus), kept with qd_plus (J) */
    int held;              /* 1 once gac_hold_resting changed the velocities after the law */
    int rounds, plastic;
    double rest_work;      /* the work of the law's rest rule (J; gac_impact_rounds_work), or -1: not known */
    double law_change;     /* the kinetic energy's change the law gives without round-off (J; gac_impact_rounds_work:
                              0 for rounds with e = 1 only), or NaN: not known (impulses with e < 1, a plastic round,
                              a frictional law) */
} gac_impact_event;

/* T(qd_to) - T(qd_from) at the configuration x (J), what an impact's energy checks compare with its accuracy: with
 * the model's long-double energy kernel, evaluated in long double (where the velocities' components cancel in T,
 * along a soft direction of I_f, each double evaluation is known only to about eps sum_i |qd_i| |(I_f qd)_i|, which
 * can exceed the impact's measured accuracy); else the difference of two double evaluations. */
static double gac_kinetic_change(const gac_model *md, const double *x, const double *qd_from, const double *qd_to,
                                 const double *p)
{
    double E_from[2], E_to[2];
    if (md->energy_ld) {
        long double from_ld[2], to_ld[2];
        md->energy_ld(x, qd_from, p, from_ld);
        md->energy_ld(x, qd_to, p, to_ld);
        return (double)(to_ld[0] - from_ld[0]);
    }
    md->energy(x, qd_from, p, E_from);
    md->energy(x, qd_to, p, E_to);
    return E_to[0] - E_from[0];
}

/* An impulse that the law's solve and refinements leave below zero by round-off is taken out, with its tangential
 * impulses and the velocities they gave: qd+ -= I_f^-1 g, g the contact's generalized impulse (a wall's J^T f, f its
 * impulses in the Jacobian's rows; a link pair's or an obstacle's F J^T n + Ft_1 J^T t1 + Ft_2 J^T t2 along its
 * contact frame).  Round-off: at most 1e-12 of the largest impulse, or an impulse whose work against the velocities
 * after, |g . qd+|, is at most eps T (T the kinetic energy before: what evaluating T resolves; a solve that ends at
 * -1e-26 N s beside no other impulse).  A larger one stays, and the law's post-conditions refuse it.  No impulse
 * pulls, and the velocities still balance the impulses.  F, Ft (2 per contact) and qd_plus in place, of the contacts
 * list[0..n-1] at the configuration x. */
void gac_drop_roundoff_pulls(const gac_model *md, const double *x, const double *p, int n, const int *list, double T,
                             double *F, double *Ft, double *qd_plus)
{
    const int nq = md->nq;
    double largest = 0.0, f[GAC_AT_LEAST_1(md->njrow)], g[GAC_AT_LEAST_1(nq)], dq[GAC_AT_LEAST_1(nq)];
    double row[GAC_AT_LEAST_1(nq)];
    int k, i, j;
    for (k = 0; k < n; ++k) largest = F[k] > largest ? F[k] : largest;
    for (k = 0; k < n; ++k) {
        const gac_contact *c = &md->contacts[list[k]];
        double work = 0.0;
        if (!(F[k] < 0.0) || (c->kind != GAC_CONTACT_WALL && !gac_rowless(md, list[k]))) continue;
        if (gac_rowless(md, list[k])) {                  /* along its frame */
            gac_contact_frame frame;
            if (gac_rowless_frame(md, x, p, list[k], &frame) != GAC_OK) continue;
            gac_link_contact_direction(md, x, p, list[k], g);
            for (i = 0; i < nq; ++i) g[i] *= F[k];
            for (j = 0; j < 2; ++j) {
                if (Ft[2 * k + j] == 0.0) continue;
                (void)gac_frame_direction(md, x, p, &frame, j + 1, row);
                for (i = 0; i < nq; ++i) g[i] += Ft[2 * k + j] * row[i];
            }
        } else {
            for (i = 0; i < md->njrow; ++i) f[i] = 0.0;
            f[c->row] = c->normal_sign * F[k];
            for (j = 0; j < 2; ++j) {
                if (c->trow[j] >= 0) f[c->trow[j]] = Ft[2 * k + j];
            }
            md->contact_generalized_force(x, f, p, g);
        }
        for (i = 0; i < nq; ++i) work += g[i] * qd_plus[i];
        if (-F[k] > 1e-12 * largest && !(fabs(work) <= GAC_EPS * T)) continue;
        md->inertia_solve(x, g, p, dq);
        if (!gac_finite(dq, nq)) continue;
        for (i = 0; i < nq; ++i) qd_plus[i] -= dq[i];
        F[k] = Ft[2 * k] = Ft[2 * k + 1] = 0.0;
    }
}

/* After several frictionless rounds, how far the model's kinetic energy change dT = T(qd+) - T(qd-) (in long double:
 * gac_kinetic_change) stands beyond what the law solved without round-off can give (relative to T before): with
 * e = 1 only (ev->law_change 0) the law keeps T, and |dT| is off; else no round gains energy but by the rest rule
 * (its work ev->rest_work, known from the rounds), and max(0, dT - rest_work) is off.  The refinement brings the
 * model's velocities to the rounds' own (gac_refine_impulses) by impulses that differ from the rounds' where their
 * rows are nearly dependent, and such a change of the impulses along a direction that barely moves the contacts'
 * velocities still moves T by its work against them, which no other term measures.  0 for one round (its law
 * residual measures it) or a frictional law. */
static double gac_rounds_energy_miss(const gac_sim *s, const gac_impact_event *ev)
{
    const double T = ev->T_before > 0.0 ? ev->T_before : 1e-300;
    double change;
    if (ev->rounds <= 1 || ev->friction || (isnan(ev->law_change) && ev->rest_work < 0.0)) return 0.0;
    change = gac_kinetic_change(s->model, ev->x, ev->x + s->model->nq, ev->qd_plus, s->p);
    if (!isnan(ev->law_change)) return fabs(change - ev->law_change) / T;
    return change > ev->rest_work ? (change - ev->rest_work) / T : 0.0;
}

/* The accuracy of the law just solved (ev->qd_plus, ev->F, ev->Ft with restitutions e), relative to T before, at
 * least 1e-10: measured after the solve, with qd_plus and the impulses refined in place (gac_impact_accuracy: the momentum balance
 * I_f (qd+ - qd-) = J^T Lambda and, for a law solved in one round, its contact conditions, as the energy their
 * residuals can move, plus what evaluating them can resolve). */
static double gac_law_accuracy(const gac_sim *s, gac_impact_event *ev, const double *e)
{
    const int nq = s->model->nq;
    const int refine = ev->rounds >= 1 && ev->law == GAC_IMPACT_LAW_FRICTIONLESS;
    double b = 0.0, v = 0.0, targets[GAC_AT_LEAST_1(nq)];
    int pass, a;
    for (a = 0; a < ev->n; ++a) targets[a] = NAN;       /* the rounds' velocities, from their own impulses */
    if (!refine && ev->rounds >= 1) {                   /* a frictional law that left a contact approaching beyond
                                                           round-off: its plastic closing round (nearly dependent
                                                           rows), or a round it ended as solved to its tolerance
                                                           (GAC_FRICTION_RESIDUAL_MAX of the velocities the motion can
                                                           have, above the approach gac_finish allows): struck by
                                                           plastic normal impulses of its own, which take energy and
                                                           keep every impulse in its cone (a link pair's or
                                                           obstacle's too: its normal J^T n) */
        double vel[3 * GAC_AT_LEAST_1(s->model->npoint)];
        s->model->contact_velocities(ev->x, ev->qd_plus, s->p, vel);
        for (a = 0; a < ev->n; ++a) {
            if (gac_normal_value(s->model, ev->x, s->p, ev->list[a], ev->qd_plus, vel) < -1e-9 * ev->scale) {
                gac_close_approach(s->model, ev->x, s->p, ev->n, ev->list, ev->F, ev->x + nq, ev->qd_plus,
                                   1e-11 * ev->scale, s->work);
                break;
            }
        }
    }
    if (gac_has_link(s->model, ev->n, ev->list)) {      /* a link pair has no Jacobian row: the velocities refined
                                                           against the momentum balance alone, then measured */
        const double T = ev->T_before > 0.0 ? ev->T_before : 1e-300;
        double law = 0.0;
        if (refine) {                                    /* the law's conditions, and where they leave more than
                                                            1e-11 of T the impulses refined against them first */
            double v[GAC_AT_LEAST_1(nq)];
            if (ev->rounds > 1 && gac_rounds_velocities(s->model, ev->x, ev->x + nq, s->p, ev->n, ev->list, ev->F,
                                                        ev->rounds, s->work, v) == GAC_OK) {
                for (a = 0; a < ev->n; ++a) targets[a] = ev->F[a] > 0.0 ? v[a] : NAN;   /* the rounds' own */
            }
            law = gac_frictionless_law_work(s->model, ev->x, s->p, ev->n, ev->list, e, ev->F, ev->rounds,
                                            ev->plastic, targets, ev->rest_work, ev->x + nq, ev->qd_plus);
            if (law > 1e-11 * T)
                gac_refine_impulses(s->model, ev->x, s->p, ev->n, ev->list, e, ev->rounds, ev->F, ev->x + nq,
                                    ev->qd_plus, s->work, targets);
            else if (ev->rounds > 1)                     /* an approach the rounds' round-off left, whatever the
                                                            law's work (0-74/8: 2.2e-7 m/s after 257 rounds and a
                                                            plastic one, the work 1e-11 of T) */
                gac_close_approach(s->model, ev->x, s->p, ev->n, ev->list, ev->F, ev->x + nq, ev->qd_plus,
                                   1e-11 * ev->scale, s->work);
            gac_link_refine(s->model, ev->x, s->p, ev->n, ev->list, ev->F, ev->x + nq, ev->qd_plus, s->work);
            law = gac_frictionless_law_work(s->model, ev->x, s->p, ev->n, ev->list, e, ev->F, ev->rounds,
                                            ev->plastic, targets, ev->rest_work, ev->x + nq, ev->qd_plus);
        }
        gac_drop_roundoff_pulls(s->model, ev->x, s->p, ev->n, ev->list, ev->T_before, ev->F, ev->Ft, ev->qd_plus);
        {
            const double balance = gac_link_law_accuracy(s->model, ev->x, s->p, ev->n, ev->list, ev->F, ev->Ft,
                                                         ev->x + nq, ev->qd_plus, ev->T_before);
            const double miss = gac_rounds_energy_miss(s, ev);
            b = balance + law / T + miss;
            ev->cause = balance >= law / T && balance >= miss ? GAC_ROUNDOFF_LINK
                        : law / T >= miss ? GAC_ROUNDOFF_LAW : GAC_ROUNDOFF_ROUNDS_ENERGY;
        }
        if (!(b > 1e-10)) ev->cause = GAC_ROUNDOFF_FLOOR;
        return b > 1e-10 ? b : 1e-10;
    }
    for (pass = 0; pass < (refine ? 2 : 1); ++pass) {   /* the impulses against the velocities, then the velocities
                                                           against the impulses (the momentum balance), twice */
        if (refine)
            gac_refine_impulses(s->model, ev->x, s->p, ev->n, ev->list, e, ev->rounds, ev->F, ev->x + nq,
                                ev->qd_plus, s->work, targets);
        b = gac_impact_accuracy(s->model, ev->x, s->p, ev->n, ev->list, e, ev->F, ev->Ft, ev->law, ev->rounds,
                                ev->plastic, ev->x + nq, ev->qd_plus, ev->T_before, s->work, &v,
                                refine ? targets : 0, ev->rest_work, &ev->cause);
    }
    gac_drop_roundoff_pulls(s->model, ev->x, s->p, ev->n, ev->list, ev->T_before, ev->F, ev->Ft, ev->qd_plus);
    if (v > ev->v_acc) ev->v_acc = v;
    {
        const double miss = gac_rounds_energy_miss(s, ev);
        if (miss > b) ev->cause = GAC_ROUNDOFF_ROUNDS_ENERGY;
        b += miss;
    }
    if (!(b > 1e-10)) ev->cause = GAC_ROUNDOFF_FLOOR;
    return b > 1e-10 ? b : 1e-10;
}

/* The fastest approach to its wall a contact may keep after the impact (m/s): 10 times what the energy's accuracy
 * b allows, b max|v-|, plus the normal velocities' own measured accuracy (gac_impact_accuracy: large along
 * directions where I_f is ill-conditioned, where an accurate energy still leaves the contact velocities uncertain),
 * and 1e-15 m/s. */
static double gac_approach_tolerance(const gac_impact_event *ev)
{
    return 10.0 * (ev->bound * ev->scale + ev->v_acc) + 1e-15;
}

/* The accuracy of the whole change qd- -> s->x1's velocities once the resting set[0..nset-1] is held (gac_hold):
 * the hold's impulses lambda, recovered from N_R I_f^-1 N_R^T lambda = N_R (qd_held - qd+) (refined responses),
 * join the law's, and the momentum balance of the total is measured as in gac_law_accuracy (the contact law's
 * conditions are not: holding replaces them on the set).  R: the set and every other contact of the impact that
 * the hold leaves at rest (|v| <= 1e-9 of the fastest approach before), since gac_hold may push those too and
 * gac_settle may then drop a held contact from the set (the set alone where R's rows are dependent); an impulse
 * left out would count as a momentum residual, and its refinement would move the velocities.  The held velocities
 * are refined in place. */
static double gac_held_accuracy(gac_sim *s, gac_impact_event *ev, int nset, const int *set)
{
    const gac_model *md = s->model;
    const int nq = md->nq;
    double change[nq], lambda[nq], e_unused[nq], F[nq], Ft[2 * nq], b, v = 0.0;
    double *A = GAC_WORK_A(md, s->work);
    int rest[nq], nrest = 0, a, k, pass;
    for (k = 0; k < nq; ++k) change[k] = s->x1[nq + k] - ev->qd_plus[k];
    for (k = 0; k < ev->n; ++k) F[k] = ev->F[k];
    for (a = 0; a < nset; ++a) rest[nrest++] = set[a];
    for (k = 0; k < ev->n && nrest < nq; ++k) {
        const int c = ev->list[k];
        int in_set = 0;
        for (a = 0; a < nset; ++a) in_set |= set[a] == c;
        if (!in_set && fabs(ev->vn[c]) <= 1e-9 * ev->scale) rest[nrest++] = c;
    }
    for (pass = 0; pass < 2; ++pass) {                   /* R, else the set alone */
        const int nr = pass == 0 ? nrest : nset;
        if (pass == 1 && nrest == nset) break;
        if (gac_impact_system_refined(md, ev->x, change, s->p, nr, rest, s->work, lambda, e_unused) == GAC_OK
            && gac_ldlt(nr, A, 1e-12) == 0) {
            gac_ldlt_solve(nr, A, lambda);               /* lambda = A_RR^-1 N_R (qd_held - qd+) */
            for (a = 0; a < nr; ++a) {
                for (k = 0; k < ev->n; ++k) {
                    if (ev->list[k] == rest[a]) F[k] += lambda[a];
                }
            }
            break;
        }
    }
    for (k = 0; k < 2 * ev->n; ++k) Ft[k] = ev->Ft[k];
    if (gac_has_link(md, ev->n, ev->list)) {
        b = gac_link_law_accuracy(md, ev->x, s->p, ev->n, ev->list, F, Ft, ev->x + nq, s->x1 + nq, ev->T_before);
        return b > 1e-10 ? b : 1e-10;
    }
    b = gac_impact_accuracy(md, ev->x, s->p, ev->n, ev->list, ev->e, F, Ft, ev->law, 0, 0, ev->x + nq,
                            s->x1 + nq, ev->T_before, s->work, &v, 0, -1.0, 0);
    if (v > ev->v_acc) ev->v_acc = v;
    return b > 1e-10 ? b : 1e-10;
}

/* 1 if the event at ev->x is an impact: a contact that is not resting approaches its wall faster than
 * gac_v_round within contact_tol (c_event whatever its gap), or c_event came back to its wall at its apex; 0: a
 * grazing touch, nothing to resolve. */
static int gac_is_impact(const gac_sim *s, gac_impact_event *ev)
{
    const gac_model *md = s->model;
    const double v_rest = gac_v_round(md, ev->vn);
    int c, impact = 0;
    ev->scale = 0.0;
    for (c = 0; c < md->ncontact; ++c) {
        const double gap = ev->gaps[c], v = ev->vn[c];
        if (fabs(v) > ev->scale) ev->scale = fabs(v);
        if (!s->is_resting[c] && (((c == ev->c_event || gap <= s->opt.contact_tol) && v < -v_rest)
                                 || (c == ev->c_event && gap <= 0.0 && v <= 0.0)))   /* back at the apex */
            impact = 1;
    }
    return impact;
}

/* Who takes part: every contact within contact_tol of its wall, c_event, every approaching contact within the
 * simultaneity window and every resting one, approaching ones first, then those at rest, then separating ones
 * (at most nq: more approaching ones is GAC_ERR_TOO_MANY_CONTACTS; resting or leaving ones beyond nq are held by the
 * others).  Before that, every other point must be on the right side of its wall to the event search's tolerance
 * (GAC_ERR_LOST_CONTACT) and the base chart usable (GAC_ERR_GIMBAL_LOCK). */
static int gac_gather(gac_sim *s, gac_impact_event *ev)
{
    const gac_model *md = s->model;
    const double v_rest = gac_v_round(md, ev->vn);
    const double depth = s->opt.contact_tol + gac_simultaneity_window(s, ev->x);
    const double window = gac_simultaneity_window(s, ev->x);
    double gaps[GAC_AT_LEAST_1(md->ncontact)], geometry[GAC_LINK_NGEOMETRY * GAC_AT_LEAST_1(md->ncontact)];
    int c, pass;
    for (c = 0; c < md->ncontact; ++c) {
        if (ev->gaps[c] < -depth) {
            gac_note_lost(s, c, ev->t, ev->gaps[c], depth);
            return GAC_ERR_LOST_CONTACT;
        }
    }
    if (gac_chart_measure(md, ev->x) < gac_chart_floor(s)) return GAC_ERR_GIMBAL_LOCK;
    gac_contact_gaps_geometry(md, ev->x, s->p, gaps, geometry);   /* (the rowless contacts' geometry) */
    ev->n = 0;
    ev->first = -1;
    for (pass = 0; pass < 3; ++pass) {                   /* approaching, then at rest, then separating */
        for (c = 0; c < md->ncontact; ++c) {
            const int near = s->is_resting[c] || c == ev->c_event || ev->gaps[c] <= s->opt.contact_tol
                             || (ev->vn[c] < -v_rest && ev->gaps[c] <= window);
            const int kind = ev->vn[c] < 0.0 ? 0 : ev->vn[c] == 0.0 ? 1 : 2;
            if (!near || kind != pass || gac_redundant(s, c, ev->gaps, geometry)) continue;   /* (an end's takes
                                                                                        part instead) */
            if (ev->n == md->nq) {
                if (pass == 0) return GAC_ERR_TOO_MANY_CONTACTS;
                continue;                                /* resting or leaving: the others hold it */
            }
            if (c == ev->c_event) ev->first = ev->n;
            ev->list[ev->n++] = c;
        }
    }
    return GAC_OK;
}

/* Who lands: a contact that approaches a wall with e < 1 and whose bounce would rise less than the rest height h
 * ((e v-)^2 <= 2 a h, a its normal acceleration towards the wall with the resting contacts held; h = rest_height,
 * never below the resolution of the positions, graze_depth + 16 eps l, unless both rules are off), or that has had
 * zeno_impacts impacts at shrinking intervals, is struck with e = 0.  On a wall with e = 1 a contact lands only if
 * it arrives at rest (v-^2 <= 2 a h).  A resting contact takes part with its own e (at rest e does not matter;
 * driven into its wall in a later round, it bounces) and stays if it ends at rest. */
static int gac_who_lands(gac_sim *s, gac_impact_event *ev)
{
    const gac_model *md = s->model;
    int c, k;
    for (c = 0; c < md->ncontact; ++c) {
        ev->an[c] = 0.0;
        ev->shrinking[c] = s->dt_last[c] >= 0.0 && ev->t - s->t_last[c] <= s->dt_last[c];   /* shrinking intervals */
    }
    ev->height = 0.0;
    if (s->rest_height > 0.0 || s->opt.zeno_impacts > 0) {
        const double floor = gac_graze_depth(s, ev->x) + 16.0 * GAC_EPS * gac_extent(s, ev->x);
        int code = gac_normal_accelerations(s, ev->t, ev->x, s->nresting, s->resting, ev->an);
        if (code == GAC_ERR_FRICTION)        /* the resting contacts slide in the Painleve paradox (resolved after the
                                                impact): the free accelerations */
            code = gac_normal_accelerations(s, ev->t, ev->x, 0, 0, ev->an);
        if (code != GAC_OK) return code;
        ev->height = s->rest_height > floor ? s->rest_height : floor;
    }
    for (k = 0; k < ev->n; ++k) {
        c = ev->list[k];
        ev->e_law[k] = ev->e[k] = gac_restitution(md, s->p, c);
        ev->landing[k] = s->is_resting[c];
        if (gac_rowless(md, c) && !gac_holdable(s, ev->x, c)) {   /* a link pair or an obstacle that cannot be
            held (gac_holdable) never lands: struck with its own e, unless it would by the Zeno rule, or is struck
            again and again at one instant (held by the others) */
            const int stalled = s->dt_last[c] > -1.5 && ev->t - s->t_last[c] <= 1e-12 * (1.0 + fabs(ev->t));
            ev->shrinking[c] = (ev->shrinking[c] && ev->e_law[k] < 1.0) || stalled;
            if (s->opt.zeno_impacts > 0 && ev->shrinking[c] && s->n_shrink[c] + 1 >= s->opt.zeno_impacts)
                return GAC_ERR_LINK_REST;
            if (stalled && ev->e_law[k] == 0.0) return GAC_ERR_LINK_REST;   /* left at rest by a plastic strike and
                                                                              pressed on at once: resting */
            continue;
        }
        if (!s->is_resting[c] && ev->vn[c] <= 0.0 && ev->gaps[c] <= s->opt.contact_tol) {
            const double reach = 2.0 * (-ev->an[c]) * ev->height;   /* v^2 of a bounce that rises that high */
            const double bounce = ev->e_law[k] < 1.0 ? ev->e_law[k] * ev->vn[c] : ev->vn[c];   /* e = 1: at rest */
            const int rests = ev->an[c] < 0.0 && bounce * bounce <= reach;
            const int zeno = ev->e_law[k] < 1.0 && s->opt.zeno_impacts > 0 && ev->shrinking[c]
                             && s->n_shrink[c] + 1 >= s->opt.zeno_impacts;
            if (rests || zeno) {
                ev->landing[k] = 1;
                ev->e[k] = 0.0;
            }
        }
    }
    return GAC_OK;
}

/* The impact law with restitutions e: gac_impact_rounds_friction where friction acts, else gac_impact_rounds. */
static int gac_law(gac_sim *s, gac_impact_event *ev, const double *e)
{
    const gac_model *md = s->model;
    const double *x = ev->x;
    int k;
    ev->rest_work = -1.0;
    ev->law_change = NAN;
    if (ev->friction)
        return gac_impact_rounds_friction(md, x, x + md->nq, s->p, ev->n, ev->list, e, ev->first, s->opt.impact_law,
                                          ev->qd_plus, ev->F, ev->Ft, s->work, &ev->rounds, &ev->plastic, &ev->law,
                                          &ev->residual, &ev->parts);
    ev->law = GAC_IMPACT_LAW_FRICTIONLESS;
    ev->residual = ev->parts = 0.0;
    for (k = 0; k < 2 * ev->n; ++k) ev->Ft[k] = 0.0;
    return gac_impact_rounds_work(md, x, x + md->nq, s->p, ev->n, ev->list, e, ev->first, ev->qd_plus, ev->F,
                                  s->work, &ev->rounds, &ev->plastic, &ev->rest_work, &ev->law_change);
}

/* 1 if the law gave some contact a tangential impulse (then e = 1 need not keep the energy: friction took some). */
static int gac_tangential(const gac_impact_event *ev)
{
    int k;
    for (k = 0; k < 2 * ev->n; ++k) {
        if (ev->Ft[k] != 0.0) return 1;
    }
    return 0;
}

/* GAC_ERR_IMPACT_ACCURACY, the check that refused the impact recorded (r->refusal, GAC_REFUSED_*). */
static int gac_refuse(gac_impact_record *r, int check)
{
    r->refusal = check;
    return GAC_ERR_IMPACT_ACCURACY;
}

/* The law (gac_impact_rounds: Newton's law, Eq. 47, with complementarity, in rounds) with every contact's own e,
 * its round-off bound and its own verdict (refused: a bound gac_impact_inaccurate refuses, a plastic closing round
 * when every contact has e = 1, an elastic law that changed the energy beyond its bound); then, if some contact
 * lands, with the landings plastic, a landing on an e = 1 wall kept only if it takes no more than round-off
 * energy (it arrived at rest).  r->rounds, plastic, law_elastic, roundoff. */
static int gac_apply_law(gac_sim *s, gac_impact_event *ev, gac_impact_record *r)
{
    const gac_model *md = s->model;
    const double *x = ev->x;
    double accuracy;
    int k, pass, changed = 0, all_elastic = 1, code;
    ev->friction = 0;
    for (k = 0; k < ev->n; ++k) {
        if (s->opt.impact_law != GAC_IMPACT_LAW_FRICTIONLESS && gac_contact_friction(md, s->p, ev->list[k]) > 0.0)
            ev->friction = 1;
    }
    code = gac_law(s, ev, ev->e_law);
    r->residual = ev->residual;
    if (code != GAC_OK) return code;
    ev->bound = r->roundoff = gac_law_accuracy(s, ev, ev->e_law);
    r->roundoff_cause = ev->cause;
    if (gac_impact_inaccurate(s, ev->bound)) return gac_refuse(r, GAC_REFUSED_ACCURACY);   /* no useful accuracy
                                                                                               left */
    for (k = 0; k < ev->n; ++k) all_elastic &= ev->e_law[k] == 1.0;
    if (ev->plastic && all_elastic && !ev->friction) return gac_refuse(r, GAC_REFUSED_ELASTIC_ROUNDS);   /* the plastic closing round
                                                                                         takes energy */
    md->energy(x, ev->qd_plus, s->p, ev->E_plus);
    ev->T_law = ev->E_plus[0];
    r->law_elastic = !ev->plastic && !gac_tangential(ev);   /* contacts on walls with e < 1 may take part, without
                                                               impulse; friction may take energy at e = 1 */
    for (k = 0; k < ev->n; ++k) {
        if (ev->F[k] > 0.0 && ev->e_law[k] != 1.0) r->law_elastic = 0;
    }
    if (r->law_elastic && fabs(gac_kinetic_change(md, x, x + md->nq, ev->qd_plus, s->p)) > ev->bound * ev->T_before)
        return gac_refuse(r, GAC_REFUSED_ELASTIC_CHANGE);
    for (k = 0; k < ev->n; ++k) changed |= ev->e[k] != ev->e_law[k];
    for (pass = 0; changed && pass < 2; ++pass) {
        int elastic_landing = 0;
        code = gac_law(s, ev, ev->e);
        if (ev->residual > r->residual) r->residual = ev->residual;
        if (code != GAC_OK) return code;
        accuracy = gac_law_accuracy(s, ev, ev->e);
        if (accuracy > ev->bound) {
            ev->bound = r->roundoff = accuracy;
            r->roundoff_cause = ev->cause;
        }
        if (gac_impact_inaccurate(s, ev->bound)) return gac_refuse(r, GAC_REFUSED_ACCURACY);
        md->energy(x, ev->qd_plus, s->p, ev->E_plus);
        for (k = 0; k < ev->n; ++k) {
            if (ev->landing[k] && !s->is_resting[ev->list[k]] && ev->e_law[k] == 1.0
                && ev->T_law - ev->E_plus[0] > ev->bound * ev->T_before) {
                ev->landing[k] = 0;
                ev->e[k] = 1.0;
                elastic_landing = 1;
            }
        }
        if (!elastic_landing) break;
    }
    r->rounds = ev->rounds;
    r->plastic = ev->plastic;
    r->law = ev->law;
    return GAC_OK;
}

/* The record's contacts (those that approached or took an impulse) and the law's post-conditions at the impact
 * configuration, to its round-off bound b: every impulse >= 0, the kinetic energy not grown by more than b T and,
 * when every contact that takes an impulse has e = 1 and no plastic round closed the rounds, changed by at most
 * b T (each beyond eps times the run's energy scale, what its energy balance resolves: a chain nearly at rest, T
 * of 1e-27 J, is struck at round-off speeds).  The state after the law is in s->x1. */
static int gac_check_law(gac_sim *s, gac_impact_event *ev, gac_impact_record *r)
{
    const gac_model *md = s->model;
    const int nq = md->nq;
    double T_after, change, resolved;
    int i, k, elastic = 1;
    for (i = 0; i < nq; ++i) {
        s->x1[i] = ev->x[i];
        s->x1[nq + i] = ev->qd_plus[i];
    }
    T_after = ev->E_plus[0];                             /* s->x1 = (x, qd_plus) */
    r->energy_rest = ev->T_law - T_after;
    r->complementarity = ev->rounds > 1;
    for (k = 0; k < ev->n; ++k) {
        const int c = ev->list[k];
        if (ev->F[k] > 0.0 || (!s->is_resting[c] && ev->vn[c] < 0.0)) {
            r->contact[r->ncontact] = c;
            r->impulse_t[2 * r->ncontact] = ev->Ft[2 * k];
            r->impulse_t[2 * r->ncontact + 1] = ev->Ft[2 * k + 1];
            r->impulse[r->ncontact++] = ev->F[k];
            if (!(ev->F[k] > 0.0) || !(ev->vn[c] < 0.0)) r->complementarity = 1;
            if (ev->F[k] > 0.0 && ev->e[k] != 1.0) elastic = 0;
        }
        if (ev->F[k] < 0.0) return gac_refuse(r, GAC_REFUSED_PULL);
    }
    change = gac_kinetic_change(md, ev->x, ev->x + nq, ev->qd_plus, s->p);
    resolved = ev->bound * ev->T_before + GAC_EPS * s->energy_scale + 1e-300;   /* (a chain nearly at rest: its
                                                           T far below what the run's energy resolves) */
    if (change > resolved)
        return ev->law == GAC_IMPACT_LAW_NEWTON_COULOMB ? GAC_ERR_IMPACT_ENERGY : gac_refuse(r, GAC_REFUSED_GAIN);
    if (elastic && !ev->plastic && !gac_tangential(ev) && fabs(change) > resolved)
        return gac_refuse(r, GAC_REFUSED_ELASTIC_CHANGE);
    return GAC_OK;
}

/* The resting set after the impact, set[0..*nset-1]: landing and resting contacts that end at rest, any other
 * contact within contact_tol of its wall that the law leaves at rest (after a plastic round, or rounds that end at
 * round-off, whatever its approach speed; holding it takes no energy; left free, a contact pressed into its wall
 * would sink from gap <= 0, where no crossing is looked for), and a resting contact of a wall with e < 1 that the
 * impact lifts by less than h (its small lift velocity, what the bounces of the accumulation it stands for would
 * carry, is removed with the others'); one lifted higher is released.  Independent rows only.  ev->vn: the normal
 * velocities after the law. */
static int gac_choose_resting(gac_sim *s, gac_impact_event *ev, int *nset, int *set)
{
    const gac_model *md = s->model;
    const int nc1 = GAC_AT_LEAST_1(md->ncontact);
    const double v_hold = 1e-9 * ev->scale;         /* at rest, to the law's round-off */
    int k, code;
    for (k = 0; k < ev->n; ++k) {
        const int c = ev->list[k];
        const int left_at_rest = ev->height > 0.0 && !s->is_resting[c] && ev->gaps[c] <= s->opt.contact_tol
                                 && fabs(ev->vn[c]) <= v_hold;
        int held_lift = 0;
        if (!gac_holdable(s, s->x1, c)) continue;      /* a link pair or obstacle without a held normal */
        if (s->is_resting[c] && ev->vn[c] > v_hold && ev->e_law[k] < 1.0 && ev->height > 0.0) {
            /* its acceleration towards the wall with the other resting contacts held */
            double a_free[nc1];
            int others[md->nq], m = 0, a;
            for (a = 0; a < s->nresting; ++a) {
                if (s->resting[a] != c) others[m++] = s->resting[a];
            }
            code = gac_normal_accelerations(s, ev->t, s->x1, m, others, a_free);   /* (none where the others
                slide in the Painleve paradox: not held, and the loop resolves the paradox after the impact) */
            if (code != GAC_OK && code != GAC_ERR_FRICTION) return code;
            held_lift = code == GAC_OK && a_free[c] < 0.0 && ev->vn[c] * ev->vn[c] <= 2.0 * (-a_free[c]) * ev->height;
        }
        if ((ev->landing[k] && ev->vn[c] <= v_hold) || held_lift || left_at_rest) {
            code = gac_add_independent(s, s->x1, nset, set, c);
            if (code != GAC_OK) return code;
        }
    }
    return GAC_OK;
}

/* Bring the resting set to rest (gac_hold, which drives no other contact into its wall, then gac_settle keeps those
 * that push), each landing contact held at the gap it landed at (the configuration stays, so V does too).  If
 * holding them drives a contact whose row is (nearly) dependent on theirs into its wall, the contacts are too
 * degenerate to say which push, or none of them pushes once held, nothing is held this time (the law's velocities
 * stand).  Holding changes the velocities too: the accuracy is then measured on the whole change
 * (gac_held_accuracy), and ev->held says the velocities are the hold's. */
static int gac_hold_resting(gac_sim *s, gac_impact_event *ev, int *nset, int *set, gac_impact_record *r)
{
    const gac_model *md = s->model;
    const int nq = md->nq;
    int i, k, code;
    for (k = 0; k < *nset; ++k) {
        if (!s->is_resting[set[k]]) s->gap_held[set[k]] = ev->gaps[set[k]];
    }
    code = gac_hold(s, s->x1, *nset, set, ev->n, ev->list);
    if (code == GAC_OK) code = gac_settle(s, ev->t, s->x1, nset, set);
    if (code != GAC_OK && code != GAC_ERR_LCP) return code;
    ev->held = 1;                                        /* the velocities are the hold's */
    gac_normal_velocities(md, s->x1, s->p, ev->vn);
    for (k = 0; k < ev->n; ++k) {
        if (code == GAC_ERR_LCP || *nset == 0 || ev->vn[ev->list[k]] < -gac_approach_tolerance(ev)) {
            for (i = 0; i < nq; ++i) s->x1[nq + i] = ev->qd_plus[i];
            *nset = 0;
            ev->held = 0;
            break;
        }
    }
    gac_normal_velocities(md, s->x1, s->p, ev->vn);
    if (ev->held) {
        const double held = gac_held_accuracy(s, ev, *nset, set);
        int c;
        if (held > ev->bound) {
            ev->bound = r->roundoff = held;
            r->roundoff_cause = GAC_ROUNDOFF_HOLD;
        }
        if (gac_impact_inaccurate(s, ev->bound)) return gac_refuse(r, GAC_REFUSED_ACCURACY);
        gac_normal_velocities(md, s->x1, s->p, ev->vn);   /* (the refined velocities) */
        for (c = 0; c < md->ncontact; ++c) {             /* the refinement, along rows nearly dependent on the held
                                                            ones, left a contact at its wall approaching: the law's
                                                            velocities stand, nothing held */
            if (ev->gaps[c] <= s->opt.contact_tol && ev->vn[c] < -gac_approach_tolerance(ev)) {
                for (i = 0; i < nq; ++i) s->x1[nq + i] = ev->qd_plus[i];
                *nset = 0;
                ev->held = 0;
                gac_normal_velocities(md, s->x1, s->p, ev->vn);
                break;
            }
        }
    }
    return GAC_OK;
}

/* The record after the impact (velocities, energies, the fastest approach left, checked to the law's round-off:
 * no contact within contact_tol of its wall approaches it faster than 10 b max|v-| + 1e-15 m/s), each struck
 * contact's impact history (for the Zeno rule), and the new resting set. */
static int gac_finish(gac_sim *s, gac_impact_event *ev, int nset, const int *set, gac_impact_record *r)
{
    const gac_model *md = s->model;
    const int nq = md->nq;
    int c, i, k;
    for (i = 0; i < nq; ++i) r->qd_after[i] = s->x1[nq + i];
    if (ev->held) {                                   /* s->x1: the impact configuration, the velocities after */
        md->energy(s->x1, s->x1 + nq, s->p, s->energy_x1);
    } else {
        s->energy_x1[0] = ev->E_plus[0];
        s->energy_x1[1] = ev->E_plus[1];
    }
    s->energy_x1_valid = 1;                           /* for the balance check at s->x1 (gac_sim_advance) */
    r->energy_rest = ev->T_law > s->energy_x1[0] ? ev->T_law - s->energy_x1[0] : 0.0;   /* (a landing may also
                                                         leave more than the law) */
    r->energy_after = s->energy_x1[0] + s->energy_x1[1];
    r->approach_after = 0.0;                  /* fastest approach of a contact at its wall, afterwards */
    for (c = 0; c < md->ncontact; ++c) {
        if (ev->gaps[c] <= s->opt.contact_tol && -ev->vn[c] > r->approach_after) r->approach_after = -ev->vn[c];
    }
    r->approach_before = ev->scale;
    if (r->approach_after > gac_approach_tolerance(ev)) return gac_refuse(r, GAC_REFUSED_APPROACH);
    for (k = 0; k < r->ncontact; ++k) {                    /* impact history of each new contact */
        c = r->contact[k];
        if (s->is_resting[c]) continue;
        s->n_shrink[c] = ev->shrinking[c] ? s->n_shrink[c] + 1 : 0;
        s->dt_last[c] = s->dt_last[c] < -1.5 ? -1.0 : ev->t - s->t_last[c];
        s->t_last[c] = ev->t;
    }
    gac_set_resting(s, nset, set, r);
    s->loss_impacts += r->energy_before - r->energy_after;
    s->energy_roundoff += r->roundoff * ev->T_before;   /* what this impact's energy is known to */
    return 1;
}

/* Resolve the impact at state s->xs (time t) in named steps: is it an impact (gac_is_impact), who takes part
 * (gac_gather), who lands (gac_who_lands), the law and its own verdict (gac_apply_law), its post-conditions
 * (gac_check_law), the resting set (gac_choose_resting, gac_hold_resting) and the record (gac_finish).  Refused
 * (GAC_ERR_IMPACT_ACCURACY): a post-condition that fails beyond the law's measured accuracy b (gac_law_accuracy,
 * at least 1e-10), a bound gac_impact_inaccurate refuses, a plastic closing round when every
 * contact has e = 1.  r->energy_rest is the kinetic energy the landings take (the law with every contact's own e
 * minus the law with the landings plastic).  The state after the impact is in s->x1.  Returns 1 (impact applied),
 * 0 (graze) or an error. */
int gac_resolve(gac_sim *s, double t, int c_event, gac_impact_record *r)
{
    const gac_model *md = s->model;
    const int nc1 = GAC_AT_LEAST_1(md->ncontact);
    const int nq = md->nq;
    double gaps[nc1], vn[nc1], an[nc1], e[nq], e_law[nq], qd_plus[nq], F[nq], Ft[2 * nq], E[2];
    int list[nq], landing[nq], shrinking[nc1], set[nq];
    int i, k, code, nset = 0;
    gac_impact_event ev;
    ev.t = t;
    ev.x = s->xs;
    ev.c_event = c_event;
    ev.cause = GAC_ROUNDOFF_FLOOR;
    ev.list = list, ev.landing = landing, ev.shrinking = shrinking;
    ev.held = 0;
    s->energy_x1_valid = 0;                              /* set again by gac_finish, for the state it leaves */
    ev.gaps = gaps, ev.vn = vn, ev.an = an, ev.e = e, ev.e_law = e_law, ev.qd_plus = qd_plus, ev.F = F, ev.Ft = Ft;
    ev.friction = 0, ev.law = GAC_IMPACT_LAW_FRICTIONLESS, ev.residual = ev.parts = 0.0, ev.v_acc = 0.0;
    ev.rest_work = -1.0;
    gac_contact_gaps(md, ev.x, s->p, gaps);
    /* The resting contacts are at rest: their normal velocities at an event inside a step are the dense output's,
       off by its error (~rtol |qd|, of either sign), where the law's rounds tell rest from separation at 1e-11 of
       the approach; a held contact a hair's breadth from separating would sit out the first round and be struck in
       a later one with its own e.  So they are brought to rest first (the velocity projection of the step ends: a
       plastic correction of that error, which cannot gain energy). */
    if (s->nresting > 0) (void)gac_project(s, s->xs, s->nresting, s->resting, 0);   /* ev.x: unchanged if it fails */
    gac_normal_velocities(md, ev.x, s->p, vn);
    r->ncontact = 0;
    r->nlanded = r->nreleased = 0;
    r->rounds = r->plastic = r->law_elastic = 0;
    r->energy_rest = 0.0;
    r->roundoff = 1e-10;
    r->roundoff_cause = GAC_ROUNDOFF_FLOOR;
    r->refusal = GAC_REFUSED_NONE;
    r->law = GAC_IMPACT_LAW_FRICTIONLESS;
    r->residual = 0.0;
    if (!gac_is_impact(s, &ev)) return 0;                /* grazing touch: nothing to resolve */
    code = gac_gather(s, &ev);
    if (code != GAC_OK) return code;
    r->t = t;
    md->energy(ev.x, ev.x + nq, s->p, E);
    if (!gac_finite(E, 2)) return GAC_ERR_NONFINITE;
    ev.T_before = E[0];
    r->energy_before = E[0] + E[1];
    for (i = 0; i < nq; ++i) {
        r->q[i] = ev.x[i];
        r->qd_before[i] = ev.x[nq + i];
    }
    code = gac_who_lands(s, &ev);
    if (code == GAC_OK) code = gac_apply_law(s, &ev, r);
    if (code == GAC_OK) code = gac_check_law(s, &ev, r);
    if (code != GAC_OK) return code;
    gac_normal_velocities(md, s->x1, s->p, vn);          /* from here on: after the law */
    code = gac_choose_resting(s, &ev, &nset, set);
    if (code == GAC_OK && nset > 0) code = gac_hold_resting(s, &ev, &nset, set, r);
    if (code != GAC_OK) return code;
    if (ev.rounds == 0) {                               /* no impulse: an impact only if a contact lands */
        int same = nset == s->nresting;
        for (k = 0; same && k < nset; ++k) same = s->is_resting[set[k]];
        if (same) return 0;
    }
    return gac_finish(s, &ev, nset, set, r);
}

