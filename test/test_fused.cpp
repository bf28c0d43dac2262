// The one-pass update kernel for serial vectors must give exactly the numbers
// of the generic N_Vector path it replaces, with and without compensation: end to end through
// the integrator, and kernel against reference (src/ceode_kernels.hpp).
#include <ceode/ceode.h>
#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "../src/ceode_kernels.hpp"
#include "ceode_sundials_compat.h"  // SUN_COMM_NULL on SUNDIALS 6.4
#include "ceode_testing.h"          // CEodeSetFusedKernel, CEodeSetInPlaceUpdate

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

// The chain's initial state on n masses: smooth positions and velocities without symmetry.
void ChainStart(SUNContext ctx, sunindextype n, N_Vector* x, N_Vector* v) {
  *x = N_VNew_Serial(n, ctx);
  *v = N_VNew_Serial(n, ctx);
  for (sunindextype i = 0; i < n; ++i) {
    N_VGetArrayPointer(*x)[i] = std::sin(0.3 * static_cast<sunrealtype>(i));
    N_VGetArrayPointer(*v)[i] = 0.1 * std::cos(0.7 * static_cast<sunrealtype>(i));
  }
}

// n >= ceode::kInPlaceMinLen: the fused explicit step updates the history in place (unless
// in_place is false or compensated). The state at each of touts, one after the other;
// guard_every > 0 checks the stability guard every so many steps (an early exit of the lean loop).
RunResult RunChain(const std::string& method, bool fused, bool compensated, sunindextype kN = 64,
                   bool in_place = true, const std::vector<sunrealtype>& touts = {5.0},
                   long guard_every = 0) {
  SUNContext ctx = nullptr;
  SUNContext_Create(SUN_COMM_NULL, &ctx);
  N_Vector x = nullptr;
  N_Vector v = nullptr;
  ChainStart(ctx, kN, &x, &v);
  void* mem = CEodeCreate(ctx);
  EXPECT_EQ(CEodeInit(mem, ChainRhs, 0, x, v), CE_SUCCESS);
  EXPECT_EQ(CEodeSetMethodByName(mem, method.c_str()), CE_SUCCESS);
  EXPECT_EQ(CEodeSetFixedStep(mem, 0.01), CE_SUCCESS);
  EXPECT_EQ(
      CEodeSetStabilityGuard(mem, guard_every > 0 ? CE_GUARD_WARN : CE_GUARD_OFF, guard_every),
      CE_SUCCESS);
  EXPECT_EQ(CEodeSetFusedKernel(mem, fused ? SUNTRUE : SUNFALSE), CE_SUCCESS);
  EXPECT_EQ(CEodeSetCompensatedSummation(mem, compensated ? SUNTRUE : SUNFALSE), CE_SUCCESS);
  EXPECT_EQ(CEodeSetInPlaceUpdate(mem, in_place ? SUNTRUE : SUNFALSE), CE_SUCCESS);
  RunResult r;
  for (sunrealtype tout : touts) {
    sunrealtype t = 0;
    EXPECT_EQ(CEodeEvolve(mem, tout, x, v, &t, CE_NORMAL), CE_SUCCESS);
    r.x.insert(r.x.end(), N_VGetArrayPointer(x), N_VGetArrayPointer(x) + kN);
    r.v.insert(r.v.end(), N_VGetArrayPointer(v), N_VGetArrayPointer(v) + kN);
  }
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

// The in-place plans (n >= kInPlaceMinLen) against the generic path and the fused kernel's own
// out-of-place plans.
TEST_P(FusedKernel, GivesBitwiseTheNumbersOfTheGenericPathWhenUpdatingInPlace) {
  constexpr sunindextype kN = 3 * ceode::kInPlaceMinLen + 5;  // block tails too
  const RunResult generic = RunChain(GetParam(), false, false, kN);
  const RunResult in_place = RunChain(GetParam(), true, false, kN, true);
  const RunResult out_of_place = RunChain(GetParam(), true, false, kN, false);
  ASSERT_EQ(generic.x.size(), in_place.x.size());
  long differing = 0;
  for (size_t i = 0; i < generic.x.size(); ++i) {
    differing += generic.x[i] != in_place.x[i] || generic.v[i] != in_place.v[i];
    differing += out_of_place.x[i] != in_place.x[i] || out_of_place.v[i] != in_place.v[i];
  }
  EXPECT_EQ(differing, 0);
  EXPECT_TRUE(std::isfinite(in_place.x[kN / 2]) && in_place.x[kN / 2] != 0);
}

// The lean loop writes every position but its last step's over the one before (and so knows its
// last step in advance): runs of every length to touts on and off the step grid, with the guard's
// checks cutting them, give the numbers of the step-by-step generic path at every tout.
TEST_P(FusedKernel, GivesBitwiseTheGenericNumbersAtEveryToutWhenWritingPositionsInPlace) {
  constexpr sunindextype kN = 2 * ceode::kInPlaceMinLen + 3;
  std::vector<sunrealtype> touts;
  sunrealtype tout = 0;
  for (int k = 1; k <= 24; ++k) touts.push_back(tout += 0.01 * k + 0.0037 * (k % 3));
  for (long guard_every : {0L, 7L}) {
    SCOPED_TRACE("guard every " + std::to_string(guard_every));
    const RunResult generic = RunChain(GetParam(), false, false, kN, true, touts, guard_every);
    const RunResult lean = RunChain(GetParam(), true, false, kN, true, touts, guard_every);
    ASSERT_EQ(generic.x.size(), lean.x.size());
    long differing = 0;
    for (size_t i = 0; i < generic.x.size(); ++i) {
      differing += generic.x[i] != lean.x[i] || generic.v[i] != lean.v[i];
    }
    EXPECT_EQ(differing, 0);
    EXPECT_TRUE(std::isfinite(lean.x.back()) && lean.x.back() != 0);
  }
}

INSTANTIATE_TEST_SUITE_P(EveryDegree, FusedKernel,
                         ::testing::Values("G3_CD", "G3_A2", "G4_A34", "G5", "G5_TOP", "G5_O4",
                                           "G6_O5", "G6_O6", "G7_O7", "G8_O8"),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           return info.param;
                         });

