/* -----------------------------------------------------------------------------
 * chain_dae: a planar chain of N point-mass pendulums as an index-3 DAE,
 * solved by CEODE through the sparse (KLU) saddle-point path, to show that the
 * cost of a step grows linearly with the size of the model.
 *
 * Problem: N point masses m_i = 1 kg at p_i = (x_i, y_i), i = 1..N, joined by
 * massless rigid links of length l = L/N (L = 1 m) to each other and the first
 * to the fixed origin p_0 = 0, gravity g = 9.81 m/s^2 along -y:
 *     x'' + G(x)^T lambda = f = (0, -g, 0, -g, ...),   M = I (no mass function),
 *     Phi_i(x) = |p_i - p_{i-1}|^2 - l^2 = 0,  i = 1..N   (n = 2N, nc = N).
 * Start: the chain straight at 60 deg from the downward vertical, at rest.
 * Each run takes a fixed number of steps (NSTEPS of h = 1e-4 s) so that the
 * time per step is comparable between sizes; h stays inside the stability
 * limit of central differences (Omega_max = 2) for the highest transverse
 * frequency of the chain, about 2 N sqrt(g/L) rad/s: Omega ~ 0.6 at N = 1000,
 * ~ 1.9 at N = 3000 (N = 10000 would need a smaller h: there it is unstable and
 * the constraint Newton iteration diverges).
 *
 * Figures: error = max |E - E0| with E = sum(1/2 |v_i|^2 + g y_i) (the chain is
 * conservative, so this measures the integration error; there is no reference
 * solution), drift = max_i |Phi_i| over all steps, vres = max |G(x) x'|.
 *
 * Method: CEODE G3_CD (central differences; with constraints this is SHAKE),
 * fixed step, no velocity dependence, the (n+nc) x (n+nc) CSR saddle-point
 * matrix factored by KLU (SUNLinSol_KLU); G(x) is filled as an nc x n CSR
 * SUNSparseMatrix by the constraint Jacobian callback.
 *
 * Exit code 0 only if every run succeeds, the least-squares slope of
 * log(time per step) against log N is <= 1.3 (no worse than linear within
 * noise), and the drift of every run is <= 1e-10 l^2 (relative to the size of
 * Phi_i; position round-off alone gives ~1e-16 |p| l, i.e. ~1e-13 l^2 at N =
 * 1000, so this leaves room for round-off but not for any real drift).
 *
 * Timing: each size is run repeatedly until one timing lasts >= 50 ms; the
 * median of 3 timings is reported (one run when a run takes more than 2 s).
 * Wall and process CPU time are both reported; the slope check uses CPU time,
 * which other jobs on a shared machine disturb less (the code is serial, so
 * on an idle machine the two agree).
 *
 * Usage: chain_dae [--csv FILE] [--full]    (N = 10 ... 1000; --full adds 3000)
 * ---------------------------------------------------------------------------*/
#define _POSIX_C_SOURCE 200809L /* clock_gettime under -std=c99 */
#include <ceode/ceode.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_sparse.h>
#include <time.h>

#define GRAV 9.81
#define LTOT 1.0
#define HSTEP 1e-4
#define NSTEPS 1000
#define ANGLE0 1.04719755119659774615 /* 60 deg from the downward vertical */
#define METHOD "G3_CD"

struct chain {
  long N;   /* number of masses = number of constraints */
  double l; /* link length */
};

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double cpu_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
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

static int rhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
  const struct chain* c = (const struct chain*)data;
  double* F = N_VGetArrayPointer(f);
  long i;
  (void)t;
  (void)x;
  (void)v;
  for (i = 0; i < c->N; ++i) {
    F[2 * i] = 0.0;
    F[2 * i + 1] = -GRAV;
  }
  return 0;
}

