/* -----------------------------------------------------------------------------
 * mri_inner_cost: fast f evaluations of CEODE and of an ARKStep ERK (classic
 * RK4) as MRIStep's inner stepper, on the problem of examples/mri_two_scale.c
 * (stiff oscillator q'' = -omega^2 (q - s), slow s' = -lambda s + cos t,
 * closed-form solution there).
 *
 * Usage: mri_inner_cost [ceode|ceode-w|erk4|erk4-adapt] [h_inner or rtol] [CEODE method] [omega]
 *        mri_inner_cost equal-error [omega]
 * "ceode-w" gives CEODE the fast frequency (CEodeSetMaxFrequency(omega)): its
 * stability guard then makes no evaluation (otherwise its Lanczos estimate runs
 * once per MRI run, at the first inner integration).
 * The second form compares at equal error: for each H, the reference error is
 * that of MRI with an (almost) exact inner solve (RK4, h = 5e-5); for each inner
 * stepper it reports the fewest fast f evaluations over n = 1 .. 64 inner steps
 * per fast stage (ERK33a's stages are H/3 long; the inner step is H/(3n), so that
 * CEODE and RK4 take exactly n steps) whose MRI error is within 10 % of the
 * reference, the ratio of the cheapest CEODE to RK4, and how many of the five H
 * meet "at most 1/3".
 * Prints, for slow steps H = 2/10 .. 2/160: H, max error at t = 2, fast f
 * evaluations (counted inside the fast right-hand side, every call), and the
 * order of a log-log fit of the errors.
 * ---------------------------------------------------------------------------*/
#include <arkode/arkode_arkstep.h>
#include <arkode/arkode_mristep.h>
#include <ceode/ceode.h>
#include <ceode/ceode_stepper.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double OMEGA = 10.0; /* argv[4] */
#define LAMBDA 2.0
#define S0 1.0
#define TEND 2.0
#define NRUNS 5

#if SUNDIALS_VERSION_MAJOR >= 7
#define CTX_COMM SUN_COMM_NULL
#else
#define CTX_COMM NULL
#endif

static void exact(double t, double* q, double* s, double* p) {
  const double a = LAMBDA / (1 + LAMBDA * LAMBDA), b = 1 / (1 + LAMBDA * LAMBDA);
  const double C = S0 - a, w2 = OMEGA * OMEGA;
  const double K = w2 * C / (w2 + LAMBDA * LAMBDA);
  const double M = w2 * a / (w2 - 1), N = w2 * b / (w2 - 1);
  const double e = exp(-LAMBDA * t);
  *s = C * e + a * cos(t) + b * sin(t);
  *q = K * e + M * cos(t) + N * sin(t);
  *p = -LAMBDA * K * e - M * sin(t) + N * cos(t);
}

static int fast_accel(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
  (void)t;
  (void)v;
  ++*(long*)data;
  NV_Ith_S(f, 0) = -OMEGA * OMEGA * (NV_Ith_S(x, 0) - NV_Ith_S(x, 1));
  NV_Ith_S(f, 1) = 0;
  return 0;
}

/* The same fast part in first-order form for ARKStep: y = (q, s, p, w). */
static int fast_first_order(sunrealtype t, N_Vector y, N_Vector ydot, void* data) {
  (void)t;
  ++*(long*)data;
  NV_Ith_S(ydot, 0) = NV_Ith_S(y, 2);
  NV_Ith_S(ydot, 1) = NV_Ith_S(y, 3);
  NV_Ith_S(ydot, 2) = -OMEGA * OMEGA * (NV_Ith_S(y, 0) - NV_Ith_S(y, 1));
  NV_Ith_S(ydot, 3) = 0;
  return 0;
}

static int slow_rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* data) {
  (void)data;
  N_VConst(0, ydot);
  NV_Ith_S(ydot, 1) = -LAMBDA * NV_Ith_S(y, 1) + cos(t);
  return 0;
}

static ARKodeButcherTable classic_rk4(void) {
  const sunrealtype c[4] = {0, 0.5, 0.5, 1};
  const sunrealtype A[16] = {0, 0, 0, 0, 0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 1, 0};
  const sunrealtype b[4] = {1.0 / 6, 1.0 / 3, 1.0 / 3, 1.0 / 6};
  return ARKodeButcherTable_Create(4, 4, 0, (sunrealtype*)c, (sunrealtype*)A, (sunrealtype*)b,
                                   NULL);
}

/* The inner stepper of the chosen kind; *mem is its integrator memory. */
static int is_ceode(const char* kind) { return strncmp(kind, "ceode", 5) == 0; }

