// The benchmark harness (bench/wp_common.h), on which every ratio in docs/results.md rests: the
// equal-error rule (TimeAtError: log time interpolated linearly in log error), the repetition
// plan and median of TimeMedian, the interleaved rounds of the FE scenes (wp::Rounds), and the
// one problem description: its lifts to CEODE's and the first-order form, and the runners'
// two modes on x'' = -x. The timed functions spin on the harness's own clock (process CPU time)
// for a set time, so the number of calls each rule makes is known in advance.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "wp_common.h"

namespace {

wp::Row MakeRow(const std::string& solver, double error, double seconds) {
  wp::Row r;
  r.solver = solver;
  r.config = "c";
  r.error = error;
  r.seconds = seconds;
  r.steps = 1;
  return r;
}

// Busy for `seconds` of the harness's clock (a sleep would not count: the clock is CPU time).
void Spin(double seconds) {
  const double t0 = wp::Now();
  volatile double sink = 0;
  while (wp::Now() - t0 < seconds) sink = sink + 1;
}

TEST(TimeAtError, InterpolatesLogTimeLinearlyInLogErrorBetweenTwoPoints) {
  const std::vector<wp::Row> rows = {MakeRow("A", 1e-2, 1.0), MakeRow("A", 1e-4, 100.0)};
  // Half way in log error between 1e-2 and 1e-4 is half way in log time between 1 and 100.
  EXPECT_NEAR(wp::TimeAtError(rows, "A", "c", 1e-3), 10.0, 1e-12);
  EXPECT_NEAR(wp::TimeAtError(rows, "A", "c", 1e-4), 100.0, 1e-12);
}

TEST(TimeAtError, TakesTheCheapestCrossingOnANonMonotoneCurveAndNeverExtrapolates) {
  // A non-monotone curve: the second point already reaches 1e-5, more cheaply than the third.
  const std::vector<wp::Row> rows = {MakeRow("A", 1e-3, 1.0), MakeRow("A", 1e-6, 2.0),
                                     MakeRow("A", 1e-5, 3.0), MakeRow("B", 1e-9, 0.1)};
  EXPECT_NEAR(wp::TimeAtError(rows, "A", "c", 1e-5), std::exp(std::log(2.0) * 2.0 / 3.0), 1e-12);
  EXPECT_LT(wp::TimeAtError(rows, "A", "c", 1e-7), 0);  // never reached: no extrapolation
  EXPECT_NEAR(wp::TimeAtError(rows, "B", "c", 1e-3), 0.1, 0);
}

TEST(PlanReps, RepeatsShortRunsUntilARepetitionFillsTheMinimumTime) {
  const wp::RepPlan p = wp::PlanReps(0.01);
  EXPECT_EQ(p.calls, 5);
  EXPECT_EQ(p.reps, wp::kReps);
}

TEST(PlanReps, TimesLongRunsThreeTimesAndVeryLongRunsOnce) {
  EXPECT_EQ(wp::PlanReps(0.2).calls, 1);
  EXPECT_EQ(wp::PlanReps(0.2).reps, wp::kReps);
  EXPECT_EQ(wp::PlanReps(wp::kFewRepSeconds).reps, 3);
  EXPECT_EQ(wp::PlanReps(wp::kOneRunSeconds).reps, 0);
}

TEST(MedianOf, IsTheMiddleValueAndNaNWhenAnyValueIsNaN) {
  EXPECT_EQ(wp::MedianOf({5, 1, 4, 2, 3}), 3);
  EXPECT_TRUE(std::isnan(wp::MedianOf({1, std::nan(""), 3})));
}

TEST(TimeMedian, CallsOnceToCalibrateThenOnceARepetitionAndReportsThePerCallTime) {
  int calls = 0;
  const double t = wp::TimeMedian([&]() {
    ++calls;
    Spin(1.2 * wp::kMinRepSeconds);
    return 0;
  });
  EXPECT_EQ(calls, 1 + wp::kReps);
  EXPECT_GE(t, 1.2 * wp::kMinRepSeconds);
  EXPECT_LT(t, 3 * wp::kMinRepSeconds);  // not the sum of the repetitions
}

TEST(TimeMedian, ReportsAFailureOfAnyCallAsNegative) {
  int calls = 0;
  EXPECT_LT(wp::TimeMedian([&]() { return ++calls == 3 ? 1 : 0; }), 0);
  EXPECT_LT(wp::TimeMedian([]() { return 1; }), 0);
}

// Two configurations of one spin each, queued as "first" and "second" and timed by Run(); every
// call's id goes to log_.
class RoundsOfTwoSpins : public testing::Test {
 protected:
  RoundsOfTwoSpins() {
    for (int id : {0, 1}) {
      rounds_.Measure("S", id == 0 ? "first" : "second", id, [this, id](wp::Outcome* o) {
        log_.push_back(id);
        Spin(1.2 * wp::kMinRepSeconds);
        o->error = 1e-3 * (id + 1);
        o->steps = 10;
        return 0;
      });
    }
    queued_rows_ = table_.rows().size();
    rounds_.Run();
  }
  wp::Table table_{"harness", ""};
  wp::Rounds rounds_{&table_};
  std::vector<int> log_;
  size_t queued_rows_ = 0;  // rows before Run()
};

// The numbers run of each, then one repetition of each in every round: the timed calls alternate
// between the two (in a shuffled order per round).
TEST_F(RoundsOfTwoSpins, TimeOneRepetitionOfEveryConfigurationPerRound) {
  EXPECT_EQ(queued_rows_, 0U);  // rows come with their times, after the rounds
  ASSERT_EQ(log_.size(), 2U + 2U * wp::kReps);
  for (size_t r = 0; r < static_cast<size_t>(wp::kReps); ++r) {
    EXPECT_NE(log_[2 + 2 * r], log_[3 + 2 * r])
        << "round " << r << " timed one configuration twice";
  }
}

TEST_F(RoundsOfTwoSpins, AddRowsInQueueOrderWithTheNumbersRunsFigures) {
  ASSERT_EQ(table_.rows().size(), 2U);
  EXPECT_EQ(table_.rows()[0].config, "first");
  EXPECT_EQ(table_.rows()[1].config, "second");
  EXPECT_EQ(table_.rows()[1].error, 2e-3);
  EXPECT_EQ(table_.failures(), 0);
}

TEST_F(RoundsOfTwoSpins, ReportTheMedianSecondsOfOneCallNotTheSumOfTheRounds) {
  for (const wp::Row& row : table_.rows()) {
    EXPECT_GE(row.seconds, 1.2 * wp::kMinRepSeconds);
    EXPECT_LT(row.seconds, 3 * wp::kMinRepSeconds);
  }
}

TEST(Rounds, ReportsAFailedNumbersRunAndAFailureWhileTimingAsFailuresNotRows) {
  wp::Table table("harness", "");
  wp::Rounds rounds(&table);
  EXPECT_LT(rounds.Measure("S", "fails", 1, [](wp::Outcome*) { return 1; }), 0);
  int calls = 0;
  EXPECT_GE(rounds.Measure("S", "fails later", 2, [&calls](wp::Outcome*) { return ++calls > 3; }),
            0);
  rounds.Run();
  EXPECT_TRUE(table.rows().empty());
  EXPECT_EQ(table.failures(), 2);
}

// ---- the problem description and the runners, on x'' = -x, x(0) = 1, x'(0) = 0 ----
int Spring(double, const double* x, const double*, double* a, void* calls) {
  ++*static_cast<int*>(calls);
  a[0] = -x[0];
  return 0;
}

double SpringError(double t, const double* x, const double*, void*) {
  return std::fabs(x[0] - std::cos(t));
}

class SpringProblem : public testing::Test {
 protected:
  SpringProblem() {
    SUNContext_Create(SUN_COMM_NULL, &ctx_);
    p_.n = 1;
    p_.Lift<Spring>();
    p_.user = &calls_;
    p_.tend = 1;
    p_.x0 = {1};
    p_.v0 = {0};
    p_.err = SpringError;
  }
  ~SpringProblem() override { SUNContext_Free(&ctx_); }
  SUNContext ctx_ = nullptr;
  int calls_ = 0;
  wp::Problem p_;
};

TEST_F(SpringProblem, FirstOrderLiftCopiesTheVelocitiesAndCallsTheAccelerationOnce) {
  N_Vector y = N_VNew_Serial(2, ctx_), yd = N_VNew_Serial(2, ctx_);
  NV_Ith_S(y, 0) = 0.5;
  NV_Ith_S(y, 1) = -2.0;
  ASSERT_EQ(p_.f1(0, y, yd, p_.user), 0);
  EXPECT_EQ(NV_Ith_S(yd, 0), -2.0);
  EXPECT_EQ(NV_Ith_S(yd, 1), -0.5);
  EXPECT_EQ(calls_, 1);
  EXPECT_EQ(p_.FirstOrderStart(), (std::vector<double>{1, 0}));
  N_VDestroy(y);
  N_VDestroy(yd);
}

TEST_F(SpringProblem, CeodeLiftWritesTheAccelerationOfThePositions) {
  N_Vector x = N_VNew_Serial(1, ctx_), v = N_VNew_Serial(1, ctx_), a = N_VNew_Serial(1, ctx_);
  NV_Ith_S(x, 0) = 0.25;
  NV_Ith_S(v, 0) = 7.0;
  ASSERT_EQ(p_.f2(0, x, v, a, p_.user), 0);
  EXPECT_EQ(NV_Ith_S(a, 0), -0.25);
  for (N_Vector w : {x, v, a}) N_VDestroy(w);
}

TEST_F(SpringProblem, CeodeRunTakesTheFixedStepsAndKeepsTheLargestErrorOfEveryStep) {
  wp::Outcome o;
  ASSERT_EQ(wp::CeodeRun(ctx_, p_, "G5", 0.01, &o), 0);
  EXPECT_EQ(o.steps, 100);
  EXPECT_GT(o.error, 0);
  EXPECT_LT(o.error, 1e-8);
  EXPECT_GE(o.rhs_evals, o.steps);
}

TEST_F(SpringProblem, SundialsRunReachesTheToleranceOnTheLiftedFirstOrderForm) {
  for (wp::Sun kind : {wp::Sun::kErk, wp::Sun::kCvodeAdams, wp::Sun::kCvodeBdf,
                       wp::Sun::kArkDirk, wp::Sun::kBdfSpgmr}) {
    wp::Outcome o;
    ASSERT_EQ(wp::SundialsRun(ctx_, p_, {kind}, 1e-8, &o), 0) << wp::SunName(kind);
    EXPECT_LT(o.error, 1e-5) << wp::SunName(kind);
    EXPECT_GT(o.steps, 0) << wp::SunName(kind);
  }
}

TEST_F(SpringProblem, OutputModeRoundsTheStepToDivideEachOutputInterval) {
  p_.nout = 4;
  p_.ref = {{std::cos(0.25)}, {std::cos(0.5)}, {std::cos(0.75)}, {std::cos(1.0)}};
  EXPECT_EQ(wp::StepsPerOutput(p_, 0.1), 3);
  EXPECT_DOUBLE_EQ(wp::FixedStep(p_, 0.1), 0.25 / 3);
  wp::Outcome o;
  ASSERT_EQ(wp::CeodeRun(ctx_, p_, "G3_CD", 0.1, &o), 0);
  EXPECT_EQ(o.steps, 12);
}

TEST_F(SpringProblem, LeapfrogHandLoopIsCeodesCentralDifferencesInOutputMode) {
  p_.nout = 4;
  for (int k = 1; k <= 4; ++k) p_.ref.push_back({std::cos(0.25 * k)});
  wp::Outcome ce, hand;
  ASSERT_EQ(wp::CeodeRun(ctx_, p_, "G3_CD", 0.01, &ce), 0);
  ASSERT_EQ(wp::LeapfrogRun(p_, 0.01, [](const double* x, double* a) { a[0] = -x[0]; }, &hand), 0);
  EXPECT_EQ(hand.steps, ce.steps);
  EXPECT_NEAR(hand.error, ce.error, 1e-6 * ce.error);
}

}  // namespace
