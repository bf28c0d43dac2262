// Index-3 constraints without index reduction (docs/theory.md section 8): the DAE pendulum of the
// paper's Table 11, multipliers, velocity-dependent forces, error paths, dense versus KLU.
#include <ceode/ceode.h>
#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "ceode_testing.h"  // CEodeSetSchurComplement
#include "test_util.hpp"

namespace {

using namespace ceode_test;  // the handles and helpers of test_util.hpp

constexpr double kG = 9.81;
constexpr double kL = 1.0;
constexpr double kM = 1.0;
constexpr double kPi = 3.14159265358979323846;

// The paper's DAE pendulum: q = (x, y, theta) of the centre of mass, M = diag(m, m, 0),
// Phi = (x - L sin theta, y + L cos theta); options for damping, a duplicated constraint
// and a constraint function that fails on request.
struct Pendulum {
  double damping = 0;      // f = (-c x', -m g - c y', 0)
  bool redundant = false;  // Phi_3 = Phi_1
  long fail_at = -1;       // the constraint function fails at this call
  long calls = 0;
  bool sparse = false;
  int nc() const { return redundant ? 3 : 2; }
};

int Rhs(sunrealtype, N_Vector q, N_Vector v, N_Vector f, void* ud) {
  auto* p = static_cast<Pendulum*>(ud);
  const double* vd = N_VGetArrayPointer(v);
  double* fd = N_VGetArrayPointer(f);
  (void)q;
  fd[0] = -p->damping * vd[0];
  fd[1] = -kM * kG - p->damping * vd[1];
  fd[2] = 0;
  return 0;
}

int VelJac(sunrealtype, N_Vector, N_Vector, N_Vector, SUNMatrix J, void* ud, N_Vector, N_Vector,
           N_Vector) {
  auto* p = static_cast<Pendulum*>(ud);
  if (SUNMatGetID(J) == SUNMATRIX_DENSE) {
    SUNDenseMatrix_Column(J, 0)[0] = -p->damping;
    SUNDenseMatrix_Column(J, 1)[1] = -p->damping;
    return 0;
  }
  sunindextype* ptr = SUNSparseMatrix_IndexPointers(J);
  sunindextype* idx = SUNSparseMatrix_IndexValues(J);
  sunrealtype* val = SUNSparseMatrix_Data(J);
  ptr[0] = 0;
  idx[0] = 0;
  val[0] = -p->damping;
  ptr[1] = 1;
  idx[1] = 1;
  val[1] = -p->damping;
  ptr[2] = 2;
  ptr[3] = 2;
  return 0;
}

int Mass(sunrealtype, N_Vector, SUNMatrix M, void*, N_Vector, N_Vector, N_Vector) {
  if (SUNMatGetID(M) == SUNMATRIX_DENSE) {
    SUNDenseMatrix_Column(M, 0)[0] = kM;
    SUNDenseMatrix_Column(M, 1)[1] = kM;
    SUNDenseMatrix_Column(M, 2)[2] = 0;  // point mass: no rotational inertia
    return 0;
  }
  sunindextype* ptr = SUNSparseMatrix_IndexPointers(M);
  sunindextype* idx = SUNSparseMatrix_IndexValues(M);
  sunrealtype* val = SUNSparseMatrix_Data(M);
  for (int i = 0; i < 3; ++i) {
    ptr[i] = i;
    idx[i] = i;
    val[i] = i < 2 ? kM : 0;
  }
  ptr[3] = 3;
  return 0;
}

int Phi(sunrealtype, N_Vector q, N_Vector phi, void* ud) {
  auto* p = static_cast<Pendulum*>(ud);
  if (p->calls++ == p->fail_at) return -1;
  const double* qd = N_VGetArrayPointer(q);
  double* r = N_VGetArrayPointer(phi);
  r[0] = qd[0] - kL * std::sin(qd[2]);
  r[1] = qd[1] + kL * std::cos(qd[2]);
  if (p->redundant) r[2] = r[0];
  return 0;
}

int Jac(sunrealtype, N_Vector q, SUNMatrix G, void* ud) {
  auto* p = static_cast<Pendulum*>(ud);
  const double th = N_VGetArrayPointer(q)[2];
  const double g02 = -kL * std::cos(th);
  const double g12 = -kL * std::sin(th);
  if (SUNMatGetID(G) == SUNMATRIX_DENSE) {
    for (int r = 0; r < p->nc(); ++r) {
      const int rr = r % 2;
      SUNDenseMatrix_Column(G, rr)[r] = 1;
      SUNDenseMatrix_Column(G, 2)[r] = rr == 0 ? g02 : g12;
    }
    return 0;
  }
  sunindextype* ptr = SUNSparseMatrix_IndexPointers(G);
  sunindextype* idx = SUNSparseMatrix_IndexValues(G);
  sunrealtype* val = SUNSparseMatrix_Data(G);
  if (SUNSparseMatrix_NNZ(G) < 2 * p->nc()) return -1;
  for (int r = 0; r < p->nc(); ++r) {
    const int rr = r % 2;
    ptr[r] = 2 * r;
    idx[2 * r] = rr;
    val[2 * r] = 1;
    idx[2 * r + 1] = 2;
    val[2 * r + 1] = rr == 0 ? g02 : g12;
  }
  ptr[p->nc()] = 2 * p->nc();
  return 0;
}

struct RunResult {
  int flag = 0;
  double error = 0;  // max |E - E0|
  double drift = 0;  // max |x^2 + y^2 - L^2|
  long steps = 0;
  long iters = 0;
  long setups = 0;
  long jac_evals = 0;
  long constr_jac_evals = 0;
  std::vector<double> q, v, lambda;  // at the end
  double tension_err = 0;            // max relative error of the rod tension from lambda
  sunrealtype ic_dx = -1;            // CEodeGetICCorrection's dx (RunOptions::calc_ic)
  std::string message;               // the last error message where a call failed
  int first_flag = 0;                // RunOptions::retry_tol: the flag of the failed call
  double t_end = 0;                  // where the run ended
};

// Runs the pendulum with CEODE; checks energy and drift at every step.
struct RunOptions {
  const char* method = "G5_ONES";
  double h = 1e-3;
  double tend = 10;
  bool zero_start = true;
  bool sparse = false;  // KLU with CSR matrices instead of the default dense path
  bool vel_dependent = false;
  bool user_jac = false;
  int maxcor = 0;         // > 0: CEodeSetMaxNonlinIters
  double nls_reltol = 0;  // > 0: CEodeSetNonlinTolerances(reltol, 0)
  long msbj = 0;          // > 0: CEodeSetJacEvalFrequency
  bool schur = true;      // false: CEodeSetSchurComplement(SUNFALSE), the full saddle solve
  double tol = 0;         // > 0: error control with rtol = atol = tol instead of the fixed h
  double retry_tol = 0;   // > 0: after a failed call, these tolerances and the run goes on
  double x0_offset = 0;   // x(0) = L + x0_offset: off the constraints when not 0
  bool calc_ic = false;   // CEodeCalcIC(CE_IC_POSITION | CE_IC_VELOCITY) before the first step
  Pendulum* problem = nullptr;
};

RunResult RunPendulum(const RunOptions& o) {
  RunResult res;
  Context ctx;
  Pendulum local;
  Pendulum* p = o.problem != nullptr ? o.problem : &local;
  p->sparse = o.sparse;
  const int nc = p->nc();
  Vector q0 = SerialVector(3, ctx);
  Vector v0 = SerialVector(3, ctx);
  double* qd0 = N_VGetArrayPointer(q0.get());
  qd0[0] = kL + o.x0_offset;
  qd0[1] = 0;
  qd0[2] = kPi / 2;
  Mem mem(CEodeCreate(ctx));
  CEodeSetErrFile(mem.get(), nullptr);
  EXPECT_EQ(CEodeInit(mem.get(), Rhs, 0, q0.get(), v0.get()), CE_SUCCESS);
  EXPECT_EQ(CEodeSetMethodByName(mem.get(), o.method), CE_SUCCESS);
  EXPECT_EQ(CEodeSetFixedStep(mem.get(), o.h), CE_SUCCESS);
  if (o.tol > 0) {
    EXPECT_EQ(CEodeSStolerances(mem.get(), o.tol, o.tol), CE_SUCCESS);
    EXPECT_EQ(CEodeSetStopTime(mem.get(), o.tend), CE_SUCCESS);
  }
  CEodeSetZeroStart(mem.get(), o.zero_start ? SUNTRUE : SUNFALSE);
  CEodeSetUserData(mem.get(), p);
  CEodeSetMaxNumSteps(mem.get(), 100000000L);
  Vector tmpl = SerialVector(nc, ctx);
  EXPECT_EQ(CEodeSetConstraints(mem.get(), tmpl.get(), Phi, Jac), CE_SUCCESS);
  Matrix Mmat, A;
  LinearSolver LS;
  Vector lsv = SerialVector(3 + nc, ctx);
  if (o.sparse) {
    Mmat.reset(SUNSparseMatrix(3, 3, 3, CSR_MAT, ctx));
    A.reset(SUNSparseMatrix(3 + nc, 3 + nc, 4, CSR_MAT, ctx));  // too small: CEODE reallocates
    LS.reset(SUNLinSol_KLU(lsv.get(), A.get(), ctx));
  } else {
    Mmat.reset(SUNDenseMatrix(3, 3, ctx));
    A.reset(SUNDenseMatrix(3 + nc, 3 + nc, ctx));
    LS.reset(SUNLinSol_Dense(lsv.get(), A.get(), ctx));
  }
  EXPECT_EQ(CEodeSetMassFn(mem.get(), Mass, Mmat.get(), SUNTRUE), CE_SUCCESS);
  EXPECT_EQ(CEodeSetLinearSolver(mem.get(), LS.get(), A.get()), CE_SUCCESS);
  if (o.vel_dependent) CEodeSetVelocityDependence(mem.get(), SUNTRUE);
  if (o.user_jac) CEodeSetVelJacFn(mem.get(), VelJac);
  if (o.maxcor > 0) EXPECT_EQ(CEodeSetMaxNonlinIters(mem.get(), o.maxcor), CE_SUCCESS);
  if (o.nls_reltol > 0) {
    EXPECT_EQ(CEodeSetNonlinTolerances(mem.get(), o.nls_reltol, 0), CE_SUCCESS);
  }
  if (o.msbj > 0) EXPECT_EQ(CEodeSetJacEvalFrequency(mem.get(), o.msbj), CE_SUCCESS);
  if (!o.schur) EXPECT_EQ(CEodeSetSchurComplement(mem.get(), SUNFALSE), CE_SUCCESS);
  if (o.calc_ic) {
    sunrealtype dv = 0;
    EXPECT_EQ(CEodeCalcIC(mem.get(), CE_IC_POSITION | CE_IC_VELOCITY), CE_SUCCESS);
    EXPECT_EQ(CEodeGetICCorrection(mem.get(), &res.ic_dx, &dv), CE_SUCCESS);
    EXPECT_EQ(dv, 0);  // at rest: G v = 0 already
  }

  Vector q = SerialVector(3, ctx);
  Vector v = SerialVector(3, ctx);
  Vector lam = SerialVector(nc, ctx);
  const double E0 = 0;  // at rest at y = 0
  double t = 0;
  const long nsteps = o.tol > 0 ? 100000000L : std::lround(o.tend / o.h);
  double dissipated = 0;
  double pvv = 0;
  for (long k = 0; k < nsteps && t < o.tend; ++k) {
    const double tprev = t;
    res.flag = CEodeEvolve(mem.get(), t + o.h, q.get(), v.get(), &t, CE_ONE_STEP);
    if (res.flag < 0) {
      const char* msg = nullptr;
      CEodeGetLastErrorMessage(mem.get(), &msg);
      res.message = msg != nullptr ? msg : "";
      std::printf("  %s\n", res.message.c_str());
      if (o.retry_tol > 0 && res.first_flag == 0) {
        res.first_flag = res.flag;
        EXPECT_EQ(CEodeSStolerances(mem.get(), o.retry_tol, o.retry_tol), CE_SUCCESS);
        continue;
      }
      break;
    }
    const double dt = t - tprev;
    const double* qd = N_VGetArrayPointer(q.get());
    const double* vd = N_VGetArrayPointer(v.get());
    const double vv = vd[0] * vd[0] + vd[1] * vd[1];
    dissipated += 0.5 * dt * p->damping * (vv + pvv);  // trapezoid of c |v|^2
    pvv = vv;
    const double E = 0.5 * kM * vv + kM * kG * qd[1] + dissipated;
    res.error = std::max(res.error, std::fabs(E - E0));
    res.drift = std::max(res.drift, std::fabs(qd[0] * qd[0] + qd[1] * qd[1] - kL * kL));
    if (k % 97 == 0 && p->damping == 0) {
      // Rod tension from the multipliers against m (|v|^2 / L + g cos(angle from vertical)).
      CEodeGetMultipliers(mem.get(), lam.get());
      const double* ld = N_VGetArrayPointer(lam.get());
      const double tension = (ld[0] * qd[0] + ld[1] * qd[1]) / kL;
      const double exact = kM * (vv / kL - kG * qd[1] / kL);
      res.tension_err = std::max(res.tension_err, std::fabs(tension - exact) / (kM * kG));
    }
  }
  res.t_end = t;
  CEodeGetNumSteps(mem.get(), &res.steps);
  CEodeGetNumNonlinSolvIters(mem.get(), &res.iters);
  CEodeGetNumLinSolvSetups(mem.get(), &res.setups);
  CEodeGetNumJacEvals(mem.get(), &res.jac_evals);
  CEodeGetNumConstrJacEvals(mem.get(), &res.constr_jac_evals);
  res.q.assign(N_VGetArrayPointer(q.get()), N_VGetArrayPointer(q.get()) + 3);
  res.v.assign(N_VGetArrayPointer(v.get()), N_VGetArrayPointer(v.get()) + 3);
  if (CEodeGetMultipliers(mem.get(), lam.get()) == CE_SUCCESS) {
    res.lambda.assign(N_VGetArrayPointer(lam.get()), N_VGetArrayPointer(lam.get()) + nc);
  }
  std::printf(
      "  %-8s h = %g %s: error %.3e drift %.3e, %.2f Newton iterations/step, "
      "%ld setups\n",
      o.method, o.h, o.zero_start ? "(zero start)" : "(consistent)", res.error, res.drift,
      res.steps > 0 ? static_cast<double>(res.iters) / res.steps : 0.0, res.setups);
  return res;
}

// Table 11 of the paper, from test/data/paper_pendulum_dae.csv: h -> (error, drift).
std::map<double, std::pair<double, double>> PaperTable11() {
  std::map<double, std::pair<double, double>> out;
  std::ifstream in(std::string(CEODE_TEST_DATA_DIR) + "/paper_pendulum_dae.csv");
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("method", 0) == 0) continue;
    std::stringstream ss(line);
    std::string method, hs, es, ds, ts;
    std::getline(ss, method, ',');
    std::getline(ss, hs, ',');
    std::getline(ss, es, ',');
    std::getline(ss, ds, ',');
    if (method == "G5_ONES") out[std::stod(hs)] = {std::stod(es), std::stod(ds)};
  }
  return out;
}

