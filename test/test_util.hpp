// Shared helpers of the CEODE test suite: RAII handles for SUNDIALS objects,
// test problems with exact solutions, runs against them and log-log fits.
#ifndef CEODE_TEST_TEST_UTIL_HPP_
#define CEODE_TEST_TEST_UTIL_HPP_

#include <ceode/ceode.h>
#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "ceode_sundials_compat.h"  // SUN_COMM_NULL on SUNDIALS 6.4

namespace ceode_test {

// gtest alone (no gmock): a substring check that prints both strings on failure.
inline ::testing::AssertionResult Contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "\"" << text << "\" does not contain \"" << part << "\"";
}

// ---------------------------------------------------------------------------
// RAII handles: a failing ASSERT must not leak under the sanitizers.

class Context {
 public:
  Context() { SUNContext_Create(SUN_COMM_NULL, &ctx_); }
  ~Context() { SUNContext_Free(&ctx_); }
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  operator SUNContext() const { return ctx_; }  // NOLINT: reads like the C handle

 private:
  SUNContext ctx_ = nullptr;
};

struct VectorDeleter {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
using Vector = std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorDeleter>;

struct MatrixDeleter {
  void operator()(SUNMatrix m) const { SUNMatDestroy(m); }
};
using Matrix = std::unique_ptr<std::remove_pointer_t<SUNMatrix>, MatrixDeleter>;

struct LinearSolverDeleter {
  void operator()(SUNLinearSolver ls) const { SUNLinSolFree(ls); }
};
using LinearSolver = std::unique_ptr<std::remove_pointer_t<SUNLinearSolver>, LinearSolverDeleter>;

struct MemDeleter {
  void operator()(void* mem) const { CEodeFree(&mem); }
};
using Mem = std::unique_ptr<void, MemDeleter>;

inline Vector SerialVector(sunindextype n, SUNContext ctx, sunrealtype value = 0) {
  Vector v(N_VNew_Serial(n, ctx));
  if (v) N_VConst(value, v.get());
  return v;
}

// Flag names are malloc'd by the library; the caller frees them.
inline std::string FlagName(long int flag) {
  char* name = CEodeGetReturnFlagName(flag);
  std::string out = name != nullptr ? name : "(null)";
  std::free(name);
  return out;
}

// ---------------------------------------------------------------------------
// Problems with exact solutions (all 1 DOF, written with generic N_Vector
// operations so that they run on every vector implementation).

// Interface of a scalar problem x'' = g(t, x, x') with a closed-form solution.
struct ExactProblem {
  virtual ~ExactProblem() = default;
  virtual CEodeRhsFn Rhs() const = 0;
  virtual bool VelocityDependent() const = 0;
  virtual void Exact(sunrealtype t, sunrealtype* x, sunrealtype* v) const = 0;
  sunrealtype x0 = 1;
  sunrealtype v0 = SUN_RCONST(0.5);
};

// x'' = -w^2 x: conservative. x'(0) != 0 so that the initial jerk -w^2 v0 is not zero.
struct Harmonic : ExactProblem {
  sunrealtype w = 1;
  static int F(sunrealtype /*t*/, N_Vector x, N_Vector /*v*/, N_Vector f, void* data) {
    const auto* p = static_cast<const Harmonic*>(data);
    N_VScale(-p->w * p->w, x, f);
    return 0;
  }
  CEodeRhsFn Rhs() const override { return F; }
  bool VelocityDependent() const override { return false; }
  void Exact(sunrealtype t, sunrealtype* x, sunrealtype* v) const override {
    *x = x0 * std::cos(w * t) + v0 / w * std::sin(w * t);
    *v = -x0 * w * std::sin(w * t) + v0 * std::cos(w * t);
  }
};

// x'' + 2 zeta w x' + w^2 x = F cos(W t): velocity dependent, forced, with an
// initial jerk -2 zeta w a0 - w^2 v0 that is far from zero.
struct DampedForced : ExactProblem {
  sunrealtype w = 1;
  sunrealtype zeta = SUN_RCONST(0.1);
  sunrealtype force = 1;
  sunrealtype W = 2;
  static int F(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
    const auto* p = static_cast<const DampedForced*>(data);
    N_VLinearSum(-p->w * p->w, x, -2 * p->zeta * p->w, v, f);
    N_VAddConst(f, p->force * std::cos(p->W * t), f);
    return 0;
  }
  CEodeRhsFn Rhs() const override { return F; }
  bool VelocityDependent() const override { return true; }
  void Exact(sunrealtype t, sunrealtype* x, sunrealtype* v) const override {
    // Particular solution A cos Wt + B sin Wt plus the underdamped transient.
    const sunrealtype d2 = w * w - W * W;
    const sunrealtype dd = 2 * zeta * w * W;
    const sunrealtype den = d2 * d2 + dd * dd;
    const sunrealtype A = force * d2 / den;
    const sunrealtype B = force * dd / den;
    const sunrealtype wd = w * std::sqrt(1 - zeta * zeta);
    const sunrealtype s = zeta * w;
    const sunrealtype C1 = x0 - A;
    const sunrealtype C2 = (v0 - W * B + s * C1) / wd;
    const sunrealtype e = std::exp(-s * t);
    const sunrealtype c = std::cos(wd * t);
    const sunrealtype sn = std::sin(wd * t);
    *x = A * std::cos(W * t) + B * std::sin(W * t) + e * (C1 * c + C2 * sn);
    *v = -A * W * std::sin(W * t) + B * W * std::cos(W * t) +
         e * (-s * (C1 * c + C2 * sn) + wd * (-C1 * sn + C2 * c));
  }
};

// ---------------------------------------------------------------------------
// A coupled, velocity-dependent system: n unit masses in a chain of linear
// springs between two walls, with nonlinear dampers d(u) = c1 u + c3 u^3 on
// every relative velocity u. df/dv is tridiagonal (dense, band and sparse
// storage all fit). Uses N_VGetArrayPointer, so it runs on serial and OpenMP
// vectors alike.
struct DampedChain {
  sunindextype n = 5;
  sunrealtype k = 10;
  sunrealtype c1 = SUN_RCONST(0.5);
  sunrealtype c3 = 2;
  bool damped = true;  // false: conservative chain for the explicit path

