// CEODE on NVECTOR_PETSC (docs/mpi.md, "NVECTOR_PETSC"): the Q4 cantilever plate of
// bench/mpi_fe_plate_model.h (the linear FE scene: K in CSR, lumped M), one block of node
// columns per rank on a PETSc MPI Vec wrapped by N_VMake_Petsc, the halo columns exchanged inside
// f. PETSc vectors expose no array to N_VGetArrayPointer, so CEODE runs its generic N_Vector path
// and f reaches the entries through VecGetArrayRead / VecGetArray, as a PETSc code does.
//
// Reference: the same plate on one NVECTOR_SERIAL vector, run by the same program (no reference
// file: the claim is equality). Every per-entry operation is the serial one and the one global
// reduction per step (the growth check's L1 norm) does not feed back into the state, so the
// gathered state must equal the serial one bit for bit, with the serial run's fused kernel or
// its generic path. A plate of 2176 DOFs (a 64 x 16 mesh, 64 free node columns of 34 DOFs: blocks
// of 22, 21 and 21 columns on 3 ranks, the middle one with two neighbours), 200 steps at 0.9 of
// each set's stability limit from the Gershgorin bound. The same Vecs wrapped instead as
// NVECTOR_PARALLEL vectors on their local arrays (so CEODE runs its fused kernel, docs/mpi.md) must
// give the same bits. A negative control shows the comparison notices a stale halo.
//
// Built when Debian's SUNDIALS provides SUNDIALS::nvecpetsc (it always does: libsundials-dev
// depends on petsc-dev); one GoogleTest program run by every rank (mpiexec -n 2 / -n 3).
#include <ceode/ceode.h>
#include <gtest/gtest.h>
#include <nvector/nvector_parallel.h>
#include <nvector/nvector_petsc.h>
#include <petscvec.h>

#include <string>
#include <vector>

#include "ceode_sundials_compat.h"
#include "mpi_fe_plate_model.h"
#include "mpi_gtest.h"

namespace {

using mpi_gtest::BitwiseDifferences;
using mpi_gtest::Case;
using mpi_gtest::CaseName;
using mpi_gtest::GatherOnRankZero;
using mpi_gtest::OnRankZero;
using mpi_gtest::RunCase;

constexpr long kDofs = 2000;
constexpr long kSteps = 200;

// f on PETSc vectors: the model's halo-exchanging Accel on the Vecs' local arrays.
int PetscRhs(sunrealtype /*t*/, N_Vector x, N_Vector /*v*/, N_Vector f, void* data) {
  Vec X = N_VGetVector_Petsc(x);
  Vec F = N_VGetVector_Petsc(f);
  const PetscScalar* xa = nullptr;
  PetscScalar* fa = nullptr;
  if (VecGetArrayRead(X, &xa) != 0 || VecGetArray(F, &fa) != 0) return -1;
  const int rv = fe_strip::Accel(static_cast<fe_strip::Strip*>(data), xa, fa);
  VecRestoreArrayRead(X, &xa);
  VecRestoreArray(F, &fa);
  return rv;
}

// The initial state on x and v, whichever kind they are.
void SetInitialState(const fe_strip::Strip& s, N_Vector x, N_Vector v) {
  if (N_VGetVectorID(x) != SUNDIALS_NVEC_PETSC) {
    fe_strip::InitialState(s, N_VGetArrayPointer(x), N_VGetArrayPointer(v));
    return;
  }
  PetscScalar* xa = nullptr;
  PetscScalar* va = nullptr;
  VecGetArray(N_VGetVector_Petsc(x), &xa);
  VecGetArray(N_VGetVector_Petsc(v), &va);
  fe_strip::InitialState(s, xa, va);
  VecRestoreArray(N_VGetVector_Petsc(x), &xa);
  VecRestoreArray(N_VGetVector_Petsc(v), &va);
}

// kSteps steps from the initial state; the state ends in x. Returns CEODE's flag.
int Integrate(N_Vector x, fe_strip::Strip* s, const Case& c, bool fused, CEodeRhsFn f) {
  N_Vector v = N_VClone(x);
  SetInitialState(*s, x, v);
  const int flag = RunCase(c, fused, f, s, fe_strip::OmegaMax(*s), kSteps, x, v);
  N_VDestroy(v);
  return flag;
}

// The serial reference on one rank: the whole plate on NVECTOR_SERIAL.
std::vector<double> SerialRun(const Case& c, bool fused) {
  SUNContext ctx = nullptr;
  EXPECT_EQ(SUNContext_Create(SUN_COMM_NULL, &ctx), 0);
  fe_strip::Strip s = fe_strip::MakeStrip(MPI_COMM_NULL, kDofs);
  N_Vector x = N_VNew_Serial(fe_strip::GlobalLength(s), ctx);
  EXPECT_EQ(Integrate(x, &s, c, fused, fe_strip::Rhs), CE_SUCCESS);
  const double* d = N_VGetArrayPointer(x);
  std::vector<double> out(d, d + fe_strip::GlobalLength(s));
  N_VDestroy(x);
  SUNContext_Free(&ctx);
  return out;
}

struct PetscResult {
  std::vector<double> x;  // gathered on rank 0
  int flag = CE_SUCCESS;  // the worst rank's
  long exchanges = 0;     // halo exchanges summed over the ranks
  long global = 0;        // the Vec's global size
};

// How CEODE sees the PETSc Vec: as NVECTOR_PETSC (the generic path), or as NVECTOR_PARALLEL
// vectors made on the Vecs' local arrays (the fused kernel; docs/mpi.md).
enum class Wrap { kPetsc, kParallelOnArrays };

// Every rank: its block on a PETSc MPI Vec; the state gathered on rank 0 in DOF order.
PetscResult PetscRun(const Case& c, bool exchange, Wrap wrap = Wrap::kPetsc) {
  MPI_Comm comm = MPI_COMM_WORLD;
  SUNContext ctx = nullptr;
  EXPECT_EQ(SUNContext_Create(CEODE_SUN_COMM_ARG(comm), &ctx), 0);
  fe_strip::Strip s = fe_strip::MakeStrip(comm, kDofs);
  s.exchange = exchange;
  Vec X = nullptr;
  EXPECT_EQ(VecCreateMPI(comm, fe_strip::LocalLength(s), fe_strip::GlobalLength(s), &X), 0);
  PetscInt global = 0;
  VecGetSize(X, &global);
  PetscScalar* xarray = nullptr;
  N_Vector x = nullptr;
  if (wrap == Wrap::kPetsc) {
    x = N_VMake_Petsc(X, ctx);
  } else {  // the array stays checked out of X until the run ends
    VecGetArray(X, &xarray);
    x = N_VMake_Parallel(comm, fe_strip::LocalLength(s), global, xarray, ctx);
  }
  PetscResult r;
  r.global = global;
  r.flag = Integrate(x, &s, c, true, wrap == Wrap::kPetsc ? PetscRhs : fe_strip::Rhs);
  N_VDestroy(x);  // neither wrapper owns X or its array
  if (xarray != nullptr) VecRestoreArray(X, &xarray);
  MPI_Allreduce(MPI_IN_PLACE, &r.flag, 1, MPI_INT, MPI_MIN, comm);
  MPI_Allreduce(&s.nexchange, &r.exchanges, 1, MPI_LONG, MPI_SUM, comm);
  const PetscScalar* xa = nullptr;
  VecGetArrayRead(X, &xa);
  r.x = GatherOnRankZero(xa, fe_strip::LocalLength(s));
  VecRestoreArrayRead(X, &xa);
  VecDestroy(&X);
  SUNContext_Free(&ctx);
  return r;
}

class FePlateOnPetscVectors : public testing::TestWithParam<Case> {};

TEST_P(FePlateOnPetscVectors, GivesTheSerialFusedKernelsNumbersBitForBit) {
  const std::vector<double> serial =
      OnRankZero() ? SerialRun(GetParam(), true) : std::vector<double>{};
  const PetscResult par = PetscRun(GetParam(), true);
  ASSERT_EQ(par.flag, CE_SUCCESS);
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size > 1) EXPECT_GT(par.exchanges, 0) << "no halo was exchanged: the test would be vacuous";
  EXPECT_EQ(BitwiseDifferences(serial, par.x), 0) << "of " << par.global << " entries";
}

