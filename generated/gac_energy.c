/*
 * gac_energy.c -- the energy balance of the hybrid loop (gac.h, "Energy balance"): its residual and scale, checked
 * at every step end and impact (GAC_ERR_DRIFT), the energy change of each projection onto the resting contacts
 * (GAC_ERR_PROJECTION), and the energy error of one conservative flight step for the step-size control.
 */
#include "gac_internal.h"

#include <math.h>

/* opt.energy_tol resolved: < 0 is min(0.1, max(1e-8, 1e4 rtol)) for the adaptive methods and 0 (off) for RK4. */
double gac_energy_tolerance(const gac_options *opt)
{
    double tol;
    if (opt->energy_tol >= 0.0) return opt->energy_tol;
    if (opt->method == GAC_METHOD_RK4) return 0.0;
    tol = 1e4 * opt->rtol;
    if (tol < 1e-8) tol = 1e-8;
    return tol < 0.1 ? tol : 0.1;
}

/* Start the balance at the state s->x (gac_sim_init). */
void gac_energy_start(gac_sim *s)
{
    double E[2];
    s->model->energy(s->x, s->x + s->model->nq, s->p, E);
    s->energy_x = s->energy_initial = E[0] + E[1];
    s->energy_scale = E[0] + fabs(E[1]);
    if (s->model->weight_scale != 0) {               /* a chain at rest: M g L, not its T + V near 0 */
        const double weight = s->model->weight_scale(s->p);
        if (weight > s->energy_scale) s->energy_scale = weight;
    }
    s->loss_impacts = s->energy_projection = s->energy_residual = s->energy_roundoff = 0.0;
    s->energy_x1_valid = 0;
    s->energy_tol = gac_energy_tolerance(&s->opt);
}

/* The balance at the current state s->x, after a step end or an impact: its energy (s->energy_x), the scale and
 * the residual.  GAC_OK, or GAC_ERR_DRIFT when |residual| > energy_tol x scale. */
int gac_energy_check(gac_sim *s, const double *E_known)
{
    double E[2], scale;
    if (E_known != 0) {                                  /* T and V at x, already evaluated */
        E[0] = E_known[0];
        E[1] = E_known[1];
    } else {
        s->model->energy(s->x, s->x + s->model->nq, s->p, E);
    }
    s->energy_x = E[0] + E[1];
    if (E[0] + fabs(E[1]) > s->energy_scale) s->energy_scale = E[0] + fabs(E[1]);
    s->energy_residual = s->energy_x - s->energy_initial - s->work_input + s->loss_damping + s->loss_friction
                         + s->loss_impacts;
    scale = s->energy_scale + fabs(s->work_input) + s->loss_damping + s->loss_friction + fabs(s->loss_impacts);
    /* the integration's share (energy_tol of the scale) and what the impacts' laws may change by round-off */
    if (s->energy_tol > 0.0 && fabs(s->energy_residual) > s->energy_tol * scale + s->energy_roundoff)
        return GAC_ERR_DRIFT;
    return GAC_OK;
}

/* The energy change of a projection onto the resting contacts that took the state from energy E_before to x:
 * summed in s->energy_projection; GAC_ERR_PROJECTION when it exceeds energy_tol x scale / 10, else GAC_OK. */
int gac_energy_projected(gac_sim *s, double E_before, const double *x)
{
    const double change = gac_total_energy(s->model, x, s->p) - E_before;
    const double scale = s->energy_scale + fabs(s->work_input) + s->loss_damping + s->loss_friction
                         + fabs(s->loss_impacts);
    s->energy_projection += change;
    if (s->energy_tol > 0.0 && fabs(change) > 0.1 * s->energy_tol * scale) return GAC_ERR_PROJECTION;
    return GAC_OK;
}

/* The energy error of the adaptive step just taken from s->x (energy s->energy_x) to s->x1, relative to
 * rtol x energy_scale / 10 (a step's energy error has a sign that persists over many steps of an orbit: held to
 * the tolerance alone, 1e4 steps drift by 1e4 rtol; a tenth of it keeps the drift near 1e3 rtol), where the flight is
 * free and conservative: no power kernel (nothing does work but gravity) and no resting contact.  Elsewhere 0: the
 * step's energy balance would need the inputs' and dampers' work over the step, and with resting contacts the state
 * at a step's end is off the constraints until it is projected (the projection's own energy change is checked,
 * gac_energy_projected). */
