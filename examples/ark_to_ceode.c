/* -----------------------------------------------------------------------------
 * ark_to_ceode: an ark_analytic-style ERKStep program for a second-order system,
 * switched to CEODE through the first-order adapter.
 *
 * Problem: a damped chain of N = 10 unit masses between fixed walls, springs of
 * stiffness K and a damper C on every mass, written in first-order form
 *     y = [x; v],   x_i' = v_i,
 *     v_i' = K (x_{i-1} - 2 x_i + x_{i+1}) - C v_i,   x_0 = x_{N+1} = 0,
 * for 0 <= t <= 10, x_i(0) = 0.1 i (N + 1 - i) / (N + 1)^2, v_i(0) = 0 except
 * v_1(0) = 1. y is a serial vector of length 2N, as an ARKODE user writes it.
 *
 * Reference solution (exact): the modes phi_j(i) = sqrt(2/(N+1)) sin(i j pi/(N+1))
 * decouple the system into q_j'' + C q_j' + w_j^2 q_j = 0 with
 * w_j = 2 sqrt(K) sin(j pi / (2 (N+1))); every mode is underdamped (C < 2 w_1), so
 *     q_j(t) = exp(-C t/2) (A_j cos(d_j t) + B_j sin(d_j t)),  d_j = sqrt(w_j^2 - C^2/4),
 * A_j = q_j(0), B_j = (q_j'(0) + C A_j / 2) / d_j. exact() evaluates it.
 *
 * The switch: run_erkstep and run_ceode are the same function but for these five
 * lines (the right-hand side f, the vectors and the output loop are untouched):
 *   (1)  void* mem = ERKStepCreate(f, T0, y, ctx);
 *     -> void* mem = CEodeCreate(ctx);
 *   (2)  int flag = mem ? ERKStepSStolerances(mem, RTOL, ATOL) : -1;
 *     -> int flag = mem ? CEodeInitFirstOrder(mem, f, T0, y) || CEodeSetMethodByName(mem, "G5")
 *                       : -1;
 *   (3)  if (!flag) flag = ERKStepSetMaxNumSteps(mem, MXSTEPS);
 *     -> if (!flag) flag = CEodeSetFixedStep(mem, H) || CEodeSetVelocityDependence(mem, SUNTRUE);
 *   (4)  flag = ERKStepEvolve(mem, tout, y, &t, ARK_NORMAL);
 *     -> flag = CEodeEvolveFirstOrder(mem, tout, y, &t, CE_NORMAL);
 *   (5)  ERKStepFree(&mem);
 *     -> CEodeFree(&mem);
 * (2) and (3) each chain two CEODE calls where ERKStep needs one: CEODE has a fixed
 * step and a method name instead of tolerances, and must be told that f depends on
 * v (the damper). Each chained call is checked (|| stops at the first failure, whose
 * message CEODE prints).
 *
 * G5 at h = 2e-3 is CEODE's cheapest set for 1e-10 here; its stability guard warns
 * that G5 is weakly unstable (errors double every ~1.7e5 steps; this run takes 5000).
 *
 * Output: y and the error against exact() every 1 time unit, then the time of both
 * runs. Exit code 0 only if both runs stay within 1e-10 of the exact solution.
 * ---------------------------------------------------------------------------*/
#include <arkode/arkode_erkstep.h> /* ERKStep */
#include <ceode/ceode.h>           /* CEODE */
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <time.h>

#include "ceode_sundials_compat.h" /* SUN_COMM_NULL on SUNDIALS 6.4 */

#define N 10           /* masses */
#define K 1.0          /* spring stiffness */
#define C 0.05         /* damper */
#define T0 0.0         /* initial time */
#define TF 10.0        /* final time */
#define NOUT 10        /* outputs */
#define RTOL 1.0e-13   /* ERKStep tolerances */
#define ATOL 1.0e-15   /* ... */
#define MXSTEPS 100000 /* ERKStep steps per output */
#define H 2.0e-3       /* CEODE fixed step */
#define TOL 1.0e-10    /* answer right: max error against exact() */

static const double kPi = 3.14159265358979323846;

/* User-supplied right-hand side: the same for both integrators. */
static int f(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data) {
  const sunrealtype* x = N_VGetArrayPointer(y);
  const sunrealtype* v = x + N;
  sunrealtype* dx = N_VGetArrayPointer(ydot);
  sunrealtype* dv = dx + N;
  int i;
  (void)t;
  (void)user_data;
  for (i = 0; i < N; i++) {
    const sunrealtype left = i > 0 ? x[i - 1] : 0.0;
    const sunrealtype right = i < N - 1 ? x[i + 1] : 0.0;
    dx[i] = v[i];
    dv[i] = K * (left - 2.0 * x[i] + right) - C * v[i];
  }
  return 0;
}

static void initial(N_Vector y) {
  sunrealtype* d = N_VGetArrayPointer(y);
  int i;
  for (i = 0; i < N; i++) {
    d[i] = 0.1 * (i + 1) * (N - i) / ((N + 1.0) * (N + 1.0));
    d[N + i] = i == 0 ? 1.0 : 0.0;
  }
}

