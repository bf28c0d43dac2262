/* -----------------------------------------------------------------------------
 * mri_two_scale: CEODE as the fast integrator inside ARKODE's MRIStep, side by
 * side with an ARKStep RK4 inner stepper.
 *
 * Problem (examples/mri_two_scale_model.h, closed-form solution there): a fast
 * oscillator q (frequency omega = 10) whose equilibrium is a slow first-order
 * field s,
 *     q'' = -omega^2 (q - s)                 (fast: CEODE or RK4)
 *     s'  = -lambda s + cos t                (slow: MRIStep's explicit part)
 * lambda = 2, t in [0, 2], started on the slow manifold. MRIStep sees y = [x; v],
 * x = (q, s), v = (p, w), a serial vector of 2n = 4 entries.
 *
 * Method: MRIStep with ARKODE_MRI_GARK_ERK33a (third order), slow steps
 * H = 0.05 ... 0.00625; its fast stages are H/3 long. Inner step rule: n steps
 * per stage, h = H/(3n): CEODE G4_A34 with n = 3, RK4 with n = 1, the fewest
 * steps with which each one's MRI error is within 10 % of the error with an
 * exact inner solve (bench/mri_inner_cost equal-error), so the two columns are
 * at equal error.
 *
 * Why omega = 10 and this H range: the MRI order is a clean 3 only where
 * H omega <~ 1.25; at larger H omega the forcing polynomial's kinks between
 * stages excite the undamped fast mode and the error falls irregularly with H
 * (order 2.76 at omega = 100 over H = 0.2 .. 0.0125, 1.24 at omega = 300). In
 * that range a stage is short against the fast period, RK4 needs one step
 * (4 f) per stage, and CEODE a step and a restart per stage: CEODE does NOT
 * reach a third of RK4's fast f here (ratio about 1.0). Where it does (0.16 to
 * 0.28 of RK4 at omega = 100, H >= 0.025) the order is not in the asymptotic
 * range; docs/porting.md ("Measured") gives the numbers and the reasoning.
 *
 * Exit code 0 only if both inner steppers give an MRI order in [2.8, 3.1] from
 * a log-log fit of the max error at t = 2, the finest CEODE error is below
 * 1e-6, and CEODE's error is within 10 % of RK4's at every H. The ratio of fast
 * f evaluations is printed, not checked (it is the measured result).
 * ---------------------------------------------------------------------------*/
#include <arkode/arkode_arkstep.h>
#include <arkode/arkode_mristep.h>
#include <ceode/ceode.h>
#include <ceode/ceode_stepper.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>

#include "mri_two_scale_model.h"

#define OMEGA 10.0
#define TEND 2.0
#define NRUNS 4
#define NSUB_CEODE 3
#define NSUB_RK4 1

#if SUNDIALS_VERSION_MAJOR >= 7
#define CTX_COMM SUN_COMM_NULL
#else
#define CTX_COMM NULL
#endif

static int check(int flag, const char* call) {
  if (flag < 0) fprintf(stderr, "ERROR: %s returned %d\n", call, flag);
  return flag < 0;
}

/* CEODE G4_A34 as the inner stepper, started from y; *ce is its memory. */
static int make_ceode(SUNContext ctx, N_Vector y, double h, TwoScale* m, void** ce,
                      MRIStepInnerStepper* inner) {
  N_Vector x0 = N_VNew_Serial(2, ctx), v0 = N_VNew_Serial(2, ctx);
  NV_Ith_S(x0, 0) = NV_Ith_S(y, 0);
  NV_Ith_S(x0, 1) = NV_Ith_S(y, 1);
  NV_Ith_S(v0, 0) = NV_Ith_S(y, 2);
  NV_Ith_S(v0, 1) = NV_Ith_S(y, 3);
  *ce = CEodeCreate(ctx);
  int bad = *ce == NULL || check(CEodeInit(*ce, two_scale_fast_accel, 0, x0, v0), "CEodeInit");
  bad = bad || check(CEodeSetUserData(*ce, m), "CEodeSetUserData");
  bad = bad || check(CEodeSetMethodByName(*ce, "G4_A34"), "CEodeSetMethodByName");
  bad = bad || check(CEodeSetFixedStep(*ce, h), "CEodeSetFixedStep");
  bad = bad || check(CEodeCreateMRIStepInnerStepper(*ce, inner), "CEodeCreateMRIStepInnerStepper");
  N_VDestroy(x0);
  N_VDestroy(v0);
  return bad;
}

/* ARKStep with classic RK4 at fixed step h as the inner stepper; *ark is its memory. */
static int make_rk4(SUNContext ctx, N_Vector y, double h, TwoScale* m, void** ark,
                    MRIStepInnerStepper* inner) {
  *ark = ARKStepCreate(two_scale_fast_first_order, NULL, 0, y, ctx);
  if (*ark == NULL) return 1;
  ARKodeButcherTable B = two_scale_rk4_table();
  int bad = check(ARKStepSetTables(*ark, 4, 0, NULL, B), "ARKStepSetTables");
  ARKodeButcherTable_Free(B);
  bad = bad || check(ARKStepSetUserData(*ark, m), "ARKStepSetUserData");
  bad = bad || check(ARKStepSetFixedStep(*ark, h), "ARKStepSetFixedStep");
  bad = bad ||
        check(ARKStepCreateMRIStepInnerStepper(*ark, inner), "ARKStepCreateMRIStepInnerStepper");
  return bad;
}

