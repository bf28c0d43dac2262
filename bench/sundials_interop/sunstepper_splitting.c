/* -----------------------------------------------------------------------------
 * sunstepper_splitting: CEODE's SUNStepper (SUNDIALS >= 7.2) inside ARKODE's
 * SplittingStep and MRIStep, on the two-scale problem of examples/mri_two_scale.c
 * (q'' = -omega^2 (q - s) fast, s' = -lambda s + cos t slow, omega = 10; the
 * model and its closed form from examples/mri_two_scale_model.h), y = [q, s, p, w] serial.
 *
 *   1. SplittingStep, Strang: CEODE (G4_A34, h <= 1e-3) for the fast partition,
 *      ERKStep (order 4, h = 1e-3) for the slow one; order of a log-log fit of the
 *      max error at t = 2 over H = 0.1 .. 0.0125 (expected about 2).
 *   2. MRIStep ERK33a with CEODE through MRIStepInnerStepper_CreateFromSUNStepper
 *      (expected about 3).
 *   3. SplittingStep Yoshida (4th order, negative substeps): CEODE must refuse.
 * Exit code 0 when all three hold (Strang order in [1.8, 2.2], MRI in [2.8, 3.1]).
 * On SUNDIALS < 7.2 the program only says so and exits 77 (ctest: skipped).
 * ---------------------------------------------------------------------------*/
#include <ceode/ceode.h>
#include <ceode/ceode_stepper.h>
#include <stdio.h>

#ifndef CEODE_HAVE_SUNSTEPPER
int main(void) {
  printf("sunstepper_splitting needs SUNDIALS >= 7.2 (built against %s): nothing to do.\n",
         SUNDIALS_VERSION);
  return 77;
}
#else
#include <arkode/arkode_erkstep.h>
#include <arkode/arkode_splittingstep.h>
#include <math.h>
#include <nvector/nvector_serial.h>

#include "../../examples/mri_two_scale_model.h"

#define OMEGA 10.0
#define TEND 2.0

/* kind 0: Strang, 1: MRI ERK33a, 2: Yoshida 4th order. Returns the error or -1. */
static double run(SUNContext ctx, int kind, int nslow) {
  N_Vector y = N_VNew_Serial(4, ctx), x0 = N_VNew_Serial(2, ctx), v0 = N_VNew_Serial(2, ctx);
  TwoScale m = {OMEGA, 0.0, 0};
  two_scale_state(&m, 0, y);
  NV_Ith_S(x0, 0) = NV_Ith_S(y, 0), NV_Ith_S(x0, 1) = NV_Ith_S(y, 1);
  NV_Ith_S(v0, 0) = NV_Ith_S(y, 2), NV_Ith_S(v0, 1) = 0;
  void* ce = CEodeCreate(ctx);
  void *erk = NULL, *outer = NULL;
  SUNStepper steppers[2] = {NULL, NULL};
  MRIStepInnerStepper inner = NULL;
  double err = -1;
  sunrealtype t = 0;
  int flag = CEodeInit(ce, two_scale_fast_accel, 0, x0, v0);
  if (!flag) flag = CEodeSetUserData(ce, &m);
  if (!flag) flag = CEodeSetMethodByName(ce, "G4_A34");
  if (!flag) flag = CEodeSetFixedStep(ce, 1e-3);
  if (!flag) flag = CEodeCreateSUNStepper(ce, &steppers[0]);
  if (flag) goto done;
  if (kind == 1) {
    if (MRIStepInnerStepper_CreateFromSUNStepper(steppers[0], &inner)) goto done;
    outer = MRIStepCreate(two_scale_slow_rhs, NULL, 0, y, inner, ctx);
    MRIStepCoupling C = MRIStepCoupling_LoadTable(ARKODE_MRI_GARK_ERK33a);
    flag = MRIStepSetCoupling(outer, C);
    MRIStepCoupling_Free(C);
  } else {
    erk = ERKStepCreate(two_scale_slow_rhs, 0, y, ctx);
    if (ARKodeSetFixedStep(erk, 1e-3) || ARKodeCreateSUNStepper(erk, &steppers[1])) goto done;
    outer = SplittingStepCreate(steppers, 2, 0, y, ctx);
    SplittingStepCoefficients c = SplittingStepCoefficients_LoadCoefficients(
        kind == 0 ? ARKODE_SPLITTING_STRANG_2_2_2 : ARKODE_SPLITTING_YOSHIDA_4_4_2);
    flag = SplittingStepSetCoefficients(outer, c);
    SplittingStepCoefficients_Destroy(&c);
  }
  if (!flag) flag = ARKodeSetFixedStep(outer, TEND / nslow);
  if (!flag) flag = ARKodeSetMaxNumSteps(outer, 100000);
  if (!flag) flag = ARKodeEvolve(outer, TEND, y, &t, ARK_NORMAL);
  if (flag >= 0) err = two_scale_error(&m, t, y);
  if (kind == 2 && flag < 0) {
    const char* msg = NULL;
    CEodeGetLastErrorMessage(ce, &msg);
    printf("Yoshida (negative substeps): ARKodeEvolve = %d, CEODE says: %s\n", flag, msg);
  }
done:
  ARKodeFree(&outer);
  MRIStepInnerStepper_Free(&inner);
  /* SUNStepper_Destroy dereferences its argument: only non-NULL steppers. */
  for (int i = 0; i < 2; ++i)
    if (steppers[i] != NULL) SUNStepper_Destroy(&steppers[i]);
  ARKodeFree(&erk);
  CEodeFree(&ce);
  N_VDestroy(y), N_VDestroy(x0), N_VDestroy(v0);
  return err;
}

static double fit_order(SUNContext ctx, int kind, const char* name) {
  double mx = 0, my = 0, sxy = 0, sxx = 0, lx[4], ly[4];
  for (int i = 0; i < 4; ++i) {
    const int n = (kind == 1 ? 40 : 20) << i;
    const double e = run(ctx, kind, n);
    printf("%-8s H = %.5f  max error = %.6e\n", name, TEND / n, e);
    if (!(e > 0)) return 0;
    lx[i] = log(TEND / n), ly[i] = log(e), mx += lx[i] / 4, my += ly[i] / 4;
  }
  for (int i = 0; i < 4; ++i)
    sxy += (lx[i] - mx) * (ly[i] - my), sxx += (lx[i] - mx) * (lx[i] - mx);
  printf("%-8s order (log-log fit) = %.3f\n", name, sxy / sxx);
  return sxy / sxx;
}

int main(void) {
  SUNContext ctx = NULL;
  if (SUNContext_Create(SUN_COMM_NULL, &ctx)) return 1;
  printf("SUNDIALS %s\n", SUNDIALS_VERSION);
  const double p_strang = fit_order(ctx, 0, "Strang");
  const double p_mri = fit_order(ctx, 1, "MRI");
  const double e_yoshida = run(ctx, 2, 20);
  SUNContext_Free(&ctx);
  const int ok =
      p_strang >= 1.8 && p_strang <= 2.2 && p_mri >= 2.8 && p_mri <= 3.1 && e_yoshida < 0;
  printf("%s\n", ok ? "PASSED" : "FAILED");
  return ok ? 0 : 1;
}
#endif
