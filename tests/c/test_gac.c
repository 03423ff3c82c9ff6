/*
 * test_gac.c -- the library gac (runtime/c) on hand-written models, with no Python and no generated code.
 *
 *   gcc -std=c99 -Wall -Wextra -pedantic -Werror -O2 -I runtime/c tests/c/test_gac.c runtime/c/gac_*.c -lm \
 *       -o test_gac && ./test_gac            (or: make -C tests/c)
 *
 * Models:
 *   ball  a point mass m on a floor under gravity g, q = [y]; restitution e from p.  Dropped from rest at
 *         height h it strikes the floor at t_1 = sqrt(2 h / g) with speed u_1 = g t_1, and after impact k at
 *         speed u_k leaves at e u_k: u_k = e^(k-1) u_1, t_(k+1) = t_k + 2 e u_k / g.  Every integrator is
 *         exact on this motion (a quadratic), so the loop must match these closed forms to round-off.
 *         An input u (N) pushes it up: with u held at m g + m a from rest at height h it rises as
 *         h + a t^2 / 2, the input doing the work u (y - h); a PD controller u = m g - k (y - y_ref) - c v
 *         makes it a damped oscillator about y_ref (closed form), and a linear input schedule gives a cubic.
 *   box   a point mass in the square [0, 2] x [0, 2] under gravity, q = [x, y], e = 1 on every wall: x moves
 *         at constant speed between the side walls (closed-form impact times), y bounces on the floor, and
 *         the energy is kept.
 *   spring  the ball's point on a spring, qdd = -w^2 y, its wall out of reach: y = cos(w t) (the integrators'
 *         orders of convergence and dense output).
 *   skew  a point in a corner with the coupled inertia [[2, 1], [1, 2]]: Newton's law on two contacts by hand.
 *   checked_ball  the ball with a parameter table and a check of its own (g, m > 0, e in [0, 1]), as a generated
 *         model has: gac_sim_init refuses parameters outside it.
 *   lever  a point on a rough floor whose inertia couples its two directions, I_f = [[2, 1], [1, 1]] (kg): sliding
 *         towards -x with c_f = 3 its compliance with sliding W_yy - c_f sgn(v) W_xy is 2 - 3 < 0, the Painleve
 *         paradox: the tangential impact by hand.
 * Exit status 0 if every check holds; with the argument --break one expected value is made wrong on
 * purpose, and the program must fail (the checks can fail).
 */
#include "gac.h"
#include "gac_internal.h"   /* the library's internal steps tested on their own */

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

static int checks = 0, failures = 0, broken = 0;

