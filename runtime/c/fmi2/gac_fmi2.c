/*
 * gac_fmi2.c -- the FMI 2.0 Co-Simulation interface over a gac_model (see gac_fmi2.h for the variables).
 *
 * States of an instance (FMI 2.0, section 4.2.4): instantiated -> initialization mode -> stepping ->
 * terminated, and error after a failed step.  Parameters and initial values may be set until the end of
 * initialization mode, each parameter within its range (the model's parameter_info); fmi2ExitInitializationMode
 * checks the parameters together (gac_check_parameters: the relations between them too), starts the simulation
 * (gac_sim_init) and reports a bad parameter, a start outside the box or a bad option by name.  Inputs may be set
 * between steps; each step holds them.
 */
#ifdef GAC_FMI2_STANDARD_HEADERS
#include "fmi2Functions.h"
#else
#include "fmi2_types.h"
#endif
#include "gac_fmi2.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(__GNUC__) && !defined(GAC_FMI2_STANDARD_HEADERS)
#  define GAC_FMI2_EXPORT __attribute__((visibility("default")))
#elif defined(_WIN32) && !defined(GAC_FMI2_STANDARD_HEADERS)
#  define GAC_FMI2_EXPORT __declspec(dllexport)
#else
#  define GAC_FMI2_EXPORT
#endif

enum { MODE_INSTANTIATED, MODE_INITIALIZATION, MODE_STEPPING, MODE_TERMINATED, MODE_ERROR };

/* The index of solver row `row` (GAC_FMI2_RTOL .. GAC_FMI2_HMAX) in Instance.solver. */
#define SOLVER(row) ((row) - GAC_FMI2_RTOL)

typedef struct {
    const gac_model *m;
    const gac_fmi2_description *d;
    fmi2CallbackLogger logger;
    fmi2CallbackAllocateMemory allocate_memory;
    fmi2CallbackFreeMemory free_memory;
    fmi2ComponentEnvironment environment;
    char *name;
    int logging;
    int mode;
    double t0;
    int tolerance_defined;       /* fmi2SetupExperiment gave a tolerance ... */
    double tolerance;
    int rtol_set, atol_set;      /* ... which rtol and atol follow unless they were set themselves */
    double *p, *q0, *qd0, *u;    /* nparam, nq, nq, nu */
    double solver[GAC_FMI2_NSOLVER_REAL];
    int method;
    int impact_law;
    int stick;
    long n_impacts;
    double loss_impacts;
    gac_sim sim;
    double *dwork;               /* gac_sim_ndouble(m) */
    int *iwork;                  /* gac_sim_nint(m) */
    gac_impact_record record;
    double *rdwork;              /* gac_record_ndouble(m) */
    int *riwork;                 /* gac_record_nint(m) */
} Instance;

/* A saved state (fmi2GetFMUstate): what a step changes. */
typedef struct {
    int mode;
    long n_impacts;
    double loss_impacts;
    gac_sim sim;
    double *dwork, *u;
    int *iwork;
} Snapshot;

