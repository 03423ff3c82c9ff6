/*
 * gac_fmi2.h -- an FMI 2.0 Co-Simulation slave for any model of the gac library (gac.h).  Plain C99.
 *
 * gac_fmi2.c implements every function of the FMI 2.0 C interface for Co-Simulation (fmi2Instantiate,
 * fmi2DoStep, fmi2GetReal, ...) over one const gac_model.  The hybrid loop stays inside the FMU: each
 * fmi2DoStep integrates the flight phase, locates and applies every impact and keeps resting contacts, to the
 * end of the communication step.  A model's FMU adds one small generated file that defines
 * gac_fmi2_describe() (which model, its GUID) and a modelDescription.xml that names the variables below.
 *
 * Variables: the rows of GAC_FMI2_REALS and GAC_FMI2_INTEGERS below, their one description.  Real value references
 * run through the Real rows in order (a row of count nq takes nq of them, ...), Integer ones likewise from 0.  There
 * are no Boolean or String variables.
 *
 * Energy balance: kinetic + potential + loss_impacts + loss_damping + loss_friction - work_input stays equal
 * to its value at the start (to the integration tolerance).
 *
 * Memory: every allocation goes through the importer's allocateMemory / freeMemory (at fmi2Instantiate and
 * fmi2GetFMUstate); fmi2DoStep allocates nothing.  Instances share nothing: one per thread.
 */
#ifndef GAC_FMI2_H
#define GAC_FMI2_H

#include "gac.h"

/* ---- the variables, described once --------------------------------------------------------------------------
 * The slave numbers its value references by these rows; runtime/fmu.py reads them (runtime.header.fmi2_rows) for
 * the FMU's modelDescription.xml (codegen/fmu.py), and docs/fmi.md's variable table is rendered from them.
 * One row per variable or block of variables, in value-reference order:
 *     X(id, name, count, causality, variability, unit, start, what)
 *   name         the variable's name; in a block ("q.C", "p.NAME") C is each of the model's coordinates (those the
 *                specialised model keeps, or for u.C each actuated one) and NAME each parameter's name
 *   count        how many: nq, nu, nparam (the model's) or 1
 *   unit         an FMI unit ("s", "J"), "" for none, or each variable's own: "coordinate" (m or rad), "rate"
 *                (m/s or rad/s), "force" (N or N m), "parameter" (the parameter's)
 *   start        the value after fmi2Instantiate (the slave's reset); p, q0, qd0 start at the scene's values, and
 *                outputs have none
 *   what         the variable's description; in a block "%s" is its coordinate, or its parameter's description */
#define GAC_FMI2_REALS(X) \
    X(Q, "q.C", nq, "output", "continuous", "coordinate", 0.0, "coordinate %s") \
    X(QD, "qd.C", nq, "output", "continuous", "rate", 0.0, "rate of %s") \
    X(U, "u.C", nu, "input", "continuous", "force", 0.0, "generalised force on %s, held over each step") \
    X(P, "p.NAME", nparam, "parameter", "fixed", "parameter", 0.0, "%s") \
    X(Q0, "q0.C", nq, "parameter", "fixed", "coordinate", 0.0, "initial %s") \
    X(QD0, "qd0.C", nq, "parameter", "fixed", "rate", 0.0, "initial rate of %s") \
    X(RTOL, "solver.rtol", 1, "parameter", "fixed", "", 1e-8, \
      "relative tolerance of DOPRI5/DOP853 (default: the experiment's tolerance if one is given)") \
    X(ATOL, "solver.atol", 1, "parameter", "fixed", "", 1e-10, \
      "absolute tolerance of DOPRI5/DOP853 (default: the experiment's tolerance / 100 if one is given)") \
    X(DT, "solver.dt", 1, "parameter", "fixed", "s", 0.0, "RK4 step; the first step of DOPRI5/DOP853 (0: automatic)") \
    X(HMAX, "solver.h_max", 1, "parameter", "fixed", "s", 0.0, "largest step (0: unbounded)") \
    X(KINETIC, "energy.kinetic", 1, "output", "continuous", "J", 0.0, "kinetic energy T") \
    X(POTENTIAL, "energy.potential", 1, "output", "continuous", "J", 0.0, \
      "potential energy V (gravity and joint springs)") \
    X(WORK_INPUT, "energy.work_input", 1, "output", "continuous", "J", 0.0, "work of the inputs since the start") \
    X(LOSS_DAMPING, "energy.loss_damping", 1, "output", "continuous", "J", 0.0, \
      "energy the joint dampers took since the start") \
    X(LOSS_IMPACTS, "energy.loss_impacts", 1, "output", "continuous", "J", 0.0, \
      "kinetic energy the impacts took since the start") \
    X(LOSS_FRICTION, "energy.loss_friction", 1, "output", "continuous", "J", 0.0, \
      "energy sliding friction took at resting contacts since the start")