#define CHECK(cond, ...)                                                      \
    do {                                                                      \
        ++checks;                                                             \
        if (!(cond)) {                                                        \
            ++failures;                                                       \
            printf("FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond);            \
            printf(__VA_ARGS__);                                              \
            printf("\n");                                                     \
        }                                                                     \
    } while (0)

#define NEAR(a, b, tol) (fabs((a) - (b)) <= (tol))

/* ---- ball: p = [g, m, e] ------------------------------------------------------------------------ */
static void ball_solve(const double *q, const double *Q, const double *p, double *x) { (void)q; x[0] = Q[0] / p[1]; }
static void ball_momentum(const double *q, const double *qd, const double *p, double *h) { (void)q; h[0] = p[1] * qd[0]; }
static void ball_fd(const double *q, const double *qd, const double *u, const double *p, double *qdd)
{
    (void)q; (void)qd;
    qdd[0] = -p[0] + u[0] / p[1];
}
static void ball_power(const double *q, const double *qd, const double *u, const double *p, double *P)
{
    (void)q; (void)p;
    P[0] = u[0] * qd[0];
    P[1] = 0.0;
}
static void ball_points(const double *q, const double *p, double *r)
{
    (void)p;
    r[0] = 0.0; r[1] = q[0]; r[2] = 0.0;
}
static void ball_velocities(const double *q, const double *qd, const double *p, double *v)
{
    (void)q; (void)p;
    v[0] = 0.0; v[1] = qd[0]; v[2] = 0.0;
}
static void ball_force(const double *q, const double *f, const double *p, double *Q) { (void)q; (void)p; Q[0] = f[0]; }
static void ball_gaps(const double *q, const double *p, double *gap) { (void)p; gap[0] = q[0]; }
static void ball_jbias(const double *q, const double *qd, const double *p, double *a)
{
    (void)q; (void)qd; (void)p;
    a[0] = 0.0;
}
static void ball_energy(const double *q, const double *qd, const double *p, double *E)
{
    E[0] = 0.5 * p[1] * qd[0] * qd[0];
    E[1] = p[1] * p[0] * q[0];
}
static void ball_rhs(double t, const double *x, const double *u, const double *p, double *xdot)
{
    (void)t;
    xdot[0] = x[1];
    ball_fd(x, x + 1, u, p, xdot + 1);
}

static const gac_contact ball_contacts[1] = {{1, 1, +1, 0, 2, 0.0, GAC_CONTACT_WALL, -1, 0, -1, 0.0, {-1, -1}, GAC_END_LINK}};   /* O_1 on the floor, e = p[2] */
static const double ball_p[3] = {9.81, 2.0, 0.8};
static const double ball_q0[1] = {1.0}, ball_qd0[1] = {0.0};

static const gac_model ball = {
    .name = "ball", .n = 0, .nq = 1, .nx = 2, .nparam = 3, .nu = 1, .npoint = 1, .ncontact = 1, .njrow = 1,
    .contacts = ball_contacts,
    .chart = {.a = {0.0, 1.0}, .b = {1.0, 0.0}, .theta0_index = -1, .theta0_value = 0.0},   /* measure 1 */
    .default_parameters = ball_p, .q0 = ball_q0, .qd0 = ball_qd0,
    .forward_dynamics = ball_fd, .inertia_solve = ball_solve, .generalized_momentum = ball_momentum,
    .contact_points = ball_points, .contact_velocities = ball_velocities, .contact_generalized_force = ball_force,
    .contact_gaps = ball_gaps,
    .contact_bias = ball_jbias, .energy = ball_energy, .rhs = ball_rhs, .power = ball_power
};

/* ---- checked_ball: the ball with its parameters' ranges and a check ------------------------------- */
static const gac_parameter_info ball_info[3] = {
    {"g", -1e6, 1e6, "must be within [-1e6, 1e6] m/s^2"},
    {"m", 1e-12, 1e12, "must be in [1e-12, 1e+12] kg"},
    {"e", 0.0, 1.0, "restitution must be in [0, 1]"},
};
static int ball_check(const double *p, int *bad_index)
{
    int i;
    for (i = 0; i < 3; ++i) {
        if (!gac_in_range(p[i], ball_info[i].lo, ball_info[i].hi)) {
            if (bad_index != 0) *bad_index = i;
            return GAC_ERR_BAD_PARAMETER;
        }
    }
    return GAC_OK;
}

/* ---- box: p = [g, m, e], walls x = 0, x = 2, y = 0, y = 2 ---------------------------------------- */
static void box_solve(const double *q, const double *Q, const double *p, double *x)
{
    (void)q;
    x[0] = Q[0] / p[1]; x[1] = Q[1] / p[1];
}
static void box_momentum(const double *q, const double *qd, const double *p, double *h)
{
    (void)q;
    h[0] = p[1] * qd[0]; h[1] = p[1] * qd[1];
}
static void box_fd(const double *q, const double *qd, const double *u, const double *p, double *qdd)
{
    (void)q; (void)qd; (void)u;
    qdd[0] = 0.0; qdd[1] = -p[0];
}
static void box_points(const double *q, const double *p, double *r)
{
    (void)p;
    r[0] = q[0]; r[1] = q[1]; r[2] = 0.0;
}
static void box_velocities(const double *q, const double *qd, const double *p, double *v)
{
    (void)q; (void)p;
    v[0] = qd[0]; v[1] = qd[1]; v[2] = 0.0;
}
static void box_force(const double *q, const double *f, const double *p, double *Q)
{
    (void)q; (void)p;
    Q[0] = f[0]; Q[1] = f[1];
}
static void box_gaps(const double *q, const double *p, double *gap)
{
    (void)p;
    gap[0] = q[0]; gap[1] = 2.0 - q[0]; gap[2] = q[1]; gap[3] = 2.0 - q[1];
}
static void box_jbias(const double *q, const double *qd, const double *p, double *a)
{
    (void)q; (void)qd; (void)p;
    a[0] = 0.0; a[1] = 0.0;
}
static void box_energy(const double *q, const double *qd, const double *p, double *E)
{
    E[0] = 0.5 * p[1] * (qd[0] * qd[0] + qd[1] * qd[1]);
    E[1] = p[1] * p[0] * q[1];
}
static void box_rhs(double t, const double *x, const double *u, const double *p, double *xdot)
{
    (void)t;
    xdot[0] = x[2]; xdot[1] = x[3];
    box_fd(x, x + 2, u, p, xdot + 2);
}

static const gac_contact box_contacts[4] = {
    {1, 0, +1, 0, 2, 0.0, GAC_CONTACT_WALL, -1, 0, -1, 0.0, {-1, -1}, GAC_END_LINK}, {1, 0, -1, 0, 2, 0.0, GAC_CONTACT_WALL, -1, 0, -1, 0.0, {-1, -1}, GAC_END_LINK},
    {1, 1, +1, 1, 2, 0.0, GAC_CONTACT_WALL, -1, 0, -1, 0.0, {-1, -1}, GAC_END_LINK}, {1, 1, -1, 1, 2, 0.0, GAC_CONTACT_WALL, -1, 0, -1, 0.0, {-1, -1}, GAC_END_LINK}
};
static const double box_p[3] = {9.81, 0.5, 1.0};
static const double box_q0[2] = {1.0, 1.0}, box_qd0[2] = {1.3, 2.0};

static const gac_model box = {
    .name = "box", .n = 0, .nq = 2, .nx = 4, .nparam = 3, .npoint = 1, .ncontact = 4, .njrow = 2,
    .contacts = box_contacts,
    .chart = {.a = {0.0, 1.0}, .b = {1.0, 0.0}, .theta0_index = -1, .theta0_value = 0.0},
    .default_parameters = box_p, .q0 = box_q0, .qd0 = box_qd0,
    .forward_dynamics = box_fd, .inertia_solve = box_solve, .generalized_momentum = box_momentum,
    .contact_points = box_points, .contact_velocities = box_velocities, .contact_generalized_force = box_force,
    .contact_gaps = box_gaps,
    .contact_bias = box_jbias, .energy = box_energy, .rhs = box_rhs
};

/* box_fused: the box with a fused forward_dynamics_energy kernel (counting its calls); the loop takes the energy at
 * each step's end from it and must end where the box does, bit for bit. */
static long fused_calls;
static void box_fde(const double *q, const double *qd, const double *u, const double *p, double *y)
{
    ++fused_calls;
    box_fd(q, qd, u, p, y);
    box_energy(q, qd, p, y + 2);
}

static gac_model box_with_fused(void)
{
    gac_model m = box;
    m.forward_dynamics_energy = box_fde;
    return m;
}

/* ---- sled: the box's point on a rough floor, p = [g, m, e, c_f]; friction along x (row 0) ----------------- */
static void sled_gaps(const double *q, const double *p, double *gap)
{
    (void)p;
    gap[0] = q[1];
}
static const gac_contact sled_contacts[1] = {{1, 1, +1, 1, 2, 0.0, GAC_CONTACT_WALL, -1, 1, 3, 0.0, {0, -1}, GAC_END_LINK}};
static const double sled_p[4] = {9.81, 0.5, 0.0, 0.5};
static const double sled_q0[2] = {0.0, 0.0}, sled_qd0[2] = {3.0, 0.0};

static const gac_model sled = {
    .name = "sled", .n = 0, .nq = 2, .nx = 4, .nparam = 4, .npoint = 1, .ncontact = 1, .njrow = 2,
    .contacts = sled_contacts,
    .chart = {.a = {0.0, 1.0}, .b = {1.0, 0.0}, .theta0_index = -1, .theta0_value = 0.0},
    .default_parameters = sled_p, .q0 = sled_q0, .qd0 = sled_qd0,
    .forward_dynamics = box_fd, .inertia_solve = box_solve, .generalized_momentum = box_momentum,
    .contact_points = box_points, .contact_velocities = box_velocities, .contact_generalized_force = box_force,
    .contact_gaps = sled_gaps,
    .contact_bias = box_jbias, .energy = box_energy, .rhs = box_rhs, .friction_velocity = 1e-4
};

/* ---- lever: a point on a rough floor with I_f = [[2, 1], [1, 1]], W = I_f^-1 = [[1, -1], [-1, 2]], V = G y;
 *      p = [G, unused, e, c_f]; friction along x (row 0) ---------------------------------------------------- */
static void lever_solve(const double *q, const double *Q, const double *p, double *x)
{
    (void)q; (void)p;
    x[0] = Q[0] - Q[1]; x[1] = -Q[0] + 2.0 * Q[1];
}
static void lever_momentum(const double *q, const double *qd, const double *p, double *h)
{
    (void)q; (void)p;
    h[0] = 2.0 * qd[0] + qd[1]; h[1] = qd[0] + qd[1];
}
static void lever_fd(const double *q, const double *qd, const double *u, const double *p, double *qdd)
{
    const double Q[2] = {0.0, -p[0]};
    (void)qd; (void)u;
    lever_solve(q, Q, p, qdd);
}
static void lever_energy(const double *q, const double *qd, const double *p, double *E)
{
    E[0] = 0.5 * (2.0 * qd[0] * qd[0] + 2.0 * qd[0] * qd[1] + qd[1] * qd[1]);
    E[1] = p[0] * q[1];
}
static void lever_rhs(double t, const double *x, const double *u, const double *p, double *xdot)
{
    (void)t;
    xdot[0] = x[2]; xdot[1] = x[3];
    lever_fd(x, x + 2, u, p, xdot + 2);
}
static const double lever_p[4] = {9.81, 0.0, 0.0, 3.0};
static const double lever_q0[2] = {0.0, 0.0}, lever_qd0[2] = {-1.0, 0.0};

static const gac_model lever = {
    .name = "lever", .n = 0, .nq = 2, .nx = 4, .nparam = 4, .npoint = 1, .ncontact = 1, .njrow = 2,
    .contacts = sled_contacts,
    .chart = {.a = {0.0, 1.0}, .b = {1.0, 0.0}, .theta0_index = -1, .theta0_value = 0.0},
    .default_parameters = lever_p, .q0 = lever_q0, .qd0 = lever_qd0,
    .forward_dynamics = lever_fd, .inertia_solve = lever_solve, .generalized_momentum = lever_momentum,
    .contact_points = box_points, .contact_velocities = box_velocities, .contact_generalized_force = box_force,
    .contact_gaps = sled_gaps,
    .contact_bias = box_jbias, .energy = lever_energy, .rhs = lever_rhs, .friction_velocity = 1e-4
};

/* ---- caller-owned memory, large enough for both models ------------------------------------------ */
#define NDOUBLE 2048
#define NINT 256
static double dwork[NDOUBLE], rdwork[64], work[256];
static const double zero_input[1] = {0.0};
static int iwork[NINT], riwork[64];

static void test_sizes(void)
{
    CHECK(gac_model_check(&ball) == GAC_OK && gac_model_check(&box) == GAC_OK, "models consistent");
    CHECK(gac_impact_nwork(&box) == 2 * 4 + 2 + 3 * 1 + 2, "impact work %ld", gac_impact_nwork(&box));
    CHECK(gac_sim_ndouble(&box) == 28 * 4 + 3 + 9 * 4 + gac_impact_nwork(&box) + 4, "sim doubles %ld",
          gac_sim_ndouble(&box));
    CHECK(gac_sim_nint(&box) == 2 + 7 * 4 && gac_record_ndouble(&box) == 12 && gac_record_nint(&box) == 10, "ints");
    CHECK(gac_sim_ndouble(&box) <= NDOUBLE && gac_sim_nint(&box) <= NINT, "test arrays large enough");
    CHECK(NEAR(gac_chart_measure(&box, box_q0), 1.0, 0.0), "chart measure 1");
}

/* The dense matrices formed from the operators: I_f = m I, R = -m g + u, J = I. */
static void test_dense(void)
{
    const double q[2] = {0.5, 1.5}, qd[2] = {0.3, -0.2}, u[1] = {0.7};
    double M[4], R[1], J[4];
    gac_mass_matrix(&box, q, box_p, M);
    CHECK(M[0] == box_p[1] && M[1] == 0.0 && M[2] == 0.0 && M[3] == box_p[1], "mass matrix m I");
    gac_bias(&ball, q, qd, u, ball_p, R);
    CHECK(NEAR(R[0], -ball_p[1] * ball_p[0] + u[0], 1e-14), "bias -m g + u: %.17g", R[0]);
    gac_contact_jacobian(&box, q, box_p, J);
    CHECK(J[0] == 1.0 && J[1] == 0.0 && J[2] == 0.0 && J[3] == 1.0, "contact Jacobian I");
}

/* The impact law at one state, without the loop: Eq. 47 for one contact is qd+ = -e qd-, F = m (1 + e) |qd-|. */
static void test_impact_kernels(void)
{
    const double q[1] = {0.0}, down[1] = {-3.0}, up[1] = {1.0}, rest[1] = {0.0};
    const int contact_set[1] = {0}, bad[2] = {0, 0};
    double qd_plus[1], F[2], qdd[1], lambda[1];
    int code = gac_impact(&ball, q, down, ball_p, 1, contact_set, qd_plus, F, work);
    CHECK(code == GAC_OK && NEAR(qd_plus[0], 2.4, 1e-15) && NEAR(F[0], 2.0 * 1.8 * 3.0, 1e-14),
          "impact: code %d, qd+ %.17g, F %.17g", code, qd_plus[0], F[0]);
    code = gac_impact_complementarity(&ball, q, up, ball_p, 1, contact_set, qd_plus, F, work);
    CHECK(code == GAC_OK && qd_plus[0] == 1.0 && F[0] == 0.0, "separating: no impulse (F %g)", F[0]);
    code = gac_impact_complementarity(&ball, q, down, ball_p, 1, contact_set, qd_plus, F, work);
    CHECK(code == GAC_OK && NEAR(qd_plus[0], 2.4, 1e-15), "complementarity = Eq. 47 here (%.17g)", qd_plus[0]);
    CHECK(gac_impact(&ball, q, down, ball_p, 2, bad, qd_plus, F, work) == GAC_ERR_BAD_CONTACT, "repeated contact");
    CHECK(gac_impact(&ball, q, down, ball_p, 0, contact_set, qd_plus, F, work) == GAC_ERR_BAD_CONTACT, "no contact");
    code = gac_constrained_dynamics(&ball, q, rest, zero_input, ball_p, 1, contact_set, qdd, lambda, work);
    CHECK(code == GAC_OK && NEAR(qdd[0], 0.0, 1e-15) && NEAR(lambda[0], 2.0 * 9.81, 1e-13),
          "resting: qdd %g, lambda %.17g (m g)", qdd[0], lambda[0]);
}

/* The bouncing ball against its closed form, for each integrator. */
static void test_ball(int method)
{
    const double g = ball_p[0], m = ball_p[1], e = ball_p[2], h = 1.0;
    const double t1 = sqrt(2.0 * h / g) + (broken && method == GAC_METHOD_DOPRI5 ? 1e-9 : 0.0);
    double t_eval[3] = {0.1, 0.2, 0.3}, x_eval[6], t_expect = t1, u = g * sqrt(2.0 * h / g);
    gac_options opt;
    gac_sim sim;
    gac_impact_record rec;
    int code, k = 0, i_eval = 0, rested = 0, i;
    gac_default_options(&opt);
    opt.method = method;
    if (method == GAC_METHOD_RK4) opt.dt = 1e-3;
    code = gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, &opt);
    CHECK(code == GAC_OK, "init %d", code);
    gac_record_bind(&rec, &ball, rdwork, riwork);
    while ((code = gac_sim_advance(&sim, 10.0, t_eval, 3, &i_eval, x_eval, &rec)) == GAC_SIM_IMPACT
           || code == GAC_SIM_CONTACT) {
        if (rec.nlanded > 0) rested = 1;
        if (code != GAC_SIM_IMPACT) continue;
        ++k;
        if (k <= 8) {                                     /* well above the resting threshold */
            CHECK(NEAR(rec.t, t_expect, 1e-10), "method %d impact %d at %.17g, expected %.17g", method, k, rec.t,
                  t_expect);
            CHECK(NEAR(rec.qd_before[0], -u, 1e-10 * u) && NEAR(rec.qd_after[0], e * u, 1e-10 * u),
                  "impact %d: v- %.17g v+ %.17g, expected -+%.17g", k, rec.qd_before[0], rec.qd_after[0], u);
            CHECK(rec.ncontact == 1 && rec.contact[0] == 0 && NEAR(rec.impulse[0], m * (1.0 + e) * u, 1e-10 * u),
                  "impact %d: impulse %.17g", k, rec.impulse[0]);
            CHECK(NEAR(rec.energy_before - rec.energy_after, 0.5 * m * u * u * (1.0 - e * e), 1e-9),
                  "impact %d: energy lost %.17g", k, rec.energy_before - rec.energy_after);
            CHECK(rec.rounds == 1 && !rec.plastic && !rec.complementarity, "plain Eq. 47");
        }
        t_expect += 2.0 * e * u / g;
        u *= e;
    }
    CHECK(code == GAC_SIM_END && sim.t == 10.0, "method %d ends at t_end: code %d (%s)", method, code,
          gac_error_message(code));
    CHECK(k >= 10 && rested && sim.nresting == 1 && sim.resting[0] == 0, "accumulation ends resting (%d impacts)", k);
    CHECK(fabs(sim.x[0]) <= 1e-5 && fabs(sim.x[1]) < 1e-12, "at rest on the floor: y %g, v %g", sim.x[0],
          sim.x[1]);
    CHECK(i_eval == 3, "samples %d", i_eval);
    for (i = 0; i < 3; ++i) {                              /* before the first impact: y = h - g t^2 / 2 */
        CHECK(NEAR(x_eval[2 * i], h - 0.5 * g * t_eval[i] * t_eval[i], 1e-12)
              && NEAR(x_eval[2 * i + 1], -g * t_eval[i], 1e-12), "sample %d: %.17g %.17g", i, x_eval[2 * i],
              x_eval[2 * i + 1]);
    }
}

/* A PD controller on the ball's height: u = m g - k (y - y_ref) - c v (gains per unit mass in *user). */
typedef struct { double k, c, y_ref; } pd_gains;
static void ball_pd(double t, const double *q, const double *qd, double *u, void *user)
{
    const pd_gains *pd = (const pd_gains *)user;
    const double m = ball_p[1];
    (void)t;
    u[0] = m * ball_p[0] - m * pd->k * (q[0] - pd->y_ref) - m * pd->c * qd[0];
}

/* ball_pd's Jacobian (1 x 1 each) */
static void ball_pd_jacobian(double t, const double *q, const double *qd, double *du_dq, double *du_dqd, void *user)
{
    const pd_gains *pd = (const pd_gains *)user;
    (void)t, (void)q, (void)qd;
    du_dq[0] = -ball_p[1] * pd->k;
    du_dqd[0] = -ball_p[1] * pd->c;
}

static void nan_controller(double t, const double *q, const double *qd, double *u, void *user)
{
    (void)t; (void)q; (void)qd; (void)user;
    u[0] = NAN;
}

/* Inputs: held between advance calls, from a controller, from a schedule; the inputs' work. */
static void test_inputs(void)
{
    const double g = ball_p[0], m = ball_p[1];
    gac_options opt;
    gac_sim sim;
    gac_impact_record rec;
    double u, E0, E[2], v_ref;
    int code;
    gac_default_options(&opt);
    opt.rtol = 1e-12;
    opt.atol = 1e-12;
    gac_record_bind(&rec, &ball, rdwork, riwork);

    /* held: u = m (g + 2) lifts it as 1 + t^2 until t = 1, then u = m g keeps v = 2 */
    code = gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, &opt);
    u = m * (g + 2.0);
    code = code == GAC_OK ? gac_sim_set_input(&sim, &u) : code;
    CHECK(code == GAC_OK, "init and set_input %d", code);
    code = gac_sim_advance(&sim, 1.0, 0, 0, 0, 0, &rec);
    CHECK(code == GAC_SIM_END && NEAR(sim.x[0], 2.0, 1e-12) && NEAR(sim.x[1], 2.0, 1e-12),
          "held input: y %.17g v %.17g, expected 2, 2", sim.x[0], sim.x[1]);
    CHECK(NEAR(sim.work_input, u * 1.0, 1e-11), "work %.17g, expected %.17g", sim.work_input, u);
    u = m * g;
    gac_sim_set_input(&sim, &u);
    code = gac_sim_advance(&sim, 2.0, 0, 0, 0, 0, &rec);
    v_ref = m * (g + 2.0) + 2.0 * m * g + (broken ? 1e-6 : 0.0);
    CHECK(code == GAC_SIM_END && NEAR(sim.x[0], 4.0, 1e-12) && NEAR(sim.x[1], 2.0, 1e-12),
          "hover: y %.17g v %.17g, expected 4, 2", sim.x[0], sim.x[1]);
    CHECK(NEAR(sim.work_input, v_ref, 1e-10), "work %.17g, expected %.17g", sim.work_input, v_ref);

    /* PD controller: a damped oscillator about y_ref = 1.5, omega_0 = 2, zeta = 0.2 */
    {
        pd_gains pd = {4.0, 0.8, 1.5};
        const double w0 = 2.0, zeta = 0.2, wd = w0 * sqrt(1.0 - zeta * zeta), e0 = -0.5, T = 3.0;
        const double e = e0 * exp(-zeta * w0 * T) * (cos(wd * T) + zeta * w0 / wd * sin(wd * T));
        code = gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, &opt);
        code = code == GAC_OK ? gac_sim_set_controller(&sim, ball_pd, &pd) : code;
        ball_energy(sim.x, sim.x + 1, ball_p, E);
        E0 = E[0] + E[1];
        code = code == GAC_OK ? gac_sim_advance(&sim, T, 0, 0, 0, 0, &rec) : code;
        CHECK(code == GAC_SIM_END && NEAR(sim.x[0], 1.5 + e, 1e-9), "PD: y %.17g, expected %.17g (code %d)",
              sim.x[0], 1.5 + e, code);
        ball_energy(sim.x, sim.x + 1, ball_p, E);
        CHECK(NEAR(E[0] + E[1] - E0, sim.work_input, 1e-9 * fabs(E0)), "PD: energy change %.17g, work %.17g",
              E[0] + E[1] - E0, sim.work_input);
    }

    /* linear schedule: a = 6 t on [0, 1] (y = 1 + t^3), then held at a = 6 */
    {
        const double times[2] = {0.0, 1.0}, values[2] = {m * g, m * (g + 6.0)};
        gac_schedule schedule = {2, 1, times, values, 1};
        CHECK(gac_schedule_check(&schedule) == GAC_OK, "schedule ok");
        code = gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, &opt);
        code = code == GAC_OK ? gac_sim_set_controller(&sim, gac_schedule_input, &schedule) : code;
        code = code == GAC_OK ? gac_sim_advance(&sim, 1.0, 0, 0, 0, 0, &rec) : code;
        CHECK(code == GAC_SIM_END && NEAR(sim.x[0], 2.0, 1e-12) && NEAR(sim.x[1], 3.0, 1e-12),
              "schedule at 1: y %.17g v %.17g, expected 2, 3", sim.x[0], sim.x[1]);
        code = gac_sim_advance(&sim, 1.5, 0, 0, 0, 0, &rec);
        CHECK(code == GAC_SIM_END && NEAR(sim.x[0], 4.25, 1e-12) && NEAR(sim.x[1], 6.0, 1e-12),
              "schedule at 1.5: y %.17g v %.17g, expected 4.25, 6", sim.x[0], sim.x[1]);
    }

    /* errors */
    {
        const double bad_times[2] = {1.0, 0.5}, values[2] = {0.0, 0.0};
        gac_schedule bad = {2, 1, bad_times, values, 0};
        double nan_u = NAN;
        CHECK(gac_schedule_check(&bad) == GAC_ERR_BAD_OPTION, "decreasing schedule times refused");
        code = gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, &opt);
        CHECK(gac_sim_set_input(&sim, &nan_u) == GAC_ERR_BAD_INPUT, "NaN input refused");
        CHECK(gac_sim_set_input(&sim, 0) == GAC_ERR_NULL_ARGUMENT, "NULL input refused");
        gac_sim_set_controller(&sim, nan_controller, 0);
        code = gac_sim_advance(&sim, 1.0, 0, 0, 0, 0, &rec);
        CHECK(code == GAC_ERR_BAD_INPUT, "NaN from the controller stops the loop: %d", code);
    }
}