double gac_step_energy_error(gac_sim *s)
{
    const gac_model *md = s->model;
    const double *E = s->energy_x1;
    double change;
    if (md->power != 0 || s->nresting > 0 || !(s->energy_scale > 0.0)) return 0.0;
    if (!s->energy_x1_valid) {                           /* (not already from the step's end, gac_f_end) */
        md->energy(s->x1, s->x1 + md->nq, s->p, s->energy_x1);
        s->energy_x1_valid = 1;                          /* the step end's energies, for gac_energy_check */
    }
    /* what evaluating T + V twice leaves by round-off (its terms may be far larger than the scale: a heavy link
     * high above a light chain's zero of V) is no error of the step */
    change = fabs(E[0] + E[1] - s->energy_x) - 64.0 * GAC_EPS * (E[0] + fabs(E[1]) + s->energy_scale);
    return change > 0.0 ? change / (0.1 * s->opt.rtol * s->energy_scale) : 0.0;
}

/* Add the work of the inputs, the dissipation of the dampers and (with resting contacts on walls with friction)
 * that of sliding friction over [s->t, t_b] of the current step to s->work_input, s->loss_damping and
 * s->loss_friction: 5-point Gauss-Legendre (exact for polynomials of degree 9) on the step's dense output. */
void gac_add_work(gac_sim *s, double t_b)
{
    static const double node[5] = {0.04691007703066800, 0.23076534494715845, 0.5, 0.76923465505284155,
                                   0.95308992296933200};
    static const double weight[5] = {0.11846344252809454, 0.23931433524968324, 0.28444444444444444,
                                     0.23931433524968324, 0.11846344252809454};
    const gac_model *md = s->model;
    const double h = t_b - s->t;
    const int friction = s->nresting > 0 && gac_has_friction(md);
    double x[md->nx], P[2], w_in = 0.0, w_damp = 0.0, w_friction = 0.0;
    int j;
    if ((md->power == 0 && !friction) || !(h > 0.0)) return;
    for (j = 0; j < 5; ++j) {
        const double t = s->t + node[j] * h;
        gac_dense(s, t, x);
        if (md->power != 0) {
            md->power(x, x + md->nq, gac_input(s, t, x), s->p, P);
            w_in += weight[j] * P[0];
            w_damp += weight[j] * P[1];
        }
        if (friction) {
            double qdd[md->nq], lambda[md->nq], D = 0.0;
            if (gac_rest_forces(s, t, x, qdd, lambda, 0, &D) == GAC_OK)
                w_friction += weight[j] * D;
        }
    }
    s->work_input += h * w_in;
    s->loss_damping += h * w_damp;
    s->loss_friction += h * w_friction;
}

/* 1 if at x a rough resting contact (not stuck) slides slower than GAC_SLOW_SLIDING friction_velocity
 * (its velocity along the wall, as in gac_constrained_dynamics_friction): the regularised friction force is then
 * (nearly) viscous, -c_f lambda v_t / friction_velocity, a stiff term that bounds an explicit method's step. */
int gac_slow_sliding(const gac_sim *s, const double *x)
{
    const gac_model *md = s->model;
    const double slow = GAC_SLOW_SLIDING * md->friction_velocity;
    double vq[3 * GAC_AT_LEAST_1(md->npoint)];
    int a;
    if (s->nresting == 0 || !gac_has_friction(md)) return 0;
    md->contact_velocities(x, x + md->nq, s->p, vq);
    for (a = 0; a < s->nresting; ++a) {
        const int c = s->resting[a];
        double vt[2];
        if (!(gac_rest_friction(md, s->p, c) > 0.0) || s->is_stuck[c]) continue;
        gac_tangential_velocity(md, x, s->p, c, vq, vt);   /* a wall's two axes ascending, or a frame's tangents */
        if (vt[0] * vt[0] + vt[1] * vt[1] < slow * slow) return 1;
    }
    return 0;
}
