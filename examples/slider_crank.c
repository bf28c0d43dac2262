/* -----------------------------------------------------------------------------
 * slider_crank: SUNDIALS' IDA slider-crank problem (examples/ida/serial/
 * idaSlCrank_dns.c in the SUNDIALS sources) ported to CEODE, the worked IDA
 * example of docs/porting.md.
 *
 * Problem: a crank (angle q, half-length a = 0.5, inertia J1 = 1), a connecting
 * rod (angle p, mass m2 = 1, inertia J2 = 2) and a slider (position xs); a
 * spring-damper (k = 1, c = 1, free length l0 = 1) joins crank and rod, a
 * constant horizontal force F = 1 acts on the rod. Generalised coordinates
 * x = (q, xs, p), two position constraints
 *     Phi(x) = (xs - cos p - a cos q,  -sin p - a sin q) = 0,
 *     M x'' + G(x)^T lambda = Q(x, x'),   M = diag(J1, m2, J2),  G = dPhi/dx,
 * released at rest from q = pi/2, p = asin(-a), xs = cos p; t in [0, 10].
 * Q depends on x' through the damper: CEODE's implicit path.
 *
 * IDA (the original) integrates the stabilised index-2 GGL form with 10
 * unknowns (x, x', lambda, mu); CEODE takes the index-3 form above directly:
 * 3 unknowns, mass function + constraint functions, no index reduction.
 *
 * Reference: IDA on the same GGL residual at rtol = atol = 1e-10, started from
 * the consistent accelerations and multipliers that CEODE computes at t = 0.
 * The program exits 0 only if CEODE (G3_CD, h = 1e-3) agrees with it within
 * 1e-6 in q, xs, p at t = 0.25, 0.5, ..., 10, and the constraint residual stays
 * below 1e-10, and the multipliers at t = 10 agree within 1e-6. It also prints
 * IDA's published t = 10 row (rtol = 1e-6).
 * ---------------------------------------------------------------------------*/
#include <ceode/ceode.h>
#include <ida/ida.h>
#include <ida/ida_ls.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#define A_HALF 0.5
#define J1 1.0
#define M2 1.0
#define J2 2.0
#define KSPRING 1.0
#define CDAMP 1.0
#define L0 1.0
#define FORCE 1.0
#define NOUT 40
#define TEND 10.0
#define HSTEP 1e-3
#define TOL 1e-6

#if SUNDIALS_VERSION_MAJOR >= 7
#define CTX_COMM SUN_COMM_NULL
#else
#define CTX_COMM NULL
#endif

/* Generalised forces of the spring-damper and F at (x, x') = (q, xs, p, qd, xd, pd). */
static void forces(const double* x, const double* v, double* Q) {
  const double s1 = sin(x[0]), c1 = cos(x[0]), s2 = sin(x[2]), c2 = cos(x[2]);
  const double s21 = s2 * c1 - c2 * s1, c21 = c2 * c1 + s2 * s1, xs = x[1];
  const double l =
      sqrt(xs * xs - xs * (c2 + A_HALF * c1) + (1 + A_HALF * A_HALF) / 4 + A_HALF * c21 / 2);
  const double ldot = (2 * xs * v[1] - v[1] * (c2 + A_HALF * c1) +
                       xs * (s2 * v[2] + A_HALF * s1 * v[0]) - A_HALF * s21 * (v[2] - v[0]) / 2) /
                      (2 * l);
  const double fl = (KSPRING * (l - L0) + CDAMP * ldot) / l;
  Q[0] = -fl * A_HALF * (s21 / 2 + xs * s1) / 2;
  Q[1] = fl * (c2 / 2 - xs + A_HALF * c1 / 2) + FORCE;
  Q[2] = -fl * (xs * s2 - A_HALF * s21 / 2) / 2 - FORCE * s2;
}

