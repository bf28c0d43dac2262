// CEODE as MRIStep's inner stepper (src/ceode_stepper.cpp): the MRI order with
// CEODE inside, agreement with an ARKStep RK4 inner stepper on a forced,
// velocity-dependent problem, counters across restarts, and bad input.
#include <arkode/arkode_arkstep.h>
#include <arkode/arkode_mristep.h>
#include <ceode/ceode_stepper.h>
#include <nvector/nvector_manyvector.h>

#ifdef CEODE_HAVE_SUNSTEPPER
#include <arkode/arkode_erkstep.h>
#include <arkode/arkode_splittingstep.h>
#endif

#include <cstring>
#include <iterator>

#include "../examples/mri_two_scale_model.h"
#include "test_util.hpp"

namespace {

using ceode_test::Context;
using ceode_test::Mem;
using ceode_test::SerialVector;
using ceode_test::Vector;

// Problem A (examples/mri_two_scale.c): x = (q, s), v = (p, w),
// q'' = -omega^2 (q - s) fast, s' = -lambda s + cos t slow; closed form in
// examples/mri_two_scale_model.h.
constexpr double kOmega = 10.0;
constexpr double kLambda = TWO_SCALE_LAMBDA;

void ExactA(double t, double* q, double* s, double* p) {
  const TwoScale model = {kOmega, 0.0, 0};
  two_scale_exact(&model, t, q, s, p);
}

int FastA(sunrealtype /*t*/, N_Vector x, N_Vector /*v*/, N_Vector f, void* /*data*/) {
  NV_Ith_S(f, 0) = -kOmega * kOmega * (NV_Ith_S(x, 0) - NV_Ith_S(x, 1));
  NV_Ith_S(f, 1) = 0;
  return 0;
}

// y is a ManyVector [x; v]: the slow part acts on s (x-part) only.
int SlowA(sunrealtype t, N_Vector y, N_Vector ydot, void* /*data*/) {
  const sunrealtype* x = N_VGetSubvectorArrayPointer_ManyVector(y, 0);
  N_VConst(0, ydot);
  N_VGetSubvectorArrayPointer_ManyVector(ydot, 0)[1] = -kLambda * x[1] + std::cos(t);
  return 0;
}

// A first-order state y = [x; v] as a ManyVector over two serial parts.
struct ManyState {
  Vector x, v, y;
  ManyState(SUNContext ctx, sunindextype n) : x(SerialVector(n, ctx)), v(SerialVector(n, ctx)) {
    N_Vector parts[2] = {x.get(), v.get()};
    y.reset(N_VNew_ManyVector(2, parts, ctx));
  }
};

struct InnerDeleter {
  void operator()(MRIStepInnerStepper s) const { CEodeFreeMRIStepInnerStepper(&s); }
};
using Inner = std::unique_ptr<std::remove_pointer_t<MRIStepInnerStepper>, InnerDeleter>;
struct ArkDeleter {
  void operator()(void* mem) const { ARKStepFree(&mem); }
};
struct MriDeleter {
  void operator()(void* mem) const { MRIStepFree(&mem); }
};

// A CEODE memory for the fast part, ready for CEodeCreateMRIStepInnerStepper.
Mem FastMemory(SUNContext ctx, CEodeRhsFn g, N_Vector x0, N_Vector v0, double h,
               const char* method = "G4_A34") {
  Mem ce(CEodeCreate(ctx));
  if (CEodeInit(ce.get(), g, 0, x0, v0) != CE_SUCCESS ||
      CEodeSetMethodByName(ce.get(), method) != CE_SUCCESS ||
      CEodeSetFixedStep(ce.get(), h) != CE_SUCCESS) {
    ce.reset();
  }
  return ce;
}

// MRI-GARK-ERK33a with nslow fixed slow steps on [0, tend]; returns MRIStepEvolve's flag.
int RunMri(SUNContext ctx, ARKRhsFn slow, MRIStepInnerStepper inner, N_Vector y, double tend,
           int nslow) {
  std::unique_ptr<void, MriDeleter> mri(MRIStepCreate(slow, nullptr, 0, y, inner, ctx));
  if (!mri) return -100;
  MRIStepCoupling C = MRIStepCoupling_LoadTable(ARKODE_MRI_GARK_ERK33a);
  int flag = MRIStepSetCoupling(mri.get(), C);
  MRIStepCoupling_Free(C);
  if (flag == 0) flag = MRIStepSetFixedStep(mri.get(), tend / nslow);
  if (flag == 0) flag = MRIStepSetMaxNumSteps(mri.get(), 100000);
  sunrealtype t = 0;
  if (flag == 0) flag = MRIStepEvolve(mri.get(), tend, y, &t, ARK_NORMAL);
  return flag;
}

struct OrderRun {
  double err;
  long nst, nrestarts, nfe_guard, nfe_start;
};

// velocity: declare (unneeded) velocity dependence, which takes the implicit path and so
// the full consistent start at every restart. tol > 0: the inner steps under error control.
OrderRun RunProblemA(SUNContext ctx, int nslow, const char* method = "G4_A34",
                     bool velocity = false, double tol = 0) {
  ManyState st(ctx, 2);
  double q, s, p;
  ExactA(0, &q, &s, &p);
  sunrealtype* x = N_VGetArrayPointer(st.x.get());
  sunrealtype* v = N_VGetArrayPointer(st.v.get());
  x[0] = q, x[1] = s, v[0] = p, v[1] = 0;
  Mem ce = FastMemory(ctx, FastA, st.x.get(), st.v.get(), 1e-3, method);
  OrderRun r{-1, 0, 0, 0, 0};
  MRIStepInnerStepper raw = nullptr;
  if (!ce || (velocity && CEodeSetVelocityDependence(ce.get(), SUNTRUE) != CE_SUCCESS) ||
      (tol > 0 && CEodeSStolerances(ce.get(), tol, tol) != CE_SUCCESS) ||
      CEodeCreateMRIStepInnerStepper(ce.get(), &raw) != CE_SUCCESS) {
    return r;
  }
  Inner inner(raw);
  if (RunMri(ctx, SlowA, raw, st.y.get(), 2.0, nslow) < 0) return r;
  ExactA(2.0, &q, &s, &p);
  r.err = std::max({std::fabs(x[0] - q), std::fabs(x[1] - s), std::fabs(v[0] - p) / kOmega});
  CEodeGetNumSteps(ce.get(), &r.nst);
  CEodeGetNumInnerRestarts(ce.get(), &r.nrestarts);
  long int nme_guard = 0, nsetups_guard = 0;
  CEodeGetGuardStats(ce.get(), &r.nfe_guard, &nme_guard, &nsetups_guard);
  CEodeGetNumStartRhsEvals(ce.get(), &r.nfe_start);
  return r;
}

TEST(MriInnerStepper, GivesThirdOrderWithMriGarkErk33aOnTheTwoScaleProblem) {
  Context ctx;
  std::vector<double> H, E;
  for (int nslow : {40, 80, 160, 320}) {
    const OrderRun r = RunProblemA(ctx, nslow);
    ASSERT_GT(r.err, 0) << "MRI run with " << nslow << " slow steps failed";
    H.push_back(2.0 / nslow);
    E.push_back(r.err);
  }
  const double order = ceode_test::FitOrder(H, E);
  EXPECT_GE(order, 2.8);
  EXPECT_LE(order, 3.1);
  EXPECT_LT(E.back(), 1e-7);
}

// With tolerances on the inner memory the inner steps follow its error control (each stage ends
// on the stage's time): the slow method's third order and error are kept.
TEST(MriInnerStepper, WithTolerancesKeepsTheSlowMethodsOrder) {
  Context ctx;
  std::vector<double> H, E;
  for (int nslow : {40, 80, 160}) {
    const OrderRun r = RunProblemA(ctx, nslow, "G6_O5", false, 1e-12);
    ASSERT_GT(r.err, 0) << "MRI run with " << nslow << " slow steps failed";
    H.push_back(2.0 / nslow);
    E.push_back(r.err);
  }
  const double order = ceode_test::FitOrder(H, E);
  EXPECT_GE(order, 2.8);
  EXPECT_LE(order, 3.2);
  // The slow method's error: as with the fixed inner step of 1e-3.
  EXPECT_LT(E.back(), 1.5 * RunProblemA(ctx, 160).err);
}

TEST(MriInnerStepper, AccumulatesCountersOverRestartsAndEstimatesOmegaOnce) {
  Context ctx;
  const OrderRun r40 = RunProblemA(ctx, 40);
  const OrderRun r80 = RunProblemA(ctx, 80);
  ASSERT_GT(r40.err, 0);
  // Every inner step of [0, 2] with h <= 1e-3 is counted: at least 2000 of them.
  EXPECT_GE(r40.nst, 2000);
  EXPECT_GE(r80.nst, 2000);
  EXPECT_GE(r40.nrestarts, 3 * 40);  // three fast stages per slow step
  EXPECT_GE(r80.nrestarts, 3 * 80);
  // The power iteration ran once: twice the restarts, the same guard cost.
  EXPECT_GT(r40.nfe_guard, 0);
  EXPECT_EQ(r40.nfe_guard, r80.nfe_guard);
}

// The restart after a stage that ended on the state the next one starts from reuses the end
// point's g and carries the history over (docs/porting.md, "What a restart costs"): G3 sets
// evaluate nothing, every set of degree 4 and up one directional difference for the jump of x'
// (problem A's forcing moves s, so r_x jumps at every stage). Only the first start is a full
// one: 1, 3, 5 evaluations for degrees 3, 4, 5 and 13 for G8_O8 (a_0 and the high-degree
// start's 3 sweeps of 2, 4 and 6). From degree 5 on the carried history is no longer exact (the g
// parts of D_4 .. D_{d-1} change with the jump of the forcing); CheapRestart checks its errors.
struct RestartCost {
  const char* set;
  long full_start;   // evaluations of the first, full start
  long per_restart;  // evaluations of each later restart
};

void PrintTo(const RestartCost& c, std::ostream* os) {
  *os << c.set << " (full start " << c.full_start << ", restart " << c.per_restart << ")";
}

class RestartCostOf : public ::testing::TestWithParam<RestartCost> {};

TEST_P(RestartCostOf, IsItsFullStartOnceAndThenItsCarriedHistory) {
  Context ctx;
  const RestartCost& c = GetParam();
  const OrderRun r = RunProblemA(ctx, 40, c.set);
  ASSERT_GT(r.err, 0);
  ASSERT_EQ(r.nrestarts, 120);
  EXPECT_EQ(r.nfe_start, c.full_start + c.per_restart * (r.nrestarts - 1));
}

const RestartCost kRestartCosts[] = {
    {"G3_CD", 1, 0}, {"G4_A34", 3, 1}, {"G5_TOP", 5, 1}, {"G8_O8", 13, 1}};

INSTANTIATE_TEST_SUITE_P(Sets, RestartCostOf, ::testing::ValuesIn(kRestartCosts),
                         [](const ::testing::TestParamInfo<RestartCost>& p) {
                           return std::string(p.param.set);
                         });

// A reset to another state (here MRIStepReset halfway with v moved by 1e-6) cannot reuse the
// end of the last inner integration: that one restart is a full one (3 evaluations for G4_A34),
// a reset to the very state the stepper stands on changes nothing.
long StartEvalsWithAResetHalfway(SUNContext ctx, double dv) {
  ManyState st(ctx, 2);
  double q, s, p;
  ExactA(0, &q, &s, &p);
  sunrealtype* x = N_VGetArrayPointer(st.x.get());
  sunrealtype* v = N_VGetArrayPointer(st.v.get());
  x[0] = q, x[1] = s, v[0] = p, v[1] = 0;
  Mem ce = FastMemory(ctx, FastA, st.x.get(), st.v.get(), 1e-3);
  MRIStepInnerStepper raw = nullptr;
  if (!ce || CEodeCreateMRIStepInnerStepper(ce.get(), &raw) != CE_SUCCESS) return -1;
  Inner inner(raw);
  std::unique_ptr<void, MriDeleter> mri(MRIStepCreate(SlowA, nullptr, 0, st.y.get(), raw, ctx));
  MRIStepCoupling C = MRIStepCoupling_LoadTable(ARKODE_MRI_GARK_ERK33a);
  int flag = mri ? MRIStepSetCoupling(mri.get(), C) : -1;
  MRIStepCoupling_Free(C);
  if (flag == 0) flag = MRIStepSetFixedStep(mri.get(), 0.05);
  if (flag == 0) flag = MRIStepSetStopTime(mri.get(), 1.0);  // no interpolated output at t = 1
  sunrealtype t = 0;
  if (flag == 0) flag = MRIStepEvolve(mri.get(), 1.0, st.y.get(), &t, ARK_NORMAL);
  if (flag == ARK_TSTOP_RETURN) flag = 0;  // SUNDIALS 7 says it stopped at tstop
  v[0] += dv;
  if (flag == 0) flag = MRIStepReset(mri.get(), t, st.y.get());
  if (flag == 0) flag = MRIStepEvolve(mri.get(), 2.0, st.y.get(), &t, ARK_NORMAL);
  long nfe_start = -1;
  if (flag == 0) CEodeGetNumStartRhsEvals(ce.get(), &nfe_start);
  return nfe_start;
}

TEST(MriInnerStepper, AResetToAnotherStateRestartsInFull) {
  Context ctx;
  const long same = StartEvalsWithAResetHalfway(ctx, 0.0);
  const long moved = StartEvalsWithAResetHalfway(ctx, 1e-6);
  ASSERT_GT(same, 0);
  EXPECT_EQ(same, 3 + 119);  // 120 restarts, only the first one full
  EXPECT_EQ(moved, same + 2);
}

// The carried-over history is as good as a full start: the same MRI errors (to 1 %) as the
// full consistent start that the implicit path takes at every restart (3 evaluations each).
// The full restarts (the implicit path's) cost 3, 5 and 41 evaluations (G8_O8 with velocity
// dependence: a_0 and 5 sweeps of 8); the cheap ones must cost less than half of that.
class CheapRestart : public ::testing::TestWithParam<const char*> {};

TEST_P(CheapRestart, GivesTheErrorsOfFullRestarts) {
  Context ctx;
  for (int nslow : {40, 160}) {
    const OrderRun cheap = RunProblemA(ctx, nslow, GetParam());
    const OrderRun full = RunProblemA(ctx, nslow, GetParam(), true);
    ASSERT_GT(cheap.err, 0);
    ASSERT_GT(full.err, 0);
    EXPECT_LT(cheap.nfe_start, full.nfe_start / 2);
    EXPECT_NEAR(cheap.err, full.err, 0.01 * full.err) << nslow << " slow steps";
  }
}

INSTANTIATE_TEST_SUITE_P(Sets, CheapRestart, ::testing::Values("G4_A34", "G5_TOP", "G8_O8"),
                         [](const ::testing::TestParamInfo<const char*>& p) {
                           return std::string(p.param);
                         });

// Problem B: forcing on both halves and a velocity-dependent fast part,
// q'' = -omega^2 q - c q' (fast), slow y' = [0.5 cos t; -0.3 q].
// The x-part forcing enters g through v = u - r_x: CEODE and RK4 inside must agree.
constexpr double kDamp = 0.7;

int FastB(sunrealtype /*t*/, N_Vector x, N_Vector v, N_Vector f, void* /*data*/) {
  NV_Ith_S(f, 0) = -kOmega * kOmega * NV_Ith_S(x, 0) - kDamp * NV_Ith_S(v, 0);
  return 0;
}

int FastBFirstOrder(sunrealtype /*t*/, N_Vector y, N_Vector ydot, void* /*data*/) {
  NV_Ith_S(ydot, 0) = NV_Ith_S(y, 1);
  NV_Ith_S(ydot, 1) = -kOmega * kOmega * NV_Ith_S(y, 0) - kDamp * NV_Ith_S(y, 1);
  return 0;
}

int SlowB(sunrealtype t, N_Vector y, N_Vector ydot, void* /*data*/) {
  NV_Ith_S(ydot, 0) = 0.5 * std::cos(t);
  NV_Ith_S(ydot, 1) = -0.3 * NV_Ith_S(y, 0);
  return 0;
}

// Problems B and C run on one unknown, x0 = 1, v0 = 0, both halves forced by SlowB over [0, 1]
// with 20 slow steps, once with CEODE inside (h = kInnerH; its start evaluations and restarts
// in *starts) and once with an ARKStep ERK inside at the same fixed step. Returns 0 when both MRI
// runs succeeded.
constexpr double kInnerH = 1e-4;

int RunCeodeAndRk4Inside(SUNContext ctx, CEodeRhsFn g, ARKRhsFn g_first_order, bool velocity,
                         N_Vector yc, N_Vector yr, OrderRun* starts,
                         const char* method = "G4_A34") {
  Vector x0 = SerialVector(1, ctx, 1.0), v0 = SerialVector(1, ctx, 0.0);
  NV_Ith_S(yc, 0) = NV_Ith_S(yr, 0) = 1.0;
  NV_Ith_S(yc, 1) = NV_Ith_S(yr, 1) = 0.0;
  Mem ce = FastMemory(ctx, g, x0.get(), v0.get(), kInnerH, method);
  MRIStepInnerStepper raw = nullptr;
  if (!ce || (velocity && CEodeSetVelocityDependence(ce.get(), SUNTRUE) != CE_SUCCESS) ||
      CEodeCreateMRIStepInnerStepper(ce.get(), &raw) != CE_SUCCESS) {
    return -1;
  }
  Inner inner(raw);
  if (RunMri(ctx, SlowB, raw, yc, 1.0, 20) != 0) return -2;
  CEodeGetNumStartRhsEvals(ce.get(), &starts->nfe_start);
  CEodeGetNumInnerRestarts(ce.get(), &starts->nrestarts);
  std::unique_ptr<void, ArkDeleter> ark(ARKStepCreate(g_first_order, nullptr, 0, yr, ctx));
  MRIStepInnerStepper rk = nullptr;
  if (!ark || ARKStepSetTableNum(ark.get(), ARKODE_DIRK_NONE, ARKODE_ZONNEVELD_5_3_4) != 0 ||
      ARKStepSetFixedStep(ark.get(), kInnerH) != 0 ||
      ARKStepSetMaxNumSteps(ark.get(), 1000000) != 0 ||
      ARKStepCreateMRIStepInnerStepper(ark.get(), &rk) != 0) {
    return -3;
  }
  const int flag = RunMri(ctx, SlowB, rk, yr, 1.0, 20);
  MRIStepInnerStepper_Free(&rk);
  return flag == 0 ? 0 : -4;
}

// Both solve the same forced inner problems; the gap is the inner errors (h = 1e-4).
void ExpectTheSameState(N_Vector yc, N_Vector yr) {
  EXPECT_NEAR(NV_Ith_S(yc, 0), NV_Ith_S(yr, 0), 1e-9);
  EXPECT_NEAR(NV_Ith_S(yc, 1), NV_Ith_S(yr, 1), 1e-8);
  EXPECT_GT(std::fabs(NV_Ith_S(yc, 0) - 1.0), 1e-3);  // the state did move
}

TEST(MriInnerStepper, MatchesAnRk4InnerStepperWhenBothHalvesAreForcedAndFDependsOnV) {
  Context ctx;
  Vector yc = SerialVector(2, ctx), yr = SerialVector(2, ctx);
  OrderRun starts{};
  ASSERT_EQ(RunCeodeAndRk4Inside(ctx, FastB, FastBFirstOrder, true, yc.get(), yr.get(), &starts),
            0);
  ExpectTheSameState(yc.get(), yr.get());
}

// Problem C: a nonlinear, time-dependent fast part without velocity dependence (the cheap
// restart carries g_t and g_x x' over), q'' = -omega^2 sin q + 0.3 cos 2t, forced on both
// halves by SlowB. CEODE (1 start evaluation per restart) and RK4 inside must agree.
int FastC(sunrealtype t, N_Vector x, N_Vector /*v*/, N_Vector f, void* /*data*/) {
  NV_Ith_S(f, 0) = -kOmega * kOmega * std::sin(NV_Ith_S(x, 0)) + 0.3 * std::cos(2 * t);
  return 0;
}

int FastCFirstOrder(sunrealtype t, N_Vector y, N_Vector ydot, void* /*data*/) {
  NV_Ith_S(ydot, 0) = NV_Ith_S(y, 1);
  NV_Ith_S(ydot, 1) = -kOmega * kOmega * std::sin(NV_Ith_S(y, 0)) + 0.3 * std::cos(2 * t);
  return 0;
}

// Problem C with the carried history of degrees 4 to 8: G4_A34 (exact to the difference), G5_TOP
// and G8_O8 (D_4 and up carried approximately), one evaluation per restart each. (G3_CD's restart
// is exact, but the set is second order: at h = 1e-4 it is 3e-6 from RK4 here, the set's own
// truncation error.)
class CheapRestartOnC : public ::testing::TestWithParam<RestartCost> {};

TEST_P(CheapRestartOnC, MatchesAnRk4InnerStepperOnANonlinearTimeDependentFastPart) {
  Context ctx;
  const RestartCost& c = GetParam();
  Vector yc = SerialVector(2, ctx), yr = SerialVector(2, ctx);
  OrderRun starts{};
  ASSERT_EQ(
      RunCeodeAndRk4Inside(ctx, FastC, FastCFirstOrder, false, yc.get(), yr.get(), &starts, c.set),
      0);
  EXPECT_EQ(starts.nfe_start, c.full_start + c.per_restart * (starts.nrestarts - 1));
  ExpectTheSameState(yc.get(), yr.get());
}

INSTANTIATE_TEST_SUITE_P(Sets, CheapRestartOnC,
                         ::testing::ValuesIn(std::begin(kRestartCosts) + 1,
                                             std::end(kRestartCosts)),
                         [](const ::testing::TestParamInfo<RestartCost>& p) {
                           return std::string(p.param.set);
                         });

// ---------------------------------------------------------------------------
// Bad input: a flag and a message naming the cause, nothing crashes.

// ARKODE's own report of the failure is noise here (SUNDIALS 7 logs it through
// the SUNContext's logger and has no per-integrator error file).
void QuietArkode(void* arkode_mem) {
#if SUNDIALS_VERSION_MAJOR < 7
  MRIStepSetErrFile(arkode_mem, nullptr);
#else
  (void)arkode_mem;
#endif
}

std::string LastMessage(void* ce) {
  const char* msg = nullptr;
  CEodeGetLastErrorMessage(ce, &msg);
  return msg != nullptr ? msg : "";
}

class MriInnerStepperBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    x0_ = SerialVector(2, ctx_, 0.5);
    v0_ = SerialVector(2, ctx_, 0.0);
    ce_ = FastMemory(ctx_, FastA, x0_.get(), v0_.get(), 1e-2);
    ASSERT_TRUE(ce_);
    CEodeSetErrFile(ce_.get(), nullptr);
  }
  // MRIStep with CEODE inside on the state y, evolved with slow step h to tout: the evolve must
  // fail; CEODE's last message is returned (empty if a step of the set-up failed).
  std::string FailedEvolveMessage(N_Vector y, sunrealtype h, sunrealtype tout);

  Context ctx_;
  Vector x0_, v0_;
  Mem ce_;
};