  // Damper j joins node j-1 and node j (nodes -1 and n are the walls, at rest).
  static int Rhs(sunrealtype /*t*/, N_Vector x, N_Vector v, N_Vector f, void* data) {
    const auto* p = static_cast<const DampedChain*>(data);
    const sunrealtype* xd = N_VGetArrayPointer(x);
    const sunrealtype* vd = N_VGetArrayPointer(v);
    sunrealtype* fd = N_VGetArrayPointer(f);
    const sunindextype n = p->n;
    for (sunindextype i = 0; i < n; ++i) {
      const sunrealtype xl = i > 0 ? xd[i - 1] : 0;
      const sunrealtype xr = i + 1 < n ? xd[i + 1] : 0;
      fd[i] = p->k * (xl - 2 * xd[i] + xr);
    }
    if (!p->damped) return 0;
    for (sunindextype j = 0; j <= n; ++j) {
      const sunrealtype vl = j > 0 ? vd[j - 1] : 0;
      const sunrealtype vr = j < n ? vd[j] : 0;
      const sunrealtype u = vr - vl;
      const sunrealtype d = p->c1 * u + p->c3 * u * u * u;
      if (j > 0) fd[j - 1] += d;
      if (j < n) fd[j] -= d;
    }
    return 0;
  }

  // Calls emit(row, col, df_row/dv_col) for every entry of the tridiagonal
  // Jacobian, column by column and row-sorted within a column (CSC order; the
  // matrix is symmetric, so the same sequence is the CSR order too).
  template <typename Emit>
  void VelJacobian(N_Vector v, Emit emit) const {
    const sunrealtype* vd = N_VGetArrayPointer(v);
    auto dd = [&](sunindextype j) {  // d'(u) of damper j
      const sunrealtype vl = j > 0 ? vd[j - 1] : 0;
      const sunrealtype vr = j < n ? vd[j] : 0;
      const sunrealtype u = vr - vl;
      return c1 + 3 * c3 * u * u;
    };
    for (sunindextype c = 0; c < n; ++c) {
      if (c > 0) emit(c - 1, c, dd(c));
      emit(c, c, -dd(c) - dd(c + 1));
      if (c + 1 < n) emit(c + 1, c, dd(c + 1));
    }
  }