/* The point in the box with e = 1: side-wall impacts at closed-form times, energy kept. */
static void test_box(void)
{
    const double g = box_p[0], vx = box_qd0[0], vy = box_qd0[1];
    const double t_floor = (vy + sqrt(vy * vy + 2.0 * g * box_q0[1])) / g;     /* first floor impact */
    const double v_floor = sqrt(vy * vy + 2.0 * g * box_q0[1]), period = 2.0 * v_floor / g;
    double E0[2], E1[2], t_side = (2.0 - box_q0[0]) / vx, t_down = t_floor;
    gac_sim sim;
    gac_impact_record rec;
    int code, sides = 0, floors = 0;
    code = gac_sim_init(&sim, &box, dwork, iwork, 0.0, box_q0, box_qd0, 0, 0);    /* default options */
    CHECK(code == GAC_OK, "init %d", code);
    gac_record_bind(&rec, &box, rdwork, riwork);
    box_energy(sim.x, sim.x + 2, sim.p, E0);
    while ((code = gac_sim_advance(&sim, 5.0, 0, 0, 0, 0, &rec)) == GAC_SIM_IMPACT) {
        int c = rec.contact[0];
        CHECK(rec.ncontact == 1 && NEAR(rec.energy_after, rec.energy_before, 1e-12 * fabs(rec.energy_before)),
              "elastic impact at %.17g: %.17g -> %.17g", rec.t, rec.energy_before, rec.energy_after);
        if (c <= 1) {                                        /* side walls: x = 1 + vx t, reflected */
            CHECK(c == (sides % 2 == 0 ? 1 : 0) && NEAR(rec.t, t_side, 1e-10), "side impact %d (contact %d) at "
                  "%.17g, expected %.17g", sides, c, rec.t, t_side);
            CHECK(NEAR(rec.qd_after[0], -rec.qd_before[0], 1e-12), "reflected");
            t_side += 2.0 / vx;
            ++sides;
        } else {
            CHECK(c == 2 && NEAR(rec.t, t_down, 1e-10), "floor impact %d at %.17g, expected %.17g", floors, rec.t,
                  t_down);
            t_down += period;
            ++floors;
        }
    }
    CHECK(code == GAC_SIM_END && sides == 3 && floors == 5, "end: code %d, %d side and %d floor impacts", code, sides,
          floors);
    box_energy(sim.x, sim.x + 2, sim.p, E1);
    CHECK(NEAR(E1[0] + E1[1], E0[0] + E0[1], 1e-12 * (E0[0] + E0[1])), "energy %.17g -> %.17g", E0[0] + E0[1],
          E1[0] + E1[1]);
    CHECK(sim.x[0] > 0.0 && sim.x[0] < 2.0 && sim.x[1] > 0.0 && sim.x[1] < 2.0 && sim.nresting == 0, "inside");
}

/* The budget and the progress callback: a fake clock that advances 1 s per reading, a callback that asks to stop
 * at its third call; a run stopped either way goes on from where it stopped, to the same end state bit for bit. */
static double fake_clock(void *user)
{
    double *now = (double *)user;
    *now += 1.0;
    return *now;
}

static int stop_at_third(double t, long n_steps, long n_impacts, void *user)
{
    int *calls = (int *)user;
    (void)t; (void)n_steps; (void)n_impacts;
    return ++*calls == 3;
}

static int run_box_to_end(gac_sim *sim, gac_impact_record *rec)
{
    int code;
    while ((code = gac_sim_advance(sim, 5.0, 0, 0, 0, 0, rec)) == GAC_SIM_IMPACT) {
    }
    return code;
}

/* The fused kernel: gac_forward_dynamics_energy formed (the box has none) and called (box_fused); a run on the
 * fused model ends where the box's does, bit for bit, with the same energy balance, one fused call per step. */
static void test_fused_kernel(void)
{
    const gac_model fused = box_with_fused();
    const double q[2] = {0.3, 1.7}, qd[2] = {-0.4, 2.5};
    double y[4], z[4], E[2];
    static double dwork_b[NDOUBLE];
    static int iwork_b[NINT];
    gac_sim a, b;
    gac_impact_record rec;
    int code_a, code_b, i, same = 1;
    gac_forward_dynamics_energy(&box, q, qd, 0, box_p, y);
    box_fd(q, qd, 0, box_p, z);
    box_energy(q, qd, box_p, E);
    CHECK(y[0] == z[0] && y[1] == z[1] && y[2] == E[0] && y[3] == E[1], "formed: forward_dynamics, then energy");
    fused_calls = 0;
    gac_forward_dynamics_energy(&fused, q, qd, 0, box_p, y);
    CHECK(fused_calls == 1 && y[2] == E[0] && y[3] == E[1], "the model's own kernel called");
    CHECK(gac_model_check(&fused) == GAC_OK, "a model with a fused kernel is consistent");
    gac_record_bind(&rec, &box, rdwork, riwork);
    code_a = gac_sim_init(&a, &box, dwork, iwork, 0.0, box_q0, box_qd0, 0, 0);
    code_a = code_a == GAC_OK ? run_box_to_end(&a, &rec) : code_a;
    fused_calls = 0;
    code_b = gac_sim_init(&b, &fused, dwork_b, iwork_b, 0.0, box_q0, box_qd0, 0, 0);
    code_b = code_b == GAC_OK ? run_box_to_end(&b, &rec) : code_b;
    for (i = 0; i < 4; ++i) same &= a.x[i] == b.x[i];
    CHECK(code_a == GAC_SIM_END && code_b == GAC_SIM_END && same && a.t == b.t, "same end: %d %d", code_a, code_b);
    CHECK(a.n_rhs == b.n_rhs && a.n_steps == b.n_steps && a.energy_residual == b.energy_residual,
          "same counts and balance: rhs %ld %ld, residual %.17g %.17g", a.n_rhs, b.n_rhs, a.energy_residual,
          b.energy_residual);
    CHECK(fused_calls == b.n_steps + b.n_rejected, "one fused call per step tried: %ld, steps %ld + %ld rejected",
          fused_calls, b.n_steps, b.n_rejected);
}


static void test_budget_and_progress(void)
{
    static double dwork2[NDOUBLE];
    static int iwork2[NINT];
    double now = 0.0, x_ref[4];
    gac_options opt;
    gac_sim sim, ref;
    gac_impact_record rec;
    int code, calls = 0, i, same = 1;
    long steps_ref;
    gac_record_bind(&rec, &box, rdwork, riwork);
    gac_default_options(&opt);
    CHECK(opt.max_wall_time == 0.0, "no budget by default");
    opt.h_max = 1e-3;                              /* 5,000 steps: about 80 looks */
    CHECK(gac_sim_init(&ref, &box, dwork2, iwork2, 0.0, box_q0, box_qd0, 0, &opt) == GAC_OK, "reference init");
    CHECK(run_box_to_end(&ref, &rec) == GAC_SIM_END, "reference run");
    for (i = 0; i < 4; ++i) x_ref[i] = ref.x[i];
    steps_ref = ref.n_steps;
    opt.max_wall_time = 10.5;
    CHECK(gac_sim_init(&sim, &box, dwork, iwork, 0.0, box_q0, box_qd0, 0, &opt) == GAC_OK, "init with a budget");
    CHECK(gac_sim_set_clock(&sim, fake_clock, &now) == GAC_OK && now == 1.0, "clock read once when set");
    code = run_box_to_end(&sim, &rec);
    CHECK(code == GAC_ERR_WALL_TIME && sim.wall_time == 11.0 && now == 12.0 && sim.t < 5.0,
          "the budget stops the run at the 11th reading: code %d, wall_time %g, t %g", code, sim.wall_time, sim.t);
    CHECK(sim.n_steps + sim.n_rejected <= 11L * GAC_LOOK_STEPS, "looked at every %d steps (%ld steps)", GAC_LOOK_STEPS,
          sim.n_steps + sim.n_rejected);
    CHECK(gac_sim_set_clock(&sim, fake_clock, &now) == GAC_OK && sim.wall_time == 0.0, "the budget starts again");
    sim.opt.max_wall_time = 0.0;
    code = run_box_to_end(&sim, &rec);
    for (i = 0; i < 4; ++i) same = same && sim.x[i] == x_ref[i];
    CHECK(code == GAC_SIM_END && same && sim.n_steps == steps_ref, "resumed after the budget: same end state");

    opt.max_wall_time = 0.0;
    CHECK(gac_sim_init(&sim, &box, dwork, iwork, 0.0, box_q0, box_qd0, 0, &opt) == GAC_OK, "init");
    CHECK(gac_sim_set_progress(&sim, stop_at_third, &calls) == GAC_OK, "progress set");
    code = run_box_to_end(&sim, &rec);
    CHECK(code == GAC_ERR_STOPPED && calls == 3 && sim.t > 0.0 && sim.t < 5.0, "stopped by the callback: code %d",
          code);
    CHECK(gac_sim_set_progress(&sim, 0, 0) == GAC_OK, "progress cleared");
    code = run_box_to_end(&sim, &rec);
    for (same = 1, i = 0; i < 4; ++i) same = same && sim.x[i] == x_ref[i];
    CHECK(code == GAC_SIM_END && same, "resumed after the callback's stop: same end state");
    CHECK(gac_sim_set_clock(0, 0, 0) == GAC_ERR_NULL_ARGUMENT && gac_sim_set_progress(0, 0, 0) == GAC_ERR_NULL_ARGUMENT,
          "NULL sim refused");
    opt.max_wall_time = -1.0;
    CHECK(gac_sim_init(&sim, &box, dwork, iwork, 0.0, box_q0, box_qd0, 0, &opt) == GAC_ERR_BAD_OPTION,
          "a negative budget refused");
}

