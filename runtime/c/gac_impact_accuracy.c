/*
 * gac_impact_accuracy.c -- how accurately an impact's law was solved, measured after the solve (a posteriori) and
 * improved by iterative refinement:
 *   the responses Y_a = I_f^-1 n_a the law works with are refined before it (r = n_a - I_f Y_a, Y_a += I_f^-1 r);
 *   after it, the velocities qd+ are refined against the momentum balance I_f (qd+ - qd-) = J^T Lambda with the
 *   law's impulses Lambda and, together, against what the law wants of the contacts' velocities (gamma+ = -e gamma-
 *   on the normals, and on the tangents of the contacts that stick), and the energy the remaining residuals can move
 *   is the impact's accuracy.
 * I_f v is the model's generalized_momentum and J^T Lambda its contact_generalized_force (O(n) each, neither is
 * formed); the corrections use inertia_solve.  The momentum balance and the energy identity are evaluated with the
 * kernels' long-double variants where the model has them (generalized_momentum_ld, contact_generalized_force_ld,
 * energy_ld), in double otherwise.
 */
#include "gac_internal.h"

#include <fenv.h>
#include <float.h>
#include <math.h>

#define GAC_REFINE_STEPS 4        /* refinement steps at most (each one O(n)); they stop once no longer improving */
#define GAC_REFINE_BALANCE_STEPS 32  /* of the impulses against the velocities, qd+ kept (each O(n)); on nearly
                                        dependent rows of an ill-conditioned I_f a step can take off as little as
                                        half, and they stop once not halving */
#define GAC_REFINE_IMPULSE_STEPS 8   /* of the impulses against the velocities they give (each O(n) per contact); on
                                        nearly dependent rows with large impulses a step gains only a factor ~10 */

/* y = I_f^-1 g refined in place: r = g - I_f y, y += I_f^-1 r, while |r| (largest component) falls by half and is
 * above round-off of g; a step that does not improve is undone.  With the model's generalized_momentum_ld, r is
 * evaluated in long double (mixed-precision refinement: each step then shrinks y's error by about cond(I_f) eps,
 * down to y's own rounding in double, where a residual in double stalls at cond(I_f) eps of y).  r, dy: nq
 * scratch. */
void gac_refine_response(const gac_model *m, const double *q, const double *p, const double *g, double *y,
                         double *r, double *dy)
{
    const int nq = m->nq;
    double size = 0.0, previous = INFINITY;
    int i, it;
    for (i = 0; i < nq; ++i) size = fabs(g[i]) > size ? fabs(g[i]) : size;
    for (it = 0; it <= GAC_REFINE_STEPS; ++it) {
        double norm = 0.0;
        if (m->generalized_momentum_ld) {
            long double h[GAC_AT_LEAST_1(nq)];
            m->generalized_momentum_ld(q, y, p, h);
            for (i = 0; i < nq; ++i) r[i] = (double)((long double)g[i] - h[i]);
        } else {
            m->generalized_momentum(q, y, p, r);
            for (i = 0; i < nq; ++i) r[i] = g[i] - r[i];
        }
        for (i = 0; i < nq; ++i) norm = fabs(r[i]) > norm ? fabs(r[i]) : norm;
        if (!(norm < previous)) {                        /* worse (or not finite): back to the previous y */
            if (it > 0) {
                for (i = 0; i < nq; ++i) y[i] += dy[i];
            }
            return;
        }
        if (norm <= 4.0 * GAC_EPS * size || norm > 0.5 * previous || it == GAC_REFINE_STEPS) return;
        previous = norm;
        m->inertia_solve(q, r, p, dy);
        if (!gac_finite(dy, nq)) return;
        for (i = 0; i < nq; ++i) y[i] += dy[i];
        for (i = 0; i < nq; ++i) dy[i] = -dy[i];         /* to undo the step */
    }
}

/* The impact system of gac_impact_system with its responses refined: Y_a = I_f^-1 n_a by gac_refine_response,
 * then A = N I_f^-1 N^T again from them. */
int gac_impact_system_refined(const gac_model *m, const double *q, const double *qd, const double *p,
                              int ncontact_set, const int *contact_set, double *work, double *v, double *e)
{
    const int nq = m->nq;
    double *Y = GAC_WORK_Y(m, work), *A = GAC_WORK_A(m, work), *g = GAC_WORK_G(m, work), *f = GAC_WORK_F(m, work);
    double r[GAC_AT_LEAST_1(nq)], dy[GAC_AT_LEAST_1(nq)];
    int a, c, i;
    const int code = gac_impact_system(m, q, qd, p, ncontact_set, contact_set, work, v, e);
    if (code != GAC_OK) return code;
    for (a = 0; a < ncontact_set; ++a) {
        gac_contact_direction(m, q, p, contact_set[a], f, g);   /* n_a */
        gac_refine_response(m, q, p, g, Y + (long)a * nq, r, dy);
        for (c = 0; c < a; ++c) {
            double s = 0.0;
            for (i = 0; i < nq; ++i) s += g[i] * Y[(long)c * nq + i];
            A[a*ncontact_set + c] = A[c*ncontact_set + a] = s;
        }
        {
            double s = 0.0;
            for (i = 0; i < nq; ++i) s += g[i] * Y[(long)a * nq + i];
            A[a*ncontact_set + a] = s;
        }
    }
    return GAC_OK;
}

/* A direction held by the refinement of an impact's velocities: a combination of Jacobian rows (a contact's inward
 * normal; a tangential axis; or, for a contact sliding on a rough wall, its normal with the tangential rows in the
 * ratio of the law's impulses, so that a correction keeps the impulse on the cone and its direction), the impulses
 * a multiplier along it adds to, and what the law wants of its velocity. */
typedef struct {
    int nrow, row[3];
    double coef[3];
    int contact, tangent;  /* the impact's contact (index into list), and -1 (normal or slide) or the tangential axis */
    int aimed;             /* the law sets its velocity: target */
    double target, weight; /* m/s; N s (the impulse that a miss of the target costs work against) */
} gac_held;

/* w = W^T f of held direction h: f (njrow, scratch) its rows with their coefficients, w (nq) their generalized
 * force. */
static void gac_held_force(const gac_model *m, const double *q, const double *p, const gac_held *h, double *f,
                           double *w)
{
    int k;
    for (k = 0; k < m->njrow; ++k) f[k] = 0.0;
    for (k = 0; k < h->nrow; ++k) f[h->row[k]] += h->coef[k];
    m->contact_generalized_force(q, f, p, w);
}

/* The system of nh held directions, responses refined: Y_h = I_f^-1 w_h (gac_refine_response), A = W I_f^-1 W^T from
 * them, in work's Y and A. */
static void gac_held_system(const gac_model *m, const double *q, const double *p, int nh, const gac_held *held,
                            double *work)
{
    const int nq = m->nq;
    double *Y = GAC_WORK_Y(m, work), *A = GAC_WORK_A(m, work), *g = GAC_WORK_G(m, work), *f = GAC_WORK_F(m, work);
    double r[GAC_AT_LEAST_1(nq)], dy[GAC_AT_LEAST_1(nq)];
    int h, c, i;
    for (h = 0; h < nh; ++h) {
        double *Yh = Y + (long)h * nq;
        gac_held_force(m, q, p, &held[h], f, g);         /* w_h */
        m->inertia_solve(q, g, p, Yh);
        gac_refine_response(m, q, p, g, Yh, r, dy);
        for (c = 0; c <= h; ++c) {
            double s = 0.0;
            for (i = 0; i < nq; ++i) s += g[i] * Y[(long)c * nq + i];
            A[h*nh + c] = A[c*nh + h] = s;
        }
    }
}

/* The velocity along held direction h (its rows' velocities from the model's contact velocities vel, or qd for a
 * stop), less the tangential part of a slide's (held at its value: the slide's target is its normal velocity). */
static double gac_held_velocity(const gac_model *m, const int *list, const gac_held *h, const double *qd,
                                const double *vel)
{
    const gac_contact *k = &m->contacts[list[h->contact]];
    if (h->tangent < 0) return k->normal_sign * gac_row_value(m, list[h->contact], qd, vel);
    return vel[3 * (k->point - 1) + h->tangent];
}

/* The contact law's residual after the impact, as energy (J): the work its violated conditions leave, for a law
 * solved in one round (none after several rounds or a plastic closing one, where the conditions are the rounds';
 * nor for the law with a common e).  At contact a with normal velocities gamma-/+ (xi_N = gamma+ + e gamma-, e = 0
 * for a contact that rested: |gamma-| <= 1e-11 of the fastest), |Lambda_N xi_N| (complementarity), and on a
 * rough wall |Lambda_T . xi_T + c_f Lambda_N |xi_T|| (Coulomb's maximal dissipation: 0 when sliding against xi_T,
 * and at the stick |xi_T| = 0), xi_T = gamma+_T + e gamma-_T (GDI) or gamma+_T (Newton + Coulomb).  covered[a]
 * (or NULL): bit 1, contact a's normal condition, bit 2, its stuck tangents', are left out (the refinement holds and
 * aims them: their misses are in the step's energy, gac_step_energy). */
