// Hostile input, one class per test: objects of the wrong size or type, degenerate steps and
// tolerances, a start that overflows, NaN where a number is expected. Each test asserts a negative
// flag, a message naming the real cause, finite outputs, and memory that still gives the right
// answer afterwards (docs/api.md, "Validation of attached objects"). The suite's sanitizer build
// runs these under ASan and UBSan, so an out-of-bounds access is a failure too.
#include <ceode/ceode_stability.h>
#include <ceode/ceode_stepper.h>
#include <gtest/gtest.h>
#include <nvector/nvector_manyvector.h>
#include <sunlinsol/sunlinsol_band.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunmatrix/sunmatrix_band.h>
#include <sunmatrix/sunmatrix_sparse.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>
#include <sunnonlinsol/sunnonlinsol_newton.h>

#include <cmath>
#include <string>
#include <vector>

#include "ceode_testing.h"  // CEodeSetFusedKernel
#include "test_util.hpp"

namespace {

using namespace ceode_test;  // the handles and helpers of test_util.hpp

struct NlsDeleter {
  void operator()(SUNNonlinearSolver s) const { SUNNonlinSolFree(s); }
};
using NonlinearSolver = std::unique_ptr<std::remove_pointer_t<SUNNonlinearSolver>, NlsDeleter>;

// x'' = -x - c x' on every component (generic vector operations, any length); its exact solution
// from x0 = 1, v0 = 0.5 is known for c = 0. With nan_after, f returns NaN values from that time
// on; with nan_before, before it; with poison_x, f also overwrites its input x with NaN; from
// fail_after on it returns fail_retval.
struct Oscillator {
  sunrealtype c = 0;
  sunrealtype nan_after = INFINITY;
  sunrealtype nan_before = -INFINITY;
  bool poison_x = false;
  int jac_retval = 0;
  sunrealtype fail_after = INFINITY;
  int fail_retval = 0;
  static int F(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
    const auto* p = static_cast<const Oscillator*>(data);
    if (t >= p->fail_after) return p->fail_retval;
    N_VLinearSum(-1, x, -p->c, v, f);
    if (t >= p->nan_after || t < p->nan_before) {
      N_VConst(NAN, f);
      if (p->poison_x) N_VConst(NAN, x);
    }
    return 0;
  }
  static int Jac(sunrealtype, N_Vector, N_Vector, N_Vector, SUNMatrix J, void* data, N_Vector,
                 N_Vector, N_Vector) {
    const auto* p = static_cast<const Oscillator*>(data);
    if (p->jac_retval != 0) return p->jac_retval;
    for (sunindextype j = 0; j < SUNDenseMatrix_Columns(J); ++j)
      SUNDenseMatrix_Column(J, j)[j] = -p->c;
    return 0;
  }
};

// x'' = -x^3: finite at x0 = 1e100 (a = -1e300) but overflowing one step away.
int Cubic(sunrealtype, N_Vector x, N_Vector, N_Vector f, void*) {
  N_VProd(x, x, f);
  N_VProd(f, x, f);
  N_VScale(-1, f, f);
  return 0;
}

// M = I in whatever size the matrix has (dense), so that a wrong size is the only fault.
int IdentityMass(sunrealtype, N_Vector, SUNMatrix M, void*, N_Vector, N_Vector, N_Vector) {
  if (SUNMatGetID(M) == SUNMATRIX_DENSE) {
    for (sunindextype j = 0; j < SUNDenseMatrix_Columns(M); ++j) SUNDenseMatrix_Column(M, j)[j] = 1;
  } else if (SUNMatGetID(M) == SUNMATRIX_BAND) {
    for (sunindextype j = 0; j < SUNBandMatrix_Columns(M); ++j) SUNBandMatrix_Column(M, j)[0] = 1;
  }
  return 0;
}

// The Cartesian pendulum x'' = (0, -g) - G^T lambda on |x| = 1 (n = 2, nc = 1), M = I.
// Phi writes `written` of the template's entries (1 is correct).
struct Pendulum {
  int written = 1;
  static int F(sunrealtype, N_Vector, N_Vector, N_Vector f, void*) {
    NV_Ith_S(f, 0) = 0;
    NV_Ith_S(f, 1) = -9.81;
    return 0;
  }
  static int Phi(sunrealtype, N_Vector x, N_Vector phi, void* data) {
    const auto* p = static_cast<const Pendulum*>(data);
    const sunrealtype r = NV_Ith_S(x, 0) * NV_Ith_S(x, 0) + NV_Ith_S(x, 1) * NV_Ith_S(x, 1) - 1;
    for (int i = 0; i < p->written; ++i) NV_Ith_S(phi, i) = r;
    return 0;
  }
  static int G(sunrealtype, N_Vector x, SUNMatrix G, void* data) {
    const auto* p = static_cast<const Pendulum*>(data);
    for (int i = 0; i < p->written; ++i) {
      SM_ELEMENT_D(G, i, 0) = 2 * NV_Ith_S(x, 0);
      SM_ELEMENT_D(G, i, 1) = 2 * NV_Ith_S(x, 1);
    }
    return 0;
  }
};

class HostileInput : public ::testing::Test {
 protected:
  void SetUp() override {
    mem_.reset(CEodeCreate(ctx_));
    ASSERT_NE(mem_, nullptr);
    CEodeSetErrFile(mem(), nullptr);
    x_ = SerialVector(2, ctx_, 1);
    v_ = SerialVector(2, ctx_, SUN_RCONST(0.5));
  }
  void* mem() { return mem_.get(); }
  // Init with n entries of x0 = 1, v0 = 0.5, step h, the guard off (not the subject here).
  int Start(sunindextype n = 2, sunrealtype h = SUN_RCONST(1e-3), CEodeRhsFn f = Oscillator::F) {
    x_ = SerialVector(n, ctx_, 1);
    v_ = SerialVector(n, ctx_, SUN_RCONST(0.5));
    int flag = CEodeInit(mem(), f, 0, x_.get(), v_.get());
    if (flag == CE_SUCCESS) flag = CEodeSetUserData(mem(), &osc_);
    if (flag == CE_SUCCESS) flag = CEodeSetFixedStep(mem(), h);
    if (flag == CE_SUCCESS) flag = CEodeSetStabilityGuard(mem(), CE_GUARD_OFF, 0);
    return flag;
  }
  int Evolve(sunrealtype tout, sunrealtype* t) {
    return CEodeEvolve(mem(), tout, x_.get(), v_.get(), t, CE_NORMAL);
  }
  std::string Message() {
    const char* msg = nullptr;
    EXPECT_EQ(CEodeGetLastErrorMessage(mem(), &msg), CE_SUCCESS);
    return msg != nullptr ? msg : "";
  }
  // Entry by entry: the L1 norm of finite values near 1e308 overflows.
  static bool AllFinite(N_Vector y) {
    for (sunindextype i = 0; i < N_VGetLength(y); ++i) {
      if (!std::isfinite(NV_Ith_S(y, i))) return false;
    }
    return true;
  }
  bool Finite() const { return AllFinite(x_.get()) && AllFinite(v_.get()); }
  // After the fault is repaired the same memory integrates the undamped oscillator correctly
  // from the current time: ReInit at t0 = 0 and compare with cos t + 0.5 sin t at t = 1.
  void ExpectCorrectRunAfterReInit() {
    osc_ = Oscillator{};
    N_VConst(1, x_.get());
    N_VConst(SUN_RCONST(0.5), v_.get());
    ASSERT_EQ(CEodeReInit(mem(), 0, x_.get(), v_.get()), CE_SUCCESS);
    sunrealtype t = -1;
    ASSERT_EQ(Evolve(1, &t), CE_SUCCESS) << Message();
    EXPECT_DOUBLE_EQ(t, 1);
    const sunrealtype exact = std::cos(1.0) + 0.5 * std::sin(1.0);
    for (sunindextype i = 0; i < N_VGetLength(x_.get()); ++i)
      EXPECT_NEAR(NV_Ith_S(x_.get(), i), exact, 1e-5);
  }
  // The repair of a wrong-size mass matrix or solver for n = 2: a 2 x 2 identity mass matrix and
  // a dense solver of that size, then the correct run.
  void ExpectCorrectRunWithRightSizedMassAndSolver() {
    Matrix M2(SUNDenseMatrix(2, 2, ctx_));
    Matrix A2(SUNDenseMatrix(2, 2, ctx_));
    LinearSolver LS2(SUNLinSol_Dense(x_.get(), A2.get(), ctx_));
    ASSERT_EQ(CEodeSetMassFn(mem(), IdentityMass, M2.get(), SUNTRUE), CE_SUCCESS);
    ASSERT_EQ(CEodeSetLinearSolver(mem(), LS2.get(), A2.get()), CE_SUCCESS);
    ExpectCorrectRunAfterReInit();
  }

