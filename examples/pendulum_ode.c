/* -----------------------------------------------------------------------------
 * pendulum_ode: the IFToMM "simple pendulum" benchmark with every named CEODE
 * parameter set (docs/theory.md sections 5 and 11).
 *
 * Problem: a point mass m = 1 kg on a massless rod L = 1 m, gravity g = 9.81,
 * angle theta from the horizontal,
 *     theta'' = -(g/L) cos(theta),  theta(0) = 0, theta'(0) = 0,  t in [0, 10] s.
 * The exact solution conserves E = 1/2 m L^2 theta'^2 + m g L sin(theta), so the
 * error of a run is max over its steps of |E(t) - E(0)|, with theta and theta'
 * taken at the same instant (every step of CE_ONE_STEP).
 *
 * Method: CEODE's conditionally explicit family, degrees 3, 4 and 5, fixed step
 * h = 1e-2 ... 1e-4 (--hmin to go further), explicit path (f does not depend on theta').
 *
 * Reference: the paper's Tables 1-2, 4 and 6 (Fernandez de Bustos et al.,
 * Mathematics 2024, 12, 2862; docs/theory.md section 11). The program exits 0
 * only if every figure above 1e-10 at h = 1e-3 and 1e-4 matches within 5 %.
 * (The timed comparison with ARKODE and CVODE is bench/wp_pendulum_ode.cpp.)
 *
 * Usage: pendulum_ode [--hmin H] [--compensated] [--only METHOD]
 * ---------------------------------------------------------------------------*/
#include <ceode/ceode.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ceode_sundials_compat.h" /* SUN_COMM_NULL on SUNDIALS 6.4 */

#define GRAV 9.81
#define LEN 1.0
#define MASS 1.0

static int rhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
  (void)t;
  (void)v;
  (void)data;
  NV_Ith_S(f, 0) = -(GRAV / LEN) * cos(NV_Ith_S(x, 0));
  return 0;
}

static double energy(double th, double om) {
  return 0.5 * MASS * LEN * LEN * om * om + MASS * GRAV * LEN * sin(th);
}

static int check_flag(int flag, const char* call) {
  if (flag < 0) {
    fprintf(stderr, "ERROR: %s returned %d\n", call, flag);
    return 1;
  }
  return 0;
}

/* Paper's reference errors at h = 1e-3 and 1e-4 (Tables 1, 2, 4, 6); 0 = none. */
struct reference {
  const char* method;
  double e3, e4;
};
static const struct reference refs[] = {
    {"G3_CD", 2.00492e-5, 2.00492e-7},  {"G3_A43", 1.27955e-5, 1.21061e-7},
    {"G3_A2", 3.85689e-6, 3.99453e-8},  {"G4_A54", 5.54063e-11, 5.66297e-13},
    {"G4_A14", 8.67265e-7, 8.6753e-10}, {"G4_A34", 4.3364e-7, 4.33685e-10},
    {"G5", 6.71e-11, 1.97e-11},
};

/* Runs one configuration; returns 0 on success and fills error and steps. */
static int run(SUNContext ctx, const char* method, double h, int compensated, double* err,
               long* steps) {
  N_Vector x = N_VNew_Serial(1, ctx), v = N_VNew_Serial(1, ctx);
  void* mem = NULL;
  int fail = 0;
  double t = 0.0, e0, emax = 0.0;
  NV_Ith_S(x, 0) = 0.0;
  NV_Ith_S(v, 0) = 0.0;
  e0 = energy(0.0, 0.0);
  mem = CEodeCreate(ctx);
  if (mem == NULL) return 1;
  fail |= check_flag(CEodeInit(mem, rhs, 0.0, x, v), "CEodeInit");
  fail |= check_flag(CEodeSetMethodByName(mem, method), "CEodeSetMethodByName");
  fail |= check_flag(CEodeSetFixedStep(mem, h), "CEodeSetFixedStep");
  fail |= check_flag(CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0), "CEodeSetStabilityGuard");
  fail |= check_flag(CEodeSetStopTime(mem, 10.0), "CEodeSetStopTime");
  fail |= check_flag(CEodeSetCompensatedSummation(mem, compensated), "CEodeSetCompensated");
  while (!fail && t < 10.0 - 0.5 * h) {
    int flag = CEodeEvolve(mem, 10.0, x, v, &t, CE_ONE_STEP);
    double de;
    if (check_flag(flag, "CEodeEvolve")) fail = 1;
    de = fabs(energy(NV_Ith_S(x, 0), NV_Ith_S(v, 0)) - e0);
    if (de > emax) emax = de;
  }
  *err = emax;
  fail |= check_flag(CEodeGetNumSteps(mem, steps), "CEodeGetNumSteps");
  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  return fail;
}

int main(int argc, char** argv) {
  SUNContext ctx;
  double hmin = 1e-4; /* the reference figures are at 1e-3 and 1e-4 */
  const char* only = NULL;
  int i, k, nbad = 0, nchecked = 0, compensated = 0;
  for (i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--hmin") == 0 && i + 1 < argc) {
      hmin = atof(argv[++i]);
    } else if (strcmp(argv[i], "--compensated") == 0) {
      compensated = 1;
    } else if (strcmp(argv[i], "--only") == 0 && i + 1 < argc) {
      only = argv[++i];
    }
  }
  if (SUNContext_Create(SUN_COMM_NULL, &ctx)) return 1;
  printf("IFToMM simple pendulum, 10 s: max |E - E0| for every CEODE set\n");
  printf("%-8s %8s %13s %13s %7s %10s\n", "method", "h", "error", "paper", "ratio", "steps");
  for (k = 0; k < CEodeGetNumMethods(); ++k) {
    const char* method = CEodeGetMethodName(k);
    double h;
    if (strcmp(method, "G5_TOP") == 0 || strcmp(method, "G5_ONES") == 0) continue;
    if (only != NULL && strcmp(method, only) != 0) continue;
    for (h = 1e-2; h >= hmin * 0.999; h /= 10) {
      double err = 0, ref = 0;
      long steps = 0;
      size_t r;
      if (run(ctx, method, h, compensated, &err, &steps)) {
        fprintf(stderr, "run %s h=%g failed\n", method, h);
        ++nbad;
        continue;
      }
      for (r = 0; r < sizeof(refs) / sizeof(refs[0]); ++r) {
        if (strcmp(refs[r].method, method) != 0) continue;
        if (fabs(h - 1e-3) < 1e-12) ref = refs[r].e3;
        if (fabs(h - 1e-4) < 1e-13) ref = refs[r].e4;
      }
      printf("%-8s %8.0e %13.6e ", method, h, err);
      if (ref > 0) {
        printf("%13.6e %7.4f", ref, err / ref);
      } else {
        printf("%13s %7s", "-", "-");
      }
      printf(" %10ld", steps);
      if (ref > 1e-10) {
        ++nchecked;
        if (fabs(err / ref - 1) > 0.05) {
          ++nbad;
          printf("  <-- off by more than 5 %%");
        }
      }
      printf("\n");
    }
  }
  printf("%d reference figures checked, %d off\n", nchecked, nbad);
  SUNContext_Free(&ctx);
  return nbad == 0 && nchecked > 0 ? 0 : 1;
}