/* The exact solution at t, by modes (see the header). */
static void exact(double t, const double* y0, double* y) {
  int i, j;
  for (i = 0; i < 2 * N; i++) y[i] = 0.0;
  for (j = 1; j <= N; j++) {
    double q0 = 0.0, p0 = 0.0, phi[N];
    const double w = 2.0 * sqrt(K) * sin(j * kPi / (2.0 * (N + 1)));
    const double d = sqrt(w * w - 0.25 * C * C);
    double a, b, e, q, p;
    for (i = 0; i < N; i++) {
      phi[i] = sqrt(2.0 / (N + 1)) * sin((i + 1) * j * kPi / (N + 1));
      q0 += phi[i] * y0[i];
      p0 += phi[i] * y0[N + i];
    }
    a = q0;
    b = (p0 + 0.5 * C * q0) / d;
    e = exp(-0.5 * C * t);
    q = e * (a * cos(d * t) + b * sin(d * t));
    p = -0.5 * C * q + e * d * (-a * sin(d * t) + b * cos(d * t));
    for (i = 0; i < N; i++) {
      y[i] += q * phi[i];
      y[N + i] += p * phi[i];
    }
  }
}

/* Prints one output line; returns the max error against exact(). */
static double report(double t, N_Vector y, const double* y0) {
  double ref[2 * N], err = 0.0;
  const sunrealtype* d = N_VGetArrayPointer(y);
  int i;
  exact(t, y0, ref);
  for (i = 0; i < 2 * N; i++) err = fmax(err, fabs(d[i] - ref[i]));
  printf("  %5.2f  %12.9f  %12.9f  %12.9f   %.2e\n", t, d[0], d[N / 2], d[N], err);
  return err;
}

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* The original program: ERKStep, adaptive, on y = [x; v]. */
static int run_erkstep(SUNContext ctx, N_Vector y, const double* y0, double* maxerr) {
  sunrealtype t = T0, tout = T0;
  int iout;
  void* mem = ERKStepCreate(f, T0, y, ctx);
  int flag = mem ? ERKStepSStolerances(mem, RTOL, ATOL) : -1;
  if (!flag) flag = ERKStepSetMaxNumSteps(mem, MXSTEPS);
  for (iout = 1; !flag && iout <= NOUT; iout++) {
    tout = T0 + iout * (TF - T0) / NOUT;
    flag = ERKStepEvolve(mem, tout, y, &t, ARK_NORMAL);
    if (!flag) *maxerr = fmax(*maxerr, report(t, y, y0));
  }
  ERKStepFree(&mem);
  return flag;
}

/* The same program on CEODE: five lines changed (see the header). */
static int run_ceode(SUNContext ctx, N_Vector y, const double* y0, double* maxerr) {
  sunrealtype t = T0, tout = T0;
  int iout;
  void* mem = CEodeCreate(ctx);
  int flag = mem ? CEodeInitFirstOrder(mem, f, T0, y) || CEodeSetMethodByName(mem, "G5") : -1;
  if (!flag) flag = CEodeSetFixedStep(mem, H) || CEodeSetVelocityDependence(mem, SUNTRUE);
  for (iout = 1; !flag && iout <= NOUT; iout++) {
    tout = T0 + iout * (TF - T0) / NOUT;
    flag = CEodeEvolveFirstOrder(mem, tout, y, &t, CE_NORMAL);
    if (!flag) *maxerr = fmax(*maxerr, report(t, y, y0));
  }
  CEodeFree(&mem);
  return flag;
}

int main(void) {
  SUNContext ctx = NULL;
  N_Vector y = NULL;
  double y0[2 * N], err_erk = 0.0, err_ce = 0.0, t_erk, t_ce;
  int i, flag_erk, flag_ce, ok;
  if (SUNContext_Create(SUN_COMM_NULL, &ctx)) {
    fprintf(stderr, "ERROR: SUNContext_Create failed\n");
    return 1;
  }
  y = N_VNew_Serial(2 * N, ctx);
  if (y == NULL) {
    fprintf(stderr, "ERROR: N_VNew_Serial failed\n");
    SUNContext_Free(&ctx);
    return 1;
  }
  initial(y);
  for (i = 0; i < 2 * N; i++) y0[i] = NV_Ith_S(y, i);
  printf("Damped spring chain, N = %d, K = %g, C = %g, first-order form y = [x; v]\n", N, K, C);
  printf("      t          x_1           x_%d          v_1      max error\n", N / 2 + 1);

  printf("ERKStep (default table, rtol = %g, atol = %g):\n", RTOL, ATOL);
  t_erk = now();
  flag_erk = run_erkstep(ctx, y, y0, &err_erk);
  t_erk = now() - t_erk;

  initial(y);
  printf("CEODE G5 through CEodeInitFirstOrder (h = %g):\n", H);
  t_ce = now();
  flag_ce = run_ceode(ctx, y, y0, &err_ce);
  t_ce = now() - t_ce;

  printf("ERKStep: flag %d, max error %.2e, %.4f s\n", flag_erk, err_erk, t_erk);
  printf("CEODE:   flag %d, max error %.2e, %.4f s\n", flag_ce, err_ce, t_ce);
  ok = flag_erk == 0 && flag_ce == 0 && err_erk <= TOL && err_ce <= TOL;
  printf("%s: both within %g of the exact solution\n", ok ? "PASSED" : "FAILED", TOL);
  N_VDestroy(y);
  SUNContext_Free(&ctx);
  return ok ? 0 : 1;
}
