// The prediction-correction mode of the implicit step (CE_IMPLICIT_PC, P(EC)^k), the automatic
// choice between it and Newton (CE_IMPLICIT_AUTO), the Newton matrix's reuse on the ODE path and
// the start's check for an undeclared velocity dependence (docs/theory.md section 4.3).
// Reference: the closed-form solution of the damped forced oscillator (test_util.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "test_util.hpp"

namespace {

using ceode_test::Context;
using ceode_test::ConvergenceSteps;
using ceode_test::DampedForced;
using ceode_test::ExactProblem;
using ceode_test::FitOrder;
using ceode_test::Harmonic;
using ceode_test::LinearSolver;
using ceode_test::Matrix;
using ceode_test::Mem;
using ceode_test::SerialVector;
using ceode_test::Vector;

struct Config {
  std::string method = "G3_CD";
  sunrealtype h = SUN_RCONST(0.01);
  sunrealtype tend = 10;
  int mode = CE_IMPLICIT_NEWTON;
  int corrections = 0;
  int vel = SUNTRUE;  // CEodeSetVelocityDependence's argument; -1: never called
  long int msbj = 0;  // 0: default
};

struct Run {
  int flag = CE_SUCCESS;
  double err_x = 0, err_v = 0;
  std::vector<double> x, v;  // at every step
  long int nst = 0, nfe = 0, npc = 0, nnls = 0, nfe_coupling = 0, nje = 0, nsetups = 0;
  sunrealtype coupling = 0;
  std::vector<std::string> warnings;
};

void CollectWarnings(int code, const char*, const char*, char* msg, void* data) {
  if (code == CE_WARNING) static_cast<std::vector<std::string>*>(data)->push_back(msg);
}

// Newton with a dense matrix and difference-quotient Jacobian is attached in every mode, so that
// the runs differ only in the mode.
Run Integrate(const ExactProblem& prob, const Config& c) {
  Run r;
  Context ctx;
  Vector x = SerialVector(1, ctx, prob.x0);
  Vector v = SerialVector(1, ctx, prob.v0);
  Matrix A(SUNDenseMatrix(1, 1, ctx));
  LinearSolver LS(SUNLinSol_Dense(x.get(), A.get(), ctx));
  Mem mem(CEodeCreate(ctx));
  auto fail = [&r](int flag) {
    if (flag < 0 && r.flag == CE_SUCCESS) r.flag = flag;
    return flag < 0;
  };
  if (fail(CEodeInit(mem.get(), prob.Rhs(), 0, x.get(), v.get())) ||
      fail(CEodeSetUserData(mem.get(), const_cast<ExactProblem*>(&prob))) ||
      fail(CEodeSetErrHandlerFn(mem.get(), CollectWarnings, &r.warnings)) ||
      fail(CEodeSetMethodByName(mem.get(), c.method.c_str())) ||
      fail(CEodeSetFixedStep(mem.get(), c.h)) ||
      fail(CEodeSetStabilityGuard(mem.get(), CE_GUARD_OFF, 0)) ||
      fail(CEodeSetLinearSolver(mem.get(), LS.get(), A.get())) ||
      fail(CEodeSetImplicitMode(mem.get(), c.mode)) ||
      fail(CEodeSetPCCorrections(mem.get(), c.corrections)) ||
      (c.msbj > 0 && fail(CEodeSetJacEvalFrequency(mem.get(), c.msbj))) ||
      (c.vel >= 0 && fail(CEodeSetVelocityDependence(mem.get(), c.vel)))) {
    return r;
  }
  const long int nsteps = std::lround(c.tend / c.h);
  sunrealtype t = 0;
  for (long int i = 0; i < nsteps; ++i) {
    if (fail(CEodeEvolve(mem.get(), c.tend, x.get(), v.get(), &t, CE_ONE_STEP))) return r;
    sunrealtype xe = 0, ve = 0;
    prob.Exact(t, &xe, &ve);
    r.x.push_back(NV_Ith_S(x.get(), 0));
    r.v.push_back(NV_Ith_S(v.get(), 0));
    r.err_x = std::max(r.err_x, std::fabs(r.x.back() - xe));
    r.err_v = std::max(r.err_v, std::fabs(r.v.back() - ve));
  }
  CEodeGetNumSteps(mem.get(), &r.nst);
  CEodeGetNumRhsEvals(mem.get(), &r.nfe);
  CEodeGetNumJacEvals(mem.get(), &r.nje);
  CEodeGetNumLinSolvSetups(mem.get(), &r.nsetups);
  CEodeGetImplicitStats(mem.get(), &r.npc, &r.nnls, &r.nfe_coupling, &r.coupling);
  return r;
}

double MaxDiff(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return INFINITY;
  double d = 0;
  for (size_t i = 0; i < a.size(); ++i) d = std::max(d, std::fabs(a[i] - b[i]));
  return d;
}

// ---------------------------------------------------------------------------
// Orders of the PC mode against Newton's.

struct SetCase {
  const char* method;
  int corrections;  // k of P(EC)^k (0: the default for the degree)
  double order;     // measured order of the Newton path (test_convergence)
  double hmax;      // largest step of the fit (as test_convergence)
  const char* label;
};

void PrintTo(const SetCase& c, std::ostream* os) {
  *os << c.method << ", k = " << c.corrections << ", order " << c.order;
}

const SetCase kSets[] = {
    {"G3_CD", 1, 2, 0.04, "CentralDifferencesWithOneCorrection"},
    {"G3_A2", 1, 2, 0.04, "G3AlphaTwoWithOneCorrection"},
    {"G4_A34", 1, 3, 0.04, "G4AlphaThreeQuartersWithOneCorrection"},
    {"G4_A14", 2, 3, 0.04, "G4AlphaOneQuarterWithTwoCorrections"},
    {"G5", 1, 4, 0.08, "G5WithOneCorrection"},
    {"G5_ONES", 2, 4, 0.08, "G5OnesWithTwoCorrections"},
};

constexpr double kOrderTol = 0.1;  // as test_convergence: a lost order moves a slope by 1

struct Fit {
  double x = 0, v = 0, diff_x = 0, diff_v = 0;
  std::vector<double> ex, ev, dx, dv;
};

Fit FitBothModes(const SetCase& c) {
  Fit f;
  DampedForced prob;  // x(0) = 1, x'(0) = 0.5: initial jerk -2.7
  const std::vector<double> hs = ConvergenceSteps(c.hmax);
  for (double h : hs) {
    Config cfg;
    cfg.method = c.method;
    cfg.h = h;
    const Run newton = Integrate(prob, cfg);
    cfg.mode = CE_IMPLICIT_PC;
    cfg.corrections = c.corrections;
    const Run pc = Integrate(prob, cfg);
    EXPECT_EQ(newton.flag, CE_SUCCESS);
    EXPECT_EQ(pc.flag, CE_SUCCESS);
    EXPECT_EQ(pc.npc, pc.nst);  // every step by prediction-correction
    EXPECT_EQ(pc.nnls, 0);
    f.ex.push_back(pc.err_x);
    f.ev.push_back(pc.err_v);
    f.dx.push_back(MaxDiff(pc.x, newton.x));
    f.dv.push_back(MaxDiff(pc.v, newton.v));
    std::printf(
        "[ pc       ] %-7s k=%d h=%-8g err x %.3e (Newton %.3e)  v %.3e (%.3e)  "
        "|pc-newton| x %.3e v %.3e\n",
        c.method, c.corrections, h, pc.err_x, newton.err_x, pc.err_v, newton.err_v, f.dx.back(),
        f.dv.back());
  }
  f.x = FitOrder(hs, f.ex);
  f.v = FitOrder(hs, f.ev);
  f.diff_x = FitOrder(hs, f.dx);
  f.diff_v = FitOrder(hs, f.dv);
  return f;
}

class PredictorCorrector : public ::testing::TestWithParam<SetCase> {};

// Consistent start, initial jerk -2.7: the fitted orders in x and x' are Newton's.
TEST_P(PredictorCorrector, KeepsTheOrderOfTheNewtonPathInPositionAndVelocity) {
  const SetCase& c = GetParam();
  const Fit f = FitBothModes(c);
  std::printf("[ pc order ] %-7s k=%d  x: %.3f  v: %.3f  |pc-newton| x: %.3f v: %.3f\n", c.method,
              c.corrections, f.x, f.v, f.diff_x, f.diff_v);
  EXPECT_GT(f.ex.back(), 1e-11);  // above round-off, or the fit measures noise
  EXPECT_NEAR(f.x, c.order, kOrderTol);
  EXPECT_NEAR(f.v, c.order, kOrderTol);
  // The two answers differ by a term of the method's order (or higher), not by a lower one.
  EXPECT_GE(f.diff_x, c.order - kOrderTol);
  EXPECT_GE(f.diff_v, c.order - kOrderTol);
}

INSTANTIATE_TEST_SUITE_P(NamedSets, PredictorCorrector, ::testing::ValuesIn(kSets),
                         [](const ::testing::TestParamInfo<SetCase>& info) {
                           return std::string(info.param.label);
                         });

}  // namespace
