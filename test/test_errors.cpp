// Bad input gets a clear error: the right flag, a message that names the
// function and says what to do, and memory that stays usable afterwards.
#include <gtest/gtest.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_sparse.h>
#include <sunnonlinsol/sunnonlinsol_newton.h>

#include <cmath>
#include <string>
#include <vector>

#include "ceode_testing.h"  // CEodeSetSchurComplement
#include "test_util.hpp"

namespace {

using ceode_test::Context;
using ceode_test::FlagName;
using ceode_test::Harmonic;
using ceode_test::LinearSolver;
using ceode_test::Matrix;
using ceode_test::Mem;
using ceode_test::SerialVector;
using ceode_test::Vector;

using ceode_test::Contains;

struct Reported {
  int code;
  std::string module;
  std::string function;
  std::string msg;
};

void CollectErrors(int code, const char* module, const char* function, char* msg, void* data) {
  static_cast<std::vector<Reported>*>(data)->push_back({code, module, function, msg});
}

// A problem whose f misbehaves on request: returns a flag or NaN after t_bad.
struct Faulty {
  Harmonic harmonic;
  sunrealtype t_bad = INFINITY;
  int retval = 0;  // returned from t_bad on (0: return NaN values instead)
  bool nan = false;
  static int Rhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
    auto* p = static_cast<Faulty*>(data);
    Harmonic::F(t, x, v, f, &p->harmonic);
    if (t >= p->t_bad) {
      if (p->retval != 0) return p->retval;
      if (p->nan) N_VConst(NAN, f);
    }
    return 0;
  }
};

class BadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    mem_.reset(CEodeCreate(ctx_));
    ASSERT_NE(mem_, nullptr);
    ASSERT_EQ(CEodeSetErrHandlerFn(mem(), CollectErrors, &errors_), CE_SUCCESS);
    x_ = SerialVector(2, ctx_, 1);
    v_ = SerialVector(2, ctx_, SUN_RCONST(0.5));
  }
  void* mem() { return mem_.get(); }
  int Init() { return CEodeInit(mem(), Faulty::Rhs, 0, x_.get(), v_.get()); }
  int SetUpRun(sunrealtype h = SUN_RCONST(0.01)) {
    int flag = Init();
    if (flag == CE_SUCCESS) flag = CEodeSetUserData(mem(), &prob_);
    if (flag == CE_SUCCESS) flag = CEodeSetFixedStep(mem(), h);
    // The guard's stability sweep is not the subject (except where a test turns
    // it back on), and it is slow under the sanitizers.
    if (flag == CE_SUCCESS) flag = CEodeSetStabilityGuard(mem(), CE_GUARD_OFF, 0);
    return flag;
  }
  int Evolve(sunrealtype tout, sunrealtype* t) {
    return CEodeEvolve(mem(), tout, x_.get(), v_.get(), t, CE_NORMAL);
  }
  // The message of the last error, checked to name the failing function.
  std::string LastMessage(const char* function) {
    EXPECT_FALSE(errors_.empty());
    if (errors_.empty()) return "";
    EXPECT_EQ(errors_.back().module, "CEODE");
    EXPECT_EQ(errors_.back().function, function);
    const char* last = nullptr;
    EXPECT_EQ(CEodeGetLastErrorMessage(mem(), &last), CE_SUCCESS);
    EXPECT_EQ(errors_.back().msg, std::string(last));
    return errors_.back().msg;
  }
  bool Finite() const {
    return std::isfinite(N_VL1Norm(x_.get())) && std::isfinite(N_VL1Norm(v_.get()));
  }

  Context ctx_;
  Mem mem_;
  Vector x_, v_;
  Faulty prob_;
  std::vector<Reported> errors_;
};

