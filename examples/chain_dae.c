/* -----------------------------------------------------------------------------
 * chain_dae: a planar chain of N point-mass pendulums as an index-3 DAE.
 * Two studies in one program:
 *  (1) N-scaling: CEODE through the sparse (KLU) saddle-point path, to show
 *      that the cost of a step grows linearly with the size of the model;
 *  (2) work-precision at a fixed N (= 8 by default): CEODE side by side with
 *      ARKODE (RK3 and adaptive ERK on the index-1 form) and IDA (GGL), timed
 *      in one run (method.md sections 3, 6 and 7; the chain is the N-body
 *      version of the DAE pendulum of examples/pendulum_dae.c).
 *
 * Problem: N point masses m_i = 1 kg at p_i = (x_i, y_i), i = 1..N, joined by
 * massless rigid links of length l = L/N (L = 1 m) to each other and the first
 * to the fixed origin p_0 = 0, gravity g = 9.81 m/s^2 along -y:
 *     x'' + G(x)^T lambda = f = (0, -g, 0, -g, ...),   M = I (no mass function),
 *     Phi_i(x) = |p_i - p_{i-1}|^2 - l^2 = 0,  i = 1..N   (n = 2N, nc = N).
 * Start: the chain straight at 60 deg from the downward vertical, at rest.
 * There is no reference solution; the chain is conservative, so
 *     error = max |E - E0|,  E = sum(1/2 |v_i|^2 + g y_i),
 *     drift = max_i |Phi_i|  (in m^2),   vres = max_i |(G(x) x')_i|,
 * taken after every step, where the solver has x and x' at the same instant.
 *
 * (1) N-scaling. Each run takes a fixed number of steps (NSTEPS of h = 1e-4 s)
 * so that the time per step is comparable between sizes; h stays inside the
 * stability limit of central differences (Omega_max = 2) for the highest
 * transverse frequency of the chain, about 2 N sqrt(g/L) rad/s: Omega ~ 0.6 at
 * N = 1000, ~ 1.9 at N = 3000 (N = 10000 would need a smaller h: there it is
 * unstable and the constraint Newton iteration diverges). Method: CEODE G3_CD
 * (central differences; with constraints this is SHAKE), the (n+nc) x (n+nc)
 * CSR saddle-point matrix factored by KLU (SUNLinSol_KLU); G(x) is filled as
 * an nc x n CSR SUNSparseMatrix by the constraint Jacobian callback.
 * Rows: scene chain_dae in the --csv file.
 *
 * (2) Work-precision, N = WP_N = 8 (n = 16, nc = 8), t in [0, WP_TEND = 2 s]
 * (the chain falls, swings through the bottom and whips; its fastest
 * transverse mode, ~ 2 N sqrt(g/L) ~ 50 rad/s at rest, stiffens with the link
 * tension during the whip). Solvers:
 *  - CEODE, index 3, no index reduction, fixed h = 6e-3 ... 2e-5 s (1e-5 with
 *    --full): G3_CD, G4_A34 and G5_ONES, all with the library's consistent
 *    start (CEodeSetZeroStart(SUNFALSE), the default; the chain starts at
 *    rest, so its initial jerk is 0 but x^(4)(0) is not, and only G5 would
 *    differ with the paper's zero start), the 24 x 24 CSR saddle-point matrix
 *    [[I, G^T], [G, 0]] factored by KLU; G5_ONES also with SUNLinSol_Dense.
 *    (G5_ONES at h = 1e-2 stops with CE_CONV_FAILURE near t = 1.98 s, so the
 *    steps start at 6e-3.)
 *  - ARKODE ERKStep with Kutta's RK3 (c = 0, 1/2, 1; a21 = 1/2, a31 = -1,
 *    a32 = 2; b = 1/6, 2/3, 1/6) as a user Butcher table, same fixed steps, on
 *    the index-1 form: the constraints differentiated twice,
 *    G a = -(dG/dt) v with ((dG/dt) v)_i = 2 |v_i - v_{i-1}|^2, and the
 *    saddle system [[I, G^T], [G, 0]] (a, lambda) = (f, -(dG/dt) v) solved at
 *    every stage by KLU (the same matrix and solver as CEODE's; once more with
 *    SUNLinSol_Dense). (a) "RK3": no stabilisation; (b) "RK3+proj": after
 *    every step the positions are moved to the nearest point of Phi = 0
 *    (minimum-norm Newton, x -= G^T (G G^T)^-1 Phi, solved through the same
 *    saddle matrix, repeated to round-off), velocities untouched. Both call
 *    ERKStepReset after every step: SUNDIALS < 6.6.2 (Debian's is 6.4.1)
 *    treats any table with c_s = 1 as first-same-as-last and would reuse
 *    f(last stage) as f(t_n+1, y_n+1), which silently turns Kutta's RK3 into
 *    another, second-order method; the reset forces a fresh f. The program
 *    checks that every RK3 run took exactly 3 f evaluations per step.
 *  - ARKODE ERKStep adaptive, default (4th-order) table, the same index-1
 *    right-hand side (KLU), rtol = atol = 1e-4 ... 1e-12 (1e-13 with --full),
 *    no stabilisation.
 *  - IDA (variable-order BDF, rtol = atol = 1e-4 ... 1e-10) on the stabilised
 *    index-2 GGL form  q' = v + G^T mu,  v' + G^T lambda = f,  Phi(q) = 0,
 *    G(q) v = 0  (48 unknowns; lambda and mu algebraic and excluded from the
 *    error test), analytic 48 x 48 dense iteration matrix (IDASetJacFn,
 *    SUNLinSol_Dense), first step 1e-5 s, as in examples/pendulum_dae.c. At
 *    rtol = atol = 1e-11 IDA fails in its first steps (corrector convergence
 *    failures down to h ~ 1e-11), so its curve stops at 1e-10.
 * Rows: scene chain_dae_wp in the --wp-csv file (seconds = CPU time); the
 * program also prints the time of the best CEODE and the best SUNDIALS curve
 * at equal error.
 *
 * Timing: every run is the whole job (create, init, integrate in one-step
 * mode with the figures taken after each step, free). It is repeated until one
 * timing lasts >= 50 ms; the median of 3 (scaling) or 5 (work-precision) such
 * timings is reported, or a single run when one run takes more than 2 s
 * (scaling) or 1 s (work-precision). Wall and process CPU time are both
 * measured; CPU time is what the work-precision rows and the slope check use,
 * since other jobs on a shared machine disturb it less (the code is serial,
 * so on an idle machine the two agree).
 *
 * Reference: Fernandez de Bustos, Uriarte, Urkullu, Coria, "A Family of
 * Conditionally Explicit Methods for Second-Order ODEs and DAEs: Application
 * in Multibody Dynamics", Mathematics 2024, 12, 2862 (its DAE pendulum,
 * Tables 9-11, is the one-body case of this chain).
 *
 * Exit code 0 only if every run succeeds and
 *  (1) the least-squares slope of log(CPU time per step) against log N is
 *      <= 1.3 and the drift of every scaling run is <= 1e-10 l^2 (position
 *      round-off alone gives ~1e-16 |p| l, i.e. ~1e-13 l^2 at N = 1000);
 *  (2) every CEODE and every RK3+proj run has drift <= 1e-10 l^2, and every
 *      fixed-step RK3 run took exactly 3 f evaluations per step.
 *
 * Usage: chain_dae [--csv FILE] [--wp-csv FILE] [--full] [--no-scaling] [--no-wp]
 *   --full  adds N = 3000 to the scaling study and h = 1e-5 / tol = 1e-11 to
 *           the work-precision study.
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
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>
#include <time.h>

#include "ceode_sundials_compat.h" /* SUN_COMM_NULL on SUNDIALS 6.4 */