TEST(Constraints, G5OnesReproducesThePapersTable11EnergyErrorWithinTenPercent) {
  const auto table = PaperTable11();
  ASSERT_EQ(table.count(1e-2), 1u) << "test/data/paper_pendulum_dae.csv is missing rows";
  ASSERT_EQ(table.count(1e-3), 1u);
  for (double h : {1e-2, 1e-3}) {
    RunOptions o;
    o.h = h;
    const RunResult r = RunPendulum(o);
    ASSERT_EQ(r.flag, CE_SUCCESS);
    const double ref = table.at(h).first;
    EXPECT_NEAR(r.error, ref, 0.1 * ref) << "h = " << h;
    EXPECT_LE(r.drift, 1e-14) << "h = " << h;
  }
}

TEST(Constraints, G5OnesKeepsTheEnergyErrorBelowTwoTimesTenToTheMinusTwelveAtHEqualsOneEMinus4) {
  RunOptions o;
  o.h = 1e-4;
  const RunResult r = RunPendulum(o);
  ASSERT_EQ(r.flag, CE_SUCCESS);
  EXPECT_LE(r.error, 2e-12);
  EXPECT_LE(r.drift, 1e-14);
}

// One million steps (about 2 s in Release): the paper's Table 11 reports 2.63e-12 here.
TEST(Constraints, G5OnesKeepsTheDriftAtRoundOffAtHEqualsOneEMinus5) {
  RunOptions o;
  o.h = 1e-5;
  const RunResult r = RunPendulum(o);
  ASSERT_EQ(r.flag, CE_SUCCESS);
  EXPECT_LE(r.drift, 1e-14);
  EXPECT_LE(r.error, 1e-11);
}