  Context ctx_;
  Mem mem_;
  Vector x_, v_;
  Oscillator osc_;
};

// --- 1. Solver matrices and linear solvers of the wrong size -----------------------------------

TEST_F(HostileInput, ALargerLinearSolverOnTheOdePathIsRefusedAtEvolveNotUsed) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  ASSERT_EQ(CEodeSetVelocityDependence(mem(), SUNTRUE), CE_SUCCESS);
  Vector y3 = SerialVector(3, ctx_);
  Matrix A3(SUNDenseMatrix(3, 3, ctx_));
  LinearSolver LS3(SUNLinSol_Dense(y3.get(), A3.get(), ctx_));
  // Accepted by the setter (constraints could still follow), refused once the size is final.
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS3.get(), A3.get()), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(1, &t), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "3 x 3"));
  EXPECT_TRUE(Contains(Message(), "size n"));
  EXPECT_EQ(t, 0);
  EXPECT_TRUE(Finite());
  Matrix A2(SUNDenseMatrix(2, 2, ctx_));
  LinearSolver LS2(SUNLinSol_Dense(x_.get(), A2.get(), ctx_));
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS2.get(), A2.get()), CE_SUCCESS);
  ExpectCorrectRunAfterReInit();
}

TEST_F(HostileInput, ASmallerMatrixThanTheProblemIsRefusedByTheSetter) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  Vector y1 = SerialVector(1, ctx_);
  Matrix A1(SUNDenseMatrix(1, 1, ctx_));
  LinearSolver LS1(SUNLinSol_Dense(y1.get(), A1.get(), ctx_));
  EXPECT_EQ(CEodeSetLinearSolver(mem(), LS1.get(), A1.get()), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "1 x 1"));
  ExpectCorrectRunAfterReInit();
}

TEST_F(HostileInput, ASolverCreatedForAnotherSizeThanItsMatrixIsRefused) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  Vector y1 = SerialVector(1, ctx_);
  Matrix A1(SUNDenseMatrix(1, 1, ctx_));
  Matrix A2(SUNDenseMatrix(2, 2, ctx_));
  LinearSolver LS1(SUNLinSol_Dense(y1.get(), A1.get(), ctx_));
  EXPECT_EQ(CEodeSetLinearSolver(mem(), LS1.get(), A2.get()), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "created for 1 unknowns"));
  Matrix B2(SUNBandMatrix(2, 1, 1, ctx_));
  EXPECT_EQ(CEodeSetLinearSolver(mem(), LS1.get(), B2.get()), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "incompatible"));
  ExpectCorrectRunAfterReInit();
}

TEST_F(HostileInput, ASolverLeftAttachedAcrossInitWithANewSizeIsRefusedAtTheNextEvolve) {
  ASSERT_EQ(Start(2), CE_SUCCESS);
  ASSERT_EQ(CEodeSetVelocityDependence(mem(), SUNTRUE), CE_SUCCESS);
  Matrix A2(SUNDenseMatrix(2, 2, ctx_));
  LinearSolver LS2(SUNLinSol_Dense(x_.get(), A2.get(), ctx_));
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS2.get(), A2.get()), CE_SUCCESS);
  sunrealtype t = 0;
  ASSERT_EQ(Evolve(SUN_RCONST(0.1), &t), CE_SUCCESS);
  ASSERT_EQ(Start(3), CE_SUCCESS);  // the old 2 x 2 solver stays attached
  EXPECT_EQ(Evolve(1, &t), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "2 x 2"));
  EXPECT_TRUE(Finite());
  Matrix A3(SUNDenseMatrix(3, 3, ctx_));
  LinearSolver LS3(SUNLinSol_Dense(x_.get(), A3.get(), ctx_));
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS3.get(), A3.get()), CE_SUCCESS);
  ExpectCorrectRunAfterReInit();
}

TEST_F(HostileInput, TheSaddlePointSolverLeftAttachedAfterRemovingConstraintsIsRefused) {
  Pendulum pend;
  x_ = SerialVector(2, ctx_);
  v_ = SerialVector(2, ctx_);
  NV_Ith_S(x_.get(), 0) = 1;
  ASSERT_EQ(CEodeInit(mem(), Pendulum::F, 0, x_.get(), v_.get()), CE_SUCCESS);
  ASSERT_EQ(CEodeSetUserData(mem(), &pend), CE_SUCCESS);
  ASSERT_EQ(CEodeSetFixedStep(mem(), SUN_RCONST(1e-3)), CE_SUCCESS);
  ASSERT_EQ(CEodeSetStabilityGuard(mem(), CE_GUARD_OFF, 0), CE_SUCCESS);
  Vector lam = SerialVector(1, ctx_);
  Vector y3 = SerialVector(3, ctx_);
  Matrix A3(SUNDenseMatrix(3, 3, ctx_));
  LinearSolver LS3(SUNLinSol_Dense(y3.get(), A3.get(), ctx_));
  ASSERT_EQ(CEodeSetConstraints(mem(), lam.get(), Pendulum::Phi, Pendulum::G), CE_SUCCESS);
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS3.get(), A3.get()), CE_SUCCESS);
  sunrealtype t = 0;
  ASSERT_EQ(Evolve(SUN_RCONST(0.5), &t), CE_SUCCESS) << Message();
  const sunrealtype r =
      NV_Ith_S(x_.get(), 0) * NV_Ith_S(x_.get(), 0) + NV_Ith_S(x_.get(), 1) * NV_Ith_S(x_.get(), 1);
  EXPECT_NEAR(r, 1, 1e-9);  // the constrained run itself is right
  ASSERT_EQ(CEodeSetConstraints(mem(), nullptr, nullptr, nullptr), CE_SUCCESS);
  ASSERT_EQ(CEodeSetVelocityDependence(mem(), SUNTRUE), CE_SUCCESS);
  EXPECT_EQ(Evolve(1, &t), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "3 x 3"));
  EXPECT_TRUE(Contains(Message(), "without constraints"));
  EXPECT_TRUE(Finite());
  Matrix A2(SUNDenseMatrix(2, 2, ctx_));
  LinearSolver LS2(SUNLinSol_Dense(x_.get(), A2.get(), ctx_));
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS2.get(), A2.get()), CE_SUCCESS);
  ASSERT_EQ(CEodeInit(mem(), Oscillator::F, 0, x_.get(), v_.get()), CE_SUCCESS);
  ASSERT_EQ(CEodeSetUserData(mem(), &osc_), CE_SUCCESS);
  ExpectCorrectRunAfterReInit();
}

