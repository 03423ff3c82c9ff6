/*
 * gac_impact_friction.c -- impacts with Coulomb friction, at rough walls and at rough link pairs and obstacles
 * (the latter along their contact frame at the closest points, gac_rowless_frame: rows J^T n, J^T t1, J^T t2).
 *
 * The law (the "global dissipation index" form of Moreau's and Glocker's impact laws): at each contact the
 * normal and tangential velocities gamma = (gamma_N, gamma_T) share one restitution e, and Coulomb's cone holds
 * on their weighted sum xi = gamma+ + e gamma-:
 *     0 <= Lambda_N  _|_  xi_N >= 0,
 *     Lambda_T = -c_f Lambda_N xi_T / |xi_T|  where xi_T != 0,   |Lambda_T| <= c_f Lambda_N  where xi_T = 0,
 * Lambda the impulse (normal, and along the wall's tangential axes).  With gamma+ = gamma- + W Lambda (W the
 * contact-space inverse inertia, positive semidefinite) the kinetic energy changes by
 *     T+ - T- = 1/2 Lambda^T (gamma+ + gamma-)
 *             = 1/2 Lambda^T xi (1 + (1 - e)/(1 + e)) - (1 - e)/(2 (1 + e)) Lambda^T W Lambda  <= 0
 * for a common e in [0, 1], since Lambda^T xi = -c_f Lambda_N |xi_T| <= 0 contact by contact: the law never
 * gains energy, it stops, sticks, slides and reverses the slip as the impulses require, and with c_f = 0 it is
 * Newton's law with complementarity (Eq. 47).  With different e at simultaneous contacts the identity no longer
 * bounds the sign; a round whose energy would grow, or that has no solution with its contacts' own e (dependent
 * contacts), is solved again with the smallest e of its contacts for all of them (the record's law says so).  Newton + Coulomb (Newton's restitution on the normal velocity, Coulomb's cone
 * on the tangential velocity after the impact) is kept as an option: it gains energy when the slip reverses
 * during the impact (Kane's rod), and the loop then stops (GAC_ERR_IMPACT_ENERGY).
 *
 * Each round of the rounds (gac_impact_rounds) is this frictional contact problem on the contacts that approach
 * or rest, solved by projected Gauss-Seidel over the contacts, each contact's own problem solved exactly
 * (separate, stick, or slide: a sign for one tangential axis, for two every direction in which it can slide, the
 * real roots of a quartic; with W positive definite one of them always solves it); where the sweeps stall (coupled contacts with friction are not a monotone problem), the contacts' modes
 * are enumerated exactly (up to GAC_ENUM_MAX contacts).  Where that leaves a round above its tolerance (dependent
 * rows: W singular, the impulses not unique), a round whose approach is within the tolerance of the velocities
 * the motion can have ends the rounds (a later one, whose approach left is closed by plastic normal strikes after
 * the law, gac_close_approach; or a first one, contacts touching at rest at round-off speed: no impulse), and any
 * other is solved by the proximal point method
 * (gac_round_proximal), else with every pushing contact held at rest (gac_round_stick); rounds the plain solve
 * meets are untouched.  Its residual is reported, and a round still
 * left above GAC_FRICTION_RESIDUAL_MAX (or 16 eps cond W) is GAC_ERR_IMPACT_FRICTION.
 */
#include "gac_internal.h"

#include <math.h>

#define GAC_PGS_SWEEPS 20000      /* Gauss-Seidel sweeps allowed for one round */
#define GAC_ENUM_MAX 6            /* contacts of a round whose modes are enumerated where Gauss-Seidel stalls */
#define GAC_SLIDE_STARTS 144      /* starts on a grid of the slide angles for Newton's method, per combination */
#define GAC_PROX_STEPS 40         /* proximal point steps for a round the plain solve leaves unsolved */

/* Coulomb coefficient of contact c's wall, at rest and at impacts: its c_f (0 for a frictionless wall, a stop, a
 * link pair or an obstacle: those have no Jacobian rows; their coefficient is gac_contact_friction's, at rest
 * gac_rest_friction's). */
double gac_friction_coefficient(const gac_model *m, const double *p, int c)
{
    const gac_contact *k = &m->contacts[c];
    if (k->kind != GAC_CONTACT_WALL || !k->has_friction) return 0.0;
    return k->friction_index >= 0 ? p[k->friction_index] : k->friction_value;
}

/* Coulomb coefficient of contact c at an impact (and at rest): a wall's c_f, or a link pair's or an obstacle's
 * (along its contact frame); 0 for a frictionless contact or a stop. */
double gac_contact_friction(const gac_model *m, const double *p, int c)
{
    const gac_contact *k = &m->contacts[c];
    if (!k->has_friction || (k->kind != GAC_CONTACT_WALL && !gac_rowless(m, c))) return 0.0;
    return k->friction_index >= 0 ? p[k->friction_index] : k->friction_value;
}

/* x = A^-1 b for a d x d (d <= 3) row-major A by Gaussian elimination with partial pivoting; 0 if singular. */
static int gac_small_solve(int d, const double *A, const double *b, double *x)
{
    double M[9], y[3];
    int i, j, c;
    for (i = 0; i < d * d; ++i) M[i] = A[i];
    for (i = 0; i < d; ++i) y[i] = b[i];
    for (c = 0; c < d; ++c) {
        int p = c;
        for (i = c + 1; i < d; ++i) {
            if (fabs(M[i*d + c]) > fabs(M[p*d + c])) p = i;
        }
        if (!(fabs(M[p*d + c]) > 1e-300)) return 0;
        if (p != c) {
            for (j = 0; j < d; ++j) {
                const double t = M[c*d + j];
                M[c*d + j] = M[p*d + j];
                M[p*d + j] = t;
            }
            { const double t = y[c]; y[c] = y[p]; y[p] = t; }
        }
        for (i = c + 1; i < d; ++i) {
            const double f = M[i*d + c] / M[c*d + c];
            for (j = c; j < d; ++j) M[i*d + j] -= f * M[c*d + j];
            y[i] -= f * y[c];
        }
    }
    for (i = d - 1; i >= 0; --i) {
        double s = y[i];
        for (j = i + 1; j < d; ++j) s -= M[i*d + j] * x[j];
        x[i] = s / M[i*d + i];
    }
    return 1;
}

/* Sliding along the unit direction (dx, dy) of xi_T (two tangential axes; dy = 0 for one): the impulse
 * L = L_N (1, -c_f d) with xi_N = 0, and xi_T's components across and along d.  0 if L_N would not push. */
static int gac_slide(int d, const double *W, const double *r, double cf, double dx, double dy, double *L,
                     double *across, double *along)
{
    double denom = W[0] - cf * (W[1] * dx + (d > 2 ? W[2] * dy : 0.0)), xt[2] = {0.0, 0.0};
    int j;
    if (!(denom > 0.0)) return 0;
    L[0] = -r[0] / denom;
    L[1] = -cf * L[0] * dx;
    if (d > 2) L[2] = -cf * L[0] * dy;
    for (j = 1; j < d; ++j) {
        int i;
        double s = r[j];
        for (i = 0; i < d; ++i) s += W[j*d + i] * L[i];
        xt[j - 1] = s;
    }
    *across = xt[0] * dy - xt[1] * dx;
    *along = xt[0] * dx + xt[1] * dy;
    return L[0] > 0.0;
}

/* p(t) = c[0] + c[1] t + ... + c[n] t^n. */
static double gac_poly(int n, const double *c, double t)
{
    double v = c[n];
    int i;
    for (i = n - 1; i >= 0; --i) v = v * t + c[i];
    return v;
}

/* The real roots of p (degree n <= 4, c[n] != 0), ascending, in root[]; returns how many.  Between consecutive
 * roots of p' (found the same way, degree by degree) p is monotone: each such interval, and the two outer ones up
 * to Cauchy's bound 1 + max |c_i / c_n|, holds at most one root, found by bisection where p changes sign; a root of
 * p' where p vanishes (a double root) counts too. */
static int gac_poly_roots(int n, const double *c, double *root)
{
    double d[4], crit[4], ends[6], bound = 0.0;
    int ncrit = 0, nends = 0, count = 0, i, k;
    for (i = 0; i < n; ++i) bound = fabs(c[i] / c[n]) > bound ? fabs(c[i] / c[n]) : bound;
    bound += 1.0;
    if (n == 1) {
        root[0] = -c[0] / c[1];
        return 1;
    }
    for (i = 1; i <= n; ++i) d[i - 1] = i * c[i];
    ncrit = gac_poly_roots(n - 1, d, crit);
    ends[nends++] = -bound;
    for (k = 0; k < ncrit; ++k) {
        if (crit[k] > -bound && crit[k] < bound) ends[nends++] = crit[k];
    }
    ends[nends++] = bound;
    for (k = 0; k + 1 < nends; ++k) {
        double lo = ends[k], hi = ends[k + 1], p_lo = gac_poly(n, c, lo), p_hi = gac_poly(n, c, hi);
        int it;
        if (p_lo == 0.0) {
            if (count == 0 || root[count - 1] != lo) root[count++] = lo;
            continue;
        }
        if (p_hi == 0.0 || (p_lo > 0.0) == (p_hi > 0.0)) continue;
        for (it = 0; it < 200 && hi - lo > 2.0 * GAC_EPS * (fabs(lo) + fabs(hi)); ++it) {
            const double mid = 0.5 * (lo + hi), p_mid = gac_poly(n, c, mid);
            if (p_mid == 0.0) {
                lo = hi = mid;
                break;
            }
            if ((p_mid > 0.0) == (p_lo > 0.0)) {
                lo = mid;
                p_lo = p_mid;
            } else {
                hi = mid;
            }
        }
        root[count++] = 0.5 * (lo + hi);
    }
    return count;
}

/* The sliding directions d = (cos phi, sin phi) of one contact with two tangential axes, where xi_T is parallel to
 * d: with L = L_N (1, -c_f d) and xi_N = 0 (L_N = -r_N / D, D = W_NN - c_f W_NT . d), xi_T x d = 0 times D is
 *     g(phi) = D (r_T x d) - r_N ((W_TN - c_f W_TT d) x d) = alpha c + beta s + gamma c^2 + delta c s + eps s^2,
 * which has no pole where D = 0 (where L_N grows without bound: solutions can lie next to it, in pairs when r_N
 * is small), a trigonometric polynomial of degree 2.  With t = tan(phi / 2), g (1 + t^2)^2 is a quartic in t,
 * whose real roots (gac_poly_roots) are all the directions, and phi = pi (t infinite) where its leading
 * coefficient vanishes.  Returns how many, their angles in phi[0..3]. */
