/* -----------------------------------------------------------------------------
 * pendulum_dae: the pendulum as an index-3 constrained multibody DAE, solved
 * side by side by CEODE, ARKODE (RK3) and IDA, and timed in one run
 * (method.md sections 3, 6 and 7).
 *
 * Problem: the IFToMM simple pendulum (m = 1 kg point mass, massless rod
 * L = 1 m, g = 9.81) in the coordinates of its centre of mass q = (x, y, theta):
 *     M q'' + G(q)^T lambda = f,   M = diag(m, m, I_zz = 0),  f = (0, -m g, 0),
 *     Phi(q) = (x - L sin theta, y + L cos theta) = 0,  G = dPhi/dq,
 * released at rest from theta = 90 deg (x = L, y = 0), t in [0, 10] s. M is
 * singular (a point mass has no rotational inertia); only the saddle-point
 * matrix [[M, G^T], [G, 0]] is regular. Figures of every run, taken at every
 * step where the solver has q and q' at the same instant:
 *     error = max |E - E0|,  E = 1/2 m (x'^2 + y'^2) + 1/2 I_zz theta'^2 + m g y,
 *     drift = max |x^2 + y^2 - L^2|    (the paper's "assembly error"),
 *     vres  = max |G(q) q'|_inf        (velocity-level constraint residual).
 *
 * Solvers and formulations:
 *  - CEODE, index 3 with no index reduction: G5_ONES (the paper's Table 11 set),
 *    G3_CD (SHAKE) and G4_A34, fixed h = 1e-2 ... 1e-4 (1e-5 with --full),
 *    through CEodeSetConstraints, with the 5 x 5 saddle-point matrix
 *    [[M, G^T], [G, 0]] factored by SUNLinSol_Dense (attached explicitly: a
 *    mass function without an attached solver is refused by CEodeInit).
 *    G5_ONES is run twice: with the library's consistent start and with the
 *    paper's zero start of the higher derivatives (CEodeSetZeroStart), which
 *    is the configuration the paper's Table 11 was made with.
 *  - ARKODE ERKStep with Kutta's classic third-order table (c = 0, 1/2, 1;
 *    a21 = 1/2, a31 = -1, a32 = 2; b = 1/6, 2/3, 1/6) as a user Butcher table,
 *    same fixed steps, on the index-1 form: both constraints differentiated
 *    twice, G q'' = -(dG/dt) q', and the 5 x 5 saddle system for
 *    (x'', y'', theta'', lambda1, lambda2) solved at every stage (Gaussian
 *    elimination with partial pivoting; M alone is singular). (a) "RK3": no
 *    stabilisation; (b) "RK3+proj": after every step (ARK_ONE_STEP) the
 *    positions are moved to the nearest point of Phi(q) = 0 (minimum-norm
 *    Newton, q -= G^T (G G^T)^-1 Phi, to round-off), velocities untouched,
 *    then ERKStepReset. This is how the paper's Tables 9 and 10 were made.
 *    Both variants call ERKStepReset after every step: SUNDIALS before 6.6.2
 *    (Debian's is 6.4.1) wrongly treats every table with c_s = 1 as "first
 *    same as last" and reuses f(last stage) as f(t_n+1, y_n+1); for Kutta's
 *    table (a_3j != b_j) that silently drops the method to order 2 (2 f
 *    evaluations per step instead of 3; error 2.5e-3 instead of 5.05e-5 at
 *    h = 1e-2). The reset forces a fresh f at the start of the next step.
 *  - IDA (variable-step BDF, rtol = atol = 1e-4 ... 1e-10, 1e-11 with --full,
 *    SUNLinSol_Dense on a 10 x 10 SUNDenseMatrix) on the stabilised index-2
 *    GGL form (Gear-Gupta-Leimkuhler):
 *        q' = v + G^T mu,  M v' + G^T lambda = f,  Phi(q) = 0,  G(q) v = 0,
 *    with lambda, mu and (because I_zz = 0) theta' algebraic, excluded from the
 *    error test (IDASetId + IDASetSuppressAlg), as SUNDIALS' own slider-crank
 *    example does. Why GGL and not index 1: GGL keeps the position constraint
 *    (and the velocity constraint) satisfied to the Newton tolerance at every
 *    step with no projection, which is what a multibody user of IDA would run
 *    and the fair opponent of an index-3 method that has no drift; the index-1
 *    form lets the drift grow like the unstabilised RK3. Measured while writing
 *    this example at rtol = atol = 1e-8: index 1 took 4863 steps for error
 *    3.1e-5 and drift 6.1e-6; GGL 1915 steps for 8.1e-6 and 1.1e-8. The
 *    iteration matrix is analytic (IDASetJacFn; CEODE gets the analytic G
 *    too), and the first step is set to 1e-5 s (IDASetInitStep): IDA's own
 *    estimate, ~ tol / |y'|, is so small at tight tolerances that the index-2
 *    Newton iteration, which amplifies round-off by 1/h, never converges.
 *
 * Reference: the paper's Tables 9 (RK3), 10 (RK3 + projection) and 11 (G5 ones)
 * (Fernandez de Bustos et al., Mathematics 2024, 12, 2862), method.md section 7.
 * The program exits 0 only if: RK3 reproduces Table 9's error and drift and
 * RK3+proj Table 10's error within 10 % at h = 1e-2 and 1e-3; CEODE G5_ONES
 * (paper start) reproduces Table 11's error within 10 % at 1e-2 and 1e-3 and
 * reaches <= 2e-12 at 1e-4; and every G5_ONES (paper start) run has drift
 * <= 1e-14. The other CEODE rows are reported, not checked.
 *
 * Timing: every run is repeated until one timing lasts >= 50 ms; the median of
 * 3 such timings is reported (one plain run when a run takes more than 1 s).
 * Then the ratio CEODE time / RK3 time and CEODE time / IDA time at equal
 * error is printed (log time interpolated linearly in log error on each curve).
 *
 * Usage: pendulum_dae [--csv FILE] [--full]
 *   --full  adds h = 1e-5 for every fixed-step solver and tol = 1e-11 for IDA.
 * ---------------------------------------------------------------------------*/
