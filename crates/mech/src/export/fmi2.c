/* FMI 2.0 wrapper for the C99 file `lagrange export --to c` writes: appended
 * after that file (with the three defines below filled in), it turns the model
 * into one FMU binary for both Model Exchange and Co-Simulation, exporting the
 * standard fmi2* functions without a prefix. It needs no FMI header; the FMI
 * 2.0 types are declared here as the standard's ABI defines them.
 *
 * Value references, with N = LAGRANGE_N, P = LAGRANGE_N_PARAMETERS,
 * NU = LAGRANGE_N_INPUTS and NOUT = 1 + FMU_HAS_ENERGY:
 *   0 .. 2N-1        the continuous states q, then q'
 *   2N .. 4N-1       their derivatives q', then q''
 *   4N .. 4N+P-1     the parameters (tunable)
 *   next NU          the inputs u (their default expression in t until set)
 *   next NOUT        the outputs: h, then the energy T + U0 when FMU_HAS_ENERGY
 *   next 1           solver.tolerance (Co-Simulation rtol = atol, tunable)
 * Optionally `#define FMU_START_STATE {q..., q'...}` before this file's
 * definitions gives the states' start values (else they start at 0).
 */
#define FMU_GUID "@GUID@"
#define FMU_HAS_ENERGY @HAS_ENERGY@
#define FMU_DEFAULT_TOLERANCE @TOLERANCE@

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- FMI 2.0 types (fmi2TypesPlatform.h, fmi2FunctionTypes.h) ---- */
typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char *fmi2String;
typedef char fmi2Byte;
#define fmi2True 1
#define fmi2False 0

typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum { fmi2DoStepStatus, fmi2PendingStatus, fmi2LastSuccessfulTime, fmi2Terminated } fmi2StatusKind;

typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...);
typedef void *(*fmi2CallbackAllocateMemory)(size_t, size_t);
typedef void (*fmi2CallbackFreeMemory)(void *);
typedef void (*fmi2StepFinished)(fmi2ComponentEnvironment, fmi2Status);