static double gac_law_residual(const gac_model *m, const double *q, const double *p, int n, const int *list,
                               const double *e, const double *F, const double *Ft, int law, const double *qd,
                               const double *qd_plus, const int *covered)
{
    double before[3 * GAC_AT_LEAST_1(m->npoint)], after[3 * GAC_AT_LEAST_1(m->npoint)], scale = 0.0, v_tol, work = 0.0;
    int a;
    m->contact_velocities(q, qd, p, before);
    m->contact_velocities(q, qd_plus, p, after);
    for (a = 0; a < n; ++a) {
        const double v = m->contacts[list[a]].normal_sign * gac_row_value(m, list[a], qd, before);
        scale = fabs(v) > scale ? fabs(v) : scale;
    }
    v_tol = 1e-11 * scale;
    for (a = 0; a < n; ++a) {
        const gac_contact *k = &m->contacts[list[a]];
        const double sign = (double)k->normal_sign;
        const double vm = sign * gac_row_value(m, list[a], qd, before);
        const double vp = sign * gac_row_value(m, list[a], qd_plus, after);
        const double ea = vm < -v_tol ? e[a] : 0.0;
        const double cf = law == GAC_IMPACT_LAW_FRICTIONLESS ? 0.0 : gac_friction_coefficient(m, p, list[a]);
        if (!covered || !(covered[a] & 1)) work += fabs(F[a] * (vp + ea * vm));   /* (else its miss is in the
                                                                                   step's energy) */
        if (covered && (covered[a] & 2)) continue;       /* its stuck tangents' miss: likewise */
        if (cf > 0.0 && k->kind == GAC_CONTACT_WALL) {
            double xi2 = 0.0, power = 0.0;
            int j, axis = 0;
            for (j = 0; j < 2; ++j, ++axis) {
                double xi;
                int comp;
                if (axis == k->axis) ++axis;
                if (k->trow[j] < 0) continue;
                comp = 3 * (k->point - 1) + axis;
                xi = after[comp] + (law == GAC_IMPACT_LAW_NEWTON_COULOMB ? 0.0 : ea * before[comp]);
                xi2 += xi * xi;
                power += Ft[2*a + j] * xi;
            }
            work += fabs(power + cf * F[a] * sqrt(xi2));
        }
    }
    return work;
}

/* The energy identity's residual (J), signed: T(qd+) - T(qd-) - 1/2 Lambda . (gamma+ + gamma-), gamma the velocities
 * along the rows Lambda acts on, T the model's energy; it holds exactly for velocities that balance the impulses,
 * whatever the law, and measures what evaluating T and the rates resolves (the quantity the post-conditions
 * compare). */
static double gac_energy_identity(const gac_model *m, const double *q, const double *p, int n, const int *list,
                                  const double *F, const double *Ft, const double *qd, const double *qd_plus)
{
    double before[3 * GAC_AT_LEAST_1(m->npoint)], after[3 * GAC_AT_LEAST_1(m->npoint)], E0[2], E1[2];
    long double work = 0.0L;
    int a;
    m->contact_velocities(q, qd, p, before);
    m->contact_velocities(q, qd_plus, p, after);
    m->energy(q, qd, p, E0);
    m->energy(q, qd_plus, p, E1);
    for (a = 0; a < n; ++a) {
        const gac_contact *k = &m->contacts[list[a]];
        int j, axis = 0;
        work += (long double)F[a] * k->normal_sign
                * (gac_row_value(m, list[a], qd, before) + gac_row_value(m, list[a], qd_plus, after));
        for (j = 0; j < 2 && k->kind == GAC_CONTACT_WALL; ++j, ++axis) {
            int comp;
            if (axis == k->axis) ++axis;
            if (k->trow[j] < 0) continue;
            comp = 3 * (k->point - 1) + axis;
            work += (long double)Ft[2*a + j] * (before[comp] + after[comp]);
        }
    }
    return (double)(((long double)E1[0] - E0[0]) - 0.5L * work);
}

/* The energy identity's residual in long double (the model's long-double kernels), signed: T(qd+) - T(qd-) by energy_ld,
 * and Lambda . (gamma+ + gamma-) = (J^T Lambda) . (qd+ + qd-) with J^T Lambda by contact_generalized_force_ld (f:
 * Lambda in the Jacobian's rows). */
static double gac_energy_identity_ld(const gac_model *m, const double *q, const double *p, const double *f,
                                     const double *qd, const double *qd_plus)
{
    long double E0[2], E1[2], g[GAC_AT_LEAST_1(m->nq)], work = 0.0L;
    int i;
    m->energy_ld(q, qd, p, E0);
    m->energy_ld(q, qd_plus, p, E1);
    m->contact_generalized_force_ld(q, f, p, g);
    for (i = 0; i < m->nq; ++i) work += g[i] * ((long double)qd[i] + qd_plus[i]);
    return (double)((E1[0] - E0[0]) - 0.5L * work);
}

/* f = Lambda in the Jacobian's rows (njrow): each contact's normal impulse F[a] along its inward normal, its
 * tangential impulses Ft[2a..2a+1] along its tangential rows. */
static void gac_impulse_rows(const gac_model *m, int n, const int *list, const double *F, const double *Ft, double *f)
{
    int a, i;
    for (i = 0; i < m->njrow; ++i) f[i] = 0.0;
    for (a = 0; a < n; ++a) {
        const gac_contact *k = &m->contacts[list[a]];
        int j;
        f[k->row] += k->normal_sign * F[a];
        for (j = 0; j < 2 && k->kind == GAC_CONTACT_WALL; ++j) {
            if (k->trow[j] >= 0) f[k->trow[j]] += Ft[2*a + j];
        }
    }
}

/* The velocities the law's rounds leave the contacts with, as the targets of the refinement after several rounds
 * (n): v = v- + A F in contact space, A from refined responses (gac_impact_system_refined, into work), except that
 * a contact the rounds leave at rest is at rest to the law, target 0: one approaching within the rounds' rest
 * tolerance (gac_rounds: the larger of 1e-11 of the fastest approach and the contact's round-off in v, 4 (k + 1)
 * eps (|v_a| + sum_b |A_ab F_b|) summed over the rounds, k the round's contacts; here 4 (n + 1) eps (rounds |v-_a|
 * + sum_b |A_ab| F_b), the rounds' impulses being >= 0), which the rounds did not strike, or one separating slower
 * than 1e-11 of the fastest approach (the law's rest rule; a faster separation within the round-off stays a target:
 * holding it at 0 would take a pull).  On nearly dependent rows with large impulses that round-off reaches 1e-10
 * m/s where the fastest approach is 1 m/s, and the refinement aimed at such a v would move the impulses by it:
 * energy of F times that, not the law's. */
int gac_rounds_velocities(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                          const int *list, const double *F, int rounds, double *work, double *v)
{
    double e_unused[GAC_AT_LEAST_1(m->nq)], v_minus[GAC_AT_LEAST_1(m->nq)], scale = 0.0;
    const double *A = GAC_WORK_A(m, work);
    int a, b;
    const int code = gac_impact_system_refined(m, q, qd, p, n, list, work, v, e_unused);
    if (code != GAC_OK) return code;
    for (a = 0; a < n; ++a) {
        v_minus[a] = v[a];
        scale = fabs(v[a]) > scale ? fabs(v[a]) : scale;
    }
    for (a = 0; a < n; ++a) {
        double size = rounds * fabs(v_minus[a]), tol;
        for (b = 0; b < n; ++b) {
            v[a] += A[a * n + b] * F[b];
            size += fabs(A[a * n + b]) * fabs(F[b]);
        }
        tol = 4.0 * (n + 1) * GAC_EPS * size;
        if (tol < 1e-11 * scale) tol = 1e-11 * scale;
        if ((v[a] < 0.0 && -v[a] <= tol) || (v[a] > 0.0 && v[a] <= 1e-11 * scale)) v[a] = 0.0;
    }
    return GAC_OK;
}

/* The impulses of a frictionless law solved in one round, refined against the velocities they give (iterative
 * refinement of the whole impact, not only of I_f's solves): the contacts that push (F > 0) must end with
 * gamma+ + e gamma- = 0 (e = 0 for a contact that rested: |gamma-| <= 1e-11 of the fastest; after several rounds,
 * with the velocities v- + A F the law's impulses give in contact space: where rows are nearly dependent the
 * impulses can be large, and their responses' round-off moves the model's velocities far from them; targets[a]
 * keeps them as the rounds' impulses gave them on the first call (targets[a] NaN until then), reused as they are on
 * a later call: v- + A F of impulses refined since, by as little as 1e-9 of themselves, can stand far from the
 * rounds' velocities when A is ill-conditioned and the impulses large), gamma+ read off qd_plus
 * with the model's contact velocities.  Their miss d is removed by F_S += A_SS^-1 (-d), qd_plus += Y_S (that change),
 * A_SS = N_S I_f^-1 N_S^T from refined responses (gac_impact_system_refined), while max|d| falls by half; a step
 * that would pull (F < 0) or not improve is not taken.  Each step's length is then set by the misses it made (the
 * model's velocities are linear in the impulses): alpha = -d . Dd / |Dd|^2, Dd the change the full step made to d,
 * where alpha is in (0, 4), the misses before the step were above 1,000 times the stopping miss 4 eps (fastest
 * approach) and the step so scaled does not pull (on nearly dependent rows A_SS is known only to a fraction of itself
 * along its smallest eigenvector, and the full step overshoots or falls short by that fraction).
 * Returns the contacts' largest miss left (m/s). */
