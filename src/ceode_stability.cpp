// Linear stability from the integrator's own step map (method.md section 4),
// and the runtime guard that compares h * omega_max with the method's limit.
#include <ceode/ceode_stability.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Dense>
#include <cmath>
#include <memory>

#include "ceode_impl.hpp"

namespace ceode {

namespace {

struct TestProblem {
  sunrealtype omega;
  sunrealtype xi;
};

// x'' = -Omega^2 x - 2 xi Omega x' with h = 1, so that omega h = Omega.
int TestRhs(sunrealtype /*t*/, N_Vector x, N_Vector v, N_Vector f, void* data) {
  const auto* p = static_cast<const TestProblem*>(data);
  N_VLinearSum(-p->omega * p->omega, x, -2 * p->xi * p->omega, v, f);
  return 0;
}

int TestJac(sunrealtype /*t*/, N_Vector /*x*/, N_Vector /*v*/, N_Vector /*f*/, SUNMatrix J,
            void* data, N_Vector, N_Vector, N_Vector) {
  const auto* p = static_cast<const TestProblem*>(data);
  SUNDenseMatrix_Data(J)[0] = -2 * p->xi * p->omega;
  return 0;
}

// Owns a one-degree-of-freedom CEODE run whose step is applied to unit states.
class StepMap {
 public:
  StepMap(int degree, const sunrealtype* params, sunrealtype xi) : prob_{0, xi} {
    SUNContext_Create(nullptr, &ctx_);
    x_ = N_VNew_Serial(1, ctx_);
    v_ = N_VNew_Serial(1, ctx_);
    N_VConst(0, x_);
    N_VConst(0, v_);
    mem_ = CEodeCreate(ctx_);
    CEodeSetErrFile(mem_, nullptr);
    ok_ = CEodeInit(mem_, TestRhs, 0, x_, v_) == CE_SUCCESS &&
          CEodeSetMethod(mem_, degree, params) == CE_SUCCESS &&
          CEodeSetFixedStep(mem_, 1) == CE_SUCCESS && CEodeSetUserData(mem_, &prob_) == CE_SUCCESS &&
          CEodeSetStabilityGuard(mem_, CE_GUARD_OFF, 0) == CE_SUCCESS;
    if (ok_ && xi > 0) {
      A_ = SUNDenseMatrix(1, 1, ctx_);
      LS_ = SUNLinSol_Dense(x_, A_, ctx_);
      ok_ = CEodeSetVelocityDependence(mem_, SUNTRUE) == CE_SUCCESS &&
            CEodeSetLinearSolver(mem_, LS_, A_) == CE_SUCCESS &&
            CEodeSetVelJacFn(mem_, TestJac) == CE_SUCCESS &&
            CEodeSetNonlinTolerances(mem_, 1e-15, 1e-300) == CE_SUCCESS;
    }
    sunrealtype t = 0;
    // One real step builds the solver objects and coefficients for h = 1.
    ok_ = ok_ && CEodeEvolve(mem_, 1, x_, v_, &t, CE_ONE_STEP) == CE_SUCCESS;
  }
  ~StepMap() {
    CEodeFree(&mem_);
    if (LS_ != nullptr) SUNLinSolFree(LS_);
    if (A_ != nullptr) SUNMatDestroy(A_);
    N_VDestroy(x_);
    N_VDestroy(v_);
    SUNContext_Free(&ctx_);
  }
  StepMap(const StepMap&) = delete;
  StepMap& operator=(const StepMap&) = delete;

  bool ok() const { return ok_; }

  // Column k of A: the step applied to the k-th unit state (x(t), D_1..D_{d-1}(t-h)).
  bool Build(sunrealtype Omega, Eigen::MatrixXd* A) {
    auto* ce = static_cast<CEodeMemRec*>(mem_);
    const int d = ce->degree;
    prob_.omega = Omega;
    A->resize(d, d);
    for (int k = 0; k < d; ++k) {
      N_VConst(0, ce->xnext);
      for (int j = 1; j < d; ++j) N_VConst(k == j ? 1 : 0, ce->D[j]);
      if (k == 0) N_VConst(1, ce->xnext);
      ce->jac_current = false;
      if (TakeStep(ce) != CE_SUCCESS) return false;
      (*A)(0, k) = N_VGetArrayPointer(ce->xnext)[0];
      for (int j = 1; j < d; ++j) (*A)(j, k) = N_VGetArrayPointer(ce->D[j])[0];
    }
    return true;
  }