/* The first value reference of Real row `row` of model m (the counts of the rows before it, gac_fmi2.h). */
static long vr_first(const gac_model *m, int row)
{
    long first = 0;
#define GAC_FMI2_ADD_COUNT(id, name, count, causality, variability, unit, start, what) \
    if (GAC_FMI2_##id < row) first += GAC_FMI2_COUNT_##count(m);
    GAC_FMI2_REALS(GAC_FMI2_ADD_COUNT)
#undef GAC_FMI2_ADD_COUNT
    return first;
}

#define GAC_FMI2_ROW_NAME(id, name, count, causality, variability, unit, start, what) name,
#define GAC_FMI2_ROW_START(id, name, count, causality, variability, unit, start, what) start,
static const char *const real_names[] = { GAC_FMI2_REALS(GAC_FMI2_ROW_NAME) };
static const double real_starts[] = { GAC_FMI2_REALS(GAC_FMI2_ROW_START) };
static const int integer_starts[] = { GAC_FMI2_INTEGERS(GAC_FMI2_ROW_START) };

long gac_fmi2_nreal(const gac_model *m)
{
    return vr_first(m, GAC_FMI2_NREAL_ROWS);
}

/* ---- logging ------------------------------------------------------------------------------------ */

/* Send one message (no printf directives of its own: '%' is written as "pct") to the importer's logger.
 * Errors are always sent; other messages only with logging on. */
static void say(const Instance *in, fmi2Status status, const char *category, const char *text)
{
    char message[1040];
    size_t k = 0;
    if (in == 0 || in->logger == 0) return;
    if (status < fmi2Error && !in->logging) return;
    for (; *text != '\0' && k + 4 < sizeof message; text++) {
        if (*text == '%') {
            memcpy(message + k, "pct", 3);
            k += 3;
        } else {
            message[k++] = *text;
        }
    }
    message[k] = '\0';
    in->logger(in->environment, in->name, status, category, message);
}

static fmi2Status fail(Instance *in, const char *function, const char *why)
{
    char text[480];
    snprintf(text, sizeof text, "%.60s: %.400s", function, why);
    say(in, fmi2Error, "logStatusError", text);
    return fmi2Error;
}

/* v with the fewest significant digits (up to 17) that give it back exactly. */
static void format_real(char *text, size_t size, double v)
{
    int digits;
    for (digits = 1; digits <= 17; digits++) {
        snprintf(text, size, "%.*g", digits, v);
        if (strtod(text, 0) == v) return;
    }
}

/* Why parameter i may not be v: "p.NAME = v: the rule in words" (the model's parameter_info). */
static void parameter_problem(const gac_model *m, int i, double v, char *why, size_t size)
{
    char value[32];
    format_real(value, sizeof value, v);
    if (m->parameter_info == 0) {
        snprintf(why, size, "parameter %d = %s is not allowed (finite values only)", i, value);
        return;
    }
    snprintf(why, size, "p.%.40s = %s: %.260s%s", m->parameter_info[i].name, value, m->parameter_info[i].range,
             v != 0.0 && fabs(v) < DBL_MIN ? " (nonzero below the smallest normal double: give 0 or a larger magnitude)"
                                           : "");
}

/* ---- value references --------------------------------------------------------------------------- */

static long vr_u(const gac_model *m) { return vr_first(m, GAC_FMI2_U); }
static long vr_p(const gac_model *m) { return vr_first(m, GAC_FMI2_P); }
static long vr_q0(const gac_model *m) { return vr_first(m, GAC_FMI2_Q0); }
static long vr_qd0(const gac_model *m) { return vr_first(m, GAC_FMI2_QD0); }
static long vr_solver(const gac_model *m) { return vr_first(m, GAC_FMI2_RTOL); }
static long vr_out(const gac_model *m) { return vr_first(m, GAC_FMI2_KINETIC); }

/* The state the outputs show: the simulation's once it runs (in chart A's coordinates, whichever base chart the
 * loop integrates: gac_sim_state), the initial values before.  q, qd: nq each. */
static void current_state(const Instance *in, double *q, double *qd)
{
    int i;
    if (in->mode == MODE_INSTANTIATED || in->mode == MODE_INITIALIZATION) {
        for (i = 0; i < in->m->nq; ++i) {
            q[i] = in->q0[i];
            qd[i] = in->qd0[i];
        }
    } else {
        gac_sim_state(&in->sim, 0, q, qd);
    }
}

static double real_value(const Instance *in, long r)
{
    const gac_model *m = in->m;
    double q[m->nq], qd[m->nq];
    current_state(in, q, qd);
    if (r < m->nq) return q[r];
    if (r < vr_u(m)) return qd[r - m->nq];
    if (r < vr_p(m)) return in->u[r - vr_u(m)];
    if (r < vr_q0(m)) return in->p[r - vr_p(m)];
    if (r < vr_qd0(m)) return in->q0[r - vr_q0(m)];
    if (r < vr_solver(m)) return in->qd0[r - vr_qd0(m)];
    if (r < vr_out(m)) return in->solver[r - vr_solver(m)];
    r = GAC_FMI2_KINETIC + (r - vr_out(m));          /* a row of one variable from here on */
    if (r == GAC_FMI2_KINETIC || r == GAC_FMI2_POTENTIAL) {
        double E[2];
        if (in->mode == MODE_INSTANTIATED || in->mode == MODE_INITIALIZATION) {
            m->energy(q, qd, in->p, E);
        } else {                        /* on the chart integrated now: chart A's rates grow near its lock */
            in->sim.model->energy(in->sim.x, in->sim.x + m->nq, in->p, E);
        }
        return E[r - GAC_FMI2_KINETIC];
    }
    if (in->mode == MODE_INSTANTIATED || in->mode == MODE_INITIALIZATION) return 0.0;
    if (r == GAC_FMI2_WORK_INPUT) return in->sim.work_input;
    if (r == GAC_FMI2_LOSS_DAMPING) return in->sim.loss_damping;
    if (r == GAC_FMI2_LOSS_FRICTION) return in->sim.loss_friction;
    return in->loss_impacts;                                  /* GAC_FMI2_LOSS_IMPACTS */
}

/* ---- instances ---------------------------------------------------------------------------------- */

static size_t align8(size_t n) { return (n + 7u) & ~(size_t)7u; }

GAC_FMI2_EXPORT const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
GAC_FMI2_EXPORT const char *fmi2GetVersion(void) { return fmi2Version; }

GAC_FMI2_EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                                               const fmi2String categories[])
{
    Instance *in = (Instance *)c;
    (void)nCategories;
    (void)categories;
    if (in == 0) return fmi2Error;
    in->logging = loggingOn ? 1 : 0;
    return fmi2OK;
}

/* Back to the state after fmi2Instantiate: the scene's parameters and initial state, the solver settings' starts
 * (their rows in gac_fmi2.h, gac_default_options' values). */