static double gac_refine_targets(const gac_model *m, const double *q, const double *p, int n, const int *list,
                                 const double *e, int rounds, double *F, const double *qd, double *qd_plus,
                                 double *work, double *targets)
{
    const int nq = m->nq;
    double before[3 * GAC_AT_LEAST_1(m->npoint)], after[3 * GAC_AT_LEAST_1(m->npoint)], scale = 0.0, v_tol;
    double target[GAC_AT_LEAST_1(nq)], d[GAC_AT_LEAST_1(nq)], d_kept[GAC_AT_LEAST_1(nq)], v_unused[GAC_AT_LEAST_1(nq)], e_unused[GAC_AT_LEAST_1(nq)];
    double previous = INFINITY, trial[GAC_AT_LEAST_1(nq)], kept_F[GAC_AT_LEAST_1(nq)], kept[GAC_AT_LEAST_1(nq)];
    double *Y = GAC_WORK_Y(m, work), *A = GAC_WORK_A(m, work);
    int set[GAC_AT_LEAST_1(nq)], pos[GAC_AT_LEAST_1(nq)], ns = 0, a, i, it, built = 0;
    m->contact_velocities(q, qd, p, before);
    for (a = 0; a < n; ++a) {
        const double v = gac_normal_value(m, q, p, list[a], qd, before);
        scale = fabs(v) > scale ? fabs(v) : scale;
    }
    v_tol = 1e-11 * scale;
    if (rounds > 1) {                                    /* several rounds: the velocities the law's impulses give
                                                            in contact space, v- + A F, are its own */
        double v[GAC_AT_LEAST_1(nq)];
        if (gac_rounds_velocities(m, q, qd, p, n, list, F, rounds, work, v) != GAC_OK) return 0.0;
        for (a = 0; a < n; ++a) {
            if (!(F[a] > 0.0)) continue;
            if (isnan(targets[a])) targets[a] = v[a];    /* the rounds' own, once */
            target[ns] = targets[a];
            pos[ns] = a;
            set[ns++] = list[a];
        }
    } else {
        for (a = 0; a < n; ++a) {
            const double v = gac_normal_value(m, q, p, list[a], qd, before);
            if (!(F[a] > 0.0)) continue;
            target[ns] = v < -v_tol ? -e[a] * v : 0.0;   /* gamma+ wanted */
            pos[ns] = a;
            set[ns++] = list[a];
        }
    }
    if (ns == 0) return 0.0;
    for (it = 0; it < GAC_REFINE_IMPULSE_STEPS; ++it) {
        double miss = 0.0;
        int j;
        m->contact_velocities(q, qd_plus, p, after);
        for (a = 0; a < ns; ++a) d[a] = gac_normal_value(m, q, p, set[a], qd_plus, after) - target[a];
        if (it > 0 && previous > 4e3 * GAC_EPS * scale) {   /* the step's length that the misses it made call
                                                            for (misses well above round-off: near it, their
                                                            quantisation would set the length) */
            double dd = 0.0, dchange = 0.0, length;
            for (a = 0; a < ns; ++a) {
                dd += (d[a] - d_kept[a]) * (d[a] - d_kept[a]);
                dchange += d_kept[a] * (d[a] - d_kept[a]);
            }
            length = dd > 0.0 ? -dchange / dd : 1.0;
            if (length > 0.0 && length < 4.0 && fabs(length - 1.0) > 1e-3) {
                int pulls = 0;
                for (a = 0; a < ns; ++a) pulls |= kept_F[a] + length * (F[pos[a]] - kept_F[a]) < 0.0;
                if (!pulls) {
                    for (a = 0; a < ns; ++a) F[pos[a]] = kept_F[a] + length * (F[pos[a]] - kept_F[a]);
                    for (i = 0; i < nq; ++i) qd_plus[i] = kept[i] + length * (qd_plus[i] - kept[i]);
                    m->contact_velocities(q, qd_plus, p, after);
                    for (a = 0; a < ns; ++a) d[a] = gac_normal_value(m, q, p, set[a], qd_plus, after) - target[a];
                }
            }
        }
        for (a = 0; a < ns; ++a) miss = fabs(d[a]) > miss ? fabs(d[a]) : miss;
        if (!(miss < previous)) {                        /* the last step did not improve: undo it */
            for (a = 0; a < ns; ++a) F[pos[a]] = kept_F[a];
            gac_copy(qd_plus, kept, nq);
            return previous;
        }
        if (miss <= 4.0 * GAC_EPS * scale || miss > 0.5 * previous) return miss;
        previous = miss;
        if (!built) {                                    /* A_SS and Y_S, once */
            if (gac_impact_system_refined(m, q, qd, p, ns, set, work, v_unused, e_unused) != GAC_OK
                || gac_ldlt(ns, A, 1e-13) != 0) return miss;
            built = 1;
        }
        for (a = 0; a < ns; ++a) trial[a] = -d[a];
        gac_ldlt_solve(ns, A, trial);                    /* the impulses' change */
        if (!gac_finite(trial, ns)) return miss;
        for (a = 0; a < ns; ++a) {
            if (F[pos[a]] + trial[a] < 0.0) return miss;  /* it would pull: keep the law's */
        }
        for (a = 0; a < ns; ++a) {
            kept_F[a] = F[pos[a]];
            d_kept[a] = d[a];
            F[pos[a]] += trial[a];
        }
        gac_copy(kept, qd_plus, nq);
        for (i = 0; i < nq; ++i) {
            double s = 0.0;
            for (j = 0; j < ns; ++j) s += Y[(long)j * nq + i] * trial[j];
            qd_plus[i] += s;
        }
    }
    return previous;
}

/* After several rounds, the approach the model's velocities still show: the rounds end when no contact approaches
 * in their own contact-space velocities (v += A F per round), which on nearly dependent rows can differ from the
 * model's (qd+ read through the contact velocities) by A's round-off times large impulses; a contact left
 * approaching faster than v_tol (the rounds' own) is then struck by a plastic round of its own, F_a += -v_a / A_aa,
 * qd+ += Y_a of that (Gauss-Seidel over such contacts, a few sweeps, each taking energy: dT = 1/2 dF_a v_a < 0), as
 * the law would strike it were its velocities exact.  A joint solve over them would ask nearly dependent rows for
 * independent velocities: impulses of the rows' condition number, and round-off of their energy. */
void gac_close_approach(const gac_model *m, const double *q, const double *p, int n, const int *list,
                        double *F, const double *qd, double *qd_plus, double v_tol, double *work)
{
    const int nq = m->nq;
    double v[GAC_AT_LEAST_1(nq)], e_unused[GAC_AT_LEAST_1(nq)], vel[3 * GAC_AT_LEAST_1(m->npoint)];
    const double *Y = GAC_WORK_Y(m, work), *A = GAC_WORK_A(m, work);
    int a, b, i, sweep, built = 0;
    for (sweep = 0; sweep < 4; ++sweep) {
        int struck = 0;
        m->contact_velocities(q, qd_plus, p, vel);
        for (a = 0; a < n; ++a) v[a] = gac_normal_value(m, q, p, list[a], qd_plus, vel);
        for (a = 0; a < n; ++a) {
            double dF;
            if (!(v[a] < -v_tol)) continue;
            if (!built) {
                double v_unused[GAC_AT_LEAST_1(nq)];
                if (gac_impact_system_refined(m, q, qd, p, n, list, work, v_unused, e_unused) != GAC_OK) return;
                built = 1;
            }
            if (!(A[a * n + a] > 0.0)) continue;
            dF = -v[a] / A[a * n + a];
            F[a] += dF;
            for (i = 0; i < nq; ++i) qd_plus[i] += Y[(long)a * nq + i] * dF;
            for (b = 0; b < n; ++b) v[b] += A[b * n + a] * dF;
            struck = 1;
        }
        if (!struck) return;
    }
}

/* The impulses of a frictionless law refined against the velocities they give (gac_refine_targets; targets[n]: the
 * several rounds' velocities of the contacts that push, NaN until the first call computes them), then, after
 * several rounds, the approach left closed (gac_close_approach).  Returns the contacts' largest miss left (m/s). */
double gac_refine_impulses(const gac_model *m, const double *q, const double *p, int n, const int *list,
                           const double *e, int rounds, double *F, const double *qd, double *qd_plus, double *work,
                           double *targets)
{
    const double miss = gac_refine_targets(m, q, p, n, list, e, rounds, F, qd, qd_plus, work, targets);
    if (rounds > 1) {
        double vel[3 * GAC_AT_LEAST_1(m->npoint)], scale = 0.0;
        int a;
        m->contact_velocities(q, qd, p, vel);
        for (a = 0; a < n; ++a) {
            const double v = fabs(gac_normal_value(m, q, p, list[a], qd, vel));
            scale = v > scale ? v : scale;
        }
        gac_close_approach(m, q, p, n, list, F, qd, qd_plus, 1e-11 * scale, work);
    }
    return miss;
}