TEST(NullMemory, IsRejectedByEveryKindOfCallWithAHintToCreateIt) {
  Context ctx;
  Vector x = SerialVector(1, ctx);
  sunrealtype t = 0;
  long int n = 0;
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(CEodeInit(nullptr, Harmonic::F, 0, x.get(), x.get()), CE_MEM_NULL);
  EXPECT_EQ(CEodeReInit(nullptr, 0, x.get(), x.get()), CE_MEM_NULL);
  EXPECT_EQ(CEodeSetFixedStep(nullptr, 1), CE_MEM_NULL);
  EXPECT_EQ(CEodeSetMethodByName(nullptr, "G5"), CE_MEM_NULL);
  EXPECT_EQ(CEodeEvolve(nullptr, 1, x.get(), x.get(), &t, CE_NORMAL), CE_MEM_NULL);
  EXPECT_EQ(CEodeGetNumSteps(nullptr, &n), CE_MEM_NULL);
  EXPECT_EQ(CEodeGetNumConstrJacEvals(nullptr, &n), CE_MEM_NULL);
  EXPECT_EQ(CEodeSetSchurComplement(nullptr, SUNFALSE), CE_MEM_NULL);
  EXPECT_EQ(CEodePrintAllStats(nullptr, stdout, SUN_OUTPUTFORMAT_TABLE), CE_MEM_NULL);
  EXPECT_EQ(CEodeCreate(nullptr), nullptr);
  void* none = nullptr;
  CEodeFree(&none);  // harmless, as CVodeFree
  CEodeFree(nullptr);
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_TRUE(Contains(err, "CEodeEvolve"));
  EXPECT_TRUE(Contains(err, "CE_MEM_NULL"));
  EXPECT_TRUE(Contains(err, "CEodeCreate"));
  EXPECT_TRUE(Contains(err, "SUNContext_Create"));
}

TEST_F(BadInput, TheConstraintJacobianCounterRefusesANullOutputPointer) {
  ASSERT_EQ(Init(), CE_SUCCESS);
  EXPECT_EQ(CEodeGetNumConstrJacEvals(mem(), nullptr), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage("CEodeGetNumConstrJacEvals"), "output pointer is NULL"));
}

TEST_F(BadInput, InitRejectsInitialVectorsOfDifferentLengths) {
  Vector v3 = SerialVector(3, ctx_);
  EXPECT_EQ(CEodeInit(mem(), Faulty::Rhs, 0, x_.get(), v3.get()), CE_ILL_INPUT);
  const std::string msg = LastMessage("CEodeInit");
  EXPECT_TRUE(Contains(msg, "2"));
  EXPECT_TRUE(Contains(msg, "3"));
  EXPECT_TRUE(Contains(msg, "same length"));
  EXPECT_EQ(CEodeInit(mem(), Faulty::Rhs, 0, x_.get(), nullptr), CE_ILL_INPUT);
  EXPECT_EQ(CEodeInit(mem(), nullptr, 0, x_.get(), v_.get()), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage("CEodeInit"), "right-hand side"));
  N_VConst(NAN, x_.get());
  EXPECT_EQ(Init(), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage("CEodeInit"), "NaN"));
}

TEST_F(BadInput, EvolveAndReInitRejectVectorsOfTheWrongLength) {
  ASSERT_EQ(SetUpRun(), CE_SUCCESS);
  Vector x3 = SerialVector(3, ctx_);
  sunrealtype t = 0;
  EXPECT_EQ(CEodeEvolve(mem(), 1, x3.get(), v_.get(), &t, CE_NORMAL), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage("CEodeEvolve"), "xout has 3 entries but the problem has 2"));
  EXPECT_EQ(CEodeEvolve(mem(), 1, x_.get(), x3.get(), &t, CE_NORMAL), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage("CEodeEvolve"), "vout"));
  EXPECT_EQ(CEodeEvolve(mem(), 1, x_.get(), nullptr, &t, CE_NORMAL), CE_ILL_INPUT);
  EXPECT_EQ(CEodeEvolve(mem(), 1, x_.get(), v_.get(), nullptr, CE_NORMAL), CE_ILL_INPUT);
  EXPECT_EQ(CEodeEvolve(mem(), 1, x_.get(), v_.get(), &t, 7), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage("CEodeEvolve"), "CE_ONE_STEP"));
  EXPECT_EQ(CEodeReInit(mem(), 0, x3.get(), x3.get()), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage("CEodeReInit"), "CEodeInit"));
  // Nothing was disturbed: the run goes ahead.
  EXPECT_EQ(Evolve(1, &t), CE_SUCCESS);
  EXPECT_DOUBLE_EQ(t, 1);
}