static void reset(Instance *in)
{
    const gac_model *m;
    int i;
    m = in->m;
    for (i = 0; i < m->nparam; i++) in->p[i] = m->default_parameters[i];
    for (i = 0; i < m->nq; i++) {
        in->q0[i] = m->q0[i];
        in->qd0[i] = m->qd0[i];
    }
    for (i = 0; i < m->nu; i++) in->u[i] = 0.0;
    for (i = GAC_FMI2_RTOL; i < GAC_FMI2_KINETIC; i++) in->solver[SOLVER(i)] = real_starts[i];
    in->method = integer_starts[GAC_FMI2_METHOD];
    in->impact_law = integer_starts[GAC_FMI2_IMPACT_LAW];
    in->stick = integer_starts[GAC_FMI2_STICK];
    in->tolerance_defined = 0;
    in->tolerance = 0.0;
    in->rtol_set = in->atol_set = 0;
    in->t0 = 0.0;
    in->n_impacts = 0;
    in->loss_impacts = 0.0;
    in->mode = MODE_INSTANTIATED;
}

GAC_FMI2_EXPORT fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                              fmi2String fmuResourceLocation,
                                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                                              fmi2Boolean loggingOn)
{
    const gac_fmi2_description *d = gac_fmi2_describe();
    const gac_model *m = d->model;
    Instance probe, *in;
    size_t name_len, ndouble, nint, bytes;
    char *block;
    (void)fmuResourceLocation;
    (void)visible;
    if (functions == 0 || functions->allocateMemory == 0 || functions->freeMemory == 0) return 0;
    memset(&probe, 0, sizeof probe);
    probe.logger = functions->logger;
    probe.environment = functions->componentEnvironment;
    probe.name = (char *)(instanceName ? instanceName : "?");
    if (instanceName == 0 || instanceName[0] == '\0') {
        fail(&probe, "fmi2Instantiate", "instanceName must be a non-empty string");
        return 0;
    }
    if (fmuType != fmi2CoSimulation) {
        fail(&probe, "fmi2Instantiate", "this FMU supports Co-Simulation only (fmuType must be fmi2CoSimulation)");
        return 0;
    }
    if (fmuGUID == 0 || strcmp(fmuGUID, d->guid) != 0) {
        fail(&probe, "fmi2Instantiate", "fmuGUID does not match the GUID of this FMU's modelDescription.xml");
        return 0;
    }
    if (gac_model_check(m) != GAC_OK) {
        fail(&probe, "fmi2Instantiate", gac_error_message(GAC_ERR_BAD_MODEL));
        return 0;
    }
    /* One block: the instance, its name, then the doubles and ints it owns. */
    name_len = strlen(instanceName) + 1;
    ndouble = (size_t)m->nparam + 2u * (size_t)m->nq + (size_t)m->nu + (size_t)gac_sim_ndouble(m)
              + (size_t)gac_record_ndouble(m);
    nint = (size_t)gac_sim_nint(m) + (size_t)gac_record_nint(m);
    bytes = align8(sizeof(Instance)) + align8(name_len) + ndouble * sizeof(double) + nint * sizeof(int);
    block = (char *)functions->allocateMemory(1, bytes);
    if (block == 0) {
        fail(&probe, "fmi2Instantiate", "allocateMemory returned NULL");
        return 0;
    }
    memset(block, 0, bytes);
    in = (Instance *)block;
    in->m = m;
    in->d = d;
    in->logger = functions->logger;
    in->allocate_memory = functions->allocateMemory;
    in->free_memory = functions->freeMemory;
    in->environment = functions->componentEnvironment;
    in->name = block + align8(sizeof(Instance));
    memcpy(in->name, instanceName, name_len);
    in->logging = loggingOn ? 1 : 0;
    in->p = (double *)(block + align8(sizeof(Instance)) + align8(name_len));
    in->q0 = in->p + m->nparam;
    in->qd0 = in->q0 + m->nq;
    in->u = in->qd0 + m->nq;
    in->dwork = in->u + m->nu;
    in->rdwork = in->dwork + gac_sim_ndouble(m);
    in->iwork = (int *)(in->rdwork + gac_record_ndouble(m));
    in->riwork = in->iwork + gac_sim_nint(m);
    reset(in);
    return in;
}

GAC_FMI2_EXPORT void fmi2FreeInstance(fmi2Component c)
{
    Instance *in = (Instance *)c;
    if (in != 0) in->free_memory(in);
}

GAC_FMI2_EXPORT fmi2Status fmi2Reset(fmi2Component c)
{
    if (c == 0) return fmi2Error;
    reset((Instance *)c);
    return fmi2OK;
}