#define GRAV 9.81
#define LTOT 1.0
#define HSTEP 1e-4
#define NSTEPS 1000
#define ANGLE0 1.04719755119659774615 /* 60 deg from the downward vertical */
#define METHOD "G3_CD"
/* work-precision study */
#define WP_N 8
#define WP_TEND 2.0

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

/* G: nc x n, CSR sparse (KLU path) or dense. Row i: d Phi_i / d(p_{i-1}, p_i). */
static int G_fn(sunrealtype t, N_Vector x, SUNMatrix G, void* data) {
  const struct chain* c = (const struct chain*)data;
  const double* X = N_VGetArrayPointer(x);
  sunindextype *ptr, *idx, k = 0, nnz = 4 * c->N - 2;
  double* d;
  double xp = 0.0, yp = 0.0;
  long i;
  (void)t;
  if (SUNMatGetID(G) == SUNMATRIX_DENSE) {
    if (SUNMatZero(G) != SUNMAT_SUCCESS) return -1;
    for (i = 0; i < c->N; ++i) {
      double dx = X[2 * i] - xp, dy = X[2 * i + 1] - yp;
      if (i > 0) {
        SM_ELEMENT_D(G, i, 2 * i - 2) = -2.0 * dx;
        SM_ELEMENT_D(G, i, 2 * i - 1) = -2.0 * dy;
      }
      SM_ELEMENT_D(G, i, 2 * i) = 2.0 * dx;
      SM_ELEMENT_D(G, i, 2 * i + 1) = 2.0 * dy;
      xp = X[2 * i];
      yp = X[2 * i + 1];
    }
    return 0;
  }
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

static void initial_state(const struct chain* c, double* X, double* V) {
  long i;
  for (i = 0; i < c->N; ++i) {
    X[2 * i] = (double)(i + 1) * c->l * sin(ANGLE0);
    X[2 * i + 1] = -(double)(i + 1) * c->l * cos(ANGLE0);
    V[2 * i] = V[2 * i + 1] = 0.0;
  }
}

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
  initial_state(&c, X, V);
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


/* ======================================================= work-precision study */

/* Figures of one work-precision run. */
struct wpres {
  double err, drift, secs, cpu;
  long steps, nfe;
};

/* The chain at rest, straight at ANGLE0. */
static void wp_track(const struct chain* c, const double* X, const double* V, double e0,
                     struct wpres* r) {
  double de = fabs(energy(c->N, X, V) - e0), dr, vr;
  residuals(c, X, V, &dr, &vr);
  if (de > r->err || de != de) r->err = de;
  if (dr > r->drift || dr != dr) r->drift = dr;
}

/* ---------------------------------------------------------------- CEODE */

static int wp_ceode(SUNContext ctx, const char* method, int dense, double h, struct wpres* r) {
  struct chain c;
  N_Vector x = NULL, v = NULL, phi = NULL, b = NULL;
  SUNMatrix A = NULL;
  SUNLinearSolver LS = NULL;
  void* mem = NULL;
  double *X, *V, e0, t = 0.0;
  long N = WP_N, n = 2 * WP_N;
  int fail = 0;
  memset(r, 0, sizeof(*r));
  c.N = N;
  c.l = LTOT / (double)N;
  x = N_VNew_Serial(n, ctx);
  v = N_VNew_Serial(n, ctx);
  phi = N_VNew_Serial(N, ctx);
  b = N_VNew_Serial(n + N, ctx);
  A = dense ? SUNDenseMatrix(n + N, n + N, ctx)
            : SUNSparseMatrix(n + N, n + N, n + 2 * (4 * N - 2), CSR_MAT, ctx);
  if (check_ptr(x, "N_VNew_Serial") || check_ptr(v, "N_VNew_Serial") ||
      check_ptr(phi, "N_VNew_Serial") || check_ptr(b, "N_VNew_Serial") ||
      check_ptr(A, "SUNDenseMatrix/SUNSparseMatrix")) {
    fail = 1;
    goto done;
  }
  LS = dense ? SUNLinSol_Dense(b, A, ctx) : SUNLinSol_KLU(b, A, ctx);
  if (check_ptr(LS, "SUNLinSol_Dense/SUNLinSol_KLU")) {
    fail = 1;
    goto done;
  }
  X = N_VGetArrayPointer(x);
  V = N_VGetArrayPointer(v);
  initial_state(&c, X, V);
  e0 = energy(N, X, V);
  mem = CEodeCreate(ctx);
  if (check_ptr(mem, "CEodeCreate")) {
    fail = 1;
    goto done;
  }
  fail |= check_flag(CEodeInit(mem, rhs, 0.0, x, v), "CEodeInit");
  if (!fail) fail |= check_flag(CEodeSetUserData(mem, &c), "CEodeSetUserData");
  if (!fail) fail |= check_flag(CEodeSetMethodByName(mem, method), "CEodeSetMethodByName");
  if (!fail) fail |= check_flag(CEodeSetZeroStart(mem, SUNFALSE), "CEodeSetZeroStart");
  if (!fail) fail |= check_flag(CEodeSetFixedStep(mem, h), "CEodeSetFixedStep");
  if (!fail) fail |= check_flag(CEodeSetLinearSolver(mem, LS, A), "CEodeSetLinearSolver");
  if (!fail) fail |= check_flag(CEodeSetConstraints(mem, phi, phi_fn, G_fn), "CEodeSetConstraints");
  if (!fail) fail |= check_flag(CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0),
                                "CEodeSetStabilityGuard");
  if (!fail) fail |= check_flag(CEodeSetStopTime(mem, WP_TEND), "CEodeSetStopTime");
  if (!fail) fail |= check_flag(CEodeSetMaxNumSteps(mem, -1), "CEodeSetMaxNumSteps");
  while (!fail && t < WP_TEND - 0.5 * h) {
    int flag = CEodeEvolve(mem, WP_TEND, x, v, &t, CE_ONE_STEP);
    if (check_flag(flag, "CEodeEvolve")) {
      fail = 1;
      break;
    }
    wp_track(&c, X, V, e0, r);
  }
  if (!fail) {
    fail |= check_flag(CEodeGetNumSteps(mem, &r->steps), "CEodeGetNumSteps");
    fail |= check_flag(CEodeGetNumRhsEvals(mem, &r->nfe), "CEodeGetNumRhsEvals");
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

/* ------------------------------------------- index-1 form (ARKODE runs) */

/* The saddle-point system [[I, G^T], [G, 0]] (dense, (n+nc) x (n+nc)) and its
 * LU, owned by one ARKODE run and reached through its user data. */
struct index1 {
  struct chain c;
  int sparse; /* 1: CSR + KLU, 0: dense + SUNLinSol_Dense */
  SUNMatrix A;
  SUNLinearSolver LS;
  N_Vector rhs, sol; /* length n + nc */
};

/* Fills A = [[I, G(X)^T], [G(X), 0]] and factors it. CSR rows, columns in
 * increasing order: row 2j+k (coordinate k of p_j): j's own diagonal, then
 * constraints j and j+1 (if any); row n+i: p_{i-1} (if i > 0), then p_i. */
static int saddle_setup(struct index1* s, const double* X) {
  long N = s->c.N, n = 2 * N, i;
  double xp = 0.0, yp = 0.0;
  if (s->sparse) {
    sunindextype* ptr = SUNSparseMatrix_IndexPointers(s->A);
    sunindextype* idx = SUNSparseMatrix_IndexValues(s->A);
    double* d = SUNSparseMatrix_Data(s->A);
    sunindextype k = 0;
    long j, c;
    double gx[WP_N + 1][2]; /* gradient of Phi_i with respect to p_i */
    for (i = 0; i < N; ++i) {
      gx[i][0] = 2.0 * (X[2 * i] - xp);
      gx[i][1] = 2.0 * (X[2 * i + 1] - yp);
      xp = X[2 * i];
      yp = X[2 * i + 1];
    }
    for (j = 0; j < N; ++j) {
      for (c = 0; c < 2; ++c) {
        ptr[2 * j + c] = k;
        idx[k] = 2 * j + c, d[k++] = 1.0;
        idx[k] = n + j, d[k++] = gx[j][c];
        if (j + 1 < N) idx[k] = n + j + 1, d[k++] = -gx[j + 1][c];
      }
    }
    for (i = 0; i < N; ++i) {
      ptr[n + i] = k;
      if (i > 0) {
        idx[k] = 2 * i - 2, d[k++] = -gx[i][0];
        idx[k] = 2 * i - 1, d[k++] = -gx[i][1];
      }
      idx[k] = 2 * i, d[k++] = gx[i][0];
      idx[k] = 2 * i + 1, d[k++] = gx[i][1];
    }
    ptr[n + N] = k;
    return SUNLinSolSetup(s->LS, s->A) == SUNLS_SUCCESS ? 0 : 1;
  }
  if (SUNMatZero(s->A) != SUNMAT_SUCCESS) return -1;
  for (i = 0; i < n; ++i) SM_ELEMENT_D(s->A, i, i) = 1.0;
  for (i = 0; i < N; ++i) {
    double dx = X[2 * i] - xp, dy = X[2 * i + 1] - yp;
    if (i > 0) {
      SM_ELEMENT_D(s->A, n + i, 2 * i - 2) = SM_ELEMENT_D(s->A, 2 * i - 2, n + i) = -2.0 * dx;
      SM_ELEMENT_D(s->A, n + i, 2 * i - 1) = SM_ELEMENT_D(s->A, 2 * i - 1, n + i) = -2.0 * dy;
    }
    SM_ELEMENT_D(s->A, n + i, 2 * i) = SM_ELEMENT_D(s->A, 2 * i, n + i) = 2.0 * dx;
    SM_ELEMENT_D(s->A, n + i, 2 * i + 1) = SM_ELEMENT_D(s->A, 2 * i + 1, n + i) = 2.0 * dy;
    xp = X[2 * i];
    yp = X[2 * i + 1];
  }
  return SUNLinSolSetup(s->LS, s->A) == SUNLS_SUCCESS ? 0 : 1;
}

/* Index-1 accelerations (and multipliers): the saddle system with right-hand
 * side (f, -(dG/dt) v), ((dG/dt) v)_i = 2 |v_i - v_{i-1}|^2. */
static int index1_accel(struct index1* s, const double* X, const double* V, double* acc,
                        double* lam) {
  long N = s->c.N, n = 2 * N, i;
  double* B = N_VGetArrayPointer(s->rhs);
  const double* Z = N_VGetArrayPointer(s->sol);
  double up = 0.0, wp = 0.0;
  if (saddle_setup(s, X)) return 1;
  for (i = 0; i < N; ++i) {
    double du = V[2 * i] - up, dw = V[2 * i + 1] - wp;
    B[2 * i] = 0.0;
    B[2 * i + 1] = -GRAV;
    B[n + i] = -2.0 * (du * du + dw * dw);
    up = V[2 * i];
    wp = V[2 * i + 1];
  }
  if (SUNLinSolSolve(s->LS, s->A, s->sol, s->rhs, 0.0) != SUNLS_SUCCESS) return 1;
  for (i = 0; i < n; ++i) acc[i] = Z[i];
  if (lam) {
    for (i = 0; i < N; ++i) lam[i] = Z[n + i];
  }
  return 0;
}

/* Minimum-norm Newton projection of the positions onto Phi = 0: the saddle
 * system with right-hand side (0, Phi) gives dx = G^T (G G^T)^-1 Phi; x -= dx,
 * repeated (G re-evaluated) until the correction is at round-off. */
static int project_positions(struct index1* s, double* X) {
  long N = s->c.N, n = 2 * N, i;
  double* B = N_VGetArrayPointer(s->rhs);
  const double* Z = N_VGetArrayPointer(s->sol);
  int it;
  for (it = 0; it < 10; ++it) {
    double xp = 0.0, yp = 0.0, dn = 0.0, pn = 0.0;
    for (i = 0; i < N; ++i) {
      double dx = X[2 * i] - xp, dy = X[2 * i + 1] - yp;
      B[2 * i] = B[2 * i + 1] = 0.0;
      B[n + i] = dx * dx + dy * dy - s->c.l * s->c.l;
      if (fabs(B[n + i]) > pn) pn = fabs(B[n + i]);
      xp = X[2 * i];
      yp = X[2 * i + 1];
    }
    if (pn <= 1e-16 * s->c.l * s->c.l) return 0; /* at round-off already */
    if (saddle_setup(s, X)) return 1;
    if (SUNLinSolSolve(s->LS, s->A, s->sol, s->rhs, 0.0) != SUNLS_SUCCESS) return 1;
    for (i = 0; i < n; ++i) {
      X[i] -= Z[i];
      if (fabs(Z[i]) > dn) dn = fabs(Z[i]);
    }
    if (dn <= 1e-15 * LTOT) return 0;
  }
  return 0; /* stagnated at round-off: as good as it gets */
}

/* y = (x, v): y' = (v, a(x, v)) */
static int ark_rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* data) {
  struct index1* s = (struct index1*)data;
  const double* Y = N_VGetArrayPointer(y);
  double* F = N_VGetArrayPointer(ydot);
  long n = 2 * s->c.N, i;
  (void)t;
  for (i = 0; i < n; ++i) F[i] = Y[n + i];
  return index1_accel(s, Y, Y + n, F + n, NULL) ? 1 : 0;
}

static int index1_create(SUNContext ctx, struct index1* s, int sparse) {
  long N = WP_N, n = 2 * WP_N;
  memset(s, 0, sizeof(*s));
  s->c.N = N;
  s->c.l = LTOT / (double)N;
  s->sparse = sparse;
  s->rhs = N_VNew_Serial(n + N, ctx);
  s->sol = N_VNew_Serial(n + N, ctx);
  s->A = sparse ? SUNSparseMatrix(n + N, n + N, n + 2 * (4 * N - 2), CSR_MAT, ctx)
                : SUNDenseMatrix(n + N, n + N, ctx);
  if (check_ptr(s->rhs, "N_VNew_Serial") || check_ptr(s->sol, "N_VNew_Serial") ||
      check_ptr(s->A, "SUNSparseMatrix/SUNDenseMatrix"))
    return 1;
  s->LS = sparse ? SUNLinSol_KLU(s->rhs, s->A, ctx) : SUNLinSol_Dense(s->rhs, s->A, ctx);
  if (check_ptr(s->LS, "SUNLinSol_KLU/SUNLinSol_Dense")) return 1;
  return check_flag(SUNLinSolInitialize(s->LS), "SUNLinSolInitialize");
}

static void index1_free(struct index1* s) {
  if (s->LS) SUNLinSolFree(s->LS);
  if (s->A) SUNMatDestroy(s->A);
  if (s->rhs) N_VDestroy(s->rhs);
  if (s->sol) N_VDestroy(s->sol);
}

/* ARKODE ERKStep on the index-1 form. rk3: Kutta's RK3 at fixed step h (with a
 * reset after every step, see the header), else the default adaptive ERK at
 * rtol = atol = h. project: coordinate projection after every step. */
static int wp_arkode(SUNContext ctx, int rk3, int project, int sparse, double h,
                     struct wpres* r) {
  static const double c3[3] = {0.0, 0.5, 1.0};
  static const double A3[9] = {0.0, 0.0, 0.0, 0.5, 0.0, 0.0, -1.0, 2.0, 0.0};
  static const double b3[3] = {1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0};
  double cc[3], AA[9], bb[3];
  struct index1 s;
  N_Vector y = NULL;
  void* mem = NULL;
  ARKodeButcherTable B = NULL;
  double t = 0.0, e0, *Y;
  long n = 2 * WP_N;
  int fail = 0, i;
  memset(r, 0, sizeof(*r));
  for (i = 0; i < 3; ++i) cc[i] = c3[i], bb[i] = b3[i];
  for (i = 0; i < 9; ++i) AA[i] = A3[i];
  if (index1_create(ctx, &s, sparse)) {
    fail = 1;
    goto done;
  }
  y = N_VNew_Serial(2 * n, ctx);
  if (check_ptr(y, "N_VNew_Serial")) {
    fail = 1;
    goto done;
  }
  Y = N_VGetArrayPointer(y);
  initial_state(&s.c, Y, Y + n);
  e0 = energy(WP_N, Y, Y + n);
  mem = ERKStepCreate(ark_rhs, 0.0, y, ctx);
  if (check_ptr(mem, "ERKStepCreate")) {
    fail = 1;
    goto done;
  }
  fail |= check_flag(ERKStepSetUserData(mem, &s), "ERKStepSetUserData");
  if (rk3) {
    B = ARKodeButcherTable_Create(3, 3, 0, cc, AA, bb, NULL);
    fail |= check_ptr(B, "ARKodeButcherTable_Create");
    if (!fail) fail |= check_flag(ERKStepSetTable(mem, B), "ERKStepSetTable");
    if (!fail) fail |= check_flag(ERKStepSetFixedStep(mem, h), "ERKStepSetFixedStep");
  } else {
    if (!fail) fail |= check_flag(ERKStepSStolerances(mem, h, h), "ERKStepSStolerances");
  }
  if (!fail) fail |= check_flag(ERKStepSetStopTime(mem, WP_TEND), "ERKStepSetStopTime");
  if (!fail) fail |= check_flag(ERKStepSetMaxNumSteps(mem, -1), "ERKStepSetMaxNumSteps");
  while (!fail && (rk3 ? t < WP_TEND - 0.5 * h : t < WP_TEND)) {
    int flag = ERKStepEvolve(mem, WP_TEND, y, &t, ARK_ONE_STEP);
    if (check_flag(flag, "ERKStepEvolve")) {
      fail = 1;
      break;
    }
    if (project && project_positions(&s, Y)) {
      fprintf(stderr, "ERROR: projection failed at t = %g\n", t);
      fail = 1;
      break;
    }
    /* SUNDIALS < 6.6.2 would reuse f(last stage) of Kutta's table (c3 = 1) as
     * the next first stage; the reset forces a fresh f(t_n+1, y_n+1). A
     * projected state must be handed back to ARKODE the same way. */
    if ((rk3 || project) && check_flag(ERKStepReset(mem, t, y), "ERKStepReset")) {
      fail = 1;
      break;
    }
    wp_track(&s.c, Y, Y + n, e0, r);
    if (flag == ARK_TSTOP_RETURN) break;
  }
  if (!fail) {
    fail |= check_flag(ERKStepGetNumSteps(mem, &r->steps), "ERKStepGetNumSteps");
    fail |= check_flag(ERKStepGetNumRhsEvals(mem, &r->nfe), "ERKStepGetNumRhsEvals");
  }
done:
  if (mem) ERKStepFree(&mem);
  if (B) ARKodeButcherTable_Free(B);
  if (y) N_VDestroy(y);
  index1_free(&s);
  return fail;
}

/* ---------------------------------------------------------------- IDA, GGL */

/* y = (q[n], v[n], lambda[nc], mu[nc]); residual rows in the same order. */
static int ida_res(sunrealtype t, N_Vector yy, N_Vector yp, N_Vector rr, void* data) {
  const struct chain* c = (const struct chain*)data;
  const double* Y = N_VGetArrayPointer(yy);
  const double* P = N_VGetArrayPointer(yp);
  double* R = N_VGetArrayPointer(rr);
  long N = c->N, n = 2 * N, i;
  const double *Q = Y, *V = Y + n, *L = Y + 2 * n, *U = Y + 2 * n + N;
  double xp = 0.0, yq = 0.0, up = 0.0, wp = 0.0;
  (void)t;
  for (i = 0; i < n; ++i) {
    R[i] = P[i] - V[i];                          /* q' - v (- G^T mu below) */
    R[n + i] = P[n + i] - ((i & 1) ? -GRAV : 0); /* v' - f (+ G^T lambda below) */
  }
  for (i = 0; i < N; ++i) {
    double dx = Q[2 * i] - xp, dy = Q[2 * i + 1] - yq;
    double du = V[2 * i] - up, dw = V[2 * i + 1] - wp;
    R[2 * i] -= 2.0 * dx * U[i];
    R[2 * i + 1] -= 2.0 * dy * U[i];
    R[n + 2 * i] += 2.0 * dx * L[i];
    R[n + 2 * i + 1] += 2.0 * dy * L[i];
    if (i > 0) {
      R[2 * i - 2] += 2.0 * dx * U[i];
      R[2 * i - 1] += 2.0 * dy * U[i];
      R[n + 2 * i - 2] -= 2.0 * dx * L[i];
      R[n + 2 * i - 1] -= 2.0 * dy * L[i];
    }
    R[2 * n + i] = dx * dx + dy * dy - c->l * c->l;   /* Phi(q) */
    R[2 * n + N + i] = 2.0 * (dx * du + dy * dw);     /* G(q) v */
    xp = Q[2 * i];
    yq = Q[2 * i + 1];
    up = V[2 * i];
    wp = V[2 * i + 1];
  }
  return 0;
}

/* Analytic iteration matrix J = dF/dy + cj dF/dy' of the GGL residual.
 * With H_i = Hessian of Phi_i (2 on the diagonal blocks of p_{i-1} and p_i,
 * -2 on the blocks between them): dRq/dq = cj I - sum mu_i H_i, dRq/dv = -I,
 * dRq/dmu = -G^T; dRv/dq = sum lambda_i H_i, dRv/dv = cj I, dRv/dlambda = G^T;
 * dPhi/dq = G; d(G v)/dq = G evaluated on the velocity differences, d(G v)/dv = G. */
static int ida_jac(sunrealtype t, sunrealtype cj, N_Vector yy, N_Vector yp, N_Vector rr,
                   SUNMatrix J, void* data, N_Vector t1, N_Vector t2, N_Vector t3) {
  const struct chain* c = (const struct chain*)data;
  const double* Y = N_VGetArrayPointer(yy);
  long N = c->N, n = 2 * N, i, k;
  const double *Q = Y, *V = Y + n, *L = Y + 2 * n, *U = Y + 2 * n + N;
  double xp = 0.0, yq = 0.0, up = 0.0, wp = 0.0;
  (void)t;
  (void)yp;
  (void)rr;
  (void)t1;
  (void)t2;
  (void)t3;
  if (SUNMatZero(J) != SUNMAT_SUCCESS) return -1;
  for (i = 0; i < n; ++i) {
    SM_ELEMENT_D(J, i, i) = cj;
    SM_ELEMENT_D(J, i, n + i) = -1.0;
    SM_ELEMENT_D(J, n + i, n + i) = cj;
  }
  for (i = 0; i < N; ++i) {
    double g[2], gv[2];
    long rl = 2 * n + i, rg = 2 * n + N + i, cl = 2 * n + i, cu = 2 * n + N + i;
    g[0] = 2.0 * (Q[2 * i] - xp);
    g[1] = 2.0 * (Q[2 * i + 1] - yq);
    gv[0] = 2.0 * (V[2 * i] - up);
    gv[1] = 2.0 * (V[2 * i + 1] - wp);
    for (k = 0; k < 2; ++k) {
      long a = 2 * i + k; /* coordinate k of p_i */
      /* Hessian terms: diagonal of p_i, and of p_{i-1} and the coupling if i > 0 */
      SM_ELEMENT_D(J, a, a) -= 2.0 * U[i];
      SM_ELEMENT_D(J, n + a, a) += 2.0 * L[i];
      SM_ELEMENT_D(J, a, cu) = -g[k];
      SM_ELEMENT_D(J, n + a, cl) = g[k];
      SM_ELEMENT_D(J, rl, a) = g[k];
      SM_ELEMENT_D(J, rg, a) = gv[k];
      SM_ELEMENT_D(J, rg, n + a) = g[k];
      if (i > 0) {
        long p = 2 * (i - 1) + k; /* coordinate k of p_{i-1} */
        SM_ELEMENT_D(J, p, p) -= 2.0 * U[i];
        SM_ELEMENT_D(J, a, p) += 2.0 * U[i];
        SM_ELEMENT_D(J, p, a) += 2.0 * U[i];
        SM_ELEMENT_D(J, n + p, p) += 2.0 * L[i];
        SM_ELEMENT_D(J, n + a, p) -= 2.0 * L[i];
        SM_ELEMENT_D(J, n + p, a) -= 2.0 * L[i];
        SM_ELEMENT_D(J, p, cu) = g[k];
        SM_ELEMENT_D(J, n + p, cl) = -g[k];
        SM_ELEMENT_D(J, rl, p) = -g[k];
        SM_ELEMENT_D(J, rg, p) = -gv[k];
        SM_ELEMENT_D(J, rg, n + p) = -g[k];
      }
    }
    xp = Q[2 * i];
    yq = Q[2 * i + 1];
    up = V[2 * i];
    wp = V[2 * i + 1];
  }
  return 0;
}

static int wp_ida(SUNContext ctx, double tol, struct wpres* r) {
  struct index1 s;
  N_Vector yy = NULL, yp = NULL, id = NULL;
  SUNMatrix J = NULL;
  SUNLinearSolver LS = NULL;
  void* mem = NULL;
  double t = 0.0, e0, *Y, *P, *I;
  long N = WP_N, n = 2 * WP_N, neq = 4 * WP_N + 2 * WP_N, i;
  long nre = 0, nreLS = 0;
  int fail = 0;
  memset(r, 0, sizeof(*r));
  memset(&s, 0, sizeof(s));
  yy = N_VNew_Serial(neq, ctx);
  yp = N_VNew_Serial(neq, ctx);
  id = N_VNew_Serial(neq, ctx);
  if (check_ptr(yy, "N_VNew_Serial") || check_ptr(yp, "N_VNew_Serial") ||
      check_ptr(id, "N_VNew_Serial") || index1_create(ctx, &s, 1)) {
    fail = 1;
    goto done;
  }
  Y = N_VGetArrayPointer(yy);
  P = N_VGetArrayPointer(yp);
  I = N_VGetArrayPointer(id);
  for (i = 0; i < neq; ++i) Y[i] = P[i] = 0.0;
  initial_state(&s.c, Y, Y + n);
  /* consistent start: q' = v = 0, v' and lambda from the index-1 saddle system, mu = 0 */
  if (index1_accel(&s, Y, Y + n, P + n, Y + 2 * n)) {
    fprintf(stderr, "ERROR: initial saddle solve failed\n");
    fail = 1;
    goto done;
  }
  for (i = 0; i < neq; ++i) I[i] = i < 2 * n ? 1.0 : 0.0;
  e0 = energy(N, Y, Y + n);
  mem = IDACreate(ctx);
  if (check_ptr(mem, "IDACreate")) {
    fail = 1;
    goto done;
  }
  fail |= check_flag(IDAInit(mem, ida_res, 0.0, yy, yp), "IDAInit");
  if (!fail) fail |= check_flag(IDASetUserData(mem, &s.c), "IDASetUserData");
  if (!fail) fail |= check_flag(IDASStolerances(mem, tol, tol), "IDASStolerances");
  if (!fail) fail |= check_flag(IDASetId(mem, id), "IDASetId");
  if (!fail) fail |= check_flag(IDASetSuppressAlg(mem, SUNTRUE), "IDASetSuppressAlg");
  if (!fail) fail |= check_flag(IDASetStopTime(mem, WP_TEND), "IDASetStopTime");
  if (!fail) fail |= check_flag(IDASetMaxNumSteps(mem, 10000000L), "IDASetMaxNumSteps");
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
  while (!fail && t < WP_TEND) {
    int flag = IDASolve(mem, WP_TEND, &t, yy, yp, IDA_ONE_STEP);
    if (check_flag(flag, "IDASolve")) {
      fail = 1;
      break;
    }
    wp_track(&s.c, Y, Y + n, e0, r);
    if (flag == IDA_TSTOP_RETURN) break;
  }
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
  index1_free(&s);
  return fail;
}

/* ---------------------------------------------------------------- WP driver */

enum wpkind { W_CEODE, W_CEODE_DENSE, W_RK3, W_RK3_DENSE, W_RK3P, W_ERK, W_IDA };

struct wpconfig {
  enum wpkind kind;
  const char* solver; /* CSV solver column */
  const char* name;   /* CSV config column */
  const char* method; /* CEODE method name */
};

static int wp_run(SUNContext ctx, const struct wpconfig* c, double h, struct wpres* r) {
  int fail = 1;
  double t0 = now(), c0 = cpu_now();
  switch (c->kind) {
    case W_CEODE: fail = wp_ceode(ctx, c->method, 0, h, r); break;
    case W_CEODE_DENSE: fail = wp_ceode(ctx, c->method, 1, h, r); break;
    case W_RK3: fail = wp_arkode(ctx, 1, 0, 1, h, r); break;
    case W_RK3_DENSE: fail = wp_arkode(ctx, 1, 0, 0, h, r); break;
    case W_RK3P: fail = wp_arkode(ctx, 1, 1, 1, h, r); break;
    case W_ERK: fail = wp_arkode(ctx, 0, 0, 1, h, r); break;
    case W_IDA: fail = wp_ida(ctx, h, r); break;
  }
  r->secs = now() - t0;
  r->cpu = cpu_now() - c0;
  return fail;
}

/* One run for the figures; then batches of runs lasting >= 50 ms, median of 5
 * batches (CPU and wall separately), unless one run takes more than 1 s. */
static int wp_measure(SUNContext ctx, const struct wpconfig* c, double h, struct wpres* r) {
  struct wpres tmp;
  double times[5], cpus[5];
  long reps, k;
  int b;
  if (wp_run(ctx, c, h, r)) return 1;
  if (r->secs > 1.0) return 0;
  reps = r->secs > 0.05 ? 1 : (long)ceil(0.05 / (r->secs > 1e-7 ? r->secs : 1e-7));
  for (b = 0; b < 5; ++b) {
    double t0 = now(), c0 = cpu_now();
    for (k = 0; k < reps; ++k) {
      if (wp_run(ctx, c, h, &tmp)) return 1;
    }
    times[b] = (now() - t0) / (double)reps;
    cpus[b] = (cpu_now() - c0) / (double)reps;
  }
  qsort(times, 5, sizeof(double), cmp_double);
  qsort(cpus, 5, sizeof(double), cmp_double);
  r->secs = times[2];
  r->cpu = cpus[2];
  return 0;
}

/* Cheapest time at which a curve (points in run order) reaches error <= e:
 * measured points at or below e, and log t interpolated linearly in log error
 * on every segment that crosses e (as scripts/wp_curves.py). < 0: never. */
static double time_to_reach(int n, const double* err, const double* secs, double e) {
  double best = -1.0;
  int i;
  for (i = 0; i < n; ++i) {
    if (err[i] > 0 && err[i] <= e && (best < 0 || secs[i] < best)) best = secs[i];
  }
  for (i = 0; i + 1 < n; ++i) {
    double e1 = err[i], e2 = err[i + 1], w, s;
    if (!(e1 > 0 && e2 > 0) || (e1 - e) * (e2 - e) >= 0 || e1 == e2) continue;
    w = (log(e) - log(e1)) / (log(e2) - log(e1));
    s = exp(log(secs[i]) + w * (log(secs[i + 1]) - log(secs[i])));
    if (best < 0 || s < best) best = s;
  }
  return best;
}

#define WP_MAXPTS 12

/* Runs the work-precision study; returns the number of failed runs plus
 * failed checks. */
static int work_precision(SUNContext ctx, FILE* csv, int full) {
  static const struct wpconfig configs[] = {
      {W_CEODE, "CEODE", "G5_ONES KLU", "G5_ONES"},
      {W_CEODE_DENSE, "CEODE", "G5_ONES dense", "G5_ONES"},
      {W_CEODE, "CEODE", "G4_A34 KLU", "G4_A34"},
      {W_CEODE, "CEODE", "G3_CD KLU", "G3_CD"},
      {W_RK3, "ARKODE", "RK3 index-1 KLU", NULL},
      {W_RK3_DENSE, "ARKODE", "RK3 index-1 dense", NULL},
      {W_RK3P, "ARKODE", "RK3+proj index-1 KLU", NULL},
      {W_ERK, "ARKODE", "ERK adaptive index-1 KLU", NULL},
      {W_IDA, "IDA", "BDF-GGL", NULL},
  };
  static const double hs[] = {6e-3, 4e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5};
  static const double tols[] = {1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13};
  enum { NCONF = sizeof(configs) / sizeof(configs[0]) };
  double errs[NCONF][WP_MAXPTS], cpus[NCONF][WP_MAXPTS];
  int npts[NCONF], k, nbad = 0;
  double l2 = (LTOT / WP_N) * (LTOT / WP_N);
  printf("\nWork-precision: N = %d (n = %d, nc = %d), t in [0, %g] s, from rest at 60 deg\n", WP_N,
         2 * WP_N, WP_N, WP_TEND);
  printf("error = max |E - E0|, drift = max |Phi_i| (l^2 = %.4g); time = CPU s per run, median of 5\n\n",
         l2);
  printf("%-7s %-25s %8s %11s %11s %9s %9s %11s %11s\n", "solver", "config", "h/tol", "error",
         "drift", "steps", "f evals", "cpu s", "wall s");
  for (k = 0; k < NCONF; ++k) {
    const struct wpconfig* c = &configs[k];
    int adaptive = c->kind == W_IDA || c->kind == W_ERK;
    /* points: fixed steps 6e-3 ... 2e-5 (1e-5 with --full); tolerances
     * 1e-4 ... 1e-12 for the adaptive ERK (1e-13 with --full) and 1e-4 ...
     * 1e-10 for IDA (at 1e-11 its first steps fail: corrector convergence
     * failures down to h ~ 1e-11 at t ~ 4e-6) */
    int np = c->kind == W_ERK ? (full ? 10 : 9) : c->kind == W_IDA ? 7 : (full ? 10 : 9);
    int j;
    npts[k] = 0;
    for (j = 0; j < np; ++j) {
      double h = adaptive ? tols[j] : hs[j];
      struct wpres r;
      if (wp_measure(ctx, c, h, &r)) {
        fprintf(stderr, "run %s %s %g failed\n", c->solver, c->name, h);
        printf("%-7s %-25s %8.0e  run failed\n", c->solver, c->name, h);
        ++nbad;
        continue;
      }
      errs[k][npts[k]] = r.err;
      cpus[k][npts[k]] = r.cpu;
      ++npts[k];
      printf("%-7s %-25s %8.0e %11.3e %11.3e %9ld %9ld %11.3e %11.3e", c->solver, c->name, h, r.err,
             r.drift, r.steps, r.nfe, r.cpu, r.secs);
      if ((c->kind == W_CEODE || c->kind == W_CEODE_DENSE || c->kind == W_RK3P) &&
          !(r.drift <= 1e-10 * l2)) {
        ++nbad;
        printf("  <-- drift above 1e-10 l^2");
      }
      if ((c->kind == W_RK3 || c->kind == W_RK3_DENSE || c->kind == W_RK3P) &&
          r.nfe != 3 * r.steps) {
        ++nbad;
        printf("  <-- not 3 f evaluations per step");
      }
      printf("\n");
      if (csv) {
        fprintf(csv, "chain_dae_wp,%s,%s,%.3g,%.6e,%.6e,%ld,%ld,%.6e\n", c->solver, c->name, h,
                r.err, r.drift, r.steps, r.nfe, r.cpu);
      }
    }
  }

  /* best CEODE and best SUNDIALS curve at equal error */
  {
    static const double levels[] = {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11};
    size_t l;
    printf("\nCPU time at equal energy error (log t interpolated in log error), best curve per side:\n");
    printf("%9s %-24s %11s %-24s %11s %9s\n", "error", "best CEODE", "cpu s", "best SUNDIALS",
           "cpu s", "ratio");
    for (l = 0; l < sizeof(levels) / sizeof(levels[0]); ++l) {
      double tc = -1, ts = -1;
      int kc = -1, ks = -1;
      for (k = 0; k < NCONF; ++k) {
        double tk = time_to_reach(npts[k], errs[k], cpus[k], levels[l]);
        int ce = configs[k].kind == W_CEODE || configs[k].kind == W_CEODE_DENSE;
        if (tk <= 0) continue;
        if (ce && (tc < 0 || tk < tc)) tc = tk, kc = k;
        if (!ce && (ts < 0 || tk < ts)) ts = tk, ks = k;
      }
      if (kc < 0 && ks < 0) continue;
      printf("%9.0e %-24s ", levels[l], kc >= 0 ? configs[kc].name : "not reached");
      if (kc >= 0) {
        printf("%11.3e ", tc);
      } else {
        printf("%11s ", "-");
      }
      printf("%-24s ", ks >= 0 ? configs[ks].name : "not reached");
      if (ks >= 0) {
        printf("%11.3e ", ts);
      } else {
        printf("%11s ", "-");
      }
      if (kc >= 0 && ks >= 0) {
        printf("%9.3f\n", tc / ts);
      } else {
        printf("%9s\n", "-");
      }
    }
    printf("ratio = CEODE / SUNDIALS (< 1: CEODE faster)\n");
  }
  return nbad;
}

static FILE* open_csv(const char* path) {
  FILE* f = fopen(path, "w");
  if (f == NULL) {
    fprintf(stderr, "cannot open %s\n", path);
    return NULL;
  }
  fprintf(f, "scene,solver,config,h_or_tol,error,drift,steps,rhs_evals,seconds\n");
  return f;
}

int main(int argc, char** argv) {
  static const long sizes[] = {10, 30, 100, 300, 1000, 3000};
  double lx[6], ly[6], lw[6];
  SUNContext ctx;
  FILE *csv = NULL, *wpcsv = NULL;
  int full = 0, scaling = 1, wp = 1, i, npts = 0, nfail = 0, nbad = 0, nsizes, wpbad = 0;
  double slope = 0.0;
  for (i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--csv") == 0 && i + 1 < argc) {
      if ((csv = open_csv(argv[++i])) == NULL) return 1;
    } else if (strcmp(argv[i], "--wp-csv") == 0 && i + 1 < argc) {
      if ((wpcsv = open_csv(argv[++i])) == NULL) return 1;
    } else if (strcmp(argv[i], "--full") == 0) {
      full = 1;
    } else if (strcmp(argv[i], "--no-scaling") == 0) {
      scaling = 0;
    } else if (strcmp(argv[i], "--no-wp") == 0) {
      wp = 0;
    } else {
      fprintf(stderr, "usage: %s [--csv FILE] [--wp-csv FILE] [--full] [--no-scaling] [--no-wp]\n",
              argv[0]);
      return 1;
    }
  }
  nsizes = scaling ? (full ? 6 : 5) : 0;
  if (SUNContext_Create(SUN_COMM_NULL, &ctx)) return 1;
  if (scaling) {
    printf("Planar chain of N unit point masses, links L/N, index-3 DAE, CEODE %s + KLU\n", METHOD);
    printf("%d steps of h = %g s from rest at 60 deg; error = max |E - E0|, drift = max |Phi_i|\n\n",
           NSTEPS, HSTEP);
    printf("%6s %6s %11s %11s %11s %8s %8s %8s %11s %12s %12s\n", "N", "n+nc", "error", "drift",
           "vres", "steps", "f evals", "NLS its", "wall s", "wall/step", "cpu/step");
  }
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
  if (scaling && npts >= 2) {
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
  } else if (scaling) {
    ++nbad;
  }
  if (scaling) printf("scaling: %d runs failed, %d checks off\n", nfail, nbad);
  if (wp) {
    wpbad = work_precision(ctx, wpcsv, full);
    printf("work-precision: %d runs failed or checks off\n", wpbad);
  }
  if (csv) fclose(csv);
  if (wpcsv) fclose(wpcsv);
  SUNContext_Free(&ctx);
  return (nfail == 0 && nbad == 0 && wpbad == 0) ? 0 : 1;
}
