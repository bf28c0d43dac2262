// The precision floor (docs/theory.md section 10, issue "Stability"): at very small
// steps the pendulum's energy error stops falling because of round-off. Summing
// each increment before the large term, and optionally Kahan-compensating the
// accumulated quantities, pushes that floor below the paper's ~2e-11.
// Labelled slow: 1e7 steps per run (a few seconds optimised, far more under ASan).
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "test_util.hpp"

namespace {

using ceode_test::PendulumEnergyError;

// Target of the issue: G5 with compensated summation at h = 1e-5 and 1e-6.
constexpr double kFloorTarget = 1e-13;

TEST(PrecisionFloor, CompensatedSummationKeepsG5BelowOneEMinus13AtTinySteps) {
  for (double h : {1e-5, 1e-6}) {
    const double err = PendulumEnergyError("G5", h, false, true);
    std::printf("[ floor ] G5 h = %g compensated: %.3e\n", h, err);
    EXPECT_LE(err, kFloorTarget) << "h = " << h;
  }
}

// Degree 4 has the same floor once compensated; without compensation its
// error at h = 1e-6 is set by round-off, not by truncation (~1e-15 at that h).
TEST(PrecisionFloor, CompensatedSummationLowersTheDegreeFourFloor) {
  const double plain = PendulumEnergyError("G4_A34", 1e-6, false, false);
  const double comp = PendulumEnergyError("G4_A34", 1e-6, false, true);
  std::printf("[ floor ] G4_A34 h = 1e-6: plain %.3e, compensated %.3e\n", plain, comp);
  EXPECT_LE(comp, kFloorTarget);
  EXPECT_LT(comp, plain);
}

// Degree 3 at h = 1e-6: compensated, the error lies on its second-order
// truncation line (4.006e-10 at h = 1e-5, divided by 100); plain summation
// adds round-off on top of it.
TEST(PrecisionFloor, DegreeThreeIsTruncationLimitedAtOneEMinus6) {
  const double plain = PendulumEnergyError("G3_A2", 1e-6, false, false);
  const double comp = PendulumEnergyError("G3_A2", 1e-6, false, true);
  std::printf("[ floor ] G3_A2 h = 1e-6: plain %.3e, compensated %.3e\n", plain, comp);
  EXPECT_NEAR(comp / 4.0e-12, 1.0, 0.05);
  EXPECT_LE(comp, plain);
}

}  // namespace