// The chain with a damper that f reads from its velocity argument.
int DampedChainRhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
  ChainRhs(t, x, v, f, data);
  N_VLinearSum(1, f, -0.05, v, f);
  return 0;
}

// With the independence declared, f on the explicit path receives the previous step's velocity
// (docs/api.md), also where G3_CD's lean loop could carry the half-step velocity instead: a
// damper read from it gives the generic path's numbers bit for bit.
TEST(LeanExplicitLoop, HandsFThePreviousVelocityWhenTheIndependenceIsDeclared) {
  constexpr sunindextype kN = 2 * ceode::kInPlaceMinLen + 3;
  RunResult r[2];
  for (int fused = 0; fused < 2; ++fused) {
    SUNContext ctx = nullptr;
    SUNContext_Create(SUN_COMM_NULL, &ctx);
    N_Vector x = nullptr;
    N_Vector v = nullptr;
    ChainStart(ctx, kN, &x, &v);
    void* mem = CEodeCreate(ctx);
    EXPECT_EQ(CEodeInit(mem, DampedChainRhs, 0, x, v), CE_SUCCESS);
    EXPECT_EQ(CEodeSetMethodByName(mem, "G3_CD"), CE_SUCCESS);
    EXPECT_EQ(CEodeSetVelocityDependence(mem, SUNFALSE), CE_SUCCESS);
    EXPECT_EQ(CEodeSetFixedStep(mem, 0.01), CE_SUCCESS);
    EXPECT_EQ(CEodeSetFusedKernel(mem, fused != 0 ? SUNTRUE : SUNFALSE), CE_SUCCESS);
    sunrealtype t = 0;
    EXPECT_EQ(CEodeEvolve(mem, 1.0, x, v, &t, CE_NORMAL), CE_SUCCESS);
    r[fused].x.assign(N_VGetArrayPointer(x), N_VGetArrayPointer(x) + kN);
    r[fused].v.assign(N_VGetArrayPointer(v), N_VGetArrayPointer(v) + kN);
    CEodeFree(&mem);
    N_VDestroy(x);
    N_VDestroy(v);
    SUNContext_Free(&ctx);
  }
  EXPECT_TRUE(r[0].x == r[1].x);
  EXPECT_TRUE(r[0].v == r[1].v);
}

// ---- failures on the in-place path (docs/theory.md, "In-place update") --------------------
// The chain whose f fails from t = kFailAt on: returning 1 (a recoverable error) or, with
// status 0, a NaN in one entry.
constexpr sunrealtype kFailAt = 2.0;
struct FailingChain {
  bool nan = false;  // false: return 1
};
int FailingChainRhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
  ChainRhs(t, x, v, f, nullptr);
  if (t < kFailAt) return 0;
  if (!static_cast<FailingChain*>(data)->nan) return 1;
  N_VGetArrayPointer(f)[7] = NAN;
  return 0;
}

struct FailedRun {
  int flag = 0;
  sunrealtype t = 0;
  long steps = 0;
  RunResult state;
  std::string message;  // what CEODE wrote to its error file
};

// fused = false takes the generic step, one TakeStep at a time; fused without a mass matrix takes
// the lean loop of many explicit steps (src/ceode_step.cpp). guard_every > 0 checks the stability
// guard every so many steps (an early exit of that loop).
FailedRun RunToFailure(bool in_place, bool nan, bool fused = true, long guard_every = 0,
                       const char* method = "G4_A34") {
  constexpr sunindextype kN = 2 * ceode::kInPlaceMinLen;
  SUNContext ctx = nullptr;
  SUNContext_Create(SUN_COMM_NULL, &ctx);
  N_Vector x = N_VNew_Serial(kN, ctx);
  N_Vector v = N_VNew_Serial(kN, ctx);
  for (sunindextype i = 0; i < kN; ++i) {
    N_VGetArrayPointer(x)[i] = std::sin(0.01 * static_cast<sunrealtype>(i));
    N_VGetArrayPointer(v)[i] = 0;
  }
  FailingChain fc{nan};
  void* mem = CEodeCreate(ctx);
  EXPECT_EQ(CEodeInit(mem, FailingChainRhs, 0, x, v), CE_SUCCESS);
  EXPECT_EQ(CEodeSetUserData(mem, &fc), CE_SUCCESS);
  FILE* err = std::tmpfile();
  EXPECT_EQ(CEodeSetErrFile(mem, err), CE_SUCCESS);
  EXPECT_EQ(CEodeSetMethodByName(mem, method), CE_SUCCESS);
  EXPECT_EQ(CEodeSetFixedStep(mem, 0.01), CE_SUCCESS);
  EXPECT_EQ(
      CEodeSetStabilityGuard(mem, guard_every > 0 ? CE_GUARD_WARN : CE_GUARD_OFF, guard_every),
      CE_SUCCESS);
  EXPECT_EQ(CEodeSetFusedKernel(mem, fused ? SUNTRUE : SUNFALSE), CE_SUCCESS);
  EXPECT_EQ(CEodeSetInPlaceUpdate(mem, in_place ? SUNTRUE : SUNFALSE), CE_SUCCESS);
  FailedRun r;
  r.flag = CEodeEvolve(mem, 5.0, x, v, &r.t, CE_NORMAL);
  EXPECT_EQ(CEodeGetNumSteps(mem, &r.steps), CE_SUCCESS);
  r.state.x.assign(N_VGetArrayPointer(x), N_VGetArrayPointer(x) + kN);
  r.state.v.assign(N_VGetArrayPointer(v), N_VGetArrayPointer(v) + kN);
  CEodeFree(&mem);
  std::rewind(err);
  for (int c = std::fgetc(err); c != EOF; c = std::fgetc(err)) r.message += static_cast<char>(c);
  std::fclose(err);
  N_VDestroy(x);
  N_VDestroy(v);
  SUNContext_Free(&ctx);
  return r;
}