 private:
  TestProblem prob_;
  SUNContext ctx_ = nullptr;
  N_Vector x_ = nullptr;
  N_Vector v_ = nullptr;
  SUNMatrix A_ = nullptr;
  SUNLinearSolver LS_ = nullptr;
  void* mem_ = nullptr;
  bool ok_ = false;
};

int CheckArgs(int degree, const sunrealtype* params, sunrealtype xi) {
  if (degree < kMinDegree || degree > kMaxDegree || params == nullptr || !(xi >= 0)) {
    return CE_ILL_INPUT;
  }
  return CE_SUCCESS;
}

sunrealtype Radius(const Eigen::MatrixXd& A) {
  return A.eigenvalues().cwiseAbs().maxCoeff();
}

// Tolerance on rho = 1: the undamped eigenvalues sit on the unit circle.
constexpr sunrealtype kRhoTol = 1e-9;

}  // namespace

int MethodStabilityLimit(int degree, const sunrealtype* params, sunrealtype* Omega_max) {
  return CEodeStabilityLimit(degree, params, 0, Omega_max);
}

int GuardCheck(CEodeMemRec* ce, const char* func) {
  if (ce->guard_mode == CE_GUARD_OFF) return CE_SUCCESS;
  if (ce->omega_user > 0) {
    ce->omega_est = ce->omega_user;
  } else if (HasConstraints(ce)) {
    return CE_SUCCESS;  // constrained frequencies need the user's estimate
  } else {
    // Power iteration on -dg/dx, g = M^{-1} f, by directional differences at (x, v, t).
    N_Vector w = ce->vtmp;
    N_Vector g0 = ce->atmp;
    N_Vector xp = ce->xnew;
    N_Vector gp = ce->apred;
    sunrealtype* wd = N_VGetArrayPointer(w);
    N_VConst(1, w);
    // A pseudo-random start avoids a start vector orthogonal to the top mode;
    // vectors without one local array (MPI) start from ones.
    if (wd != nullptr && N_VGetCommunicator(w) == nullptr) {
      unsigned long seed = 12345;
      const sunindextype nl = N_VGetLength(w);
      for (sunindextype i = 0; i < nl; ++i) {
        seed = seed * 6364136223846793005UL + 1442695040888963407UL;
        wd[i] = 0.5 + static_cast<sunrealtype>(seed >> 33) / 4294967296.0;
      }
    }
    int flag = EvalAccel(ce, ce->tcur, ce->xcur, ce->D[1], g0, func);
    if (flag != CE_SUCCESS) return flag;
    const sunrealtype xscale = 1 + N_VMaxNorm(ce->xcur);
    sunrealtype lam = 0;
    for (int it = 0; it < 60; ++it) {
      const sunrealtype wn = std::sqrt(N_VDotProd(w, w));
      if (!(wn > 0)) break;
      N_VScale(1 / wn, w, w);
      const sunrealtype sig = std::sqrt(SUN_UNIT_ROUNDOFF) * xscale;
      N_VLinearSum(1, ce->xcur, sig, w, xp);
      flag = EvalAccel(ce, ce->tcur, xp, ce->D[1], gp, func);
      if (flag != CE_SUCCESS) return flag;
      N_VLinearSum(-1 / sig, gp, 1 / sig, g0, w);
      lam = std::sqrt(N_VDotProd(w, w));
    }
    ce->omega_est = std::sqrt(lam);
  }
  if (ce->omega_limit == 0) {
    sunrealtype lim = 0;
    if (MethodStabilityLimit(ce->degree, ce->params, &lim) != CE_SUCCESS) return CE_SUCCESS;
    ce->omega_limit = lim > 0 ? lim : -1;  // -1: unstable for every step
  }
  const sunrealtype Omega = ce->h * ce->omega_est;
  if (ce->omega_limit > 0 && Omega <= ce->omega_limit) return CE_SUCCESS;
  const int flag = ce->guard_mode == CE_GUARD_REFUSE ? CE_UNSTABLE : CE_WARNING;
  if (ce->omega_limit < 0) {
    sunrealtype rho = 1;
    CEodeSpectralRadius(ce->degree, ce->params, Omega, 0, &rho);
    if (flag == CE_WARNING && ce->guard_warned) return CE_SUCCESS;
    ce->guard_warned = true;
    ProcessError(ce, flag, func,
                 "%s is unstable for every step: at h * omega_max = %g the error grows by rho = "
                 "%.9g per step (doubling after about %.3g steps). Use a stable set for long runs.",
                 ce->method_name.c_str(), static_cast<double>(Omega), static_cast<double>(rho),
                 static_cast<double>(std::log(2.0) / std::log(std::max(rho, 1 + 1e-300))));
    return flag == CE_WARNING ? CE_SUCCESS : flag;
  }
  if (flag == CE_WARNING && ce->guard_warned) return CE_SUCCESS;
  ce->guard_warned = true;
  ProcessError(ce, flag, func,
               "h * omega_max = %g * %g = %g exceeds the stability limit Omega_max = %.6g of %s: "
               "the run will diverge. Use h < %.6g%s.",
               static_cast<double>(ce->h), static_cast<double>(ce->omega_est),
               static_cast<double>(Omega), static_cast<double>(ce->omega_limit),
               ce->method_name.c_str(), static_cast<double>(ce->omega_limit / ce->omega_est),
               flag == CE_WARNING ? " (set CE_GUARD_REFUSE to stop instead of warning)" : "");
  return flag == CE_WARNING ? CE_SUCCESS : flag;
}

}  // namespace ceode