TEST_F(MriInnerStepperBadInput, NullMemoryAndNullStepperAreRejected) {
  MRIStepInnerStepper s = nullptr;
  EXPECT_EQ(CEodeCreateMRIStepInnerStepper(nullptr, &s), CE_MEM_NULL);
  EXPECT_EQ(CEodeCreateMRIStepInnerStepper(ce_.get(), nullptr), CE_ILL_INPUT);
  EXPECT_NE(LastMessage(ce_.get()).find("stepper = NULL"), std::string::npos);
  EXPECT_EQ(CEodeFreeMRIStepInnerStepper(nullptr), CE_SUCCESS);
  long n = 0;
  EXPECT_EQ(CEodeGetNumInnerRestarts(ce_.get(), &n), CE_ILL_INPUT);
  EXPECT_EQ(CEodeGetNumInnerRestarts(nullptr, &n), CE_MEM_NULL);
}

int IdentityMass(sunrealtype, N_Vector, SUNMatrix M, void*, N_Vector, N_Vector, N_Vector) {
  SUNMatZero(M);
  for (sunindextype i = 0; i < SUNDenseMatrix_Rows(M); ++i) SM_ELEMENT_D(M, i, i) = 1;
  return 0;
}

TEST_F(MriInnerStepperBadInput, MemoryWithoutInitOrStepOrWithAMassMatrixIsRejected) {
  MRIStepInnerStepper s = nullptr;
  Mem raw(CEodeCreate(ctx_));
  CEodeSetErrFile(raw.get(), nullptr);
  EXPECT_EQ(CEodeCreateMRIStepInnerStepper(raw.get(), &s), CE_NO_MALLOC);
  ASSERT_EQ(CEodeInit(raw.get(), FastA, 0, x0_.get(), v0_.get()), CE_SUCCESS);
  EXPECT_EQ(CEodeCreateMRIStepInnerStepper(raw.get(), &s), CE_ILL_INPUT);
  EXPECT_NE(LastMessage(raw.get()).find("CEodeSetFixedStep"), std::string::npos);
  ceode_test::Matrix M(SUNDenseMatrix(2, 2, ctx_));
  ASSERT_EQ(CEodeSetFixedStep(raw.get(), 1e-2), CE_SUCCESS);
  ASSERT_EQ(CEodeSetMassFn(raw.get(), IdentityMass, M.get(), SUNTRUE), CE_SUCCESS);
  EXPECT_EQ(CEodeCreateMRIStepInnerStepper(raw.get(), &s), CE_ILL_INPUT);
  EXPECT_NE(LastMessage(raw.get()).find("M = I"), std::string::npos);
  EXPECT_EQ(s, nullptr);
}