typedef struct {
    const fmi2CallbackLogger logger;
    const fmi2CallbackAllocateMemory allocateMemory;
    const fmi2CallbackFreeMemory freeMemory;
    const fmi2StepFinished stepFinished;
    const fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

typedef struct {
    fmi2Boolean newDiscreteStatesNeeded;
    fmi2Boolean terminateSimulation;
    fmi2Boolean nominalsOfContinuousStatesChanged;
    fmi2Boolean valuesOfContinuousStatesChanged;
    fmi2Boolean nextEventTimeDefined;
    fmi2Real nextEventTime;
} fmi2EventInfo;

#if defined(_WIN32)
#define FMU_EXPORT __declspec(dllexport)
#elif defined(__GNUC__)
#define FMU_EXPORT __attribute__((visibility("default")))
#else
#define FMU_EXPORT
#endif

/* ---- the value-reference layout ---- */
#ifndef LAGRANGE_N_INPUTS
#define LAGRANGE_N_INPUTS 0
#endif
#define FMU_NX (2 * LAGRANGE_N)
#define FMU_N_OUTPUTS (1 + FMU_HAS_ENERGY)
#define FMU_VR_DERIVATIVES FMU_NX
#define FMU_VR_PARAMETERS (2 * FMU_NX)
#define FMU_VR_INPUTS (FMU_VR_PARAMETERS + LAGRANGE_N_PARAMETERS)
#define FMU_VR_OUTPUTS (FMU_VR_INPUTS + LAGRANGE_N_INPUTS)
#define FMU_VR_TOLERANCE (FMU_VR_OUTPUTS + FMU_N_OUTPUTS)
#define FMU_N_VR (FMU_VR_TOLERANCE + 1)
/* Arrays of the inputs keep at least one element (C has no empty arrays). */
#define FMU_NU_ARRAY (LAGRANGE_N_INPUTS > 0 ? LAGRANGE_N_INPUTS : 1)

#ifndef FMU_START_STATE
#define FMU_START_STATE {0.0}
#endif
static const double fmu_start_state[FMU_NX] = FMU_START_STATE;

/* One instance. */
typedef struct {
    const char *name;                         /* stored right after the struct */
    fmi2Type type;
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment env;
    int env_memory;                           /* 1: from the environment's allocateMemory */
    fmi2CallbackFreeMemory free_memory;
    int debug_logging;
    double t;
    double x[FMU_NX];                         /* [q, q'] */
    double params[LAGRANGE_N_PARAMETERS + 1]; /* + 1: never empty */
    double u[FMU_NU_ARRAY];                   /* inputs set by the environment */
    int u_set[FMU_NU_ARRAY];                  /* 1 once fmi2SetReal set input i */
    double tolerance;                         /* Co-Simulation rtol = atol */
    double h_next;                            /* step size carried to the next doStep; 0: guess */
} Fmu;

/* ---- logging ---- */

/* Logs through the environment's logger: errors always (category "logError"),
 * anything else only with debug logging on ("logAll"). The message is
 * formatted here, and '%' doubled since the logger takes it as a format. */
static void fmu_log(const Fmu *c, fmi2Status status, const char *fmt, ...) {
    char text[512], escaped[1024];
    size_t i, j = 0;
    va_list args;
    if (c == NULL || c->logger == NULL) return;
    if (status < fmi2Error && !c->debug_logging) return;
    va_start(args, fmt);
    vsnprintf(text, sizeof text, fmt, args);
    va_end(args);
    for (i = 0; text[i] != '\0' && j + 2 < sizeof escaped; i++) {
        if (text[i] == '%') escaped[j++] = '%';
        escaped[j++] = text[i];
    }
    escaped[j] = '\0';
    c->logger(c->env, c->name, status, status >= fmi2Error ? "logError" : "logAll", escaped);
}

/* An unsupported function: logs and fails. */
static fmi2Status fmu_unsupported(fmi2Component c, const char *function) {
    fmu_log((Fmu *)c, fmi2Error, "%s is not supported by this FMU", function);
    return fmi2Error;
}

/* ---- the model ---- */

/* The instantiated values: start states, default parameters and tolerance. */
static void fmu_defaults(Fmu *c) {
    c->t = 0.0;
    memcpy(c->x, fmu_start_state, sizeof c->x);
    memcpy(c->params, lagrange_parameter_defaults, sizeof c->params);
    memset(c->u, 0, sizeof c->u);
    memset(c->u_set, 0, sizeof c->u_set);
    c->tolerance = FMU_DEFAULT_TOLERANCE;
    c->h_next = 0.0;
}

#if LAGRANGE_N_INPUTS > 0
/* The inputs at (t, x): the value set by the environment, else the default. */
static void fmu_inputs(const Fmu *c, double t, const double *x, double *u) {
    int i;
    lagrange_inputs(t, x, c->params, u);
    for (i = 0; i < LAGRANGE_N_INPUTS; i++)
        if (c->u_set[i]) u[i] = c->u[i];
}
#endif

/* dx = [q', q''] at (t, x); non-zero where the model's rhs fails. */
static int fmu_rhs(const Fmu *c, double t, const double *x, double *dx) {
#if LAGRANGE_N_INPUTS > 0
    double u[LAGRANGE_N_INPUTS];
    fmu_inputs(c, t, x, u);
    return lagrange_rhs_u(t, x, c->params, u, dx);
#else
    return lagrange_rhs(t, x, c->params, dx);
#endif
}

/* The derivatives at the instance's (t, x), logging a failure. */
static fmi2Status fmu_derivatives(const Fmu *c, double *dx) {
    int code = fmu_rhs(c, c->t, c->x, dx);
    if (code != 0) {
        fmu_log(c, fmi2Error, "the right-hand side failed at t = %.17g (code %d: %s)", c->t, code,
                code == 1 ? "singular mass matrix" : "a value is not finite");
        return fmi2Error;
    }
    return fmi2OK;
}

/* ---- the Co-Simulation integrator: Dormand-Prince 5(4) ---- */

static const double dp_c[7] = {0.0, 1.0 / 5, 3.0 / 10, 4.0 / 5, 8.0 / 9, 1.0, 1.0};
static const double dp_a[7][6] = {
    {0, 0, 0, 0, 0, 0},
    {1.0 / 5, 0, 0, 0, 0, 0},
    {3.0 / 40, 9.0 / 40, 0, 0, 0, 0},
    {44.0 / 45, -56.0 / 15, 32.0 / 9, 0, 0, 0},
    {19372.0 / 6561, -25360.0 / 2187, 64448.0 / 6561, -212.0 / 729, 0, 0},
    {9017.0 / 3168, -355.0 / 33, 46732.0 / 5247, 49.0 / 176, -5103.0 / 18656, 0},
    {35.0 / 384, 0, 500.0 / 1113, 125.0 / 192, -2187.0 / 6784, 11.0 / 84}}; /* = b (FSAL) */
/* The 5th-order weights minus the embedded 4th-order ones. */
static const double dp_e[7] = {71.0 / 57600, 0, -71.0 / 16695, 71.0 / 1920, -17253.0 / 339200, 22.0 / 525, -1.0 / 40};

/* RMS norm of v scaled by tol (1 + |y|). */
static double fmu_norm(const double *v, const double *y, double tol) {
    double s = 0.0;
    int i;
    for (i = 0; i < FMU_NX; i++) {
        double r = v[i] / (tol + tol * fabs(y[i]));
        s += r * r;
    }
    return sqrt(s / FMU_NX);
}

/* First step size (Hairer, Norsett & Wanner, II.4), at most span. */
static double fmu_first_step(const Fmu *c, double t, const double *y, const double *f0, double span) {
    double y1[FMU_NX], f1[FMU_NX], diff[FMU_NX];
    double d0 = fmu_norm(y, y, c->tolerance), d1 = fmu_norm(f0, y, c->tolerance), d2, h0, h1;
    int i;
    h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    if (h0 > span) h0 = span;
    for (i = 0; i < FMU_NX; i++) y1[i] = y[i] + h0 * f0[i];
    if (fmu_rhs(c, t + h0, y1, f1) != 0) return h0;
    for (i = 0; i < FMU_NX; i++) diff[i] = f1[i] - f0[i];
    d2 = fmu_norm(diff, y, c->tolerance) / h0;
    if (fmax(d1, d2) <= 1e-15) h1 = fmax(1e-6, h0 * 1e-3);
    else h1 = pow(0.01 / fmax(d1, d2), 1.0 / 5);
    return fmin(fmin(100 * h0, h1), span);
}

/* Integrates the instance from c->t to t_end. Each accepted step is stored at
 * once, so on failure the instance stays at the last good point. A trial step
 * in which the rhs fails is retried 4x shorter, down to underflow. */
static fmi2Status fmu_integrate(Fmu *c, double t_end) {
    double k[7][FMU_NX], ynew[FMU_NX], err[FMU_NX], scale[FMU_NX], h;
    int i, j, s, rejected = 0, code = 0;
    if (fmu_derivatives(c, k[0]) != fmi2OK) return fmi2Error;
    h = c->h_next > 0.0 ? c->h_next : fmu_first_step(c, c->t, c->x, k[0], t_end - c->t);
    while (c->t < t_end) {
        double t = c->t, hs = h, e, factor;
        int last = t + 1.01 * h >= t_end; /* then land exactly on t_end */
        if (!(h >= 16 * DBL_EPSILON * fmax(fabs(t), 1.0)) && !(h >= 0.5 * (t_end - t))) { /* or NaN */
            if (code != 0)
                fmu_log(c, fmi2Error, "the right-hand side failed (code %d: %s) near t = %.17g", code,
                        code == 1 ? "singular mass matrix" : "a value is not finite", t);
            else
                fmu_log(c, fmi2Error, "the step size underflowed at t = %.17g (h = %g)", t, h);
            return fmi2Error;
        }
        if (last) hs = t_end - t;
        /* stages 2..7; the 7th is f at the 5th-order solution */
        for (s = 1, code = 0; s < 7 && code == 0; s++) {
            for (i = 0; i < FMU_NX; i++) {
                double sum = 0.0;
                for (j = 0; j < s; j++) sum += dp_a[s][j] * k[j][i];
                ynew[i] = c->x[i] + hs * sum;
            }
            code = fmu_rhs(c, s == 6 ? t + hs : t + dp_c[s] * hs, ynew, k[s]);
        }
        if (code != 0) {
            fmu_log(c, fmi2OK, "the rhs failed in a trial step from t = %.17g; retrying with h = %g", t, hs / 4);
            h = hs / 4;
            rejected = 1;
            continue;
        }
        for (i = 0; i < FMU_NX; i++) {
            double sum = 0.0;
            for (j = 0; j < 7; j++) sum += dp_e[j] * k[j][i];
            err[i] = hs * sum;
            scale[i] = fmax(fabs(c->x[i]), fabs(ynew[i]));
        }
        e = fmu_norm(err, scale, c->tolerance);
        factor = fmin(fmax(e > 0.0 ? 0.9 * pow(e, -1.0 / 5) : 5.0, 0.2), 5.0);
        if (e <= 1.0) { /* accept: store the point, reuse f there (FSAL) */
            double proposed = hs * (rejected ? fmin(factor, 1.0) : factor);
            memcpy(c->x, ynew, sizeof c->x);
            memcpy(k[0], k[6], sizeof k[0]);
            c->t = last ? t_end : t + hs;
            h = last ? fmax(h, proposed) : proposed; /* a shortened step says little */
            rejected = 0;
        } else {
            h = hs * fmin(factor, 1.0);
            rejected = 1;
        }
    }
    c->h_next = h;
    return fmi2OK;
}

/* ---- common functions ---- */

FMU_EXPORT const char *fmi2GetTypesPlatform(void) { return "default"; }
FMU_EXPORT const char *fmi2GetVersion(void) { return "2.0"; }

FMU_EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                                          const fmi2String categories[]) {
    (void)nCategories; (void)categories;
    if (c == NULL) return fmi2Error;
    ((Fmu *)c)->debug_logging = loggingOn != fmi2False;
    return fmi2OK;
}