#define _POSIX_C_SOURCE 200809L /* clock_gettime under -std=c99 */
#include <arkode/arkode_erkstep.h>
#include <ceode/ceode.h>
#include <ida/ida.h>
#include <ida/ida_ls.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sundials/sundials_math.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>
#include <time.h>

#include "ceode_sundials_compat.h" /* SUN_COMM_NULL on SUNDIALS 6.4 */

#define GRAV 9.81
#define LEN 1.0
#define MASS 1.0
#define IZZ 0.0
#define TEND 10.0
#define PI_2 1.57079632679489661923
#define MAXPTS 16

/* ---------------------------------------------------------------- helpers */

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int check_flag(int flag, const char* call) {
  if (flag < 0) {
    fprintf(stderr, "ERROR: %s returned %d\n", call, flag);
    return 1;
  }
  return 0;
}

static int check_ptr(const void* p, const char* call) {
  if (p == NULL) {
    fprintf(stderr, "ERROR: %s returned NULL\n", call);
    return 1;
  }
  return 0;
}

static double energy(const double* q, const double* v) {
  return 0.5 * MASS * (v[0] * v[0] + v[1] * v[1]) + 0.5 * IZZ * v[2] * v[2] + MASS * GRAV * q[1];
}

static double drift_of(const double* q) { return fabs(q[0] * q[0] + q[1] * q[1] - LEN * LEN); }

/* max |G(q) v| */
static double vres_of(const double* q, const double* v) {
  double c = cos(q[2]), s = sin(q[2]);
  double r1 = fabs(v[0] - LEN * c * v[2]), r2 = fabs(v[1] - LEN * s * v[2]);
  return r1 > r2 ? r1 : r2;
}

/* Solves A z = b in place (A row-major n x n, b overwritten by z) by Gaussian
 * elimination with partial pivoting. Returns 0, or 1 if A is singular. */
static int dense_solve(int n, double* A, double* b) {
  int i, j, k;
  for (k = 0; k < n; ++k) {
    int p = k;
    double amax = fabs(A[k * n + k]);
    for (i = k + 1; i < n; ++i) {
      if (fabs(A[i * n + k]) > amax) {
        amax = fabs(A[i * n + k]);
        p = i;
      }
    }
    if (amax == 0.0) return 1;
    if (p != k) {
      double tmp;
      for (j = 0; j < n; ++j) {
        tmp = A[k * n + j];
        A[k * n + j] = A[p * n + j];
        A[p * n + j] = tmp;
      }
      tmp = b[k];
      b[k] = b[p];
      b[p] = tmp;
    }
    for (i = k + 1; i < n; ++i) {
      double l = A[i * n + k] / A[k * n + k];
      if (l == 0.0) continue;
      for (j = k + 1; j < n; ++j) A[i * n + j] -= l * A[k * n + j];
      b[i] -= l * b[k];
    }
  }
  for (i = n - 1; i >= 0; --i) {
    double s = b[i];
    for (j = i + 1; j < n; ++j) s -= A[i * n + j] * b[j];
    b[i] = s / A[i * n + i];
  }
  return 0;
}

/* Index-1 accelerations: solves the 5 x 5 saddle system
 *   [M G^T; G 0] (q'', lambda) = (f, -(dG/dt) q')   ->  acc[3], lam[2]. */
static int index1_accel(const double* q, const double* v, double* acc, double* lam) {
  double c = cos(q[2]), s = sin(q[2]), w2 = v[2] * v[2];
  double A[25] = {MASS, 0,    0,        1,        0,        /* */
                  0,    MASS, 0,        0,        1,        /* */
                  0,    0,    IZZ,      -LEN * c, -LEN * s, /* */
                  1,    0,    -LEN * c, 0,        0,        /* */
                  0,    1,    -LEN * s, 0,        0};
  double b[5];
  b[0] = 0.0;
  b[1] = -MASS * GRAV;
  b[2] = 0.0;
  b[3] = -LEN * s * w2;
  b[4] = LEN * c * w2;
  if (dense_solve(5, A, b)) return 1;
  acc[0] = b[0];
  acc[1] = b[1];
  acc[2] = b[2];
  if (lam) {
    lam[0] = b[3];
    lam[1] = b[4];
  }
  return 0;
}