TEST_F(HostileInput, MassAndSolverMatricesBothTooLargeAreRefusedBeforeAnySolve) {
  Matrix M3(SUNDenseMatrix(3, 3, ctx_));
  Matrix A3(SUNDenseMatrix(3, 3, ctx_));
  Vector y3 = SerialVector(3, ctx_);
  LinearSolver LS3(SUNLinSol_Dense(y3.get(), A3.get(), ctx_));
  // Attached before Init, when no size is known yet: the start checks them.
  ASSERT_EQ(CEodeSetMassFn(mem(), IdentityMass, M3.get(), SUNTRUE), CE_SUCCESS);
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS3.get(), A3.get()), CE_SUCCESS);
  ASSERT_EQ(Start(), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(1, &t), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "mass matrix M is 3 x 3"));
  EXPECT_TRUE(Finite());
  // After Init the setter itself refuses it.
  EXPECT_EQ(CEodeSetMassFn(mem(), IdentityMass, M3.get(), SUNTRUE), CE_ILL_INPUT);
  ExpectCorrectRunWithRightSizedMassAndSolver();
}

// --- 2. Mass matrix of the wrong size with constraints -----------------------------------------

TEST_F(HostileInput, AWrongSizeMassMatrixWithConstraintsIsRefusedBeforeTheSaddleAssembly) {
  Pendulum pend;
  Matrix M3(SUNDenseMatrix(3, 3, ctx_));
  ASSERT_EQ(CEodeSetMassFn(mem(), IdentityMass, M3.get(), SUNTRUE), CE_SUCCESS);
  x_ = SerialVector(2, ctx_);
  v_ = SerialVector(2, ctx_);
  NV_Ith_S(x_.get(), 0) = 1;
  ASSERT_EQ(CEodeInit(mem(), Pendulum::F, 0, x_.get(), v_.get()), CE_SUCCESS);
  ASSERT_EQ(CEodeSetUserData(mem(), &pend), CE_SUCCESS);
  ASSERT_EQ(CEodeSetFixedStep(mem(), SUN_RCONST(1e-3)), CE_SUCCESS);
  ASSERT_EQ(CEodeSetStabilityGuard(mem(), CE_GUARD_OFF, 0), CE_SUCCESS);
  Vector lam = SerialVector(1, ctx_);
  ASSERT_EQ(CEodeSetConstraints(mem(), lam.get(), Pendulum::Phi, Pendulum::G), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(1, &t), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "mass matrix M is 3 x 3"));
  EXPECT_TRUE(Contains(Message(), "n = 2"));
  EXPECT_TRUE(Finite());
  Matrix M2(SUNDenseMatrix(2, 2, ctx_));
  ASSERT_EQ(CEodeSetMassFn(mem(), IdentityMass, M2.get(), SUNTRUE), CE_SUCCESS);
  ASSERT_EQ(Evolve(SUN_RCONST(0.5), &t), CE_SUCCESS) << Message();
  const sunrealtype r =
      NV_Ith_S(x_.get(), 0) * NV_Ith_S(x_.get(), 0) + NV_Ith_S(x_.get(), 1) * NV_Ith_S(x_.get(), 1);
  EXPECT_NEAR(r, 1, 1e-9);
}

// --- 3. A nonlinear solver built for another vector length -------------------------------------

TEST_F(HostileInput, ANewtonOrFixedPointSolverForAnotherLengthIsRefused) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  ASSERT_EQ(CEodeSetVelocityDependence(mem(), SUNTRUE), CE_SUCCESS);
  Vector y5 = SerialVector(5, ctx_);
  NonlinearSolver newton(SUNNonlinSol_Newton(y5.get(), ctx_));
  NonlinearSolver fixed(SUNNonlinSol_FixedPoint(y5.get(), 0, ctx_));
  EXPECT_EQ(CEodeSetNonlinearSolver(mem(), newton.get()), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "length 5"));
  EXPECT_EQ(CEodeSetNonlinearSolver(mem(), fixed.get()), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "length 5"));
  // A right one, then a new size under it: refused at the next Evolve.
  NonlinearSolver fixed2(SUNNonlinSol_FixedPoint(x_.get(), 0, ctx_));
  ASSERT_EQ(CEodeSetNonlinearSolver(mem(), fixed2.get()), CE_SUCCESS);
  ASSERT_EQ(Start(3), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(1, &t), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "length 2"));
  NonlinearSolver fixed3(SUNNonlinSol_FixedPoint(x_.get(), 0, ctx_));
  ASSERT_EQ(CEodeSetNonlinearSolver(mem(), fixed3.get()), CE_SUCCESS);
  ExpectCorrectRunAfterReInit();
  mem_.reset();  // before the solvers it used
}

// --- 4. A constraint template longer than what Phi writes --------------------------------------

TEST_F(HostileInput, ATemplateLongerThanWhatPhiWritesIsNamedNotCalledRedundant) {
  Pendulum pend;
  x_ = SerialVector(2, ctx_);
  v_ = SerialVector(2, ctx_);
  NV_Ith_S(x_.get(), 0) = 1;
  ASSERT_EQ(CEodeInit(mem(), Pendulum::F, 0, x_.get(), v_.get()), CE_SUCCESS);
  ASSERT_EQ(CEodeSetUserData(mem(), &pend), CE_SUCCESS);
  ASSERT_EQ(CEodeSetFixedStep(mem(), SUN_RCONST(1e-3)), CE_SUCCESS);
  ASSERT_EQ(CEodeSetStabilityGuard(mem(), CE_GUARD_OFF, 0), CE_SUCCESS);
  Vector lam3 = SerialVector(3, ctx_);
  ASSERT_EQ(CEodeSetConstraints(mem(), lam3.get(), Pendulum::Phi, Pendulum::G), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(1, &t), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "wrote only 1"));
  EXPECT_TRUE(Contains(Message(), "nc = 3"));
  EXPECT_FALSE(Contains(Message(), "redundant"));
  EXPECT_TRUE(Finite());
  Vector lam1 = SerialVector(1, ctx_);
  ASSERT_EQ(CEodeSetConstraints(mem(), lam1.get(), Pendulum::Phi, Pendulum::G), CE_SUCCESS);
  ASSERT_EQ(Evolve(SUN_RCONST(0.5), &t), CE_SUCCESS) << Message();
  const sunrealtype r =
      NV_Ith_S(x_.get(), 0) * NV_Ith_S(x_.get(), 0) + NV_Ith_S(x_.get(), 1) * NV_Ith_S(x_.get(), 1);
  EXPECT_NEAR(r, 1, 1e-9);
}

// --- 5. The consistent start, checked in full --------------------------------------------------