static int gac_slide_directions(const double *W, const double *r, double cf, double *phi)
{
    const double alpha = -W[0] * r[2] + r[0] * W[6], beta = W[0] * r[1] - r[0] * W[3];
    const double gamma = cf * (W[1] * r[2] - r[0] * W[7]);
    const double delta = cf * (-W[1] * r[1] + W[2] * r[2] + r[0] * W[4] - r[0] * W[8]);
    const double eps = cf * (-W[2] * r[1] + r[0] * W[5]);
    double c[5], t[4], size = 0.0;
    int n = 4, count, i;
    c[0] = alpha + gamma;
    c[1] = 2.0 * (beta + delta);
    c[2] = 4.0 * eps - 2.0 * gamma;
    c[3] = 2.0 * (beta - delta);
    c[4] = gamma - alpha;
    for (i = 0; i < 5; ++i) size = fabs(c[i]) > size ? fabs(c[i]) : size;
    if (!(size > 0.0)) return 0;
    while (n > 0 && fabs(c[n]) <= 1e-14 * size) --n;     /* phi = pi is (nearly) a root */
    count = n > 0 ? gac_poly_roots(n, c, t) : 0;
    for (i = 0; i < count; ++i) phi[i] = 2.0 * atan2(t[i], 1.0);     /* (the library calls no atan) */
    if (n < 4) phi[count++] = 3.14159265358979323846;
    return count;
}

/* One contact's frictional problem, exactly: xi = W L + r (d = 1 + its tangential axes, W d x d row-major), the
 * cone of coefficient cf.  Separate (L = 0) when r_N >= 0, else stick (xi = 0) when that impulse lies in the cone,
 * else slide (xi_N = 0, L_T = -cf L_N xi_T / |xi_T|: for two tangential axes, every direction of
 * gac_slide_directions that pushes, L_N > 0, and slides along it).  Where sliding has several solutions (friction strong enough
 * for the Painleve paradox at an impact), the one nearest the direction of r_T is taken. */
static void gac_local_contact(int d, const double *W, const double *r, double cf, double *L)
{
    double Ls[3] = {0.0, 0.0, 0.0}, best[3] = {0.0, 0.0, 0.0}, best_score = -1e300, mr[3] = {0.0, 0.0, 0.0};
    int i, found = 0;
    for (i = 0; i < d; ++i) L[i] = 0.0;
    if (r[0] >= 0.0) return;                                   /* separates: no impulse */
    if (d == 1 || !(cf > 0.0)) {
        L[0] = -r[0] / W[0];
        return;
    }
    for (i = 0; i < d; ++i) mr[i] = -r[i];
    if (gac_small_solve(d, W, mr, Ls) && Ls[0] > 0.0) {       /* sticks */
        double t2 = 0.0;
        for (i = 1; i < d; ++i) t2 += Ls[i] * Ls[i];
        if (sqrt(t2) <= cf * Ls[0]) {
            for (i = 0; i < d; ++i) L[i] = Ls[i];
            return;
        }
    }
    if (d == 2) {                                              /* slides one way or the other */
        int s;
        for (s = -1; s <= 1; s += 2) {
            double across, along, score;
            if (!gac_slide(d, W, r, cf, (double)s, 0.0, Ls, &across, &along) || along < 0.0) continue;
            score = s * r[1];
            if (!found || score > best_score) {
                for (i = 0; i < d; ++i) best[i] = Ls[i];
                best_score = score;
                found = 1;
            }
        }
    } else {                                                   /* the sliding directions: all of them */
        double phi[5], rt = sqrt(r[1] * r[1] + r[2] * r[2]);
        const int nphi = gac_slide_directions(W, r, cf, phi);
        int k;
        for (k = 0; k < nphi; ++k) {
            double across, along;
            if (gac_slide(d, W, r, cf, cos(phi[k]), sin(phi[k]), Ls, &across, &along) && along >= 0.0) {
                const double score = rt > 0.0 ? (cos(phi[k]) * r[1] + sin(phi[k]) * r[2]) / rt : 0.0;
                if (!found || score > best_score) {
                    for (i = 0; i < d; ++i) best[i] = Ls[i];
                    best_score = score;
                    found = 1;
                }
            }
        }
    }
    if (found) {
        for (i = 0; i < d; ++i) L[i] = best[i];
    } else {                                                   /* no sliding solution: the frictionless push, */
        L[0] = -r[0] / W[0];                                   /* which the residual then reports */
    }
}

/* The largest relative violation of the law's conditions by L (nr rows of contacts start[k] .. + dim[k], the
 * round's rows rows[] of the full W, nd x nd): 0 <= L_N _|_ xi_N >= 0, |L_T| <= cf L_N, xi_T = 0 where it sticks,
 * xi_T along -L_T where it slides; velocities relative to max |q|, impulses to max |L|. */
static double gac_round_residual(int nd, const double *W, int ncon, const int *start, const int *dim,
                                 const double *cf, const int *rows, const double *q, const double *L)
{
    const int nr = start[ncon - 1] + dim[ncon - 1];
    double vscale = 0.0, lscale = 0.0, res = 0.0;
    int k, i, j;
    for (i = 0; i < nr; ++i) {
        if (fabs(q[i]) > vscale) vscale = fabs(q[i]);
        if (fabs(L[i]) > lscale) lscale = fabs(L[i]);
    }
    if (!(vscale > 0.0)) vscale = 1.0;
    if (!(lscale > 0.0)) lscale = 1.0;
    for (k = 0; k < ncon; ++k) {
        const int s = start[k], d = dim[k];
        double xi[3], lt = 0.0, xt = 0.0, dot = 0.0, r;
        for (i = 0; i < d; ++i) {
            double v = q[s + i];
            for (j = 0; j < nr; ++j) v += W[rows[s + i] * nd + rows[j]] * L[j];
            xi[i] = v;
        }
        r = L[s] / lscale < xi[0] / vscale ? L[s] / lscale : xi[0] / vscale;     /* min(L_N, xi_N) */
        if (fabs(r) > res) res = fabs(r);
        if (d == 1 || !(cf[k] > 0.0)) continue;
        for (i = 1; i < d; ++i) {
            lt += L[s + i] * L[s + i];
            xt += xi[i] * xi[i];
            dot += -L[s + i] * xi[i];
        }
        lt = sqrt(lt);
        xt = sqrt(xt);
        r = (lt - cf[k] * L[s]) / lscale;                     /* inside the cone */
        if (r > res) res = r;
        if (lt < cf[k] * L[s] * (1.0 - 1e-9)) {
            r = xt / vscale;                                   /* sticks: xi_T = 0 */
        } else if (lt > 0.0) {
            r = (lt * xt - dot) / (lt * vscale);               /* slides: xi_T along -L_T */
        } else {
            r = 0.0;                                           /* L = 0 at the cone's tip */
        }
        if (r > res) res = r;
    }
    return res;
}

/* The round's problem for given modes: mode[k] 0 separates (L = 0), 1 sticks (xi = 0 on all its rows), 2 slides
 * along dir[k] (xi_N = 0, L_T = -cf L_N dir); one linear solve for the unknowns.  0 if it is singular. */
static int gac_round_modes(int nd, const double *W, int ncon, const int *start, const int *dim, const double *cf,
                           const int *rows, const double *q, const int *mode, const double *dir, double *L)
{
    const int nr = start[ncon - 1] + dim[ncon - 1];
    double P[3 * GAC_ENUM_MAX * 3 * GAC_ENUM_MAX], A[9 * GAC_ENUM_MAX * GAC_ENUM_MAX], b[3 * GAC_ENUM_MAX];
    int eq[3 * GAC_ENUM_MAX], nz = 0, i, j, k, c;
    for (i = 0; i < nr * nr; ++i) P[i] = 0.0;
    for (k = 0; k < ncon; ++k) {                 /* L = P z: the unknowns z of each contact, and its equations */
        const int s = start[k], d = dim[k];
        if (mode[k] == 1) {
            for (i = 0; i < d; ++i) {
                P[(s + i) * nr + nz] = 1.0;
                eq[nz++] = s + i;
            }
        } else if (mode[k] == 2) {
            P[s * nr + nz] = 1.0;
            for (i = 1; i < d; ++i) P[(s + i) * nr + nz] = -cf[k] * dir[2 * k + i - 1];
            eq[nz++] = s;
        }
    }
    for (i = 0; i < nz; ++i) {                  /* (E W P) z = -E q */
        for (c = 0; c < nz; ++c) {
            double v = 0.0;
            for (j = 0; j < nr; ++j) v += W[rows[eq[i]] * nd + rows[j]] * P[j * nr + c];
            A[i * nz + c] = v;
        }
        b[i] = -q[eq[i]];
    }
    if (nz > 0 && gac_lu_solve(nz, A, b, 1e-13) != 0) return 0;
    for (j = 0; j < nr; ++j) {
        double v = 0.0;
        for (c = 0; c < nz; ++c) v += P[j * nr + c] * b[c];
        L[j] = v;
    }
    return 1;
}

/* For the modes mode[] with the 3D sliding contacts slide[0..ns-1] at angles phi (their slide directions
 * (cos, sin)): the impulses (trial) and, for each of them, xi_T's component across its direction (cross).  0 if
 * the modes' system is singular. */
static int gac_slide_cross(int nd, const double *W, int ncon, const int *start, const int *dim, const double *cf,
                           const int *rows, const double *q, const int *mode, int ns, const int *slide,
                           const double *phi, double *dir, double *trial, double *cross)
{
    const int nr = start[ncon - 1] + dim[ncon - 1];
    int j, i;
    for (j = 0; j < ns; ++j) {
        dir[2 * slide[j]] = cos(phi[j]);
        dir[2 * slide[j] + 1] = sin(phi[j]);
    }
    if (!gac_round_modes(nd, W, ncon, start, dim, cf, rows, q, mode, dir, trial)) return 0;
    for (j = 0; j < ns; ++j) {
        const int s = start[slide[j]];
        double x = q[s + 1], y = q[s + 2];
        for (i = 0; i < nr; ++i) {
            x += W[rows[s + 1] * nd + rows[i]] * trial[i];
            y += W[rows[s + 2] * nd + rows[i]] * trial[i];
        }
        cross[j] = x * sin(phi[j]) - y * cos(phi[j]);
    }
    return 1;
}

