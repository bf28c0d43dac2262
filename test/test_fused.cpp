// The one-pass update kernel for serial vectors must give exactly the numbers
// of the generic N_Vector path it replaces, with and without compensation.
#include <ceode/ceode.h>
#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>

#include <cmath>
#include <string>
#include <vector>

#include "ceode_sundials_compat.h"  // SUN_COMM_NULL on SUNDIALS 6.4

namespace {

// A chain of unit masses with cubic springs, fixed at both ends.
int ChainRhs(sunrealtype /*t*/, N_Vector x, N_Vector /*v*/, N_Vector f, void* /*data*/) {
  const sunindextype n = N_VGetLength(x);
  const sunrealtype* xd = N_VGetArrayPointer(x);
  sunrealtype* fd = N_VGetArrayPointer(f);
  for (sunindextype i = 0; i < n; ++i) {
    const sunrealtype left = i > 0 ? xd[i] - xd[i - 1] : xd[i];
    const sunrealtype right = i + 1 < n ? xd[i + 1] - xd[i] : -xd[i];
    fd[i] = right - left + 0.1 * (right * right * right - left * left * left);
  }
  return 0;
}

struct RunResult {
  std::vector<sunrealtype> x;
  std::vector<sunrealtype> v;
};

RunResult RunChain(const std::string& method, bool fused, bool compensated) {
  constexpr sunindextype kN = 64;
  SUNContext ctx = nullptr;
  SUNContext_Create(SUN_COMM_NULL, &ctx);
  N_Vector x = N_VNew_Serial(kN, ctx);
  N_Vector v = N_VNew_Serial(kN, ctx);
  for (sunindextype i = 0; i < kN; ++i) {
    N_VGetArrayPointer(x)[i] = std::sin(0.3 * static_cast<sunrealtype>(i));
    N_VGetArrayPointer(v)[i] = 0.1 * std::cos(0.7 * static_cast<sunrealtype>(i));
  }
  void* mem = CEodeCreate(ctx);
  EXPECT_EQ(CEodeInit(mem, ChainRhs, 0, x, v), CE_SUCCESS);
  EXPECT_EQ(CEodeSetMethodByName(mem, method.c_str()), CE_SUCCESS);
  EXPECT_EQ(CEodeSetFixedStep(mem, 0.01), CE_SUCCESS);
  EXPECT_EQ(CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0), CE_SUCCESS);
  EXPECT_EQ(CEodeSetFusedKernel(mem, fused ? SUNTRUE : SUNFALSE), CE_SUCCESS);
  EXPECT_EQ(CEodeSetCompensatedSummation(mem, compensated ? SUNTRUE : SUNFALSE), CE_SUCCESS);
  sunrealtype t = 0;
  EXPECT_EQ(CEodeEvolve(mem, 5.0, x, v, &t, CE_NORMAL), CE_SUCCESS);
  RunResult r;
  r.x.assign(N_VGetArrayPointer(x), N_VGetArrayPointer(x) + kN);
  r.v.assign(N_VGetArrayPointer(v), N_VGetArrayPointer(v) + kN);
  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  SUNContext_Free(&ctx);
  return r;
}

class FusedKernel : public ::testing::TestWithParam<std::string> {};

TEST_P(FusedKernel, GivesBitwiseTheNumbersOfTheGenericPath) {
  for (bool compensated : {false, true}) {
    const RunResult generic = RunChain(GetParam(), false, compensated);
    const RunResult fused = RunChain(GetParam(), true, compensated);
    ASSERT_EQ(generic.x.size(), fused.x.size());
    for (size_t i = 0; i < generic.x.size(); ++i) {
      EXPECT_EQ(generic.x[i], fused.x[i]) << "x[" << i << "] compensated=" << compensated;
      EXPECT_EQ(generic.v[i], fused.v[i]) << "v[" << i << "] compensated=" << compensated;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(EveryDegree, FusedKernel,
                         ::testing::Values("G3_CD", "G3_A2", "G4_A34", "G5", "G5_TOP"));

}  // namespace