/* The momentum before the impact, I_f qd-, evaluated once: in long double, and in double under each sampling
 * rounding mode (gac_sampled). */
typedef struct {
    long double *ld;                                     /* nq, or NULL: no long-double kernels */
    double *sampled;                                     /* GAC_ROUNDING_SAMPLES x nq */
} gac_momentum_before;

/* The rounding modes the double kernels are evaluated under to sample their evaluation error: to nearest, and
 * upward and downward where the platform has them (Kahan's test of rerunning a computation under each rounding
 * mode: directed rounding biases every operation's error, so a sample cannot come out small by chance). */
#if defined(FE_UPWARD) && defined(FE_DOWNWARD) && LDBL_MANT_DIG > DBL_MANT_DIG
#define GAC_ROUNDING_SAMPLES 3
static const int gac_rounding_modes[GAC_ROUNDING_SAMPLES] = {FE_TONEAREST, FE_UPWARD, FE_DOWNWARD};
#else
#define GAC_ROUNDING_SAMPLES 1
static const int gac_rounding_modes[GAC_ROUNDING_SAMPLES] = {0};
#endif
#define GAC_SAMPLED_FLOOR (LDBL_MANT_DIG > DBL_MANT_DIG)   /* long double is wider: its error is double's scaled */
#define GAC_SAMPLED_SAFETY 4.0L   /* the floor is this many times the sampled estimate */

/* out = kernel(q, v, p) (generalized_momentum or contact_generalized_force) in double under sampling rounding mode
 * k, the caller's mode restored after. */
static void gac_sampled(void (*kernel)(const double *, const double *, const double *, double *), const double *q,
                        const double *v, const double *p, int k, double *out)
{
    const int mode = fegetround();
    if (GAC_ROUNDING_SAMPLES > 1) fesetround(gac_rounding_modes[k]);
    kernel(q, v, p, out);
    if (GAC_ROUNDING_SAMPLES > 1) fesetround(mode);
}

/* I_f qd- once: in long double where the model has the kernels (with its double samples), else nothing. */
static void gac_momentum_before_eval(const gac_model *m, const double *q, const double *qd, const double *p,
                                     gac_momentum_before *before)
{
    int k;
    if (!before->ld) return;
    m->generalized_momentum_ld(q, qd, p, before->ld);
    for (k = 0; k < GAC_ROUNDING_SAMPLES; ++k) gac_sampled(m->generalized_momentum, q, qd, p, k, before->sampled + (long)k * m->nq);
}

/* The momentum balance's residual r = I_f (qd+ - qd-) - J^T Lambda for the impulses F, Ft (before: I_f qd- in long
 * double, when the model has the long-double kernels; its ld NULL: in double), with what it moves:
 * balance = |qd+ . r| (T's change were qd+ moved to balance), moved = |qd- . r| (with it, the energy identity's miss
 * for these impulses: T+ - T- - 1/2 Lambda . (gamma+ + gamma-) = 1/2 (qd+ + qd-) . r), the floors of what
 * evaluating r resolves, stored = eps/2 sum_i |qd+_i| |(I_f qd+)_i| (what rounding qd+ to doubles can move T by: no
 * refinement of qd+ gets below it), and each component's bound (|r_i| and its evaluation).  In long double r is
 * evaluated from the stored qd+ itself, so balance already measures what storing it moved, and stored only ends the
 * refinement; in double qd+ - qd- is rounded before I_f applies to it, so floor carries stored too.
 * The long-double evaluation's error is measured, not bounded a priori: the same kernels evaluated in double
 * (h+, h-, g under each sampling rounding mode k, gac_rounding_modes) give r_d,k, and qd+ . (r_d,k - r) is double's
 * error in the measure qd+ . r; the kernels being the same straight-line programs, long double's is that scaled by
 * eps_L / eps (their unit round-offs), and the floor is 4 eps_L / eps max_k |qd+ . (r_d,k - r)| (moved's with qd-),
 * plus eps_L sum_i |qd+_i| (|(I_f qd+)_i| + |(I_f qd-)_i| + |g_i|), the rounding of the outputs themselves.  (The
 * measure is signed: along a soft direction of I_f, qd+'s components are large and the rounding errors of I_f qd+
 * lie mostly along I_f's stiff directions, which they do not move T along; sum_i |qd+_i| |delta_i| would count them.)
 * Where long double is no wider than double, the a-priori 4 (nq + 1) eps_L sum_i |qd+_i| (...). */
typedef struct {
    double *r, *bound;                                   /* nq each, the caller's */
    double *h;                                           /* nq, the caller's or NULL: I_f qd+ (long double route) */
    double balance, floor, stored, moved, moved_floor;
    double signed_balance, signed_moved;                 /* qd+ . r and qd- . r with their signs */
} gac_balance;

static void gac_balance_residual(const gac_model *m, const double *q, const double *p, int n, const int *list,
                                 const double *F, const double *Ft, const double *qd, const double *qd_plus,
                                 const gac_momentum_before *before, gac_balance *b)
{
    const int nq = m->nq;
    double f[GAC_AT_LEAST_1(m->njrow)], g[GAC_AT_LEAST_1(nq)], change[GAC_AT_LEAST_1(nq)];
    double p_change[GAC_AT_LEAST_1(nq)], p_plus[GAC_AT_LEAST_1(nq)];
    long double h_plus[GAC_AT_LEAST_1(nq)], g_ld[GAC_AT_LEAST_1(nq)];
    long double work_r = 0.0L, work_m = 0.0L, size = 0.0L, size_m = 0.0L, stored = 0.0L;
    int i, k;
    gac_impulse_rows(m, n, list, F, Ft, f);              /* Lambda in the Jacobian's rows */
    if (before && before->ld) {                          /* r = I_f qd+ - I_f qd- - g, all in long double */
        const long double *h_minus = before->ld;
        long double sampled = 0.0L, sampled_m = 0.0L;
        m->contact_generalized_force_ld(q, f, p, g_ld);
        m->generalized_momentum_ld(q, qd_plus, p, h_plus);
        for (k = 0; k < GAC_ROUNDING_SAMPLES && GAC_SAMPLED_FLOOR; ++k) {   /* double's evaluation error of the
                                                                               measures qd+ . r and qd- . r */
            const double *h_minus_d = before->sampled + (long)k * nq;
            long double d_plus = 0.0L, d_minus = 0.0L;
            gac_sampled(m->generalized_momentum, q, qd_plus, p, k, p_plus);
            gac_sampled(m->contact_generalized_force, q, f, p, k, g);
            for (i = 0; i < nq; ++i) {
                const long double delta = (((long double)p_plus[i] - h_minus_d[i]) - g[i])
                                          - ((h_plus[i] - h_minus[i]) - g_ld[i]);
                d_plus += qd_plus[i] * delta;
                d_minus += qd[i] * delta;
            }
            sampled = fabsl(d_plus) > sampled ? fabsl(d_plus) : sampled;
            sampled_m = fabsl(d_minus) > sampled_m ? fabsl(d_minus) : sampled_m;
        }
        for (i = 0; i < nq; ++i) {
            const long double ri = (h_plus[i] - h_minus[i]) - g_ld[i];
            const long double evaluated = fabsl(h_plus[i]) + fabsl(h_minus[i]) + fabsl(g_ld[i]);
            b->r[i] = (double)ri;
            work_r += qd_plus[i] * ri;
            work_m += qd[i] * ri;
            size += fabsl((long double)qd_plus[i]) * evaluated;
            size_m += fabsl((long double)qd[i]) * evaluated;
            stored += fabsl((long double)qd_plus[i]) * fabsl(h_plus[i]);
            if (b->h) b->h[i] = (double)h_plus[i];
            b->bound[i] = (double)(fabsl(ri) + 4.0L * (nq + 1) * LDBL_EPSILON * evaluated
                                   + 0.5L * GAC_EPS * fabsl(h_plus[i]));
        }
        if (GAC_SAMPLED_FLOOR) {
            const long double scale = GAC_SAMPLED_SAFETY * LDBL_EPSILON / DBL_EPSILON;
            b->floor = (double)(scale * sampled + LDBL_EPSILON * size);
            b->moved_floor = (double)(scale * sampled_m + LDBL_EPSILON * size_m);
        } else {
            b->floor = (double)(4.0L * (nq + 1) * LDBL_EPSILON * size);
            b->moved_floor = (double)(4.0L * (nq + 1) * LDBL_EPSILON * size_m);
        }
        b->stored = (double)(0.5L * GAC_EPS * stored);
    } else {
        m->contact_generalized_force(q, f, p, g);
        for (i = 0; i < nq; ++i) change[i] = qd_plus[i] - qd[i];
        m->generalized_momentum(q, change, p, p_change);  /* I_f (qd+ - qd-): no cancelling of qd-'s parts */
        m->generalized_momentum(q, qd_plus, p, p_plus);
        for (i = 0; i < nq; ++i) {
            const long double ri = (long double)p_change[i] - g[i];
            b->r[i] = (double)ri;
            work_r += qd_plus[i] * ri;
            work_m += qd[i] * ri;
            size += fabsl((long double)qd_plus[i]) * (fabs(p_change[i]) + fabs(g[i]));
            size_m += fabsl((long double)qd[i]) * (fabs(p_change[i]) + fabs(g[i]));
            stored += fabsl((long double)qd_plus[i]) * fabs(p_plus[i]);
            if (b->h) b->h[i] = p_plus[i];
            b->bound[i] = fabs(b->r[i]) + 4.0 * (nq + 1) * GAC_EPS * (fabs(p_change[i]) + fabs(g[i]))
                          + 0.5 * GAC_EPS * fabs(p_plus[i]);
        }
        b->floor = 4.0 * (nq + 1) * GAC_EPS * (double)size + 0.5 * GAC_EPS * (double)stored;
        b->stored = 0.0;
        b->moved_floor = 4.0 * (nq + 1) * GAC_EPS * (double)size_m;
    }
    b->signed_balance = (double)work_r;
    b->signed_moved = (double)work_m;
    b->balance = fabs(b->signed_balance);
    b->moved = fabs(b->signed_moved);
}