/* A point sliding on a rough floor (Coulomb c_f, resting from the start): the normal force m g, the deceleration
 * c_f g, x(t) = v0 t - c_f g t^2 / 2 until it stops at v0^2 / (2 c_f g), and the friction loss m v0^2 / 2.  With
 * stick = 0 the regularised friction holds it after the stop (slow, stiff steps); with stick = 1 it sticks once. */
static void test_sled_run(int stick)
{
    const double g = sled_p[0], m = sled_p[1], c_f = sled_p[3], v0 = sled_qd0[0], t_stop = v0 / (c_f * g);
    const double t_eval[2] = {0.3, 1.0};
    double x_eval[8], qdd[2], lambda[2], swork[128];
    const int contact_set[1] = {0};
    gac_options opt;
    gac_sim sim;
    gac_impact_record rec;
    int code, i_eval = 0, n_stuck = 0;
    double t_stuck = -1.0;
    CHECK(gac_model_check(&sled) == GAC_OK && gac_impact_nwork(&sled) == 24 * 4 + 2 + 3 + 2, "sled model, work %ld",
          gac_impact_nwork(&sled));
    code = gac_constrained_dynamics(&sled, sled_q0, sled_qd0, 0, sled_p, 1, contact_set, qdd, lambda, swork);
    CHECK(code == GAC_OK && NEAR(lambda[0], m * g, 1e-12) && NEAR(qdd[0], -c_f * g, 1e-12) && NEAR(qdd[1], 0.0, 1e-12),
          "sliding: lambda %.17g, qdd %.17g %.17g", lambda[0], qdd[0], qdd[1]);
    gac_default_options(&opt);
    opt.rtol = 1e-10;
    opt.atol = 1e-12;
    opt.stick = stick;
    code = gac_sim_init(&sim, &sled, dwork, iwork, 0.0, sled_q0, sled_qd0, 0, &opt);
    CHECK(code == GAC_OK, "init %d", code);
    gac_record_bind(&rec, &sled, rdwork, riwork);
    while ((code = gac_sim_advance(&sim, 1.0, t_eval, 2, &i_eval, x_eval, &rec)) == GAC_SIM_CONTACT) {
        CHECK(rec.nslipped == 0 && (rec.nstuck == 0 || (rec.nstuck == 1 && rec.stuck[0] == 0)), "stuck %d, slipped %d",
              rec.nstuck, rec.nslipped);
        if (rec.nstuck > 0) t_stuck = rec.t;
        n_stuck += rec.nstuck;
    }
    CHECK(code == GAC_SIM_END && sim.nresting == 1 && i_eval == 2, "end %d, resting %d", code, sim.nresting);
    CHECK(n_stuck == sim.n_sticks, "stick events %d, n_sticks %ld", n_stuck, sim.n_sticks);
    CHECK(NEAR(x_eval[0], v0 * 0.3 - 0.5 * c_f * g * 0.09, 1e-8), "x(0.3) %.17g", x_eval[0]);
    CHECK(t_stop < 1.0 && NEAR(x_eval[4], v0 * v0 / (2.0 * c_f * g), 1e-8), "x(1) %.17g, expected %.17g", x_eval[4],
          v0 * v0 / (2.0 * c_f * g));
    CHECK(NEAR(sim.loss_friction, 0.5 * m * v0 * v0, 1e-9), "friction loss %.17g", sim.loss_friction);
    if (!stick) {
        /* the steps in the regularised regime: those begun after the stop or within GAC_SLOW_SLIDING v_s of it */
        CHECK(sim.n_slow_sliding > 0 && sim.t_slow_sliding > 0.5 * (1.0 - t_stop)
              && sim.t_slow_sliding <= 1.0 - t_stop + GAC_SLOW_SLIDING * sled.friction_velocity / (c_f * g) + 1e-12,
              "slow sliding: %ld steps over %.17g s, at rest for %.17g s", sim.n_slow_sliding, sim.t_slow_sliding,
              1.0 - t_stop);
        CHECK(sim.n_sticks == 0 && sim.n_slips == 0, "no sticking: %ld, %ld", sim.n_sticks, sim.n_slips);
    } else {
        /* stuck at the stop: no creep, the steps after it not slowed by the regularisation */
        CHECK(sim.n_sticks == 1 && sim.n_slips == 0 && sim.t_slow_sliding < 1e-3 && x_eval[6] == 0.0,
              "stuck once: sticks %ld, slips %ld, slow for %.3g s, v(1) %.3g", sim.n_sticks, sim.n_slips,
              sim.t_slow_sliding, x_eval[6]);
        CHECK(fabs(sim.energy_residual) < 1e-12, "energy residual %.3g", sim.energy_residual);
        CHECK(fabs(t_stuck - t_stop) < 1e-3, "stuck at %.17g, stops at %.17g", t_stuck, t_stop);
    }
    CHECK(fabs(x_eval[5]) < 1e-12 && fabs(x_eval[7]) < 1e-12, "on the floor");
}

static void test_sled(void)
{
    test_sled_run(0);
    test_sled_run(1);
}

/* The Painleve paradox resolved by a tangential impact (the lever): sliding at v = -1 along x on the floor, the
 * compliance with sliding W_yy - c_f sgn(v) W_xy = 2 - 3 = -1 < 0 (the constrained dynamics refuses it); the run
 * starts, and the first advance after the contact event takes the tangential impact at t = 0: the stick impulse
 * L = -W^-1 gamma- = -I_f (-1, 0) = (2, 1) (tangential, normal), |L_T| = 2 <= c_f L_N = 3, which stops the point
 * (qd+ = qd + W L = 0) and takes its kinetic energy, T- = 1 = -L_T v / 2.  Then stuck (lambda_T = 0), at rest.
 * Sliding the other way (B = 5 > 0) there is no impact. */
static void test_tangential_impact(void)
{
    const int contact_set[1] = {0};
    const double t_eval[1] = {0.5};
    double qdd[2], lambda[2], swork[128], x_eval[4], qd_other[2] = {1.0, 0.0};
    gac_options opt;
    gac_sim sim;
    gac_impact_record rec;
    int code, i_eval = 0;
    CHECK(gac_model_check(&lever) == GAC_OK, "lever model");
    code = gac_constrained_dynamics(&lever, lever_q0, lever_qd0, 0, lever_p, 1, contact_set, qdd, lambda, swork);
    CHECK(code == GAC_ERR_FRICTION, "sliding in the paradox refused by the constrained dynamics: %d", code);
    gac_default_options(&opt);
    opt.rtol = 1e-10;
    opt.atol = 1e-12;
    code = gac_sim_init(&sim, &lever, dwork, iwork, 0.0, lever_q0, lever_qd0, 0, &opt);
    CHECK(code == GAC_OK && sim.nresting == 1, "init %d, resting %d", code, sim.nresting);
    gac_record_bind(&rec, &lever, rdwork, riwork);
    code = gac_sim_advance(&sim, 0.5, t_eval, 1, &i_eval, x_eval, &rec);
    CHECK(code == GAC_SIM_CONTACT && rec.nlanded == 1, "at rest at the start: %d", code);
    code = gac_sim_advance(&sim, 0.5, t_eval, 1, &i_eval, x_eval, &rec);
    CHECK(code == GAC_SIM_IMPACT && rec.law == GAC_IMPACT_LAW_GDI_TANGENTIAL && rec.t == 0.0 && rec.ncontact == 1,
          "the tangential impact: %d, law %d, t %.17g", code, rec.law, rec.t);
    CHECK(NEAR(rec.impulse[0], 1.0, 1e-14) && NEAR(rec.impulse_t[0], 2.0, 1e-14) && rec.impulse_t[1] == 0.0,
          "impulses %.17g, %.17g", rec.impulse[0], rec.impulse_t[0]);
    CHECK(NEAR(rec.qd_after[0], 0.0, 1e-14) && NEAR(rec.qd_after[1], 0.0, 1e-14), "stopped: %.3g %.3g",
          rec.qd_after[0], rec.qd_after[1]);
    CHECK(NEAR(rec.energy_before - rec.energy_after, 1.0, 1e-14) && sim.n_tangential_impacts == 1
          && sim.n_impacts == 1 && sim.n_sticks == 1, "energy taken %.17g, counts %ld %ld %ld",
          rec.energy_before - rec.energy_after, sim.n_tangential_impacts, sim.n_impacts, sim.n_sticks);
    CHECK(rec.nstuck == 1 && rec.stuck[0] == 0 && rec.nslipped == 0, "the impact's record: stuck %d, slipped %d",
          rec.nstuck, rec.nslipped);
    while ((code = gac_sim_advance(&sim, 0.5, t_eval, 1, &i_eval, x_eval, &rec)) == GAC_SIM_CONTACT) {
    }
    CHECK(code == GAC_SIM_END && sim.nresting == 1 && sim.is_stuck[0] && i_eval == 1 && x_eval[0] == 0.0
          && fabs(x_eval[1]) < 1e-12, "stuck at rest after: %d, x %.3g, y %.3g", code, x_eval[0], x_eval[1]);
    code = gac_sim_init(&sim, &lever, dwork, iwork, 0.0, lever_q0, qd_other, 0, &opt);
    i_eval = 0;
    while (code >= 0 && (code = gac_sim_advance(&sim, 0.5, t_eval, 1, &i_eval, x_eval, &rec)) == GAC_SIM_CONTACT) {
    }
    CHECK(code == GAC_SIM_END && sim.n_impacts == 0 && sim.n_tangential_impacts == 0, "sliding towards +x: %d", code);
}