static void gac_round_refine(int nd, const double *W, int ncon, const int *start, const int *dim, const double *cf,
                             const int *rows, const double *q, double *L, double *residual);

/* The round's problem solved exactly by its modes (at most GAC_ENUM_MAX contacts): every combination of separate,
 * stick and slide, the guess L's own modes first.  One tangential axis: a slide is one of two signs, one linear
 * solve.  Two: the slide directions are the roots of xi_T x d = 0, found by Newton's method on their angles
 * (Jacobian by central differences, steps halved until |xi_T x d| falls) from the guess's direction, the velocity's
 * before, and a grid of about GAC_SLIDE_STARTS starts around the circle(s).  1 with L (its residual in *residual) if a combination
 * meets the law to accept (the rounds: GAC_FRICTION_RESIDUAL_MAX / 1000).  nontrivial: only solutions in which some
 * contact pushes (L_N > 0; the tangential impact, whose trivial solution L = 0 always exists). */
static int gac_round_enumerate(int nd, const double *W, int ncon, const int *start, const int *dim,
                               const double *cf, const int *rows, const double *q, int nontrivial, double accept,
                               double *L, double *residual)
{
    const int nr = start[ncon - 1] + dim[ncon - 1];
    double guess[3 * GAC_ENUM_MAX], trial[3 * GAC_ENUM_MAX], dir[2 * GAC_ENUM_MAX], scale = 0.0;
    int mode[GAC_ENUM_MAX], base[GAC_ENUM_MAX], choices[GAC_ENUM_MAX], slide[GAC_ENUM_MAX], i, k;
    long combo, total = 1;
    if (ncon > GAC_ENUM_MAX) return 0;
    for (i = 0; i < nr; ++i) {
        guess[i] = L[i];
        if (fabs(q[i]) > scale) scale = fabs(q[i]);
    }
    for (k = 0; k < ncon; ++k) {                 /* the guess's modes; choices: 0 separate, 1 stick, 2.. slide */
        const int s = start[k], d = dim[k];
        double lt = 0.0;
        for (i = 1; i < d; ++i) lt += guess[s + i] * guess[s + i];
        lt = sqrt(lt);
        choices[k] = d == 1 || !(cf[k] > 0.0) ? 2 : d == 2 ? 4 : 3;
        base[k] = !(guess[s] > 0.0) ? 0 : choices[k] == 2 || lt < cf[k] * guess[s] * (1.0 - 1e-6) ? 1
                : d == 2 ? (guess[s + 1] < 0.0 ? 2 : 3) : 2;
        total *= choices[k];
    }
    for (combo = 0; combo < total; ++combo) {
        long rest = combo;
        double phi0[GAC_ENUM_MAX];
        long grid;
        int ns = 0, attempt, per, pushing = 0;
        for (k = 0; k < ncon; ++k) {             /* combo 0 is the guess's modes */
            const int c = (int)((base[k] + rest % choices[k]) % choices[k]);
            rest /= choices[k];
            mode[k] = c >= 2 ? 2 : c;
            pushing |= mode[k] != 0;
            dir[2 * k] = dir[2 * k + 1] = 0.0;
            if (c >= 2 && dim[k] == 2) dir[2 * k] = c == 2 ? 1.0 : -1.0;       /* xi_T along +X or -X */
            if (c >= 2 && dim[k] == 3) {         /* the guess's direction, or the velocity's before */
                const int s = start[k];
                double x = -guess[s + 1], y = -guess[s + 2];
                if (!(fabs(x) + fabs(y) > 0.0)) x = q[s + 1], y = q[s + 2];
                phi0[ns] = fabs(x) + fabs(y) > 0.0 ? atan2(y, x) : 0.0;
                slide[ns++] = k;
            }
        }
        if (nontrivial && !pushing) continue;    /* every contact separates: L = 0 */
        per = 1;                                 /* starts per angle on a grid: about GAC_SLIDE_STARTS in all */
        while (ns > 0 && pow((double)(per + 1), (double)ns) <= GAC_SLIDE_STARTS) ++per;
        grid = 1;
        for (k = 0; k < ns; ++k) grid *= per;
        for (attempt = 0; attempt < (ns > 0 ? 2 + grid : 1); ++attempt) {
            double phi[GAC_ENUM_MAX], cross[GAC_ENUM_MAX], res;
            long cell = attempt - 2;
            int iter, ok = 1;
            for (k = 0; k < ns; ++k) {           /* the guess's direction, the velocity's before, then the grid */
                const int s = start[slide[k]];
                phi[k] = attempt == 0 ? phi0[k] : attempt == 1 ? atan2(q[s + 2], q[s + 1])
                       : phi0[k] + 6.283185307179586 * (double)(cell % per) / per;
                if (attempt > 1) cell /= per;
            }
            if (!gac_slide_cross(nd, W, ncon, start, dim, cf, rows, q, mode, ns, slide, phi, dir, trial, cross))
                continue;
            for (iter = 0; ns > 0 && iter < 50; ++iter) {    /* Newton on the angles */
                double J[GAC_ENUM_MAX * GAC_ENUM_MAX], step[GAC_ENUM_MAX], norm = 0.0, t = 1.0;
                int a, b;
                for (a = 0; a < ns; ++a) norm = fabs(cross[a]) > norm ? fabs(cross[a]) : norm;
                if (norm <= 1e-15 * scale) break;
                for (b = 0; b < ns && ok; ++b) {
                    double hi[GAC_ENUM_MAX], lo[GAC_ENUM_MAX], ch[GAC_ENUM_MAX], cl[GAC_ENUM_MAX];
                    const double h = 1e-7;
                    for (a = 0; a < ns; ++a) hi[a] = lo[a] = phi[a];
                    hi[b] += h;
                    lo[b] -= h;
                    ok = gac_slide_cross(nd, W, ncon, start, dim, cf, rows, q, mode, ns, slide, hi, dir, trial, ch)
                         && gac_slide_cross(nd, W, ncon, start, dim, cf, rows, q, mode, ns, slide, lo, dir, trial, cl);
                    for (a = 0; ok && a < ns; ++a) J[a * ns + b] = (ch[a] - cl[a]) / (2.0 * h);
                }
                for (a = 0; a < ns; ++a) step[a] = -cross[a];
                if (!ok || gac_lu_solve(ns, J, step, 1e-14) != 0) {
                    ok = 0;
                    break;
                }
                for (; t > 1e-4; t *= 0.5) {     /* halve the step until |xi_T x d| falls */
                    double trial_phi[GAC_ENUM_MAX], next = 0.0;
                    for (a = 0; a < ns; ++a) trial_phi[a] = phi[a] + t * step[a];
                    if (!gac_slide_cross(nd, W, ncon, start, dim, cf, rows, q, mode, ns, slide, trial_phi, dir,
                                         trial, cross)) continue;
                    for (a = 0; a < ns; ++a) next = fabs(cross[a]) > next ? fabs(cross[a]) : next;
                    if (next < norm) {
                        for (a = 0; a < ns; ++a) phi[a] = trial_phi[a];
                        break;
                    }
                }
                if (!(t > 1e-4)) break;
            }
            if (!ok || !gac_slide_cross(nd, W, ncon, start, dim, cf, rows, q, mode, ns, slide, phi, dir, trial, cross))
                continue;
            res = gac_round_residual(nd, W, ncon, start, dim, cf, rows, q, trial);
            if (nontrivial) {                    /* some normal impulse beyond round-off of the impulses' size */
                double push = 0.0, size = 0.0;
                for (i = 0; i < nr; ++i) size = fabs(trial[i]) > size ? fabs(trial[i]) : size;
                for (k = 0; k < ncon; ++k) push = trial[start[k]] > push ? trial[start[k]] : push;
                if (!(push > 1e-9 * size)) continue;
            }
            if (res > accept && res <= 1e3 * accept)   /* near: its modes' equations to round-off */
                gac_round_refine(nd, W, ncon, start, dim, cf, rows, q, trial, &res);
            if (res <= accept) {
                for (i = 0; i < nr; ++i) L[i] = trial[i];
                *residual = res;
                return 1;
            }
        }
    }
    return 0;
}

/* The modes of a round's solution L (velocities xi = W L + q): at each contact the condition L or xi meets worse,
 * relative to their scales, decides.  mode[k] 0 separates (L_N / lscale <= xi_N / vscale), 1 sticks (its cone's
 * slack (c_f L_N - |L_T|) / lscale above |xi_T| / vscale), 2 slides; dir[2k..2k+1] the slide's direction of xi_T
 * (that of -L_T where xi_T is below round-off of the velocities: at the stick's edge). */
static void gac_round_mode_of(int nd, const double *W, int ncon, const int *start, const int *dim, const double *cf,
                              const int *rows, const double *q, const double *L, double vscale, double lscale,
                              int *mode, double *dir)
{
    const int nr = start[ncon - 1] + dim[ncon - 1];
    int k, i, j;
    for (k = 0; k < ncon; ++k) {
        const int s = start[k], d = dim[k];
        double xi[3], lt = 0.0, xt = 0.0;
        for (i = 0; i < d; ++i) {
            double v = q[s + i];
            for (j = 0; j < nr; ++j) v += W[rows[s + i] * nd + rows[j]] * L[j];
            xi[i] = v;
        }
        dir[2 * k] = dir[2 * k + 1] = 0.0;
        if (!(L[s] / lscale > xi[0] / vscale)) {
            mode[k] = 0;
            continue;
        }
        if (d == 1 || !(cf[k] > 0.0)) {
            mode[k] = 1;
            continue;
        }
        for (i = 1; i < d; ++i) {
            lt += L[s + i] * L[s + i];
            xt += xi[i] * xi[i];
        }
        lt = sqrt(lt);
        xt = sqrt(xt);
        if ((cf[k] * L[s] - lt) / lscale > xt / vscale) {
            mode[k] = 1;
            continue;
        }
        mode[k] = 2;
        for (i = 1; i < d; ++i) {
            dir[2 * k + i - 1] = xt > 1e-12 * vscale ? xi[i] / xt : lt > 0.0 ? -L[s + i] / lt : (i == 1 ? 1.0 : 0.0);
        }
    }
}