TEST_P(FePlateOnPetscVectors, GivesTheSerialGenericPathsNumbersBitForBit) {
  const std::vector<double> serial =
      OnRankZero() ? SerialRun(GetParam(), false) : std::vector<double>{};
  const PetscResult par = PetscRun(GetParam(), true);
  ASSERT_EQ(par.flag, CE_SUCCESS);
  EXPECT_EQ(BitwiseDifferences(serial, par.x), 0) << "of " << par.global << " entries";
}

TEST_P(FePlateOnPetscVectors, WrappedAsParallelVectorsOnTheirArraysGivesTheSameNumbers) {
  const std::vector<double> serial =
      OnRankZero() ? SerialRun(GetParam(), true) : std::vector<double>{};
  const PetscResult par = PetscRun(GetParam(), true, Wrap::kParallelOnArrays);
  ASSERT_EQ(par.flag, CE_SUCCESS);
  EXPECT_EQ(BitwiseDifferences(serial, par.x), 0) << "of " << par.global << " entries";
}

INSTANTIATE_TEST_SUITE_P(Sets, FePlateOnPetscVectors,
                         testing::Values(Case{"G3_CD", false}, Case{"G4_A34", false},
                                         Case{"G5_O4", false}, Case{"G4_A34", true}),
                         CaseName);

// Negative control: with the halo columns never exchanged (stale zeros), the blocks' edge
// columns see neighbours that are not there, and the comparison must notice.
TEST(FePlateOnPetscVectorsControl, WithoutTheHaloExchangeDiffersFromSerial) {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size == 1) GTEST_SKIP() << "one rank has no halo";
  const Case c{"G3_CD", false};
  const std::vector<double> serial = OnRankZero() ? SerialRun(c, true) : std::vector<double>{};
  const PetscResult par = PetscRun(c, false);
  ASSERT_EQ(par.flag, CE_SUCCESS);
  EXPECT_GT(BitwiseDifferences(serial, par.x), 0);
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  // PETSc on the MPI already initialised: PetscFinalize leaves MPI to MPI_Finalize.
  if (PetscInitializeNoArguments() != 0) MPI_Abort(MPI_COMM_WORLD, 2);
  testing::InitGoogleTest(&argc, argv);
  const int failed = mpi_gtest::RunOnAllRanks();
  PetscFinalize();
  MPI_Finalize();
  return failed;
}
