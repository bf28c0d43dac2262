// What the MPI GoogleTest programs of test/mpi share: the parameter sets and one CEODE run of a
// partitioned model, bitwise comparison of a gathered state on rank 0, and running the collective
// tests on every rank with one report.
#ifndef CEODE_TEST_MPI_MPI_GTEST_H_
#define CEODE_TEST_MPI_MPI_GTEST_H_

#include <ceode/ceode.h>
#include <ceode/ceode_stability.h>
#include <gtest/gtest.h>
#include <mpi.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "ceode_testing.h"  // CEodeSetFusedKernel

namespace mpi_gtest {

struct Case {
  const char* method;
  bool compensated;
};

inline std::string CaseName(const testing::TestParamInfo<Case>& info) {
  return std::string(info.param.method) + (info.param.compensated ? "_compensated" : "");
}

// 0.9 of the set's stability limit Omega_max / omega_max.
inline double StepSize(const char* method, double omega_max) {
  int degree = 0;
  sunrealtype params[16];
  sunrealtype Omega = 0;
  EXPECT_EQ(CEodeGetMethodParams(method, &degree, params, 16), CE_SUCCESS);
  EXPECT_EQ(CEodeStabilityLimit(degree, params, 0, &Omega), CE_SUCCESS);
  return 0.9 * Omega / omega_max;
}

// steps steps of c at StepSize from (x, v), which hold the initial state; the state ends in x.
// Returns CEODE's flag and, on a failure, its message in *msg (if given).
inline int RunCase(const Case& c, bool fused, CEodeRhsFn f, void* user, double omega_max,
                   long steps, N_Vector x, N_Vector v, std::string* msg = nullptr) {
  const double h = StepSize(c.method, omega_max);
  void* mem = CEodeCreate(x->sunctx);
  int flag = CEodeInit(mem, f, 0, x, v);
  if (flag == CE_SUCCESS) flag = CEodeSetMethodByName(mem, c.method);
  if (flag == CE_SUCCESS) flag = CEodeSetFixedStep(mem, h);
  if (flag == CE_SUCCESS) flag = CEodeSetUserData(mem, user);
  if (flag == CE_SUCCESS) flag = CEodeSetCompensatedSummation(mem, c.compensated ? 1 : 0);
  if (flag == CE_SUCCESS) flag = CEodeSetFusedKernel(mem, fused ? 1 : 0);
  sunrealtype t = 0;
  if (flag == CE_SUCCESS) {
    flag = CEodeEvolve(mem, static_cast<sunrealtype>(steps) * h, x, v, &t, CE_NORMAL);
  }
  const char* text = nullptr;
  if (flag != CE_SUCCESS && msg != nullptr && CEodeGetLastErrorMessage(mem, &text) == CE_SUCCESS &&
      text != nullptr) {
    *msg = text;
  }
  CEodeFree(&mem);
  return flag;
}

// The bit pattern (so that -0 and +0 differ and a NaN never matches itself).
inline uint64_t Bits(double d) {
  uint64_t u = 0;
  std::memcpy(&u, &d, sizeof u);
  return u;
}

inline bool OnRankZero() {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank == 0;
}

// Entries whose bits differ (rank 0's count, -1 for different sizes, broadcast so that every rank
// asserts the same).
inline long BitwiseDifferences(const std::vector<double>& a, const std::vector<double>& b) {
  long n = 0;
  if (OnRankZero()) {
    n = a.size() == b.size() ? 0 : -1;
    for (size_t i = 0; n >= 0 && i < a.size(); ++i) {
      if (Bits(a[i]) != Bits(b[i])) ++n;
    }
  }
  MPI_Bcast(&n, 1, MPI_LONG, 0, MPI_COMM_WORLD);
  return n;
}

// Every rank's block of a distributed state (contiguous, in rank order, as both models partition)
// gathered on rank 0 in global order; empty on the other ranks.
inline std::vector<double> GatherOnRankZero(const double* local, long len) {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const int n = static_cast<int>(len);
  std::vector<int> counts(static_cast<size_t>(size)), displs(static_cast<size_t>(size));
  MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  long total = 0;
  for (int q = 0; q < size; ++q) {
    displs[q] = static_cast<int>(total);
    total += counts[q];
  }
  std::vector<double> all(OnRankZero() ? static_cast<size_t>(total) : 0);
  MPI_Gatherv(local, n, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, 0,
              MPI_COMM_WORLD);
  return all;
}

// RUN_ALL_TESTS on every rank (the tests are collective), printed by rank 0 alone; 1 when any
// rank failed. Call after MPI_Init and testing::InitGoogleTest.
inline int RunOnAllRanks() {
  if (!OnRankZero()) {
    auto& listeners = testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  int failed = RUN_ALL_TESTS() != 0 ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &failed, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  return failed;
}

}  // namespace mpi_gtest

#endif  // CEODE_TEST_MPI_MPI_GTEST_H_