static void constraints(const double* x, double* phi) {
  phi[0] = x[1] - cos(x[2]) - A_HALF * cos(x[0]);
  phi[1] = -sin(x[2]) - A_HALF * sin(x[0]);
}

/* G = dPhi/dx, row-major 2 x 3 */
static void jacobian(const double* x, double G[2][3]) {
  G[0][0] = A_HALF * sin(x[0]), G[0][1] = 1, G[0][2] = sin(x[2]);
  G[1][0] = -A_HALF * cos(x[0]), G[1][1] = 0, G[1][2] = -cos(x[2]);
}

/* ---- CEODE callbacks */
static int ce_force(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
  (void)t, (void)data;
  forces(N_VGetArrayPointer(x), N_VGetArrayPointer(v), N_VGetArrayPointer(f));
  return 0;
}

static int ce_mass(sunrealtype t, N_Vector x, SUNMatrix M, void* data, N_Vector t1, N_Vector t2,
                   N_Vector t3) {
  (void)t, (void)x, (void)data, (void)t1, (void)t2, (void)t3;
  SUNMatZero(M);
  SM_ELEMENT_D(M, 0, 0) = J1, SM_ELEMENT_D(M, 1, 1) = M2, SM_ELEMENT_D(M, 2, 2) = J2;
  return 0;
}

static int ce_phi(sunrealtype t, N_Vector x, N_Vector phi, void* data) {
  (void)t, (void)data;
  constraints(N_VGetArrayPointer(x), N_VGetArrayPointer(phi));
  return 0;
}

static int ce_G(sunrealtype t, N_Vector x, SUNMatrix G, void* data) {
  double g[2][3];
  (void)t, (void)data;
  jacobian(N_VGetArrayPointer(x), g);
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 3; ++j) SM_ELEMENT_D(G, i, j) = g[i][j];
  return 0;
}

/* ---- IDA residual of the GGL form, y = (x, x', lambda, mu) */
static int ida_res(sunrealtype t, N_Vector yy, N_Vector yp, N_Vector rr, void* data) {
  const double *y = N_VGetArrayPointer(yy), *d = N_VGetArrayPointer(yp);
  double *r = N_VGetArrayPointer(rr), Q[3], G[2][3], phi[2];
  const double mass[3] = {J1, M2, J2};
  (void)t, (void)data;
  forces(y, y + 3, Q);
  jacobian(y, G);
  constraints(y, phi);
  for (int j = 0; j < 3; ++j) {
    r[j] = d[j] - y[3 + j] + G[0][j] * y[8] + G[1][j] * y[9]; /* x' = v - G^T mu */
    r[3 + j] = mass[j] * d[3 + j] - Q[j] + G[0][j] * y[6] + G[1][j] * y[7];
  }
  r[6] = phi[0], r[7] = phi[1];
  r[8] = G[0][0] * y[3] + G[0][1] * y[4] + G[0][2] * y[5]; /* G v = 0 */
  r[9] = G[1][0] * y[3] + G[1][1] * y[4] + G[1][2] * y[5];
  return 0;
}

static int check(int flag, const char* call) {
  if (flag < 0) fprintf(stderr, "ERROR: %s returned %d\n", call, flag);
  return flag < 0;
}

