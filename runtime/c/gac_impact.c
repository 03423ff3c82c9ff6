/*
 * gac_impact.c -- the impact phase (Eq. 42-48 of the paper): the impact system of the contacts in the contact set,
 * Newton's law (Eq. 47) solved as in Eq. 48, and its complementarity form in rounds with an exact LCP solve.
 */
#include "gac_internal.h"

#include <math.h>

/* Jacobian row and inward-normal sign (+1.0 / -1.0) of contact c. */
void gac_contact_row(const gac_model *m, int c, int *row, double *sign)
{
    *row = m->contacts[c].row;
    *sign = (double)m->contacts[c].normal_sign;
}

/* Restitution coefficient of contact c's wall: p[e_index], or the model's constant. */
double gac_restitution(const gac_model *m, const double *p, int c)
{
    const gac_contact *contact = &m->contacts[c];
    return contact->e_index >= 0 ? p[contact->e_index] : contact->e_value;
}

/* The base chart's measure |det E| at configuration q: the triple product of the three base joint axes,
 * |a . (e_z x Rz(theta_0) b)| with a = T_0^T e_z, b = T_1 e_z (only their x, y enter; |cos theta_0| for the
 * default twists).  The chart is singular (gimbal lock) where it is 0; I_f's smallest eigenvalue falls like
 * its square.  Of several turning bases (gac_model.nbase), the smallest of their measures. */
double gac_chart_measure(const gac_model *m, const double *q)
{
    double chi = gac_chart_measure_of(gac_model_chart(m, 0), q);
    int j;
    for (j = 1; j < gac_nbase(m); ++j) {
        const double chi_j = gac_chart_measure_of(gac_model_chart(m, j), q);
        if (chi_j < chi) chi = chi_j;
    }
    return chi;
}

/* Contact c's Jacobian row applied to velocities w, unsigned: the rate of its point along its wall's axis,
 * read from vel = contact_velocities(q, w) (npoint x 3), or, for a stop, the rate of its joint angle. */
double gac_row_value(const gac_model *m, int c, const double *w, const double *vel)
{
    const gac_contact *k = &m->contacts[c];
    return k->kind == GAC_CONTACT_STOP ? w[k->coordinate] : vel[3 * (k->point - 1) + k->axis];
}

/* Contact c's normal rate of the generalised velocity w, along its inward normal: its signed Jacobian row applied to
 * w (vel = contact_velocities(q, w)), or for a link pair or an obstacle g . w = n . (v_P - v_Q) at its closest
 * points (gac_link_contact_rate). */
double gac_normal_value(const gac_model *m, const double *q, const double *p, int c, const double *w,
                        const double *vel)
{
    if (gac_rowless(m, c)) return gac_link_contact_rate(m, q, p, c, vel);
    return (double)m->contacts[c].normal_sign * gac_row_value(m, c, w, vel);
}

/* The part of contact c's normal acceleration that does not depend on qdd, along its inward normal: its signed
 * contact_bias row (bias = contact_bias(q, qd)), or for a link pair or an obstacle dg(qd) . qd (gac_rowless_bias).
 * GAC_OK, or GAC_ERR_LINK_CONTACT where that normal has no derivative (crossing axes). */
int gac_normal_bias(const gac_model *m, const double *q, const double *qd, const double *p, int c, const double *bias,
                    double *b)
{
    if (gac_rowless(m, c)) return gac_rowless_bias(m, q, qd, p, c, b);
    *b = (double)m->contacts[c].normal_sign * bias[m->contacts[c].row];
    return GAC_OK;
}

/* n_c = J^T (sign e_row): the generalised force of a unit force along contact c's inward normal (its signed
 * Jacobian row), into g (nq); f (njrow) is scratch.  A link pair: J^T n at its closest points (gac_link.c). */
