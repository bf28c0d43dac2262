/* -----------------------------------------------------------------------------
 * CEODE as the fast (inner) integrator of ARKODE's multirate and splitting
 * methods (src/ceode_stepper.cpp, docs/porting.md "CEODE inside ARKODE").
 *
 * A separate header because it needs ARKODE's types: programs that only use
 * ceode.h do not need ARKODE's headers or library.
 *
 * The inner state is first order, y = [x; v]: an NVECTOR_MANYVECTOR of two
 * parts of the length of CEODE's x0, or a serial vector of 2n entries. The
 * CEODE memory must be initialised (CEodeInit, with the fast acceleration
 * g(t, x, v) as its right-hand side) and have a fixed step (CEodeSetFixedStep:
 * the largest inner step) before the stepper is created. From then on the
 * stepper drives that memory: do not call CEodeSetUserData or CEodeEvolve on
 * it until the stepper is freed. Counters (CEodeGetNumSteps, ...) of the CEODE
 * memory accumulate over all inner integrations. Until its first reset the
 * stepper's state is the CEODE memory's (x0, v0 at t0 of CEodeInit); a reset
 * copies the state it is given (the stepper owns its start state).
 * Every inner integration restarts the method. When it continues the previous
 * one (same time, same state) and no velocity dependence is declared, the start
 * reuses the previous history corrected by the known change of the forcing:
 * 0 evaluations for degree 3, 1 for degree 4; otherwise the full consistent
 * start (docs/porting.md, "What a restart costs").
 * ---------------------------------------------------------------------------*/
#ifndef CEODE_CEODE_STEPPER_H_
#define CEODE_CEODE_STEPPER_H_

#include <arkode/arkode_mristep.h>
#include <ceode/ceode.h>
#include <sundials/sundials_config.h>

#if SUNDIALS_VERSION_MAJOR > 7 || (SUNDIALS_VERSION_MAJOR == 7 && SUNDIALS_VERSION_MINOR >= 2)
#define CEODE_HAVE_SUNSTEPPER 1
#include <sundials/sundials_stepper.h>
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* MRIStep's custom inner stepper (SUNDIALS 6.4 and 7.x). Free it with
 * CEodeFreeMRIStepInnerStepper (not MRIStepInnerStepper_Free alone: the
 * CEODE part of the stepper would leak). */
SUNDIALS_EXPORT int CEodeCreateMRIStepInnerStepper(void* ce_mem, MRIStepInnerStepper* stepper);
SUNDIALS_EXPORT int CEodeFreeMRIStepInnerStepper(MRIStepInnerStepper* stepper);

/* Number of inner integrations (restarts of the CEODE history) so far. */
SUNDIALS_EXPORT int CEodeGetNumInnerRestarts(void* ce_mem, long int* nrestarts);

#ifdef CEODE_HAVE_SUNSTEPPER
/* A SUNStepper (MRIStep, SplittingStep, ForcingStep of SUNDIALS >= 7.2).
 * SUNStepper_Destroy frees it completely. */
SUNDIALS_EXPORT int CEodeCreateSUNStepper(void* ce_mem, SUNStepper* stepper);
#endif

#ifdef __cplusplus
}
#endif

#endif /* CEODE_CEODE_STEPPER_H_ */