TEST_F(BadInput, FixedStepMustBePositiveAndFinite) {
  ASSERT_EQ(Init(), CE_SUCCESS);
  for (sunrealtype h : {SUN_RCONST(0.0), SUN_RCONST(-0.1), static_cast<sunrealtype>(NAN),
                        static_cast<sunrealtype>(INFINITY)}) {
    EXPECT_EQ(CEodeSetFixedStep(mem(), h), CE_ILL_INPUT) << h;
    EXPECT_TRUE(Contains(LastMessage("CEodeSetFixedStep"), "positive and finite"));
  }
}

TEST_F(BadInput, UnknownMethodNameIsRejectedWithTheListOfKnownNames) {
  ASSERT_EQ(Init(), CE_SUCCESS);
  EXPECT_EQ(CEodeSetMethodByName(mem(), "G7_FAST"), CE_ILL_INPUT);
  const std::string msg = LastMessage("CEodeSetMethodByName");
  EXPECT_TRUE(Contains(msg, "G7_FAST"));
  for (int i = 0; i < CEodeGetNumMethods(); ++i) EXPECT_TRUE(Contains(msg, CEodeGetMethodName(i)));
  EXPECT_EQ(CEodeSetMethodByName(mem(), nullptr), CE_ILL_INPUT);
  EXPECT_EQ(CEodeSetMethodByName(mem(), ""), CE_ILL_INPUT);
  EXPECT_EQ(CEodeSetMethodByName(mem(), "g5"), CE_ILL_INPUT);  // names are exact
  EXPECT_EQ(CEodeGetMethodName(-1), nullptr);
  EXPECT_EQ(CEodeGetMethodName(CEodeGetNumMethods()), nullptr);
}

TEST_F(BadInput, InvalidDegreeOrParametersAreRejected) {
  ASSERT_EQ(Init(), CE_SUCCESS);
  const sunrealtype p[] = {1, SUN_RCONST(0.5), SUN_RCONST(0.5), 1, 1, 1, 1, 1, 1};
  EXPECT_EQ(CEodeSetMethod(mem(), 2, p), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage("CEodeSetMethod"), "supported degrees are 3.."));
  EXPECT_EQ(CEodeSetMethod(mem(), 99, p), CE_ILL_INPUT);
  EXPECT_EQ(CEodeSetMethod(mem(), 3, nullptr), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage("CEodeSetMethod"), "params = NULL"));
  const sunrealtype zero_beta[] = {1, 0};
  EXPECT_EQ(CEodeSetMethod(mem(), 3, zero_beta), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage("CEodeSetMethod"), "beta"));
  const sunrealtype zero_gamma[] = {SUN_RCONST(0.75), SUN_RCONST(1.0) / 3, 0};
  EXPECT_EQ(CEodeSetMethod(mem(), 4, zero_gamma), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage("CEodeSetMethod"), "gamma"));
  const sunrealtype nan_param[] = {1, SUN_RCONST(0.5), static_cast<sunrealtype>(NAN)};
  EXPECT_EQ(CEodeSetMethod(mem(), 4, nan_param), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage("CEodeSetMethod"), "params[2]"));
}