TEST_F(MriInnerStepperBadInput, ASecondStepperOnTheSameMemoryIsRejected) {
  MRIStepInnerStepper s1 = nullptr, s2 = nullptr;
  ASSERT_EQ(CEodeCreateMRIStepInnerStepper(ce_.get(), &s1), CE_SUCCESS);
  Inner keep(s1);
  EXPECT_EQ(CEodeCreateMRIStepInnerStepper(ce_.get(), &s2), CE_ILL_INPUT);
  EXPECT_NE(LastMessage(ce_.get()).find("already drives"), std::string::npos);
  long n = -1;
  EXPECT_EQ(CEodeGetNumInnerRestarts(ce_.get(), &n), CE_SUCCESS);
  EXPECT_EQ(n, 0);
}

int SlowNone(sunrealtype, N_Vector, N_Vector ydot, void*) {
  N_VConst(0, ydot);
  return 0;
}

std::string MriInnerStepperBadInput::FailedEvolveMessage(N_Vector y, sunrealtype h,
                                                         sunrealtype tout) {
  MRIStepInnerStepper s = nullptr;
  if (CEodeCreateMRIStepInnerStepper(ce_.get(), &s) != CE_SUCCESS) return "";
  Inner keep(s);
  std::unique_ptr<void, MriDeleter> mri(MRIStepCreate(SlowNone, nullptr, 0, y, s, ctx_));
  if (!mri) return "";
  QuietArkode(mri.get());
  if (MRIStepSetFixedStep(mri.get(), h) != 0) return "";
  sunrealtype t = 0;
  EXPECT_LT(MRIStepEvolve(mri.get(), tout, y, &t, ARK_NORMAL), 0);
  return LastMessage(ce_.get());
}