/* The round's solution L refined to round-off for the modes it has (gac_round_mode_of): Newton's method on the
 * modes' equations, all rows at once,
 *     separate: L = 0;   stick: xi = 0;   slide: xi_N = 0, L_T + c_f L_N u = 0,
 * u the sliding direction: fixed for one tangential axis (and at the stick's edge), else u = xi_T / |xi_T| with
 * its derivative (I - u u^T) W_T / |xi_T| in the Jacobian (the equations on L scaled by W's largest diagonal to
 * velocities).  Steps are taken while the round's residual (gac_round_residual) falls; L and *residual are
 * replaced only if it ends below where it started.  least: each step the least change of L that meets the
 * linearised equations, J^T (J J^T + 1e-13 max diag(J J^T) I)^-1 (-F) (dependent rows: J singular, the equations
 * consistent), else J^-1 (-F). */
static void gac_round_refine_by(int nd, const double *W, int ncon, const int *start, const int *dim,
                                const double *cf, const int *rows, const double *q, int least, double *L,
                                double *residual)
{
    const int nr = start[ncon - 1] + dim[ncon - 1];
    double vscale = 0.0, lscale = 0.0, wscale = 0.0, best = *residual, dir[2 * GAC_AT_LEAST_1(ncon)];
    double cur[GAC_AT_LEAST_1(nr)], J[GAC_AT_LEAST_1(nr * nr)], F[GAC_AT_LEAST_1(nr)], xi[GAC_AT_LEAST_1(nr)];
    int mode[GAC_AT_LEAST_1(ncon)], k, i, j, it;
    for (i = 0; i < nr; ++i) {
        vscale = fabs(q[i]) > vscale ? fabs(q[i]) : vscale;
        lscale = fabs(L[i]) > lscale ? fabs(L[i]) : lscale;
        wscale = fabs(W[rows[i] * nd + rows[i]]) > wscale ? fabs(W[rows[i] * nd + rows[i]]) : wscale;
        cur[i] = L[i];
    }
    if (!(vscale > 0.0) || !(lscale > 0.0) || !(wscale > 0.0) || !(best > 0.0)) return;
    gac_round_mode_of(nd, W, ncon, start, dim, cf, rows, q, L, vscale, lscale, mode, dir);
    for (it = 0; it < 6; ++it) {
        double res;
        for (i = 0; i < nr; ++i) {               /* xi = W L + q, in long double: the residual's own round-off */
            long double v = q[i];
            for (j = 0; j < nr; ++j) v += (long double)W[rows[i] * nd + rows[j]] * cur[j];
            xi[i] = (double)v;
        }
        for (i = 0; i < nr * nr; ++i) J[i] = 0.0;
        for (k = 0; k < ncon; ++k) {
            const int s = start[k], d = dim[k];
            if (mode[k] == 0) {                  /* L = 0 */
                for (i = 0; i < d; ++i) {
                    F[s + i] = wscale * cur[s + i];
                    J[(s + i) * nr + s + i] = wscale;
                }
                continue;
            }
            for (j = 0; j < nr; ++j) J[s * nr + j] = W[rows[s] * nd + rows[j]];
            F[s] = xi[s];                        /* xi_N = 0 */
            if (mode[k] == 1) {                  /* xi_T = 0 */
                for (i = 1; i < d; ++i) {
                    for (j = 0; j < nr; ++j) J[(s + i) * nr + j] = W[rows[s + i] * nd + rows[j]];
                    F[s + i] = xi[s + i];
                }
                continue;
            }
            {                                    /* L_T + c_f L_N u = 0 */
                double u[2] = {dir[2 * k], dir[2 * k + 1]}, xt = 0.0;
                int moving = 0;
                if (d == 3) {
                    xt = sqrt(xi[s + 1] * xi[s + 1] + xi[s + 2] * xi[s + 2]);
                    moving = xt > 1e-12 * vscale;
                    if (moving) u[0] = xi[s + 1] / xt, u[1] = xi[s + 2] / xt;
                }
                for (i = 1; i < d; ++i) {
                    F[s + i] = wscale * (cur[s + i] + cf[k] * cur[s] * u[i - 1]);
                    J[(s + i) * nr + s + i] += wscale;
                    J[(s + i) * nr + s] += wscale * cf[k] * u[i - 1];
                    if (moving) {                /* c_f L_N (I - u u^T) W_T / |xi_T| */
                        int l;
                        for (l = 1; l < d; ++l) {
                            const double P = ((i == l) - u[i - 1] * u[l - 1]) * wscale * cf[k] * cur[s] / xt;
                            for (j = 0; j < nr; ++j) J[(s + i) * nr + j] += P * W[rows[s + l] * nd + rows[j]];
                        }
                    }
                }
            }
        }
        for (i = 0; i < nr; ++i) F[i] = -F[i];
        if (least) {                             /* the least-norm step */
            double G[GAC_AT_LEAST_1(nr * nr)], y[GAC_AT_LEAST_1(nr)], gmax = 0.0;
            int c;
            for (i = 0; i < nr; ++i) {
                for (j = 0; j < nr; ++j) {
                    double v = 0.0;
                    for (c = 0; c < nr; ++c) v += J[i * nr + c] * J[j * nr + c];
                    G[i * nr + j] = v;
                }
                gmax = G[i * nr + i] > gmax ? G[i * nr + i] : gmax;
                y[i] = F[i];
            }
            for (i = 0; i < nr; ++i) G[i * nr + i] += 1e-13 * gmax;
            if (gac_ldlt(nr, G, 1e-300) != 0) break;
            gac_ldlt_solve(nr, G, y);
            for (i = 0; i < nr; ++i) {
                double v = 0.0;
                for (c = 0; c < nr; ++c) v += J[c * nr + i] * y[c];
                F[i] = v;
            }
            if (!gac_finite(F, nr)) break;
        } else if (gac_lu_solve(nr, J, F, 1e-16) != 0 || !gac_finite(F, nr)) {
            break;
        }
        for (i = 0; i < nr; ++i) cur[i] += F[i];
        for (k = 0; k < ncon; ++k) {             /* the separating contacts exactly at 0 */
            if (mode[k] == 0) {
                for (i = 0; i < dim[k]; ++i) cur[start[k] + i] = 0.0;
            }
        }
        res = gac_round_residual(nd, W, ncon, start, dim, cf, rows, q, cur);
        if (!(res < best)) break;
        best = res;
        for (i = 0; i < nr; ++i) L[i] = cur[i];
        if (res <= 4.0 * GAC_EPS) break;
    }
    *residual = best;
}

static void gac_round_refine(int nd, const double *W, int ncon, const int *start, const int *dim, const double *cf,
                             const int *rows, const double *q, double *L, double *residual)
{
    gac_round_refine_by(nd, W, ncon, start, dim, cf, rows, q, 0, L, residual);
}

/* The frictional contact problem of one round: rows rows[0..nr-1] of the full system (W, nd x nd), grouped by
 * contact (contact k's rows at start[k] .. start[k] + dim[k] - 1, its normal first), xi = W L + q, the cone of
 * coefficient cf[k].  Projected Gauss-Seidel over the contacts with each one's exact solve; where that leaves the
 * law's conditions violated by more than round-off, the contacts' modes are enumerated (gac_round_enumerate).  L
 * (nr) out, the residual (gac_round_residual) through *residual.  quick: Gauss-Seidel starts from L's impulses,
 * for at most GAC_PGS_SWEEPS / 20 sweeps, and no enumeration (else from 0). */
static void gac_round_solve(int nd, const double *W, int ncon, const int *start, const int *dim,
                            const double *cf, const int *rows, const double *q, int quick, double *L, double *residual)
{
    const int nr = start[ncon - 1] + dim[ncon - 1];
    int k, i, j, sweep;
    if (!quick) {
        for (i = 0; i < nr; ++i) L[i] = 0.0;
    }
    for (sweep = 0; sweep < (quick ? GAC_PGS_SWEEPS / 20 : GAC_PGS_SWEEPS); ++sweep) {
        double change = 0.0, size = 0.0;
        for (k = 0; k < ncon; ++k) {
            const int s = start[k], d = dim[k];
            double Wl[9] = {0.0}, r[3] = {0.0, 0.0, 0.0}, Lk[3] = {0.0, 0.0, 0.0};
            for (i = 0; i < d; ++i) {
                double v = q[s + i];
                for (j = 0; j < nr; ++j) {
                    if (j < s || j >= s + d) v += W[rows[s + i] * nd + rows[j]] * L[j];
                }
                r[i] = v;
                for (j = 0; j < d; ++j) Wl[i*d + j] = W[rows[s + i] * nd + rows[s + j]];
            }
            gac_local_contact(d, Wl, r, cf[k], Lk);
            for (i = 0; i < d; ++i) {
                if (fabs(Lk[i] - L[s + i]) > change) change = fabs(Lk[i] - L[s + i]);
                if (fabs(Lk[i]) > size) size = fabs(Lk[i]);
                L[s + i] = Lk[i];
            }
        }
        if (ncon == 1 || change <= 4.0 * GAC_EPS * size) break;
    }
    *residual = gac_round_residual(nd, W, ncon, start, dim, cf, rows, q, L);
    if (*residual > 4.0 * GAC_EPS) gac_round_refine(nd, W, ncon, start, dim, cf, rows, q, L, residual);
    if (*residual > 1e-12 && !quick) {
        double exact[3 * GAC_ENUM_MAX], res;
        for (i = 0; i < nr && i < 3 * GAC_ENUM_MAX; ++i) exact[i] = L[i];
        if (gac_round_enumerate(nd, W, ncon, start, dim, cf, rows, q, 0, GAC_FRICTION_RESIDUAL_MAX * 1e-3, exact, &res)
            && res < *residual) {
            for (i = 0; i < nr; ++i) L[i] = exact[i];
            *residual = res;
        }
    }
    if (*residual > 4.0 * GAC_EPS) gac_round_refine(nd, W, ncon, start, dim, cf, rows, q, L, residual);
}

/* The round's problem solved by the proximal point method, where the plain solve (gac_round_solve) leaves it
 * above accept: contacts whose rows are dependent (two walls at one point, a link held at both ends: W singular,
 * the impulses not unique) or nearly so, where Gauss-Seidel cycles and the modes' linear systems are singular.
 * Each step solves the problem regularised about the last impulses L_k,
 *     xi = (W + delta I) L + q - delta L_k     (the same law; W + delta I positive definite),
 * from L_k: Newton's method on L_k's modes (gac_round_refine), else a short Gauss-Seidel started there
 * (gac_round_solve, quick); its fixed points L_k+1 = L_k are the round's solutions.  Each step's impulses are then
 * refined on the round's own W by least-norm Newton steps (gac_round_refine_by: the modes' equations of dependent
 * rows are consistent but singular).  delta starts at 1e-2 of W's largest diagonal and shrinks by 0.3 a step (the
 * steps then converge superlinearly); a step whose regularised problem is left above GAC_FRICTION_RESIDUAL_MAX and
 * above a tenth of the best residual yet is taken again with delta ten times larger.  L and *residual (the round's
 * own residual, gac_round_residual, on W and q) are replaced by the best step's; it stops below accept, after
 * GAC_PROX_STEPS steps, or when the best residual has not halved in 20 steps. */