TEST_F(HostileInput, AnOverflowInTheStartStencilIsReportedAsTheStartsFailure) {
  ASSERT_EQ(Start(2, SUN_RCONST(1e-3), Cubic), CE_SUCCESS);
  ASSERT_EQ(CEodeSetMethodByName(mem(), "G4_A34"), CE_SUCCESS);
  N_VConst(1e100, x_.get());
  N_VConst(0, v_.get());
  ASSERT_EQ(CEodeReInit(mem(), 0, x_.get(), v_.get()), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(1, &t), CE_FIRST_RHSFUNC_ERR);
  EXPECT_TRUE(Contains(Message(), "start"));
  EXPECT_TRUE(Contains(Message(), "non-finite derivative D_3"));
  EXPECT_FALSE(Contains(Message(), "t = 0.001"));
  EXPECT_EQ(t, 0);
  EXPECT_TRUE(Finite());
  ASSERT_EQ(CEodeInit(mem(), Oscillator::F, 0, x_.get(), v_.get()), CE_SUCCESS);
  ExpectCorrectRunAfterReInit();
}

TEST_F(HostileInput, ANaNBehindTheInitialTimeIsReportedAsTheStartsFailure) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  ASSERT_EQ(CEodeSetMethodByName(mem(), "G5"), CE_SUCCESS);
  osc_.nan_before = 0;  // f is NaN at the stencil's points t0 - j h only
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(1, &t), CE_FIRST_RHSFUNC_ERR);
  EXPECT_TRUE(Contains(Message(), "start stencil"));
  EXPECT_FALSE(Contains(Message(), "step"));
  EXPECT_TRUE(Finite());
  ExpectCorrectRunAfterReInit();
}

TEST_F(HostileInput, AFirstPositionThatOverflowsIsReportedAsTheStartsFailure) {
  ASSERT_EQ(Start(2, 1), CE_SUCCESS);  // G3_CD, h = 1: x(h) = x0 + v0 + a0/2
  N_VConst(SUN_RCONST(1e308), x_.get());
  N_VConst(SUN_RCONST(1.5e308), v_.get());
  ASSERT_EQ(CEodeReInit(mem(), 0, x_.get(), v_.get()), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(5, &t), CE_FIRST_RHSFUNC_ERR);
  EXPECT_TRUE(Contains(Message(), "first position"));
  EXPECT_TRUE(Finite());
  ASSERT_EQ(CEodeSetFixedStep(mem(), SUN_RCONST(1e-3)), CE_SUCCESS);
  ExpectCorrectRunAfterReInit();
}

// --- 6. The failure diagnosis sees NaN --------------------------------------------------------

TEST_F(HostileInput, ANaNStateIsNotDiagnosedAsAFiniteOne) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  osc_.nan_after = SUN_RCONST(0.5);
  osc_.poison_x = true;  // f overwrites its input x: the state itself becomes NaN
  sunrealtype t = -1;
  EXPECT_LT(Evolve(1, &t), 0);
  EXPECT_FALSE(Contains(Message(), "max |x| = 0"));
  EXPECT_FALSE(Contains(Message(), "state was finite"));
  EXPECT_TRUE(Contains(Message(), "nan"));
  EXPECT_NEAR(t, 0.5, 2e-3);  // the last good step
  EXPECT_TRUE(Finite());
  ExpectCorrectRunAfterReInit();
}

// --- 7. Degenerate step sizes -----------------------------------------------------------------

struct DegenerateStep {
  const char* label;
  const char* method;
  double h;
  double t0;
  const char* words;  // key words of the message
};

class DegenerateSteps : public HostileInput,
                        public ::testing::WithParamInterface<DegenerateStep> {};

TEST_P(DegenerateSteps, AreRefusedWithTheReasonAndLeaveTimeAndOutputsAlone) {
  const DegenerateStep& p = GetParam();
  ASSERT_EQ(Start(2, p.h), CE_SUCCESS);
  ASSERT_EQ(CEodeSetMethodByName(mem(), p.method), CE_SUCCESS);
  ASSERT_EQ(CEodeReInit(mem(), p.t0, x_.get(), v_.get()), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(p.t0 + 1, &t), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), p.words));
  EXPECT_EQ(t, p.t0);
  EXPECT_TRUE(Finite());
  EXPECT_EQ(CEodeEvolve(mem(), p.t0 + 1, x_.get(), v_.get(), &t, CE_ONE_STEP), CE_ILL_INPUT);
  ASSERT_EQ(CEodeSetFixedStep(mem(), SUN_RCONST(1e-3)), CE_SUCCESS);
  ASSERT_EQ(CEodeSetMethodByName(mem(), "G3_CD"), CE_SUCCESS);
  ExpectCorrectRunAfterReInit();
}

INSTANTIATE_TEST_SUITE_P(
    HostileInput, DegenerateSteps,
    ::testing::Values(DegenerateStep{"DenormalH", "G3_CD", 7.9e-323, 0, "zero"},
                      DegenerateStep{"UnderflowingSquare", "G3_CD", 1e-300, 0, "zero"},
                      DegenerateStep{"UnderflowingFifthPower", "G5", 1e-70, 0, "h^5"},
                      DegenerateStep{"OverflowingSquare", "G4_A34", 1e300, 0, "not finite"},
                      DegenerateStep{"StepLostInTheTime", "G3_CD", 1e-3, 1e20, "t + h == t"}),
    [](const ::testing::TestParamInfo<DegenerateStep>& info) { return info.param.label; });

TEST_F(HostileInput, ALargeButUsableStepReturnsExactlyTheStopTime) {
  ASSERT_EQ(Start(2, SUN_RCONST(0.3)), CE_SUCCESS);
  ASSERT_EQ(CEodeSetStopTime(mem(), 1), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(5, &t), CE_TSTOP_RETURN);
  EXPECT_EQ(t, 1);
  EXPECT_TRUE(Finite());
}

// --- 8. GetDky at a time that is not a number ---------------------------------------------------

TEST_F(HostileInput, GetDkyAtNaNOrInfinityIsABadTime) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  sunrealtype t = 0;
  ASSERT_EQ(Evolve(SUN_RCONST(0.5), &t), CE_SUCCESS);
  Vector dky = SerialVector(2, ctx_, 7);
  EXPECT_EQ(CEodeGetDky(mem(), NAN, 0, dky.get()), CE_BAD_T);
  EXPECT_EQ(CEodeGetDky(mem(), INFINITY, 1, dky.get()), CE_BAD_T);
  EXPECT_EQ(CEodeGetDky(mem(), -INFINITY, 0, dky.get()), CE_BAD_T);
  EXPECT_TRUE(Contains(Message(), "outside the current interval"));
  EXPECT_EQ(NV_Ith_S(dky.get(), 0), 7);  // untouched
  EXPECT_EQ(CEodeGetDky(mem(), t, 0, dky.get()), CE_SUCCESS);
  EXPECT_DOUBLE_EQ(NV_Ith_S(dky.get(), 0), NV_Ith_S(x_.get(), 0));
}

// --- 9. Tolerances and method parameters -------------------------------------------------------

TEST_F(HostileInput, NonlinearTolerancesMustBeFiniteAndNonNegative) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  const double bad[][2] = {{INFINITY, 0}, {NAN, 0}, {1e-8, NAN}, {1e-8, INFINITY},
                           {1e-8, -1},    {0, 0},   {-1, 0}};
  for (const auto& tol : bad) {
    EXPECT_EQ(CEodeSetNonlinTolerances(mem(), tol[0], tol[1]), CE_ILL_INPUT)
        << tol[0] << " " << tol[1];
    EXPECT_TRUE(Contains(Message(), "finite reltol > 0"));
  }
  EXPECT_EQ(CEodeSetNonlinTolerances(mem(), 1e-10, 1e-12), CE_SUCCESS);
  ExpectCorrectRunAfterReInit();
}

