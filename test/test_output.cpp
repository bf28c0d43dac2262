// Output: dense output between steps, one-step mode, stop time, step limit and
// the statistics printout.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "test_util.hpp"

namespace {

using ceode_test::Context;
using ceode_test::ConvergenceSteps;
using ceode_test::DampedForced;
using ceode_test::FitOrder;
using ceode_test::Harmonic;
using ceode_test::Mem;
using ceode_test::RunExact;
using ceode_test::RunOptions;
using ceode_test::RunResult;
using ceode_test::SerialVector;
using ceode_test::Vector;

struct InterpCase {
  const char* method;
  int order;
  const char* label;
};

// Printable parameter (gtest prints it in test listings).
void PrintTo(const InterpCase& c, std::ostream* os) { *os << c.method << ", order " << c.order; }

class DenseOutput : public ::testing::TestWithParam<InterpCase> {};

// Output times 0.1234 k never fall on a step for any h of the fit, so every
// output comes from the interpolant inside a step.
TEST_P(DenseOutput, IsAccurateToTheMethodsOrderBetweenSteps) {
  const InterpCase& c = GetParam();
  DampedForced prob;
  RunOptions opt;
  opt.method = c.method;
  opt.implicit = true;
  for (int k = 1; k <= 80; ++k) opt.tout.push_back(SUN_RCONST(0.1234) * k + SUN_RCONST(1e-4));
  const std::vector<double> hs = ConvergenceSteps(0.04);
  std::vector<double> ex, ev, ex_steps;
  for (double h : hs) {
    opt.h = h;
    const RunResult r = RunExact(prob, opt);
    ASSERT_EQ(r.flag, CE_SUCCESS);
    ex.push_back(r.err_x);
    ev.push_back(r.err_v);
    RunOptions at_steps = opt;
    at_steps.tout.clear();
    ex_steps.push_back(RunExact(prob, at_steps).err_x);
  }
  const double px = FitOrder(hs, ex);
  const double pv = FitOrder(hs, ev);
  std::printf(
      "[ output   ] %-7s interpolated order x: %.3f v: %.3f; at h = %g error x %.3e "
      "(%.3e at the steps)\n",
      c.method, px, pv, hs.back(), ex.back(), ex_steps.back());
  EXPECT_GE(px, c.order - 0.1);
  EXPECT_GE(pv, c.order - 0.1);
  // The interpolant adds no error of its own worth speaking of.
  EXPECT_LE(ex.back(), 2 * ex_steps.back());
}

INSTANTIATE_TEST_SUITE_P(Sets, DenseOutput,
                         ::testing::Values(InterpCase{"G3_CD", 2, "G3CentralDifferences"},
                                           InterpCase{"G3_A2", 2, "G3AlphaTwo"},
                                           InterpCase{"G4_A34", 3, "G4AlphaThreeQuarters"},
                                           InterpCase{"G4_A14", 3, "G4AlphaOneQuarter"},
                                           InterpCase{"G5", 3, "G5"}),
                         [](const ::testing::TestParamInfo<InterpCase>& info) {
                           return info.param.label;
                         });

// A harmonic run on the explicit path with h = 0.01.
class HarmonicRun : public ::testing::Test {
 protected:
  void SetUp() override {
    x_ = SerialVector(1, ctx_, prob_.x0);
    v_ = SerialVector(1, ctx_, prob_.v0);
    mem_.reset(CEodeCreate(ctx_));
    ASSERT_EQ(CEodeInit(mem(), Harmonic::F, 0, x_.get(), v_.get()), CE_SUCCESS);
    ASSERT_EQ(CEodeSetUserData(mem(), &prob_), CE_SUCCESS);
    ASSERT_EQ(CEodeSetMethodByName(mem(), "G4_A34"), CE_SUCCESS);
    ASSERT_EQ(CEodeSetFixedStep(mem(), SUN_RCONST(0.01)), CE_SUCCESS);
    ASSERT_EQ(CEodeSetErrFile(mem(), nullptr), CE_SUCCESS);
    ASSERT_EQ(CEodeSetStabilityGuard(mem(), CE_GUARD_OFF, 0), CE_SUCCESS);  // slow under ASan
  }
  void* mem() { return mem_.get(); }
  int Evolve(sunrealtype tout, sunrealtype* t, int itask = CE_NORMAL) {
    return CEodeEvolve(mem(), tout, x_.get(), v_.get(), t, itask);
  }
  sunrealtype X() const { return NV_Ith_S(x_.get(), 0); }
  sunrealtype V() const { return NV_Ith_S(v_.get(), 0); }