/* Refusals: NULL pointers, bad options, an inconsistent model, a start beyond a wall (sim unchanged). */
static void test_errors(void)
{
    gac_options opt;
    gac_sim sim, before;
    gac_impact_record rec;
    gac_model bad = box;
    gac_contact wrong[4];
    const double below[1] = {-0.01};
    double t = -1.0;
    gac_default_options(&opt);
    CHECK(gac_sim_init(0, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, 0) == GAC_ERR_NULL_ARGUMENT, "sim NULL");
    CHECK(gac_sim_init(&sim, 0, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, 0) == GAC_ERR_NULL_ARGUMENT, "model NULL");
    CHECK(gac_sim_init(&sim, &ball, 0, iwork, 0.0, ball_q0, ball_qd0, 0, 0) == GAC_ERR_NULL_ARGUMENT, "dwork NULL");
    CHECK(gac_sim_init(&sim, &ball, dwork, iwork, 0.0, 0, ball_qd0, 0, 0) == GAC_ERR_NULL_ARGUMENT, "q NULL");
    CHECK(opt.chart_switch == 0.3, "chart_switch default 0.3");
    opt.chart_switch = 0.5;                                 /* back at 1.0: chart B need not be better there */
    CHECK(gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, &opt) == GAC_ERR_BAD_OPTION,
          "chart_switch above GAC_CHART_SWITCH_MAX");
    opt.chart_switch = 0.05;
    CHECK(gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, &opt) == GAC_ERR_BAD_OPTION,
          "chart_switch below GAC_CHART_SWITCH_MIN");
    opt.chart_switch = 0.0;
    CHECK(gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, &opt) == GAC_OK, "chart_switch 0");
    CHECK(sim.chart == 0 && sim.n_chart_switches == 0, "no second chart: chart A");
    bad.chart_b = &ball;                                    /* a second chart of other sizes */
    CHECK(gac_model_check(&bad) == GAC_ERR_BAD_MODEL, "chart_b of other sizes refused");
    bad = box;
    gac_default_options(&opt);
    opt.method = 7;
    CHECK(gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, &opt) == GAC_ERR_BAD_OPTION, "method");
    bad.nx = 3;
    CHECK(gac_sim_init(&sim, &bad, dwork, iwork, 0.0, box_q0, box_qd0, 0, 0) == GAC_ERR_BAD_MODEL, "nx != 2 nq");
    memcpy(wrong, box_contacts, sizeof wrong);
    wrong[3].row = 2;                                       /* njrow is 2 */
    bad = box;
    bad.contacts = wrong;
    CHECK(gac_model_check(&bad) == GAC_ERR_BAD_MODEL, "Jacobian row out of range");
    memcpy(wrong, box_contacts, sizeof wrong);
    wrong[1].end = GAC_END_FINISH;                          /* a joint point alone: a plane's contacts only */
    CHECK(gac_model_check(&bad) == GAC_ERR_BAD_MODEL, "a wall's contact of one end refused");
    wrong[1].end = GAC_END_LINK;
    CHECK(gac_model_check(&bad) == GAC_OK, "the same table with the whole link accepted");
    memset(&sim, 0xab, sizeof sim);
    memcpy(&before, &sim, sizeof sim);
    CHECK(gac_sim_init(&sim, &ball, dwork, iwork, 0.0, below, ball_qd0, 0, 0) == GAC_ERR_START_OUTSIDE,
          "start 1 cm below the floor");
    CHECK(memcmp(&sim, &before, sizeof sim) == 0, "a refused start leaves sim unchanged");
    CHECK(gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, 0) == GAC_OK, "init");
    gac_record_bind(&rec, &ball, rdwork, riwork);
    CHECK(gac_sim_advance(&sim, 1.0, 0, 0, 0, 0, 0) == GAC_ERR_NULL_ARGUMENT, "record NULL");
    CHECK(gac_sim_advance(0, 1.0, 0, 0, 0, 0, &rec) == GAC_ERR_NULL_ARGUMENT, "sim NULL");
    CHECK(gac_sim_advance(&sim, -1.0, 0, 0, 0, 0, &rec) == GAC_ERR_BAD_OPTION, "t_end before t");
    CHECK(gac_sim_advance(&sim, NAN, 0, 0, 0, 0, &rec) == GAC_ERR_BAD_OPTION, "t_end NaN");
    gac_sim_state(&sim, &t, 0, 0);
    CHECK(t == 0.0, "refused calls change nothing (t %g)", t);
    CHECK(strcmp(gac_error_message(GAC_ERR_START_OUTSIDE), gac_error_message(GAC_ERR_BAD_OPTION)) != 0
          && strcmp(gac_error_message(12345), "unknown error code") == 0, "messages");
}

/* Parameters: the range test of one value, the inertia test, and gac_sim_init refusing a vector outside the model's
 * check (sim unchanged) with the index gac_check_parameters gives. */
static void test_parameters(void)
{
    static const double plate[6] = {1.0, 2.0, 3.0, 0.0, 0.0, 0.0};               /* Izz = Ixx + Iyy: a flat plate */
    static const double rod[6] = {0.0, 1.0, 1.0, 0.0, 0.0, 0.0};                 /* no moment about its axis */
    static const double turned[6] = {2.0, 2.0, 3.5, -1.0, 0.0, 0.0};             /* diag(1, 3, 3.5) turned 45 deg */
    static const double turned_bad[6] = {2.0, 2.0, 4.5, -1.0, 0.0, 0.0};         /* diag(1, 3, 4.5): 1 + 3 < 4.5 */
    static const double indefinite[6] = {1.0, 1.0, 1.0, 2.0, 0.0, 0.0};          /* eigenvalues -1, 1, 3 */
    static const double within_tol[6] = {1.0, 2.0, 3.0 + 2e-12, 0.0, 0.0, 0.0};  /* tol = 1e-12 c */
    static const double beyond_tol[6] = {1.0, 2.0, 3.0 + 1e-11, 0.0, 0.0, 0.0};
    static const double huge[6] = {2e100, 2e100, 3e100, 1e99, -1e99, 0.0};       /* moments 1.9, 2.1, 3.0 e100 */
    static const double huge_bad[6] = {1e100, 2e100, 3e100, 1e99, -1e99, 0.0};   /* 0.99, 2.0, 3.005 e100 */
    gac_model checked = ball, bad_table = ball;
    gac_parameter_info wrong[3];
    const double bad_e[3] = {9.81, 2.0, 1.5}, bad_m[3] = {9.81, -2.0, 0.5}, good[3] = {9.81, 2.0, 0.5};
    double nan_p[3] = {9.81, 2.0, 0.5};
    gac_sim sim, before;
    int bad = -1;
    checked.check_parameters = ball_check;
    checked.parameter_info = ball_info;

    CHECK(gac_in_range(0.5, 0.0, 1.0) && gac_in_range(0.0, 0.0, 1.0) && gac_in_range(1.0, 0.0, 1.0), "in range");
    CHECK(!gac_in_range(-0.5, 0.0, 1.0) && !gac_in_range(1.5, 0.0, 1.0), "out of range");
    CHECK(!gac_in_range(NAN, -1e9, 1e9) && !gac_in_range(INFINITY, -1e300, 1e300), "not finite");
    CHECK(!gac_in_range(1e-310, 0.0, 1.0) && gac_in_range(3e-308, 0.0, 1.0), "below the smallest normal double");

    CHECK(gac_inertia_admissible(plate) && gac_inertia_admissible(rod) && gac_inertia_admissible(turned),
          "physical inertias");
    CHECK(!gac_inertia_admissible(turned_bad) && !gac_inertia_admissible(indefinite), "unphysical inertias");
    CHECK(gac_inertia_admissible(within_tol) && !gac_inertia_admissible(beyond_tol), "the tolerance 1e-12 c");
    CHECK(gac_inertia_admissible(huge) && !gac_inertia_admissible(huge_bad), "large entries");

    {   /* an obstacle's geometry as parameters: a box's rotation and a plane's normal */
        const double c = cos(0.3), s = sin(0.3), turn[9] = {c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0};
        const double mirror[9] = {c, s, 0.0, s, -c, 0.0, 0.0, 0.0, 1.0};            /* orthonormal, det -1 */
        const double off[9] = {c, -s, 0.0, s, c, 2e-9, 0.0, 0.0, 1.0}, near[9] = {c, -s, 0.0, s, c, 5e-10, 0.0, 0.0, 1.0};
        const double unit[3] = {0.6, -0.8, 0.0}, scaled[3] = {0.6, -0.8, 2e-4}, close[3] = {0.6, -0.8, 4e-5};
        CHECK(gac_rotation_admissible(turn) && gac_rotation_admissible(near), "a rotation, within 1e-9");
        CHECK(!gac_rotation_admissible(mirror) && !gac_rotation_admissible(off), "a reflection, not orthonormal");
        CHECK(gac_unit_admissible(unit) && gac_unit_admissible(close) && !gac_unit_admissible(scaled),
              "a unit normal within 1e-9");
    }

    CHECK(gac_model_check(&checked) == GAC_OK, "model with a parameter table");
    CHECK(gac_check_parameters(&checked, good, &bad) == GAC_OK && bad == -1, "good parameters");
    CHECK(gac_check_parameters(&checked, bad_e, &bad) == GAC_ERR_BAD_PARAMETER && bad == 2
          && strcmp(checked.parameter_info[bad].name, "e") == 0, "e = 1.5 refused as parameter %d", bad);
    CHECK(gac_check_parameters(&checked, bad_m, 0) == GAC_ERR_BAD_PARAMETER, "m < 0 refused, bad_index NULL");
    CHECK(gac_check_parameters(0, good, &bad) == GAC_ERR_NULL_ARGUMENT, "model NULL");
    memset(&sim, 0xab, sizeof sim);
    memcpy(&before, &sim, sizeof sim);
    CHECK(gac_sim_init(&sim, &checked, dwork, iwork, 0.0, ball_q0, ball_qd0, bad_e, 0) == GAC_ERR_BAD_PARAMETER,
          "sim_init refuses e = 1.5");
    CHECK(memcmp(&sim, &before, sizeof sim) == 0, "a refused start leaves sim unchanged");
    CHECK(gac_sim_init(&sim, &checked, dwork, iwork, 0.0, ball_q0, ball_qd0, good, 0) == GAC_OK, "good start");
    CHECK(gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, bad_e, 0) == GAC_OK,
          "a model without a check takes any finite parameters");
    nan_p[1] = NAN;
    bad = -1;
    CHECK(gac_check_parameters(&ball, nan_p, &bad) == GAC_ERR_BAD_PARAMETER && bad == 1, "NaN refused (%d)", bad);
    CHECK(gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, nan_p, 0) == GAC_ERR_BAD_PARAMETER,
          "sim_init refuses a NaN parameter");
    memcpy(wrong, ball_info, sizeof wrong);
    wrong[1].lo = 2e12;                                                          /* lo > hi */
    bad_table.parameter_info = wrong;
    CHECK(gac_model_check(&bad_table) == GAC_ERR_BAD_MODEL, "a parameter row with lo > hi");
    CHECK(strcmp(gac_error_message(GAC_ERR_BAD_PARAMETER), gac_error_message(GAC_ERR_BAD_OPTION)) != 0
          && strstr(gac_error_message(GAC_ERR_BAD_PARAMETER), "parameter_info") != 0, "message");
}

/* ---- spring: the ball's kernels with a spring in place of gravity and no wall in reach, p = [w^2, m, e] ------
 * qdd = -w^2 y: from y(0) = 1, v(0) = 0 the motion is y = cos(w t), v = -w sin(w t) (w = 2 here).  Its contact's
 * gap is y + 10 >= 9: never touched. */
static void spring_fd(const double *q, const double *qd, const double *u, const double *p, double *qdd)
{
    (void)qd; (void)u;
    qdd[0] = -p[0] * q[0];
}
static void spring_gaps(const double *q, const double *p, double *gap) { (void)p; gap[0] = q[0] + 10.0; }
static void spring_energy(const double *q, const double *qd, const double *p, double *E)
{
    E[0] = 0.5 * p[1] * qd[0] * qd[0];
    E[1] = 0.5 * p[1] * p[0] * q[0] * q[0];
}
static void spring_rhs(double t, const double *x, const double *u, const double *p, double *xdot)
{
    (void)t;
    xdot[0] = x[1];
    spring_fd(x, x + 1, u, p, xdot + 1);
}
static const double spring_p[3] = {4.0, 1.0, 1.0};
static const double spring_q0[1] = {1.0}, spring_qd0[1] = {0.0};
static const gac_model spring = {
    .name = "spring", .n = 0, .nq = 1, .nx = 2, .nparam = 3, .nu = 1, .npoint = 1, .ncontact = 1, .njrow = 1,
    .contacts = ball_contacts,
    .chart = {.a = {0.0, 1.0}, .b = {1.0, 0.0}, .theta0_index = -1, .theta0_value = 0.0},
    .default_parameters = spring_p, .q0 = spring_q0, .qd0 = spring_qd0,
    .forward_dynamics = spring_fd, .inertia_solve = ball_solve, .generalized_momentum = ball_momentum,
    .contact_points = ball_points, .contact_velocities = ball_velocities, .contact_generalized_force = ball_force,
    .contact_gaps = spring_gaps,
    .contact_bias = ball_jbias, .energy = spring_energy, .rhs = spring_rhs, .power = ball_power
};

/* ---- skew: a point in the corner x >= 0, y >= 0 with the coupled inertia I_f = [[2, 1], [1, 2]] (kg), no gravity,
 * J = I, e = p[0] on both walls.  I_f^-1 = [[2, -1], [-1, 2]] / 3, so the contact-space matrix J I_f^-1 J^T is
 * I_f^-1 itself: its diagonal is 2/3 and its off-diagonal -1/3 (a P-matrix: both principal minors 2/3 and 1/3 > 0). */