// f fails before the step writes anything, but the lean loop's earlier steps wrote the position
// over x(t): it is rebuilt from x(t + h) less the last increment, to rounding; the velocity and
// the time are exactly those of the out-of-place path.
TEST(InPlaceUpdate, AFailingRhsLeavesTheLastGoodStateWithItsPositionToRounding) {
  const FailedRun exact = RunToFailure(false, false);
  const FailedRun in_place = RunToFailure(true, false);
  EXPECT_EQ(exact.flag, CE_RHSFUNC_FAIL);
  EXPECT_EQ(in_place.flag, CE_RHSFUNC_FAIL);
  EXPECT_EQ(in_place.t, exact.t);
  EXPECT_EQ(in_place.steps, exact.steps);
  EXPECT_GT(exact.t, kFailAt - 0.02);
  EXPECT_TRUE(in_place.state.v == exact.state.v);
  // One addition undone by one subtraction: a few units in the last place of |x| <= 1.
  sunrealtype worst = 0;
  for (size_t i = 0; i < exact.state.x.size(); ++i) {
    worst = std::max(worst, std::fabs(in_place.state.x[i] - exact.state.x[i]));
  }
  EXPECT_LE(worst, 4 * std::numeric_limits<sunrealtype>::epsilon());
}

// A non-finite acceleration is seen by the check after the update, which the lean loop wrote over
// the last good position: the state returned is the failed step's (non-finite where f was), and
// f is named as the cause.
TEST(InPlaceUpdate, ANonFiniteAccelerationReturnsTheFailedStepsStateAndNamesF) {
  const FailedRun exact = RunToFailure(false, true);
  const FailedRun in_place = RunToFailure(true, true);
  EXPECT_EQ(exact.flag, CE_RHSFUNC_FAIL);
  EXPECT_EQ(in_place.flag, CE_RHSFUNC_FAIL);
  EXPECT_EQ(in_place.t, exact.t);
  EXPECT_EQ(in_place.steps, exact.steps);
  for (sunrealtype xi : exact.state.x) ASSERT_TRUE(std::isfinite(xi));
  EXPECT_FALSE(std::isfinite(in_place.state.x[7]));
  EXPECT_FALSE(std::isfinite(in_place.state.v[7]));
  EXPECT_TRUE(std::isfinite(in_place.state.x[1000]));
  EXPECT_NE(in_place.message.find("f returned non-finite values"), std::string::npos)
      << in_place.message;
  EXPECT_EQ(in_place.message.find("callbacks must not modify x"), std::string::npos)
      << in_place.message;
}

// G3_CD's lean loop carries the half-step velocity u = v + c a where v was (LeapKernels). On f's
// failure the velocity is formed back, v = u - c a, and the position rebuilt: both within a few
// units in the last place of the out-of-place run's (one addition undone by one subtraction); on
// a non-finite acceleration the failed step's state is returned and f is named.
TEST(InPlaceUpdate, G3CDsHalfStepVelocityIsTurnedBackIntoTheVelocityOnEveryFailure) {
  const FailedRun exact = RunToFailure(false, false, true, 0, "G3_CD");
  const FailedRun leap = RunToFailure(true, false, true, 0, "G3_CD");
  EXPECT_EQ(exact.flag, CE_RHSFUNC_FAIL);
  EXPECT_EQ(leap.flag, CE_RHSFUNC_FAIL);
  EXPECT_EQ(leap.t, exact.t);
  EXPECT_EQ(leap.steps, exact.steps);
  EXPECT_GT(exact.t, kFailAt - 0.02);
  sunrealtype dx = 0, dv = 0, vmax = 0;
  for (size_t i = 0; i < exact.state.x.size(); ++i) {
    dx = std::max(dx, std::fabs(leap.state.x[i] - exact.state.x[i]));
    dv = std::max(dv, std::fabs(leap.state.v[i] - exact.state.v[i]));
    vmax = std::max(vmax, std::fabs(exact.state.v[i]));
  }
  constexpr sunrealtype kEps = std::numeric_limits<sunrealtype>::epsilon();
  EXPECT_GT(dv, 0);  // u - c a is not v bit for bit: the test sees the half-step path
  EXPECT_LE(dv, 4 * kEps * vmax);
  EXPECT_LE(dx, 4 * kEps);  // |x| <= 1
  const FailedRun bad = RunToFailure(true, true, true, 0, "G3_CD");
  EXPECT_EQ(bad.flag, CE_RHSFUNC_FAIL);
  EXPECT_EQ(bad.t, exact.t);
  EXPECT_FALSE(std::isfinite(bad.state.x[7]));
  EXPECT_FALSE(std::isfinite(bad.state.v[7]));
  EXPECT_TRUE(std::isfinite(bad.state.x[1000]) && std::isfinite(bad.state.v[1000]));
  EXPECT_NE(bad.message.find("f returned non-finite values"), std::string::npos) << bad.message;
}

