"""C text of the FMI 2.0 co-simulation wrapper around an exported model step (private).

:data:`FMI2_TYPES` declares the FMI 2.0 types the wrapper uses (the standard's C ABI: the values
of ``fmi2Real``, ``fmi2Status``, ``fmi2CallbackFunctions``, ...), so that the sources compile
without the standard's header files. :data:`WRAPPER` implements every function of the FMI 2.0
co-simulation interface over ``<name>_init`` / ``<name>_step`` (or ``<name>_inverse_step``).

Semantics of one instance (fixed communication step ``DT``): the state ``s`` holds the model
after the samples already taken. The outputs are those of the last sample, for every kind the
same rule: once the inputs of a communication point are set, the step applied to a copy of ``s``
with those inputs (the force has direct feedthrough), so reading them never changes the state;
before they are set (right after ``fmi2DoStep``), the outputs of the sample that step took.
``fmi2DoStep`` commits that copy (computing it if the outputs were not read) and moves time on by
``DT``. So a master that sets the inputs, reads the outputs, then steps gets every sample's force
as sampled; a master that reads the outputs right after ``fmi2DoStep`` (fmpy's ``simulate_fmu``)
gets, at every kind, the force of the previous sample: one communication step late. A
communication step other than ``DT`` is refused (``canHandleVariableCommunicationStepSize`` is
false); a non-finite output makes ``fmi2DoStep`` return ``fmi2Error``.
"""

from __future__ import annotations

__all__ = ["FMI2_TYPES", "WRAPPER"]

FMI2_TYPES = r"""/* {p}_fmi2.h: the FMI 2.0 types used by {p}_fmu.c (the standard's C ABI). */
#ifndef {P}_FMI2_H
#define {P}_FMI2_H
#include <stddef.h>

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

typedef enum {{ fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending }} fmi2Status;
typedef enum {{ fmi2ModelExchange, fmi2CoSimulation }} fmi2Type;
typedef enum {{
    fmi2DoStepStatus,
    fmi2PendingStatus,
    fmi2LastSuccessfulTime,
    fmi2Terminated
}} fmi2StatusKind;

typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String,
                                   fmi2String, ...);
typedef void *(*fmi2CallbackAllocateMemory)(size_t, size_t);
typedef void (*fmi2CallbackFreeMemory)(void *);
typedef void (*fmi2StepFinished)(fmi2ComponentEnvironment, fmi2Status);
typedef struct {{
    const fmi2CallbackLogger logger;
    const fmi2CallbackAllocateMemory allocateMemory;
    const fmi2CallbackFreeMemory freeMemory;
    const fmi2StepFinished stepFinished;
    const fmi2ComponentEnvironment componentEnvironment;
}} fmi2CallbackFunctions;
#endif /* {P}_FMI2_H */
"""