/* Minimum-norm Newton projection of q onto Phi(q) = 0 (positions only). */
static int project_positions(double* q) {
  int it;
  for (it = 0; it < 20; ++it) {
    double c = cos(q[2]), s = sin(q[2]);
    double p1 = q[0] - LEN * s, p2 = q[1] + LEN * c;
    /* G = [1 0 -Lc; 0 1 -Ls], G G^T = [1+L^2c^2, L^2cs; L^2cs, 1+L^2s^2] */
    double a11 = 1 + LEN * LEN * c * c, a12 = LEN * LEN * c * s, a22 = 1 + LEN * LEN * s * s;
    double det = a11 * a22 - a12 * a12;
    double m1 = (a22 * p1 - a12 * p2) / det, m2 = (a11 * p2 - a12 * p1) / det;
    double d0 = m1, d1 = m2, d2 = -LEN * c * m1 - LEN * s * m2;
    double dn = fabs(d0) + fabs(d1) + fabs(d2);
    q[0] -= d0;
    q[1] -= d1;
    q[2] -= d2;
    if (dn <= 1e-16 * (1 + fabs(q[2]))) return 0;
  }
  return 0; /* round-off level reached or stagnated: positions are as good as it gets */
}

/* One measured quantity set per run. */
struct result {
  double err, drift, vres, secs;
  long steps, nfe;
};

static void track(struct result* r, const double* q, const double* v, double e0) {
  double de = fabs(energy(q, v) - e0), dr = drift_of(q), vr = vres_of(q, v);
  if (de > r->err || de != de) r->err = de;
  if (dr > r->drift || dr != dr) r->drift = dr;
  if (vr > r->vres || vr != vr) r->vres = vr;
}

/* ---------------------------------------------------------------- ARKODE RK3 */

static int ark_rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* data) {
  double* Y = N_VGetArrayPointer(y);
  double* F = N_VGetArrayPointer(ydot);
  (void)t;
  (void)data;
  F[0] = Y[3];
  F[1] = Y[4];
  F[2] = Y[5];
  return index1_accel(Y, Y + 3, F + 3, NULL) ? -1 : 0;
}

static int run_rk3(SUNContext ctx, int project, double h, struct result* r) {
  static const double c[3] = {0.0, 0.5, 1.0};
  static const double A[9] = {0.0, 0.0, 0.0, 0.5, 0.0, 0.0, -1.0, 2.0, 0.0};
  static const double b[3] = {1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0};
  double cc[3], AA[9], bb[3];
  N_Vector y = NULL;
  void* mem = NULL;
  ARKodeButcherTable B = NULL;
  double t = 0.0, e0, *Y;
  int fail = 0, i;
  long nfe = 0, nfi = 0;
  memset(r, 0, sizeof(*r));
  for (i = 0; i < 3; ++i) cc[i] = c[i], bb[i] = b[i];
  for (i = 0; i < 9; ++i) AA[i] = A[i];
  y = N_VNew_Serial(6, ctx);
  if (check_ptr(y, "N_VNew_Serial")) return 1;
  Y = N_VGetArrayPointer(y);
  Y[0] = LEN;
  Y[1] = 0.0;
  Y[2] = PI_2;
  Y[3] = Y[4] = Y[5] = 0.0;
  e0 = energy(Y, Y + 3);
  B = ARKodeButcherTable_Create(3, 3, 0, cc, AA, bb, NULL);
  fail |= check_ptr(B, "ARKodeButcherTable_Create");
  if (!fail) mem = ERKStepCreate(ark_rhs, 0.0, y, ctx);
  fail |= check_ptr(mem, "ERKStepCreate");
  if (!fail) fail |= check_flag(ERKStepSetTable(mem, B), "ERKStepSetTable");
  if (!fail) fail |= check_flag(ERKStepSetFixedStep(mem, h), "ERKStepSetFixedStep");
  if (!fail) fail |= check_flag(ERKStepSetStopTime(mem, TEND), "ERKStepSetStopTime");
  if (!fail) fail |= check_flag(ERKStepSetMaxNumSteps(mem, -1), "ERKStepSetMaxNumSteps");
  r->secs = now();
  while (!fail && t < TEND - 0.5 * h) {
    int flag = ERKStepEvolve(mem, TEND, y, &t, ARK_ONE_STEP);
    if (check_flag(flag, "ERKStepEvolve")) {
      fail = 1;
      break;
    }
    if (project) project_positions(Y);
    /* Reset after every step, projected or not: SUNDIALS < 6.6.2 treats a table
     * with c_s = 1 as FSAL and would reuse f(last stage) as f(t_n+1, y_n+1),
     * which Kutta's table is not (a_3j != b_j); the reset forces a fresh f. */
    if (check_flag(ERKStepReset(mem, t, y), "ERKStepReset")) fail = 1;
    track(r, Y, Y + 3, e0);
  }
  r->secs = now() - r->secs;
  if (mem) {
    fail |= check_flag(ERKStepGetNumSteps(mem, &r->steps), "ERKStepGetNumSteps");
    fail |= check_flag(ERKStepGetNumRhsEvals(mem, &nfe), "ERKStepGetNumRhsEvals");
  }
  (void)nfi;
  r->nfe = nfe;
  ERKStepFree(&mem);
  ARKodeButcherTable_Free(B);
  N_VDestroy(y);
  return fail;
}