GAC_FMI2_EXPORT fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    Instance *in = (Instance *)c;
    (void)stopTimeDefined;
    (void)stopTime;
    if (in == 0) return fmi2Error;
    if (in->mode != MODE_INSTANTIATED)
        return fail(in, "fmi2SetupExperiment", "allowed only after fmi2Instantiate or fmi2Reset");
    if (!isfinite(startTime)) return fail(in, "fmi2SetupExperiment", "startTime must be finite");
    if (toleranceDefined && !(tolerance > 0.0 && tolerance < 1.0))
        return fail(in, "fmi2SetupExperiment", "tolerance must be in (0, 1)");
    in->t0 = startTime;
    in->tolerance_defined = toleranceDefined ? 1 : 0;
    in->tolerance = tolerance;
    return fmi2OK;
}

GAC_FMI2_EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    Instance *in = (Instance *)c;
    if (in == 0) return fmi2Error;
    if (in->mode != MODE_INSTANTIATED)
        return fail(in, "fmi2EnterInitializationMode", "allowed only after fmi2Instantiate or fmi2Reset");
    in->mode = MODE_INITIALIZATION;
    return fmi2OK;
}

/* Start the hybrid loop at t0 with the initial values, parameters and options set so far.  The tolerance of
 * fmi2SetupExperiment gives rtol (and atol = tolerance / 100) unless solver.rtol (solver.atol) was set. */
GAC_FMI2_EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    Instance *in = (Instance *)c;
    gac_options opt;
    int code, bad = 0;
    char why[480], problem[420];
    if (in == 0) return fmi2Error;
    if (in->mode != MODE_INITIALIZATION)
        return fail(in, "fmi2ExitInitializationMode", "allowed only in initialization mode");
    if (gac_check_parameters(in->m, in->p, &bad) != GAC_OK) {        /* the parameters together: the relations too */
        parameter_problem(in->m, bad, in->p[bad], problem, sizeof problem);
        snprintf(why, sizeof why, "the simulation cannot start: %s", problem);
        return fail(in, "fmi2ExitInitializationMode", why);
    }
    if (in->tolerance_defined && !in->rtol_set) in->solver[SOLVER(GAC_FMI2_RTOL)] = in->tolerance;
    if (in->tolerance_defined && !in->atol_set) in->solver[SOLVER(GAC_FMI2_ATOL)] = in->tolerance / 100.0;
    gac_default_options(&opt);
    opt.method = in->method;
    opt.impact_law = in->impact_law;
    opt.stick = in->stick;
    opt.rtol = in->solver[SOLVER(GAC_FMI2_RTOL)];
    opt.atol = in->solver[SOLVER(GAC_FMI2_ATOL)];
    opt.dt = in->solver[SOLVER(GAC_FMI2_DT)];
    opt.h_max = in->solver[SOLVER(GAC_FMI2_HMAX)];
    opt.max_impacts = 0;          /* a co-simulation has no end the FMU knows of: the master bounds each step */
    code = gac_sim_init(&in->sim, in->m, in->dwork, in->iwork, in->t0, in->q0, in->qd0, in->p, &opt);
    if (code == GAC_OK && in->m->nu > 0) code = gac_sim_set_input(&in->sim, in->u);
    if (code != GAC_OK) {
        snprintf(why, sizeof why, "the simulation cannot start: %s", gac_error_message(code));
        return fail(in, "fmi2ExitInitializationMode", why);
    }
    gac_record_bind(&in->record, in->m, in->rdwork, in->riwork);
    in->n_impacts = 0;
    in->loss_impacts = 0.0;
    in->mode = MODE_STEPPING;
    return fmi2OK;
}

GAC_FMI2_EXPORT fmi2Status fmi2Terminate(fmi2Component c)
{
    Instance *in = (Instance *)c;
    if (in == 0) return fmi2Error;
    if (in->mode != MODE_STEPPING && in->mode != MODE_ERROR)
        return fail(in, "fmi2Terminate", "allowed only after initialization");
    in->mode = MODE_TERMINATED;
    return fmi2OK;
}

/* ---- getting and setting values ----------------------------------------------------------------- */

GAC_FMI2_EXPORT fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
    Instance *in = (Instance *)c;
    size_t k;
    if (in == 0) return fmi2Error;
    if (nvr > 0 && (vr == 0 || value == 0)) return fail(in, "fmi2GetReal", "vr and value must not be NULL");
    for (k = 0; k < nvr; k++) {
        if ((long)vr[k] >= gac_fmi2_nreal(in->m)) {
            char why[160];
            snprintf(why, sizeof why, "no Real variable has value reference %u (0..%ld)", vr[k],
                     gac_fmi2_nreal(in->m) - 1);
            return fail(in, "fmi2GetReal", why);
        }
        value[k] = real_value(in, (long)vr[k]);
    }
    return fmi2OK;
}