static int make_inner(SUNContext ctx, const char* kind, double hin, const char* method, N_Vector y,
                      long* nfast, void** mem, MRIStepInnerStepper* inner) {
  if (is_ceode(kind)) {
    N_Vector x0 = N_VNew_Serial(2, ctx), v0 = N_VNew_Serial(2, ctx);
    NV_Ith_S(x0, 0) = NV_Ith_S(y, 0);
    NV_Ith_S(x0, 1) = NV_Ith_S(y, 1);
    NV_Ith_S(v0, 0) = NV_Ith_S(y, 2);
    NV_Ith_S(v0, 1) = NV_Ith_S(y, 3);
    *mem = CEodeCreate(ctx);
    int flag = CEodeInit(*mem, fast_accel, 0, x0, v0);
    if (!flag) flag = CEodeSetUserData(*mem, nfast);
    if (!flag) flag = CEodeSetMethodByName(*mem, method);
    if (!flag) flag = CEodeSetFixedStep(*mem, hin);
    if (!flag && strcmp(kind, "ceode-w") == 0) flag = CEodeSetMaxFrequency(*mem, OMEGA);
    if (!flag) flag = CEodeCreateMRIStepInnerStepper(*mem, inner);
    N_VDestroy(x0);
    N_VDestroy(v0);
    return flag;
  }
  *mem = ARKStepCreate(fast_first_order, NULL, 0, y, ctx);
  ARKodeButcherTable B = classic_rk4();
  int flag = ARKStepSetTables(*mem, 4, 0, NULL, B);
  ARKodeButcherTable_Free(B);
  if (!flag) flag = ARKStepSetUserData(*mem, nfast);
  if (!flag && strcmp(kind, "erk4") == 0) flag = ARKStepSetFixedStep(*mem, hin);
  if (!flag && strcmp(kind, "erk4") != 0)
    flag = ARKStepSetTableNum(*mem, ARKODE_DIRK_NONE, ARKODE_ZONNEVELD_5_3_4);
  if (!flag && strcmp(kind, "erk4") != 0) flag = ARKStepSStolerances(*mem, hin, 1e-3 * hin);
  if (!flag) flag = ARKStepSetMaxNumSteps(*mem, 1000000);
  if (!flag) flag = ARKStepCreateMRIStepInnerStepper(*mem, inner);
  return flag;
}

static double run(SUNContext ctx, const char* kind, double hin, const char* method, int nslow,
                  long* nfast) {
  double q, s, p, err = -1;
  sunrealtype t = 0;
  exact(0, &q, &s, &p);
  N_Vector y = N_VNew_Serial(4, ctx);
  NV_Ith_S(y, 0) = q;
  NV_Ith_S(y, 1) = s;
  NV_Ith_S(y, 2) = p;
  NV_Ith_S(y, 3) = 0;
  *nfast = 0;
  void* imem = NULL;
  MRIStepInnerStepper inner = NULL;
  if (make_inner(ctx, kind, hin, method, y, nfast, &imem, &inner) == 0) {
    void* mri = MRIStepCreate(slow_rhs, NULL, 0, y, inner, ctx);
    MRIStepCoupling C = MRIStepCoupling_LoadTable(ARKODE_MRI_GARK_ERK33a);
    int flag = MRIStepSetCoupling(mri, C);
    if (!flag) flag = MRIStepSetFixedStep(mri, TEND / nslow);
    if (!flag) flag = MRIStepSetMaxNumSteps(mri, 100000);
    if (!flag) flag = MRIStepEvolve(mri, TEND, y, &t, ARK_NORMAL);
    if (flag >= 0) {
      exact(t, &q, &s, &p);
      err = fmax(fabs(NV_Ith_S(y, 0) - q), fabs(NV_Ith_S(y, 1) - s));
      err = fmax(err, fabs(NV_Ith_S(y, 2) - p) / OMEGA);
    }
    MRIStepCoupling_Free(C);
    MRIStepFree(&mri);
  }
  if (is_ceode(kind)) {
    CEodeFreeMRIStepInnerStepper(&inner);
    CEodeFree(&imem);
  } else {
    MRIStepInnerStepper_Free(&inner);
    ARKStepFree(&imem);
  }
  N_VDestroy(y);
  return err;
}

#define NKINDS 5