/* ---------------------------------------------------------------- IDA, GGL */

/* y = (x, y, theta, vx, vy, vtheta, lambda1, lambda2, mu1, mu2) */
static int ida_res(sunrealtype t, N_Vector yy, N_Vector yp, N_Vector rr, void* data) {
  const double* Y = N_VGetArrayPointer(yy);
  const double* P = N_VGetArrayPointer(yp);
  double* R = N_VGetArrayPointer(rr);
  double c = cos(Y[2]), s = sin(Y[2]);
  (void)t;
  (void)data;
  /* q' - v - G^T mu */
  R[0] = P[0] - Y[3] - Y[8];
  R[1] = P[1] - Y[4] - Y[9];
  R[2] = P[2] - Y[5] + LEN * c * Y[8] + LEN * s * Y[9];
  /* M v' + G^T lambda - f */
  R[3] = MASS * P[3] + Y[6];
  R[4] = MASS * P[4] + Y[7] + MASS * GRAV;
  R[5] = IZZ * P[5] - LEN * c * Y[6] - LEN * s * Y[7];
  /* Phi(q) */
  R[6] = Y[0] - LEN * s;
  R[7] = Y[1] + LEN * c;
  /* G(q) v */
  R[8] = Y[3] - LEN * c * Y[5];
  R[9] = Y[4] - LEN * s * Y[5];
  return 0;
}

/* Analytic iteration matrix J = dF/dy + cj dF/dy' of the GGL residual. */
static int ida_jac(sunrealtype t, sunrealtype cj, N_Vector yy, N_Vector yp, N_Vector rr,
                   SUNMatrix J, void* data, N_Vector t1, N_Vector t2, N_Vector t3) {
  const double* Y = N_VGetArrayPointer(yy);
  double c = cos(Y[2]), s = sin(Y[2]);
  (void)t;
  (void)yp;
  (void)rr;
  (void)data;
  (void)t1;
  (void)t2;
  (void)t3;
  if (SUNMatZero(J) != SUNMAT_SUCCESS) return -1;
  SM_ELEMENT_D(J, 0, 0) = cj;
  SM_ELEMENT_D(J, 0, 3) = -1.0;
  SM_ELEMENT_D(J, 0, 8) = -1.0;
  SM_ELEMENT_D(J, 1, 1) = cj;
  SM_ELEMENT_D(J, 1, 4) = -1.0;
  SM_ELEMENT_D(J, 1, 9) = -1.0;
  SM_ELEMENT_D(J, 2, 2) = cj - LEN * s * Y[8] + LEN * c * Y[9];
  SM_ELEMENT_D(J, 2, 5) = -1.0;
  SM_ELEMENT_D(J, 2, 8) = LEN * c;
  SM_ELEMENT_D(J, 2, 9) = LEN * s;
  SM_ELEMENT_D(J, 3, 3) = cj * MASS;
  SM_ELEMENT_D(J, 3, 6) = 1.0;
  SM_ELEMENT_D(J, 4, 4) = cj * MASS;
  SM_ELEMENT_D(J, 4, 7) = 1.0;
  SM_ELEMENT_D(J, 5, 2) = LEN * s * Y[6] - LEN * c * Y[7];
  SM_ELEMENT_D(J, 5, 5) = cj * IZZ;
  SM_ELEMENT_D(J, 5, 6) = -LEN * c;
  SM_ELEMENT_D(J, 5, 7) = -LEN * s;
  SM_ELEMENT_D(J, 6, 0) = 1.0;
  SM_ELEMENT_D(J, 6, 2) = -LEN * c;
  SM_ELEMENT_D(J, 7, 1) = 1.0;
  SM_ELEMENT_D(J, 7, 2) = -LEN * s;
  SM_ELEMENT_D(J, 8, 2) = LEN * s * Y[5];
  SM_ELEMENT_D(J, 8, 3) = 1.0;
  SM_ELEMENT_D(J, 8, 5) = -LEN * c;
  SM_ELEMENT_D(J, 9, 2) = -LEN * c * Y[5];
  SM_ELEMENT_D(J, 9, 4) = 1.0;
  SM_ELEMENT_D(J, 9, 5) = -LEN * s;
  return 0;
}

