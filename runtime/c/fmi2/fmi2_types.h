/*
 * fmi2_types.h -- the types and constants of the FMI 2.0 C interface (Functional Mock-up Interface for Model
 * Exchange and Co-Simulation, version 2.0, Modelica Association, 2014: section 2.1.2, "Platform dependent
 * definitions", and 2.1.3-2.1.5), written out from the standard's text so that an FMU can be built with no
 * other file.  An importer's own fmi2Functions.h declares the same ABI; gac_fmi2.c can be compiled against it
 * instead (define GAC_FMI2_STANDARD_HEADERS and put its folder on the include path).
 */
#ifndef GAC_FMI2_TYPES_H
#define GAC_FMI2_TYPES_H

#include <stddef.h>

typedef void *fmi2Component;               /* an FMU instance */
typedef void *fmi2ComponentEnvironment;    /* the importer's environment, handed back to its callbacks */
typedef void *fmi2FMUstate;                /* a saved internal state */
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char *fmi2String;
typedef char fmi2Byte;

#define fmi2True  1
#define fmi2False 0

typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum { fmi2DoStepStatus, fmi2PendingStatus, fmi2LastSuccessfulTime, fmi2Terminated } fmi2StatusKind;

typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment componentEnvironment, fmi2String instanceName,
                                   fmi2Status status, fmi2String category, fmi2String message, ...);
typedef void *(*fmi2CallbackAllocateMemory)(size_t nobj, size_t size);
typedef void (*fmi2CallbackFreeMemory)(void *obj);
typedef void (*fmi2StepFinished)(fmi2ComponentEnvironment componentEnvironment, fmi2Status status);

typedef struct {
    const fmi2CallbackLogger logger;
    const fmi2CallbackAllocateMemory allocateMemory;
    const fmi2CallbackFreeMemory freeMemory;
    const fmi2StepFinished stepFinished;
    const fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

#define fmi2TypesPlatform "default"
#define fmi2Version "2.0"

#endif
