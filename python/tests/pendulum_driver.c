/* The pendulum of examples/pendulum_ode.c driven as its run() drives it (fixed step, guard off,
 * stop time, CE_ONE_STEP), printing t, theta, theta' of every step with %.17g: the reference
 * the Python module must reproduce bit for bit.
 * Usage: pendulum_driver METHOD H TEND */
#include <ceode/ceode.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <stdlib.h>

#include "ceode_sundials_compat.h"

#define GRAV 9.81
#define LEN 1.0

static int rhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
  (void)t, (void)v, (void)data;
  NV_Ith_S(f, 0) = -(GRAV / LEN) * cos(NV_Ith_S(x, 0));
  return 0;
}

int main(int argc, char** argv) {
  SUNContext ctx;
  N_Vector x, v;
  void* mem;
  double h, tend, t = 0.0;
  int fail;
  if (argc != 4) return 2;
  h = atof(argv[2]);
  tend = atof(argv[3]);
  if (SUNContext_Create(SUN_COMM_NULL, &ctx)) return 1;
  x = N_VNew_Serial(1, ctx);
  v = N_VNew_Serial(1, ctx);
  NV_Ith_S(x, 0) = 0.0;
  NV_Ith_S(v, 0) = 0.0;
  mem = CEodeCreate(ctx);
  fail = CEodeInit(mem, rhs, 0.0, x, v) < 0 || CEodeSetMethodByName(mem, argv[1]) < 0 ||
         CEodeSetFixedStep(mem, h) < 0 || CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0) < 0 ||
         CEodeSetStopTime(mem, tend) < 0;
  while (!fail && t < tend - 0.5 * h) {
    fail = CEodeEvolve(mem, tend, x, v, &t, CE_ONE_STEP) < 0;
    if (!fail) printf("%.17g %.17g %.17g\n", t, NV_Ith_S(x, 0), NV_Ith_S(v, 0));
  }
  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  SUNContext_Free(&ctx);
  return fail;
}