static void gac_round_proximal(int nd, const double *W, int ncon, const int *start, const int *dim,
                               const double *cf, const int *rows, const double *q, double accept, double *L,
                               double *residual)
{
    const int nr = start[ncon - 1] + dim[ncon - 1];
    double Wd[GAC_AT_LEAST_1(nr * nr)], qk[GAC_AT_LEAST_1(nr)], cur[GAC_AT_LEAST_1(nr)], next[GAC_AT_LEAST_1(nr)];
    double wmax = 0.0, rel = 1e-2, inner, res, mark = *residual;
    int idx[GAC_AT_LEAST_1(nr)], i, j, step, since = 0;
    for (i = 0; i < nr; ++i) {
        wmax = W[rows[i] * nd + rows[i]] > wmax ? W[rows[i] * nd + rows[i]] : wmax;
        idx[i] = i;
        cur[i] = L[i];
    }
    if (!(wmax > 0.0)) return;
    for (step = 0; step < GAC_PROX_STEPS && since < 20 && rel <= 1e2; ++step, ++since) {
        const double delta = rel * wmax;
        for (i = 0; i < nr; ++i) {
            for (j = 0; j < nr; ++j) Wd[i * nr + j] = W[rows[i] * nd + rows[j]];
            Wd[i * nr + i] += delta;
            qk[i] = q[i] - delta * cur[i];
            next[i] = cur[i];
        }
        inner = gac_round_residual(nr, Wd, ncon, start, dim, cf, idx, qk, next);   /* Newton from L_k's modes, */
        gac_round_refine(nr, Wd, ncon, start, dim, cf, idx, qk, next, &inner);
        if (inner > GAC_FRICTION_RESIDUAL_MAX) {                                    /* else the plain solve */
            for (i = 0; i < nr; ++i) next[i] = cur[i];
            gac_round_solve(nr, Wd, ncon, start, dim, cf, idx, qk, 1, next, &inner);
        }
        if (inner > GAC_FRICTION_RESIDUAL_MAX && inner > 0.1 * *residual) {   /* unsolved: more regularisation */
            rel *= 10.0;
            continue;
        }
        res = gac_round_residual(nd, W, ncon, start, dim, cf, rows, q, next);
        gac_round_refine_by(nd, W, ncon, start, dim, cf, rows, q, 1, next, &res);   /* on the round's own W */
        if (res < *residual) {
            *residual = res;
            for (i = 0; i < nr; ++i) L[i] = next[i];
        }
        if (*residual <= accept) break;
        if (*residual <= 0.5 * mark) mark = *residual, since = 0;
        for (i = 0; i < nr; ++i) cur[i] = next[i];
        rel *= 0.3;
    }
}

/* Every contact of the round that pushes in L held at rest, xi = 0 on its rows (the others at L = 0), with impulses
 * in the cones: a point of the cones' product on the affine set W_S L_S = -q_S, by alternating projections from L
 * (onto the set: the least-norm change W_S (W_S W_S + 1e-13 max diag I)^-1 (-(W_S L_S + q_S)); onto each cone
 * |L_T| <= c_f L_N: Euclidean, in closed form), ending on the set.  The impulses are not unique where the rows
 * are dependent (W_S singular), and such a point exists where the round's solution sticks everywhere it pushes.
 * L and *residual are replaced if that lowers the round's residual. */
static void gac_round_stick(int nd, const double *W, int ncon, const int *start, const int *dim, const double *cf,
                            const int *rows, const double *q, double *L, double *residual)
{
    const int nr = start[ncon - 1] + dim[ncon - 1];
    double G[GAC_AT_LEAST_1(nr * nr)], cur[GAC_AT_LEAST_1(nr)], r[GAC_AT_LEAST_1(nr)], y[GAC_AT_LEAST_1(nr)];
    double gmax = 0.0, res;
    int held[GAC_AT_LEAST_1(nr)], i, j, c, k, it;
    for (k = 0; k < ncon; ++k) {
        for (i = 0; i < dim[k]; ++i) held[start[k] + i] = L[start[k]] > 0.0;
    }
    for (i = 0; i < nr; ++i) {                   /* G = W_S W_S (+ the identity on the rows not held) */
        cur[i] = held[i] ? L[i] : 0.0;
        for (j = 0; j < nr; ++j) {
            double v = 0.0;
            for (c = 0; c < nr; ++c) {
                if (held[i] && held[j] && held[c]) v += W[rows[i] * nd + rows[c]] * W[rows[c] * nd + rows[j]];
            }
            G[i * nr + j] = v;
        }
        gmax = G[i * nr + i] > gmax ? G[i * nr + i] : gmax;
    }
    if (!(gmax > 0.0)) return;
    for (i = 0; i < nr; ++i) G[i * nr + i] += held[i] ? 1e-13 * gmax : 1.0;
    if (gac_ldlt(nr, G, 1e-300) != 0) return;
    for (it = 0; it < 2000; ++it) {
        double change = 0.0, size = 0.0;
        for (i = 0; i < nr; ++i) {               /* onto the set */
            double v = q[i];
            for (j = 0; j < nr; ++j) v += held[j] ? W[rows[i] * nd + rows[j]] * cur[j] : 0.0;
            y[i] = held[i] ? -v : 0.0;
        }
        gac_ldlt_solve(nr, G, y);
        for (i = 0; i < nr; ++i) {
            double v = 0.0;
            for (j = 0; j < nr; ++j) v += held[i] && held[j] ? W[rows[i] * nd + rows[j]] * y[j] : 0.0;
            r[i] = cur[i] + v;
        }
        if (it == 1999) break;
        for (k = 0; k < ncon; ++k) {             /* onto the cones */
            const int s = start[k], d = dim[k];
            double n = r[s], t = 0.0, mu = cf[k];
            if (!held[s]) continue;
            for (i = 1; i < d; ++i) t += r[s + i] * r[s + i];
            t = sqrt(t);
            if (d == 1 || !(mu > 0.0)) {
                n = n > 0.0 ? n : 0.0;
                for (i = 1; i < d; ++i) r[s + i] = 0.0;
            } else if (t <= mu * n) {
            } else if (mu * t <= -n) {
                n = 0.0;
                for (i = 1; i < d; ++i) r[s + i] = 0.0;
            } else {
                n = (n + mu * t) / (1.0 + mu * mu);
                for (i = 1; i < d; ++i) r[s + i] *= mu * n / t;
            }
            r[s] = n;
        }
        for (i = 0; i < nr; ++i) {
            change = fabs(r[i] - cur[i]) > change ? fabs(r[i] - cur[i]) : change;
            size = fabs(r[i]) > size ? fabs(r[i]) : size;
            cur[i] = r[i];
        }
        if (change <= 4.0 * GAC_EPS * size) it = 1998;   /* in both: once more onto the set */
    }
    res = gac_round_residual(nd, W, ncon, start, dim, cf, rows, q, r);
    if (res < *residual) {
        *residual = res;
        for (i = 0; i < nr; ++i) L[i] = r[i];
    }
}

/* The round's problem (gac_round_solve); with proximal set, where that leaves the residual above accept, the
 * proximal point method from its impulses (gac_round_proximal), and where that too is left above accept, every
 * pushing contact held at rest (gac_round_stick). */
static void gac_round_friction(int nd, const double *W, int ncon, const int *start, const int *dim,
                               const double *cf, const int *rows, const double *q, int proximal, double accept,
                               double *L, double *residual)
{
    gac_round_solve(nd, W, ncon, start, dim, cf, rows, q, 0, L, residual);
    if (proximal && *residual > accept)
        gac_round_proximal(nd, W, ncon, start, dim, cf, rows, q, 1e-3 * accept, L, residual);
    if (proximal && *residual > accept) gac_round_stick(nd, W, ncon, start, dim, cf, rows, q, L, residual);
}

/* The velocities of the system's rows (gac_friction_system: each contact's normal, then its tangential axes) at
 * velocities w, read off the model's contact velocities; a link pair's or an obstacle's along its frame (its
 * normal, t1, t2: axis_of 0, 1). */
static void gac_row_velocities(const gac_model *m, const double *q, const double *p, int n, const int *list,
                               const int *start, const int *dim, const int *axis_of, const double *w, double *out)
{
    double vel[3 * GAC_AT_LEAST_1(m->npoint)], size;
    int a, i;
    m->contact_velocities(q, w, p, vel);
    for (a = 0; a < n; ++a) {
        const gac_contact *k = &m->contacts[list[a]];
        if (gac_rowless(m, list[a])) {
            gac_contact_frame frame;
            if (gac_rowless_frame(m, q, p, list[a], &frame) != GAC_OK) {
                for (i = 0; i < dim[a]; ++i) out[start[a] + i] = NAN;
                continue;
            }
            for (i = 0; i < dim[a]; ++i)
                out[start[a] + i] = gac_frame_rate(&frame, vel, i == 0 ? 0 : 1 + axis_of[start[a] + i], &size);
            continue;
        }
        out[start[a]] = k->normal_sign * gac_row_value(m, list[a], w, vel);
        for (i = 1; i < dim[a]; ++i) {
            int axis = 0, j;
            for (j = 0; ; ++axis) {               /* the axis_of-th axis other than the normal's */
                if (axis == k->axis) continue;
                if (j++ == axis_of[start[a] + i]) break;
            }
            out[start[a] + i] = vel[3 * (k->point - 1) + axis];
        }
    }
}

/* A law solved in one round, refined against the velocities its impulses give (iterative refinement of the whole
 * nonlinear solve): the round's velocities xi = gamma+ + e gamma- read off qd_plus with the model's contact
 * velocities differ from W L + q by d (the responses' and W's round-off, large where the impulses are large and W
 * ill-conditioned); the round's modes are solved again for the constant q + d (gac_round_refine, from L) and the
 * change of L applied to qd_plus and total, while the round's residual with q + d falls by half (3 times at
 * most). */
