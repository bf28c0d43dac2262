/* -----------------------------------------------------------------------------
 * fe_plate_stable_step: the stable step of an explicit finite-element run, the
 * way structural codes give it, and proof that it is the real limit.
 *
 * Problem: a cantilever plate 4 x 1 (thickness 1) in plane stress, E = 1,
 * nu = 0.3, rho = 1, clamped at x = 0, meshed by NX x NY = 20 x 5 bilinear (Q4)
 * elements (2 x 2 Gauss points), row-sum lumped masses (a quarter of each
 * element's mass at each of its nodes). K is assembled once into a CSR
 * SUNMatrix; f returns the accelerations a = -M^{-1} K x, so no mass matrix or
 * linear solver is attached and a G3_CD (central differences) step is one f call.
 *
 * The stable step h_lim = Omega_max / omega_max (Omega_max = 2 for G3_CD):
 *  1. the guard's estimate: CEodeSetGuardMass tells it the lumped masses (M^{-1}
 *     K is symmetric in the M inner product), CEodeGetStableStep(mem, 1) returns
 *     Omega_max / omega_est with omega_est an upper estimate by Lanczos;
 *  2. a guaranteed bound, as explicit FE codes compute it: CEodeGetFrequencyBound
 *     (Gershgorin on the assembled K and the masses) gives omega_b >= omega_max,
 *     so h_b = Omega_max / omega_b is stable without any estimate.
 * Reference: the runs themselves bracket the true limit. From a smooth start
 * (the static shape under a tip load, scaled to a tip deflection of 1) over
 * NSTEPS steps:
 *  - h = 0.99 h_lim with the guard refusing: runs, and max |x| stays <= 2;
 *  - h = 1.01 h_lim with the guard refusing: CEodeEvolve returns CE_UNSTABLE
 *    before any step;
 *  - h = 1.01 h_lim with the guard off: the top mode, seeded by round-off,
 *    grows (|lambda| = 1.33 per step for G3_CD at Omega = 2.02) until the
 *    state check stops the run with CE_UNSTABLE;
 *  - h = h_b (omega_b given by CEodeSetMaxFrequency, guard refusing): runs, and
 *    h_b <= h_lim.
 * So the estimate is within 1 % of the true limit, on the safe side. Exit code
 * 0 when all four hold (test/test_frequency_bound.cpp compares both figures
 * with the exact omega_max from a dense eigensolver).
 * ---------------------------------------------------------------------------*/
#include <ceode/ceode.h>
#include <ceode/ceode_stability.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <stdlib.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include "ceode_sundials_compat.h" /* SUN_COMM_NULL on SUNDIALS 6.4 */

#define NX 20
#define NY 5
#define NDOF (2 * NX * (NY + 1))
#define NSTEPS 3000L

struct plate {
  SUNMatrix K;   /* stiffness, CSR */
  N_Vector mass; /* lumped masses */
};

static int check_flag(int flag, const char* call) {
  if (flag < 0) {
    fprintf(stderr, "ERROR: %s returned %d\n", call, flag);
    return 1;
  }
  return 0;
}

/* Q4 plane-stress stiffness of a dx x dy element, DOFs (u0, v0, ..., u3, v3). */
static void q4_stiffness(sunrealtype dx, sunrealtype dy, sunrealtype ke[8][8]) {
  const sunrealtype E = 1.0, nu = 0.3, c = E / (1.0 - nu * nu), g = 1.0 / sqrt(3.0);
  const sunrealtype D[3][3] = {{c, c * nu, 0}, {c * nu, c, 0}, {0, 0, c * (1 - nu) / 2}};
  const sunrealtype xn[4] = {-1, 1, 1, -1}, yn[4] = {-1, -1, 1, 1};
  int gp, a, i, j, p, q;
  for (i = 0; i < 8; ++i)
    for (j = 0; j < 8; ++j) ke[i][j] = 0.0;
  for (gp = 0; gp < 4; ++gp) {
    const sunrealtype xi = (gp & 1) ? g : -g, eta = (gp & 2) ? g : -g;
    sunrealtype B[3][8] = {{0}};
    for (a = 0; a < 4; ++a) {
      const sunrealtype nx = 0.5 * xn[a] * (1 + eta * yn[a]) / dx;
      const sunrealtype ny = 0.5 * yn[a] * (1 + xi * xn[a]) / dy;
      B[0][2 * a] = nx, B[1][2 * a + 1] = ny, B[2][2 * a] = ny, B[2][2 * a + 1] = nx;
    }
    for (i = 0; i < 8; ++i)
      for (j = 0; j < 8; ++j)
        for (p = 0; p < 3; ++p)
          for (q = 0; q < 3; ++q) ke[i][j] += 0.25 * dx * dy * B[p][i] * D[p][q] * B[q][j];
  }
}