/* The IDA reference at the NOUT output times into ref[k][0..2]; y0, yp0 consistent. */
static int ida_reference(SUNContext ctx, N_Vector y, N_Vector yp, double ref[][3],
                         double lam_end[2]) {
  N_Vector id = N_VClone(y);
  SUNMatrix J = SUNDenseMatrix(10, 10, ctx);
  SUNLinearSolver LS = SUNLinSol_Dense(y, J, ctx);
  void* ida = IDACreate(ctx);
  int fail = ida == NULL || LS == NULL;
  N_VConst(1, id);
  for (int i = 6; i < 10; ++i) NV_Ith_S(id, i) = 0; /* lambda, mu: algebraic */
  if (!fail) fail |= check(IDAInit(ida, ida_res, 0, y, yp), "IDAInit");
  if (!fail) fail |= check(IDASStolerances(ida, 1e-10, 1e-10), "IDASStolerances");
  if (!fail) fail |= check(IDASetId(ida, id), "IDASetId");
  if (!fail) fail |= check(IDASetSuppressAlg(ida, SUNTRUE), "IDASetSuppressAlg");
  if (!fail) fail |= check(IDASetLinearSolver(ida, LS, J), "IDASetLinearSolver");
  if (!fail) fail |= check(IDASetMaxNumSteps(ida, 1000000), "IDASetMaxNumSteps");
  if (!fail) fail |= check(IDASetInitStep(ida, 1e-5), "IDASetInitStep");
  long nst = 0;
  for (int k = 0; !fail && k < NOUT; ++k) {
    sunrealtype t;
    fail |= check(IDASolve(ida, TEND * (k + 1) / NOUT, &t, y, yp, IDA_NORMAL), "IDASolve");
    for (int j = 0; j < 3; ++j) ref[k][j] = NV_Ith_S(y, j);
  }
  lam_end[0] = NV_Ith_S(y, 6), lam_end[1] = NV_Ith_S(y, 7);
  IDAGetNumSteps(ida, &nst);
  printf("IDA (GGL, 10 unknowns, rtol = atol = 1e-10): %ld steps\n", nst);
  IDAFree(&ida);
  SUNLinSolFree(LS);
  SUNMatDestroy(J);
  N_VDestroy(id);
  return fail;
}