  Context ctx_;
  Harmonic prob_;
  Vector x_, v_;
  Mem mem_;
};

TEST_F(HarmonicRun, OneStepModeReturnsEveryStepWithTheSameValuesAsNormalMode) {
  std::vector<sunrealtype> xs, vs;
  sunrealtype t = 0;
  for (int k = 1; k <= 50; ++k) {
    ASSERT_EQ(Evolve(10, &t, CE_ONE_STEP), CE_SUCCESS);
    EXPECT_NEAR(t, 0.01 * k, 1e-14);
    xs.push_back(X());
    vs.push_back(V());
  }
  long int nst = 0;
  CEodeGetNumSteps(mem(), &nst);
  EXPECT_EQ(nst, 50);
  // Normal mode on the step grid returns the method's own values, not interpolated ones.
  Vector x0 = SerialVector(1, ctx_, prob_.x0);
  Vector v0 = SerialVector(1, ctx_, prob_.v0);
  ASSERT_EQ(CEodeReInit(mem(), 0, x0.get(), v0.get()), CE_SUCCESS);
  for (int k : {7, 20, 50}) {
    ASSERT_EQ(Evolve(SUN_RCONST(0.01) * k, &t), CE_SUCCESS);
    EXPECT_EQ(X(), xs[k - 1]) << k;
    EXPECT_EQ(V(), vs[k - 1]) << k;
  }
}

// n independent springs x_i'' = -(1 + i/n) x_i: large enough (n = 2000) for the in-place update.
int SpringChain(sunrealtype /*t*/, N_Vector x, N_Vector /*v*/, N_Vector a, void* /*data*/) {
  const sunindextype n = N_VGetLength(x);
  const sunrealtype* xp = N_VGetArrayPointer(x);
  sunrealtype* ap = N_VGetArrayPointer(a);
  for (sunindextype i = 0; i < n; ++i) {
    ap[i] = -(1 + static_cast<sunrealtype>(i) / static_cast<sunrealtype>(n)) * xp[i];
  }
  return 0;
}

// States after k steps of h = 1e-3: every CE_ONE_STEP return (tret, x, v), or CE_NORMAL returns
// at the given step counts.
struct ChainStates {
  std::vector<sunrealtype> t;
  std::vector<std::vector<sunrealtype>> x, v;
};
ChainStates RunChain(const char* method, int itask, const std::vector<int>& outputs) {
  constexpr sunindextype kN = 2000;
  constexpr sunrealtype kH = SUN_RCONST(1e-3);
  Context ctx;
  Vector x = SerialVector(kN, ctx, 1);
  Vector v = SerialVector(kN, ctx, 0);
  Mem mem(CEodeCreate(ctx));
  ChainStates s;
  if (CEodeInit(mem.get(), SpringChain, 0, x.get(), v.get()) != CE_SUCCESS ||
      CEodeSetMethodByName(mem.get(), method) != CE_SUCCESS ||
      CEodeSetFixedStep(mem.get(), kH) != CE_SUCCESS ||
      CEodeSetStabilityGuard(mem.get(), CE_GUARD_OFF, 0) != CE_SUCCESS) {
    return s;
  }
  const auto keep = [&](sunrealtype t) {
    const sunrealtype* xp = N_VGetArrayPointer(x.get());
    const sunrealtype* vp = N_VGetArrayPointer(v.get());
    s.t.push_back(t);
    s.x.emplace_back(xp, xp + kN);
    s.v.emplace_back(vp, vp + kN);
  };
  sunrealtype t = 0;
  for (int k : outputs) {
    const sunrealtype tout = itask == CE_NORMAL ? kH * k : 1;
    if (CEodeEvolve(mem.get(), tout, x.get(), v.get(), &t, itask) != CE_SUCCESS) return s;
    keep(t);
  }
  return s;
}

// The direct one-step call (the step and both outputs in one function) returns at each step the
// step's own state, bit for bit what CE_NORMAL returns at that step (the lean loop, in-place
// update), and the step grid's time, for sets of degree 3, 4 and 8.
TEST(OneStepMode, ReturnsBitwiseTheStatesOfNormalModeOnALargeSystem) {
  for (const char* method : {"G3_CD", "G4_A34", "G8_O8"}) {
    std::vector<int> every(40);
    for (int k = 0; k < 40; ++k) every[k] = k + 1;
    const ChainStates one = RunChain(method, CE_ONE_STEP, every);
    const ChainStates normal = RunChain(method, CE_NORMAL, {7, 20, 40});
    ASSERT_EQ(one.t.size(), 40U) << method;
    ASSERT_EQ(normal.t.size(), 3U) << method;
    const int steps[] = {7, 20, 40};
    for (int j = 0; j < 3; ++j) {
      const int k = steps[j] - 1;
      EXPECT_EQ(one.t[k], normal.t[j]) << method << " step " << k + 1;
      EXPECT_TRUE(one.x[k] == normal.x[j]) << method << " step " << k + 1;
      EXPECT_TRUE(one.v[k] == normal.v[j]) << method << " step " << k + 1;
    }
  }
}

// One call, one step, wherever t is: t0 = 4499.9 and -4500.1 with h = 0.01 cross |t| = 4.5e5 h,
// the edge of the span where the call tests no grid (the grid's times there are exact to 2.5e-10 h,
// the tolerance 1e-8 h); every return is the grid's time t0 + k h and the states are CE_NORMAL's
// on the same grid bit for bit.
TEST_F(HarmonicRun, OneStepModeTakesOneStepPerCallAcrossTheDirectSpan) {
  for (const sunrealtype t0 : {SUN_RCONST(4499.9), SUN_RCONST(-4500.1)}) {
    std::vector<sunrealtype> xs, vs;
    for (const int itask : {CE_ONE_STEP, CE_NORMAL}) {
      Vector x0 = SerialVector(1, ctx_, prob_.x0);
      Vector v0 = SerialVector(1, ctx_, prob_.v0);
      ASSERT_EQ(CEodeReInit(mem(), t0, x0.get(), v0.get()), CE_SUCCESS);
      sunrealtype t = t0;
      for (int k = 1; k <= 30; ++k) {
        const sunrealtype tk = t0 + static_cast<sunrealtype>(k) * SUN_RCONST(0.01);  // the grid's
        ASSERT_EQ(Evolve(itask == CE_ONE_STEP ? t0 + 1 : tk, &t, itask), CE_SUCCESS);
        EXPECT_EQ(t, tk) << "t0 " << t0 << " step " << k;
        if (itask == CE_ONE_STEP) {
          xs.push_back(X());
          vs.push_back(V());
        } else {
          EXPECT_EQ(X(), xs[k - 1]) << "t0 " << t0 << " step " << k;
          EXPECT_EQ(V(), vs[k - 1]) << "t0 " << t0 << " step " << k;
        }
      }
      long int nst = 0;
      CEodeGetNumSteps(mem(), &nst);
      EXPECT_EQ(nst, 30) << "t0 " << t0;
    }
  }
}

// User data set between one-step calls reaches f at the next step: a switch to another problem
// record (w = 2) after 20 steps gives bit for bit the run in which the record f already reads
// changes to w = 2 at that point; had the steps kept the old record, they would go on at w = 1.
TEST_F(HarmonicRun, UserDataSetBetweenOneStepCallsReachesFAtTheNextStep) {
  Harmonic other = prob_;
  other.w = 2;
  std::vector<sunrealtype> xs;
  for (const bool switch_record : {true, false}) {
    prob_.w = 1;
    ASSERT_EQ(CEodeSetUserData(mem(), &prob_), CE_SUCCESS);
    Vector x0 = SerialVector(1, ctx_, prob_.x0);
    Vector v0 = SerialVector(1, ctx_, prob_.v0);
    ASSERT_EQ(CEodeReInit(mem(), 0, x0.get(), v0.get()), CE_SUCCESS);
    sunrealtype t = 0;
    for (int k = 1; k <= 40; ++k) {
      if (k == 21 && switch_record) ASSERT_EQ(CEodeSetUserData(mem(), &other), CE_SUCCESS);
      if (k == 21 && !switch_record) prob_.w = 2;
      ASSERT_EQ(Evolve(10, &t, CE_ONE_STEP), CE_SUCCESS);
      if (switch_record) {
        xs.push_back(X());
      } else {
        EXPECT_EQ(X(), xs[k - 1]) << "step " << k;
      }
    }
  }
  prob_.w = 1;
}

// g = t - 0.2537: a root inside the step from 0.25 to 0.26.
int RootInStep(sunrealtype t, N_Vector /*x*/, N_Vector /*v*/, sunrealtype* g, void* /*data*/) {
  g[0] = t - SUN_RCONST(0.2537);
  return 0;
}

// After a few one-step calls (those on the grid need no test of their own), a stop time and then
// a root function set between calls take effect at the next call: the call whose step passes the
// stop time 0.1537 returns it exactly with CE_TSTOP_RETURN, and with the stop time cleared the
// call whose interval holds the root returns it with CE_ROOT_RETURN (to the root finder's
// tolerance, 1e-10 here), each after exactly the steps of the grid (h = 0.01) before it.
TEST_F(HarmonicRun, OneStepModeHonoursAStopTimeAndRootsSetBetweenCalls) {
  sunrealtype t = 0;
  for (int k = 1; k <= 10; ++k) ASSERT_EQ(Evolve(10, &t, CE_ONE_STEP), CE_SUCCESS);
  ASSERT_EQ(CEodeSetStopTime(mem(), SUN_RCONST(0.1537)), CE_SUCCESS);
  for (int k = 11; k <= 15; ++k) {
    ASSERT_EQ(Evolve(10, &t, CE_ONE_STEP), CE_SUCCESS) << "call " << k;
    EXPECT_NEAR(t, 0.01 * k, 1e-14) << "call " << k;
  }
  EXPECT_EQ(Evolve(10, &t, CE_ONE_STEP), CE_TSTOP_RETURN);
  EXPECT_EQ(t, SUN_RCONST(0.1537));
  ASSERT_EQ(CEodeClearStopTime(mem()), CE_SUCCESS);
  for (int k = 17; k <= 20; ++k) ASSERT_EQ(Evolve(10, &t, CE_ONE_STEP), CE_SUCCESS);
  ASSERT_EQ(CEodeRootInit(mem(), 1, RootInStep), CE_SUCCESS);
  int flag = CE_SUCCESS;
  int calls = 0;
  while (flag == CE_SUCCESS && calls < 20) {
    flag = Evolve(10, &t, CE_ONE_STEP);
    ++calls;
  }
  EXPECT_EQ(flag, CE_ROOT_RETURN);
  EXPECT_NEAR(t, 0.2537, 1e-10);
  long int nst = 0;
  CEodeGetNumSteps(mem(), &nst);
  EXPECT_EQ(nst, 25);  // to t = 0.25: the roots of [0.25, 0.26] are found before its step
}

// h = 1e-9 at t = 1e6 lies below the grid tolerance of t's round-off (64 units, 7.5e-9): every
// CE_ONE_STEP call takes exactly one step, the first (with the start) too, and a CE_NORMAL call
// 100 steps ahead takes 100.
TEST_F(HarmonicRun, OneStepModeTakesOneStepPerCallBelowTheRoundOffOfT) {
  Vector x0 = SerialVector(1, ctx_, prob_.x0);
  Vector v0 = SerialVector(1, ctx_, prob_.v0);
  const sunrealtype t0 = SUN_RCONST(1e6);
  const sunrealtype h = SUN_RCONST(1e-9);
  ASSERT_EQ(CEodeReInit(mem(), t0, x0.get(), v0.get()), CE_SUCCESS);
  ASSERT_EQ(CEodeSetFixedStep(mem(), h), CE_SUCCESS);
  sunrealtype t = 0;
  ASSERT_EQ(Evolve(t0 + 100 * h, &t, CE_NORMAL), CE_SUCCESS);
  long int nst0 = 0;
  CEodeGetNumSteps(mem(), &nst0);
  EXPECT_EQ(nst0, 100);
  ASSERT_EQ(CEodeReInit(mem(), t0, x0.get(), v0.get()), CE_SUCCESS);
  ASSERT_EQ(Evolve(2e6, &t, CE_ONE_STEP), CE_SUCCESS);  // the start and one step
  CEodeGetNumSteps(mem(), &nst0);
  EXPECT_EQ(nst0, 1);
  for (int k = 1; k <= 30; ++k) {
    const sunrealtype tlast = t;
    ASSERT_EQ(Evolve(2e6, &t, CE_ONE_STEP), CE_SUCCESS);
    EXPECT_GT(t, tlast) << "call " << k;
    long int nst = 0;
    CEodeGetNumSteps(mem(), &nst);
    EXPECT_EQ(nst, nst0 + k) << "call " << k;
  }
}

TEST_F(HarmonicRun, StopTimeIsHitExactlyAndReturnsTstopReturn) {
  ASSERT_EQ(CEodeSetStopTime(mem(), SUN_RCONST(0.377)), CE_SUCCESS);
  sunrealtype t = 0;
  EXPECT_EQ(Evolve(1, &t), CE_TSTOP_RETURN);
  EXPECT_EQ(t, SUN_RCONST(0.377));
  sunrealtype xe = 0, ve = 0;
  prob_.Exact(t, &xe, &ve);
  // From the interpolant: within the 10 s run's max error at this h (4e-7, third order).
  EXPECT_NEAR(X(), xe, 1e-6);
  EXPECT_NEAR(V(), ve, 1e-6);
  long int nst = 0;
  CEodeGetNumSteps(mem(), &nst);
  EXPECT_EQ(nst, 37);  // no step beyond what tstop needs
  // The stop time is used up: the run continues to tout.
  EXPECT_EQ(Evolve(1, &t), CE_SUCCESS);
  EXPECT_EQ(t, 1);
  // One-step mode stops at tstop too.
  ASSERT_EQ(CEodeSetStopTime(mem(), SUN_RCONST(1.005)), CE_SUCCESS);
  EXPECT_EQ(Evolve(2, &t, CE_ONE_STEP), CE_TSTOP_RETURN);
  EXPECT_EQ(t, SUN_RCONST(1.005));
}

// Far from t = 0 a time on the step grid and the user's stop time differ by round-off larger than
// 1e-8 h (at t = 1e8 one unit in the last place is 1.5e-6 h): the last step is still taken and
// its own values are returned, as at the same step without a stop time.
TEST_F(HarmonicRun, AStopTimeOneRoundingOffTheStepGridEndsOnTheMethodsOwnStep) {
  const sunrealtype t0 = SUN_RCONST(1e8);
  const sunrealtype h = SUN_RCONST(0.01);
  for (int itask : {CE_ONE_STEP, CE_NORMAL}) {
    for (sunrealtype dir : {-1e9, 1e9}) {
      Vector x0 = SerialVector(1, ctx_, prob_.x0);
      Vector v0 = SerialVector(1, ctx_, prob_.v0);
      // Without a stop time: the method's own state after 37 steps.
      ASSERT_EQ(CEodeReInit(mem(), t0, x0.get(), v0.get()), CE_SUCCESS);
      sunrealtype t = 0;
      for (int k = 0; k < 37; ++k) ASSERT_EQ(Evolve(t0 + 1, &t, CE_ONE_STEP), CE_SUCCESS);
      const sunrealtype x37 = X();
      const sunrealtype v37 = V();
      ASSERT_EQ(CEodeReInit(mem(), t0, x0.get(), v0.get()), CE_SUCCESS);
      const sunrealtype tstop = std::nextafter(t0 + 37 * h, dir);
      ASSERT_EQ(CEodeSetStopTime(mem(), tstop), CE_SUCCESS);
      int flag = CE_SUCCESS;
      for (int k = 0; k < 100 && flag == CE_SUCCESS; ++k) flag = Evolve(t0 + 1, &t, itask);
      EXPECT_EQ(flag, CE_TSTOP_RETURN);
      EXPECT_EQ(t, tstop);
      long int nst = 0;
      CEodeGetNumSteps(mem(), &nst);
      EXPECT_EQ(nst, 37) << "itask " << itask << ", tstop " << (dir < 0 ? "below" : "above");
      EXPECT_EQ(X(), x37);
      EXPECT_EQ(V(), v37);
    }
  }
}

TEST_F(HarmonicRun, StepLimitGivesTooMuchWorkAndTheRunCanContinue) {
  ASSERT_EQ(CEodeSetMaxNumSteps(mem(), 30), CE_SUCCESS);
  sunrealtype t = 0;
  EXPECT_EQ(Evolve(1, &t), CE_TOO_MUCH_WORK);
  EXPECT_NEAR(t, 0.3, 1e-14);
  const char* msg = nullptr;
  ASSERT_EQ(CEodeGetLastErrorMessage(mem(), &msg), CE_SUCCESS);
  EXPECT_NE(std::string(msg).find("CEodeSetMaxNumSteps"), std::string::npos) << msg;
  EXPECT_TRUE(std::isfinite(X()));
  // The limit counts per call: each call makes 30 more steps.
  EXPECT_EQ(Evolve(1, &t), CE_TOO_MUCH_WORK);
  EXPECT_NEAR(t, 0.6, 1e-14);
  ASSERT_EQ(CEodeSetMaxNumSteps(mem(), 0), CE_SUCCESS);  // back to the default
  EXPECT_EQ(Evolve(1, &t), CE_SUCCESS);
  EXPECT_EQ(t, 1);
  // The interruptions changed nothing: the same state as one uninterrupted run.
  const sunrealtype x_interrupted = X();
  const sunrealtype v_interrupted = V();
  Vector x0 = SerialVector(1, ctx_, prob_.x0);
  Vector v0 = SerialVector(1, ctx_, prob_.v0);
  ASSERT_EQ(CEodeReInit(mem(), 0, x0.get(), v0.get()), CE_SUCCESS);
  EXPECT_EQ(Evolve(1, &t), CE_SUCCESS);
  EXPECT_EQ(X(), x_interrupted);
  EXPECT_EQ(V(), v_interrupted);
}

std::string ReadAll(std::FILE* f) {
  std::string s;
  std::rewind(f);
  char buf[512];
  size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof(buf), f)) > 0) s.append(buf, n);
  return s;
}