// The lean loop leaves on f's failure, on a non-finite update and for the guard's check; each
// time the state, the time and the step count are those of the generic step-by-step path.
TEST(LeanExplicitLoop, LeavesTheStateOfTheStepByStepPathOnEveryEarlyExit) {
  for (bool nan : {false, true}) {
    for (long guard_every : {0L, 7L}) {
      SCOPED_TRACE(std::string(nan ? "non-finite f" : "failing f") + " guard every " +
                   std::to_string(guard_every));
      const FailedRun generic = RunToFailure(false, nan, false, guard_every);
      const FailedRun lean = RunToFailure(false, nan, true, guard_every);
      EXPECT_EQ(generic.flag, CE_RHSFUNC_FAIL);
      EXPECT_EQ(lean.flag, generic.flag);
      EXPECT_EQ(lean.t, generic.t);
      EXPECT_EQ(lean.steps, generic.steps);
      EXPECT_GT(generic.steps, 150);
      EXPECT_TRUE(lean.state.x == generic.state.x);
      EXPECT_TRUE(lean.state.v == generic.state.v);
    }
  }
}

// One unknown: the entry-by-entry kernel, which also runs the high-degree start's Taylor samples
// and stencil sums (src/ceode_start.cpp). The pendulum theta'' = -9.81 cos theta.
int PendulumRhs(sunrealtype /*t*/, N_Vector x, N_Vector /*v*/, N_Vector f, void* /*data*/) {
  N_VGetArrayPointer(f)[0] = -9.81 * std::cos(N_VGetArrayPointer(x)[0]);
  return 0;
}

std::pair<sunrealtype, sunrealtype> RunPendulum(const std::string& method, bool fused,
                                                bool compensated, sunrealtype tend) {
  SUNContext ctx = nullptr;
  SUNContext_Create(SUN_COMM_NULL, &ctx);
  N_Vector x = N_VNew_Serial(1, ctx);
  N_Vector v = N_VNew_Serial(1, ctx);
  N_VConst(0, x);
  N_VConst(0, v);
  void* mem = CEodeCreate(ctx);
  EXPECT_EQ(CEodeInit(mem, PendulumRhs, 0, x, v), CE_SUCCESS);
  EXPECT_EQ(CEodeSetMethodByName(mem, method.c_str()), CE_SUCCESS);
  EXPECT_EQ(CEodeSetFixedStep(mem, 0.0125), CE_SUCCESS);
  EXPECT_EQ(CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0), CE_SUCCESS);
  EXPECT_EQ(CEodeSetFusedKernel(mem, fused ? SUNTRUE : SUNFALSE), CE_SUCCESS);
  EXPECT_EQ(CEodeSetCompensatedSummation(mem, compensated ? SUNTRUE : SUNFALSE), CE_SUCCESS);
  sunrealtype t = 0;
  EXPECT_EQ(CEodeEvolve(mem, tend, x, v, &t, CE_NORMAL), CE_SUCCESS);
  const std::pair<sunrealtype, sunrealtype> r{N_VGetArrayPointer(x)[0], N_VGetArrayPointer(v)[0]};
  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  SUNContext_Free(&ctx);
  return r;
}

TEST_P(FusedKernel, GivesBitwiseTheNumbersOfTheGenericPathOnOneUnknown) {
  for (bool compensated : {false, true}) {
    for (sunrealtype tend : {0.0125, 10.0}) {  // the start alone (one step), and a long run
      const auto generic = RunPendulum(GetParam(), false, compensated, tend);
      const auto fused = RunPendulum(GetParam(), true, compensated, tend);
      EXPECT_EQ(generic.first, fused.first) << "x compensated=" << compensated << " t=" << tend;
      EXPECT_EQ(generic.second, fused.second) << "v compensated=" << compensated << " t=" << tend;
      EXPECT_TRUE(std::isfinite(fused.first) && std::fabs(fused.first) < 4);
    }
  }
}

}  // namespace

// The kernel itself, without an integrator: the serial backend against the generic reference on
// plans of every shape the step builds (0, 1, 2 and more terms; the two-term shortcuts of
// N_VLinearSum; accumulated terms with and without compensation), on sizes that exercise the
// entry-by-entry branch (n < 16), the block tails of plans without a shape of their own (the block
// is 256 entries) and the streamed stores of large systems.
namespace kernel {

constexpr sunindextype kBlock = 256;
// From 2^19 entries on the new position is stored past the cache (SSE2): a size beyond it, with
// a block tail.
constexpr sunindextype kStreamed = (sunindextype{1} << 19) + 5;
constexpr int kPool = 19;  // vectors: inputs 0-7, outputs 8-15, new compensations 16-18

struct KernelCase {
  sunindextype n;
  bool compensated;
};

void PrintTo(const KernelCase& c, std::ostream* os) {
  *os << "n = " << c.n << (c.compensated ? ", compensated" : ", plain");
}

std::string CaseName(const ::testing::TestParamInfo<KernelCase>& info) {
  return "Size" + std::to_string(info.param.n) + (info.param.compensated ? "Compensated" : "Plain");
}

class FusedKernelAgainstReference : public ::testing::TestWithParam<KernelCase> {
 protected:
  void SetUp() override {
    SUNContext_Create(SUN_COMM_NULL, &ctx_);
    for (N_Vector& v : pool_) v = N_VNew_Serial(GetParam().n, ctx_);
    tmp_ = N_VNew_Serial(GetParam().n, ctx_);
  }
  void TearDown() override {
    for (N_Vector& v : pool_) N_VDestroy(v);
    N_VDestroy(tmp_);
    SUNContext_Free(&ctx_);
  }
  // Deterministic, sign-mixed data with a spread of magnitudes, so roundings differ by order.
  void Fill() {
    std::uint64_t seed = 2024;
    for (N_Vector v : pool_) {
      sunrealtype* d = N_VGetArrayPointer(v);
      for (sunindextype i = 0; i < GetParam().n; ++i) {
        seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
        const double u = static_cast<double>(seed >> 11) / 9007199254740992.0;
        d[i] = (u - 0.5) * std::pow(10.0, static_cast<double>(seed % 7) - 3);
      }
    }
  }
  std::vector<sunrealtype> Snapshot() const {
    std::vector<sunrealtype> all;
    for (N_Vector v : pool_) {
      all.insert(all.end(), N_VGetArrayPointer(v), N_VGetArrayPointer(v) + GetParam().n);
    }
    return all;
  }
  // A plan with one combination of each shape; later combinations read earlier outputs, as the
  // step's lower derivatives read z.
  ceode::UpdatePlan Plan() {
    ceode::UpdatePlan plan;
    const sunrealtype third = 1.0 / 3.0;
    auto add = [&](std::initializer_list<std::pair<sunrealtype, int>> terms, int out, int old,
                   int level) {
      ceode::Combo& cb = plan.combos[plan.n++];
      cb = ceode::Combo{};
      for (const auto& t : terms) cb.Add(t.first, pool_[t.second]);
      cb.out = pool_[out];
      cb.old = old >= 0 ? pool_[old] : nullptr;
      cb.level = level;
    };
    add({}, 8, -1, 0);                                          // zero terms
    add({{0.7, 0}}, 9, -1, 0);                                  // one term
    add({{third, 0}, {third, 1}}, 10, -1, 0);                   // a = b shortcut
    add({{third, 9}, {-third, 2}}, 11, -1, 0);                  // a = -b shortcut
    add({{1.0, 10}, {-1.0, 3}}, 12, -1, 0);                     // unit coefficients: no shortcut
    add({{0.1, 0}, {0.2, 1}, {0.3, 2}, {-0.4, 11}}, 13, 4, 1);  // accumulated, four terms
    add({{2.5, 12}}, 14, 5, 2);                                 // accumulated, one term
    add({{0.5, 13}, {0.25, 14}, {0.125, 0}}, 15, 6, 0);         // the position, last
    return plan;
  }
  ceode::Compensation Comp() {
    comp_[0] = pool_[1];
    comp_[1] = pool_[2];
    comp_[2] = pool_[3];
    for (int k = 0; k < 3; ++k) compnew_[k] = pool_[16 + k];
    return {GetParam().compensated, comp_, compnew_, tmp_};
  }