static void gac_refine_round(const gac_model *m, const double *q, const double *p, int n, const int *list,
                             const int *start, const int *dim, const int *axis_of, const double *const *resp,
                             int nd, const double *W, int k, const int *st, const int *dm, const double *cfk,
                             const int *rows, const double *ek, const double *gam0, double *L, double *total,
                             double *qd_plus)
{
    const int nq = m->nq, nr = st[k - 1] + dm[k - 1];
    double gp[GAC_AT_LEAST_1(nd)], qn[GAC_AT_LEAST_1(nr)], trial[GAC_AT_LEAST_1(nr)];
    int it, b, i, j;
    for (it = 0; it < 3; ++it) {
        double before, after;
        gac_row_velocities(m, q, p, n, list, start, dim, axis_of, qd_plus, gp);
        for (b = 0; b < k; ++b) {
            for (i = st[b]; i < st[b] + dm[b]; ++i) {  /* q + d = xi (model) - W L */
                long double v = (long double)gp[rows[i]] + ek[b] * gam0[rows[i]];
                for (j = 0; j < nr; ++j) v -= (long double)W[rows[i] * nd + rows[j]] * L[j];
                qn[i] = (double)v;
            }
        }
        before = gac_round_residual(nd, W, k, st, dm, cfk, rows, qn, L);
        if (!(before > 4.0 * GAC_EPS)) return;
        for (i = 0; i < nr; ++i) trial[i] = L[i];
        after = before;
        gac_round_refine(nd, W, k, st, dm, cfk, rows, qn, trial, &after);
        if (!(after < 0.5 * before)) return;
        for (i = 0; i < nr; ++i) {
            const double change = trial[i] - L[i];
            int c;
            if (change == 0.0) continue;
            for (c = 0; c < nq; ++c) qd_plus[c] += resp[rows[i]][c] * change;
            total[rows[i]] += change;
            L[i] = trial[i];
        }
    }
}

/* The contact-space system of the contacts list[0..n-1] at (q, qd): each contact's directions (its normal, then,
 * with friction under law, its tangential directions: start[a], dim[a], cf[a] its Coulomb coefficient, 0 where it
 * has no tangential part), their responses resp[r] = I_f^-1 d_r (in work's Y and Z), W = D I_f^-1 D^T (nd x nd,
 * in work's W, symmetric) and the velocities gam = D qd; axis_of[r] the tangential direction (0, 1) of row r, -1
 * for a normal.  A wall's tangential directions are the Jacobian rows trow[] of its point along the box axes other
 * than its normal; a link pair's or an obstacle's (no rows) are J^T t1, J^T t2 of its contact frame
 * (gac_rowless_frame), its velocities the closest points' relative velocity along n, t1, t2 (gac_frame_rate); a
 * direction that no motion of the chain takes (|J^T t| below 1e-10 of its columns' size: a planar model's t2) is
 * left out, as a wall's axis without a row.  *nd_out the rows.  GAC_OK or the error of gac_impact_system /
 * gac_row_response / gac_rowless_frame. */
static int gac_friction_system(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                               const int *list, int law, double *work, double *cf, int *start, int *dim,
                               int *axis_of, const double **resp, double *gam, int *nd_out)
{
    const int nq = m->nq, nd_max = 3 * n;
    double v_unused[GAC_AT_LEAST_1(nq)], e_wall[GAC_AT_LEAST_1(nq)];
    double *Y = GAC_WORK_Y(m, work), *g = GAC_WORK_G(m, work), *vel = GAC_WORK_VEL(m, work);
    double *f = GAC_WORK_F(m, work), *Z = GAC_WORK_Z(m, work), *W = GAC_WORK_W(m, work);
    double r_scratch[GAC_AT_LEAST_1(nq)], dy_scratch[GAC_AT_LEAST_1(nq)];
    gac_contact_frame frames[GAC_AT_LEAST_1(n)];
    int owner[nd_max], comp[nd_max];
    int a, b, i, j, nd = 0, nt = 0, code;
    code = gac_impact_system_refined(m, q, qd, p, n, list, work, v_unused, e_wall);   /* Y_a = I_f^-1 n_a, refined */
    if (code != GAC_OK) return code;
    for (a = 0; a < n; ++a) {                 /* the directions: each contact's normal, then its tangential axes */
        const gac_contact *k = &m->contacts[list[a]];
        const int rowless = gac_rowless(m, list[a]);
        int axis = 0;
        if (rowless) {
            code = gac_rowless_frame(m, q, p, list[a], &frames[a]);
            if (code != GAC_OK) return code;
        }
        cf[a] = law == GAC_IMPACT_LAW_FRICTIONLESS ? 0.0 : gac_contact_friction(m, p, list[a]);
        start[a] = nd;
        owner[nd] = a, comp[nd] = -1, axis_of[nd] = -1, resp[nd++] = Y + (long)a * nq;
        if (!(cf[a] > 0.0)) {
            dim[a] = 1;
            continue;
        }
        for (j = 0; j < 2; ++j, ++axis) {
            double *Zt = Z + (long)nt * nq;
            if (rowless) {                    /* J^T t_j of the frame, and its response */
                double norm = 0.0;
                const double scale = gac_frame_direction(m, q, p, &frames[a], j + 1, g);
                for (i = 0; i < nq; ++i) norm += g[i] * g[i];
                if (!(sqrt(norm) > 1e-10 * scale)) continue;
                m->inertia_solve(q, g, p, Zt);
                for (i = 0; i < nq; ++i) {
                    if (!isfinite(Zt[i])) return GAC_ERR_SINGULAR_MASS;
                }
                gac_refine_response(m, q, p, g, Zt, r_scratch, dy_scratch);
                owner[nd] = a, comp[nd] = -2, axis_of[nd] = j, resp[nd++] = Zt;
                ++nt;
                continue;
            }
            if (axis == k->axis) ++axis;
            if (k->trow[j] < 0) continue;
            code = gac_row_response(m, q, p, k->trow[j], f, g, Zt);   /* a unit force along +X_axis */
            if (code != GAC_OK) return code;
            gac_refine_response(m, q, p, g, Zt, r_scratch, dy_scratch);
            owner[nd] = a, comp[nd] = 3 * (k->point - 1) + axis, axis_of[nd] = j, resp[nd++] = Zt;
            ++nt;
        }
        dim[a] = nd - start[a];
    }
    /* W[r][s] = d_r . I_f^-1 d_s, read off the velocities of the rows for the response of s; gam = velocities */
    for (b = 0; b <= nd; ++b) {
        const double *w = b < nd ? resp[b] : qd;
        m->contact_velocities(q, w, p, vel);
        for (a = 0; a < nd; ++a) {
            const int c = list[owner[a]];
            double value, size;
            if (gac_rowless(m, c))            /* along the frame: its normal (comp -1), t1 or t2 (comp -2) */
                value = gac_frame_rate(&frames[owner[a]], vel, comp[a] == -1 ? 0 : 1 + axis_of[a], &size);
            else
                value = comp[a] < 0 ? m->contacts[c].normal_sign * gac_row_value(m, c, w, vel) : vel[comp[a]];
            if (b < nd) W[a*nd + b] = value;
            else gam[a] = value;
        }
    }
    for (a = 0; a < nd; ++a) {                 /* symmetric up to round-off: make it exactly so */
        for (b = 0; b < a; ++b) W[a*nd + b] = W[b*nd + a] = 0.5 * (W[a*nd + b] + W[b*nd + a]);
    }
    *nd_out = nd;
    return GAC_OK;
}

int gac_impact_rounds_friction(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                               const int *list, const double *e, int first, int law, double *qd_plus, double *F,
                               double *Ft, double *work, int *rounds, int *plastic, int *law_used, double *residual,
                               double *tangential_parts)
{
    return gac_impact_rounds_friction_traced(m, q, qd, p, n, list, e, first, law, qd_plus, F, Ft, work, rounds,
                                             plastic, law_used, residual, tangential_parts, 0);
}

/* gac_impact_rounds_friction, each round recorded in trace (NULL: none) as well: its contacts (positions in list),
 * whether struck with their own e, their rows and impulses. */