TEST_F(MriInnerStepperBadInput, ABackwardInnerStepIsRefusedAsForwardOnly) {
  Vector y = SerialVector(4, ctx_, 0.5);
  const std::string msg = FailedEvolveMessage(y.get(), -0.1, -0.5);
  EXPECT_NE(msg.find("forward only"), std::string::npos) << msg;
}

TEST_F(MriInnerStepperBadInput, AManyVectorOfThreePartsIsRefused) {
  Vector a = SerialVector(2, ctx_), b = SerialVector(2, ctx_), c = SerialVector(2, ctx_);
  N_Vector parts[3] = {a.get(), b.get(), c.get()};
  Vector y(N_VNew_ManyVector(3, parts, ctx_));
  const std::string msg = FailedEvolveMessage(y.get(), 0.1, 0.5);
  EXPECT_NE(msg.find("has 3 parts"), std::string::npos) << msg;
}

TEST_F(MriInnerStepperBadInput, ASerialStateOfTheWrongLengthIsRefused) {
  Vector y = SerialVector(3, ctx_);
  const std::string msg = FailedEvolveMessage(y.get(), 0.1, 0.5);
  EXPECT_NE(msg.find("serial vector of length 4"), std::string::npos) << msg;
}

TEST_F(MriInnerStepperBadInput, UserDataChangedBehindTheStepperIsRefusedNotFollowed) {
  MRIStepInnerStepper s = nullptr;
  ASSERT_EQ(CEodeCreateMRIStepInnerStepper(ce_.get(), &s), CE_SUCCESS);
  Inner keep(s);
  int other = 0;
  ASSERT_EQ(CEodeSetUserData(ce_.get(), &other), CE_SUCCESS);
  Vector y = SerialVector(4, ctx_, 0.5);
  std::unique_ptr<void, MriDeleter> mri(MRIStepCreate(SlowNone, nullptr, 0, y.get(), s, ctx_));
  ASSERT_TRUE(mri);
  QuietArkode(mri.get());
  ASSERT_EQ(MRIStepSetFixedStep(mri.get(), 0.1), 0);
  sunrealtype t = 0;
  EXPECT_LT(MRIStepEvolve(mri.get(), 0.5, y.get(), &t, ARK_NORMAL), 0);
  EXPECT_NE(LastMessage(ce_.get()).find("CEodeSetUserData"), std::string::npos)
      << LastMessage(ce_.get());
}

