// Degrees above 5 run through the same degree-generic step (docs/theory.md section 2):
// nothing in the library is written per degree. The paper stops at d = 5, so the
// degree-6 parameters here come from a scan with the library's own stability
// analysis (CEodeStabilityLimit) for a set whose Omega_max is about 1.09.
#include <ceode/ceode.h>
#include <ceode/ceode_stability.h>
#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>

#include <cmath>
#include <vector>

#include "test_util.hpp"

namespace {

using ceode_test::Context;
using ceode_test::FitOrder;
using ceode_test::Mem;
using ceode_test::SerialVector;
using ceode_test::Vector;

// x'' = -x + 0.3 sin 2t, x(0) = 1, x'(0) = 0.5: x = cos t + 0.7 sin t - 0.1 sin 2t.
// Its initial jerk is not zero, so the consistent start is exercised too.
int ForcedRhs(sunrealtype t, N_Vector x, N_Vector /*v*/, N_Vector f, void* /*data*/) {
  NV_Ith_S(f, 0) = -NV_Ith_S(x, 0) + 0.3 * std::sin(2 * t);
  return 0;
}

sunrealtype Exact(sunrealtype t) { return std::cos(t) + 0.7 * std::sin(t) - 0.1 * std::sin(2 * t); }

constexpr sunrealtype kStableSixth[5] = {0.8, 1.0404, 1.9762, 1.4293, 0.8987};

// Max |x - exact| over 2 s of steps; returns the last flag through *flag.
double MaxError(const sunrealtype* params, sunrealtype h, int* flag) {
  Context ctx;
  Vector x = SerialVector(1, ctx, 1);
  Vector v = SerialVector(1, ctx, 0.5);
  Mem mem(CEodeCreate(ctx));
  CEodeSetErrFile(mem.get(), nullptr);
  EXPECT_EQ(CEodeInit(mem.get(), ForcedRhs, 0, x.get(), v.get()), CE_SUCCESS);
  EXPECT_EQ(CEodeSetMethod(mem.get(), 6, params), CE_SUCCESS);
  EXPECT_EQ(CEodeSetFixedStep(mem.get(), h), CE_SUCCESS);
  EXPECT_EQ(CEodeSetStabilityGuard(mem.get(), CE_GUARD_OFF, 0), CE_SUCCESS);
  const long int n = std::lround(2.0 / h);
  double emax = 0;
  sunrealtype t = 0;
  *flag = CE_SUCCESS;
  for (long int i = 0; i < n && *flag == CE_SUCCESS; ++i) {
    *flag = CEodeEvolve(mem.get(), 10, x.get(), v.get(), &t, CE_ONE_STEP);
    EXPECT_TRUE(std::isfinite(NV_Ith_S(x.get(), 0)));
    emax = std::max(emax, std::fabs(NV_Ith_S(x.get(), 0) - Exact(t)));
  }
  return emax;
}

TEST(DegreeSix, AStableSetFoundByTheAnalysisHasALimitAboveOne) {
  sunrealtype lim = 0;
  ASSERT_EQ(CEodeStabilityLimit(6, kStableSixth, 0, &lim), CE_SUCCESS);
  EXPECT_NEAR(lim, 1.088, 0.01);
}

TEST(DegreeSix, RunsThroughTheGenericStepAtFourthOrder) {
  std::vector<double> hs, errs;
  for (double h = 0.02; h > 0.0012; h /= 2) {
    int flag = 0;
    errs.push_back(MaxError(kStableSixth, h, &flag));
    hs.push_back(h);
    ASSERT_EQ(flag, CE_SUCCESS);
  }
  const double order = FitOrder(hs, errs);
  std::printf("[ degree 6 ] observed order in x: %.3f\n", order);
  EXPECT_NEAR(order, 4.0, 0.1);  // measured 4.00; higher than the G4/G5 sets' 3
}

// All-ones parameters are not zero-stable at degree 6: the run must stop with
// CE_UNSTABLE and a finite state, never hand back NaN.
TEST(DegreeSix, AnUnstableSetStopsWithCeUnstableAndFiniteOutput) {
  const sunrealtype ones[5] = {1, 1, 1, 1, 1};
  sunrealtype rho = 0;
  ASSERT_EQ(CEodeSpectralRadius(6, ones, 1e-3, 0, &rho), CE_SUCCESS);
  EXPECT_GT(rho, 1.01);
  int flag = 0;
  MaxError(ones, 0.01, &flag);
  EXPECT_EQ(flag, CE_UNSTABLE);
}

}  // namespace
