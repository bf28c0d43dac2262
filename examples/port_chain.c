/* -----------------------------------------------------------------------------
 * port_chain: one second-order problem written three ways, ARKODE (ERKStep),
 * CVODE and CEODE, the worked program of the ARKODE and CVODE sections of
 * docs/porting.md. Each solver block is what a user of that package writes.
 *
 * Problem: a chain of N = 8 unit masses between two walls, springs K = 100,
 * light damping C = 0.1, the first mass driven by F sin(2t):
 *     x_i'' = K (x_{i-1} - 2 x_i + x_{i+1}) - C x_i' + [i = 0] F sin(2t),
 * x(0) = 0, x'(0) = 0, t in [0, 5]. ARKODE and CVODE see y = [x; v] (2N);
 * CEODE sees x and v and only the acceleration.
 *
 * Runs: ERKStep (default 4th-order table) fixed h = 1e-3; CVODE BDF,
 * rtol = 1e-11, atol = 1e-13 (the reference); CEODE G4_A34, h = 1e-3, damping
 * declared (CEodeSetVelocityDependence; fixed-point solve, no linear solver).
 * Exit code 0 only if ERKStep and CEODE both agree with CVODE within 1e-7
 * (max over x and v at t = 5).
 * ---------------------------------------------------------------------------*/
#include <arkode/arkode_erkstep.h>
#include <ceode/ceode.h>
#include <cvode/cvode.h>
#include <cvode/cvode_ls.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#define N 8
#define K 100.0
#define C 0.1
#define F 1.0
#define TEND 5.0
#define HSTEP 1e-3

#if SUNDIALS_VERSION_MAJOR >= 7
#define CTX_COMM SUN_COMM_NULL
#else
#define CTX_COMM NULL
#endif

/* The acceleration, shared by all three. */
static void accel(double t, const double* x, const double* v, double* a) {
  for (int i = 0; i < N; ++i) {
    const double left = i > 0 ? x[i - 1] : 0, right = i < N - 1 ? x[i + 1] : 0;
    a[i] = K * (left - 2 * x[i] + right) - C * v[i];
  }
  a[0] += F * sin(2 * t);
}

/* ARKODE / CVODE: y' = [v; a(t, x, v)] on y = [x; v]. */
static int rhs_first_order(sunrealtype t, N_Vector y, N_Vector ydot, void* data) {
  const double* yd = N_VGetArrayPointer(y);
  double* dd = N_VGetArrayPointer(ydot);
  (void)data;
  for (int i = 0; i < N; ++i) dd[i] = yd[N + i];
  accel(t, yd, yd + N, dd + N);
  return 0;
}

/* CEODE: only the acceleration. */
static int rhs_second_order(sunrealtype t, N_Vector x, N_Vector v, N_Vector a, void* data) {
  (void)data;
  accel(t, N_VGetArrayPointer(x), N_VGetArrayPointer(v), N_VGetArrayPointer(a));
  return 0;
}

static int check(int flag, const char* call) {
  if (flag < 0) fprintf(stderr, "ERROR: %s returned %d\n", call, flag);
  return flag < 0;
}

static int run_arkode(SUNContext ctx, N_Vector y) {
  sunrealtype t = 0;
  N_VConst(0, y);
  void* ark = ERKStepCreate(rhs_first_order, 0, y, ctx);
  int fail = ark == NULL;
  if (!fail) fail |= check(ERKStepSetFixedStep(ark, HSTEP), "ERKStepSetFixedStep");
  if (!fail) fail |= check(ERKStepSetMaxNumSteps(ark, 100000), "ERKStepSetMaxNumSteps");
  if (!fail) fail |= check(ERKStepEvolve(ark, TEND, y, &t, ARK_NORMAL), "ERKStepEvolve");
  long nfe = 0;
  ERKStepGetNumRhsEvals(ark, &nfe);
  printf("ERKStep (order 4, h = %g): %ld f evaluations\n", HSTEP, nfe);
  ERKStepFree(&ark);
  return fail;
}