extern "C" {

int CEodeAmplificationMatrix(int degree, const sunrealtype* params, sunrealtype Omega,
                             sunrealtype xi, sunrealtype* A) {
  if (ceode::CheckArgs(degree, params, xi) != CE_SUCCESS || A == nullptr || !(Omega >= 0)) {
    return CE_ILL_INPUT;
  }
  ceode::StepMap map(degree, params, xi);
  Eigen::MatrixXd M;
  if (!map.ok() || !map.Build(Omega, &M)) return CE_ILL_INPUT;
  for (int i = 0; i < degree; ++i) {
    for (int j = 0; j < degree; ++j) A[i * degree + j] = M(i, j);
  }
  return CE_SUCCESS;
}

int CEodeSpectralRadius(int degree, const sunrealtype* params, sunrealtype Omega, sunrealtype xi,
                        sunrealtype* rho) {
  if (ceode::CheckArgs(degree, params, xi) != CE_SUCCESS || rho == nullptr || !(Omega >= 0)) {
    return CE_ILL_INPUT;
  }
  ceode::StepMap map(degree, params, xi);
  Eigen::MatrixXd M;
  if (!map.ok() || !map.Build(Omega, &M)) return CE_ILL_INPUT;
  *rho = ceode::Radius(M);
  return CE_SUCCESS;
}

int CEodeStabilityLimit(int degree, const sunrealtype* params, sunrealtype xi,
                        sunrealtype* Omega_max) {
  if (ceode::CheckArgs(degree, params, xi) != CE_SUCCESS || Omega_max == nullptr) {
    return CE_ILL_INPUT;
  }
  ceode::StepMap map(degree, params, xi);
  if (!map.ok()) return CE_ILL_INPUT;
  Eigen::MatrixXd M;
  auto stable = [&](sunrealtype Om) {
    return map.Build(Om, &M) && ceode::Radius(M) <= 1 + ceode::kRhoTol;
  };
  // Scan (0, 20] on a fine grid, then bisect the first sign change.
  constexpr sunrealtype kStep = 1e-3;
  constexpr int kMaxK = 20000;
  int k = 1;
  while (k <= kMaxK && stable(k * kStep)) ++k;
  if (k == 1) {
    *Omega_max = 0;
    return CE_SUCCESS;
  }
  if (k > kMaxK) {
    *Omega_max = kMaxK * kStep;
    return CE_SUCCESS;
  }
  sunrealtype lo = (k - 1) * kStep;
  sunrealtype hi = k * kStep;
  for (int it = 0; it < 60 && hi - lo > 1e-13 * hi; ++it) {
    const sunrealtype mid = 0.5 * (lo + hi);
    (stable(mid) ? lo : hi) = mid;
  }
  *Omega_max = lo;
  return CE_SUCCESS;
}

}  // extern "C"