static void skew_solve(const double *q, const double *Q, const double *p, double *x)
{
    (void)q; (void)p;
    x[0] = (2.0 * Q[0] - Q[1]) / 3.0; x[1] = (2.0 * Q[1] - Q[0]) / 3.0;
}
static void skew_momentum(const double *q, const double *qd, const double *p, double *h)
{
    (void)q; (void)p;
    h[0] = 2.0 * qd[0] + qd[1]; h[1] = qd[0] + 2.0 * qd[1];
}
static void skew_fd(const double *q, const double *qd, const double *u, const double *p, double *qdd)
{
    (void)q; (void)qd; (void)u; (void)p;
    qdd[0] = 0.0; qdd[1] = 0.0;
}
static void skew_gaps(const double *q, const double *p, double *gap)
{
    (void)p;
    gap[0] = q[0]; gap[1] = q[1];
}
static void skew_energy(const double *q, const double *qd, const double *p, double *E)
{
    (void)q; (void)p;
    E[0] = 0.5 * (2.0 * qd[0] * qd[0] + 2.0 * qd[0] * qd[1] + 2.0 * qd[1] * qd[1]);
    E[1] = 0.0;
}
static void skew_rhs(double t, const double *x, const double *u, const double *p, double *xdot)
{
    (void)t;
    xdot[0] = x[2]; xdot[1] = x[3];
    skew_fd(x, x + 2, u, p, xdot + 2);
}
static const gac_contact skew_contacts[2] = {
    {1, 0, +1, 0, 0, 0.0, GAC_CONTACT_WALL, -1, 0, -1, 0.0, {-1, -1}, GAC_END_LINK}, {1, 1, +1, 1, 0, 0.0, GAC_CONTACT_WALL, -1, 0, -1, 0.0, {-1, -1}, GAC_END_LINK}
};
static const double skew_p[3] = {0.5, 0.0, 0.0};
static const double skew_q0[2] = {1.0, 1.0}, skew_qd0[2] = {0.0, 0.0};
static const gac_model skew = {
    .name = "skew", .n = 0, .nq = 2, .nx = 4, .nparam = 3, .npoint = 1, .ncontact = 2, .njrow = 2,
    .contacts = skew_contacts,
    .chart = {.a = {0.0, 1.0}, .b = {1.0, 0.0}, .theta0_index = -1, .theta0_value = 0.0},
    .default_parameters = skew_p, .q0 = skew_q0, .qd0 = skew_qd0,
    .forward_dynamics = skew_fd, .inertia_solve = skew_solve, .generalized_momentum = skew_momentum,
    .contact_points = box_points, .contact_velocities = box_velocities, .contact_generalized_force = box_force,
    .contact_gaps = skew_gaps,
    .contact_bias = box_jbias, .energy = skew_energy, .rhs = skew_rhs
};

/* skew_ld: skew with the long-double variants of its momentum, generalised force and energy, with which the library
 * measures an impact's accuracy (gac_impact_accuracy: the momentum balance and the energy identity in long double). */
static void skew_momentum_ld(const double *q, const double *qd, const double *p, long double *h)
{
    (void)q; (void)p;
    h[0] = 2.0L * qd[0] + qd[1]; h[1] = qd[0] + 2.0L * qd[1];
}
static void skew_force_ld(const double *q, const double *f, const double *p, long double *Q)
{
    (void)q; (void)p;
    Q[0] = f[0]; Q[1] = f[1];
}
static void skew_energy_ld(const double *q, const double *qd, const double *p, long double *E)
{
    const long double x = qd[0], y = qd[1];
    (void)q; (void)p;
    E[0] = x * x + x * y + y * y;
    E[1] = 0.0L;
}
static gac_model skew_with_ld(void)
{
    gac_model m = skew;
    m.generalized_momentum_ld = skew_momentum_ld;
    m.contact_generalized_force_ld = skew_force_ld;
    m.energy_ld = skew_energy_ld;
    return m;
}

/* The first impact of the point thrown into skew's corner, with and without the long-double kernels: the same law,
 * the same velocities to 4096 units in the last place (with them, each component is moved by whole units to bring the
 * energy nearest the law's, GAC_ROUND_ULPS at most), an energy at least as near the exact law's (0.5, -1.05): T = 0.8275 J, and an accuracy
 * at least as fine. */
static void test_extended_accuracy(void)
{
    const gac_model extended = skew_with_ld();
    const gac_model *models[2] = {&skew, &extended};
    const double q0[2] = {0.3, 0.7}, qd0[2] = {-1.0, -0.3};
    double qd_after[2][2], roundoff[2];
    int k;
    for (k = 0; k < 2; ++k) {
        gac_options opt;
        gac_sim sim;
        gac_impact_record rec;
        int code;
        gac_default_options(&opt);
        gac_record_bind(&rec, models[k], rdwork, riwork);
        code = gac_sim_init(&sim, models[k], dwork, iwork, 0.0, q0, qd0, 0, &opt);
        if (code == GAC_OK) code = gac_sim_advance(&sim, 10.0, 0, 0, 0, 0, &rec);
        CHECK(code == GAC_SIM_IMPACT, "%s: code %d", models[k]->name, code);
        qd_after[k][0] = rec.qd_after[0];
        qd_after[k][1] = rec.qd_after[1];
        roundoff[k] = rec.roundoff;
    }
    for (k = 0; k < 2; ++k) {
        CHECK(fabs(qd_after[1][k] - qd_after[0][k]) <= 4096.0 * DBL_EPSILON * fabs(qd_after[0][k]),
              "the same velocities: (%.17g, %.17g), (%.17g, %.17g)", qd_after[0][0], qd_after[0][1], qd_after[1][0],
              qd_after[1][1]);
    }
    {
        long double miss[2];
        for (k = 0; k < 2; ++k) {
            const long double x = qd_after[k][0], y = qd_after[k][1];
            miss[k] = fabsl(x * x + x * y + y * y - 0.8275L);
        }
        CHECK(miss[1] <= miss[0], "energy's miss with long double %Lg, double %Lg", miss[1], miss[0]);
    }
    CHECK(roundoff[1] <= roundoff[0] && roundoff[1] <= 1e-10, "accuracy with long double %g, double %g", roundoff[1],
          roundoff[0]);
}

/* The spring's y(1) with the loop stepping at a fixed h (RK4: dt = h; DOPRI5 and DOP853: first step h, h_max = h and
 * tolerances so loose that every step is accepted); the error against cos(w). */
static double spring_error(int method, double h)
{
    gac_options opt;
    gac_sim sim;
    gac_impact_record rec;
    int code;
    gac_default_options(&opt);
    opt.method = method;
    opt.dt = h;
    opt.h_max = h;
    opt.rtol = 0.5;
    opt.atol = 1e3;
    gac_record_bind(&rec, &spring, rdwork, riwork);
    code = gac_sim_init(&sim, &spring, dwork, iwork, 0.0, spring_q0, spring_qd0, 0, &opt);
    if (code == GAC_OK) code = gac_sim_advance(&sim, 1.0, 0, 0, 0, 0, &rec);
    CHECK(code == GAC_SIM_END && sim.n_rejected == 0, "spring run: code %d, %ld rejected", code, sim.n_rejected);
    return fabs(sim.x[0] - cos(2.0));
}

/* Order of convergence: the global error of a method of order k falls by 2^k when h halves (once h is small enough
 * for the leading error term to dominate: DOPRI5 from h = 1/64 here).  And dense output: samples between the steps
 * against the closed form y = cos(2 t). */
static void test_integrators(void)
{
    static const struct { int method; double h, order; } cases[3] = {
        {GAC_METHOD_RK4, 1.0 / 32, 4.0}, {GAC_METHOD_DOPRI5, 1.0 / 64, 5.0}, {GAC_METHOD_DOP853, 1.0 / 4, 8.0}};
    double t_eval[41], x_eval[82], worst = 0.0;
    gac_options opt;
    gac_sim sim;
    gac_impact_record rec;
    int k, i_eval = 0, code;
    for (k = 0; k < 3; ++k) {
        double e1 = spring_error(cases[k].method, cases[k].h), e2 = spring_error(cases[k].method, cases[k].h / 2);
        double order = log2(e1 / e2);
        CHECK(fabs(order - cases[k].order) < 0.3, "method %d: observed order %.3f (errors %.3g, %.3g), expected %g",
              cases[k].method, order, e1, e2, cases[k].order);
    }
    for (k = 0; k < 3; ++k) {
        gac_default_options(&opt);
        opt.method = cases[k].method;
        opt.rtol = 1e-11;
        opt.atol = 1e-13;
        if (cases[k].method == GAC_METHOD_RK4) opt.dt = 1e-3;
        for (i_eval = 0; i_eval < 41; ++i_eval) t_eval[i_eval] = 0.0371 * i_eval;    /* between the steps */
        i_eval = 0;
        gac_record_bind(&rec, &spring, rdwork, riwork);
        code = gac_sim_init(&sim, &spring, dwork, iwork, 0.0, spring_q0, spring_qd0, 0, &opt);
        if (code == GAC_OK) code = gac_sim_advance(&sim, 1.6, t_eval, 41, &i_eval, x_eval, &rec);
        worst = 0.0;
        for (int i = 0; i < 41; ++i) {
            worst = fmax(worst, fabs(x_eval[2 * i] - cos(2.0 * t_eval[i])));
            worst = fmax(worst, fabs(x_eval[2 * i + 1] + 2.0 * sin(2.0 * t_eval[i])));
        }
        /* RK4 at dt = 1e-3: its cubic Hermite interpolant errs O(dt^4) = 1e-12 times the derivatives (16); the
         * adaptive methods' interpolants are of order 4 and 7 on steps the tolerance 1e-11 keeps short */
        CHECK(code == GAC_SIM_END && i_eval == 41 && worst < 1e-8, "method %d dense output: code %d, %d samples, "
              "worst error %.3g", cases[k].method, code, i_eval, worst);
    }
}

/* Event location on the ball pushed away from its floor (g = -128 m/s^2: an upward acceleration a = 128) and thrown
 * down at 1 m/s from y0: y = y0 - t + 64 t^2, lowest at t = 1/128, where y = y0 - 1/256.  DOPRI5 is exact on it, so
 * with a first step and h_max of 0.02 s and one event sample per step the first step spans the whole dip.
 *   y0 = 1/512: the dip crosses the floor, y = 0 at t* = (1 - sqrt(1 - 256 y0)) / 128 = (1 - sqrt(1/2)) / 128, where
 *     v = -1 + 128 t* = -sqrt(1/2); the impact (e = 1/2) leaves at +sqrt(1/2) / 2.  Both ends of the step lie above the
 *     floor (y(0.02) = y0 + 0.0056), so the crossing is found from the gap's minimum between the samples.
 *   y0 = 1/256: the lowest point touches the floor at zero speed: a graze, no impact; y(0.05) = 1/256 - 0.05 + 0.16. */
static void test_events(void)
{
    const double p[3] = {-128.0, 1.0, 0.5}, down[1] = {-1.0};
    const double t_star = (1.0 - sqrt(0.5)) / 128.0;
    double y0[1] = {1.0 / 512.0};
    gac_options opt;
    gac_sim sim;
    gac_impact_record rec;
    int code, impacts = 0;
    gac_default_options(&opt);
    opt.dt = 0.02;
    opt.h_max = 0.02;
    opt.event_samples = 1;
    gac_record_bind(&rec, &ball, rdwork, riwork);
    code = gac_sim_init(&sim, &ball, dwork, iwork, 0.0, y0, down, p, &opt);
    if (code == GAC_OK) code = gac_sim_advance(&sim, 0.05, 0, 0, 0, 0, &rec);
    CHECK(code == GAC_SIM_IMPACT && NEAR(rec.t, t_star, 1e-12) && NEAR(rec.qd_before[0], -sqrt(0.5), 1e-10)
          && NEAR(rec.qd_after[0], 0.5 * sqrt(0.5), 1e-10),
          "dip between samples: code %d, t %.17g (expected %.17g), v %.17g -> %.17g", code, rec.t, t_star,
          rec.qd_before[0], rec.qd_after[0]);
    y0[0] = 1.0 / 256.0;
    code = gac_sim_init(&sim, &ball, dwork, iwork, 0.0, y0, down, p, &opt);
    while (code == GAC_OK || code == GAC_SIM_IMPACT || code == GAC_SIM_CONTACT) {
        code = gac_sim_advance(&sim, 0.05, 0, 0, 0, 0, &rec);
        impacts += code == GAC_SIM_IMPACT;
        if (code == GAC_SIM_END) break;
    }
    CHECK(code == GAC_SIM_END && impacts == 0 && NEAR(sim.x[0], 1.0 / 256.0 - 0.05 + 0.16, 1e-12)
          && NEAR(sim.x[1], -1.0 + 128.0 * 0.05, 1e-11),
          "graze: code %d, %d impacts, y %.17g, v %.17g", code, impacts, sim.x[0], sim.x[1]);
}