static int run_cvode(SUNContext ctx, N_Vector y) {
  sunrealtype t = 0;
  N_VConst(0, y);
  SUNMatrix A = SUNDenseMatrix(2 * N, 2 * N, ctx);
  SUNLinearSolver LS = SUNLinSol_Dense(y, A, ctx);
  void* cv = CVodeCreate(CV_BDF, ctx);
  int fail = cv == NULL || LS == NULL;
  if (!fail) fail |= check(CVodeInit(cv, rhs_first_order, 0, y), "CVodeInit");
  if (!fail) fail |= check(CVodeSStolerances(cv, 1e-11, 1e-13), "CVodeSStolerances");
  if (!fail) fail |= check(CVodeSetLinearSolver(cv, LS, A), "CVodeSetLinearSolver");
  if (!fail) fail |= check(CVodeSetMaxNumSteps(cv, 1000000), "CVodeSetMaxNumSteps");
  if (!fail) fail |= check(CVode(cv, TEND, y, &t, CV_NORMAL), "CVode");
  long nfe = 0;
  CVodeGetNumRhsEvals(cv, &nfe);
  printf("CVODE (BDF, rtol 1e-11): %ld f evaluations\n", nfe);
  CVodeFree(&cv);
  SUNLinSolFree(LS);
  SUNMatDestroy(A);
  return fail;
}

static int run_ceode(SUNContext ctx, N_Vector x, N_Vector v) {
  sunrealtype t = 0;
  N_VConst(0, x);
  N_VConst(0, v);
  void* ce = CEodeCreate(ctx);
  int fail = ce == NULL;
  if (!fail) fail |= check(CEodeInit(ce, rhs_second_order, 0, x, v), "CEodeInit");
  if (!fail) fail |= check(CEodeSetMethodByName(ce, "G4_A34"), "CEodeSetMethodByName");
  if (!fail) fail |= check(CEodeSetFixedStep(ce, HSTEP), "CEodeSetFixedStep");
  if (!fail) fail |= check(CEodeSetVelocityDependence(ce, SUNTRUE), "CEodeSetVelocityDependence");
  if (!fail) fail |= check(CEodeEvolve(ce, TEND, x, v, &t, CE_NORMAL), "CEodeEvolve");
  long nfe = 0;
  CEodeGetNumRhsEvals(ce, &nfe);
  printf("CEODE (G4_A34, h = %g): %ld f evaluations\n", HSTEP, nfe);
  CEodeFree(&ce);
  return fail;
}

int main(void) {
  SUNContext ctx = NULL;
  if (check(SUNContext_Create(CTX_COMM, &ctx), "SUNContext_Create")) return 1;
  N_Vector ya = N_VNew_Serial(2 * N, ctx), yc = N_VNew_Serial(2 * N, ctx);
  N_Vector x = N_VNew_Serial(N, ctx), v = N_VNew_Serial(N, ctx);
  int fail = run_arkode(ctx, ya) || run_cvode(ctx, yc) || run_ceode(ctx, x, v);
  double e_ark = 0, e_ce = 0;
  for (int i = 0; i < 2 * N; ++i) {
    const double ref = NV_Ith_S(yc, i);
    const double ce = i < N ? NV_Ith_S(x, i) : NV_Ith_S(v, i - N);
    e_ark = fmax(e_ark, fabs(NV_Ith_S(ya, i) - ref));
    e_ce = fmax(e_ce, fabs(ce - ref));
  }
  printf("x_0(5) = %.12f (CVODE)\n", NV_Ith_S(yc, 0));
  printf("max |ERKStep - CVODE| = %.3e, max |CEODE - CVODE| = %.3e\n", e_ark, e_ce);
  const int ok = !fail && e_ark <= 1e-7 && e_ce <= 1e-7;
  printf("%s\n", ok ? "PASSED" : "FAILED");
  N_VDestroy(ya), N_VDestroy(yc), N_VDestroy(x), N_VDestroy(v);
  SUNContext_Free(&ctx);
  return ok ? 0 : 1;
}