TEST_F(BadInput, EvolveBeforeInitSaysToCallCEodeInit) {
  sunrealtype t = 0;
  EXPECT_EQ(Evolve(1, &t), CE_NO_MALLOC);
  EXPECT_TRUE(Contains(LastMessage("CEodeEvolve"), "CEodeInit"));
  EXPECT_EQ(CEodeReInit(mem(), 0, x_.get(), v_.get()), CE_NO_MALLOC);
}

TEST_F(BadInput, EvolveWithoutAStepSizeSaysToCallCEodeSetFixedStep) {
  ASSERT_EQ(Init(), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(1, &t), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage("CEodeEvolve"), "CEodeSetFixedStep"));
  EXPECT_EQ(t, 0);  // tret is the current time
}

TEST_F(BadInput, ToutBehindTheCurrentTimeIsRejectedAndTheRunCanGoOn) {
  ASSERT_EQ(SetUpRun(), CE_SUCCESS);
  sunrealtype t = 0;
  ASSERT_EQ(Evolve(1, &t), CE_SUCCESS);
  EXPECT_EQ(Evolve(SUN_RCONST(0.5), &t), CE_BAD_T);
  const std::string msg = LastMessage("CEodeEvolve");
  EXPECT_TRUE(Contains(msg, "behind the current time"));
  EXPECT_TRUE(Contains(msg, "CEodeReInit"));
  EXPECT_EQ(Evolve(2, &t), CE_SUCCESS);
  EXPECT_DOUBLE_EQ(t, 2);
}

TEST_F(BadInput, AFailingRightHandSideStopsTheRunWithItsFlagAndTheLastGoodState) {
  for (int retval : {-1, 1}) {
    SCOPED_TRACE(retval);
    prob_ = Faulty{};
    prob_.t_bad = SUN_RCONST(0.5);
    prob_.retval = retval;
    ASSERT_EQ(SetUpRun(), CE_SUCCESS);
    sunrealtype t = 0;
    EXPECT_EQ(Evolve(1, &t), CE_RHSFUNC_FAIL);
    const std::string msg = LastMessage("CEodeEvolve");
    EXPECT_TRUE(Contains(msg, "returned " + std::to_string(retval)));
    EXPECT_TRUE(Contains(msg, "right-hand side"));
    // The failing evaluation is at the first step time >= 0.5; the state returned
    // is the last one the method completed, one step earlier.
    EXPECT_NEAR(t, 0.49, 1e-12);
    EXPECT_TRUE(Finite());
  }
}

TEST_F(BadInput, ARightHandSideFailingAtTheStartIsReported) {
  prob_.t_bad = 0;
  prob_.retval = -3;
  ASSERT_EQ(SetUpRun(), CE_SUCCESS);
  sunrealtype t = 1;
  EXPECT_EQ(Evolve(1, &t), CE_RHSFUNC_FAIL);
  EXPECT_TRUE(Contains(LastMessage("CEodeEvolve"), "returned -3"));
  EXPECT_EQ(t, 0);
}

TEST_F(BadInput, ARightHandSideFailingInsideTheNonlinearSolveIsReported) {
  prob_.t_bad = SUN_RCONST(0.5);
  prob_.retval = -2;
  ASSERT_EQ(SetUpRun(), CE_SUCCESS);
  ASSERT_EQ(CEodeSetVelocityDependence(mem(), SUNTRUE), CE_SUCCESS);       // fixed point
  ASSERT_EQ(CEodeSetImplicitMode(mem(), CE_IMPLICIT_NEWTON), CE_SUCCESS);  // not AUTO's PC
  sunrealtype t = 0;
  EXPECT_EQ(Evolve(1, &t), CE_RHSFUNC_FAIL);
  EXPECT_TRUE(Contains(LastMessage("CEodeEvolve"), "nonlinear solve"));
  EXPECT_TRUE(Finite());
}

