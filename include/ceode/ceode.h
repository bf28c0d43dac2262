/* -----------------------------------------------------------------------------
 * CEODE: conditionally explicit integrators for second-order ODEs and index-3
 * constrained multibody DAEs, as a SUNDIALS-style module.
 *
 *   M(x,t) x'' + G(x)^T lambda = f(t, x, x'),   Phi(x, t) = 0
 *
 * The C API follows CVODE/ARKODE/IDA: opaque memory, Create/Init/Set/Get/
 * Evolve/Free, integer return flags. This header is laid out as cvode.h is:
 *
 *   1. constants (version, itask, return flags, modes)
 *   2. user-supplied function types
 *   3. creation and initialisation
 *   4. optional inputs (CEodeSet*)
 *   5. solver functions (CEodeEvolve, dense output)
 *   6. optional outputs (CEodeGet*)
 *   7. utilities (method table, frequency bound, statistics, flag names, CEodeFree)
 *
 * docs/api.md documents every function in the same order. The stability
 * analysis (ceode_stability.h) and ARKODE's inner stepper (ceode_stepper.h)
 * have headers of their own.
 * ---------------------------------------------------------------------------*/
#ifndef CEODE_CEODE_H_
#define CEODE_CEODE_H_

#include <ceode/ceode_config.h> /* CEODE_VERSION, CEODE_VERSION_MAJOR/MINOR/PATCH/LABEL */
#include <stdio.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>
#include <sundials/sundials_nonlinearsolver.h>
#include <sundials/sundials_nvector.h>
#include <sundials/sundials_types.h>
#if SUNDIALS_VERSION_MAJOR >= 7
#include <sundials/sundials_adaptcontroller.h>
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* =============================================================================
 * 1. Constants
 * ===========================================================================*/

/* CEODE_VERSION ("0.1.0") and CEODE_VERSION_MAJOR/MINOR/PATCH/LABEL: ceode_config.h,
 * configured from the CMake project version; CEodeGetVersion reports the library's. */

/* itask values of CEodeEvolve */
#define CE_NORMAL 1
#define CE_ONE_STEP 2

/* Return flags */
#define CE_SUCCESS 0
#define CE_TSTOP_RETURN 1
#define CE_ROOT_RETURN 2 /* CEodeEvolve stopped at a root of g (CEodeRootInit) */
#define CE_WARNING 99

#define CE_MEM_NULL (-1)
#define CE_ILL_INPUT (-2)
#define CE_NO_MALLOC (-3)
#define CE_MEM_FAIL (-4)
#define CE_RHSFUNC_FAIL (-5)
#define CE_FIRST_RHSFUNC_ERR (-6)
#define CE_CONV_FAILURE (-7)
#define CE_LSETUP_FAIL (-8)
#define CE_LSOLVE_FAIL (-9)
#define CE_LINIT_FAIL (-10)
#define CE_NLS_INIT_FAIL (-11)
#define CE_NLS_FAIL (-12)
#define CE_CONSTR_FAIL (-13)
#define CE_MASSFUNC_FAIL (-14)
#define CE_JACFUNC_FAIL (-15)
#define CE_UNSTABLE (-16)
#define CE_TOO_MUCH_WORK (-17)
#define CE_BAD_T (-18)
#define CE_VECTOROP_ERR (-19)
#define CE_ERR_FAILURE (-20)
#define CE_INCONSISTENT_IC (-21)
#define CE_RTFUNC_FAIL (-22) /* the root function failed or returned NaN/Inf */

/* What CEodeCalcIC projects (bitwise or) */
#define CE_IC_POSITION 1
#define CE_IC_VELOCITY 2

/* Stability guard modes (CEodeSetStabilityGuard) */
#define CE_GUARD_OFF 0
#define CE_GUARD_WARN 1
#define CE_GUARD_REFUSE 2

/* How f's dependence on the velocity x' is handled (CEodeSetVelocityMode).
 *   CE_VELOCITY_INDEPENDENT  explicit step: f receives the previous step's velocity.
 *   CE_VELOCITY_DEPENDENT    implicit step: the acceleration is solved for as
 *                            CEodeSetImplicitMode says.
 *   CE_VELOCITY_DETECT       at every (re)start one directional difference of f in
 *                            x' decides: the implicit step when f depends on x', the
 *                            explicit one otherwise.
 * When no velocity mode is set (default), the first start makes the same check
 * once per right-hand side function (not again at restarts or CEodeReInit) and
 * switches the implicit step on when f depends on x'. */
