/* -----------------------------------------------------------------------------
 * CEODE: conditionally explicit integrators for second-order ODEs and index-3
 * constrained multibody DAEs, as a SUNDIALS-style module.
 *
 *   M(x,t) x'' + G(x)^T lambda = f(t, x, x'),   Phi(x, t) = 0
 *
 * The C API follows CVODE/ARKODE/IDA: opaque memory, Create/Init/Set/Get/
 * Evolve/Free, integer return flags. See docs/api.md for every function.
 * ---------------------------------------------------------------------------*/
#ifndef CEODE_CEODE_H_
#define CEODE_CEODE_H_

#include <stdio.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>
#include <sundials/sundials_nonlinearsolver.h>
#include <sundials/sundials_nvector.h>
#include <sundials/sundials_types.h>

#ifdef __cplusplus
extern "C" {
#endif

#define CEODE_VERSION_MAJOR 0
#define CEODE_VERSION_MINOR 1
#define CEODE_VERSION_PATCH 0

/* itask values of CEodeEvolve */
#define CE_NORMAL 1
#define CE_ONE_STEP 2

/* Return flags */
#define CE_SUCCESS 0
#define CE_TSTOP_RETURN 1
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

/* Stability guard modes (CEodeSetStabilityGuard) */
#define CE_GUARD_OFF 0
#define CE_GUARD_WARN 1
#define CE_GUARD_REFUSE 2

/* Problem callbacks: return 0 on success, > 0 recoverable, < 0 unrecoverable. */
typedef int (*CEodeRhsFn)(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* user_data);
typedef int (*CEodeMassFn)(sunrealtype t, N_Vector x, SUNMatrix M, void* user_data, N_Vector tmp1,
                           N_Vector tmp2, N_Vector tmp3);
typedef int (*CEodeVelJacFn)(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, SUNMatrix J,
                             void* user_data, N_Vector tmp1, N_Vector tmp2, N_Vector tmp3);
typedef int (*CEodeConstrFn)(sunrealtype t, N_Vector x, N_Vector phi, void* user_data);
typedef int (*CEodeConstrJacFn)(sunrealtype t, N_Vector x, SUNMatrix G, void* user_data);
typedef void (*CEodeErrHandlerFn)(int error_code, const char* module, const char* function,
                                  char* msg, void* eh_data);

/* Creation, initialisation, integration, destruction (ceode.cpp) */
SUNDIALS_EXPORT void* CEodeCreate(SUNContext sunctx);
SUNDIALS_EXPORT int CEodeInit(void* mem, CEodeRhsFn f, sunrealtype t0, N_Vector x0, N_Vector v0);
SUNDIALS_EXPORT int CEodeReInit(void* mem, sunrealtype t0, N_Vector x0, N_Vector v0);
SUNDIALS_EXPORT int CEodeEvolve(void* mem, sunrealtype tout, N_Vector xout, N_Vector vout,
                                sunrealtype* tret, int itask);
SUNDIALS_EXPORT int CEodeGetDky(void* mem, sunrealtype t, int k, N_Vector dky);
SUNDIALS_EXPORT void CEodeFree(void** mem);

/* Method selection (ceode_io.cpp). params holds degree-1 values: alpha, beta, gamma, zeta, ... */
SUNDIALS_EXPORT int CEodeSetMethod(void* mem, int degree, const sunrealtype* params);
SUNDIALS_EXPORT int CEodeSetMethodByName(void* mem, const char* name);
SUNDIALS_EXPORT int CEodeGetMethodParams(const char* name, int* degree, sunrealtype* params,
                                         int max_params);
SUNDIALS_EXPORT int CEodeGetNumMethods(void);
SUNDIALS_EXPORT const char* CEodeGetMethodName(int index);
SUNDIALS_EXPORT int CEodeSetZeroStart(void* mem, sunbooleantype zero_start);
SUNDIALS_EXPORT int CEodeSetCompensatedSummation(void* mem, sunbooleantype on);
SUNDIALS_EXPORT int CEodeSetFusedKernel(void* mem, sunbooleantype on);
SUNDIALS_EXPORT int CEodeSetInPlaceUpdate(void* mem, sunbooleantype on);

/* Optional inputs (ceode_io.cpp) */
SUNDIALS_EXPORT int CEodeSetFixedStep(void* mem, sunrealtype h);
SUNDIALS_EXPORT int CEodeSetVelocityDependence(void* mem, sunbooleantype depends);
SUNDIALS_EXPORT int CEodeSetUserData(void* mem, void* user_data);
SUNDIALS_EXPORT int CEodeSetStopTime(void* mem, sunrealtype tstop);
SUNDIALS_EXPORT int CEodeClearStopTime(void* mem);
SUNDIALS_EXPORT int CEodeSetMaxNumSteps(void* mem, long int mxsteps);
SUNDIALS_EXPORT int CEodeSetMaxNonlinIters(void* mem, int maxcor);
SUNDIALS_EXPORT int CEodeSetNonlinTolerances(void* mem, sunrealtype reltol, sunrealtype abstol);
SUNDIALS_EXPORT int CEodeSetJacEvalFrequency(void* mem, long int msbj);
SUNDIALS_EXPORT int CEodeSetErrHandlerFn(void* mem, CEodeErrHandlerFn ehfun, void* eh_data);
SUNDIALS_EXPORT int CEodeSetErrFile(void* mem, FILE* errfp);
SUNDIALS_EXPORT int CEodeSetStabilityGuard(void* mem, int mode, long int every);
SUNDIALS_EXPORT int CEodeSetMaxFrequency(void* mem, sunrealtype omega_max);

/* Mass matrix, linear and nonlinear solvers (ceode_ls.cpp, ceode_nls.cpp) */
SUNDIALS_EXPORT int CEodeSetMassFn(void* mem, CEodeMassFn mfn, SUNMatrix M,
                                   sunbooleantype constant);
SUNDIALS_EXPORT int CEodeSetLinearSolver(void* mem, SUNLinearSolver LS, SUNMatrix A);
SUNDIALS_EXPORT int CEodeSetNonlinearSolver(void* mem, SUNNonlinearSolver NLS);
SUNDIALS_EXPORT int CEodeSetVelJacFn(void* mem, CEodeVelJacFn jac);

/* Constraints (ceode_constraints.cpp) */
SUNDIALS_EXPORT int CEodeSetConstraints(void* mem, N_Vector phi_template, CEodeConstrFn phi,
                                        CEodeConstrJacFn G);
SUNDIALS_EXPORT int CEodeGetMultipliers(void* mem, N_Vector lambda);
/* SUNTRUE (default): saddle systems with n + nc <= 200 are solved by the Schur complement of
 * a block factored once and kept across steps (docs/theory.md section 8.3); SUNFALSE: the full
 * saddle-point matrix is assembled and factored by the linear solver at every setup. */
SUNDIALS_EXPORT int CEodeSetSchurComplement(void* mem, sunbooleantype use);

/* Optional outputs (ceode_io.cpp) */
SUNDIALS_EXPORT int CEodeGetAccel(void* mem, N_Vector a);
SUNDIALS_EXPORT int CEodeGetCurrentTime(void* mem, sunrealtype* tcur);
SUNDIALS_EXPORT int CEodeGetCurrentStep(void* mem, sunrealtype* hcur);
SUNDIALS_EXPORT int CEodeGetNumSteps(void* mem, long int* nsteps);
SUNDIALS_EXPORT int CEodeGetNumRhsEvals(void* mem, long int* nfevals);
SUNDIALS_EXPORT int CEodeGetNumStartRhsEvals(void* mem, long int* nfevals);
SUNDIALS_EXPORT int CEodeGetNumGuardRhsEvals(void* mem, long int* nfevals);
SUNDIALS_EXPORT int CEodeGetNumNonlinSolvIters(void* mem, long int* nniters);
SUNDIALS_EXPORT int CEodeGetNumNonlinSolvConvFails(void* mem, long int* nnfails);
SUNDIALS_EXPORT int CEodeGetNumLinSolvSetups(void* mem, long int* nlinsetups);
SUNDIALS_EXPORT int CEodeGetNumLinSolves(void* mem, long int* nlinsolves);
SUNDIALS_EXPORT int CEodeGetNumJacEvals(void* mem, long int* njevals);
SUNDIALS_EXPORT int CEodeGetNumRhsEvalsJacDQ(void* mem, long int* nfevalsLS);
SUNDIALS_EXPORT int CEodeGetNumMassEvals(void* mem, long int* nmevals);
SUNDIALS_EXPORT int CEodeGetNumConstrEvals(void* mem, long int* ncevals);
SUNDIALS_EXPORT int CEodeGetNumConstrJacEvals(void* mem, long int* ngevals);
SUNDIALS_EXPORT int CEodeGetMaxFrequencyEstimate(void* mem, sunrealtype* omega_max);
SUNDIALS_EXPORT int CEodeGetLastErrorMessage(void* mem, const char** msg);
SUNDIALS_EXPORT int CEodePrintAllStats(void* mem, FILE* outfile, SUNOutputFormat fmt);
SUNDIALS_EXPORT char* CEodeGetReturnFlagName(long int flag);

/* -----------------------------------------------------------------------------
 * First-order adapter (ceode_first_order.cpp): an unchanged ARKODE/CVODE
 * right-hand side F(t, y, ydot) with y = [x; v], ydot = [v; a], y an
 * NVECTOR_MANYVECTOR of two equal parts or a serial vector of length 2n. CEODE
 * integrates x'' = a; F's first half must be v (checked once at the start).
 * ---------------------------------------------------------------------------*/
typedef int (*CEodeFirstOrderRhsFn)(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data);
SUNDIALS_EXPORT int CEodeInitFirstOrder(void* mem, CEodeFirstOrderRhsFn F, sunrealtype t0,
                                        N_Vector y0);
SUNDIALS_EXPORT int CEodeReInitFirstOrder(void* mem, sunrealtype t0, N_Vector y0);
SUNDIALS_EXPORT int CEodeEvolveFirstOrder(void* mem, sunrealtype tout, N_Vector yout,
                                          sunrealtype* tret, int itask);
/* ------------------------------------------------- end of the first-order adapter */

/* ---- Stability guard: stable step and the guard's own counters (ceode_guard.cpp) ----
 * The guard estimates omega_max at the current state by Lanczos on M^{-1} df/dx
 * (directional differences of f) as theta + r: the top Ritz value plus its
 * residual norm, an upper bound of omega_max^2 for a symmetric stiffness (at
 * most 0.1 % above it), or CEodeSetMaxFrequency's value when one is given.
 * When df/dx is not symmetric in that product (tested at every Lanczos step, at no
 * extra evaluation) the guard continues by Arnoldi: omega_max^2 is then the largest
 * |Ritz value| with a positive real part (the spectral radius of M^{-1} df/dx when
 * converged), an estimate and not a bound; the warning names the estimator.
 * CEodeGetStableStep returns hmax = safety * Omega_max / omega_max for the chosen
 * set; safety in (0, 1], 0 selects the default 0.99 (the guard's own recommended
 * step uses 0.99 too). hmax = 0 for a set unstable for every step, SUN_BIG_REAL
 * when f does not depend on x. The guard's f and mass evaluations and the
 * factorisations of its own copy of M are counted apart from the integration's
 * (CEodeGetGuardStats; nfevals is CEodeGetNumGuardRhsEvals) and reset by CEodeReInit. */
SUNDIALS_EXPORT int CEodeGetStableStep(void* mem, sunrealtype safety, sunrealtype* hmax);
/* When f returns accelerations M^{-1} force with a lumped (diagonal) M and no mass matrix
 * is attached, M^{-1} K is symmetric only in the M inner product: give the lumped masses
 * here (after CEodeInit; NULL clears) and the guard's Lanczos works in that product, so its
 * estimate is again an upper bound within 0.1 %. Ignored when CEodeSetMassFn is used. */
SUNDIALS_EXPORT int CEodeSetGuardMass(void* mem, N_Vector mass);
SUNDIALS_EXPORT int CEodeGetGuardStats(void* mem, long int* nfevals, long int* nmevals,
                                       long int* nlinsetups);
/* ---- end of the stability guard block ---- */

/* ---- Implicit-step modes and velocity-dependence detection (ceode_pc.cpp) ----
 * CEodeSetImplicitMode chooses how a velocity-dependent step solves for the
 * acceleration: CE_IMPLICIT_NEWTON hands it to the nonlinear solver (Newton with
 * a linear solver attached, fixed point otherwise); CE_IMPLICIT_PC predicts and
 * corrects a fixed number of times, no convergence test (CEodeSetPCCorrections:
 * k = 1 or 2, 0 = the set's default: 2 for sets of order d and from degree 5
 * on, 1 otherwise); CE_IMPLICIT_AUTO (default)
 * estimates kappa ||M^{-1} df/dv|| at every (re)start and every msbj steps and
 * takes PC when it is at most 0.05, the nonlinear solver above (docs/api.md).
 * CE_VELOCITY_DETECT (CEodeSetVelocityDependence) switches the implicit step on
 * when one directional difference at the start shows that f depends on x'; if the
 * setter was never called and f depends on x', CEODE warns (CE_WARNING). */
#define CE_IMPLICIT_NEWTON 0
#define CE_IMPLICIT_PC 1
#define CE_IMPLICIT_AUTO 2
#define CE_VELOCITY_DETECT 2
SUNDIALS_EXPORT int CEodeSetImplicitMode(void* mem, int mode);
SUNDIALS_EXPORT int CEodeSetPCCorrections(void* mem, int k);
SUNDIALS_EXPORT int CEodeGetImplicitStats(void* mem, long int* npcsteps, long int* nnlssteps,
                                          long int* nfecoupling, sunrealtype* coupling);
/* ---- end of the implicit-step block ---- */

/* ---- Guaranteed frequency bound (ceode_bound.cpp) ----
 * omega_bound >= omega_max of M x'' = -K x with a lumped (diagonal) M: Gershgorin's
 * theorem on M^{-1} K and on M^{-1/2} K M^{-1/2} (the smaller of the two row-sum
 * bounds), from the assembled stiffness K (dense, band, or sparse CSR/CSC) and the
 * lumped masses (NULL: M = I). Never below omega_max, whatever K is; one pass over
 * K's entries. Give it to CEodeSetMaxFrequency for a stable step that needs no
 * f evaluations and is guaranteed: CEodeGetStableStep then returns
 * safety * Omega_max / omega_bound. Only an error path needs mem (CEodeCreate). */
SUNDIALS_EXPORT int CEodeGetFrequencyBound(void* mem, SUNMatrix K, N_Vector mass,
                                           sunrealtype* omega_bound);
/* ---- end of the frequency bound block ---- */

#ifdef __cplusplus
}
#endif

#endif /* CEODE_CEODE_H_ */