int main(void) {
  SUNContext ctx = NULL;
  if (check(SUNContext_Create(CTX_COMM, &ctx), "SUNContext_Create")) return 1;
  N_Vector x = N_VNew_Serial(3, ctx), v = N_VNew_Serial(3, ctx), a = N_VNew_Serial(3, ctx);
  N_Vector lam = N_VNew_Serial(2, ctx), tmpl = N_VNew_Serial(5, ctx);
  N_Vector y = N_VNew_Serial(10, ctx), yp = N_VNew_Serial(10, ctx);
  SUNMatrix M = SUNDenseMatrix(3, 3, ctx), A = SUNDenseMatrix(5, 5, ctx);
  SUNLinearSolver LS = SUNLinSol_Dense(tmpl, A, ctx);
  void* mem = CEodeCreate(ctx);
  static double ref[NOUT][3];
  double lam_ida[2] = {0, 0};
  double err = 0, drift = 0;
  int fail = mem == NULL || LS == NULL;

  /* Consistent positions at rest (Phi(x0) = 0, G v0 = 0): no IC solver needed. */
  const double p0 = asin(-A_HALF);
  NV_Ith_S(x, 0) = 2 * atan(1.0), NV_Ith_S(x, 1) = cos(p0), NV_Ith_S(x, 2) = p0;
  N_VConst(0, v);
  if (!fail) fail |= check(CEodeInit(mem, ce_force, 0, x, v), "CEodeInit");
  if (!fail) fail |= check(CEodeSetMethodByName(mem, "G3_CD"), "CEodeSetMethodByName");
  if (!fail) fail |= check(CEodeSetFixedStep(mem, HSTEP), "CEodeSetFixedStep");
  if (!fail) fail |= check(CEodeSetMassFn(mem, ce_mass, M, SUNTRUE), "CEodeSetMassFn");
  if (!fail) fail |= check(CEodeSetLinearSolver(mem, LS, A), "CEodeSetLinearSolver");
  if (!fail) fail |= check(CEodeSetConstraints(mem, lam, ce_phi, ce_G), "CEodeSetConstraints");
  if (!fail) fail |= check(CEodeSetVelocityDependence(mem, SUNTRUE), "CEodeSetVelocityDependence");
  if (!fail) fail |= check(CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0), "CEodeSetStabilityGuard");

  /* Evolving to t0 starts the method: a(0) and lambda(0) are then known. */
  sunrealtype t = 0;
  if (!fail) fail |= check(CEodeEvolve(mem, 0, x, v, &t, CE_NORMAL), "CEodeEvolve(t0)");
  if (!fail) fail |= check(CEodeGetAccel(mem, a), "CEodeGetAccel");
  if (!fail) fail |= check(CEodeGetMultipliers(mem, lam), "CEodeGetMultipliers");
  N_VConst(0, y);
  N_VConst(0, yp);
  for (int j = 0; j < 3; ++j) {
    NV_Ith_S(y, j) = NV_Ith_S(x, j);
    NV_Ith_S(yp, 3 + j) = NV_Ith_S(a, j);
  }
  NV_Ith_S(y, 6) = NV_Ith_S(lam, 0), NV_Ith_S(y, 7) = NV_Ith_S(lam, 1);
  if (!fail) {
    printf("t = 0: a = (%.10f, %.10f, %.10f), lambda = (%.10f, %.10f)\n", NV_Ith_S(a, 0),
           NV_Ith_S(a, 1), NV_Ith_S(a, 2), NV_Ith_S(lam, 0), NV_Ith_S(lam, 1));
    fail |= ida_reference(ctx, y, yp, ref, lam_ida);
  }

  printf("%6s %13s %13s %13s %10s\n", "t", "q", "xs", "p", "|x - IDA|");
  for (int k = 0; !fail && k < NOUT; ++k) {
    fail |= check(CEodeEvolve(mem, TEND * (k + 1) / NOUT, x, v, &t, CE_NORMAL), "CEodeEvolve");
    double e = 0, phi[2];
    for (int j = 0; j < 3; ++j) e = fmax(e, fabs(NV_Ith_S(x, j) - ref[k][j]));
    constraints(N_VGetArrayPointer(x), phi);
    drift = fmax(drift, fmax(fabs(phi[0]), fabs(phi[1])));
    err = fmax(err, e);
    if ((k + 1) % 4 == 0)
      printf("%6.2f %13.6e %13.6e %13.6e %10.2e\n", t, NV_Ith_S(x, 0), NV_Ith_S(x, 1),
             NV_Ith_S(x, 2), e);
  }
  printf("IDA's published t = 10 row (rtol 1e-6): 1.2757e+00 1.0236e+00 -4.9881e-01\n");
  /* The multipliers are the same quantity in both: CEodeGetMultipliers vs IDA's y[6], y[7]. */
  if (!fail) fail |= check(CEodeGetMultipliers(mem, lam), "CEodeGetMultipliers");
  const double dlam =
      fmax(fabs(NV_Ith_S(lam, 0) - lam_ida[0]), fabs(NV_Ith_S(lam, 1) - lam_ida[1]));
  printf("t = 10: lambda CEODE (%.8f, %.8f), IDA (%.8f, %.8f)\n", NV_Ith_S(lam, 0),
         NV_Ith_S(lam, 1), lam_ida[0], lam_ida[1]);
  if (!fail) CEodePrintAllStats(mem, stdout, SUN_OUTPUTFORMAT_TABLE);
  const int ok = !fail && err <= TOL && drift <= 1e-10 && dlam <= 1e-6;
  printf("max |CEODE - IDA| = %.3e (tolerance %.0e), max |Phi| = %.3e: %s\n", err, TOL, drift,
         ok ? "PASSED" : "FAILED");
  CEodeFree(&mem);
  SUNLinSolFree(LS);
  SUNMatDestroy(M), SUNMatDestroy(A);
  N_VDestroy(x), N_VDestroy(v), N_VDestroy(a), N_VDestroy(lam), N_VDestroy(tmpl);
  N_VDestroy(y), N_VDestroy(yp);
  SUNContext_Free(&ctx);
  return ok ? 0 : 1;
}