FMU_EXPORT fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                         fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                                         fmi2Boolean visible, fmi2Boolean loggingOn) {
    Fmu probe, *c;
    const char *name = instanceName != NULL ? instanceName : "";
    fmi2CallbackAllocateMemory allocate = functions != NULL ? functions->allocateMemory : NULL;
    size_t size = sizeof(Fmu) + strlen(name) + 1; /* the instance, then its name */
    (void)fmuResourceLocation; (void)visible;
    memset(&probe, 0, sizeof probe); /* for logging before the instance exists */
    probe.name = name;
    probe.logger = functions != NULL ? functions->logger : NULL;
    probe.env = functions != NULL ? functions->componentEnvironment : NULL;
    if (fmuGUID == NULL || strcmp(fmuGUID, FMU_GUID) != 0) {
        fmu_log(&probe, fmi2Error, "the GUID \"%s\" does not match this FMU's \"%s\"",
                fmuGUID != NULL ? fmuGUID : "(null)", FMU_GUID);
        return NULL;
    }
    if (fmuType != fmi2ModelExchange && fmuType != fmi2CoSimulation) {
        fmu_log(&probe, fmi2Error, "unknown FMU type %d", (int)fmuType);
        return NULL;
    }
    c = allocate != NULL ? allocate(1, size) : calloc(1, size);
    if (c == NULL) {
        fmu_log(&probe, fmi2Error, "out of memory");
        return NULL;
    }
    c->name = strcpy((char *)(c + 1), name);
    c->env_memory = allocate != NULL;
    c->free_memory = allocate != NULL ? functions->freeMemory : NULL;
    c->type = fmuType;
    c->logger = probe.logger;
    c->env = probe.env;
    c->debug_logging = loggingOn != fmi2False;
    fmu_defaults(c);
    fmu_log(c, fmi2OK, "instantiated (%s)", fmuType == fmi2CoSimulation ? "Co-Simulation" : "Model Exchange");
    return c;
}