void gac_contact_direction(const gac_model *m, const double *q, const double *p, int c, double *f, double *g)
{
    int r;
    if (gac_rowless(m, c)) {
        gac_link_contact_direction(m, q, p, c, g);
        return;
    }
    for (r = 0; r < m->njrow; ++r) f[r] = 0.0;
    f[m->contacts[c].row] = (double)m->contacts[c].normal_sign;
    m->contact_generalized_force(q, f, p, g);
}

/* out = I_f^-1 J^T e_row: the response (nq) to a unit force along Jacobian row `row` (+X_axis of its point, or a
 * stop's joint); f (njrow) and g (nq) are scratch.  GAC_ERR_SINGULAR_MASS if the solve is not finite. */
int gac_row_response(const gac_model *m, const double *q, const double *p, int row, double *f, double *g,
                     double *out)
{
    int i;
    for (i = 0; i < m->njrow; ++i) f[i] = 0.0;
    f[row] = 1.0;
    m->contact_generalized_force(q, f, p, g);
    m->inertia_solve(q, g, p, out);
    for (i = 0; i < m->nq; ++i) {
        if (!isfinite(out[i])) return GAC_ERR_SINGULAR_MASS;
    }
    return GAC_OK;
}

/* Assemble the impact problem of the contacts in the contact set (Eq. 44-48 with the velocities eliminated):
 *   Y_a = I_f^-1 n_a (n_a = signed Jacobian row of contact a),  A = N I_f^-1 N^T,  v_a = n_a . qd,
 * with O(n) operators of the model: n_a = J^T (sign e_row) (contact_generalized_force), Y_a by inertia_solve
 * (the articulated-body recursion); neither I_f nor J is formed, so the cost is O(ncontact_set n + ncontact_set^2 nq).
 * work layout: GAC_WORK_Y, GAC_WORK_A, ... (gac_internal.h).
 * v[a] (m/s) and e[a] receive the normal velocity and the restitution of contact contact_set[a]. */
int gac_impact_system(const gac_model *m, const double *q, const double *qd, const double *p, int ncontact_set,
                      const int *contact_set, double *work, double *v, double *e)
{
    const int nq = m->nq;
    double *Y = GAC_WORK_Y(m, work), *A = GAC_WORK_A(m, work), *g = GAC_WORK_G(m, work), *f = GAC_WORK_F(m, work);
    int a, c, i;
    if (m->ncontact == 0) return GAC_ERR_BAD_CONTACT;   /* the scene has no walls */
    if (ncontact_set < 1 || ncontact_set > nq) return GAC_ERR_BAD_CONTACT;
    for (a = 0; a < ncontact_set; ++a) {
        if (contact_set[a] < 0 || contact_set[a] >= m->ncontact) return GAC_ERR_BAD_CONTACT;
        for (c = 0; c < a; ++c) {
            if (contact_set[c] == contact_set[a]) return GAC_ERR_BAD_CONTACT;
        }
    }
    if (gac_chart_measure(m, q) < GAC_CHART_FLOOR) return GAC_ERR_GIMBAL_LOCK;
    for (a = 0; a < ncontact_set; ++a) {
        double rate = 0.0;
        double *Ya = Y + (long)a * nq;
        gac_contact_direction(m, q, p, contact_set[a], f, g);
        m->inertia_solve(q, g, p, Ya);
        for (i = 0; i < nq; ++i) {
            if (!isfinite(Ya[i])) return GAC_ERR_SINGULAR_MASS;
            rate += g[i] * qd[i];
        }
        for (c = 0; c <= a; ++c) {             /* A is symmetric: n_a . Y_c = n_a I_f^-1 n_c */
            double s = 0.0;
            for (i = 0; i < nq; ++i) s += g[i] * Y[(long)c * nq + i];
            A[a*ncontact_set + c] = A[c*ncontact_set + a] = s;
        }
        v[a] = rate;
        e[a] = gac_restitution(m, p, contact_set[a]);
    }
    return GAC_OK;
}