/* Local node (0..3) of node (i, j) in element (ei, ej), -1 when not in it. */
static int local_node(int ei, int ej, int i, int j) {
  const int di = i - ei, dj = j - ej;
  if (di < 0 || di > 1 || dj < 0 || dj > 1) return -1;
  return di == 0 ? (dj == 0 ? 0 : 3) : (dj == 0 ? 1 : 2);
}

/* K in CSR straight from the 3 x 3 node stencil (free nodes i = 1..NX), and the masses. */
static void assemble(struct plate* p, SUNContext ctx) {
  const sunrealtype dx = 4.0 / NX, dy = 1.0 / NY;
  sunrealtype ke[8][8], *val, *m = N_VGetArrayPointer(p->mass);
  sunindextype *rp = SUNSparseMatrix_IndexPointers(p->K), *ci = SUNSparseMatrix_IndexValues(p->K);
  sunindextype nz = 0, row = 0;
  int i, j, r, ib, jb, c, ei, ej;
  (void)ctx;
  val = SUNSparseMatrix_Data(p->K);
  q4_stiffness(dx, dy, ke);
  for (i = 1; i <= NX; ++i)
    for (j = 0; j <= NY; ++j)
      for (r = 0; r < 2; ++r, ++row) {
        rp[row] = nz;
        m[row] = 0.25 * dx * dy * ((i < NX) + 1) * ((j > 0) + (j < NY));
        for (ib = i - 1; ib <= i + 1; ++ib)
          for (jb = j - 1; jb <= j + 1; ++jb) {
            if (ib < 1 || ib > NX || jb < 0 || jb > NY) continue;
            for (c = 0; c < 2; ++c, ++nz) {
              ci[nz] = 2 * ((ib - 1) * (NY + 1) + jb) + c;
              val[nz] = 0.0;
              for (ei = i - 1; ei <= i; ++ei)
                for (ej = j - 1; ej <= j; ++ej) {
                  const int la = local_node(ei, ej, i, j), lb = local_node(ei, ej, ib, jb);
                  if (ei < 0 || ei >= NX || ej < 0 || ej >= NY || la < 0 || lb < 0) continue;
                  val[nz] += ke[2 * la + r][2 * lb + c];
                }
            }
          }
      }
  rp[row] = nz;
}

/* a = -M^{-1} K x */
static int accel(sunrealtype t, N_Vector x, N_Vector v, N_Vector a, void* data) {
  const struct plate* p = (const struct plate*)data;
  (void)t, (void)v;
  if (SUNMatMatvec(p->K, x, a) != 0) return -1;
  N_VDiv(a, p->mass, a);
  N_VScale(-1.0, a, a);
  return 0;
}

/* The start: a cantilever's static deflection shape w = s^2 (3 - s) / 2, s = x / 4. */
static void start(N_Vector x, N_Vector v) {
  sunrealtype* u = N_VGetArrayPointer(x);
  int i, j;
  for (i = 1; i <= NX; ++i)
    for (j = 0; j <= NY; ++j) {
      const sunrealtype s = (sunrealtype)i / NX;
      u[2 * ((i - 1) * (NY + 1) + j)] = 0.0;
      u[2 * ((i - 1) * (NY + 1) + j) + 1] = 0.5 * s * s * (3.0 - s);
    }
  N_VConst(0.0, v);
}

/* NSTEPS G3_CD steps of size h; returns CEodeEvolve's flag, *xmax = max |x| at the end. */
static int run(SUNContext ctx, struct plate* p, sunrealtype h, int guard, sunrealtype omega_user,
               long* nsteps, sunrealtype* xmax) {
  N_Vector x = N_VNew_Serial(NDOF, ctx), v = N_VNew_Serial(NDOF, ctx);
  void* mem = CEodeCreate(ctx);
  sunrealtype t = 0.0;
  int flag = -1;
  *nsteps = 0;
  *xmax = 0.0;
  if (x == NULL || v == NULL || mem == NULL) return CE_MEM_FAIL;
  start(x, v);
  if (!check_flag(CEodeInit(mem, accel, 0.0, x, v), "CEodeInit") &&
      !check_flag(CEodeSetUserData(mem, p), "CEodeSetUserData") &&
      !check_flag(CEodeSetMethodByName(mem, "G3_CD"), "CEodeSetMethodByName") &&
      !check_flag(CEodeSetFixedStep(mem, h), "CEodeSetFixedStep") &&
      !check_flag(CEodeSetGuardMass(mem, p->mass), "CEodeSetGuardMass") &&
      !check_flag(CEodeSetMaxFrequency(mem, omega_user), "CEodeSetMaxFrequency") &&
      !check_flag(CEodeSetStabilityGuard(mem, guard, 0), "CEodeSetStabilityGuard") &&
      !check_flag(CEodeSetErrFile(mem, NULL), "CEodeSetErrFile")) {
    flag = CEodeEvolve(mem, NSTEPS * h, x, v, &t, CE_NORMAL);
    if (check_flag(CEodeGetNumSteps(mem, nsteps), "CEodeGetNumSteps")) flag = -1;
    *xmax = N_VMaxNorm(x);
  }
  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  return flag;
}