/* The momentum balance of velocities qd -> qd_plus against a generalized impulse g (nq, long double: its terms
 * summed without rounding to double), in long double with the model's long-double kernels: r = I_f qd+ - I_f qd- - g;
 * *balance = |qd+ . r| (J) and *floor what evaluating r resolves, measured as in gac_balance_residual (the double
 * kernels under each rounding mode: 4 eps_L / eps max_k |qd+ . (r_d,k - r)| + eps_L sum_i |qd+_i| (|(I_f qd+)_i| +
 * |(I_f qd-)_i| + |g_i|)).  Returns 0 (nothing written) for a model without the long-double kernels. */
int gac_momentum_balance_ld(const gac_model *m, const double *q, const double *p, const long double *g,
                            const double *qd, const double *qd_plus, double *balance, double *floor)
{
    const int nq = m->nq;
    long double h_minus[GAC_AT_LEAST_1(nq)], h_plus[GAC_AT_LEAST_1(nq)], work = 0.0L, size = 0.0L, sampled = 0.0L;
    double d_minus[GAC_AT_LEAST_1(nq)], d_plus[GAC_AT_LEAST_1(nq)];
    int i, k;
    if (!m->generalized_momentum_ld) return 0;
    m->generalized_momentum_ld(q, qd, p, h_minus);
    m->generalized_momentum_ld(q, qd_plus, p, h_plus);
    for (i = 0; i < nq; ++i) {
        const long double ri = (h_plus[i] - h_minus[i]) - g[i];
        work += qd_plus[i] * ri;
        size += fabsl((long double)qd_plus[i]) * (fabsl(h_plus[i]) + fabsl(h_minus[i]) + fabsl(g[i]));
    }
    for (k = 0; k < GAC_ROUNDING_SAMPLES && GAC_SAMPLED_FLOOR; ++k) {
        long double d = 0.0L;
        gac_sampled(m->generalized_momentum, q, qd, p, k, d_minus);
        gac_sampled(m->generalized_momentum, q, qd_plus, p, k, d_plus);
        for (i = 0; i < nq; ++i)
            d += qd_plus[i] * (((long double)d_plus[i] - d_minus[i]) - (h_plus[i] - h_minus[i]));
        sampled = fabsl(d) > sampled ? fabsl(d) : sampled;
    }
    *balance = fabs((double)work);
    *floor = GAC_SAMPLED_FLOOR ? (double)(GAC_SAMPLED_SAFETY * LDBL_EPSILON / DBL_EPSILON * sampled
                                          + LDBL_EPSILON * size)
                               : (double)(4.0L * (nq + 1) * LDBL_EPSILON * size);
    return 1;
}

/* Lambda += dLambda along the held directions (a slide's direction adds to its tangential impulses in ratio). */
static void gac_held_add(const gac_model *m, const int *list, int nh, const gac_held *held, const double *dl,
                         double *F, double *Ft)
{
    int a, k;
    for (a = 0; a < nh; ++a) {
        const int c = held[a].contact;
        const gac_contact *kc = &m->contacts[list[c]];
        if (held[a].tangent >= 0) {
            Ft[2*c + (held[a].tangent > kc->axis ? held[a].tangent - 1 : held[a].tangent)] += dl[a];
            continue;
        }
        F[c] += dl[a];
        for (k = 1; k < held[a].nrow; ++k) Ft[2*c + (held[a].row[k] == kc->trow[0] ? 0 : 1)] += held[a].coef[k] * dl[a];
    }
}

/* 1 if adding dLambda along the held directions would make a contact's normal impulse pull (F < 0) or take a stuck
 * contact's tangential impulse out of its Coulomb cone (|Lambda_T| > c_f Lambda_N, its ratio to Lambda_N growing: a
 * slide's direction moves its impulses in ratio, along the cone). */
static int gac_held_would_pull(const gac_model *m, const double *p, const int *list, int n, int nh,
                               const gac_held *held, const double *F, const double *Ft, const double *dl)
{
    double F2[GAC_AT_LEAST_1(m->nq)], Ft2[2 * GAC_AT_LEAST_1(m->nq)];
    int a;
    for (a = 0; a < nh; ++a) {
        if (held[a].tangent < 0 && F[held[a].contact] + dl[a] < 0.0) return 1;
    }
    gac_copy(F2, F, n);
    gac_copy(Ft2, Ft, 2 * n);
    gac_held_add(m, list, nh, held, dl, F2, Ft2);
    for (a = 0; a < n; ++a) {
        const double cf = gac_friction_coefficient(m, p, list[a]);
        const double before = hypot(Ft[2*a], Ft[2*a + 1]), after = hypot(Ft2[2*a], Ft2[2*a + 1]);
        if (after > cf * F2[a] && after * F[a] > (1.0 + 1e-12) * before * F2[a]) return 1;   /* |L_T| / L_N grows */
    }
    return 0;
}

/* The held directions' misses of the law's targets at qd+ (m/s; 0 for one not aimed), in miss; returns their work
 * sum_h weight_h |miss_h| (J).  vel: the contact velocities at qd+. */
static double gac_held_misses(const gac_model *m, const int *list, int nh, const gac_held *held, const double *qd_plus,
                              const double *vel, double *miss)
{
    double missed = 0.0;
    int h;
    for (h = 0; h < nh; ++h) {
        miss[h] = held[h].aimed ? gac_held_velocity(m, list, &held[h], qd_plus, vel) - held[h].target : 0.0;
        missed += held[h].weight * fabs(miss[h]);
    }
    return missed;
}

/* What the stored qd+'s energy misses the law's by, to first order, signed (J): the refinement's next step,
 * qd+ -> qd+ - I_f^-1 r + Y_H dLambda_H with A_HH dLambda_H = Y_H . r - miss_H, balances the impulses exactly and
 * meets the held targets to first order; it moves T by -(qd+ . r - sum_h (w_h . qd+) dLambda_h) (I_f symmetric, w_h
 * the held directions' generalized forces).  signed_balance: qd+ . r; r (nq) the residual; A_HH factored and Y_H in
 * work (gac_held_system). */
static double gac_step_energy(const gac_model *m, const double *q, const double *p, int nh, const gac_held *held,
                              double *work, const double *r, const double *miss, const double *qd_plus,
                              double signed_balance)
{
    const int nq = m->nq;
    const double *Y = GAC_WORK_Y(m, work);
    double dl[GAC_AT_LEAST_1(nq)], f[GAC_AT_LEAST_1(m->njrow)], w[GAC_AT_LEAST_1(nq)];
    long double energy = signed_balance;
    int h, i;
    for (h = 0; h < nh; ++h) {
        long double sum = 0.0L;
        for (i = 0; i < nq; ++i) sum += (long double)Y[(long)h * nq + i] * r[i];
        dl[h] = (double)sum - miss[h];
    }
    if (nh > 0) gac_ldlt_solve(nh, GAC_WORK_A(m, work), dl);
    for (h = 0; h < nh; ++h) {
        long double along = 0.0L;
        gac_held_force(m, q, p, &held[h], f, w);
        for (i = 0; i < nq; ++i) along += (long double)w[i] * qd_plus[i];
        energy -= along * dl[h];
    }
    return gac_finite(dl, nh) ? (double)energy : signed_balance;
}

/* Rounding qd+ to doubles moves T by (I_f qd+) . delta: each component is moved by whole units in its last place
 * (at most GAC_ROUND_ULPS, 4096, either way: 1e-12 of it) to bring the step's energy (gac_step_energy, `energy`) nearest 0, the
 * components taken by the size of a unit's effect, largest first (greedy: the coarse ones first, the fine ones then
 * take up what is left).  h: I_f qd+; r: the residual (its change with delta, I_f delta, adds r_i delta_i).  The
 * stored velocities then are the doubles nearest the law's in energy, within a few units in the last place of each
 * component, rather than the nearest in each; the caller measures the result and keeps it only if it is better. */