/* qd_plus = qd + sum_a Y_a F_a. */
static void gac_apply_impulse(int nq, const double *qd, int ncontact_set, const double *Y, const double *F,
                              double *qd_plus)
{
    int a, i;
    for (i = 0; i < nq; ++i) {
        double v = qd[i];
        for (a = 0; a < ncontact_set; ++a) v += Y[a*nq + i] * F[a];
        qd_plus[i] = v;
    }
}

int gac_impact(const gac_model *m, const double *GAC_RESTRICT q, const double *GAC_RESTRICT qd,
               const double *GAC_RESTRICT p, int ncontact_set, const int *GAC_RESTRICT contact_set,
               double *GAC_RESTRICT qd_plus, double *GAC_RESTRICT impulse, double *GAC_RESTRICT work)
{
    const int nq = m->nq;
    double v[GAC_AT_LEAST_1(nq)], e[GAC_AT_LEAST_1(nq)];
    double *Y = GAC_WORK_Y(m, work), *A = GAC_WORK_A(m, work);
    int a;
    int code = gac_impact_system_refined(m, q, qd, p, ncontact_set, contact_set, work, v, e);
    if (code != GAC_OK) return code;
    for (a = 0; a < ncontact_set; ++a) impulse[a] = -(1.0 + e[a]) * v[a];     /* A F = -(1 + e) v  (Eq. 47) */
    if (gac_ldlt(ncontact_set, A, 1e-12) != 0) return GAC_ERR_SINGULAR_IMPACT;
    gac_ldlt_solve(ncontact_set, A, impulse);
    gac_apply_impulse(nq, qd, ncontact_set, Y, impulse, qd_plus);
    return GAC_OK;
}

/* The linear complementarity problem  0 <= F  _|_  w = A F + q >= 0  for an n x n symmetric positive
 * (semi)definite A (row-major), n <= max_lcp (<= GAC_LCP_CAP): F is the impulse of each contact along its
 * inward normal, w its normal velocity after (or its excess over the law's bound).  Solved exactly by
 * enumerating the sets S of pushing contacts (A_SS F_S = -q_S, F_S >= 0, w >= 0 elsewhere): first
 * S = {q_a < 0}, then every set, largest first.  A set whose A_SS is singular is skipped (a solution on
 * independent rows exists).  Round-off floors: F_S >= -1e-10 max|F_S| (then clipped to 0), w >= -w_tol.
 * In long double (q, F and the solves; A as given): the rounds' energy balance rests on each solve (below).
 * Returns GAC_OK or GAC_ERR_LCP. */
static int gac_lcp(int max_lcp, int n, const double *A, const long double *q, double w_tol, long double *F)
{
    long double Asub[GAC_LCP_CAP * GAC_LCP_CAP], rhs[GAC_LCP_CAP];
    unsigned long mask, guess = 0UL, full;
    int a, b, tries;
    if (n > max_lcp) return GAC_ERR_LCP;
    full = (1UL << n) - 1UL;
    for (a = 0; a < n; ++a) {
        if (q[a] < 0.0) guess |= 1UL << a;
    }
    for (tries = 0, mask = full; ; ++tries) {
        const unsigned long set = tries == 0 ? guess : mask;
        int idx[GAC_LCP_CAP], k = 0, ok = 1;
        long double fmax = 0.0L;
        for (a = 0; a < n; ++a) {
            if (set & (1UL << a)) idx[k++] = a;
        }
        for (a = 0; a < k; ++a) {
            for (b = 0; b < k; ++b) Asub[a*k + b] = A[idx[a]*n + idx[b]];
            rhs[a] = -q[idx[a]];
        }
        if (k > 0 && gac_ldlt_ld(k, Asub, 1e-12) != 0) ok = 0;
        if (ok && k > 0) gac_ldlt_ld_solve(k, Asub, rhs);
        for (a = 0; ok && a < k; ++a) {
            if (fabsl(rhs[a]) > fmax) fmax = fabsl(rhs[a]);
        }
        for (a = 0; ok && a < k; ++a) {
            if (rhs[a] < -1e-10 * fmax) ok = 0;
        }
        if (ok) {
            for (a = 0; a < n; ++a) F[a] = 0.0;
            for (a = 0; a < k; ++a) F[idx[a]] = rhs[a] > 0.0 ? rhs[a] : 0.0;
            for (a = 0; ok && a < n; ++a) {
                long double w = q[a];
                if (set & (1UL << a)) continue;
                for (b = 0; b < n; ++b) w += A[a*n + b] * F[b];
                if (w < -w_tol) ok = 0;
            }
        }
        if (ok) return GAC_OK;
        if (tries > 0) {
            if (mask == 0) break;
            --mask;
        }
    }
    return GAC_ERR_LCP;
}