TEST_F(HostileInput, SetMethodAndTheStabilityAnalysisRefuseTheSameDegenerateParameters) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  const sunrealtype tiny_gamma[] = {0.75, 1.0 / 3.0, 5e-324};
  sunrealtype Om = -1;
  EXPECT_EQ(CEodeSetMethod(mem(), 4, tiny_gamma), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "degenerate step"));
  EXPECT_EQ(CEodeStabilityLimit(4, tiny_gamma, 0, &Om), CE_ILL_INPUT);
  // beta = 5e-324 still gives a usable step of size 1, but kappa = h beta underflows at h = 1e-3:
  // the step size is refused at the start, not blamed later.
  const sunrealtype tiny_beta[] = {1.0, 5e-324};
  EXPECT_EQ(CEodeSetMethod(mem(), 3, tiny_beta), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(1, &t), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "kappa = 0"));
  const sunrealtype g4[] = {0.75, 1.0 / 3.0, 0.5};
  EXPECT_EQ(CEodeSetMethod(mem(), 4, g4), CE_SUCCESS);
  EXPECT_EQ(CEodeStabilityLimit(4, g4, 0, &Om), CE_SUCCESS);
  EXPECT_GT(Om, 0);
  ExpectCorrectRunAfterReInit();
}

// --- 10. The solver choice is made again after the user attaches a linear solver ---------------

TEST_F(HostileInput, AttachingALinearSolverAfterAFixedPointFailureSwitchesToNewton) {
  ASSERT_EQ(Start(2, SUN_RCONST(1e-2)), CE_SUCCESS);
  osc_.c = 1e4;  // kappa * df/dv = 0.005 * 1e4 = 50: the fixed-point iteration diverges
  ASSERT_EQ(CEodeSetVelocityDependence(mem(), SUNTRUE), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(1, &t), CE_CONV_FAILURE);
  EXPECT_TRUE(Contains(Message(), "fixed-point"));
  EXPECT_TRUE(Contains(Message(), "attach a linear solver"));
  Matrix A(SUNDenseMatrix(2, 2, ctx_));
  LinearSolver LS(SUNLinSol_Dense(x_.get(), A.get(), ctx_));
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS.get(), A.get()), CE_SUCCESS);
  ASSERT_EQ(CEodeSetVelJacFn(mem(), Oscillator::Jac), CE_SUCCESS);
  EXPECT_EQ(Evolve(1, &t), CE_SUCCESS) << Message();
  long int nls = 0;
  ASSERT_EQ(CEodeGetNumLinSolves(mem(), &nls), CE_SUCCESS);
  EXPECT_GT(nls, 0);
  EXPECT_TRUE(Finite());
}

// --- 11. A mass matrix of the wrong type or shape ----------------------------------------------

TEST_F(HostileInput, AMassMatrixOfAnotherTypeThanTheSolverMatrixIsIncompatibleNotSingular) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  Matrix Mb(SUNBandMatrix(2, 0, 0, ctx_));
  Matrix A(SUNDenseMatrix(2, 2, ctx_));
  LinearSolver LS(SUNLinSol_Dense(x_.get(), A.get(), ctx_));
  ASSERT_EQ(CEodeSetMassFn(mem(), IdentityMass, Mb.get(), SUNTRUE), CE_SUCCESS);
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS.get(), A.get()), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(1, &t), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "incompatible"));
  EXPECT_TRUE(Contains(Message(), "band"));
  EXPECT_FALSE(Contains(Message(), "singular"));
  Matrix Mr(SUNDenseMatrix(1, 2, ctx_));  // not square
  EXPECT_EQ(CEodeSetMassFn(mem(), IdentityMass, Mr.get(), SUNTRUE), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "1 x 2"));
  Matrix M(SUNDenseMatrix(2, 2, ctx_));
  ASSERT_EQ(CEodeSetMassFn(mem(), IdentityMass, M.get(), SUNTRUE), CE_SUCCESS);
  ExpectCorrectRunAfterReInit();
}

// --- 12. Error semantics of docs/api.md --------------------------------------------------------

TEST_F(HostileInput, AFailingVelocityJacobianReturnsCE_JACFUNC_FAIL) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  osc_.c = 1;
  osc_.jac_retval = -1;
  Matrix A(SUNDenseMatrix(2, 2, ctx_));
  LinearSolver LS(SUNLinSol_Dense(x_.get(), A.get(), ctx_));
  ASSERT_EQ(CEodeSetVelocityDependence(mem(), SUNTRUE), CE_SUCCESS);
  ASSERT_EQ(CEodeSetImplicitMode(mem(), CE_IMPLICIT_NEWTON), CE_SUCCESS);  // calls the Jacobian
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS.get(), A.get()), CE_SUCCESS);
  ASSERT_EQ(CEodeSetVelJacFn(mem(), Oscillator::Jac), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(1, &t), CE_JACFUNC_FAIL);
  EXPECT_TRUE(Contains(Message(), "Jacobian"));
  EXPECT_TRUE(Finite());
}

TEST_F(HostileInput, ErrorsBeforeAnyStepSetTretToTheCurrentTimeAndLeaveTheOutputsAlone) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  sunrealtype t = 0;
  ASSERT_EQ(Evolve(1, &t), CE_SUCCESS);
  Vector xo = SerialVector(2, ctx_, 42);
  Vector vo = SerialVector(2, ctx_, 42);
  auto untouched = [&] { return NV_Ith_S(xo.get(), 0) == 42 && NV_Ith_S(vo.get(), 1) == 42; };
  // tout behind the current time
  t = -1;
  EXPECT_EQ(CEodeEvolve(mem(), SUN_RCONST(0.5), xo.get(), vo.get(), &t, CE_NORMAL), CE_BAD_T);
  EXPECT_NEAR(t, 1, 1e-12);
  EXPECT_TRUE(untouched());
  // a stop time behind the current time
  ASSERT_EQ(CEodeSetStopTime(mem(), SUN_RCONST(0.5)), CE_SUCCESS);
  t = -1;
  EXPECT_EQ(CEodeEvolve(mem(), 2, xo.get(), vo.get(), &t, CE_NORMAL), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "stop time"));
  EXPECT_NEAR(t, 1, 1e-12);
  EXPECT_TRUE(untouched());
  ASSERT_EQ(CEodeClearStopTime(mem()), CE_SUCCESS);
  // a configuration error found at the restart
  Vector y3 = SerialVector(3, ctx_);
  Matrix A3(SUNDenseMatrix(3, 3, ctx_));
  LinearSolver LS3(SUNLinSol_Dense(y3.get(), A3.get(), ctx_));
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS3.get(), A3.get()), CE_SUCCESS);
  t = -1;
  EXPECT_EQ(CEodeEvolve(mem(), 2, xo.get(), vo.get(), &t, CE_NORMAL), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "3 x 3"));
  EXPECT_NEAR(t, 1, 1e-12);
  EXPECT_TRUE(untouched());
}

// --- 13. Non-finite times, shrinking sizes, and the Jacobian on every implicit path ------------

