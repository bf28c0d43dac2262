/* -----------------------------------------------------------------------------
 * stability: where a conditionally explicit method stops being stable, from
 * the analysis (ceode_stability.h) and from a run.
 *
 * Problem (docs/theory.md section 9): the undamped oscillator x'' = -w^2 x,
 * w = 1, x(0) = 1, x'(0) = 0, so Omega = w h. A method is stable at Omega when
 * the spectral radius rho of its amplification matrix is <= 1;
 * CEodeStabilityLimit returns the largest Omega_max with rho <= 1 on all of
 * (0, Omega_max], computed from CEODE's own step.
 *
 * Reference solution: for the G3 sets with beta = 1/2 the limit is known in
 * closed form, Omega_max = 2 / sqrt(2 alpha - 1) (central differences,
 * alpha = 1: 2; alpha = 4/3: sqrt(12/5) = 1.549193; docs/stability.md). For each of the two sets
 * the example
 *  1. computes Omega_max and checks it within 2e-3 (the scan's grid is 1e-3),
 *  2. runs 50 steps at h = 0.95 Omega_max (the solution must stay bounded,
 *     |x| <= 10) and at h = 1.05 Omega_max (it must grow, |x| >= 1e3), with
 *     the runtime stability guard off so that the unstable run is allowed.
 * Exit code 0 when every check holds.
 * ---------------------------------------------------------------------------*/
#include <ceode/ceode.h>
#include "ceode_sundials_compat.h" /* SUN_COMM_NULL on SUNDIALS 6.4 */
#include <ceode/ceode_stability.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>

#define NSTEPS 50

static int check_flag(int flag, const char* call) {
  if (flag < 0) {
    fprintf(stderr, "ERROR: %s returned %d\n", call, flag);
    return 1;
  }
  return 0;
}

static int oscillator(sunrealtype t, N_Vector x, N_Vector v, N_Vector a, void* data) {
  (void)t, (void)v, (void)data;
  NV_Ith_S(a, 0) = -NV_Ith_S(x, 0);
  return 0;
}

/* Largest |x| over NSTEPS steps of h (< 0 on failure). */
static sunrealtype max_amplitude(SUNContext ctx, const char* method, sunrealtype h) {
  N_Vector x = N_VNew_Serial(1, ctx), v = N_VNew_Serial(1, ctx);
  void* mem = CEodeCreate(ctx);
  sunrealtype t = 0.0, amax = 1.0;
  int k, fail;
  if (x == NULL || v == NULL || mem == NULL) return -1.0;
  NV_Ith_S(x, 0) = 1.0;
  NV_Ith_S(v, 0) = 0.0;
  fail = check_flag(CEodeInit(mem, oscillator, 0.0, x, v), "CEodeInit") ||
         check_flag(CEodeSetMethodByName(mem, method), "CEodeSetMethodByName") ||
         check_flag(CEodeSetFixedStep(mem, h), "CEodeSetFixedStep") ||
         check_flag(CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0), "CEodeSetStabilityGuard");
  for (k = 0; !fail && k < NSTEPS; ++k) {
    fail = check_flag(CEodeEvolve(mem, 1e9, x, v, &t, CE_ONE_STEP), "CEodeEvolve");
    if (!fail && fabs(NV_Ith_S(x, 0)) > amax) amax = fabs(NV_Ith_S(x, 0));
  }
  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  return fail ? -1.0 : amax;
}

/* The three checks for one named G3 set; returns the number that failed. */
static int study(SUNContext ctx, const char* method) {
  sunrealtype params[8], limit = 0.0, exact, below, above;
  int degree = 0, bad = 0;
  if (check_flag(CEodeGetMethodParams(method, &degree, params, 8), "CEodeGetMethodParams") ||
      check_flag(CEodeStabilityLimit(degree, params, 0.0, &limit), "CEodeStabilityLimit")) {
    return 3;
  }
  exact = 2.0 / sqrt(2.0 * params[0] - 1.0);
  below = max_amplitude(ctx, method, 0.95 * limit);
  above = max_amplitude(ctx, method, 1.05 * limit);
  printf("%-7s alpha = %.4f: Omega_max = %.6f (closed form %.6f)\n", method, params[0], limit,
         exact);
  printf("        max |x| over %d steps: %.3e at 0.95 Omega_max, %.3e at 1.05 Omega_max\n", NSTEPS,
         below, above);
  if (!(fabs(limit - exact) <= 2e-3)) {
    printf("FAILED: limit off the closed form\n");
    ++bad;
  }
  if (!(below >= 0.0 && below <= 10.0)) {
    printf("FAILED: the run below the limit did not stay bounded\n");
    ++bad;
  }
  if (!(above >= 1e3)) {
    printf("FAILED: the run above the limit did not grow\n");
    ++bad;
  }
  return bad;
}

int main(void) {
  SUNContext ctx = NULL;
  int bad;
  if (check_flag(SUNContext_Create(SUN_COMM_NULL, &ctx), "SUNContext_Create")) return 1;
  bad = study(ctx, "G3_CD") + study(ctx, "G3_A43");
  SUNContext_Free(&ctx);
  printf(bad == 0 ? "PASSED\n" : "FAILED\n");
  return bad != 0;
}