  SUNContext ctx_ = nullptr;
  N_Vector pool_[kPool] = {};
  N_Vector comp_[3] = {};
  N_Vector compnew_[3] = {};
  N_Vector tmp_ = nullptr;
};

TEST_P(FusedKernelAgainstReference, GivesBitwiseTheSameOutputsAndNorm) {
  const ceode::UpdatePlan plan = Plan();
  const ceode::Compensation cs = Comp();
  ceode::FusedPlan fp;
  ceode::BuildFusedPlan(plan, cs, &fp);
  Fill();
  ceode::UpdateReference(plan, cs);
  const sunrealtype ref_norm = N_VL1Norm(pool_[15]);
  const std::vector<sunrealtype> ref = Snapshot();
  Fill();
  const sunrealtype fused_norm = ceode::UpdateSerial(fp, GetParam().n);
  const std::vector<sunrealtype> fused = Snapshot();
  ASSERT_EQ(ref.size(), fused.size());
  int differing = 0;
  for (size_t i = 0; i < ref.size(); ++i) differing += ref[i] != fused[i] ? 1 : 0;
  EXPECT_EQ(differing, 0) << "of " << ref.size() << " entries";
  // The norm only feeds the growth check: the serial backend sums |x| in four partial sums, so
  // it may differ from N_VL1Norm's sum in index order by rounding (n terms of unit round-off).
  EXPECT_NEAR(fused_norm, ref_norm,
              static_cast<sunrealtype>(GetParam().n) * SUN_UNIT_ROUNDOFF * ref_norm);
}

// The longest sums the step builds (degree 8: seven history terms plus z and the accumulated
// term, compensated: plus its compensation), each term count from 1 to 11, against the
// reference; and a combination that writes one of its own inputs is refused.
TEST_P(FusedKernelAgainstReference, GivesBitwiseTheSameOutputsForEveryTermCount) {
  ceode::UpdatePlan plan;
  for (int m = 1; m <= 8; ++m) {
    ceode::Combo& cb = plan.combos[plan.n++];
    cb = ceode::Combo{};
    for (int j = 0; j < m + (m == 8 ? 2 : 0); ++j) {
      cb.Add(0.37 * (j + 1) - 0.9 + 0.01 * m, pool_[(j + m) % 8]);
    }
    cb.out = pool_[8 + m - 1];
    cb.old = m % 2 == 0 ? pool_[m - 1] : nullptr;
    cb.level = m % 3;
  }
  const ceode::Compensation cs = Comp();
  ceode::FusedPlan fp;
  ASSERT_TRUE(ceode::BuildFusedPlan(plan, cs, &fp));
  Fill();
  ceode::UpdateReference(plan, cs);
  const std::vector<sunrealtype> ref = Snapshot();
  Fill();
  ceode::UpdateSerial(fp, GetParam().n);
  const std::vector<sunrealtype> fused = Snapshot();
  int differing = 0;
  for (size_t i = 0; i < ref.size(); ++i) differing += ref[i] != fused[i] ? 1 : 0;
  EXPECT_EQ(differing, 0) << "of " << ref.size() << " entries";
  plan.combos[0].Add(0.5, plan.combos[0].out);  // reads its own output
  EXPECT_FALSE(ceode::BuildFusedPlan(plan, cs, &fp));
}

// The raw combination (CombineSerial) against Combine on the vectors, for every term count and
// the N_VLinearSum shortcuts (a = b, a = -b, unit coefficients), and the output copy.
TEST_P(FusedKernelAgainstReference, RawCombinationAndCopyGiveBitwiseTheReferenceNumbers) {
  const sunindextype n = GetParam().n;
  Fill();
  const std::vector<std::vector<sunrealtype>> weights = {
      {}, {0.7}, {0.3, 0.3}, {0.3, -0.3}, {1.0, -1.0}, {-1.0, 0.25}, {0.1, 0.2, -0.3}};
  std::vector<std::vector<sunrealtype>> all = weights;
  for (int m = 4; m <= 11; ++m) {
    std::vector<sunrealtype> c;
    for (int j = 0; j < m; ++j) c.push_back(0.37 * (j + 1) - 0.9 + 0.01 * m);
    all.push_back(c);
  }
  for (const std::vector<sunrealtype>& c : all) {
    const int m = static_cast<int>(c.size());
    N_Vector X[11];
    const sunrealtype* x[11];
    for (int j = 0; j < m; ++j) {
      X[j] = pool_[j % 8 + (j >= 8 ? 16 : 0)];
      x[j] = N_VGetArrayPointer(X[j]);
    }
    ceode::Combine(m, c.data(), X, pool_[8]);
    ceode::CombineSerial(n, m, c.data(), x, N_VGetArrayPointer(pool_[9]));
    const sunrealtype* ref = N_VGetArrayPointer(pool_[8]);
    const sunrealtype* raw = N_VGetArrayPointer(pool_[9]);
    EXPECT_TRUE(std::equal(ref, ref + n, raw)) << m << " terms";
    ceode::CombineSerial(n, m, c.data(), X, N_VGetArrayPointer(pool_[9]));
    EXPECT_TRUE(std::equal(ref, ref + n, raw)) << m << " terms, from the vectors";
  }
  ceode::CopyVector(pool_[0], pool_[10]);
  EXPECT_TRUE(std::equal(N_VGetArrayPointer(pool_[0]), N_VGetArrayPointer(pool_[0]) + n,
                         N_VGetArrayPointer(pool_[10])));
}

// CEodeEvolve's outputs are copied and tested in one pass (CopyPairFinite): the copies equal the
// sources bit for bit, and the answer is false exactly when a copied value is NaN or +-Inf, at
// the first, the last or the middle entry (the pair loop, its tail and n = 1's own path), and the
// same on serial vectors as through the N_Vector fallback (a vector of another kind).
TEST_P(FusedKernelAgainstReference, OutputCopyTellsEveryNonFiniteValueAndCopiesBitwise) {
  const sunindextype n = GetParam().n;
  Fill();
  N_Vector x = pool_[0], v = pool_[1], xout = pool_[10], vout = pool_[11];
  EXPECT_TRUE(ceode::CopyPairFinite(x, v, xout, vout));
  EXPECT_TRUE(
      std::equal(N_VGetArrayPointer(x), N_VGetArrayPointer(x) + n, N_VGetArrayPointer(xout)));
  EXPECT_TRUE(
      std::equal(N_VGetArrayPointer(v), N_VGetArrayPointer(v) + n, N_VGetArrayPointer(vout)));
  // A vector that is not NVECTOR_SERIAL takes the fallback: a serial vector with other operations.
  N_Vector other = N_VClone(x);
  other->ops->nvgetarraypointer = nullptr;
  N_VScale(1, x, other);
  for (const sunrealtype bad : {SUN_RCONST(NAN), SUN_RCONST(INFINITY), -SUN_RCONST(INFINITY)}) {
    for (const sunindextype at : {sunindextype{0}, n / 2, n - 1}) {
      for (N_Vector target : {x, v}) {
        sunrealtype& entry = N_VGetArrayPointer(target)[at];
        const sunrealtype kept = entry;
        entry = bad;
        EXPECT_FALSE(ceode::CopyPairFinite(x, v, xout, vout)) << bad << " at " << at;
        EXPECT_EQ(
            std::memcmp(N_VGetArrayPointer(target), N_VGetArrayPointer(target == x ? xout : vout),
                        sizeof(sunrealtype) * n),
            0);
        EXPECT_FALSE(ceode::AllFinite(target));
        entry = kept;
      }
      N_VScale(1, x, other);
      NV_DATA_S(other)[at] = bad;  // its array accessor is gone: the content directly
      EXPECT_FALSE(ceode::CopyPairFinite(other, v, xout, vout)) << "fallback, " << bad;
    }
  }
  Fill();
  N_VScale(1, x, other);
  EXPECT_TRUE(ceode::CopyPairFinite(other, v, xout, vout));
  EXPECT_TRUE(
      std::equal(N_VGetArrayPointer(x), N_VGetArrayPointer(x) + n, N_VGetArrayPointer(xout)));
  N_VDestroy(other);
}

std::vector<KernelCase> Cases() {
  std::vector<KernelCase> out;
  for (sunindextype n :
       {sunindextype{1}, sunindextype{2}, sunindextype{3}, sunindextype{4}, sunindextype{5},
        sunindextype{7}, kBlock - 1, kBlock, kBlock + 1, 2 * kBlock + 3, kStreamed}) {
    for (bool comp : {false, true}) out.push_back({n, comp});
  }
  return out;
}

INSTANTIATE_TEST_SUITE_P(TinyAndBlockTails, FusedKernelAgainstReference,
                         ::testing::ValuesIn(Cases()), CaseName);

// The step's own plans (BuildUpdatePlan) of every named set, out of place and in place, at the
// sizes of each serial kernel: the small kernels' pairs alone (2) and with a last entry (5), the
// pair loop with its tail (3077) and with streamed stores (2^19 + 5). Each must give the
// reference's outputs bit for bit; the reference runs the out-of-place plan (its combinations
// must not write an input), and an in-place plan's outputs are the same values in the history's
// vectors.
class StepPlanAgainstReference : public ::testing::TestWithParam<sunindextype> {
 protected:
  static constexpr int kVectors = 2 * ceode::kMaxDegree + 2;  // D, Dnew, x(t), x(t + h)
  void SetUp() override {
    ASSERT_EQ(SUNContext_Create(SUN_COMM_NULL, &ctx_), 0);
    for (N_Vector& v : pool_) v = N_VNew_Serial(GetParam(), ctx_);
  }
  void TearDown() override {
    for (N_Vector v : pool_) N_VDestroy(v);
    SUNContext_Free(&ctx_);
  }
  void Fill() {
    static constexpr sunrealtype kScale[] = {0.01, 0.1, 1, 10, 100};  // roundings differ by order
    std::uint64_t seed = 7;
    for (N_Vector v : pool_) {
      sunrealtype* d = N_VGetArrayPointer(v);
      for (sunindextype i = 0; i < GetParam(); ++i) {
        seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
        d[i] = (static_cast<double>(seed >> 11) / 9007199254740992.0 - 0.5) * kScale[seed % 5];
      }
    }
  }
  std::vector<sunrealtype> Entries(int v) const {
    const sunrealtype* d = N_VGetArrayPointer(pool_[v]);
    return {d, d + GetParam()};
  }
  // The new derivative k of the plan (in place: the history's vector).
  static int NewSlot(int d, int k, bool in_place) {
    return in_place && ceode::InPlaceLevel(d, k) ? k : ceode::kMaxDegree + k;
  }
  // The set's step coefficients at h = 0.01.
  static ceode::StepCoeffs Coeffs(const ceode::MethodSet& set) {
    ceode::StepCoeffs co;
    ceode::ComputeStepCoeffs(set.degree, set.params.data(), 0.01, &co);
    return co;
  }
  // over: the position too is written over its last value (pool_[0]), as the lean loop does.
  ceode::UpdatePlan Plan(int d, const ceode::StepCoeffs& co, bool in_place, bool over = false) {
    N_Vector D[ceode::kMaxDegree] = {};
    N_Vector Dn[ceode::kMaxDegree] = {};
    for (int k = 1; k < d; ++k) {
      D[k] = pool_[k];
      Dn[k] = pool_[NewSlot(d, k, in_place)];
    }
    ceode::UpdatePlan plan;
    ceode::BuildUpdatePlan(d, co, D, Dn, pool_[0], over ? pool_[0] : pool_[kVectors - 1], &plan);
    return plan;
  }