int gac_impact_rounds_friction_traced(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                                      const int *list, const double *e, int first, int law, double *qd_plus,
                                      double *F, double *Ft, double *work, int *rounds, int *plastic, int *law_used,
                                      double *residual, double *tangential_parts, gac_rounds_trace *trace)
{
    const int nq = m->nq, nd_max = 3 * n;
    double *W = GAC_WORK_W(m, work);
    double cf[GAC_AT_LEAST_1(nq)], gam[nd_max], total[nd_max], scale = 0.0, v_tol, v_solved = 0.0;
    int start[GAC_AT_LEAST_1(nq)], dim[GAC_AT_LEAST_1(nq)], axis_of[nd_max];
    const double *resp[nd_max];
    double gam0[nd_max], ek0[GAC_AT_LEAST_1(nq)], cf0[GAC_AT_LEAST_1(nq)], L0[nd_max];
    int st0[GAC_AT_LEAST_1(nq)], dm0[GAC_AT_LEAST_1(nq)], rows0[nd_max], k0 = 0;
    int a, b, i, j, nd = 0, round, code;
    *rounds = *plastic = 0;
    *residual = 0.0;
    *law_used = GAC_IMPACT_LAW_FRICTIONLESS;
    code = gac_friction_system(m, q, qd, p, n, list, law, work, cf, start, dim, axis_of, resp, gam, &nd);
    if (code != GAC_OK) return code;
    for (a = 0; a < nd; ++a) total[a] = 0.0, gam0[a] = gam[a];
    for (a = 0; a < n; ++a) {
        if (fabs(gam[start[a]]) > scale) scale = fabs(gam[start[a]]);
        if (dim[a] > 1 && *law_used == GAC_IMPACT_LAW_FRICTIONLESS)
            *law_used = law == GAC_IMPACT_LAW_NEWTON_COULOMB ? GAC_IMPACT_LAW_NEWTON_COULOMB : GAC_IMPACT_LAW_GDI;
    }
    v_tol = 1e-11 * scale;
    for (round = 0; ; ++round) {
        int rows[nd_max], st[GAC_AT_LEAST_1(nq)], dm[GAC_AT_LEAST_1(nq)];
        double ek[GAC_AT_LEAST_1(nq)], cfk[GAC_AT_LEAST_1(nq)], qv[nd_max], L[nd_max], res = 0.0, res_max = 0.0;
        double ek_own[GAC_AT_LEAST_1(nq)];
        int k = 0, nr = 0, approaching = 0, pass, attempt, quiet = 0, who[GAC_AT_LEAST_1(nq)], hit[GAC_AT_LEAST_1(nq)];
        const int law_before = *law_used;
        const int last = round >= GAC_MAX_ROUNDS;
        for (a = 0; a < n; ++a) {
            const double v = gam[start[a]];
            const int struck = v < -v_tol || (round == 0 && a == first && v < 0.0);
            if (struck) approaching = 1;
            if (last || struck || v <= v_tol) {
                ek[k] = !last && struck ? e[a] : 0.0;
                cfk[k] = cf[a];
                st[k] = nr;
                dm[k] = dim[a];
                for (i = 0; i < dim[a]; ++i) rows[nr++] = start[a] + i;
                hit[k] = !last && struck;
                who[k++] = a;
            }
        }
        if (!approaching) break;
        {                                        /* what the round's W lets its conditions be solved to: its
                                                    pivots' spread (a lower bound of cond W) times 16 eps */
            double Wr[nr * nr], dmax = 0.0, dmin = INFINITY;
            for (i = 0; i < nr; ++i) {
                for (j = 0; j < nr; ++j) Wr[i * nr + j] = W[rows[i] * nd + rows[j]];
            }
            if (gac_ldlt(nr, Wr, 1e-300) == 0) {
                for (i = 0; i < nr; ++i) {
                    dmax = Wr[i * nr + i] > dmax ? Wr[i * nr + i] : dmax;
                    dmin = Wr[i * nr + i] < dmin ? Wr[i * nr + i] : dmin;
                }
                res_max = 16.0 * GAC_EPS * dmax / dmin;
            }
            if (!(res_max > GAC_FRICTION_RESIDUAL_MAX)) res_max = GAC_FRICTION_RESIDUAL_MAX;
        }
        for (b = 0; b < k; ++b) ek_own[b] = ek[b];
        for (attempt = 0; attempt < 2; ++attempt) {  /* the plain solve; where it fails, the proximal one */
            if (attempt == 1) {                  /* the round's approach (what the earlier rounds left, or a
                                                    first round's at round-off: contacts touching at rest, rows
                                                    dependent) against the contact velocities the motion can have */
                double left = 0.0, E[2], v_motion = 0.0;
                m->energy(q, qd, p, E);
                for (b = 0; b < k; ++b) left = -gam[rows[st[b]]] > left ? -gam[rows[st[b]]] : left;
                for (a = 0; a < nd; ++a) {       /* |d_r . qd| <= sqrt(2 T W_rr) */
                    const double v = sqrt(2.0 * fabs(E[0]) * W[a * nd + a]);
                    v_motion = v > v_motion ? v : v_motion;
                }
                v_motion = v_motion > v_solved ? v_motion : v_solved;
                if (left <= res_max * v_motion) {
                    quiet = 1;                   /* within the law's tolerance: the rounds end */
                    if (left / v_motion > *residual) *residual = left / v_motion;
                    break;
                }
            }
            if (attempt == 1) {
                for (b = 0; b < k; ++b) ek[b] = ek_own[b];
                *law_used = law_before;
            }
            for (pass = 0; pass < 2; ++pass) {
                double dT = 0.0, size = 0.0;
                for (b = 0; b < k; ++b) {       /* q = (1 + e) gamma- (GDI); Newton + Coulomb: e on the normal only */
                    for (i = 0; i < dm[b]; ++i) {
                        const double gm = gam[rows[st[b] + i]];
                        const int restitutes = i == 0 || law != GAC_IMPACT_LAW_NEWTON_COULOMB;
                        qv[st[b] + i] = restitutes ? (1.0 + ek[b]) * gm : gm;
                    }
                }
                gac_round_friction(nd, W, k, st, dm, cfk, rows, qv, attempt, res_max, L, &res);
                if (law == GAC_IMPACT_LAW_NEWTON_COULOMB || pass == 1) break;
                for (i = 0; i < nr; ++i) {           /* dT = L . gamma- + L W L / 2 over the round's rows */
                    double wl = 0.0;
                    for (j = 0; j < nr; ++j) wl += W[rows[i] * nd + rows[j]] * L[j];
                    dT += L[i] * (gam[rows[i]] + 0.5 * wl);
                    size += fabs(L[i]) * (fabs(gam[rows[i]]) + 0.5 * fabs(wl));
                }
                if (dT <= 1e-12 * size && res <= res_max) break;      /* solved, no gain */
                {                                    /* else a common restitution, the smallest of the round's */
                    double e_min = 1.0;
                    for (b = 0; b < k; ++b) e_min = ek[b] < e_min ? ek[b] : e_min;
                    for (b = 0; b < k; ++b) ek[b] = e_min;
                    *law_used = GAC_IMPACT_LAW_GDI_COMMON_E;
                }
            }
            if (res <= res_max) break;
        }
        if (quiet) break;
        if (res > *residual) *residual = res;
        if (res > res_max) return GAC_ERR_IMPACT_FRICTION;
        if (trace != 0 && (trace->nround = round + 1) <= trace->cap) {   /* the round, recorded */
            trace->k[round] = k;
            for (b = 0; b < k; ++b) {
                const int o = round * trace->n + b;
                trace->idx[o] = who[b], trace->hit[o] = hit[b];
                trace->dim[o] = dm[b], trace->F[o] = L[st[b]];
                for (i = 0; i < dm[b]; ++i) trace->L[3 * o + i] = L[st[b] + i];
            }
        }
        if (round == 0) {                        /* the first round, for gac_refine_round */
            k0 = k;
            for (b = 0; b < k; ++b) st0[b] = st[b], dm0[b] = dm[b], ek0[b] = ek[b], cf0[b] = cfk[b];
            for (i = 0; i < nr; ++i) rows0[i] = rows[i], L0[i] = L[i];
        }
        for (i = 0; i < nr; ++i) {
            total[rows[i]] += L[i];
            v_solved = fabs(qv[i]) > v_solved ? fabs(qv[i]) : v_solved;   /* the velocities solved so far */
        }
        for (a = 0; a < nd; ++a) {
            for (i = 0; i < nr; ++i) gam[a] += W[a*nd + rows[i]] * L[i];
        }
        *rounds = round + 1;
        if (last) {
            *plastic = 1;
            break;
        }
    }
    for (i = 0; i < nq; ++i) {
        double value = qd[i];
        for (a = 0; a < nd; ++a) value += resp[a][i] * total[a];
        qd_plus[i] = value;
    }
    if (*rounds == 1 && !*plastic && law != GAC_IMPACT_LAW_NEWTON_COULOMB && k0 > 0)
        gac_refine_round(m, q, p, n, list, start, dim, axis_of, resp, nd, W, k0, st0, dm0, cf0, rows0, ek0, gam0, L0,
                         total, qd_plus);
    *tangential_parts = 0.0;                     /* sum |L_T| |I_f^-1 t|: the tangential changes before they cancel */
    for (a = 0; a < nd; ++a) {
        double column = 0.0;
        if (axis_of[a] < 0) continue;
        for (i = 0; i < nq; ++i) column += resp[a][i] * resp[a][i];
        *tangential_parts += fabs(total[a]) * sqrt(column);
    }
    for (a = 0; a < n; ++a) {
        F[a] = total[start[a]];
        Ft[2*a] = Ft[2*a + 1] = 0.0;
        for (i = 1; i < dim[a]; ++i) Ft[2*a + axis_of[start[a] + i]] = total[start[a] + i];
    }
    return GAC_OK;
}

int gac_impact_friction(const gac_model *m, const double *GAC_RESTRICT q, const double *GAC_RESTRICT qd,
                        const double *GAC_RESTRICT p, int ncontact_set, const int *GAC_RESTRICT contact_set, int law,
                        double *GAC_RESTRICT qd_plus, double *GAC_RESTRICT impulse, double *GAC_RESTRICT impulse_t,
                        int *law_used, double *residual, double *GAC_RESTRICT work)
{
    double e[GAC_AT_LEAST_1(m->nq)], parts;
    int a, rounds, plastic;
    if (law != GAC_IMPACT_LAW_GDI && law != GAC_IMPACT_LAW_NEWTON_COULOMB && law != GAC_IMPACT_LAW_FRICTIONLESS)
        return GAC_ERR_BAD_OPTION;
    if (ncontact_set < 1 || ncontact_set > m->nq) return GAC_ERR_BAD_CONTACT;
    for (a = 0; a < ncontact_set; ++a) {
        if (contact_set[a] < 0 || contact_set[a] >= m->ncontact) return GAC_ERR_BAD_CONTACT;
        e[a] = gac_restitution(m, p, contact_set[a]);
    }
    if (!gac_has_friction(m)) {                  /* no rough wall: every law is the frictionless one, and the work
                                                    array is the smaller one of a model without friction */
        for (a = 0; a < 2 * ncontact_set; ++a) impulse_t[a] = 0.0;
        *law_used = GAC_IMPACT_LAW_FRICTIONLESS;
        *residual = 0.0;
        return gac_impact_rounds(m, q, qd, p, ncontact_set, contact_set, e, -1, qd_plus, impulse, work, &rounds,
                                 &plastic);
    }
    return gac_impact_rounds_friction(m, q, qd, p, ncontact_set, contact_set, e, -1, law, qd_plus, impulse,
                                      impulse_t, work, &rounds, &plastic, law_used, residual, &parts);
}