static int phi_fn(sunrealtype t, N_Vector x, N_Vector phi, void* data) {
  const struct chain* c = (const struct chain*)data;
  const double* X = N_VGetArrayPointer(x);
  double* P = N_VGetArrayPointer(phi);
  double xp = 0.0, yp = 0.0;
  long i;
  (void)t;
  for (i = 0; i < c->N; ++i) {
    double dx = X[2 * i] - xp, dy = X[2 * i + 1] - yp;
    P[i] = dx * dx + dy * dy - c->l * c->l;
    xp = X[2 * i];
    yp = X[2 * i + 1];
  }
  return 0;
}

/* G: nc x n CSR. Row i: d Phi_i / d(x_{i-1}, y_{i-1}, x_i, y_i). */
static int G_fn(sunrealtype t, N_Vector x, SUNMatrix G, void* data) {
  const struct chain* c = (const struct chain*)data;
  const double* X = N_VGetArrayPointer(x);
  sunindextype *ptr, *idx, k = 0, nnz = 4 * c->N - 2;
  double* d;
  double xp = 0.0, yp = 0.0;
  long i;
  (void)t;
  if (SUNMatGetID(G) != SUNMATRIX_SPARSE || SUNSparseMatrix_SparseType(G) != CSR_MAT) return -1;
  if (SUNSparseMatrix_NNZ(G) < nnz && SUNSparseMatrix_Reallocate(G, nnz) != SUNMAT_SUCCESS)
    return -1;
  ptr = SUNSparseMatrix_IndexPointers(G);
  idx = SUNSparseMatrix_IndexValues(G);
  d = SUNSparseMatrix_Data(G);
  for (i = 0; i < c->N; ++i) {
    double dx = X[2 * i] - xp, dy = X[2 * i + 1] - yp;
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
  ptr[c->N] = k;
  return 0;
}

static double energy(long N, const double* X, const double* V) {
  double e = 0.0;
  long i;
  for (i = 0; i < N; ++i) {
    e += 0.5 * (V[2 * i] * V[2 * i] + V[2 * i + 1] * V[2 * i + 1]) + GRAV * X[2 * i + 1];
  }
  return e;
}

/* max_i |Phi_i| and max_i |(G v)_i| */
static void residuals(const struct chain* c, const double* X, const double* V, double* drift,
                      double* vres) {
  double xp = 0.0, yp = 0.0, up = 0.0, wp = 0.0, dm = 0.0, vm = 0.0;
  long i;
  for (i = 0; i < c->N; ++i) {
    double dx = X[2 * i] - xp, dy = X[2 * i + 1] - yp;
    double ph = fabs(dx * dx + dy * dy - c->l * c->l);
    double gv = fabs(2.0 * (dx * (V[2 * i] - up) + dy * (V[2 * i + 1] - wp)));
    if (ph > dm || ph != ph) dm = ph;
    if (gv > vm || gv != gv) vm = gv;
    xp = X[2 * i];
    yp = X[2 * i + 1];
    up = V[2 * i];
    wp = V[2 * i + 1];
  }
  *drift = dm;
  *vres = vm;
}

struct result {
  double err, drift, vres, secs, cpu;
  long steps, nfe, nni;
};

static int run(SUNContext ctx, long N, struct result* r) {
  struct chain c;
  N_Vector x = NULL, v = NULL, phi = NULL, b = NULL;
  SUNMatrix A = NULL;
  SUNLinearSolver LS = NULL;
  void* mem = NULL;
  double *X, *V, e0, t = 0.0;
  long i, n = 2 * N, step;
  int fail = 0;
  memset(r, 0, sizeof(*r));
  c.N = N;
  c.l = LTOT / (double)N;
  x = N_VNew_Serial(n, ctx);
  v = N_VNew_Serial(n, ctx);
  phi = N_VNew_Serial(N, ctx);
  b = N_VNew_Serial(n + N, ctx);
  /* saddle-point matrix: M = I (n), G and G^T (4N - 2 each) */
  A = SUNSparseMatrix(n + N, n + N, n + 2 * (4 * N - 2), CSR_MAT, ctx);
  if (check_ptr(x, "N_VNew_Serial") || check_ptr(v, "N_VNew_Serial") ||
      check_ptr(phi, "N_VNew_Serial") || check_ptr(b, "N_VNew_Serial") ||
      check_ptr(A, "SUNSparseMatrix")) {
    fail = 1;
    goto done;
  }
  LS = SUNLinSol_KLU(b, A, ctx);
  if (check_ptr(LS, "SUNLinSol_KLU")) {
    fail = 1;
    goto done;
  }
  X = N_VGetArrayPointer(x);
  V = N_VGetArrayPointer(v);
  for (i = 0; i < N; ++i) {
    X[2 * i] = (double)(i + 1) * c.l * sin(ANGLE0);
    X[2 * i + 1] = -(double)(i + 1) * c.l * cos(ANGLE0);
    V[2 * i] = V[2 * i + 1] = 0.0;
  }
  e0 = energy(N, X, V);
  mem = CEodeCreate(ctx);
  if (check_ptr(mem, "CEodeCreate")) {
    fail = 1;
    goto done;
  }
  fail |= check_flag(CEodeInit(mem, rhs, 0.0, x, v), "CEodeInit");
  if (!fail) fail |= check_flag(CEodeSetUserData(mem, &c), "CEodeSetUserData");
  if (!fail) fail |= check_flag(CEodeSetMethodByName(mem, METHOD), "CEodeSetMethodByName");
  if (!fail) fail |= check_flag(CEodeSetFixedStep(mem, HSTEP), "CEodeSetFixedStep");
  if (!fail) fail |= check_flag(CEodeSetLinearSolver(mem, LS, A), "CEodeSetLinearSolver");
  if (!fail) fail |= check_flag(CEodeSetConstraints(mem, phi, phi_fn, G_fn), "CEodeSetConstraints");
  if (!fail) fail |= check_flag(CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0),
                                "CEodeSetStabilityGuard");
  if (!fail) fail |= check_flag(CEodeSetMaxNumSteps(mem, -1), "CEodeSetMaxNumSteps");
  r->secs = now();
  r->cpu = cpu_now();
  for (step = 0; !fail && step < NSTEPS; ++step) {
    double de, dr, vr;
    int flag = CEodeEvolve(mem, 1.0, x, v, &t, CE_ONE_STEP);
    if (check_flag(flag, "CEodeEvolve")) {
      fail = 1;
      break;
    }
    de = fabs(energy(N, X, V) - e0);
    residuals(&c, X, V, &dr, &vr);
    if (de > r->err || de != de) r->err = de;
    if (dr > r->drift || dr != dr) r->drift = dr;
    if (vr > r->vres || vr != vr) r->vres = vr;
  }
  r->secs = now() - r->secs;
  r->cpu = cpu_now() - r->cpu;
  if (!fail) {
    fail |= check_flag(CEodeGetNumSteps(mem, &r->steps), "CEodeGetNumSteps");
    fail |= check_flag(CEodeGetNumRhsEvals(mem, &r->nfe), "CEodeGetNumRhsEvals");
    fail |= check_flag(CEodeGetNumNonlinSolvIters(mem, &r->nni), "CEodeGetNumNonlinSolvIters");
  }
done:
  if (mem) CEodeFree(&mem);
  if (LS) SUNLinSolFree(LS);
  if (A) SUNMatDestroy(A);
  if (x) N_VDestroy(x);
  if (v) N_VDestroy(v);
  if (phi) N_VDestroy(phi);
  if (b) N_VDestroy(b);
  return fail;
}