typedef enum {
  CE_VELOCITY_INDEPENDENT = 0,
  CE_VELOCITY_DEPENDENT = 1,
  CE_VELOCITY_DETECT = 2
} CEodeVelocityMode;

/* Implicit-step modes (CEodeSetImplicitMode): how a velocity-dependent step solves
 * for the acceleration.
 *   CE_IMPLICIT_NEWTON  the nonlinear solver (Newton with a linear solver attached,
 *                       fixed point otherwise).
 *   CE_IMPLICIT_PC      prediction-correction, a fixed number of corrections and no
 *                       convergence test (CEodeSetPCCorrections).
 *   CE_IMPLICIT_AUTO    (default) estimates kappa ||M^{-1} df/dv|| at every (re)start
 *                       and every msbj steps and takes PC while it is small, the
 *                       nonlinear solver otherwise (docs/api.md). */
#define CE_IMPLICIT_NEWTON 0
#define CE_IMPLICIT_PC 1
#define CE_IMPLICIT_AUTO 2

/* =============================================================================
 * 2. User-supplied function types
 *    Return 0 on success, > 0 recoverable, < 0 unrecoverable.
 * ===========================================================================*/

typedef int (*CEodeRhsFn)(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* user_data);
typedef int (*CEodeMassFn)(sunrealtype t, N_Vector x, SUNMatrix M, void* user_data, N_Vector tmp1,
                           N_Vector tmp2, N_Vector tmp3);
typedef int (*CEodeVelJacFn)(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, SUNMatrix J,
                             void* user_data, N_Vector tmp1, N_Vector tmp2, N_Vector tmp3);
typedef int (*CEodeConstrFn)(sunrealtype t, N_Vector x, N_Vector phi, void* user_data);
typedef int (*CEodeConstrJacFn)(sunrealtype t, N_Vector x, SUNMatrix G, void* user_data);
typedef void (*CEodeErrHandlerFn)(int error_code, const char* module, const char* function,
                                  char* msg, void* eh_data);
/* Error weights of the adaptive step, as CVODE's CVEwtFn: ewt_i > 0 for every entry of
 * the position x (CEodeWFtolerances). */
typedef int (*CEodeEwtFn)(N_Vector x, N_Vector ewt, void* user_data);
/* Root (event) functions: g_i(t, x, v), i < nrtfn, into gout (CEodeRootInit); 0: success */
typedef int (*CEodeRootFn)(sunrealtype t, N_Vector x, N_Vector v, sunrealtype* gout,
                           void* user_data);
/* A first-order right-hand side F(t, y, ydot), unchanged from ARKODE/CVODE, with
 * y = [x; v] and ydot = [v; a] (CEodeInitFirstOrder). */
typedef int (*CEodeFirstOrderRhsFn)(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data);

/* =============================================================================
 * 3. Creation and initialisation
 * ===========================================================================*/

SUNDIALS_EXPORT void* CEodeCreate(SUNContext sunctx);
SUNDIALS_EXPORT int CEodeInit(void* mem, CEodeRhsFn f, sunrealtype t0, N_Vector x0, N_Vector v0);
SUNDIALS_EXPORT int CEodeReInit(void* mem, sunrealtype t0, N_Vector x0, N_Vector v0);

/* First-order adapter: y an NVECTOR_MANYVECTOR of two equal parts [x; v] or a serial
 * vector of length 2n. CEODE integrates x'' = a; F's first half must be v (checked
 * at the first CEodeEvolveFirstOrder after an init). */
SUNDIALS_EXPORT int CEodeInitFirstOrder(void* mem, CEodeFirstOrderRhsFn F, sunrealtype t0,
                                        N_Vector y0);
SUNDIALS_EXPORT int CEodeReInitFirstOrder(void* mem, sunrealtype t0, N_Vector y0);

/* =============================================================================
 * 4. Optional inputs
 * ===========================================================================*/

/* Method. params holds degree-1 values: alpha, beta, gamma, zeta, ... */
SUNDIALS_EXPORT int CEodeSetMethod(void* mem, int degree, const sunrealtype* params);
SUNDIALS_EXPORT int CEodeSetMethodByName(void* mem, const char* name);
SUNDIALS_EXPORT int CEodeSetZeroStart(void* mem, sunbooleantype zero_start);
SUNDIALS_EXPORT int CEodeSetCompensatedSummation(void* mem, sunbooleantype on);

