/*
 * gac_model.c -- the model descriptor's check, the parameters' checks, the workspace sizes and the error messages.
 */
#include "gac_internal.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>

/* b, the model m on other base charts: same sizes and tables, every base's three angles at the same places. */
static int chart_model_check(const gac_model *m, const gac_model *b)
{
    int j, c;
    if (b == 0 || b->nq != m->nq || b->nx != m->nx || b->nparam != m->nparam || b->nu != m->nu
        || b->npoint != m->npoint || b->ncontact != m->ncontact || b->njrow != m->njrow || b->contacts != m->contacts
        || b->chart_b != 0 || b->chart_models != 0 || b->nbase != m->nbase || gac_model_check(b) != GAC_OK)
        return GAC_ERR_BAD_MODEL;
    for (j = 0; j < gac_nbase(m); ++j) {
        for (c = 0; c < 3; ++c) {
            const int index = gac_model_base(m, j)->index[c];
            if (index < 0 || index >= m->nq || gac_model_base(b, j)->index[c] != index) return GAC_ERR_BAD_MODEL;
        }
    }
    return GAC_OK;
}

int gac_model_check(const gac_model *m)
{
    int c;
    if (m == 0) return GAC_ERR_NULL_ARGUMENT;
    if (m->nq < 1 || m->nx != 2 * m->nq || m->nparam < 0 || m->nu < 0 || m->npoint < 1 || m->ncontact < 0
        || m->njrow < 0)
        return GAC_ERR_BAD_MODEL;
    if ((m->ncontact > 0 && m->contacts == 0) || (m->nparam > 0 && m->default_parameters == 0)
        || m->q0 == 0 || m->qd0 == 0)
        return GAC_ERR_BAD_MODEL;
    if (m->forward_dynamics == 0 || m->inertia_solve == 0 || m->generalized_momentum == 0
        || m->contact_points == 0 || m->contact_velocities == 0 || m->contact_generalized_force == 0
        || m->contact_gaps == 0 || m->contact_bias == 0 || m->energy == 0 || m->rhs == 0)
        return GAC_ERR_BAD_MODEL;
    if (m->chart.theta0_index >= m->nq) return GAC_ERR_BAD_MODEL;
    if (m->nbase != 0) {                 /* several turning bases: each one's measure and angles in q */
        if (m->nbase < 2 || m->bases == 0 || m->charts == 0) return GAC_ERR_BAD_MODEL;
        for (c = 0; c < m->nbase; ++c) {
            if (m->charts[c].theta0_index >= m->nq) return GAC_ERR_BAD_MODEL;
        }
    }
    if (m->chart_models != 0) {          /* a model per combination of the bases' charts */
        const int last = (1 << (m->nbase > 0 ? m->nbase : 1)) - 1;
        if (m->nbase < 2 || m->nbase > GAC_CHART_BASES_MAX || m->chart_models[0] != m || m->chart_b == 0
            || m->chart_models[last] != m->chart_b)
            return GAC_ERR_BAD_MODEL;
        for (c = 1; c < last; ++c) {
            if (chart_model_check(m, m->chart_models[c]) != GAC_OK) return GAC_ERR_BAD_MODEL;
        }
    }
    if (m->chart_b != 0 && chart_model_check(m, m->chart_b) != GAC_OK) return GAC_ERR_BAD_MODEL;
    for (c = 0; m->parameter_info != 0 && c < m->nparam; ++c) {
        const gac_parameter_info *info = &m->parameter_info[c];
        if (info->name == 0 || info->range == 0 || !(info->lo <= info->hi)) return GAC_ERR_BAD_MODEL;
    }
    for (c = 0; c < m->ncontact; ++c) {
        const gac_contact *k = &m->contacts[c];
        if (k->kind == GAC_CONTACT_LINK) {                /* two links, after every kernel contact, no row */
            const int apart = k->end == GAC_END_LINK ? k->coordinate - k->point       /* a pair: i < j */
                                                     : abs(k->coordinate - k->point);  /* an end: either way */
            if (k->point < 1 || k->coordinate < 1 || apart < 2 || k->point > m->npoint - 1
                || k->coordinate > m->npoint - 1 || m->link_radius == 0
                || !(m->link_radius[c - gac_kernel_contacts(m)] >= 0.0)
                || k->normal_sign != 1 || k->e_index >= m->nparam || k->friction_index >= m->nparam
                || (k->has_friction && !(k->friction_index >= 0 || k->friction_value >= 0.0))
                || (c + 1 < m->ncontact && !gac_rowless(m, c + 1))
                || (k->end != GAC_END_LINK && k->end != GAC_END_START && k->end != GAC_END_FINISH))
                return GAC_ERR_BAD_MODEL;
            continue;
        }
        if (k->kind == GAC_CONTACT_OBSTACLE) {            /* a link and an obstacle, after the link pairs, no row */
            if (k->point < 1 || k->point > m->npoint - 1 || k->coordinate < 0 || k->coordinate >= m->nobstacle
                || m->obstacle_shapes == 0 || m->link_radius == 0
                || !(m->link_radius[c - gac_kernel_contacts(m)] >= 0.0)
                || k->normal_sign != 1 || k->e_index >= m->nparam || k->friction_index >= m->nparam
                || (k->has_friction && !(k->friction_index >= 0 || k->friction_value >= 0.0))
                || (c + 1 < m->ncontact && m->contacts[c + 1].kind != GAC_CONTACT_OBSTACLE))
                return GAC_ERR_BAD_MODEL;
            if (gac_obstacle_shape_check(m, k->coordinate) != GAC_OK) return GAC_ERR_BAD_MODEL;
            /* a joint point alone: a plane's, a box's or a bar's contacts (not a sphere's: a point's nearest) */
            if (k->end != GAC_END_LINK
                && ((k->end != GAC_END_START && k->end != GAC_END_FINISH)
                    || gac_obstacle_kind(m, k->coordinate) == GAC_OBSTACLE_SPHERE))
                return GAC_ERR_BAD_MODEL;
            continue;
        }
        if ((k->normal_sign != 1 && k->normal_sign != -1) || k->row < 0 || k->row >= m->njrow
            || k->e_index >= m->nparam || k->end != GAC_END_LINK)
            return GAC_ERR_BAD_MODEL;
        if (k->has_friction) {
            if (k->kind != GAC_CONTACT_WALL || k->friction_index >= m->nparam || !(m->friction_velocity > 0.0)
                || k->trow[0] < -1 || k->trow[0] >= m->njrow || k->trow[1] < -1 || k->trow[1] >= m->njrow)
                return GAC_ERR_BAD_MODEL;
        }
        if (k->kind == GAC_CONTACT_STOP) {
            if (k->coordinate < 0 || k->coordinate >= m->nq) return GAC_ERR_BAD_MODEL;
        } else if (k->kind != GAC_CONTACT_WALL || k->point < 1 || k->point > m->npoint || k->axis < 0
                   || k->axis > 2) {
            return GAC_ERR_BAD_MODEL;
        }
    }
    return GAC_OK;
}