/* Set one Real; returns NULL or why it was refused. */
static const char *set_real(Instance *in, long r, double v, char *why, size_t size)
{
    const gac_model *m = in->m;
    int before_start = in->mode == MODE_INSTANTIATED || in->mode == MODE_INITIALIZATION;
    if (r < vr_u(m)) return "q and qd are outputs: set the initial values q0 and qd0 instead";
    if (!isfinite(v)) return "the value must be finite";
    if (r < vr_p(m)) {
        if (in->mode == MODE_TERMINATED || in->mode == MODE_ERROR) return "inputs cannot be set after the end";
        in->u[r - vr_u(m)] = v;
        if (in->mode == MODE_STEPPING && gac_sim_set_input(&in->sim, in->u) != GAC_OK) return "input refused";
        return 0;
    }
    if (r >= vr_out(m)) return "the energy outputs cannot be set";
    if (!before_start) return "parameters, initial values and solver settings are fixed after initialization";
    if (r < vr_q0(m)) {
        const int i = (int)(r - vr_p(m));
        if (in->d->bake_params) return "this FMU was built with its parameters baked into the code";
        if (m->parameter_info != 0 && !gac_in_range(v, m->parameter_info[i].lo, m->parameter_info[i].hi)) {
            parameter_problem(m, i, v, why, size);
            return why;
        }
        in->p[i] = v;
    } else if (r < vr_qd0(m)) {
        in->q0[r - vr_q0(m)] = v;
    } else if (r < vr_solver(m)) {
        in->qd0[r - vr_qd0(m)] = v;
    } else {
        const long row = GAC_FMI2_RTOL + (r - vr_solver(m));
        if (row < GAC_FMI2_RTOL || row >= GAC_FMI2_KINETIC) return "no such solver setting";
        if (row == GAC_FMI2_RTOL && !(v >= GAC_RTOL_MIN && v < 1.0))
            return "solver.rtol must be in [1e-14, 1) (GAC_RTOL_MIN: below it round-off stops the steps)";
        if (row == GAC_FMI2_ATOL && !(v > 0.0 && v < 1e300)) return "solver.atol must be in (0, 1e300)";
        if ((row == GAC_FMI2_DT || row == GAC_FMI2_HMAX) && v < 0.0) {
            snprintf(why, size, "%s must be >= 0 s (0: automatic / unbounded), got %g", real_names[row], v);
            return why;
        }
        in->solver[SOLVER(row)] = v;
        if (row == GAC_FMI2_RTOL) in->rtol_set = 1;
        if (row == GAC_FMI2_ATOL) in->atol_set = 1;
    }
    return 0;
}

GAC_FMI2_EXPORT fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Real value[])
{
    Instance *in = (Instance *)c;
    size_t k;
    if (in == 0) return fmi2Error;
    if (nvr > 0 && (vr == 0 || value == 0)) return fail(in, "fmi2SetReal", "vr and value must not be NULL");
    for (k = 0; k < nvr; k++) {
        char why[420], text[480];
        const char *refused;
        if ((long)vr[k] >= gac_fmi2_nreal(in->m)) {
            snprintf(text, sizeof text, "no Real variable has value reference %u (0..%ld)", vr[k],
                     gac_fmi2_nreal(in->m) - 1);
            return fail(in, "fmi2SetReal", text);
        }
        refused = set_real(in, (long)vr[k], value[k], why, sizeof why);
        if (refused != 0) {
            snprintf(text, sizeof text, "value reference %u: %s", vr[k], refused);
            return fail(in, "fmi2SetReal", text);
        }
    }
    return fmi2OK;
}

GAC_FMI2_EXPORT fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                          fmi2Integer value[])
{
    Instance *in = (Instance *)c;
    size_t k;
    if (in == 0) return fmi2Error;
    if (nvr > 0 && (vr == 0 || value == 0)) return fail(in, "fmi2GetInteger", "vr and value must not be NULL");
    for (k = 0; k < nvr; k++) {
        int stepping = in->mode != MODE_INSTANTIATED && in->mode != MODE_INITIALIZATION;
        if (vr[k] == GAC_FMI2_METHOD) value[k] = in->method;
        else if (vr[k] == GAC_FMI2_IMPACT_LAW) value[k] = in->impact_law;
        else if (vr[k] == GAC_FMI2_STICK) value[k] = in->stick;
        else if (vr[k] == GAC_FMI2_IMPACTS) value[k] = (fmi2Integer)in->n_impacts;
        else if (vr[k] == GAC_FMI2_RESTING) value[k] = stepping ? in->sim.nresting : 0;
        else if (vr[k] == GAC_FMI2_STICKS) value[k] = stepping ? (fmi2Integer)in->sim.n_sticks : 0;
        else if (vr[k] == GAC_FMI2_SLIPS) value[k] = stepping ? (fmi2Integer)in->sim.n_slips : 0;
        else if (vr[k] == GAC_FMI2_TANGENTIAL_IMPACTS) value[k] = stepping ? (fmi2Integer)in->sim.n_tangential_impacts : 0;
        else if (vr[k] == GAC_FMI2_PAINLEVE_CHOICES) value[k] = stepping ? (fmi2Integer)in->sim.n_painleve_choices : 0;
        else return fail(in, "fmi2GetInteger", "no Integer variable has this value reference");
    }
    return fmi2OK;
}