/* Step, stop time, work limit, user data */
SUNDIALS_EXPORT int CEodeSetFixedStep(void* mem, sunrealtype h);
SUNDIALS_EXPORT int CEodeSetStopTime(void* mem, sunrealtype tstop);
SUNDIALS_EXPORT int CEodeClearStopTime(void* mem);
SUNDIALS_EXPORT int CEodeSetMaxNumSteps(void* mem, long int mxsteps);
SUNDIALS_EXPORT int CEodeSetUserData(void* mem, void* user_data);

/* Error control (docs/api.md, "Error control"). Tolerances switch the run to the
 * adaptive step: CEODE chooses every step from a local error estimate on the positions
 * (WRMS norm with ewt_i = 1/(reltol |x_i| + abstol_i), or the user's weights) at no
 * extra f evaluation, and never above the stable step of the stability guard's
 * frequency estimate (0.9 Omega_max / omega_max). CEodeSetFixedStep switches back to
 * fixed steps; the last of the two calls decides. The controller is CE_ADAPT_PI unless
 * CEodeSetAdaptivityMethod chooses CE_ADAPT_H211B (a digital filter: smoother step
 * sequences, more failed tests). */
#define CE_ADAPT_H211B 0
#define CE_ADAPT_PI 1
SUNDIALS_EXPORT int CEodeSStolerances(void* mem, sunrealtype reltol, sunrealtype abstol);
SUNDIALS_EXPORT int CEodeSVtolerances(void* mem, sunrealtype reltol, N_Vector abstol);
SUNDIALS_EXPORT int CEodeWFtolerances(void* mem, CEodeEwtFn efun);
SUNDIALS_EXPORT int CEodeSetInitStep(void* mem, sunrealtype hin);
SUNDIALS_EXPORT int CEodeSetMinStep(void* mem, sunrealtype hmin);
SUNDIALS_EXPORT int CEodeSetMaxStep(void* mem, sunrealtype hmax);
SUNDIALS_EXPORT int CEodeSetFixedStepBounds(void* mem, sunrealtype lb, sunrealtype ub);
SUNDIALS_EXPORT int CEodeSetMaxErrTestFails(void* mem, int maxnef);
SUNDIALS_EXPORT int CEodeSetAdaptivityMethod(void* mem, int controller);
#if SUNDIALS_VERSION_MAJOR >= 7
/* SUNDIALS 7: any SUNAdaptController of single-rate type chooses the steps in place of
 * CEODE's own (EstimateStep with the set's order in x, UpdateH after every accepted
 * step, Reset at every start); CEODE's ratio bounds, hmin/hmax, the stable step and the
 * stop time still apply. The controller is not owned: destroy it after CEodeFree. NULL
 * returns to CEodeSetAdaptivityMethod's controller. */
SUNDIALS_EXPORT int CEodeSetAdaptController(void* mem, SUNAdaptController C);
#endif

/* Velocity dependence. CEodeSetVelocityDependence is the SUNDIALS-style boolean:
 * SUNTRUE is CE_VELOCITY_DEPENDENT, SUNFALSE CE_VELOCITY_INDEPENDENT, any other
 * value CE_ILL_INPUT (CE_VELOCITY_DETECT is set by CEodeSetVelocityMode). */
SUNDIALS_EXPORT int CEodeSetVelocityMode(void* mem, CEodeVelocityMode mode);
SUNDIALS_EXPORT int CEodeSetVelocityDependence(void* mem, sunbooleantype depends);

/* Implicit step: the solve for the acceleration when f depends on x' */
SUNDIALS_EXPORT int CEodeSetImplicitMode(void* mem, int mode);
/* k = 1 or 2; 0 = the set's default: 2 for sets of order d and from degree 5 on, 1 otherwise */
SUNDIALS_EXPORT int CEodeSetPCCorrections(void* mem, int k);
SUNDIALS_EXPORT int CEodeSetMaxNonlinIters(void* mem, int maxcor);
SUNDIALS_EXPORT int CEodeSetNonlinTolerances(void* mem, sunrealtype reltol, sunrealtype abstol);
SUNDIALS_EXPORT int CEodeSetJacEvalFrequency(void* mem, long int msbj);

/* Mass matrix, linear and nonlinear solvers, velocity Jacobian */
SUNDIALS_EXPORT int CEodeSetMassFn(void* mem, CEodeMassFn mfn, SUNMatrix M,
                                   sunbooleantype constant);
