/* -----------------------------------------------------------------------------
 * mpi_vectors: CEODE's core runs unchanged on MPI-parallel vectors.
 *
 * Problem: n = 64 independent pendulums theta_i'' = -(g/L_i) cos(theta_i) with
 * different lengths, released from rest, integrated with G5 for 1 s (h = 1e-3)
 * on an NVECTOR_PARALLEL vector split over the MPI ranks, and again on one
 * NVECTOR_SERIAL vector of the whole system on rank 0.
 *
 * Reference: the serial run. Every entry is computed by the same per-entry
 * operations in the same order on both vector kinds, so the distributed result
 * must equal the serial one to the bit; only global reductions (norms used by
 * the stability checks) differ in summation order.
 *
 * Exit code 0 on every rank when the gathered parallel result is bitwise equal
 * to the serial one. Run with: mpiexec -n 2 mpi_vectors
 * ---------------------------------------------------------------------------*/
#include <ceode/ceode.h>
#include <math.h>
#include <mpi.h>
#include <nvector/nvector_parallel.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <stdlib.h>

#include "ceode_sundials_compat.h" /* SUN_COMM_NULL on SUNDIALS 6.4 */

#define NGLOBAL 64

struct lengths {
  sunindextype first; /* global index of the first local entry */
};

static double length_of(sunindextype i) { return 0.5 + 0.01 * (double)i; }

static int rhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
  const struct lengths* p = (const struct lengths*)data;
  const sunrealtype* xd = N_VGetArrayPointer(x);
  sunrealtype* fd = N_VGetArrayPointer(f);
  /* The local length of either vector kind: the serial run owns everything. */
  const sunindextype nl =
      N_VGetVectorID(x) == SUNDIALS_NVEC_PARALLEL ? NV_LOCLENGTH_P(x) : NV_LENGTH_S(x);
  sunindextype i;
  (void)t;
  (void)v;
  for (i = 0; i < nl; ++i) fd[i] = -(9.81 / length_of(p->first + i)) * cos(xd[i]);
  return 0;
}

static int run(N_Vector x, N_Vector v, struct lengths* p) {
  void* mem = CEodeCreate(x->sunctx);
  sunrealtype t = 0;
  int flag;
  if (mem == NULL) return -1;
  N_VConst(0, x);
  N_VConst(0, v);
  flag = CEodeInit(mem, rhs, 0, x, v);
  if (flag == CE_SUCCESS) flag = CEodeSetMethodByName(mem, "G5");
  if (flag == CE_SUCCESS) flag = CEodeSetFixedStep(mem, 1e-3);
  if (flag == CE_SUCCESS) flag = CEodeSetUserData(mem, p);
  if (flag == CE_SUCCESS) flag = CEodeSetStabilityGuard(mem, CE_GUARD_WARN, 100);
  if (flag == CE_SUCCESS) flag = CEodeEvolve(mem, 1.0, x, v, &t, CE_NORMAL);
  CEodeFree(&mem);
  return flag;
}

int main(int argc, char** argv) {
  int rank, size, bad = 0, allbad = 0, flag, i;
  sunindextype nlocal, first;
  SUNContext ctx;
  MPI_Comm comm = MPI_COMM_WORLD;
  N_Vector x, v;
  struct lengths p;
  double* gathered = NULL;
  int* counts = NULL;
  int* displs = NULL;
  MPI_Init(&argc, &argv);
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  nlocal = NGLOBAL / size + (rank < NGLOBAL % size ? 1 : 0);
  first = rank * (NGLOBAL / size) + (rank < NGLOBAL % size ? rank : NGLOBAL % size);
  if (SUNContext_Create(CEODE_SUN_COMM_ARG(comm), &ctx)) MPI_Abort(comm, 1);
  x = N_VNew_Parallel(comm, nlocal, NGLOBAL, ctx);
  v = N_VNew_Parallel(comm, nlocal, NGLOBAL, ctx);
  p.first = first;
  flag = run(x, v, &p);
  if (flag != CE_SUCCESS) {
    fprintf(stderr, "rank %d: parallel run returned %d\n", rank, flag);
    bad = 1;
  }
  if (rank == 0) {
    gathered = (double*)malloc(NGLOBAL * sizeof(double));
    counts = (int*)malloc((size_t)size * sizeof(int));
    displs = (int*)malloc((size_t)size * sizeof(int));
    for (i = 0; i < size; ++i) {
      counts[i] = NGLOBAL / size + (i < NGLOBAL % size ? 1 : 0);
      displs[i] = i * (NGLOBAL / size) + (i < NGLOBAL % size ? i : NGLOBAL % size);
    }
  }
  MPI_Gatherv(N_VGetArrayPointer(x), (int)nlocal, MPI_DOUBLE, gathered, counts, displs, MPI_DOUBLE,
              0, comm);
  if (rank == 0) {
    SUNContext sctx;
    N_Vector xs, vs;
    struct lengths ps;
    int ndiff = 0;
    double maxdiff = 0;
    if (SUNContext_Create(SUN_COMM_NULL, &sctx)) MPI_Abort(comm, 1);
    xs = N_VNew_Serial(NGLOBAL, sctx);
    vs = N_VNew_Serial(NGLOBAL, sctx);
    ps.first = 0;
    flag = run(xs, vs, &ps);
    if (flag != CE_SUCCESS) {
      fprintf(stderr, "serial run returned %d\n", flag);
      bad = 1;
    }
    for (i = 0; i < NGLOBAL; ++i) {
      const double d = fabs(gathered[i] - NV_Ith_S(xs, i));
      if (d != 0) ++ndiff;
      if (d > maxdiff) maxdiff = d;
    }
    printf("%d ranks, %d entries: %d differ from the serial run (max |diff| %.3e)\n", size, NGLOBAL,
           ndiff, maxdiff);
    printf("theta_0(1 s) = %.15f, theta_63(1 s) = %.15f\n", NV_Ith_S(xs, 0), NV_Ith_S(xs, 63));
    if (ndiff != 0) bad = 1;
    N_VDestroy(xs);
    N_VDestroy(vs);
    SUNContext_Free(&sctx);
    free(gathered);
    free(counts);
    free(displs);
  }
  MPI_Allreduce(&bad, &allbad, 1, MPI_INT, MPI_MAX, comm);
  N_VDestroy(x);
  N_VDestroy(v);
  SUNContext_Free(&ctx);
  MPI_Finalize();
  return allbad;
}
