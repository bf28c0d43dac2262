/* -----------------------------------------------------------------------------
 * mri_two_scale: CEODE as the fast integrator inside ARKODE's MRIStep.
 *
 * Problem: a fast oscillator q (frequency omega = 10) whose equilibrium is a
 * slow first-order field s,
 *     q'' = -omega^2 (q - s)                 (fast: CEODE)
 *     s'  = -lambda s + cos(t)               (slow: MRIStep's explicit part)
 * lambda = 2, t in [0, 2]. MRIStep sees the first-order state y = [x; v] with
 * x = (q, s), v = (p, w), a serial vector of 2n = 4 entries: the fast part is
 * [p, w; -omega^2 (q - s), 0], the slow part [0, -lambda s + cos t; 0, 0]
 * (w = 0 throughout; s moves only through the MRI forcing of the x-part).
 *
 * Reference solution (closed form): with a = lambda/(1+lambda^2),
 * b = 1/(1+lambda^2), C = s0 - a,
 *     s(t) = C e^{-lambda t} + a cos t + b sin t,
 *     q(t) = K e^{-lambda t} + M cos t + N sin t + c1 cos(omega t) + c2 sin(omega t),
 * K = omega^2 C/(omega^2 + lambda^2), M = omega^2 a/(omega^2 - 1),
 * N = omega^2 b/(omega^2 - 1). The initial data lie on the slow manifold
 * (c1 = c2 = 0): the fast mode is excited only by integration errors.
 *
 * Method: MRIStep with ARKODE_MRI_GARK_ERK33a (third order), slow steps
 * H = 0.05 ... 0.00625; CEODE G4_A34 inside with largest inner step 0.001
 * (h omega = 0.01, small enough that the inner error does not show).
 *
 * Exit code 0 only if the order from a log-log fit of the max error at t = 2 is
 * in [2.8, 3.1] and the finest error is below 1e-6. bench/mri_inner_cost compares the fast
 * f evaluations with an ARKStep RK4 inner stepper.
 * ---------------------------------------------------------------------------*/
#include <arkode/arkode_mristep.h>
#include <ceode/ceode.h>
#include <ceode/ceode_stepper.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>

#include "mri_two_scale_model.h"

#define OMEGA 10.0
#define TEND 2.0
#define HINNER 0.001
#define NRUNS 4

#if SUNDIALS_VERSION_MAJOR >= 7
#define CTX_COMM SUN_COMM_NULL
#else
#define CTX_COMM NULL
#endif

static int check(int flag, const char* call) {
  if (flag < 0) fprintf(stderr, "ERROR: %s returned %d\n", call, flag);
  return flag < 0;
}

/* One MRI run with nslow slow steps; returns the max error at TEND (or -1). */
static double run(SUNContext ctx, int nslow, long* nfast, long* nrestart) {
  TwoScale m = {OMEGA, 0.0, 0};
  double err = -1;
  sunrealtype t = 0;
  N_Vector x0 = N_VNew_Serial(2, ctx), v0 = N_VNew_Serial(2, ctx), y = N_VNew_Serial(4, ctx);
  two_scale_state(&m, 0, y);
  NV_Ith_S(x0, 0) = NV_Ith_S(y, 0);
  NV_Ith_S(x0, 1) = NV_Ith_S(y, 1);
  NV_Ith_S(v0, 0) = NV_Ith_S(y, 2);
  NV_Ith_S(v0, 1) = 0;

  void* ce = CEodeCreate(ctx);
  MRIStepInnerStepper inner = NULL;
  void* mri = NULL;
  MRIStepCoupling C = NULL;
  if (ce == NULL) goto done;
  if (check(CEodeInit(ce, two_scale_fast_accel, 0, x0, v0), "CEodeInit")) goto done;
  if (check(CEodeSetUserData(ce, &m), "CEodeSetUserData")) goto done;
  if (check(CEodeSetMethodByName(ce, "G4_A34"), "CEodeSetMethodByName")) goto done;
  if (check(CEodeSetFixedStep(ce, HINNER), "CEodeSetFixedStep")) goto done;
  if (check(CEodeCreateMRIStepInnerStepper(ce, &inner), "CEodeCreateMRIStepInnerStepper"))
    goto done;

  mri = MRIStepCreate(two_scale_slow_rhs, NULL, 0, y, inner, ctx);
  if (mri == NULL) goto done;
  C = MRIStepCoupling_LoadTable(ARKODE_MRI_GARK_ERK33a);
  if (C == NULL || check(MRIStepSetCoupling(mri, C), "MRIStepSetCoupling")) goto done;
  if (check(MRIStepSetFixedStep(mri, TEND / nslow), "MRIStepSetFixedStep")) goto done;
  if (check(MRIStepSetMaxNumSteps(mri, 100000), "MRIStepSetMaxNumSteps")) goto done;
  if (check(MRIStepEvolve(mri, TEND, y, &t, ARK_NORMAL), "MRIStepEvolve")) goto done;
  if (check(CEodeGetNumInnerRestarts(ce, nrestart), "CEodeGetNumInnerRestarts")) goto done;

  err = two_scale_error(&m, t, y);
done:
  *nfast = m.nfast;
  MRIStepCoupling_Free(C);
  MRIStepFree(&mri);
  CEodeFreeMRIStepInnerStepper(&inner);
  CEodeFree(&ce);
  N_VDestroy(x0);
  N_VDestroy(v0);
  N_VDestroy(y);
  return err;
}

int main(void) {
  SUNContext ctx = NULL;
  if (check(SUNContext_Create(CTX_COMM, &ctx), "SUNContext_Create")) return 1;
  printf("MRI-GARK-ERK33a outside, CEODE G4_A34 inside (h <= %g), omega = %g\n", HINNER, OMEGA);
  printf("%8s %8s %14s %12s %10s\n", "H", "steps", "max error", "fast f", "restarts");
  double lx[NRUNS], ly[NRUNS];
  int ok = 1;
  for (int i = 0; i < NRUNS; ++i) {
    const int nslow = 40 << i;
    long nfast = 0, nrestart = 0;
    const double err = run(ctx, nslow, &nfast, &nrestart);
    if (!(err > 0)) {
      ok = 0;
      break;
    }
    printf("%8.4f %8d %14.6e %12ld %10ld\n", TEND / nslow, nslow, err, nfast, nrestart);
    lx[i] = log(TEND / nslow);
    ly[i] = log(err);
  }
  double order = 0;
  if (ok) {
    double mx = 0, my = 0, sxy = 0, sxx = 0;
    for (int i = 0; i < NRUNS; ++i) mx += lx[i] / NRUNS, my += ly[i] / NRUNS;
    for (int i = 0; i < NRUNS; ++i) {
      sxy += (lx[i] - mx) * (ly[i] - my);
      sxx += (lx[i] - mx) * (lx[i] - mx);
    }
    order = sxy / sxx;
    printf("MRI order from the log-log fit: %.3f (expected 2.8 .. 3.1)\n", order);
    ok = order >= 2.8 && order <= 3.1 && exp(ly[NRUNS - 1]) < 1e-6;
  }
  SUNContext_Free(&ctx);
  printf("%s\n", ok ? "PASSED" : "FAILED");
  return ok ? 0 : 1;
}