  int Slot(N_Vector v) const {
    return static_cast<int>(std::find(pool_, pool_ + kVectors, v) - pool_);
  }

  SUNContext ctx_ = nullptr;
  N_Vector pool_[kVectors] = {};
};

TEST_P(StepPlanAgainstReference, GivesBitwiseTheOutputsOfTheReferenceForEveryNamedSet) {
  int shaped = 0;
  for (int s = 0; s < ceode::NumMethodSets(); ++s) {
    const ceode::MethodSet& set = ceode::MethodSetAt(s);
    const int d = set.degree;
    const ceode::StepCoeffs co = Coeffs(set);
    Fill();
    ceode::UpdateReference(Plan(d, co, false), {});
    std::vector<std::vector<sunrealtype>> ref;  // the outputs: x(t + h), then level 1 .. d - 1
    ref.push_back(Entries(kVectors - 1));
    for (int k = 1; k < d; ++k) ref.push_back(Entries(NewSlot(d, k, false)));
    // Out of place, history in place, position too; each plan run once (UpdateSerial) and by the
    // kernel chosen for many runs (SerialKernel: at a few entries, each value read once).
    for (int run = 0; run < 6; ++run) {
      const int mode = run % 3;
      const bool in_place = mode > 0;
      const bool over = mode == 2;
      ceode::FusedPlan fp;
      ASSERT_TRUE(ceode::BuildFusedPlan(Plan(d, co, in_place, over), {}, &fp)) << set.name;
      shaped += fp.shape > 0 && run < 3 ? 1 : 0;
      Fill();
      if (run < 3) {
        ceode::UpdateSerial(fp, GetParam());
      } else {
        ceode::SerialKernel(fp, GetParam())(fp, GetParam());
      }
      long differing = 0;
      for (int k = 0; k < d; ++k) {
        const int slot = k == 0 ? (over ? 0 : kVectors - 1) : NewSlot(d, k, in_place);
        const std::vector<sunrealtype> got = Entries(slot);
        for (size_t i = 0; i < got.size(); ++i) differing += got[i] != ref[k][i] ? 1 : 0;
      }
      EXPECT_EQ(differing, 0) << set.name << " mode " << mode << (run < 3 ? "" : ", many runs");
    }
  }
  EXPECT_GE(shaped, 3 * 9) << "plans with a kernel of their own";
}

// A plan refreshed to another h (RefreshPlanCoefficients, as error control does when h changes)
// must give the outputs of the reference at that h bit for bit: the weights and the pairs of them
// that the shaped kernels read (a refresh that kept the old pairs fails at 2 and 5 entries).
TEST_P(StepPlanAgainstReference, GivesBitwiseTheOutputsOfTheReferenceAfterANewStepsWeights) {
  int refreshed = 0;
  for (int s = 0; s < ceode::NumMethodSets(); ++s) {
    const ceode::MethodSet& set = ceode::MethodSetAt(s);
    const int d = set.degree;
    ceode::StepCoeffs co;
    ceode::ComputeStepCoeffs(d, set.params.data(), 0.013, &co);
    Fill();
    ceode::UpdateReference(Plan(d, co, false), {});
    std::vector<std::vector<sunrealtype>> ref;  // x(t + h), then level 1 .. d - 1
    ref.push_back(Entries(kVectors - 1));
    for (int k = 1; k < d; ++k) ref.push_back(Entries(NewSlot(d, k, false)));
    ceode::KernelPlan kp;
    kp.plan = Plan(d, Coeffs(set), false);
    ceode::PreparePlan(true, &kp);
    ASSERT_TRUE(kp.serial) << set.name;
    if (!ceode::RefreshPlanCoefficients(Plan(d, co, false), &kp)) continue;  // another form
    ++refreshed;
    Fill();
    ceode::RunPlan(kp, GetParam());
    long differing = 0;
    for (int k = 0; k < d; ++k) {
      const std::vector<sunrealtype> got = Entries(k == 0 ? kVectors - 1 : NewSlot(d, k, false));
      for (size_t i = 0; i < got.size(); ++i) differing += got[i] != ref[k][i] ? 1 : 0;
    }
    EXPECT_EQ(differing, 0) << set.name;
  }
  EXPECT_GE(refreshed, 9) << "plans refreshed in place";
}

// A plan of a named set's shape whose first sum that reads a history vector also read by a later
// sum reads it from another vector (G3_CD's plan has no such vector): the roles do not match
// (RolesMatch), and the shape's kernel that reads every term through its pointer (UpdatePairs) runs
// it. It too must give the reference's outputs bit for bit.
bool MoveSharedRead(ceode::UpdatePlan* plan, int d, const N_Vector* pool, N_Vector spare) {
  for (int r = 1; r < d; ++r) {
    int first = -1;
    for (int k = 0; k < plan->n; ++k) {
      ceode::Combo& cb = plan->combos[k];
      if (std::find(cb.X, cb.X + cb.m, pool[r]) == cb.X + cb.m) continue;
      if (first >= 0) {
        ceode::Combo& f = plan->combos[first];
        std::replace(f.X, f.X + f.m, pool[r], spare);
        return true;
      }
      first = k;
    }
  }
  return false;
}

TEST_P(StepPlanAgainstReference, GivesBitwiseTheOutputsOfTheReferenceWhenTheRolesDoNotMatch) {
  constexpr int kSpare = ceode::kMaxDegree;  // a slot that no plan reads or writes
  int moved = 0;
  for (int s = 0; s < ceode::NumMethodSets(); ++s) {
    const ceode::MethodSet& set = ceode::MethodSetAt(s);
    const int d = set.degree;
    const ceode::StepCoeffs co = Coeffs(set);
    ceode::UpdatePlan plan = Plan(d, co, false);
    if (!MoveSharedRead(&plan, d, pool_, pool_[kSpare])) continue;  // each read by one sum
    ++moved;
    Fill();
    ceode::UpdateReference(plan, {});
    std::vector<std::vector<sunrealtype>> ref;
    for (int k = 0; k < plan.n; ++k) ref.push_back(Entries(Slot(plan.combos[k].out)));
    ceode::FusedPlan fp;
    ASSERT_TRUE(ceode::BuildFusedPlan(plan, {}, &fp)) << set.name;
    Fill();
    ceode::UpdateSerial(fp, GetParam());
    long differing = 0;
    for (int k = 0; k < plan.n; ++k) {
      const std::vector<sunrealtype> got = Entries(Slot(plan.combos[k].out));
      for (size_t i = 0; i < got.size(); ++i) differing += got[i] != ref[k][i] ? 1 : 0;
    }
    EXPECT_EQ(differing, 0) << set.name;
  }
  EXPECT_GE(moved, 8) << "every shape but G3_CD's, whose history vectors feed one sum each";
}

INSTANTIATE_TEST_SUITE_P(EachSerialKernel, StepPlanAgainstReference,
                         ::testing::Values(sunindextype{1}, sunindextype{2}, sunindextype{3},
                                           sunindextype{5}, 3 * ceode::kInPlaceMinLen + 5,
                                           kStreamed),
                         [](const ::testing::TestParamInfo<sunindextype>& info) {
                           return "Size" + std::to_string(info.param);
                         });

}  // namespace kernel

