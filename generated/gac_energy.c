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
    s->energy_impacts = s->energy_projection = s->energy_residual = 0.0;
    s->energy_tol = gac_energy_tolerance(&s->opt);
}

/* The balance at the current state s->x, after a step end or an impact: its energy (s->energy_x), the scale and
 * the residual.  GAC_OK, or GAC_ERR_DRIFT when |residual| > energy_tol x scale. */
int gac_energy_check(gac_sim *s)
{
    double E[2], scale;
    s->model->energy(s->x, s->x + s->model->nq, s->p, E);
    s->energy_x = E[0] + E[1];
    if (E[0] + fabs(E[1]) > s->energy_scale) s->energy_scale = E[0] + fabs(E[1]);
    s->energy_residual = s->energy_x - s->energy_initial - s->work_input + s->work_damping + s->work_friction
                         + s->energy_impacts;
    scale = s->energy_scale + fabs(s->work_input) + s->work_damping + s->work_friction + fabs(s->energy_impacts);
    if (s->energy_tol > 0.0 && fabs(s->energy_residual) > s->energy_tol * scale) return GAC_ERR_DRIFT;
    return GAC_OK;
}

/* The energy change of a projection onto the resting contacts that took the state from energy E_before to x:
 * summed in s->energy_projection; GAC_ERR_PROJECTION when it exceeds energy_tol x scale / 10, else GAC_OK. */
int gac_energy_projected(gac_sim *s, double E_before, const double *x)
{
    const double change = gac_total_energy(s->model, x, s->p) - E_before;
    const double scale = s->energy_scale + fabs(s->work_input) + s->work_damping + s->work_friction
                         + fabs(s->energy_impacts);
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
    double E[2];
    if (md->power != 0 || s->nactive > 0 || !(s->energy_scale > 0.0)) return 0.0;
    md->energy(s->x1, s->x1 + md->nq, s->p, E);
    return fabs(E[0] + E[1] - s->energy_x) / (0.1 * s->opt.rtol * s->energy_scale);
}
