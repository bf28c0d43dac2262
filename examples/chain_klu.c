/* -----------------------------------------------------------------------------
 * chain_klu: a planar chain of N pendulums as an index-3 DAE, integrated by
 * CEODE with a sparse (CSR) saddle-point matrix factored by KLU.
 *
 * Problem (docs/theory.md section 8): N = 8 point masses m_i = 1 kg at
 * p_i = (x_i, y_i), joined by massless rigid links of length l = 1/N m to each
 * other and the first to the fixed origin p_0 = 0, gravity g = 9.81 along -y:
 *     x'' + G(x)^T lambda = f = (0, -g, 0, -g, ...)     (M = I: no mass function)
 *     Phi_i(x) = |p_i - p_{i-1}|^2 - l^2 = 0,   i = 1..N  (n = 2N, nc = N).
 * Start: the chain straight at 60 deg from the downward vertical, at rest;
 * t in [0, 2] s (it falls, swings through the bottom and whips). G(x) has four
 * entries per row; the (n+nc) x (n+nc) saddle-point matrix [[I, G^T], [G, 0]]
 * is given to CEODE as an empty CSR SUNSparseMatrix with room for its
 * 2N + 2 (4N - 2) entries, and CEODE fills it at every Newton iteration.
 *
 * Method: G5_ONES, h = 1e-3, consistent start.
 *
 * Reference solution: the chain is conservative and its links are rigid, so
 * E = sum(1/2 |v_i|^2 + g y_i) stays at E0 and every Phi_i at 0. The example
 * exits 0 when max |E - E0| <= 5e-7 J (|E0| = 22 J; bench/multibody/wp_chain_dae measures
 * 2.88e-7 for this configuration) and max |Phi_i| <= 1e-10 l^2.
 * ---------------------------------------------------------------------------*/
#include <ceode/ceode.h>
#include "ceode_sundials_compat.h" /* SUN_COMM_NULL on SUNDIALS 6.4 */
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_sparse.h>

#define NB 8 /* bodies */
#define GRAV 9.81
#define LINK (1.0 / NB)
#define TEND 2.0
#define STEP 1e-3
#define ANGLE0 1.04719755119659774615 /* 60 deg */

static int check_flag(int flag, const char* call) {
  if (flag < 0) {
    fprintf(stderr, "ERROR: %s returned %d\n", call, flag);
    return 1;
  }
  return 0;
}

static int force(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
  sunrealtype* F = N_VGetArrayPointer(f);
  int i;
  (void)t, (void)x, (void)v, (void)data;
  for (i = 0; i < NB; ++i) {
    F[2 * i] = 0.0;
    F[2 * i + 1] = -GRAV;
  }
  return 0;
}

static int phi(sunrealtype t, N_Vector x, N_Vector p, void* data) {
  const sunrealtype* X = N_VGetArrayPointer(x);
  sunrealtype* P = N_VGetArrayPointer(p);
  sunrealtype xp = 0.0, yp = 0.0;
  int i;
  (void)t, (void)data;
  for (i = 0; i < NB; ++i) {
    const sunrealtype dx = X[2 * i] - xp, dy = X[2 * i + 1] - yp;
    P[i] = dx * dx + dy * dy - LINK * LINK;
    xp = X[2 * i];
    yp = X[2 * i + 1];
  }
  return 0;
}

/* G (nc x n, CSR): row i holds d Phi_i / d p_{i-1} (if i > 0) and d Phi_i / d p_i. */
static int phi_jac(sunrealtype t, N_Vector x, SUNMatrix G, void* data) {
  const sunrealtype* X = N_VGetArrayPointer(x);
  const sunindextype nnz = 4 * NB - 2;
  sunindextype *ptr, *idx, k = 0;
  sunrealtype *d, xp = 0.0, yp = 0.0;
  int i;
  (void)t, (void)data;
  if (SUNMatGetID(G) != SUNMATRIX_SPARSE || SUNSparseMatrix_SparseType(G) != CSR_MAT) return -1;
  if (SUNSparseMatrix_NNZ(G) < nnz && SUNSparseMatrix_Reallocate(G, nnz) != 0) return -1;
  ptr = SUNSparseMatrix_IndexPointers(G);
  idx = SUNSparseMatrix_IndexValues(G);
  d = SUNSparseMatrix_Data(G);
  for (i = 0; i < NB; ++i) {
    const sunrealtype dx = X[2 * i] - xp, dy = X[2 * i + 1] - yp;
    ptr[i] = k;
    if (i > 0) {
      idx[k] = 2 * i - 2, d[k++] = -2.0 * dx;
      idx[k] = 2 * i - 1, d[k++] = -2.0 * dy;
    }
    idx[k] = 2 * i, d[k++] = 2.0 * dx;
    idx[k] = 2 * i + 1, d[k++] = 2.0 * dy;
    xp = X[2 * i];
    yp = X[2 * i + 1];
  }
  ptr[NB] = k;
  return 0;
}