static int cmp_double(const void* a, const void* b) {
  double x = *(const double*)a, y = *(const double*)b;
  return (x > y) - (x < y);
}

static int measure(SUNContext ctx, long N, struct result* r) {
  struct result tmp;
  double times[3], cpus[3];
  long reps, k;
  int b;
  if (run(ctx, N, r)) return 1;
  if (r->secs > 2.0) return 0;
  reps = r->secs > 0.05 ? 1 : (long)ceil(0.05 / (r->secs > 1e-7 ? r->secs : 1e-7));
  for (b = 0; b < 3; ++b) {
    double t0 = now(), c0 = cpu_now();
    for (k = 0; k < reps; ++k) {
      if (run(ctx, N, &tmp)) return 1;
    }
    times[b] = (now() - t0) / (double)reps;
    cpus[b] = (cpu_now() - c0) / (double)reps;
  }
  qsort(times, 3, sizeof(double), cmp_double);
  qsort(cpus, 3, sizeof(double), cmp_double);
  r->secs = times[1];
  r->cpu = cpus[1];
  return 0;
}

static double lsq_slope(int n, const double* x, const double* y) {
  double mx = 0, my = 0, sxy = 0, sxx = 0;
  int k;
  for (k = 0; k < n; ++k) mx += x[k] / n, my += y[k] / n;
  for (k = 0; k < n; ++k) {
    sxy += (x[k] - mx) * (y[k] - my);
    sxx += (x[k] - mx) * (x[k] - mx);
  }
  return sxy / sxx;
}