TEST(Constraints, G5OnesWithTheConsistentStartKeepsTheDriftAtRoundOff) {
  for (double h : {1e-2, 1e-3, 1e-4}) {
    RunOptions o;
    o.h = h;
    o.zero_start = false;
    const RunResult r = RunPendulum(o);
    ASSERT_EQ(r.flag, CE_SUCCESS);
    EXPECT_LE(r.drift, 1e-14) << "h = " << h;
  }
}

TEST(Constraints, G3CentralDifferencesAndG4KeepTheDriftAtRoundOff) {
  for (const char* m : {"G3_CD", "G4_A34", "G4_A54"}) {
    for (double h : {1e-2, 1e-3}) {
      RunOptions o;
      o.method = m;
      o.h = h;
      o.zero_start = false;
      const RunResult r = RunPendulum(o);
      ASSERT_EQ(r.flag, CE_SUCCESS) << m;
      EXPECT_LE(r.drift, 1e-14) << m << " h = " << h;
      EXPECT_LE(r.error, 1e-2) << m << " h = " << h;
    }
  }
}

// In constrained directions the position x(t+h) is imposed, and the history follows the method's
// recurrence with x prescribed. For G4 alpha = 1/4 that recurrence has the root -1.94 (G4_A34: -1,
// G4_A54 and G5_ONES: |0.64|), so constrained components of the history grow by 1.94 per step.
TEST(Constraints, G4AlphaOneQuarterIsUnstableInConstrainedDirections) {
  RunOptions o;
  o.method = "G4_A14";
  o.h = 1e-2;
  o.tend = 1;
  o.zero_start = false;
  const RunResult r = RunPendulum(o);
  EXPECT_TRUE(r.flag != CE_SUCCESS || r.error > 1e-1) << "error " << r.error;
}