/* Frees with the environment's freeMemory what its allocateMemory gave. */
FMU_EXPORT void fmi2FreeInstance(fmi2Component c) {
    Fmu *fmu = (Fmu *)c;
    if (fmu == NULL) return;
    if (!fmu->env_memory) free(fmu);
    else if (fmu->free_memory != NULL) fmu->free_memory(fmu);
}

/* The start time becomes the current time; a defined tolerance becomes the
 * Co-Simulation tolerance (a later set of solver.tolerance overrides it). */
FMU_EXPORT fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                                          fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    Fmu *fmu = (Fmu *)c;
    (void)stopTimeDefined; (void)stopTime;
    if (fmu == NULL) return fmi2Error;
    fmu->t = startTime;
    if (toleranceDefined && tolerance > 0.0) fmu->tolerance = tolerance;
    return fmi2OK;
}

FMU_EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component c) { return c != NULL ? fmi2OK : fmi2Error; }
FMU_EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component c) { return c != NULL ? fmi2OK : fmi2Error; }
FMU_EXPORT fmi2Status fmi2Terminate(fmi2Component c) { return c != NULL ? fmi2OK : fmi2Error; }

FMU_EXPORT fmi2Status fmi2Reset(fmi2Component c) {
    if (c == NULL) return fmi2Error;
    fmu_defaults((Fmu *)c);
    return fmi2OK;
}

