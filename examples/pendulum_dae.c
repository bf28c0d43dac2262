/* -----------------------------------------------------------------------------
 * pendulum_dae: the simple pendulum as an index-3 multibody DAE, integrated by
 * CEODE with a constant (singular) mass matrix and a dense saddle-point solver.
 *
 * Problem (docs/theory.md sections 8 and 11): a point mass m = 1 kg on a
 * massless rod L = 1 m, g = 9.81, in the coordinates of its centre of mass
 * q = (x, y, theta):
 *     M q'' + G(q)^T lambda = f,   M = diag(m, m, 0),   f = (0, -m g, 0),
 *     Phi(q) = (x - L sin theta, y + L cos theta) = 0,   G = dPhi/dq,
 * released at rest from theta = 90 deg (x = L, y = 0), t in [0, 10] s. M alone
 * is singular (a point mass has no rotational inertia); the saddle-point matrix
 * [[M, G^T], [G, 0]] is regular, and CEODE factors it with the 5 x 5 dense
 * linear solver attached below. (With constraints and no solver attached CEODE
 * would build the same dense one itself; a mass matrix without constraints and
 * without a solver is refused by the first CEodeEvolve with CE_LINIT_FAIL.)
 *
 * Method: G5_ONES with the paper's zero start, h = 1e-3, index 3 (no index
 * reduction, no projection).
 *
 * Reference solution: the energy E = 1/2 m (x'^2 + y'^2) + m g y is conserved
 * and the constraints hold exactly. The paper's Table 11 gives, for this
 * configuration, max |E - E0| = 9.78e-10 over the 10 s. The example exits 0
 * when the measured maximum is within 10 % of that figure and the drift
 * max |x^2 + y^2 - L^2| stays below 1e-14 (round-off).
 * ---------------------------------------------------------------------------*/
#include <ceode/ceode.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "ceode_sundials_compat.h" /* SUN_COMM_NULL on SUNDIALS 6.4 */

#define GRAV 9.81
#define LEN 1.0
#define MASS 1.0
#define TEND 10.0
#define STEP 1e-3
#define PAPER_ERROR 9.78e-10 /* the paper's Table 11, G5 ones, h = 1e-3 */

static int check_flag(int flag, const char* call) {
  if (flag < 0) {
    fprintf(stderr, "ERROR: %s returned %d\n", call, flag);
    return 1;
  }
  return 0;
}

/* Applied forces: gravity only. */
static int force(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
  (void)t, (void)x, (void)v, (void)data;
  NV_Ith_S(f, 0) = 0.0;
  NV_Ith_S(f, 1) = -MASS * GRAV;
  NV_Ith_S(f, 2) = 0.0;
  return 0;
}

/* M = diag(m, m, 0), constant: CEODE evaluates it once. */
static int mass(sunrealtype t, N_Vector x, SUNMatrix M, void* data, N_Vector t1, N_Vector t2,
                N_Vector t3) {
  (void)t, (void)x, (void)data, (void)t1, (void)t2, (void)t3;
  if (SUNMatZero(M) != 0) return -1;
  SM_ELEMENT_D(M, 0, 0) = MASS;
  SM_ELEMENT_D(M, 1, 1) = MASS;
  return 0;
}

static int phi(sunrealtype t, N_Vector x, N_Vector p, void* data) {
  const sunrealtype th = NV_Ith_S(x, 2);
  (void)t, (void)data;
  NV_Ith_S(p, 0) = NV_Ith_S(x, 0) - LEN * sin(th);
  NV_Ith_S(p, 1) = NV_Ith_S(x, 1) + LEN * cos(th);
  return 0;
}

/* G = [1 0 -L cos(theta); 0 1 -L sin(theta)] (2 x 3, dense). */
static int phi_jac(sunrealtype t, N_Vector x, SUNMatrix G, void* data) {
  const sunrealtype th = NV_Ith_S(x, 2);
  (void)t, (void)data;
  if (SUNMatZero(G) != 0) return -1;
  SM_ELEMENT_D(G, 0, 0) = 1.0;
  SM_ELEMENT_D(G, 0, 2) = -LEN * cos(th);
  SM_ELEMENT_D(G, 1, 1) = 1.0;
  SM_ELEMENT_D(G, 1, 2) = -LEN * sin(th);
  return 0;
}

static sunrealtype energy(N_Vector x, N_Vector v) {
  const sunrealtype vx = NV_Ith_S(v, 0), vy = NV_Ith_S(v, 1);
  return 0.5 * MASS * (vx * vx + vy * vy) + MASS * GRAV * NV_Ith_S(x, 1);
}

static sunrealtype drift(N_Vector x) {
  const sunrealtype px = NV_Ith_S(x, 0), py = NV_Ith_S(x, 1);
  return fabs(px * px + py * py - LEN * LEN);
}

