/*
 * gac_fmi2.h -- an FMI 2.0 Co-Simulation slave for any model of the gac library (gac.h).  Plain C99.
 *
 * gac_fmi2.c implements every function of the FMI 2.0 C interface for Co-Simulation (fmi2Instantiate,
 * fmi2DoStep, fmi2GetReal, ...) over one const gac_model.  The hybrid loop stays inside the FMU: each
 * fmi2DoStep integrates the flight phase, locates and applies every impact and keeps resting contacts, to the
 * end of the communication step.  A model's FMU adds one small generated file that defines
 * gac_fmi2_describe() (which model, its GUID) and a modelDescription.xml that names the variables below.
 *
 * Value references.  With nq, nu, nparam of the model (gac_model), Real variables are numbered
 *
 *   [0, nq)                     q        output      the generalised coordinates (m or rad)
 *   [nq, 2 nq)                  qd       output      their rates (m/s or rad/s)
 *   [2 nq, 2 nq + nu)           u        input       generalised forces of the actuated coordinates (N or N m),
 *                                                    held over each communication step (start 0)
 *   then nparam                 p        parameter   the model's parameters (fixed; start: the scene's)
 *   then nq                     q0       parameter   initial coordinates (fixed; start: the scene's)
 *   then nq                     qd0      parameter   initial rates (fixed; start: the scene's)
 *   then GAC_FMI2_NSOLVER_REAL  solver   parameter   rtol, atol, dt (s), h_max (s) of gac_options (fixed)
 *   then GAC_FMI2_NOUT_REAL     energy   output      kinetic, potential (J), the inputs' work, the dampers'
 *                                                    dissipation, the impacts' losses and what sliding friction
 *                                                    took since the start (J)
 *
 * and Integer variables 0 = solver method (parameter, GAC_METHOD_*), 1 = impacts since the start (output),
 * 2 = resting contacts now (output).  There are no Boolean or String variables.
 *
 * Energy balance: kinetic + potential + impact losses + dissipation + friction - work of the inputs stays equal
 * to its value at the start (to the integration tolerance).
 *
 * Memory: every allocation goes through the importer's allocateMemory / freeMemory (at fmi2Instantiate and
 * fmi2GetFMUstate); fmi2DoStep allocates nothing.  Instances share nothing: one per thread.
 */
#ifndef GAC_FMI2_H
#define GAC_FMI2_H

#include "gac.h"

#define GAC_FMI2_NSOLVER_REAL 4   /* rtol, atol, dt, h_max */
#define GAC_FMI2_NOUT_REAL    6   /* kinetic, potential, work_input, work_damping, impact_loss, friction */
#define GAC_FMI2_NINTEGER     3   /* method, impacts, resting contacts */

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