SUNDIALS_EXPORT int CEodeSetLinearSolver(void* mem, SUNLinearSolver LS, SUNMatrix A);
SUNDIALS_EXPORT int CEodeSetNonlinearSolver(void* mem, SUNNonlinearSolver NLS);
SUNDIALS_EXPORT int CEodeSetVelJacFn(void* mem, CEodeVelJacFn jac);
/* f affine in x' with the constant Jacobian df/dx' = diag(c) (a copy is kept; f returns
 * accelerations, no mass matrix): a velocity-dependent step then solves for the acceleration
 * exactly, a = f(t, x, V0) / (1 - kappa c), with one f and no iteration, whatever
 * CEodeSetImplicitMode says (Rayleigh damping C = alpha M with lumped masses: c_i = -alpha;
 * dampers to ground). NULL removes it; a CEodeInit of another size too. */
SUNDIALS_EXPORT int CEodeSetVelJacDiagonal(void* mem, N_Vector c);

/* Position constraints Phi(x, t) = 0 with Jacobian G (phi = G = NULL removes them) */
SUNDIALS_EXPORT int CEodeSetConstraints(void* mem, N_Vector phi_template, CEodeConstrFn phi,
                                        CEodeConstrJacFn G);

/* Consistent initial conditions (IDACalcIC's counterpart). With constraints, the first
 * CEodeEvolve after CEodeInit/CEodeReInit checks that x0 lies on Phi(x, t0) = 0 and v0 on
 * G(x0) v = -Phi_t (each constraint's distance |Phi_i| / |G_i| below sqrt(uround) |x0|_max,
 * its normal velocity below sqrt(uround) times the velocity scale) and returns
 * CE_INCONSISTENT_IC naming the constraint otherwise. CEodeCalcIC projects the current x (by
 * Gauss-Newton) and then v onto the constraints with minimum-norm corrections in the metric of
 * M (the identity without a mass matrix); CEodeGetICCorrection gives how far they moved (max
 * norm) and CEodeGetConsistentIC the projected values until the integration starts. */
SUNDIALS_EXPORT int CEodeCalcIC(void* mem, int what);
SUNDIALS_EXPORT int CEodeGetICCorrection(void* mem, sunrealtype* dx_norm, sunrealtype* dv_norm);
SUNDIALS_EXPORT int CEodeGetConsistentIC(void* mem, N_Vector x0, N_Vector v0);

/* Stability guard. A check compares h * omega_max with the method's stability limit.
 * omega_max is CEodeSetMaxFrequency's value when one is given, otherwise an estimate
 * at the current state by Lanczos on M^{-1} df/dx (directional differences of f):
 * the top Ritz value plus its residual norm, an upper bound of omega_max^2 for a
 * symmetric stiffness (at most 0.2 % above it: omega_max at most 0.1 %). When df/dx is not
 * symmetric in that product (tested at every Lanczos step, at no extra evaluation) the guard
 * continues by Arnoldi: omega_max^2 is then the largest |Ritz value| with a positive real part (the
 * spectral radius of M^{-1} df/dx when converged), an estimate and not a bound; the warning names
 * the estimator. The guard's f and mass evaluations and the factorisations of its own copy of M are
 * counted apart from the integration's (CEodeGetGuardStats) and reset by CEodeReInit. */
SUNDIALS_EXPORT int CEodeSetStabilityGuard(void* mem, int mode, long int every);
SUNDIALS_EXPORT int CEodeSetMaxFrequency(void* mem, sunrealtype omega_max);
/* When f returns accelerations M^{-1} force with a lumped (diagonal) M and no mass matrix
 * is attached, M^{-1} K is symmetric only in the M inner product: give the lumped masses
 * here (after CEodeInit; NULL clears) and the guard's Lanczos works in that product, so its
 * estimate is again an upper bound within 0.1 %. Ignored when CEodeSetMassFn is used. */
SUNDIALS_EXPORT int CEodeSetGuardMass(void* mem, N_Vector mass);
/* SUNTRUE declares that a restart (CEodeReInit, CEodeReset) keeps the problem's top frequency:
 * the same f and masses, and a new state whose omega_max is not higher (a linear problem, or a
 * nonlinear one started where it is no stiffer). The first check of the next run then takes the
 * last run's estimate and evaluates nothing; later checks (every, the stable-step refresh)
 * estimate again. CEodeInit and CEodeSetGuardMass drop the kept estimate. Default SUNFALSE. */