#define GAC_ROUND_ULPS 4096.0
static void gac_round_to_energy(int nq, const double *h, const double *r, double energy, double *qd_plus)
{
    double effect[GAC_AT_LEAST_1(nq)];
    int order[GAC_AT_LEAST_1(nq)], i, j;
    for (i = 0; i < nq; ++i) {
        const double up = nextafter(qd_plus[i], INFINITY) - qd_plus[i];
        effect[i] = fabs(up * (h[i] + r[i]));
        order[i] = i;
    }
    for (i = 1; i < nq; ++i) {                           /* by effect, largest first */
        const int c = order[i];
        for (j = i; j > 0 && effect[order[j - 1]] < effect[c]; --j) order[j] = order[j - 1];
        order[j] = c;
    }
    for (j = 0; j < nq; ++j) {
        const int c = order[j];
        const double g = h[c] + r[c], toward = -energy * g > 0.0 ? INFINITY : -INFINITY;
        const double unit = nextafter(qd_plus[c], toward) - qd_plus[c];
        double units, moved, next;
        int k;
        if (!(effect[c] > 0.0) || !isfinite(unit) || unit == 0.0) continue;
        units = floor(-energy / (unit * g) + 0.5);       /* the whole units that bring it nearest 0 */
        units = units > GAC_ROUND_ULPS ? GAC_ROUND_ULPS : units;
        if (units >= 1.0) {
            next = qd_plus[c] + units * unit;
            moved = energy + (next - qd_plus[c]) * g;
            if (isfinite(next) && fabs(moved) < fabs(energy)) {
                qd_plus[c] = next;
                energy = moved;
            }
        }
        for (k = 0; k < 2; ++k) {                        /* and a unit more either way where that is nearer */
            const double up = nextafter(qd_plus[c], INFINITY), down = nextafter(qd_plus[c], -INFINITY);
            const double e_up = energy + (up - qd_plus[c]) * g, e_down = energy + (down - qd_plus[c]) * g;
            if (isfinite(up) && fabs(e_up) < fabs(energy) && fabs(e_up) <= fabs(e_down)) {
                qd_plus[c] = up;
                energy = e_up;
            } else if (isfinite(down) && fabs(e_down) < fabs(energy)) {
                qd_plus[c] = down;
                energy = e_down;
            } else {
                break;
            }
        }
    }
}

/* How accurately the contacts' normal velocities after the impact are known (m/s), the largest over list[0..n-1]:
 * the velocities that balance the impulses exactly differ from qd_plus by I_f^-1 rho, |rho_i| <= bound[i] (the
 * momentum balance's residual and what evaluating it resolves), which moves contact a's velocity by
 * Y_a . rho <= sum_i |Y_a,i| bound[i] (Y_a = I_f^-1 n_a, refined); reading the velocity off qd_plus adds
 * 4 (nq + 1) eps sum_i |n_a,i| |qd+_i|.  Large where I_f is ill-conditioned along the contacts' directions even when
 * the energy is accurate (the energy weighs a velocity error by I_f, a contact velocity by I_f^-1). */
static double gac_velocity_accuracy(const gac_model *m, const double *q, const double *p, int n, const int *list,
                                    const double *qd, const double *qd_plus, const double *bound, double *work)
{
    const int nq = m->nq;
    double v_unused[GAC_AT_LEAST_1(nq)], e_unused[GAC_AT_LEAST_1(nq)], f[GAC_AT_LEAST_1(m->njrow)];
    double g[GAC_AT_LEAST_1(nq)], worst = 0.0;
    const double *Y = GAC_WORK_Y(m, work);
    int a, i;
    if (n < 1 || gac_impact_system_refined(m, q, qd, p, n, list, work, v_unused, e_unused) != GAC_OK) return 0.0;
    for (a = 0; a < n; ++a) {
        double v = 0.0, read = 0.0;
        for (i = 0; i < m->njrow; ++i) f[i] = 0.0;
        f[m->contacts[list[a]].row] = 1.0;
        m->contact_generalized_force(q, f, p, g);        /* n_a */
        for (i = 0; i < nq; ++i) {
            v += fabs(Y[(long)a * nq + i]) * bound[i];
            read += fabs(g[i]) * fabs(qd_plus[i]);
        }
        v += 4.0 * (nq + 1) * GAC_EPS * read;
        worst = v > worst ? v : worst;
    }
    return worst;
}

/* The law's residual after several rounds, as energy (J): sum_a |Lambda_a (gamma+_a - target_a)| over the contacts
 * that push, target_a the velocity the rounds left them with (targets, gac_refine_impulses; 0 for one without, struck
 * by the plastic round that closes an approach), gamma+ read off qd_plus with the model's contact velocities: the
 * work that the velocities' miss of the rounds' own leaves.  (The rounds' conditions hold in their contact-space
 * velocities v- + A F; on nearly dependent rows with large impulses the model's velocities can miss them by A's
 * round-off times the impulses, a pushing contact then left separating, F gamma+ > 0: energy gained.) */
static double gac_rounds_residual(const gac_model *m, const double *q, const double *p, int n, const int *list,
                                  const double *F, const double *targets, const double *qd_plus)
{
    double after[3 * GAC_AT_LEAST_1(m->npoint)], work = 0.0;
    int a;
    m->contact_velocities(q, qd_plus, p, after);
    for (a = 0; a < n; ++a) {
        const double target = isnan(targets[a]) ? 0.0 : targets[a];
        if (!(F[a] > 0.0)) continue;
        work += fabs(F[a] * (gac_normal_value(m, q, p, list[a], qd_plus, after) - target));
    }
    return work;
}

/* The energy the law's rest rule can add (J): a contact whose normal velocity before is below v_tol = 1e-11 of the
 * fastest is at rest to the law (e = 0, gamma+ >= 0), also when it separates that slowly; a push F_a on it then
 * does the work 1/2 F_a gamma-_a > 0 (the energy identity's term), which no condition of the law measures.  known:
 * the rounds' own sum of it (gac_impact_rounds_work), used when >= 0; else, in one round, the sum of 1/2 F_a
 * max(gamma-_a, 0), and after several rounds (each round's resting contacts pushing with that round's velocities,
 * at most v_tol) the bound 1/2 v_tol sum_a F_a. */
static double gac_rest_work(const gac_model *m, const double *q, const double *p, int n, const int *list,
                            const double *F, int rounds, const double *qd, double known)
{
    double before[3 * GAC_AT_LEAST_1(m->npoint)], v[GAC_AT_LEAST_1(m->nq)], scale = 0.0, work = 0.0;
    int a;
    if (known >= 0.0) return known;
    m->contact_velocities(q, qd, p, before);
    for (a = 0; a < n; ++a) {
        v[a] = gac_normal_value(m, q, p, list[a], qd, before);
        scale = fabs(v[a]) > scale ? fabs(v[a]) : scale;
    }
    for (a = 0; a < n; ++a) {
        if (!(F[a] > 0.0)) continue;
        if (rounds > 1) work += 0.5 * F[a] * 1e-11 * scale;
        else if (v[a] > 0.0 && v[a] <= 1e-11 * scale) work += 0.5 * F[a] * v[a];
    }
    return work;
}

/* A frictionless law's residual as energy (J) for contacts that may include link pairs and obstacles (their normal
 * rates by gac_normal_value): solved in one round, sum_a |F_a (gamma+_a + e_a gamma-_a)| (e_a = 0 for a contact at
 * rest, |gamma-| <= 1e-11 of the fastest); after several rounds, against the rounds' velocities (gac_rounds_residual,
 * targets may be NULL: none); and what the rest rule can add (gac_rest_work; rest_work: the rounds' own, or < 0). */
double gac_frictionless_law_work(const gac_model *m, const double *q, const double *p, int n, const int *list,
                                 const double *e, const double *F, int rounds, int plastic, const double *targets,
                                 double rest_work, const double *qd, const double *qd_plus)
{
    double before[3 * GAC_AT_LEAST_1(m->npoint)], after[3 * GAC_AT_LEAST_1(m->npoint)], scale = 0.0, work = 0.0;
    int a;
    if (rounds < 1) return 0.0;
    m->contact_velocities(q, qd, p, before);
    m->contact_velocities(q, qd_plus, p, after);
    for (a = 0; a < n; ++a) {
        const double v = fabs(gac_normal_value(m, q, p, list[a], qd, before));
        scale = v > scale ? v : scale;
    }
    if (rounds == 1 && !plastic) {
        for (a = 0; a < n; ++a) {
            const double vm = gac_normal_value(m, q, p, list[a], qd, before);
            const double vp = gac_normal_value(m, q, p, list[a], qd_plus, after);
            if (F[a] > 0.0) work += fabs(F[a] * (vp + (vm < -1e-11 * scale ? e[a] : 0.0) * vm));
        }
    } else if (rounds > 1 && targets) {
        work += gac_rounds_residual(m, q, p, n, list, F, targets, qd_plus);
    }
    return work + gac_rest_work(m, q, p, n, list, F, rounds, qd, rest_work);
}