// Error control on the index-3 pendulum (docs/theory.md 12.6): the drift stays at round-off,
// the energy error follows the tolerance. (The sets of degree 6 and more do not run this
// pendulum with constraints at any fixed step either.)
TEST(Constraints, ErrorControlKeepsTheDriftAtRoundOffAndTheEnergyErrorAtTheTolerancesScale) {
  for (const char* method : {"G3_CD", "G4_A34", "G5_O4"}) {
    for (double tol : {1e-6, 1e-8, 1e-10}) {
      if (tol < 1e-8 && std::string(method) == "G3_CD") continue;  // 1.9 million steps
      RunOptions o;
      o.method = method;
      o.zero_start = false;
      o.tol = tol;
      const RunResult r = RunPendulum(o);
      ASSERT_GE(r.flag, 0) << method << " tol " << tol;
      std::printf("    tol %g: %ld steps\n", tol, r.steps);
      EXPECT_LT(r.drift, 1e-14) << method << " tol " << tol;
      EXPECT_LT(r.error, 1e3 * tol) << method << " tol " << tol;
    }
  }
}

// Tolerances below what the index-3 solve attains: the error estimate meets the position
// solve's round-off and keeps asking for smaller steps, while the velocity (a difference
// quotient of positions) gains round-off eps |x| / h. The run stops with CE_ERR_FAILURE naming
// the cause while the returned states still hold the energy (with no stop, G4_A34 at 1e-12 took
// h to 1e-19 and returned an energy error of 3e8), and goes on under looser tolerances.
TEST(Constraints, ToleranceBelowTheSolvesRoundOffStopsWithErrFailureAndTheRunGoesOnWhenLoosened) {
  RunOptions o;
  o.method = "G4_A34";
  o.zero_start = false;
  o.tol = 1e-12;
  o.tend = 0.2;
  o.retry_tol = 1e-8;
  const RunResult r = RunPendulum(o);
  EXPECT_EQ(r.first_flag, CE_ERR_FAILURE);
  EXPECT_TRUE(r.message.find("round-off") != std::string::npos) << r.message;
  EXPECT_EQ(r.flag, CE_TSTOP_RETURN);
  EXPECT_DOUBLE_EQ(r.t_end, o.tend);
  EXPECT_LT(r.error, 1e-7);  // the loosened tolerances' scale
  EXPECT_LT(r.drift, 1e-14);
}

TEST(Constraints, MultipliersGiveTheRodTension) {
  RunOptions o;
  o.h = 1e-3;
  const RunResult r = RunPendulum(o);
  ASSERT_EQ(r.flag, CE_SUCCESS);
  ASSERT_EQ(r.lambda.size(), 2u);
  // Relative to m g; the tension comes from a(t) of a third-order method.
  EXPECT_LE(r.tension_err, 1e-6);
}

TEST(Constraints, LinearDampingConvergesAndDissipatesTheRightEnergy) {
  for (bool user_jac : {false, true}) {
    Pendulum p;
    p.damping = 0.5;
    RunOptions o;
    o.h = 1e-3;
    o.zero_start = false;
    o.vel_dependent = true;
    o.user_jac = user_jac;
    o.problem = &p;
    const RunResult r = RunPendulum(o);
    ASSERT_EQ(r.flag, CE_SUCCESS);
    EXPECT_LE(r.drift, 1e-14);
    // E + dissipated work (trapezoid, O(h^2)) stays constant.
    EXPECT_LE(r.error, 1e-5);
  }
}