/* Logs an out-of-range value reference. */
static fmi2Status fmu_bad_vr(const Fmu *c, fmi2ValueReference vr, const char *what) {
    fmu_log(c, fmi2Error, "%s: value reference %u is out of range (this FMU has %u Real variables 0..%u)",
            what, vr, (unsigned)FMU_N_VR, (unsigned)FMU_N_VR - 1);
    return fmi2Error;
}

FMU_EXPORT fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    Fmu *fmu = (Fmu *)c;
    double dx[FMU_NX];
    int have_dx = 0;
    size_t i;
    if (fmu == NULL) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        fmi2ValueReference r = vr[i];
        if (r < FMU_VR_DERIVATIVES) {
            value[i] = fmu->x[r];
        } else if (r < FMU_VR_PARAMETERS) {
            if (!have_dx && fmu_derivatives(fmu, dx) != fmi2OK) return fmi2Error;
            have_dx = 1;
            value[i] = dx[r - FMU_VR_DERIVATIVES];
        } else if (r < FMU_VR_INPUTS) {
            value[i] = fmu->params[r - FMU_VR_PARAMETERS];
        } else if (r < FMU_VR_OUTPUTS) {
#if LAGRANGE_N_INPUTS > 0
            double u[LAGRANGE_N_INPUTS];
            fmu_inputs(fmu, fmu->t, fmu->x, u);
            value[i] = u[r - FMU_VR_INPUTS];
#endif
        } else if (r == FMU_VR_OUTPUTS) {
            value[i] = lagrange_hamiltonian(fmu->t, fmu->x, fmu->params);
#if FMU_HAS_ENERGY
        } else if (r == FMU_VR_OUTPUTS + 1) {
            value[i] = lagrange_energy(fmu->t, fmu->x, fmu->params);
#endif
        } else if (r == FMU_VR_TOLERANCE) {
            value[i] = fmu->tolerance;
        } else {
            return fmu_bad_vr(fmu, r, "fmi2GetReal");
        }
    }
    return fmi2OK;
}

/* States, parameters, inputs and the tolerance can be set in any mode. */
FMU_EXPORT fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    Fmu *fmu = (Fmu *)c;
    size_t i;
    if (fmu == NULL) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        fmi2ValueReference r = vr[i];
        if (r < FMU_VR_DERIVATIVES) {
            fmu->x[r] = value[i];
        } else if (r < FMU_VR_PARAMETERS) {
            fmu_log(fmu, fmi2Error, "fmi2SetReal: value reference %u is a state derivative and cannot be set", r);
            return fmi2Error;
        } else if (r < FMU_VR_INPUTS) {
            fmu->params[r - FMU_VR_PARAMETERS] = value[i];
        } else if (r < FMU_VR_OUTPUTS) {
            fmu->u[r - FMU_VR_INPUTS] = value[i];
            fmu->u_set[r - FMU_VR_INPUTS] = 1;
        } else if (r < FMU_VR_TOLERANCE) {
            fmu_log(fmu, fmi2Error, "fmi2SetReal: value reference %u is an output and cannot be set", r);
            return fmi2Error;
        } else if (r == FMU_VR_TOLERANCE) {
            if (!(value[i] > 0.0 && value[i] < 1.0)) {
                fmu_log(fmu, fmi2Error, "fmi2SetReal: solver.tolerance must lie in (0, 1), not %g", value[i]);
                return fmi2Error;
            }
            fmu->tolerance = value[i];
        } else {
            return fmu_bad_vr(fmu, r, "fmi2SetReal");
        }
    }
    return fmi2OK;
}