void gac_forward_dynamics_energy(const gac_model *m, const double *q, const double *qd, const double *u,
                                 const double *p, double *y)
{
    if (m->forward_dynamics_energy != 0) {
        m->forward_dynamics_energy(q, qd, u, p, y);
        return;
    }
    m->forward_dynamics(q, qd, u, p, y);
    m->energy(q, qd, p, y + m->nq);
}

int gac_in_range(double value, double lo, double hi)
{
    return value - value == 0.0 && lo <= value && value <= hi && (value == 0.0 || fabs(value) >= DBL_MIN);
}

/* The eigenvalues of the symmetric 3x3 matrix A (overwritten) by cyclic Jacobi rotations (Golub and Van Loan,
 * Matrix Computations, section 8.4, sym.schur2): each rotation makes one off-diagonal entry zero; the sweeps stop
 * once the off-diagonal part is below 1e-18 of the whole (|A| <= 1 here: no overflow). */
static void gac_eigenvalues3(double A[3][3], double ev[3])
{
    int sweep, p, q, r;
    for (sweep = 0; sweep < 32; ++sweep) {
        const double off = A[0][1] * A[0][1] + A[0][2] * A[0][2] + A[1][2] * A[1][2];
        const double all = 2.0 * off + A[0][0] * A[0][0] + A[1][1] * A[1][1] + A[2][2] * A[2][2];
        if (!(off > 1e-36 * all)) break;
        for (p = 0; p < 2; ++p) {
            for (q = p + 1; q < 3; ++q) {
                double tau, t, c, s;
                if (A[p][q] == 0.0) continue;
                tau = (A[q][q] - A[p][p]) / (2.0 * A[p][q]);
                t = (tau >= 0.0 ? 1.0 : -1.0) / (fabs(tau) + sqrt(1.0 + tau * tau));
                c = 1.0 / sqrt(1.0 + t * t);
                s = t * c;
                for (r = 0; r < 3; ++r) {                     /* A J: columns p and q */
                    const double arp = A[r][p], arq = A[r][q];
                    A[r][p] = c * arp - s * arq;
                    A[r][q] = s * arp + c * arq;
                }
                for (r = 0; r < 3; ++r) {                     /* J^T (A J): rows p and q */
                    const double apr = A[p][r], aqr = A[q][r];
                    A[p][r] = c * apr - s * aqr;
                    A[q][r] = s * apr + c * aqr;
                }
                A[p][q] = A[q][p] = 0.0;
            }
        }
    }
    for (p = 0; p < 3; ++p) ev[p] = A[p][p];
}

