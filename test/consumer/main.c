/* Integrates x'' = -x over one period with G4_A34 and checks the answer:
 * proves the installed headers, library and CMake package (or ceode.pc) work from C.
 * First it checks that the headers it was compiled with are those of the libraries it
 * runs with: SUNDIALS 6.4 headers with 7.x libraries would pass SUNContext_Create a
 * NULL where an MPI-enabled 7.x expects MPI_COMM_NULL, and abort inside MPI. */
#include <ceode/ceode.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <string.h>
#include <sundials/sundials_version.h>

/* 0 when the compiled-in versions of SUNDIALS and CEODE are the loaded libraries'. */
static int check_versions(void) {
  int major = -1, minor = -1, patch = -1;
  char label[64], version[64];
  if (SUNDIALSGetVersionNumber(&major, &minor, &patch, label, sizeof label) != 0 ||
      major != SUNDIALS_VERSION_MAJOR || minor != SUNDIALS_VERSION_MINOR) {
    printf("SUNDIALS headers %d.%d, library %d.%d\n", SUNDIALS_VERSION_MAJOR,
           SUNDIALS_VERSION_MINOR, major, minor);
    return 1;
  }
  if (CEodeGetVersionNumber(&major, &minor, &patch, label, sizeof label) != CE_SUCCESS ||
      major != CEODE_VERSION_MAJOR || minor != CEODE_VERSION_MINOR ||
      patch != CEODE_VERSION_PATCH || strcmp(label, CEODE_VERSION_LABEL) != 0 ||
      CEodeGetVersion(version, sizeof version) != CE_SUCCESS ||
      strcmp(version, CEODE_VERSION) != 0) {
    printf("CEODE headers %s, library %d.%d.%d\n", CEODE_VERSION, major, minor, patch);
    return 1;
  }
  return 0;
}

static int rhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
  (void)t;
  (void)v;
  (void)data;
  N_VScale(-1.0, x, f);
  return 0;
}

int main(void) {
  SUNContext ctx = NULL;
  N_Vector x, v;
  void* mem;
  sunrealtype t = 0;
  const sunrealtype period = 2.0 * 3.14159265358979323846;
  int flag;
  double err;
  if (check_versions() != 0) return 1;
    /* SUNDIALS 7 takes a SUNComm (MPI_Comm on an MPI build: NULL would abort). */
#if SUNDIALS_VERSION_MAJOR >= 7
  if (SUNContext_Create(SUN_COMM_NULL, &ctx) != 0) return 1;
#else
  if (SUNContext_Create(NULL, &ctx) != 0) return 1;
#endif
  x = N_VNew_Serial(1, ctx);
  v = N_VNew_Serial(1, ctx);
  NV_Ith_S(x, 0) = 1.0;
  NV_Ith_S(v, 0) = 0.0;
  mem = CEodeCreate(ctx);
  flag = CEodeInit(mem, rhs, 0.0, x, v);
  if (flag == CE_SUCCESS) flag = CEodeSetMethodByName(mem, "G4_A34");
  if (flag == CE_SUCCESS) flag = CEodeSetFixedStep(mem, 1e-3);
  if (flag == CE_SUCCESS) flag = CEodeEvolve(mem, period, x, v, &t, CE_NORMAL);
  err = fabs(NV_Ith_S(x, 0) - 1.0) + fabs(NV_Ith_S(v, 0));
  printf("CEODE %d.%d.%d consumer: flag %d, t = %.6f, error after one period = %.3e\n",
         CEODE_VERSION_MAJOR, CEODE_VERSION_MINOR, CEODE_VERSION_PATCH, flag, (double)t, err);
  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  SUNContext_Free(&ctx);
  return flag == CE_SUCCESS && err < 1e-8 ? 0 : 1;
}