TEST_F(HostileInput, ReInitRefusesANonFiniteInitialTimeAndKeepsTheCurrentOne) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  sunrealtype t = -1;
  ASSERT_EQ(Evolve(SUN_RCONST(0.5), &t), CE_SUCCESS);
  for (const sunrealtype t0 : {SUN_RCONST(NAN), SUN_RCONST(INFINITY), -SUN_RCONST(INFINITY)}) {
    EXPECT_EQ(CEodeReInit(mem(), t0, x_.get(), v_.get()), CE_ILL_INPUT);
    EXPECT_TRUE(Contains(Message(), "t0"));
    sunrealtype tcur = NAN;
    ASSERT_EQ(CEodeGetCurrentTime(mem(), &tcur), CE_SUCCESS);
    EXPECT_NEAR(tcur, 0.5, 1e-12);
  }
  ExpectCorrectRunAfterReInit();
}

// Per configuration (velocity dependence, a mass matrix, the stability guard): after CEodeInit
// shrinks n from 3 to 2, the 3 x 3 objects left attached are refused by Evolve and by the guard's
// own entry point (CEodeGetStableStep) before any of them is touched, and the right sizes then give
// the right answer.
TEST_F(HostileInput, ASecondInitThatShrinksTheProblemUnderALargerSolverIsRefusedCleanly) {
  for (int config = 0; config < 8; ++config) {
    SCOPED_TRACE("configuration " + std::to_string(config));
    const bool vdep = (config & 1) != 0, mass = (config & 2) != 0, guard = (config & 4) != 0;
    mem_.reset(CEodeCreate(ctx_));
    CEodeSetErrFile(mem(), nullptr);
    ASSERT_EQ(Start(3), CE_SUCCESS);
    if (guard) ASSERT_EQ(CEodeSetStabilityGuard(mem(), CE_GUARD_WARN, 10), CE_SUCCESS);
    ASSERT_EQ(CEodeSetVelocityDependence(mem(), vdep ? SUNTRUE : SUNFALSE), CE_SUCCESS);
    Matrix A3(SUNDenseMatrix(3, 3, ctx_)), M3(SUNDenseMatrix(3, 3, ctx_));
    LinearSolver LS3(SUNLinSol_Dense(x_.get(), A3.get(), ctx_));
    ASSERT_EQ(CEodeSetLinearSolver(mem(), LS3.get(), A3.get()), CE_SUCCESS);
    if (mass) ASSERT_EQ(CEodeSetMassFn(mem(), IdentityMass, M3.get(), SUNTRUE), CE_SUCCESS);
    sunrealtype t = -1;
    ASSERT_EQ(Evolve(SUN_RCONST(0.1), &t), CE_SUCCESS) << Message();
    ASSERT_EQ(Start(2), CE_SUCCESS);  // the 3 x 3 objects stay attached
    if (guard) ASSERT_EQ(CEodeSetStabilityGuard(mem(), CE_GUARD_WARN, 10), CE_SUCCESS);
    sunrealtype hmax = -1;
    if (mass) {  // the guard factors its own copy of M (without M it uses no attached object)
      EXPECT_EQ(CEodeGetStableStep(mem(), 0, &hmax), CE_ILL_INPUT);
      EXPECT_TRUE(Contains(Message(), "3 x 3"));
    } else {
      EXPECT_EQ(CEodeGetStableStep(mem(), 0, &hmax), CE_SUCCESS);
      EXPECT_NEAR(hmax, 0.99 * 2, 0.01) << "G3_CD: Omega_max = 2 over omega_max = 1";
    }
    EXPECT_EQ(Evolve(1, &t), CE_ILL_INPUT);
    EXPECT_TRUE(Contains(Message(), "3 x 3"));
    EXPECT_TRUE(Finite());
    Matrix A2(SUNDenseMatrix(2, 2, ctx_)), M2(SUNDenseMatrix(2, 2, ctx_));
    LinearSolver LS2(SUNLinSol_Dense(x_.get(), A2.get(), ctx_));
    ASSERT_EQ(CEodeSetLinearSolver(mem(), LS2.get(), A2.get()), CE_SUCCESS);
    if (mass) ASSERT_EQ(CEodeSetMassFn(mem(), IdentityMass, M2.get(), SUNTRUE), CE_SUCCESS);
    ExpectCorrectRunAfterReInit();
    mem_.reset();  // before the solvers it used
  }
}

TEST_F(HostileInput, MassAndSolverBothTooLargeLeaveTheMemoryUsableWithTheRightSizes) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  ASSERT_EQ(CEodeSetVelocityDependence(mem(), SUNTRUE), CE_SUCCESS);
  Matrix M3(SUNDenseMatrix(3, 3, ctx_));
  Matrix A3(SUNDenseMatrix(3, 3, ctx_));
  Vector y3 = SerialVector(3, ctx_);
  LinearSolver LS3(SUNLinSol_Dense(y3.get(), A3.get(), ctx_));
  EXPECT_EQ(CEodeSetMassFn(mem(), IdentityMass, M3.get(), SUNTRUE), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "3 x 3"));
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS3.get(), A3.get()), CE_SUCCESS);  // may wait for nc
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(1, &t), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "3 x 3"));
  EXPECT_TRUE(Finite());
  ExpectCorrectRunWithRightSizedMassAndSolver();
}

// The Jacobian is evaluated by the Newton matrix's setup only. Per implicit mode, with a strong
// damping (c = 50, h = 1e-2: kappa c well above AUTO's contraction limit 0.2) and a weak one
// (c = 0.1, so AUTO keeps prediction-correction): a failing Jacobian ends the run with
// CE_JACFUNC_FAIL whenever CEodeGetNumJacEvals counts a call, and a path that never calls it says
// so by njevals = 0.
TEST_F(HostileInput, AFailingVelocityJacobianReachesTheUserOnEveryPathThatCallsIt) {
  Matrix A(SUNDenseMatrix(2, 2, ctx_));
  LinearSolver LS(SUNLinSol_Dense(x_.get(), A.get(), ctx_));
  for (const int mode : {CE_IMPLICIT_NEWTON, CE_IMPLICIT_PC, CE_IMPLICIT_AUTO}) {
    for (const sunrealtype c : {SUN_RCONST(50.0), SUN_RCONST(0.1)}) {
      for (int variant = 0; variant < 4; ++variant) {  // fused or not, detection, tolerances
        SCOPED_TRACE("mode " + std::to_string(mode) + ", c " + std::to_string(c) + ", variant " +
                     std::to_string(variant));
        ASSERT_EQ(Start(2, SUN_RCONST(1e-2)), CE_SUCCESS);
        osc_.c = c;
        osc_.jac_retval = -1;
        ASSERT_EQ(variant == 2 ? CEodeSetVelocityMode(mem(), CE_VELOCITY_DETECT)
                               : CEodeSetVelocityDependence(mem(), SUNTRUE),
                  CE_SUCCESS);
        if (variant == 3) ASSERT_EQ(CEodeSStolerances(mem(), 1e-6, 1e-8), CE_SUCCESS);
        ASSERT_EQ(CEodeSetImplicitMode(mem(), mode), CE_SUCCESS);
        ASSERT_EQ(CEodeSetLinearSolver(mem(), LS.get(), A.get()), CE_SUCCESS);
        ASSERT_EQ(CEodeSetVelJacFn(mem(), Oscillator::Jac), CE_SUCCESS);
        CEodeSetFusedKernel(mem(), variant == 1 ? SUNFALSE : SUNTRUE);
        sunrealtype t = -1;
        const int flag = Evolve(1, &t);
        long int nje = -1;
        ASSERT_EQ(CEodeGetNumJacEvals(mem(), &nje), CE_SUCCESS);
        if (nje > 0) {
          EXPECT_EQ(flag, CE_JACFUNC_FAIL);
          EXPECT_TRUE(Contains(Message(), "Jacobian"));
        } else {
          EXPECT_EQ(flag, CE_SUCCESS) << Message();
        }
        EXPECT_EQ(nje > 0, mode == CE_IMPLICIT_NEWTON || (mode == CE_IMPLICIT_AUTO && c > 1));
        EXPECT_TRUE(Finite());
        osc_ = Oscillator{};
        ASSERT_EQ(CEodeSetVelJacFn(mem(), nullptr), CE_SUCCESS);
        if (variant == 3) ASSERT_EQ(CEodeSetFixedStep(mem(), SUN_RCONST(1e-3)), CE_SUCCESS);
        ExpectCorrectRunAfterReInit();
      }
    }
  }
}

