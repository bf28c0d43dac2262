// The implicit (velocity-dependent) path with every kind of SUNDIALS solver, and
// the mass-matrix bookkeeping of the explicit path (design.md "Leave out what
// the scene does not need").
#include <gtest/gtest.h>
#include <sunlinsol/sunlinsol_band.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunmatrix/sunmatrix_band.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <cmath>
#include <string>
#include <vector>

#include "test_util.hpp"

namespace {

using ceode_test::Context;
using ceode_test::DampedChain;
using ceode_test::LinearSolver;
using ceode_test::Matrix;
using ceode_test::Mem;
using ceode_test::SerialVector;
using ceode_test::Vector;

enum class Solver {
  kNewtonDenseDq,
  kNewtonDenseUserJac,
  kNewtonBandDq,
  kNewtonKluCsc,
  kNewtonKluCsr,
  kNewtonSpgmrMatrixFree,
  kFixedPoint,
};

const char* SolverName(Solver s) {
  switch (s) {
    case Solver::kNewtonDenseDq:
      return "NewtonDenseWithDifferenceQuotientJacobian";
    case Solver::kNewtonDenseUserJac:
      return "NewtonDenseWithUserJacobian";
    case Solver::kNewtonBandDq:
      return "NewtonBandWithDifferenceQuotientJacobian";
    case Solver::kNewtonKluCsc:
      return "NewtonKluWithCscUserJacobian";
    case Solver::kNewtonKluCsr:
      return "NewtonKluWithCsrUserJacobian";
    case Solver::kNewtonSpgmrMatrixFree:
      return "NewtonSpgmrMatrixFree";
    case Solver::kFixedPoint:
      return "FixedPointWithoutLinearSolver";
  }
  return "?";
}

// Printable parameter (gtest prints it in test listings).
void PrintTo(Solver s, std::ostream* os) { *os << SolverName(s); }

int DenseJac(sunrealtype /*t*/, N_Vector /*x*/, N_Vector v, N_Vector /*f*/, SUNMatrix J, void* data,
             N_Vector, N_Vector, N_Vector) {
  static_cast<const DampedChain*>(data)->VelJacobian(
      v, [J](sunindextype i, sunindextype j, sunrealtype val) { SM_ELEMENT_D(J, i, j) = val; });
  return 0;
}

// The library zeroes J before the call, structure included: rebuild it. The
// Jacobian is symmetric and emitted in column order, so the same fill is a
// valid CSC and a valid CSR matrix.
int SparseJac(sunrealtype /*t*/, N_Vector /*x*/, N_Vector v, N_Vector /*f*/, SUNMatrix J,
              void* data, N_Vector, N_Vector, N_Vector) {
  sunindextype* ptrs = SUNSparseMatrix_IndexPointers(J);
  sunindextype* idx = SUNSparseMatrix_IndexValues(J);
  sunrealtype* val = SUNSparseMatrix_Data(J);
  sunindextype nz = 0;
  sunindextype col = -1;
  static_cast<const DampedChain*>(data)->VelJacobian(
      v, [&](sunindextype i, sunindextype j, sunrealtype value) {
        while (col < j) ptrs[++col] = nz;
        idx[nz] = i;
        val[nz++] = value;
      });
  while (col < SUNSparseMatrix_Columns(J)) ptrs[++col] = nz;
  return 0;
}

struct Trajectory {
  int flag = CE_SUCCESS;
  std::vector<sunrealtype> samples;  // x and v of every DOF at every output time
  long int nst = 0;
  long int nni = 0;
  long int nnf = 0;
  long int nje = 0;
};

constexpr sunrealtype kTend = 2;
constexpr int kOutputs = 20;

Trajectory RunChain(Solver solver, const char* method, sunrealtype h) {
  Trajectory tr;
  Context ctx;
  DampedChain prob;
  const sunindextype n = prob.n;
  Vector x = SerialVector(n, ctx);
  Vector v = SerialVector(n, ctx);
  prob.Initial(x.get(), v.get());
  Mem mem(CEodeCreate(ctx));
  Matrix A;
  LinearSolver LS;
  auto ok = [&tr](int flag) {
    if (flag < 0 && tr.flag == CE_SUCCESS) tr.flag = flag;
    return flag >= 0;
  };
  bool good = ok(CEodeInit(mem.get(), DampedChain::Rhs, 0, x.get(), v.get())) &&
              ok(CEodeSetUserData(mem.get(), &prob)) &&
              ok(CEodeSetMethodByName(mem.get(), method)) && ok(CEodeSetFixedStep(mem.get(), h)) &&
              ok(CEodeSetVelocityDependence(mem.get(), SUNTRUE)) &&
              // The guard's stability sweep is not the subject, and it is slow
              // under the sanitizers.
              ok(CEodeSetStabilityGuard(mem.get(), CE_GUARD_OFF, 0));
  switch (solver) {
    case Solver::kNewtonDenseDq:
    case Solver::kNewtonDenseUserJac:
      A.reset(SUNDenseMatrix(n, n, ctx));
      LS.reset(SUNLinSol_Dense(x.get(), A.get(), ctx));
      break;
    case Solver::kNewtonBandDq:
      A.reset(SUNBandMatrix(n, 1, 1, ctx));
      LS.reset(SUNLinSol_Band(x.get(), A.get(), ctx));
      break;
    case Solver::kNewtonKluCsc:
    case Solver::kNewtonKluCsr:
      A.reset(SUNSparseMatrix(n, n, 3 * n - 2, solver == Solver::kNewtonKluCsc ? CSC_MAT : CSR_MAT,
                              ctx));
      LS.reset(SUNLinSol_KLU(x.get(), A.get(), ctx));
      break;
    case Solver::kNewtonSpgmrMatrixFree:
      LS.reset(SUNLinSol_SPGMR(x.get(), SUN_PREC_NONE, 0, ctx));
      break;
    case Solver::kFixedPoint:
      break;
  }
  if (good && LS) good = ok(CEodeSetLinearSolver(mem.get(), LS.get(), A.get()));
  if (good && solver == Solver::kFixedPoint) {
    // The fixed-point map contracts by kappa*|df/dv| ~ 0.03 here: from the
    // predictor's 1e-4 relative error, 1e-12 takes about 6 sweeps, more than the
    // default of 4 (which suits Newton).
    good = ok(CEodeSetMaxNonlinIters(mem.get(), 10));
  }
  if (good && solver == Solver::kNewtonDenseUserJac)
    good = ok(CEodeSetVelJacFn(mem.get(), DenseJac));
  if (good && (solver == Solver::kNewtonKluCsc || solver == Solver::kNewtonKluCsr)) {
    good = ok(CEodeSetVelJacFn(mem.get(), SparseJac));
  }
  for (int k = 1; good && k <= kOutputs; ++k) {
    sunrealtype t = 0;
    good = ok(CEodeEvolve(mem.get(), kTend * k / kOutputs, x.get(), v.get(), &t, CE_NORMAL));
    for (sunindextype i = 0; i < n; ++i) {
      tr.samples.push_back(NV_Ith_S(x.get(), i));
      tr.samples.push_back(NV_Ith_S(v.get(), i));
    }
  }
  CEodeGetNumSteps(mem.get(), &tr.nst);
  CEodeGetNumNonlinSolvIters(mem.get(), &tr.nni);
  CEodeGetNumNonlinSolvConvFails(mem.get(), &tr.nnf);
  CEodeGetNumJacEvals(mem.get(), &tr.nje);
  return tr;
}

sunrealtype MaxDifference(const Trajectory& a, const Trajectory& b) {
  if (a.samples.size() != b.samples.size()) return INFINITY;
  sunrealtype d = 0;
  for (size_t i = 0; i < a.samples.size(); ++i) {
    d = std::max(d, std::fabs(a.samples[i] - b.samples[i]));
  }
  return d;
}

// Each step solves for the acceleration to a relative 1e-12 (the default
// nonlinear tolerance); the states (of order 0.1 to 1) of the different solvers
// then agree far below the 1e-10 the contract asks for.
constexpr sunrealtype kAgreement = 1e-10;
constexpr sunrealtype kSmallStep = SUN_RCONST(1e-3);

class ImplicitPath : public ::testing::TestWithParam<Solver> {};

TEST_P(ImplicitPath, AgreesWithNewtonDenseOnADampedSpringChainWithNonlinearDampers) {
  const Solver solver = GetParam();
  for (const char* method : {"G3_CD", "G4_A34", "G5"}) {
    SCOPED_TRACE(method);
    const Trajectory ref = RunChain(Solver::kNewtonDenseDq, method, kSmallStep);
    const Trajectory tr = RunChain(solver, method, kSmallStep);
    ASSERT_EQ(ref.flag, CE_SUCCESS);
    ASSERT_EQ(tr.flag, CE_SUCCESS);
    ASSERT_EQ(tr.samples.size(), static_cast<size_t>(kOutputs * 2 * 5));
    const sunrealtype diff = MaxDifference(ref, tr);
    std::printf(
        "[ implicit ] %-42s %-6s max diff = %.3e  iters/step = %.3f  conv fails = %ld  "
        "Jac evals = %ld\n",
        SolverName(solver), method, diff, static_cast<double>(tr.nni) / tr.nst, tr.nnf, tr.nje);
    EXPECT_LE(diff, kAgreement);
    EXPECT_EQ(tr.nnf, 0);
    if (solver != Solver::kFixedPoint) {
      // At small h the predictor is already close and the Newton matrix is exact.
      EXPECT_LE(static_cast<double>(tr.nni) / tr.nst, 3.0);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(EverySolver, ImplicitPath,
                         ::testing::Values(Solver::kNewtonDenseDq, Solver::kNewtonDenseUserJac,
                                           Solver::kNewtonBandDq, Solver::kNewtonKluCsc,
                                           Solver::kNewtonKluCsr, Solver::kNewtonSpgmrMatrixFree,
                                           Solver::kFixedPoint),
                         [](const ::testing::TestParamInfo<Solver>& info) {
                           return SolverName(info.param);
                         });

// ---------------------------------------------------------------------------
// Mass matrix on the explicit path.

struct MassProblem {
  DampedChain chain;
  sunrealtype scale = 1;      // M = scale * (consistent tridiagonal mass), f = scale * chain force
  bool depends_on_x = false;  // M(x) = M0 * (1 + 0.1 sum x_i^2)
};

sunrealtype MassFactor(const MassProblem& p, N_Vector x) {
  if (!p.depends_on_x) return p.scale;
  return p.scale * (1 + SUN_RCONST(0.1) * N_VDotProd(x, x));
}

int MassFn(sunrealtype /*t*/, N_Vector x, SUNMatrix M, void* data, N_Vector, N_Vector, N_Vector) {
  const auto* p = static_cast<const MassProblem*>(data);
  const sunrealtype s = MassFactor(*p, x);
  const sunindextype n = p->chain.n;
  for (sunindextype i = 0; i < n; ++i) {
    SM_ELEMENT_D(M, i, i) = s * 4 / 6;
    if (i + 1 < n) SM_ELEMENT_D(M, i, i + 1) = SM_ELEMENT_D(M, i + 1, i) = s / 6;
  }
  return 0;
}

int MassRhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
  const auto* p = static_cast<const MassProblem*>(data);
  DampedChain::Rhs(t, x, v, f, const_cast<DampedChain*>(&p->chain));
  N_VScale(MassFactor(*p, x), f, f);
  return 0;
}

struct MassRun {
  int flag = CE_SUCCESS;
  long int nst = 0, nme = 0, nsetups = 0, nfe_start = 0;
  std::vector<sunrealtype> x;
};

MassRun RunMass(MassProblem prob, bool constant, const char* method) {
  MassRun r;
  Context ctx;
  prob.chain.damped = false;
  const sunindextype n = prob.chain.n;
  Vector x = SerialVector(n, ctx);
  Vector v = SerialVector(n, ctx);
  prob.chain.Initial(x.get(), v.get());
  Matrix M(SUNDenseMatrix(n, n, ctx));
  Matrix A(SUNDenseMatrix(n, n, ctx));
  LinearSolver LS(SUNLinSol_Dense(x.get(), A.get(), ctx));
  Mem mem(CEodeCreate(ctx));
  auto ok = [&r](int flag) {
    if (flag < 0 && r.flag == CE_SUCCESS) r.flag = flag;
    return flag >= 0;
  };
  bool good = ok(CEodeInit(mem.get(), MassRhs, 0, x.get(), v.get())) &&
              ok(CEodeSetUserData(mem.get(), &prob)) &&
              ok(CEodeSetMethodByName(mem.get(), method)) &&
              ok(CEodeSetFixedStep(mem.get(), SUN_RCONST(1e-3))) &&
              // The guard's power iteration evaluates the mass too; this run counts
              // only what the steps and the start need.
              ok(CEodeSetStabilityGuard(mem.get(), CE_GUARD_OFF, 0)) &&
              ok(CEodeSetMassFn(mem.get(), MassFn, M.get(), constant ? SUNTRUE : SUNFALSE)) &&
              ok(CEodeSetLinearSolver(mem.get(), LS.get(), A.get()));
  sunrealtype t = 0;
  if (good) ok(CEodeEvolve(mem.get(), 1, x.get(), v.get(), &t, CE_NORMAL));
  CEodeGetNumSteps(mem.get(), &r.nst);
  CEodeGetNumMassEvals(mem.get(), &r.nme);
  CEodeGetNumLinSolvSetups(mem.get(), &r.nsetups);
  CEodeGetNumStartRhsEvals(mem.get(), &r.nfe_start);
  for (sunindextype i = 0; i < n; ++i) r.x.push_back(NV_Ith_S(x.get(), i));
  return r;
}

TEST(ConstantMass, IsEvaluatedAndFactoredExactlyOnceOverTheRun) {
  for (const char* method : {"G3_CD", "G4_A34", "G5"}) {
    SCOPED_TRACE(method);
    const MassRun r = RunMass(MassProblem{}, true, method);
    ASSERT_EQ(r.flag, CE_SUCCESS);
    EXPECT_EQ(r.nst, 1000);
    EXPECT_EQ(r.nme, 1);
    EXPECT_EQ(r.nsetups, 1);
  }
}

TEST(ConstantMass, GivesTheSameMotionWhateverItsScale) {
  // M x'' = f with M and f both scaled by 3 is the same ODE: only the mass solve
  // differs, so the runs agree to a few ulps.
  MassProblem unit;
  MassProblem scaled;
  scaled.scale = 3;
  const MassRun a = RunMass(unit, true, "G4_A34");
  const MassRun b = RunMass(scaled, true, "G4_A34");
  ASSERT_EQ(a.flag, CE_SUCCESS);
  ASSERT_EQ(b.flag, CE_SUCCESS);
  for (size_t i = 0; i < a.x.size(); ++i) EXPECT_NEAR(a.x[i], b.x[i], 1e-13);
}

TEST(NonConstantMass, IsReEvaluatedAndRefactoredEveryStep) {
  MassProblem prob;
  prob.depends_on_x = true;
  for (const char* method : {"G3_CD", "G4_A34", "G5"}) {
    SCOPED_TRACE(method);
    const MassRun r = RunMass(prob, false, method);
    ASSERT_EQ(r.flag, CE_SUCCESS);
    EXPECT_EQ(r.nst, 1000);
    // One evaluation per step plus one per f evaluation of the start.
    EXPECT_EQ(r.nme, r.nst + r.nfe_start);
    EXPECT_EQ(r.nsetups, r.nme);
  }
}

}  // namespace