int gac_inertia_admissible(const double *I)
{
    double A[3][3], ev[3], scale = 0.0, tol, swap;
    int i, j;
    A[0][0] = I[0]; A[1][1] = I[1]; A[2][2] = I[2];
    A[0][1] = A[1][0] = I[3];
    A[0][2] = A[2][0] = I[4];
    A[1][2] = A[2][1] = I[5];
    for (i = 0; i < 6; ++i) {
        if (fabs(I[i]) > scale) scale = fabs(I[i]);
    }
    if (scale == 0.0) return 1;
    for (i = 0; i < 3; ++i) {                                 /* scaled to |A| <= 1, the eigenvalues scaled back */
        for (j = 0; j < 3; ++j) A[i][j] /= scale;
    }
    gac_eigenvalues3(A, ev);
    for (i = 0; i < 3; ++i) {
        ev[i] *= scale;
        for (j = i; j > 0 && ev[j] < ev[j - 1]; --j) {         /* ascending: a <= b <= c */
            swap = ev[j];
            ev[j] = ev[j - 1];
            ev[j - 1] = swap;
        }
    }
    tol = 1e-12 * (ev[2] > 1.0 ? ev[2] : 1.0);
    return ev[0] >= -tol && ev[0] + ev[1] >= ev[2] - tol;
}

int gac_check_parameters(const gac_model *m, const double *p, int *bad_index)
{
    int i;
    if (m == 0 || p == 0) return GAC_ERR_NULL_ARGUMENT;
    for (i = 0; i < m->nparam; ++i) {
        if (!(p[i] - p[i] == 0.0)) {
            if (bad_index != 0) *bad_index = i;
            return GAC_ERR_BAD_PARAMETER;
        }
    }
    if (m->check_parameters == 0 || m->check_parameters(p, bad_index) == GAC_OK) return GAC_OK;
    return GAC_ERR_BAD_PARAMETER;
}

/* 1 if some contact of the model has friction. */
int gac_has_friction(const gac_model *m)
{
    int c;
    for (c = 0; c < m->ncontact; ++c) {
        if (m->contacts[c].has_friction) return 1;
    }
    return 0;
}

long gac_impact_nwork(const gac_model *m)
{
    return GAC_IMPACT_NWORK(m->nq, m->npoint, m->njrow, gac_has_friction(m));
}

long gac_sim_ndouble(const gac_model *m)
{
    return GAC_SIM_NDOUBLE(m->nq, m->nparam, m->nu, m->npoint, m->ncontact, m->njrow, gac_has_friction(m));
}

long gac_sim_nint(const gac_model *m)
{
    return GAC_SIM_NINT(m->nq, m->ncontact);
}

long gac_record_ndouble(const gac_model *m)
{
    return GAC_RECORD_NDOUBLE(m->nq);
}