static sunrealtype energy(const sunrealtype* X, const sunrealtype* V) {
  sunrealtype e = 0.0;
  int i;
  for (i = 0; i < NB; ++i) {
    e += 0.5 * (V[2 * i] * V[2 * i] + V[2 * i + 1] * V[2 * i + 1]) + GRAV * X[2 * i + 1];
  }
  return e;
}

static sunrealtype drift(N_Vector x, N_Vector work) {
  phi(0.0, x, work, NULL);
  return N_VMaxNorm(work);
}

int main(void) {
  const sunindextype n = 2 * NB, m = 3 * NB;
  SUNContext ctx = NULL;
  N_Vector x, v, p, b, w;
  SUNMatrix A;
  SUNLinearSolver LS;
  void* mem;
  sunrealtype t = 0.0, e0, err = 0.0, dmax = 0.0, *X, *V;
  long nsteps = 0, nni = 0, nlsetups = 0;
  int fail, i;

  if (check_flag(SUNContext_Create(SUN_COMM_NULL, &ctx), "SUNContext_Create")) return 1;
  x = N_VNew_Serial(n, ctx);
  v = N_VNew_Serial(n, ctx);
  p = N_VNew_Serial(NB, ctx);
  b = N_VNew_Serial(m, ctx);
  w = N_VNew_Serial(NB, ctx); /* scratch for the drift */
  A = SUNSparseMatrix(m, m, 2 * NB + 2 * (4 * NB - 2), CSR_MAT, ctx);
  if (x == NULL || v == NULL || p == NULL || b == NULL || w == NULL || A == NULL) return 1;
  LS = SUNLinSol_KLU(b, A, ctx);
  mem = CEodeCreate(ctx);
  if (LS == NULL || mem == NULL) return 1;

  X = N_VGetArrayPointer(x);
  V = N_VGetArrayPointer(v);
  for (i = 0; i < NB; ++i) {
    X[2 * i] = (i + 1) * LINK * sin(ANGLE0);
    X[2 * i + 1] = -(i + 1) * LINK * cos(ANGLE0);
  }
  N_VConst(0.0, v);
  e0 = energy(X, V);

  fail = check_flag(CEodeInit(mem, force, 0.0, x, v), "CEodeInit") ||
         check_flag(CEodeSetMethodByName(mem, "G5_ONES"), "CEodeSetMethodByName") ||
         check_flag(CEodeSetFixedStep(mem, STEP), "CEodeSetFixedStep") ||
         check_flag(CEodeSetStopTime(mem, TEND), "CEodeSetStopTime") ||
         check_flag(CEodeSetLinearSolver(mem, LS, A), "CEodeSetLinearSolver") ||
         check_flag(CEodeSetConstraints(mem, p, phi, phi_jac), "CEodeSetConstraints");

  while (!fail && t < TEND - 0.5 * STEP) {
    sunrealtype de, dr;
    fail = check_flag(CEodeEvolve(mem, TEND, x, v, &t, CE_ONE_STEP), "CEodeEvolve");
    de = fabs(energy(X, V) - e0);
    dr = drift(x, w);
    if (!(de <= err)) err = de; /* also catches NaN */
    if (!(dr <= dmax)) dmax = dr;
  }
  if (!fail) {
    fail = check_flag(CEodeGetNumSteps(mem, &nsteps), "CEodeGetNumSteps") ||
           check_flag(CEodeGetNumNonlinSolvIters(mem, &nni), "CEodeGetNumNonlinSolvIters") ||
           check_flag(CEodeGetNumLinSolvSetups(mem, &nlsetups), "CEodeGetNumLinSolvSetups");
  }

  printf("Chain of %d pendulums, G5_ONES + KLU, h = %g, %g s (E0 = %.4f J)\n", NB, STEP, TEND, e0);
  printf("  steps %ld, Newton iterations %ld, KLU factorisations %ld\n", nsteps, nni, nlsetups);
  printf("  max |E - E0|    = %.4e J     (bound 5e-7)\n", err);
  printf("  max |Phi_i| / l^2 = %.4e     (bound 1e-10)\n", dmax / (LINK * LINK));
  if (!fail && (!(err <= 5e-7) || !(dmax <= 1e-10 * LINK * LINK))) {
    printf("FAILED: energy or constraint drift above its bound\n");
    fail = 1;
  }

  CEodeFree(&mem);
  SUNLinSolFree(LS);
  SUNMatDestroy(A);
  N_VDestroy(w);
  N_VDestroy(b);
  N_VDestroy(p);
  N_VDestroy(v);
  N_VDestroy(x);
  SUNContext_Free(&ctx);
  if (!fail) printf("PASSED\n");
  return fail;
}