/* The cheapest run of one inner stepper at slow step H within 10 % of ref. */
static long cheapest(SUNContext ctx, const char* kind, const char* method, int nslow, double ref,
                     int* best_n, double* best_e) {
  static const int nsub[] = {1, 2, 3, 4, 5, 6, 7, 8, 10, 12, 16, 24, 32, 48, 64};
  long best = -1;
  for (size_t j = 0; j < sizeof(nsub) / sizeof(nsub[0]); ++j) {
    long n = 0;
    const double h = TEND / nslow / 3 / nsub[j] * (1 + 1e-6);
    const double e = run(ctx, kind, h, method, nslow, &n);
    if (e > 0 && fabs(e - ref) <= 0.1 * ref && (best < 0 || n < best)) {
      best = n, *best_n = nsub[j], *best_e = e;
    }
  }
  return best;
}

static void equal_error(SUNContext ctx) {
  static const char* kinds[NKINDS][2] = {{"ceode", "G4_A34"},
                                         {"ceode", "G3_CD"},
                                         {"ceode-w", "G4_A34"},
                                         {"ceode-w", "G3_CD"},
                                         {"erk4", "RK4"}};
  int met = 0, met_w = 0;
  printf(
      "# omega %g; cheapest inner steps per stage n with MRI error within 10%% of the "
      "exact-inner error\n# -w: omega given to CEODE (CEodeSetMaxFrequency), no guard "
      "evaluations\n",
      OMEGA);
  printf(
      "# H ref_error | G4_A34 | G3_CD | G4_A34-w | G3_CD-w | RK4 (each: n err fast_f) | "
      "best CEODE/RK4 | best CEODE-w/RK4\n");
  for (int i = 0; i < NRUNS; ++i) {
    const int nslow = 10 << i;
    long nref = 0, cost[NKINDS];
    const double ref = run(ctx, "erk4", 5e-5, "", nslow, &nref);
    printf("%.5f %.4e", TEND / nslow, ref);
    for (int k = 0; k < NKINDS; ++k) {
      int bn = 0;
      double be = 0;
      cost[k] = cheapest(ctx, kinds[k][0], kinds[k][1], nslow, ref, &bn, &be);
      printf(" | %d %.3e %ld", bn, be, cost[k]);
    }
    const double rk = (double)cost[4];
    double r = -1, rw = -1;
    for (int k = 0; k < 2; ++k) {
      if (cost[k] > 0 && rk > 0 && (r < 0 || cost[k] / rk < r)) r = cost[k] / rk;
      if (cost[k + 2] > 0 && rk > 0 && (rw < 0 || cost[k + 2] / rk < rw)) rw = cost[k + 2] / rk;
    }
    met += r > 0 && r <= 1.0 / 3;
    met_w += rw > 0 && rw <= 1.0 / 3;
    printf(" | %.3f | %.3f\n", r, rw);
  }
  printf(
      "# omega %g: best CEODE <= RK4/3 at %d of %d H (guard estimating), %d of %d (omega "
      "given)\n",
      OMEGA, met, NRUNS, met_w, NRUNS);
}

int main(int argc, char** argv) {
  const char* kind = argc > 1 ? argv[1] : "ceode";
  if (strcmp(kind, "equal-error") == 0) {
    SUNContext ctx = NULL;
    if (argc > 2) OMEGA = atof(argv[2]);
    if (SUNContext_Create(CTX_COMM, &ctx) != 0) return 1;
    equal_error(ctx);
    SUNContext_Free(&ctx);
    return 0;
  }
  const double hin = argc > 2 ? atof(argv[2]) : 0.01;
  const char* method = argc > 3 ? argv[3] : "G4_A34";
  if (argc > 4) OMEGA = atof(argv[4]);
  SUNContext ctx = NULL;
  if (SUNContext_Create(CTX_COMM, &ctx) != 0) return 1;
  printf("# omega %g, inner %s (%s %g)\n# H max_error fast_f\n", OMEGA, kind,
         is_ceode(kind) ? method : "RK4", hin);
  double lx[NRUNS], ly[NRUNS];
  int n = 0;
  for (int i = 0; i < NRUNS; ++i) {
    long nfast = 0;
    const int nslow = 10 << i;
    const double err = run(ctx, kind, hin, method, nslow, &nfast);
    printf("%.5f %.6e %ld\n", TEND / nslow, err, nfast);
    if (err > 0) {
      lx[n] = log(TEND / nslow);
      ly[n++] = log(err);
    }
  }
  double mx = 0, my = 0, sxy = 0, sxx = 0;
  for (int i = 0; i < n; ++i) mx += lx[i] / n, my += ly[i] / n;
  for (int i = 0; i < n; ++i) {
    sxy += (lx[i] - mx) * (ly[i] - my);
    sxx += (lx[i] - mx) * (lx[i] - mx);
  }
  printf("# order (log-log fit over %d runs): %.3f\n", n, n > 1 ? sxy / sxx : 0.0);
  SUNContext_Free(&ctx);
  return 0;
}