TEST_F(BadInput, NaNFromTheRightHandSideIsReportedAndReInitRecovers) {
  prob_.t_bad = SUN_RCONST(0.5);
  prob_.nan = true;
  ASSERT_EQ(SetUpRun(), CE_SUCCESS);
  ASSERT_EQ(CEodeSetMethodByName(mem(), "G4_A34"), CE_SUCCESS);
  sunrealtype t = 0;
  EXPECT_EQ(Evolve(1, &t), CE_RHSFUNC_FAIL);
  const std::string msg = LastMessage("CEodeEvolve");
  EXPECT_TRUE(Contains(msg, "NaN"));
  EXPECT_TRUE(Contains(msg, "f returned non-finite values"));
  EXPECT_NEAR(t, 0.49, 1e-12);
  EXPECT_TRUE(Finite());

  // Repair f, restart from the initial data: the memory is as good as new.
  prob_.nan = false;
  Vector x0 = SerialVector(2, ctx_, 1);
  Vector v0 = SerialVector(2, ctx_, SUN_RCONST(0.5));
  ASSERT_EQ(CEodeReInit(mem(), 0, x0.get(), v0.get()), CE_SUCCESS);
  ASSERT_EQ(Evolve(1, &t), CE_SUCCESS);
  long int nst = 0;
  CEodeGetNumSteps(mem(), &nst);
  EXPECT_EQ(nst, 100);
  sunrealtype xe = 0, ve = 0;
  prob_.harmonic.Exact(1, &xe, &ve);
  EXPECT_NEAR(NV_Ith_S(x_.get(), 0), xe, 1e-6);  // third order, h = 0.01
  EXPECT_NEAR(NV_Ith_S(v_.get(), 1), ve, 1e-6);
}

TEST_F(BadInput, NaNFromTheRightHandSideInsideTheNewtonSolveIsReported) {
  prob_.t_bad = SUN_RCONST(0.5);
  prob_.nan = true;
  ASSERT_EQ(SetUpRun(), CE_SUCCESS);
  Matrix A(SUNDenseMatrix(2, 2, ctx_));
  LinearSolver LS(SUNLinSol_Dense(x_.get(), A.get(), ctx_));
  ASSERT_EQ(CEodeSetVelocityDependence(mem(), SUNTRUE), CE_SUCCESS);
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS.get(), A.get()), CE_SUCCESS);
  sunrealtype t = 0;
  EXPECT_EQ(Evolve(1, &t), CE_RHSFUNC_FAIL);
  const std::string msg = LastMessage("CEodeEvolve");
  EXPECT_TRUE(Contains(msg, "f returned non-finite values"));
  EXPECT_FALSE(Contains(msg, "reduce h"));
  EXPECT_TRUE(Finite());
  EXPECT_NEAR(t, 0.49, 1e-12);
}

TEST_F(BadInput, NaNInTheInitialAccelerationIsAFirstRhsError) {
  prob_.t_bad = 0;
  prob_.nan = true;
  ASSERT_EQ(SetUpRun(), CE_SUCCESS);
  sunrealtype t = 0;
  EXPECT_EQ(Evolve(1, &t), CE_FIRST_RHSFUNC_ERR);
  EXPECT_TRUE(Contains(LastMessage("CEodeEvolve"), "initial acceleration"));
}

int SingularMass(sunrealtype /*t*/, N_Vector /*x*/, SUNMatrix M, void* /*data*/, N_Vector, N_Vector,
                 N_Vector) {
  SM_ELEMENT_D(M, 0, 0) = 1;  // second coordinate massless: M is singular
  return 0;
}