GAC_FMI2_EXPORT fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                          const fmi2Integer value[])
{
    Instance *in = (Instance *)c;
    size_t k;
    if (in == 0) return fmi2Error;
    if (nvr > 0 && (vr == 0 || value == 0)) return fail(in, "fmi2SetInteger", "vr and value must not be NULL");
    for (k = 0; k < nvr; k++) {
        if (vr[k] != GAC_FMI2_METHOD && vr[k] != GAC_FMI2_IMPACT_LAW && vr[k] != GAC_FMI2_STICK)
            return fail(in, "fmi2SetInteger", "only solver.method (value reference 0), solver.impact_law (1) and "
                                              "solver.stick (2) can be set");
        if (in->mode != MODE_INSTANTIATED && in->mode != MODE_INITIALIZATION)
            return fail(in, "fmi2SetInteger", vr[k] == GAC_FMI2_METHOD ? "solver.method is fixed after initialization"
                        : vr[k] == GAC_FMI2_STICK ? "solver.stick is fixed after initialization"
                                                  : "solver.impact_law is fixed after initialization");
        if (vr[k] == GAC_FMI2_STICK) {
            if (value[k] != 0 && value[k] != 1)
                return fail(in, "fmi2SetInteger", "solver.stick must be 1 (stick as a constraint) or 0 (regularised "
                                                  "friction alone)");
            in->stick = value[k];
        } else if (vr[k] == GAC_FMI2_METHOD) {
            if (value[k] != GAC_METHOD_RK4 && value[k] != GAC_METHOD_DOPRI5 && value[k] != GAC_METHOD_DOP853)
                return fail(in, "fmi2SetInteger", "solver.method must be 0 (RK4), 1 (DOPRI5) or 2 (DOP853)");
            in->method = value[k];
        } else {
            if (value[k] != GAC_IMPACT_LAW_FRICTIONLESS && value[k] != GAC_IMPACT_LAW_GDI
                && value[k] != GAC_IMPACT_LAW_NEWTON_COULOMB)
                return fail(in, "fmi2SetInteger", "solver.impact_law must be 0 (frictionless), 1 (GDI) or 2 (Newton + "
                                                  "Coulomb)");
            in->impact_law = value[k];
        }
    }
    return fmi2OK;
}

static fmi2Status no_variables(Instance *in, size_t nvr, const char *function)
{
    if (in == 0) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    return fail(in, function, "this FMU has no variables of this type");
}

GAC_FMI2_EXPORT fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                          fmi2Boolean value[])
{
    (void)vr;
    (void)value;
    return no_variables((Instance *)c, nvr, "fmi2GetBoolean");
}

GAC_FMI2_EXPORT fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                          const fmi2Boolean value[])
{
    (void)vr;
    (void)value;
    return no_variables((Instance *)c, nvr, "fmi2SetBoolean");
}

GAC_FMI2_EXPORT fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                         fmi2String value[])
{
    (void)vr;
    (void)value;
    return no_variables((Instance *)c, nvr, "fmi2GetString");
}

GAC_FMI2_EXPORT fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                         const fmi2String value[])
{
    (void)vr;
    (void)value;
    return no_variables((Instance *)c, nvr, "fmi2SetString");
}

/* ---- saved states ------------------------------------------------------------------------------- */

/* A snapshot is one block from allocateMemory: the Snapshot, then the simulation's doubles and the inputs,
 * then its ints. */
GAC_FMI2_EXPORT fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    Instance *in = (Instance *)c;
    const gac_model *m;
    Snapshot *s;
    size_t nd, ni;
    if (in == 0) return fmi2Error;
    if (FMUstate == 0) return fail(in, "fmi2GetFMUstate", "FMUstate must not be NULL");
    if (in->mode != MODE_STEPPING) return fail(in, "fmi2GetFMUstate", "allowed only between steps");
    m = in->m;
    nd = (size_t)gac_sim_ndouble(m);
    ni = (size_t)gac_sim_nint(m);
    s = (Snapshot *)*FMUstate;
    if (s == 0) {
        char *block = (char *)in->allocate_memory(1, align8(sizeof(Snapshot))
                                                  + (nd + (size_t)m->nu) * sizeof(double) + ni * sizeof(int));
        if (block == 0) return fail(in, "fmi2GetFMUstate", "allocateMemory returned NULL");
        s = (Snapshot *)block;
        s->dwork = (double *)(block + align8(sizeof(Snapshot)));
        s->u = s->dwork + nd;
        s->iwork = (int *)(s->u + m->nu);
    }
    s->mode = in->mode;
    s->n_impacts = in->n_impacts;
    s->loss_impacts = in->loss_impacts;
    s->sim = in->sim;
    memcpy(s->dwork, in->dwork, nd * sizeof(double));
    memcpy(s->iwork, in->iwork, ni * sizeof(int));
    if (m->nu > 0) memcpy(s->u, in->u, (size_t)m->nu * sizeof(double));
    *FMUstate = s;
    return fmi2OK;
}