static int gac_rounds(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                      const int *list, const double *e, int first, double *qd_plus, double *F, double *work,
                      int *rounds, int *plastic, gac_rounds_trace *trace, double *rest_work, double *law_change);

/* The impact law for the contacts list[0..n-1] (at their walls), from the velocities qd, with restitution
 * e[a] for contact list[a].  Newton's law (Eq. 47) with complementarity, in rounds:
 *   round: the contacts that approach their wall (v_a < 0) or rest on it (v_a = 0: |v_a| below 1e-11 of the
 *          fastest approach before, or below the round-off v_a has gathered from the updates v += A F of the
 *          rounds, 4 (k + 1) eps sum (|v_a| + sum_b |A_ab F_b|), which over nearly dependent rows with large
 *          impulses exceeds the first and would strike a resting contact on noise, round after round) take part;
 *          0 <= F  _|_  v+ + e v- >= 0 on them (e = 0 for a resting one), the others untouched;
 *          then the velocities are updated, v += A F.
 * until no contact approaches.  A contact separating from its wall takes no impulse unless the impulses
 * of the others drive it into the wall; then it is struck in the next round by its own law.  One round is
 * Eq. 47 when every approaching contact pushes.  Each round changes the kinetic energy by
 *   dT = 1/2 sum_a F_a (v-_a + v+_a) = 1/2 sum_a (1 - e_a) F_a v-_a <= 0   (v-_a <= 0 where F_a > 0),
 * so no round gains energy and a round with e = 1 keeps it exactly.  After GAC_MAX_ROUNDS rounds the
 * remaining approach is removed by one plastic round over every listed contact (the projection of qd onto
 * {N qd >= 0} in the mass metric, which cannot gain energy either); *plastic is then 1.
 * Contact list[first] (first >= 0), the one whose crossing was located, is struck in the first round
 * whenever it approaches, however slowly.  The rounds' velocities, impulses and solves are carried in long double
 * (A as computed): a round keeps the energy only as far as its solve and its update v += A F hold, each to about
 * eps |A| |F| in double, and over many rounds with large impulses (a point struck back and forth in a corner, one
 * wall elastic) that adds F eps |A| |F| per round, beyond the energy's round-off.
 * Returns qd_plus, the total impulses F (>= 0, N s along the inward normals) and the number of rounds. */
int gac_impact_rounds(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                      const int *list, const double *e, int first, double *qd_plus, double *F, double *work,
                      int *rounds, int *plastic)
{
    double rest_work, law_change;
    return gac_rounds(m, q, qd, p, n, list, e, first, qd_plus, F, work, rounds, plastic, 0, &rest_work, &law_change);
}

/* Round `round`'s problem (its k contacts at positions idx, hit: struck with their own e) and impulses Fsub into
 * the trace, while it has room. */
static void gac_trace_round(gac_rounds_trace *trace, int round, int k, const int *idx, const int *hit,
                            const double *Fsub)
{
    int a;
    trace->nround = round + 1;
    if (round >= trace->cap) return;
    trace->k[round] = k;
    for (a = 0; a < k; ++a) {
        trace->idx[round * trace->n + a] = idx[a];
        trace->hit[round * trace->n + a] = hit[a];
        trace->F[round * trace->n + a] = Fsub[a];
    }
}

