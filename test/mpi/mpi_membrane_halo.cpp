// The membrane of bench/mpi_membrane_model.h (5-point Laplacian, lumped unit masses) with its
// rows split into strips over the MPI ranks and a halo exchange in f: CEODE on NVECTOR_PARALLEL
// must reproduce the NVECTOR_SERIAL run to the bit, with the fused serial kernel and with the
// generic N_Vector path.
//
// Grid 37 x 23 (23 rows: uneven strips on 2 and 3 ranks, and on 3 ranks a middle strip with two
// neighbours), 200 steps at 0.9 of each set's stability limit, the two modes of
// InitialModes; and a 9 x 2 grid, on 3 ranks one without rows. Reference: the serial run of the
// same program (no reference file: the claim is equality). A negative control shows the comparison
// notices a wrong halo.
//
// One GoogleTest program run by every rank (mpiexec -n 2 / -n 3); the tests are collective.
#include <ceode/ceode.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "ceode_sundials_compat.h"
#include "mpi_gtest.h"
#include "mpi_membrane_model.h"

namespace {

using mpi_gtest::BitwiseDifferences;
using mpi_gtest::Case;
using mpi_gtest::CaseName;
using mpi_gtest::GatherOnRankZero;
using mpi_gtest::OnRankZero;
using mpi_gtest::RunCase;

struct Grid {
  int nx;
  int ny;
  long Size() const { return static_cast<long>(nx) * ny; }
};
constexpr Grid kGrid{37, 23};
constexpr long kSteps = 200;

// Integrates kSteps steps on x (either vector kind); returns CEODE's flag and, on a failure, its
// message in *msg (if given).
int Integrate(N_Vector x, membrane::Strip* s, const Case& c, bool fused,
              std::string* msg = nullptr) {
  N_Vector v = N_VClone(x);
  membrane::InitialState(*s, N_VGetArrayPointer(x), N_VGetArrayPointer(v));
  const int flag = RunCase(c, fused, membrane::Rhs, s, membrane::OmegaMax(*s), kSteps, x, v, msg);
  N_VDestroy(v);
  return flag;
}

// The serial reference on one rank, the whole grid on NVECTOR_SERIAL.
std::vector<double> SerialRun(const Case& c, bool fused, Grid g = kGrid) {
  SUNContext ctx = nullptr;
  EXPECT_EQ(SUNContext_Create(SUN_COMM_NULL, &ctx), 0);
  membrane::Strip s = membrane::MakeStrip(MPI_COMM_NULL, g.nx, g.ny);
  N_Vector x = N_VNew_Serial(g.Size(), ctx);
  EXPECT_EQ(Integrate(x, &s, c, fused), CE_SUCCESS);
  const double* d = N_VGetArrayPointer(x);
  std::vector<double> out(d, d + g.Size());
  N_VDestroy(x);
  SUNContext_Free(&ctx);
  return out;
}

struct ParallelResult {
  std::vector<double> x;  // gathered on rank 0
  int flag = CE_SUCCESS;  // the worst rank's
  long exchanges = 0;     // halo exchanges summed over the ranks
  std::string msg;        // this rank's error message
};

// A global reduction that fails, as N_VDotProdMultiAllReduce does when MPI_Allreduce does.
int FailingReduction(int /*nvec*/, N_Vector /*x*/, sunrealtype* /*sum*/) { return -1; }

// Every rank: its strip on NVECTOR_PARALLEL over MPI_COMM_WORLD; the state gathered on rank 0.
// failing_reduction: the vector (and so every clone CEODE makes of it) gets FailingReduction.
ParallelResult ParallelRun(const Case& c, bool exchange, Grid g = kGrid,
                           bool failing_reduction = false) {
  MPI_Comm comm = MPI_COMM_WORLD;
  SUNContext ctx = nullptr;
  EXPECT_EQ(SUNContext_Create(CEODE_SUN_COMM_ARG(comm), &ctx), 0);
  membrane::Strip s = membrane::MakeStrip(comm, g.nx, g.ny);
  s.exchange = exchange;
  N_Vector x = N_VNew_Parallel(comm, membrane::LocalLength(s), g.Size(), ctx);
  if (failing_reduction) x->ops->nvdotprodmultiallreduce = FailingReduction;
  ParallelResult r;
  r.flag = Integrate(x, &s, c, true, &r.msg);
  MPI_Allreduce(MPI_IN_PLACE, &r.flag, 1, MPI_INT, MPI_MIN, comm);
  MPI_Allreduce(&s.nexchange, &r.exchanges, 1, MPI_LONG, MPI_SUM, comm);
  r.x = GatherOnRankZero(N_VGetArrayPointer(x), membrane::LocalLength(s));
  N_VDestroy(x);
  SUNContext_Free(&ctx);
  return r;
}

class MembraneOnRanks : public testing::TestWithParam<Case> {};

TEST_P(MembraneOnRanks, GivesTheSerialNumbersBitForBit) {
  const std::vector<double> serial =
      OnRankZero() ? SerialRun(GetParam(), true) : std::vector<double>{};
  const ParallelResult par = ParallelRun(GetParam(), true);
  ASSERT_EQ(par.flag, CE_SUCCESS);
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size > 1) EXPECT_GT(par.exchanges, 0) << "no halo was exchanged: the test would be vacuous";
  EXPECT_EQ(BitwiseDifferences(serial, par.x), 0) << "of " << kGrid.Size() << " entries";
}