// The constrained Newton iteration is bounded by CEodeSetMaxNonlinIters: one iteration cannot
// bring x(t + h) to round-off, so the first step fails with a convergence failure.
TEST(Constraints, TheConstrainedIterationObeysTheMaximumOfNonlinearIterations) {
  RunOptions o;
  o.tend = 0.01;
  o.maxcor = 1;
  EXPECT_EQ(RunPendulum(o).flag, CE_CONV_FAILURE);
  o.maxcor = 12;  // the constrained default, set explicitly
  EXPECT_EQ(RunPendulum(o).flag, CE_SUCCESS);
}

// CEodeSetNonlinTolerances replaces the round-off target of the constrained test (relative to
// |x(t + h)|): a loose tolerance takes fewer iterations (measured: 1 per step instead of 2) and
// keeps the drift below it.
TEST(Constraints, TheConstrainedIterationObeysTheNonlinearTolerances) {
  RunOptions o;
  o.tend = 1;
  const RunResult tight = RunPendulum(o);
  o.nls_reltol = 1e-6;
  const RunResult loose = RunPendulum(o);
  ASSERT_EQ(tight.flag, CE_SUCCESS);
  ASSERT_EQ(loose.flag, CE_SUCCESS);
  EXPECT_LT(loose.iters, tight.iters);
  EXPECT_LT(loose.drift, 1e-5);
}

// A damper nobody declared: the start detects it (f probed in x') and the constrained step solves
// with df/dv, as declared.
TEST(Constraints, AnUndeclaredDampingIsDetectedAndGivesTheDeclaredNumbers) {
  Pendulum pd, pu;
  pd.damping = pu.damping = 0.5;
  RunOptions o;
  o.tend = 1;
  o.zero_start = false;
  o.vel_dependent = true;
  o.problem = &pd;
  const RunResult declared = RunPendulum(o);
  o.vel_dependent = false;
  o.problem = &pu;
  const RunResult detected = RunPendulum(o);
  ASSERT_EQ(declared.flag, CE_SUCCESS);
  ASSERT_EQ(detected.flag, CE_SUCCESS);
  EXPECT_EQ(detected.q, declared.q);
  EXPECT_EQ(detected.v, declared.v);
  EXPECT_EQ(detected.jac_evals, declared.jac_evals);
}

// A start 1 cm off the rod: refused by the first CEodeEvolve (CE_INCONSISTENT_IC, not a convergence
// failure); projected by CEodeCalcIC in the metric of the singular M = diag(m, m, 0) on the dense
// and on the KLU path alike (the projection moves x only: G's first row has no theta entry at 90
// degrees), after which the run keeps the drift at round-off.
TEST(Constraints, AStartOffTheRodIsRefusedAndCalcICProjectsItOnTheDenseAndTheKluPath) {
  RunOptions o;
  o.tend = 0.1;
  o.x0_offset = 0.01;
  const RunResult refused = RunPendulum(o);
  EXPECT_EQ(refused.flag, CE_INCONSISTENT_IC);
  EXPECT_EQ(refused.steps, 0);
  o.calc_ic = true;
  for (bool sparse : {false, true}) {
    o.sparse = sparse;
    const RunResult r = RunPendulum(o);
    ASSERT_EQ(r.flag, CE_SUCCESS) << (sparse ? "KLU" : "dense");
    EXPECT_NEAR(r.ic_dx, 0.01, 1e-15);
    EXPECT_LE(r.drift, 1e-14);
  }
}

TEST(Constraints, ARedundantConstraintGivesAClearSetupError) {
  Pendulum p;
  p.redundant = true;
  RunOptions o;
  o.problem = &p;
  o.tend = 0.01;
  const RunResult r = RunPendulum(o);
  EXPECT_EQ(r.flag, CE_LSETUP_FAIL);
  for (double x : r.q) EXPECT_TRUE(std::isfinite(x));
}

TEST(Constraints, AFailingConstraintCallbackGivesConstrFailAndTheMemoryStaysUsable) {
  Context ctx;
  Pendulum p;
  Vector q0 = SerialVector(3, ctx);
  Vector v0 = SerialVector(3, ctx);
  N_VGetArrayPointer(q0.get())[0] = kL;
  N_VGetArrayPointer(q0.get())[2] = kPi / 2;
  Mem mem(CEodeCreate(ctx));
  CEodeSetErrFile(mem.get(), nullptr);
  ASSERT_EQ(CEodeInit(mem.get(), Rhs, 0, q0.get(), v0.get()), CE_SUCCESS);
  CEodeSetMethodByName(mem.get(), "G5_ONES");
  CEodeSetFixedStep(mem.get(), 1e-3);
  CEodeSetUserData(mem.get(), &p);
  Vector tmpl = SerialVector(2, ctx);
  ASSERT_EQ(CEodeSetConstraints(mem.get(), tmpl.get(), Phi, Jac), CE_SUCCESS);
  Matrix Mmat(SUNDenseMatrix(3, 3, ctx));
  Matrix A(SUNDenseMatrix(5, 5, ctx));
  Vector lsv = SerialVector(5, ctx);
  LinearSolver LS(SUNLinSol_Dense(lsv.get(), A.get(), ctx));
  CEodeSetMassFn(mem.get(), Mass, Mmat.get(), SUNTRUE);
  CEodeSetLinearSolver(mem.get(), LS.get(), A.get());
  Vector q = SerialVector(3, ctx);
  Vector v = SerialVector(3, ctx);
  double t = 0;
  ASSERT_EQ(CEodeEvolve(mem.get(), 0.1, q.get(), v.get(), &t, CE_NORMAL), CE_SUCCESS);
  p.fail_at = p.calls + 1;
  double tfail = 0;
  EXPECT_EQ(CEodeEvolve(mem.get(), 0.2, q.get(), v.get(), &tfail, CE_NORMAL), CE_CONSTR_FAIL);
  const char* msg = nullptr;
  CEodeGetLastErrorMessage(mem.get(), &msg);
  ASSERT_NE(msg, nullptr);
  EXPECT_NE(std::string(msg).find("constraint function failed"), std::string::npos) << msg;
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(std::isfinite(N_VGetArrayPointer(q.get())[i]));
  // The memory continues from the last good state and gives the uninterrupted answer.
  p.fail_at = -1;
  ASSERT_EQ(CEodeEvolve(mem.get(), 1.0, q.get(), v.get(), &t, CE_NORMAL), CE_SUCCESS);
  RunOptions o;
  o.h = 1e-3;
  o.tend = 1.0;
  o.zero_start = false;
  const RunResult ref = RunPendulum(o);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(N_VGetArrayPointer(q.get())[i], ref.q[i], 1e-12);
}

