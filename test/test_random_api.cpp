// Random API sequences (fixed seeds, so every failure replays): setters with valid and invalid
// values, objects of right and wrong sizes, degenerate step sizes, Evolve, ReInit, Init with a
// new size and GetDky in any order. Whatever the sequence, no call may crash (the sanitizer build
// runs this test) and every CE_SUCCESS / CE_TSTOP_RETURN must come with finite outputs and a
// finite tret.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "ceode_testing.h"  // CEodeSetFusedKernel
#include "test_util.hpp"

namespace {

using namespace ceode_test;  // the handles and helpers of test_util.hpp

// x'' = -x - 0.1 x' (any length), M = 2 I in the matrix's own size.
int Rhs(sunrealtype, N_Vector x, N_Vector v, N_Vector f, void*) {
  N_VLinearSum(-1, x, SUN_RCONST(-0.1), v, f);
  return 0;
}
int Mass(sunrealtype, N_Vector, SUNMatrix M, void*, N_Vector, N_Vector, N_Vector) {
  for (sunindextype j = 0; j < SUNDenseMatrix_Columns(M) && j < SUNDenseMatrix_Rows(M); ++j)
    SUNDenseMatrix_Column(M, j)[j] = 2;
  return 0;
}

bool AllFinite(N_Vector y) {
  for (sunindextype i = 0; i < N_VGetLength(y); ++i) {
    if (!std::isfinite(NV_Ith_S(y, i))) return false;
  }
  return true;
}

class Sequence {
 public:
  explicit Sequence(std::uint32_t seed) : rng_(seed) {
    mem_.reset(CEodeCreate(ctx_));
    CEodeSetErrFile(mem_.get(), nullptr);
    // One dense solver and matrix per size 1..4, kept alive for the whole sequence.
    for (sunindextype n = 1; n <= 4; ++n) {
      vecs_.push_back(SerialVector(n, ctx_, 1));
      mats_.emplace_back(SUNDenseMatrix(n, n, ctx_));
      masses_.emplace_back(SUNDenseMatrix(n, n, ctx_));
      solvers_.emplace_back(SUNLinSol_Dense(vecs_.back().get(), mats_.back().get(), ctx_));
    }
  }

  // Runs `ops` random calls; returns the number of violations (non-finite output on success).
  int Run(int ops) {
    Init();
    CEodeSetFixedStep(mem_.get(), SUN_RCONST(0.01));
    int bad = 0;
    for (int i = 0; i < ops; ++i) bad += Step();
    return bad;
  }
  int successes() const { return successes_; }

 private:
  sunrealtype Pick(std::initializer_list<sunrealtype> values) {
    std::uniform_int_distribution<size_t> d(0, values.size() - 1);
    return *(values.begin() + d(rng_));
  }
  int Int(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }

  void Init() {
    n_ = Int(1, 3);
    x_ = SerialVector(n_, ctx_, Pick({0, 1, -2, 1e100}));
    v_ = SerialVector(n_, ctx_, Pick({0, 0.5, 1e3}));
    CEodeInit(mem_.get(), Rhs, Pick({0, 1, -5, 1e20}), x_.get(), v_.get());
    CEodeSetStabilityGuard(mem_.get(), CE_GUARD_OFF, 0);
    CEodeSetMaxNumSteps(mem_.get(), 3000);
  }

  int Evolve() {
    if (!x_) return 0;
    sunrealtype t = NAN, tcur = 0;
    CEodeGetCurrentTime(mem_.get(), &tcur);
    const sunrealtype tout = tcur + Pick({-1, 0, 1e-4, 0.01, 0.3, 1, 2, NAN});
    const int itask = Int(0, 3) == 0 ? CE_ONE_STEP : CE_NORMAL;
    const int flag = CEodeEvolve(mem_.get(), tout, x_.get(), v_.get(), &t, itask);
    if (flag != CE_SUCCESS && flag != CE_TSTOP_RETURN) return 0;
    ++successes_;
    return AllFinite(x_.get()) && AllFinite(v_.get()) && std::isfinite(t) ? 0 : 1;
  }

  int GetDky() {
    if (!x_) return 0;
    Vector dky = SerialVector(n_, ctx_);
    sunrealtype tcur = 0, h = 0;
    CEodeGetCurrentTime(mem_.get(), &tcur);
    CEodeGetCurrentStep(mem_.get(), &h);
    const sunrealtype t = tcur + h * Pick({0, 0.5, 1, 2, -1, NAN, INFINITY});
    if (CEodeGetDky(mem_.get(), t, Int(-1, 9), dky.get()) != CE_SUCCESS) return 0;
    ++successes_;
    return AllFinite(dky.get()) ? 0 : 1;
  }

  void SetMethod() {
    const int degree = Int(2, 9);
    std::vector<sunrealtype> p(8);
    for (auto& q : p) q = Pick({0, 0.25, 0.5, 1, 4.0 / 3, 2, -1, 5e-324, 1e300, NAN});
    CEodeSetMethod(mem_.get(), degree, p.data());
  }

