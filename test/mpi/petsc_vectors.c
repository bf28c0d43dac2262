/* -----------------------------------------------------------------------------
 * petsc_vectors: CEODE on NVECTOR_PETSC (docs/mpi.md, "NVECTOR_PETSC").
 *
 * NOT built by CMake: PETSc is not a CEODE dependency. Debian 12's SUNDIALS 6.4.1
 * ships libsundials_nvecpetsc against Debian's PETSc 3.18 (libpetsc-real-dev);
 * the SUNDIALS builds under /opt have no PETSc. Build by hand against the Debian
 * SUNDIALS build of CEODE (./build):
 *
 *   mpicc -O2 -o petsc_vectors test/mpi/petsc_vectors.c -Iinclude $(pkg-config --cflags petsc) \
 *     -Lbuild -Wl,-rpath,$PWD/build -lceode -lsundials_nvecpetsc -lsundials_nvecserial \
 *     -lsundials_generic $(pkg-config --libs petsc) -lm
 *   mpiexec -n 2 ./petsc_vectors
 *
 * Problem: n = 1000 independent oscillators x_i'' = -k_i x_i (k_i = 1 + 0.01 i),
 * x_i(0) = 1 + 0.001 i, v = 0, G4_A34 with h = 0.01 to t = 2, on a PETSc MPI Vec
 * wrapped by N_VMake_Petsc, and again on NVECTOR_SERIAL on rank 0. Reference: the
 * serial run; the per-entry operations are the same, so the gathered PETSc state
 * must equal it bit for bit (exit code 0 when it does).
 * ---------------------------------------------------------------------------*/
#include <ceode/ceode.h>
#include <nvector/nvector_petsc.h>
#include <nvector/nvector_serial.h>
#include <petscvec.h>
#include <stdio.h>
#include <string.h>
#define NG 1000
static double kk(long i) { return 1.0 + 0.01 * (double)i; }
static int rhs_petsc(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* d) {
  Vec X = N_VGetVector_Petsc(x), F = N_VGetVector_Petsc(f);
  const PetscScalar* xa;
  PetscScalar* fa;
  PetscInt lo, hi, i;
  (void)t;
  (void)v;
  (void)d;
  VecGetOwnershipRange(X, &lo, &hi);
  VecGetArrayRead(X, &xa);
  VecGetArray(F, &fa);
  for (i = lo; i < hi; ++i) fa[i - lo] = -kk(i) * xa[i - lo];
  VecRestoreArrayRead(X, &xa);
  VecRestoreArray(F, &fa);
  return 0;
}
static int rhs_serial(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* d) {
  long i;
  (void)t;
  (void)v;
  (void)d;
  for (i = 0; i < NG; ++i) NV_Ith_S(f, i) = -kk(i) * NV_Ith_S(x, i);
  return 0;
}
static int run(N_Vector x, N_Vector v, CEodeRhsFn f) {
  void* mem = CEodeCreate(x->sunctx);
  sunrealtype t = 0;
  int flag;
  flag = CEodeInit(mem, f, 0, x, v);
  if (!flag) flag = CEodeSetMethodByName(mem, "G4_A34");
  if (!flag) flag = CEodeSetFixedStep(mem, 1e-2);
  if (!flag) flag = CEodeEvolve(mem, 2.0, x, v, &t, CE_NORMAL);
  CEodeFree(&mem);
  return flag;
}
int main(int argc, char** argv) {
  MPI_Comm comm = MPI_COMM_WORLD;
  SUNContext ctx;
  Vec X, V;
  N_Vector x, v;
  int rank, flag, bad = 0;
  PetscInt lo, hi, i;
  PetscScalar* a;
  PetscInitialize(&argc, &argv, NULL, NULL);
  MPI_Comm_rank(comm, &rank);
  SUNContext_Create(&comm, &ctx);
  VecCreateMPI(comm, PETSC_DECIDE, NG, &X);
  VecDuplicate(X, &V);
  VecGetOwnershipRange(X, &lo, &hi);
  VecGetArray(X, &a);
  for (i = lo; i < hi; ++i) a[i - lo] = 1.0 + 0.001 * (double)i;
  VecRestoreArray(X, &a);
  VecSet(V, 0.0);
  x = N_VMake_Petsc(X, ctx);
  v = N_VMake_Petsc(V, ctx);
  flag = run(x, v, rhs_petsc);
  if (rank == 0) printf("NVECTOR_PETSC run: flag %d\n", flag);
  {
    Vec G;
    VecScatter sc;
    const PetscScalar* g;
    VecScatterCreateToZero(X, &sc, &G);
    VecScatterBegin(sc, X, G, INSERT_VALUES, SCATTER_FORWARD);
    VecScatterEnd(sc, X, G, INSERT_VALUES, SCATTER_FORWARD);
    if (rank == 0) {
      SUNContext sctx;
      N_Vector xs, vs;
      long nd = 0;
      SUNContext_Create(NULL, &sctx);
      xs = N_VNew_Serial(NG, sctx);
      vs = N_VNew_Serial(NG, sctx);
      for (i = 0; i < NG; ++i) NV_Ith_S(xs, i) = 1.0 + 0.001 * (double)i;
      N_VConst(0, vs);
      flag = run(xs, vs, rhs_serial);
      VecGetArrayRead(G, &g);
      for (i = 0; i < NG; ++i)
        if (memcmp(&g[i], &NV_Ith_S(xs, i), sizeof(double))) ++nd;
      VecRestoreArrayRead(G, &g);
      printf("serial flag %d; %ld of %d entries differ bitwise; x_0(2) = %.15f\n", flag, nd, NG,
             NV_Ith_S(xs, 0));
      bad = nd != 0 || flag != 0;
      N_VDestroy(xs);
      N_VDestroy(vs);
      SUNContext_Free(&sctx);
    }
    VecScatterDestroy(&sc);
    VecDestroy(&G);
  }
  N_VDestroy(x);
  N_VDestroy(v);
  VecDestroy(&X);
  VecDestroy(&V);
  SUNContext_Free(&ctx);
  PetscFinalize();
  return bad;
}