GAC_FMI2_EXPORT fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    Instance *in = (Instance *)c;
    const Snapshot *s = (const Snapshot *)FMUstate;
    const gac_model *m;
    if (in == 0) return fmi2Error;
    if (s == 0) return fail(in, "fmi2SetFMUstate", "FMUstate must not be NULL");
    if (in->mode != MODE_STEPPING && in->mode != MODE_ERROR)
        return fail(in, "fmi2SetFMUstate", "allowed only after initialization");
    m = in->m;
    in->mode = s->mode;
    in->n_impacts = s->n_impacts;
    in->loss_impacts = s->loss_impacts;
    in->sim = s->sim;
    memcpy(in->dwork, s->dwork, (size_t)gac_sim_ndouble(m) * sizeof(double));
    memcpy(in->iwork, s->iwork, (size_t)gac_sim_nint(m) * sizeof(int));
    if (m->nu > 0) memcpy(in->u, s->u, (size_t)m->nu * sizeof(double));
    gac_sim_bind(&in->sim, m, in->dwork, in->iwork);
    return fmi2OK;
}

GAC_FMI2_EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    Instance *in = (Instance *)c;
    if (in == 0) return fmi2Error;
    if (FMUstate == 0) return fail(in, "fmi2FreeFMUstate", "FMUstate must not be NULL");
    if (*FMUstate != 0) in->free_memory(*FMUstate);
    *FMUstate = 0;
    return fmi2OK;
}

GAC_FMI2_EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    (void)FMUstate;
    (void)size;
    return c ? fail((Instance *)c, "fmi2SerializedFMUstateSize", "not supported (canSerializeFMUstate=false)")
             : fmi2Error;
}

GAC_FMI2_EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                                 size_t size)
{
    (void)FMUstate;
    (void)serializedState;
    (void)size;
    return c ? fail((Instance *)c, "fmi2SerializeFMUstate", "not supported (canSerializeFMUstate=false)")
             : fmi2Error;
}

GAC_FMI2_EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                                   fmi2FMUstate *FMUstate)
{
    (void)serializedState;
    (void)size;
    (void)FMUstate;
    return c ? fail((Instance *)c, "fmi2DeSerializeFMUstate", "not supported (canSerializeFMUstate=false)")
             : fmi2Error;
}

GAC_FMI2_EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                                        size_t nKnown, const fmi2Real dvKnown[],
                                                        fmi2Real dvUnknown[])
{
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    return c ? fail((Instance *)c, "fmi2GetDirectionalDerivative",
                    "not supported (providesDirectionalDerivative=false)")
             : fmi2Error;
}

/* ---- co-simulation ------------------------------------------------------------------------------ */

GAC_FMI2_EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                                       const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr;
    (void)order;
    (void)value;
    if (c == 0) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    return fail((Instance *)c, "fmi2SetRealInputDerivatives",
                "not supported: inputs are held over each step (canInterpolateInputs=false)");
}

GAC_FMI2_EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                                        const fmi2Integer order[], fmi2Real value[])
{
    (void)vr;
    (void)order;
    (void)value;
    if (c == 0) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    return fail((Instance *)c, "fmi2GetRealOutputDerivatives", "not supported (maxOutputDerivativeOrder=0)");
}

/* Contact c's name as the model's NAME_contact_name gives it (O1/x2_min for point O_1 on the wall x2_min,
 * theta_2_upper for a joint's stop, L1-L3 for links 1 and 3 as capsules, L2/ball for link 2 on the obstacle ball),
 * written at text (size chars). */
static void contact_name(const gac_model *m, int c, char *text, size_t size)
{
    const gac_contact *k = &m->contacts[c];
    if (k->kind == GAC_CONTACT_STOP)
        snprintf(text, size, "theta_%d_%s", k->point, k->normal_sign > 0 ? "lower" : "upper");
    else if (k->kind == GAC_CONTACT_LINK)
        snprintf(text, size, "L%d-L%d", k->point, k->coordinate);
    else if (k->kind == GAC_CONTACT_OBSTACLE)
        snprintf(text, size, "L%d/%s", k->point, m->obstacle_names[k->coordinate]);
    else
        snprintf(text, size, "O%d/x%d_%s", k->point, k->axis + 1, k->normal_sign > 0 ? "min" : "max");
}

/* The logEvents line of the impact in record: its time, its contacts by name (contact_name) and the energy. */
static void impact_message(const gac_model *m, const gac_impact_record *r, char *text, size_t size)
{
    size_t used;
    int k;
    snprintf(text, size, "impact at t = %.17g s: %d contacts", r->t, r->ncontact);
    for (k = 0; k < r->ncontact; ++k) {
        used = strlen(text);
        if (used + 100 >= size) {                 /* room kept for the energy below */
            snprintf(text + used, size - used, " ...");
            break;
        }
        text[used] = ' ';
        contact_name(m, r->contact[k], text + used + 1, size - used - 1);
    }
    used = strlen(text);
    snprintf(text + used, size - used, ", energy %.17g -> %.17g J", r->energy_before, r->energy_after);
}