/* gac_impact_rounds, each round recorded in trace (NULL: none) as well. */
int gac_impact_rounds_traced(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                             const int *list, const double *e, int first, double *qd_plus, double *F, double *work,
                             int *rounds, int *plastic, gac_rounds_trace *trace)
{
    double rest_work, law_change;
    return gac_rounds(m, q, qd, p, n, list, e, first, qd_plus, F, work, rounds, plastic, trace, &rest_work,
                      &law_change);
}

/* gac_impact_rounds, with *rest_work (J) the energy its rounds gained: the sum over the rounds of each round's
 * change 1/2 sum_a F_a (v-_a + v+_a) in its contact-space velocities where that is > 0.  A round changes the energy
 * by 1/2 sum (1 - e_a) F_a v-_a <= 0 over its struck contacts plus 1/2 F_a v-_a over those at rest, which may push
 * while separating below the rest threshold: the gain of the rest rule, which no condition of the law measures.
 * *law_change (J): the kinetic energy's change the law solved without round-off gives, where the law alone fixes it:
 * 0 when every contact that pushes in any round is struck with e = 1 (each such round keeps T exactly, whatever its
 * impulses), NaN otherwise (the change then depends on the impulses, which over nearly dependent rows are known far
 * less accurately than the velocities they give). */
int gac_impact_rounds_work(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                           const int *list, const double *e, int first, double *qd_plus, double *F, double *work,
                           int *rounds, int *plastic, double *rest_work, double *law_change)
{
    return gac_rounds(m, q, qd, p, n, list, e, first, qd_plus, F, work, rounds, plastic, 0, rest_work, law_change);
}

/* The rounds of gac_impact_rounds, traced (trace: NULL for none), with the energy they gained (rest_work) and the
 * energy change their conditions give (law_change). */