// Two runs of the pendulum (damped when vdep) from a consistent start over [0, 2] at h = kTwoWaysH,
// each on a fresh problem: once as configured, once after `change` has altered the options.
constexpr double kTwoWaysH = 1e-3;
struct TwoRuns {
  RunResult first, second;
};
TwoRuns RunPendulumTwoWays(bool vdep, bool user_jac, void (*change)(RunOptions*)) {
  Pendulum p1, p2;
  p1.damping = p2.damping = vdep ? 0.3 : 0;
  RunOptions o;
  o.h = kTwoWaysH;
  o.tend = 2;
  o.zero_start = false;
  o.vel_dependent = vdep;
  o.user_jac = user_jac;
  o.problem = &p1;
  TwoRuns r;
  r.first = RunPendulum(o);
  change(&o);
  o.problem = &p2;
  r.second = RunPendulum(o);
  return r;
}

TEST(Constraints, TheDensePathAndTheKluSparsePathGiveTheSameNumbers) {
  for (bool vdep : {false, true}) {
    SCOPED_TRACE(vdep ? "vdep" : "no vdep");
    const TwoRuns r = RunPendulumTwoWays(vdep, vdep, [](RunOptions* o) { o->sparse = true; });
    const RunResult& dense = r.first;
    const RunResult& sparse = r.second;
    ASSERT_EQ(dense.flag, CE_SUCCESS);
    ASSERT_EQ(sparse.flag, CE_SUCCESS);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(dense.q[i], sparse.q[i], 1e-12);
      EXPECT_NEAR(dense.v[i], sparse.v[i], 1e-12);
    }
    // The multipliers come from a = (x(t+h) - X0) / mu + B_2: the constraint fixes x(t+h) only to
    // round-off, so each run's a and lambda are resolved to about eps |x| m / mu (1.8e-10 at
    // h = 1e-3 for G5_ONES, mu = 1.25 h^2), whatever the linear solver. Two runs whose roundings
    // differ can therefore differ by twice that. Positions and velocities agree to 1e-12.
    const double lambda_resolution = 2 * 2.2e-16 * kL * kM / (1.25 * kTwoWaysH * kTwoWaysH);
    for (int i = 0; i < 2; ++i) {
      EXPECT_NEAR(dense.lambda[i], sparse.lambda[i], lambda_resolution);
    }
  }
}

// The saddle-point matrix of an earlier step serves until msbj steps have passed (20
// here; f independent of v, only when msbj is set): at most one Jacobian evaluation in ten steps,
// and the answer of a run that refreshes the matrix at every step (msbj = 1) to within its
// round-off. f depending on v: only df/dv is reused (default 20), the matrix is formed at every
// step.
TEST(Constraints, TheSaddleMatrixIsReusedAcrossStepsWithUnchangedAnswers) {
  for (bool vdep : {false, true}) {
    SCOPED_TRACE(vdep ? "vdep" : "no vdep");
    Pendulum pr, pf;
    pr.damping = pf.damping = vdep ? 0.3 : 0;
    RunOptions o;
    o.h = 1e-3;
    o.tend = 2;
    o.vel_dependent = vdep;
    o.msbj = vdep ? 0 : 20;  // 0: the default
    o.problem = &pr;
    const RunResult reused = RunPendulum(o);
    o.msbj = 1;
    o.problem = &pf;
    const RunResult fresh = RunPendulum(o);
    ASSERT_EQ(reused.flag, CE_SUCCESS);
    ASSERT_EQ(fresh.flag, CE_SUCCESS);
    EXPECT_LE(10 * reused.jac_evals, reused.steps);
    EXPECT_GE(fresh.jac_evals, fresh.steps);
    if (!vdep) {
      EXPECT_LE(10 * reused.setups, reused.steps);
      o.msbj = 0;  // the default: f independent of v refactors the saddle matrix at every step
      Pendulum pd;
      o.problem = &pd;
      const RunResult dflt = RunPendulum(o);
      ASSERT_EQ(dflt.flag, CE_SUCCESS);
      EXPECT_GE(dflt.setups, dflt.steps);
    }
    EXPECT_NEAR(reused.error, fresh.error, 1e-3 * fresh.error + 1e-14);
    EXPECT_LE(reused.drift, 1e-14);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(reused.q[i], fresh.q[i], 1e-12);
      EXPECT_NEAR(reused.v[i], fresh.v[i], 1e-11);
    }
  }
}