int FailingJac(sunrealtype, N_Vector, N_Vector, N_Vector, SUNMatrix, void*, N_Vector, N_Vector,
               N_Vector) {
  return -1;
}

// The constrained step evaluates df/dv in its saddle-point (or Schur) matrix on every velocity-
// dependent run: a failing Jacobian ends it there too.
TEST_F(HostileInput, AFailingVelocityJacobianReachesTheUserOnTheConstrainedPath) {
  Pendulum pend;
  x_ = SerialVector(2, ctx_);
  v_ = SerialVector(2, ctx_);
  NV_Ith_S(x_.get(), 0) = 1;
  ASSERT_EQ(CEodeInit(mem(), Pendulum::F, 0, x_.get(), v_.get()), CE_SUCCESS);
  ASSERT_EQ(CEodeSetUserData(mem(), &pend), CE_SUCCESS);
  ASSERT_EQ(CEodeSetFixedStep(mem(), SUN_RCONST(1e-3)), CE_SUCCESS);
  ASSERT_EQ(CEodeSetStabilityGuard(mem(), CE_GUARD_OFF, 0), CE_SUCCESS);
  Vector lam = SerialVector(1, ctx_);
  ASSERT_EQ(CEodeSetConstraints(mem(), lam.get(), Pendulum::Phi, Pendulum::G), CE_SUCCESS);
  ASSERT_EQ(CEodeSetVelocityDependence(mem(), SUNTRUE), CE_SUCCESS);
  ASSERT_EQ(CEodeSetVelJacFn(mem(), FailingJac), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(SUN_RCONST(0.5), &t), CE_JACFUNC_FAIL) << Message();
  EXPECT_TRUE(Contains(Message(), "Jacobian"));
  EXPECT_TRUE(Finite());
  ASSERT_EQ(CEodeSetVelJacFn(mem(), nullptr), CE_SUCCESS);
  ASSERT_EQ(Evolve(SUN_RCONST(0.5), &t), CE_SUCCESS) << Message();
  const sunrealtype r =
      NV_Ith_S(x_.get(), 0) * NV_Ith_S(x_.get(), 0) + NV_Ith_S(x_.get(), 1) * NV_Ith_S(x_.get(), 1);
  EXPECT_NEAR(r, 1, 1e-9);
}

// Detection turns the implicit step on at the start, after the configuration was checked for the
// explicit one: the Newton solver it then uses is checked too, never run on vectors of 2.
TEST_F(HostileInput, ANewtonSolverForAnotherLengthIsRefusedWhenDetectionTurnsTheImplicitStepOn) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  osc_.c = 1;  // f depends on x'
  Vector y5 = SerialVector(5, ctx_);
  Matrix A(SUNDenseMatrix(2, 2, ctx_));
  LinearSolver LS(SUNLinSol_Dense(x_.get(), A.get(), ctx_));
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS.get(), A.get()), CE_SUCCESS);
  NonlinearSolver newton5(SUNNonlinSol_Newton(y5.get(), ctx_));
  ASSERT_EQ(CEodeSetNonlinearSolver(mem(), newton5.get()), CE_ILL_INPUT);  // n is known
  // Attached for another size before the problem changes to n = 2 under it.
  ASSERT_EQ(Start(5), CE_SUCCESS);
  ASSERT_EQ(CEodeSetNonlinearSolver(mem(), newton5.get()), CE_SUCCESS);
  ASSERT_EQ(Start(2), CE_SUCCESS);
  osc_.c = 1;
  ASSERT_EQ(CEodeSetVelocityMode(mem(), CE_VELOCITY_DETECT), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(1, &t), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "length 5"));
  EXPECT_TRUE(Finite());
  NonlinearSolver newton2(SUNNonlinSol_Newton(x_.get(), ctx_));
  ASSERT_EQ(CEodeSetNonlinearSolver(mem(), newton2.get()), CE_SUCCESS);
  ExpectCorrectRunAfterReInit();
  mem_.reset();  // before the solvers it used
}

// A matrix-free Krylov solver runs on the problem's vectors with work vectors of its own length:
// one made for another length is refused, at the setter and after a CEodeInit that resizes.
TEST_F(HostileInput, AMatrixFreeSolverForAnotherLengthIsRefusedNotRunOnShorterVectors) {
  Vector y3 = SerialVector(3, ctx_);
  LinearSolver gmres3(SUNLinSol_SPGMR(y3.get(), SUN_PREC_NONE, 0, ctx_));
  Matrix M2(SUNDenseMatrix(2, 2, ctx_));
  ASSERT_EQ(Start(), CE_SUCCESS);
  EXPECT_EQ(CEodeSetLinearSolver(mem(), gmres3.get(), nullptr), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "length 3"));
  ASSERT_EQ(Start(3), CE_SUCCESS);
  ASSERT_EQ(CEodeSetLinearSolver(mem(), gmres3.get(), nullptr), CE_SUCCESS);
  ASSERT_EQ(Start(2), CE_SUCCESS);  // the solver for 3 stays attached
  ASSERT_EQ(CEodeSetMassFn(mem(), IdentityMass, M2.get(), SUNTRUE), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(1, &t), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "length 3"));
  EXPECT_TRUE(Finite());
  LinearSolver gmres2(SUNLinSol_SPGMR(x_.get(), SUN_PREC_NONE, 0, ctx_));
  ASSERT_EQ(CEodeSetLinearSolver(mem(), gmres2.get(), nullptr), CE_SUCCESS);
  ExpectCorrectRunAfterReInit();
  mem_.reset();  // before the solvers it used
}

// Finite input whose result overflows is refused, not returned as Inf with success.
TEST_F(HostileInput, OverflowingResultsOfTheUtilitiesAreRefusedNotReturnedAsInfinity) {
  Matrix K(SUNDenseMatrix(2, 2, ctx_));
  SM_ELEMENT_D(K.get(), 0, 0) = 1e300;
  SM_ELEMENT_D(K.get(), 1, 1) = 1;
  Vector mass = SerialVector(2, ctx_, 1e-300);
  sunrealtype omega = -1;
  EXPECT_EQ(CEodeGetFrequencyBound(mem(), K.get(), mass.get(), &omega), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(Message(), "overflow"));
  EXPECT_EQ(omega, -1);
  N_VConst(1, mass.get());  // the same K with unit masses: omega_max^2 <= 1e300
  ASSERT_EQ(CEodeGetFrequencyBound(mem(), K.get(), mass.get(), &omega), CE_SUCCESS);
  EXPECT_DOUBLE_EQ(omega, 1e150);
  const sunrealtype params[3] = {0.5, 2, 1.7976931348623157e308};
  sunrealtype cx[6], cv[6];
  EXPECT_EQ(CEodeMethodErrorCoeffs(4, params, 6, cx, cv), CE_ILL_INPUT);
}

