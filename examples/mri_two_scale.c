/* -----------------------------------------------------------------------------
 * mri_two_scale: CEODE as the fast integrator inside ARKODE's MRIStep, side by
 * side with an ARKStep RK4 inner stepper.
 *
 * Problem (examples/mri_two_scale_model.h, closed-form solution there): a stiff
 * fast oscillator q (frequency omega = 100) whose equilibrium is a slow
 * first-order field s, vibrating about it with amplitude A = 0.1,
 *     q'' = -omega^2 (q - s)                 (fast: CEODE or RK4)
 *     s'  = -lambda s + cos t                (slow: MRIStep's explicit part)
 * lambda = 2, t in [0, 2], q(0) = q_slow(0) + A, exact solution
 *     s(t) = C e^{-lambda t} + a cos t + b sin t,
 *     q(t) = K e^{-lambda t} + M cos t + N sin t + A cos(omega t)
 * (constants in the model header). MRIStep sees y = [x; v], x = (q, s),
 * v = (p, w), a serial vector of 2n = 4 entries.
 *
 * Method: MRIStep with ARKODE_MRI_GARK_ERK33a (third order), slow steps
 * H = 0.0125 ... 0.00078125 (H omega <= 1.25, where the MRI order is a clean
 * 3); its fast stages are H/3 long. Inner steppers at a fixed largest step:
 * CEODE G8_O8 (order 8) at h = 3.5e-4, RK4 at h = 3.3e-5, each the step at
 * which its MRI error is within 1 % of the error with an exact inner solve at
 * every H (bench/mri_inner_cost), so the two columns are at equal error. The
 * inner solver must resolve the fast vibration; RK4 needs about 100 steps per
 * fast period, G8_O8 about 18. CEODE restarts at every stage (the forcing
 * changes), for one extra evaluation: it carries its history over
 * (docs/porting.md, "What a restart costs").
 *
 * Expected output: MRI order about 3.04 for both from a log-log fit of the max
 * error at t = 2, errors from 2.26e-6 down to 4.9e-10, CEODE's fast f
 * evaluations 0.03 to 0.07 of RK4's. On the slow manifold instead (A = 0), the
 * stage is short against the fast period, one RK4 step per stage suffices and
 * CEODE's best is 0.55 to 0.8 of RK4 (bench/mri_inner_cost, docs/results.md).
 *
 * Exit code 0 only if both inner steppers give an MRI order in [2.8, 3.1],
 * CEODE's error is within 1 % of RK4's at every H, and CEODE's fast f
 * evaluations are at most a third of RK4's at every H (exact counts, made in
 * the fast right-hand side).
 * ---------------------------------------------------------------------------*/
#include <arkode/arkode_arkstep.h>
#include <arkode/arkode_mristep.h>
#include <ceode/ceode.h>
#include <ceode/ceode_stepper.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>

#include "mri_two_scale_model.h"

#define OMEGA 100.0
#define AMP 0.1
#define TEND 2.0
#define NRUNS 5
#define NSLOW0 160
#define H_CEODE 3.5e-4
#define H_RK4 3.3e-5

#if SUNDIALS_VERSION_MAJOR >= 7
#define CTX_COMM SUN_COMM_NULL
#else
#define CTX_COMM NULL
#endif

static int check(int flag, const char* call) {
  if (flag < 0) fprintf(stderr, "ERROR: %s returned %d\n", call, flag);
  return flag < 0;
}

/* CEODE G8_O8 as the inner stepper, started from y; *ce is its memory. */
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
  bad = bad || check(CEodeSetMethodByName(*ce, "G8_O8"), "CEodeSetMethodByName");
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
  TwoScale m = {OMEGA, AMP, 0};
  const double H = TEND / nslow;
  const double h = use_ceode ? H_CEODE : H_RK4;
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
      "MRI-GARK-ERK33a outside, omega = %g, A = %g; inner: CEODE G8_O8 (h = %g) | ARKStep RK4 "
      "(h = %g)\n",
      OMEGA, AMP, H_CEODE, H_RK4);
  printf("%10s %14s %10s | %14s %10s | %s\n", "H", "CEODE error", "fast f", "RK4 error", "fast f",
         "CEODE/RK4 fast f");
  double hs[NRUNS], ec[NRUNS], er[NRUNS], worst = 0;
  int ok = 1;
  for (int i = 0; i < NRUNS && ok; ++i) {
    const int nslow = NSLOW0 << i;
    long fc = 0, fr = 0;
    hs[i] = TEND / nslow;
    ec[i] = run(ctx, 1, nslow, &fc);
    er[i] = run(ctx, 0, nslow, &fr);
    ok = ec[i] > 0 && er[i] > 0 && fabs(ec[i] - er[i]) <= 0.01 * er[i];
    worst = fmax(worst, (double)fc / (double)fr);
    printf("%10.3e %14.6e %10ld | %14.6e %10ld | %.4f\n", hs[i], ec[i], fc, er[i], fr,
           (double)fc / (double)fr);
  }
  if (ok) {
    const double pc = loglog_slope(hs, ec, NRUNS), pr = loglog_slope(hs, er, NRUNS);
    printf("MRI order from the log-log fit: CEODE %.3f, RK4 %.3f (expected 2.8 .. 3.1)\n", pc, pr);
    printf("fast f: CEODE/RK4 at most %.4f at equal error (a third: %s)\n", worst,
           worst <= 1.0 / 3 ? "met" : "NOT met");
    ok = pc >= 2.8 && pc <= 3.1 && pr >= 2.8 && pr <= 3.1 && worst <= 1.0 / 3;
  }
  SUNContext_Free(&ctx);
  printf("%s\n", ok ? "PASSED" : "FAILED");
  return ok ? 0 : 1;
}