  void Initial(N_Vector x, N_Vector v) const {
    sunrealtype* xd = N_VGetArrayPointer(x);
    sunrealtype* vd = N_VGetArrayPointer(v);
    for (sunindextype i = 0; i < n; ++i) {
      xd[i] = SUN_RCONST(0.3) * std::sin(SUN_RCONST(3.0) * (i + 1) / (n + 1));
      vd[i] = (i % 2 == 0 ? 1 : -1) * SUN_RCONST(0.7) / (1 + i);
    }
  }
};

// ---------------------------------------------------------------------------
// Runs against an exact solution.

struct RunOptions {
  std::string method = "G3_CD";
  sunrealtype h = SUN_RCONST(0.01);
  sunrealtype tend = 10;
  bool zero_start = false;
  bool implicit = false;  // velocity dependence declared: Newton + dense (DQ Jacobian)
  // Output times: empty = every step (CE_ONE_STEP), where the method has x and x' together.
  std::vector<sunrealtype> tout;
};

struct RunResult {
  int flag = CE_SUCCESS;
  sunrealtype err_x = 0;  // max |x - x_exact| over the outputs
  sunrealtype err_v = 0;  // max |x' - x'_exact| over the outputs
  long int steps = 0;
  long int nni = 0;
};

inline RunResult RunExact(const ExactProblem& prob, const RunOptions& opt) {
  RunResult r;
  Context ctx;
  Vector x = SerialVector(1, ctx, prob.x0);
  Vector v = SerialVector(1, ctx, prob.v0);
  Mem mem(CEodeCreate(ctx));
  Matrix A;
  LinearSolver LS;
  auto fail = [&r](int flag) {
    if (flag < 0 && r.flag == CE_SUCCESS) r.flag = flag;
    return flag < 0;
  };
  if (fail(CEodeInit(mem.get(), prob.Rhs(), 0, x.get(), v.get())) ||
      fail(CEodeSetUserData(mem.get(), const_cast<ExactProblem*>(&prob))) ||
      fail(CEodeSetMethodByName(mem.get(), opt.method.c_str())) ||
      fail(CEodeSetFixedStep(mem.get(), opt.h)) ||
      fail(CEodeSetZeroStart(mem.get(), opt.zero_start ? SUNTRUE : SUNFALSE)) ||
      // The convergence runs include G4_A54 on purpose: no stability warnings.
      fail(CEodeSetStabilityGuard(mem.get(), CE_GUARD_OFF, 0))) {
    return r;
  }
  if (opt.implicit) {
    A.reset(SUNDenseMatrix(1, 1, ctx));
    LS.reset(SUNLinSol_Dense(x.get(), A.get(), ctx));
    if (fail(CEodeSetVelocityDependence(mem.get(), SUNTRUE)) ||
        // Newton, not the library's AUTO choice: the sets' orders are those of the exact solve
        // (prediction-correction's own orders: test_pc.cpp).
        fail(CEodeSetImplicitMode(mem.get(), CE_IMPLICIT_NEWTON)) ||
        fail(CEodeSetLinearSolver(mem.get(), LS.get(), A.get()))) {
      return r;
    }
  }
  auto record = [&](sunrealtype t) {
    sunrealtype xe = 0, ve = 0;
    prob.Exact(t, &xe, &ve);
    r.err_x = std::max(r.err_x, std::fabs(NV_Ith_S(x.get(), 0) - xe));
    r.err_v = std::max(r.err_v, std::fabs(NV_Ith_S(v.get(), 0) - ve));
  };
  sunrealtype t = 0;
  if (opt.tout.empty()) {
    const long int nsteps = std::lround(opt.tend / opt.h);
    for (long int i = 0; i < nsteps; ++i) {
      if (fail(CEodeEvolve(mem.get(), opt.tend, x.get(), v.get(), &t, CE_ONE_STEP))) return r;
      record(t);
    }
  } else {
    for (sunrealtype tout : opt.tout) {
      if (fail(CEodeEvolve(mem.get(), tout, x.get(), v.get(), &t, CE_NORMAL))) return r;
      record(t);
    }
  }
  CEodeGetNumSteps(mem.get(), &r.steps);
  CEodeGetNumNonlinSolvIters(mem.get(), &r.nni);
  return r;
}

// Least-squares slope of log(e) against log(h): the observed order.
inline double FitOrder(const std::vector<double>& h, const std::vector<double>& e) {
  const size_t n = h.size();
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < n; ++i) {
    const double lx = std::log(h[i]);
    const double ly = std::log(e[i]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

// Five halvings from hmax. With hmax <= 0.08 and w = 1 every set is well inside
// its stability region (Omega_max >= 0.6).
inline std::vector<double> ConvergenceSteps(double hmax) {
  std::vector<double> hs;
  for (int k = 0; k < 5; ++k) hs.push_back(hmax / (1 << k));
  return hs;
}

// The IFToMM simple pendulum of docs/theory.md section 11: theta from the horizontal,
// m = 1 kg, L = 1 m, released at rest from theta = 0, 10 s.
namespace pendulum {
constexpr sunrealtype kGrav = SUN_RCONST(9.81);
constexpr sunrealtype kLen = 1;
constexpr sunrealtype kMass = 1;
constexpr sunrealtype kTend = 10;

inline int Rhs(sunrealtype /*t*/, N_Vector x, N_Vector /*v*/, N_Vector f, void* /*data*/) {
  NV_Ith_S(f, 0) = -(kGrav / kLen) * std::cos(NV_Ith_S(x, 0));
  return 0;
}

inline sunrealtype Energy(sunrealtype th, sunrealtype om) {
  return SUN_RCONST(0.5) * kMass * kLen * kLen * om * om + kMass * kGrav * kLen * std::sin(th);
}
}  // namespace pendulum

// Max |E - E0| over every step, where the method has theta and theta' together.
inline double PendulumEnergyError(const std::string& method, sunrealtype h, bool zero_start,
                                  bool compensated = false) {
  Context ctx;
  Vector x = SerialVector(1, ctx, 0);
  Vector v = SerialVector(1, ctx, 0);
  Mem mem(CEodeCreate(ctx));
  EXPECT_EQ(CEodeInit(mem.get(), pendulum::Rhs, 0, x.get(), v.get()), CE_SUCCESS);
  EXPECT_EQ(CEodeSetMethodByName(mem.get(), method.c_str()), CE_SUCCESS);
  EXPECT_EQ(CEodeSetFixedStep(mem.get(), h), CE_SUCCESS);
  EXPECT_EQ(CEodeSetZeroStart(mem.get(), zero_start ? SUNTRUE : SUNFALSE), CE_SUCCESS);
  EXPECT_EQ(CEodeSetCompensatedSummation(mem.get(), compensated ? SUNTRUE : SUNFALSE), CE_SUCCESS);
  EXPECT_EQ(CEodeSetStabilityGuard(mem.get(), CE_GUARD_OFF, 0), CE_SUCCESS);
  const sunrealtype e0 = pendulum::Energy(0, 0);
  const long int nsteps = std::lround(pendulum::kTend / h);
  double emax = 0;
  sunrealtype t = 0;
  for (long int i = 0; i < nsteps; ++i) {
    const int flag = CEodeEvolve(mem.get(), pendulum::kTend, x.get(), v.get(), &t, CE_ONE_STEP);
    if (flag != CE_SUCCESS) {
      ADD_FAILURE() << method << " h = " << h << ": CEodeEvolve returned " << flag;
      return NAN;
    }
    emax = std::max(emax,
                    std::fabs(pendulum::Energy(NV_Ith_S(x.get(), 0), NV_Ith_S(v.get(), 0)) - e0));
  }
  return emax;
}

}  // namespace ceode_test

#endif  // CEODE_TEST_TEST_UTIL_HPP_
