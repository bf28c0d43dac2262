/* -----------------------------------------------------------------------------
 * bouncing_ball: events (root finding) with a restart after each one.
 *
 * Problem: a ball dropped from rest at height H0 = 1 m falls under gravity,
 *     y'' = -G,  G = 9.81,
 * and bounces on the floor y = 0 with restitution E = 0.8: at each impact the
 * velocity v becomes -E v. The impacts are the roots of g(t, y, v) = y with
 * direction -1 (the ball falling); CEodeEvolve returns CE_ROOT_RETURN at each,
 * the program reverses the velocity and restarts with CEodeReInit (a full
 * start: the velocity jumps, the solution is not smooth across the impact).
 * After the restart g = 0 at the start time: CEODE keeps that root function
 * inactive until the ball has left the floor, so the impact is not found again.
 *
 * Method: G4_A34 with the fixed step h = 0.01 s (--method, --h to change them).
 *
 * Reference (closed form): the first impact at t1 = sqrt(2 H0 / G), with the
 * speed u1 = G t1; the k-th bounce leaves with E^k u1 and flies 2 E^k u1 / G,
 * so t_{k+1} = t_k + 2 E^k t1. The motion between impacts is a parabola, which
 * every CEODE set (degree >= 3) integrates exactly: the event times carry
 * only the root finder's time tolerance, 100 ulp of |t| + |h| (7e-14 at t = 3),
 * passed on from impact to impact. Measured: 5e-15 at the first impact, 4.9e-13
 * at the eighth (G4_A34, h = 0.01); TIME_BOUND is 20x that. The program
 * exits 0 when NBOUNCE impacts are found, each within TIME_BOUND of the closed
 * form, in order, with CEodeGetRootInfo reporting -1 (y decreasing).
 *
 * Usage: bouncing_ball [--method NAME] [--h STEP]
 * ---------------------------------------------------------------------------*/
#include <ceode/ceode.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ceode_sundials_compat.h" /* SUN_COMM_NULL on SUNDIALS 6.4 */

#define GRAV 9.81
#define H0 1.0
#define RESTITUTION 0.8
#define NBOUNCE 8
#define TIME_BOUND 1e-11

static int rhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
  (void)t, (void)x, (void)v, (void)data;
  NV_Ith_S(f, 0) = -GRAV;
  return 0;
}

/* The floor: g = y. */
static int floor_contact(sunrealtype t, N_Vector x, N_Vector v, sunrealtype* g, void* data) {
  (void)t, (void)v, (void)data;
  g[0] = NV_Ith_S(x, 0);
  return 0;
}

static int check_flag(int flag, const char* call) {
  if (flag < 0) {
    fprintf(stderr, "ERROR: %s returned %d\n", call, flag);
    return 1;
  }
  return 0;
}

/* Integrates to the NBOUNCE-th impact; returns the largest event-time error, or -1 on failure.
 * CEodeReInit zeroes the counters: *nst and *nge sum them over the flights. */
static double bounce(void* mem, N_Vector x, N_Vector v, long* nst, long* nge) {
  const double t1 = sqrt(2.0 * H0 / GRAV);
  double texact = t1, speed = GRAV * t1, maxerr = 0.0;
  sunrealtype t = 0.0;
  int k, info = 0;
  long n = 0;
  for (k = 0; k < NBOUNCE; ++k) {
    const int flag = CEodeEvolve(mem, 100.0, x, v, &t, CE_NORMAL);
    if (flag != CE_ROOT_RETURN) {
      fprintf(stderr, "ERROR: impact %d not found (CEodeEvolve returned %d)\n", k + 1, flag);
      return -1;
    }
    if (check_flag(CEodeGetRootInfo(mem, &info), "CEodeGetRootInfo") || info != -1) return -1;
    printf("impact %d at t = %.15f (closed form %.15f), speed %.6f m/s\n", k + 1, t, texact,
           -NV_Ith_S(v, 0));
    if (fabs(t - texact) > maxerr) maxerr = fabs(t - texact);
    if (CEodeGetNumSteps(mem, &n) == CE_SUCCESS) *nst += n;
    if (CEodeGetNumGEvals(mem, &n) == CE_SUCCESS) *nge += n;
    /* The bounce: on the floor, velocity reversed and reduced; a full restart there. */
    NV_Ith_S(x, 0) = 0.0;
    NV_Ith_S(v, 0) = -RESTITUTION * NV_Ith_S(v, 0);
    if (check_flag(CEodeReInit(mem, t, x, v), "CEodeReInit")) return -1;
    speed *= RESTITUTION;
    texact += 2.0 * speed / GRAV;
  }
  return maxerr;
}

int main(int argc, char* argv[]) {
  const char* method = "G4_A34";
  sunrealtype h = 0.01;
  SUNContext ctx = NULL;
  N_Vector x = NULL, v = NULL;
  void* mem = NULL;
  int i, fail;
  long nge = 0, nst = 0;
  double maxerr;

  for (i = 1; i + 1 < argc; i += 2) {
    if (strcmp(argv[i], "--method") == 0) method = argv[i + 1];
    if (strcmp(argv[i], "--h") == 0) h = atof(argv[i + 1]);
  }
  if (check_flag(SUNContext_Create(SUN_COMM_NULL, &ctx), "SUNContext_Create")) return 1;
  x = N_VNew_Serial(1, ctx);
  v = N_VNew_Serial(1, ctx);
  mem = CEodeCreate(ctx);
  if (x == NULL || v == NULL || mem == NULL) return 1;
  NV_Ith_S(x, 0) = H0;
  NV_Ith_S(v, 0) = 0.0;

  fail = check_flag(CEodeInit(mem, rhs, 0.0, x, v), "CEodeInit") ||
         check_flag(CEodeSetMethodByName(mem, method), "CEodeSetMethodByName") ||
         check_flag(CEodeSetFixedStep(mem, h), "CEodeSetFixedStep") ||
         check_flag(CEodeRootInit(mem, 1, floor_contact), "CEodeRootInit");
  if (!fail) {
    int dir = -1; /* impacts only: the ball falling onto the floor */
    fail = check_flag(CEodeSetRootDirection(mem, &dir), "CEodeSetRootDirection");
  }
  maxerr = fail ? -1 : bounce(mem, x, v, &nst, &nge);
  printf(
      "%s, h = %g: %d impacts, max event-time error %.2e s (bound %.0e); %ld steps, %ld g "
      "evaluations\n",
      method, h, NBOUNCE, maxerr, TIME_BOUND, nst, nge);
  fail = fail || maxerr < 0 || maxerr > TIME_BOUND;
  printf("%s\n", fail ? "FAILED" : "PASSED");

  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  SUNContext_Free(&ctx);
  return fail ? 1 : 0;
}