long gac_record_nint(const gac_model *m)
{
    return GAC_RECORD_NINT(m->nq);
}

const char *gac_error_message(int code)
{
    switch (code) {
    case GAC_OK: return "ok";
    case GAC_ERR_BAD_CONTACT: return "bad contact set: empty, longer than NQ, repeated, or index outside 0..NCONTACT-1";
    case GAC_ERR_SINGULAR_MASS: return "inertia matrix I_f is singular to double precision (its solve by the articulated-body recursion is not finite): the chain's ratios of masses, lengths and inertias span more than 15 digits at this state";
    case GAC_ERR_SINGULAR_IMPACT: return "impact matrix J I_f^-1 J^T is singular: the constraints of the contact set are dependent";
    case GAC_ERR_LCP: return "impact complementarity problem has no solution (too many or degenerate contacts)";
    case GAC_ERR_GIMBAL_LOCK: return "gimbal lock: theta_0 is too close to the singularity of the base chart (|det E| below sqrt(16 eps / tol)) for results to the tolerance, and the run has no second chart to continue on (opt.chart_switch = 0, or a model without one: a base angle with an input, spring, damper or stop, or a planar model)";
    case GAC_ERR_BAD_OPTION: return "bad option or argument: allowed are method RK4, DOPRI5 or DOP853; RK4: 0 < dt < 1e300; DOPRI5, DOP853: 1e-14 (GAC_RTOL_MIN) <= rtol < 1, 0 < atol < 1e300, dt >= 0; h_max >= 0, event_samples >= 1, event_tol > 0, contact_tol >= 0, max_steps >= 0, rest_height < 1e300 (not NaN), zeno_impacts >= 0, 0 <= max_wall_time < 1e300, max_impacts >= 0, energy_tol < 1 (< 0: automatic, 0: off), chart_switch 0 or within [0.1, 0.35] (GAC_CHART_SWITCH_MIN, _MAX), impact_law GAC_IMPACT_LAW_FRICTIONLESS, _GDI or _NEWTON_COULOMB (gac_check_options names the option); t0, q and qd finite; sim_advance: t_end finite and >= the current time, n_eval >= 0, 0 <= *i_eval <= n_eval";
    case GAC_ERR_START_OUTSIDE: return "the start state has a contact point beyond its wall or a joint beyond its stop: allowed is a gap >= -(contact_tol + the simultaneity window + 1e-12 max(1 m, the largest |point coordinate|)), a point inside the box or on its wall";
    case GAC_ERR_NULL_ARGUMENT: return "a required pointer argument is NULL: sim_init needs sim, q and qd (and, in the library, the model and its work arrays; opt and p may be NULL: the defaults); sim_advance needs sim and record, and t_eval, i_eval and x_eval when n_eval > 0";
    case GAC_ERR_MAX_STEPS: return "maximum number of steps reached";
    case GAC_ERR_STEP_SIZE: return "step size underflow: the adaptive integrator cannot meet the tolerance";
    case GAC_ERR_NONFINITE: return "the state became NaN or infinite";
    case GAC_ERR_TOO_MANY_CONTACTS: return "more simultaneous approaching contacts than degrees of freedom";
    case GAC_ERR_SINGULAR_CONTACT: return "the resting contact constraints are dependent (N I_f^-1 N^T is singular)";
    case GAC_ERR_IMPACT_ACCURACY: return "the impact law could not be solved to round-off (an impulse < 0, a contact still approaching, an energy gain or an elastic energy change), or only to a round-off bound above GAC_IMPACT_ROUNDOFF_MAX = 1e-2 of the energy, or its elastic rounds (every contact e = 1) did not end: the impact system is ill-conditioned";
    case GAC_ERR_UNSTABLE: return "RK4 is unstable at this step: the chain's fastest mode needs dt below about 2.8 / its rate; reduce dt or use an adaptive method";
    case GAC_ERR_LOST_CONTACT: return "a point lies beyond its wall at an impact: a wall crossing was missed, the motion is too fast or I_f too ill-conditioned (extreme mass, length or inertia ratios) for the tolerance";
    case GAC_ERR_BAD_INPUT: return "an input is NaN or infinite: the inputs given to sim_set_input, and those a controller writes, must be finite";
    case GAC_ERR_IMPACT_FRICTION: return "the frictional impact law's solve (projected Gauss-Seidel over the contacts, each contact solved exactly) did not bring the law's conditions below GAC_FRICTION_RESIDUAL_MAX (1e-9, relative, or 16 eps cond(W) of the round's contact-space W where larger; record.residual says how far it got): contacts whose friction cones interact strongly; a smaller friction coefficient, or impact_law = frictionless, avoids it";
    case GAC_ERR_LINK_REST: return "two links would come to rest on each other (or a link on a fixed obstacle) where that contact cannot be held: its normal has no derivative there (crossing axes); it took zeno_impacts impacts in a row at shrinking intervals (where a wall's contact would land) or at one instant (stops on the joints between them keep links apart; a set point clear of an obstacle keeps a driven arm off it)";
    case GAC_ERR_LINK_LINE: return "a link resting on another link (or on a bar, or on a box's face) came to lie along it: its other end reached it while the held end stayed on it, a line contact that the pair's one-point contact cannot hold (it would let that end pass through)";
    case GAC_ERR_LINK_CONTACT: return "a contact of two links (a link pair) or of a link on an obstacle has no derivative of its geometry where the loop needs one: crossing axes, or a link lying parallel to a face or to the other link while not held";
    case GAC_ERR_IMPACT_ENERGY: return "the impact gained kinetic energy: Newton's restitution with Coulomb friction on the velocity after the impact (impact_law = newton-coulomb) can, when the slip reverses during the impact (Kane's rod); the default law (gdi) never does";
    case GAC_ERR_PAINLEVE_STALL: return "the resting contacts with Coulomb friction stay at the edge of the Painleve paradox: the steps met states without unique, bounded normal forces (a sliding point wedged by the others, its normal force growing without bound towards that edge) again and again (1000 times, GAC_PAINLEVE_STALL, since the last event or resolution) without ever reaching the edge, where the tangential impact would be taken; the motion follows the edge with unbounded forces at steps of its scale, which no budget covers; lower the friction coefficient";
    case GAC_ERR_FRICTION: return "the resting contacts with Coulomb friction have no unique, bounded normal forces at this state: their system B (the normal rows of I_f^-1 applied to the normal and friction directions) is no P-matrix (a principal minor <= 0), the Painleve paradox of sliding friction, and the tangential impact the hybrid loop takes there (the frictional impact law with the normal velocities 0 before, its non-trivial solution) has none either, or leaves a state as inconsistent; lower the friction coefficient";
    case GAC_ERR_BAD_MODEL: return "the model descriptor is inconsistent: nq >= 1, nx = 2 nq, npoint >= 1, ncontact, njrow, nparam, nu >= 0, every table and kernel present, each contact's kind, point, axis (a stop: its coordinate; a link pair: its two links, not adjacent, after every wall and stop), normal sign, Jacobian row and restitution index in range, each parameter_info row named with lo <= hi";
    case GAC_ERR_WALL_TIME: return "wall-time budget used up: the run took opt.max_wall_time seconds of its clock";
    case GAC_ERR_STOPPED: return "stopped by the progress callback";
    case GAC_ERR_MAX_IMPACTS: return "the max_impacts limit reached: opt.max_impacts impacts applied (raise it to go on)";
    case GAC_ERR_DRIFT: return "energy drift: the energy balance (E - E(0) - work of the inputs + what dampers, friction and impacts took) left more than energy_tol of the run's energy scale; the flight's integration error is beyond the tolerance: tighten rtol";
    case GAC_ERR_PROJECTION: return "projecting the state back onto the resting contacts changed the energy by more than energy_tol / 10 of the run's energy scale: the step left the constraints too far; tighten rtol";
    case GAC_ERR_BAD_PARAMETER: return "a parameter is outside its allowed range (not finite, beyond [lo, hi], or nonzero below the smallest normal double) or breaks a relation (a wall's max not above its min, a joint's upper limit not above its lower one, a rigid link's inertia not physical): gac_check_parameters gives its index, the model's parameter_info its name and the values it allows";
    default: return "unknown error code";
    }
}