#define GAC_FMI2_INTEGERS(X) \
    X(METHOD, "solver.method", 1, "parameter", "fixed", "", GAC_METHOD_DOPRI5, \
      "integrator: GAC_METHOD_RK4 RK4 (fixed step solver.dt), GAC_METHOD_DOPRI5 DOPRI5, GAC_METHOD_DOP853 DOP853") \
    X(IMPACT_LAW, "solver.impact_law", 1, "parameter", "fixed", "", GAC_IMPACT_LAW_GDI, \
      "impact law at rough walls: GAC_IMPACT_LAW_FRICTIONLESS none, GAC_IMPACT_LAW_GDI GDI, GAC_IMPACT_LAW_NEWTON_COULOMB Newton + Coulomb") \
    X(STICK, "solver.stick", 1, "parameter", "fixed", "", 1, \
      "points resting on rough walls: 1 stick as a constraint, 0 regularised friction alone") \
    X(IMPACTS, "impacts", 1, "output", "discrete", "", 0, "impacts since the start") \
    X(RESTING, "resting_contacts", 1, "output", "discrete", "", 0, "contacts resting on their wall now") \
    X(STICKS, "sticks", 1, "output", "discrete", "", 0, \
      "points resting on rough walls that came to stick (sliding -> stuck) since the start") \
    X(SLIPS, "slips", 1, "output", "discrete", "", 0, "stuck points that began to slip since the start") \
    X(TANGENTIAL_IMPACTS, "tangential_impacts", 1, "output", "discrete", "", 0, \
      "tangential impacts (sliding resting contacts in the Painleve paradox) since the start, within impacts") \
    X(PAINLEVE_CHOICES, "painleve_choices", 1, "output", "discrete", "", 0, \
      "Painleve choices since the start: resting contacts without consistent sliding forces where another solution exists")

/* The rows' ids: GAC_FMI2_Q .. GAC_FMI2_LOSS_FRICTION (Real rows), GAC_FMI2_METHOD .. GAC_FMI2_PAINLEVE_CHOICES (Integer rows,
 * which are their value references). */
#define GAC_FMI2_ROW_ID(id, name, count, causality, variability, unit, start, what) GAC_FMI2_##id,
enum { GAC_FMI2_REALS(GAC_FMI2_ROW_ID) GAC_FMI2_NREAL_ROWS };
enum { GAC_FMI2_INTEGERS(GAC_FMI2_ROW_ID) GAC_FMI2_NINTEGER };
#define GAC_FMI2_NSOLVER_REAL (GAC_FMI2_KINETIC - GAC_FMI2_RTOL)     /* rtol, atol, dt, h_max */
/* A row's count for model m. */
#define GAC_FMI2_COUNT_nq(m) ((long)(m)->nq)
#define GAC_FMI2_COUNT_nu(m) ((long)(m)->nu)
#define GAC_FMI2_COUNT_nparam(m) ((long)(m)->nparam)
#define GAC_FMI2_COUNT_1(m) 1L

/* What the generated glue tells the slave about its model. */
typedef struct {
    const gac_model *model;
    const char *guid;        /* the GUID of modelDescription.xml; fmi2Instantiate refuses any other */
    int bake_params;         /* 1: the parameters are constants in the code; setting p is refused */
} gac_fmi2_description;

/* Defined by the model's generated NAME_fmi2.c. */
const gac_fmi2_description *gac_fmi2_describe(void);

/* The number of Real variables of model m (value references 0 .. gac_fmi2_nreal(m) - 1). */
long gac_fmi2_nreal(const gac_model *m);

#endif