TEST_P(MembraneOnRanks, FusedAndGenericSerialKernelsAgreeBitForBit) {
  std::vector<double> fused, generic;
  if (OnRankZero()) {
    fused = SerialRun(GetParam(), true);
    generic = SerialRun(GetParam(), false);
  }
  EXPECT_EQ(BitwiseDifferences(fused, generic), 0) << "of " << kGrid.Size() << " entries";
}

INSTANTIATE_TEST_SUITE_P(Sets, MembraneOnRanks,
                         testing::Values(Case{"G3_CD", false}, Case{"G4_A34", false},
                                         Case{"G5_TOP", false}, Case{"G6_O6", false},
                                         Case{"G4_A34", true}),
                         CaseName);

// Fewer grid rows than ranks: the ranks past the last row own nothing and take no part in the halo
// exchange (on 2 ranks every rank owns a row; the case bites on 3).
TEST(MembraneOnRanksEdgeCase, WithMoreRanksThanRowsGivesTheSerialNumbers) {
  const Case c{"G4_A34", false};
  const Grid thin{9, 2};
  const std::vector<double> serial =
      OnRankZero() ? SerialRun(c, true, thin) : std::vector<double>{};
  const ParallelResult par = ParallelRun(c, true, thin);
  ASSERT_EQ(par.flag, CE_SUCCESS);
  EXPECT_EQ(BitwiseDifferences(serial, par.x), 0) << "of " << thin.Size() << " entries";
}

// Negative control: with the halo rows never exchanged (stale zeros), the strips' edge rows see
// a fixed edge that is not there, and the comparison must notice.
// The growth check's norm is CEODE's one reduction per step; when it fails, the step reports the
// vector operation (not a non-finite state or an unstable step size) on every rank, the state
// it returns is finite, and the message says which state that is. On kGrid's strips (< 1024
// entries a rank) the plans keep two buffers: the last completed step's state.
TEST(MembraneOnRanksControl, AFailedGlobalReductionIsReportedAsAVectorOperationError) {
  const ParallelResult r = ParallelRun(Case{"G3_CD", false}, true, kGrid, true);
  EXPECT_EQ(r.flag, CE_VECTOROP_ERR);
  EXPECT_NE(r.msg.find("global reduction"), std::string::npos) << r.msg;
  EXPECT_NE(r.msg.find("that of the last completed step"), std::string::npos) << r.msg;
  bool finite = true;
  for (double v : r.x) finite = finite && std::isfinite(v);
  EXPECT_TRUE(finite);
}

// With >= 1024 entries a rank the lean loop writes the velocity and the position in place, so
// the first step's failed reduction leaves the failed step's position and velocity: the message
// must say so and point to CEodeReInit (docs/theory.md, "In-place update").
TEST(MembraneOnRanksControl, AFailedReductionAfterAnInPlaceUpdateSaysTheStateIsTheFailedSteps) {
  constexpr Grid kLarge{64, 48};  // 1024 entries a rank on 3 ranks
  const ParallelResult r = ParallelRun(Case{"G3_CD", false}, true, kLarge, true);
  EXPECT_EQ(r.flag, CE_VECTOROP_ERR);
  EXPECT_NE(r.msg.find("position and velocity returned are the failed step's"), std::string::npos)
      << r.msg;
  EXPECT_NE(r.msg.find("CEodeReInit"), std::string::npos) << r.msg;
  bool finite = true;
  for (double v : r.x) finite = finite && std::isfinite(v);
  EXPECT_TRUE(finite);
}

TEST(MembraneOnRanksControl, WithoutTheHaloExchangeDiffersFromSerial) {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size == 1) GTEST_SKIP() << "one rank has no halo";
  const Case c{"G3_CD", false};
  const std::vector<double> serial = OnRankZero() ? SerialRun(c, true) : std::vector<double>{};
  const ParallelResult par = ParallelRun(c, false);
  ASSERT_EQ(par.flag, CE_SUCCESS);
  EXPECT_GT(BitwiseDifferences(serial, par.x), 0);
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  testing::InitGoogleTest(&argc, argv);
  const int failed = mpi_gtest::RunOnAllRanks();
  MPI_Finalize();
  return failed;
}