SUNDIALS_EXPORT int CEodeSetGuardReuse(void* mem, sunbooleantype reuse);

/* Error reporting */
SUNDIALS_EXPORT int CEodeSetErrHandlerFn(void* mem, CEodeErrHandlerFn ehfun, void* eh_data);
SUNDIALS_EXPORT int CEodeSetErrFile(void* mem, FILE* errfp);

/* =============================================================================
 * 5. Solver functions
 * ===========================================================================*/

SUNDIALS_EXPORT int CEodeEvolve(void* mem, sunrealtype tout, N_Vector xout, N_Vector vout,
                                sunrealtype* tret, int itask);
/* As CEodeEvolve, writing [x; v] into yout (the shape of CEodeInitFirstOrder's y0) */
SUNDIALS_EXPORT int CEodeEvolveFirstOrder(void* mem, sunrealtype tout, N_Vector yout,
                                          sunrealtype* tret, int itask);
/* Dense output: the k-th derivative of the current step's polynomial at t */
SUNDIALS_EXPORT int CEodeGetDky(void* mem, sunrealtype t, int k, N_Vector dky);

/* Root finding (events), as CVODE's: the nrtfn functions g are checked for a sign change over
 * every step on the dense output; CEodeEvolve returns CE_ROOT_RETURN at the earliest root.
 * nrtfn = 0 turns root finding off. dir[i] = +1 (-1): only roots where g_i increases
 * (decreases); 0: both. rootsfound[i] = +1 / -1: g_i has a root and increases / decreases;
 * 0: no root. A function zero at the start is inactive until it moves away from zero. */
SUNDIALS_EXPORT int CEodeRootInit(void* mem, int nrtfn, CEodeRootFn g);
SUNDIALS_EXPORT int CEodeSetRootDirection(void* mem, int* rootdir);
SUNDIALS_EXPORT int CEodeSetNoInactiveRootWarn(void* mem);
SUNDIALS_EXPORT int CEodeGetRootInfo(void* mem, int* rootsfound);
SUNDIALS_EXPORT int CEodeGetNumGEvals(void* mem, long int* ngevals);
/* A restart at (t0, x0, v0) for a state change after which the solution stays smooth (an
 * event that changes a velocity, say): keeps the counters, the options, the step size and,
 * with error control, the controller's next step; the method's history is started again. */
SUNDIALS_EXPORT int CEodeReset(void* mem, sunrealtype t0, N_Vector x0, N_Vector v0);

/* =============================================================================
 * 6. Optional outputs
 * ===========================================================================*/

/* Solution */
SUNDIALS_EXPORT int CEodeGetAccel(void* mem, N_Vector a);
SUNDIALS_EXPORT int CEodeGetMultipliers(void* mem, N_Vector lambda);
SUNDIALS_EXPORT int CEodeGetCurrentTime(void* mem, sunrealtype* tcur);
SUNDIALS_EXPORT int CEodeGetCurrentStep(void* mem, sunrealtype* hcur);

/* Error control: the step last taken, the first step, the error weights and the local
 * error estimate of the last accepted step, failed error tests, and the accepted steps
 * whose size the stable-step cap (not the error) decided. */
SUNDIALS_EXPORT int CEodeGetLastStep(void* mem, sunrealtype* hlast);
SUNDIALS_EXPORT int CEodeGetActualInitStep(void* mem, sunrealtype* hinused);
SUNDIALS_EXPORT int CEodeGetErrWeights(void* mem, N_Vector eweight);
SUNDIALS_EXPORT int CEodeGetEstLocalErrors(void* mem, N_Vector ele);
SUNDIALS_EXPORT int CEodeGetNumErrTestFails(void* mem, long int* netfails);
SUNDIALS_EXPORT int CEodeGetNumStableStepLimited(void* mem, long int* ncapped);