TEST_F(MriInnerStepperBadInput, FreeingTheStepperHandsTheMemoryBackUsable) {
  MRIStepInnerStepper s = nullptr;
  ASSERT_EQ(CEodeCreateMRIStepInnerStepper(ce_.get(), &s), CE_SUCCESS);
  ASSERT_EQ(CEodeFreeMRIStepInnerStepper(&s), CE_SUCCESS);
  EXPECT_EQ(s, nullptr);
  Vector x = SerialVector(2, ctx_), v = SerialVector(2, ctx_);
  sunrealtype t = 0;
  EXPECT_EQ(CEodeEvolve(ce_.get(), 0.1, x.get(), v.get(), &t, CE_NORMAL), CE_SUCCESS);
  // x'' = -omega^2 (q - s) with q = s = 0.5 at rest: nothing moves.
  EXPECT_NEAR(NV_Ith_S(x.get(), 0), 0.5, 1e-12);
}

#ifdef CEODE_HAVE_SUNSTEPPER
// SUNDIALS >= 7.2: CEODE's SUNStepper in SplittingStep, with ERKStep on the slow partition.
struct ArkodeDeleter {
  void operator()(void* mem) const { ARKodeFree(&mem); }
};
struct SunStepperDeleter {
  void operator()(SUNStepper s) const { SUNStepper_Destroy(&s); }
};
using SunStepperPtr = std::unique_ptr<std::remove_pointer_t<SUNStepper>, SunStepperDeleter>;