// Cartesian pendulum with M = I: no mass function and no linear solver, so CEODE builds its own
// dense saddle-point solver.
int CartRhs(sunrealtype, N_Vector, N_Vector, N_Vector f, void*) {
  double* fd = N_VGetArrayPointer(f);
  fd[0] = 0;
  fd[1] = -kG;
  return 0;
}
int CartPhi(sunrealtype, N_Vector q, N_Vector phi, void*) {
  const double* x = N_VGetArrayPointer(q);
  N_VGetArrayPointer(phi)[0] = 0.5 * (x[0] * x[0] + x[1] * x[1] - kL * kL);
  return 0;
}
int CartJac(sunrealtype, N_Vector q, SUNMatrix G, void*) {
  const double* x = N_VGetArrayPointer(q);
  SUNDenseMatrix_Column(G, 0)[0] = x[0];
  SUNDenseMatrix_Column(G, 1)[0] = x[1];
  return 0;
}

TEST(Constraints, WithoutALinearSolverCeodeBuildsItsOwnDenseSaddlePointSolver) {
  Context ctx;
  Vector q0 = SerialVector(2, ctx);
  Vector v0 = SerialVector(2, ctx);
  N_VGetArrayPointer(q0.get())[0] = kL;
  Mem mem(CEodeCreate(ctx));
  CEodeSetErrFile(mem.get(), nullptr);
  ASSERT_EQ(CEodeInit(mem.get(), CartRhs, 0, q0.get(), v0.get()), CE_SUCCESS);
  CEodeSetMethodByName(mem.get(), "G5_ONES");
  CEodeSetFixedStep(mem.get(), 1e-3);
  Vector tmpl = SerialVector(1, ctx);
  ASSERT_EQ(CEodeSetConstraints(mem.get(), tmpl.get(), CartPhi, CartJac), CE_SUCCESS);
  Vector q = SerialVector(2, ctx);
  Vector v = SerialVector(2, ctx);
  double t = 0;
  double drift = 0, err = 0;
  for (int k = 0; k < 2000; ++k) {
    ASSERT_EQ(CEodeEvolve(mem.get(), t + 1e-3, q.get(), v.get(), &t, CE_ONE_STEP), CE_SUCCESS);
    const double* x = N_VGetArrayPointer(q.get());
    const double* vd = N_VGetArrayPointer(v.get());
    drift = std::max(drift, std::fabs(x[0] * x[0] + x[1] * x[1] - kL * kL));
    err = std::max(err, std::fabs(0.5 * (vd[0] * vd[0] + vd[1] * vd[1]) + kG * x[1]));
  }
  EXPECT_LE(drift, 1e-14);
  EXPECT_LE(err, 1e-8);
}

// The Schur complement (theory 8.3) takes the same Newton step as the full saddle
// solve, so both give the same run; the pendulum's M = diag(m, m, 0) is singular, which B =
// A + rho G0^T G0 covers. The multipliers agree to their resolution (see the KLU test above).
TEST(Constraints, TheSchurComplementAndTheFullSaddleSolveGiveTheSameNumbersOnThePendulum) {
  for (bool vdep : {false, true}) {
    SCOPED_TRACE(vdep ? "vdep" : "no vdep");
    const TwoRuns r = RunPendulumTwoWays(vdep, false, [](RunOptions* o) { o->schur = false; });
    const RunResult& schur = r.first;
    const RunResult& full = r.second;
    ASSERT_EQ(schur.flag, CE_SUCCESS);
    ASSERT_EQ(full.flag, CE_SUCCESS);
    EXPECT_EQ(schur.steps, full.steps);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(schur.q[i], full.q[i], 1e-12 * (1 + std::fabs(full.q[i])));
      EXPECT_NEAR(schur.v[i], full.v[i], 1e-12 * (1 + std::fabs(full.v[i])));
    }
    const double lambda_resolution = 2 * 2.2e-16 * kL * kM / (1.25 * kTwoWaysH * kTwoWaysH);
    for (int i = 0; i < 2; ++i) EXPECT_NEAR(schur.lambda[i], full.lambda[i], lambda_resolution);
    EXPECT_NEAR(schur.error, full.error, 1e-3 * full.error + 1e-14);
    EXPECT_LE(schur.drift, 1e-14);
    // f independent of v: the full path refreshes its matrix (with G) at every step, the Schur
    // path B only every msbj = 20 steps; G is evaluated at every Newton setup on both. With f
    // depending on v, nje counts the evaluations of df/dv on both paths (reused msbj = 20 steps).
    if (!vdep) EXPECT_GE(full.jac_evals, full.steps);
    EXPECT_LE(10 * schur.jac_evals, schur.steps);
    EXPECT_GE(schur.constr_jac_evals, 2 * schur.steps);
  }
}

// The paper's Table 11 figures of the first test, at default settings: at most one evaluation of
// the iteration matrix in ten steps.
TEST(Constraints, AtDefaultSettingsThePendulumEvaluatesTheIterationMatrixAtMostOnceInTenSteps) {
  const auto table = PaperTable11();
  ASSERT_EQ(table.count(1e-3), 1u);
  RunOptions o;
  o.h = 1e-3;
  const RunResult r = RunPendulum(o);
  ASSERT_EQ(r.flag, CE_SUCCESS);
  const double ref = table.at(1e-3).first;
  EXPECT_NEAR(r.error, ref, 0.1 * ref);
  EXPECT_LE(r.drift, 1e-14);
  EXPECT_LE(10 * r.jac_evals, r.steps);
}

// The planar chain of N = 8 pendulums (the model of bench/wp_chain_dae.cpp: n = 16, nc = 8,
// M = I, |p_i - p_{i-1}|^2 = l^2), CEODE's own dense solver, t in [0, 1] s at h = 1e-3.
constexpr long kLinks = 8;
constexpr double kLink = 1.0 / kLinks;