// A set with an extreme velocity weight (beta = -1e300) passes the parameter checks, and its
// positions stay finite while the velocity overflows: CEodeEvolve returns CE_UNSTABLE then, never
// success with a non-finite output, and the memory integrates again after a new set and ReInit.
TEST_F(HostileInput, AVelocityThatOverflowsWithFinitePositionsIsNeverReturnedWithSuccess) {
  const sunrealtype params[3] = {SUN_RCONST(4.0) / 3, SUN_RCONST(-1e300), 2};
  int failures = 0;
  for (const bool adaptive : {false, true}) {
    SCOPED_TRACE(adaptive ? "tolerances" : "fixed step");
    ASSERT_EQ(Start(), CE_SUCCESS);
    ASSERT_EQ(CEodeSetMethod(mem(), 4, params), CE_SUCCESS);
    if (adaptive) ASSERT_EQ(CEodeSStolerances(mem(), 1e-6, 1e-8), CE_SUCCESS);
    sunrealtype t = -1;
    const int flag = Evolve(SUN_RCONST(0.1), &t);
    if (flag >= 0) {
      EXPECT_TRUE(Finite());
      continue;
    }
    ++failures;
    EXPECT_EQ(flag, CE_UNSTABLE) << Message();
    EXPECT_FALSE(Message().empty());
    ASSERT_EQ(CEodeSetMethodByName(mem(), "G3_CD"), CE_SUCCESS);
    ASSERT_EQ(CEodeSetFixedStep(mem(), SUN_RCONST(1e-3)), CE_SUCCESS);
    ExpectCorrectRunAfterReInit();
  }
  EXPECT_GT(failures, 0) << "the set must overflow on at least one path";
}

#ifdef CEODE_HAVE_SUNSTEPPER
// The SUNStepper refuses a non-finite forcing, stop time or direction with a message, and its
// state stays usable: an evolve afterwards returns the finite state.
TEST_F(HostileInput, TheSunStepperRefusesNonFiniteForcingStopTimeAndDirection) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  SUNStepper st = nullptr;
  ASSERT_EQ(CEodeCreateSUNStepper(mem(), &st), CE_SUCCESS);
  Vector xs = SerialVector(2, ctx_, 1), vs = SerialVector(2, ctx_, SUN_RCONST(0.5));
  N_Vector parts[2] = {xs.get(), vs.get()};
  Vector y(N_VNew_ManyVector(2, parts, ctx_));
  Vector f = SerialVector(4, ctx_, NAN);
  N_Vector forcing[1] = {f.get()};
  EXPECT_NE(SUNStepper_SetForcing(st, 0, 1, forcing, 1), SUN_SUCCESS);
  EXPECT_TRUE(Contains(Message(), "forcing is not finite"));
  EXPECT_NE(SUNStepper_SetStopTime(st, NAN), SUN_SUCCESS);
  EXPECT_TRUE(Contains(Message(), "tstop"));
  EXPECT_NE(SUNStepper_SetStepDirection(st, NAN), SUN_SUCCESS);
  EXPECT_TRUE(Contains(Message(), "NaN"));
  sunrealtype t = -1;
  ASSERT_EQ(SUNStepper_Evolve(st, SUN_RCONST(0.1), y.get(), &t), SUN_SUCCESS) << Message();
  EXPECT_DOUBLE_EQ(t, 0.1);
  EXPECT_NEAR(NV_Ith_S(xs.get(), 0), std::cos(0.1) + 0.5 * std::sin(0.1), 1e-8);
  SUNStepper_Destroy(&st);
}
#endif

}  // namespace

namespace {

// A stable step from a frequency so small that the quotient overflows is unbounded, never Inf.
TEST_F(HostileInput, ADenormalFrequencyGivesTheLargestStableStepNotInfinity) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  ASSERT_EQ(CEodeSetMaxFrequency(mem(), SUN_RCONST(5e-324)), CE_SUCCESS);
  sunrealtype hmax = 0;
  ASSERT_EQ(CEodeGetStableStep(mem(), 0, &hmax), CE_SUCCESS);
  EXPECT_TRUE(std::isfinite(hmax));
  EXPECT_EQ(hmax, SUN_BIG_REAL);
  ExpectCorrectRunAfterReInit();
}

// A right-hand side that keeps failing recoverably (returns 1) inside the implicit step's Newton
// solve ends that solve with CE_RHSFUNC_FAIL: the retry with a fresh matrix is made only after a
// failure inside the iteration, not when the first residual fails (it would evaluate the same f
// at the same point without end).
TEST_F(HostileInput, ARightHandSideThatKeepsFailingEndsTheImplicitSolveInsteadOfRetryingIt) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  osc_.c = 1;
  osc_.fail_after = SUN_RCONST(0.5);
  osc_.fail_retval = 1;
  Matrix A(SUNDenseMatrix(2, 2, ctx_));
  LinearSolver LS(SUNLinSol_Dense(x_.get(), A.get(), ctx_));
  ASSERT_EQ(CEodeSetVelocityDependence(mem(), SUNTRUE), CE_SUCCESS);
  ASSERT_EQ(CEodeSetImplicitMode(mem(), CE_IMPLICIT_NEWTON), CE_SUCCESS);
  ASSERT_EQ(CEodeSetLinearSolver(mem(), LS.get(), A.get()), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(Evolve(1, &t), CE_RHSFUNC_FAIL);
  EXPECT_TRUE(Contains(Message(), "returned 1")) << Message();
  EXPECT_LE(t, SUN_RCONST(0.5));
  EXPECT_TRUE(Finite());
  ExpectCorrectRunAfterReInit();
}

// The highest derivatives of the interpolant over a first step of 1e-300 (error control, the
// step given by CEodeSetInitStep) overflow: CEodeGetDky says so with a flag instead of returning
// infinities or NaN with success.
TEST_F(HostileInput, AnInterpolantDerivativeThatOverflowsIsRefusedNotReturned) {
  ASSERT_EQ(Start(), CE_SUCCESS);
  ASSERT_EQ(CEodeSetMethodByName(mem(), "G3_CD"), CE_SUCCESS);
  ASSERT_EQ(CEodeSStolerances(mem(), 1e-6, 1e-6), CE_SUCCESS);
  ASSERT_EQ(CEodeSetInitStep(mem(), SUN_RCONST(1e-300)), CE_SUCCESS);
  const int d = 3;
  sunrealtype t = -1;
  ASSERT_EQ(CEodeEvolve(mem(), 1, x_.get(), v_.get(), &t, CE_ONE_STEP), CE_SUCCESS) << Message();
  Vector dky = SerialVector(2, ctx_, 0);
  int refused = 0;
  for (int k = 0; k <= d; ++k) {
    const int flag = CEodeGetDky(mem(), t, k, dky.get());
    if (flag == CE_SUCCESS) {
      EXPECT_TRUE(AllFinite(dky.get())) << "k = " << k;
    } else {
      EXPECT_EQ(flag, CE_ILL_INPUT);
      EXPECT_TRUE(Contains(Message(), "not finite")) << Message();
      ++refused;
    }
  }
  EXPECT_GT(refused, 0);  // at least the top derivative, of size 1 / h^(d-1)
  ASSERT_EQ(CEodeSetInitStep(mem(), 0), CE_SUCCESS);  // the start chooses its own again
  ExpectCorrectRunAfterReInit();
}

}  // namespace