TEST_F(BadInput, ASingularMassMatrixFailsInTheLinearSolverSetup) {
  ASSERT_EQ(SetUpRun(), CE_SUCCESS);
  Matrix M(SUNDenseMatrix(2, 2, ctx_));
  Matrix A(SUNDenseMatrix(2, 2, ctx_));
  LinearSolver LS(SUNLinSol_Dense(x_.get(), A.get(), ctx_));
  ASSERT_EQ(CEodeSetMassFn(mem(), SingularMass, M.get(), SUNTRUE), CE_SUCCESS);
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS.get(), A.get()), CE_SUCCESS);
  sunrealtype t = 0;
  EXPECT_EQ(Evolve(1, &t), CE_LSETUP_FAIL);
  const std::string msg = LastMessage("CEodeEvolve");
  EXPECT_TRUE(Contains(msg, "singular"));
  EXPECT_TRUE(Contains(msg, "CEodeSetConstraints"));
}

TEST_F(BadInput, AMassMatrixWithoutALinearSolverSaysToAttachOne) {
  ASSERT_EQ(SetUpRun(), CE_SUCCESS);
  Matrix M(SUNDenseMatrix(2, 2, ctx_));
  ASSERT_EQ(CEodeSetMassFn(mem(), SingularMass, M.get(), SUNTRUE), CE_SUCCESS);
  sunrealtype t = 0;
  EXPECT_EQ(Evolve(1, &t), CE_LINIT_FAIL);
  EXPECT_TRUE(Contains(LastMessage("CEodeEvolve"), "CEodeSetLinearSolver"));
  // Half a mass specification is refused at once.
  EXPECT_EQ(CEodeSetMassFn(mem(), SingularMass, nullptr, SUNTRUE), CE_ILL_INPUT);
}

TEST_F(BadInput, ANewtonSolverWithoutALinearSolverSaysToAttachOne) {
  ASSERT_EQ(SetUpRun(), CE_SUCCESS);
  ASSERT_EQ(CEodeSetVelocityDependence(mem(), SUNTRUE), CE_SUCCESS);
  SUNNonlinearSolver nls = SUNNonlinSol_Newton(x_.get(), ctx_);
  ASSERT_EQ(CEodeSetNonlinearSolver(mem(), nls), CE_SUCCESS);
  sunrealtype t = 0;
  EXPECT_EQ(Evolve(1, &t), CE_NLS_INIT_FAIL);
  EXPECT_TRUE(Contains(LastMessage("CEodeEvolve"), "CEodeSetLinearSolver"));
  mem_.reset();  // the user's solver outlives the memory that uses it
  SUNNonlinSolFree(nls);
}

TEST_F(BadInput, ASparseMatrixWithoutAJacobianFunctionSaysToSupplyOne) {
  ASSERT_EQ(SetUpRun(), CE_SUCCESS);
  ASSERT_EQ(CEodeSetVelocityDependence(mem(), SUNTRUE), CE_SUCCESS);
  Matrix A(SUNSparseMatrix(2, 2, 4, CSC_MAT, ctx_));
  LinearSolver LS(SUNLinSol_KLU(x_.get(), A.get(), ctx_));
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS.get(), A.get()), CE_SUCCESS);
  sunrealtype t = 0;
  EXPECT_EQ(Evolve(1, &t), CE_LINIT_FAIL);
  EXPECT_TRUE(Contains(LastMessage("CEodeEvolve"), "CEodeSetVelJacFn"));
}

TEST_F(BadInput, AStepBeyondTheStabilityLimitIsRefusedWhenTheGuardSaysSo) {
  prob_.harmonic.w = 10;  // Omega = 10 h = 5 > 2 = Omega_max of central differences
  ASSERT_EQ(SetUpRun(SUN_RCONST(0.5)), CE_SUCCESS);
  ASSERT_EQ(CEodeSetStabilityGuard(mem(), CE_GUARD_REFUSE, 0), CE_SUCCESS);
  sunrealtype t = 0;
  EXPECT_EQ(Evolve(100, &t), CE_UNSTABLE);
  // Without the guard the state blows up and the run stops at the first non-finite state.
  ASSERT_EQ(CEodeSetStabilityGuard(mem(), CE_GUARD_OFF, 0), CE_SUCCESS);
  EXPECT_EQ(Evolve(1e6, &t), CE_UNSTABLE);
  EXPECT_TRUE(Contains(LastMessage("CEodeEvolve"), "reduce h"));
  EXPECT_TRUE(Finite());
}