// Problem A split into fast (CEODE) and slow (ERKStep, h = 1e-3); returns the error or -1.
double RunSplitting(SUNContext ctx, ARKODE_SplittingCoefficientsID id, int nsteps, void** ce_out,
                    Mem* keep) {
  ManyState st(ctx, 2);
  double q, s, p;
  ExactA(0, &q, &s, &p);
  sunrealtype* x = N_VGetArrayPointer(st.x.get());
  sunrealtype* v = N_VGetArrayPointer(st.v.get());
  x[0] = q, x[1] = s, v[0] = p, v[1] = 0;
  *keep = FastMemory(ctx, FastA, st.x.get(), st.v.get(), 1e-3);
  *ce_out = keep->get();
  SUNStepper raw[2] = {nullptr, nullptr};
  if (!*keep || CEodeCreateSUNStepper(keep->get(), &raw[0]) != CE_SUCCESS) return -1;
  SunStepperPtr fast(raw[0]);
  std::unique_ptr<void, ArkodeDeleter> erk(ERKStepCreate(SlowA, 0, st.y.get(), ctx));
  if (!erk || ARKodeSetFixedStep(erk.get(), 1e-3) != 0 ||
      ARKodeCreateSUNStepper(erk.get(), &raw[1]) != 0) {
    return -1;
  }
  SunStepperPtr slow(raw[1]);
  std::unique_ptr<void, ArkodeDeleter> split(SplittingStepCreate(raw, 2, 0, st.y.get(), ctx));
  SplittingStepCoefficients c = SplittingStepCoefficients_LoadCoefficients(id);
  int flag = SplittingStepSetCoefficients(split.get(), c);
  SplittingStepCoefficients_Destroy(&c);
  if (flag == 0) flag = ARKodeSetFixedStep(split.get(), 2.0 / nsteps);
  sunrealtype t = 0;
  if (flag == 0) flag = ARKodeEvolve(split.get(), 2.0, st.y.get(), &t, ARK_NORMAL);
  if (flag < 0) return -1;
  ExactA(2.0, &q, &s, &p);
  return std::max({std::fabs(x[0] - q), std::fabs(x[1] - s), std::fabs(v[0] - p) / kOmega});
}

TEST(SunStepperInner, GivesSecondOrderInsideStrangSplitting) {
  Context ctx;
  std::vector<double> H, E;
  for (int n : {20, 40, 80, 160}) {
    void* ce = nullptr;
    Mem keep;
    const double e = RunSplitting(ctx, ARKODE_SPLITTING_STRANG_2_2_2, n, &ce, &keep);
    ASSERT_GT(e, 0) << "Strang run with " << n << " steps failed";
    H.push_back(2.0 / n);
    E.push_back(e);
  }
  const double order = ceode_test::FitOrder(H, E);
  EXPECT_GE(order, 1.8);
  EXPECT_LE(order, 2.2);
}

TEST(SunStepperInner, RefusesTheNegativeSubstepsOfAFourthOrderSplitting) {
  Context ctx;
  void* ce = nullptr;
  Mem keep;
  EXPECT_LT(RunSplitting(ctx, ARKODE_SPLITTING_YOSHIDA_4_4_2, 20, &ce, &keep), 0);
  ASSERT_NE(ce, nullptr);
  EXPECT_NE(LastMessage(ce).find("forward only"), std::string::npos) << LastMessage(ce);
}
#endif

}  // namespace