WRAPPER = r"""/* {p}_fmu.c: FMI 2.0 co-simulation interface of {p}.c, written by mrdamper. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "{p}_fmi2.h"
#include "{p}.h"

#define {P}_N_IN 3
#define {P}_N_OUT {n_out}
static const char *{P}_GUID = "{guid}";
static const double {P}_STEP = {dt}; /* fixed communication step [s] */

typedef struct {{
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment env;
    char *name;
    double time;
    double in[{P}_N_IN];
    double out[{P}_N_OUT];
    {p}_state s; /* after the samples taken */
    {p}_state next; /* s after the sample at the present inputs (valid when cached) */
    int cached;
    int fresh; /* inputs set since the last fmi2DoStep (or no step taken yet) */
}} {p}_instance;

static void {p}_log({p}_instance *c, fmi2Status status, const char *msg)
{{
    if (c && c->logger) c->logger(c->env, c->name, status, "logStatusError", "%s", msg);
}}

static void {p}_reset({p}_instance *c)
{{
    int j;
    c->time = 0.0;
    for (j = 0; j < {P}_N_IN; ++j) c->in[j] = 0.0;
    for (j = 0; j < {P}_N_OUT; ++j) c->out[j] = 0.0;
    {p}_init(&c->s);
    c->cached = 0;
    c->fresh = 1;
}}

/* outputs at the present inputs, from a copy of the state */
static void {p}_evaluate({p}_instance *c)
{{
    if (c->cached) return;
    c->next = c->s;
    {compute}
    c->cached = 1;
}}

const char *fmi2GetTypesPlatform(void) {{ return "default"; }}
const char *fmi2GetVersion(void) {{ return "2.0"; }}

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean on, size_t n,
                               const fmi2String categories[])
{{
    (void)comp;
    (void)on;
    (void)n;
    (void)categories;
    return fmi2OK;
}}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String resourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{{
    {p}_instance *c;
    size_t len;
    (void)resourceLocation;
    (void)visible;
    (void)loggingOn;
    if (fmuType != fmi2CoSimulation) return NULL;
    if (!fmuGUID || strcmp(fmuGUID, {P}_GUID) != 0) {{
        if (functions && functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError", "%s", "GUID does not match this FMU");
        return NULL;
    }}
    c = ({p}_instance *)calloc(1, sizeof({p}_instance));
    if (!c) return NULL;
    if (functions) {{
        c->logger = functions->logger;
        c->env = functions->componentEnvironment;
    }}
    len = instanceName ? strlen(instanceName) : 0;
    c->name = (char *)malloc(len + 1);
    if (!c->name) {{
        free(c);
        return NULL;
    }}
    if (len) memcpy(c->name, instanceName, len);
    c->name[len] = '\0';
    {p}_reset(c);
    return c;
}}

void fmi2FreeInstance(fmi2Component comp)
{{
    {p}_instance *c = ({p}_instance *)comp;
    if (!c) return;
    free(c->name);
    free(c);
}}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{{
    {p}_instance *c = ({p}_instance *)comp;
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (!c) return fmi2Error;
    c->time = startTime;
    return fmi2OK;
}}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp) {{ return comp ? fmi2OK : fmi2Error; }}
fmi2Status fmi2ExitInitializationMode(fmi2Component comp) {{ return comp ? fmi2OK : fmi2Error; }}
fmi2Status fmi2Terminate(fmi2Component comp) {{ return comp ? fmi2OK : fmi2Error; }}

fmi2Status fmi2Reset(fmi2Component comp)
{{
    {p}_instance *c = ({p}_instance *)comp;
    if (!c) return fmi2Error;
    {p}_reset(c);
    return fmi2OK;
}}

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{{
    {p}_instance *c = ({p}_instance *)comp;
    size_t j;
    if (!c) return fmi2Error;
    for (j = 0; j < nvr; ++j) {{
        if (vr[j] < {P}_N_IN) value[j] = c->in[vr[j]];
        else if (vr[j] < {P}_N_IN + {P}_N_OUT) {{
            if (c->fresh) {p}_evaluate(c); /* else: the outputs of the sample last taken */
            value[j] = c->out[vr[j] - {P}_N_IN];
        }} else {{
            {p}_log(c, fmi2Error, "fmi2GetReal: unknown value reference");
            return fmi2Error;
        }}
    }}
    return fmi2OK;
}}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{{
    {p}_instance *c = ({p}_instance *)comp;
    size_t j;
    if (!c) return fmi2Error;
    for (j = 0; j < nvr; ++j) {{
        if (vr[j] >= {P}_N_IN) {{
            {p}_log(c, fmi2Error, "fmi2SetReal: only the inputs can be set");
            return fmi2Error;
        }}
        if (c->in[vr[j]] != value[j]) c->cached = 0;
        c->in[vr[j]] = value[j];
        c->fresh = 1;
    }}
    return fmi2OK;
}}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{{
    {p}_instance *c = ({p}_instance *)comp;
    int j;
    (void)currentCommunicationPoint;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!c) return fmi2Error;
    if (fabs(communicationStepSize - {P}_STEP) > 1e-9 * {P}_STEP) {{
        {p}_log(c, fmi2Error, "fmi2DoStep: the communication step must be {dt_text} s");
        return fmi2Error;
    }}
    {p}_evaluate(c);
    for (j = 0; j < {P}_N_OUT; ++j) {{
        if (!isfinite(c->out[j])) {{
            {p}_log(c, fmi2Error, "fmi2DoStep: the model's state diverged (non-finite output)");
            return fmi2Error;
        }}
    }}
    c->s = c->next;
    c->cached = 0;
    c->fresh = 0;
    c->time += communicationStepSize;
    return fmi2OK;
}}

/* not supported: integers, booleans, strings, FMU states, derivatives, asynchronous steps */
#define {P}_UNSUPPORTED(call)                                                                  \
    do {{                                                                                      \
        {p}_log(({p}_instance *)comp, fmi2Error, call ": not supported by this FMU");          \
        return fmi2Error;                                                                      \
    }} while (0)

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{{
    (void)vr;
    (void)value;
    if (nvr == 0) return fmi2OK;
    {P}_UNSUPPORTED("fmi2GetInteger");
}}

fmi2Status fmi2GetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{{
    (void)vr;
    (void)value;
    if (nvr == 0) return fmi2OK;
    {P}_UNSUPPORTED("fmi2GetBoolean");
}}

fmi2Status fmi2GetString(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{{
    (void)vr;
    (void)value;
    if (nvr == 0) return fmi2OK;
    {P}_UNSUPPORTED("fmi2GetString");
}}

fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{{
    (void)vr;
    (void)value;
    if (nvr == 0) return fmi2OK;
    {P}_UNSUPPORTED("fmi2SetInteger");
}}

fmi2Status fmi2SetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{{
    (void)vr;
    (void)value;
    if (nvr == 0) return fmi2OK;
    {P}_UNSUPPORTED("fmi2SetBoolean");
}}

fmi2Status fmi2SetString(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{{
    (void)vr;
    (void)value;
    if (nvr == 0) return fmi2OK;
    {P}_UNSUPPORTED("fmi2SetString");
}}

fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *state)
{{
    (void)state;
    {P}_UNSUPPORTED("fmi2GetFMUstate");
}}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate state)
{{
    (void)state;
    {P}_UNSUPPORTED("fmi2SetFMUstate");
}}

fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate *state)
{{
    (void)state;
    {P}_UNSUPPORTED("fmi2FreeFMUstate");
}}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate state, size_t *size)
{{
    (void)state;
    (void)size;
    {P}_UNSUPPORTED("fmi2SerializedFMUstateSize");
}}

fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate state, fmi2Byte bytes[],
                                 size_t size)
{{
    (void)state;
    (void)bytes;
    (void)size;
    {P}_UNSUPPORTED("fmi2SerializeFMUstate");
}}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte bytes[], size_t size,
                                   fmi2FMUstate *state)
{{
    (void)bytes;
    (void)size;
    (void)state;
    {P}_UNSUPPORTED("fmi2DeSerializeFMUstate");
}}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component comp, const fmi2ValueReference vU[],
                                        size_t nU, const fmi2ValueReference vK[], size_t nK,
                                        const fmi2Real dvK[], fmi2Real dvU[])
{{
    (void)vU;
    (void)nU;
    (void)vK;
    (void)nK;
    (void)dvK;
    (void)dvU;
    {P}_UNSUPPORTED("fmi2GetDirectionalDerivative");
}}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[])
{{
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    {P}_UNSUPPORTED("fmi2SetRealInputDerivatives");
}}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[], fmi2Real value[])
{{
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    {P}_UNSUPPORTED("fmi2GetRealOutputDerivatives");
}}

fmi2Status fmi2CancelStep(fmi2Component comp) {{ {P}_UNSUPPORTED("fmi2CancelStep"); }}

fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status *value)
{{
    (void)s;
    (void)value;
    {P}_UNSUPPORTED("fmi2GetStatus");
}}

fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Real *value)
{{
    {p}_instance *c = ({p}_instance *)comp;
    if (c && s == fmi2LastSuccessfulTime) {{
        *value = c->time;
        return fmi2OK;
    }}
    {P}_UNSUPPORTED("fmi2GetRealStatus");
}}

fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Integer *value)
{{
    (void)s;
    (void)value;
    {P}_UNSUPPORTED("fmi2GetIntegerStatus");
}}

fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Boolean *value)
{{
    (void)s;
    (void)value;
    {P}_UNSUPPORTED("fmi2GetBooleanStatus");
}}

fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s, fmi2String *value)
{{
    (void)s;
    (void)value;
    {P}_UNSUPPORTED("fmi2GetStringStatus");
}}
"""