/* The impact's accuracy, measured after its law (relative to T, the kinetic energy before), with qd_plus refined
 * in place, and the impulses with it (F, Ft in place).  Lambda: the law's impulses F (along the inward normals) and Ft
 * (along the tangential axes); g = J^T Lambda.  Momentum balance: r = I_f (qd+ - qd-) - g; were qd+ moved to the velocities that balance exactly,
 * qd+ - I_f^-1 r, T would change by qd+ . r to first order (I_f symmetric: no solve enters the measure), so qd+ is
 * refined while |qd+ . r| falls by half and stands above what evaluating r can resolve, by the step that zeroes r
 * and leaves the velocities the law set as it set them (a free step qd+ -= I_f^-1 r moves them along I_f's soft
 * directions, by far more than the law's round-off where I_f is ill-conditioned): the held rows H are the normal
 * rows of the pushing contacts (F > 0) and, under a frictional law, the tangential rows of those on rough walls
 * (their xi_T: 0 where stuck, the slide's direction where sliding):
 *   qd+ += -I_f^-1 r + Y_H dLambda_H, Lambda_H += dLambda_H, A_HH dLambda_H = N_H I_f^-1 r
 * (Y_H, A_HH from refined responses; the normal rows alone where A_HH is singular with the tangential ones, and of
 * those a row dependent on the others takes no multiplier; the law's residual and the energy identity below are measured with the
 * corrected impulses),
 *   E0 = 4 (nq + 1) eps sum_i |qd+_i| (|(I_f (qd+ - qd-))_i| + |g_i|) + eps/2 sum_i |qd+_i| |(I_f qd+)_i|
 * (about 8 (nq + 1) eps T when the velocities' components do not cancel; large where they do, along a soft
 * direction of I_f or near the base chart's singular pose).  With the model's long-double kernels r is evaluated
 * in long double as the difference of two evaluations, r = I_f qd+ - I_f qd- - g (qd+ - qd- is not exact in
 * double), and E0 is measured (gac_balance_residual): 4 eps_L / eps times double's error in qd+ . r, the same
 * kernels evaluated in double under each rounding mode, plus eps_L sum_i |qd+_i| (|(I_f qd+)_i| + |(I_f qd-)_i| +
 * |g_i|), eps_L = LDBL_EPSILON: the stored qd+ is what r is evaluated at, so |qd+ . r| measures what rounding qd+ to doubles moved, and the
 * second part (its a-priori bound) only ends the refinement (the energy identity likewise with energy_ld,
 * gac_energy_identity_ld).  Then the stored qd+'s energy miss to first order, the energy the refinement's next step
 * would move (gac_step_energy: dE = qd+ . r - sum_h (w_h . qd+) dLambda_h), is brought nearest 0 by moving each
 * component by whole units in its last place (gac_round_to_energy; kept if the measured dE falls).  The accuracy
 * is (|dE| + E0 + the contact law's residual work, gac_law_residual, for a law solved in one round, without the
 * conditions the held and aimed directions cover (their misses are in dE; after several rounds the law's conditions
 * are the rounds'; a round solved with a common e, its contacts' smallest, is measured with that e) + the energy
 * identity's residual less 1/2 (qd+ + qd-) . r, which dE counts, gac_energy_identity) / T; *part names the largest
 * of the four (GAC_ROUNDOFF_*). */