/* Resting contact: the ball (m = 2 kg, g = 9.81) with e = 0 dropped from 1 m lands at t1 = sqrt(2 / g) and stays on
 * the floor (resting contact, force m g); an upward input u = m (g + a), a = 2 m/s^2, set at t = 1 s releases it
 * and it rises as y = a (t - 1)^2 / 2: y(1.5) = 0.25 m, v(1.5) = 1 m/s. */
static void test_resting_contact(void)
{
    const double p[3] = {9.81, 2.0, 0.0}, h[1] = {1.0}, rest[1] = {0.0}, up[1] = {2.0 * (9.81 + 2.0)};
    gac_sim sim;
    gac_impact_record rec;
    int code, landed = 0, released = 0;
    gac_record_bind(&rec, &ball, rdwork, riwork);
    code = gac_sim_init(&sim, &ball, dwork, iwork, 0.0, h, rest, p, 0);
    while (code == GAC_OK || code == GAC_SIM_IMPACT || code == GAC_SIM_CONTACT) {
        code = gac_sim_advance(&sim, 1.0, 0, 0, 0, 0, &rec);
        if (code == GAC_SIM_IMPACT) {
            CHECK(NEAR(rec.t, sqrt(2.0 / 9.81), 1e-12), "landing at %.17g", rec.t);
            landed += rec.nlanded;
        }
        if (code == GAC_SIM_CONTACT) landed += rec.nlanded;
        if (code == GAC_SIM_END) break;
    }
    CHECK(code == GAC_SIM_END && landed == 1 && sim.nresting == 1 && fabs(sim.x[0]) < 1e-12 && fabs(sim.x[1]) < 1e-12,
          "at rest on the floor: code %d, landed %d, nresting %d, y %.3g, v %.3g", code, landed, sim.nresting, sim.x[0],
          sim.x[1]);
    CHECK(gac_sim_set_input(&sim, up) == GAC_OK, "input set");
    code = gac_sim_advance(&sim, 1.5, 0, 0, 0, 0, &rec);
    if (code == GAC_SIM_CONTACT) released = rec.nreleased;
    CHECK(code == GAC_SIM_CONTACT && released == 1 && rec.t == 1.0 && sim.nresting == 0,
          "released by the upward force at t = 1: code %d, released %d, t %.17g", code, released, rec.t);
    code = gac_sim_advance(&sim, 1.5, 0, 0, 0, 0, &rec);
    CHECK(code == GAC_SIM_END && NEAR(sim.x[0], 0.25, 1e-12) && NEAR(sim.x[1], 1.0, 1e-12),
          "rising: code %d, y %.17g, v %.17g", code, sim.x[0], sim.x[1]);
}

/* Newton's law (Eq. 47) on two coupled contacts (the skew model, e = 1/2), by hand with A = J I_f^-1 J^T =
 * [[2, -1], [-1, 2]] / 3 and A F = -(1 + e) v-:
 *   v- = (-1, -1): F = I_f (1.5, 1.5) = (4.5, 4.5) >= 0, v+ = v- + I_f^-1 F = (0.5, 0.5) = -e v-.
 *   v- = (-2, 0.5), with complementarity: round 1 takes the approaching contact 0 alone: F0 = 1.5 * 2 / (2/3) = 4.5,
 *     v = (-2, 0.5) + (3, -1.5) = (1, -1); contact 1, driven into its wall, is struck by its own law in round 2:
 *     F1 = 1.5 * 1 / (2/3) = 2.25, v = (1, -1) + (-0.75, 1.5) = (0.25, 0.5), both separating: done.  Impulses
 *     (4.5, 2.25), two rounds, kinetic energy 3.25 J -> 0.4375 J. */
static void test_impact_law(void)
{
    const double q[2] = {0.0, 0.0}, both[2] = {-1.0, -1.0}, one[2] = {-2.0, 0.5};
    const int contact_set[2] = {0, 1};
    double qd_plus[2], F[2];
    int code = gac_impact(&skew, q, both, skew_p, 2, contact_set, qd_plus, F, work);
    CHECK(code == GAC_OK && NEAR(F[0], 4.5, 1e-14) && NEAR(F[1], 4.5, 1e-14) && NEAR(qd_plus[0], 0.5, 1e-15)
          && NEAR(qd_plus[1], 0.5, 1e-15), "Eq. 47, two contacts: code %d, F (%.17g, %.17g), v+ (%.17g, %.17g)", code,
          F[0], F[1], qd_plus[0], qd_plus[1]);
    code = gac_impact_complementarity(&skew, q, both, skew_p, 2, contact_set, qd_plus, F, work);
    CHECK(code == GAC_OK && NEAR(F[0], 4.5, 1e-14) && NEAR(F[1], 4.5, 1e-14), "complementarity = Eq. 47 when both push");
    code = gac_impact_complementarity(&skew, q, one, skew_p, 2, contact_set, qd_plus, F, work);
    CHECK(code == GAC_OK && NEAR(F[0], 4.5, 1e-14) && NEAR(F[1], 2.25, 1e-14) && NEAR(qd_plus[0], 0.25, 1e-15)
          && NEAR(qd_plus[1], 0.5, 1e-15), "two rounds: code %d, F (%.17g, %.17g), v+ (%.17g, %.17g)", code, F[0], F[1],
          qd_plus[0], qd_plus[1]);
}

/* The loop's own rules for schedules, impact counts and options.
 * A held schedule on the ball (m, g; no impact before t = 0.6): u = 0, then m (g + 4) from t = 0.2, then 0 from
 * t = 0.5, so y is quadratic on each interval: y(0.2) = 1 - g 0.2^2 / 2, v(0.2) = -0.2 g; y(0.5) = y(0.2) + 0.3
 * v(0.2) + 2 0.3^2, v(0.5) = v(0.2) + 4 0.3; y(0.6) = y(0.5) + 0.1 v(0.5) - g 0.1^2 / 2.  DOPRI5 is exact on
 * quadratics, so with every jump on a step boundary the result is exact to round-off; a jump inside a step
 * leaves an error of the order of the tolerance (1e-6 here).  A linear schedule 0 -> 10 m over [0, 0.4] (then
 * 10 m): y'' = -g + 25 t, y(0.4) = 1 - g 0.4^2 / 2 + 25 0.4^3 / 6, v(0.4) = -0.4 g + 25 0.4^2 / 2, then y'' = 10 - g. */
static void test_loop_rules(void)
{
    const double g = ball_p[0], m = ball_p[1];
    const double t_held[3] = {0.0, 0.2, 0.5}, u_held[3] = {0.0, 2.0 * (9.81 + 4.0), 0.0};
    const double t_lin[2] = {0.0, 0.4}, u_lin[2] = {0.0, 2.0 * 10.0};
    const gac_schedule held = {3, 1, t_held, u_held, 0}, linear = {2, 1, t_lin, u_lin, 1};
    const gac_schedule wrong = {2, 2, t_lin, u_lin, 0};
    const double y2 = 1.0 - g * 0.04 / 2.0, v2 = -0.2 * g, y5 = y2 + 0.3 * v2 + 2.0 * 0.09, v5 = v2 + 1.2;
    const double y6 = y5 + 0.1 * v5 - g * 0.01 / 2.0;
    const double y4 = 1.0 - g * 0.16 / 2.0 + 25.0 * 0.064 / 6.0, v4 = -0.4 * g + 25.0 * 0.16 / 2.0;
    const double y6_lin = y4 + 0.2 * v4 + (10.0 - g) * 0.04 / 2.0;
    const char *field = 0;
    gac_options opt;
    gac_sim sim;
    gac_impact_record rec;
    int code, n;
    (void)m;
    gac_record_bind(&rec, &ball, rdwork, riwork);
    gac_default_options(&opt);
    opt.rtol = 1e-6;
    opt.atol = 1e-8;
    CHECK(gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, &opt) == GAC_OK, "init");
    {                                     /* a controller's Jacobian: set after it, dropped with it */
        pd_gains pd = {4.0, 0.8, 1.5};
        CHECK(gac_sim_set_controller_jacobian(0, ball_pd_jacobian) == GAC_ERR_NULL_ARGUMENT, "jacobian: NULL sim");
        CHECK(gac_sim_set_controller_jacobian(&sim, ball_pd_jacobian) == GAC_ERR_BAD_OPTION
              && sim.controller_jacobian == 0, "jacobian without a controller refused");
        CHECK(gac_sim_set_controller(&sim, ball_pd, &pd) == GAC_OK
              && gac_sim_set_controller_jacobian(&sim, ball_pd_jacobian) == GAC_OK
              && sim.controller_jacobian == ball_pd_jacobian, "jacobian set after its controller");
        CHECK(gac_sim_set_controller(&sim, ball_pd, &pd) == GAC_OK && sim.controller_jacobian == 0,
              "a new controller drops the jacobian");
        CHECK(gac_sim_set_controller_jacobian(&sim, ball_pd_jacobian) == GAC_OK
              && gac_sim_set_schedule(&sim, &linear) == GAC_OK && sim.controller_jacobian == 0
              && gac_sim_set_controller_jacobian(&sim, ball_pd_jacobian) == GAC_ERR_BAD_OPTION,
              "a schedule drops the jacobian and refuses one");
        CHECK(gac_sim_set_controller(&sim, 0, 0) == GAC_OK, "back to the held inputs");
    }
    CHECK(gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, &opt) == GAC_OK, "init");
    CHECK(gac_sim_set_schedule(&sim, &wrong) == GAC_ERR_BAD_OPTION && sim.schedule == 0, "a schedule of 2 inputs refused");
    CHECK(gac_sim_set_schedule(&sim, &held) == GAC_OK, "held schedule set");
    code = gac_sim_advance(&sim, 0.6, 0, 0, 0, 0, &rec);
    CHECK(code == GAC_SIM_END && NEAR(sim.x[0], y6, 1e-12) && NEAR(sim.x[1], v5 - 0.1 * g, 1e-12),
          "held schedule: y(0.6) = %.17g, exact %.17g", sim.x[0], y6);
    CHECK(gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, &opt) == GAC_OK, "init");
    CHECK(gac_sim_set_schedule(&sim, &linear) == GAC_OK, "linear schedule set");
    code = gac_sim_advance(&sim, 0.6, 0, 0, 0, 0, &rec);
    CHECK(code == GAC_SIM_END && NEAR(sim.x[0], y6_lin, 1e-12), "linear schedule: y(0.6) = %.17g, exact %.17g",
          sim.x[0], y6_lin);

    /* max_impacts: the ball bounces (e = 0.8); after 2 impacts the next advance stops before any step */
    gac_default_options(&opt);
    opt.max_impacts = 2;
    CHECK(gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, &opt) == GAC_OK, "init");
    for (n = 0; (code = gac_sim_advance(&sim, 5.0, 0, 0, 0, 0, &rec)) == GAC_SIM_IMPACT; ++n) {}
    CHECK(code == GAC_ERR_MAX_IMPACTS && n == 2 && sim.n_impacts == 2 && sim.t == rec.t,
          "stopped after 2 impacts at the second one: code %d, n %d, t %g", code, n, sim.t);
    sim.opt.max_impacts = 0;
    code = gac_sim_advance(&sim, 5.0, 0, 0, 0, 0, &rec);
    CHECK(code == GAC_SIM_IMPACT && sim.n_impacts == 3, "raising the limit goes on");

    /* gac_check_options names the option out of range */
    gac_default_options(&opt);
    CHECK(gac_check_options(&opt, &field) == GAC_OK && field == 0, "defaults pass");
    opt.rtol = 0.0;
    CHECK(gac_check_options(&opt, &field) == GAC_ERR_BAD_OPTION && strncmp(field, "rtol: ", 6) == 0, "rtol named");
    gac_default_options(&opt);
    opt.max_impacts = -1;
    CHECK(gac_check_options(&opt, &field) == GAC_ERR_BAD_OPTION && strncmp(field, "max_impacts: ", 13) == 0,
          "max_impacts named");
    CHECK(gac_sim_init(&sim, &ball, dwork, iwork, 0.0, ball_q0, ball_qd0, 0, &opt) == GAC_ERR_BAD_OPTION,
          "sim_init applies the same check");
    CHECK(gac_check_options(0, &field) == GAC_ERR_NULL_ARGUMENT, "NULL options");
}