/* One MRI run with nslow slow steps and CEODE (use_ceode) or RK4 inside; returns the max error at
 * TEND (or -1) and the fast f evaluations. */
static double run(SUNContext ctx, int use_ceode, int nslow, long* nfast) {
  TwoScale m = {OMEGA, 0.0, 0};
  const double H = TEND / nslow;
  const int nsub = use_ceode ? NSUB_CEODE : NSUB_RK4;
  const double h = H / (3 * nsub) * (1 + 1e-6); /* exactly nsub steps per stage */
  double err = -1;
  sunrealtype t = 0;
  N_Vector y = N_VNew_Serial(4, ctx);
  two_scale_state(&m, 0, y);
  void *imem = NULL, *mri = NULL;
  MRIStepInnerStepper inner = NULL;
  MRIStepCoupling C = NULL;
  if ((use_ceode ? make_ceode : make_rk4)(ctx, y, h, &m, &imem, &inner)) goto done;
  mri = MRIStepCreate(two_scale_slow_rhs, NULL, 0, y, inner, ctx);
  if (mri == NULL) goto done;
  C = MRIStepCoupling_LoadTable(ARKODE_MRI_GARK_ERK33a);
  if (C == NULL || check(MRIStepSetCoupling(mri, C), "MRIStepSetCoupling")) goto done;
  if (check(MRIStepSetFixedStep(mri, H), "MRIStepSetFixedStep")) goto done;
  if (check(MRIStepSetMaxNumSteps(mri, 100000), "MRIStepSetMaxNumSteps")) goto done;
  if (check(MRIStepEvolve(mri, TEND, y, &t, ARK_NORMAL), "MRIStepEvolve")) goto done;
  err = two_scale_error(&m, t, y);
done:
  *nfast = m.nfast;
  MRIStepCoupling_Free(C);
  MRIStepFree(&mri);
  if (use_ceode) {
    CEodeFreeMRIStepInnerStepper(&inner);
    CEodeFree(&imem);
  } else {
    MRIStepInnerStepper_Free(&inner);
    ARKStepFree(&imem);
  }
  N_VDestroy(y);
  return err;
}

/* Slope of the least-squares line through (log x, log y). */
static double loglog_slope(const double* x, const double* y, int n) {
  double mx = 0, my = 0, sxy = 0, sxx = 0;
  for (int i = 0; i < n; ++i) mx += log(x[i]) / n, my += log(y[i]) / n;
  for (int i = 0; i < n; ++i) {
    sxy += (log(x[i]) - mx) * (log(y[i]) - my);
    sxx += (log(x[i]) - mx) * (log(x[i]) - mx);
  }
  return sxy / sxx;
}

int main(void) {
  SUNContext ctx = NULL;
  if (check(SUNContext_Create(CTX_COMM, &ctx), "SUNContext_Create")) return 1;
  printf(
      "MRI-GARK-ERK33a outside, omega = %g; inner: CEODE G4_A34 (%d steps per stage) | "
      "ARKStep RK4 (%d)\n",
      OMEGA, NSUB_CEODE, NSUB_RK4);
  printf("%8s %14s %10s | %14s %10s | %s\n", "H", "CEODE error", "fast f", "RK4 error", "fast f",
         "CEODE/RK4 fast f");
  double hs[NRUNS], ec[NRUNS], er[NRUNS], worst = 0;
  int ok = 1;
  for (int i = 0; i < NRUNS && ok; ++i) {
    const int nslow = 40 << i;
    long fc = 0, fr = 0;
    hs[i] = TEND / nslow;
    ec[i] = run(ctx, 1, nslow, &fc);
    er[i] = run(ctx, 0, nslow, &fr);
    ok = ec[i] > 0 && er[i] > 0 && fabs(ec[i] - er[i]) <= 0.1 * er[i];
    worst = fmax(worst, (double)fc / (double)fr);
    printf("%8.5f %14.6e %10ld | %14.6e %10ld | %.3f\n", hs[i], ec[i], fc, er[i], fr,
           (double)fc / (double)fr);
  }
  if (ok) {
    const double pc = loglog_slope(hs, ec, NRUNS), pr = loglog_slope(hs, er, NRUNS);
    printf("MRI order from the log-log fit: CEODE %.3f, RK4 %.3f (expected 2.8 .. 3.1)\n", pc, pr);
    printf("fast f: CEODE/RK4 up to %.3f at equal error; a third is %s here (see the header)\n",
           worst, worst <= 1.0 / 3 ? "met" : "NOT met");
    ok = pc >= 2.8 && pc <= 3.1 && pr >= 2.8 && pr <= 3.1 && ec[NRUNS - 1] < 1e-6;
  }
  SUNContext_Free(&ctx);
  printf("%s\n", ok ? "PASSED" : "FAILED");
  return ok ? 0 : 1;
}