static int run_ida(SUNContext ctx, double tol, struct result* r) {
  N_Vector yy = NULL, yp = NULL, id = NULL;
  SUNMatrix J = NULL;
  SUNLinearSolver LS = NULL;
  void* mem = NULL;
  double t = 0.0, e0, *Y, *P, *I, acc[3], lam[2];
  int fail = 0, i, neq = 10;
  long nre = 0, nreLS = 0;
  memset(r, 0, sizeof(*r));
  yy = N_VNew_Serial(neq, ctx);
  yp = N_VNew_Serial(neq, ctx);
  id = N_VNew_Serial(neq, ctx);
  if (check_ptr(yy, "N_VNew_Serial") || check_ptr(yp, "N_VNew_Serial") ||
      check_ptr(id, "N_VNew_Serial")) {
    fail = 1;
    goto done;
  }
  Y = N_VGetArrayPointer(yy);
  P = N_VGetArrayPointer(yp);
  I = N_VGetArrayPointer(id);
  for (i = 0; i < neq; ++i) Y[i] = P[i] = 0.0;
  Y[0] = LEN;
  Y[1] = 0.0;
  Y[2] = PI_2;
  /* consistent start: q' = v = 0, v' and lambda from the saddle system, mu = 0 */
  if (index1_accel(Y, Y + 3, acc, lam)) {
    fail = 1;
    goto done;
  }
  P[3] = acc[0];
  P[4] = acc[1];
  P[5] = acc[2];
  Y[6] = lam[0];
  Y[7] = lam[1];
  for (i = 0; i < neq; ++i) I[i] = (i < 5 || (i == 5 && IZZ > 0.0)) ? 1.0 : 0.0;
  e0 = energy(Y, Y + 3);
  mem = IDACreate(ctx);
  if (check_ptr(mem, "IDACreate")) {
    fail = 1;
    goto done;
  }
  fail |= check_flag(IDAInit(mem, ida_res, 0.0, yy, yp), "IDAInit");
  if (!fail) fail |= check_flag(IDASStolerances(mem, tol, tol), "IDASStolerances");
  if (!fail) fail |= check_flag(IDASetId(mem, id), "IDASetId");
  if (!fail) fail |= check_flag(IDASetSuppressAlg(mem, SUNTRUE), "IDASetSuppressAlg");
  if (!fail) fail |= check_flag(IDASetStopTime(mem, TEND), "IDASetStopTime");
  if (!fail) fail |= check_flag(IDASetMaxNumSteps(mem, 10000000L), "IDASetMaxNumSteps");
  /* IDA's own first-step estimate is ~ tol / |y'| (1e-10 s at tol 1e-9); at such
   * steps the index-2 Newton iteration amplifies round-off by 1/h and never
   * converges. Start from 1e-5 s and let the error test adapt. */
  if (!fail) fail |= check_flag(IDASetInitStep(mem, 1e-5), "IDASetInitStep");
  if (!fail) {
    J = SUNDenseMatrix(neq, neq, ctx);
    fail |= check_ptr(J, "SUNDenseMatrix");
  }
  if (!fail) {
    LS = SUNLinSol_Dense(yy, J, ctx);
    fail |= check_ptr(LS, "SUNLinSol_Dense");
  }
  if (!fail) fail |= check_flag(IDASetLinearSolver(mem, LS, J), "IDASetLinearSolver");
  if (!fail) fail |= check_flag(IDASetJacFn(mem, ida_jac), "IDASetJacFn");
  r->secs = now();
  while (!fail && t < TEND) {
    int flag = IDASolve(mem, TEND, &t, yy, yp, IDA_ONE_STEP);
    if (check_flag(flag, "IDASolve")) {
      fail = 1;
      break;
    }
    track(r, Y, Y + 3, e0);
    if (flag == IDA_TSTOP_RETURN) break;
  }
  r->secs = now() - r->secs;
  if (!fail) {
    fail |= check_flag(IDAGetNumSteps(mem, &r->steps), "IDAGetNumSteps");
    fail |= check_flag(IDAGetNumResEvals(mem, &nre), "IDAGetNumResEvals");
    fail |= check_flag(IDAGetNumLinResEvals(mem, &nreLS), "IDAGetNumLinResEvals");
  }
  r->nfe = nre + nreLS;
done:
  if (mem) IDAFree(&mem);
  if (LS) SUNLinSolFree(LS);
  if (J) SUNMatDestroy(J);
  if (yy) N_VDestroy(yy);
  if (yp) N_VDestroy(yp);
  if (id) N_VDestroy(id);
  return fail;
}

/* ---------------------------------------------------------------- CEODE */

static int ce_force(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
  double* F = N_VGetArrayPointer(f);
  (void)t;
  (void)x;
  (void)v;
  (void)data;
  F[0] = 0.0;
  F[1] = -MASS * GRAV;
  F[2] = 0.0;
  return 0;
}

static int ce_mass(sunrealtype t, N_Vector x, SUNMatrix M, void* data, N_Vector t1, N_Vector t2,
                   N_Vector t3) {
  (void)t;
  (void)x;
  (void)data;
  (void)t1;
  (void)t2;
  (void)t3;
  if (SUNMatGetID(M) != SUNMATRIX_DENSE) return -1;
  if (SUNMatZero(M) != SUNMAT_SUCCESS) return -1;
  SM_ELEMENT_D(M, 0, 0) = MASS;
  SM_ELEMENT_D(M, 1, 1) = MASS;
  SM_ELEMENT_D(M, 2, 2) = IZZ;
  return 0;
}

static int ce_phi(sunrealtype t, N_Vector x, N_Vector phi, void* data) {
  const double* q = N_VGetArrayPointer(x);
  double* p = N_VGetArrayPointer(phi);
  (void)t;
  (void)data;
  p[0] = q[0] - LEN * sin(q[2]);
  p[1] = q[1] + LEN * cos(q[2]);
  return 0;
}