/* ---- the two base charts: the default base twists (chart A, first axis X2) and chart B = C T_-1 with C = Rz(-90 deg)
 * (first axis X1).  Angles round trip, the same orientation and angular velocity on both charts, the conversion's
 * derivative, the lock. ---- */
static double lcg_state = 0.5;
static double uniform(double lo, double hi)       /* a fixed pseudo-random sequence (no rand(): reproducible) */
{
    lcg_state = fmod(lcg_state * 9301.0 + 49297.0, 233280.0);
    return lo + (hi - lo) * lcg_state / 233280.0;
}

static double max_diff(const double *a, const double *b, int n)
{
    double d = 0.0;
    int i;
    for (i = 0; i < n; ++i) d = fabs(a[i] - b[i]) > d ? fabs(a[i] - b[i]) : d;
    return d;
}

/* The largest difference between gac_chart_convert_tangent's derivative at x (on `from`, y its conversion) and
 * central differences of gac_chart_convert (step 1e-6), along each of the 6 components of a 3-angle state. */
static double convert_tangent_error(const gac_base *from, const gac_base *to, const double *x, const double *y)
{
    double D[36], plus[6], minus[6], xp[6], xm[6], worst = 0.0;
    int c, i;
    for (i = 0; i < 36; ++i) D[i] = i % 7 == 0 ? 1.0 : 0.0;      /* the unit directions, one a row */
    if (gac_chart_convert_tangent(from, to, 3, x, y, 6, D) != GAC_OK) return HUGE_VAL;
    for (c = 0; c < 6; ++c) {
        for (i = 0; i < 6; ++i) xp[i] = xm[i] = x[i];
        xp[c] += 1e-6;
        xm[c] -= 1e-6;
        gac_chart_convert(from, to, 3, xp, y, plus);
        gac_chart_convert(from, to, 3, xm, y, minus);
        for (i = 0; i < 6; ++i)
            worst = fmax(worst, fabs((plus[i] - minus[i]) / 2e-6 - D[6 * c + i]) / (1.0 + fabs(D[6 * c + i])));
    }
    return worst;
}

static void test_charts(void)
{
    const gac_base A = {{1, 0, 0, 0, 0, 1, 0, -1, 0}, {1, 0, 0, 0, 0, -1, 0, 1, 0}, {0, 0, 1, 1, 0, 0, 0, 1, 0}, {0, 1, 2}};
    const gac_base B = {{0, 0, 1, -1, 0, 0, 0, -1, 0}, {1, 0, 0, 0, 0, -1, 0, 1, 0}, {0, 0, 1, 1, 0, 0, 0, 1, 0}, {0, 1, 2}};
    double worst_angles = 0.0, worst_R = 0.0, worst_omega = 0.0, worst_tangent = 0.0;
    int k, i;
    for (k = 0; k < 200; ++k) {
        /* a state of a 3-coordinate "chain" (the base angles only) with theta_0 away from both charts' locks */
        double x[6], y[6], z[6], RA[9], RB[9], EA[9], EB[9], wA[3], wB[3], near[3];
        x[0] = uniform(-3.0, 3.0);
        x[1] = uniform(-1.4, 1.4);                   /* chart A's lock is at theta_0 = +-pi/2 */
        x[2] = uniform(-3.0, 3.0);
        for (i = 3; i < 6; ++i) x[i] = uniform(-5.0, 5.0);
        gac_base_rotation(&A, x, RA);
        if (gac_base_measure(&B, RA) < 0.05) continue;          /* near chart B's own lock: not a switch state */
        CHECK(gac_chart_convert(&A, &B, 3, x, 0, y) == GAC_OK, "A -> B");
        for (i = 0; i < 3; ++i) near[i] = x[i] + (broken && k == 0 ? 1e-3 : 0.0) + 0.1;
        CHECK(gac_chart_convert(&B, &A, 3, y, near, z) == GAC_OK, "B -> A");
        gac_base_rotation(&B, y, RB);
        gac_base_axes(&A, x, EA);
        gac_base_axes(&B, y, EB);
        for (i = 0; i < 3; ++i) {
            wA[i] = EA[3 * i] * x[3] + EA[3 * i + 1] * x[4] + EA[3 * i + 2] * x[5];
            wB[i] = EB[3 * i] * y[3] + EB[3 * i + 1] * y[4] + EB[3 * i + 2] * y[5];
        }
        worst_R = fmax(worst_R, max_diff(RA, RB, 9));
        worst_omega = fmax(worst_omega, max_diff(wA, wB, 3) / (1.0 + fabs(wA[0]) + fabs(wA[1]) + fabs(wA[2])));
        worst_angles = fmax(worst_angles, max_diff(x, z, 6) + (broken && k < 3 ? 1.0 : 0.0));
        if (k < 50 && gac_base_measure(&A, RA) > 0.05) {   /* the switch's derivative, both ways */
            worst_tangent = fmax(worst_tangent, convert_tangent_error(&A, &B, x, y));
            worst_tangent = fmax(worst_tangent, convert_tangent_error(&B, &A, y, z));
        }
        /* |det E| of each chart is its measure of R */
        CHECK(NEAR(fabs(EA[0] * (EA[4] * EA[8] - EA[5] * EA[7]) - EA[1] * (EA[3] * EA[8] - EA[5] * EA[6])
                        + EA[2] * (EA[3] * EA[7] - EA[4] * EA[6])), gac_base_measure(&A, RA), 1e-12), "det E_A = chi_A");
    }
    CHECK(worst_angles <= 1e-12, "angles and rates round trip A -> B -> A: %.3g", worst_angles);
    CHECK(worst_R <= 1e-12, "the same orientation on both charts: %.3g", worst_R);
    CHECK(worst_omega <= 1e-12, "the same angular velocity on both charts: %.3g", worst_omega);
    CHECK(worst_tangent <= 1e-8, "the conversion's derivative against central differences: %.3g", worst_tangent);
    {
        /* chart A's lock: theta_0 = pi/2 puts z_1 along X2; only theta_-1 + theta_1 is defined there */
        const double x[3] = {0.7, 1.5707963267948966, -0.2}, near[3] = {0.3, 1.5, 0.1};
        double R[9], angles[3], back[9], E[9], rates[3], omega[3] = {0.3, -1.2, 0.8}, w[3], r[3], n[3], y[6];
        gac_base_rotation(&A, x, R);
        CHECK(gac_base_measure(&A, R) < 1e-15, "at the lock: %.3g", gac_base_measure(&A, R));
        CHECK(gac_base_angles(&A, R, near, angles) == GAC_OK, "angles at the lock");
        CHECK(angles[0] == near[0], "theta_-1 kept from near at the lock: %.17g", angles[0]);
        gac_base_rotation(&A, angles, back);
        CHECK(max_diff(back, R, 9) <= 1e-12, "the lock's angles recompose R: %.3g", max_diff(back, R, 9));
        /* least-squares rates of least norm: E^T (E r - omega) = 0 and r orthogonal to the null vector of E */
        gac_base_rates(&A, angles, omega, rates);
        gac_base_axes(&A, angles, E);
        for (i = 0; i < 3; ++i) w[i] = E[3 * i] * rates[0] + E[3 * i + 1] * rates[1] + E[3 * i + 2] * rates[2] - omega[i];
        for (i = 0; i < 3; ++i) r[i] = E[i] * w[0] + E[3 + i] * w[1] + E[6 + i] * w[2];
        n[0] = E[1] * E[5] - E[2] * E[4];               /* null vector: rows 0 and 1 crossed */
        n[1] = E[2] * E[3] - E[0] * E[5];
        n[2] = E[0] * E[4] - E[1] * E[3];
        CHECK(fabs(r[0]) + fabs(r[1]) + fabs(r[2]) <= 1e-12, "normal equations at the lock");
        CHECK(fabs(n[0] * rates[0] + n[1] * rates[1] + n[2] * rates[2]) <= 1e-12 * (fabs(n[0]) + fabs(n[1]) + fabs(n[2])),
              "least norm at the lock");
        /* the lock state converts to chart B (far from its own lock) and back to the same orientation */
        {
            const double xs[6] = {x[0], x[1], x[2], 0.5, 0.0, -0.5};   /* rates with omega in E's range */
            double RB[9];
            CHECK(gac_chart_convert(&A, &B, 3, xs, 0, y) == GAC_OK, "A -> B from the lock");
            gac_base_rotation(&B, y, RB);
            CHECK(max_diff(RB, R, 9) <= 1e-12, "lock state on B: %.3g", max_diff(RB, R, 9));
            CHECK(gac_base_measure(&B, RB) > 0.99, "chart B far from its lock there");
        }
    }
    {
        /* a twist that does not turn its axis a right angle: refused */
        gac_base bad = A;
        double R[9], angles[3];
        const double x[3] = {0.1, 0.2, 0.3};
        bad.T_0[8] = 1.0;
        bad.T_0[4] = 0.0;
        bad.T_0[5] = 0.0;
        bad.T_0[7] = 0.0;
        gac_base_rotation(&A, x, R);
        CHECK(gac_base_angles(&bad, R, 0, angles) == GAC_ERR_BAD_MODEL, "non-right-angle twist refused");
    }
}

/* An impulse left below zero by round-off (<= 1e-12 of the largest, or doing work against the velocities after of
 * at most eps T) is taken out with the velocities it gave; a larger one stays (the law's post-conditions refuse it). */
static void test_roundoff_pulls(void)
{
    const double x[4] = {1.0, 1.0, 0.0, 0.0};
    const int list[2] = {0, 2};                           /* the box's point on x_min and y_min */
    double F[2] = {1.0, -1e-13}, Ft[4] = {0.0, 0.0, 0.0, 0.0}, qd_plus[2] = {2.0, 0.5};
    gac_drop_roundoff_pulls(&box, x, box_p, 2, list, 1.0, F, Ft, qd_plus);
    CHECK(F[0] == 1.0 && F[1] == 0.0, "round-off pull taken out: F %g %g", F[0], F[1]);
    CHECK(qd_plus[0] == 2.0 && NEAR(qd_plus[1], 0.5 + 1e-13 / box_p[1], 1e-16),
          "its velocity change undone (qd+ += m^-1 1e-13): %.17g", qd_plus[1]);
    F[1] = -1e-11;
    qd_plus[1] = 0.5;
    gac_drop_roundoff_pulls(&box, x, box_p, 2, list, 1.0, F, Ft, qd_plus);
    CHECK(F[1] == -1e-11 && qd_plus[1] == 0.5, "a pull above round-off stays: F %g", F[1]);
    F[0] = 0.0;                                           /* alone: its work against qd+ decides */
    F[1] = -1e-26;
    gac_drop_roundoff_pulls(&box, x, box_p, 2, list, 1.0, F, Ft, qd_plus);
    CHECK(F[1] == 0.0, "a pull whose work is below eps T taken out: F %g", F[1]);
    F[1] = -1e-11;
    qd_plus[1] = 0.5;
    gac_drop_roundoff_pulls(&box, x, box_p, 2, list, 1.0, F, Ft, qd_plus);
    CHECK(F[1] == -1e-11 && qd_plus[1] == 0.5, "a pull above round-off stays: F %g", F[1]);
}

int main(int argc, char **argv)
{
    broken = argc > 1 && strcmp(argv[1], "--break") == 0;
    test_sizes();
    test_dense();
    test_impact_kernels();
    test_ball(GAC_METHOD_DOPRI5);
    test_ball(GAC_METHOD_DOP853);
    test_ball(GAC_METHOD_RK4);
    test_box();
    test_fused_kernel();
    test_sled();
    test_tangential_impact();
    test_budget_and_progress();
    test_inputs();
    test_errors();
    test_parameters();
    test_integrators();
    test_events();
    test_resting_contact();
    test_impact_law();
    test_roundoff_pulls();
    test_extended_accuracy();
    test_loop_rules();
    test_charts();
    printf("%d checks, %d failed\n", checks, failures);
    return failures == 0 ? 0 : 1;
}