/* The guard's stable step (safety 1) and the Gershgorin bound's omega_b. */
static int stable_steps(SUNContext ctx, struct plate* p, sunrealtype* h_lim, sunrealtype* w_est,
                        sunrealtype* w_b) {
  N_Vector x = N_VNew_Serial(NDOF, ctx), v = N_VNew_Serial(NDOF, ctx);
  void* mem = CEodeCreate(ctx);
  int fail = x == NULL || v == NULL || mem == NULL;
  if (!fail) {
    start(x, v);
    fail = check_flag(CEodeInit(mem, accel, 0.0, x, v), "CEodeInit") ||
           check_flag(CEodeSetUserData(mem, p), "CEodeSetUserData") ||
           check_flag(CEodeSetMethodByName(mem, "G3_CD"), "CEodeSetMethodByName") ||
           check_flag(CEodeSetGuardMass(mem, p->mass), "CEodeSetGuardMass") ||
           check_flag(CEodeGetStableStep(mem, 1.0, h_lim), "CEodeGetStableStep") ||
           check_flag(CEodeGetMaxFrequencyEstimate(mem, w_est), "CEodeGetMaxFrequencyEstimate") ||
           check_flag(CEodeGetFrequencyBound(mem, p->K, p->mass, w_b), "CEodeGetFrequencyBound");
  }
  CEodeFree(&mem);
  if (x != NULL) N_VDestroy(x);
  if (v != NULL) N_VDestroy(v);
  return fail;
}

int main(void) {
  SUNContext ctx = NULL;
  struct plate p;
  sunrealtype h_lim = 0, w_est = 0, w_b = 0, h_b, lim = 0, par[8], xmax;
  long ns;
  int fail, flag, degree = 0;
  char* name = NULL;

  if (check_flag(SUNContext_Create(SUN_COMM_NULL, &ctx), "SUNContext_Create")) return 1;
  p.K = SUNSparseMatrix(NDOF, NDOF, 18 * NDOF, CSR_MAT, ctx);
  p.mass = N_VNew_Serial(NDOF, ctx);
  if (p.K == NULL || p.mass == NULL) return 1;
  assemble(&p, ctx);

  fail = stable_steps(ctx, &p, &h_lim, &w_est, &w_b) ||
         check_flag(CEodeGetMethodParams("G3_CD", &degree, par, 8), "CEodeGetMethodParams") ||
         check_flag(CEodeStabilityLimit(degree, par, 0.0, &lim), "CEodeStabilityLimit");
  if (fail) return 1;
  h_b = lim / w_b;
  printf("Q4 cantilever plate, %d x %d elements, %d DOF, G3_CD (Omega_max = %g)\n", NX, NY, NDOF,
         lim);
  printf("  guard estimate omega_max = %.6e -> h_lim = %.6e\n", w_est, h_lim);
  printf("  Gershgorin bound omega_b = %.6e -> h_b   = %.6e (%.3f h_lim)\n", w_b, h_b, h_b / h_lim);

  flag = run(ctx, &p, 0.99 * h_lim, CE_GUARD_REFUSE, 0.0, &ns, &xmax);
  printf("  0.99 h_lim, guard refusing: flag %d, %ld steps, max|x| = %.4f\n", flag, ns, xmax);
  if (flag < 0 || ns != NSTEPS || !(xmax <= 2.0)) fail = 1;

  flag = run(ctx, &p, 1.01 * h_lim, CE_GUARD_REFUSE, 0.0, &ns, &xmax);
  name = CEodeGetReturnFlagName(flag); /* malloc'd, as SUNDIALS' GetReturnFlagName */
  printf("  1.01 h_lim, guard refusing: %s after %ld steps\n", name, ns);
  free(name);
  if (flag != CE_UNSTABLE || ns != 0) fail = 1;

  flag = run(ctx, &p, 1.01 * h_lim, CE_GUARD_OFF, 0.0, &ns, &xmax);
  name = CEodeGetReturnFlagName(flag);
  printf("  1.01 h_lim, guard off:      %s after %ld steps (the top mode grew)\n", name, ns);
  free(name);
  if (flag != CE_UNSTABLE) fail = 1;

  flag = run(ctx, &p, h_b, CE_GUARD_REFUSE, w_b, &ns, &xmax);
  printf("  h_b from the bound, guard refusing: flag %d, %ld steps, max|x| = %.4f\n", flag, ns,
         xmax);
  if (flag < 0 || ns != NSTEPS || !(xmax <= 2.0) || !(h_b <= h_lim)) fail = 1;

  SUNMatDestroy(p.K);
  N_VDestroy(p.mass);
  SUNContext_Free(&ctx);
  printf("%s\n", fail ? "FAILED" : "PASSED");
  return fail;
}