/* G = [1 0 -L cos(theta); 0 1 -L sin(theta)], dense or CSR sparse. */
static int ce_G(sunrealtype t, N_Vector x, SUNMatrix G, void* data) {
  const double* q = N_VGetArrayPointer(x);
  double c = cos(q[2]), s = sin(q[2]);
  (void)t;
  (void)data;
  if (SUNMatGetID(G) == SUNMATRIX_DENSE) {
    if (SUNMatZero(G) != SUNMAT_SUCCESS) return -1;
    SM_ELEMENT_D(G, 0, 0) = 1.0;
    SM_ELEMENT_D(G, 0, 2) = -LEN * c;
    SM_ELEMENT_D(G, 1, 1) = 1.0;
    SM_ELEMENT_D(G, 1, 2) = -LEN * s;
    return 0;
  }
  if (SUNMatGetID(G) == SUNMATRIX_SPARSE && SUNSparseMatrix_SparseType(G) == CSR_MAT) {
    sunindextype *ptr, *idx;
    double* d;
    if (SUNSparseMatrix_NNZ(G) < 4 && SUNSparseMatrix_Reallocate(G, 4) != SUNMAT_SUCCESS) return -1;
    ptr = SUNSparseMatrix_IndexPointers(G);
    idx = SUNSparseMatrix_IndexValues(G);
    d = SUNSparseMatrix_Data(G);
    ptr[0] = 0;
    idx[0] = 0, d[0] = 1.0;
    idx[1] = 2, d[1] = -LEN * c;
    ptr[1] = 2;
    idx[2] = 1, d[2] = 1.0;
    idx[3] = 2, d[3] = -LEN * s;
    ptr[2] = 4;
    return 0;
  }
  return -1;
}

static int run_ceode(SUNContext ctx, const char* method, int zero_start, double h,
                     struct result* r) {
  N_Vector x = NULL, v = NULL, phi = NULL, tmpl = NULL;
  SUNMatrix M = NULL, A = NULL;
  SUNLinearSolver LS = NULL;
  void* mem = NULL;
  double t = 0.0, e0, *X, *V;
  int fail = 0;
  memset(r, 0, sizeof(*r));
  x = N_VNew_Serial(3, ctx);
  v = N_VNew_Serial(3, ctx);
  phi = N_VNew_Serial(2, ctx);
  M = SUNDenseMatrix(3, 3, ctx);
  /* the saddle-point matrix [[M, G^T], [G, 0]] (5 x 5) and its dense solver */
  tmpl = N_VNew_Serial(5, ctx);
  A = SUNDenseMatrix(5, 5, ctx);
  if (check_ptr(x, "N_VNew_Serial") || check_ptr(v, "N_VNew_Serial") ||
      check_ptr(phi, "N_VNew_Serial") || check_ptr(M, "SUNDenseMatrix") ||
      check_ptr(tmpl, "N_VNew_Serial") || check_ptr(A, "SUNDenseMatrix")) {
    fail = 1;
    goto done;
  }
  LS = SUNLinSol_Dense(tmpl, A, ctx);
  if (check_ptr(LS, "SUNLinSol_Dense")) {
    fail = 1;
    goto done;
  }
  X = N_VGetArrayPointer(x);
  V = N_VGetArrayPointer(v);
  X[0] = LEN;
  X[1] = 0.0;
  X[2] = PI_2;
  V[0] = V[1] = V[2] = 0.0;
  e0 = energy(X, V);
  mem = CEodeCreate(ctx);
  if (check_ptr(mem, "CEodeCreate")) {
    fail = 1;
    goto done;
  }
  fail |= check_flag(CEodeInit(mem, ce_force, 0.0, x, v), "CEodeInit");
  if (!fail) fail |= check_flag(CEodeSetMethodByName(mem, method), "CEodeSetMethodByName");
  if (!fail)
    fail |=
        check_flag(CEodeSetZeroStart(mem, zero_start ? SUNTRUE : SUNFALSE), "CEodeSetZeroStart");
  if (!fail) fail |= check_flag(CEodeSetFixedStep(mem, h), "CEodeSetFixedStep");
  if (!fail) fail |= check_flag(CEodeSetMassFn(mem, ce_mass, M, SUNTRUE), "CEodeSetMassFn");
  if (!fail) fail |= check_flag(CEodeSetLinearSolver(mem, LS, A), "CEodeSetLinearSolver");
  if (!fail) fail |= check_flag(CEodeSetConstraints(mem, phi, ce_phi, ce_G), "CEodeSetConstraints");
  if (!fail)
    fail |= check_flag(CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0), "CEodeSetStabilityGuard");
  if (!fail) fail |= check_flag(CEodeSetStopTime(mem, TEND), "CEodeSetStopTime");
  if (!fail) fail |= check_flag(CEodeSetMaxNumSteps(mem, -1), "CEodeSetMaxNumSteps");
  r->secs = now();
  while (!fail && t < TEND - 0.5 * h) {
    int flag = CEodeEvolve(mem, TEND, x, v, &t, CE_ONE_STEP);
    if (check_flag(flag, "CEodeEvolve")) {
      fail = 1;
      break;
    }
    track(r, X, V, e0);
  }
  r->secs = now() - r->secs;
  if (!fail) {
    fail |= check_flag(CEodeGetNumSteps(mem, &r->steps), "CEodeGetNumSteps");
    fail |= check_flag(CEodeGetNumRhsEvals(mem, &r->nfe), "CEodeGetNumRhsEvals");
  }