int main(void) {
  SUNContext ctx = NULL;
  N_Vector x = NULL, v = NULL, p = NULL, b = NULL;
  SUNMatrix M = NULL, A = NULL;
  SUNLinearSolver LS = NULL;
  void* mem = NULL;
  sunrealtype t = 0.0, e0, err = 0.0, dmax = 0.0;
  long nsteps = 0, nfe = 0, nni = 0;
  int fail = 0;

  if (check_flag(SUNContext_Create(SUN_COMM_NULL, &ctx), "SUNContext_Create")) return 1;
  x = N_VNew_Serial(3, ctx);
  v = N_VNew_Serial(3, ctx);
  p = N_VNew_Serial(2, ctx); /* template of Phi */
  b = N_VNew_Serial(5, ctx); /* template of the saddle-point system */
  M = SUNDenseMatrix(3, 3, ctx);
  A = SUNDenseMatrix(5, 5, ctx);
  if (x == NULL || v == NULL || p == NULL || b == NULL || M == NULL || A == NULL) return 1;
  LS = SUNLinSol_Dense(b, A, ctx);
  mem = CEodeCreate(ctx);
  if (LS == NULL || mem == NULL) return 1;

  NV_Ith_S(x, 0) = LEN; /* theta = 90 deg: the rod horizontal */
  NV_Ith_S(x, 1) = 0.0;
  NV_Ith_S(x, 2) = 2.0 * atan(1.0);
  N_VConst(0.0, v);
  e0 = energy(x, v);

  fail = check_flag(CEodeInit(mem, force, 0.0, x, v), "CEodeInit") ||
         check_flag(CEodeSetMethodByName(mem, "G5_ONES"), "CEodeSetMethodByName") ||
         check_flag(CEodeSetZeroStart(mem, SUNTRUE), "CEodeSetZeroStart") ||
         check_flag(CEodeSetFixedStep(mem, STEP), "CEodeSetFixedStep") ||
         check_flag(CEodeSetStopTime(mem, TEND), "CEodeSetStopTime") ||
         check_flag(CEodeSetMassFn(mem, mass, M, SUNTRUE), "CEodeSetMassFn") ||
         check_flag(CEodeSetLinearSolver(mem, LS, A), "CEodeSetLinearSolver") ||
         check_flag(CEodeSetConstraints(mem, p, phi, phi_jac), "CEodeSetConstraints");

  /* theta = 90 deg computed in double precision lies on the constraints to round-off, so
   * CEodeCalcIC moves nothing here. A start off them (a mistyped length, a velocity across the rod)
   * would be projected onto Phi = 0 and G v = 0 by this call; without it the first CEodeEvolve
   * refuses such a start with CE_INCONSISTENT_IC, naming the constraint that is off. */
  if (!fail) {
    sunrealtype dx = 0.0, dv = 0.0;
    fail = check_flag(CEodeCalcIC(mem, CE_IC_POSITION | CE_IC_VELOCITY), "CEodeCalcIC") ||
           check_flag(CEodeGetICCorrection(mem, &dx, &dv), "CEodeGetICCorrection");
    if (!fail) printf("CEodeCalcIC moved x0 by %.1e and v0 by %.1e\n", dx, dv);
  }

  /* One step at a time: q and q' are then known at the same instant. */
  while (!fail && t < TEND - 0.5 * STEP) {
    sunrealtype de;
    fail = check_flag(CEodeEvolve(mem, TEND, x, v, &t, CE_ONE_STEP), "CEodeEvolve");
    de = fabs(energy(x, v) - e0);
    if (!(de <= err)) err = de; /* also catches NaN */
    if (!(drift(x) <= dmax)) dmax = drift(x);
  }
  if (!fail) {
    fail = check_flag(CEodeGetNumSteps(mem, &nsteps), "CEodeGetNumSteps") ||
           check_flag(CEodeGetNumRhsEvals(mem, &nfe), "CEodeGetNumRhsEvals") ||
           check_flag(CEodeGetNumNonlinSolvIters(mem, &nni), "CEodeGetNumNonlinSolvIters");
  }

  printf("DAE pendulum, G5_ONES (zero start), h = %g, %g s\n", STEP, TEND);
  printf("  steps %ld, f evaluations %ld, constraint Newton iterations %ld\n", nsteps, nfe, nni);
  printf("  max |E - E0|           = %.4e  (paper: %.3g)\n", err, PAPER_ERROR);
  printf("  max |x^2 + y^2 - L^2|  = %.4e  (bound 1e-14)\n", dmax);
  if (!fail && (fabs(err / PAPER_ERROR - 1.0) > 0.10 || !(dmax <= 1e-14))) {
    printf("FAILED: not within 10 %% of the paper or drift above round-off\n");
    fail = 1;
  }

  CEodeFree(&mem);
  SUNLinSolFree(LS);
  SUNMatDestroy(A);
  SUNMatDestroy(M);
  N_VDestroy(b);
  N_VDestroy(p);
  N_VDestroy(v);
  N_VDestroy(x);
  SUNContext_Free(&ctx);
  if (!fail) printf("PASSED\n");
  return fail;
}