namespace {

// Whether two coefficient tables hold the same bits in every entry (the fields one by one: the
// padding after the degree is not compared).
bool SameTable(const ceode::StepCoeffs& a, const ceode::StepCoeffs& b) {
  constexpr size_t kD = ceode::kMaxDegree;
  const auto same = [](const sunrealtype* x, const sunrealtype* y, size_t n) {
    return std::memcmp(x, y, n * sizeof(sunrealtype)) == 0;
  };
  return a.degree == b.degree && same(&a.h, &b.h, 1) && same(&a.T[0][0], &b.T[0][0], kD * kD) &&
         same(a.c, b.c, kD) && same(a.w, b.w, kD) && same(&a.wz_old, &b.wz_old, 1) &&
         same(&a.wz_new, &b.wz_new, 1) && same(a.V0, b.V0, kD) && same(&a.kappa, &b.kappa, 1) &&
         same(&a.mu, &b.mu, 1) && same(a.pred, b.pred, kD) && same(a.tw, b.tw, kD + 1);
}

}  // namespace

// ComputeStepCoeffs keeps a table's zeros while the degree stays and writes every other entry
// (the adaptive step's change of h): a table reused after every set, another h and the other form
// of the Taylor weights holds the bits of a fresh one.
TEST(StepCoefficients, AReusedTableHoldsTheBitsOfAFreshOne) {
  const int nsets = ceode::NumMethodSets();
  ceode::StepCoeffs reused;
  int same = 0;
  for (int a = 0; a < nsets; ++a) {
    for (int b = 0; b < nsets; ++b) {
      for (bool products : {false, true}) {
        const ceode::MethodSet& first = ceode::MethodSetAt(a);
        const ceode::MethodSet& next = ceode::MethodSetAt(b);
        ceode::ComputeStepCoeffs(first.degree, first.params.data(), 0.03, &reused, !products);
        ceode::ComputeStepCoeffs(next.degree, next.params.data(), 0.007, &reused, products);
        ceode::StepCoeffs fresh;
        ceode::ComputeStepCoeffs(next.degree, next.params.data(), 0.007, &fresh, products);
        const bool equal = SameTable(reused, fresh);
        EXPECT_TRUE(equal) << first.name << " then " << next.name << ", products " << products;
        same += equal ? 1 : 0;
      }
    }
  }
  EXPECT_EQ(same, 2 * nsets * nsets);
}