TEST_F(HarmonicRun, PrintAllStatsWritesATableAndACsvLine) {
  sunrealtype t = 0;
  ASSERT_EQ(Evolve(1, &t), CE_SUCCESS);
  long int nst = 0, nfe = 0;
  CEodeGetNumSteps(mem(), &nst);
  CEodeGetNumRhsEvals(mem(), &nfe);
  ASSERT_EQ(nst, 100);

  std::FILE* table = std::tmpfile();
  ASSERT_NE(table, nullptr);
  EXPECT_EQ(CEodePrintAllStats(mem(), table, SUN_OUTPUTFORMAT_TABLE), CE_SUCCESS);
  const std::string tab = ReadAll(table);
  std::fclose(table);
  EXPECT_NE(tab.find("Method"), std::string::npos) << tab;
  EXPECT_NE(tab.find("G4_A34"), std::string::npos) << tab;
  EXPECT_NE(tab.find("Steps"), std::string::npos) << tab;
  EXPECT_NE(tab.find("= 100\n"), std::string::npos) << tab;
  EXPECT_NE(tab.find("= " + std::to_string(nfe) + "\n"), std::string::npos) << tab;
  EXPECT_GE(std::count(tab.begin(), tab.end(), '\n'), 10);

  std::FILE* csv = std::tmpfile();
  ASSERT_NE(csv, nullptr);
  EXPECT_EQ(CEodePrintAllStats(mem(), csv, SUN_OUTPUTFORMAT_CSV), CE_SUCCESS);
  const std::string line = ReadAll(csv);
  std::fclose(csv);
  EXPECT_EQ(std::count(line.begin(), line.end(), '\n'), 1) << line;
  EXPECT_EQ(line.rfind("Method,G4_A34,", 0), 0u) << line;
  EXPECT_NE(line.find(",Steps,100,"), std::string::npos) << line;
  EXPECT_NE(line.find(",RHS fn evals," + std::to_string(nfe) + ","), std::string::npos) << line;
  // Name,value pairs: an odd number of commas.
  EXPECT_EQ(std::count(line.begin(), line.end(), ',') % 2, 1) << line;

  EXPECT_EQ(CEodePrintAllStats(mem(), nullptr, SUN_OUTPUTFORMAT_TABLE), CE_ILL_INPUT);
}

}  // namespace