double gac_impact_accuracy(const gac_model *m, const double *q, const double *p, int n, const int *list,
                           const double *e, double *F, double *Ft, int law, int rounds, int plastic,
                           const double *qd, double *qd_plus, double T, double *work, double *v_acc,
                           const double *targets, double rest_work, int *part)
{
    const int nq = m->nq;
    double f[GAC_AT_LEAST_1(m->njrow)], r[GAC_AT_LEAST_1(nq)], bound_now[GAC_AT_LEAST_1(nq)];
    double dq[GAC_AT_LEAST_1(nq)], kept[GAC_AT_LEAST_1(nq)], scratch[2 * GAC_AT_LEAST_1(nq)];
    gac_balance res;
    double previous = INFINITY, previous_balance = INFINITY, previous_missed = INFINITY;
    double balance = 0.0, floor = 0.0, law_work = 0.0, identity;
    double bound_kept[GAC_AT_LEAST_1(nq)], h_plus[GAC_AT_LEAST_1(nq)], energy;
    int covered[GAC_AT_LEAST_1(nq)];
    double Fs[GAC_AT_LEAST_1(nq)], F_kept[GAC_AT_LEAST_1(nq)], dl[GAC_AT_LEAST_1(nq)];
    double Fts[2 * GAC_AT_LEAST_1(nq)], Ft_kept[2 * GAC_AT_LEAST_1(nq)];
    const double *Y = GAC_WORK_Y(m, work);
    gac_held held[GAC_AT_LEAST_1(nq)];
    const int extended = m->generalized_momentum_ld != 0 && m->contact_generalized_force_ld != 0;
    long double h_minus[GAC_AT_LEAST_1(nq)];
    double h_minus_sampled[GAC_ROUNDING_SAMPLES * GAC_AT_LEAST_1(nq)];
    gac_momentum_before before_impact;
    double miss[GAC_AT_LEAST_1(nq)], before[3 * GAC_AT_LEAST_1(m->npoint)], after[3 * GAC_AT_LEAST_1(m->npoint)];
    double scale = 0.0, v_tol, e_round = 1.0;
    const int aims = rounds == 1 && !plastic && (law == GAC_IMPACT_LAW_FRICTIONLESS || law == GAC_IMPACT_LAW_GDI
                                                 || law == GAC_IMPACT_LAW_GDI_COMMON_E);
    int nh = 0, nnormal, a, i, it, pass;
    res.r = r;                                           /* the balance's residual and bounds, evaluated in place */
    res.bound = bound_now;
    res.h = h_plus;
    for (a = 0; a < n; ++a) {
        Fs[a] = F[a];
        Fts[2*a] = Ft[2*a];
        Fts[2*a + 1] = Ft[2*a + 1];
    }
    m->contact_velocities(q, qd, p, before);
    for (a = 0; a < n; ++a) {
        const double v = m->contacts[list[a]].normal_sign * gac_row_value(m, list[a], qd, before);
        scale = fabs(v) > scale ? fabs(v) : scale;
    }
    v_tol = 1e-11 * scale;                               /* struck (own e) or at rest (e = 0), as the law's residual */
    if (law == GAC_IMPACT_LAW_GDI_COMMON_E) {            /* the round's e: the smallest of its contacts' */
        for (a = 0; a < n; ++a) {
            const double v = m->contacts[list[a]].normal_sign * gac_row_value(m, list[a], qd, before);
            const double ea = v < -v_tol ? e[a] : 0.0;
            if (v <= v_tol && ea < e_round) e_round = ea;
        }
    }
    /* the held directions: each pushing contact's normal (a slide's with its tangential impulse's ratio), then the
     * tangential axes of those stuck on rough walls under a frictional law */
    for (pass = 0; pass < 2; ++pass) {
        for (a = 0; a < n && nh < nq; ++a) {
            const gac_contact *k = &m->contacts[list[a]];
            const double vm = k->normal_sign * gac_row_value(m, list[a], qd, before);
            const double ea = vm < -v_tol ? (law == GAC_IMPACT_LAW_GDI_COMMON_E ? e_round : e[a]) : 0.0;
            const double cf = law == GAC_IMPACT_LAW_FRICTIONLESS || k->kind != GAC_CONTACT_WALL
                              ? 0.0 : gac_friction_coefficient(m, p, list[a]);
            const int rough = cf > 0.0 && F[a] > 0.0;
            const int slides = rough && hypot(Fts[2*a], Fts[2*a + 1]) >= (1.0 - 1e-6) * cf * F[a];
            int j, axis = 0;
            if (!(F[a] > 0.0)) continue;
            if (pass == 0) {
                gac_held *h = &held[nh++];
                h->nrow = 1;
                h->row[0] = k->row;
                h->coef[0] = (double)k->normal_sign;
                for (j = 0; j < 2 && slides; ++j) {
                    if (k->trow[j] < 0) continue;
                    h->row[h->nrow] = k->trow[j];
                    h->coef[h->nrow++] = Fts[2*a + j] / F[a];
                }
                h->contact = a;
                h->tangent = -1;
                h->aimed = aims;
                h->target = -ea * vm;
                h->weight = F[a];
                continue;
            }
            if (!rough || slides) continue;
            for (j = 0; j < 2; ++j, ++axis) {
                gac_held *h;
                if (axis == k->axis) ++axis;
                if (k->trow[j] < 0 || nh == nq) continue;
                h = &held[nh++];
                h->nrow = 1;
                h->row[0] = k->trow[j];
                h->coef[0] = 1.0;
                h->contact = a;
                h->tangent = axis;
                h->aimed = aims;                         /* stuck: xi_T = 0 */
                h->target = -ea * before[3 * (k->point - 1) + axis];
                h->weight = cf * F[a];
            }
        }
        if (pass == 0) nnormal = nh;
    }
    if (nh > nnormal) {                                  /* with the stuck tangents, if they are independent */
        gac_held_system(m, q, p, nh, held, work);
        if (gac_ldlt(nh, GAC_WORK_A(m, work), 1e-13) != 0) nh = nnormal;
        else nnormal = -1;                               /* factored */
    }
    if (nnormal >= 0 && nh > 0) {                        /* the normals; a normal dependent on the others (held
                                                            with them) takes no multiplier */
        gac_held_system(m, q, p, nh, held, work);
        if (gac_ldlt_drop(nh, GAC_WORK_A(m, work), 1e-13) < 0) nh = 0;   /* none to hold: free steps */
    }
    before_impact.ld = extended ? h_minus : 0;           /* I_f qd-, once */
    before_impact.sampled = h_minus_sampled;
    gac_momentum_before_eval(m, q, qd, p, &before_impact);
    for (it = 0; ; ++it) {
        double missed;
        gac_balance_residual(m, q, p, n, list, Fs, Fts, qd, qd_plus, &before_impact, &res);
        balance = res.balance;
        floor = res.floor;
        m->contact_velocities(q, qd_plus, p, after);
        missed = gac_held_misses(m, list, nh, held, qd_plus, after, miss);   /* of the law's targets */
        if (!(balance + missed < previous)) {            /* the last step did not improve: undo it */
            if (it > 0) {
                gac_copy(qd_plus, kept, nq);
                gac_copy(Fs, F_kept, n);
                gac_copy(Fts, Ft_kept, 2 * n);
                balance = previous_balance;
            }
            break;
        }
        gac_copy(bound_kept, bound_now, nq);
        if (it == GAC_REFINE_STEPS
            || ((balance <= floor + res.stored || balance > 0.5 * previous_balance)          /* neither part still halving */
                && (missed == 0.0 || missed > 0.5 * previous_missed))) break;
        previous = balance + missed;
        previous_balance = balance;
        previous_missed = missed;
        m->inertia_solve(q, r, p, dq);
        if (!gac_finite(dq, nq)) break;
        gac_refine_response(m, q, p, r, dq, scratch, scratch + nq);   /* dq = I_f^-1 r, refined */
        gac_copy(kept, qd_plus, nq);
        gac_copy(F_kept, Fs, n);
        gac_copy(Ft_kept, Fts, 2 * n);
        for (a = 0; a < nh; ++a) {                       /* W_H dq: what the free step does to H's velocities (the
                                                            step taken, rather than Y_H . r, its image through the
                                                            responses, which differ along I_f's soft directions) */
            double s = 0.0;
            gac_held_force(m, q, p, &held[a], f, scratch);   /* w_a */
            for (i = 0; i < nq; ++i) s += scratch[i] * dq[i];
            dl[a] = s;
        }
        for (a = 0; a < nh; ++a) dl[a] -= miss[a];
        if (nh > 0) gac_ldlt_solve(nh, GAC_WORK_A(m, work), dl);   /* A_HH dLambda_H = N_H I_f^-1 r - miss_H */
        if (nh > 0 && !gac_finite(dl, nh)) break;
        if (gac_held_would_pull(m, p, list, n, nh, held, Fs, Fts, dl)) break;   /* keep the impulses as they are */
        for (i = 0; i < nq; ++i) {
            double s = -dq[i];
            for (a = 0; a < nh; ++a) s += Y[(long)a * nq + i] * dl[a];
            qd_plus[i] += s;
        }
        gac_held_add(m, list, nh, held, dl, Fs, Fts);    /* the impulses along the held directions */
    }
    /* The impulses refined against the velocities, qd+ kept (after several rounds over nearly dependent rows the
     * rounds' impulses can stand far from those that balance the velocities, r then lying along the held rows,
     * where it moves no velocity, qd+ . r ~ 0, but the energy identity by qd- . r): Lambda_H += dLambda_H,
     * A_HH dLambda_H = N_H I_f^-1 r, while |qd+ . r| + |qd- . r| falls by half above its floor; never a pull. */
    if (nh > 0) gac_balance_residual(m, q, p, n, list, Fs, Fts, qd, qd_plus, &before_impact, &res);
    for (it = 0; nh > 0 && it < GAC_REFINE_BALANCE_STEPS; ++it) {
        const double now = res.balance + res.moved;
        if (now <= 2.0 * (res.floor + res.stored + res.moved_floor)) break;
        for (a = 0; a < nh; ++a) {                       /* N_H I_f^-1 r = Y_H . r */
            double sum = 0.0;
            for (i = 0; i < nq; ++i) sum += Y[(long)a * nq + i] * res.r[i];
            dl[a] = sum;
        }
        gac_ldlt_solve(nh, GAC_WORK_A(m, work), dl);
        if (!gac_finite(dl, nh)) break;
        if (gac_held_would_pull(m, p, list, n, nh, held, Fs, Fts, dl)) break;
        gac_copy(F_kept, Fs, n);
        gac_copy(Ft_kept, Fts, 2 * n);
        gac_held_add(m, list, nh, held, dl, Fs, Fts);
        gac_balance_residual(m, q, p, n, list, Fs, Fts, qd, qd_plus, &before_impact, &res);
        if (!(res.balance + res.moved <= 0.5 * now)) {   /* not halving: undo the step */
            gac_copy(Fs, F_kept, n);
            gac_copy(Fts, Ft_kept, 2 * n);
            gac_balance_residual(m, q, p, n, list, Fs, Fts, qd, qd_plus, &before_impact, &res);
            break;
        }
        balance = res.balance;
        floor = res.floor;
        gac_copy(bound_kept, res.bound, nq);
    }
    /* The stored qd+'s energy miss, to first order (the next step's, gac_step_energy), with each component's rounding
     * to doubles chosen to bring it nearest 0 where the long-double residual resolves it (kept only if the measure
     * falls) */
    gac_balance_residual(m, q, p, n, list, Fs, Fts, qd, qd_plus, &before_impact, &res);
    m->contact_velocities(q, qd_plus, p, after);
    gac_held_misses(m, list, nh, held, qd_plus, after, miss);
    energy = gac_step_energy(m, q, p, nh, held, work, res.r, miss, qd_plus, res.signed_balance);
    if (extended && fabs(energy) > res.floor) {
        gac_copy(kept, qd_plus, nq);
        gac_round_to_energy(nq, h_plus, res.r, energy, qd_plus);
        gac_balance_residual(m, q, p, n, list, Fs, Fts, qd, qd_plus, &before_impact, &res);
        m->contact_velocities(q, qd_plus, p, after);
        gac_held_misses(m, list, nh, held, qd_plus, after, miss);
        {
            const double rounded = gac_step_energy(m, q, p, nh, held, work, res.r, miss, qd_plus, res.signed_balance);
            if (fabs(rounded) < fabs(energy)) {
                energy = rounded;
            } else {                                     /* no better: the rounding as it was */
                gac_copy(qd_plus, kept, nq);
                gac_balance_residual(m, q, p, n, list, Fs, Fts, qd, qd_plus, &before_impact, &res);
            }
        }
    }
    balance = fabs(energy);
    floor = res.floor;
    gac_copy(bound_kept, res.bound, nq);
    for (a = 0; a < n; ++a) covered[a] = 0;
    for (a = 0; a < nh; ++a) {                           /* the held, aimed directions: in the step's energy (not
                                                            one dependent on the others: no multiplier, no step) */
        if (!held[a].aimed || !(GAC_WORK_A(m, work)[a * nh + a] < 1e299)) continue;
        covered[held[a].contact] |= held[a].tangent < 0 ? 1 : 2;
    }
    if (rounds == 1 && !plastic && law != GAC_IMPACT_LAW_GDI_COMMON_E)
        law_work = gac_law_residual(m, q, p, n, list, e, Fs, Fts, law, qd, qd_plus, covered);
    if (rounds == 1 && !plastic && law == GAC_IMPACT_LAW_GDI_COMMON_E) {   /* the round's law: its smallest e
                                                                             (e_round, as the targets used it) */
        double e_common[GAC_AT_LEAST_1(nq)];
        for (a = 0; a < n; ++a) e_common[a] = e_round;
        law_work = gac_law_residual(m, q, p, n, list, e_common, Fs, Fts, GAC_IMPACT_LAW_GDI, qd, qd_plus, covered);
    }
    if (rounds > 1 && targets)                           /* after several rounds: against the rounds' velocities */
        law_work = gac_rounds_residual(m, q, p, n, list, Fs, targets, qd_plus);
    if (rounds >= 1)                                     /* what the law's rest rule can add */
        law_work += gac_rest_work(m, q, p, n, list, Fs, rounds, qd, rest_work);
    if (extended && m->energy_ld != 0) {                 /* in long double: what 1/2 (qd+ + qd-) . r, the identity's
                                                            miss for velocities off the balance, does not explain */
        gac_impulse_rows(m, n, list, Fs, Fts, f);
        identity = fabs(gac_energy_identity_ld(m, q, p, f, qd, qd_plus)
                        - 0.5 * (res.signed_balance + res.signed_moved));
    } else {
        identity = fabs(gac_energy_identity(m, q, p, n, list, Fs, Fts, qd, qd_plus));
    }
    gac_copy(F, Fs, n);                                  /* the impulses that balance the refined velocities */
    gac_copy(Ft, Fts, 2 * n);
    if (v_acc) *v_acc = gac_velocity_accuracy(m, q, p, n, list, qd, qd_plus, bound_kept, work);
    if (part) {                                          /* the largest part */
        const double parts[4] = {balance, floor, law_work, identity};
        const int names[4] = {GAC_ROUNDOFF_STORED, GAC_ROUNDOFF_EVALUATION, GAC_ROUNDOFF_LAW, GAC_ROUNDOFF_IDENTITY};
        int k, largest = 0;
        for (k = 1; k < 4; ++k) largest = parts[k] > parts[largest] ? k : largest;
        *part = names[largest];
    }
    return (balance + floor + law_work + identity) / (T > 0.0 ? T : 1e-300);
}