done:
  if (mem) CEodeFree(&mem);
  if (LS) SUNLinSolFree(LS);
  if (A) SUNMatDestroy(A);
  if (tmpl) N_VDestroy(tmpl);
  if (M) SUNMatDestroy(M);
  if (x) N_VDestroy(x);
  if (v) N_VDestroy(v);
  if (phi) N_VDestroy(phi);
  return fail;
}

/* ---------------------------------------------------------------- driver */

enum kind { K_CEODE, K_RK3, K_RK3P, K_IDA };

struct config {
  enum kind kind;
  const char* solver; /* CSV solver column */
  const char* name;   /* CSV config column */
  const char* method; /* CEODE method name */
  int zero_start;
};

static int run_any(SUNContext ctx, const struct config* c, double h, struct result* r) {
  switch (c->kind) {
    case K_CEODE:
      return run_ceode(ctx, c->method, c->zero_start, h, r);
    case K_RK3:
      return run_rk3(ctx, 0, h, r);
    case K_RK3P:
      return run_rk3(ctx, 1, h, r);
    case K_IDA:
      return run_ida(ctx, h, r);
  }
  return 1;
}

static int cmp_double(const void* a, const void* b) {
  double x = *(const double*)a, y = *(const double*)b;
  return (x > y) - (x < y);
}

/* One run for the figures, then timing: batches of runs lasting >= 50 ms,
 * median of 3 batches, unless a single run takes more than 1 s. */
static int measure(SUNContext ctx, const struct config* c, double h, struct result* r) {
  struct result tmp;
  double times[3];
  long reps, k;
  int b;
  if (run_any(ctx, c, h, r)) return 1;
  if (r->secs > 1.0) return 0;
  reps = r->secs > 0.05 ? 1 : (long)ceil(0.05 / (r->secs > 1e-7 ? r->secs : 1e-7));
  for (b = 0; b < 3; ++b) {
    double t0 = now();
    for (k = 0; k < reps; ++k) {
      if (run_any(ctx, c, h, &tmp)) return 1;
    }
    times[b] = (now() - t0) / (double)reps;
  }
  qsort(times, 3, sizeof(double), cmp_double);
  r->secs = times[1];
  return 0;
}

/* Time at which a curve (points in order of increasing cost) reaches error e,
 * log t interpolated linearly in log error on the first bracketing segment;
 * returns < 0 if the curve does not reach e. */
static double time_at_error(int n, const double* err, const double* secs, double e) {
  int i;
  for (i = 0; i + 1 < n; ++i) {
    double e1 = err[i], e2 = err[i + 1];
    if (e1 > 0 && e2 > 0 && e1 >= e && e2 <= e && e1 > e2) {
      double w = (log(e) - log(e1)) / (log(e2) - log(e1));
      return exp(log(secs[i]) + w * (log(secs[i + 1]) - log(secs[i])));
    }
    if (e1 == e) return secs[i];
  }
  if (n > 0 && err[n - 1] == e) return secs[n - 1];
  return -1.0;
}

/* Paper's Tables 9-11 at h = 1e-2 and 1e-3: error, drift (0 = not checked). */
struct reference {
  enum kind kind;
  double h, err, drift;
};
static const struct reference refs[] = {
    {K_RK3, 1e-2, 5.05e-5, 1.0474e-4}, {K_RK3, 1e-3, 3.74e-8, 1.03e-7},
    {K_RK3P, 1e-2, 4.16e-4, 0.0},      {K_RK3P, 1e-3, 4.14e-7, 0.0},
    {K_CEODE, 1e-2, 1.83e-5, 0.0},     {K_CEODE, 1e-3, 9.78e-10, 0.0},
};

