/* -----------------------------------------------------------------------------
 * fe_bar: axial vibration of a steel bar, 1-D finite elements with lumped
 * masses, integrated by CEODE's explicit central differences (G3_CD) -- the
 * way explicit structural dynamics codes step.
 *
 * Problem: a bar of length 1 m, cross-section A = 1e-4 m^2, Young's modulus
 * E = 210 GPa, density rho = 7850 kg/m^3, fixed at x = 0, free at x = 1 m,
 * cut into NE = 20 linear elements of length le. Element stiffness
 * k = E A / le; lumped nodal masses m = rho A le (m/2 at the free end). The
 * unknowns are the displacements u_1..u_NE of the free nodes (u_0 = 0):
 *     m u_i''  = k (u_{i-1} - 2 u_i + u_{i+1}),   i < NE,
 *     m/2 u_NE'' = k (u_{NE-1} - u_NE).
 * The right-hand side returns the accelerations (force / lumped mass), so no
 * mass matrix or linear solver is needed: one f evaluation per step.
 *
 * Reference solution: the discrete system's first mode is exact,
 *     u_i(t) = U0 sin(theta i) cos(w1 t),   theta = pi / (2 NE),
 *     w1^2 = 2 k (1 - cos theta) / m,
 * so starting on it (u_i(0) = U0 sin(theta i), u' = 0) the solution stays on
 * it. Central differences reproduce it with a phase error only: at a step h
 * the discrete frequency w~ has cos(w~ h) = 1 - (w1 h)^2 / 2, and over
 * t in [0, T] the error is at most U0 |w~ - w1| T (~ U0 w1^3 h^2 T / 24). The
 * example takes h = 0.8 times the stability limit 2 / w_max of the bar's
 * highest mode, runs 5 periods of the first mode and exits 0 when the maximum
 * nodal error is at most that bound (+1 % for round-off) and CEODE took one f
 * evaluation per step (plus its start).
 * ---------------------------------------------------------------------------*/
#include <ceode/ceode.h>
#include "ceode_sundials_compat.h" /* SUN_COMM_NULL on SUNDIALS 6.4 */
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>

#define NE 20
#define LENGTH 1.0
#define AREA 1e-4
#define YOUNG 210e9
#define RHO 7850.0
#define U0 1e-4 /* m */

struct bar {
  sunrealtype k, m; /* element stiffness, interior nodal mass */
};

static int check_flag(int flag, const char* call) {
  if (flag < 0) {
    fprintf(stderr, "ERROR: %s returned %d\n", call, flag);
    return 1;
  }
  return 0;
}

/* Accelerations of the free nodes: internal forces over lumped masses. */
static int accel(sunrealtype t, N_Vector x, N_Vector v, N_Vector a, void* data) {
  const struct bar* b = (const struct bar*)data;
  const sunrealtype* u = N_VGetArrayPointer(x);
  sunrealtype* A = N_VGetArrayPointer(a);
  int i;
  (void)t, (void)v;
  for (i = 0; i < NE - 1; ++i) {
    const sunrealtype left = i > 0 ? u[i - 1] : 0.0;
    A[i] = b->k * (left - 2.0 * u[i] + u[i + 1]) / b->m;
  }
  A[NE - 1] = b->k * (u[NE - 2] - u[NE - 1]) / (0.5 * b->m);
  return 0;
}

int main(void) {
  const sunrealtype le = LENGTH / NE, pi = 4.0 * atan(1.0), theta = pi / (2.0 * NE);
  const sunrealtype theta_max = (2.0 * NE - 1.0) * pi / (2.0 * NE);
  struct bar b;
  SUNContext ctx = NULL;
  N_Vector x, v;
  void* mem;
  sunrealtype w1, wmax, h, tend, wh, bound, t = 0.0, err = 0.0, *u;
  long nsteps = 0, nfe = 0, nfe_start = 0;
  int fail, i;

  b.k = YOUNG * AREA / le;
  b.m = RHO * AREA * le;
  w1 = sqrt(2.0 * b.k * (1.0 - cos(theta)) / b.m);
  wmax = sqrt(2.0 * b.k * (1.0 - cos(theta_max)) / b.m);
  h = 0.8 * 2.0 / wmax;
  tend = 5.0 * 2.0 * pi / w1;
  wh = acos(1.0 - 0.5 * (w1 * h) * (w1 * h)) / h; /* discrete frequency of G3_CD */
  bound = U0 * fabs(wh - w1) * tend;

  if (check_flag(SUNContext_Create(SUN_COMM_NULL, &ctx), "SUNContext_Create")) return 1;
  x = N_VNew_Serial(NE, ctx);
  v = N_VNew_Serial(NE, ctx);
  mem = CEodeCreate(ctx);
  if (x == NULL || v == NULL || mem == NULL) return 1;
  u = N_VGetArrayPointer(x);
  for (i = 0; i < NE; ++i) u[i] = U0 * sin(theta * (i + 1));
  N_VConst(0.0, v);

  fail = check_flag(CEodeInit(mem, accel, 0.0, x, v), "CEodeInit") ||
         check_flag(CEodeSetUserData(mem, &b), "CEodeSetUserData") ||
         check_flag(CEodeSetMethodByName(mem, "G3_CD"), "CEodeSetMethodByName") ||
         check_flag(CEodeSetFixedStep(mem, h), "CEodeSetFixedStep") ||
         check_flag(CEodeSetStopTime(mem, tend), "CEodeSetStopTime") ||
         /* the limit is known here, so the guard's frequency estimate is not needed */
         check_flag(CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0), "CEodeSetStabilityGuard");

  while (!fail && t < tend - 0.5 * h) {
    fail = check_flag(CEodeEvolve(mem, tend, x, v, &t, CE_ONE_STEP), "CEodeEvolve");
    for (i = 0; !fail && i < NE; ++i) {
      const sunrealtype e = fabs(u[i] - U0 * sin(theta * (i + 1)) * cos(w1 * t));
      if (!(e <= err)) err = e; /* also catches NaN */
    }
  }
  if (!fail) {
    fail = check_flag(CEodeGetNumSteps(mem, &nsteps), "CEodeGetNumSteps") ||
           check_flag(CEodeGetNumRhsEvals(mem, &nfe), "CEodeGetNumRhsEvals") ||
           check_flag(CEodeGetNumStartRhsEvals(mem, &nfe_start), "CEodeGetNumStartRhsEvals");
  }

  printf("Steel bar, %d elements, lumped masses, G3_CD\n", NE);
  printf("  w1 = %.6e rad/s, w_max = %.6e rad/s, h = %.4e s (0.8 x 2 / w_max)\n", w1, wmax, h);
  printf("  %ld steps over %.4e s (5 periods), f evaluations %ld (start: %ld)\n", nsteps, tend, nfe,
         nfe_start);
  printf("  max nodal error = %.4e m   phase-error bound U0 |w~ - w1| T = %.4e m\n", err, bound);
  if (!fail && !(err <= 1.01 * bound + 1e-12 * U0)) {
    printf("FAILED: error above the central-difference phase error\n");
    fail = 1;
  }
  if (!fail && nfe > nsteps + nfe_start + 1) {
    printf("FAILED: more than one f evaluation per step\n");
    fail = 1;
  }

  CEodeFree(&mem);
  N_VDestroy(v);
  N_VDestroy(x);
  SUNContext_Free(&ctx);
  if (!fail) printf("PASSED\n");
  return fail;
}