/* No Integer, Boolean or String variables. */
static fmi2Status fmu_no_variables(fmi2Component c, size_t nvr, const fmi2ValueReference vr[], const char *function) {
    if (c == NULL) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    fmu_log((Fmu *)c, fmi2Error, "%s: no such variable (value reference %u)", function, vr[0]);
    return fmi2Error;
}

/* Get/Set of Integer, Boolean and String: only nvr = 0 succeeds. */
#define FMU_NO_VARIABLES(function, type)                                                                   \
    FMU_EXPORT fmi2Status function(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, type v[]) { \
        (void)v;                                                                                           \
        return fmu_no_variables(c, nvr, vr, #function);                                                    \
    }
FMU_NO_VARIABLES(fmi2GetInteger, fmi2Integer)
FMU_NO_VARIABLES(fmi2GetBoolean, fmi2Boolean)
FMU_NO_VARIABLES(fmi2GetString, fmi2String)
FMU_NO_VARIABLES(fmi2SetInteger, const fmi2Integer)
FMU_NO_VARIABLES(fmi2SetBoolean, const fmi2Boolean)
FMU_NO_VARIABLES(fmi2SetString, const fmi2String)

/* FMU states and directional derivatives are not provided (capability flags false). */
FMU_EXPORT fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    (void)state;
    return fmu_unsupported(c, "fmi2GetFMUstate");
}
FMU_EXPORT fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    (void)state;
    return fmu_unsupported(c, "fmi2SetFMUstate");
}
FMU_EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    (void)state;
    return fmu_unsupported(c, "fmi2FreeFMUstate");
}
FMU_EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    (void)state; (void)size;
    return fmu_unsupported(c, "fmi2SerializedFMUstateSize");
}
FMU_EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    (void)state; (void)bytes; (void)size;
    return fmu_unsupported(c, "fmi2SerializeFMUstate");
}
FMU_EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                              fmi2FMUstate *state) {
    (void)bytes; (void)size; (void)state;
    return fmu_unsupported(c, "fmi2DeSerializeFMUstate");
}
FMU_EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference unknowns[],
                                                   size_t nUnknown, const fmi2ValueReference knowns[],
                                                   size_t nKnown, const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    (void)unknowns; (void)nUnknown; (void)knowns; (void)nKnown; (void)dvKnown; (void)dvUnknown;
    return fmu_unsupported(c, "fmi2GetDirectionalDerivative");
}

/* ---- Model Exchange ---- */

FMU_EXPORT fmi2Status fmi2EnterEventMode(fmi2Component c) { return c != NULL ? fmi2OK : fmi2Error; }

/* No events: nothing to update, no time event, no termination. */
FMU_EXPORT fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *eventInfo) {
    if (c == NULL || eventInfo == NULL) return fmi2Error;
    memset(eventInfo, 0, sizeof *eventInfo); /* every flag fmi2False, nextEventTime 0 */
    return fmi2OK;
}

FMU_EXPORT fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { return c != NULL ? fmi2OK : fmi2Error; }

FMU_EXPORT fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                                  fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    if (c == NULL) return fmi2Error;
    if (enterEventMode != NULL) *enterEventMode = fmi2False;
    if (terminateSimulation != NULL) *terminateSimulation = fmi2False;
    return fmi2OK;
}

FMU_EXPORT fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    if (c == NULL) return fmi2Error;
    ((Fmu *)c)->t = time;
    return fmi2OK;
}

/* Checks that the environment's nx is the number of states. */
static fmi2Status fmu_check_nx(const Fmu *c, size_t nx, const char *function) {
    if (nx == FMU_NX) return fmi2OK;
    fmu_log(c, fmi2Error, "%s: nx = %u, but this FMU has %u continuous states", function, (unsigned)nx,
            (unsigned)FMU_NX);
    return fmi2Error;
}

FMU_EXPORT fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    Fmu *fmu = (Fmu *)c;
    if (fmu == NULL || fmu_check_nx(fmu, nx, "fmi2SetContinuousStates") != fmi2OK) return fmi2Error;
    memcpy(fmu->x, x, sizeof fmu->x);
    return fmi2OK;
}