int main(int argc, char** argv) {
  static const long sizes[] = {10, 30, 100, 300, 1000, 3000};
  double lx[6], ly[6], lw[6];
  SUNContext ctx;
  FILE* csv = NULL;
  int full = 0, i, npts = 0, nfail = 0, nbad = 0, nsizes;
  double slope = 0.0;
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
  nsizes = full ? 6 : 5;
  if (SUNContext_Create(NULL, &ctx)) return 1;
  printf("Planar chain of N unit point masses, links L/N, index-3 DAE, CEODE %s + KLU\n", METHOD);
  printf("%d steps of h = %g s from rest at 60 deg; error = max |E - E0|, drift = max |Phi_i|\n\n",
         NSTEPS, HSTEP);
  printf("%6s %6s %11s %11s %11s %8s %8s %8s %11s %12s %12s\n", "N", "n+nc", "error", "drift",
         "vres", "steps", "f evals", "NLS its", "wall s", "wall/step", "cpu/step");
  for (i = 0; i < nsizes; ++i) {
    struct result r;
    long N = sizes[i];
    if (measure(ctx, N, &r)) {
      fprintf(stderr, "run N=%ld failed\n", N);
      ++nfail;
      continue;
    }
    printf("%6ld %6ld %11.3e %11.3e %11.3e %8ld %8ld %8ld %11.3e %12.3e %12.3e", N, 3 * N, r.err,
           r.drift, r.vres, r.steps, r.nfe, r.nni, r.secs, r.secs / (double)r.steps,
           r.cpu / (double)r.steps);
    if (!(r.drift <= 1e-10 * (LTOT / (double)N) * (LTOT / (double)N))) {
      ++nbad;
      printf("  <-- drift above 1e-10 l^2");
    }
    printf("\n");
    lx[npts] = log((double)N);
    ly[npts] = log(r.cpu / (double)r.steps);
    lw[npts] = log(r.secs / (double)r.steps);
    ++npts;
    if (csv) {
      fprintf(csv, "chain_dae,CEODE,N=%ld %s,%.3g,%.6e,%.6e,%ld,%ld,%.6e\n", N, METHOD, HSTEP,
              r.err, r.drift, r.steps, r.nfe, r.secs);
    }
  }
  if (npts >= 2) {
    slope = lsq_slope(npts, lx, ly);
    printf("\nlog-log slope of time per step against N (least squares, all sizes):\n");
    printf("  CPU time %.3f (checked), wall time %.3f\n", slope, lsq_slope(npts, lx, lw));
    if (npts >= 3) {
      printf("  over the three largest sizes: CPU %.3f, wall %.3f\n",
             lsq_slope(3, lx + npts - 3, ly + npts - 3), lsq_slope(3, lx + npts - 3, lw + npts - 3));
    }
    if (slope > 1.3) {
      ++nbad;
      printf("slope above 1.3: the step cost grows faster than linearly\n");
    }
  } else {
    ++nbad;
  }
  printf("%d runs failed, %d checks off\n", nfail, nbad);
  if (csv) fclose(csv);
  SUNContext_Free(&ctx);
  return (nfail == 0 && nbad == 0) ? 0 : 1;
}