int gac_impact_tangential(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                          const int *list, double *qd_plus, double *F, double *Ft, double *work, double *residual,
                          double *tangential_parts)
{
    const int nq = m->nq, nd_max = 3 * GAC_AT_LEAST_1(n);
    double cf[GAC_AT_LEAST_1(nq)], gam[nd_max], L[nd_max];
    int start[GAC_AT_LEAST_1(nq)], dim[GAC_AT_LEAST_1(nq)], axis_of[nd_max], rows[nd_max];
    const double *resp[nd_max];
    int a, i, nd = 0, code;
    *residual = *tangential_parts = 0.0;
    if (n < 1 || n > GAC_ENUM_MAX) return GAC_ERR_FRICTION;
    code = gac_friction_system(m, q, qd, p, n, list, GAC_IMPACT_LAW_GDI, work, cf, start, dim, axis_of, resp, gam, &nd);
    if (code != GAC_OK) return code;
    for (i = 0; i < nd; ++i) {                  /* every row takes part; the guess: every contact sticks */
        rows[i] = i;
        L[i] = axis_of[i] < 0 ? 1.0 : 0.0;
    }
    /* xi = gamma+ (e = 0: the contacts are at rest), 0 <= L_N _|_ gamma_N+ >= 0, Coulomb's cone on gamma_T+ */
    if (!gac_round_enumerate(nd, GAC_WORK_W(m, work), n, start, dim, cf, rows, gam, 1, GAC_FRICTION_RESIDUAL_MAX, L, residual))
        return GAC_ERR_FRICTION;
    for (a = 0; a < n; ++a) {                   /* a stick at the cone's edge (the jam): onto the cone */
        double lt = 0.0;
        for (i = 1; i < dim[a]; ++i) lt += L[start[a] + i] * L[start[a] + i];
        lt = sqrt(lt);
        if (L[start[a]] < 0.0) L[start[a]] = 0.0;
        if (lt > cf[a] * L[start[a]]) {
            for (i = 1; i < dim[a]; ++i) L[start[a] + i] *= cf[a] * L[start[a]] / lt;
        }
    }
    for (i = 0; i < nq; ++i) {
        double value = qd[i];
        for (a = 0; a < nd; ++a) value += resp[a][i] * L[a];
        qd_plus[i] = value;
    }
    for (a = 0; a < nd; ++a) {                  /* sum |L_T| |I_f^-1 t|, as gac_impact_rounds_friction */
        double column = 0.0;
        if (axis_of[a] < 0) continue;
        for (i = 0; i < nq; ++i) column += resp[a][i] * resp[a][i];
        *tangential_parts += fabs(L[a]) * sqrt(column);
    }
    for (a = 0; a < n; ++a) {
        F[a] = L[start[a]];
        Ft[2*a] = Ft[2*a + 1] = 0.0;
        for (i = 1; i < dim[a]; ++i) Ft[2*a + axis_of[start[a] + i]] = L[start[a] + i];
    }
    return GAC_OK;
}

/* f(L) = L . gam + L W L / 2 along the ray L = t u of the cone's surface, u = (1, -c_f cos phi, -c_f sin phi):
 * its least value over t >= 0, -g^2 / (2 h) (g = u . gam < 0, h = u W u > 0), else 0; *t_best the t there. */
static double gac_cone_ray(int d, double W[3][3], const double *gam, double cf, double phi, double *t_best)
{
    double u[3], g = 0.0, h = 0.0;
    int a, b;
    u[0] = 1.0, u[1] = -cf * cos(phi), u[2] = -cf * sin(phi);
    for (a = 0; a < d; ++a) {
        g += u[a] * gam[a];
        for (b = 0; b < d; ++b) h += u[a] * W[a][b] * u[b];
    }
    *t_best = g < 0.0 && h > 0.0 ? -g / h : 0.0;
    return g < 0.0 && h > 0.0 ? -g * g / (2.0 * h) : 0.0;
}

/* The least f(L) = L . gam + L W L / 2 over Coulomb's cone |L_T| <= c_f L_N of one contact (d = 2: one tangential
 * direction, 3: two; W its d x d contact-space inverse inertia, symmetric positive definite): at the apex L = 0
 * (f = 0), at the stick impulse -W^-1 gam where it lies inside the cone, or on the cone's surface, L = t u(phi) with
 * t = -g / h, phi by a grid and golden sections (d = 3; d = 2: the cone's two edges).  L (d) and the value. */
static double gac_cone_min(int d, double W[3][3], const double *gam, double cf, double *L)
{
    const int grid = d == 2 ? 2 : 720;
    double best = 0.0, phi_best = 0.0, t, lo, hi;
    int a, b, k;
    for (a = 0; a < 3; ++a) L[a] = 0.0;
    for (k = 0; k < grid; ++k) {                   /* the cone's surface: phi on a grid ... */
        const double phi = d == 2 ? (k == 0 ? 0.0 : 3.14159265358979323846) : 6.283185307179586 * k / grid;
        const double value = gac_cone_ray(d, W, gam, cf, phi, &t);
        if (value < best) best = value, phi_best = phi;
    }
    lo = phi_best - 6.283185307179586 / grid, hi = phi_best + 6.283185307179586 / grid;
    for (k = 0; d == 3 && best < 0.0 && k < 80; ++k) {   /* ... then golden sections */
        const double m1 = hi - 0.6180339887498949 * (hi - lo), m2 = lo + 0.6180339887498949 * (hi - lo);
        if (gac_cone_ray(d, W, gam, cf, m1, &t) < gac_cone_ray(d, W, gam, cf, m2, &t)) hi = m2;
        else lo = m1;
    }
    if (best < 0.0) {
        const double phi = d == 3 ? 0.5 * (lo + hi) : phi_best;
        const double value = gac_cone_ray(d, W, gam, cf, phi, &t);
        const double use = value <= best ? phi : phi_best;
        best = gac_cone_ray(d, W, gam, cf, use, &t);
        L[0] = t, L[1] = -cf * cos(use) * t, L[2] = -cf * sin(use) * t;
    }
    {                                              /* inside the cone: the stick impulse, where it lies there */
        double A[9], Ls[3], t2 = 0.0, value = 0.0;
        for (a = 0; a < d; ++a) {
            Ls[a] = -gam[a];
            for (b = 0; b < d; ++b) A[a * d + b] = W[a][b];
        }
        if (gac_lu_solve(d, A, Ls, 1e-13) == 0 && Ls[0] > 0.0) {
            for (a = 1; a < d; ++a) t2 += Ls[a] * Ls[a];
            for (a = 0; a < d; ++a) value += 0.5 * Ls[a] * gam[a];           /* f = -gam W^-1 gam / 2 */
            if (sqrt(t2) <= cf * Ls[0] && value < best) {
                for (a = 0; a < d; ++a) L[a] = Ls[a];
                best = value;
            }
        }
    }
    for (a = d; a < 3; ++a) L[a] = 0.0;
    return best;
}

/* The impulses in the Coulomb cones of the resting contacts list[0..n-1] (n <= GAC_JAM_CONTACTS) that take the most
 * kinetic energy: Lambda = argmin over the cones of f(Lambda) = Lambda . gamma- + Lambda W Lambda / 2 (= T+ - T-, W
 * the contact-space inverse inertia of the contacts' normal and tangential directions, gac_friction_system; the
 * maximal-dissipation impact, a convex problem with a solution).  Its optimum has gamma+ = gamma- + W Lambda in the
 * dual cones, gamma+_N >= c_f |gamma+_T| >= 0 (no contact approaches), and Lambda . gamma+ = 0 per contact.  While a
 * contact slides, f < 0 along its cone's edge against the slip, so the minimum is not trivial.  Solved by block
 * coordinate descent (each contact's block by gac_cone_min, a smooth contact's alone, with the others' impulses in
 * its gamma; f falls at every block, and for a strictly convex f over a product of closed convex sets the sweeps
 * converge to the optimum), until no impulse moves by 1e-12 of the largest, at most GAC_CONE_SWEEPS sweeps; one
 * contact: one block, one sweep.  qd_plus (nq), F (n), Ft (2 n) as gac_impact_tangential.  GAC_ERR_FRICTION if the
 * minimum is trivial (f not below 0), or the error of gac_friction_system. */
#define GAC_CONE_SWEEPS 500
int gac_impact_cones(const gac_model *m, const double *q, const double *qd, const double *p, int n, const int *list,
                     double *qd_plus, double *F, double *Ft, double *work)
{
    const int nq = m->nq, nd_max = 3 * GAC_AT_LEAST_1(n);
    double cf[GAC_AT_LEAST_1(nq)], gam[nd_max], L[nd_max], total = 0.0;
    int start[GAC_AT_LEAST_1(nq)], dim[GAC_AT_LEAST_1(nq)], axis_of[nd_max];
    const double *resp[nd_max];
    const double *W = GAC_WORK_W(m, work);
    int sweep, a, b, i, j, k, nd = 0, code;
    if (n < 1 || n > GAC_JAM_CONTACTS) return GAC_ERR_FRICTION;
    code = gac_friction_system(m, q, qd, p, n, list, GAC_IMPACT_LAW_GDI, work, cf, start, dim, axis_of, resp, gam, &nd);
    if (code != GAC_OK) return code;
    for (k = 0; k < nd; ++k) L[k] = 0.0;
    for (sweep = 0; sweep < GAC_CONE_SWEEPS; ++sweep) {   /* block coordinate descent over the contacts */
        double moved = 0.0, size = 0.0;
        for (a = 0; a < n; ++a) {
            const int d = dim[a], o = start[a];
            double Wa[3][3], ga[3], La[3];
            for (i = 0; i < d; ++i) {                 /* its block, the others' impulses in its gamma */
                ga[i] = gam[o + i];
                for (k = 0; k < nd; ++k) {
                    if (k < o || k >= o + d) ga[i] += W[(o + i)*nd + k] * L[k];
                }
                for (j = 0; j < d; ++j) Wa[i][j] = W[(o + i)*nd + o + j];
            }
            if (d == 1) {                             /* a smooth contact: the normal impulse alone, >= 0 */
                La[0] = Wa[0][0] > 0.0 && ga[0] < 0.0 ? -ga[0] / Wa[0][0] : 0.0;
            } else {
                gac_cone_min(d, Wa, ga, cf[a], La);
            }
            for (i = 0; i < d; ++i) {
                if (fabs(La[i] - L[o + i]) > moved) moved = fabs(La[i] - L[o + i]);
                L[o + i] = La[i];
            }
        }
        for (k = 0; k < nd; ++k) size = fabs(L[k]) > size ? fabs(L[k]) : size;
        if (!(moved > 1e-12 * size)) break;
    }
    for (k = 0; k < nd; ++k) {                   /* f(Lambda) = T+ - T-: it must fall */
        total += L[k] * gam[k];
        for (b = 0; b < nd; ++b) total += 0.5 * L[k] * W[k*nd + b] * L[b];
    }
    if (!(total < 0.0)) return GAC_ERR_FRICTION;
    for (i = 0; i < nq; ++i) {
        double value = qd[i];
        for (k = 0; k < nd; ++k) value += resp[k][i] * L[k];
        qd_plus[i] = value;
    }
    for (a = 0; a < n; ++a) {
        F[a] = L[start[a]];
        Ft[2*a] = Ft[2*a + 1] = 0.0;
        for (i = 1; i < dim[a]; ++i) Ft[2*a + axis_of[start[a] + i]] = L[start[a] + i];
    }
    return GAC_OK;
}