FMU_EXPORT fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    Fmu *fmu = (Fmu *)c;
    if (fmu == NULL || fmu_check_nx(fmu, nx, "fmi2GetContinuousStates") != fmi2OK) return fmi2Error;
    memcpy(x, fmu->x, sizeof fmu->x);
    return fmi2OK;
}

FMU_EXPORT fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    Fmu *fmu = (Fmu *)c;
    if (fmu == NULL || fmu_check_nx(fmu, nx, "fmi2GetDerivatives") != fmi2OK) return fmi2Error;
    return fmu_derivatives(fmu, derivatives);
}

FMU_EXPORT fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    size_t i;
    if (c == NULL || fmu_check_nx((Fmu *)c, nx, "fmi2GetNominalsOfContinuousStates") != fmi2OK) return fmi2Error;
    for (i = 0; i < nx; i++) x_nominal[i] = 1.0;
    return fmi2OK;
}

/* No event indicators. */
FMU_EXPORT fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    (void)eventIndicators;
    if (c == NULL) return fmi2Error;
    if (ni == 0) return fmi2OK;
    fmu_log((Fmu *)c, fmi2Error, "fmi2GetEventIndicators: ni = %u, but this FMU has no event indicators",
            (unsigned)ni);
    return fmi2Error;
}

/* ---- Co-Simulation ---- */

FMU_EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                                  const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr; (void)nvr; (void)order; (void)value;
    return fmu_unsupported(c, "fmi2SetRealInputDerivatives (canInterpolateInputs is false)");
}

FMU_EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                                   const fmi2Integer order[], fmi2Real value[]) {
    (void)vr; (void)nvr; (void)order; (void)value;
    return fmu_unsupported(c, "fmi2GetRealOutputDerivatives (maxOutputDerivativeOrder is 0)");
}

/* Integrates from the current time to currentCommunicationPoint + h. */
FMU_EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                                 fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    Fmu *fmu = (Fmu *)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (fmu == NULL) return fmi2Error;
    if (fmu->type != fmi2CoSimulation) {
        fmu_log(fmu, fmi2Error, "fmi2DoStep: the instance was instantiated for Model Exchange");
        return fmi2Error;
    }
    if (!(communicationStepSize >= 0.0)) {
        fmu_log(fmu, fmi2Error, "fmi2DoStep: negative step size %g", communicationStepSize);
        return fmi2Error;
    }
    if (fabs(currentCommunicationPoint - fmu->t) > 1e-9 * fmax(1.0, fabs(fmu->t))) {
        fmu_log(fmu, fmi2Error, "fmi2DoStep: currentCommunicationPoint %.17g is not the FMU's time %.17g",
                currentCommunicationPoint, fmu->t);
        return fmi2Error;
    }
    if (communicationStepSize == 0.0) return fmi2OK;
    return fmu_integrate(fmu, currentCommunicationPoint + communicationStepSize);
}

FMU_EXPORT fmi2Status fmi2CancelStep(fmi2Component c) {
    return fmu_unsupported(c, "fmi2CancelStep (doStep never returns fmi2Pending)");
}

FMU_EXPORT fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    if (c == NULL) return fmi2Error;
    if (s != fmi2DoStepStatus) return fmi2Discard;
    *value = fmi2OK;
    return fmi2OK;
}

FMU_EXPORT fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    if (c == NULL) return fmi2Error;
    if (s != fmi2LastSuccessfulTime) return fmi2Discard;
    *value = ((Fmu *)c)->t;
    return fmi2OK;
}

/* No Integer, Boolean or String status. */
#define FMU_NO_STATUS(function, type)                                                      \
    FMU_EXPORT fmi2Status function(fmi2Component c, const fmi2StatusKind s, type *value) { \
        (void)s; (void)value;                                                              \
        return c != NULL ? fmi2Discard : fmi2Error;                                        \
    }
FMU_NO_STATUS(fmi2GetIntegerStatus, fmi2Integer)
FMU_NO_STATUS(fmi2GetBooleanStatus, fmi2Boolean)
FMU_NO_STATUS(fmi2GetStringStatus, fmi2String)