/* The logEvents lines of the resting contacts the record changed, one per contact and in the record's order: "rest",
 * "release", "stick" or "slip", "at t = T s: " and its name (contact_name). */
static void log_contact_events(const Instance *in, const gac_impact_record *r)
{
    const char *kinds[4] = {"rest", "release", "stick", "slip"};
    const int counts[4] = {r->nlanded, r->nreleased, r->nstuck, r->nslipped};
    const int *lists[4] = {r->landed, r->released, r->stuck, r->slipped};
    char line[200];
    int j, k;
    for (j = 0; j < 4; ++j) {
        for (k = 0; k < counts[j]; ++k) {
            const int used = snprintf(line, sizeof line, "%s at t = %.17g s: ", kinds[j], r->t);
            contact_name(in->m, lists[j][k], line + used, sizeof line - (size_t)used);
            say(in, fmi2OK, "logEvents", line);
        }
    }
}

/* Advance from currentCommunicationPoint (the instance's time) by communicationStepSize: flight, impacts
 * and resting contacts, with the inputs held. */
GAC_FMI2_EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    Instance *in = (Instance *)c;
    double t_end;
    int code, i_eval = 0;
    char why[400];
    (void)noSetFMUStatePriorToCurrentPoint;
    if (in == 0) return fmi2Error;
    if (in->mode != MODE_STEPPING)
        return fail(in, "fmi2DoStep", in->mode == MODE_ERROR ? "an earlier step failed: reset or free the instance"
                                                             : "allowed only after initialization and before the end");
    if (!isfinite(communicationStepSize) || communicationStepSize < 0.0)
        return fail(in, "fmi2DoStep", "communicationStepSize must be finite and >= 0");
    if (!(fabs(currentCommunicationPoint - in->sim.t) <= 1e-12 * (1.0 + fabs(in->sim.t)))) {
        snprintf(why, sizeof why, "currentCommunicationPoint %.17g differs from the FMU's time %.17g",
                 currentCommunicationPoint, in->sim.t);
        return fail(in, "fmi2DoStep", why);
    }
    t_end = in->sim.t + communicationStepSize;
    for (;;) {
        code = gac_sim_advance(&in->sim, t_end, 0, 0, &i_eval, 0, &in->record);
        if (code == GAC_SIM_IMPACT) {
            in->n_impacts++;
            in->loss_impacts += in->record.energy_before - in->record.energy_after;
            if (in->logging) {
                char line[1024];
                impact_message(in->m, &in->record, line, sizeof line);
                say(in, fmi2OK, "logEvents", line);
            }
        } else if (code != GAC_SIM_CONTACT) {
            break;
        }
        if (in->logging) log_contact_events(in, &in->record);      /* after its impact's line */
    }
    if (code != GAC_SIM_END) {
        in->mode = MODE_ERROR;
        snprintf(why, sizeof why, "the simulation stopped at t = %.17g s: %s", in->sim.t, gac_error_message(code));
        return fail(in, "fmi2DoStep", why);
    }
    return fmi2OK;
}

GAC_FMI2_EXPORT fmi2Status fmi2CancelStep(fmi2Component c)
{
    return c ? fail((Instance *)c, "fmi2CancelStep", "not supported: steps are synchronous (canRunAsynchronuously=false)")
             : fmi2Error;
}

GAC_FMI2_EXPORT fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    Instance *in = (Instance *)c;
    if (in == 0 || value == 0) return fmi2Error;
    if (s != fmi2DoStepStatus) return fail(in, "fmi2GetStatus", "only fmi2DoStepStatus is reported");
    *value = in->mode == MODE_ERROR ? fmi2Error : fmi2OK;
    return fmi2OK;
}

GAC_FMI2_EXPORT fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    Instance *in = (Instance *)c;
    if (in == 0 || value == 0) return fmi2Error;
    if (s != fmi2LastSuccessfulTime) return fail(in, "fmi2GetRealStatus", "only fmi2LastSuccessfulTime is reported");
    *value = in->mode == MODE_INSTANTIATED || in->mode == MODE_INITIALIZATION ? in->t0 : in->sim.t;
    return fmi2OK;
}

GAC_FMI2_EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s;
    (void)value;
    return c ? fail((Instance *)c, "fmi2GetIntegerStatus", "no Integer status is reported") : fmi2Error;
}

GAC_FMI2_EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    Instance *in = (Instance *)c;
    if (in == 0 || value == 0) return fmi2Error;
    if (s != fmi2Terminated) return fail(in, "fmi2GetBooleanStatus", "only fmi2Terminated is reported");
    *value = fmi2False;
    return fmi2OK;
}

GAC_FMI2_EXPORT fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)s;
    (void)value;
    return c ? fail((Instance *)c, "fmi2GetStringStatus", "no String status is reported") : fmi2Error;
}