static int gac_rounds(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                      const int *list, const double *e, int first, double *qd_plus, double *F, double *work,
                      int *rounds, int *plastic, gac_rounds_trace *trace, double *rest_work, double *law_change)
{
    const int nq = m->nq, max_lcp = GAC_MAX_LCP(m);
    double v0[GAC_AT_LEAST_1(nq)], e_wall[GAC_AT_LEAST_1(nq)], noise[GAC_AT_LEAST_1(nq)], scale = 0.0, v_tol;
    long double v[GAC_AT_LEAST_1(nq)], total[GAC_AT_LEAST_1(nq)], gain;
    int elastic = 1;                       /* every contact that pushed was struck with e = 1 */
    double *Y = GAC_WORK_Y(m, work), *A = GAC_WORK_A(m, work);
    int a, b, i, round, code;
    *rounds = *plastic = 0;
    *rest_work = *law_change = 0.0;
    code = gac_impact_system_refined(m, q, qd, p, n, list, work, v0, e_wall);   /* Y_a refined (gac_impact_accuracy.c) */
    if (code != GAC_OK) return code;
    for (a = 0; a < n; ++a) {
        v[a] = v0[a];
        total[a] = 0.0L;
        noise[a] = 0.0;
        if (fabs(v0[a]) > scale) scale = fabs(v0[a]);
    }
    v_tol = 1e-11 * scale;                 /* a normal velocity below this is round-off: at rest */
    for (round = 0; ; ++round) {
        double Asub[GAC_LCP_CAP * GAC_LCP_CAP];
        long double qsub[GAC_AT_LEAST_1(nq)], Fsub[GAC_LCP_CAP];
        int idx[GAC_AT_LEAST_1(nq)], hit[GAC_AT_LEAST_1(nq)], k = 0, approaching = 0;
        const int last = round >= GAC_MAX_ROUNDS;
        for (a = 0; a < n; ++a) {
            const double tol = v_tol > noise[a] ? v_tol : noise[a];   /* at rest to round-off */
            const int struck = v[a] < -tol || (round == 0 && a == first && v[a] < 0.0);
            if (struck) approaching = 1;
            if (last || struck || v[a] <= tol) {
                qsub[k] = !last && struck ? (1.0 + e[a]) * v[a] : v[a];
                hit[k] = !last && struck;
                idx[k++] = a;
            }
        }
        if (!approaching) break;
        if (k > max_lcp) return GAC_ERR_LCP;          /* more than one solve takes */
        for (a = 0; a < k; ++a) {
            for (b = 0; b < k; ++b) Asub[a*k + b] = A[idx[a]*n + idx[b]];
        }
        code = gac_lcp(max_lcp, k, Asub, qsub, 1e-10 * scale, Fsub);
        if (code != GAC_OK) return code;
        if (trace != 0) {
            double Ftrace[GAC_LCP_CAP];
            for (a = 0; a < k; ++a) Ftrace[a] = (double)Fsub[a];
            gac_trace_round(trace, round, k, idx, hit, Ftrace);
        }
        gain = 0.0L;
        for (a = 0; a < k; ++a) {
            total[idx[a]] += Fsub[a];
            gain += 0.5L * Fsub[a] * v[idx[a]];          /* 1/2 F (v- + v+) with v+ = A F + v-, below */
            if (Fsub[a] > 0.0L && !(hit[a] && e[idx[a]] == 1.0)) elastic = 0;
        }
        for (a = 0; a < n; ++a) {
            double size = fabs((double)v[a]);
            for (b = 0; b < k; ++b) {
                v[a] += A[a*n + idx[b]] * Fsub[b];
                size += fabs(A[a*n + idx[b]] * (double)Fsub[b]);
            }
            noise[a] += 4.0 * (k + 1) * GAC_EPS * size;  /* A's round-off times the impulses, summed over the
                                                            rounds (the updates themselves in long double) */
        }
        for (a = 0; a < k; ++a) gain += 0.5L * Fsub[a] * v[idx[a]];
        if (gain > 0.0L) *rest_work += (double)gain;     /* the round gained energy (its contacts at rest) */
        *rounds = round + 1;
        if (last) {
            *plastic = 1;
            break;
        }
    }
    *law_change = elastic && !*plastic ? 0.0 : NAN;
    for (a = 0; a < n; ++a) F[a] = (double)total[a];
    for (i = 0; i < nq; ++i) {
        long double value = qd[i];
        for (a = 0; a < n; ++a) value += Y[a*nq + i] * total[a];
        qd_plus[i] = (double)value;
    }
    return GAC_OK;
}

int gac_impact_complementarity(const gac_model *m, const double *GAC_RESTRICT q, const double *GAC_RESTRICT qd,
                               const double *GAC_RESTRICT p, int ncontact_set, const int *GAC_RESTRICT contact_set,
                               double *GAC_RESTRICT qd_plus, double *GAC_RESTRICT impulse,
                               double *GAC_RESTRICT work)
{
    double v[GAC_AT_LEAST_1(m->nq)], e[GAC_AT_LEAST_1(m->nq)];
    int rounds, plastic;
    int code = gac_impact_system(m, q, qd, p, ncontact_set, contact_set, work, v, e);
    if (code != GAC_OK) return code;
    return gac_impact_rounds(m, q, qd, p, ncontact_set, contact_set, e, -1, qd_plus, impulse, work, &rounds, &plastic);
}

void gac_contact_info(const gac_model *m, int c, int *point, int *axis, int *normal_sign)
{
    if (m == 0 || c < 0 || c >= m->ncontact) {
        *point = 0;
        *axis = -1;
        *normal_sign = 0;
        return;
    }
    *point = m->contacts[c].point;
    *axis = m->contacts[c].kind == GAC_CONTACT_WALL ? m->contacts[c].axis : -1;
    *normal_sign = m->contacts[c].normal_sign;
}
