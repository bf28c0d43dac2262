/* -----------------------------------------------------------------------------
 * kepler_orbits: counting orbits with a root function, as SUNDIALS'
 * ark_kepler --count-orbits does.
 *
 * Problem: SUNDIALS' Kepler problem (examples/arkode/C_serial/ark_kepler.c),
 *     q'' = -q / |q|^3,  q in R^2,  eccentricity e = 0.6,
 *     q(0) = (1 - e, 0),  q'(0) = (0, sqrt((1 + e) / (1 - e))),
 * period 2 pi, t in [0, 20 pi + 1] (a little over 10 orbits). The body starts
 * at pericentre on the positive q1 axis, moving up: each orbit ends when q2
 * crosses 0 upwards. The root function is g = q2 with direction +1; g = 0 at
 * the start, so CEODE keeps it inactive until q2 leaves 0 and the start does
 * not count as an orbit.
 *
 * Method: G8_O8 with error control, rtol = atol = 1e-10 (--method, --rtol).
 * The events are located on CEODE's dense output: no f evaluation is spent on
 * them (the run reports its g evaluations).
 *
 * Reference: the exact solution passes pericentre at t = 2 pi k. The program
 * exits 0 when NORBITS orbits are counted, every event reports direction +1,
 * and each event time is within TIME_BOUND of 2 pi k. Measured at the default
 * settings: 2880 steps, 2948 f and 2952 g evaluations, largest event-time
 * error 6.7e-8 at the tenth orbit (the phase error of ten orbits, which the
 * tolerance sets: kepler_adaptive's |q(20 pi) - q(0)| is 8.8e-8 at this rtol);
 * TIME_BOUND is 7x that. G5_O4 at the same rtol: 1.1e-8.
 *
 * Usage: kepler_orbits [--method NAME] [--rtol R]
 * ---------------------------------------------------------------------------*/
#include <ceode/ceode.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ceode_sundials_compat.h" /* SUN_COMM_NULL on SUNDIALS 6.4 */

#define ECC 0.6
#define NORBITS 10
#define TIME_BOUND 5e-7

static int rhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
  const sunrealtype q1 = NV_Ith_S(x, 0), q2 = NV_Ith_S(x, 1);
  const sunrealtype r = sqrt(q1 * q1 + q2 * q2);
  const sunrealtype r3 = r * r * r;
  (void)t, (void)v, (void)data;
  NV_Ith_S(f, 0) = -q1 / r3;
  NV_Ith_S(f, 1) = -q2 / r3;
  return 0;
}

/* The pericentre side of the q1 axis: g = q2 (its upward crossings end the orbits). */
static int axis_crossing(sunrealtype t, N_Vector x, N_Vector v, sunrealtype* g, void* data) {
  (void)t, (void)v, (void)data;
  g[0] = NV_Ith_S(x, 1);
  return 0;
}

static int check_flag(int flag, const char* call) {
  if (flag < 0) {
    fprintf(stderr, "ERROR: %s returned %d\n", call, flag);
    return 1;
  }
  return 0;
}

/* Counts the orbits up to tend; *maxerr: the largest |t_event - 2 pi k|. -1: a failure. */
static int count_orbits(void* mem, N_Vector x, N_Vector v, sunrealtype tend, double* maxerr) {
  const double two_pi = 8.0 * atan(1.0);
  sunrealtype t = 0.0;
  int orbits = 0, info = 0, flag = CE_ROOT_RETURN;
  *maxerr = 0.0;
  while (flag == CE_ROOT_RETURN) {
    flag = CEodeEvolve(mem, tend, x, v, &t, CE_NORMAL);
    if (check_flag(flag, "CEodeEvolve")) return -1;
    if (flag != CE_ROOT_RETURN) break;
    if (check_flag(CEodeGetRootInfo(mem, &info), "CEodeGetRootInfo")) return -1;
    if (info != 1) {
      fprintf(stderr, "ERROR: event at t = %.15f with direction %d\n", t, info);
      return -1;
    }
    ++orbits;
    if (fabs(t - two_pi * orbits) > *maxerr) *maxerr = fabs(t - two_pi * orbits);
    printf("orbit %2d completed at t = %.12f (2 pi k: %.12f)\n", orbits, t, two_pi * orbits);
  }
  return orbits;
}

int main(int argc, char* argv[]) {
  const char* method = "G8_O8";
  sunrealtype rtol = 1e-10;
  SUNContext ctx = NULL;
  N_Vector x = NULL, v = NULL;
  void* mem = NULL;
  int i, fail, orbits = -1, dir = 1;
  long nst = 0, nfe = 0, nge = 0;
  double maxerr = 0.0;

  for (i = 1; i + 1 < argc; i += 2) {
    if (strcmp(argv[i], "--method") == 0) method = argv[i + 1];
    if (strcmp(argv[i], "--rtol") == 0) rtol = atof(argv[i + 1]);
  }
  if (check_flag(SUNContext_Create(SUN_COMM_NULL, &ctx), "SUNContext_Create")) return 1;
  x = N_VNew_Serial(2, ctx);
  v = N_VNew_Serial(2, ctx);
  mem = CEodeCreate(ctx);
  if (x == NULL || v == NULL || mem == NULL) return 1;
  NV_Ith_S(x, 0) = 1.0 - ECC;
  NV_Ith_S(x, 1) = 0.0;
  NV_Ith_S(v, 0) = 0.0;
  NV_Ith_S(v, 1) = sqrt((1.0 + ECC) / (1.0 - ECC));

  fail = check_flag(CEodeInit(mem, rhs, 0.0, x, v), "CEodeInit") ||
         check_flag(CEodeSetMethodByName(mem, method), "CEodeSetMethodByName") ||
         check_flag(CEodeSStolerances(mem, rtol, rtol), "CEodeSStolerances") ||
         check_flag(CEodeRootInit(mem, 1, axis_crossing), "CEodeRootInit") ||
         check_flag(CEodeSetRootDirection(mem, &dir), "CEodeSetRootDirection");
  if (!fail) orbits = count_orbits(mem, x, v, 8.0 * atan(1.0) * NORBITS + 1.0, &maxerr);
  CEodeGetNumSteps(mem, &nst);
  CEodeGetNumRhsEvals(mem, &nfe);
  CEodeGetNumGEvals(mem, &nge);
  printf(
      "%s, rtol %.0e: %d orbits, max event-time error %.2e (bound %.0e); %ld steps, %ld f, "
      "%ld g evaluations\n",
      method, rtol, orbits, maxerr, TIME_BOUND, nst, nfe, nge);
  fail = fail || orbits != NORBITS || maxerr > TIME_BOUND;
  printf("%s\n", fail ? "FAILED" : "PASSED");

  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  SUNContext_Free(&ctx);
  return fail ? 1 : 0;
}
