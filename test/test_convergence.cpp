// Observed convergence orders of every named parameter set (docs/theory.md section 5)
// from log-log least-squares fits of the max error over a 10 s run against the
// exact solution, in x and in x'.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "test_util.hpp"

namespace {

using ceode_test::ConvergenceSteps;
using ceode_test::DampedForced;
using ceode_test::ExactProblem;
using ceode_test::FitOrder;
using ceode_test::Harmonic;
using ceode_test::RunExact;
using ceode_test::RunOptions;
using ceode_test::RunResult;

struct SetCase {
  const char* method;
  int claimed;        // the paper's global order (docs/theory.md section 5): a lower bound
  double observed;    // order measured on the damped forced oscillator; 0: only the bound holds
  double hmax;        // largest step of the fit: keeps the smallest error above round-off
  const char* label;  // test-name sentence
};

std::ostream& operator<<(std::ostream& os, const SetCase& c) { return os << c.method; }

// G4_A54 is weakly unstable for every h (rho - 1 ~ 0.33 Omega^2 per step): over
// 10 s at Omega <= 0.08 the parasitic growth stays below a factor 1.5, so these
// short runs measure its order without being spoiled by the instability.
//
// Measured, not claimed: G4_A54, G5 and G5_ONES are fourth order on both
// problems. G5_TOP's parameters sit a few per cent from G5_ONES, so its third-
// order error term is small and the fitted slope over these steps lies between
// 3 and 4 (3.4 to 3.8); only the lower bound is a property of the set.
const SetCase kSets[] = {
    {"G3_CD", 2, 2, 0.04, "G3CentralDifferencesIsSecondOrder"},
    {"G3_A43", 2, 2, 0.04, "G3AlphaFourThirdsIsSecondOrder"},
    {"G3_A2", 2, 2, 0.04, "G3AlphaTwoIsSecondOrder"},
    {"G4_A54", 3, 4, 0.08, "G4AlphaFiveQuartersIsFourthOrderOnAShortRun"},
    {"G4_A14", 3, 3, 0.04, "G4AlphaOneQuarterIsThirdOrder"},
    {"G4_A34", 3, 3, 0.04, "G4AlphaThreeQuartersIsThirdOrder"},
    {"G5", 3, 4, 0.08, "G5IsFourthOrderBeyondTheClaimedThird"},
    {"G5_TOP", 3, 0, 0.08, "G5SpinningTopSetIsAtLeastThirdOrder"},
    {"G5_ONES", 3, 4, 0.08, "G5OnesSetIsFourthOrderBeyondTheClaimedThird"},
};

struct Orders {
  double x = 0;
  double v = 0;
  std::vector<double> ex, ev;
};

Orders MeasureOrders(const ExactProblem& prob, RunOptions opt, double hmax) {
  Orders o;
  const std::vector<double> hs = ConvergenceSteps(hmax);
  for (double h : hs) {
    opt.h = h;
    const RunResult r = RunExact(prob, opt);
    EXPECT_EQ(r.flag, CE_SUCCESS) << opt.method << " h = " << h;
    o.ex.push_back(r.err_x);
    o.ev.push_back(r.err_v);
  }
  o.x = FitOrder(hs, o.ex);
  o.v = FitOrder(hs, o.ev);
  return o;
}

void Report(const char* what, const std::string& method, const Orders& o, double hmax) {
  const std::vector<double> hs = ConvergenceSteps(hmax);
  std::printf(
      "[ order    ] %-8s %-26s x: %.3f  v: %.3f   (h = %g: ex = %.3e ev = %.3e; h = %g: "
      "ex = %.3e ev = %.3e)\n",
      method.c_str(), what, o.x, o.v, hs.front(), o.ex.front(), o.ev.front(), hs.back(),
      o.ex.back(), o.ev.back());
  ::testing::Test::RecordProperty("order_x", std::to_string(o.x));
  ::testing::Test::RecordProperty("order_v", std::to_string(o.v));
}

// The smallest error must sit far above round-off, or the fit would measure noise.
constexpr double kRoundoffFloor = 1e-11;
// A least-squares slope over five halvings is good to a few hundredths in the
// asymptotic regime; 0.1 leaves room for the next error term without hiding a
// lost order (a lost order moves the slope by 1).
constexpr double kOrderTol = 0.1;

class ConservativeProblem : public ::testing::TestWithParam<SetCase> {};

// x'' = -x, explicit path. The claimed order is a lower bound here: conservative
// problems may show one order more in x.
TEST_P(ConservativeProblem, ReachesAtLeastTheClaimedOrderInPositionAndVelocity) {
  const SetCase& c = GetParam();
  Harmonic prob;
  RunOptions opt;
  opt.method = c.method;
  const Orders o = MeasureOrders(prob, opt, c.hmax);
  Report("x'' = -x", c.method, o, c.hmax);
  EXPECT_GT(o.ex.back(), kRoundoffFloor);
  EXPECT_GT(o.ev.back(), kRoundoffFloor);
  EXPECT_GE(o.x, c.claimed - kOrderTol);
  EXPECT_GE(o.v, c.claimed - kOrderTol);
}

INSTANTIATE_TEST_SUITE_P(NamedSets, ConservativeProblem, ::testing::ValuesIn(kSets),
                         [](const ::testing::TestParamInfo<SetCase>& info) {
                           return std::string(info.param.label);
                         });

class VelocityDependentProblem : public ::testing::TestWithParam<SetCase> {};

// Damped forced oscillator on the implicit path (Newton + dense, DQ Jacobian)
// from x(0) = 1, x'(0) = 0.5: its initial jerk is -2.7, so a degree-4 or -5
// method only keeps its order with the consistent start.
TEST_P(VelocityDependentProblem, ReachesItsOrderInPositionAndVelocity) {
  const SetCase& c = GetParam();
  DampedForced prob;
  RunOptions opt;
  opt.method = c.method;
  opt.implicit = true;
  const Orders o = MeasureOrders(prob, opt, c.hmax);
  Report("damped forced, implicit", c.method, o, c.hmax);
  EXPECT_GT(o.ex.back(), kRoundoffFloor);
  EXPECT_GT(o.ev.back(), kRoundoffFloor);
  EXPECT_GE(o.x, c.claimed - kOrderTol);
  EXPECT_GE(o.v, c.claimed - kOrderTol);
  if (c.observed > 0) {
    EXPECT_NEAR(o.x, c.observed, kOrderTol);
    EXPECT_NEAR(o.v, c.observed, kOrderTol);
  }
}

INSTANTIATE_TEST_SUITE_P(NamedSets, VelocityDependentProblem, ::testing::ValuesIn(kSets),
                         [](const ::testing::TestParamInfo<SetCase>& info) {
                           return std::string(info.param.label);
                         });

class PapersZeroStart : public ::testing::TestWithParam<const char*> {};

// The paper's zero start sets the initial jerk (and x^(4)) to zero. On a problem
// whose initial jerk is -2.7 that wrong history is never forgotten and the order
// falls to 2; the same runs with the default consistent start keep order >= 3.
TEST_P(PapersZeroStart, DropsAHigherDegreeSetToSecondOrderWhenTheInitialJerkIsNotZero) {
  DampedForced prob;
  RunOptions opt;
  opt.method = GetParam();
  opt.implicit = true;
  opt.zero_start = true;
  const double hmax = 0.04;
  const Orders zero = MeasureOrders(prob, opt, hmax);
  Report("damped forced, zero start", opt.method, zero, hmax);
  opt.zero_start = false;
  const Orders consistent = MeasureOrders(prob, opt, hmax);
  EXPECT_NEAR(zero.x, 2, 0.15);
  EXPECT_NEAR(zero.v, 2, 0.15);
  EXPECT_GE(consistent.x, 3 - kOrderTol);
  EXPECT_GE(consistent.v, 3 - kOrderTol);
  // The gap grows like 1/h; at h = 0.0025 the zero start is measured 25 to 130
  // times less accurate in x.
  EXPECT_GT(zero.ex.back(), 10 * consistent.ex.back());
}

INSTANTIATE_TEST_SUITE_P(HigherDegreeSets, PapersZeroStart,
                         ::testing::Values("G4_A34", "G4_A14", "G5"),
                         [](const ::testing::TestParamInfo<const char*>& info) {
                           return std::string(info.param);
                         });

}  // namespace