TEST(ErrorReporting, WithoutAHandlerGoesToTheErrorFileAndNowhereWhenItIsNull) {
  Context ctx;
  Mem mem(CEodeCreate(ctx));
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(CEodeSetFixedStep(mem.get(), -1), CE_ILL_INPUT);
  const std::string on = ::testing::internal::GetCapturedStderr();
  EXPECT_TRUE(Contains(on, "CEodeSetFixedStep"));
  EXPECT_TRUE(Contains(on, "CE_ILL_INPUT"));
  ASSERT_EQ(CEodeSetErrFile(mem.get(), nullptr), CE_SUCCESS);
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(CEodeSetFixedStep(mem.get(), -1), CE_ILL_INPUT);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
  const char* msg = nullptr;
  ASSERT_EQ(CEodeGetLastErrorMessage(mem.get(), &msg), CE_SUCCESS);
  EXPECT_TRUE(Contains(std::string(msg), "positive and finite"));
}

TEST(ReturnFlagName, NamesEveryFlagAndNothingElse) {
  const std::vector<std::pair<long int, const char*>> flags = {
      {CE_SUCCESS, "CE_SUCCESS"},
      {CE_TSTOP_RETURN, "CE_TSTOP_RETURN"},
      {CE_ROOT_RETURN, "CE_ROOT_RETURN"},
      {CE_WARNING, "CE_WARNING"},
      {CE_MEM_NULL, "CE_MEM_NULL"},
      {CE_ILL_INPUT, "CE_ILL_INPUT"},
      {CE_NO_MALLOC, "CE_NO_MALLOC"},
      {CE_MEM_FAIL, "CE_MEM_FAIL"},
      {CE_RHSFUNC_FAIL, "CE_RHSFUNC_FAIL"},
      {CE_FIRST_RHSFUNC_ERR, "CE_FIRST_RHSFUNC_ERR"},
      {CE_CONV_FAILURE, "CE_CONV_FAILURE"},
      {CE_LSETUP_FAIL, "CE_LSETUP_FAIL"},
      {CE_LSOLVE_FAIL, "CE_LSOLVE_FAIL"},
      {CE_LINIT_FAIL, "CE_LINIT_FAIL"},
      {CE_NLS_INIT_FAIL, "CE_NLS_INIT_FAIL"},
      {CE_NLS_FAIL, "CE_NLS_FAIL"},
      {CE_CONSTR_FAIL, "CE_CONSTR_FAIL"},
      {CE_MASSFUNC_FAIL, "CE_MASSFUNC_FAIL"},
      {CE_JACFUNC_FAIL, "CE_JACFUNC_FAIL"},
      {CE_UNSTABLE, "CE_UNSTABLE"},
      {CE_TOO_MUCH_WORK, "CE_TOO_MUCH_WORK"},
      {CE_BAD_T, "CE_BAD_T"},
      {CE_VECTOROP_ERR, "CE_VECTOROP_ERR"},
      {CE_ERR_FAILURE, "CE_ERR_FAILURE"},
      {CE_INCONSISTENT_IC, "CE_INCONSISTENT_IC"},
      {CE_RTFUNC_FAIL, "CE_RTFUNC_FAIL"},
  };
  for (const auto& f : flags) EXPECT_EQ(FlagName(f.first), f.second);
  EXPECT_EQ(FlagName(-12345), "NONE");
  EXPECT_EQ(FlagName(42), "NONE");
  EXPECT_EQ(FlagName(CE_RTFUNC_FAIL - 1), "NONE");  // the first code past the last flag
  EXPECT_EQ(FlagName(CE_ROOT_RETURN + 1), "NONE");
}

}  // namespace
