/* Quick start: x'' = -x, x(0) = 1, x'(0) = 0 to t = 10 with G5_O4 (order 4) at h = 0.01. */
#include <ceode/ceode.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>

static int accel(sunrealtype t, N_Vector x, N_Vector v, N_Vector a, void* data) {
  (void)t, (void)v, (void)data;
  NV_Ith_S(a, 0) = -NV_Ith_S(x, 0); /* the acceleration x'' = f(t, x, x') */
  return 0;
}

int main(void) {
  SUNContext ctx;
#if SUNDIALS_VERSION_MAJOR >= 7
  SUNContext_Create(SUN_COMM_NULL, &ctx);
#else
  SUNContext_Create(NULL, &ctx);
#endif
  N_Vector x = N_VNew_Serial(1, ctx), v = N_VNew_Serial(1, ctx);
  NV_Ith_S(x, 0) = 1.0;
  NV_Ith_S(v, 0) = 0.0;
  void* mem = CEodeCreate(ctx);
  CEodeInit(mem, accel, 0.0, x, v);
  CEodeSetMethodByName(mem, "G5_O4");
  CEodeSetFixedStep(mem, 0.01);
  sunrealtype t = 0.0;
  int flag = CEodeEvolve(mem, 10.0, x, v, &t, CE_NORMAL);
  double err = fabs(NV_Ith_S(x, 0) - cos(10.0));
  printf("x(%g) = %.9f, error %.1e\n", t, NV_Ith_S(x, 0), err);
  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  SUNContext_Free(&ctx);
  /* h^4 t times G5_O4's error constant 0.286 is 2.9e-8; the run errs by 7.7e-9 */
  return flag == CE_SUCCESS && err < 2.9e-8 ? 0 : 1;
}