/* Counters (reset by CEodeInit and CEodeReInit) */
SUNDIALS_EXPORT int CEodeGetNumSteps(void* mem, long int* nsteps);
SUNDIALS_EXPORT int CEodeGetNumRhsEvals(void* mem, long int* nfevals);
SUNDIALS_EXPORT int CEodeGetNumStartRhsEvals(void* mem, long int* nfevals);
SUNDIALS_EXPORT int CEodeGetNumNonlinSolvIters(void* mem, long int* nniters);
SUNDIALS_EXPORT int CEodeGetNumNonlinSolvConvFails(void* mem, long int* nnfails);
SUNDIALS_EXPORT int CEodeGetNumLinSolvSetups(void* mem, long int* nlinsetups);
SUNDIALS_EXPORT int CEodeGetNumLinSolves(void* mem, long int* nlinsolves);
SUNDIALS_EXPORT int CEodeGetNumJacEvals(void* mem, long int* njevals);
SUNDIALS_EXPORT int CEodeGetNumRhsEvalsJacDQ(void* mem, long int* nfevalsLS);
SUNDIALS_EXPORT int CEodeGetNumMassEvals(void* mem, long int* nmevals);
SUNDIALS_EXPORT int CEodeGetNumConstrEvals(void* mem, long int* ncevals);
SUNDIALS_EXPORT int CEodeGetNumConstrJacEvals(void* mem, long int* ngevals);
/* Prediction-correction (CE_IMPLICIT_PC, or AUTO's PC steps): the steps it solved and its
 * evaluation-corrections (one f each; NLS iterations count the nonlinear solver's only) */
SUNDIALS_EXPORT int CEodeGetNumPCSteps(void* mem, long int* npcsteps);
SUNDIALS_EXPORT int CEodeGetNumPCCorrections(void* mem, long int* npccorrections);
SUNDIALS_EXPORT int CEodeGetImplicitStats(void* mem, long int* npcsteps, long int* nnlssteps,
                                          long int* nfecoupling, sunrealtype* coupling);

/* Stability guard: its own counters, the omega_max of its last check, and the stable
 * step hmax = safety * Omega_max / omega_max for the chosen set; safety in (0, 1], 0
 * selects the default 0.99 (the guard's own recommended step uses 0.99 too). hmax = 0
 * for a set unstable for every step, SUN_BIG_REAL when f does not depend on x. */
SUNDIALS_EXPORT int CEodeGetGuardStats(void* mem, long int* nfevals, long int* nmevals,
                                       long int* nlinsetups);
SUNDIALS_EXPORT int CEodeGetMaxFrequencyEstimate(void* mem, sunrealtype* omega_max);
SUNDIALS_EXPORT int CEodeGetStableStep(void* mem, sunrealtype safety, sunrealtype* hmax);

SUNDIALS_EXPORT int CEodeGetLastErrorMessage(void* mem, const char** msg);

/* =============================================================================
 * 7. Utilities
 * ===========================================================================*/

/* The library's version, as SUNDIALSGetVersion/SUNDIALSGetVersionNumber: the string
 * ("0.1.0", "-label" appended when there is one) and its numbers; no memory needed.
 * CE_ILL_INPUT when an output is NULL or len does not hold the string and its '\0'. */
SUNDIALS_EXPORT int CEodeGetVersion(char* version, int len);
SUNDIALS_EXPORT int CEodeGetVersionNumber(int* major, int* minor, int* patch, char* label, int len);

/* The named parameter sets; no memory needed */
SUNDIALS_EXPORT int CEodeGetMethodParams(const char* name, int* degree, sunrealtype* params,
                                         int max_params);
SUNDIALS_EXPORT int CEodeGetNumMethods(void);
SUNDIALS_EXPORT const char* CEodeGetMethodName(int index);

/* Guaranteed frequency bound: omega_bound >= omega_max of M x'' = -K x with a lumped
 * (diagonal) M, by Gershgorin's theorem on M^{-1} K and on M^{-1/2} K M^{-1/2} (the
 * smaller of the two row-sum bounds), from the assembled stiffness K (dense, band, or
 * sparse CSR/CSC) and the lumped masses (NULL: M = I). Never below omega_max, whatever
 * K is; one pass over K's entries. Given to CEodeSetMaxFrequency it makes a stable step
 * that needs no f evaluations and is guaranteed: CEodeGetStableStep then returns
 * safety * Omega_max / omega_bound. Only an error path needs mem (CEodeCreate). */
SUNDIALS_EXPORT int CEodeGetFrequencyBound(void* mem, SUNMatrix K, N_Vector mass,
                                           sunrealtype* omega_bound);

SUNDIALS_EXPORT int CEodePrintAllStats(void* mem, FILE* outfile, SUNOutputFormat fmt);
SUNDIALS_EXPORT char* CEodeGetReturnFlagName(long int flag);
SUNDIALS_EXPORT void CEodeFree(void** mem);

#ifdef __cplusplus
}
#endif

#endif /* CEODE_CEODE_H_ */