  void SetSolvers() {
    const int k = Int(0, 3);
    switch (Int(0, 3)) {
      case 0:
        CEodeSetLinearSolver(mem_.get(), solvers_[k].get(), mats_[k].get());
        break;
      case 1:
        CEodeSetMassFn(mem_.get(), Mass, masses_[k].get(), Int(0, 1) ? SUNTRUE : SUNFALSE);
        break;
      case 2:
        CEodeSetMassFn(mem_.get(), nullptr, nullptr, SUNTRUE);
        break;
      default:
        CEodeSetLinearSolver(mem_.get(), solvers_[k].get(), mats_[Int(0, 3)].get());
        break;
    }
  }

  // Tolerances, step bounds and the error-control getters, with every kind of bad argument.
  void ErrorControl() {
    void* m = mem_.get();
    const sunrealtype bad[] = {0, 1e-8, 1e-3, -1, NAN, INFINITY, 1e300};
    switch (Int(0, 6)) {
      case 0:
        CEodeSStolerances(m, bad[Int(0, 6)], bad[Int(0, 6)]);
        break;
      case 1:
        CEodeSVtolerances(m, bad[Int(0, 6)], Int(0, 1) && x_ ? v_.get() : nullptr);
        break;
      case 2:
        CEodeSetInitStep(m, bad[Int(0, 6)]);
        CEodeSetMaxStep(m, bad[Int(0, 6)]);
        break;
      case 3:
        CEodeSetMinStep(m, bad[Int(0, 6)]);
        CEodeSetMaxErrTestFails(m, Int(-1, 9));
        break;
      case 4:
        CEodeSetAdaptivityMethod(m, Int(-1, 2));
        break;
      case 5: {
        sunrealtype h = 0;
        long int n = 0;
        CEodeGetLastStep(m, Int(0, 3) ? &h : nullptr);
        CEodeGetActualInitStep(m, &h);
        CEodeGetNumErrTestFails(m, Int(0, 3) ? &n : nullptr);
        CEodeGetNumStableStepLimited(m, &n);
        if (x_) CEodeGetErrWeights(m, x_.get());
        break;
      }
      default:
        if (x_) CEodeGetEstLocalErrors(m, Int(0, 1) ? x_.get() : nullptr);
        break;
    }
  }

  int Step() {
    void* m = mem_.get();
    switch (Int(0, 18)) {
      case 0:
        Init();
        return 0;
      case 1:
        if (x_) CEodeReInit(m, Pick({0, 2, NAN}), x_.get(), v_.get());
        return 0;
      case 2:
        CEodeSetFixedStep(m, Pick({1e-3, 1e-2, 1e-2, 0.1, 0.1, 0.3, 1, 7.9e-323, 1e-300, 1e-150,
                                   1e300, -1, 0, NAN, INFINITY}));
        return 0;
      case 3:
        CEodeSetMethodByName(m, CEodeGetMethodName(Int(-1, CEodeGetNumMethods())));
        return 0;
      case 4:
        SetMethod();
        return 0;
      case 5:
        if (Int(0, 1)) {
          CEodeSetVelocityDependence(m, Int(-1, 2));  // -1 and 2 are refused
        } else {  // 3: inside the enum type's range of values, outside its enumerators
          CEodeSetVelocityMode(m, static_cast<CEodeVelocityMode>(Int(0, 3)));
        }
        return 0;
      case 6:
        SetSolvers();
        return 0;
      case 7:
        CEodeSetNonlinTolerances(m, Pick({1e-10, 0, -1, INFINITY, NAN}),
                                 Pick({0, 1e-12, -1, INFINITY, NAN}));
        return 0;
      case 8:
        if (Int(0, 1)) {
          sunrealtype tcur = 0;
          CEodeGetCurrentTime(m, &tcur);
          CEodeSetStopTime(m, tcur + Pick({-1, 0.05, 0.5, NAN}));
        } else {
          CEodeClearStopTime(m);
        }
        return 0;
      case 9:
        CEodeSetZeroStart(m, Int(0, 1) ? SUNTRUE : SUNFALSE);
        CEodeSetCompensatedSummation(m, Int(0, 1) ? SUNTRUE : SUNFALSE);
        CEodeSetFusedKernel(m, Int(0, 1) ? SUNTRUE : SUNFALSE);
        return 0;
      case 10:
        CEodeSetMaxNonlinIters(m, Int(-1, 8));
        return 0;
      case 11:
        return GetDky();
      case 12:
        ErrorControl();
        return 0;
      default:
        return Evolve();
    }
  }

  std::mt19937 rng_;
  Context ctx_;
  Mem mem_;
  sunindextype n_ = 0;
  Vector x_, v_;
  std::vector<Vector> vecs_;
  std::vector<Matrix> mats_, masses_;
  std::vector<LinearSolver> solvers_;
  int successes_ = 0;
};

TEST(RandomApiSequences, NeverCrashAndNeverReturnNonFiniteValuesWithSuccess) {
  int bad = 0, successes = 0;
  for (std::uint32_t seed = 1; seed <= 1000; ++seed) {
    Sequence seq(seed);
    const int b = seq.Run(80);
    EXPECT_EQ(b, 0) << "seed " << seed;
    bad += b;
    successes += seq.successes();
  }
  EXPECT_EQ(bad, 0);
  std::printf("%d successful Evolve/GetDky calls checked\n", successes);
  // The sequences must reach real integrations, or they would test nothing but refusals.
  EXPECT_GT(successes, 5000) << successes;
}

}  // namespace