int ChainRhs(sunrealtype, N_Vector, N_Vector, N_Vector f, void*) {
  double* F = N_VGetArrayPointer(f);
  for (long i = 0; i < kLinks; ++i) F[2 * i] = 0, F[2 * i + 1] = -kG;
  return 0;
}
int ChainPhi(sunrealtype, N_Vector x, N_Vector phi, void*) {
  const double* X = N_VGetArrayPointer(x);
  double* P = N_VGetArrayPointer(phi);
  for (long i = 0; i < kLinks; ++i) {
    const double dx = X[2 * i] - (i > 0 ? X[2 * i - 2] : 0);
    const double dy = X[2 * i + 1] - (i > 0 ? X[2 * i - 1] : 0);
    P[i] = dx * dx + dy * dy - kLink * kLink;
  }
  return 0;
}
int ChainJac(sunrealtype, N_Vector x, SUNMatrix G, void*) {
  const double* X = N_VGetArrayPointer(x);
  for (long i = 0; i < kLinks; ++i) {
    const double dx = X[2 * i] - (i > 0 ? X[2 * i - 2] : 0);
    const double dy = X[2 * i + 1] - (i > 0 ? X[2 * i - 1] : 0);
    if (i > 0) {
      SM_ELEMENT_D(G, i, 2 * i - 2) = -2 * dx;
      SM_ELEMENT_D(G, i, 2 * i - 1) = -2 * dy;
    }
    SM_ELEMENT_D(G, i, 2 * i) = 2 * dx;
    SM_ELEMENT_D(G, i, 2 * i + 1) = 2 * dy;
  }
  return 0;
}

struct ChainRun {
  int flag = 0;
  double error = 0, drift = 0;  // max |E - E0|, max |Phi_i|
  long steps = 0, jac_evals = 0;
  std::vector<double> x;
};

ChainRun RunChain(bool schur) {
  constexpr long n = 2 * kLinks;
  constexpr double h = 1e-3, kAngle0 = 0.5;
  Context ctx;
  Vector x0 = SerialVector(n, ctx);
  Vector v0 = SerialVector(n, ctx);
  double* X0 = N_VGetArrayPointer(x0.get());
  double e0 = 0;
  for (long i = 0; i < kLinks; ++i) {
    X0[2 * i] = (i + 1) * kLink * std::sin(kAngle0);
    X0[2 * i + 1] = -(i + 1) * kLink * std::cos(kAngle0);
    e0 += kG * X0[2 * i + 1];
  }
  Mem mem(CEodeCreate(ctx));
  CEodeSetErrFile(mem.get(), nullptr);
  EXPECT_EQ(CEodeInit(mem.get(), ChainRhs, 0, x0.get(), v0.get()), CE_SUCCESS);
  CEodeSetMethodByName(mem.get(), "G5_ONES");
  CEodeSetFixedStep(mem.get(), h);
  Vector tmpl = SerialVector(kLinks, ctx);
  EXPECT_EQ(CEodeSetConstraints(mem.get(), tmpl.get(), ChainPhi, ChainJac), CE_SUCCESS);
  if (!schur) EXPECT_EQ(CEodeSetSchurComplement(mem.get(), SUNFALSE), CE_SUCCESS);
  Vector x = SerialVector(n, ctx);
  Vector v = SerialVector(n, ctx);
  Vector phi = SerialVector(kLinks, ctx);
  ChainRun r;
  double t = 0;
  for (long k = 0; k < 1000 && r.flag >= 0; ++k) {
    r.flag = CEodeEvolve(mem.get(), t + h, x.get(), v.get(), &t, CE_ONE_STEP);
    const double* X = N_VGetArrayPointer(x.get());
    const double* V = N_VGetArrayPointer(v.get());
    double e = 0;
    for (long i = 0; i < n; ++i) e += 0.5 * V[i] * V[i] + (i % 2 == 1 ? kG * X[i] : 0);
    r.error = std::max(r.error, std::fabs(e - e0));
    ChainPhi(t, x.get(), phi.get(), nullptr);
    r.drift = std::max(r.drift, N_VMaxNorm(phi.get()));
  }
  CEodeGetNumSteps(mem.get(), &r.steps);
  CEodeGetNumJacEvals(mem.get(), &r.jac_evals);
  r.x.assign(N_VGetArrayPointer(x.get()), N_VGetArrayPointer(x.get()) + n);
  return r;
}

TEST(Constraints, TheSchurComplementAndTheFullSaddleSolveGiveTheSameNumbersOnTheChain) {
  const ChainRun schur = RunChain(true);
  const ChainRun full = RunChain(false);
  ASSERT_EQ(schur.flag, CE_SUCCESS);
  ASSERT_EQ(full.flag, CE_SUCCESS);
  ASSERT_EQ(schur.steps, 1000);
  for (size_t i = 0; i < full.x.size(); ++i) {
    EXPECT_NEAR(schur.x[i], full.x[i], 1e-12 * (1 + std::fabs(full.x[i])));
  }
  EXPECT_NEAR(schur.error, full.error, 1e-3 * full.error + 1e-14);
  // bench/wp_chain_dae.cpp's check: drift <= 1e-10 l^2.
  EXPECT_LE(schur.drift, 1e-10 * kLink * kLink);
  EXPECT_LE(full.drift, 1e-10 * kLink * kLink);
  EXPECT_LE(10 * schur.jac_evals, schur.steps);
  EXPECT_GE(full.jac_evals, full.steps);
  std::printf("  chain: error %.3e / %.3e, drift %.3e / %.3e, nje %ld / %ld (Schur / full)\n",
              schur.error, full.error, schur.drift, full.drift, schur.jac_evals, full.jac_evals);
}

}  // namespace