int main(int argc, char** argv) {
  static const struct config configs[] = {
      {K_CEODE, "CEODE", "G5_ONES", "G5_ONES", 1},
      {K_CEODE, "CEODE", "G5_ONES/consistent", "G5_ONES", 0},
      {K_CEODE, "CEODE", "G4_A34", "G4_A34", 0},
      {K_CEODE, "CEODE", "G3_CD", "G3_CD", 0},
      {K_RK3, "ARKODE", "RK3", NULL, 0},
      {K_RK3P, "ARKODE", "RK3+proj", NULL, 0},
      {K_IDA, "IDA", "BDF-GGL", NULL, 0},
  };
  enum { NCONF = sizeof(configs) / sizeof(configs[0]) };
  static double errs[NCONF][MAXPTS], secs[NCONF][MAXPTS];
  int npts[NCONF];
  SUNContext ctx;
  FILE* csv = NULL;
  int full = 0, i, k, nbad = 0, nchecked = 0, nfailed = 0;
  double hmin;
  for (i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--csv") == 0 && i + 1 < argc) {
      csv = fopen(argv[++i], "w");
      if (csv == NULL) {
        fprintf(stderr, "cannot open %s\n", argv[i]);
        return 1;
      }
      fprintf(csv, "scene,solver,config,h_or_tol,error,drift,steps,rhs_evals,seconds\n");
    } else if (strcmp(argv[i], "--full") == 0) {
      full = 1;
    } else {
      fprintf(stderr, "usage: %s [--csv FILE] [--full]\n", argv[0]);
      return 1;
    }
  }
  hmin = full ? 1e-5 : 1e-4;
  if (SUNContext_Create(SUN_COMM_NULL, &ctx)) return 1;
  printf(
      "DAE pendulum (index 3, q = (x, y, theta), I_zz = 0), 10 s, from theta = 90 deg at rest\n");
  printf("error = max |E - E0|, drift = max |x^2 + y^2 - L^2|, vres = max |G q'|\n\n");
  printf("%-7s %-19s %8s %11s %11s %11s %9s %9s %10s  %s\n", "solver", "config", "h/tol", "error",
         "drift", "vres", "steps", "f evals", "seconds", "paper (err / drift)");
  for (k = 0; k < NCONF; ++k) {
    const struct config* c = &configs[k];
    int ida = c->kind == K_IDA;
    double lo = ida ? (full ? 1e-11 : 1e-10) : hmin;
    double hi = ida ? 1e-4 : 1e-2;
    double h;
    int j;
    npts[k] = 0;
    for (j = 0, h = hi; h >= lo * 0.999 && j < MAXPTS; ++j, h = hi * pow(10.0, -(j))) {
      struct result r;
      size_t m;
      const struct reference* ref = NULL;
      if (measure(ctx, c, h, &r)) {
        fprintf(stderr, "run %s %s %g failed\n", c->solver, c->name, h);
        ++nfailed;
        continue;
      }
      errs[k][npts[k]] = r.err;
      secs[k][npts[k]] = r.secs;
      ++npts[k];
      printf("%-7s %-19s %8.0e %11.3e %11.3e %11.3e %9ld %9ld %10.3e", c->solver, c->name, h, r.err,
             r.drift, r.vres, r.steps, r.nfe, r.secs);
      for (m = 0; m < sizeof(refs) / sizeof(refs[0]); ++m) {
        if (refs[m].kind == c->kind && fabs(h / refs[m].h - 1) < 1e-9) ref = &refs[m];
      }
      if (ref && !(c->kind == K_CEODE && !(c->zero_start && strcmp(c->method, "G5_ONES") == 0))) {
        int bad = fabs(r.err / ref->err - 1) > 0.10;
        ++nchecked;
        if (ref->drift > 0) {
          ++nchecked;
          bad |= fabs(r.drift / ref->drift - 1) > 0.10;
          printf("  %.3g / %.3g", ref->err, ref->drift);
        } else {
          printf("  %.3g", ref->err);
        }
        if (bad) {
          ++nbad;
          printf("  <-- off by more than 10 %%");
        }
      }
      if (c->kind == K_CEODE && strcmp(c->method, "G5_ONES") == 0 && c->zero_start) {
        if (fabs(h - 1e-4) < 1e-12) {
          ++nchecked;
          if (!(r.err <= 2e-12)) {
            ++nbad;
            printf("  <-- error above 2e-12");
          }
        }
        ++nchecked;
        if (!(r.drift <= 1e-14)) {
          ++nbad;
          printf("  <-- drift above 1e-14");
        }
      }
      printf("\n");
      if (csv) {
        fprintf(csv, "pendulum_dae,%s,%s,%.3g,%.6e,%.6e,%ld,%ld,%.6e\n", c->solver, c->name, h,
                r.err, r.drift, r.steps, r.nfe, r.secs);
      }
    }
  }

  /* Time ratios at equal error: CEODE G5_ONES (paper start) against the others. */
  {
    static const double levels[] = {1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11};
    const int against[3] = {4, 5, 6}; /* RK3, RK3+proj, IDA */
    size_t l;
    printf("\nTime ratio at equal energy error (log t interpolated in log error):\n");
    printf("%9s %14s %14s %14s %14s %14s %14s\n", "error", "t CEODE G5", "t RK3", "CEODE/RK3",
           "t RK3+proj", "CEODE/RK3proj", "CEODE/IDA");
    for (l = 0; l < sizeof(levels) / sizeof(levels[0]); ++l) {
      double tc = time_at_error(npts[0], errs[0], secs[0], levels[l]);
      double to[3];
      int a;
      if (tc <= 0) continue;
      for (a = 0; a < 3; ++a)
        to[a] = time_at_error(npts[against[a]], errs[against[a]], secs[against[a]], levels[l]);
      if (to[0] <= 0 && to[1] <= 0 && to[2] <= 0) continue;
      printf("%9.0e %14.3e", levels[l], tc);
      if (to[0] > 0) {
        printf(" %14.3e %14.3f", to[0], tc / to[0]);
      } else {
        printf(" %14s %14s", "-", "-");
      }
      if (to[1] > 0) {
        printf(" %14.3e %14.3f", to[1], tc / to[1]);
      } else {
        printf(" %14s %14s", "-", "-");
      }
      if (to[2] > 0) {
        printf(" %14.3f  (t IDA %.3e)", tc / to[2], to[2]);
      } else {
        printf(" %14s", "-");
      }
      printf("\n");
    }
  }

  printf("\n%d checks, %d off, %d runs failed\n", nchecked, nbad, nfailed);
  if (csv) fclose(csv);
  SUNContext_Free(&ctx);
  return (nbad == 0 && nfailed == 0 && nchecked >= 12) ? 0 : 1;
}
